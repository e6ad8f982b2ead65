/*
 * accelcal -- the pointer-based core of ac_xf (internal, not installed).
 *
 * The on-device inversion calls these instead of the public by-value API: on
 * the H8/300H a 6-byte struct passed by value costs some 40 bytes of code per
 * call and stack per frame.  Errors are sticky instead of returned: an exponent
 * overflow gives the invalid value (e == AC_XF_BAD), every operation on an
 * invalid operand gives it again, and the caller checks once at the end.
 * Results may alias operands.
 */
#ifndef AC_XF_CORE_H
#define AC_XF_CORE_H

#include "accelcal/ac_xf.h"

#define AC_XF_BAD (-32767 - 1)

/* Bring any mantissa (even INT32_MIN, or one below 2^29) into the normalised
 * form every other function assumes (zero and normalised values are left as
 * they are); the public API and ac_invert6 call it on every value that comes
 * from outside. */
void ac_xfp_normalize(ac_xf *x);
void ac_xfp_from_fixed(ac_xf *r, int32_t v, int16_t frac);
void ac_xfp_add(ac_xf *r, const ac_xf *a, const ac_xf *b);
void ac_xfp_sub(ac_xf *r, const ac_xf *a, const ac_xf *b);
void ac_xfp_mul(ac_xf *r, const ac_xf *a, const ac_xf *b);
/* r += a b */
void ac_xfp_mac(ac_xf *r, const ac_xf *a, const ac_xf *b);
/* b == 0 gives the invalid value */
void ac_xfp_div(ac_xf *r, const ac_xf *a, const ac_xf *b);
void ac_xfp_ldexp(ac_xf *r, int16_t k);
/* -1, 0, 1 as |a| <, ==, > |b| */
int8_t ac_xfp_cmpabs(const ac_xf *a, const ac_xf *b);
/* max = max(max, |v|); sum += |v| when sum is not NULL */
void ac_xfp_acc_abs(ac_xf *max, ac_xf *sum, const ac_xf *v);
/* round(x 2^frac) half up; AC_SATURATED when clipped, AC_ERR_RANGE when invalid */
ac_status ac_xfp_to_fixed(const ac_xf *x, int16_t frac, int32_t *out);

#endif /* AC_XF_CORE_H */
