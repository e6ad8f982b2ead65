/*
 * Unit tests of ac_invert.h: sensor and centripetal rows, the 6x6 inverse
 * (identity, exact diagonal, random matrices, singular and ill-conditioned
 * ones), and the on-device table build for the seed geometry of
 * docs/design.md, perturbed versions of it and redundant 9/12-channel
 * layouts: the quantised M times the sensor matrix is the identity within the
 * bound its quantisation allows, k and g match M o and M C, the shifts follow
 * the quantizer's rule, and a full resolve reproduces a known motion.  Errors:
 * NULL, n out of range, a singular geometry (every channel along x) and an
 * ill-conditioned one, with the output table left untouched.
 *
 * Reference arithmetic is long double (64-bit mantissa).
 */
#include <accelcal/accelcal.h>

#include <math.h>
#include <string.h>

#include "ac_test.h"

#define PI_L 3.141592653589793238462643383279502884L
#define SENS_CPMS2 (1250.0L / 9.80665L) /* ADXL202E: 1250 counts per g */
#define RADIUS_M 0.060L
#define REL_XF 1.862645149230957e-09L /* 2^-29 */

typedef long double mat6[6][6];

/* ---- long double linear algebra ----------------------------------------------- */

/* In-place inverse by Gauss-Jordan with partial pivoting; 0 if singular. */
static int inv6_ld(mat6 a)
{
    int perm[6];
    int i, j, k;
    for (k = 0; k < 6; k++) {
        int p = k;
        long double piv;
        for (i = k + 1; i < 6; i++) {
            if (fabsl(a[i][k]) > fabsl(a[p][k])) {
                p = i;
            }
        }
        if (a[p][k] == 0.0L) {
            return 0;
        }
        perm[k] = p;
        for (j = 0; j < 6; j++) {
            long double t = a[k][j];
            a[k][j] = a[p][j];
            a[p][j] = t;
        }
        piv = a[k][k];
        a[k][k] = 1.0L;
        for (j = 0; j < 6; j++) {
            a[k][j] /= piv;
        }
        for (i = 0; i < 6; i++) {
            long double f;
            if (i == k) {
                continue;
            }
            f = a[i][k];
            a[i][k] = 0.0L;
            for (j = 0; j < 6; j++) {
                a[i][j] -= f * a[k][j];
            }
        }
    }
    for (k = 5; k >= 0; k--) {
        if (perm[k] != k) {
            for (i = 0; i < 6; i++) {
                long double t = a[i][k];
                a[i][k] = a[i][perm[k]];
                a[i][perm[k]] = t;
            }
        }
    }
    return 1;
}

static long double norm1_ld(mat6 a)
{
    long double best = 0.0L;
    int i, j;
    for (j = 0; j < 6; j++) {
        long double s = 0.0L;
        for (i = 0; i < 6; i++) {
            s += fabsl(a[i][j]);
        }
        if (s > best) {
            best = s;
        }
    }
    return best;
}

static long double cond1_ld(mat6 a)
{
    mat6 b;
    memcpy(b, a, sizeof b);
    if (!inv6_ld(b)) {
        return INFINITY;
    }
    return norm1_ld(a) * norm1_ld(b);
}

/* ---- geometry ------------------------------------------------------------------- */

typedef struct geom {
    unsigned n;
    ac_channel_cal cal[AC_MAX_CHANNELS];
    /* exact values of the fixed-point parameters */
    long double s[AC_MAX_CHANNELS][3], r[AC_MAX_CHANNELS][3], o[AC_MAX_CHANNELS];
} geom;

static int32_t fix(long double v, int frac)
{
    return (int32_t)lroundl(ldexpl(v, frac));
}

static void geom_set(geom *g, unsigned i, const long double s[3], const long double r[3],
                     long double offset)
{
    int a;
    for (a = 0; a < 3; a++) {
        g->cal[i].sens[a] = fix(s[a], AC_SENS_FRAC);
        g->cal[i].pos[a] = fix(r[a], AC_POS_FRAC);
        g->s[i][a] = ldexpl((long double)g->cal[i].sens[a], -AC_SENS_FRAC);
        g->r[i][a] = ldexpl((long double)g->cal[i].pos[a], -AC_POS_FRAC);
    }
    g->cal[i].offset = fix(offset, AC_OFFSET_FRAC);
    g->o[i] = ldexpl((long double)g->cal[i].offset, -AC_OFFSET_FRAC);
}

/* The seed prototype (docs/design.md): chip k at 120k deg on the 60 mm circle,
 * channel 2k along the tangent, 2k+1 along z.  'jitter' > 0 perturbs gains,
 * directions (radians) and positions (m) by up to that relative amount. */
static void seed_geom(geom *g, long double jitter)
{
    unsigned k;
    g->n = 6;
    for (k = 0; k < 3; k++) {
        long double phi = 2.0L * PI_L * (long double)k / 3.0L;
        long double r[3], t[3], z[3] = {0.0L, 0.0L, 1.0L};
        long double st[3], sz[3];
        int a;
        r[0] = RADIUS_M * cosl(phi);
        r[1] = RADIUS_M * sinl(phi);
        r[2] = 0.0L;
        t[0] = -sinl(phi);
        t[1] = cosl(phi);
        t[2] = 0.0L;
        for (a = 0; a < 3; a++) {
            long double e1 = jitter * ((long double)ac_test_range(-1000, 1000) / 1000.0L);
            long double e2 = jitter * ((long double)ac_test_range(-1000, 1000) / 1000.0L);
            st[a] = SENS_CPMS2 * (t[a] + e1);
            sz[a] = SENS_CPMS2 * (z[a] + e2);
            r[a] += RADIUS_M * jitter * ((long double)ac_test_range(-1000, 1000) / 1000.0L);
        }
        geom_set(g, 2 * k, st, r,
                 jitter > 0 ? (long double)ac_test_range(-4000, 4000) / 1000.0L : 0.0L);
        geom_set(g, 2 * k + 1, sz, r,
                 jitter > 0 ? (long double)ac_test_range(-4000, 4000) / 1000.0L : 0.3L);
    }
}

/* n / 3 tri-axial chips (tangent, radial, z), chip k at angle 360k/(n/3) deg,
 * radius 60 mm, heights alternating +-10 mm. */
static void triax_geom(geom *g, unsigned n)
{
    unsigned k, chips = n / 3;
    g->n = n;
    for (k = 0; k < chips; k++) {
        long double phi = 2.0L * PI_L * (long double)k / (long double)chips + 0.1L;
        long double r[3], dir[3][3];
        unsigned c;
        r[0] = RADIUS_M * cosl(phi);
        r[1] = RADIUS_M * sinl(phi);
        r[2] = (k & 1) ? 0.010L : -0.010L;
        dir[0][0] = -sinl(phi);
        dir[0][1] = cosl(phi);
        dir[0][2] = 0.0L;
        dir[1][0] = cosl(phi);
        dir[1][1] = sinl(phi);
        dir[1][2] = 0.0L;
        dir[2][0] = 0.0L;
        dir[2][1] = 0.0L;
        dir[2][2] = 1.0L;
        for (c = 0; c < 3; c++) {
            long double s[3];
            int a;
            for (a = 0; a < 3; a++) {
                s[a] = SENS_CPMS2 * dir[c][a] * (1.0L + 0.01L * (long double)c);
            }
            geom_set(g, 3 * k + c, s, r, 0.5L - 0.25L * (long double)c);
        }
    }
}

/* Sensor matrix R (n x 6) and centripetal matrix C (n x 6) of the exact parameters. */
static void sensor_ld(const geom *g, unsigned i, long double row[6])
{
    const long double *s = g->s[i], *r = g->r[i];
    row[0] = s[0];
    row[1] = s[1];
    row[2] = s[2];
    row[3] = r[1] * s[2] - r[2] * s[1];
    row[4] = r[2] * s[0] - r[0] * s[2];
    row[5] = r[0] * s[1] - r[1] * s[0];
}

static void centripetal_ld(const geom *g, unsigned i, long double row[6])
{
    const long double *s = g->s[i], *r = g->r[i];
    long double sr = s[0] * r[0] + s[1] * r[1] + s[2] * r[2];
    row[0] = s[0] * r[0] - sr;
    row[1] = s[1] * r[1] - sr;
    row[2] = s[2] * r[2] - sr;
    row[3] = s[0] * r[1] + s[1] * r[0];
    row[4] = s[1] * r[2] + s[2] * r[1];
    row[5] = s[2] * r[0] + s[0] * r[2];
}

/* M = pinv(R) (6 x n, output units per count); returns cond_1 of the
 * equilibrated matrix the core inverts, through *cond. */
static int pinv_ld(const geom *g, long double M[6][AC_MAX_CHANNELS], long double *cond)
{
    long double R[AC_MAX_CHANNELS][6];
    long double colscale[6];
    mat6 A;
    unsigned i;
    int j, l;
    for (i = 0; i < g->n; i++) {
        sensor_ld(g, i, R[i]);
    }
    for (j = 0; j < 6; j++) {
        long double mx = 0.0L;
        int e;
        for (i = 0; i < g->n; i++) {
            if (fabsl(R[i][j]) > mx) {
                mx = fabsl(R[i][j]);
            }
        }
        if (mx == 0.0L) {
            return 0;
        }
        (void)frexpl(mx, &e); /* mx 2^-e in [0.5, 1) */
        colscale[j] = ldexpl(1.0L, -e);
    }
    for (j = 0; j < 6; j++) {
        for (l = 0; l < 6; l++) {
            if (g->n == 6) {
                A[j][l] = R[j][l] * colscale[l];
            } else {
                long double acc = 0.0L;
                for (i = 0; i < g->n; i++) {
                    acc += R[i][j] * colscale[j] * R[i][l] * colscale[l];
                }
                A[j][l] = acc;
            }
        }
    }
    *cond = cond1_ld(A);
    if (!inv6_ld(A)) {
        return 0;
    }
    /* M = D (A^-1) (R D)^T for n > 6, D A^-1 for n == 6 */
    for (j = 0; j < 6; j++) {
        for (i = 0; i < g->n; i++) {
            long double v;
            if (g->n == 6) {
                v = A[j][i];
            } else {
                v = 0.0L;
                for (l = 0; l < 6; l++) {
                    v += A[j][l] * R[i][l] * colscale[l];
                }
            }
            M[j][i] = ldexpl(v * colscale[j], AC_OUT_FRAC); /* output LSB per count */
        }
    }
    return 1;
}

/* ---- tests ------------------------------------------------------------------------ */

static void test_rows(void)
{
    geom g;
    long it;
    ac_xf row[6];
    ac_test_seed(5ul);
    CHECK_STATUS(ac_sensor_row(NULL, row), AC_ERR_NULL);
    CHECK_STATUS(ac_centripetal_row(NULL, row), AC_ERR_NULL);
    for (it = 0; it < 200; it++) {
        unsigned i;
        ac_test_context("rows", it);
        seed_geom(&g, it == 0 ? 0.0L : 0.3L);
        CHECK_STATUS(ac_sensor_row(&g.cal[0], NULL), AC_ERR_NULL);
        for (i = 0; i < g.n; i++) {
            long double want[6], c[6];
            const long double *s = g.s[i], *r = g.r[i];
            /* magnitudes of the terms each entry is made of: the bound on its
             * rounding error scales with them, not with the (cancelling) result */
            long double mag_s[6], mag_c[6];
            long double sr = fabsl(s[0] * r[0]) + fabsl(s[1] * r[1]) + fabsl(s[2] * r[2]);
            int j;
            sensor_ld(&g, i, want);
            centripetal_ld(&g, i, c);
            mag_s[0] = fabsl(s[0]);
            mag_s[1] = fabsl(s[1]);
            mag_s[2] = fabsl(s[2]);
            mag_s[3] = fabsl(r[1] * s[2]) + fabsl(r[2] * s[1]);
            mag_s[4] = fabsl(r[2] * s[0]) + fabsl(r[0] * s[2]);
            mag_s[5] = fabsl(r[0] * s[1]) + fabsl(r[1] * s[0]);
            mag_c[0] = fabsl(s[0] * r[0]) + sr;
            mag_c[1] = fabsl(s[1] * r[1]) + sr;
            mag_c[2] = fabsl(s[2] * r[2]) + sr;
            mag_c[3] = fabsl(s[0] * r[1]) + fabsl(s[1] * r[0]);
            mag_c[4] = fabsl(s[1] * r[2]) + fabsl(s[2] * r[1]);
            mag_c[5] = fabsl(s[2] * r[0]) + fabsl(s[0] * r[2]);
            CHECK_STATUS(ac_sensor_row(&g.cal[i], row), AC_OK);
            for (j = 0; j < 6; j++) {
                CHECK_NEAR(ldexpl((long double)row[j].m, row[j].e), want[j],
                           4.0L * REL_XF * mag_s[j]);
            }
            CHECK_STATUS(ac_centripetal_row(&g.cal[i], row), AC_OK);
            for (j = 0; j < 6; j++) {
                CHECK_NEAR(ldexpl((long double)row[j].m, row[j].e), c[j],
                           8.0L * REL_XF * mag_c[j]);
            }
        }
    }
    ac_test_context("", -1);
}

static void xf_matrix(ac_xf x[6][6], mat6 a)
{
    int i, j;
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 6; j++) {
            int e;
            long double f = frexpl(a[i][j], &e); /* a = f 2^e, |f| in [0.5, 1) */
            x[i][j].m = (int32_t)lroundl(ldexpl(f, 30));
            x[i][j].e = (int16_t)(e - 30);
            if (x[i][j].m == 0x40000000L || x[i][j].m == -0x40000000L) {
                x[i][j].m /= 2;
                x[i][j].e++;
            }
            a[i][j] = ldexpl((long double)x[i][j].m, x[i][j].e); /* exactly what the core sees */
        }
    }
}

/* || A X - I ||_max for the core's X */
static long double residual(mat6 a, ac_xf x[6][6])
{
    long double worst = 0.0L;
    int i, j, k;
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 6; j++) {
            long double acc = (i == j) ? -1.0L : 0.0L;
            for (k = 0; k < 6; k++) {
                acc += a[i][k] * ldexpl((long double)x[k][j].m, x[k][j].e);
            }
            if (fabsl(acc) > worst) {
                worst = fabsl(acc);
            }
        }
    }
    return worst;
}

static int ceil_log2_ld(long double c)
{
    return (int)ceill(log2l(c));
}

static void test_invert6(void)
{
    static ac_xf x[6][6];
    mat6 a;
    int8_t perm[6];
    int16_t cl2;
    int i, j;
    long it;

    /* identity: exact, cond 1 */
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 6; j++) {
            a[i][j] = (i == j) ? 1.0L : 0.0L;
        }
    }
    xf_matrix(x, a);
    cl2 = 99;
    CHECK_STATUS(ac_invert6(x, perm, &cl2), AC_OK);
    CHECK_EQ(cl2, 0);
    CHECK(residual(a, x) == 0.0L);

    /* diag(1, 2, ..., 32), permuted: exact inverse, cond 32 */
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 6; j++) {
            a[i][j] = (j == (i + 2) % 6) ? ldexpl(1.0L, i) : 0.0L;
        }
    }
    xf_matrix(x, a);
    CHECK_STATUS(ac_invert6(x, perm, &cl2), AC_OK);
    CHECK_EQ(cl2, 5);
    CHECK(residual(a, x) == 0.0L);
    CHECK_STATUS(ac_invert6(x, perm, NULL), AC_OK); /* cond_log2 may be NULL */

    CHECK_STATUS(ac_invert6(NULL, perm, &cl2), AC_ERR_NULL);
    CHECK_STATUS(ac_invert6(x, NULL, &cl2), AC_ERR_NULL);

    /* random matrices over wide scales */
    ac_test_seed(66ul);
    for (it = 0; it < 3000; it++) {
        long double c, res;
        int scale = (int)ac_test_range(-300, 300);
        ac_status st;
        ac_test_context("invert6", it);
        for (i = 0; i < 6; i++) {
            for (j = 0; j < 6; j++) {
                a[i][j] = ldexpl((long double)ac_test_range(-1000000, 1000000) / 1000000.0L, scale);
                if (it % 3 == 0 && i == j) {
                    a[i][j] += ldexpl(3.0L, scale); /* diagonally dominant */
                }
            }
        }
        xf_matrix(x, a);
        c = cond1_ld(a);
        st = ac_invert6(x, perm, &cl2);
        if (c > ldexpl(1.0L, AC_COND_LOG2_MAX + 1)) {
            CHECK_EQ(st, AC_ERR_ILL_COND);
            continue;
        }
        if (c < ldexpl(1.0L, AC_COND_LOG2_MAX - 1)) {
            CHECK_EQ(st, AC_OK);
        }
        if (st != AC_OK) {
            continue;
        }
        /* backward-stable elimination with a 29-bit mantissa: ||A X - I|| is a
         * modest multiple of cond * 2^-29 */
        res = residual(a, x);
        CHECK_MSG(res <= 64.0L * c * REL_XF, ("residual %.3Lg, cond %.3Lg", res, c));
        /* ceil(log2 cond) exactly, unless cond is within 2^-20 of a power of two */
        {
            long double l2 = log2l(c);
            if (fabsl(l2 - roundl(l2)) > 1e-6L) {
                CHECK_EQ(cl2, ceil_log2_ld(c));
            } else {
                CHECK(cl2 == ceil_log2_ld(c) || cl2 == ceil_log2_ld(c) + 1 ||
                      cl2 == ceil_log2_ld(c) - 1);
            }
        }
    }
    ac_test_context("", -1);

    /* singular: zero matrix, two equal rows, rows equal to 2^-30 */
    memset(a, 0, sizeof a);
    xf_matrix(x, a);
    CHECK_STATUS(ac_invert6(x, perm, &cl2), AC_ERR_SINGULAR);
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 6; j++) {
            a[i][j] = (long double)((i * 7 + j * 3) % 11) - 5.0L + (i == j ? 20.0L : 0.0L);
        }
    }
    for (j = 0; j < 6; j++) {
        a[4][j] = a[1][j];
    }
    xf_matrix(x, a);
    CHECK_STATUS(ac_invert6(x, perm, &cl2), AC_ERR_SINGULAR);
    a[4][0] = a[1][0] * (1.0L + ldexpl(1.0L, -30));
    xf_matrix(x, a);
    CHECK_STATUS(ac_invert6(x, perm, &cl2), AC_ERR_SINGULAR);
    /* nearly singular, but above the pivot tolerance: ill-conditioned */
    a[4][0] = a[1][0] * (1.0L + ldexpl(1.0L, -20));
    xf_matrix(x, a);
    CHECK_STATUS(ac_invert6(x, perm, &cl2), AC_ERR_ILL_COND);
}

/* Check a built table against the long double pseudo-inverse. */
static void check_table(const geom *g, const ac_resolver *r, const ac_build_info *info,
                        long double worst_identity[1])
{
    long double M[6][AC_MAX_CHANNELS], cond;
    long double R[AC_MAX_CHANNELS][6], C[AC_MAX_CHANNELS][6];
    unsigned i;
    int j, l;

    CHECK(pinv_ld(g, M, &cond));
    CHECK_STATUS(ac_resolver_check(r), AC_OK);
    CHECK_EQ(r->n, g->n);
    for (i = 0; i < g->n; i++) {
        sensor_ld(g, i, R[i]);
        centripetal_ld(g, i, C[i]);
    }
    /* the condition number of the matrix actually inverted */
    {
        long double l2 = log2l(cond);
        if (fabsl(l2 - roundl(l2)) > 1e-6L) {
            CHECK_EQ(info->cond_log2, ceil_log2_ld(cond));
        } else {
            CHECK(info->cond_log2 >= ceil_log2_ld(cond) - 1 &&
                  info->cond_log2 <= ceil_log2_ld(cond) + 1);
        }
    }
    for (j = 0; j < 6; j++) {
        long double lsb_m = ldexpl(1.0L, -r->m_shift[j]); /* output LSB per count per unit m */
        long double lsb_g = ldexpl(1.0L, -r->g_shift[j]);
        long double mmax = 0.0L, msum = 0.0L, mo = 0.0L, moabs = 0.0L;
        /* G entries with the error the build may make on each: M is accurate
         * to rel * max_i |M_ji| (normwise, as checked below), so G_jl = sum_i
         * M_ji C_il to rel * max|M_j.| * sum_i |C_il| (rows of M C cancel to ~0) */
        long double G[6], eg[6];
        long double gmax_lo = 0.0L, gmax_hi = 0.0L, gsum_lo = 0.0L, gsum_hi = 0.0L;
        /* relative error the xf build may add (cond * 2^-29 with margin) */
        long double rel = 64.0L * cond * REL_XF;
        for (i = 0; i < g->n; i++) {
            mmax = fabsl(M[j][i]) > mmax ? fabsl(M[j][i]) : mmax;
            msum += fabsl(M[j][i]);
            mo += M[j][i] * g->o[i];
            moabs += fabsl(g->o[i]);
        }
        for (l = 0; l < 6; l++) {
            long double terms = 0.0L, lo;
            G[l] = 0.0L;
            for (i = 0; i < g->n; i++) {
                G[l] += M[j][i] * C[i][l];
                terms += fabsl(C[i][l]);
            }
            eg[l] = rel * mmax * terms;
            lo = fabsl(G[l]) > eg[l] ? fabsl(G[l]) - eg[l] : 0.0L;
            gmax_lo = lo > gmax_lo ? lo : gmax_lo;
            gmax_hi = fabsl(G[l]) + eg[l] > gmax_hi ? fabsl(G[l]) + eg[l] : gmax_hi;
            gsum_lo += lo;
            gsum_hi += fabsl(G[l]) + eg[l];
        }
        /* entries: round(M 2^m_shift), within 0.5 + build error */
        for (i = 0; i < g->n; i++) {
            CHECK_MSG(fabsl((long double)r->m[j][i] * lsb_m - M[j][i]) <=
                          0.5L * lsb_m + rel * mmax,
                      ("m[%d][%u] = %d * 2^-%d vs %.9Lg", j, i, r->m[j][i], r->m_shift[j],
                       M[j][i]));
        }
        for (i = g->n; i < AC_MAX_CHANNELS; i++) {
            CHECK_EQ(r->m[j][i], 0);
        }
        CHECK_MSG(fabsl((long double)r->k[j] * lsb_m - mo) <= 0.5L * lsb_m + rel * mmax * moabs,
                  ("k[%d] = %ld * 2^-%d vs %.9Lg", j, (long)r->k[j], r->m_shift[j], mo));
        for (l = 0; l < 6; l++) {
            CHECK_MSG(fabsl((long double)r->g[j][l] * lsb_g - G[l]) <= 0.5L * lsb_g + eg[l],
                      ("g[%d][%d] = %d * 2^-%d vs %.9Lg", j, l, r->g[j][l], r->g_shift[j], G[l]));
        }
        /* the quantizer's rule: largest shift <= 31 with max 2^s <= 32767 and
         * sum 2^s <= 65535 - N (exact unless within the build error of a limit) */
        {
            long double lim_m = 32767.0L, lim_s = 65535.0L - (long double)g->n;
            long double e = 1.0L + rel;
            CHECK(mmax * ldexpl(1.0L, r->m_shift[j]) <= lim_m * e);
            CHECK(msum * ldexpl(1.0L, r->m_shift[j]) <= lim_s * e);
            CHECK(r->m_shift[j] == 31 || mmax * ldexpl(1.0L, r->m_shift[j] + 1) > lim_m / e ||
                  msum * ldexpl(1.0L, r->m_shift[j] + 1) > lim_s / e);
            lim_s = 65535.0L - 6.0L;
            CHECK(gmax_lo * ldexpl(1.0L, r->g_shift[j]) <= lim_m);
            CHECK(gsum_lo * ldexpl(1.0L, r->g_shift[j]) <= lim_s);
            CHECK(r->g_shift[j] == 31 || gmax_hi * ldexpl(1.0L, r->g_shift[j] + 1) > lim_m ||
                  gsum_hi * ldexpl(1.0L, r->g_shift[j] + 1) > lim_s);
        }
        /* (M_q R)_jl = delta_jl within the quantisation bound
         *   sum_i (0.5 2^-m_shift + rel max|M|) |R_il| 2^-OUT_FRAC   (output units -> SI) */
        for (l = 0; l < 6; l++) {
            long double acc = 0.0L, bound = 0.0L;
            for (i = 0; i < g->n; i++) {
                acc += (long double)r->m[j][i] * lsb_m * R[i][l];
                bound += (0.5L * lsb_m + rel * mmax) * fabsl(R[i][l]);
            }
            acc = ldexpl(acc, -AC_OUT_FRAC);
            bound = ldexpl(bound, -AC_OUT_FRAC);
            CHECK_MSG(fabsl(acc - (j == l ? 1.0L : 0.0L)) <= bound,
                      ("(M R)[%d][%d] = %.9Lg, bound %.3Lg", j, l, acc, bound));
            if (fabsl(acc - (j == l ? 1.0L : 0.0L)) > worst_identity[0]) {
                worst_identity[0] = fabsl(acc - (j == l ? 1.0L : 0.0L));
            }
        }
    }
}

/* Resolve a known motion with the built table and compare with the truth.
 * The error budget (output LSB) is the triangle inequality over what differs
 * from the exact model: the table's actual deviations from M, M o and M C
 * (each checked on its own in check_table) times the inputs, the readings
 * rounded to whole counts, and ac_resolve's own 0.5 LSB + E_j. */
static void check_motion(const geom *g, const ac_resolver *r, long double worst[1])
{
    long double M[6][AC_MAX_CHANNELS], cond;
    long double f[3], al[3], w[3], p[6], xr[AC_MAX_CHANNELS];
    long double C[AC_MAX_CHANNELS][6];
    int16_t x[AC_MAX_CHANNELS], wq[3];
    int32_t out[6];
    long double truth[6];
    unsigned i;
    int j, a, q;
    CHECK(pinv_ld(g, M, &cond));
    for (a = 0; a < 3; a++) {
        f[a] = (long double)ac_test_range(-20000, 20000) / 1000.0L;  /* +-2 g */
        al[a] = (long double)ac_test_range(-50000, 50000) / 1000.0L; /* +-50 rad/s^2 */
        wq[a] = (int16_t)ac_test_range(-6000, 6000);                  /* +-5.9 rad/s */
        w[a] = ldexpl((long double)wq[a], -AC_OMEGA_FRAC);
        truth[a] = f[a];
        truth[3 + a] = al[a];
    }
    p[0] = w[0] * w[0];
    p[1] = w[1] * w[1];
    p[2] = w[2] * w[2];
    p[3] = w[0] * w[1];
    p[4] = w[1] * w[2];
    p[5] = w[2] * w[0];
    for (i = 0; i < g->n; i++) {
        long double row[6];
        long double v = g->o[i];
        sensor_ld(g, i, row);
        centripetal_ld(g, i, C[i]);
        for (a = 0; a < 3; a++) {
            v += row[a] * f[a] + row[3 + a] * al[a];
        }
        for (q = 0; q < 6; q++) {
            v += C[i][q] * p[q];
        }
        xr[i] = v;
        x[i] = (int16_t)lroundl(v);
    }
    CHECK_STATUS(ac_resolve(r, x, wq, out), AC_OK);
    for (j = 0; j < 6; j++) {
        long double lsb_m = ldexpl(1.0L, -r->m_shift[j]);
        long double lsb_g = ldexpl(1.0L, -r->g_shift[j]);
        long double b = 0.5L, mo = 0.0L;
        long double err = fabsl(ldexpl((long double)out[j], -AC_OUT_FRAC) - truth[j]);
        for (i = 0; i < g->n; i++) {
            b += fabsl((long double)r->m[j][i] * lsb_m - M[j][i]) * fabsl((long double)x[i]);
            b += fabsl(M[j][i]) * fabsl(xr[i] - (long double)x[i]);
            mo += M[j][i] * g->o[i];
        }
        b += fabsl((long double)r->k[j] * lsb_m - mo);
        for (q = 0; q < 6; q++) {
            long double G = 0.0L;
            for (i = 0; i < g->n; i++) {
                G += M[j][i] * C[i][q];
            }
            b += fabsl((long double)r->g[j][q] * lsb_g - G) * fabsl(p[q]);
        }
        {
            /* E_j of ac_resolve.h */
            long double gabs = 0.0L;
            long maxsq = 0;
            int s = 0, d;
            for (a = 0; a < 3; a++) {
                long sq = (long)wq[a] * wq[a];
                maxsq = sq > maxsq ? sq : maxsq;
            }
            for (; maxsq != 0; maxsq >>= 1) {
                s++;
            }
            s = s > 14 ? s - 14 : 0;
            for (q = 0; q < 6; q++) {
                gabs += fabsl((long double)r->g[j][q]);
            }
            d = s - 2 * AC_OMEGA_FRAC - r->g_shift[j] + r->m_shift[j];
            if (s > 0) {
                b += ldexpl(gabs, s - 1 - 2 * AC_OMEGA_FRAC - r->g_shift[j]);
            }
            if (d < 0) {
                b += ldexpl(1.0L, -1 - r->m_shift[j]);
            }
        }
        b = ldexpl(b, -AC_OUT_FRAC) * (1.0L + 1e-12L); /* -> m/s^2 or rad/s^2 */
        CHECK_MSG(err <= b, ("output %d: %.6Lg vs truth %.6Lg, err %.3Lg > bound %.3Lg", j,
                             ldexpl((long double)out[j], -AC_OUT_FRAC), truth[j], err, b));
        if (err > worst[0]) {
            worst[0] = err;
        }
    }
}

static void test_build(void)
{
    static geom g;
    static ac_build_work work;
    static ac_resolver r, before;
    ac_build_info info;
    long double worst_id = 0.0L, worst_motion = 0.0L;
    long it;
    int k;

    /* the nominal seed geometry */
    ac_test_seed(1ul);
    seed_geom(&g, 0.0L);
    info.cond_log2 = -99;
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_OK);
    printf("seed geometry: cond_log2 = %d, m_shift = %d %d %d %d %d %d, g_shift = %d %d %d %d %d %d\n",
           info.cond_log2, r.m_shift[0], r.m_shift[1], r.m_shift[2], r.m_shift[3], r.m_shift[4],
           r.m_shift[5], r.g_shift[0], r.g_shift[1], r.g_shift[2], r.g_shift[3], r.g_shift[4],
           r.g_shift[5]);
    check_table(&g, &r, &info, &worst_id);
    printf("seed geometry: max |M_q R - I| = %.3Le\n", worst_id);
    for (k = 0; k < 50; k++) {
        ac_test_context("seed motion", k);
        check_motion(&g, &r, &worst_motion);
    }
    /* info may be NULL */
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &before, NULL), AC_OK);
    CHECK(memcmp(&before, &r, sizeof r) == 0);

    /* perturbed prototypes (gain and alignment errors up to 5 %, positions 5 %) */
    for (it = 0; it < 100; it++) {
        ac_test_context("perturbed seed", it);
        seed_geom(&g, 0.05L);
        info.cond_log2 = -99;
        CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_OK);
        check_table(&g, &r, &info, &worst_id);
        check_motion(&g, &r, &worst_motion);
    }
    /* redundant layouts: least squares */
    for (k = 9; k <= AC_MAX_CHANNELS; k += 3) {
        ac_test_context("tri-axial", k);
        triax_geom(&g, (unsigned)k);
        CHECK_STATUS(ac_resolver_build(g.cal, (uint16_t)k, &work, &r, &info), AC_OK);
        check_table(&g, &r, &info, &worst_id);
        for (it = 0; it < 20; it++) {
            check_motion(&g, &r, &worst_motion);
        }
    }
    ac_test_context("", -1);
    printf("all builds: max |M_q R - I| = %.3Le, max motion error = %.3Le\n", worst_id,
           worst_motion);

    /* errors leave the output table untouched */
    seed_geom(&g, 0.0L);
    memset(&r, 0xA5, sizeof r);
    memcpy(&before, &r, sizeof r);
    CHECK_STATUS(ac_resolver_build(NULL, 6, &work, &r, &info), AC_ERR_NULL);
    CHECK_STATUS(ac_resolver_build(g.cal, 6, NULL, &r, &info), AC_ERR_NULL);
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, NULL, &info), AC_ERR_NULL);
    CHECK_STATUS(ac_resolver_build(g.cal, 5, &work, &r, &info), AC_ERR_SIZE);
    CHECK_STATUS(ac_resolver_build(g.cal, 0, &work, &r, &info), AC_ERR_SIZE);
    CHECK_STATUS(ac_resolver_build(g.cal, AC_MAX_CHANNELS + 1, &work, &r, &info), AC_ERR_SIZE);
    CHECK(memcmp(&r, &before, sizeof r) == 0);

    /* singular: every channel along x (f_y, f_z unobservable) */
    {
        long double sx[3] = {SENS_CPMS2, 0.0L, 0.0L};
        unsigned i;
        for (i = 0; i < 6; i++) {
            long double pos[3];
            pos[0] = 0.01L * (long double)i;
            pos[1] = 0.02L * (long double)(i % 3);
            pos[2] = 0.005L * (long double)(i % 2);
            geom_set(&g, i, sx, pos, 0.0L);
        }
        CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_ERR_SINGULAR);
        CHECK(memcmp(&r, &before, sizeof r) == 0);
    }
    /* singular: the seed layout with every chip at the centre (no lever arm) */
    seed_geom(&g, 0.0L);
    for (k = 0; k < 6; k++) {
        g.cal[k].pos[0] = 0;
        g.cal[k].pos[1] = 0;
        g.cal[k].pos[2] = 0;
    }
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_ERR_SINGULAR);
    CHECK(memcmp(&r, &before, sizeof r) == 0);
    /* singular: two channels of chip 2 both along its tangent */
    seed_geom(&g, 0.0L);
    g.cal[5].sens[0] = g.cal[4].sens[0];
    g.cal[5].sens[1] = g.cal[4].sens[1];
    g.cal[5].sens[2] = g.cal[4].sens[2];
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_ERR_SINGULAR);
    CHECK(memcmp(&r, &before, sizeof r) == 0);
    /* ill-conditioned: chip 2's z channel tilted to within ~2^-20 of... its
     * tangent (z component of a few LSB): cond ~ 2^21, pivot far above 2^-26 */
    g.cal[5].sens[2] = 8; /* 8 * 2^-16 counts per m/s^2 against 127 */
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_ERR_ILL_COND);
    CHECK(memcmp(&r, &before, sizeof r) == 0);
    /* ... and a milder tilt, cond ~ 2^11: accepted */
    g.cal[5].sens[2] = 8 << 10;
    CHECK_STATUS(ac_resolver_build(g.cal, 6, &work, &r, &info), AC_OK);
}

int main(void)
{
    test_rows();
    test_invert6();
    test_build();
    return AC_TEST_END();
}
