/* accelcal -- the public, status-returning ac_xf API (ac_xf.h) over the core. */
#include "ac_xf_core.h"

static ac_status result(const ac_xf *r)
{
    return (r->e == AC_XF_BAD) ? AC_ERR_RANGE : AC_OK;
}

ac_status ac_xf_from_fixed(int32_t v, int16_t frac, ac_xf *out)
{
    ac_xf r;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ac_xfp_from_fixed(&r, v, frac);
    if (result(&r) != AC_OK) {
        return AC_ERR_RANGE;
    }
    *out = r;
    return AC_OK;
}

ac_status ac_xf_to_fixed(ac_xf x, int16_t frac, int32_t *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ac_xfp_normalize(&x);
    return ac_xfp_to_fixed(&x, frac, out);
}

#define AC_XF_BINARY(name, op)                                                                     \
    ac_status name(ac_xf a, ac_xf b, ac_xf *out)                                                   \
    {                                                                                              \
        ac_xf r;                                                                                   \
        if (out == 0) {                                                                            \
            return AC_ERR_NULL;                                                                    \
        }                                                                                          \
        ac_xfp_normalize(&a);                                                                      \
        ac_xfp_normalize(&b);                                                                      \
        op(&r, &a, &b);                                                                            \
        if (result(&r) != AC_OK) {                                                                 \
            return AC_ERR_RANGE;                                                                   \
        }                                                                                          \
        *out = r;                                                                                  \
        return AC_OK;                                                                              \
    }

AC_XF_BINARY(ac_xf_add, ac_xfp_add)
AC_XF_BINARY(ac_xf_sub, ac_xfp_sub)
AC_XF_BINARY(ac_xf_mul, ac_xfp_mul)

ac_status ac_xf_div(ac_xf a, ac_xf b, ac_xf *out)
{
    ac_xf r;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (b.m == 0) {
        return AC_ERR_SINGULAR;
    }
    ac_xfp_normalize(&a);
    ac_xfp_normalize(&b);
    ac_xfp_div(&r, &a, &b);
    if (result(&r) != AC_OK) {
        return AC_ERR_RANGE;
    }
    *out = r;
    return AC_OK;
}

ac_status ac_xf_neg(ac_xf a, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ac_xfp_normalize(&a);
    if (a.e == AC_XF_BAD) {
        return AC_ERR_RANGE;
    }
    out->m = -a.m; /* normalised: |m| < 2^30, no overflow */
    out->e = a.e;
    return AC_OK;
}

ac_status ac_xf_abs(ac_xf a, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ac_xfp_normalize(&a);
    if (a.e == AC_XF_BAD) {
        return AC_ERR_RANGE;
    }
    out->m = (a.m < 0) ? -a.m : a.m;
    out->e = a.e;
    return AC_OK;
}

ac_status ac_xf_cmpabs(ac_xf a, ac_xf b, int8_t *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ac_xfp_normalize(&a);
    ac_xfp_normalize(&b);
    *out = ac_xfp_cmpabs(&a, &b);
    return AC_OK;
}

ac_status ac_xf_ldexp(ac_xf x, int16_t k, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ac_xfp_normalize(&x);
    ac_xfp_ldexp(&x, k);
    if (result(&x) != AC_OK) {
        return AC_ERR_RANGE;
    }
    *out = x;
    return AC_OK;
}
