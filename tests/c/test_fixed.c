/*
 * Unit tests of ac_fixed.h against the host's 64-bit arithmetic: every pair
 * of edge values (0, +-1, INT32_MIN/MAX, +-2^k, +-2^k +-1, the int16 limits)
 * and a few thousand pseudo-random values, checking results, saturation
 * flags, range errors (output left unwritten) and NULL handling.
 */
#include <accelcal/accelcal.h>

#include "ac_test.h"

#define SENTINEL32 0x5A5A5A5AL

static long long edges[200];
static int n_edges = 0;

static void add_edge(long long v)
{
    int i;
    if (v < -2147483648ll || v > 2147483647ll || n_edges >= 200) {
        return;
    }
    for (i = 0; i < n_edges; i++) {
        if (edges[i] == v) {
            return;
        }
    }
    edges[n_edges++] = v;
}

static void make_edges(void)
{
    int k;
    add_edge(0);
    add_edge(1);
    add_edge(-1);
    add_edge(2147483647ll);
    add_edge(-2147483647ll - 1);
    add_edge(2147483646ll);
    add_edge(-2147483647ll);
    for (k = 1; k <= 31; k++) {
        long long p = 1ll << k;
        add_edge(p);
        add_edge(p - 1);
        add_edge(p + 1);
        add_edge(-p);
        add_edge(-p + 1);
        add_edge(-p - 1);
    }
    add_edge(32767);
    add_edge(-32768);
    add_edge(-32769);
    add_edge(46341);  /* ~ sqrt(2^31) */
    add_edge(-46341);
    add_edge(1000000007);
    add_edge(-999999937);
}

/* floor(x / 2^n), 0 <= n <= 62, exact for any long long x */
static long long floor_pow2(long long x, int n)
{
    long long d = 1ll << n;
    long long q = x / d;
    if (q * d != x && x < 0) {
        q--;
    }
    return q;
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

static int bitlen_ref(long long v)
{
    unsigned long long u = (unsigned long long)(v < 0 ? -v : v);
    int n = 0;
    while (u != 0ull) {
        n++;
        u >>= 1;
    }
    return n;
}

/* ---- per-function checks of one input ------------------------------------ */

static void check_sat16(long long v)
{
    int16_t out = 0x5A5A;
    int sat = 0;
    long long want = v;
    ac_status st = ac_sat16((int32_t)v, &out);
    if (want > 32767) {
        want = 32767;
        sat = 1;
    } else if (want < -32768) {
        want = -32768;
        sat = 1;
    }
    CHECK_EQ(out, want);
    CHECK_EQ(st, sat ? AC_SATURATED : AC_OK);
}

static void check_add(long long a, long long b)
{
    int32_t out = SENTINEL32;
    int sat = 0;
    long long want = clamp32(a + b, &sat);
    ac_status st = ac_add32_sat((int32_t)a, (int32_t)b, &out);
    CHECK_MSG(out == want && st == (sat ? AC_SATURATED : AC_OK),
              ("ac_add32_sat(%lld, %lld) = %ld st %d, want %lld st %d", a, b, (long)out,
               (int)st, want, sat));
}

static void check_asr(long long v, int n)
{
    int32_t out = SENTINEL32;
    ac_status st = ac_asr32((int32_t)v, (uint8_t)n, &out);
    long long want = floor_pow2(v, n);
    CHECK_MSG(out == want && st == AC_OK,
              ("ac_asr32(%lld, %d) = %ld st %d, want %lld", v, n, (long)out, (int)st, want));
}

static void check_scale(long long v, int shift)
{
    int32_t out = SENTINEL32;
    int sat = 0;
    long long want;
    ac_status st = ac_scale_round32((int32_t)v, (int16_t)shift, &out);
    if (shift > 62) {
        want = 0; /* |v| 2^-shift < 2^-31: rounds to 0 (half up) */
    } else if (shift > 0) {
        want = floor_pow2(v + (1ll << (shift - 1)), shift); /* half up */
    } else if (shift < -31) {
        want = v == 0 ? 0 : clamp32(v < 0 ? -4294967296ll : 4294967296ll, &sat);
    } else {
        want = clamp32(v * (1ll << -shift), &sat);
    }
    CHECK_MSG(out == want && st == (sat ? AC_SATURATED : AC_OK),
              ("ac_scale_round32(%lld, %d) = %ld st %d, want %lld st %d", v, shift,
               (long)out, (int)st, want, sat));
}

static void check_u32(unsigned long u)
{
    int32_t out = SENTINEL32;
    ac_status st = ac_u32_to_i32((uint32_t)u, &out);
    CHECK_MSG(st == AC_OK && out == ac_test_s32(u),
              ("ac_u32_to_i32(0x%08lx) = %ld st %d", u, (long)out, (int)st));
}

static void check_mul64(long long a, long long b)
{
    ac_i64 out;
    long long p = a * b;
    long long lo = (long long)((unsigned long long)p & 0xFFFFFFFFull);
    long long hi = floor_pow2(p - lo, 32);
    ac_status st;
    out.hi = SENTINEL32;
    out.lo = 0xA5A5A5A5ul;
    st = ac_mul32x32((int32_t)a, (int32_t)b, &out);
    CHECK_MSG(st == AC_OK && out.hi == hi && (long long)out.lo == lo,
              ("ac_mul32x32(%lld, %lld) = {%ld, 0x%08lx} st %d, want {%lld, 0x%08llx}", a, b,
               (long)out.hi, (unsigned long)out.lo, (int)st, hi, lo));
}

static void check_mulsh(long long a, long long b, int n)
{
    int32_t out = SENTINEL32;
    int sat = 0;
    long long p = a * b; /* |p| <= 2^62 */
    long long want;
    ac_status st = ac_mul32_shift((int32_t)a, (int32_t)b, (uint8_t)n, &out);
    if (n == 0) {
        want = p;
    } else {
        want = floor_pow2(p + (1ll << (n - 1)), n); /* p + 2^61 < 2^63 */
    }
    want = clamp32(want, &sat);
    CHECK_MSG(out == want && st == (sat ? AC_SATURATED : AC_OK),
              ("ac_mul32_shift(%lld, %lld, %d) = %ld st %d, want %lld st %d", a, b, n,
               (long)out, (int)st, want, sat));
}

static void check_bitlen(long long v)
{
    uint8_t out = 0xA5;
    ac_status st = ac_bitlen32((int32_t)v, &out);
    CHECK_MSG(st == AC_OK && out == bitlen_ref(v),
              ("ac_bitlen32(%lld) = %u st %d, want %d", v, (unsigned)out, (int)st,
               bitlen_ref(v)));
}

/* ---- groups ---------------------------------------------------------------- */

static void test_null_and_range(void)
{
    int32_t o32 = SENTINEL32;
    uint8_t o8 = 0xA5;

    CHECK_STATUS(ac_sat16(5, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_add32_sat(1, 2, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_asr32(1, 1, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_scale_round32(1, 1, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_mul32x32(1, 2, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_mul32_shift(1, 2, 0, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_bitlen32(1, NULL), AC_ERR_NULL);

    CHECK_STATUS(ac_u32_to_i32(1u, NULL), AC_ERR_NULL);

    /* ac_scale_round32 takes any int16 shift: beyond 31 the result is 0 (right)
     * or saturates unless v == 0 (left). */
    CHECK_STATUS(ac_scale_round32(INT32_MAX, 32, &o32), AC_OK);
    CHECK_EQ(o32, 0);
    CHECK_STATUS(ac_scale_round32(INT32_MIN, 32, &o32), AC_OK); /* -0.5 -> 0 */
    CHECK_EQ(o32, 0);
    CHECK_STATUS(ac_scale_round32(INT32_MIN, 31, &o32), AC_OK); /* -1 */
    CHECK_EQ(o32, -1);
    CHECK_STATUS(ac_scale_round32(INT32_MIN + 1, 32, &o32), AC_OK);
    CHECK_EQ(o32, 0);
    CHECK_STATUS(ac_scale_round32(-1, INT16_MAX, &o32), AC_OK);
    CHECK_EQ(o32, 0);
    CHECK_STATUS(ac_scale_round32(1, -32, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MAX);
    CHECK_STATUS(ac_scale_round32(-1, -32, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MIN);
    CHECK_STATUS(ac_scale_round32(-1, INT16_MIN, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MIN);
    CHECK_STATUS(ac_scale_round32(0, INT16_MIN, &o32), AC_OK);
    CHECK_EQ(o32, 0);
    CHECK_STATUS(ac_scale_round32(0, INT16_MAX, &o32), AC_OK);
    CHECK_EQ(o32, 0);
    o32 = SENTINEL32;

    /* ac_mul32_shift: n in 0..62; beyond is out of range. */
    CHECK_STATUS(ac_mul32_shift(3, 5, 63, &o32), AC_ERR_RANGE);
    CHECK_EQ(o32, SENTINEL32);
    CHECK_STATUS(ac_mul32_shift(3, 5, 255, &o32), AC_ERR_RANGE);
    CHECK_EQ(o32, SENTINEL32);

    /* ac_asr32: n in 0..31.  Out of range is either refused (AC_ERR_RANGE,
     * output untouched) or, if accepted, must still be floor(v / 2^n). */
    {
        ac_status st = ac_asr32(-5, 32, &o32);
        CHECK(st == AC_ERR_RANGE || (st == AC_OK && o32 == -1));
        if (st < 0) {
            CHECK_EQ(o32, SENTINEL32);
        }
        o32 = SENTINEL32;
        st = ac_asr32(5, 40, &o32);
        CHECK(st == AC_ERR_RANGE || (st == AC_OK && o32 == 0));
    }

    /* named spot values */
    CHECK_STATUS(ac_bitlen32(0, &o8), AC_OK);
    CHECK_EQ(o8, 0);
    CHECK_STATUS(ac_bitlen32(INT32_MIN, &o8), AC_OK);
    CHECK_EQ(o8, 32);
    CHECK_STATUS(ac_bitlen32(INT32_MAX, &o8), AC_OK);
    CHECK_EQ(o8, 31);
    CHECK_STATUS(ac_bitlen32(-1, &o8), AC_OK);
    CHECK_EQ(o8, 1);
    CHECK_STATUS(ac_asr32(-1, 31, &o32), AC_OK);
    CHECK_EQ(o32, -1);
    CHECK_STATUS(ac_asr32(INT32_MIN, 31, &o32), AC_OK);
    CHECK_EQ(o32, -1);
    CHECK_STATUS(ac_scale_round32(-3, 1, &o32), AC_OK); /* -1.5 -> -1 (half up) */
    CHECK_EQ(o32, -1);
    CHECK_STATUS(ac_scale_round32(3, 1, &o32), AC_OK); /* 1.5 -> 2 */
    CHECK_EQ(o32, 2);
    CHECK_STATUS(ac_scale_round32(INT32_MAX, 1, &o32), AC_OK); /* 2^30 - 0.5 -> 2^30 */
    CHECK_EQ(o32, 1073741824L);
    CHECK_STATUS(ac_scale_round32(1, -31, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MAX);
    CHECK_STATUS(ac_scale_round32(-1, -31, &o32), AC_OK);
    CHECK_EQ(o32, INT32_MIN);
    CHECK_STATUS(ac_mul32_shift(INT32_MIN, INT32_MIN, 62, &o32), AC_OK);
    CHECK_EQ(o32, 1);
    CHECK_STATUS(ac_mul32_shift(INT32_MIN, INT32_MIN, 31, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MAX);
    CHECK_STATUS(ac_mul32_shift(INT32_MIN, 1, 0, &o32), AC_OK);
    CHECK_EQ(o32, INT32_MIN);
    CHECK_STATUS(ac_mul32_shift(-3, 1, 1, &o32), AC_OK); /* -1.5 -> -1 */
    CHECK_EQ(o32, -1);
    CHECK_STATUS(ac_mul32_shift(-1, 1, 62, &o32), AC_OK); /* -2^-62 -> 0 */
    CHECK_EQ(o32, 0);
    CHECK_STATUS(ac_add32_sat(INT32_MAX, 1, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MAX);
    CHECK_STATUS(ac_add32_sat(INT32_MIN, -1, &o32), AC_SATURATED);
    CHECK_EQ(o32, INT32_MIN);
    CHECK_STATUS(ac_add32_sat(INT32_MIN, INT32_MAX, &o32), AC_OK);
    CHECK_EQ(o32, -1);
}

static void test_edges(void)
{
    int i, j, n;
    for (i = 0; i < n_edges; i++) {
        ac_test_context("edge", i);
        check_sat16(edges[i]);
        check_bitlen(edges[i]);
        for (n = 0; n <= 31; n++) {
            check_asr(edges[i], n);
        }
        for (n = -70; n <= 70; n++) {
            check_scale(edges[i], n);
        }
        check_scale(edges[i], 32767);
        check_scale(edges[i], -32768);
        check_u32((unsigned long)(edges[i] & 0xFFFFFFFFll));
        for (j = 0; j < n_edges; j++) {
            check_add(edges[i], edges[j]);
            check_mul64(edges[i], edges[j]);
            for (n = 0; n <= 62; n++) {
                check_mulsh(edges[i], edges[j], n);
            }
        }
    }
    ac_test_context("", -1);
}

static void test_random(void)
{
    long i;
    ac_test_seed(12345ul);
    for (i = 0; i < 5000; i++) {
        long long a = ac_test_rand_i32();
        long long b = ac_test_rand_i32();
        long long full = ac_test_s32(ac_test_rand32());
        int n31 = (int)ac_test_range(0, 31);
        int s = (int)ac_test_range(-31, 31);
        int s16 = (int)ac_test_range(-32768, 32767);
        int n62 = (int)ac_test_range(0, 62);
        ac_test_context("random", i);
        check_sat16(a);
        check_sat16(full);
        check_bitlen(a);
        check_bitlen(full);
        check_add(a, b);
        check_add(full, b);
        check_add(a, ac_test_s32(ac_test_rand32()));
        check_asr(a, n31);
        check_asr(full, n31);
        check_scale(a, s);
        check_scale(full, s);
        check_scale(a, s16);
        check_u32(ac_test_rand32());
        check_mul64(a, b);
        check_mul64(full, ac_test_s32(ac_test_rand32()));
        check_mulsh(a, b, n62);
        check_mulsh(full, ac_test_s32(ac_test_rand32()), (int)ac_test_range(20, 62));
        check_mulsh(a, b, (int)ac_test_range(0, 20));
    }
    ac_test_context("", -1);
}

int main(void)
{
    make_edges();
    test_null_and_range();
    test_edges();
    test_random();
    return AC_TEST_END();
}
