/* accelcal -- integer square root, division and CORDIC atan2. */
#include "accelcal/ac_trig.h"
#include "ac_internal.h"

/* round(atan(2^-i) 2^28), i = 0..27 */
static const int32_t atan_q28[28] = {
    210828714L, 124459457L, 65760959L, 33381290L, 16755422L, 8385879L, 4193963L,
    2097109L,   1048571L,   524287L,   262144L,   131072L,   65536L,   32768L,
    16384L,     8192L,      4096L,     2048L,     1024L,     512L,     256L,
    128L,       64L,        32L,       16L,       8L,        4L,       2L};

/* round(2^16 / K), K = prod sqrt(1 + 2^-2i) the CORDIC gain (same value for 12..28 rotations) */
#define AC_CORDIC_INVK_Q16 39797u
#define AC_HALF_PI_Q28 421657428L

ac_status ac_isqrt32(uint32_t v, uint16_t *out)
{
    uint32_t rem = v, root = 0u, bit = (uint32_t)1u << 30;
    if (out == 0) {
        return AC_ERR_NULL;
    }
    if (v > 4294901760UL) { /* round(sqrt(v)) = 65536 */
        *out = 65535u;
        return AC_SATURATED;
    }
    while (bit > rem) {
        bit >>= 2;
    }
    while (bit != 0u) {
        if (rem >= root + bit) {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    /* root = floor(sqrt(v)), rem = v - root^2; round up iff v > root^2 + root */
    if (rem > root) {
        root++;
    }
    *out = (uint16_t)root;
    return AC_OK;
}

/* floor(num / den) and the remainder; requires num_hi < den (quotient < 2^32). */
static uint32_t udiv_floor(uint32_t num_hi, uint32_t num_lo, uint32_t den, uint32_t *rem_out)
{
    uint32_t rem = num_hi, q = 0u;
    uint8_t i;
    for (i = 0u; i < 32u; i++) {
        uint32_t carry = rem >> 31;
        rem = (rem << 1) | (num_lo >> 31);
        num_lo <<= 1;
        q <<= 1;
        if (carry != 0u || rem >= den) {
            rem -= den; /* modulo 2^32 this is right also when carry is set */
            q |= 1u;
        }
    }
    *rem_out = rem;
    return q;
}

ac_status ac_udiv64(uint32_t num_hi, uint32_t num_lo, uint32_t den, uint32_t *q)
{
    uint32_t quot, rem;
    if (q == 0) {
        return AC_ERR_NULL;
    }
    if (den == 0u) {
        return AC_ERR_RANGE;
    }
    if (num_hi >= den) {
        *q = UINT32_MAX;
        return AC_SATURATED;
    }
    quot = udiv_floor(num_hi, num_lo, den, &rem);
    if (rem >= den - rem) { /* 2 rem >= den: round half up */
        if (quot == UINT32_MAX) {
            *q = UINT32_MAX;
            return AC_SATURATED;
        }
        quot++;
    }
    *q = quot;
    return AC_OK;
}

/* |a| b exactly as a 48-bit value (two 16 x 16 partial products). */
static ac_u64 mul_u32_u16(uint32_t a, uint16_t b)
{
    uint32_t ll = ac_mul16u((uint16_t)(a & 0xFFFFu), b);
    uint32_t hl = ac_mul16u((uint16_t)(a >> 16), b);
    ac_u64 r;
    r.lo = ll + (hl << 16);
    r.hi = (hl >> 16) + ((r.lo < ll) ? 1u : 0u);
    return r;
}

ac_status ac_atan2(int32_t y, int32_t x, int16_t *angle, uint32_t *mag)
{
    uint32_t ax = ac_abs_u(x), ay = ac_abs_u(y), mx;
    int32_t cx, cy, z = 0;
    uint8_t e, i, sat = 0u, rotated = 1u;
    int8_t k;
    if (angle == 0) {
        return AC_ERR_NULL;
    }
    if (ax == 0u && ay == 0u) {
        *angle = 0;
        if (mag != 0) {
            *mag = 0u;
        }
        return AC_OK;
    }
    /* normalise max(|x|, |y|) to [2^28, 2^29): x grows by at most K sqrt 2 < 2.33 */
    mx = (ax > ay) ? ax : ay;
    e = ac_bitlen_u(mx);
    k = (int8_t)(29 - (int)e);
    if (k < 0) {
        ax >>= (uint8_t)(-k);
        ay >>= (uint8_t)(-k);
    } else {
        ax <<= (uint8_t)k;
        ay <<= (uint8_t)k;
    }
    cx = (int32_t)ax;
    cy = (int32_t)ay;
    if (cy == 0) {
        rotated = 0u; /* on the x axis: angle 0, magnitude x */
    } else if (cx == 0) {
        rotated = 0u; /* on the y axis: angle pi/2, magnitude y */
        z = AC_HALF_PI_Q28;
        cx = cy;
    } else {
        for (i = 0u; i < (uint8_t)AC_ATAN2_ITERS; i++) {
            int32_t dx = ac_floor_shift(cy, i);
            int32_t dy = (int32_t)ac_shr_u((uint32_t)cx, i); /* cx > 0 throughout */
            if (cy > 0) {
                cx += dx;
                cy -= dy;
                z += atan_q28[i];
            } else {
                cx -= dx;
                cy += dy;
                z -= atan_q28[i];
            }
        }
    }
    if (x < 0) {
        z = AC_PI_Q28 - z;
    }
    if (y < 0) {
        z = -z;
    }
    *angle = ac_sat_to16(ac_scale_round(z, (int16_t)(28 - AC_ANGLE_FRAC), &sat), &sat);
    if (mag != 0) {
        ac_u64 m;
        int sh;
        if (rotated) {
            m = mul_u32_u16((uint32_t)cx, (uint16_t)AC_CORDIC_INVK_Q16); /* x_N / K */
            sh = 16 + k;
        } else {
            m.hi = 0u;
            m.lo = (uint32_t)cx;
            sh = k;
        }
        /* undo the normalisation: value * 2^-sh, rounded half up (sh >= -3) */
        if (sh > 0) {
            ac_u64 one = {0u, 1u};
            m = ac_u64_add(m, ac_u64_shl(one, (uint8_t)(sh - 1)));
            m = ac_u64_shr(m, (uint8_t)sh);
        } else if (sh < 0) {
            m = ac_u64_shl(m, (uint8_t)(-sh));
        }
        *mag = (m.hi != 0u) ? UINT32_MAX : m.lo;
    }
    return sat ? AC_SATURATED : AC_OK;
}
