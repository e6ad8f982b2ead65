/* accelcal -- the array's own angular rate (see ac_omega.h for the arithmetic). */
#include "accelcal/ac_omega.h"
#include "ac_internal.h"
#include "ac_xf_core.h"

/* index of the upper triangle's entry (i, j) of a symmetric 6x6 */
static const uint8_t sym6[6][6] = {{0u, 1u, 2u, 3u, 4u, 5u},      {1u, 6u, 7u, 8u, 9u, 10u},
                                   {2u, 7u, 11u, 12u, 13u, 14u},  {3u, 8u, 12u, 15u, 16u, 17u},
                                   {4u, 9u, 13u, 16u, 18u, 19u},  {5u, 10u, 14u, 17u, 19u, 20u}};
/* index of the six entries (00 01 02 11 12 22) of a symmetric 3x3 */
static const uint8_t sym3[3][3] = {{0u, 1u, 2u}, {1u, 3u, 4u}, {2u, 4u, 5u}};
/* the nonzero entries of J's columns (in increasing order): products terms skip the zeros,
 * which leaves every sum as it was (a zero term adds nothing) */
static const uint8_t nz[3][3] = {{0u, 3u, 5u}, {1u, 3u, 4u}, {2u, 4u, 5u}};

/* r = sum over column c's nonzeros of col[k] v[k] */
static void dot_col(ac_xf *r, uint8_t c, const ac_xf *col, const ac_xf *v)
{
    ac_xf s;
    ac_xfp_mul(&s, &col[nz[c][0]], &v[nz[c][0]]);
    ac_xfp_mac(&s, &col[nz[c][1]], &v[nz[c][1]]);
    ac_xfp_mac(&s, &col[nz[c][2]], &v[nz[c][2]]);
    *r = s;
}

typedef struct work {
    ac_xf q[6];      /* centripetal readings */
    ac_xf lin[3];    /* alpha before its centripetal correction */
    ac_xf lam[6];    /* P^-1 of the prediction */
    ac_xf wp[3];     /* the prior's centre */
    ac_xf cols[3][6];
    ac_xf mj[3][6];
    ac_xf v6[6];
    ac_xf h[6];
    ac_xf hi[6];
    ac_xf g[3];
    ac_xf c[3];
    ac_xf t3[3];
} work;

static void xzero(ac_xf *r)
{
    r->m = 0;
    r->e = 0;
}

static int8_t xsign(const ac_xf *a)
{
    int8_t s = 0;
    if (a->m > 0) {
        s = 1;
    } else if (a->m < 0) {
        s = -1;
    }
    return s;
}

static void xneg(ac_xf *r, const ac_xf *a)
{
    *r = *a;
    r->m = -r->m; /* |m| < 2^30: no overflow */
}

/* r = sum_{i<6} a[i] b[i] */
static void dot6(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    uint8_t i;
    ac_xf s;
    xzero(&s);
    for (i = 0u; i < 6u; i++) {
        ac_xfp_mac(&s, &a[i], &b[i]);
    }
    *r = s;
}

static void dot3(ac_xf *r, const ac_xf *a, const ac_xf *b)
{
    ac_xf s;
    ac_xfp_mul(&s, &a[0], &b[0]);
    ac_xfp_mac(&s, &a[1], &b[1]);
    ac_xfp_mac(&s, &a[2], &b[2]);
    *r = s;
}

/* r = m v, m symmetric 6x6 (21 entries); r must not alias v */
static void mul6(ac_xf *r, const ac_xf *m, const ac_xf *v)
{
    uint8_t i, j;
    for (i = 0u; i < 6u; i++) {
        ac_xf s;
        xzero(&s);
        for (j = 0u; j < 6u; j++) {
            ac_xfp_mac(&s, &m[sym6[i][j]], &v[j]);
        }
        r[i] = s;
    }
}

/* r = a v, a symmetric 3x3 (six entries); r must not alias v */
static void mul3(ac_xf *r, const ac_xf *a, const ac_xf *v)
{
    uint8_t i;
    for (i = 0u; i < 3u; i++) {
        ac_xf s;
        ac_xfp_mul(&s, &a[sym3[i][0]], &v[0]);
        ac_xfp_mac(&s, &a[sym3[i][1]], &v[1]);
        ac_xfp_mac(&s, &a[sym3[i][2]], &v[2]);
        r[i] = s;
    }
}

/* r = a^-1 by the adjugate (a symmetric, six entries); det == 0 gives the invalid value */
static void inv3(ac_xf *r, const ac_xf *a)
{
    ac_xf c[6], det, t;
    /* c00 = a11 a22 - a12^2, c01 = a02 a12 - a01 a22, c02 = a01 a12 - a02 a11 */
    ac_xfp_mul(&c[0], &a[3], &a[5]);
    ac_xfp_mul(&t, &a[4], &a[4]);
    ac_xfp_sub(&c[0], &c[0], &t);
    ac_xfp_mul(&c[1], &a[2], &a[4]);
    ac_xfp_mul(&t, &a[1], &a[5]);
    ac_xfp_sub(&c[1], &c[1], &t);
    ac_xfp_mul(&c[2], &a[1], &a[4]);
    ac_xfp_mul(&t, &a[2], &a[3]);
    ac_xfp_sub(&c[2], &c[2], &t);
    /* c11 = a00 a22 - a02^2, c12 = a01 a02 - a00 a12, c22 = a00 a11 - a01^2 */
    ac_xfp_mul(&c[3], &a[0], &a[5]);
    ac_xfp_mul(&t, &a[2], &a[2]);
    ac_xfp_sub(&c[3], &c[3], &t);
    ac_xfp_mul(&c[4], &a[1], &a[2]);
    ac_xfp_mul(&t, &a[0], &a[4]);
    ac_xfp_sub(&c[4], &c[4], &t);
    ac_xfp_mul(&c[5], &a[0], &a[3]);
    ac_xfp_mul(&t, &a[1], &a[1]);
    ac_xfp_sub(&c[5], &c[5], &t);
    ac_xfp_mul(&det, &a[0], &c[0]);
    ac_xfp_mac(&det, &a[1], &c[1]);
    ac_xfp_mac(&det, &a[2], &c[2]);
    {
        uint8_t i;
        for (i = 0u; i < 6u; i++) {
            ac_xfp_div(&r[i], &c[i], &det);
        }
    }
}

/* r = sqrt(a) for a >= 0 (0 for a <= 0): AC_OMEGA_SQRT_ITER Newton steps from
 * 2^ceil(bitlen/2) >= sqrt(a), which descend monotonically */
static void xsqrt(ac_xf *r, const ac_xf *a)
{
    ac_xf y, t;
    int16_t s, half;
    uint8_t k;
    if (a->e == AC_XF_BAD) {
        *r = *a;
        return;
    }
    if (a->m <= 0) {
        xzero(r);
        return;
    }
    s = (int16_t)(a->e + 30); /* a < 2^s */
    half = (int16_t)((s >= 0) ? ((s + 1) / 2) : -((-s) / 2));
    y.m = 0x20000000L; /* 2^29 */
    y.e = (int16_t)(half - 29);
    for (k = 0u; k < AC_OMEGA_SQRT_ITER; k++) {
        ac_xfp_div(&t, a, &y);
        ac_xfp_add(&y, &y, &t);
        ac_xfp_ldexp(&y, -1);
    }
    *r = y;
}

/* p(x) = (x0^2, x1^2, x2^2, x0 x1, x1 x2, x2 x0) */
static void products(ac_xf *p, const ac_xf *x)
{
    ac_xfp_mul(&p[0], &x[0], &x[0]);
    ac_xfp_mul(&p[1], &x[1], &x[1]);
    ac_xfp_mul(&p[2], &x[2], &x[2]);
    ac_xfp_mul(&p[3], &x[0], &x[1]);
    ac_xfp_mul(&p[4], &x[1], &x[2]);
    ac_xfp_mul(&p[5], &x[2], &x[0]);
}

/* the columns of J = dp/dx at x */
static void columns(ac_xf cols[3][6], const ac_xf *x)
{
    uint8_t i, j;
    for (i = 0u; i < 3u; i++) {
        for (j = 0u; j < 6u; j++) {
            xzero(&cols[i][j]);
        }
    }
    for (i = 0u; i < 3u; i++) {
        cols[i][i] = x[i];
        ac_xfp_ldexp(&cols[i][i], 1);
    }
    cols[0][3] = x[1];
    cols[0][5] = x[2];
    cols[1][3] = x[0];
    cols[1][4] = x[2];
    cols[2][4] = x[1];
    cols[2][5] = x[0];
}

/* info = J^T m J (six entries); w->mj = m J's columns */
static void information(work *w, const ac_omega_table *t, ac_xf *info)
{
    uint8_t i, j;
    for (i = 0u; i < 3u; i++) {
        uint8_t r;
        for (r = 0u; r < 6u; r++) { /* row r of m times column i (its nonzeros) */
            ac_xf s;
            ac_xfp_mul(&s, &t->m[sym6[r][nz[i][0]]], &w->cols[i][nz[i][0]]);
            ac_xfp_mac(&s, &t->m[sym6[r][nz[i][1]]], &w->cols[i][nz[i][1]]);
            ac_xfp_mac(&s, &t->m[sym6[r][nz[i][2]]], &w->cols[i][nz[i][2]]);
            w->mj[i][r] = s;
        }
    }
    for (i = 0u; i < 3u; i++) {
        for (j = i; j < 3u; j++) {
            dot_col(&info[sym3[i][j]], i, w->cols[i], w->mj[j]);
        }
    }
}

/* alpha = lin - L p(x) */
static void alpha_at(ac_xf *a, const ac_omega_table *t, const ac_xf *lin, const ac_xf *x)
{
    ac_xf p[6], s;
    uint8_t i;
    products(p, x);
    for (i = 0u; i < 3u; i++) {
        dot6(&s, t->leak[i], p);
        ac_xfp_sub(&a[i], &lin[i], &s);
    }
}

/* cost(x) - cost(wp), cost(x) = (x - wp)^T lam (x - wp) + p^T m p - 2 q^T p, as
 *   (x - wp)^T lam (x - wp) + (p(x) - p(wp))^T (m (p(x) + p(wp)) - 2 q):
 * the costs themselves are about q^T m^-1 q (5e10 on a 12.5 cm array at 30 rad/s and
 * 0.3 counts of noise), their difference a few units, beyond ac_xf's 30 bits when taken apart */
static void cost_delta(ac_xf *r, work *w, const ac_omega_table *t, const ac_xf *x)
{
    ac_xf px[6], pw[6], ps[6], mp[6], d[3], ld[3], s, u;
    uint8_t i;
    products(px, x);
    products(pw, w->wp);
    for (i = 0u; i < 6u; i++) {
        ac_xfp_add(&ps[i], &px[i], &pw[i]);
        ac_xfp_sub(&px[i], &px[i], &pw[i]);
    }
    mul6(mp, t->m, ps);
    for (i = 0u; i < 6u; i++) {
        ac_xf q2 = w->q[i];
        ac_xfp_ldexp(&q2, 1);
        ac_xfp_sub(&mp[i], &mp[i], &q2);
    }
    dot6(&s, px, mp);
    for (i = 0u; i < 3u; i++) {
        ac_xfp_sub(&d[i], &x[i], &w->wp[i]);
    }
    mul3(ld, w->lam, d);
    dot3(&u, d, ld);
    ac_xfp_add(r, &s, &u);
}

/* one Gauss-Newton step: x += (prior + J^T m J)^-1 (prior (wp - x) + J^T (q - m p)).
 * prior: lam (the posterior) or NULL (the ML: ridge I and no prior gradient). */
static void gauss_newton(work *w, const ac_omega_table *t, ac_xf *x, const ac_xf *lam)
{
    ac_xf p[6], info[6], step[3];
    uint8_t i;
    columns(w->cols, x);
    information(w, t, info);
    products(p, x);
    mul6(w->v6, t->m, p);
    for (i = 0u; i < 6u; i++) {
        ac_xfp_sub(&w->v6[i], &w->q[i], &w->v6[i]);
    }
    if (lam != 0) {
        for (i = 0u; i < 3u; i++) {
            ac_xfp_sub(&w->t3[i], &w->wp[i], &x[i]);
        }
        mul3(w->g, lam, w->t3);
        for (i = 0u; i < 6u; i++) {
            ac_xfp_add(&w->h[i], &lam[i], &info[i]);
        }
    } else {
        for (i = 0u; i < 3u; i++) {
            xzero(&w->g[i]);
        }
        for (i = 0u; i < 6u; i++) {
            w->h[i] = info[i];
        }
        ac_xfp_add(&w->h[0], &w->h[0], &t->ridge);
        ac_xfp_add(&w->h[3], &w->h[3], &t->ridge);
        ac_xfp_add(&w->h[5], &w->h[5], &t->ridge);
    }
    for (i = 0u; i < 3u; i++) {
        ac_xf s;
        dot_col(&s, i, w->cols[i], w->v6);
        ac_xfp_add(&w->g[i], &w->g[i], &s);
    }
    inv3(w->hi, w->h);
    mul3(step, w->hi, w->g);
    for (i = 0u; i < 3u; i++) {
        ac_xfp_add(&x[i], &x[i], &step[i]);
    }
}

/* the per-sample ML estimate (up to its sign) into w->c */
static void ml_estimate(work *w, const ac_omega_table *t)
{
    static const uint8_t col_of[3][3] = {{0u, 3u, 5u}, {3u, 1u, 4u}, {5u, 4u, 2u}};
    ac_xf phat[6], s;
    uint8_t i, k = 0u;
    mul6(phat, t->minv, w->q);
    /* the largest diagonal entry (the first of equals) */
    for (i = 1u; i < 3u; i++) {
        ac_xf d;
        int8_t gt;
        ac_xfp_sub(&d, &phat[i], &phat[k]);
        gt = xsign(&d);
        if (gt > 0) {
            k = i;
        }
    }
    if (phat[k].m <= 0) {
        for (i = 0u; i < 3u; i++) {
            xzero(&w->c[i]);
        }
    } else {
        xsqrt(&s, &phat[k]);
        for (i = 0u; i < 3u; i++) {
            ac_xfp_div(&w->c[i], &phat[col_of[k][i]], &s);
        }
    }
    for (i = 0u; i < AC_OMEGA_ML_ITER; i++) {
        gauss_newton(w, t, w->c, 0);
    }
}

static int xbad(const ac_xf *v, uint8_t n)
{
    uint8_t i;
    for (i = 0u; i < n; i++) {
        if (v[i].e == AC_XF_BAD) {
            return 1;
        }
    }
    return 0;
}

static int xunnormal(const ac_xf *v, uint8_t n)
{
    uint8_t i;
    for (i = 0u; i < n; i++) {
        uint32_t a = ac_abs_u(v[i].m);
        if (v[i].e == AC_XF_BAD || (a != 0u && (a < 0x20000000UL || a >= 0x40000000UL))) {
            return 1;
        }
    }
    return 0;
}

ac_status ac_omega_check(const ac_omega_table *t)
{
    uint8_t j, i;
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 6u || t->n > AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    for (j = 0u; j < 9u; j++) {
        uint32_t sum = 0u;
        if (t->shift[j] < -31 || t->shift[j] > 31) {
            return AC_ERR_FORMAT;
        }
        uint32_t suml = 0u;
        for (i = 0u; i < (uint8_t)t->n; i++) {
            sum += ac_abs_u((int32_t)t->t[j][i]);
            suml += ac_abs_u((int32_t)t->tl[j][i]);
        }
        if (sum > 65535UL || suml > 65535UL) {
            return AC_ERR_FORMAT;
        }
    }
    if (xunnormal(t->k, 9u) || xunnormal(t->m, 21u) || xunnormal(t->minv, 21u) ||
        xunnormal(t->leak[0], 6u) || xunnormal(t->leak[1], 6u) || xunnormal(t->leak[2], 6u) ||
        xunnormal(t->qn, 6u) || xunnormal(t->p0, 6u) || xunnormal(&t->dt, 1u) ||
        xunnormal(&t->half_dt, 1u) || xunnormal(&t->jump, 1u) || xunnormal(&t->ridge, 1u)) {
        return AC_ERR_RANGE;
    }
    return AC_OK;
}

ac_status ac_omega_init(ac_omega_state *st, const ac_omega_table *t)
{
    uint8_t i;
    ac_status s;
    if (st == 0 || t == 0) {
        return AC_ERR_NULL;
    }
    s = ac_omega_check(t);
    if (s != AC_OK) {
        return s;
    }
    for (i = 0u; i < 3u; i++) {
        xzero(&st->w[i]);
        xzero(&st->a_prev[i]);
    }
    for (i = 0u; i < 6u; i++) {
        st->p[i] = t->p0[i];
    }
    st->started = 0u;
    return AC_OK;
}

/* P = F P F^T + Qn, F = I - dt L J (J's columns in w->cols) */
static void propagate(work *w, const ac_omega_table *t, ac_xf *p)
{
    ac_xf f[3][3], fp[3][3];
    uint8_t i, j;
    for (i = 0u; i < 3u; i++) {
        for (j = 0u; j < 3u; j++) {
            ac_xf d;
            dot_col(&d, j, w->cols[j], t->leak[i]);
            ac_xfp_mul(&d, &d, &t->dt);
            if (i == j) {
                ac_xfp_from_fixed(&f[i][j], 1, 0);
                ac_xfp_sub(&f[i][j], &f[i][j], &d);
            } else {
                xneg(&f[i][j], &d);
            }
        }
    }
    for (i = 0u; i < 3u; i++) {
        mul3(fp[i], p, f[i]); /* row i of F P */
    }
    for (i = 0u; i < 3u; i++) {
        for (j = i; j < 3u; j++) {
            ac_xf s;
            dot3(&s, fp[i], f[j]);
            ac_xfp_add(&p[sym3[i][j]], &s, &t->qn[sym3[i][j]]);
        }
    }
}

/* field by field: a struct assignment may become a memcpy call (no libc on the H8) */
static void copy_state(ac_omega_state *d, const ac_omega_state *s)
{
    uint8_t i;
    for (i = 0u; i < 3u; i++) {
        d->w[i] = s->w[i];
        d->a_prev[i] = s->a_prev[i];
    }
    for (i = 0u; i < 6u; i++) {
        d->p[i] = s->p[i];
    }
    d->started = s->started;
}

ac_status ac_omega_step(ac_omega_state *st, const ac_omega_table *t, const int16_t *x,
                        int32_t *omega_q16, int16_t *omega_q10, uint8_t *flags)
{
    ac_omega_state s;
    work w;
    ac_xf a[3], info[6];
    int32_t out[3];
    int16_t out10[3];
    uint8_t i, fl = 0u, sat = 0u;
    ac_status status;
    if (st == 0 || t == 0 || x == 0 || omega_q16 == 0) {
        return AC_ERR_NULL;
    }
    status = ac_omega_check(t);
    if (status != AC_OK) {
        return status;
    }
    copy_state(&s, st);
    /* the readings through the table's rows */
    for (i = 0u; i < 9u; i++) {
        ac_xf v, vl;
        int32_t acc = ac_i_from_u(ac_dot16(0u, t->t[i], x, (uint8_t)t->n));
        int32_t accl = ac_i_from_u(ac_dot16(0u, t->tl[i], x, (uint8_t)t->n));
        ac_xfp_from_fixed(&v, acc, (int16_t)t->shift[i]);
        ac_xfp_from_fixed(&vl, accl, (int16_t)(t->shift[i] + AC_OMEGA_LO_BITS));
        ac_xfp_add(&v, &v, &vl);
        ac_xfp_sub((i < 6u) ? &w.q[i] : &w.lin[i - 6u], &v, &t->k[i]);
    }
    /* 1. prediction */
    if (!s.started) {
        alpha_at(s.a_prev, t, w.lin, s.w);
        s.started = 1u;
    } else {
        ac_xf w0[3];
        alpha_at(a, t, w.lin, s.w);
        columns(w.cols, s.w);
        propagate(&w, t, s.p);
        for (i = 0u; i < 3u; i++) {
            ac_xf d;
            ac_xfp_add(&d, &s.a_prev[i], &a[i]);
            ac_xfp_mul(&d, &d, &t->half_dt);
            ac_xfp_add(&w0[i], &s.w[i], &d);
        }
        alpha_at(a, t, w.lin, w0);
        for (i = 0u; i < 3u; i++) {
            ac_xf d;
            ac_xfp_add(&d, &s.a_prev[i], &a[i]);
            ac_xfp_mul(&d, &d, &t->half_dt);
            ac_xfp_add(&s.w[i], &s.w[i], &d);
        }
    }
    for (i = 0u; i < 3u; i++) {
        w.wp[i] = s.w[i];
    }
    inv3(w.lam, s.p);
    /* 2. the jump test: a c can pass only when cost(wp) - jump > min cost = -q^T m^-1 q,
     * i.e. (p(wp) - m^-1 q)^T m (p(wp) - m^-1 q) > jump (taken as that difference) */
    {
        ac_xf cc, e[6], me[6], lhs;
        products(e, w.wp);
        mul6(me, t->minv, w.q);
        for (i = 0u; i < 6u; i++) {
            ac_xfp_sub(&e[i], &e[i], &me[i]);
        }
        mul6(me, t->m, e);
        dot6(&lhs, e, me);
        ac_xfp_sub(&lhs, &lhs, &t->jump);
        if (lhs.m > 0) {
            fl |= AC_OMEGA_FLAG_ML;
            ml_estimate(&w, t);
            dot3(&cc, w.c, w.wp);
            if (cc.m < 0) {
                for (i = 0u; i < 3u; i++) {
                    xneg(&w.c[i], &w.c[i]);
                }
            }
            cost_delta(&cc, &w, t, w.c);
            ac_xfp_add(&cc, &cc, &t->jump);
            if (cc.m < 0) {
                fl |= AC_OMEGA_FLAG_JUMP;
                for (i = 0u; i < 3u; i++) {
                    s.w[i] = w.c[i];
                    w.wp[i] = w.c[i];
                }
            }
        }
    }
    /* 3. Gauss-Newton on the posterior */
    for (i = 0u; i < AC_OMEGA_ITER; i++) {
        gauss_newton(&w, t, s.w, w.lam);
    }
    /* 4. the posterior covariance, alpha at the estimate */
    columns(w.cols, s.w);
    information(&w, t, info);
    for (i = 0u; i < 6u; i++) {
        ac_xfp_add(&w.h[i], &w.lam[i], &info[i]);
    }
    inv3(s.p, w.h);
    alpha_at(s.a_prev, t, w.lin, s.w);
    if (xbad(s.w, 3u) || xbad(s.p, 6u) || xbad(s.a_prev, 3u)) {
        return AC_ERR_RANGE;
    }
    for (i = 0u; i < 3u; i++) {
        int32_t v10;
        if (ac_xfp_to_fixed(&s.w[i], AC_OMEGA_Q16_FRAC, &out[i]) != AC_OK) {
            sat = 1u;
        }
        (void)ac_xfp_to_fixed(&s.w[i], AC_OMEGA_FRAC, &v10);
        {
            uint8_t s16 = 0u;
            out10[i] = ac_sat_to16(v10, &s16);
            if (s16) {
                fl |= AC_OMEGA_FLAG_SAT16;
            }
        }
    }
    copy_state(st, &s);
    for (i = 0u; i < 3u; i++) {
        omega_q16[i] = out[i];
        if (omega_q10 != 0) {
            omega_q10[i] = out10[i];
        }
    }
    if (flags != 0) {
        *flags = fl;
    }
    if ((fl & AC_OMEGA_FLAG_SAT16) != 0u && omega_q10 != 0) {
        sat = 1u;
    }
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_omega_sigma(const ac_omega_state *st, int32_t *sigma_q16)
{
    static const uint8_t diag[3] = {0u, 3u, 5u};
    uint8_t i, sat = 0u;
    int32_t out[3];
    if (st == 0 || sigma_q16 == 0) {
        return AC_ERR_NULL;
    }
    for (i = 0u; i < 3u; i++) {
        ac_xf r;
        ac_status s;
        xsqrt(&r, &st->p[diag[i]]);
        s = ac_xfp_to_fixed(&r, AC_OMEGA_Q16_FRAC, &out[i]);
        if (s < 0) {
            return s;
        }
        if (s != AC_OK) {
            sat = 1u;
        }
    }
    for (i = 0u; i < 3u; i++) {
        sigma_q16[i] = out[i];
    }
    return sat ? AC_SATURATED : AC_OK;
}
