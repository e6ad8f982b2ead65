/*
 * accelcal -- one libFuzzer harness over the whole C core API.
 *
 * The first input byte picks a target; the rest is read as a little-endian
 * byte stream (reads past the end give 0, so every input is valid):
 *
 *   0 ac_trim, ac_trim_rails_s16  pre-trim vs clip(raw - trim); the signed rails
 *   1 ac_resolve                  random tables, checked and unchecked; on a
 *                                 checked table the outputs against an
 *                                 independent 128-bit computation within the
 *                                 bound of ac_resolve.h
 *   2 ac_process, ac_process_batch   batch == per sample == trim + resolve
 *   3 ac_resolver_build           random / structured / degenerate channel
 *                                 parameters, n in and out of range; on AC_OK
 *                                 the table passes ac_resolver_check and agrees
 *                                 with a double-precision pseudo-inverse; on an
 *                                 error the output table is untouched
 *   4 ac_invert6                  random, structured, singular and badly scaled
 *                                 matrices; on AC_OK  A * inv ~ I, cond_log2
 *   5 ac_xf_*                     every operation against exact 128-bit results
 *   6 ac_fixed                    every primitive against exact 128-bit results
 *   7 ac_rate_*                   the documented recurrence, exactly
 *   8 NULL pointers               AC_ERR_NULL from every function
 *   9 ac_sensor_row, ac_centripetal_row   against double precision
 *  10 ac_isqrt32, ac_udiv64, ac_mul32x16_shift exactly; ac_atan2 within its
 *                                 stated bound (ac_trig.h)
 *  11 ac_rest_*                   flags against the documented detector, run
 *                                 exactly; batch == steps; rate reset at rest
 *  12 ac_triad_*, ac_att_*        triad exact rounding; theta, dw, w2 as
 *                                 documented from the stored constants; batch ==
 *                                 steps; init errors leave the state unwritten
 *  13 ac_disp_*, ac_tilt_frame    flags and invariants (no estimate before the
 *                                 first rest, v = 0 at rest, 1-D components);
 *                                 batch == steps; the frame within 2 LSB
 *
 *  14 ac_temp_*, ac_skew_*, ac_nonlin_*   each against its header's integer recurrence
 *                                 written out in 64-bit (every rounding, clip and the
 *                                 flag); in place == separate; the temperature and the
 *                                 nonlinearity within their headers' bounds against the
 *                                 float formula (fuzz/fuzz_terms.c)
 *  15 ac_omega_*                  the vectors' table (perturbed or not) and random
 *                                 tables: check == its rules; errors write nothing;
 *                                 the state normalised; q10 == q16 / 64 within 1 LSB;
 *                                 the saturation flags; step == replayed step
 *                                 (fuzz/fuzz_omega.c)
 *
 * (the first byte is taken mod 16)
 * Everywhere: the status is one of the ac_status values, and a negative status
 * leaves the outputs unwritten (ac_status.h).  A violated property prints what
 * failed and aborts, which libFuzzer reports as a crash.
 *
 * Build (tools/fuzz.sh):
 *   clang -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
 *         -std=c99 -Iinclude -Icsrc fuzz/fuzz_core.c csrc/\*.c
 * Without libFuzzer (tests/python/test_fuzz_smoke.py): add fuzz/replay_main.c.
 *
 * Host test code: may use floating point, malloc and 128-bit integers (a GCC /
 * Clang extension); the core it tests may not.
 *
 * -DFUZZ_RAW_XF_MIN lets the raw (unnormalised) ac_xf inputs of targets 4 and 5
 * have the mantissa INT32_MIN, which ac_xf_neg / ac_xf_abs negate with signed
 * overflow (reported; off by default so that fuzzing goes past it).
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accelcal/accelcal.h"

__extension__ typedef __int128 i128;

#define TWO_PI_Q13 (6.283185307179586 * 8192.0) /* 2 pi in Q.13 angle LSB (no M_PI in C99) */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* ------------------------------------------------------------------------- */
/* failure reporting                                                         */

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "fuzz_core: property failed at %s:%d: %s\n  ", __FILE__, __LINE__,     \
                    #cond);                                                                        \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

static int status_valid(ac_status s)
{
    switch (s) {
    case AC_OK:
    case AC_SATURATED:
    case AC_AT_RAIL:
    case AC_AT_RAIL_SATURATED:
    case AC_ERR_NULL:
    case AC_ERR_SIZE:
    case AC_ERR_SINGULAR:
    case AC_ERR_ILL_COND:
    case AC_ERR_RANGE:
    case AC_ERR_FORMAT:
        return 1;
    default:
        return 0;
    }
}

#define CHECK_STATUS(st) CHECK(status_valid(st), "status %d is not an ac_status value", (int)(st))

/* ------------------------------------------------------------------------- */
/* input reader                                                              */

typedef struct rd {
    const uint8_t *p;
    size_t n;
} rd;

static uint8_t rd_u8(rd *r)
{
    if (r->n == 0u) {
        return 0u;
    }
    r->n--;
    return *r->p++;
}

static uint16_t rd_u16(rd *r)
{
    uint16_t lo = rd_u8(r);
    uint16_t hi = rd_u8(r);
    return (uint16_t)(lo | (uint16_t)(hi << 8));
}

static uint32_t rd_u32(rd *r)
{
    uint32_t lo = rd_u16(r);
    uint32_t hi = rd_u16(r);
    return lo | (hi << 16);
}

static int16_t rd_i16(rd *r) { return (int16_t)rd_u16(r); }
static int32_t rd_i32(rd *r) { return (int32_t)rd_u32(r); }
static int8_t rd_i8(rd *r) { return (int8_t)rd_u8(r); }

/* an int32 that is an edge value a quarter of the time */
static int32_t rd_i32_edge(rd *r)
{
    static const int32_t edges[16] = {0,         1,          -1,          INT32_MAX, INT32_MIN,
                                      INT32_MAX - 1, INT32_MIN + 1, 1 << 29,   -(1 << 29),
                                      (1 << 30) - 1, 1 << 30,    -(1 << 30),  32767,     -32768,
                                      65535,     -65536};
    uint8_t sel = rd_u8(r);
    if ((sel & 3u) == 0u) {
        return edges[(sel >> 2) & 15u];
    }
    return rd_i32(r);
}

static int16_t rd_i16_edge(rd *r)
{
    static const int16_t edges[8] = {0, 1, -1, 32767, -32768, 32766, -32767, 181};
    uint8_t sel = rd_u8(r);
    if ((sel & 3u) == 0u) {
        return edges[(sel >> 2) & 7u];
    }
    return rd_i16(r);
}

/* ------------------------------------------------------------------------- */
/* exact helpers                                                             */

static i128 p2(int k) /* 2^k, 0 <= k <= 125 */
{
    return (i128)1 << k;
}

static i128 floor_div_p2(i128 v, int k) /* floor(v / 2^k), 0 <= k <= 125 */
{
    i128 d = p2(k);
    i128 q = v / d;
    if (v % d != 0 && v < 0) {
        q -= 1;
    }
    return q;
}

static i128 round_half_up_p2(i128 v, int k) /* floor(v / 2^k + 1/2) */
{
    if (k == 0) {
        return v;
    }
    return floor_div_p2(v + p2(k - 1), k);
}

static int fits32(i128 v) { return v >= INT32_MIN && v <= INT32_MAX; }

static int32_t clip32(i128 v)
{
    return v > INT32_MAX ? INT32_MAX : (v < INT32_MIN ? INT32_MIN : (int32_t)v);
}

static i128 abs128(i128 v) { return v < 0 ? -v : v; }

static void *xmalloc(size_t n)
{
    void *p = malloc(n == 0u ? 1u : n);
    if (p == NULL) {
        abort();
    }
    return p;
}

/* ========================================================================= */
/* 0: ac_trim                                                                */

static void target_trim(rd *r)
{
    uint16_t n = (uint16_t)(rd_u8(r) % 20u);
    uint16_t *raw = xmalloc(n * sizeof *raw), *trim = xmalloc(n * sizeof *trim);
    int16_t *x = xmalloc((n + 1u) * sizeof *x);
    uint16_t i;
    int sat = 0;
    ac_status st;
    for (i = 0; i < n; i++) {
        raw[i] = rd_u16(r);
        trim[i] = rd_u16(r);
    }
    x[n] = 0x5a5a;
    st = ac_trim(raw, trim, n, x);
    CHECK_STATUS(st);
    if (n == 0u) {
        CHECK(st == AC_ERR_SIZE, "ac_trim n=0 gave %d", st);
    } else {
        CHECK(st >= 0, "ac_trim gave %d", st);
        for (i = 0; i < n; i++) {
            int32_t d = (int32_t)raw[i] - (int32_t)trim[i];
            int32_t e = d > 32767 ? 32767 : (d < -32768 ? -32768 : d);
            sat |= (e != d);
            CHECK(x[i] == e, "ac_trim x[%u]=%d, expected %d", i, x[i], e);
        }
        CHECK((st == AC_SATURATED) == (sat != 0), "ac_trim status %d, clipped %d", st, sat);
    }
    CHECK(x[n] == 0x5a5a, "ac_trim wrote past n");
    {
        /* the same readings as a signed chip's (code - 32768) with drawn rails in its counts:
         * ac_trim_rails_s16 gives ac_trim's x and saturation, and AC_AT_RAIL by the written-out
         * test on the signed values (raw_min >= raw_max: unknown, nothing flagged) */
        int16_t *sraw = xmalloc((n + 1u) * sizeof *sraw), *strim = xmalloc((n + 1u) * sizeof *strim);
        int16_t *sx = xmalloc((n + 1u) * sizeof *sx);
        int16_t lo = (int16_t)((int32_t)rd_u16(r) - 32768), hi = (int16_t)((int32_t)rd_u16(r) - 32768);
        int rail = 0;
        ac_status ss;
        if (rd_u8(r) & 1u) { /* a 12-bit chip's rails, often */
            lo = -2048;
            hi = 2047;
        }
        for (i = 0; i < n; i++) {
            sraw[i] = (int16_t)((int32_t)raw[i] - 32768);
            strim[i] = (int16_t)((int32_t)trim[i] - 32768);
            rail |= sraw[i] <= lo || sraw[i] >= hi;
        }
        sx[n] = 0x5a5a;
        ss = ac_trim_rails_s16(sraw, strim, n, lo, hi, sx);
        CHECK_STATUS(ss);
        if (n == 0u) {
            CHECK(ss == AC_ERR_SIZE, "ac_trim_rails_s16 n=0 gave %d", ss);
        } else {
            CHECK(ss >= 0 && (ss & AC_SATURATED) == st, "ac_trim_rails_s16 status %d, ac_trim %d", ss, st);
            CHECK(((ss & AC_AT_RAIL) != 0) == (lo < hi && rail), "ac_trim_rails_s16 status %d, rails %d %d",
                  ss, lo, hi);
            CHECK(memcmp(sx, x, n * sizeof *x) == 0, "ac_trim_rails_s16 x != ac_trim x");
            CHECK(ac_trim_s16(sraw, strim, n, sx) == st, "ac_trim_s16 status != ac_trim's");
        }
        CHECK(sx[n] == 0x5a5a, "ac_trim_rails_s16 wrote past n");
        free(sraw);
        free(strim);
        free(sx);
    }
    free(raw);
    free(trim);
    free(x);
}

/* ========================================================================= */
/* resolver tables                                                           */

/* A table from the input.  valid: every invariant of ac_resolver_check holds
 * (row sums scaled down into range); else anything, including garbage beyond
 * n, shifts out of range and n out of range. */
static void gen_table(rd *r, ac_resolver *t, int valid)
{
    uint8_t j;
    uint16_t i;
    uint8_t style = rd_u8(r);
    memset(t, 0, sizeof *t);
    if (valid) {
        t->n = (uint16_t)(6u + rd_u8(r) % (AC_MAX_CHANNELS - 5u));
    } else {
        static const uint16_t ns[8] = {0u, 5u, 6u, 7u, AC_MAX_CHANNELS, AC_MAX_CHANNELS + 1u,
                                       65535u, 3u};
        uint8_t sel = rd_u8(r);
        t->n = (sel & 1u) ? ns[(sel >> 1) & 7u] : (uint16_t)(6u + rd_u8(r) % (AC_MAX_CHANNELS - 5u));
    }
    for (j = 0; j < 6; j++) {
        int64_t l1 = 0, gl1 = 0;
        for (i = 0; i < AC_MAX_CHANNELS; i++) {
            int16_t v = (style & 1u) ? rd_i16_edge(r) : (int16_t)(rd_i8(r) * ((style & 2u) ? 1 : 97));
            if (valid && i >= t->n) {
                v = (style & 4u) ? rd_i16(r) : 0; /* garbage beyond n must not matter */
            }
            t->m[j][i] = v;
            if (i < t->n) {
                l1 += v < 0 ? -(int64_t)v : v;
            }
        }
        for (i = 0; i < 6; i++) {
            t->g[j][i] = (style & 8u) ? rd_i16_edge(r) : (int16_t)(rd_i8(r) * 131);
            gl1 += t->g[j][i] < 0 ? -(int64_t)t->g[j][i] : t->g[j][i];
        }
        if (valid && l1 > 65535) {
            for (i = 0; i < t->n; i++) {
                t->m[j][i] = (int16_t)((int64_t)t->m[j][i] * 65535 / l1);
            }
        }
        if (valid && gl1 > 65535) {
            for (i = 0; i < 6; i++) {
                t->g[j][i] = (int16_t)((int64_t)t->g[j][i] * 65535 / gl1);
            }
        }
        if (valid && (style & 16u) && j == (style >> 5)) {
            /* the extreme rows the invariant allows */
            memset(t->m[j], 0, sizeof t->m[j]);
            t->m[j][0] = -32768;
            t->m[j][t->n - 1u] = 32767;
            memset(t->g[j], 0, sizeof t->g[j]);
            t->g[j][0] = -32768;
            t->g[j][1] = 32767;
            t->g[j][2] = 0;
        }
        t->k[j] = rd_i32_edge(r);
        if (valid) {
            t->m_shift[j] = (int8_t)((int)(rd_u8(r) % 63u) - 31);
            t->g_shift[j] = (int8_t)((int)(rd_u8(r) % 63u) - 31);
        } else {
            t->m_shift[j] = rd_i8(r);
            t->g_shift[j] = rd_i8(r);
        }
    }
    /* the converter's rails: any pair (raw_min >= raw_max: unknown, nothing flagged) */
    t->raw_min = rd_u16(r);
    t->raw_max = rd_u16(r);
}

/* the rail test of ac_trim_rails, written out: some raw_i <= lo or >= hi, known rails */
static int at_rail(const uint16_t *raw, uint16_t n, uint16_t lo, uint16_t hi)
{
    uint16_t i;
    int any = 0;
    for (i = 0; i < n; i++) {
        any |= raw[i] <= lo || raw[i] >= hi;
    }
    return lo < hi && any;
}

static int table_row_ok(const ac_resolver *t)
{
    uint8_t j;
    uint16_t i;
    if (t->n < 6u || t->n > AC_MAX_CHANNELS) {
        return 0;
    }
    for (j = 0; j < 6; j++) {
        int64_t l1 = 0, gl1 = 0;
        if (t->m_shift[j] < -31 || t->m_shift[j] > 31 || t->g_shift[j] < -31 || t->g_shift[j] > 31) {
            return 0;
        }
        for (i = 0; i < t->n; i++) {
            l1 += t->m[j][i] < 0 ? -(int64_t)t->m[j][i] : t->m[j][i];
        }
        for (i = 0; i < 6; i++) {
            gl1 += t->g[j][i] < 0 ? -(int64_t)t->g[j][i] : t->g[j][i];
        }
        if (l1 > 65535 || gl1 > 65535) {
            return 0;
        }
    }
    return 1;
}

static unsigned bitlen64(uint64_t u)
{
    unsigned n = 0;
    while (u != 0u) {
        n++;
        u >>= 1;
    }
    return n;
}

/* The outputs of ac_resolve on a table that passed ac_resolver_check, against
 * the exact value of the table's arithmetic (ac_resolve.h):
 *   exact_j = (sum_i m x - k) 2^-ms - sum_q g P_q 2^-(gs + 2W)   (output LSB)
 * with P the exact products of omega (Q.2W).  AC_OK: every output within
 * 0.5 + E_j (E_j as documented; E = 0 and the output correctly rounded without
 * omega).  AC_SATURATED: rows whose every intermediate is far inside int32
 * still obey the bound, and a call where all rows are so must give AC_OK. */
static void check_resolve(const ac_resolver *t, const int16_t *x, const int16_t *omega,
                          const int32_t *out, ac_status st, const char *what)
{
    const int W2 = 2 * AC_OMEGA_FRAC;
    int64_t P[6] = {0, 0, 0, 0, 0, 0};
    unsigned s = 0;
    uint8_t j, q;
    uint16_t i;
    int all_inside = 1;
    CHECK(st == AC_OK || st == AC_SATURATED, "%s: status %d on a checked table", what, st);
    if (omega != NULL) {
        int64_t mx;
        P[0] = (int64_t)omega[0] * omega[0];
        P[1] = (int64_t)omega[1] * omega[1];
        P[2] = (int64_t)omega[2] * omega[2];
        P[3] = (int64_t)omega[0] * omega[1];
        P[4] = (int64_t)omega[1] * omega[2];
        P[5] = (int64_t)omega[2] * omega[0];
        mx = P[0] > P[1] ? P[0] : P[1];
        mx = mx > P[2] ? mx : P[2];
        s = bitlen64((uint64_t)mx);
        s = s > 14u ? s - 14u : 0u;
    }
    for (j = 0; j < 6; j++) {
        int ms = t->m_shift[j], gs = t->g_shift[j];
        int64_t A = 0, G = 0, gabs = 0;
        i128 L, X, B;
        int D, inside;
        double exact_d, T_d;
        for (i = 0; i < t->n; i++) {
            A += (int64_t)t->m[j][i] * x[i];
        }
        L = (i128)A - t->k[j];
        for (q = 0; q < 6; q++) {
            G += (int64_t)t->g[j][q] * P[q];
            gabs += t->g[j][q] < 0 ? -(int64_t)t->g[j][q] : t->g[j][q];
        }
        if (omega == NULL) {
            i128 e;
            exact_d = ldexp((double)L, -ms);
            inside = fabs((double)L) < 0x1p29 && fabs(exact_d) < 0x1p29;
            if (!inside) {
                all_inside = 0;
            }
            if (st == AC_SATURATED && !inside) {
                continue;
            }
            e = ms > 0 ? round_half_up_p2(L, ms) : L * p2(-ms);
            CHECK(fits32(e) && out[j] == (int32_t)e,
                  "%s: row %u out=%ld, exact rounded=%.17g (no rotation, ms=%d, status %d)", what,
                  j, (long)out[j], (double)e, ms, st);
            continue;
        }
        /* with rotation: everything scaled by 2^D to integers */
        D = ms + 1;
        if (gs + W2 + 1 > D) {
            D = gs + W2 + 1;
        }
        if (D < 1) {
            D = 1;
        }
        X = (i128)out[j] * p2(D) - (L * p2(D - ms) - (i128)G * p2(D - gs - W2));
        B = p2(D - 1);
        if (s > 0u) {
            B += (i128)gabs * p2((int)s - 1 - W2 - gs + D);
        }
        if ((int)s - W2 - gs + ms < 0) {
            B += p2(D - 1 - ms);
        }
        exact_d = ldexp((double)L, -ms) - ldexp((double)G, -(gs + W2));
        T_d = ldexp((double)gabs * (double)(1u << 30), ms - gs - W2); /* |T| bound, acc units */
        inside = fabs((double)L) < 0x1p29 && T_d < 0x1p29 && fabs(exact_d) < 0x1p29;
        if (!inside) {
            all_inside = 0;
        }
        if (st == AC_SATURATED && !inside) {
            continue;
        }
        CHECK(abs128(X) <= B,
              "%s: row %u out=%ld exact=%.17g bound=0.5+E, |err|*2^D=%.17g > %.17g (ms=%d gs=%d "
              "s=%u D=%d status %d)",
              what, j, (long)out[j], exact_d, (double)abs128(X), (double)B, ms, gs, s, D, st);
    }
    if (all_inside) {
        CHECK(st == AC_OK, "%s: status %d though nothing came near int32 limits", what, st);
    }
}

static void fill_sentinel(void *p, size_t n) { memset(p, 0xA5, n); }

static int is_sentinel(const void *p, size_t n)
{
    const uint8_t *b = p;
    size_t i;
    for (i = 0; i < n; i++) {
        if (b[i] != 0xA5u) {
            return 0;
        }
    }
    return 1;
}

/* ========================================================================= */
/* 1: ac_resolve                                                             */

static void target_resolve(rd *r)
{
    uint8_t mode = rd_u8(r);
    int valid = (mode & 1u) != 0u;
    ac_resolver *t = xmalloc(sizeof *t);
    int16_t *x, *omega = NULL;
    int32_t *out = xmalloc(6 * sizeof *out), *out2 = xmalloc(6 * sizeof *out2);
    uint16_t i, n_alloc;
    ac_status st, chk;

    gen_table(r, t, valid);
    n_alloc = (t->n >= 1u && t->n <= AC_MAX_CHANNELS) ? t->n : 1u;
    x = xmalloc(n_alloc * sizeof *x);
    for (i = 0; i < n_alloc; i++) {
        x[i] = (mode & 4u) ? rd_i16_edge(r) : rd_i16(r);
    }
    if (mode & 2u) {
        omega = xmalloc(3 * sizeof *omega);
        for (i = 0; i < 3; i++) {
            omega[i] = (mode & 8u) ? rd_i16_edge(r) : (int16_t)(rd_i8(r) * ((mode & 16u) ? 1 : 64));
        }
    }
    chk = ac_resolver_check(t);
    CHECK_STATUS(chk);
    CHECK((chk == AC_OK) == table_row_ok(t), "ac_resolver_check gave %d, invariants hold: %d", chk,
          table_row_ok(t));
    if (valid) {
        CHECK(chk == AC_OK, "generated a valid table, ac_resolver_check gave %d", chk);
    }
    fill_sentinel(out, 6 * sizeof *out);
    /* firmware checks once; this harness also feeds the unchecked table
     * (it must never be undefined behaviour, whatever the numbers) */
    st = ac_resolve(t, x, omega, out);
    CHECK_STATUS(st);
    if (st < 0) {
        CHECK(is_sentinel(out, 6 * sizeof *out), "ac_resolve error %d but outputs written", st);
        CHECK(t->n < 6u || t->n > AC_MAX_CHANNELS || chk != AC_OK, "ac_resolve error %d on a checked table", st);
    }
    if (chk == AC_OK) {
        check_resolve(t, x, omega, out, st, "ac_resolve");
        /* garbage beyond n must not change anything */
        {
            ac_resolver *t2 = xmalloc(sizeof *t2);
            uint8_t j;
            ac_status st2;
            memcpy(t2, t, sizeof *t2);
            for (j = 0; j < 6; j++) {
                for (i = t->n; i < AC_MAX_CHANNELS; i++) {
                    t2->m[j][i] = (int16_t)(t->m[j][i] ^ 0x7fff);
                }
            }
            st2 = ac_resolve(t2, x, omega, out2);
            CHECK(st2 == st && memcmp(out, out2, 6 * sizeof *out) == 0,
                  "ac_resolve depends on m[][i >= n]");
            free(t2);
        }
    }
    free(t);
    free(x);
    free(omega);
    free(out);
    free(out2);
}

/* ========================================================================= */
/* 2: ac_process, ac_process_batch                                           */

static ac_status merge(ac_status a, ac_status b)
{
    if (a < 0) {
        return a;
    }
    if (b < 0) {
        return b;
    }
    return (ac_status)((unsigned)a | (unsigned)b);
}

static void target_process(rd *r)
{
    uint8_t mode = rd_u8(r);
    int valid = (mode & 1u) != 0u;
    uint32_t count = rd_u8(r) % 9u, k;
    ac_resolver *t = xmalloc(sizeof *t);
    uint16_t n, i, *trim, *raw;
    int16_t *omega = NULL, x[AC_MAX_CHANNELS];
    int32_t *out, o1[6], o2[6];
    uint8_t *flags;
    ac_status st, chk;

    gen_table(r, t, valid);
    chk = ac_resolver_check(t);
    n = (t->n >= 1u && t->n <= AC_MAX_CHANNELS) ? t->n : 1u;
    trim = xmalloc(n * sizeof *trim);
    raw = xmalloc((count ? count : 1u) * n * sizeof *raw);
    out = xmalloc((count ? count : 1u) * 6u * sizeof *out);
    flags = xmalloc(count ? count : 1u);
    for (i = 0; i < n; i++) {
        trim[i] = (mode & 4u) ? rd_u16(r) : (uint16_t)(32768u + (uint16_t)rd_i8(r));
    }
    for (k = 0; k < count * n; k++) {
        raw[k] = (mode & 8u) ? rd_u16(r) : (uint16_t)(trim[k % n] + (uint16_t)(rd_i8(r) * 37));
    }
    if (mode & 2u) {
        omega = xmalloc((count ? count : 1u) * 3u * sizeof *omega);
        for (k = 0; k < (count ? count : 1u) * 3u; k++) {
            omega[k] = (mode & 16u) ? rd_i16_edge(r) : (int16_t)(rd_i8(r) * 16);
        }
    }
    fill_sentinel(out, (count ? count : 1u) * 6u * sizeof *out);
    fill_sentinel(flags, count ? count : 1u);
    st = ac_process_batch(t, trim, raw, count, omega, out, (mode & 32u) ? NULL : flags);
    CHECK_STATUS(st);
    if (chk != AC_OK) {
        CHECK(st == chk, "ac_process_batch on a bad table gave %d, ac_resolver_check %d", st, chk);
        CHECK(is_sentinel(out, (count ? count : 1u) * 6u * sizeof *out), "batch wrote on error");
    } else {
        ac_status any = AC_OK;
        for (k = 0; k < count; k++) {
            const int16_t *om = omega ? omega + 3u * k : NULL;
            ac_status sp = ac_process(t, trim, raw + k * n, om, o1);
            ac_status s1 = ac_trim(raw + k * n, trim, n, x);
            ac_status s2 = ac_resolve(t, x, om, o2);
            int rail = at_rail(raw + k * n, n, t->raw_min, t->raw_max);
            uint8_t f = (uint8_t)((s1 == AC_SATURATED ? AC_FLAG_TRIM_SAT : 0u) |
                                  (s2 == AC_SATURATED ? AC_FLAG_OUT_SAT : 0u) | (rail ? AC_FLAG_AT_RAIL : 0u));
            CHECK_STATUS(sp);
            if (rail && s2 >= 0) {
                s1 = merge(s1, AC_AT_RAIL);
            }
            CHECK(sp == merge(s1, s2), "ac_process %d, trim %d + resolve %d", sp, s1, s2);
            CHECK(memcmp(o1, o2, sizeof o1) == 0, "ac_process != ac_trim + ac_resolve");
            CHECK(memcmp(o1, out + 6u * k, sizeof o1) == 0, "batch sample %u != ac_process", k);
            if (!(mode & 32u)) {
                CHECK(flags[k] == f, "batch flags[%u]=%u, expected %u", k, flags[k], f);
            }
            check_resolve(t, x, om, o2, s2, "ac_process");
            any = merge(any, sp);
        }
        CHECK(st == any, "ac_process_batch %d, samples %d", st, any);
    }
    free(t);
    free(trim);
    free(raw);
    free(out);
    free(flags);
    free(omega);
}

/* ========================================================================= */
/* double-precision reference for the build                                  */

static int dinv6(double a[6][6]) /* Gauss-Jordan, partial pivoting; 0 if singular */
{
    int perm[6], i, j, k;
    for (k = 0; k < 6; k++) {
        int p = k;
        double inv;
        for (i = k + 1; i < 6; i++) {
            if (fabs(a[i][k]) > fabs(a[p][k])) {
                p = i;
            }
        }
        if (a[p][k] == 0.0) {
            return 0;
        }
        if (p != k) {
            for (j = 0; j < 6; j++) {
                double tt = a[k][j];
                a[k][j] = a[p][j];
                a[p][j] = tt;
            }
        }
        perm[k] = p;
        inv = 1.0 / a[k][k];
        a[k][k] = 1.0;
        for (j = 0; j < 6; j++) {
            a[k][j] *= inv;
        }
        for (i = 0; i < 6; i++) {
            double f;
            if (i == k) {
                continue;
            }
            f = a[i][k];
            a[i][k] = 0.0;
            for (j = 0; j < 6; j++) {
                a[i][j] -= f * a[k][j];
            }
        }
    }
    for (k = 5; k >= 0; k--) {
        if (perm[k] != k) {
            for (i = 0; i < 6; i++) {
                double tt = a[i][k];
                a[i][k] = a[i][perm[k]];
                a[i][perm[k]] = tt;
            }
        }
    }
    return 1;
}

static double norm1_6(double a[6][6])
{
    double mx = 0.0;
    int i, j;
    for (j = 0; j < 6; j++) {
        double s = 0.0;
        for (i = 0; i < 6; i++) {
            s += fabs(a[i][j]);
        }
        if (s > mx) {
            mx = s;
        }
    }
    return mx;
}

static void dsensor_row(const ac_channel_cal *c, double row[6])
{
    double s[3], p[3];
    int a;
    for (a = 0; a < 3; a++) {
        s[a] = ldexp((double)c->sens[a], -AC_SENS_FRAC);
        p[a] = ldexp((double)c->pos[a], -AC_POS_FRAC);
        row[a] = s[a];
    }
    for (a = 0; a < 3; a++) {
        int b = (a + 1) % 3, cc = (a + 2) % 3;
        row[3 + a] = p[b] * s[cc] - p[cc] * s[b];
    }
}

static void dcentripetal_row(const ac_channel_cal *c, double row[6])
{
    double s[3], p[3], sr = 0.0;
    int a;
    for (a = 0; a < 3; a++) {
        s[a] = ldexp((double)c->sens[a], -AC_SENS_FRAC);
        p[a] = ldexp((double)c->pos[a], -AC_POS_FRAC);
        sr += s[a] * p[a];
    }
    for (a = 0; a < 3; a++) {
        int b = (a + 1) % 3;
        row[a] = s[a] * p[a] - sr;
        row[3 + a] = s[a] * p[b] + s[b] * p[a];
    }
}

/* x rounded to 30 significant bits (ties away from zero), as ac_xf holds it */
static double round30(double x)
{
    int e;
    double f = frexp(x, &e);
    return ldexp(round(ldexp(f, 30)), e - 30);
}

/* the magnitudes of the terms that make up each centripetal entry: the core
 * forms s_a r_a - s.r in 30-bit arithmetic, so a channel whose axis is
 * perpendicular to its position (every tangential channel) cancels, and the
 * error is relative to these, not to the (small) result */
static void dcentripetal_terms(const ac_channel_cal *c, double row[6])
{
    double s[3], p[3], sr = 0.0;
    int a;
    for (a = 0; a < 3; a++) {
        s[a] = ldexp((double)c->sens[a], -AC_SENS_FRAC);
        p[a] = ldexp((double)c->pos[a], -AC_POS_FRAC);
        sr += fabs(s[a] * p[a]);
    }
    for (a = 0; a < 3; a++) {
        int b = (a + 1) % 3;
        row[a] = fabs(s[a] * p[a]) + sr;
        row[3 + a] = fabs(s[a] * p[b]) + fabs(s[b] * p[a]);
    }
}

/* M (6 x n) = pinv(R) in output LSB per count, via column-equilibrated R;
 * returns log2 of the condition number it saw, or 99 if singular. */
static double dresolve_matrix(const ac_channel_cal *cal, uint16_t n, double M[6][AC_MAX_CHANNELS])
{
    double R[AC_MAX_CHANNELS][6], a[6][6], a0[6][6], colmax[6] = {0, 0, 0, 0, 0, 0};
    int ce[6], i, j, l;
    for (i = 0; i < n; i++) {
        dsensor_row(&cal[i], R[i]);
        for (j = 0; j < 6; j++) {
            /* the core equilibrates by its 30-bit rounded entries: same powers of two */
            if (round30(fabs(R[i][j])) > colmax[j]) {
                colmax[j] = round30(fabs(R[i][j]));
            }
        }
    }
    for (j = 0; j < 6; j++) {
        if (colmax[j] == 0.0) {
            return 99.0;
        }
        (void)frexp(colmax[j], &ce[j]);
        for (i = 0; i < n; i++) {
            R[i][j] = ldexp(R[i][j], -ce[j]);
        }
    }
    for (j = 0; j < 6; j++) {
        for (l = 0; l < 6; l++) {
            double sum = 0.0;
            if (n == 6) {
                sum = R[j][l];
            } else {
                for (i = 0; i < n; i++) {
                    sum += R[i][j] * R[i][l];
                }
            }
            a[j][l] = sum;
            a0[j][l] = sum;
        }
    }
    if (!dinv6(a)) {
        return 99.0;
    }
    for (j = 0; j < 6; j++) {
        for (i = 0; i < n; i++) {
            double v = 0.0;
            if (n == 6) {
                v = a[j][i];
            } else {
                for (l = 0; l < 6; l++) {
                    v += a[j][l] * R[i][l];
                }
            }
            M[j][i] = ldexp(v, AC_OUT_FRAC - ce[j]);
        }
    }
    return log2(norm1_6(a0) * norm1_6(a));
}

/* ========================================================================= */
/* 3: ac_resolver_build                                                      */

static int32_t q_of(double v, int frac)
{
    double q = floor(ldexp(v, frac) + 0.5);
    if (q > 2147483647.0) {
        return INT32_MAX;
    }
    if (q < -2147483648.0) {
        return INT32_MIN;
    }
    return (int32_t)q;
}

/* structured geometries (unit axes and positions in m), perturbed by the input */
static uint16_t gen_geometry(rd *r, ac_channel_cal *cal, uint16_t cap)
{
    static const double tri[3][2] = {{1.0, 0.0}, {-0.5, 0.8660254037844386}, {-0.5, -0.8660254037844386}};
    static const double tet[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
    double ax[AC_MAX_CHANNELS][3], pos[AC_MAX_CHANNELS][3];
    uint8_t kind = rd_u8(r);
    uint8_t deg = rd_u8(r);
    uint16_t n = 6, i;
    int a;
    double radius = 0.001 * (1 + rd_u8(r)); /* 1..256 mm */
    int gexp = (int)(rd_u8(r) % 24u) - 6;   /* gain 2^gexp counts per m/s^2 */
    int pert = rd_u8(r) % 40u;              /* perturbation scale 2^-pert */
    memset(ax, 0, sizeof ax);
    memset(pos, 0, sizeof pos);
    switch (kind % 6u) {
    case 0: /* the seed's three dual-axis chips on a circle */
        for (i = 0; i < 3; i++) {
            pos[2 * i][0] = pos[2 * i + 1][0] = radius * tri[i][0];
            pos[2 * i][1] = pos[2 * i + 1][1] = radius * tri[i][1];
            ax[2 * i][0] = -tri[i][1];
            ax[2 * i][1] = tri[i][0];
            ax[2 * i + 1][2] = 1.0;
        }
        n = 6;
        break;
    case 1: /* two triads on the x axis: alpha_x unobservable (singular) */
        for (i = 0; i < 6; i++) {
            ax[i][i % 3] = 1.0;
            pos[i][0] = (i < 3) ? radius : 2.0 * radius;
        }
        n = 6;
        break;
    case 2: /* four triads on a tetrahedron: N = 12 */
        for (i = 0; i < 12; i++) {
            ax[i][i % 3] = 1.0;
            for (a = 0; a < 3; a++) {
                pos[i][a] = radius * tet[i / 3][a];
            }
        }
        n = 12;
        break;
    case 3: /* three triads on a triangle: N = 9 */
        for (i = 0; i < 9; i++) {
            ax[i][i % 3] = 1.0;
            pos[i][0] = radius * tri[i / 3][0];
            pos[i][1] = radius * tri[i / 3][1];
        }
        n = 9;
        break;
    case 4: /* a triad at the origin plus three tangential channels: N = 6 */
        for (i = 0; i < 3; i++) {
            ax[i][i] = 1.0;
            pos[3 + i][i] = radius;
            ax[3 + i][(i + 1) % 3] = 1.0;
        }
        n = 6;
        break;
    default: /* anything: directions and positions from the input */
        n = (uint16_t)(6u + rd_u8(r) % (AC_MAX_CHANNELS - 5u));
        for (i = 0; i < n; i++) {
            for (a = 0; a < 3; a++) {
                ax[i][a] = rd_i8(r) / 127.0;
                pos[i][a] = radius * rd_i8(r) / 127.0;
            }
        }
        break;
    }
    if (n > cap) {
        n = cap;
    }
    /* degenerations */
    if ((deg & 7u) == 1u && n > 1) { /* duplicate channel */
        memcpy(ax[1], ax[0], sizeof ax[0]);
        memcpy(pos[1], pos[0], sizeof pos[0]);
    } else if ((deg & 7u) == 2u) { /* all at one point: alpha unobservable */
        memset(pos, 0, sizeof pos);
    } else if ((deg & 7u) == 3u) { /* nothing senses z */
        for (i = 0; i < n; i++) {
            ax[i][2] = 0.0;
        }
    } else if ((deg & 7u) == 4u) { /* one channel nearly dead: ill-conditioned */
        for (a = 0; a < 3; a++) {
            ax[deg >> 5][a] = ldexp(ax[deg >> 5][a], -(int)((deg >> 3) & 3u) * 6);
        }
    } else if ((deg & 7u) == 5u) { /* huge lever arms */
        for (i = 0; i < n; i++) {
            for (a = 0; a < 3; a++) {
                pos[i][a] *= 1000.0;
            }
        }
    }
    for (i = 0; i < n; i++) {
        for (a = 0; a < 3; a++) {
            double p = ldexp((double)rd_i16(r) / 32768.0, -pert);
            double gain = ldexp(1.0, gexp) * (1.0 + ((deg & 8u) ? ldexp(rd_i8(r), -9) : 0.0));
            cal[i].sens[a] = q_of(gain * (ax[i][a] + p), AC_SENS_FRAC);
            cal[i].pos[a] = q_of(pos[i][a] + ldexp(p, -10), AC_POS_FRAC);
        }
        cal[i].offset = (deg & 16u) ? rd_i32_edge(r) : (int32_t)rd_i16(r) * 16;
    }
    return n;
}

static void check_build_ok(const ac_channel_cal *cal, uint16_t n, const ac_resolver *t,
                           const ac_build_info *info, rd *r)
{
    double M[6][AC_MAX_CHANNELS], cl2d;
    ac_status st;
    uint16_t i;
    uint8_t j, q;
    CHECK(ac_resolver_check(t) == AC_OK, "built table fails ac_resolver_check");
    CHECK(t->n == n, "built table n=%u, expected %u", t->n, n);
    CHECK(info->cond_log2 <= AC_COND_LOG2_MAX, "built with cond_log2 %d", info->cond_log2);
    for (j = 0; j < 6; j++) {
        for (i = n; i < AC_MAX_CHANNELS; i++) {
            CHECK(t->m[j][i] == 0, "m[%u][%u] beyond n not zeroed", j, i);
        }
    }
    cl2d = dresolve_matrix(cal, n, M);
    if (cl2d < 30.0) {
        CHECK(fabs(cl2d - info->cond_log2) <= 2.0, "cond_log2 %d, double reference %.3f",
              info->cond_log2, cl2d);
        /* entries within 1 LSB of the row's scale plus the inversion's error */
        for (j = 0; j < 6; j++) {
            double rowmax = 0.0, ksum = 0.0, kd = 0.0;
            double rel = ldexp(1.0, (int)info->cond_log2 - 20);
            double Cd[AC_MAX_CHANNELS][6], G[6] = {0, 0, 0, 0, 0, 0}, Gsum[6] = {0, 0, 0, 0, 0, 0};
            double osum = 0.0, Csum[6] = {0, 0, 0, 0, 0, 0};
            for (i = 0; i < n; i++) {
                if (fabs(M[j][i]) > rowmax) {
                    rowmax = fabs(M[j][i]);
                }
            }
            /* error of M_ji: up to rel * rowmax for every i, so (M o)_j and (M C)_jq
             * carry rel * (rowmax sum_i |o_i| + sum_i |M_ji o_i|) (likewise for C) */
            for (i = 0; i < n; i++) {
                double o = ldexp((double)cal[i].offset, -AC_OFFSET_FRAC);
                kd += M[j][i] * o;
                ksum += fabs(M[j][i] * o);
                osum += fabs(o);
                double Ct[6];
                dcentripetal_row(&cal[i], Cd[i]);
                dcentripetal_terms(&cal[i], Ct);
                for (q = 0; q < 6; q++) {
                    G[q] += M[j][i] * Cd[i][q];
                    Gsum[q] += fabs(M[j][i]) * Ct[q];
                    Csum[q] += Ct[q];
                }
            }
            ksum += rowmax * osum;
            for (q = 0; q < 6; q++) {
                Gsum[q] += rowmax * Csum[q];
            }
            for (i = 0; i < n; i++) {
                double got = ldexp((double)t->m[j][i], -t->m_shift[j]);
                double tol = ldexp(1.0, -t->m_shift[j]) + rel * rowmax;
                CHECK(fabs(got - M[j][i]) <= tol,
                      "m[%u][%u]=%d (2^-%d): %.9g, double reference %.9g, tol %.3g (cond 2^%d)", j,
                      i, t->m[j][i], t->m_shift[j], got, M[j][i], tol, info->cond_log2);
            }
            {
                double got = ldexp((double)t->k[j], -t->m_shift[j]);
                double tol = ldexp(1.0, -t->m_shift[j]) + rel * ksum;
                CHECK(fabs(got - kd) <= tol, "k[%u]=%ld: %.9g, double reference %.9g, tol %.3g", j,
                      (long)t->k[j], got, kd, tol);
            }
            {
                double gmax = 0.0;
                for (q = 0; q < 6; q++) {
                    if (fabs(G[q]) > gmax) {
                        gmax = fabs(G[q]);
                    }
                }
                for (q = 0; q < 6; q++) {
                    double got = ldexp((double)t->g[j][q], -t->g_shift[j]);
                    double tol = ldexp(1.0, -t->g_shift[j]) + rel * (Gsum[q] + gmax);
                    CHECK(fabs(got - G[q]) <= tol, "g[%u][%u]=%d: %.9g, double reference %.9g, tol %.3g",
                          j, q, t->g[j][q], got, G[q], tol);
                }
            }
        }
    }
    /* and the table works */
    {
        int16_t *x = xmalloc(n * sizeof *x), om[3];
        int32_t out[6];
        uint8_t mode = rd_u8(r);
        for (i = 0; i < n; i++) {
            x[i] = (int16_t)(rd_i8(r) * 64);
        }
        for (i = 0; i < 3; i++) {
            om[i] = (int16_t)(rd_i8(r) * ((mode & 2u) ? 128 : 4));
        }
        st = ac_resolve(t, x, (mode & 1u) ? om : NULL, out);
        check_resolve(t, x, (mode & 1u) ? om : NULL, out, st, "resolve on a built table");
        free(x);
    }
}

static void target_build(rd *r)
{
    uint8_t mode = rd_u8(r);
    uint16_t n, cap = AC_MAX_CHANNELS, alloc, i;
    ac_channel_cal *cal;
    ac_build_work *w = xmalloc(sizeof *w);
    ac_resolver *t = xmalloc(sizeof *t), *t0 = xmalloc(sizeof *t0);
    ac_build_info info;
    ac_status st;

    if ((mode & 3u) == 0u) { /* raw random parameters */
        n = (uint16_t)(6u + rd_u8(r) % (AC_MAX_CHANNELS - 5u));
        cal = xmalloc(n * sizeof *cal);
        for (i = 0; i < n; i++) {
            int a;
            for (a = 0; a < 3; a++) {
                cal[i].sens[a] = (mode & 4u) ? rd_i32_edge(r) : (int32_t)rd_i16(r) * 4096;
                cal[i].pos[a] = (mode & 8u) ? rd_i32_edge(r) : (int32_t)rd_i16(r) * 4;
            }
            cal[i].offset = rd_i32_edge(r);
        }
        alloc = n;
    } else {
        cal = xmalloc(cap * sizeof *cal);
        n = gen_geometry(r, cal, cap);
        alloc = cap;
    }
    if ((mode & 0x30u) == 0x30u) { /* n out of range: the core must not read cal[] */
        static const uint16_t bad[6] = {0u, 1u, 5u, AC_MAX_CHANNELS + 1u, 1000u, 65535u};
        n = bad[(mode >> 6) % 6u];
        if (n < alloc) {
            alloc = n;
        }
        if (n < 6u) {
            ac_channel_cal *c2 = xmalloc((n ? n : 1u) * sizeof *c2);
            memcpy(c2, cal, (n ? n : 1u) * sizeof *c2);
            free(cal);
            cal = c2;
        }
    }
    (void)alloc;
    fill_sentinel(t, sizeof *t);
    memcpy(t0, t, sizeof *t);
    info.cond_log2 = -32768;
    st = ac_resolver_build(cal, n, w, t, (mode & 0x40u) && (mode & 0x30u) != 0x30u ? NULL : &info);
    CHECK_STATUS(st);
    CHECK(st != AC_SATURATED, "ac_resolver_build returned AC_SATURATED");
    if (n < 6u || n > AC_MAX_CHANNELS) {
        CHECK(st == AC_ERR_SIZE, "ac_resolver_build n=%u gave %d", n, st);
    }
    if (st < 0) {
        CHECK(memcmp(t, t0, sizeof *t) == 0, "ac_resolver_build error %d but the table was written", st);
    } else if (!((mode & 0x40u) && (mode & 0x30u) != 0x30u)) {
        check_build_ok(cal, n, t, &info, r);
    } else {
        CHECK(ac_resolver_check(t) == AC_OK, "built table fails ac_resolver_check");
    }
    free(cal);
    free(w);
    free(t);
    free(t0);
}

/* ========================================================================= */
/* ac_xf helpers                                                             */

static int xf_normal(ac_xf x)
{
    int32_t m = x.m;
    if (m == 0) {
        return 1;
    }
    if (m < 0) {
        m = -m;
    }
    return m >= (1L << 29) && m < (1L << 30);
}

/* a normalised value; exponent within +-30000 unless wide */
static ac_xf rd_xf(rd *r, int wide)
{
    ac_xf x;
    uint32_t u = rd_u32(r);
    int16_t e = rd_i16(r);
    if ((u & 0xFu) == 0u) {
        x.m = 0;
        x.e = 0;
        return x;
    }
    x.m = (int32_t)((u >> 2) & 0x1FFFFFFFu) | (int32_t)0x20000000;
    if (u & 2u) {
        x.m = -x.m;
    }
    if (!wide) {
        e = (int16_t)(e % 30001);
    } else if (e == -32768) {
        e = 32767; /* -32768 is the core's invalid marker (AC_XF_BAD, ac_xf_core.h) */
    }
    x.e = e;
    return x;
}

/* anything at all (unnormalised); INT32_MIN mantissa only with FUZZ_RAW_XF_MIN */
static ac_xf rd_xf_raw(rd *r)
{
    ac_xf x;
    x.m = rd_i32_edge(r);
    x.e = rd_i16_edge(r);
#ifndef FUZZ_RAW_XF_MIN
    if (x.m == INT32_MIN) {
        x.m = INT32_MIN + 1;
    }
#endif
    return x;
}

/* |value(r) - exact| <= 1/2 ulp(r), exact = S * 2^se (S integer), ties away
 * from zero; r normalised.  Underflow (r == 0, exact != 0) only when the
 * exponent would be below -30000. */
static void check_xf_rounded(ac_xf res, i128 S, int se, const char *what)
{
    int k;
    i128 diff, half;
    CHECK(xf_normal(res), "%s: result m=%ld not normalised", what, (long)res.m);
    if (res.m == 0) {
        CHECK(S == 0 || se < -30000 + 40, "%s: zero result for nonzero exact %.17g*2^%d", what,
              (double)S, se);
        return;
    }
    k = res.e - se; /* value(res) = m 2^k in units of 2^se */
    if (k >= 0) {
        CHECK(k <= 90, "%s: exponent gap %d", what, k);
        diff = (i128)res.m * p2(k) - S;
        half = k > 0 ? p2(k - 1) : 0;
        CHECK(abs128(diff) <= half, "%s: m=%ld e=%d vs exact %.17g*2^%d", what, (long)res.m, res.e,
              (double)S, se);
        if (k > 0 && abs128(diff) == half) {
            CHECK(abs128((i128)res.m * p2(k)) > abs128(S), "%s: tie not away from zero", what);
        }
    } else {
        CHECK(-k <= 90, "%s: exponent gap %d", what, k);
        CHECK((i128)res.m == S * p2(-k), "%s: m=%ld e=%d vs exact %.17g*2^%d (must be exact)", what,
              (long)res.m, res.e, (double)S, se);
    }
}

/* ========================================================================= */
/* 5: ac_xf                                                                  */

static void target_xf(rd *r)
{
    uint8_t op = rd_u8(r);
    int wide = (op & 0x80u) != 0u;
    ac_xf a = rd_xf(r, wide), b = rd_xf(r, wide), res;
    int32_t v;
    int16_t k16;
    int8_t c;
    ac_status st;
    res.m = 0x55;
    res.e = 0x55;
    switch (op % 12u) {
    case 0: { /* from_fixed */
        v = rd_i32_edge(r);
        k16 = (int16_t)(rd_i16(r) % 200);
        if (op & 0x40u) {
            k16 = rd_i16(r);
        }
        st = ac_xf_from_fixed(v, k16, &res);
        CHECK_STATUS(st);
        if (st == AC_ERR_RANGE) {
            CHECK(k16 < -29000, "from_fixed(%ld, %d): AC_ERR_RANGE", (long)v, k16);
            break;
        }
        CHECK(st == AC_OK, "from_fixed gave %d", st);
        if (k16 > 29000) {
            CHECK(xf_normal(res), "from_fixed: not normalised");
            break;
        }
        /* |v| < 2^30 gives res.e <= -k16, where check_xf_rounded demands exactness */
        check_xf_rounded(res, v, -k16, "from_fixed");
        break;
    }
    case 1: { /* to_fixed */
        int32_t out = 12345;
        int kk;
        i128 e;
        int sat = 0;
        k16 = rd_i16(r);
        if (!(op & 0x40u)) {
            k16 = (int16_t)(k16 % 100);
        }
        st = ac_xf_to_fixed(a, k16, &out);
        CHECK_STATUS(st);
        CHECK(st >= 0, "to_fixed gave %d", st);
        kk = (int)a.e + k16;
        if (a.m == 0) {
            e = 0;
        } else if (kk >= 0) {
            if (kk > 60) {
                e = a.m > 0 ? (i128)INT32_MAX + 1 : (i128)INT32_MIN - 1;
            } else {
                e = (i128)a.m * p2(kk);
            }
        } else if (kk < -100) {
            e = 0;
        } else {
            e = round_half_up_p2(a.m, -kk);
        }
        if (!fits32(e)) {
            sat = 1;
        }
        CHECK(out == clip32(e) && (st == AC_SATURATED) == sat,
              "to_fixed(m=%ld e=%d, %d) = %ld st %d, expected %.17g", (long)a.m, a.e, k16, (long)out,
              st, (double)e);
        break;
    }
    case 2:
    case 3: { /* add, sub */
        ac_xf bb = b, hi, lo;
        int d;
        if (op % 12u == 3u) {
            bb.m = -b.m;
            st = ac_xf_sub(a, b, &res);
        } else {
            st = ac_xf_add(a, b, &res);
        }
        CHECK_STATUS(st);
        if (st == AC_ERR_RANGE) {
            CHECK((a.e > 29000 || bb.e > 29000), "add: AC_ERR_RANGE for small operands");
            break;
        }
        CHECK(st == AC_OK, "add gave %d", st);
        if (a.m == 0 || bb.m == 0) {
            ac_xf o = a.m == 0 ? bb : a;
            CHECK(res.m == o.m && (o.m == 0 || res.e == o.e), "add with zero");
            break;
        }
        hi = a.e >= bb.e ? a : bb;
        lo = a.e >= bb.e ? bb : a;
        d = hi.e - lo.e;
        if (d > 33) {
            CHECK(res.m == hi.m && res.e == hi.e, "add far apart should give the larger");
            break;
        }
        if (hi.e + 2 > 30000 || lo.e < -29000) {
            break; /* near the exponent limits: statuses checked above */
        }
        check_xf_rounded(res, (i128)hi.m * p2(d) + lo.m, lo.e, "add");
        break;
    }
    case 4: { /* mul */
        st = ac_xf_mul(a, b, &res);
        CHECK_STATUS(st);
        if (st == AC_ERR_RANGE) {
            CHECK(a.e + b.e > 29000, "mul: AC_ERR_RANGE for e=%d+%d", a.e, b.e);
            break;
        }
        CHECK(st == AC_OK, "mul gave %d", st);
        if ((int)a.e + b.e < -29000 || (int)a.e + b.e > 29000) {
            CHECK(xf_normal(res), "mul: not normalised");
            break;
        }
        check_xf_rounded(res, (i128)a.m * b.m, a.e + b.e, "mul");
        break;
    }
    case 5: { /* div */
        st = ac_xf_div(a, b, &res);
        CHECK_STATUS(st);
        if (b.m == 0) {
            CHECK(st == AC_ERR_SINGULAR, "div by zero gave %d", st);
            CHECK(res.m == 0x55 && res.e == 0x55, "div by zero wrote");
            break;
        }
        if (st == AC_ERR_RANGE) {
            CHECK(a.e - b.e > 29000, "div: AC_ERR_RANGE for e=%d-%d", a.e, b.e);
            break;
        }
        CHECK(st == AC_OK, "div gave %d", st);
        CHECK(xf_normal(res), "div: not normalised");
        if (a.m == 0) {
            CHECK(res.m == 0, "0 / b");
            break;
        }
        if ((int)a.e - b.e < -29000 || (int)a.e - b.e > 29000) {
            break;
        }
        {
            /* a/b = res within 1/2 ulp:  |res.m * b.m * 2^k - a.m| <= |b.m| 2^(k-1), k = res.e - a.e + b.e */
            int kk = res.e - a.e + b.e;
            i128 lhs, bm = abs128(b.m);
            CHECK(kk <= 0 && kk >= -40, "div: exponent %d", kk);
            lhs = (i128)res.m * b.m - (i128)a.m * p2(-kk);
            CHECK(2 * abs128(lhs) <= bm, "div: m=%ld e=%d for %ld*2^%d / %ld*2^%d", (long)res.m,
                  res.e, (long)a.m, a.e, (long)b.m, b.e);
            if (2 * abs128(lhs) == bm) {
                CHECK(abs128((i128)res.m * b.m) > abs128((i128)a.m * p2(-kk)), "div: tie not away");
            }
        }
        break;
    }
    case 6: /* neg, abs */
        st = ac_xf_neg(a, &res);
        CHECK(st == AC_OK && res.m == -a.m && res.e == a.e, "neg");
        st = ac_xf_abs(a, &res);
        CHECK(st == AC_OK && res.m == (a.m < 0 ? -a.m : a.m) && res.e == a.e, "abs");
        break;
    case 7: { /* cmpabs */
        int expect;
        st = ac_xf_cmpabs(a, b, &c);
        CHECK(st == AC_OK, "cmpabs gave %d", st);
        if (a.m == 0 || b.m == 0) {
            expect = (a.m != 0) - (b.m != 0);
        } else if (a.e != b.e) {
            expect = a.e > b.e ? 1 : -1;
        } else {
            int32_t ma = a.m < 0 ? -a.m : a.m, mb = b.m < 0 ? -b.m : b.m;
            expect = (ma > mb) - (ma < mb);
        }
        CHECK(c == expect, "cmpabs %d, expected %d", c, expect);
        break;
    }
    case 8: { /* ldexp */
        int32_t e;
        k16 = rd_i16(r);
        st = ac_xf_ldexp(a, k16, &res);
        CHECK_STATUS(st);
        e = (int32_t)a.e + k16;
        if (a.m == 0) {
            CHECK(st == AC_OK && res.m == 0, "ldexp of 0");
        } else if (e > 30000) {
            CHECK(st == AC_ERR_RANGE, "ldexp overflow gave %d", st);
        } else if (e < -30000) {
            CHECK(st == AC_OK && res.m == 0, "ldexp underflow");
        } else {
            CHECK(st == AC_OK && res.m == a.m && res.e == e, "ldexp");
        }
        break;
    }
    case 9: { /* raw (unnormalised) operands: no undefined behaviour, valid statuses */
        ac_xf ra = rd_xf_raw(r), rb = rd_xf_raw(r);
        int32_t o32;
        CHECK_STATUS(ac_xf_add(ra, rb, &res));
        CHECK_STATUS(ac_xf_sub(ra, rb, &res));
        CHECK_STATUS(ac_xf_mul(ra, rb, &res));
        CHECK_STATUS(ac_xf_div(ra, rb, &res));
        CHECK_STATUS(ac_xf_neg(ra, &res));
        CHECK_STATUS(ac_xf_abs(ra, &res));
        CHECK_STATUS(ac_xf_cmpabs(ra, rb, &c));
        CHECK_STATUS(ac_xf_ldexp(ra, rd_i16(r), &res));
        CHECK_STATUS(ac_xf_to_fixed(ra, rd_i16(r), &o32));
        break;
    }
    case 10: { /* chains stay normalised */
        int i;
        ac_xf acc = rd_xf(r, 0);
        for (i = 0; i < 8; i++) {
            ac_xf x = rd_xf(r, 0);
            uint8_t o = rd_u8(r) & 3u;
            st = o == 0 ? ac_xf_add(acc, x, &acc)
                        : o == 1 ? ac_xf_sub(acc, x, &acc)
                                 : o == 2 ? ac_xf_mul(acc, x, &acc) : ac_xf_div(acc, x, &acc);
            CHECK_STATUS(st);
            if (st < 0) {
                break;
            }
            CHECK(xf_normal(acc) && acc.e >= -30000 && acc.e <= 30000, "chain: m=%ld e=%d",
                  (long)acc.m, acc.e);
        }
        break;
    }
    default: { /* round trip fixed -> xf -> fixed */
        int32_t out = 0;
        k16 = (int16_t)(rd_i16(r) % 64);
        v = rd_i32_edge(r);
        st = ac_xf_from_fixed(v, k16, &res);
        CHECK(st == AC_OK, "from_fixed gave %d", st);
        st = ac_xf_to_fixed(res, k16, &out);
        if (v > -(1L << 30) && v < (1L << 30)) {
            CHECK(st == AC_OK && out == v, "round trip %ld -> %ld", (long)v, (long)out);
        } else {
            CHECK(st >= 0 && (i128)abs128((i128)out - v) <= 2, "round trip %ld -> %ld", (long)v, (long)out);
        }
        break;
    }
    }
}

/* ========================================================================= */
/* 4: ac_invert6                                                             */

static void target_invert(rd *r)
{
    uint8_t mode = rd_u8(r);
    ac_xf a[6][6];
    double ad[6][6], id[6][6];
    int8_t perm[6];
    int16_t cl2 = -32768;
    int i, j, raw = (mode & 7u) == 7u, cl2_res;
    ac_status st;
    for (i = 0; i < 6; i++) {
        for (j = 0; j < 6; j++) {
            int32_t v;
            int16_t frac;
            switch (mode & 7u) {
            case 0: /* identity plus noise */
                v = (i == j ? (1 << 20) : 0) + rd_i8(r) * ((mode & 8u) ? 4096 : 16);
                frac = 20;
                break;
            case 1: /* badly scaled rows */
                v = rd_i16(r);
                frac = (int16_t)(rd_u8(r) % 64u) - 32;
                frac = (int16_t)(frac + i * ((mode >> 4) % 8u));
                break;
            case 2: /* rank deficient: row 5 = row 0 + row 1 (exactly, before rounding) */
                v = rd_i16(r);
                frac = 8;
                if (i == 5) {
                    v = (int32_t)(ad[0][j] * 256.0 + ad[1][j] * 256.0);
                }
                break;
            case 3: /* nearly singular */
                v = rd_i16(r) * 64;
                frac = 6;
                if (i == 5) {
                    v = (int32_t)(ad[0][j] * 64.0) + rd_i8(r) % 3;
                }
                break;
            default:
                v = rd_i32_edge(r);
                frac = (int16_t)(rd_u8(r) % 80u) - 40;
                break;
            }
            CHECK(ac_xf_from_fixed(v, frac, &a[i][j]) == AC_OK, "from_fixed");
            if (raw) {
                a[i][j] = rd_xf_raw(r);
            }
            ad[i][j] = a[i][j].m == 0 ? 0.0 : ldexp((double)a[i][j].m, a[i][j].e);
        }
    }
    st = ac_invert6(a, perm, (mode & 0x80u) ? NULL : &cl2);
    CHECK_STATUS(st);
    CHECK(st != AC_SATURATED, "ac_invert6 returned AC_SATURATED");
    if (raw || st < 0) {
        return;
    }
    for (i = 0; i < 6; i++) {
        CHECK(perm[i] >= i && perm[i] < 6, "perm[%d]=%d", i, perm[i]);
        for (j = 0; j < 6; j++) {
            CHECK(xf_normal(a[i][j]), "inverse entry not normalised");
            id[i][j] = a[i][j].m == 0 ? 0.0 : ldexp((double)a[i][j].m, a[i][j].e);
        }
    }
    /* X against the double inverse of the same A, normwise: Gauss-Jordan with partial
     * pivoting is forward stable, |X - A^-1| <~ n^2 kappa u max |A^-1| (u = 2^-29).
     * (Its right residual A X - I is not bounded by kappa u: with rows and columns
     * scaled 2^60 apart it reached 2^-11 at kappa 2^13, within kappa^2 u.) */
    {
        double ref[6][6], kappa, emax = 0.0, rmax = 0.0;
        for (i = 0; i < 6; i++) {
            for (j = 0; j < 6; j++) {
                ref[i][j] = ad[i][j];
            }
        }
        /* (singular in double: nothing to compare with) */
        kappa = dinv6(ref) ? norm1_6(ad) * norm1_6(ref) : INFINITY;
        for (i = 0; i < 6; i++) {
            for (j = 0; j < 6; j++) {
                double d = fabs(id[i][j] - ref[i][j]);
                emax = d > emax ? d : emax;
                rmax = fabs(ref[i][j]) > rmax ? fabs(ref[i][j]) : rmax;
            }
        }
        cl2_res = isfinite(kappa) && kappa > 0.0 ? (int)ceil(log2(kappa)) : 99;
        if (isfinite(kappa) && isfinite(rmax) && rmax > 0.0 && kappa < 0x1p40) {
            CHECK(emax <= 36.0 * kappa * ldexp(rmax, -29),
                  "|inv(A) - double| %.3g of max %.3g (kappa 2^%d, bound 36 kappa 2^-29)", emax, rmax,
                  cl2_res);
        }
    }
    if (!(mode & 0x80u)) {
        double c = norm1_6(ad) * norm1_6(id);
        CHECK(cl2 <= AC_COND_LOG2_MAX, "AC_OK with cond_log2 %d", cl2);
        if (isfinite(c) && c > 0.0) {
            CHECK(fabs(ceil(log2(c)) - cl2) <= 1.0, "cond_log2 %d, double %.4f", cl2, log2(c));
        }
    }
}

/* ========================================================================= */
/* 6: ac_fixed                                                               */

static void target_fixed(rd *r)
{
    uint8_t op = rd_u8(r);
    int32_t a = rd_i32_edge(r), b = rd_i32_edge(r), out = 0x5a5a5a5a;
    ac_status st;
    switch (op % 8u) {
    case 0: {
        int16_t o = 0x5a5a;
        i128 e = a > 32767 ? 32767 : (a < -32768 ? -32768 : a);
        st = ac_sat16(a, &o);
        CHECK(st == (e == a ? AC_OK : AC_SATURATED) && o == e, "sat16(%ld)=%d st %d", (long)a, o, st);
        break;
    }
    case 1: {
        i128 e = (i128)a + b;
        st = ac_add32_sat(a, b, &out);
        CHECK(st == (fits32(e) ? AC_OK : AC_SATURATED) && out == clip32(e), "add32_sat(%ld,%ld)=%ld",
              (long)a, (long)b, (long)out);
        break;
    }
    case 2: {
        uint8_t n = rd_u8(r);
        if (!(op & 8u)) {
            n &= 31u;
        }
        st = ac_asr32(a, n, &out);
        if (n > 31u) {
            CHECK(st == AC_ERR_RANGE && out == 0x5a5a5a5a, "asr32 n=%u gave %d", n, st);
        } else {
            CHECK(st == AC_OK && out == (int32_t)floor_div_p2(a, n), "asr32(%ld,%u)=%ld", (long)a, n,
                  (long)out);
        }
        break;
    }
    case 3: {
        int16_t sh = (op & 8u) ? rd_i16_edge(r) : (int16_t)((int)(rd_u8(r) % 80u) - 40);
        i128 e;
        int sat;
        if (sh > 0) {
            e = sh > 100 ? 0 : round_half_up_p2(a, sh);
        } else if (a == 0) {
            e = 0;
        } else if (sh < -80) {
            e = a > 0 ? (i128)INT32_MAX + 1 : (i128)INT32_MIN - 1;
        } else {
            e = (i128)a * p2(-sh);
        }
        sat = !fits32(e);
        st = ac_scale_round32(a, sh, &out);
        CHECK(st == (sat ? AC_SATURATED : AC_OK) && out == clip32(e), "scale_round32(%ld,%d)=%ld st %d",
              (long)a, sh, (long)out, st);
        break;
    }
    case 4: {
        ac_i64 p;
        i128 got, e = (i128)a * b;
        st = ac_mul32x32(a, b, &p);
        got = (i128)p.hi * p2(32) + p.lo;
        CHECK(st == AC_OK && got == e, "mul32x32(%ld,%ld)", (long)a, (long)b);
        break;
    }
    case 5: {
        uint8_t n = rd_u8(r);
        i128 e;
        if (!(op & 8u)) {
            n = (uint8_t)(n % 63u);
        }
        st = ac_mul32_shift(a, b, n, &out);
        if (n > 62u) {
            CHECK(st == AC_ERR_RANGE && out == 0x5a5a5a5a, "mul32_shift n=%u gave %d", n, st);
            break;
        }
        e = round_half_up_p2((i128)a * b, n);
        CHECK(st == (fits32(e) ? AC_OK : AC_SATURATED) && out == clip32(e),
              "mul32_shift(%ld,%ld,%u)=%ld st %d, expected %.17g", (long)a, (long)b, n, (long)out, st,
              (double)e);
        break;
    }
    case 6: {
        uint32_t u = (uint32_t)a;
        i128 e = u >= 0x80000000u ? (i128)u - p2(32) : (i128)u;
        st = ac_u32_to_i32(u, &out);
        CHECK(st == AC_OK && out == e, "u32_to_i32(%lu)", (unsigned long)u);
        break;
    }
    default: {
        uint8_t bl = 0xff;
        i128 m = abs128(a);
        unsigned e = 0;
        while (m != 0) {
            e++;
            m >>= 1;
        }
        st = ac_bitlen32(a, &bl);
        CHECK(st == AC_OK && bl == e, "bitlen32(%ld)=%u, expected %u", (long)a, bl, e);
        break;
    }
    }
}

/* ========================================================================= */
/* 7: ac_rate                                                                */

static void target_rate(rd *r)
{
    uint8_t mode = rd_u8(r);
    ac_rate st_, *rs = &st_;
    uint16_t dt_m = (mode & 1u) ? rd_u16(r) : (uint16_t)(32768u + (rd_u16(r) >> 1));
    uint8_t dt_shift = (mode & 2u) ? rd_u8(r) : (uint8_t)(16u + rd_u8(r) % 31u);
    uint16_t leak = (mode & 4u) ? rd_u16(r) : (uint16_t)(rd_u8(r) >> (mode >> 5));
    int steps = rd_u8(r) % 32, i, a;
    ac_status st;
    i128 w[3] = {0, 0, 0};
    if (mode & 8u) { /* garbage state: ac_rate_step must cope (no UB) */
        uint8_t *p = (uint8_t *)rs;
        size_t k;
        int16_t om[3];
        int32_t al[3] = {rd_i32(r), rd_i32(r), rd_i32(r)};
        for (k = 0; k < sizeof *rs; k++) {
            p[k] = rd_u8(r);
        }
        st = ac_rate_step(rs, al, om);
        CHECK_STATUS(st);
        if (rs->dt_m == 0u || rs->dt_shift < 16u || rs->dt_shift > 46u) {
            CHECK(st == AC_ERR_RANGE, "step on bad state gave %d", st);
        }
        return;
    }
    memset(rs, 0xA5, sizeof *rs);
    st = ac_rate_init(rs, dt_m, dt_shift, leak);
    CHECK_STATUS(st);
    if (dt_m == 0u || dt_shift < 16u || dt_shift > 46u) {
        CHECK(st == AC_ERR_RANGE, "ac_rate_init(%u,%u) gave %d", dt_m, dt_shift, st);
        CHECK(is_sentinel(rs, sizeof *rs), "ac_rate_init error but the state was written");
        return;
    }
    CHECK(st == AC_OK && rs->w[0] == 0 && rs->w[1] == 0 && rs->w[2] == 0, "ac_rate_init");
    for (i = 0; i < steps; i++) {
        int32_t al[3];
        int16_t om[3];
        int sat = 0;
        for (a = 0; a < 3; a++) {
            al[a] = (mode & 16u) ? rd_i32_edge(r) : (int32_t)rd_i16(r) * 64;
        }
        if (rd_u8(r) == 0xFFu) {
            CHECK(ac_rate_reset(rs) == AC_OK, "reset");
            w[0] = w[1] = w[2] = 0;
        }
        st = ac_rate_step(rs, al, om);
        CHECK(st == AC_OK || st == AC_SATURATED, "ac_rate_step gave %d", st);
        /* w - round(w leak 2^-16) + clip32(round(alpha dt_m 2^-(dt_shift-16))), clipped at each add */
        for (a = 0; a < 3; a++) {
            i128 dec = round_half_up_p2(w[a] * leak, 16);
            i128 inc = round_half_up_p2((i128)al[a] * dt_m, dt_shift - (AC_RATE_STATE_FRAC - AC_OUT_FRAC));
            i128 o;
            if (!fits32(inc)) {
                sat = 1;
                inc = clip32(inc);
            }
            w[a] = w[a] - dec;
            if (!fits32(w[a])) {
                sat = 1;
                w[a] = clip32(w[a]);
            }
            w[a] = w[a] + inc;
            if (!fits32(w[a])) {
                sat = 1;
                w[a] = clip32(w[a]);
            }
            o = round_half_up_p2(w[a], AC_RATE_STATE_FRAC - AC_OMEGA_FRAC);
            if (o > 32767 || o < -32768) {
                sat = 1;
                o = o > 0 ? 32767 : -32768;
            }
            CHECK(rs->w[a] == w[a] && om[a] == o,
                  "rate step %d axis %d: state %ld omega %d, expected %.17g %d", i, a, (long)rs->w[a],
                  om[a], (double)w[a], (int)o);
        }
        CHECK((st == AC_SATURATED) == (sat != 0), "rate step status %d, clipped %d", st, sat);
    }
}

/* ========================================================================= */
/* 8: NULL pointers                                                          */

static void target_null(rd *r)
{
    ac_resolver t;
    ac_channel_cal cal[6];
    ac_build_work w;
    ac_rate rs;
    ac_xf x = {0, 0}, a66[6][6], row[6];
    int8_t perm[6];
    int16_t x16[12] = {0};
    uint16_t u16[12] = {0};
    int32_t out[6];
    (void)r;
    memset(&t, 0, sizeof t);
    t.n = 6;
    memset(cal, 0, sizeof cal);
    memset(a66, 0, sizeof a66);
#define NUL(call) CHECK((call) == AC_ERR_NULL, "%s did not give AC_ERR_NULL", #call)
    NUL(ac_trim(NULL, u16, 6, x16));
    NUL(ac_trim(u16, NULL, 6, x16));
    NUL(ac_trim(u16, u16, 6, NULL));
    NUL(ac_trim_rails_s16(NULL, x16, 6, -2048, 2047, x16));
    NUL(ac_trim_rails_s16(x16, NULL, 6, -2048, 2047, x16));
    NUL(ac_trim_rails_s16(x16, x16, 6, -2048, 2047, NULL));
    NUL(ac_resolver_check(NULL));
    NUL(ac_resolve(NULL, x16, NULL, out));
    NUL(ac_resolve(&t, NULL, NULL, out));
    NUL(ac_resolve(&t, x16, NULL, NULL));
    NUL(ac_process(NULL, u16, u16, NULL, out));
    NUL(ac_process(&t, NULL, u16, NULL, out));
    NUL(ac_process(&t, u16, NULL, NULL, out));
    NUL(ac_process(&t, u16, u16, NULL, NULL));
    NUL(ac_process_batch(NULL, u16, u16, 1, NULL, out, NULL));
    NUL(ac_process_batch(&t, NULL, u16, 1, NULL, out, NULL));
    NUL(ac_process_batch(&t, u16, NULL, 1, NULL, out, NULL));
    NUL(ac_process_batch(&t, u16, u16, 1, NULL, NULL, NULL));
    NUL(ac_resolver_build(NULL, 6, &w, &t, NULL));
    NUL(ac_resolver_build(cal, 6, NULL, &t, NULL));
    NUL(ac_resolver_build(cal, 6, &w, NULL, NULL));
    NUL(ac_sensor_row(NULL, row));
    NUL(ac_sensor_row(cal, NULL));
    NUL(ac_centripetal_row(NULL, row));
    NUL(ac_centripetal_row(cal, NULL));
    NUL(ac_invert6(NULL, perm, NULL));
    NUL(ac_invert6(a66, NULL, NULL));
    NUL(ac_rate_init(NULL, 1, 20, 0));
    NUL(ac_rate_reset(NULL));
    NUL(ac_rate_step(NULL, out, x16));
    (void)ac_rate_init(&rs, 34953, 21, 0);
    NUL(ac_rate_step(&rs, NULL, x16));
    NUL(ac_rate_step(&rs, out, NULL));
    NUL(ac_sat16(0, NULL));
    NUL(ac_add32_sat(0, 0, NULL));
    NUL(ac_asr32(0, 0, NULL));
    NUL(ac_scale_round32(0, 0, NULL));
    NUL(ac_mul32x32(0, 0, NULL));
    NUL(ac_mul32_shift(0, 0, 0, NULL));
    NUL(ac_u32_to_i32(0, NULL));
    NUL(ac_bitlen32(0, NULL));
    NUL(ac_xf_from_fixed(0, 0, NULL));
    NUL(ac_xf_to_fixed(x, 0, NULL));
    NUL(ac_xf_add(x, x, NULL));
    NUL(ac_xf_sub(x, x, NULL));
    NUL(ac_xf_mul(x, x, NULL));
    NUL(ac_xf_div(x, x, NULL));
    NUL(ac_xf_neg(x, NULL));
    NUL(ac_xf_abs(x, NULL));
    NUL(ac_xf_cmpabs(x, x, NULL));
    NUL(ac_xf_ldexp(x, 0, NULL));
    {
        ac_rest_cfg rc = {100, 0u, UINT32_MAX, 100, 100, 3u, 2u};
        ac_rest rest;
        ac_triad tri;
        ac_att att;
        ac_att_out ao;
        ac_disp_cfg dc;
        ac_disp disp;
        ac_disp_out dout;
        uint32_t q;
        int16_t rot[3][3];
        uint8_t fl;
        int32_t f3[6] = {0, 0, 10042, 0, 0, 10042};
        memset(&tri, 0, sizeof tri);
        NUL(ac_isqrt32(4u, NULL));
        NUL(ac_udiv64(0u, 1u, 1u, NULL));
        NUL(ac_mul32x16_shift(1, 1u, 0u, NULL));
        NUL(ac_atan2(1, 1, NULL, &q));
        NUL(ac_rest_init(NULL, &rc));
        NUL(ac_rest_init(&rest, NULL));
        NUL(ac_rest_reset(NULL));
        CHECK(ac_rest_init(&rest, &rc) == AC_OK, "ac_rest_init");
        NUL(ac_rest_step(NULL, f3, NULL, &fl));
        NUL(ac_rest_step(&rest, NULL, NULL, &fl));
        NUL(ac_rest_step(&rest, f3, NULL, NULL));
        NUL(ac_rest_step_ref(&rest, NULL, NULL, f3, &fl));
        NUL(ac_rest_batch(NULL, f3, NULL, 1u, &fl));
        NUL(ac_rest_batch(&rest, NULL, NULL, 1u, &fl));
        NUL(ac_rest_batch(&rest, f3, NULL, 1u, NULL));
        NUL(ac_rest_rate_step(NULL, &rs, f3, f3, x16, &fl));
        NUL(ac_rest_rate_step(&rest, NULL, f3, f3, x16, &fl));
        NUL(ac_rest_rate_step(&rest, &rs, NULL, f3, x16, &fl));
        NUL(ac_rest_rate_step(&rest, &rs, f3, NULL, x16, &fl));
        NUL(ac_rest_rate_step(&rest, &rs, f3, f3, NULL, &fl));
        NUL(ac_triad_check(NULL));
        NUL(ac_triad_apply(NULL, u16, out));
        NUL(ac_triad_apply(&tri, NULL, out));
        NUL(ac_triad_apply(&tri, u16, NULL));
        NUL(ac_att_init(NULL, 1000, 2000, 41943u, 22u, 512u, 0, 0u));
        NUL(ac_att_reset(NULL));
        CHECK(ac_att_init(&att, 100L << 10, 300L << 10, 41943u, 22u, 512u, 0, 0u) == AC_OK, "ac_att_init");
        NUL(ac_att_step(NULL, f3, f3 + 3, &ao));
        NUL(ac_att_step(&att, NULL, f3 + 3, &ao));
        NUL(ac_att_step(&att, f3, NULL, &ao));
        NUL(ac_att_step(&att, f3, f3 + 3, NULL));
        NUL(ac_att_batch(NULL, f3, 1u, &ao));
        NUL(ac_att_batch(&att, NULL, 1u, &ao));
        NUL(ac_att_batch(&att, f3, 1u, NULL));
        dc.rest = rc;
        dc.dt_m = 41943u;
        dc.dt_shift = 22u;
        dc.axis = -1;
        NUL(ac_disp_init(NULL, &dc));
        NUL(ac_disp_init(&disp, NULL));
        NUL(ac_disp_reset(NULL));
        CHECK(ac_disp_init(&disp, &dc) == AC_OK, "ac_disp_init");
        NUL(ac_disp_step(NULL, f3, &dout));
        NUL(ac_disp_step(&disp, NULL, &dout));
        NUL(ac_disp_step(&disp, f3, NULL));
        NUL(ac_disp_finish(NULL, &dout));
        NUL(ac_disp_finish(&disp, NULL));
        NUL(ac_disp_batch(NULL, f3, 1u, &dout));
        NUL(ac_disp_batch(&disp, NULL, 1u, &dout));
        NUL(ac_disp_batch(&disp, f3, 1u, NULL));
        NUL(ac_tilt_frame(NULL, rot));
        NUL(ac_tilt_frame(f3, NULL));
    }
#undef NUL
}

/* ========================================================================= */
/* 9: sensor and centripetal rows                                            */

static void target_rows(rd *r)
{
    ac_channel_cal cal;
    ac_xf row[6], crow[6];
    double d[6], dc[6], smax = 0.0, pmax = 0.0;
    int a, wide = rd_u8(r) & 1;
    ac_status st1, st2;
    for (a = 0; a < 3; a++) {
        cal.sens[a] = wide ? rd_i32_edge(r) : (int32_t)rd_i16(r) * 256;
        cal.pos[a] = wide ? rd_i32_edge(r) : (int32_t)rd_i16(r) * 8;
        smax = fmax(smax, fabs(ldexp((double)cal.sens[a], -AC_SENS_FRAC)));
        pmax = fmax(pmax, fabs(ldexp((double)cal.pos[a], -AC_POS_FRAC)));
    }
    cal.offset = rd_i32(r);
    st1 = ac_sensor_row(&cal, row);
    st2 = ac_centripetal_row(&cal, crow);
    CHECK(st1 == AC_OK && st2 == AC_OK, "rows gave %d %d", st1, st2);
    dsensor_row(&cal, d);
    dcentripetal_row(&cal, dc);
    for (a = 0; a < 6; a++) {
        double v = row[a].m == 0 ? 0.0 : ldexp((double)row[a].m, row[a].e);
        double cv = crow[a].m == 0 ? 0.0 : ldexp((double)crow[a].m, crow[a].e);
        double scale = a < 3 ? smax : smax * pmax;
        CHECK(xf_normal(row[a]) && xf_normal(crow[a]), "row entry not normalised");
        CHECK(fabs(v - d[a]) <= ldexp(scale, -27), "sensor row[%d] %.12g vs %.12g", a, v, d[a]);
        CHECK(fabs(cv - dc[a]) <= ldexp(3.0 * smax * pmax, -27), "centripetal row[%d] %.12g vs %.12g",
              a, cv, dc[a]);
    }
}

/* ========================================================================= */
/* 10: ac_trig                                                               */

static void target_trig(rd *r)
{
    uint8_t op = rd_u8(r);
    ac_status st;
    switch (op % 4u) {
    case 0: {
        uint32_t v = (op & 4u) ? (uint32_t)rd_i32_edge(r) : rd_u32(r);
        uint16_t o = 0x5a5a;
        st = ac_isqrt32(v, &o);
        if (v > 4294901760UL) {
            CHECK(st == AC_SATURATED && o == 65535u, "isqrt32(%lu) = %u st %d", (unsigned long)v, o, st);
        } else {
            /* |o - sqrt(v)| <= 1/2  <=>  (2o - 1)^2 <= 4v <= (2o + 1)^2 */
            i128 four = (i128)4 * v, hi = (i128)(2 * (i128)o + 1) * (2 * (i128)o + 1);
            i128 lo = o == 0 ? 0 : (i128)(2 * (i128)o - 1) * (2 * (i128)o - 1);
            CHECK(st == AC_OK && lo <= four && four <= hi, "isqrt32(%lu) = %u st %d", (unsigned long)v, o, st);
        }
        break;
    }
    case 1: {
        uint32_t hi = rd_u32(r), lo = rd_u32(r), den = (op & 4u) ? (uint32_t)rd_i32_edge(r) : rd_u32(r), q = 0x5a5a5a5au;
        i128 num, e;
        if (op & 8u) {
            hi %= (den ? den : 1u); /* mostly in range */
        }
        st = ac_udiv64(hi, lo, den, &q);
        if (den == 0u) {
            CHECK(st == AC_ERR_RANGE && q == 0x5a5a5a5au, "udiv64 by 0 gave %d", st);
            break;
        }
        num = (i128)hi * p2(32) + lo;
        e = (2 * num + den) / (2 * (i128)den); /* floor(num / den + 1/2) */
        if (e > UINT32_MAX) {
            CHECK(st == AC_SATURATED && q == UINT32_MAX, "udiv64 saturation: %lu st %d", (unsigned long)q, st);
        } else {
            CHECK(st == AC_OK && q == (uint32_t)e, "udiv64(%lu:%lu / %lu) = %lu, expected %.17g", (unsigned long)hi,
                  (unsigned long)lo, (unsigned long)den, (unsigned long)q, (double)e);
        }
        break;
    }
    case 2: {
        int32_t a = rd_i32_edge(r), out = 0x5a5a5a5a;
        uint16_t b = rd_u16(r);
        uint8_t n = rd_u8(r);
        i128 e;
        if (!(op & 4u)) {
            n = (uint8_t)(n % 48u);
        }
        st = ac_mul32x16_shift(a, b, n, &out);
        CHECK_STATUS(st);
        if (n > 47u) {
            CHECK(st == AC_ERR_RANGE && out == 0x5a5a5a5a, "mul32x16_shift n=%u gave %d", n, st);
            break;
        }
        e = round_half_up_p2((i128)a * b, n);
        CHECK(st == (fits32(e) ? AC_OK : AC_SATURATED) && out == clip32(e),
              "mul32x16_shift(%ld,%u,%u)=%ld st %d, expected %.17g", (long)a, b, n, (long)out, st, (double)e);
        break;
    }
    default: {
        int32_t y = rd_i32_edge(r), x = rd_i32_edge(r);
        int16_t ang = 0x5a5a;
        uint32_t mag = 0x5a5a5a5au;
        int shift = rd_u8(r) % 32;
        if (op & 4u) { /* small operands too */
            y = (int32_t)floor_div_p2(y, shift);
            x = (int32_t)floor_div_p2(x, shift);
        }
        st = ac_atan2(y, x, &ang, (op & 8u) ? NULL : &mag);
        CHECK(st == AC_OK, "atan2(%ld,%ld) gave %d", (long)y, (long)x, st);
        CHECK(ang >= -AC_PI_Q13 && ang <= AC_PI_Q13, "atan2 angle %d out of -pi..pi", ang);
        if (x == 0 && y == 0) {
            CHECK(ang == 0 && ((op & 8u) || mag == 0u), "atan2(0,0) = %d, mag %lu", ang, (unsigned long)mag);
            break;
        }
        {
            double ex = atan2((double)y, (double)x) * 8192.0, d = ang - ex;
            double h = hypot((double)x, (double)y);
            if (d > 25736.0) {
                d -= TWO_PI_Q13; /* +pi vs -pi at the cut */
            } else if (d < -25736.0) {
                d += TWO_PI_Q13;
            }
            CHECK(fabs(d) <= 0.76, "atan2(%ld,%ld) = %d LSB, exact %.4f (|err| %.3f > 0.76 LSB)", (long)y, (long)x,
                  ang, ex, fabs(d));
            if (y == 0 && x < 0) {
                CHECK(ang == AC_PI_Q13, "atan2(0, x<0) = %d, expected +pi", ang);
            }
            if (!(op & 8u)) {
                CHECK(fabs((double)mag - h) <= ldexp(h, -14) + 1.0, "atan2 mag %lu, hypot %.3f", (unsigned long)mag, h);
            }
        }
        break;
    }
    }
}

/* ========================================================================= */
/* 11: ac_rest (+ ac_rest_rate_step)                                          */

typedef struct rest_model {
    int64_t m[3];
    unsigned run;
    int started, at_rest;
} rest_model;

/* the documented detector, exactly (ac_rest.h) */
static uint8_t rest_model_step(rest_model *md, const ac_rest_cfg *c, const int32_t *f, const int32_t *alpha,
                               const int32_t *ref)
{
    int64_t x[3], g2 = 0;
    int k, quiet = 1, clip = 0, was = md->at_rest;
    uint8_t out = 0;
    for (k = 0; k < 3; k++) {
        int32_t v = f[k] > 32767 ? 32767 : (f[k] < -32768 ? -32768 : f[k]);
        clip |= v != f[k];
        x[k] = (int64_t)v * 256;
        g2 += (int64_t)v * v;
    }
    if (!md->started) {
        for (k = 0; k < 3; k++) {
            md->m[k] = x[k];
        }
        md->started = 1;
    }
    for (k = 0; k < 3; k++) {
        int64_t d = x[k] - md->m[k];
        if ((d < 0 ? -d : d) > (int64_t)c->dev_max * 256) {
            quiet = 0;
        }
        md->m[k] += (int64_t)floor_div_p2(d, c->ema_shift);
    }
    if (g2 < c->g2_lo || g2 > c->g2_hi) {
        quiet = 0;
    }
    if (ref != NULL) {
        for (k = 0; k < 3; k++) {
            int64_t d = x[k] - ref[k];
            if ((d < 0 ? -d : d) > (int64_t)c->ref_max * 256) {
                quiet = 0;
            }
        }
    }
    if (alpha != NULL) {
        for (k = 0; k < 3; k++) {
            int64_t a = alpha[k];
            if ((a < 0 ? -a : a) > c->alpha_max) {
                quiet = 0;
            }
        }
    }
    if (quiet) {
        md->run = md->run < 65535u ? md->run + 1u : 65535u;
        out |= AC_REST_QUIET;
    } else {
        md->run = 0;
    }
    md->at_rest = md->run >= c->hold;
    if (md->at_rest) {
        out |= AC_REST_AT_REST;
        if (!was) {
            out |= AC_REST_ENTER;
        }
    } else if (was) {
        out |= AC_REST_LEAVE;
    }
    if (clip) {
        out |= AC_REST_CLIP;
    }
    return out;
}

static void target_rest(rd *r)
{
    uint8_t mode = rd_u8(r);
    ac_rest_cfg c;
    ac_rest st, st0;
    rest_model md;
    int steps = rd_u8(r) % 48, i, k, valid;
    int32_t g = (int32_t)(9.80665 * 1024.0);
    ac_status s;
    memset(&md, 0, sizeof md);
    if (mode & 1u) { /* anything */
        c.dev_max = rd_i32_edge(r);
        c.g2_lo = (uint32_t)rd_i32_edge(r);
        c.g2_hi = (uint32_t)rd_i32_edge(r);
        c.alpha_max = rd_i32_edge(r);
        c.ref_max = rd_i32_edge(r);
        c.hold = rd_u16(r);
        c.ema_shift = rd_u8(r);
    } else { /* plausible */
        c.dev_max = rd_u8(r) + 1;
        c.g2_lo = (uint32_t)((int64_t)(g - 300 - rd_u8(r)) * (g - 300));
        c.g2_hi = (uint32_t)((int64_t)(g + 300 + rd_u8(r)) * (g + 300));
        c.alpha_max = rd_u8(r) * 4;
        c.ref_max = rd_u8(r) * 8;
        c.hold = (uint16_t)(1u + rd_u8(r) % 8u);
        c.ema_shift = (uint8_t)(1u + rd_u8(r) % 12u);
    }
    valid = c.dev_max >= 0 && c.alpha_max >= 0 && c.ref_max >= 0 && c.hold >= 1u && c.hold <= 65534u &&
            c.ema_shift >= 1u && c.ema_shift <= 12u && c.g2_lo <= c.g2_hi;
    memset(&st, 0xA5, sizeof st);
    memcpy(&st0, &st, sizeof st);
    s = ac_rest_init(&st, &c);
    CHECK_STATUS(s);
    if (!valid) {
        CHECK(s == AC_ERR_RANGE, "ac_rest_init with a bad cfg gave %d", s);
        CHECK(memcmp(&st, &st0, sizeof st) == 0, "ac_rest_init wrote on error");
        return;
    }
    CHECK(s == AC_OK, "ac_rest_init gave %d", s);
    for (i = 0; i < steps; i++) {
        int32_t f[3], al[3], ref[3];
        uint8_t fl = 0xEE, e;
        int use_al = (rd_u8(r) & 1u) != 0u, use_ref = (mode & 2u) != 0u;
        for (k = 0; k < 3; k++) {
            f[k] = (mode & 4u) ? rd_i32_edge(r) : (k == 2 ? g : 0) + rd_i8(r) * ((mode & 8u) ? 64 : 1);
            al[k] = (mode & 16u) ? rd_i32_edge(r) : rd_i8(r) * 4;
            ref[k] = (mode & 32u) ? rd_i32_edge(r) : ((k == 2 ? g : 0) + rd_i8(r)) * 256;
        }
        e = rest_model_step(&md, &c, f, use_al ? al : NULL, use_ref ? ref : NULL);
        s = use_ref ? ac_rest_step_ref(&st, f, use_al ? al : NULL, ref, &fl)
                    : ac_rest_step(&st, f, use_al ? al : NULL, &fl);
        CHECK(s == AC_OK, "ac_rest_step gave %d", s);
        CHECK(fl == e, "rest step %d: flags 0x%02x, documented model 0x%02x", i, fl, e);
    }
    /* batch == steps; rate step with reset on rest */
    {
        ac_rest a, b;
        ac_rate ra;
        int n = rd_u8(r) % 8, use_al = (mode & 64u) != 0u;
        int32_t *f = xmalloc((size_t)(n ? n : 1) * 3 * sizeof *f), *al = xmalloc((size_t)(n ? n : 1) * 3 * sizeof *al);
        uint8_t *fl = xmalloc((size_t)(n ? n : 1)), one;
        int16_t om[3];
        for (k = 0; k < 3 * n; k++) {
            f[k] = (k % 3 == 2 ? g : 0) + rd_i8(r) * 4;
            al[k] = rd_i8(r) * 4;
        }
        CHECK(ac_rest_init(&a, &c) == AC_OK && ac_rest_init(&b, &c) == AC_OK, "init");
        s = ac_rest_batch(&a, f, use_al ? al : NULL, (uint32_t)n, fl);
        CHECK(s == AC_OK, "ac_rest_batch gave %d", s);
        for (k = 0; k < n; k++) {
            CHECK(ac_rest_step(&b, f + 3 * k, use_al ? al + 3 * k : NULL, &one) == AC_OK && one == fl[k],
                  "batch flags[%d] 0x%02x, step 0x%02x", k, fl[k], one);
        }
        CHECK(ac_rest_init(&a, &c) == AC_OK && ac_rate_init(&ra, 34953, 21, 0) == AC_OK, "init");
        for (k = 0; k < n; k++) {
            s = ac_rest_rate_step(&a, &ra, f + 3 * k, al + 3 * k, om, &one);
            CHECK(s == AC_OK || s == AC_SATURATED, "ac_rest_rate_step gave %d", s);
            if (one & AC_REST_AT_REST) {
                CHECK(om[0] == 0 && om[1] == 0 && om[2] == 0, "omega not 0 at rest");
            }
        }
        free(f);
        free(al);
        free(fl);
    }
}

/* ========================================================================= */
/* 12: ac_triad_*, ac_att_*                                                  */

static void target_attitude(rd *r)
{
    uint8_t mode = rd_u8(r);
    if (mode & 1u) { /* triad */
        ac_triad t;
        uint16_t raw[3];
        int32_t f[3];
        int j, i, ok = 1;
        ac_status s, c;
        for (j = 0; j < 3; j++) {
            int64_t l1 = 0;
            t.trim[j] = rd_u16(r);
            raw[j] = (mode & 2u) ? rd_u16(r) : (uint16_t)(t.trim[j] + (uint16_t)rd_i16(r) / 4u);
            if (j == 0) {
                t.raw_min = rd_u16(r);
                t.raw_max = rd_u16(r);
            }
            t.shift[j] = (mode & 4u) ? rd_i8(r) : (int8_t)((int)(rd_u8(r) % 63u) - 31);
            t.k[j] = rd_i32_edge(r);
            for (i = 0; i < 3; i++) {
                t.m[j][i] = rd_i16_edge(r);
                l1 += t.m[j][i] < 0 ? -(int64_t)t.m[j][i] : t.m[j][i];
            }
            if (!(mode & 8u) && l1 > 65535) {
                for (i = 0; i < 3; i++) {
                    t.m[j][i] = (int16_t)((int64_t)t.m[j][i] * 65535 / l1);
                }
                l1 = 65535;
            }
            ok &= l1 <= 65535 && t.shift[j] >= -31 && t.shift[j] <= 31;
        }
        c = ac_triad_check(&t);
        CHECK(c == (ok ? AC_OK : AC_ERR_FORMAT), "ac_triad_check %d, invariants %d", c, ok);
        memset(f, 0xA5, sizeof f);
        s = ac_triad_apply(&t, raw, f);
        CHECK_STATUS(s);
        if (s < 0) {
            CHECK(is_sentinel(f, sizeof f), "ac_triad_apply wrote on error %d", s);
            return;
        }
        CHECK(((s & AC_AT_RAIL) != 0) == at_rail(raw, 3u, t.raw_min, t.raw_max),
              "ac_triad_apply status %d, rails %u %u", s, t.raw_min, t.raw_max);
        if (ok) {
            int clipped = 0;
            for (j = 0; j < 3; j++) {
                i128 acc = -(i128)t.k[j], e;
                int32_t x[3];
                for (i = 0; i < 3; i++) {
                    int32_t d = (int32_t)raw[i] - (int32_t)t.trim[i];
                    x[i] = d > 32767 ? 32767 : (d < -32768 ? -32768 : d);
                    clipped |= x[i] != d;
                    acc += (i128)t.m[j][i] * x[i];
                }
                e = t.shift[j] > 0 ? round_half_up_p2(acc, t.shift[j]) : acc * p2(-t.shift[j]);
                if (fits32(acc) && fits32(e)) {
                    CHECK(f[j] == (int32_t)e, "triad f[%d]=%ld, exact %.17g", j, (long)f[j], (double)e);
                } else {
                    CHECK(s & AC_SATURATED, "triad: clipped without AC_SATURATED");
                }
            }
            if (clipped) {
                CHECK(s & AC_SATURATED, "triad: trim clipped without AC_SATURATED");
            }
        }
        return;
    }
    {
        ac_att st, st0, sb;
        ac_att_out out, ob[8];
        int32_t r1, r2, w2_gate;
        uint16_t dt_m, gain, leak;
        uint8_t dt_shift;
        int steps = rd_u8(r) % 40, i, k;
        int32_t fb[8 * 6];
        ac_status s;
        if (mode & 2u) {
            r1 = rd_i32_edge(r);
            r2 = rd_i32_edge(r);
            dt_m = rd_u16(r);
            dt_shift = rd_u8(r);
            w2_gate = rd_i32_edge(r);
        } else {
            r1 = (int32_t)rd_i16(r) * 16;
            r2 = (int32_t)rd_i16(r) * 16;
            dt_m = (uint16_t)(32768u + (rd_u16(r) >> 1));
            dt_shift = (uint8_t)(16u + rd_u8(r) % 31u);
            w2_gate = rd_u8(r) * 64;
        }
        gain = rd_u16(r);
        leak = rd_u16(r);
        memset(&st, 0xA5, sizeof st);
        memcpy(&st0, &st, sizeof st);
        s = ac_att_init(&st, r1, r2, dt_m, dt_shift, gain, w2_gate, leak);
        CHECK_STATUS(s);
        if (s < 0) {
            CHECK(memcmp(&st, &st0, sizeof st) == 0, "ac_att_init error %d but the state was written", s);
            if (r1 == r2 && r1 >= -(1L << 30) && r1 <= (1L << 30) && dt_m != 0u && dt_shift >= 16u &&
                dt_shift <= 46u && w2_gate >= 0) {
                CHECK(s == AC_ERR_SINGULAR, "r1 == r2 gave %d", s);
            }
            return;
        }
        CHECK(s == AC_OK && r1 != r2, "ac_att_init gave %d", s);
        memcpy(&sb, &st, sizeof st);
        for (i = 0; i < steps; i++) {
            int32_t f1[3], f2[3], c1[3], c2[3];
            double y, x;
            for (k = 0; k < 3; k++) {
                f1[k] = (mode & 4u) ? rd_i32_edge(r) : rd_i16(r);
                f2[k] = (mode & 4u) ? rd_i32_edge(r) : rd_i16(r);
                c1[k] = f1[k] > 32767 ? 32767 : (f1[k] < -32768 ? -32768 : f1[k]);
                c2[k] = f2[k] > 32767 ? 32767 : (f2[k] < -32768 ? -32768 : f2[k]);
                if (i < 8) {
                    fb[6 * i + k] = f1[k];
                    fb[6 * i + 3 + k] = f2[k];
                }
            }
            memset(&out, 0xA5, sizeof out);
            s = ac_att_step(&st, f1, f2, &out);
            CHECK(s == AC_OK || s == AC_SATURATED, "ac_att_step gave %d", s);
            CHECK((out.flags & ~0x3Fu) == 0u, "ac_att_step flags 0x%02x", out.flags);
            CHECK(out.theta >= -AC_PI_Q13 && out.theta <= AC_PI_Q13, "theta %d", out.theta);
            CHECK((s == AC_SATURATED) == ((out.flags & AC_ATT_SAT) != 0u), "status %d flags 0x%02x", s, out.flags);
            /* (only x and z are used; the header says "each component", the code clips
             * and flags x and z only: reported) */
            if (f1[0] != c1[0] || f1[2] != c1[2] || f2[0] != c2[0] || f2[2] != c2[2]) {
                CHECK(out.flags & AC_ATT_SAT, "clipped input without AC_ATT_SAT");
            }
            /* theta = atan2(y, x) within 1 LSB, y = c1 f2x - c2 f1x, x = c2 f1z - c1 f2z */
            y = (double)st.cfg.c1 * c2[0] - (double)st.cfg.c2 * c1[0];
            x = (double)st.cfg.c2 * c1[2] - (double)st.cfg.c1 * c2[2];
            if (x == 0.0 && y == 0.0) {
                CHECK(out.flags & AC_ATT_NO_GRAVITY, "x = y = 0 without AC_ATT_NO_GRAVITY");
            } else {
                double d = out.theta - atan2(y, x) * 8192.0;
                if (d > 25736.0) {
                    d -= TWO_PI_Q13;
                } else if (d < -25736.0) {
                    d += TWO_PI_Q13;
                }
                CHECK(fabs(d) <= AC_ATAN2_BOUND_LSB, "theta %d vs atan2 %.3f LSB", out.theta, atan2(y, x) * 8192.0);
            }
            /* dw = round((f2z - f1z) k_m 2^-k_shift), w2 with k_shift - 10 (clipped to int32) */
            {
                i128 pz = (i128)(c2[2] - c1[2]) * st.cfg.k_m, px = (i128)(c2[0] - c1[0]) * st.cfg.k_m;
                int ks = st.cfg.k_shift;
                i128 dw = ks >= 0 ? round_half_up_p2(pz, ks) : pz * p2(-ks);
                i128 w2 = ks - 10 >= 0 ? round_half_up_p2(px, ks - 10) : px * p2(10 - ks);
                CHECK(out.dw == clip32(dw), "dw %ld, exact %.17g", (long)out.dw, (double)dw);
                CHECK(out.w2 == clip32(w2), "w2 %ld, exact %.17g", (long)out.w2, (double)w2);
            }
        }
        /* batch == steps */
        {
            int n = steps < 8 ? steps : 8;
            ac_att sa;
            memcpy(&sa, &sb, sizeof sa);
            s = ac_att_batch(&sb, fb, (uint32_t)n, ob);
            CHECK(s == AC_OK || s == AC_SATURATED, "ac_att_batch gave %d", s);
            for (i = 0; i < n; i++) {
                CHECK(ac_att_step(&sa, fb + 6 * i, fb + 6 * i + 3, &out) >= 0, "step");
                CHECK(out.theta == ob[i].theta && out.w == ob[i].w && out.dw == ob[i].dw && out.w2 == ob[i].w2 &&
                          out.gmag == ob[i].gmag && out.flags == ob[i].flags,
                      "ac_att_batch sample %d differs from ac_att_step", i);
            }
        }
    }
}

/* ========================================================================= */
/* 13: ac_disp_*, ac_tilt_frame                                              */

static void target_displace(rd *r)
{
    uint8_t mode = rd_u8(r);
    if (mode & 1u) { /* tilt frame */
        int32_t g[3];
        int16_t rot[3][3];
        int k, a;
        ac_status s;
        double n2 = 0.0, gd[3], z[3], ex[3], ey[3], xa[3], ya[3], nrm, rho2;
        for (k = 0; k < 3; k++) {
            g[k] = (mode & 2u) ? rd_i32_edge(r) : (int32_t)rd_i16(r) * (1 << (rd_u8(r) % 16u));
            gd[k] = g[k];
            n2 += gd[k] * gd[k];
        }
        memset(rot, 0xA5, sizeof rot);
        s = ac_tilt_frame(g, rot);
        CHECK_STATUS(s);
        if (n2 == 0.0) {
            CHECK(s == AC_ERR_SINGULAR && is_sentinel(rot, sizeof rot), "tilt_frame(0) gave %d", s);
            return;
        }
        CHECK(s == AC_OK, "tilt_frame gave %d", s);
        nrm = sqrt(n2);
        for (k = 0; k < 3; k++) {
            z[k] = gd[k] / nrm;
        }
        rho2 = (gd[1] * gd[1] + gd[2] * gd[2]) / n2;
        if (fabs(rho2 - 0.25) < 1e-3) {
            return; /* the x/y decision is taken on g scaled to 15 bits: either is right here */
        }
        /* x = horizontal projection of body x (or y = that of body y), then the third axis */
        for (k = 0; k < 3; k++) {
            ex[k] = (k == 0) - z[0] * z[k];
            ey[k] = (k == 1) - z[1] * z[k];
        }
        if (rho2 >= 0.25) {
            nrm = sqrt(ex[0] * ex[0] + ex[1] * ex[1] + ex[2] * ex[2]);
            for (k = 0; k < 3; k++) {
                xa[k] = ex[k] / nrm;
            }
            ya[0] = z[1] * xa[2] - z[2] * xa[1];
            ya[1] = z[2] * xa[0] - z[0] * xa[2];
            ya[2] = z[0] * xa[1] - z[1] * xa[0];
        } else {
            nrm = sqrt(ey[0] * ey[0] + ey[1] * ey[1] + ey[2] * ey[2]);
            for (k = 0; k < 3; k++) {
                ya[k] = ey[k] / nrm;
            }
            xa[0] = ya[1] * z[2] - ya[2] * z[1];
            xa[1] = ya[2] * z[0] - ya[0] * z[2];
            xa[2] = ya[0] * z[1] - ya[1] * z[0];
        }
        for (a = 0; a < 3; a++) {
            const double *row = a == 0 ? xa : (a == 1 ? ya : z);
            for (k = 0; k < 3; k++) {
                CHECK(fabs(rot[a][k] - row[k] * 16384.0) <= 2.0,
                      "tilt_frame g=(%ld,%ld,%ld): rot[%d][%d]=%d, exact %.3f", (long)g[0], (long)g[1], (long)g[2], a,
                      k, rot[a][k], row[k] * 16384.0);
            }
        }
        return;
    }
    {
        ac_disp_cfg c;
        ac_disp st, st0, sb;
        ac_disp_out out, ob[8];
        int steps = rd_u8(r) % 64, i, k;
        int32_t fb[8 * 3];
        int32_t g = (int32_t)(9.80665 * 1024.0);
        ac_status s;
        if (mode & 2u) {
            c.rest.dev_max = rd_i32_edge(r);
            c.rest.g2_lo = (uint32_t)rd_i32_edge(r);
            c.rest.g2_hi = (uint32_t)rd_i32_edge(r);
            c.rest.alpha_max = rd_i32_edge(r);
            c.rest.ref_max = rd_i32_edge(r);
            c.rest.hold = rd_u16(r);
            c.rest.ema_shift = rd_u8(r);
            c.dt_m = rd_u16(r);
            c.dt_shift = rd_u8(r);
            c.axis = rd_i8(r);
        } else {
            c.rest.dev_max = 20 + rd_u8(r);
            c.rest.g2_lo = (uint32_t)((int64_t)(g - 400) * (g - 400));
            c.rest.g2_hi = (uint32_t)((int64_t)(g + 400) * (g + 400));
            c.rest.alpha_max = 1000;
            c.rest.ref_max = 50 + rd_u8(r);
            c.rest.hold = (uint16_t)(1u + rd_u8(r) % 6u);
            c.rest.ema_shift = (uint8_t)(1u + rd_u8(r) % 6u);
            c.dt_m = 41943u;
            c.dt_shift = 22u; /* 0.01 s */
            c.axis = (int8_t)((int)(rd_u8(r) % 4u) - 1);
        }
        memset(&st, 0xA5, sizeof st);
        memcpy(&st0, &st, sizeof st);
        s = ac_disp_init(&st, &c);
        CHECK_STATUS(s);
        if (s < 0) {
            CHECK(memcmp(&st, &st0, sizeof st) == 0, "ac_disp_init error %d but the state was written", s);
            return;
        }
        CHECK(s == AC_OK, "ac_disp_init gave %d", s);
        memcpy(&sb, &st, sizeof st);
        for (i = 0; i < steps; i++) {
            int32_t f[3];
            uint8_t kind = rd_u8(r);
            for (k = 0; k < 3; k++) {
                if (mode & 4u) {
                    f[k] = rd_i32_edge(r);
                } else if ((kind & 3u) == 0u) { /* rest-like: g along z plus a little */
                    f[k] = (k == 2 ? g : 0) + rd_i8(r) / 16;
                } else {
                    f[k] = (k == 2 ? g : 0) + rd_i8(r) * 16;
                }
                if (i < 8) {
                    fb[3 * i + k] = f[k];
                }
            }
            memset(&out, 0xA5, sizeof out);
            s = ac_disp_step(&st, f, &out);
            CHECK(s == AC_OK || s == AC_SATURATED, "ac_disp_step gave %d", s);
            CHECK((out.flags & ~0x03FFu) == 0u, "ac_disp_step flags 0x%04x", out.flags);
            CHECK((s == AC_SATURATED) == ((out.flags & AC_DISP_SAT) != 0u), "status %d flags 0x%04x", s, out.flags);
            if (out.flags & AC_DISP_NO_REF) {
                for (k = 0; k < 3; k++) {
                    CHECK(out.v[k] == 0 && out.p[k] == 0, "v, p not 0 before the first rest");
                }
            }
            if (c.axis >= 0) {
                for (k = 0; k < 3; k++) {
                    if (k != c.axis) {
                        CHECK(out.v[k] == 0 && out.p[k] == 0, "1-D mode: component %d not 0", k);
                    }
                }
            }
            if (out.flags & AC_DISP_REST) {
                for (k = 0; k < 3; k++) {
                    CHECK(out.v[k] == 0, "v not 0 at rest");
                }
            }
            if (!(out.flags & AC_DISP_SEG_END)) {
                for (k = 0; k < 3; k++) {
                    CHECK(out.zp[k] == 0, "zp set without AC_DISP_SEG_END");
                }
            }
        }
        memset(&out, 0xA5, sizeof out);
        s = ac_disp_finish(&st, &out);
        CHECK(s == AC_OK || s == AC_SATURATED, "ac_disp_finish gave %d", s);
        /* batch == steps */
        {
            int n = steps < 8 ? steps : 8;
            ac_disp sa;
            memcpy(&sa, &sb, sizeof sa);
            s = ac_disp_batch(&sb, fb, (uint32_t)n, ob);
            CHECK(s == AC_OK || s == AC_SATURATED, "ac_disp_batch gave %d", s);
            for (i = 0; i < n; i++) {
                CHECK(ac_disp_step(&sa, fb + 3 * i, &out) >= 0, "step");
                CHECK(memcmp(out.v, ob[i].v, sizeof out.v) == 0 && memcmp(out.p, ob[i].p, sizeof out.p) == 0 &&
                          memcmp(out.zp, ob[i].zp, sizeof out.zp) == 0 && out.nseg == ob[i].nseg &&
                          out.flags == ob[i].flags,
                      "ac_disp_batch sample %d differs from ac_disp_step", i);
            }
        }
    }
}

/* ========================================================================= */

#include "fuzz_terms.c"

/* ========================================================================= */

#include "fuzz_omega.c"

/* ========================================================================= */

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rd r;
    uint8_t sel;
    if (size == 0u) {
        return 0;
    }
    sel = data[0];
    r.p = data + 1;
    r.n = size - 1u;
    switch (sel % 16u) {
    case 0:
        target_trim(&r);
        break;
    case 1:
        target_resolve(&r);
        break;
    case 2:
        target_process(&r);
        break;
    case 3:
        target_build(&r);
        break;
    case 4:
        target_invert(&r);
        break;
    case 5:
        target_xf(&r);
        break;
    case 6:
        target_fixed(&r);
        break;
    case 7:
        target_rate(&r);
        break;
    case 8:
        target_null(&r);
        break;
    case 9:
        target_rows(&r);
        break;
    case 10:
        target_trig(&r);
        break;
    case 11:
        target_rest(&r);
        break;
    case 12:
        target_attitude(&r);
        break;
    case 13:
        target_displace(&r);
        break;
    case 14:
        target_terms(&r);
        break;
    default:
        target_omega(&r);
        break;
    }
    return 0;
}
