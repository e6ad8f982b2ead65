/*
 * Unit tests of ac_resolve.h: table checks, a hand-built table with values
 * worked out by hand, random tables against an exact reference (64-bit
 * integers for the linear part, long double for the centripetal term) held to
 * the accuracy bound stated in the header, saturation, ac_process and
 * ac_process_batch against the one-sample calls.
 */
#include <accelcal/accelcal.h>

#include <math.h>
#include <string.h>

#include "ac_test.h"

/* ---- reference ------------------------------------------------------------ */

static int bitlen_u(unsigned long long u)
{
    int n = 0;
    while (u != 0ull) {
        n++;
        u >>= 1;
    }
    return n;
}

static long long floor_pow2(long long x, int n)
{
    long long d = 1ll << n;
    long long q = x / d;
    if (q * d != x && x < 0) {
        q--;
    }
    return q;
}

/* round half up of acc * 2^-shift, exact (|acc| < 2^40, -31 <= shift <= 31) */
static long long round_shift(long long acc, int shift)
{
    if (shift > 0) {
        return floor_pow2(acc + (1ll << (shift - 1)), shift);
    }
    return acc * (1ll << -shift);
}

static long long clamp32(long long v, int *sat)
{
    if (v > 2147483647ll) {
        *sat = 1;
        return 2147483647ll;
    }
    if (v < -2147483648ll) {
        *sat = 1;
        return -2147483648ll;
    }
    return v;
}

/* sum_i m[j][i] x_i - k[j], exact */
static long long lin_acc(const ac_resolver *r, const int16_t *x, int j)
{
    long long acc = 0;
    unsigned i;
    for (i = 0; i < r->n; i++) {
        acc += (long long)r->m[j][i] * x[i];
    }
    return acc - r->k[j];
}

/* Exact out_j (in LSB, unrounded) and the header's bound E_j. */
static long double exact_out(const ac_resolver *r, const int16_t *x, const int16_t *w, int j,
                             long double *bound_e, long double *fp_tol)
{
    long double acc = (long double)lin_acc(r, x, j);
    long double t = 0.0L, e = 0.0L;
    if (w != NULL) {
        long long p[6], maxsq;
        long long gabs = 0, tg = 0;
        int q, s, d;
        p[0] = (long long)w[0] * w[0];
        p[1] = (long long)w[1] * w[1];
        p[2] = (long long)w[2] * w[2];
        p[3] = (long long)w[0] * w[1];
        p[4] = (long long)w[1] * w[2];
        p[5] = (long long)w[2] * w[0];
        maxsq = p[0] > p[1] ? p[0] : p[1];
        maxsq = maxsq > p[2] ? maxsq : p[2];
        s = bitlen_u((unsigned long long)maxsq) - 14;
        if (s < 0) {
            s = 0;
        }
        for (q = 0; q < 6; q++) {
            tg += (long long)r->g[j][q] * p[q]; /* exact: |.| < 2^47 */
            gabs += r->g[j][q] < 0 ? -(long long)r->g[j][q] : r->g[j][q];
        }
        /* T in accumulator units: g p 2^(m_shift - g_shift - 2 OMEGA_FRAC) */
        t = ldexpl((long double)tg, r->m_shift[j] - r->g_shift[j] - 2 * AC_OMEGA_FRAC);
        d = s - 2 * AC_OMEGA_FRAC - r->g_shift[j] + r->m_shift[j];
        if (s > 0) {
            e += ldexpl((long double)gabs, s - 1 - 2 * AC_OMEGA_FRAC - r->g_shift[j]);
        }
        if (d < 0) {
            e += ldexpl(1.0L, -1 - r->m_shift[j]);
        }
    }
    *bound_e = e;
    /* long double rounding of the reference itself (64-bit mantissa) */
    *fp_tol = ldexpl(fabsl(acc) + fabsl(t), -r->m_shift[j] - 60);
    return ldexpl(acc - t, -r->m_shift[j]);
}

/* ---- table helpers -------------------------------------------------------- */

static void zero_table(ac_resolver *r, uint16_t n)
{
    memset(r, 0, sizeof *r);
    r->n = n;
}

/* Random table; m rows with sum |m| <= l1max, g rows with sum |g| <= 65535.
 * k and the shifts keep |sum m x - k - T| < 2^31 (no intermediate clipping)
 * when 'no_clip' is set. */
static void random_table(ac_resolver *r, int no_clip)
{
    int j, q;
    unsigned i;
    zero_table(r, (uint16_t)ac_test_range(6, AC_MAX_CHANNELS));
    for (j = 0; j < 6; j++) {
        long l1max = no_clip ? 16383 : 65535;
        long budget = (long)ac_test_range(0, l1max);
        r->m_shift[j] = (int8_t)ac_test_range(-3, 24);
        for (i = 0; i < r->n && budget > 0; i++) {
            long lim = budget < 32767 ? budget : 32767;
            long v = (long)ac_test_range(-lim, lim);
            if ((ac_test_rand32() & 3ul) == 0ul) {
                v /= 64; /* small entries too */
            }
            r->m[j][i] = (int16_t)v;
            budget -= v < 0 ? -v : v;
        }
        r->k[j] = (int32_t)(no_clip ? ac_test_range(-(1ll << 29), 1ll << 29)
                                    : ac_test_s32(ac_test_rand32()) / 2);
        /* d = s - 20 - g_shift + m_shift <= 0 for every s <= 17 keeps T within
         * 2^30 accumulator units */
        {
            long gs = (long)r->m_shift[j] - 3 + (long)ac_test_range(0, 12);
            r->g_shift[j] = (int8_t)(gs > 31 ? 31 : (gs < -31 ? -31 : gs));
        }
        budget = (long)ac_test_range(0, 65535);
        for (q = 0; q < 6 && budget > 0; q++) {
            long lim = budget < 32767 ? budget : 32767;
            long v = (long)ac_test_range(-lim, lim);
            r->g[j][q] = (int16_t)v;
            budget -= v < 0 ? -v : v;
        }
    }
}

static void random_x(int16_t *x, unsigned n)
{
    unsigned i;
    for (i = 0; i < n; i++) {
        x[i] = (int16_t)((long)(ac_test_rand32() & 0xFFFFul) - 32768L);
        if (ac_test_rand32() & 1ul) {
            x[i] = (int16_t)(x[i] / 16); /* realistic readings: well inside int16 */
        }
        if (x[i] == 0 && (ac_test_rand32() & 1ul)) {
            x[i] = (int16_t)((ac_test_rand32() & 1ul) ? 32767 : -32768);
        }
    }
}

static void random_omega(int16_t *w)
{
    int a;
    int kind = (int)ac_test_range(0, 3);
    for (a = 0; a < 3; a++) {
        long v = (long)(ac_test_rand32() & 0xFFFFul) - 32768L;
        if (kind == 0) {
            v = (long)ac_test_range(-127, 127); /* |w| < 0.125 rad/s: p exact */
        } else if (kind == 1) {
            v = (long)ac_test_range(-4096, 4096); /* up to 4 rad/s */
        } else if (kind == 2) {
            v = (long)ac_test_range(-300, 300);
        }
        w[a] = (int16_t)v;
    }
}

/* ---- tests ------------------------------------------------------------------ */

static void test_check(void)
{
    static ac_resolver r;
    zero_table(&r, 6);
    CHECK_STATUS(ac_resolver_check(NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);
    r.n = 5;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_SIZE);
    r.n = 0;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_SIZE);
    r.n = AC_MAX_CHANNELS + 1;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_SIZE);
    r.n = AC_MAX_CHANNELS;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);

    /* shifts in -31..31 */
    r.m_shift[2] = 31;
    r.g_shift[3] = -31;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);
    r.m_shift[2] = 32;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_FORMAT);
    r.m_shift[2] = -32;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_FORMAT);
    r.m_shift[2] = 0;
    r.g_shift[5] = 32;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_FORMAT);
    r.g_shift[5] = -128;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_FORMAT);
    r.g_shift[5] = 0;

    /* row sums of |m| and |g| <= 65535 */
    r.m[1][0] = 32767;
    r.m[1][1] = -32767;
    r.m[1][11 % AC_MAX_CHANNELS] = 1;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK); /* 65535 */
    r.m[1][2] = 1;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_FORMAT); /* 65536 */
    r.m[1][2] = 0;
    r.g[4][0] = -32767;
    r.g[4][5] = -32767;
    r.g[4][3] = 1;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);
    r.g[4][2] = -1;
    CHECK_STATUS(ac_resolver_check(&r), AC_ERR_FORMAT);
    r.g[4][2] = 0;
    /* entries beyond n do not count */
    r.n = 6;
    r.m[0][6] = 32767;
    r.m[0][7] = 32767;
    r.m[0][8] = 32767;
    r.m[0][0] = 32767;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);

    /* -32768 is a legal int16 entry and a row {-32768, 0, ...} has sum |m| =
     * 32768 <= 65535: the header's invariants accept it. */
    zero_table(&r, 6);
    r.m[0][0] = -32768;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);
    zero_table(&r, 6);
    r.g[0][0] = -32768;
    CHECK_STATUS(ac_resolver_check(&r), AC_OK);
}

static void test_hand_table(void)
{
    static ac_resolver r;
    int16_t x[6] = {100, 30, -7, 0, 0, 0};
    int16_t w[3] = {1024, 0, 0}; /* 1 rad/s about x */
    int32_t out[6];
    int j;

    zero_table(&r, 6);
    /* out0 = (4*100 - 4*30 - 6) / 4 = 68.5 -> 69 (ties up) */
    r.m_shift[0] = 2;
    r.m[0][0] = 4;
    r.m[0][1] = -4;
    r.k[0] = 6;
    /* out1 = -(4*100 - 4*30 - 6) / 4 = -68.5 -> -68 */
    r.m_shift[1] = 2;
    r.m[1][0] = -4;
    r.m[1][1] = 4;
    r.k[1] = -6;
    /* out2 = 1024 * x2 (m_shift -10: an output LSB per count = 1 unit per count) */
    r.m_shift[2] = -10;
    r.m[2][2] = 1;
    /* out3 = x0 + x1 + x2 = 123 */
    r.m[3][0] = 1;
    r.m[3][1] = 1;
    r.m[3][2] = 1;
    /* out4 = round((3*100 + 5) * 2^-3) = round(38.125) = 38 */
    r.m_shift[4] = 3;
    r.m[4][0] = 3;
    r.k[4] = -5;
    /* out5 = k only: -(-12345) */
    r.k[5] = -12345;

    CHECK_STATUS(ac_resolver_check(&r), AC_OK);
    CHECK_STATUS(ac_resolve(&r, x, NULL, out), AC_OK);
    CHECK_EQ(out[0], 69);
    CHECK_EQ(out[1], -68);
    CHECK_EQ(out[2], -7 * 1024);
    CHECK_EQ(out[3], 123);
    CHECK_EQ(out[4], 38);
    CHECK_EQ(out[5], 12345);

    /* zero rotation == no rotation */
    {
        int16_t w0[3] = {0, 0, 0};
        int32_t out0[6];
        CHECK_STATUS(ac_resolve(&r, x, w0, out0), AC_OK);
        for (j = 0; j < 6; j++) {
            CHECK_EQ(out0[j], out[j]);
        }
    }

    /* centripetal: g[0][0] = 1 with g_shift = -10 is (M C)_00 = 1 m/s^2 per (rad/s)^2;
     * at 1 rad/s about x it removes exactly 1 m/s^2 = 1024 LSB from out0.
     * g[3] = (0,1,0, 0,0,0) senses wy^2 only: no change at w = (1,0,0). */
    r.g_shift[0] = -10;
    r.g[0][0] = 1;
    r.g_shift[3] = -10;
    r.g[3][1] = 1;
    CHECK_STATUS(ac_resolve(&r, x, w, out), AC_OK);
    CHECK_EQ(out[0], 69 - 1024);
    CHECK_EQ(out[1], -68);
    CHECK_EQ(out[3], 123);
    /* w = (0, 2, 0) rad/s: wy^2 = 4 (rad/s)^2 -> out3 = 123 - 4096, out0 unchanged */
    w[0] = 0;
    w[1] = 2048;
    CHECK_STATUS(ac_resolve(&r, x, w, out), AC_OK);
    CHECK_EQ(out[0], 69);
    CHECK_EQ(out[3], 123 - 4096);
    /* w = (-1, 0.5, 0): cross term wx*wy through g[5][3] = -2: +1 m/s^2 */
    r.g_shift[5] = -10;
    r.g[5][3] = -2;
    w[0] = -1024;
    w[1] = 512;
    CHECK_STATUS(ac_resolve(&r, x, w, out), AC_OK);
    CHECK_EQ(out[5], 12345 - 1024);
    CHECK_EQ(out[0], 69 - 1024);
    CHECK_EQ(out[3], 123 - 256);

    /* NULLs and a bad table */
    CHECK_STATUS(ac_resolve(NULL, x, w, out), AC_ERR_NULL);
    CHECK_STATUS(ac_resolve(&r, NULL, w, out), AC_ERR_NULL);
    CHECK_STATUS(ac_resolve(&r, x, w, NULL), AC_ERR_NULL);
    out[0] = 0x5A5A5A5AL;
    r.n = 3;
    CHECK_STATUS(ac_resolve(&r, x, w, out), AC_ERR_SIZE);
    r.n = AC_MAX_CHANNELS + 1;
    CHECK_STATUS(ac_resolve(&r, x, w, out), AC_ERR_SIZE);
    r.n = 6;
    r.m_shift[0] = 40;
    CHECK_STATUS(ac_resolve(&r, x, w, out), AC_ERR_FORMAT);
    CHECK_EQ(out[0], 0x5A5A5A5AL); /* outputs not written on error */
}

static void test_saturation(void)
{
    static ac_resolver r;
    int16_t x[AC_MAX_CHANNELS];
    int32_t out[6];
    int j;
    unsigned i;

    /* Full-range rows: sum |m| = 65535 with x = -32768 everywhere stays inside
     * int32 (|sum| = 2^31 - 2^15) and is exact. */
    zero_table(&r, AC_MAX_CHANNELS);
    for (i = 0; i < AC_MAX_CHANNELS; i++) {
        x[i] = -32768;
    }
    for (j = 0; j < 6; j++) {
        r.m[j][0] = 32767;
        r.m[j][1] = 32767;
        r.m[j][2] = 1;
    }
    r.m[1][0] = -32767; /* row 1: -32767 + 32767 + 1 */
    r.m_shift[2] = 31;  /* -(2^31 - 2^15) / 2^31 = -0.99998 -> -1 */
    r.m_shift[3] = 15;  /* -(2^16 - 1) exactly */
    r.m_shift[4] = -1;  /* doubles out of range: clipped */
    CHECK_STATUS(ac_resolve(&r, x, NULL, out), AC_SATURATED);
    CHECK_EQ(out[0], -2147450880LL);
    CHECK_EQ(out[1], -32768);
    CHECK_EQ(out[2], -1);
    CHECK_EQ(out[3], -65535);
    CHECK_EQ(out[4], INT32_MIN);
    CHECK_EQ(out[5], -2147450880LL);
    for (i = 0; i < AC_MAX_CHANNELS; i++) {
        x[i] = 32767;
    }
    r.m_shift[4] = 0;
    CHECK_STATUS(ac_resolve(&r, x, NULL, out), AC_OK);
    CHECK_EQ(out[0], 2147385345LL); /* 65535 * 32767 */

    /* the offset pushes the accumulator past int32: clipped, AC_SATURATED */
    r.k[0] = INT32_MIN;
    CHECK_STATUS(ac_resolve(&r, x, NULL, out), AC_SATURATED);
    CHECK_EQ(out[0], INT32_MAX);
    r.k[0] = 0;

    /* a centripetal term beyond int32 (w = 32 rad/s, g = 32767 with g_shift = -31:
     * T ~ 2^56 accumulator units): the exact output is far below INT32_MIN, so
     * the clipped output is INT32_MIN whatever the linear part is. */
    r.g_shift[5] = -31;
    r.g[5][0] = 32767;
    {
        int16_t w[3] = {-32768, 0, 0};
        CHECK_STATUS(ac_resolve(&r, x, w, out), AC_SATURATED);
        CHECK_EQ(out[5], INT32_MIN);
        CHECK_EQ(out[0], 2147385345LL); /* other rows unaffected */
    }
}

static void test_random(void)
{
    static ac_resolver r;
    int16_t x[AC_MAX_CHANNELS], w[3];
    int32_t out[6], out_null[6];
    long it;
    int j;
    long double worst = 0.0L; /* largest error as a fraction of the allowed bound */

    ac_test_seed(2024ul);
    for (it = 0; it < 20000; it++) {
        ac_status st;
        int sat = 0;
        ac_test_context("random resolve", it);
        random_table(&r, 1);
        random_x(x, r.n);
        random_omega(w);
        CHECK_STATUS(ac_resolver_check(&r), AC_OK);

        /* no rotation: exact (one rounding, ties up) */
        st = ac_resolve(&r, x, NULL, out_null);
        for (j = 0; j < 6; j++) {
            long long want = clamp32(round_shift(lin_acc(&r, x, j), r.m_shift[j]), &sat);
            CHECK_MSG(out_null[j] == want, ("row %d: %ld != %lld (m_shift %d)", j,
                                            (long)out_null[j], want, r.m_shift[j]));
        }
        CHECK_EQ(st, sat ? AC_SATURATED : AC_OK);

        /* rotation: within 0.5 LSB + E_j of the exact value */
        sat = 0;
        st = ac_resolve(&r, x, w, out);
        for (j = 0; j < 6; j++) {
            long double e, tol;
            long double want = exact_out(&r, x, w, j, &e, &tol);
            if (want > 2147483647.0L || want < -2147483648.0L) {
                sat = 1;
                CHECK_EQ(out[j], want > 0 ? INT32_MAX : INT32_MIN);
            } else {
                long double err = fabsl((long double)out[j] - want);
                long double lim = 0.5L + e + tol;
                if (err / lim > worst) {
                    worst = err / lim;
                }
                CHECK_MSG(err <= lim,
                          ("row %d: out %ld, exact %.6Lf, err %.6Lf > 0.5 + E %.6Lf "
                           "(w = %d %d %d, m_shift %d, g_shift %d)",
                           j, (long)out[j], want, err, e, w[0], w[1], w[2], r.m_shift[j],
                           r.g_shift[j]));
            }
        }
        if (sat) {
            CHECK_EQ(st, AC_SATURATED);
        } else {
            CHECK(st == AC_OK || st == AC_SATURATED); /* a near-limit value may clip */
        }
    }
    ac_test_context("", -1);
    printf("random resolve: worst error / allowed bound = %.4Lf\n", worst);
}

static void test_process(void)
{
    static ac_resolver r;
    enum { COUNT = 17 };
    static uint16_t raw[COUNT * AC_MAX_CHANNELS];
    static int16_t omega[COUNT * 3];
    static int32_t out[COUNT * 6];
    static uint8_t flags[COUNT];
    uint16_t trim[AC_MAX_CHANNELS];
    int16_t x[AC_MAX_CHANNELS];
    int32_t one[6];
    long it;
    unsigned i, k;
    int j;

    ac_test_seed(31337ul);
    for (it = 0; it < 300; it++) {
        ac_status st, st_batch, any = AC_OK;
        ac_test_context("process", it);
        random_table(&r, (int)(it & 1));
        for (i = 0; i < r.n; i++) {
            trim[i] = (uint16_t)ac_test_range(3000, 7000);
        }
        for (k = 0; k < COUNT; k++) {
            for (i = 0; i < r.n; i++) {
                /* mostly near the trim; now and then far enough to clip */
                long v = (long)trim[i] + (long)ac_test_range(-5000, 5000);
                if ((ac_test_rand32() & 15ul) == 0ul) {
                    v = (long)(ac_test_rand32() & 0xFFFFul);
                }
                raw[k * r.n + i] = (uint16_t)(v < 0 ? 0 : (v > 65535 ? 65535 : v));
            }
            random_omega(&omega[k * 3]);
        }

        /* ac_process == ac_trim + ac_resolve */
        for (k = 0; k < COUNT; k++) {
            ac_status st_t, st_r, want;
            int32_t out_p[6];
            const int16_t *wk = (k % 3 == 0) ? NULL : &omega[k * 3];
            st_t = ac_trim(&raw[k * r.n], trim, r.n, x);
            st_r = ac_resolve(&r, x, wk, one);
            st = ac_process(&r, trim, &raw[k * r.n], wk, out_p);
            want = (st_t == AC_SATURATED || st_r == AC_SATURATED) ? AC_SATURATED : AC_OK;
            CHECK_EQ(st, want);
            for (j = 0; j < 6; j++) {
                CHECK_EQ(out_p[j], one[j]);
            }
        }

        /* batch with omega and flags */
        memset(flags, 0xEE, sizeof flags);
        st_batch = ac_process_batch(&r, trim, raw, COUNT, omega, out, flags);
        for (k = 0; k < COUNT; k++) {
            ac_status st_t = ac_trim(&raw[k * r.n], trim, r.n, x);
            ac_status st_r = ac_resolve(&r, x, &omega[k * 3], one);
            unsigned want_f = (st_t == AC_SATURATED ? AC_FLAG_TRIM_SAT : 0u) |
                              (st_r == AC_SATURATED ? AC_FLAG_OUT_SAT : 0u);
            if (want_f) {
                any = AC_SATURATED;
            }
            CHECK_EQ(flags[k], want_f);
            for (j = 0; j < 6; j++) {
                CHECK_EQ(out[k * 6 + (unsigned)j], one[j]);
            }
        }
        CHECK_EQ(st_batch, any);

        /* batch without omega or flags */
        any = AC_OK;
        st_batch = ac_process_batch(&r, trim, raw, COUNT, NULL, out, NULL);
        for (k = 0; k < COUNT; k++) {
            ac_status st_t = ac_trim(&raw[k * r.n], trim, r.n, x);
            ac_status st_r = ac_resolve(&r, x, NULL, one);
            if (st_t == AC_SATURATED || st_r == AC_SATURATED) {
                any = AC_SATURATED;
            }
            for (j = 0; j < 6; j++) {
                CHECK_EQ(out[k * 6 + (unsigned)j], one[j]);
            }
        }
        CHECK_EQ(st_batch, any);
    }
    ac_test_context("", -1);

    /* status codes */
    CHECK_STATUS(ac_process(NULL, trim, raw, NULL, one), AC_ERR_NULL);
    CHECK_STATUS(ac_process(&r, NULL, raw, NULL, one), AC_ERR_NULL);
    CHECK_STATUS(ac_process(&r, trim, NULL, NULL, one), AC_ERR_NULL);
    CHECK_STATUS(ac_process(&r, trim, raw, NULL, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_process_batch(NULL, trim, raw, 1, NULL, out, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_process_batch(&r, NULL, raw, 1, NULL, out, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_process_batch(&r, trim, NULL, 1, NULL, out, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_process_batch(&r, trim, raw, 1, NULL, NULL, NULL), AC_ERR_NULL);
    {
        /* count = 0: nothing to do (or refused as a size error); nothing written */
        ac_status st;
        out[0] = 0x5A5A5A5AL;
        st = ac_process_batch(&r, trim, raw, 0, NULL, out, NULL);
        CHECK(st == AC_OK || st == AC_ERR_SIZE);
        CHECK_EQ(out[0], 0x5A5A5A5AL);
    }
    /* A corrupt table (row sums far beyond 65535): ac_resolve checks only the
     * shape per call and may give wrong numbers, but never undefined behaviour
     * (the sanitizer build runs this); ac_process_batch runs the full check. */
    {
        static ac_resolver bad;
        int16_t xs[AC_MAX_CHANNELS];
        ac_status st;
        zero_table(&bad, AC_MAX_CHANNELS);
        for (i = 0; i < AC_MAX_CHANNELS; i++) {
            xs[i] = -32768;
            raw[i] = 0;
            trim[i] = 65535;
            for (j = 0; j < 6; j++) {
                bad.m[j][i] = 32767;
                bad.g[j][i % 6] = -32768;
            }
        }
        for (j = 0; j < 6; j++) {
            bad.k[j] = INT32_MIN;
            bad.m_shift[j] = (int8_t)(j - 3);
            bad.g_shift[j] = (int8_t)(-31 + 12 * j);
        }
        CHECK_STATUS(ac_resolver_check(&bad), AC_ERR_FORMAT);
        {
            int16_t wbad[3] = {-32768, -32768, -32768};
            st = ac_resolve(&bad, xs, wbad, one);
            CHECK(st == AC_OK || st == AC_SATURATED || st == AC_ERR_FORMAT);
            st = ac_process(&bad, trim, raw, wbad, one);
            CHECK(st == AC_OK || st == AC_SATURATED || st == AC_ERR_FORMAT);
        }
        out[0] = 0x5A5A5A5AL;
        CHECK_STATUS(ac_process_batch(&bad, trim, raw, 1, NULL, out, NULL), AC_ERR_FORMAT);
        CHECK_EQ(out[0], 0x5A5A5A5AL);
    }

    r.n = 5;
    one[0] = 0x5A5A5A5AL;
    CHECK_STATUS(ac_process(&r, trim, raw, NULL, one), AC_ERR_SIZE);
    CHECK_STATUS(ac_process_batch(&r, trim, raw, 1, NULL, out, NULL), AC_ERR_SIZE);
    CHECK_EQ(one[0], 0x5A5A5A5AL);
    r.n = AC_MAX_CHANNELS + 1;
    CHECK_STATUS(ac_process(&r, trim, raw, NULL, one), AC_ERR_SIZE);
    CHECK_STATUS(ac_process_batch(&r, trim, raw, 1, NULL, out, NULL), AC_ERR_SIZE);
}

int main(void)
{
    test_check();
    test_hand_table();
    test_saturation();
    test_random();
    test_process();
    return AC_TEST_END();
}
