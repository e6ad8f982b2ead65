/*
 * accelcal -- a tiny self-contained test framework for the C unit tests.
 *
 * One translation unit per test program includes this header once.  Checks
 * count as passed or failed; a failed check prints "file:line: message" with
 * the values involved.  AC_TEST_END() prints the final line, exactly
 *
 *     N passed, N failed
 *
 * and returns the process exit code (0 only if nothing failed).
 *
 * Host-only (stdio); test code may use long long and floating point, the
 * library may not.
 */
#ifndef AC_TEST_H
#define AC_TEST_H

#include <stdio.h>

static unsigned long ac_test_passed_ = 0ul;
static unsigned long ac_test_failed_ = 0ul;
/* Failure messages printed per program before going quiet (counting goes on). */
#ifndef AC_TEST_MAX_REPORTS
#define AC_TEST_MAX_REPORTS 60ul
#endif
/* Optional context printed with each failure (e.g. the random case number). */
static const char *ac_test_ctx_ = "";
static long long ac_test_ctx_i_ = -1;

static inline void ac_test_context(const char *what, long long i)
{
    ac_test_ctx_ = what;
    ac_test_ctx_i_ = i;
}

static inline int ac_test_report_(const char *file, int line)
{
    ac_test_failed_++;
    if (ac_test_failed_ > AC_TEST_MAX_REPORTS) {
        if (ac_test_failed_ == AC_TEST_MAX_REPORTS + 1ul) {
            printf("(further failures are counted but not printed)\n");
        }
        return 0;
    }
    printf("%s:%d: FAIL", file, line);
    if (ac_test_ctx_[0] != '\0') {
        printf(" [%s #%lld]", ac_test_ctx_, ac_test_ctx_i_);
    }
    printf(": ");
    return 1;
}

#define CHECK(cond)                                                              \
    do {                                                                         \
        if (cond) {                                                              \
            ac_test_passed_++;                                                   \
        } else if (ac_test_report_(__FILE__, __LINE__)) {                        \
            printf("%s\n", #cond);                                               \
        }                                                                        \
    } while (0)

/* Like CHECK, with a printf-style explanation (parenthesised argument list). */
#define CHECK_MSG(cond, args)                                                    \
    do {                                                                         \
        if (cond) {                                                              \
            ac_test_passed_++;                                                   \
        } else if (ac_test_report_(__FILE__, __LINE__)) {                        \
            printf("%s: ", #cond);                                               \
            printf args;                                                         \
            printf("\n");                                                        \
        }                                                                        \
    } while (0)

/* Integer equality (both sides converted to long long). */
#define CHECK_EQ(a, b)                                                           \
    do {                                                                         \
        long long ac_t_a_ = (long long)(a), ac_t_b_ = (long long)(b);            \
        if (ac_t_a_ == ac_t_b_) {                                                \
            ac_test_passed_++;                                                   \
        } else if (ac_test_report_(__FILE__, __LINE__)) {                        \
            printf("%s == %s: %lld (0x%llx) != %lld (0x%llx)\n", #a, #b,         \
                   ac_t_a_, (unsigned long long)ac_t_a_, ac_t_b_,                \
                   (unsigned long long)ac_t_b_);                                 \
        }                                                                        \
    } while (0)

/* A status-returning call gives exactly the expected status. */
#define CHECK_STATUS(call, expected) CHECK_EQ((int)(call), (int)(expected))

/* |a - b| <= tol, in long double. */
#define CHECK_NEAR(a, b, tol)                                                    \
    do {                                                                         \
        long double ac_t_a_ = (long double)(a), ac_t_b_ = (long double)(b);      \
        long double ac_t_t_ = (long double)(tol);                                \
        long double ac_t_d_ = ac_t_a_ - ac_t_b_;                                 \
        if (ac_t_d_ < 0) {                                                       \
            ac_t_d_ = -ac_t_d_;                                                  \
        }                                                                        \
        if (ac_t_d_ <= ac_t_t_) {                                                \
            ac_test_passed_++;                                                   \
        } else if (ac_test_report_(__FILE__, __LINE__)) {                        \
            printf("|%s - %s| <= %s: |%.17Lg - %.17Lg| = %.6Lg > %.6Lg\n", #a,  \
                   #b, #tol, ac_t_a_, ac_t_b_, ac_t_d_, ac_t_t_);                \
        }                                                                        \
    } while (0)

/* Print the summary line and give the exit code. */
#define AC_TEST_END()                                                            \
    (printf("%lu passed, %lu failed\n", ac_test_passed_, ac_test_failed_),       \
     fflush(stdout), (ac_test_failed_ == 0ul && ac_test_passed_ > 0ul) ? 0 : 1)

/* ---- deterministic pseudo-random numbers (xorshift32) ------------------- */
static unsigned long ac_test_rng_state_ = 2463534242ul;

static inline void ac_test_seed(unsigned long s)
{
    ac_test_rng_state_ = (s & 0xFFFFFFFFul) ? (s & 0xFFFFFFFFul) : 2463534242ul;
}

static inline unsigned long ac_test_rand32(void)
{
    unsigned long x = ac_test_rng_state_;
    x ^= (x << 13) & 0xFFFFFFFFul;
    x ^= x >> 17;
    x ^= (x << 5) & 0xFFFFFFFFul;
    ac_test_rng_state_ = x & 0xFFFFFFFFul;
    return ac_test_rng_state_;
}

/* Uniform-ish in [lo, hi] (hi - lo < 2^32). */
static inline long long ac_test_range(long long lo, long long hi)
{
    unsigned long long span = (unsigned long long)(hi - lo) + 1ull;
    return lo + (long long)((unsigned long long)ac_test_rand32() % span);
}

/* Two's complement reinterpretation of a 32-bit pattern. */
static inline long long ac_test_s32(unsigned long u)
{
    u &= 0xFFFFFFFFul;
    return (u & 0x80000000ul) ? (long long)u - 4294967296ll : (long long)u;
}

/* A random int32 with a random magnitude (uniform in bit length, so small,
 * medium and huge values all occur) -- returned as long long. */
static inline long long ac_test_rand_i32(void)
{
    unsigned long r = ac_test_rand32();
    unsigned sh = (unsigned)(ac_test_rand32() % 32ul);
    return ac_test_s32(r) / (1ll << sh);
}

#endif /* AC_TEST_H */
