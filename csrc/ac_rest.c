/* accelcal -- rest detector (see ac_rest.h) and rate integration with reset on rest. */
#include "accelcal/ac_rest.h"
#include "ac_internal.h"

static ac_status check_cfg(const ac_rest_cfg *c)
{
    if (c->dev_max < 0 || c->alpha_max < 0 || c->ref_max < 0 || c->hold == 0u || c->hold == 65535u ||
        c->ema_shift < 1u || c->ema_shift > 12u || c->g2_lo > c->g2_hi) {
        return AC_ERR_RANGE;
    }
    return AC_OK;
}

/* a threshold (Q.AC_OUT_FRAC, >= 0) in Q.18, saturating */
static uint32_t widen(int32_t t)
{
    return ((uint32_t)t > (UINT32_MAX >> AC_REST_EXTRA_FRAC)) ? UINT32_MAX
                                                               : (uint32_t)t << AC_REST_EXTRA_FRAC;
}

ac_status ac_rest_init(ac_rest *st, const ac_rest_cfg *cfg)
{
    ac_status s;
    if (st == 0 || cfg == 0) {
        return AC_ERR_NULL;
    }
    s = check_cfg(cfg);
    if (s != AC_OK) {
        return s;
    }
    /* field by field: a struct assignment may become a memcpy call (no libc on the H8) */
    st->cfg.dev_max = cfg->dev_max;
    st->cfg.g2_lo = cfg->g2_lo;
    st->cfg.g2_hi = cfg->g2_hi;
    st->cfg.alpha_max = cfg->alpha_max;
    st->cfg.ref_max = cfg->ref_max;
    st->cfg.hold = cfg->hold;
    st->cfg.ema_shift = cfg->ema_shift;
    return ac_rest_reset(st);
}

ac_status ac_rest_reset(ac_rest *st)
{
    if (st == 0) {
        return AC_ERR_NULL;
    }
    st->m[0] = 0;
    st->m[1] = 0;
    st->m[2] = 0;
    st->run = 0u;
    st->started = 0u;
    st->at_rest = 0u;
    return AC_OK;
}

ac_status ac_rest_step(ac_rest *st, const int32_t *f, const int32_t *alpha, uint8_t *flags)
{
    return ac_rest_step_ref(st, f, alpha, 0, flags);
}

ac_status ac_rest_step_ref(ac_rest *st, const int32_t *f, const int32_t *alpha, const int32_t *ref,
                           uint8_t *flags)
{
    uint8_t clip = 0u, quiet = 1u, out = 0u, k, was;
    int32_t x[3];
    uint32_t g2 = 0u, devmax;
    if (st == 0 || f == 0 || flags == 0) {
        return AC_ERR_NULL;
    }
    if (check_cfg(&st->cfg) != AC_OK) {
        return AC_ERR_RANGE; /* not initialised */
    }
    devmax = widen(st->cfg.dev_max);
    for (k = 0u; k < 3u; k++) {
        int16_t c = ac_sat_to16(f[k], &clip);
        uint16_t a = (uint16_t)ac_abs_u((int32_t)c);
        x[k] = (int32_t)c * (int32_t)(1L << AC_REST_EXTRA_FRAC); /* |x| <= 2^23 */
        g2 += ac_mul16u(a, a); /* <= 3 * 2^30: no wrap */
    }
    if (!st->started) {
        st->m[0] = x[0];
        st->m[1] = x[1];
        st->m[2] = x[2];
        st->started = 1u;
    }
    for (k = 0u; k < 3u; k++) {
        int32_t d = x[k] - st->m[k]; /* both within +-2^23 */
        if (ac_abs_u(d) > devmax) {
            quiet = 0u;
        }
        st->m[k] += ac_floor_shift(d, st->cfg.ema_shift);
    }
    if (g2 < st->cfg.g2_lo || g2 > st->cfg.g2_hi) {
        quiet = 0u;
    }
    if (ref != 0) {
        uint32_t refmax = widen(st->cfg.ref_max);
        for (k = 0u; k < 3u; k++) {
            /* |x| <= 2^23; a reference beyond +-2^30 is simply far: saturate */
            uint8_t dummy = 0u;
            if (ac_abs_u(ac_sat_sub(x[k], ref[k], &dummy)) > refmax) {
                quiet = 0u;
            }
        }
    }
    if (alpha != 0) {
        for (k = 0u; k < 3u; k++) {
            if (ac_abs_u(alpha[k]) > (uint32_t)st->cfg.alpha_max) {
                quiet = 0u;
            }
        }
    }
    was = st->at_rest;
    if (quiet) {
        if (st->run < 65535u) {
            st->run++;
        }
        out |= AC_REST_QUIET;
    } else {
        st->run = 0u;
    }
    st->at_rest = (st->run >= st->cfg.hold) ? 1u : 0u;
    if (st->at_rest) {
        out |= AC_REST_AT_REST;
        if (!was) {
            out |= AC_REST_ENTER;
        }
    } else if (was) {
        out |= AC_REST_LEAVE;
    }
    if (clip) {
        out |= AC_REST_CLIP;
    }
    *flags = out;
    return AC_OK;
}

ac_status ac_rest_batch(ac_rest *st, const int32_t *f, const int32_t *alpha, uint32_t count,
                        uint8_t *flags)
{
    uint32_t n;
    if (st == 0 || f == 0 || flags == 0) {
        return AC_ERR_NULL;
    }
    for (n = 0u; n < count; n++) {
        ac_status s = ac_rest_step(st, f, alpha, flags);
        if (s < 0) {
            return s;
        }
        f += 3;
        if (alpha != 0) {
            alpha += 3;
        }
        flags++;
    }
    return AC_OK;
}

ac_status ac_rest_rate_step(ac_rest *rest, ac_rate *rate, const int32_t *f, const int32_t *alpha,
                            int16_t *omega, uint8_t *flags)
{
    ac_status s1, s2;
    if (rest == 0 || rate == 0 || f == 0 || alpha == 0 || omega == 0 || flags == 0) {
        return AC_ERR_NULL;
    }
    s1 = ac_rest_step(rest, f, alpha, flags);
    if (s1 < 0) {
        return s1;
    }
    s2 = ac_rate_step(rate, alpha, omega);
    if (s2 < 0) {
        return s2;
    }
    if (*flags & AC_REST_AT_REST) {
        (void)ac_rate_reset(rate);
        omega[0] = 0;
        omega[1] = 0;
        omega[2] = 0;
        s2 = AC_OK;
    }
    return ac_merge(s1, s2);
}
