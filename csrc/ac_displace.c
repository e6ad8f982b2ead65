/* accelcal -- streaming stop-to-stop displacement (see ac_displace.h). */
#include "accelcal/ac_displace.h"
#include "accelcal/ac_trig.h"
#include "ac_internal.h"

#define PHASE_WAIT 0u
#define PHASE_REST 1u
#define PHASE_MOVING 2u

/* ---- frame of the first rest ------------------------------------------------------ */

/* round(h 2^14 / den) with a sign; h <= 2^15, h <= den (result <= 2^14) */
static int16_t ratio_q14(uint32_t h, int negative, uint32_t den)
{
    uint32_t q = 0u;
    (void)ac_udiv64(0u, h << 14, den, &q);
    if (negative) {
        return (int16_t)(-(int16_t)q);
    }
    return (int16_t)q;
}

/* round(a b 2^-14) for |a|, |b| <= 2^14 */
static int16_t mul_q14(int16_t a, int16_t b)
{
    uint8_t sat = 0u;
    return (int16_t)ac_scale_round((int32_t)a * (int32_t)b, 14, &sat);
}

ac_status ac_tilt_frame(const int32_t *g, int16_t rot[3][3])
{
    uint32_t h[3], mx = 0u, n2 = 0u;
    int neg[3];
    uint16_t n = 0u;
    uint8_t k, e;
    int16_t u[3];
    if (g == 0 || rot == 0) {
        return AC_ERR_NULL;
    }
    for (k = 0u; k < 3u; k++) {
        h[k] = ac_abs_u(g[k]);
        neg[k] = g[k] < 0;
        if (h[k] > mx) {
            mx = h[k];
        }
    }
    if (mx == 0u) {
        return AC_ERR_SINGULAR;
    }
    /* scale to 15 bits (max in [2^14, 2^15], rounded): squares sum below 2^32 */
    e = ac_bitlen_u(mx);
    for (k = 0u; k < 3u; k++) {
        if (e > 15u) {
            uint8_t sh = (uint8_t)(e - 15u);
            h[k] = ((h[k] >> (uint8_t)(sh - 1u)) + 1u) >> 1;
        } else {
            h[k] <<= (uint8_t)(15u - e);
        }
        n2 += ac_mul16u((uint16_t)h[k], (uint16_t)h[k]);
    }
    (void)ac_isqrt32(n2, &n); /* >= 2^14 */
    for (k = 0u; k < 3u; k++) {
        u[k] = ratio_q14(h[k], neg[k], n);
        rot[2][k] = u[k];
    }
    {
        uint32_t yz2 = ac_mul16u((uint16_t)h[1], (uint16_t)h[1]) + ac_mul16u((uint16_t)h[2], (uint16_t)h[2]);
        if (yz2 >= (n2 >> 2)) {
            /* x of the frame = body x projected: rho = |(h_y, h_z)| / n */
            uint16_t rh = 0u;
            int16_t qy, qz;
            (void)ac_isqrt32(yz2, &rh);
            qy = ratio_q14(h[1], neg[1], rh);
            qz = ratio_q14(h[2], neg[2], rh);
            rot[0][0] = ratio_q14(rh, 0, n);
            rot[0][1] = (int16_t)(-mul_q14(u[0], qy));
            rot[0][2] = (int16_t)(-mul_q14(u[0], qz));
            rot[1][0] = 0;
            rot[1][1] = qz;
            rot[1][2] = (int16_t)(-qy);
        } else {
            /* body x near vertical: y of the frame = body y projected */
            uint32_t xz2 = ac_mul16u((uint16_t)h[0], (uint16_t)h[0]) + ac_mul16u((uint16_t)h[2], (uint16_t)h[2]);
            uint16_t sh = 0u;
            int16_t qx, qz;
            (void)ac_isqrt32(xz2, &sh);
            qx = ratio_q14(h[0], neg[0], sh);
            qz = ratio_q14(h[2], neg[2], sh);
            rot[0][0] = qz;
            rot[0][1] = 0;
            rot[0][2] = (int16_t)(-qx);
            rot[1][0] = (int16_t)(-mul_q14(u[1], qx));
            rot[1][1] = ratio_q14(sh, 0, n);
            rot[1][2] = (int16_t)(-mul_q14(u[1], qz));
        }
    }
    return AC_OK;
}

/* ---- state ------------------------------------------------------------------------------ */

ac_status ac_disp_init(ac_disp *st, const ac_disp_cfg *cfg)
{
    ac_status s;
    if (st == 0 || cfg == 0) {
        return AC_ERR_NULL;
    }
    if (cfg->dt_m == 0u || cfg->dt_shift < 16u || cfg->dt_shift > 46u || cfg->axis < -1 ||
        cfg->axis > 2) {
        return AC_ERR_RANGE;
    }
    s = ac_rest_init(&st->rest, &cfg->rest);
    if (s != AC_OK) {
        return s;
    }
    /* field by field (a struct copy may call memcpy, absent on the H8) */
    st->cfg.rest.dev_max = cfg->rest.dev_max;
    st->cfg.rest.g2_lo = cfg->rest.g2_lo;
    st->cfg.rest.g2_hi = cfg->rest.g2_hi;
    st->cfg.rest.alpha_max = cfg->rest.alpha_max;
    st->cfg.rest.ref_max = cfg->rest.ref_max;
    st->cfg.rest.hold = cfg->rest.hold;
    st->cfg.rest.ema_shift = cfg->rest.ema_shift;
    st->cfg.dt_m = cfg->dt_m;
    st->cfg.dt_shift = cfg->dt_shift;
    st->cfg.axis = cfg->axis;
    return ac_disp_reset(st);
}

ac_status ac_disp_reset(ac_disp *st)
{
    uint8_t k, j;
    if (st == 0) {
        return AC_ERR_NULL;
    }
    (void)ac_rest_reset(&st->rest);
    for (k = 0u; k < 3u; k++) {
        st->gsum[k] = 0;
        st->g[k] = 0;
        st->gref[k] = 0;
        st->c[k] = 0;
        st->a_prev[k] = 0;
        st->v[k] = 0;
        st->p[k] = 0;
        st->f_prev[k] = 0;
        for (j = 0u; j < 3u; j++) {
            st->rot[k][j] = (int16_t)((k == j) ? (1 << AC_DISP_ROT_FRAC) : 0);
        }
    }
    st->gcount = 0u;
    st->nseg = 0u;
    st->phase = PHASE_WAIT;
    st->have_ref = 0u;
    st->long_seg = 0u;
    return AC_OK;
}

/* a (Q.16) of a clipped sample */
static void accel(const ac_disp *st, const int16_t *fc, int32_t *a, uint8_t *sat)
{
    uint8_t j;
    if (st->cfg.axis >= 0) {
        for (j = 0u; j < 3u; j++) {
            a[j] = 0;
        }
        a[(uint8_t)st->cfg.axis] = (int32_t)fc[(uint8_t)st->cfg.axis] * (int32_t)(1L << (AC_DISP_A_FRAC - AC_OUT_FRAC));
        return;
    }
    for (j = 0u; j < 3u; j++) {
        /* |rot| <= 2^14, |fc| <= 2^15: the sum of three stays below 3 * 2^29 */
        int32_t acc = ac_i_from_u(
            ac_mac16(ac_mac16(ac_mac16(0u, st->rot[j][0], fc[0]), st->rot[j][1], fc[1]), st->rot[j][2], fc[2]));
        acc = ac_scale_round(acc, (int16_t)(AC_DISP_ROT_FRAC + AC_OUT_FRAC - AC_DISP_A_FRAC), sat);
        a[j] = ac_sat_sub(acc, st->c[j], sat);
    }
}

/* g = round(gsum 2^6 / count) (Q.16) and the rest reference; 3-axis: R, c = round(R g 2^-14) */
static ac_status set_reference(ac_disp *st)
{
    uint8_t j, k;
    ac_status s;
    for (k = 0u; k < 3u; k++) {
        uint32_t a = ac_abs_u(st->gsum[k]), q = 0u; /* |gsum| < 2^27 */
        (void)ac_udiv64(a >> 26, a << 6, st->gcount, &q);
        st->g[k] = (st->gsum[k] < 0) ? -(int32_t)q : (int32_t)q;
        st->gref[k] = st->g[k] * 4; /* |g| < 2^22: exact */
    }
    if (st->cfg.axis >= 0) {
        return AC_OK;
    }
    s = ac_tilt_frame(st->g, st->rot);
    if (s != AC_OK) {
        return s;
    }
    for (j = 0u; j < 3u; j++) {
        /* exact: g = gh 2^8 + gl, 0 <= gl < 2^8, |gh| < 2^14 */
        int32_t sh = 0, sl = 0;
        for (k = 0u; k < 3u; k++) {
            int32_t gh = ac_floor_shift(st->g[k], 8u);
            int32_t gl = st->g[k] - gh * 256;
            sh += (int32_t)st->rot[j][k] * (int32_t)(int16_t)gh;
            sl += (int32_t)st->rot[j][k] * (int32_t)(int16_t)gl; /* 0 <= gl < 2^8: 16 x 16 bits */
        }
        st->c[j] = ac_floor_shift(sh + ac_floor_shift(sl + (int32_t)8192, 8u), 6u);
    }
    return AC_OK;
}

static void out_state(const ac_disp *st, ac_disp_out *out, uint16_t flags)
{
    uint8_t k;
    for (k = 0u; k < 3u; k++) {
        out->v[k] = st->v[k];
        out->p[k] = st->p[k];
        out->zp[k] = 0;
    }
    out->nseg = st->nseg;
    out->flags = flags;
    out->rest = 0u;
}

/* one trapezoid step of v and p with the new acceleration a */
static void integrate(ac_disp *st, const int32_t *a, uint8_t *sat)
{
    uint8_t k;
    for (k = 0u; k < 3u; k++) {
        int32_t dv = 0, dp = 0, v;
        if (ac_mul32x16_shift(ac_sat_add(st->a_prev[k], a[k], sat), st->cfg.dt_m,
                              (uint8_t)(st->cfg.dt_shift + 1u - (AC_DISP_V_FRAC - AC_DISP_A_FRAC)), &dv) ==
            AC_SATURATED) {
            *sat = 1u;
        }
        v = ac_sat_add(st->v[k], dv, sat);
        if (ac_mul32x16_shift(ac_sat_add(st->v[k], v, sat), st->cfg.dt_m,
                              (uint8_t)(st->cfg.dt_shift + 1u + (AC_DISP_V_FRAC - AC_DISP_P_FRAC)), &dp) ==
            AC_SATURATED) {
            *sat = 1u;
        }
        st->v[k] = v;
        st->p[k] = ac_sat_add(st->p[k], dp, sat);
        st->a_prev[k] = a[k];
    }
}

/* the seed's correction at the end of a motion: p -= v T / 2, zp = v / T, v = 0 */
static uint16_t end_segment(ac_disp *st, int32_t *zp, uint8_t *sat)
{
    uint32_t tq;
    uint8_t k;
    uint16_t flags = AC_DISP_SEG_END;
    /* T = nseg dt in Q.16 s; dt_shift - 16 in 0..30 */
    tq = ac_mul16u(st->nseg, st->cfg.dt_m);
    if (st->cfg.dt_shift > 16u) {
        uint8_t sh = (uint8_t)(st->cfg.dt_shift - 16u);
        tq = ((tq >> (uint8_t)(sh - 1u)) + 1u) >> 1;
    }
    if (st->long_seg || tq == 0u || tq > (uint32_t)INT32_MAX) {
        flags |= AC_DISP_LONG;
        for (k = 0u; k < 3u; k++) {
            zp[k] = 0;
            st->v[k] = 0;
        }
        return flags;
    }
    for (k = 0u; k < 3u; k++) {
        int32_t half = 0;
        uint32_t av = ac_abs_u(st->v[k]), q = 0u;
        if (ac_mul32_shift(st->v[k], (int32_t)tq, (uint8_t)(AC_DISP_V_FRAC + 16 + 1 - AC_DISP_P_FRAC), &half) ==
            AC_SATURATED) {
            *sat = 1u;
        }
        st->p[k] = ac_sat_sub(st->p[k], half, sat);
        /* zp = v / T: Q.24 / Q.16 -> Q.16 needs 2^8 more */
        if (ac_udiv64(av >> 24, av << 8, tq, &q) == AC_SATURATED || q > (uint32_t)INT32_MAX) {
            q = (uint32_t)INT32_MAX;
            *sat = 1u;
        }
        zp[k] = (st->v[k] < 0) ? -(int32_t)q : (int32_t)q;
        st->v[k] = 0;
    }
    return flags;
}

ac_status ac_disp_step(ac_disp *st, const int32_t *f, ac_disp_out *out)
{
    uint8_t rf = 0u, sat = 0u, k;
    uint16_t flags = 0u;
    int16_t fc[3];
    int32_t a[3];
    ac_status s;
    int zp_set = 0;
    int32_t zp[3];
    /* element by element: h8300-hms-gcc 3.4.6 at -Os turns the initialiser
     * {0, 0, 0} into a call to memset, which firmware does not have */
    zp[0] = 0;
    zp[1] = 0;
    zp[2] = 0;
    if (st == 0 || f == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    if (st->cfg.dt_m == 0u || st->cfg.dt_shift < 16u || st->cfg.dt_shift > 46u) {
        return AC_ERR_RANGE; /* not initialised */
    }
    s = ac_rest_step_ref(&st->rest, f, 0, st->have_ref ? st->gref : 0, &rf);
    if (s < 0) {
        return s;
    }
    for (k = 0u; k < 3u; k++) {
        fc[k] = ac_sat_to16(f[k], &sat);
    }
    if (st->phase != PHASE_MOVING && !st->have_ref) {
        /* the first rest (or the run of quiet samples that may become it): sum f */
        if (rf & AC_REST_QUIET) {
            if (st->gcount < AC_DISP_GSUM_MAX) {
                for (k = 0u; k < 3u; k++) {
                    st->gsum[k] += fc[k];
                }
                st->gcount++;
            }
        } else if (st->phase == PHASE_WAIT) {
            st->gsum[0] = st->gsum[1] = st->gsum[2] = 0;
            st->gcount = 0u;
        }
    }
    switch (st->phase) {
    case PHASE_WAIT:
        if (rf & AC_REST_AT_REST) {
            st->phase = PHASE_REST;
            flags |= AC_DISP_REST;
        } else {
            flags |= AC_DISP_NO_REF;
        }
        break;
    case PHASE_REST:
        if (rf & AC_REST_AT_REST) {
            flags |= AC_DISP_REST;
            break;
        }
        /* motion starts: integrate from the previous (rest) sample */
        if (!st->have_ref) {
            if (set_reference(st) != AC_OK) {
                st->phase = PHASE_WAIT;
                st->gsum[0] = st->gsum[1] = st->gsum[2] = 0;
                st->gcount = 0u;
                flags |= AC_DISP_NO_REF | AC_DISP_BAD_REF;
                break;
            }
            st->have_ref = 1u;
            flags |= AC_DISP_REF_SET;
        }
        accel(st, st->f_prev, st->a_prev, &sat);
        for (k = 0u; k < 3u; k++) {
            st->v[k] = 0;
        }
        st->nseg = 0u;
        st->long_seg = 0u;
        st->phase = PHASE_MOVING;
        /* fall through */
    case PHASE_MOVING:
    default:
        accel(st, fc, a, &sat);
        integrate(st, a, &sat);
        if (st->nseg == 65535u) {
            st->long_seg = 1u;
        } else {
            st->nseg++;
        }
        if (rf & AC_REST_AT_REST) {
            flags |= end_segment(st, zp, &sat) | AC_DISP_REST;
            zp_set = 1;
            st->phase = PHASE_REST;
        } else {
            flags |= AC_DISP_MOVING;
        }
        break;
    }
    for (k = 0u; k < 3u; k++) {
        st->f_prev[k] = fc[k];
    }
    if (sat || (rf & AC_REST_CLIP)) {
        flags |= AC_DISP_SAT;
    }
    out_state(st, out, flags);
    out->rest = rf;
    if (zp_set) {
        for (k = 0u; k < 3u; k++) {
            out->zp[k] = zp[k];
        }
    }
    return (flags & AC_DISP_SAT) ? AC_SATURATED : AC_OK;
}

ac_status ac_disp_finish(const ac_disp *st, ac_disp_out *out)
{
    uint16_t flags = 0u;
    if (st == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    if (st->phase == PHASE_MOVING) {
        flags |= AC_DISP_OPEN | AC_DISP_MOVING;
    } else if (st->phase == PHASE_WAIT) {
        flags |= AC_DISP_NO_REST | AC_DISP_NO_REF;
    } else {
        flags |= AC_DISP_REST;
    }
    out_state(st, out, flags);
    return AC_OK;
}

ac_status ac_disp_batch(ac_disp *st, const int32_t *f, uint32_t count, ac_disp_out *out)
{
    uint32_t n;
    ac_status all = AC_OK;
    if (st == 0 || f == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    for (n = 0u; n < count; n++) {
        ac_status s = ac_disp_step(st, f, out);
        if (s < 0) {
            return s;
        }
        all = ac_merge(all, s);
        f += 3;
        out++;
    }
    return all;
}
