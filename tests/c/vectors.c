/*
 * accelcal -- deterministic test vectors: the bit-for-bit cross-check.
 *
 * Calls every public function of the core over pseudo-random inputs and
 * prints each result (status and outputs) as a line of hex.  The program
 * uses only the library and the platform layer in vectors.h (no libc, no
 * floating point), and every value is computed with explicitly sized
 * integers, so the output must be identical on any target: the host build
 * and the AVR build (16-bit int) are compared byte for byte by
 * tools/run_avr_tests.sh.  A 16-bit promotion bug or an implementation-
 * defined operation in the core shows up as a difference.
 *
 * Output: "BEGIN accelcal-vectors 1", the vector lines, then
 * "END accelcal-vectors <line count> <CRC-32 of the vector lines>" (hex).
 * Anything after the END line (cycle counts, stack use) is platform specific
 * and not compared.
 *
 * RAM: meant for a 2 KB part.  The big objects (resolver ~250 B, build work
 * ~560 B on AVR, calibration) are static and shared through a union where
 * their lives do not overlap.
 */
#include <accelcal/accelcal.h>

#include "vectors.h"

/* main's steps are kept out of line: inlined (gcc -O2 inlines a static function called once) their
 * locals all sat in main's frame, under every later step's; the -O2 H8/300H run has the 64 KB of
 * normal mode for code, data and stack */
#if defined(__GNUC__)
#define VEC_STEP __attribute__((noinline))
#else
#define VEC_STEP
#endif

/* ---- output ------------------------------------------------------------------ */

static uint32_t crc = 0xFFFFFFFFUL;
static uint32_t n_lines = 0UL;
static uint8_t framing = 0u; /* inside BEGIN..END: count and checksum */

static void out_c(char c)
{
    if (framing) {
        uint8_t k;
        crc ^= (uint32_t)(uint8_t)c;
        for (k = 0u; k < 8u; k++) {
            crc = (crc & 1UL) ? ((crc >> 1) ^ 0xEDB88320UL) : (crc >> 1);
        }
        if (c == '\n') {
            n_lines++;
        }
    }
    ac_test_putc(c);
}

/* s is a string in read-only memory (AC_STR) */
static void out_s(const char *s)
{
    char c;
    while ((c = (char)AC_ROM_U8(s)) != '\0') {
        out_c(c);
        s++;
    }
}
#define OUT_S(lit) out_s(AC_STR(lit))
#define TAG(lit) out_s(AC_STR(lit))

static void out_hex(uint32_t v, uint8_t digits)
{
    while (digits > 0u) {
        uint8_t d;
        digits--;
        d = (uint8_t)((v >> (uint8_t)(4u * digits)) & 0xFUL);
        out_c(d < 10u ? (char)('0' + d) : (char)('A' + (d - 10u)));
    }
}

static void out_dec(uint32_t v)
{
    static const uint32_t p10[10] AC_ROM = {1000000000UL, 100000000UL, 10000000UL, 1000000UL,
                                       100000UL,     10000UL,     1000UL,     100UL,
                                       10UL,         1UL};
    uint8_t i, started = 0u;
    for (i = 0u; i < 10u; i++) {
        char d = '0';
        uint32_t p = AC_ROM_U32(&p10[i]);
        while (v >= p) {
            v -= p;
            d++;
        }
        if (d != '0' || started || i == 9u) {
            out_c(d);
            started = 1u;
        }
    }
}

static void nl(void)
{
    out_c('\n');
}
static void st(ac_status s)
{
    out_c(' ');
    if ((int)s < 0) {
        out_c('-');
        out_c((char)('0' - (int)s));
    } else {
        out_c((char)('0' + (int)s));
    }
}
static void h32(int32_t v)
{
    out_c(' ');
    out_hex((uint32_t)v, 8u);
}
static void hu32(uint32_t v)
{
    out_c(' ');
    out_hex(v, 8u);
}
static void h16(int16_t v)
{
    out_c(' ');
    out_hex((uint32_t)(uint16_t)v, 4u);
}
static void hu16(uint16_t v)
{
    out_c(' ');
    out_hex((uint32_t)v, 4u);
}
static void h8(uint8_t v)
{
    out_c(' ');
    out_hex((uint32_t)v, 2u);
}
static void hxf(ac_xf x)
{
    h32(x.m);
    h16(x.e);
}

/* ---- pseudo-random inputs (xorshift32, unsigned 32-bit only) ------------------ */

static uint32_t rng = 2463534242UL;

static uint32_t rnd(void)
{
    uint32_t x = rng;
    x ^= (uint32_t)(x << 13);
    x ^= (uint32_t)(x >> 17);
    x ^= (uint32_t)(x << 5);
    rng = x;
    return x;
}

/* two's complement of a 32-bit pattern, without implementation-defined casts */
static int32_t s32(uint32_t u)
{
    if (u <= 0x7FFFFFFFUL) {
        return (int32_t)u;
    }
    return -(int32_t)(uint32_t)~u - 1;
}

/* uniform in [0, n) for n <= 2^16 (bias irrelevant here) */
static uint16_t below(uint16_t n)
{
    return (uint16_t)((uint32_t)(rnd() >> 16) % (uint32_t)n);
}

static int32_t rnd_range(int32_t lo, int32_t hi) /* hi - lo < 2^16 */
{
    return lo + (int32_t)below((uint16_t)(uint32_t)(hi - lo + 1));
}

/* int32 with a random bit length (small, medium, huge and the edges) */
static int32_t rnd_i32(void)
{
    uint32_t u = rnd();
    uint8_t kind = (uint8_t)(rnd() & 15UL);
    if (kind == 0u) {
        static const uint32_t edge[8] AC_ROM = {0UL,          1UL,          0xFFFFFFFFUL, 0x7FFFFFFFUL,
                                         0x80000000UL, 0x80000001UL, 0x00008000UL, 0xFFFF7FFFUL};
        return s32(AC_ROM_U32(&edge[u & 7UL]));
    }
    if (kind < 4u) {
        return s32(u);
    }
    u >>= (uint8_t)(rnd() & 31UL);
    return (rnd() & 1UL) ? -(int32_t)(u >> 1) : (int32_t)(u >> 1);
}

static int16_t rnd_i16(void)
{
    return (int16_t)((int32_t)(rnd() & 0xFFFFUL) - 32768L);
}

static ac_xf rnd_xf(int16_t emin, int16_t emax)
{
    ac_xf x;
    uint32_t u = rnd();
    x.m = (int32_t)(0x20000000UL | (u & 0x1FFFFFFFUL));
    if (rnd() & 1UL) {
        x.m = -x.m;
    }
    x.e = (int16_t)rnd_range(emin, emax);
    if ((rnd() & 31UL) == 0UL) {
        x.m = 0;
        x.e = 0;
    }
    return x;
}

/* ---- shared static memory ---------------------------------------------------------- */

#define BATCH 4u

static ac_resolver res;
static ac_channel_cal cal[AC_MAX_CHANNELS];
static union {
    ac_build_work work;
    ac_xf mat[6][6];
    struct {
        uint16_t raw[BATCH * AC_MAX_CHANNELS];
        int16_t omega[BATCH * 3u];
        int32_t out[BATCH * 6u];
        uint8_t flags[BATCH];
    } batch;
    struct { /* tests/c/vectors_terms.c */
        ac_temp_table temp;
        ac_skew_table skew;
        ac_nonlin_table nl;
        int16_t line[AC_MAX_CHANNELS * 8u];
    } terms;
} mem;

/* ---- fixed ----------------------------------------------------------------------- */

/* every rounding shift at its edges: the values around 0, +-2^(n-1) (the
 * rounding ties) and the int32 limits, for each shift 1..31 and a few left
 * shifts; AVR has its own assembly for these, the host plain C */
static VEC_STEP void vec_shift_edges(void)
{
    int16_t sh;
    for (sh = -3; sh <= 31; sh++) {
        uint32_t half = (sh > 0) ? (uint32_t)1u << (uint8_t)(sh - 1) : 1u;
        int32_t v[12];
        uint8_t k;
        v[0] = INT32_MIN;
        v[1] = INT32_MIN + 1;
        v[2] = -(int32_t)(half - 1u) - 2;
        v[3] = -(int32_t)(half - 1u) - 1; /* -half */
        v[4] = -(int32_t)(half - 1u);
        v[5] = -1;
        v[6] = 0;
        v[7] = 1;
        v[8] = (int32_t)(half - 1u);
        v[9] = (int32_t)half;
        v[10] = (int32_t)(half | (half << 1u)) & INT32_MAX;
        v[11] = INT32_MAX;
        for (k = 0u; k < 12u; k++) {
            int32_t o32 = 0;
            ac_status s = ac_scale_round32(v[k], sh, &o32);
            TAG("SCE");
            h32(v[k]);
            h16(sh);
            st(s);
            h32(o32);
            nl();
        }
    }
}

static VEC_STEP void vec_fixed(void)
{
    uint16_t i;
    for (i = 0u; i < 400u; i++) {
        int32_t a = rnd_i32(), b = rnd_i32(), o32 = 0;
        int16_t o16 = 0, sh;
        uint8_t n, o8 = 0u;
        ac_i64 p = {0, 0UL};
        ac_status s;

        s = ac_sat16(a, &o16);
        TAG("S16");
        h32(a);
        st(s);
        h16(o16);
        nl();

        s = ac_add32_sat(a, b, &o32);
        TAG("ADD");
        h32(a);
        h32(b);
        st(s);
        h32(o32);
        nl();

        n = (uint8_t)(rnd() & 31UL);
        if ((i & 63u) == 0u) {
            n = (uint8_t)(32u + (rnd() & 7UL)); /* out of range */
        }
        o32 = 0;
        s = ac_asr32(a, n, &o32);
        TAG("ASR");
        h32(a);
        h8(n);
        st(s);
        h32(o32);
        nl();

        sh = (int16_t)rnd_range(-40, 40);
        if ((i & 15u) == 0u) {
            sh = rnd_i16();
        }
        o32 = 0;
        s = ac_scale_round32(a, sh, &o32);
        TAG("SCL");
        h32(a);
        h16(sh);
        st(s);
        h32(o32);
        nl();

        s = ac_mul32x32(a, b, &p);
        TAG("M64");
        h32(a);
        h32(b);
        st(s);
        h32(p.hi);
        hu32(p.lo);
        nl();

        n = (uint8_t)below(63u);
        if ((i & 63u) == 1u) {
            n = (uint8_t)(63u + (rnd() & 3UL));
        }
        o32 = 0;
        s = ac_mul32_shift(a, b, n, &o32);
        TAG("MSH");
        h32(a);
        h32(b);
        h8(n);
        st(s);
        h32(o32);
        nl();

        s = ac_bitlen32(a, &o8);
        TAG("BL");
        h32(a);
        st(s);
        h8(o8);
        nl();

        {
            uint32_t u = rnd();
            o32 = 0;
            s = ac_u32_to_i32(u, &o32);
            TAG("U2I");
            hu32(u);
            st(s);
            h32(o32);
            nl();
        }
    }
    TAG("NUL");
    st(ac_sat16(1, 0));
    st(ac_add32_sat(1, 1, 0));
    st(ac_asr32(1, 1u, 0));
    st(ac_scale_round32(1, 1, 0));
    st(ac_mul32x32(1, 1, 0));
    st(ac_mul32_shift(1, 1, 1u, 0));
    st(ac_bitlen32(1, 0));
    st(ac_u32_to_i32(1UL, 0));
    nl();
}

/* ---- xf ------------------------------------------------------------------------------ */

static VEC_STEP void vec_xf(void)
{
    uint16_t i;
    for (i = 0u; i < 300u; i++) {
        ac_xf a, b, r;
        int32_t v = rnd_i32(), o32 = 0;
        int16_t frac = (int16_t)rnd_range(-80, 80);
        int8_t c = 0;
        ac_status s;

        r.m = 0;
        r.e = 0;
        s = ac_xf_from_fixed(v, frac, &r);
        TAG("XFF");
        h32(v);
        h16(frac);
        st(s);
        hxf(r);
        nl();

        a = rnd_xf(-70, 20);
        frac = (int16_t)rnd_range(-20, 70);
        s = ac_xf_to_fixed(a, frac, &o32);
        TAG("XFT");
        hxf(a);
        h16(frac);
        st(s);
        h32(o32);
        nl();

        a = rnd_xf(-60, 60);
        if ((i & 3u) == 0u) {
            b = a; /* near cancellation */
            b.m = -b.m + rnd_range(-100, 100);
            if (a.m == 0 || (b.m > -0x20000000L && b.m < 0x20000000L) || b.m >= 0x40000000L ||
                b.m <= -0x40000000L) {
                b.m = -a.m; /* keep b normalised */
            }
        } else {
            b = rnd_xf((int16_t)(a.e - 40), (int16_t)(a.e + 40));
        }
        TAG("XAB");
        hxf(a);
        hxf(b);
        nl();
        s = ac_xf_add(a, b, &r);
        TAG(" +");
        st(s);
        hxf(r);
        s = ac_xf_sub(a, b, &r);
        TAG(" -");
        st(s);
        hxf(r);
        nl();
        s = ac_xf_mul(a, b, &r);
        TAG(" *");
        st(s);
        hxf(r);
        r.m = 0;
        r.e = 0;
        s = ac_xf_div(a, b, &r);
        TAG(" /");
        st(s);
        hxf(r);
        nl();
        s = ac_xf_neg(a, &r);
        TAG(" n");
        st(s);
        hxf(r);
        s = ac_xf_abs(b, &r);
        TAG(" a");
        st(s);
        hxf(r);
        s = ac_xf_cmpabs(a, b, &c);
        TAG(" c");
        st(s);
        h8((uint8_t)c);
        nl();
        frac = (int16_t)rnd_range(-200, 200);
        s = ac_xf_ldexp(a, frac, &r);
        TAG(" l");
        h16(frac);
        st(s);
        hxf(r);
        nl();
    }
}

/* ---- trim ------------------------------------------------------------------------------ */

static VEC_STEP void vec_trim(void)
{
    uint16_t i, k;
    uint16_t raw[AC_MAX_CHANNELS + 2u], trim[AC_MAX_CHANNELS + 2u];
    int16_t x[AC_MAX_CHANNELS + 2u];
    for (i = 0u; i < 60u; i++) {
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS + 2u));
        ac_status s;
        for (k = 0u; k < n; k++) {
            uint32_t u = rnd();
            if (i & 1u) {
                raw[k] = (uint16_t)(u & 0xFFFFUL);
                trim[k] = (uint16_t)(u >> 16);
            } else {
                trim[k] = (uint16_t)(3000u + (uint16_t)((u >> 16) & 0xFFFUL));
                raw[k] = (uint16_t)(trim[k] + (uint16_t)(u & 0x1FFFUL) - 0x1000u);
            }
            x[k] = 0;
        }
        s = ac_trim(raw, trim, n, x);
        TAG("TRM");
        h8((uint8_t)n);
        st(s);
        for (k = 0u; k < n; k++) {
            h16(x[k]);
        }
        nl();
    }
    TAG("TRM0");
    st(ac_trim(raw, trim, 0u, x));
    st(ac_trim(0, trim, 1u, x));
    nl();
    /* signed readings (ac_trim_s16): random int16 pairs, near pairs, the extremes */
    for (i = 0u; i < 60u; i++) {
        int16_t sraw[AC_MAX_CHANNELS], strim[AC_MAX_CHANNELS];
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS));
        ac_status s;
        for (k = 0u; k < n; k++) {
            uint32_t u = rnd();
            if (i < 4u) {
                sraw[k] = (int16_t)((k + i) & 1u ? 32767 : -32767 - 1);
                strim[k] = (int16_t)((k + i) & 2u ? 32767 : -32767 - 1);
            } else if (i & 1u) {
                sraw[k] = (int16_t)(int32_t)((u & 0xFFFFUL) - 32768L);
                strim[k] = (int16_t)(int32_t)((long)(u >> 16) - 32768L);
            } else {
                strim[k] = (int16_t)(int32_t)((long)((u >> 16) & 0xFFFUL) - 2048L);
                sraw[k] = (int16_t)(strim[k] + (int16_t)(int32_t)((long)(u & 0x1FFFUL) - 0x1000L));
            }
            x[k] = 0;
        }
        s = ac_trim_s16(sraw, strim, n, x);
        TAG("TRS");
        h8((uint8_t)n);
        st(s);
        for (k = 0u; k < n; k++) {
            h16(x[k]);
        }
        nl();
    }
}

/* ---- one triad (f only) ----------------------------------------------------------- */

/* ac_triad_build from random channel parameters: gains 50..4000 counts per m/s^2 with
 * cross-axis terms up to 1/8, some nearly singular, and the table it makes */
/* about uniform in [-lim, lim] (lim >= 1): a power-of-two mask, no division */
static int32_t rnd_pm(int32_t lim)
{
    uint32_t mask = 1u;
    while (mask < (uint32_t)lim) {
        mask = (mask << 1) | 1u;
    }
    return (int32_t)(rnd() & mask) - (int32_t)(mask >> 1);
}

static VEC_STEP void vec_triad_build(void)
{
    uint16_t i, j, q;
    ac_build_work work;
    for (i = 0u; i < 40u; i++) {
        ac_channel_cal ch[3];
        uint16_t trim[3];
        ac_triad t;
        ac_status s;
        int32_t k = rnd_range(50L, 4000L) * 65536L;
        for (j = 0u; j < 3u; j++) {
            for (q = 0u; q < 3u; q++) {
                ch[j].sens[q] = (j == q) ? k + rnd_pm(k >> 4) : rnd_pm(k >> 3);
                ch[j].pos[q] = 0;
            }
            ch[j].offset = rnd_range(-128L, 127L);
            trim[j] = (uint16_t)rnd();
        }
        if ((i & 7u) == 7u) {           /* two axes nearly parallel */
            for (q = 0u; q < 3u; q++) {
                ch[1].sens[q] = ch[0].sens[q] + (int32_t)(q == 2u);
            }
        }
        s = ac_triad_build(ch, trim, &work, &t);
        TAG("TBU");
        st(s);
        if (s == AC_OK) {
            for (j = 0u; j < 3u; j++) {
                hu16(t.trim[j]);
                h8((uint8_t)t.shift[j]);
                h32(t.k[j]);
                for (q = 0u; q < 3u; q++) {
                    h16(t.m[j][q]);
                }
            }
        }
        nl();
    }
}

static VEC_STEP void vec_triad(void)
{
    uint16_t i, j, q;
    for (i = 0u; i < 40u; i++) {
        ac_triad t;
        int16_t x[3];
        int32_t f[3];
        for (j = 0u; j < 3u; j++) {
            uint32_t budget = 65535u;
            t.trim[j] = (uint16_t)rnd();
            t.shift[j] = (int8_t)((int16_t)below(40u) - 8);
            t.k[j] = (int32_t)rnd();
            if (i & 1u) {
                t.k[j] = (int32_t)((long)(t.k[j] & 0xFFFFFL) - 0x80000L);
            }
            for (q = 0u; q < 3u; q++) {
                uint32_t v = below((uint16_t)(budget < 32768u ? budget + 1u : 32768u));
                budget -= v;
                t.m[j][q] = (int16_t)((rnd() & 1u) ? -(int32_t)(v > 32767u ? 32767u : v) : (int32_t)(v > 32767u ? 32767u : v));
            }
            x[j] = (int16_t)(int32_t)((long)(rnd() & 0xFFFFUL) - 32768L);
        }
        TAG("TRI");
        st(ac_triad_check(&t));
        st(ac_triad_resolve(&t, x, f));
        for (j = 0u; j < 3u; j++) {
            h32(f[j]);
        }
        nl();
    }
}

/* ---- resolve ---------------------------------------------------------------------- */

/* A random table that keeps the invariants (rows of |m| and |g| summing to
 * at most 65535), sometimes with large offsets and shifts that clip. */
static void random_table(void)
{
    uint8_t j, q;
    uint16_t i;
    res.n = (uint16_t)(6u + below(AC_MAX_CHANNELS - 5u));
    for (j = 0u; j < 6u; j++) {
        int32_t budget = (int32_t)below(65535u);
        res.m_shift[j] = (int8_t)rnd_range(-4, 26);
        res.g_shift[j] = (int8_t)rnd_range(-8, 31);
        for (i = 0u; i < AC_MAX_CHANNELS; i++) {
            int32_t lim = budget < 32767L ? budget : 32767L;
            int32_t v = 0;
            if (i < res.n && lim > 0) {
                v = rnd_range(-(lim < 32767L ? lim : 32767L), lim < 32767L ? lim : 32767L);
                if ((rnd() & 3UL) == 0UL) {
                    v = v / 64;
                }
            }
            res.m[j][i] = (int16_t)v;
            budget -= v < 0 ? -v : v;
        }
        res.k[j] = (rnd() & 1UL) ? s32(rnd()) / 4 : (int32_t)rnd_range(-30000, 30000);
        budget = (int32_t)below(65535u);
        for (q = 0u; q < 6u; q++) {
            int32_t lim = budget < 32767L ? budget : 32767L;
            int32_t v = lim > 0 ? rnd_range(-lim, lim) : 0;
            res.g[j][q] = (int16_t)v;
            budget -= v < 0 ? -v : v;
        }
    }
}

static void random_omega(int16_t w[3])
{
    uint8_t a, kind = (uint8_t)(rnd() & 3UL);
    for (a = 0u; a < 3u; a++) {
        w[a] = kind == 0u ? (int16_t)rnd_range(-127, 127)
                          : (kind == 1u ? (int16_t)rnd_range(-8000, 8000) : rnd_i16());
    }
}

static void print_out6(const int32_t *out)
{
    uint8_t j;
    for (j = 0u; j < 6u; j++) {
        h32(out[j]);
    }
}

static VEC_STEP void vec_resolve(void)
{
    uint16_t t, i, k;
    int16_t x[AC_MAX_CHANNELS], w[3];
    uint16_t trim[AC_MAX_CHANNELS];
    int32_t out[6];
    for (t = 0u; t < 60u; t++) {
        ac_status s;
        random_table();
        s = ac_resolver_check(&res);
        TAG("TBL");
        h8((uint8_t)res.n);
        st(s);
        nl();
        for (k = 0u; k < 4u; k++) {
            for (i = 0u; i < res.n; i++) {
                x[i] = (rnd() & 1UL) ? rnd_i16() : (int16_t)rnd_range(-3000, 3000);
            }
            random_omega(w);
            s = ac_resolve(&res, x, 0, out);
            TAG("RES0");
            st(s);
            print_out6(out);
            nl();
            s = ac_resolve(&res, x, w, out);
            TAG("RESW");
            h16(w[0]);
            h16(w[1]);
            h16(w[2]);
            st(s);
            nl();
            TAG(" ");
            print_out6(out);
            nl();
        }
        /* per-sample processing and the batch entry */
        for (i = 0u; i < res.n; i++) {
            trim[i] = (uint16_t)rnd_range(3000, 7000);
        }
        for (k = 0u; k < BATCH; k++) {
            for (i = 0u; i < res.n; i++) {
                int32_t v = (int32_t)trim[i] + rnd_range(-6000, 6000);
                if ((rnd() & 15UL) == 0UL) {
                    v = (int32_t)(rnd() & 0xFFFFUL);
                }
                mem.batch.raw[k * res.n + i] = (uint16_t)(v < 0 ? 0 : (v > 65535L ? 65535L : v));
            }
            random_omega(&mem.batch.omega[k * 3u]);
        }
        s = ac_process(&res, trim, mem.batch.raw, &mem.batch.omega[0], out);
        TAG("PRC");
        st(s);
        print_out6(out);
        nl();
        s = ac_process(&res, trim, mem.batch.raw, 0, out);
        TAG("PRC0");
        st(s);
        print_out6(out);
        nl();
        s = ac_process_batch(&res, trim, mem.batch.raw, BATCH, (t & 1u) ? mem.batch.omega : 0,
                             mem.batch.out, (t & 2u) ? mem.batch.flags : 0);
        TAG("BAT");
        st(s);
        if (t & 2u) {
            for (k = 0u; k < BATCH; k++) {
                h8(mem.batch.flags[k]);
            }
        }
        nl();
        for (k = 0u; k < BATCH; k++) {
            TAG(" ");
            print_out6(&mem.batch.out[k * 6u]);
            nl();
        }
    }
    /* invalid tables */
    res.n = 5u;
    TAG("BAD");
    st(ac_resolver_check(&res));
    res.n = AC_MAX_CHANNELS + 1u;
    st(ac_resolver_check(&res));
    st(ac_resolve(&res, x, 0, out));
    res.n = 6u;
    res.m_shift[0] = 32;
    st(ac_resolver_check(&res));
    res.m_shift[0] = 0;
    res.m[0][0] = 32767;
    res.m[0][1] = 32767;
    res.m[0][2] = 2;
    st(ac_resolver_check(&res));
    st(ac_resolver_check(0));
    st(ac_resolve(0, x, 0, out));
    nl();
}

/* Edge cases of the per-sample kernel (the H8/300H runs it in assembly, the
 * fast path for n = 6 with x in registers): every rounding-shift length and
 * the cold paths (zero, negative and > 31 shifts, the centripetal term that
 * clips alone), saturated offsets, extreme rates and readings, and the
 * pre-trim's clip limits.  Tables may break the row-sum invariant: the sums
 * then wrap in uint32 on every target alike. */
static const int8_t edge_mshift[] = {-31, -17, -1, 0, 1, 2, 7, 8, 9, 15, 16, 17, 30, 31};
static const int8_t edge_gshift[] = {-31, -8, 0, 9, 17, 23, 31};
static const int16_t edge_w[][3] = {{0, 0, 0},          {-32767 - 1, -32767 - 1, -32767 - 1},
                                    {32767, -32767 - 1, 1}, {127, -128, 126},
                                    {181, 0, -181},     {-2896, 2896, 100}};

static VEC_STEP void vec_resolve_edges(void)
{
    uint16_t t, i, k;
    int16_t x[AC_MAX_CHANNELS], w[3];
    uint16_t trim[AC_MAX_CHANNELS], raw[AC_MAX_CHANNELS];
    int32_t out[6];
    for (t = 0u; t < 48u; t++) {
        uint8_t j, q;
        ac_status s;
        res.n = (t % 4u == 3u) ? (uint16_t)AC_MAX_CHANNELS : 6u;
        for (j = 0u; j < 6u; j++) {
            uint8_t big = (uint8_t)((t + j) % 5u == 0u);
            res.m_shift[j] = edge_mshift[(t * 5u + j * 3u) % sizeof edge_mshift];
            res.g_shift[j] = edge_gshift[(t * 3u + j) % sizeof edge_gshift];
            for (i = 0u; i < AC_MAX_CHANNELS; i++) {
                res.m[j][i] = big ? (int16_t)((i & 1u) ? 32767 : -32767 - 1) : rnd_i16();
            }
            for (q = 0u; q < 6u; q++) {
                res.g[j][q] = big ? (int16_t)((q & 1u) ? -32767 - 1 : 32767) : rnd_i16();
            }
            switch ((t + 2u * j) % 4u) {
            case 0u: res.k[j] = INT32_MAX; break;
            case 1u: res.k[j] = INT32_MIN; break;
            case 2u: res.k[j] = 0; break;
            default: res.k[j] = s32(rnd()); break;
            }
        }
        for (k = 0u; k < 3u; k++) {
            for (i = 0u; i < res.n; i++) {
                x[i] = (k == 0u) ? (int16_t)((i & 1u) ? -32767 - 1 : 32767)
                                 : (k == 1u ? (int16_t)rnd_range(-40, 40) : rnd_i16());
            }
            for (q = 0u; q < 3u; q++) {
                w[q] = (k == 2u && (t & 1u)) ? rnd_i16() : edge_w[(t + k) % 6u][q];
            }
            s = ac_resolve(&res, x, 0, out);
            TAG("EDG0");
            h8((uint8_t)res.n);
            st(s);
            print_out6(out);
            nl();
            s = ac_resolve(&res, x, w, out);
            TAG("EDGW");
            h16(w[0]);
            h16(w[1]);
            h16(w[2]);
            st(s);
            print_out6(out);
            nl();
        }
        /* the pre-trim's limits: differences 32767, 32768, -32768, -32769, +-65535 */
        for (i = 0u; i < res.n; i++) {
            static const uint16_t tr[6] = {0u, 0u, 32768u, 32769u, 65535u, 1000u};
            static const uint16_t rw[6] = {32767u, 32768u, 0u, 0u, 0u, 65535u};
            trim[i] = tr[(i + t) % 6u];
            raw[i] = rw[(i + t) % 6u];
        }
        s = ac_process(&res, trim, raw, (t & 1u) ? edge_w[t % 6u] : 0, out);
        TAG("EDGP");
        st(s);
        print_out6(out);
        nl();
        s = ac_trim(raw, trim, res.n, x);
        TAG("EDGT");
        st(s);
        for (i = 0u; i < res.n; i++) {
            h16(x[i]);
        }
        nl();
    }
}

/* The checks before any arithmetic, in ac_process and ac_resolve (the H8/300H
 * runs ac_process's in assembly, the 12 shift checks folded into one
 * register): each NULL pointer, n outside 6..AC_MAX_CHANNELS (also with the
 * high byte set), each of the 12 shifts at and beyond its limits for n = 6
 * (the pre-trim into registers) and n = AC_MAX_CHANNELS, several faults at
 * once (the C's order decides: NULL, then n, then the shifts), and out left as
 * it was after every error. */
static VEC_STEP void vec_resolve_errors(void)
{
    static const int8_t bad[] = {32, -32, 33, -33, 63, -63, 64, -64, 96, -96, 127, -128};
    static const int8_t good[] = {31, -31, 30, -30, 1, -1, 0};
    static const uint16_t bad_n[] = {0u, 1u, 5u, AC_MAX_CHANNELS + 1u, 64u, 0x0106u, 0x8006u, 0xFFFFu};
    uint16_t trim[AC_MAX_CHANNELS], raw[AC_MAX_CHANNELS];
    int16_t x[AC_MAX_CHANNELS];
    static const int16_t w[3] = {2100, -1300, 700};
    int32_t out[6];
    uint16_t i, q;
    uint8_t j, pos, nn;
    int8_t *sh;

    random_table();
    for (i = 0u; i < AC_MAX_CHANNELS; i++) {
        trim[i] = (uint16_t)(20000u + 97u * i);
        raw[i] = (uint16_t)(trim[i] + 1500u - 301u * i);
        x[i] = (int16_t)(1500 - 301 * (int16_t)i);
    }
    for (j = 0u; j < 6u; j++) {
        out[j] = 0x5A5A5A5AL + (int32_t)j;
    }
    for (nn = 0u; nn < 2u; nn++) {
        res.n = nn ? (uint16_t)AC_MAX_CHANNELS : 6u;
        TAG("ERRN");
        h8((uint8_t)res.n);
        st(ac_process(0, trim, raw, w, out));
        st(ac_process(&res, 0, raw, w, out));
        st(ac_process(&res, trim, 0, w, out));
        st(ac_process(&res, trim, raw, w, 0));
        st(ac_process(&res, trim, raw, 0, 0));
        st(ac_process(0, 0, 0, 0, 0));
        st(ac_resolve(0, x, w, out));
        st(ac_resolve(&res, 0, w, out));
        st(ac_resolve(&res, x, w, 0));
        print_out6(out);
        nl();
    }
    /* n out of range; with a bad shift too, and with a NULL pointer too */
    for (q = 0u; q < sizeof bad_n / sizeof bad_n[0]; q++) {
        res.n = bad_n[q];
        TAG("ERRS");
        h16((int16_t)res.n);
        st(ac_process(&res, trim, raw, w, out));
        st(ac_process(&res, trim, raw, 0, out));
        st(ac_resolve(&res, x, w, out));
        res.g_shift[5] = 32;
        st(ac_process(&res, trim, raw, w, out));
        st(ac_process(&res, trim, 0, w, out));
        res.g_shift[5] = 3;
        print_out6(out);
        nl();
    }
    /* each shift out of range, for n = 6 and n = AC_MAX_CHANNELS */
    for (nn = 0u; nn < 2u; nn++) {
        res.n = nn ? (uint16_t)AC_MAX_CHANNELS : 6u;
        for (pos = 0u; pos < 12u; pos++) {
            int8_t keep;
            sh = (pos < 6u) ? &res.m_shift[pos] : &res.g_shift[pos - 6u];
            keep = *sh;
            TAG("ERRF");
            h8((uint8_t)res.n);
            h8(pos);
            for (q = 0u; q < sizeof bad; q++) {
                *sh = bad[q];
                st(ac_process(&res, trim, raw, w, out));
                st(ac_process(&res, trim, raw, 0, out));
                st(ac_resolve(&res, x, w, out));
            }
            *sh = keep;
            print_out6(out);
            nl();
        }
    }
    /* several at once: every shift 32, then every shift -32, then one bad among limits */
    for (pos = 0u; pos < 12u; pos++) {
        sh = (pos < 6u) ? &res.m_shift[pos] : &res.g_shift[pos - 6u];
        *sh = 32;
    }
    TAG("ERRM");
    st(ac_process(&res, trim, raw, w, out));
    for (pos = 0u; pos < 12u; pos++) {
        sh = (pos < 6u) ? &res.m_shift[pos] : &res.g_shift[pos - 6u];
        *sh = (pos & 1u) ? -32 : 31;
    }
    st(ac_process(&res, trim, raw, w, out));
    st(ac_resolve(&res, x, w, out));
    print_out6(out);
    nl();
    /* the shifts at their limits are accepted and run through the arithmetic */
    for (nn = 0u; nn < 2u; nn++) {
        res.n = nn ? (uint16_t)AC_MAX_CHANNELS : 6u;
        for (pos = 0u; pos < 12u; pos++) {
            sh = (pos < 6u) ? &res.m_shift[pos] : &res.g_shift[pos - 6u];
            *sh = (int8_t)(8 + (int8_t)pos);
        }
        for (pos = 0u; pos < 12u; pos++) {
            sh = (pos < 6u) ? &res.m_shift[pos] : &res.g_shift[pos - 6u];
            for (q = 0u; q < sizeof good; q++) {
                *sh = good[q];
                TAG("ERRG");
                h8((uint8_t)res.n);
                h8(pos);
                h8((uint8_t)good[q]);
                st(ac_process(&res, trim, raw, w, out));
                print_out6(out);
                st(ac_process(&res, trim, raw, 0, out));
                print_out6(out);
                nl();
            }
            *sh = (int8_t)(8 + (int8_t)pos);
        }
    }
}

/* The centripetal term's alignment at its boundaries: t = g . p with the
 * shift of t (2 AC_OMEGA_FRAC - s + g_shift - m_shift) from -2 to 33 around 0,
 * 16/17 (the word step) and 31/32, for t = +-2^30 exactly, one p step beyond,
 * and near +-1.6e9 (omega = 2^14 on every axis: s = 15, every p = 2^13; m = 0
 * and m_shift = 0, so out = -k - round(t 2^-shift) shows the aligned t itself). */
static VEC_STEP void vec_tshift_edges(void)
{
    static const int8_t dshift[] = {-2, -1, 0, 1, 2, 15, 16, 17, 18, 29, 30, 31, 32, 33};
    static const int16_t gq[6][6] = {{32767, 32767, 32767, 32767, 32767, 32767},
                                     {-32768, -32768, -32768, -32768, -32768, -32768},
                                     {32767, 32767, 32767, 32767, 4, 0},
                                     {-32768, -32768, -32768, -32768, 0, 0},
                                     {-32768, -32768, -32768, -32768, 0, -1},
                                     {32767, 32767, 32767, 32767, 3, 0}};
    static const int16_t w[3] = {16384, 16384, 16384};
    uint16_t trim[6], raw[6];
    int16_t x[6];
    int32_t out[6];
    uint8_t j, q, d;
    res.n = 6u;
    for (j = 0u; j < 6u; j++) {
        for (q = 0u; q < AC_MAX_CHANNELS; q++) {
            res.m[j][q] = 0;
        }
        for (q = 0u; q < 6u; q++) {
            res.g[j][q] = gq[j][q];
        }
        res.k[j] = (j & 1u) ? 0 : 7;
        res.m_shift[j] = 0;
        trim[j] = 100u;
        raw[j] = 200u;
        x[j] = 100;
    }
    for (d = 0u; d < sizeof dshift; d++) {
        for (j = 0u; j < 6u; j++) {
            res.g_shift[j] = (int8_t)(dshift[d] - (2 * AC_OMEGA_FRAC - 15));
        }
        TAG("TSH");
        h8((uint8_t)dshift[d]);
        st(ac_resolve(&res, x, w, out));
        print_out6(out);
        st(ac_process(&res, trim, raw, w, out));
        print_out6(out);
        nl();
    }
}

/* ---- inversion and table build ----------------------------------------------------------- */

/* seed prototype: 1250 counts per g (127.4645 counts per m/s^2) in Q16, the
 * tangent of chip k at 120k deg, the 60 mm circle in Q20 */
#define S1 8353515L /* 127.4645 * 2^16 */
#define SC 7234356L /* S1 * sin 60 */
#define SH 4176758L /* S1 / 2 */
#define R1 62915L   /* 0.060 m * 2^20 */
#define RC 54486L   /* R1 * sin 60 */
#define RH 31457L   /* R1 / 2 */

static const int32_t seed_t[3][3] AC_ROM = {{0, S1, 0}, {-SC, -SH, 0}, {SC, -SH, 0}};
static const int32_t seed_rad[3][3] AC_ROM = {{S1, 0, 0}, {-SH, SC, 0}, {-SH, -SC, 0}};
static const int32_t seed_pos[3][3] AC_ROM = {{R1, 0, 0}, {-RH, RC, 0}, {-RH, -RC, 0}};

static int32_t jitter(int32_t v, uint32_t mask)
{
    return v + (int32_t)(rnd() & mask) - (int32_t)(mask >> 1);
}

static int32_t rom_i32(const int32_t *p)
{
    return s32(AC_ROM_U32(p));
}

/* s and r point to read-only memory */
static void set_cal(uint16_t i, const int32_t *s, const int32_t *r, uint32_t js, uint32_t jr)
{
    uint8_t a;
    for (a = 0u; a < 3u; a++) {
        cal[i].sens[a] = jitter(rom_i32(&s[a]), js);
        cal[i].pos[a] = jitter(rom_i32(&r[a]), jr);
    }
    cal[i].offset = jitter(0, 0x7FFUL); /* +-4 counts in Q8 */
}

/* 6 channels: the seed; 9: three tri-axial chips; 12: four tri-axial chips
 * at 90 deg steps, heights +-10 mm. */
static void make_geometry(uint16_t n, uint32_t js, uint32_t jr)
{
    static const int32_t z[3] AC_ROM = {0, 0, S1};
    static const int32_t quad_t[4][3] AC_ROM = {{0, S1, 0}, {-S1, 0, 0}, {0, -S1, 0}, {S1, 0, 0}};
    static const int32_t quad_r[4][3] AC_ROM = {{S1, 0, 0}, {0, S1, 0}, {-S1, 0, 0}, {0, -S1, 0}};
    static const int32_t quad_p[4][3] AC_ROM = {
        {R1, 0, 10486L}, {0, R1, -10486L}, {-R1, 0, 10486L}, {0, -R1, -10486L}};
    uint16_t k;
    if (n == 6u) {
        for (k = 0u; k < 3u; k++) {
            set_cal((uint16_t)(2u * k), seed_t[k], seed_pos[k], js, jr);
            set_cal((uint16_t)(2u * k + 1u), z, seed_pos[k], js, jr);
        }
    } else if (n == 9u) {
        for (k = 0u; k < 3u; k++) {
            set_cal((uint16_t)(3u * k), seed_t[k], seed_pos[k], js, jr);
            set_cal((uint16_t)(3u * k + 1u), seed_rad[k], seed_pos[k], js, jr);
            set_cal((uint16_t)(3u * k + 2u), z, seed_pos[k], js, jr);
        }
    } else {
        for (k = 0u; k < 4u; k++) {
            set_cal((uint16_t)(3u * k), quad_t[k], quad_p[k], js, jr);
            set_cal((uint16_t)(3u * k + 1u), quad_r[k], quad_p[k], js, jr);
            set_cal((uint16_t)(3u * k + 2u), z, quad_p[k], js, jr);
        }
    }
}

static void print_table(void)
{
    uint8_t j;
    uint16_t i;
    for (j = 0u; j < 6u; j++) {
        TAG(" ms");
        h8((uint8_t)res.m_shift[j]);
        h32(res.k[j]);
        TAG(" gs");
        h8((uint8_t)res.g_shift[j]);
        for (i = 0u; i < 6u; i++) {
            h16(res.g[j][i]);
        }
        nl();
        TAG(" m");
        for (i = 0u; i < res.n; i++) {
            h16(res.m[j][i]);
        }
        nl();
    }
}

static VEC_STEP void vec_build(void)
{
    static const uint16_t sizes[4] AC_ROM = {6u, 6u, 9u, 12u};
    uint16_t t, i;
    ac_build_info info;
    ac_xf row[6];
    for (t = 0u; t < 24u; t++) {
        uint16_t n = AC_ROM_U16(&sizes[t & 3u]);
        ac_status s;
        uint8_t a;
        make_geometry(n, t == 0u ? 0UL : 0x7FFFFUL, t == 0u ? 0UL : 0xFFFUL);
        for (i = 0u; i < n; i++) {
            s = ac_sensor_row(&cal[i], row);
            TAG("SROW");
            st(s);
            for (a = 0u; a < 6u; a++) {
                hxf(row[a]);
                if (a == 2u) {
                    nl();
                    TAG(" ");
                }
            }
            nl();
            s = ac_centripetal_row(&cal[i], row);
            TAG("CROW");
            st(s);
            for (a = 0u; a < 6u; a++) {
                hxf(row[a]);
                if (a == 2u) {
                    nl();
                    TAG(" ");
                }
            }
            nl();
        }
        info.cond_log2 = 0;
        s = ac_resolver_build(cal, n, &mem.work, &res, &info);
        TAG("BLD");
        h8((uint8_t)n);
        st(s);
        h16(info.cond_log2);
        nl();
        print_table();
    }

    /* errors: singular (all along x), ill-conditioned, sizes, NULL */
    make_geometry(6u, 0UL, 0UL);
    for (i = 0u; i < 6u; i++) {
        cal[i].sens[0] = S1;
        cal[i].sens[1] = 0;
        cal[i].sens[2] = 0;
    }
    TAG("BLDE");
    st(ac_resolver_build(cal, 6u, &mem.work, &res, &info));
    make_geometry(6u, 0UL, 0UL);
    cal[5].sens[0] = cal[4].sens[0];
    cal[5].sens[1] = cal[4].sens[1];
    cal[5].sens[2] = 8;
    st(ac_resolver_build(cal, 6u, &mem.work, &res, &info));
    cal[5].sens[2] = 0;
    st(ac_resolver_build(cal, 6u, &mem.work, &res, &info));
    st(ac_resolver_build(cal, 5u, &mem.work, &res, &info));
    st(ac_resolver_build(cal, AC_MAX_CHANNELS + 1u, &mem.work, &res, &info));
    st(ac_resolver_build(0, 6u, &mem.work, &res, &info));
    st(ac_sensor_row(0, row));
    st(ac_centripetal_row(0, row));
    nl();
}

static VEC_STEP void vec_invert6(void)
{
    uint16_t t;
    uint8_t i, j;
    int8_t perm[6];
    for (t = 0u; t < 30u; t++) {
        int16_t cl2 = 0;
        ac_status s;
        int16_t scale = (int16_t)rnd_range(-100, 100);
        for (i = 0u; i < 6u; i++) {
            for (j = 0u; j < 6u; j++) {
                mem.mat[i][j] = rnd_xf((int16_t)(scale - 3), scale);
            }
            if (t & 1u) {
                mem.mat[i][i].e = (int16_t)(scale + 3); /* diagonally dominant */
            }
        }
        if (t == 7u) {
            for (j = 0u; j < 6u; j++) {
                mem.mat[4][j] = mem.mat[1][j]; /* singular */
            }
        }
        s = ac_invert6(mem.mat, perm, &cl2);
        TAG("INV");
        st(s);
        h16(cl2);
        for (i = 0u; i < 6u; i++) {
            h8((uint8_t)perm[i]);
        }
        nl();
        if (s == AC_OK) {
            for (i = 0u; i < 6u; i++) {
                TAG(" ");
                for (j = 0u; j < 6u; j++) {
                    hxf(mem.mat[i][j]);
                    if (j == 2u) {
                        nl();
                        TAG(" ");
                    }
                }
                nl();
            }
        }
    }
}

/* ---- rate ---------------------------------------------------------------------------------- */

static ac_rate rs;

static VEC_STEP void vec_rate(void)
{
    uint16_t run, k;
    int32_t alpha[3];
    int16_t omega[3];
    for (run = 0u; run < 12u; run++) {
        uint16_t dt_m = (uint16_t)(0x8000u | (uint16_t)(rnd() & 0x7FFFUL));
        uint8_t dt_shift = (uint8_t)rnd_range(16, 47); /* 47: out of range */
        uint16_t leak = (run & 3u) == 0u ? 0u : (uint16_t)(rnd() & 0xFFFFUL);
        ac_status s = ac_rate_init(&rs, dt_m, dt_shift, leak);
        TAG("RTI");
        hu16(dt_m);
        h8(dt_shift);
        hu16(leak);
        st(s);
        nl();
        if (s != AC_OK) {
            continue;
        }
        for (k = 0u; k < 40u; k++) {
            uint8_t a;
            for (a = 0u; a < 3u; a++) {
                alpha[a] = (run & 1u) ? rnd_i32() : rnd_range(-20000, 20000);
            }
            s = ac_rate_step(&rs, alpha, omega);
            TAG("RT");
            st(s);
            h16(omega[0]);
            h16(omega[1]);
            h16(omega[2]);
            h32(rs.w[0]);
            h32(rs.w[1]);
            h32(rs.w[2]);
            nl();
        }
        s = ac_rate_reset(&rs);
        TAG("RTR");
        st(s);
        h32(rs.w[0]);
        nl();
    }
    TAG("RTN");
    st(ac_rate_init(0, 1u, 20u, 0u));
    st(ac_rate_reset(0));
    st(ac_rate_step(0, alpha, omega));
    nl();
}

/* ---- cycle counts (platforms with a counter; after END, not compared) ------------------- */

static uint32_t t0;
static void bench_start(void)
{
    t0 = ac_test_cycles();
}
static void bench_end(const char *name) /* name in read-only memory */
{
    uint32_t dt = ac_test_cycles() - t0;
    OUT_S("CYCLES ");
    out_s(name);
    out_c(' ');
    out_dec(dt);
    out_c('\n');
}

static void bench(void)
{
    uint16_t trim[AC_MAX_CHANNELS], raw[AC_MAX_CHANNELS];
    int16_t x[AC_MAX_CHANNELS], w[3] = {1200, -700, 3000};
    int32_t out[6], a32 = 0;
    ac_xf xa, xb, xr;
    uint16_t i;

    make_geometry(6u, 0UL, 0UL);
    bench_start();
    (void)ac_resolver_build(cal, 6u, &mem.work, &res, 0);
    bench_end(AC_STR("ac_resolver_build(n=6)"));
    make_geometry(12u, 0UL, 0UL);
    bench_start();
    (void)ac_resolver_build(cal, 12u, &mem.work, &res, 0);
    bench_end(AC_STR("ac_resolver_build(n=12)"));
    make_geometry(6u, 0UL, 0UL);
    (void)ac_resolver_build(cal, 6u, &mem.work, &res, 0);
    for (i = 0u; i < 6u; i++) {
        trim[i] = 5000u;
        raw[i] = (uint16_t)(4000u + 300u * i);
    }
    bench_start();
    (void)ac_trim(raw, trim, 6u, x);
    bench_end(AC_STR("ac_trim(n=6)"));
    bench_start();
    (void)ac_resolve(&res, x, 0, out);
    bench_end(AC_STR("ac_resolve(n=6,omega=NULL)"));
    bench_start();
    (void)ac_resolve(&res, x, w, out);
    bench_end(AC_STR("ac_resolve(n=6,omega)"));
    bench_start();
    (void)ac_process(&res, trim, raw, w, out);
    bench_end(AC_STR("ac_process(n=6,omega)"));
    (void)ac_rate_init(&rs, 34953u, 21u, 655u);
    bench_start();
    (void)ac_rate_step(&rs, &out[3], w);
    bench_end(AC_STR("ac_rate_step(leak)"));
    bench_start();
    (void)ac_mul32_shift(123456789L, -987654321L, 40u, &a32);
    bench_end(AC_STR("ac_mul32_shift"));
    xa.m = 0x2468ACE0L;
    xa.e = 3;
    xb.m = -0x35555555L;
    xb.e = -7;
    bench_start();
    (void)ac_xf_mul(xa, xb, &xr);
    bench_end(AC_STR("ac_xf_mul"));
    bench_start();
    (void)ac_xf_add(xa, xb, &xr);
    bench_end(AC_STR("ac_xf_add"));
    bench_start();
    (void)ac_xf_div(xa, xb, &xr);
    bench_end(AC_STR("ac_xf_div"));
    bench_start();
    bench_end(AC_STR("(empty)"));
}

/* ---- the converter's rails (ac_trim_rails, _s16, ac_process, ac_process_batch, ac_triad_apply) --
 * Rails from a few kinds (a 16-bit and a 12-bit converter, arbitrary, one code apart,
 * equal and inverted: rails unknown), readings at and around them (raw_min - 1 .. + 1,
 * raw_max - 1 .. + 1, the code range's ends) and random; the H8/300H checks them in its
 * assembly pre-trim (n = 6 in registers, n > 6 into a buffer), so both shapes run. */
static uint16_t rail_pick(uint16_t lo, uint16_t hi)
{
    switch (below(10u)) {
    case 0u: return lo;
    case 1u: return (uint16_t)(lo + 1u);
    case 2u: return (uint16_t)(lo - 1u);
    case 3u: return hi;
    case 4u: return (uint16_t)(hi - 1u);
    case 5u: return (uint16_t)(hi + 1u);
    case 6u: return (rnd() & 1UL) ? 0u : 65535u;
    default: return (uint16_t)rnd();
    }
}

static void rail_pair(uint16_t t, uint16_t *lo, uint16_t *hi)
{
    switch (t % 7u) {
    case 0u: *lo = 0u; *hi = 65535u; break;
    case 1u: *lo = 0u; *hi = 4095u; break;
    case 2u: *lo = (uint16_t)rnd(); *hi = (uint16_t)(*lo + 1u + below(60000u)); break;
    case 3u: *lo = (uint16_t)rnd(); *hi = (uint16_t)(*lo + 1u); break;
    case 4u: *lo = 0u; *hi = 0u; break;
    case 5u: *lo = (uint16_t)rnd(); *hi = *lo; break;
    default: *hi = (uint16_t)rnd(); *lo = (uint16_t)(*hi + 1u + below(1000u)); break;
    }
}

static VEC_STEP void vec_rails(void)
{
    uint16_t t, i, k, lo, hi;
    uint16_t raw[AC_MAX_CHANNELS + 2u], trim[AC_MAX_CHANNELS + 2u];
    int16_t x[AC_MAX_CHANNELS + 2u];
    int32_t out[6];
    for (t = 0u; t < 70u; t++) {
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS + 2u));
        rail_pair(t, &lo, &hi);
        for (k = 0u; k < n; k++) {
            raw[k] = rail_pick(lo, hi);
            trim[k] = (t & 8u) ? (uint16_t)rnd() : (uint16_t)(raw[k] + (uint16_t)below(2000u) - 1000u);
            x[k] = 0;
        }
        TAG("RLT");
        h16((int16_t)lo);
        h16((int16_t)hi);
        st(ac_trim_rails(raw, trim, n, lo, hi, x));
        for (k = 0u; k < n; k++) {
            h16(x[k]);
        }
        nl();
    }
    TAG("RLT0");
    st(ac_trim_rails(raw, trim, 0u, 0u, 4095u, x));
    st(ac_trim_rails(0, trim, 1u, 0u, 4095u, x));
    st(ac_trim_rails(raw, 0, 1u, 0u, 4095u, x));
    st(ac_trim_rails(raw, trim, 1u, 0u, 4095u, 0));
    nl();
    for (t = 0u; t < 42u; t++) {
        ac_status s;
        random_table();
        if (t & 1u) {
            res.n = 6u; /* the H8's registers path */
        }
        rail_pair(t / 2u, &lo, &hi);
        res.raw_min = lo;
        res.raw_max = hi;
        for (i = 0u; i < res.n; i++) {
            trim[i] = (uint16_t)rnd_range(1000, 7000);
        }
        for (k = 0u; k < BATCH; k++) {
            for (i = 0u; i < res.n; i++) {
                /* mostly inside: one rail reading in a sample, or none */
                mem.batch.raw[k * res.n + i] = (uint16_t)(trim[i] + (uint16_t)below(200u));
            }
            if (below(3u) != 0u) {
                mem.batch.raw[k * res.n + below(res.n)] = rail_pick(lo, hi);
            }
            random_omega(&mem.batch.omega[k * 3u]);
        }
        for (k = 0u; k < BATCH; k++) {
            s = ac_process(&res, trim, &mem.batch.raw[k * res.n], (k & 1u) ? &mem.batch.omega[k * 3u] : 0, out);
            TAG("RLP");
            h8((uint8_t)res.n);
            st(s);
            print_out6(out);
            nl();
        }
        s = ac_process_batch(&res, trim, mem.batch.raw, BATCH, (t & 2u) ? mem.batch.omega : 0, mem.batch.out,
                             mem.batch.flags);
        TAG("RLB");
        st(s);
        for (k = 0u; k < BATCH; k++) {
            h8(mem.batch.flags[k]);
        }
        nl();
    }
    res.raw_min = 0u;
    res.raw_max = 0u;
    /* a signed chip's pre-trim with its rails in its own counts (ac_trim_rails_s16): the
     * same rail pairs and readings read as int16 (code - 32768: a 12-bit chip's -2048, 2047
     * among them), compared with int16 operators */
    for (t = 0u; t < 70u; t++) {
        int16_t sraw[AC_MAX_CHANNELS + 2u], strim[AC_MAX_CHANNELS + 2u], slo, shi;
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS + 2u));
        rail_pair(t, &lo, &hi);
        if (t % 7u == 1u) {
            lo = (uint16_t)(32768u - 2048u); /* -2048 .. 2047 */
            hi = (uint16_t)(32768u + 2047u);
        }
        slo = (int16_t)(int32_t)((long)lo - 32768L);
        shi = (int16_t)(int32_t)((long)hi - 32768L);
        for (k = 0u; k < n; k++) {
            uint16_t r = rail_pick(lo, hi);
            uint16_t tc = (t & 8u) ? (uint16_t)rnd() : (uint16_t)(r + (uint16_t)below(2000u) - 1000u);
            sraw[k] = (int16_t)(int32_t)((long)r - 32768L);
            strim[k] = (int16_t)(int32_t)((long)tc - 32768L);
            x[k] = 0;
        }
        TAG("RLS");
        h16(slo);
        h16(shi);
        st(ac_trim_rails_s16(sraw, strim, n, slo, shi, x));
        for (k = 0u; k < n; k++) {
            h16(x[k]);
        }
        nl();
    }
    TAG("RLS0");
    {
        int16_t sraw[1] = {0}, strim[1] = {0};
        st(ac_trim_rails_s16(sraw, strim, 0u, -2048, 2047, x));
        st(ac_trim_rails_s16(0, strim, 1u, -2048, 2047, x));
        st(ac_trim_rails_s16(sraw, 0, 1u, -2048, 2047, x));
        st(ac_trim_rails_s16(sraw, strim, 1u, -2048, 2047, 0));
    }
    nl();
    for (t = 0u; t < 28u; t++) {
        ac_triad tr;
        int32_t f[3];
        uint8_t j, q;
        rail_pair(t, &lo, &hi);
        tr.raw_min = lo;
        tr.raw_max = hi;
        for (j = 0u; j < 3u; j++) {
            raw[j] = rail_pick(lo, hi);
            tr.trim[j] = (uint16_t)(raw[j] + (uint16_t)below(4000u) - 2000u);
            tr.shift[j] = (int8_t)((int16_t)below(20u) - 2);
            tr.k[j] = (int32_t)rnd_range(-30000, 30000);
            for (q = 0u; q < 3u; q++) {
                tr.m[j][q] = (int16_t)rnd_range(-20000, 20000);
            }
        }
        TAG("RLA");
        h16((int16_t)lo);
        h16((int16_t)hi);
        st(ac_triad_apply(&tr, raw, f));
        for (j = 0u; j < 3u; j++) {
            h32(f[j]);
        }
        nl();
    }
}

#include "vectors_terms.c"
#include "vectors_omega.c"

int main(void)
{
    ac_test_platform_init();
    OUT_S("BEGIN accelcal-vectors 1\n");
    framing = 1u;
    vec_shift_edges();
    vec_fixed();
    vec_xf();
    vec_trim();
    vec_triad();
    vec_triad_build();
    vec_resolve();
    vec_resolve_edges();
    vec_build();
    vec_invert6();
    vec_rate();
    vec_resolve_errors();
    vec_tshift_edges();
    vec_rails();
    vec_terms();
    vec_omega();
    framing = 0u;
    OUT_S("END accelcal-vectors ");
    out_hex(n_lines, 8u);
    out_c(' ');
    out_hex(crc ^ 0xFFFFFFFFUL, 8u);
    out_c('\n');
    if (ac_test_have_cycles()) {
        bench();
    }
    ac_test_platform_exit();
    return 0;
}
