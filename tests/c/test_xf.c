/*
 * Unit tests of ac_xf.h against long double (64-bit mantissa on the host):
 * results must be normalised (m == 0 or 2^29 <= |m| < 2^30) and within a
 * relative error of 2^-28 of the exact value; exact operations (from_fixed of
 * values that fit 30 bits, neg, abs, ldexp, cmpabs, to_fixed) are checked
 * exactly, as are a few hand-made ties (rounded away from zero).
 */
#include <accelcal/accelcal.h>

#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "ac_test.h"

#define REL_BOUND 3.7252902984619140625e-09L /* 2^-28 */

static long double xval(ac_xf x)
{
    return ldexpl((long double)x.m, x.e);
}

static int normalised(ac_xf x)
{
    long m = (long)x.m;
    if (m < 0) {
        m = -m;
    }
    return x.m == 0 || (m >= 0x20000000L && m < 0x40000000L);
}

/* v is representable with a 30-bit mantissa */
static int fits30(long long v)
{
    unsigned long long u = (unsigned long long)(v < 0 ? -v : v);
    while (u >= 0x40000000ull) {
        if (u & 1ull) {
            return 0;
        }
        u >>= 1;
    }
    return 1;
}

static int rel_ok(long double got, long double want)
{
    long double d = fabsl(got - want);
    return d <= REL_BOUND * fabsl(want);
}

/* A random normalised xf with exponent in [emin, emax] (or zero, 1 in 32). */
static ac_xf rand_xf(int emin, int emax)
{
    ac_xf x;
    unsigned long r = ac_test_rand32();
    long m = (long)(0x20000000ul | (r & 0x1FFFFFFFul));
    if ((ac_test_rand32() & 31ul) == 0ul) {
        x.m = 0;
        x.e = 0;
        return x;
    }
    if (ac_test_rand32() & 1ul) {
        m = -m;
    }
    x.m = (int32_t)m;
    x.e = (int16_t)ac_test_range(emin, emax);
    return x;
}

#define CHECK_XF(x) CHECK_MSG(normalised(x), ("not normalised: m=%ld e=%d", (long)(x).m, (x).e))

static void check_binop(const char *name, ac_status st, ac_xf r, long double want, ac_xf a,
                        ac_xf b)
{
    CHECK_MSG(st == AC_OK, ("%s status %d", name, (int)st));
    CHECK_XF(r);
    CHECK_MSG(rel_ok(xval(r), want),
              ("%s({%ld,%d}, {%ld,%d}) = {%ld,%d} = %.21Lg, want %.21Lg (rel err %.3Lg)", name,
               (long)a.m, a.e, (long)b.m, b.e, (long)r.m, r.e, xval(r), want,
               want != 0 ? fabsl(xval(r) - want) / fabsl(want) : fabsl(xval(r))));
}

/* Strict "rounded to nearest": the error is at most half a unit of the last
 * mantissa place of the result (checked where long double is exact). */
static void check_round_nearest(const char *name, ac_xf r, long double want)
{
    long double half_ulp = ldexpl(1.0L, r.e - 1);
    if (r.m == 0) {
        CHECK_MSG(want == 0.0L, ("%s gave 0, want %.21Lg", name, want));
        return;
    }
    CHECK_MSG(fabsl(xval(r) - want) <= half_ulp,
              ("%s = {%ld,%d} is not the nearest to %.21Lg (err %.3Lg ulp)", name, (long)r.m,
               r.e, want, fabsl(xval(r) - want) / ldexpl(1.0L, r.e)));
}

static void test_from_to_fixed(void)
{
    long i;
    ac_xf x;
    int32_t v;
    static const long spot[] = {0L, 1L, -1L, 2L, 3L, -3L, 1073741823L, -1073741823L,
                                1073741824L, -1073741824L, 536870912L, 536870911L,
                                -536870913L, 2147483647L, -2147483647L - 1L, 12345L};
    unsigned k;

    CHECK_STATUS(ac_xf_from_fixed(1, 0, NULL), AC_ERR_NULL);
    x.m = 0x20000000L;
    x.e = 0;
    CHECK_STATUS(ac_xf_to_fixed(x, 0, NULL), AC_ERR_NULL);

    for (k = 0; k < sizeof spot / sizeof spot[0]; k++) {
        int frac;
        for (frac = -40; frac <= 40; frac += 8) {
            long double want = ldexpl((long double)spot[k], -frac);
            ac_test_context("from_fixed spot", (long long)k);
            CHECK_STATUS(ac_xf_from_fixed((int32_t)spot[k], (int16_t)frac, &x), AC_OK);
            CHECK_XF(x);
            if (fits30(spot[k])) {
                /* fits the 30-bit mantissa: must be exact */
                CHECK_MSG(xval(x) == want, ("from_fixed(%ld, %d) = %.21Lg, want %.21Lg",
                                            spot[k], frac, xval(x), want));
            } else {
                CHECK(rel_ok(xval(x), want));
            }
        }
    }

    ac_test_seed(777ul);
    for (i = 0; i < 4000; i++) {
        long long v0 = ac_test_rand_i32();
        int frac = (int)ac_test_range(-100, 100);
        long double want = ldexpl((long double)v0, -frac);
        ac_test_context("from_fixed", i);
        CHECK_STATUS(ac_xf_from_fixed((int32_t)v0, (int16_t)frac, &x), AC_OK);
        CHECK_XF(x);
        if (fits30(v0)) {
            CHECK_MSG(xval(x) == want,
                      ("from_fixed(%lld, %d) = %.21Lg, want %.21Lg", v0, frac, xval(x), want));
        } else {
            CHECK(rel_ok(xval(x), want));
        }

        /* to_fixed: round(x * 2^frac) half up, clipped to int32 */
        {
            ac_xf y = rand_xf(-70, 10);
            int f2 = (int)ac_test_range(-10, 60);
            long long want2;
            int sat = 0;
            int k2 = y.e + f2; /* y * 2^f2 = m * 2^k2 */
            ac_status st;
            if (y.m == 0) {
                want2 = 0;
            } else if (k2 >= 0) {
                if (k2 > 31) {
                    want2 = y.m > 0 ? 2147483647ll : -2147483648ll;
                    sat = 1;
                } else {
                    want2 = (long long)y.m * (1ll << k2);
                    if (want2 > 2147483647ll) {
                        want2 = 2147483647ll;
                        sat = 1;
                    } else if (want2 < -2147483648ll) {
                        want2 = -2147483648ll;
                        sat = 1;
                    }
                }
            } else if (k2 < -40) {
                want2 = 0; /* |m| 2^k2 < 2^-10 */
            } else {
                long long num = (long long)y.m + (1ll << (-k2 - 1));
                long long d = 1ll << -k2;
                want2 = num / d;
                if (want2 * d != num && num < 0) {
                    want2--;
                }
            }
            v = 0x5A5A5A5AL;
            st = ac_xf_to_fixed(y, (int16_t)f2, &v);
            CHECK_MSG(v == want2 && st == (sat ? AC_SATURATED : AC_OK),
                      ("to_fixed({%ld,%d}, %d) = %ld st %d, want %lld st %d", (long)y.m, y.e, f2,
                       (long)v, (int)st, want2, sat));
        }
    }
    ac_test_context("", -1);

    /* round trip of every int32 edge through xf and back */
    for (k = 0; k < sizeof spot / sizeof spot[0]; k++) {
        if (!fits30(spot[k])) {
            continue;
        }
        CHECK_STATUS(ac_xf_from_fixed((int32_t)spot[k], 12, &x), AC_OK);
        CHECK_STATUS(ac_xf_to_fixed(x, 12, &v), AC_OK);
        CHECK_EQ(v, spot[k]);
    }
    /* ties of to_fixed go up: 1.5 -> 2, -1.5 -> -1, -2.5 -> -2 */
    CHECK_STATUS(ac_xf_from_fixed(3, 1, &x), AC_OK);
    CHECK_STATUS(ac_xf_to_fixed(x, 0, &v), AC_OK);
    CHECK_EQ(v, 2);
    CHECK_STATUS(ac_xf_from_fixed(-3, 1, &x), AC_OK);
    CHECK_STATUS(ac_xf_to_fixed(x, 0, &v), AC_OK);
    CHECK_EQ(v, -1);
    CHECK_STATUS(ac_xf_from_fixed(-5, 1, &x), AC_OK);
    CHECK_STATUS(ac_xf_to_fixed(x, 0, &v), AC_OK);
    CHECK_EQ(v, -2);
    /* clipping */
    CHECK_STATUS(ac_xf_from_fixed(1, -31, &x), AC_OK);
    CHECK_STATUS(ac_xf_to_fixed(x, 0, &v), AC_SATURATED);
    CHECK_EQ(v, INT32_MAX);
    CHECK_STATUS(ac_xf_from_fixed(-1, -31, &x), AC_OK);
    CHECK_STATUS(ac_xf_to_fixed(x, 0, &v), AC_OK);
    CHECK_EQ(v, INT32_MIN);
    CHECK_STATUS(ac_xf_from_fixed(-1, -32, &x), AC_OK);
    CHECK_STATUS(ac_xf_to_fixed(x, 0, &v), AC_SATURATED);
    CHECK_EQ(v, INT32_MIN);
}

static void test_arith(void)
{
    long i;
    ac_xf a, b, r;
    ac_test_seed(4242ul);
    for (i = 0; i < 20000; i++) {
        long double va, vb, want;
        ac_status st;
        ac_test_context("arith", i);
        a = rand_xf(-60, 60);
        if ((i & 3) == 0) {
            /* near-cancellation: b close to -a */
            b = a;
            b.m = (int32_t)(-(long)b.m + (long)ac_test_range(-200, 200));
            if (!normalised(b)) {
                b = rand_xf(-60, 60);
            }
        } else if ((i & 3) == 1) {
            b = rand_xf(a.e - 40, a.e + 40);
        } else {
            b = rand_xf(-60, 60);
        }
        va = xval(a);
        vb = xval(b);

        st = ac_xf_add(a, b, &r);
        want = va + vb; /* exact in long double while the exponents are < 34 apart */
        check_binop("add", st, r, want, a, b);
        if (abs(a.e - b.e) < 34 || a.m == 0 || b.m == 0) {
            check_round_nearest("add", r, want);
        }

        st = ac_xf_sub(a, b, &r);
        want = va - vb;
        check_binop("sub", st, r, want, a, b);
        if (abs(a.e - b.e) < 34 || a.m == 0 || b.m == 0) {
            check_round_nearest("sub", r, want);
        }

        st = ac_xf_mul(a, b, &r);
        want = va * vb; /* 60-bit product: exact */
        check_binop("mul", st, r, want, a, b);
        check_round_nearest("mul", r, want);

        if (b.m != 0) {
            st = ac_xf_div(a, b, &r);
            want = va / vb;
            check_binop("div", st, r, want, a, b);
        }

        CHECK_STATUS(ac_xf_neg(a, &r), AC_OK);
        CHECK_XF(r);
        CHECK(xval(r) == -va);
        CHECK_STATUS(ac_xf_abs(a, &r), AC_OK);
        CHECK_XF(r);
        CHECK(xval(r) == fabsl(va));
        {
            int8_t c = 7;
            int want_c = fabsl(va) < fabsl(vb) ? -1 : (fabsl(va) > fabsl(vb) ? 1 : 0);
            CHECK_STATUS(ac_xf_cmpabs(a, b, &c), AC_OK);
            CHECK_EQ(c, want_c);
            CHECK_STATUS(ac_xf_cmpabs(a, a, &c), AC_OK);
            CHECK_EQ(c, 0);
            r = a;
            r.m = -r.m;
            CHECK_STATUS(ac_xf_cmpabs(a, r, &c), AC_OK);
            CHECK_EQ(c, 0);
        }
        {
            int k = (int)ac_test_range(-100, 100);
            CHECK_STATUS(ac_xf_ldexp(a, (int16_t)k, &r), AC_OK);
            CHECK_XF(r);
            CHECK(xval(r) == ldexpl(va, k));
        }
    }
    ac_test_context("", -1);
}

static void test_special(void)
{
    ac_xf a, b, r, z;
    int8_t c;
    z.m = 0;
    z.e = 0;
    a.m = 0x20000000L; /* 2^29 */
    a.e = 0;

    /* NULL outputs */
    CHECK_STATUS(ac_xf_add(a, a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_sub(a, a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_mul(a, a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_div(a, a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_neg(a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_abs(a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_cmpabs(a, a, NULL), AC_ERR_NULL);
    CHECK_STATUS(ac_xf_ldexp(a, 1, NULL), AC_ERR_NULL);

    /* division by zero: AC_ERR_SINGULAR, output untouched */
    r.m = 0x5A5A5A5AL;
    r.e = 1234;
    CHECK_STATUS(ac_xf_div(a, z, &r), AC_ERR_SINGULAR);
    CHECK(r.m == 0x5A5A5A5AL && r.e == 1234);

    /* zero results and zero operands */
    CHECK_STATUS(ac_xf_sub(a, a, &r), AC_OK);
    CHECK_EQ(r.m, 0);
    CHECK_STATUS(ac_xf_mul(a, z, &r), AC_OK);
    CHECK_EQ(r.m, 0);
    CHECK_STATUS(ac_xf_div(z, a, &r), AC_OK);
    CHECK_EQ(r.m, 0);
    CHECK_STATUS(ac_xf_add(z, a, &r), AC_OK);
    CHECK(xval(r) == xval(a));
    CHECK_STATUS(ac_xf_cmpabs(z, a, &c), AC_OK);
    CHECK_EQ(c, -1);
    CHECK_STATUS(ac_xf_cmpabs(z, z, &c), AC_OK);
    CHECK_EQ(c, 0);

    /* ties are rounded away from zero:
     * 2^29 + 0.5 -> 2^29 + 1;  -(2^29 + 0.5) -> -(2^29 + 1) */
    b.m = 0x20000000L;
    b.e = -30; /* 0.5 */
    CHECK_STATUS(ac_xf_add(a, b, &r), AC_OK);
    CHECK(xval(r) == 536870913.0L);
    a.m = -a.m;
    b.m = -b.m;
    CHECK_STATUS(ac_xf_add(a, b, &r), AC_OK);
    CHECK(xval(r) == -536870913.0L);
    /* (2^29 + 1) * 3 * 2^28 = 805306369.5 * 2^29 -> 805306370 * 2^29 */
    a.m = 0x20000001L;
    a.e = 0;
    b.m = 0x30000000L;
    b.e = 0;
    CHECK_STATUS(ac_xf_mul(a, b, &r), AC_OK);
    CHECK(xval(r) == ldexpl(805306370.0L, 29));
    b.m = -b.m;
    CHECK_STATUS(ac_xf_mul(a, b, &r), AC_OK);
    CHECK(xval(r) == ldexpl(-805306370.0L, 29));
    /* exact quotients */
    a.m = 0x30000000L; /* 3 * 2^28 */
    a.e = -28;         /* = 3 */
    b.m = 0x20000000L;
    b.e = -28; /* = 2 */
    CHECK_STATUS(ac_xf_div(a, b, &r), AC_OK);
    CHECK(xval(r) == 1.5L);
    CHECK_STATUS(ac_xf_div(b, a, &r), AC_OK); /* 2/3 */
    CHECK(rel_ok(xval(r), 2.0L / 3.0L));
    CHECK_XF(r);
}

int main(void)
{
    test_from_to_fixed();
    test_arith();
    test_special();
    return AC_TEST_END();
}
