/* accelcal -- fixed-point primitives (status-returning public wrappers). */
#include "accelcal/ac_fixed.h"
#include "ac_internal.h"

ac_status ac_sat16(int32_t v, int16_t *out)
{
    uint8_t sat = 0u;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    *out = ac_sat_to16(v, &sat);
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_add32_sat(int32_t a, int32_t b, int32_t *out)
{
    uint8_t sat = 0u;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    *out = ac_sat_add(a, b, &sat);
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_asr32(int32_t v, uint8_t n, int32_t *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (n > 31u) {
        return AC_ERR_RANGE;
    }
    *out = ac_floor_shift(v, n);
    return AC_OK;
}

ac_status ac_scale_round32(int32_t v, int16_t shift, int32_t *out)
{
    uint8_t sat = 0u;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    *out = ac_scale_round(v, shift, &sat);
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_u32_to_i32(uint32_t u, int32_t *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    *out = ac_i_from_u(u);
    return AC_OK;
}

/* signed product as two's complement halves */
static ac_i64 mul_signed(int32_t a, int32_t b)
{
    ac_u64 m = ac_mul32u(ac_abs_u(a), ac_abs_u(b));
    ac_i64 r;
    if ((a < 0) != (b < 0)) {
        /* two's complement negation of the 64-bit magnitude */
        uint32_t carry = (m.lo == 0u) ? 1u : 0u; /* -x = ~x + 1, carried into hi */
        m.lo = ~m.lo + 1u;
        m.hi = ~m.hi + carry;
    }
    r.hi = ac_i_from_u(m.hi);
    r.lo = m.lo;
    return r;
}

ac_status ac_mul32x32(int32_t a, int32_t b, ac_i64 *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    *out = mul_signed(a, b);
    return AC_OK;
}

ac_status ac_mul32_shift(int32_t a, int32_t b, uint8_t n, int32_t *out)
{
    ac_u64 m;
    int neg;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (n > 62u) {
        return AC_ERR_RANGE;
    }
    neg = ((a < 0) != (b < 0)) && a != 0 && b != 0;
    m = ac_mul32u(ac_abs_u(a), ac_abs_u(b));
    /* Round half up on the signed value: for a positive product add 2^(n-1)
     * then floor; for a negative one, -floor((|p| - 2^(n-1)) / 2^n) rounded
     * towards zero, i.e. floor((|p| - 2^(n-1)) / 2^n) with ties going up. */
    if (n > 0u) {
        ac_u64 one = {0u, 1u};
        ac_u64 half = ac_u64_shl(one, (uint8_t)(n - 1u));
        if (!neg) {
            m = ac_u64_add(m, half);
            m = ac_u64_shr(m, n);
        } else {
            /* value = -|p| / 2^n; round half up = -floor(|p|/2^n + 1/2 - eps)
             * = -floor((|p| + 2^(n-1) - 1) / 2^n) */
            m = ac_u64_add(m, half);
            m = ac_u64_sub(m, one);
            m = ac_u64_shr(m, n);
        }
    }
    /* m is now the magnitude of the result */
    return ac_from_sign_mag(neg, m.hi, m.lo, out);
}

ac_status ac_bitlen32(int32_t v, uint8_t *out)
{
    if (out == 0) {
        return AC_ERR_NULL;
    }
    *out = ac_bitlen_u(ac_abs_u(v));
    return AC_OK;
}
