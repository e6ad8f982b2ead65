/*
 * accelcal -- extended-range numbers for on-device inversion.
 *
 * ac_xf is a number m * 2^e with a 32-bit mantissa and 16-bit exponent,
 * normalised so that 2^29 <= |m| < 2^30 (or m == 0).  It gives the
 * inversion about 29 bits of relative precision over any scale, using only
 * integer arithmetic (no FPU, no soft-float library).  It is meant for the
 * rarely-run matrix build, not the per-sample path.
 *
 * Every function accepts any mantissa (it normalises its inputs first, so
 * INT32_MIN or an unnormalised value is fine).  Exponents are kept within
 * +-30000; a result beyond that is AC_ERR_RANGE.  The exponent -32768 is
 * reserved: it marks an invalid value, and any operation on it gives
 * AC_ERR_RANGE.
 */
#ifndef AC_XF_H
#define AC_XF_H

#include "ac_config.h"
#include "ac_status.h"

typedef struct ac_xf {
    int32_t m;
    int16_t e;
} ac_xf;

/* *out = v * 2^-frac, exact when |v| < 2^30, else rounded to the 30-bit mantissa. */
ac_status ac_xf_from_fixed(int32_t v, int16_t frac, ac_xf *out);
/* *out = round(x * 2^frac), half up, clipped to int32. */
ac_status ac_xf_to_fixed(ac_xf x, int16_t frac, int32_t *out);
/* Arithmetic, each rounded to nearest (ties away from zero). */
ac_status ac_xf_add(ac_xf a, ac_xf b, ac_xf *out);
ac_status ac_xf_sub(ac_xf a, ac_xf b, ac_xf *out);
ac_status ac_xf_mul(ac_xf a, ac_xf b, ac_xf *out);
/* AC_ERR_SINGULAR for b == 0. */
ac_status ac_xf_div(ac_xf a, ac_xf b, ac_xf *out);
ac_status ac_xf_neg(ac_xf a, ac_xf *out);
ac_status ac_xf_abs(ac_xf a, ac_xf *out);
/* *out = -1, 0, 1 as |a| <, ==, > |b|. */
ac_status ac_xf_cmpabs(ac_xf a, ac_xf b, int8_t *out);
/* *out = x * 2^k (exact). */
ac_status ac_xf_ldexp(ac_xf x, int16_t k, ac_xf *out);

#endif /* AC_XF_H */
