/*
 * Unit tests of the correctable terms (ac_temp.h, ac_skew.h, ac_nonlin.h) against
 * double-precision references of the arithmetic their headers define, within the
 * bounds stated there; status codes, "not written on error", the delay line's start.
 */
#include <math.h>
#include <stdlib.h>

#include <accelcal/accelcal.h>

#include "ac_test.h"

static unsigned long seed = 12345ul;
static long rnd(long lo, long hi)
{
    seed = seed * 1103515245ul + 12345ul;
    return lo + (long)((seed >> 8) % (unsigned long)(hi - lo + 1));
}

static void test_lag(void)
{
    ac_temp_lag f;
    int16_t out = 0;
    double c = 1.0 - exp(-0.01 / 2.0), ref;
    int shift = 16, k, n;
    /* the quantizer's weight: k in 32768..65535 at the largest shift */
    while (c * ldexp(1.0, shift + 1) <= 65535.0) {
        shift++;
    }
    k = (int)floor(c * ldexp(1.0, shift) + 0.5);
    CHECK_STATUS(ac_temp_lag_init(NULL, 1, 0), AC_ERR_NULL);
    CHECK_STATUS(ac_temp_lag_init(&f, 3, 1), AC_ERR_RANGE);
    CHECK_STATUS(ac_temp_lag_init(&f, 1, 48), AC_ERR_RANGE);
    CHECK_STATUS(ac_temp_lag_init(&f, (uint16_t)k, (uint8_t)shift), AC_OK);
    CHECK_STATUS(ac_temp_lag_step(&f, 0, NULL), AC_ERR_NULL);
    /* a step of 20 degC from 5 degC, 1000 samples of 10 ms at tau 2 s */
    CHECK_STATUS(ac_temp_lag_step(&f, 5 * 256, &out), AC_OK);
    CHECK_EQ(out, 5 * 256);
    ref = 5.0;
    for (n = 0; n < 1000; n++) {
        ac_temp_lag_step(&f, 25 * 256, &out);
        ref += c * (25.0 - ref);
        /* 2^-9 + 2^-25 / c + 2^-16 * 20 degC */
        CHECK_NEAR(out / 256.0, ref, ldexp(1.0, -9) + ldexp(1.0, -25) / c + ldexp(1.0, -16) * 20.0);
    }
    CHECK_NEAR(ref, 25.0 - 20.0 * exp(-5.0), 0.01);
    /* no lag: weight 1 */
    CHECK_STATUS(ac_temp_lag_init(&f, 1, 0), AC_OK);
    ac_temp_lag_step(&f, 100, &out);
    ac_temp_lag_step(&f, -7000, &out);
    CHECK_EQ(out, -7000);
    /* a jump of more than 128 degC clips the update, flagged */
    CHECK_STATUS(ac_temp_lag_init(&f, 1, 0), AC_OK);
    ac_temp_lag_step(&f, -32768, &out);
    CHECK_STATUS(ac_temp_lag_step(&f, 32767, &out), AC_SATURATED);
}

static void test_temp_correct(void)
{
    ac_temp_table t;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    int it, i;
    t.frac = 0u;
    t.n = 0;
    CHECK_STATUS(ac_temp_check(&t), AC_ERR_SIZE);
    t.n = 1;
    t.o[0] = -129;
    CHECK_STATUS(ac_temp_check(&t), AC_ERR_FORMAT);
    y[0] = 0x5A5A;
    x[0] = 0;
    t.n = 0;
    CHECK_STATUS(ac_temp_correct(&t, 0, 0, x, y), AC_ERR_SIZE);
    CHECK_EQ(y[0], 0x5A5A);
    t.n = 1;
    t.o[0] = 0;
    CHECK_STATUS(ac_temp_check(&t), AC_OK);
    CHECK_STATUS(ac_temp_correct(NULL, 0, 0, x, y), AC_ERR_NULL);
    for (it = 0; it < 20000; it++) {
        int16_t toff = (int16_t)rnd(-30 * 256, 60 * 256), tgain = (int16_t)rnd(-30 * 256, 60 * 256);
        ac_status st;
        t.n = (uint16_t)rnd(1, AC_MAX_CHANNELS);
        t.t_ref = (int16_t)rnd(0, 40 * 256);
        for (i = 0; i < (int)t.n; i++) {
            t.oc[i] = (int16_t)rnd(-32767, 32767);
            t.gc[i] = (int16_t)rnd(-32767, 32767);
            t.o[i] = (int16_t)rnd(-128, 127);
            x[i] = (int16_t)rnd(-32768, 32767);
        }
        st = ac_temp_correct(&t, toff, tgain, x, y);
        CHECK(st == AC_OK || st == AC_SATURATED);
        if (st != AC_OK) {
            continue;
        }
        for (i = 0; i < (int)t.n; i++) {
            double dto = (toff - t.t_ref) / 256.0, dtg = (tgain - t.t_ref) / 256.0;
            double oc = ldexp(t.oc[i], -AC_TEMP_OC_FRAC), gc = ldexp(t.gc[i], -AC_TEMP_GC_FRAC), o = t.o[i] / 256.0;
            double e = fabs(gc * dtg);
            double ref = o + (x[i] - o - oc * dto) / (1.0 + gc * dtg);
            double bound = 0.5 + ldexp(1.0, -8) + 0.54 * e + (fabs((double)x[i]) + 1.0) * (ldexp(1.0, -18) + pow(e, 4) / (1 - e));
            ac_test_context("temp_correct case", it);
            CHECK_NEAR(y[i], ref, bound);
        }
    }
}

static void test_skew(void)
{
    ac_skew_table t;
    ac_skew_line line;
    int16_t buf[4 * 2], x[2], y[2];
    int n;
    t.n = 2;
    t.len = 3;
    t.whole[0] = 1;
    t.whole[1] = 0;
    t.frac[0] = 0;
    t.frac[1] = 16384; /* half a sample */
    CHECK_STATUS(ac_skew_init(&line, &t, buf, 5), AC_ERR_SIZE);
    CHECK_STATUS(ac_skew_init(&line, &t, NULL, 8), AC_ERR_NULL);
    CHECK_STATUS(ac_skew_init(&line, &t, buf, 6), AC_OK);
    for (n = 0; n < 20; n++) {
        x[0] = (int16_t)(n * 100);
        x[1] = (int16_t)(n * 100 + 1);
        CHECK_STATUS(ac_skew_step(&t, &line, x, y), AC_OK);
        /* channel 0 one sample late; channel 1 half a sample (ties round up); the line starts full
         * of the first sample */
        CHECK_EQ(y[0], n == 0 ? 0 : (n - 1) * 100);
        CHECK_EQ(y[1], n == 0 ? 1 : n * 100 + 1 - 50);
    }
    /* extremes: the interpolation of -32768 and 32767 stays in range */
    x[0] = 32767;
    x[1] = -32768;
    ac_skew_step(&t, &line, x, y);
    x[0] = -32768;
    x[1] = 32767;
    CHECK_STATUS(ac_skew_step(&t, &line, x, y), AC_OK);
    CHECK_EQ(y[1], 0); /* (-32768 + 32767) / 2 = -0.5, half up */
    t.len = 4;
    CHECK_STATUS(ac_skew_step(&t, &line, x, y), AC_ERR_SIZE); /* the line was made for len 3 */
}

static void test_nonlin(void)
{
    ac_nonlin_table t;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    int it, i, k, nit;
    t.n = 1;
    t.iterations = 0u;
    t.shift = 31;
    CHECK_STATUS(ac_nonlin_check(&t), AC_ERR_FORMAT);
    t.shift = -1;
    CHECK_STATUS(ac_nonlin_check(&t), AC_ERR_FORMAT);
    t.shift = 20;
    t.a2[0] = 20000;
    t.a3[0] = -12768;
    CHECK_STATUS(ac_nonlin_check(&t), AC_ERR_FORMAT); /* |a2| + |a3| = 32768 */
    t.a3[0] = 0;
    t.a2[0] = 0;
    x[0] = 1234;
    CHECK_STATUS(ac_nonlin_invert(&t, x, y), AC_OK);
    CHECK_EQ(y[0], 1234);
    t.iterations = (uint8_t)(AC_NONLIN_MAX_ITERATIONS + 1);
    CHECK_STATUS(ac_nonlin_check(&t), AC_ERR_FORMAT);
    CHECK_STATUS(ac_nonlin_invert(&t, x, y), AC_ERR_FORMAT);
    t.iterations = (uint8_t)AC_NONLIN_MAX_ITERATIONS;
    CHECK_STATUS(ac_nonlin_check(&t), AC_OK);
    for (it = 0; it < 20000; it++) {
        ac_status st;
        t.iterations = (uint8_t)((it & 1) ? rnd(0, AC_NONLIN_MAX_ITERATIONS) : 0);
        nit = t.iterations ? (int)t.iterations : AC_NONLIN_ITERATIONS;
        t.n = (uint16_t)rnd(1, AC_MAX_CHANNELS);
        t.shift = (int8_t)rnd(10, 26);
        for (i = 0; i < (int)t.n; i++) {
            long a2 = rnd(-20000, 20000), room = 32767 - labs(a2);
            t.a2[i] = (int16_t)a2;
            t.a3[i] = (int16_t)rnd(-room, room);
            x[i] = (int16_t)rnd(-32768, 32767);
        }
        st = ac_nonlin_invert(&t, x, y);
        CHECK(st == AC_OK || st == AC_SATURATED);
        if (st != AC_OK) {
            continue;
        }
        for (i = 0; i < (int)t.n; i++) {
            double c2 = ldexp(t.a2[i], -(15 + t.shift)), c3 = ldexp(t.a3[i], -(30 + t.shift));
            double z = x[i], zk = z, zm, L, E, D = 0.0;
            for (k = 0; k < nit; k++) {
                zk = z - (c2 + c3 * zk) * zk * zk;
            }
            zm = fmax(fabs(z), fabs(zk)) + 1.0;
            L = 2 * fabs(c2) * zm + 3 * fabs(c3) * zm * zm;
            E = 0.5 + (zm * zm * ldexp(1.0, -16) + 0.5 * zm) * ldexp(1.0, -t.shift);
            for (k = 0; k < nit; k++) {
                D = E + L * D; /* D_0 = 0: the reference starts at x itself here */
            }
            ac_test_context("nonlin case", it);
            CHECK_NEAR(y[i], zk, D);
        }
    }
}

int main(void)
{
    test_lag();
    test_temp_correct();
    test_skew();
    test_nonlin();
    return AC_TEST_END();
}
