/*
 * accelcal -- extended-range numbers (mantissa 2^29 <= |m| < 2^30, exponent):
 * the pointer-based core (ac_xf_core.h).  A value is handled as sign + 64-bit
 * magnitude + exponent and rounded once, to nearest with ties away from zero,
 * when it is packed.
 */
#include "ac_xf_core.h"
#include "ac_internal.h"

#define XF_HI 0x40000000UL /* 2^30 */
#define XF_EMAX 30000L
#define XF_EMIN (-30000L)

static int bad(const ac_xf *x)
{
    return x->e == AC_XF_BAD;
}

static void set_bad(ac_xf *r)
{
    r->m = 0;
    r->e = AC_XF_BAD;
}

/* r = (neg ? -1 : 1) * mag * 2^e, normalised */
static void pack(ac_xf *r, int neg, ac_u64 mag, int32_t e)
{
    uint8_t len;
    if (mag.hi == 0u && mag.lo == 0u) {
        r->m = 0;
        r->e = 0;
        return;
    }
    len = (mag.hi != 0u) ? (uint8_t)(32u + ac_bitlen_u(mag.hi)) : ac_bitlen_u(mag.lo);
    if (len > 30u) {
        uint8_t k = (uint8_t)(len - 30u);
        /* ties away from zero: floor((mag + 2^(k-1)) / 2^k) = floor((floor(mag / 2^(k-1)) + 1) / 2),
         * the shifted value < 2^31 (one 64-bit shift and no 64-bit add) */
        uint32_t t = (k > 1u) ? ac_u64_shr(mag, (uint8_t)(k - 1u)).lo : mag.lo;
        mag.lo = (t >> 1) + (t & 1u); /* (mag.hi is not read again) */
        e += (int32_t)k;
        if (mag.lo >= XF_HI) { /* rounding carried into a new bit */
            mag.lo >>= 1;
            e += 1;
        }
    } else {
        uint8_t k = (uint8_t)(30u - len);
        mag.lo <<= k;
        e -= (int32_t)k;
    }
    if (e > XF_EMAX) {
        set_bad(r);
        return;
    }
    if (e < XF_EMIN) { /* underflow: flush to zero */
        r->m = 0;
        r->e = 0;
        return;
    }
    r->m = neg ? -(int32_t)mag.lo : (int32_t)mag.lo;
    r->e = (int16_t)e;
}

static ac_u64 u64_of(uint32_t v)
{
    ac_u64 r;
    r.hi = 0u;
    r.lo = v;
    return r;
}

void ac_xfp_normalize(ac_xf *x)
{
    uint32_t m = ac_abs_u(x->m);
    /* zero and normalised values pass unchanged (whatever their exponent) */
    if (!bad(x) && m != 0u && (m < 0x20000000UL || m >= XF_HI)) {
        pack(x, x->m < 0, u64_of(m), (int32_t)x->e);
    }
}

void ac_xfp_from_fixed(ac_xf *r, int32_t v, int16_t frac)
{
    pack(r, v < 0, u64_of(ac_abs_u(v)), -(int32_t)frac);
}

ac_status ac_xfp_to_fixed(const ac_xf *x, int16_t frac, int32_t *out)
{
    uint8_t sat = 0u;
    int32_t k;
    if (bad(x)) {
        return AC_ERR_RANGE;
    }
    if (x->m == 0) {
        *out = 0;
        return AC_OK;
    }
    k = (int32_t)x->e + (int32_t)frac; /* value * 2^frac = m * 2^k */
    if (k > 31) {
        *out = (x->m > 0) ? INT32_MAX : INT32_MIN;
        return AC_SATURATED;
    }
    if (k < -31) {
        *out = 0; /* |m| * 2^k < 2^-1 */
        return AC_OK;
    }
    *out = ac_scale_round(x->m, (int16_t)-k, &sat);
    return sat ? AC_SATURATED : AC_OK;
}

static void add_signed(ac_xf *r, const ac_xf *a, const ac_xf *b, int negate_b)
{
    const ac_xf *big = a, *small = b;
    int nbig, nsmall;
    int32_t d;
    ac_u64 mb, ms;
    if (bad(a) || bad(b)) {
        set_bad(r);
        return;
    }
    if (b->m == 0) {
        *r = *a;
        return;
    }
    if (a->m == 0) {
        r->e = b->e;
        r->m = negate_b ? -b->m : b->m;
        return;
    }
    nbig = a->m < 0;
    nsmall = (b->m < 0) != (negate_b != 0);
    if (a->e < b->e) { /* big = the operand with the larger exponent */
        int t = nbig;
        big = b;
        small = a;
        nbig = nsmall;
        nsmall = t;
    }
    d = (int32_t)big->e - (int32_t)small->e;
    if (d > 33) {
        /* |small| < 2^(big.e - 4): below an eighth of big's ulp, and big is
         * normalised, so the rounded sum is big */
        r->e = big->e;
        r->m = nbig ? -(int32_t)ac_abs_u(big->m) : (int32_t)ac_abs_u(big->m);
        return;
    }
    mb = ac_u64_shl(u64_of(ac_abs_u(big->m)), (uint8_t)d); /* < 2^63 */
    ms = u64_of(ac_abs_u(small->m));
    if (nbig == nsmall) {
        pack(r, nbig, ac_u64_add(mb, ms), small->e);
    } else if (ac_u64_lt(mb, ms)) {
        pack(r, nsmall, ac_u64_sub(ms, mb), small->e);
    } else {
        pack(r, nbig, ac_u64_sub(mb, ms), small->e);
    }
}

void ac_xfp_add(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    add_signed(r, a, b, 0);
}

void ac_xfp_sub(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    add_signed(r, a, b, 1);
}

void ac_xfp_mul(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    if (bad(a) || bad(b)) {
        set_bad(r);
        return;
    }
    if (a->m == 0 || b->m == 0) {
        r->m = 0;
        r->e = 0;
        return;
    }
    pack(r, (a->m < 0) != (b->m < 0), ac_mul32u(ac_abs_u(a->m), ac_abs_u(b->m)),
         (int32_t)a->e + (int32_t)b->e);
}

void ac_xfp_mac(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    ac_xf p;
    ac_xfp_mul(&p, a, b);
    ac_xfp_add(r, r, &p);
}

void ac_xfp_div(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    uint32_t rem, d, q = 0u;
    uint8_t i;
    ac_u64 mag;
    if (bad(a) || bad(b) || b->m == 0) {
        set_bad(r);
        return;
    }
    if (a->m == 0) {
        r->m = 0;
        r->e = 0;
        return;
    }
    rem = ac_abs_u(a->m);
    d = ac_abs_u(b->m);
    /* restoring division: q = floor(rem * 2^31 / d); rem < 2d throughout */
    if (rem >= d) {
        q = 1u;
        rem -= d;
    }
    for (i = 0u; i < 31u; i++) {
        rem <<= 1;
        q <<= 1;
        if (rem >= d) {
            rem -= d;
            q |= 1u;
        }
    }
    /* q in [2^30, 2^32); a sticky remainder bit makes the final rounding see
     * values just above a tie as above it */
    mag.hi = q >> 31;
    mag.lo = (q << 1) | ((rem != 0u) ? 1u : 0u);
    pack(r, (a->m < 0) != (b->m < 0), mag, (int32_t)a->e - (int32_t)b->e - 32);
}

void ac_xfp_ldexp(ac_xf *r, int16_t k)
{
    int32_t e;
    if (bad(r) || r->m == 0) {
        return;
    }
    e = (int32_t)r->e + (int32_t)k;
    if (e > XF_EMAX) {
        set_bad(r);
    } else if (e < XF_EMIN) {
        r->m = 0;
        r->e = 0;
    } else {
        r->e = (int16_t)e;
    }
}

int8_t ac_xfp_cmpabs(const ac_xf *a, const ac_xf *b)
{
    uint32_t ma = ac_abs_u(a->m), mb = ac_abs_u(b->m);
    if (ma == 0u || mb == 0u) {
        return (int8_t)((ma != 0u) - (mb != 0u));
    }
    if (a->e != b->e) {
        return (a->e > b->e) ? (int8_t)1 : (int8_t)-1;
    }
    return (int8_t)((ma > mb) - (ma < mb));
}

void ac_xfp_acc_abs(ac_xf *max, ac_xf *sum, const ac_xf *v)
{
    ac_xf av = *v;
    if (av.m < 0) {
        av.m = -av.m; /* normalised: |m| < 2^30 */
    }
    if (bad(v)) {
        set_bad(max);
    } else if (ac_xfp_cmpabs(&av, max) > 0) {
        *max = av;
    }
    if (sum != 0) {
        ac_xfp_add(sum, sum, &av);
    }
}
