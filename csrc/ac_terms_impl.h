/*
 * accelcal -- constant-shift roundings of the correctable terms (ac_temp.c, ac_skew.c,
 * ac_nonlin.c; not installed).  Macros, so that even h8300-hms-gcc 3.4 (which does not
 * inline the helpers of ac_internal.h) pays no call: each adds a bias that makes the value
 * non-negative, shifts the unsigned sum by a constant (a shift by 15 or 16 is a word move
 * on the H8/300H, not a loop) and removes the bias again.  No ">>" of a negative value, no
 * signed overflow; every sum is taken modulo 2^32 (cast to uint32_t: unsigned long is
 * wider on 64-bit hosts).  Each is round(v 2^-n) half up (ties towards +inf), exactly, on
 * the range stated.
 */
#ifndef AC_TERMS_IMPL_H
#define AC_TERMS_IMPL_H

#include "accelcal/ac_config.h"
#include "ac_internal.h"

/* round(v / 2^15), |v| <= 2^30 */
#define AC_R15(v) ((int32_t)((uint32_t)((uint32_t)(v) + (uint32_t)0x40004000UL) >> 15) - 0x8000L)

/* round(v / 2^15), -2^31 <= v < 2^31 - 2^14 */
#define AC_R15W(v) ((int32_t)((uint32_t)((uint32_t)(v) + (uint32_t)0x80004000UL) >> 15) - 0x10000L)

/* round(v / 2^16) as int16, -2^31 <= v < 2^31 - 2^15 (the result is in int16 there) */
#define AC_R16(v) ((int16_t)((int32_t)((uint32_t)((uint32_t)(v) + (uint32_t)0x80008000UL) >> 16) - 0x8000L))

/* round(v / 2^19), |v| <= 2^30 */
#define AC_R19(v) ((int32_t)((uint16_t)((uint32_t)((uint32_t)(v) + (uint32_t)0x40040000UL) >> 16) >> 3) - 0x800L)

/* round(v / 2^13), |v| < 2^28 - 2^12 */
#define AC_R13(v) ((int32_t)((((uint32_t)((uint32_t)(v) + (uint32_t)0x10001000UL) << 3) >> 16)) - 0x8000L)

/* round(v / 2^3), |v| <= 2^30 */
#define AC_R3(v) ((int32_t)((uint32_t)((uint32_t)(v) + (uint32_t)0x40000004UL) >> 3) - 0x08000000L)

/* the H8/300H assembly kernels (ac_terms_h8.c; AC_H8_RESOLVE_ASM of ac_internal.h) */
#if AC_H8_RESOLVE_ASM
#include "accelcal/ac_nonlin.h"
/* on the H8/300H ac_nonlin_invert is assembly (ac_terms_h8.c) that jumps to this, the C, for what
 * it does not take (NULL, a bad n, a shift below 15 or above 30) */
ac_status ac_nonlin_invert_c(const ac_nonlin_table *t, const int16_t *x, int16_t *y);
#define AC_NONLIN_INVERT_C ac_nonlin_invert_c
#include "accelcal/ac_temp.h"
/* on the H8/300H ac_temp_correct and ac_temp_lag_step are assembly (ac_terms_h8.c) that jumps to
 * these, the C, for what it does not take (NULL, a bad n, a first step, a shift below 17 ...) */
ac_status ac_temp_correct_c(const ac_temp_table *t, int16_t t_off, int16_t t_gain, const int16_t *x,
                            int16_t *y);
ac_status ac_temp_lag_step_c(ac_temp_lag *f, int16_t temp, int16_t *lagged);
#define AC_TEMP_CORRECT_C ac_temp_correct_c
#define AC_TEMP_LAG_STEP_C ac_temp_lag_step_c
#else
#define AC_NONLIN_INVERT_C ac_nonlin_invert
#define AC_TEMP_CORRECT_C ac_temp_correct
#define AC_TEMP_LAG_STEP_C ac_temp_lag_step
#endif

/* 16 x 16 -> 32 signed product */
#define AC_MUL16(a, b) ((int32_t)(int16_t)(a) * (int16_t)(b))

#endif /* AC_TERMS_IMPL_H */
