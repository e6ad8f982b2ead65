/* accelcal -- ac_mul32x16_shift (ac_fixed.h), in an object of its own: the
 * per-sample estimators and ac_rate_step link it without the rest of ac_fixed. */
#include "accelcal/ac_fixed.h"
#include "ac_internal.h"

/* 1 << n for 0 <= n <= 31, in byte steps (see ac_shr_u). */
static uint32_t ac_pow2_u(uint8_t n)
{
    uint32_t u = (uint32_t)1u << (n & 7u);
    if ((n & 8u) != 0u) {
        u <<= 8;
    }
    if ((n & 16u) != 0u) {
        u <<= 16;
    }
    return u;
}

/* u << n for 0 <= n <= 31, in byte steps (8-bit cores shift one bit a loop). */
static uint32_t shl_u(uint32_t u, uint8_t n)
{
    if ((n & 16u) != 0u) {
        u <<= 16;
    }
    if ((n & 8u) != 0u) {
        u <<= 8;
    }
    return u << (n & 7u);
}

/* The int32 with sign neg and 64-bit magnitude hi 2^32 + lo, clipped to
 * int32 (then AC_SATURATED): the last step of the rounding multiplies. */
ac_status ac_from_sign_mag(int neg, uint32_t hi, uint32_t lo, int32_t *out)
{
    if (hi != 0u || lo > (uint32_t)INT32_MAX + (neg ? 1u : 0u)) {
        *out = neg ? INT32_MIN : INT32_MAX;
        return AC_SATURATED;
    }
    *out = neg ? ac_i_from_u((uint32_t)0u - lo) : (int32_t)lo;
    return AC_OK;
}

ac_status ac_mul32x16_shift(int32_t a, uint16_t b, uint8_t n, int32_t *out)
{
    uint32_t ua, ll, hl, lo, hi, rlo, rhi;
    int neg;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (n > 47u) {
        return AC_ERR_RANGE;
    }
    neg = (a < 0) && (b != 0u);
    ua = ac_abs_u(a);
    /* |a| b = hi 2^32 + lo, hi < 2^16: two 16 x 16 partial products */
    ll = ac_mul16u((uint16_t)(ua & 0xFFFFu), b);
    hl = ac_mul16u((uint16_t)(ua >> 16), b);
    lo = ll + (hl << 16);
    hi = (hl >> 16) + ((lo < ll) ? 1u : 0u);
    if (n == 0u) {
        rlo = lo;
        rhi = hi;
    } else {
        /* + 2^(n-1), less 1 for a negative value: ties go towards +inf */
        if (n <= 32u) {
            uint32_t h = ac_pow2_u((uint8_t)(n - 1u));
            if (neg) {
                h -= 1u;
            }
            lo += h;
            if (lo < h) {
                hi++;
            }
        } else {
            hi += ac_pow2_u((uint8_t)(n - 33u));
            if (neg) {
                if (lo == 0u) {
                    hi--;
                }
                lo--;
            }
        }
        if (n >= 32u) {
            rlo = ac_shr_u(hi, (uint8_t)(n - 32u));
            rhi = 0u;
        } else {
            rlo = ac_shr_u(lo, n) | shl_u(hi, (uint8_t)(32u - n));
            rhi = ac_shr_u(hi, n);
        }
    }
    return ac_from_sign_mag(neg, rhi, rlo, out);
}
