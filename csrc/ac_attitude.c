/* accelcal -- pendulum attitude and rate from two triads (see ac_attitude.h). */
#include "accelcal/ac_attitude.h"
#include "accelcal/ac_trig.h"
#include "ac_internal.h"

/* ---- constants ----------------------------------------------------------------------- */

/* mant 2^-shift = num / den rounded, mant in [2^(bits-1), 2^bits) (bits <= 16). */
static ac_status mant_ratio(uint32_t num, uint32_t den, uint8_t bits, uint16_t *mant, int8_t *shift)
{
    int sh = (int)bits - 1 - ((int)ac_bitlen_u(num) - (int)ac_bitlen_u(den));
    uint8_t tries;
    for (tries = 0u; tries < 3u; tries++) {
        uint32_t q = 0u;
        ac_u64 n;
        uint32_t d = den;
        ac_status s;
        n.hi = 0u;
        n.lo = num;
        if (sh >= 0) {
            if (sh > 62) {
                return AC_ERR_RANGE;
            }
            n = ac_u64_shl(n, (uint8_t)sh);
        } else {
            if ((int)ac_bitlen_u(den) - sh > 32) {
                return AC_ERR_RANGE;
            }
            d = den << (uint8_t)(-sh);
        }
        s = ac_udiv64(n.hi, n.lo, d, &q);
        if (s != AC_OK) {
            return AC_ERR_RANGE;
        }
        if (q < ((uint32_t)1u << (uint8_t)(bits - 1u))) {
            sh++;
        } else if (q >= ((uint32_t)1u << bits)) {
            sh--;
        } else {
            if (sh < -127 || sh > 127) {
                return AC_ERR_RANGE;
            }
            *mant = (uint16_t)q;
            *shift = (int8_t)sh;
            return AC_OK;
        }
    }
    return AC_ERR_RANGE;
}

/* round(|r| 2^14 / rmax) with the given sign, |r| <= rmax <= 2^30 */
static int16_t unit_q14(uint32_t ar, uint32_t rmax, int negative)
{
    uint32_t q = 0u;
    (void)ac_udiv64(ar >> 18, ar << 14, rmax, &q); /* q <= 2^14 */
    if (negative) {
        return (int16_t)(-(int16_t)q);
    }
    return (int16_t)q;
}

ac_status ac_att_init(ac_att *st, int32_t r1, int32_t r2, uint16_t dt_m, uint8_t dt_shift,
                      uint16_t gain_q8, int32_t w2_gate, uint16_t leak)
{
    uint32_t ar1, ar2, rmax, delta, p;
    uint16_t km = 0u, gsm = 0u;
    int8_t ksh = 0, gsh = 0;
    int r2_above;
    ac_status s;
    if (st == 0) {
        return AC_ERR_NULL;
    }
    if (dt_m == 0u || dt_shift < 16u || dt_shift > 46u || w2_gate < 0) {
        return AC_ERR_RANGE;
    }
    ar1 = ac_abs_u(r1);
    ar2 = ac_abs_u(r2);
    if (ar1 > ((uint32_t)1u << 30) || ar2 > ((uint32_t)1u << 30)) {
        return AC_ERR_RANGE;
    }
    if (r1 == r2) {
        return AC_ERR_SINGULAR;
    }
    r2_above = r2 > r1;
    /* |r2 - r1| <= 2^31: exact in uint32 arithmetic */
    delta = r2_above ? (uint32_t)r2 - (uint32_t)r1 : (uint32_t)r1 - (uint32_t)r2;
    rmax = (ar1 > ar2) ? ar1 : ar2;
    if (delta < ((uint32_t)1u << 22) && rmax > (delta << 10)) {
        return AC_ERR_ILL_COND;
    }
    /* theta's x and y use s r_i / rmax, s = sign(r2 - r1) */
    st->cfg.c1 = unit_q14(ar1, rmax, (r1 < 0) == r2_above);
    st->cfg.c2 = unit_q14(ar2, rmax, (r2 < 0) == r2_above);
    /* 1/(r1 - r2) [1/m] = 2^AC_POS_FRAC / (r1 - r2)_q */
    s = mant_ratio((uint32_t)1u << AC_POS_FRAC, delta, 15u, &km, &ksh);
    if (s != AC_OK) {
        return s;
    }
    st->cfg.k_m = (int16_t)km; /* km < 2^15 */
    if (r2_above) {
        st->cfg.k_m = (int16_t)(-st->cfg.k_m);
    }
    st->cfg.k_shift = ksh;
    s = mant_ratio(rmax, delta, 16u, &gsm, &gsh);
    if (s != AC_OK) {
        return s;
    }
    st->cfg.gs_m = gsm;
    st->cfg.gs_shift = gsh;
    st->cfg.dt_m = dt_m;
    st->cfg.dt_shift = dt_shift;
    /* kdt = gain_q8 dt_m, reduced to 16 bits */
    p = ac_mul16u(gain_q8, dt_m);
    if (p == 0u) {
        st->cfg.kdt_m = 0u;
        st->cfg.kdt_shift = 0u;
    } else {
        uint8_t e = ac_bitlen_u(p), sh = 0u;
        uint32_t q = p;
        if (e > 16u) {
            sh = (uint8_t)(e - 16u);
            q = ((p >> (uint8_t)(sh - 1u)) + 1u) >> 1;
            if (q > 65535u) {
                sh++;
                q = ((p >> (uint8_t)(sh - 1u)) + 1u) >> 1;
            }
        }
        st->cfg.kdt_m = (uint16_t)q;
        st->cfg.kdt_shift = (uint8_t)(dt_shift + 2u - sh);
    }
    st->cfg.leak = leak;
    st->cfg.w2_gate = w2_gate;
    return ac_att_reset(st);
}

ac_status ac_att_reset(ac_att *st)
{
    if (st == 0) {
        return AC_ERR_NULL;
    }
    st->w = 0;
    st->a_prev = 0;
    st->started = 0u;
    st->settled = 0u;
    return AC_OK;
}

/* round(P 2^-shift) with P = d * km, |d| <= 65535 and |km| <= 32767 (so |P| < 2^31) */
static int32_t ratio_term(int32_t d, int16_t km, int16_t shift, uint8_t *sat)
{
    uint32_t pm = ac_mul16u((uint16_t)ac_abs_u(d), (uint16_t)ac_abs_u((int32_t)km));
    int32_t p = ((d < 0) != (km < 0)) ? -(int32_t)pm : (int32_t)pm;
    return ac_scale_round(p, shift, sat);
}

ac_status ac_att_step(ac_att *st, const int32_t *f1, const int32_t *f2, ac_att_out *out)
{
    const ac_att_cfg *c;
    uint8_t sat = 0u, flags = 0u, gated;
    int16_t a1x, a1z, a2x, a2z, theta = 0;
    int32_t x, y, dw, w2, inc = 0, wp, w;
    uint32_t mag = 0u;
    int32_t gmag = 0;
    ac_status s;
    if (st == 0 || f1 == 0 || f2 == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    c = &st->cfg;
    if (c->dt_m == 0u || c->dt_shift < 16u || c->dt_shift > 46u || c->k_m == 0) {
        return AC_ERR_RANGE; /* not initialised */
    }
    a1x = ac_sat_to16(f1[0], &sat);
    a1z = ac_sat_to16(f1[2], &sat);
    a2x = ac_sat_to16(f2[0], &sat);
    a2z = ac_sat_to16(f2[2], &sat);

    /* attitude: |c| <= 2^14, |a| <= 2^15 so every product and difference fits int32 */
    y = ac_i_from_u(ac_mac16(ac_mac16(0u, c->c1, a2x), (int16_t)(-c->c2), a1x));
    x = ac_i_from_u(ac_mac16(ac_mac16(0u, c->c2, a1z), (int16_t)(-c->c1), a2z));
    (void)ac_atan2(y, x, &theta, &mag);
    if (x == 0 && y == 0) {
        flags |= AC_ATT_NO_GRAVITY;
    }
    /* |g| = hypot(x, y) max|r| / |r1 - r2| 2^-14 (x, y are Q.24: Q.14 times Q.10) */
    s = ac_mul32x16_shift((int32_t)mag, c->gs_m, (uint8_t)(c->gs_shift + 14), &gmag);
    if (s == AC_SATURATED) {
        sat = 1u;
    }

    /* angular acceleration and squared rate */
    dw = ratio_term((int32_t)a2z - (int32_t)a1z, c->k_m, (int16_t)c->k_shift, &sat);
    w2 = ratio_term((int32_t)a2x - (int32_t)a1x, c->k_m, (int16_t)(c->k_shift - 10), &sat);

    /* predict: trapezoid of alpha (nothing to integrate on the first sample) */
    if (!st->started) {
        st->a_prev = dw;
        st->w = 0;
    } else {
        s = ac_mul32x16_shift(ac_sat_add(st->a_prev, dw, &sat), c->dt_m,
                              (uint8_t)(c->dt_shift + 1u - (AC_ATT_W_FRAC - AC_OUT_FRAC)), &inc);
        if (s == AC_SATURATED) {
            sat = 1u;
        }
    }
    wp = ac_sat_add(st->w, inc, &sat);

    if (w2 < 0) {
        flags |= AC_ATT_W2_NEG;
    }
    gated = (w2 < c->w2_gate) ? 1u : 0u; /* w2_gate >= 0: negative w2 is always gated */
    if (gated) {
        int32_t dec = 0;
        (void)ac_mul32x16_shift(wp, c->leak, 16u, &dec); /* |dec| <= |wp|: no overflow below */
        w = wp - dec;
        /* started in the gated band: sign and size come from the integral of a known
         * small rate (settled); otherwise the sign is now right, the size is re-taken
         * from the measurement when the band is left */
        st->settled = (!st->started || st->settled == 2u) ? 2u : 1u;
        flags |= AC_ATT_GATED;
    } else {
        uint16_t m = 0u;
        uint32_t k;
        int32_t wm;
        (void)ac_isqrt32((uint32_t)w2, &m); /* w2 < 2^31: m <= 46341, no saturation */
        wm = (int32_t)m * (int32_t)(1L << (AC_ATT_W_FRAC - AC_OMEGA_FRAC)); /* Q.20, < 2^26 */
        if (wp < 0) {
            wm = -wm;
            flags |= AC_ATT_SIGN_NEG;
        }
        if (!st->started || st->settled == 1u) {
            k = 65536u; /* first sample, or leaving the band after an unsettled start */
            if (st->started) {
                st->settled = 2u;
            }
        } else if (c->kdt_shift > 32u) {
            k = 0u;
        } else if (c->kdt_shift == 0u) {
            k = (c->kdt_m == 0u) ? 0u : 65536u;
        } else {
            uint32_t q = ac_shr_u(ac_mul16u(m, c->kdt_m), (uint8_t)(c->kdt_shift - 1u));
            k = (q >> 1) + (q & 1u); /* round half up */
            if (k > 65536u) {
                k = 65536u;
            }
        }
        if (k >= 65536u) {
            w = wm;
        } else {
            int32_t corr = 0;
            s = ac_mul32x16_shift(ac_sat_sub(wm, wp, &sat), (uint16_t)k, 16u, &corr);
            if (s == AC_SATURATED) {
                sat = 1u;
            }
            w = ac_sat_add(wp, corr, &sat);
        }
    }
    st->w = w;
    st->a_prev = dw;
    st->started = 1u;
    if (st->settled != 2u) {
        flags |= AC_ATT_UNSETTLED;
    }
    out->theta = theta;
    out->w = ac_sat_to16(ac_scale_round(w, (int16_t)(AC_ATT_W_FRAC - AC_OMEGA_FRAC), &sat), &sat);
    out->dw = dw;
    out->w2 = w2;
    out->gmag = gmag;
    if (sat) {
        flags |= AC_ATT_SAT;
    }
    out->flags = flags;
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_att_batch(ac_att *st, const int32_t *f, uint32_t count, ac_att_out *out)
{
    uint32_t n;
    ac_status all = AC_OK;
    if (st == 0 || f == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    for (n = 0u; n < count; n++) {
        ac_status s = ac_att_step(st, f, f + 3, out);
        if (s < 0) {
            return s;
        }
        all = ac_merge(all, s);
        f += 6;
        out++;
    }
    return all;
}
