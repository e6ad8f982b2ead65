/*
 * accelcal -- benchmark program of tools/bench_h8.py, run on the patched H8
 * simulator (tools/build_h8sim.sh) with H8SIM_PROFILE set.
 *
 * Each measured call runs inside a profile region: `jsr @@0xcd' with r0 = the
 * region's number before the call's argument set-up and with r0 = 0 after its
 * return (the REGION macro), so the simulator counts every instruction the
 * call executes, by address, in that region.  A region is entered `calls'
 * times with different inputs; region EMPTY brackets nothing and gives the
 * bracket's own instructions, which bench_h8.py subtracts once per entry.
 *
 * Stack: before each measured call the free RAM below the stack pointer is
 * painted; after it the lowest changed byte gives the call's deepest stack use
 * (return address included).
 *
 * Output lines (write trap, stdout):
 *   REGION <id> <name> <entries> <samples>   samples: what one entry processes
 *   STACK <id> <bytes>                       deepest use over all entries
 *   END bench                                 the last line
 */
#include <accelcal/accelcal.h>

void h8sim_exit(int status); /* crt0.s */
extern uint8_t end;          /* linker: end of .bss */

#define REGION(id)                                                          \
    do {                                                                    \
        register uint16_t r0_ __asm__("r0") = (uint16_t)(id);               \
        __asm__ volatile("jsr @@0xcd" : "+r"(r0_) : : "memory");            \
    } while (0)

enum {
    R_EMPTY = 1,
    R_TRIM,
    R_PROCESS,
    R_PROCESS_W,
    R_RESOLVE_W,
    R_RATE,
    R_ATT,
    R_DISP,
    R_BATCH_W,
    R_BUILD,
    R_TRIAD,
    R_TRIAD_BUILD,
    R_TEMP_LAG,
    R_TEMP,
    R_SKEW,
    R_NONLIN,
    R_TERMS,
    R_TERMS_PATH,
    R_OMEGA_REST,
    R_OMEGA_TURN,
    R_TEMP_K2,
    R_TERMS_K2,
    R_NONLIN_K2,
    R_NONLIN_S16,
    R_NONLIN_S17,
    R_NONLIN_S19,
    R_COUNT
};
static const char *const region_name[R_COUNT] = {
    "", "empty", "ac_trim", "ac_process", "ac_process_omega", "ac_resolve_omega",
    "ac_rate_step", "ac_att_step", "ac_disp_step", "ac_process_batch_omega", "ac_resolver_build",
    "ac_triad_apply", "ac_triad_build", "ac_temp_lag_step", "ac_temp_correct", "ac_skew_step",
    "ac_nonlin_invert", "terms_temp_nonlin", "terms_full_path", "ac_omega_step_rest", "ac_omega_step_turn",
    "ac_temp_correct_k2", "terms_temp_nonlin_k2", "ac_nonlin_invert_k2", "ac_nonlin_invert_s16",
    "ac_nonlin_invert_s17", "ac_nonlin_invert_s19"};
static uint16_t entries[R_COUNT], samples[R_COUNT], deepest[R_COUNT];

/* ---- output through the write trap ---- */
static char line[96];
static uint16_t line_n;
static void flush(void)
{
    register uint16_t r0 __asm__("r0") = 1u;
    register const char *r1 __asm__("r1") = line;
    register uint16_t r2 __asm__("r2") = line_n;
    __asm__ volatile("jsr @@0xc7" : "+r"(r0) : "r"(r1), "r"(r2) : "memory");
    line_n = 0u;
}
static void put_c(char c)
{
    line[line_n++] = c;
    if (c == '\n' || line_n == sizeof line) {
        flush();
    }
}
static void put_s(const char *s)
{
    while (*s != '\0') {
        put_c(*s++);
    }
}
static void put_u(uint16_t v)
{
    char d[6];
    uint8_t i = 0u;
    do {
        d[i++] = (char)('0' + v % 10u);
        v = (uint16_t)(v / 10u);
    } while (v != 0u);
    while (i > 0u) {
        put_c(d[--i]);
    }
}

/* ---- stack painting (inline in main: no frame of its own below sp) ---- */
#define PAINT 0xA5u
static uint16_t sp_now(void)
{
    uint16_t sp;
    __asm__ volatile("mov.w r7,%0" : "=r"(sp));
    return sp;
}

/* ---- inputs ---- */
static uint32_t rng = 2463534242UL;
static uint16_t rnd16(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 17;
    rng ^= rng << 5;
    return (uint16_t)(rng >> 8);
}
static int16_t rnd_range(int16_t lo, uint16_t span)
{
    return (int16_t)(lo + (int16_t)(rnd16() % span));
}

/* the seed's 6 channels (as tests/c/vectors.c) */
#define S1 8353515L
#define SC 7234356L
#define SH 4176758L
#define R1 62915L
#define RC 54486L
#define RH 31457L
static const int32_t seed_t[3][3] = {{0, S1, 0}, {-SC, -SH, 0}, {SC, -SH, 0}};
static const int32_t seed_pos[3][3] = {{R1, 0, 0}, {-RH, RC, 0}, {-RH, -RC, 0}};

/* one 3-axis sensor: about 127 counts per m/s^2 on its own axis, cross-axis terms of
 * 0.5-2 %, offsets of a few counts (Q.AC_SENS_FRAC, Q.AC_OFFSET_FRAC) */
static const int32_t triad_sens[3][3] = {{S1, 83535L, -41768L},
                                         {-125303L, S1 + 58475L, 167070L},
                                         {25061L, -100242L, S1 - 33414L}};
static const int32_t triad_offset[3] = {300L, -200L, 512L};

static ac_channel_cal cal[6], tcal[3];
static ac_build_work work;
static ac_resolver res;
static ac_triad tri;
static ac_rate rate;
static ac_att att;
static ac_disp disp;

/* the correctable terms on the seed's 6 channels (firmware.terms_fixed's tables for tempcos of
 * 0.2 % of g per degC and 3e-4/degC at a 20 s and 5 s lag, skews of -5..6 ms at 60 Hz, a square
 * and a cube term of 0.5 % and 0.1 % of the reading at 1 g) */
static const ac_temp_table terms_temp = {6u, 6400, {640, 640, 640, 640, 640, 640},
                                         {5033, 5033, 5033, 5033, 5033, 5033}, {0, 0, 0, 0, 0, 0}, 0u};
static const ac_skew_table terms_skew = {6u, 3u, {1, 0, 1, 1, 1, 0}, {7864u, 26870u, 3932u, 0u, 11796u, 22938u}};
static const ac_nonlin_table terms_nl = {6u, 15, {4295, 4295, 4295, 4295, 4295, 4295},
                                         {22518, 22518, 22518, 22518, 22518, 22518}, 0u};
/* the same terms as a header writes them now for the seed's 0..10000 converter: the hand-off in
 * 2^-2 counts (AC_CAL_TERMS_FRAC 2): ac_temp_correct's frac 2, the
 * nonlinearity's coefficients per 2^-2 count (shift 18) */
static const ac_temp_table terms_temp_k2 = {6u, 6400, {640, 640, 640, 640, 640, 640},
                                            {5033, 5033, 5033, 5033, 5033, 5033}, {0, 0, 0, 0, 0, 0}, 2u};
static const ac_nonlin_table terms_nl_k2 = {6u, 18, {8590, 8590, 8590, 8590, 8590, 8590},
                                            {11259, 11259, 11259, 11259, 11259, 11259}, 0u};
/* a 2^-2-count table's shift is 15 + 2 for a square alone up to 15 + 4 for a cube alone: the same
 * coefficients at the shifts next to the seed's 18 (the states do not depend on a2, a3 but through a
 * clip, none here) */
static const ac_nonlin_table terms_nl_s16 = {6u, 16, {8590, 8590, 8590, 8590, 8590, 8590},
                                             {11259, 11259, 11259, 11259, 11259, 11259}, 0u};
static const ac_nonlin_table terms_nl_s17 = {6u, 17, {8590, 8590, 8590, 8590, 8590, 8590},
                                             {11259, 11259, 11259, 11259, 11259, 11259}, 0u};
static const ac_nonlin_table terms_nl_s19 = {6u, 19, {8590, 8590, 8590, 8590, 8590, 8590},
                                             {11259, 11259, 11259, 11259, 11259, 11259}, 0u};
static ac_temp_lag lag_off, lag_gain;
static int16_t skew_buf[3u * 6u];
static ac_skew_line skew_line;

/* the terms between the pre-trim and the resolve: two lags, the temperature, the nonlinearity
 * (and with `full', the pre-trim, the skew and the resolve with omega): what firmware calls */
static int terms_path(int16_t temp, const uint16_t *raw, const uint16_t *trim, int16_t *x,
                            const int16_t *w, int32_t *out, uint8_t full)
{
    int16_t t_off, t_gain;
    int s = 0;
    if (full) {
        s = (int)ac_trim_rails(raw, trim, 6u, 0u, 65535u, x);
    }
    s |= (int)ac_temp_lag_step(&lag_off, temp, &t_off);
    s |= (int)ac_temp_lag_step(&lag_gain, temp, &t_gain);
    s |= (int)ac_temp_correct(&terms_temp, t_off, t_gain, x, x);
    if (full) {
        s |= (int)ac_skew_step(&terms_skew, &skew_line, x, x);
    }
    s |= (int)ac_nonlin_invert(&terms_nl, x, x);
    if (full) {
        s |= (int)ac_resolve(&res, x, w, out);
    }
    return s;
}

/* the same with the 2^-2 count tables (no pre-trim, skew or resolve) */
static int terms_path_k2(int16_t temp, int16_t *x)
{
    int16_t t_off, t_gain;
    int s = (int)ac_temp_lag_step(&lag_off, temp, &t_off);
    s |= (int)ac_temp_lag_step(&lag_gain, temp, &t_gain);
    s |= (int)ac_temp_correct(&terms_temp_k2, t_off, t_gain, x, x);
    s |= (int)ac_nonlin_invert(&terms_nl_k2, x, x);
    return s;
}

#define BATCH 8u
#define N_SAMPLES 16u

/* one measured call: RAM from the end of .bss up to the stack pointer painted,
 * the call in its region, then the lowest changed byte (all inline in main, so
 * nothing but the call writes below the stack pointer in between) */
#define MEASURE(id, nsamp, call)                                            \
    do {                                                                    \
        uint16_t sp_ = sp_now();                                            \
        uint8_t *p_ = &end;                                                 \
        while ((uint16_t)p_ < sp_) {                                        \
            *p_++ = PAINT;                                                  \
        }                                                                   \
        REGION(id);                                                         \
        (void)(call);                                                       \
        REGION(0);                                                          \
        p_ = &end;                                                          \
        while ((uint16_t)p_ < sp_ && *p_ == PAINT) {                        \
            p_++;                                                           \
        }                                                                   \
        if ((uint16_t)(sp_ - (uint16_t)p_) > deepest[id]) {                 \
            deepest[id] = (uint16_t)(sp_ - (uint16_t)p_);                   \
        }                                                                   \
        entries[id]++;                                                      \
        samples[id] = (nsamp);                                              \
    } while (0)

/* the array's own omega (ac_omega.h): the tetrahedron's table and readings of the vector
 * program (tests/c/vectors_omega_data.h) */
#define AC_ROM
#include "../../tests/c/vectors_omega_data.h"
static ac_omega_table om_tab;
static ac_omega_state om_st;

static void omega_load(void)
{
    uint16_t i, j, k = 0u;
    ac_xf *dst[VO_NXF];
    om_tab.n = (uint16_t)VO_N;
    for (j = 0u; j < 9u; j++) {
        om_tab.shift[j] = vo_shift[j];
        for (i = 0u; i < VO_N; i++) {
            om_tab.t[j][i] = vo_t[j * VO_N + i];
            om_tab.tl[j][i] = vo_tl[j * VO_N + i];
        }
    }
    for (i = 0u; i < 9u; i++) {
        dst[k++] = &om_tab.k[i];
    }
    for (i = 0u; i < 21u; i++) {
        dst[k++] = &om_tab.m[i];
    }
    for (i = 0u; i < 21u; i++) {
        dst[k++] = &om_tab.minv[i];
    }
    for (i = 0u; i < 18u; i++) {
        dst[k++] = &om_tab.leak[i / 6u][i % 6u];
    }
    for (i = 0u; i < 6u; i++) {
        dst[k++] = &om_tab.qn[i];
    }
    for (i = 0u; i < 6u; i++) {
        dst[k++] = &om_tab.p0[i];
    }
    dst[k++] = &om_tab.dt;
    dst[k++] = &om_tab.half_dt;
    dst[k++] = &om_tab.jump;
    dst[k++] = &om_tab.ridge;
    for (i = 0u; i < k; i++) {
        dst[i]->m = vo_xm[i];
        dst[i]->e = vo_xe[i];
    }
}

int main(void)
{
    static uint16_t trim[6], raw[BATCH * 6u];
    static int16_t x[6], w[BATCH * 3u];
    static int32_t out[BATCH * 6u], f[6];
    static ac_att_out aout;
    static ac_disp_out dout;
    ac_disp_cfg dcfg;
    uint16_t k, i;
    uint8_t a, id;

    for (k = 0u; k < 3u; k++) {
        for (a = 0u; a < 3u; a++) {
            cal[2u * k].sens[a] = seed_t[k][a];
            cal[2u * k].pos[a] = seed_pos[k][a];
            cal[2u * k + 1u].sens[a] = (a == 2u) ? S1 : 0;
            cal[2u * k + 1u].pos[a] = seed_pos[k][a];
        }
        cal[2u * k].offset = 300;
        cal[2u * k + 1u].offset = -200;
    }
    MEASURE(R_BUILD, 1u, ac_resolver_build(cal, 6u, &work, &res, 0));
    res.raw_min = 0u; /* the converter's rails, copied in after the build (ac_resolve.h) */
    res.raw_max = 65535u;
    for (k = 0u; k < 3u; k++) {
        for (a = 0u; a < 3u; a++) {
            tcal[k].sens[a] = triad_sens[k][a];
            tcal[k].pos[a] = 0;
        }
        tcal[k].offset = triad_offset[k];
        trim[k] = (uint16_t)(5000u + 10u * k);
    }
    MEASURE(R_TRIAD_BUILD, 1u, ac_triad_build(tcal, trim, &work, &tri));
    tri.raw_min = 0u;
    tri.raw_max = 65535u;
    (void)ac_rate_init(&rate, 34953u, 21u, 655u); /* 60 Hz */
    (void)ac_att_init(&att, 104858L, 314573L, 34953u, 21u, 512u, 1000L, 328u);
    dcfg.rest.dev_max = 51;
    dcfg.rest.g2_lo = 0u;
    dcfg.rest.g2_hi = 0xFFFFFFFFUL;
    dcfg.rest.alpha_max = 0;
    dcfg.rest.ref_max = 154;
    dcfg.rest.hold = 20u;
    dcfg.rest.ema_shift = 3u;
    dcfg.dt_m = 34953u;
    dcfg.dt_shift = 21u;
    dcfg.axis = -1;
    (void)ac_disp_init(&disp, &dcfg);
    (void)ac_temp_lag_init(&lag_off, 55901u, 26u);
    (void)ac_temp_lag_init(&lag_gain, 55831u, 24u);
    (void)ac_skew_init(&skew_line, &terms_skew, skew_buf, 18u);

    for (k = 0u; k < N_SAMPLES; k++) {
        for (i = 0u; i < 6u; i++) {
            trim[i] = (uint16_t)(5000u + (uint16_t)rnd_range(-50, 100));
            raw[i] = (uint16_t)(trim[i] + rnd_range(-1500, 3000));
        }
        for (i = 0u; i < 3u; i++) {
            w[i] = rnd_range(-3000, 6000); /* +-2.9 rad/s */
        }
        MEASURE(R_EMPTY, 1u, 0);
        MEASURE(R_TRIM, 1u, ac_trim(raw, trim, 6u, x));
        MEASURE(R_PROCESS, 1u, ac_process(&res, trim, raw, 0, out));
        MEASURE(R_PROCESS_W, 1u, ac_process(&res, trim, raw, w, out));
        MEASURE(R_RESOLVE_W, 1u, ac_resolve(&res, x, w, out));
        MEASURE(R_RATE, 1u, ac_rate_step(&rate, &out[3], w));
        MEASURE(R_TRIAD, 1u, ac_triad_apply(&tri, raw, f));
        {
            int16_t temp = (int16_t)(25 * 256 + rnd_range(-2560, 5120)), tl = 0, y[6], x2[6];
            MEASURE(R_TEMP_LAG, 1u, ac_temp_lag_step(&lag_off, temp, &tl));
            MEASURE(R_TEMP, 1u, ac_temp_correct(&terms_temp, tl, temp, x, y));
            MEASURE(R_SKEW, 1u, ac_skew_step(&terms_skew, &skew_line, y, y));
            MEASURE(R_NONLIN, 1u, ac_nonlin_invert(&terms_nl, x, y));
            MEASURE(R_TERMS, 1u, terms_path(temp, raw, trim, y, w, out, 0u));
            MEASURE(R_TERMS_PATH, 1u, terms_path(temp, raw, trim, y, w, out, 1u));
            MEASURE(R_TEMP_K2, 1u, ac_temp_correct(&terms_temp_k2, tl, temp, x, y));
            MEASURE(R_TERMS_K2, 1u, terms_path_k2(temp, y));
            /* the nonlinearity alone at shift 18, on the Q.2 output of the terms */
            MEASURE(R_NONLIN_K2, 1u, ac_nonlin_invert(&terms_nl_k2, y, y));
            MEASURE(R_NONLIN_S16, 1u, ac_nonlin_invert(&terms_nl_s16, y, x2));
            MEASURE(R_NONLIN_S17, 1u, ac_nonlin_invert(&terms_nl_s17, y, x2));
            MEASURE(R_NONLIN_S19, 1u, ac_nonlin_invert(&terms_nl_s19, y, x2));
        }
        for (i = 0u; i < 6u; i++) {
            f[i] = (int32_t)rnd_range(-2000, 4000); /* +-2 m/s^2 */
        }
        f[2] += 10045L; /* g */
        f[5] += 10045L;
        MEASURE(R_ATT, 1u, ac_att_step(&att, &f[0], &f[3], &aout));
        /* displacement: 24 samples at rest, then moving */
        if (k >= 8u) {
            f[0] += 3000L;
        } else {
            f[0] = 0;
            f[1] = 0;
            f[2] = 10045L;
        }
        MEASURE(R_DISP, 1u, ac_disp_step(&disp, f, &dout));
    }
    for (k = 0u; k < 2u; k++) {
        for (i = 0u; i < BATCH * 6u; i++) {
            raw[i] = (uint16_t)(trim[i % 6u] + rnd_range(-1500, 3000));
        }
        for (i = 0u; i < BATCH * 3u; i++) {
            w[i] = rnd_range(-3000, 6000);
        }
        MEASURE(R_BATCH_W, BATCH, ac_process_batch(&res, trim, raw, BATCH, w, out, 0));
    }

    /* omega: the 12 samples at rest (the ML skipped), then from mid-turn (the ML each sample) */
    omega_load();
    {
        static int32_t ow[3];
        static int16_t ow10[3];
        uint8_t ofl, len0 = vo_len[0], len1 = vo_len[1];
        (void)ac_omega_init(&om_st, &om_tab);
        for (k = 0u; k < len0; k++) {
            MEASURE(R_OMEGA_REST, 1u, ac_omega_step(&om_st, &om_tab, &vo_x[k * VO_N], ow, ow10, &ofl));
        }
        (void)ac_omega_init(&om_st, &om_tab);
        for (k = 0u; k < len1; k++) {
            MEASURE(R_OMEGA_TURN, 1u, ac_omega_step(&om_st, &om_tab, &vo_x[(len0 + k) * VO_N], ow, ow10, &ofl));
        }
    }
    put_s("SIZE ac_omega_table ");
    put_u((uint16_t)sizeof(ac_omega_table));
    put_c('\n');
    put_s("SIZE ac_omega_state ");
    put_u((uint16_t)sizeof(ac_omega_state));
    put_c('\n');

    for (id = 1u; id < R_COUNT; id++) {
        put_s("REGION ");
        put_u(id);
        put_c(' ');
        put_s(region_name[id]);
        put_c(' ');
        put_u(entries[id]);
        put_c(' ');
        put_u(samples[id]);
        put_c('\n');
        put_s("STACK ");
        put_u(id);
        put_c(' ');
        put_u(deepest[id]);
        put_c('\n');
    }
    put_s("SIZE ac_temp_lag ");
    put_u((uint16_t)sizeof(ac_temp_lag));
    put_c('\n');
    put_s("SIZE ac_skew_line ");
    put_u((uint16_t)sizeof(ac_skew_line));
    put_c('\n');
    put_s("SIZE skew_buf ");
    put_u((uint16_t)sizeof(skew_buf));
    put_c('\n');
    put_s("END bench\n");
    return 0;
}
