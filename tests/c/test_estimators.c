/*
 * Unit tests of the motion estimators (ac_trig, ac_rest, ac_attitude,
 * ac_displace): exact primitives against 64-bit integer arithmetic, atan2
 * against the C library within the header's bound, status codes and NULL
 * handling, a noise-free pendulum (theta, w, dw against the physics), a
 * noise-free stop-to-stop motion with a zero-point error (corrected end
 * point), and the end-of-stream flags.  The hypothesis properties against
 * the float twins are in tests/python/test_estimators.py; this program gives
 * the sanitizer and valgrind builds the C paths.
 */
#include <accelcal/accelcal.h>

#include <math.h>

#include "ac_test.h"

static unsigned long long rng_state = 88172645463325252ull;
static unsigned long long rnd(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return rng_state;
}

static void test_primitives(void)
{
    int i;
    uint16_t r16 = 0;
    uint32_t q = 0;
    int32_t o = 0;
    CHECK_STATUS(ac_isqrt32(0u, &r16), AC_OK);
    CHECK_EQ(r16, 0);
    CHECK_STATUS(ac_isqrt32(4294901760u, &r16), AC_OK);
    CHECK_EQ(r16, 65535);
    CHECK_STATUS(ac_isqrt32(4294901761u, &r16), AC_SATURATED);
    CHECK_STATUS(ac_isqrt32(5u, 0), AC_ERR_NULL);
    CHECK_STATUS(ac_udiv64(0u, 7u, 0u, &q), AC_ERR_RANGE);
    CHECK_STATUS(ac_udiv64(5u, 0u, 5u, &q), AC_SATURATED);
    CHECK_STATUS(ac_mul32x16_shift(1, 1, 48u, &o), AC_ERR_RANGE);
    for (i = 0; i < 20000; i++) {
        uint32_t v = (uint32_t)rnd();
        unsigned long long s = (unsigned long long)sqrt((double)v);
        uint32_t den = (uint32_t)rnd() | 1u;
        uint32_t hi = (uint32_t)rnd() % den, lo = (uint32_t)rnd();
        unsigned long long num = ((unsigned long long)hi << 32) | lo; /* < 2^64: hi < den */
        unsigned long long qf = num / den, rem = num % den;
        unsigned long long exact = qf + ((rem >= den - rem) ? 1u : 0u);
        int32_t a = (int32_t)(uint32_t)rnd();
        uint16_t b = (uint16_t)rnd();
        uint8_t n = (uint8_t)(rnd() % 48u);
        long long p = (long long)a * b, e;
        while (s * s > v) {
            s--;
        }
        while ((s + 1) * (s + 1) <= v) {
            s++;
        }
        if (v - s * s > s) {
            s++;
        }
        ac_test_context("random", i);
        if (s <= 65535u) {
            CHECK_STATUS(ac_isqrt32(v, &r16), AC_OK);
            CHECK_EQ(r16, s);
        }
        if (exact <= 0xFFFFFFFFu) {
            CHECK_STATUS(ac_udiv64(hi, lo, den, &q), AC_OK);
            CHECK_EQ(q, exact);
        }
        /* floor((p + 2^(n-1)) / 2^n), half up */
        e = (n == 0u) ? p : (p + (1ll << (n - 1u))) >> n; /* arithmetic shift of long long on the host */
        if (e >= INT32_MIN && e <= INT32_MAX) {
            CHECK_STATUS(ac_mul32x16_shift(a, b, n, &o), AC_OK);
            CHECK_EQ(o, e);
        } else {
            CHECK_STATUS(ac_mul32x16_shift(a, b, n, &o), AC_SATURATED);
        }
    }
    ac_test_context("", -1);
}

static void test_atan2(void)
{
    int i;
    int16_t ang = 0;
    uint32_t mag = 0;
    CHECK_STATUS(ac_atan2(0, 0, &ang, &mag), AC_OK);
    CHECK_EQ(ang, 0);
    CHECK_STATUS(ac_atan2(0, -5, &ang, &mag), AC_OK);
    CHECK_EQ(ang, AC_PI_Q13);
    CHECK_STATUS(ac_atan2(1, 1, 0, &mag), AC_ERR_NULL);
    for (i = 0; i < 20000; i++) {
        int sh = (int)(rnd() % 32u);
        int32_t y = (int32_t)((int64_t)(int32_t)(uint32_t)rnd() >> sh);
        int32_t x = (int32_t)((int64_t)(int32_t)(uint32_t)rnd() >> sh);
        double t, err, h;
        if (x == 0 && y == 0) {
            continue;
        }
        (void)ac_atan2(y, x, &ang, &mag);
        t = atan2((double)y, (double)x) * 8192.0;
        err = fabs(ang - t);
        if (err > 8192.0 * 3.141592653589793) {
            err = fabs(err - 2.0 * 8192.0 * 3.141592653589793);
        }
        h = hypot((double)x, (double)y);
        ac_test_context("atan2", i);
        CHECK_MSG(err <= 0.76, ("y=%ld x=%ld angle=%d exact=%.3f", (long)y, (long)x, ang, t));
        CHECK_MSG(fabs((double)mag - h) <= h / 16384.0 + 1.0, ("mag %lu vs %.1f", (unsigned long)mag, h));
    }
    ac_test_context("", -1);
}

static void test_attitude(void)
{
    /* noise-free pendulum, r1 = 0.1 m, r2 = 0.3 m, 100 Hz, theta = 0.6 cos(pi t) */
    static ac_att st;
    ac_att_out out;
    int32_t f1[3], f2[3];
    const double g = 9.80665, dt = 0.01, om = 3.141592653589793, A = 0.6;
    double worst_th = 0, worst_w = 0, worst_a = 0;
    int n;
    CHECK_STATUS(ac_att_init(&st, 104858, 104858, 41943u, 22u, 512u, 0, 0), AC_ERR_SINGULAR);
    CHECK_STATUS(ac_att_init(0, 1, 2, 41943u, 22u, 512u, 0, 0), AC_ERR_NULL);
    CHECK_STATUS(ac_att_init(&st, 104858, 314573, 41943u, 22u, 512u, 1000, 328u), AC_OK);
    CHECK_STATUS(ac_att_step(&st, 0, f2, &out), AC_ERR_NULL);
    for (n = 0; n < 400; n++) {
        double t = n * dt, th = A * cos(om * t), w = -A * om * sin(om * t), a = -A * om * om * cos(om * t);
        int k;
        for (k = 0; k < 2; k++) {
            double r = k ? 0.3 : 0.1;
            int32_t *f = k ? f2 : f1;
            f[0] = (int32_t)lround((-g * sin(th) - w * w * r) * 1024.0);
            f[1] = 0;
            f[2] = (int32_t)lround((g * cos(th) - a * r) * 1024.0);
        }
        CHECK(ac_att_step(&st, f1, f2, &out) == AC_OK);
        if (fabs(out.theta / 8192.0 - th) > worst_th) {
            worst_th = fabs(out.theta / 8192.0 - th);
        }
        if (n > 0 && fabs(out.w / 1024.0 - w) > worst_w) {
            worst_w = fabs(out.w / 1024.0 - w);
        }
        if (fabs(out.dw / 1024.0 - a) > worst_a) {
            worst_a = fabs(out.dw / 1024.0 - a);
        }
        CHECK((out.flags & AC_ATT_UNSETTLED) == 0u); /* starts at a turning point: gated */
        CHECK_NEAR(out.gmag / 1024.0, g, 0.01);
    }
    CHECK_MSG(worst_th < 0.0015, ("theta worst %.5f rad", worst_th));
    CHECK_MSG(worst_w < 0.03, ("w worst %.4f rad/s", worst_w));
    CHECK_MSG(worst_a < 0.02, ("alpha worst %.4f rad/s^2", worst_a));
}

static void rest_cfg(ac_rest_cfg *c)
{
    c->dev_max = 51;         /* 0.05 m/s^2 */
    c->g2_lo = 0u;
    c->g2_hi = 0xFFFFFFFFu;
    c->alpha_max = 0;
    c->ref_max = 154;        /* 0.15 m/s^2 */
    c->hold = 20u;
    c->ema_shift = 3u;
}

static void test_displacement(void)
{
    /* 1-D: 1 s rest, 0.5 m in 2 s (min-jerk), 2 s rest, zero-point error 0.05 m/s^2; 100 Hz */
    static ac_disp st;
    ac_disp_cfg cfg;
    ac_disp_out out;
    int32_t f[3];
    int n, ends = 0;
    double p_end = 0.0, zp = 0.0;
    rest_cfg(&cfg.rest);
    cfg.dt_m = 41943u; /* 0.01 s = 41943 2^-22 */
    cfg.dt_shift = 22u;
    cfg.axis = 0;
    CHECK_STATUS(ac_disp_init(&st, &cfg), AC_OK);
    cfg.axis = 3;
    CHECK_STATUS(ac_disp_init(&st, &cfg), AC_ERR_RANGE);
    cfg.axis = 0;
    (void)ac_disp_init(&st, &cfg);
    for (n = 0; n < 500; n++) {
        double t = n * 0.01 - 1.0, a = 0.0;
        if (t >= 0.0 && t < 2.0) {
            double u = t / 2.0;
            a = 0.5 / 4.0 * 60.0 * (u - 3 * u * u + 2 * u * u * u);
        }
        f[0] = (int32_t)lround((a + 0.05) * 1024.0);
        f[1] = 0;
        f[2] = 10042;
        CHECK(ac_disp_step(&st, f, &out) == AC_OK);
        if (out.flags & AC_DISP_SEG_END) {
            ends++;
            p_end = out.p[0] / 1048576.0;
            zp = out.zp[0] / 65536.0;
        }
    }
    CHECK_EQ(ends, 1);
    CHECK_NEAR(p_end, 0.5, 0.5 * 0.002);
    CHECK_NEAR(zp, 0.05, 0.002);
    CHECK(ac_disp_finish(&st, &out) == AC_OK && (out.flags & AC_DISP_REST));

    /* 3-axis, level, never at rest: finish says NO_REST; NULLs */
    cfg.axis = -1;
    (void)ac_disp_init(&st, &cfg);
    for (n = 0; n < 100; n++) {
        f[0] = (n & 1) ? 600 : -600;
        f[1] = 0;
        f[2] = 10042;
        (void)ac_disp_step(&st, f, &out);
        CHECK(out.flags & AC_DISP_NO_REF);
    }
    CHECK(ac_disp_finish(&st, &out) == AC_OK && (out.flags & AC_DISP_NO_REST));
    CHECK_STATUS(ac_disp_step(&st, 0, &out), AC_ERR_NULL);
    CHECK_STATUS(ac_disp_finish(0, &out), AC_ERR_NULL);
}

static void test_tilt_frame(void)
{
    int i;
    int16_t rot[3][3];
    int32_t g[3] = {0, 0, 0};
    CHECK_STATUS(ac_tilt_frame(g, rot), AC_ERR_SINGULAR);
    for (i = 0; i < 2000; i++) {
        double v[3], n = 0.0, m[3][3];
        int j, k;
        for (k = 0; k < 3; k++) {
            v[k] = (double)(int32_t)(uint32_t)rnd() / 2147483648.0;
            n += v[k] * v[k];
        }
        n = sqrt(n);
        if (n < 0.01) {
            continue;
        }
        for (k = 0; k < 3; k++) {
            g[k] = (int32_t)lround(v[k] / n * 9.8 * 65536.0);
        }
        CHECK(ac_tilt_frame(g, rot) == AC_OK);
        /* orthonormal rows, z along g */
        for (j = 0; j < 3; j++) {
            for (k = 0; k < 3; k++) {
                m[j][k] = rot[j][k] / 16384.0;
            }
        }
        for (j = 0; j < 3; j++) {
            for (k = 0; k < 3; k++) {
                double d = m[j][0] * m[k][0] + m[j][1] * m[k][1] + m[j][2] * m[k][2];
                CHECK_NEAR(d, j == k ? 1.0 : 0.0, 6.0 / 16384.0);
            }
            CHECK_NEAR(m[2][j], v[j] / n, 2.0 / 16384.0);
        }
    }
}

static void test_rest(void)
{
    static ac_rest st;
    static ac_rate rate;
    ac_rest_cfg c;
    int32_t f[3] = {0, 0, 10042}, a[3] = {0, 0, 0};
    int16_t w[3];
    uint8_t fl = 0;
    int n;
    rest_cfg(&c);
    c.hold = 0u;
    CHECK_STATUS(ac_rest_init(&st, &c), AC_ERR_RANGE);
    rest_cfg(&c);
    c.alpha_max = 100;
    CHECK_STATUS(ac_rest_init(&st, &c), AC_OK);
    (void)ac_rate_init(&rate, 41943u, 22u, 0u);
    for (n = 0; n < 60; n++) {
        a[2] = (n >= 30) ? 2000 : 0;   /* rotation starts: no longer at rest */
        CHECK(ac_rest_rate_step(&st, &rate, f, a, w, &fl) >= 0);
        if (n == 19) {
            CHECK(fl & AC_REST_ENTER);
        }
        if (n >= 19 && n < 30) {
            CHECK((fl & AC_REST_AT_REST) && w[2] == 0);
        }
        if (n == 30) {
            CHECK(fl & AC_REST_LEAVE);
        }
    }
    CHECK(!(fl & AC_REST_AT_REST) && w[2] > 0);
}

int main(void)
{
    test_primitives();
    test_atan2();
    test_attitude();
    test_tilt_frame();
    test_displacement();
    test_rest();
    return AC_TEST_END();
}
