/*
 * accelcal -- fixed-point integer primitives.
 *
 * Every operation that can leave its range saturates and says so with
 * AC_SATURATED; nothing wraps.  Shifts of negative values are done without
 * relying on implementation-defined ">>" of signed integers.  No routine
 * here multiplies two 32-bit values with "*" or divides 32-bit values with
 * "/": the H8/300H toolchain has no libgcc for those.
 */
#ifndef AC_FIXED_H
#define AC_FIXED_H

#include "ac_config.h"
#include "ac_status.h"

/* 64-bit two's-complement value as two 32-bit halves (value = hi*2^32 + lo),
 * for the few places outside the per-sample path that need it. */
typedef struct ac_i64 {
    int32_t hi;
    uint32_t lo;
} ac_i64;

/* *out = v clipped to int16. */
ac_status ac_sat16(int32_t v, int16_t *out);

/* *out = a + b, clipped to int32. */
ac_status ac_add32_sat(int32_t a, int32_t b, int32_t *out);

/* *out = floor(v / 2^n) for 0 <= n <= 31 (arithmetic shift right). */
ac_status ac_asr32(int32_t v, uint8_t n, int32_t *out);

/* *out = v * 2^-shift rounded half up (towards +inf at ties) for shift > 0,
 * v * 2^-shift exactly for shift <= 0, clipped to int32.  Any int16 shift:
 * beyond 31 the result is 0 (right) or saturates unless v == 0 (left). */
ac_status ac_scale_round32(int32_t v, int16_t shift, int32_t *out);

/* *out = a * b exactly, with 16x16-bit partial products only. */
ac_status ac_mul32x32(int32_t a, int32_t b, ac_i64 *out);

/* *out = round(a * b / 2^n), half up, for 0 <= n <= 62, clipped to int32. */
ac_status ac_mul32_shift(int32_t a, int32_t b, uint8_t n, int32_t *out);

/* *out = round(a * b / 2^n), half up (ties towards +inf), for 0 <= n <= 47: exact
 * (two 16 x 16 partial products, the cheap case of ac_mul32_shift), clipped to
 * int32 (AC_SATURATED). */
ac_status ac_mul32x16_shift(int32_t a, uint16_t b, uint8_t n, int32_t *out);

/* Two's-complement reinterpretation of u as int32, without relying on the
 * implementation-defined conversion of out-of-range unsigned values. */
ac_status ac_u32_to_i32(uint32_t u, int32_t *out);

/* Number of significant bits of |v| (0 for v == 0, 32 for INT32_MIN). */
ac_status ac_bitlen32(int32_t v, uint8_t *out);

#endif /* AC_FIXED_H */
