/*
 * Unit tests of ac_trim.h: x_i = raw_i - trim_i clipped to int16, with
 * AC_SATURATED when any channel clipped, and the status codes for NULL.
 */
#include <accelcal/accelcal.h>

#include "ac_test.h"

static long long sat16_ref(long long v, int *sat)
{
    if (v > 32767) {
        *sat = 1;
        return 32767;
    }
    if (v < -32768) {
        *sat = 1;
        return -32768;
    }
    return v;
}

int main(void)
{
    uint16_t raw[AC_MAX_CHANNELS + 4], trim[AC_MAX_CHANNELS + 4];
    int16_t x[AC_MAX_CHANNELS + 4];
    unsigned i;
    long it;

    /* NULL pointers */
    for (i = 0; i < AC_MAX_CHANNELS; i++) {
        raw[i] = 5000;
        trim[i] = 4990;
        x[i] = 0x5A5A;
    }
    CHECK_STATUS(ac_trim(NULL, trim, 6, x), AC_ERR_NULL);
    CHECK_STATUS(ac_trim(raw, NULL, 6, x), AC_ERR_NULL);
    CHECK_STATUS(ac_trim(raw, trim, 6, NULL), AC_ERR_NULL);
    CHECK_EQ(x[0], 0x5A5A); /* not written on error */

    /* n = 0: nothing to trim -- either refused as a size error or a no-op */
    {
        ac_status st = ac_trim(raw, trim, 0, x);
        CHECK(st == AC_ERR_SIZE || st == AC_OK);
        CHECK_EQ(x[0], 0x5A5A);
    }

    /* plain differences, only the first n written */
    CHECK_STATUS(ac_trim(raw, trim, 6, x), AC_OK);
    for (i = 0; i < 6; i++) {
        CHECK_EQ(x[i], 10);
    }
    CHECK_EQ(x[6], 0x5A5A);

    /* the seed's raw range is 0..10000 with zero at ~5000: never clips */
    raw[0] = 0;
    trim[0] = 6400;
    raw[1] = 10000;
    trim[1] = 3600;
    CHECK_STATUS(ac_trim(raw, trim, 2, x), AC_OK);
    CHECK_EQ(x[0], -6400);
    CHECK_EQ(x[1], 6400);

    /* edges of int16: exact at the limits, clipped one past them */
    raw[0] = 32767;
    trim[0] = 0;
    raw[1] = 0;
    trim[1] = 32768;
    CHECK_STATUS(ac_trim(raw, trim, 2, x), AC_OK);
    CHECK_EQ(x[0], 32767);
    CHECK_EQ(x[1], -32768);
    raw[0] = 32768;
    trim[0] = 0;
    CHECK_STATUS(ac_trim(raw, trim, 2, x), AC_SATURATED);
    CHECK_EQ(x[0], 32767);
    CHECK_EQ(x[1], -32768);
    raw[0] = 0;
    trim[0] = 65535;
    raw[1] = 65535;
    trim[1] = 0;
    CHECK_STATUS(ac_trim(raw, trim, 2, x), AC_SATURATED);
    CHECK_EQ(x[0], -32768);
    CHECK_EQ(x[1], 32767);
    /* 30000 + 30000 style: differences beyond int16 that a 16-bit int would wrap */
    raw[0] = 60000;
    trim[0] = 1;
    raw[1] = 1;
    trim[1] = 60000;
    CHECK_STATUS(ac_trim(raw, trim, 2, x), AC_SATURATED);
    CHECK_EQ(x[0], 32767);
    CHECK_EQ(x[1], -32768);

    /* random, every n from 1 to AC_MAX_CHANNELS + 4 (ac_trim has no upper limit
     * of its own) -- a saturation anywhere sets the status */
    ac_test_seed(99ul);
    for (it = 0; it < 3000; it++) {
        unsigned n = 1u + (unsigned)(it % (AC_MAX_CHANNELS + 4));
        int any = 0;
        ac_status st;
        ac_test_context("random", it);
        for (i = 0; i < n; i++) {
            unsigned long r = ac_test_rand32();
            if (it & 1) {
                raw[i] = (uint16_t)(r & 0xFFFFu);
                trim[i] = (uint16_t)(r >> 16);
            } else {
                /* realistic: raw near trim */
                trim[i] = (uint16_t)(3000u + (unsigned)((r >> 16) % 4000u));
                raw[i] = (uint16_t)((unsigned)trim[i] + (r & 0x1FFFu) - 0x1000u);
            }
        }
        st = ac_trim(raw, trim, (uint16_t)n, x);
        for (i = 0; i < n; i++) {
            long long want = sat16_ref((long long)raw[i] - (long long)trim[i], &any);
            CHECK_EQ(x[i], want);
        }
        CHECK_EQ(st, any ? AC_SATURATED : AC_OK);
    }
    return AC_TEST_END();
}
