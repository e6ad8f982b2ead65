/*
 * Unit tests of ac_rate.h: status codes, integration of a constant alpha
 * against N dt alpha, the leaky integrator against its exact recurrence
 * (held to the header's rounding bound: at most 2 x 2^-27 rad/s per step),
 * omega as the rounded state, and saturation without wrap-around.
 */
#include <accelcal/accelcal.h>

#include <math.h>
#include <string.h>

#include "ac_test.h"

#define STATE_LSB 1.490116119384765625e-08L /* 2^-26 rad/s */

static long long floor_pow2(long long x, int n)
{
    long long d = 1ll << n;
    long long q = x / d;
    if (q * d != x && x < 0) {
        q--;
    }
    return q;
}

/* omega expected from the state: round(w 2^-16) half up, clipped to int16 */
static long long omega_of(long long w, int *sat)
{
    long long o = floor_pow2(w + (1ll << 15), 16);
    if (o > 32767) {
        *sat = 1;
        return 32767;
    }
    if (o < -32768) {
        *sat = 1;
        return -32768;
    }
    return o;
}

static long double dt_of(unsigned dt_m, unsigned dt_shift)
{
    return ldexpl((long double)dt_m, -(int)dt_shift);
}

static void test_status(void)
{
    ac_rate st, copy;
    int32_t alpha[3] = {0, 0, 0};
    int16_t omega[3];

    memset(&st, 0x5A, sizeof st);
    copy = st;
    CHECK_STATUS(ac_rate_init(NULL, 34953, 21, 0), AC_ERR_NULL);
    CHECK_STATUS(ac_rate_init(&st, 34953, 15, 0), AC_ERR_RANGE);
    CHECK(memcmp(&st, &copy, sizeof st) == 0);
    CHECK_STATUS(ac_rate_init(&st, 34953, 47, 0), AC_ERR_RANGE);
    CHECK_STATUS(ac_rate_init(&st, 34953, 255, 0), AC_ERR_RANGE);
    CHECK(memcmp(&st, &copy, sizeof st) == 0);

    CHECK_STATUS(ac_rate_init(&st, 34953, 16, 0), AC_OK);
    CHECK_STATUS(ac_rate_init(&st, 34953, 46, 0), AC_OK);
    CHECK_STATUS(ac_rate_init(&st, 34953, 21, 655), AC_OK);
    CHECK_EQ(st.w[0], 0);
    CHECK_EQ(st.w[1], 0);
    CHECK_EQ(st.w[2], 0);
    CHECK_EQ(st.dt_m, 34953);
    CHECK_EQ(st.dt_shift, 21);
    CHECK_EQ(st.leak, 655);

    CHECK_STATUS(ac_rate_reset(NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_rate_step(NULL, alpha, omega), AC_ERR_NULL);
    CHECK_STATUS(ac_rate_step(&st, NULL, omega), AC_ERR_NULL);
    CHECK_STATUS(ac_rate_step(&st, alpha, NULL), AC_ERR_NULL);

    /* reset clears the state and keeps dt and leak */
    alpha[0] = 1024;
    alpha[1] = -1024;
    alpha[2] = 7;
    CHECK_STATUS(ac_rate_step(&st, alpha, omega), AC_OK);
    CHECK(st.w[0] != 0 && st.w[1] != 0 && st.w[2] != 0);
    CHECK_STATUS(ac_rate_reset(&st), AC_OK);
    CHECK_EQ(st.w[0], 0);
    CHECK_EQ(st.w[1], 0);
    CHECK_EQ(st.w[2], 0);
    CHECK_EQ(st.dt_m, 34953);
    CHECK_EQ(st.dt_shift, 21);
    CHECK_EQ(st.leak, 655);
}

/* Constant alpha, no leak: w_N = N dt alpha (within N x 2 x 2^-27 rad/s). */
static void test_constant(unsigned dt_m, unsigned dt_shift, long a0, long a1, long a2, int steps)
{
    ac_rate st;
    int32_t alpha[3];
    int16_t omega[3];
    int n, a;
    long double dt = dt_of(dt_m, dt_shift);
    alpha[0] = (int32_t)a0;
    alpha[1] = (int32_t)a1;
    alpha[2] = (int32_t)a2;
    CHECK_STATUS(ac_rate_init(&st, (uint16_t)dt_m, (uint8_t)dt_shift, 0), AC_OK);
    for (n = 1; n <= steps; n++) {
        int sat = 0;
        ac_status s = ac_rate_step(&st, alpha, omega);
        for (a = 0; a < 3; a++) {
            long double exact = (long double)n * dt * ldexpl((long double)alpha[a], -AC_OUT_FRAC);
            long double got = (long double)st.w[a] * STATE_LSB;
            CHECK_MSG(fabsl(got - exact) <= (long double)n * 2.0L * STATE_LSB / 2.0L,
                      ("axis %d step %d: w %.12Lg, exact %.12Lg", a, n, got, exact));
            CHECK_EQ(omega[a], omega_of(st.w[a], &sat));
            CHECK_NEAR((long double)omega[a] / 1024.0L, exact,
                       (long double)n * STATE_LSB + 1.0L / 2048.0L);
        }
        CHECK_EQ(s, sat ? AC_SATURATED : AC_OK);
    }
}

/* Leaky integration against the exact recurrence, random alpha. */
static void test_leaky_random(void)
{
    long run;
    ac_test_seed(8080ul);
    for (run = 0; run < 200; run++) {
        ac_rate st;
        int32_t alpha[3];
        int16_t omega[3];
        long double w_ex[3] = {0.0L, 0.0L, 0.0L};
        unsigned dt_shift = (unsigned)ac_test_range(16, 46);
        unsigned dt_m = (unsigned)ac_test_range(32768, 65535); /* 16 significant bits */
        unsigned leak = (run % 4 == 0) ? 0u : (unsigned)ac_test_range(1, 65535);
        long double dt = dt_of(dt_m, dt_shift);
        long double keep = 1.0L - ldexpl((long double)leak, -16);
        /* alpha range so that |w| stays well below 32 rad/s for 400 steps */
        long double amax = 8.0L / (400.0L * dt);
        long amax_q = amax * 1024.0L > 2.0e9L ? 2000000000L : (long)(amax * 1024.0L);
        int n, a;
        if (amax_q < 1) {
            amax_q = 1;
        }
        ac_test_context("leaky run", run);
        CHECK_STATUS(ac_rate_init(&st, (uint16_t)dt_m, (uint8_t)dt_shift, (uint16_t)leak), AC_OK);
        for (n = 1; n <= 400; n++) {
            int sat = 0;
            ac_status s;
            for (a = 0; a < 3; a++) {
                alpha[a] = (int32_t)ac_test_range(-amax_q, amax_q);
            }
            s = ac_rate_step(&st, alpha, omega);
            for (a = 0; a < 3; a++) {
                long double got = (long double)st.w[a] * STATE_LSB;
                w_ex[a] = w_ex[a] * keep + dt * ldexpl((long double)alpha[a], -AC_OUT_FRAC);
                /* each step: the previous error shrinks by keep <= 1, two new
                 * roundings of at most 2^-27 each */
                CHECK_MSG(fabsl(got - w_ex[a]) <= (long double)n * STATE_LSB * 1.0000001L,
                          ("axis %d step %d (dt %u*2^-%u, leak %u): w %.12Lg, exact %.12Lg, "
                           "err %.3Lg LSB",
                           a, n, dt_m, dt_shift, leak, got, w_ex[a],
                           fabsl(got - w_ex[a]) / STATE_LSB));
                CHECK_EQ(omega[a], omega_of(st.w[a], &sat));
            }
            CHECK_EQ(s, sat ? AC_SATURATED : AC_OK);
        }
    }
    ac_test_context("", -1);
}

/* The leak makes a high-pass: constant alpha settles at dt alpha 2^16 / leak. */
static void test_leaky_steady(void)
{
    ac_rate st;
    int32_t alpha[3] = {1024, -3072, 0}; /* 1 and -3 rad/s^2 */
    int16_t omega[3];
    int n;
    long double dt = dt_of(34953, 21);
    long double gain = dt * 65536.0L / 655.0L; /* tau ~ 1.67 s */
    CHECK_STATUS(ac_rate_init(&st, 34953, 21, 655), AC_OK);
    for (n = 0; n < 6000; n++) {
        CHECK_STATUS(ac_rate_step(&st, alpha, omega), AC_OK);
    }
    /* e^-(6000 / 100) of the start-up is left; the rounding error is bounded by
     * 2^-26 / (leak / 2^16) */
    CHECK_NEAR((long double)st.w[0] * STATE_LSB, 1.0L * gain, STATE_LSB * 65536.0L / 655.0L);
    CHECK_NEAR((long double)st.w[1] * STATE_LSB, -3.0L * gain, STATE_LSB * 65536.0L / 655.0L);
    CHECK_EQ(st.w[2], 0);
    /* after alpha goes away, omega decays to zero */
    alpha[0] = 0;
    alpha[1] = 0;
    for (n = 0; n < 6000; n++) {
        CHECK_STATUS(ac_rate_step(&st, alpha, omega), AC_OK);
    }
    CHECK_EQ(omega[0], 0);
    CHECK_EQ(omega[1], 0);
}

static void test_saturation(void)
{
    ac_rate st;
    int32_t alpha[3] = {102400, -102400, 0}; /* +-100 rad/s^2 */
    int16_t omega[3];
    int n;
    ac_status s = AC_OK;
    long long inc;

    /* dt = 1/60 s: 20 steps reach 33 rad/s > the 32 rad/s range */
    CHECK_STATUS(ac_rate_init(&st, 34953, 21, 0), AC_OK);
    for (n = 0; n < 40; n++) {
        s = ac_rate_step(&st, alpha, omega);
    }
    CHECK_EQ(s, AC_SATURATED);
    CHECK_EQ(omega[0], 32767);
    CHECK_EQ(omega[1], -32768);
    CHECK_EQ(omega[2], 0);
    CHECK_EQ(st.w[0], INT32_MAX);
    CHECK_EQ(st.w[1], INT32_MIN);

    /* no wrap-around: reversing alpha walks back from the limit */
    alpha[0] = -102400;
    alpha[1] = 102400;
    s = ac_rate_step(&st, alpha, omega);
    inc = floor_pow2(102400ll * 34953ll + (1ll << 4), 5); /* alpha dt in 2^-26 rad/s */
    CHECK_EQ(st.w[0], 2147483647ll - inc);
    CHECK_EQ(st.w[1], -2147483648ll + inc);
    CHECK(omega[0] > 30000 && omega[1] < -30000);
    CHECK_EQ(s, AC_OK);

    /* a step whose increment alone is beyond int32 */
    CHECK_STATUS(ac_rate_init(&st, 65535, 16, 0), AC_OK);
    alpha[0] = INT32_MAX;
    alpha[1] = INT32_MIN;
    alpha[2] = 1;
    CHECK_STATUS(ac_rate_step(&st, alpha, omega), AC_SATURATED);
    CHECK_EQ(st.w[0], INT32_MAX);
    CHECK_EQ(st.w[1], INT32_MIN);
    CHECK_EQ(omega[0], 32767);
    CHECK_EQ(omega[1], -32768);
    CHECK_EQ(st.w[2], 65535); /* 2^-10 rad/s^2 * 65535 * 2^-16 s = 65535 LSB */
}

int main(void)
{
    test_status();
    /* 1/60 s: 1 rad/s^2 for 10 s, -2.5 rad/s^2, 1 LSB */
    test_constant(34953, 21, 1024, -2560, 1, 600);
    /* 1 ms as 33554 * 2^-25 (error 5e-6), 20 rad/s^2 */
    test_constant(33554, 25, 20480, -20480, 0, 1000);
    /* the coarsest and finest time steps */
    test_constant(1, 16, 1024, -1, 123456, 100);
    test_constant(65535, 46, 2000000000L, -2000000000L, 1, 100);
    test_leaky_random();
    test_leaky_steady();
    test_saturation();
    return AC_TEST_END();
}
