/*
 * accelcal -- extended-range numbers (mantissa 2^29 <= |m| < 2^30, exponent).
 *
 * Internally a value is handled as sign + 64-bit magnitude + exponent and
 * rounded once, to nearest with ties away from zero, when it is normalised.
 */
#include "accelcal/ac_xf.h"
#include "ac_internal.h"

#define XF_LO 0x20000000UL /* 2^29 */
#define XF_HI 0x40000000UL /* 2^30 */
#define XF_EMAX 30000L
#define XF_EMIN (-30000L)

static const ac_xf xf_zero = {0, 0};

/* Normalise sign * mag * 2^e into *out.  mag may use all 64 bits. */
static ac_status xf_pack(int neg, ac_u64 mag, int32_t e, ac_xf *out)
{
    uint8_t len;
    if (mag.hi == 0u && mag.lo == 0u) {
        *out = xf_zero;
        return AC_OK;
    }
    len = (mag.hi != 0u) ? (uint8_t)(32u + ac_bitlen_u(mag.hi)) : ac_bitlen_u(mag.lo);
    if (len > 30u) {
        uint8_t k = (uint8_t)(len - 30u);
        ac_u64 one = {0u, 1u};
        mag = ac_u64_add(mag, ac_u64_shl(one, (uint8_t)(k - 1u))); /* ties away from zero */
        mag = ac_u64_shr(mag, k);
        e += (int32_t)k;
        if (mag.lo >= XF_HI) { /* rounding carried into a new bit */
            mag.lo >>= 1;
            e += 1;
        }
    } else if (len < 30u) {
        uint8_t k = (uint8_t)(30u - len);
        mag.lo <<= k;
        e -= (int32_t)k;
    }
    if (e > XF_EMAX) {
        return AC_ERR_RANGE;
    }
    if (e < XF_EMIN) { /* underflow: flush to zero */
        *out = xf_zero;
        return AC_OK;
    }
    out->m = neg ? -(int32_t)mag.lo : (int32_t)mag.lo;
    out->e = (int16_t)e;
    return AC_OK;
}

static ac_u64 u64_of(uint32_t v)
{
    ac_u64 r;
    r.hi = 0u;
    r.lo = v;
    return r;
}

ac_status ac_xf_from_fixed(int32_t v, int16_t frac, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    return xf_pack(v < 0, u64_of(ac_abs_u(v)), -(int32_t)frac, out);
}

ac_status ac_xf_to_fixed(ac_xf x, int16_t frac, int32_t *out)
{
    uint8_t sat = 0u;
    int32_t k;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (x.m == 0) {
        *out = 0;
        return AC_OK;
    }
    k = (int32_t)x.e + (int32_t)frac; /* value * 2^frac = m * 2^k */
    if (k > 31) {
        *out = (x.m > 0) ? INT32_MAX : INT32_MIN;
        return AC_SATURATED;
    }
    if (k < -31) {
        *out = 0; /* |m| * 2^k < 2^-1 */
        return AC_OK;
    }
    *out = ac_scale_round(x.m, (int16_t)-k, &sat);
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_xf_add(ac_xf a, ac_xf b, ac_xf *out)
{
    ac_u64 ma, mb;
    int32_t d;
    int na, nb;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (a.m == 0) {
        *out = b;
        return AC_OK;
    }
    if (b.m == 0) {
        *out = a;
        return AC_OK;
    }
    if (a.e < b.e) { /* make a the one with the larger exponent */
        ac_xf t = a;
        a = b;
        b = t;
    }
    d = (int32_t)a.e - (int32_t)b.e;
    if (d > 33) {
        /* |b| < 2^(30 + b.e) <= 2^(a.e - 4): below half an ulp of a, and a is
         * normalised, so the rounded sum is a (even after cancellation of
         * the leading bit the error stays under one ulp). */
        *out = a;
        return AC_OK;
    }
    na = a.m < 0;
    nb = b.m < 0;
    ma = ac_u64_shl(u64_of(ac_abs_u(a.m)), (uint8_t)d); /* < 2^63 */
    mb = u64_of(ac_abs_u(b.m));
    if (na == nb) {
        return xf_pack(na, ac_u64_add(ma, mb), b.e, out);
    }
    if (ac_u64_lt(ma, mb)) {
        return xf_pack(nb, ac_u64_sub(mb, ma), b.e, out);
    }
    return xf_pack(na, ac_u64_sub(ma, mb), b.e, out);
}

ac_status ac_xf_neg(ac_xf a, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    out->m = -a.m; /* |m| < 2^30: no overflow */
    out->e = a.e;
    return AC_OK;
}

ac_status ac_xf_sub(ac_xf a, ac_xf b, ac_xf *out)
{
    ac_xf nb;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    (void)ac_xf_neg(b, &nb);
    return ac_xf_add(a, nb, out);
}

ac_status ac_xf_mul(ac_xf a, ac_xf b, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (a.m == 0 || b.m == 0) {
        *out = xf_zero;
        return AC_OK;
    }
    return xf_pack((a.m < 0) != (b.m < 0), ac_mul32u(ac_abs_u(a.m), ac_abs_u(b.m)),
                   (int32_t)a.e + (int32_t)b.e, out);
}

ac_status ac_xf_div(ac_xf a, ac_xf b, ac_xf *out)
{
    uint32_t r, d, q = 0u;
    uint8_t i;
    ac_u64 mag;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (b.m == 0) {
        return AC_ERR_SINGULAR;
    }
    if (a.m == 0) {
        *out = xf_zero;
        return AC_OK;
    }
    r = ac_abs_u(a.m);
    d = ac_abs_u(b.m);
    /* restoring division: q = floor(r * 2^31 / d), r < 2d throughout */
    if (r >= d) {
        q = 1u;
        r -= d;
    }
    for (i = 0u; i < 31u; i++) {
        r <<= 1;
        q <<= 1;
        if (r >= d) {
            r -= d;
            q |= 1u;
        }
    }
    /* q in [2^30, 2^32); a sticky remainder bit makes the final rounding
     * see values just above a tie as above it */
    mag.hi = q >> 31;
    mag.lo = (q << 1) | ((r != 0u) ? 1u : 0u);
    return xf_pack((a.m < 0) != (b.m < 0), mag, (int32_t)a.e - (int32_t)b.e - 32, out);
}

ac_status ac_xf_abs(ac_xf a, ac_xf *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    out->m = (a.m < 0) ? -a.m : a.m;
    out->e = a.e;
    return AC_OK;
}

ac_status ac_xf_cmpabs(ac_xf a, ac_xf b, int8_t *out)
{
    uint32_t ma, mb;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    ma = ac_abs_u(a.m);
    mb = ac_abs_u(b.m);
    if (ma == 0u || mb == 0u) {
        *out = (int8_t)((ma != 0u) - (mb != 0u));
        return AC_OK;
    }
    if (a.e != b.e) {
        *out = (a.e > b.e) ? (int8_t)1 : (int8_t)-1;
        return AC_OK;
    }
    *out = (int8_t)((ma > mb) - (ma < mb));
    return AC_OK;
}

ac_status ac_xf_ldexp(ac_xf x, int16_t k, ac_xf *out)
{
    int32_t e;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (x.m == 0) {
        *out = xf_zero;
        return AC_OK;
    }
    e = (int32_t)x.e + (int32_t)k;
    if (e > XF_EMAX) {
        return AC_ERR_RANGE;
    }
    if (e < XF_EMIN) {
        *out = xf_zero;
        return AC_OK;
    }
    out->m = x.m;
    out->e = (int16_t)e;
    return AC_OK;
}
