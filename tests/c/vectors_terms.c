/*
 * accelcal -- test vectors of the correctable terms (ac_temp.h, ac_skew.h, ac_nonlin.h).
 * Included by tests/c/vectors.c (it uses that file's output and pseudo-random helpers),
 * so every build of the vector program (host, AVR, H8/300H) runs them unchanged.
 */

/* the tables and the delay line share vectors.c's static union (2 KB parts) */
#define vt_temp (mem.terms.temp)
#define vt_skew (mem.terms.skew)
#define vt_nl (mem.terms.nl)
#define vt_line_buf (mem.terms.line)

/* an int16 that is often near an edge: the limits, zero, or small */
static int16_t vt_i16(void)
{
    uint8_t kind = (uint8_t)(rnd() & 7UL);
    if (kind == 0u) {
        return (rnd() & 1UL) ? (int16_t)32767 : (int16_t)(-32767 - 1);
    }
    if (kind < 3u) {
        return (int16_t)rnd_range(-300, 300);
    }
    return rnd_i16();
}

static void vec_temp_lag(void)
{
    uint8_t t, k;
    for (t = 0u; t < 48u; t++) {
        ac_temp_lag f;
        /* weights 2^-14 .. 1 mostly (visible in 10 steps); any shift, 48 and 49 out of range */
        uint8_t shift = (t & 4u) ? (uint8_t)below(50u) : (uint8_t)rnd_range(14, 28);
        uint16_t kk = (uint16_t)rnd();
        int16_t out = 0, temp = vt_i16();
        if (shift < 16u && (t & 1u) != 0u) {
            kk = (uint16_t)(1u << shift); /* weight 1: no lag */
        } else if (shift >= 16u && (t & 2u) != 0u) {
            kk = (uint16_t)(32768u + (kk >> 1)); /* the quantizer's range */
        }
        TAG("VTL");
        h8(shift);
        hu16(kk);
        st(ac_temp_lag_init(&f, kk, shift));
        if (shift <= 47u && (shift >= 16u || (uint32_t)kk <= ((uint32_t)1u << shift))) {
            for (k = 0u; k < 10u; k++) {
                if ((rnd() & 3UL) != 0UL) {
                    temp = (int16_t)(temp + (int16_t)rnd_range(-200, 200));
                } else {
                    temp = vt_i16();
                }
                st(ac_temp_lag_step(&f, temp, &out));
                h16(out);
            }
        }
        nl();
    }
    TAG("VTL0");
    {
        ac_temp_lag f;
        int16_t out;
        st(ac_temp_lag_init(0, 1u, 0u));
        st(ac_temp_lag_init(&f, 1u, 0u));
        st(ac_temp_lag_step(&f, 0, 0));
        st(ac_temp_lag_step(0, 0, &out));
    }
    nl();
}

/* with_frac 0: whole counts (VTC); 1: output fraction bits frac 1..AC_TEMP_MAX_OUT_FRAC, one beyond
 * refused, the readings scaled by 2^-frac so that most fit Q.frac (VTF; the H8/300H runs the C there) */
static void vec_temp_run(uint8_t count, uint8_t with_frac)
{
    uint8_t t, i;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    for (t = 0u; t < count; t++) {
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS));
        int16_t t_off, t_gain;
        vt_temp.n = (t % 29u == 3u) ? 0u : n;
        vt_temp.frac = with_frac ? (uint8_t)(1u + below(AC_TEMP_MAX_OUT_FRAC + 1u)) : 0u;
        vt_temp.t_ref = vt_i16();
        for (i = 0u; i < n; i++) {
            vt_temp.oc[i] = (t & 4u) ? vt_i16() : (int16_t)rnd_range(-3000, 3000);
            vt_temp.gc[i] = (t & 8u) ? vt_i16() : (int16_t)rnd_range(-5000, 5000);
            vt_temp.o[i] = (int16_t)((t % 23u == 4u) ? 129 : rnd_range(-128, 128)); /* 129 refused */
            x[i] = (int16_t)(vt_i16() / (int16_t)(1 << (vt_temp.frac > 7u ? 7u : vt_temp.frac)));
        }
        if (t & 16u) {
            t_off = vt_i16();
        } else {
            t_off = (int16_t)((int32_t)vt_temp.t_ref / 2 + rnd_range(-5000, 5000));
        }
        if (with_frac && (t & 3u) == 1u && vt_temp.frac <= AC_TEMP_MAX_OUT_FRAC) {
            /* channel 0 at the final rounding's edges (gc = o = 0, dTo = 1 LSB: w = x 2^16 - oc):
             * x = +-2^(15-frac), oc = 2^(15-frac) (+1 when t & 4) puts w at 32767.5 2^-frac counts (the
             * tie, rounded up: clipped) or one below (kept), and at -32768.5 (kept) or one beyond
             * (clipped) */
            const int16_t h = (int16_t)(1 << (15u - vt_temp.frac));
            x[0] = (t & 8u) ? (int16_t)-h : h;
            vt_temp.oc[0] = (int16_t)(h + (int16_t)((t >> 2) & 1u));
            vt_temp.gc[0] = 0;
            vt_temp.o[0] = 0;
            t_off = (int16_t)(vt_temp.t_ref + 1);
        }
        if (t & 32u) {
            t_gain = vt_i16();
        } else {
            t_gain = (int16_t)((int32_t)vt_temp.t_ref / 2 + rnd_range(-5000, 5000));
        }
        if (with_frac) {
            TAG("VTF");
            h8(vt_temp.frac);
        } else {
            TAG("VTC");
        }
        h16(t_off);
        h16(t_gain);
        st(ac_temp_correct(&vt_temp, t_off, t_gain, x, y));
        if ((int)ac_temp_check(&vt_temp) == 0) {
            for (i = 0u; i < n; i++) {
                h16(y[i]);
            }
        }
        nl();
    }
}

static void vec_temp_correct(void)
{
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    vec_temp_run(120u, 0u);
    x[0] = 0;
    TAG("VTC0");
    st(ac_temp_correct(0, 0, 0, x, y));
    st(ac_temp_correct(&vt_temp, 0, 0, 0, y));
    st(ac_temp_correct(&vt_temp, 0, 0, x, 0));
    nl();
}

static void vec_skew(void)
{
    uint8_t t, k, i;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    for (t = 0u; t < 40u; t++) {
        ac_skew_line line;
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS));
        uint16_t len = (uint16_t)(2u + below(7u));
        vt_skew.n = n;
        vt_skew.len = (t % 13u == 5u) ? 1u : len;
        for (i = 0u; i < n; i++) {
            vt_skew.whole[i] = (uint8_t)below((uint16_t)(len - 1u));
            vt_skew.frac[i] = (t % 11u == 7u && i == 0u) ? 40000u : (uint16_t)below(32768u);
        }
        TAG("VSK");
        hu16(vt_skew.len);
        st(ac_skew_init(&line, &vt_skew, vt_line_buf, (uint16_t)(AC_MAX_CHANNELS * 8u)));
        if ((int)ac_skew_check(&vt_skew) == 0) {
            for (k = 0u; k < 10u; k++) {
                for (i = 0u; i < n; i++) {
                    x[i] = vt_i16();
                }
                st(ac_skew_step(&vt_skew, &line, x, y));
                for (i = 0u; i < n; i++) {
                    h16(y[i]);
                }
            }
        }
        nl();
    }
    TAG("VSK0");
    {
        ac_skew_line line;
        vt_skew.n = 2u;
        vt_skew.len = 4u;
        vt_skew.whole[0] = 0u;
        vt_skew.whole[1] = 2u;
        vt_skew.frac[0] = 0u;
        vt_skew.frac[1] = 1u;
        st(ac_skew_init(&line, &vt_skew, vt_line_buf, 7u));
        st(ac_skew_init(&line, &vt_skew, 0, 8u));
        st(ac_skew_init(&line, &vt_skew, vt_line_buf, 8u));
        st(ac_skew_step(&vt_skew, &line, 0, y));
        vt_skew.len = 5u;
        st(ac_skew_step(&vt_skew, &line, x, y)); /* a line made for another table */
    }
    nl();
}

static void vec_nonlin(void)
{
    uint8_t t, i;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    for (t = 0u; t < 120u; t++) {
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS));
        vt_nl.n = n;
        vt_nl.iterations = 0u; /* the default, AC_NONLIN_ITERATIONS (the union's other tables share it) */
        vt_nl.shift = (int8_t)((t % 3u == 0u) ? rnd_range(-1, 31) : rnd_range(12, 30));
        for (i = 0u; i < n; i++) {
            int32_t a2 = (t & 4u) ? (int32_t)rnd_range(-32767, 32767) : (int32_t)rnd_range(-3000, 3000);
            int32_t room = 32767L - (a2 < 0 ? -a2 : a2);
            int32_t a3 = (int32_t)rnd_range(-room, room);
            if (t % 17u == 9u && i == 0u) {
                a3 = room + 1L; /* |a2| + |a3| = 32768: refused */
                if (a3 > 32767L) {
                    a3 = 32767L;
                    a2 = 1L;
                }
            }
            vt_nl.a2[i] = (int16_t)a2;
            vt_nl.a3[i] = (int16_t)a3;
            x[i] = vt_i16();
        }
        TAG("VNL");
        h8((uint8_t)vt_nl.shift);
        st(ac_nonlin_invert(&vt_nl, x, y));
        if ((int)ac_nonlin_check(&vt_nl) == 0) {
            for (i = 0u; i < n; i++) {
                h16(y[i]);
            }
        }
        nl();
    }
    TAG("VNL0");
    st(ac_nonlin_invert(0, x, y));
    st(ac_nonlin_invert(&vt_nl, 0, y));
    st(ac_nonlin_invert(&vt_nl, x, 0));
    nl();
}

/* the edges of the H8/300H assembly (csrc/ac_terms_h8.c) that random inputs seldom reach: the lag's
 * difference at +-2^30 (its fast path's bound), the gain term's clip at exactly +-E32, the
 * nonlinearity's one product g z = 2^30 (a table |a2| + |a3| > 32767 makes it: y printed anyway,
 * host and targets must agree) and its clips */
static void vec_terms_edges(void)
{
    static const int32_t dl[] = {-0x40000000L, -0x3FFFFFFFL, -0x3FFF0000L, 0x3FFFFFFFL, 0x40000000L,
                                 -0x40010000L, 0x3FFF0000L, 0x3FFF8000L, -0x3FFF8000L};
    /* a2 (a3 from the first six): the clips and the product 2^30, then for z = +-4096 with a3 = 0
     * the rounding ties g z = 3 2^(s-1) at s = 16..19, both signs (a2 = 3 2^(s-10)) */
    static const int16_t gl[] = {-32768, 32767, 28672, -28672, 1,    -1,    192,   -192,
                                 384,    -384,  768,   -768,   1536, -1536};
    uint8_t i, j;
    for (i = 0u; i < (uint8_t)(sizeof dl / sizeof dl[0]); i++) {
        for (j = 17u; j <= 47u; j = (uint8_t)(j + 10u)) {
            ac_temp_lag f;
            int16_t out = 0, temp = (int16_t)((i & 1u) ? 100 : -100);
            TAG("VTE_L");
            h8(j);
            st(ac_temp_lag_init(&f, (uint16_t)(40000u + 977u * i), j));
            f.started = 1u;
            f.y = (int32_t)((int32_t)temp * (int32_t)65536 - dl[i]); /* |temp| = 100: no overflow */
            st(ac_temp_lag_step(&f, temp, &out));
            h16(out);
            h32(f.y);
            nl();
        }
    }
    /* e32 = gc dTg at E32 = 28672 * 8192 + 4095 = 22657 * 10367 and at E32 + 1 = 30720 * 7646, both
     * signs (the largest unclipped and the smallest clipped gain term) */
    for (i = 0u; i < 8u; i++) {
        int16_t x[2] = {1000, -32768}, y[2];
        int16_t gc = (i & 1u) ? (int16_t)30720 : (int16_t)22657;
        int16_t tg = (i & 1u) ? (int16_t)7646 : (int16_t)10367;
        vt_temp.n = 2u;
        vt_temp.frac = 0u;
        vt_temp.t_ref = 0;
        vt_temp.oc[0] = vt_temp.oc[1] = 0;
        vt_temp.o[0] = vt_temp.o[1] = 0;
        vt_temp.gc[0] = vt_temp.gc[1] = (i & 2u) ? (int16_t)-gc : gc;
        if (i & 4u) {
            tg = (int16_t)-tg;
        }
        TAG("VTE_T");
        h16(vt_temp.gc[0]);
        h16(tg);
        st(ac_temp_correct(&vt_temp, 0, tg, x, y));
        h16(y[0]);
        h16(y[1]);
        nl();
    }
    for (i = 0u; i < (uint8_t)(sizeof gl / sizeof gl[0]); i++) {
        int16_t x[4] = {0, -32768, 32767, -1}, y[4];
        if (i >= 6u) {
            x[1] = 4096; /* channels 1 and 3: a3 = 0, h = a2, g = a2 z 2^-15 exactly */
            x[3] = -4096;
        }
        vt_nl.n = 4u;
        vt_nl.iterations = 0u;
        for (j = 0u; j < 4u; j++) {
            vt_nl.a2[j] = gl[i];
            vt_nl.a3[j] = (int16_t)((j & 1u) ? 0 : gl[(i + 1u) % 6u]);
        }
        for (j = 15u; j <= 30u; j++) { /* every shift the assembly takes (15, 16..19, 20..30) */
            uint8_t k;
            vt_nl.shift = (int8_t)j;
            TAG("VTE_N");
            h8((uint8_t)vt_nl.shift);
            st(ac_nonlin_invert(&vt_nl, x, y));
            for (k = 0u; k < 4u; k++) {
                h16(y[k]);
            }
            nl();
        }
    }
}

/* the nonlinearity with a table's own iteration count (0: the default 3; 1..AC_NONLIN_MAX_ITERATIONS;
 * one beyond it refused), strong bends included (|a2| + |a3| near 32767 at shifts 15..30: the
 * H8/300H runs the C for a count other than 0 and 3, the assembly for those) */
static void vec_nonlin_iterations(void)
{
    uint8_t t, i;
    int16_t x[AC_MAX_CHANNELS], y[AC_MAX_CHANNELS];
    const uint32_t saved = rng; /* the later vectors keep their inputs */
    for (t = 0u; t < 60u; t++) {
        uint16_t n = (uint16_t)(1u + below(AC_MAX_CHANNELS));
        vt_nl.n = n;
        vt_nl.iterations = (uint8_t)below(AC_NONLIN_MAX_ITERATIONS + 2u);
        vt_nl.shift = (int8_t)rnd_range(14, 30);
        for (i = 0u; i < n; i++) {
            int32_t a2 = (int32_t)rnd_range(-32767, 32767);
            int32_t room = 32767L - (a2 < 0 ? -a2 : a2);
            vt_nl.a2[i] = (int16_t)a2;
            vt_nl.a3[i] = (int16_t)rnd_range(-room, room);
            x[i] = vt_i16();
        }
        TAG("VNLK");
        h8(vt_nl.iterations);
        h8((uint8_t)vt_nl.shift);
        st(ac_nonlin_check(&vt_nl));
        st(ac_nonlin_invert(&vt_nl, x, y));
        if ((int)ac_nonlin_check(&vt_nl) == 0) {
            for (i = 0u; i < n; i++) {
                h16(y[i]);
            }
        }
        nl();
    }
    rng = saved;
}

/* ac_temp_correct with output fraction bits (frac 1..AC_TEMP_MAX_OUT_FRAC; one beyond refused):
 * random tables and inputs, a quarter of them with channel 0 at the final rounding's and the
 * clip's edges (vec_temp_run); on the H8/300H the assembly's Q.frac loop */
static void vec_temp_frac(void)
{
    const uint32_t saved = rng; /* the later vectors keep their inputs */
    vec_temp_run(120u, 1u);
    rng = saved;
}

/* the last sum of ac_temp_correct at int32's ends (no random numbers: the later vectors keep theirs):
 * gc = 0 (g = 0), dTo = 1 LSB, channel 0 at x = -32768 with o = -128 (o 2^8 = -2^15), so that
 * w + o 2^8 = -2^31 - oc: exactly INT32_MIN (oc 0), one below (oc 1: the C's sum saturates and
 * flags though w itself is in range) or far below (oc 32767, w clipped before); channel 1 at
 * x = 32767, o = 128, oc = -oc (the top end).  At frac 0 channel 1 stays in range, so the status
 * is channel 0's (a sum of o 2^8 and the rounding's 2^15 before the V test, as the H8/300H
 * assembly does at frac >= 1, drops the flag of oc 1); at frac 1..8 both clip (y = x 2^frac) and
 * the lines hold the clips' directions */
static void vec_temp_sum_edges(void)
{
    static const int16_t ocs[3] = {0, 1, 32767};
    int16_t x[2], y[2];
    uint8_t k, j;
    vt_temp.n = 2u;
    vt_temp.t_ref = 0;
    vt_temp.gc[0] = 0;
    vt_temp.gc[1] = 0;
    vt_temp.o[0] = -128;
    vt_temp.o[1] = 128;
    for (k = 0u; k <= (uint8_t)AC_TEMP_MAX_OUT_FRAC; k++) {
        for (j = 0u; j < 3u; j++) {
            vt_temp.frac = k;
            vt_temp.oc[0] = ocs[j];
            vt_temp.oc[1] = (int16_t)-ocs[j];
            x[0] = INT16_MIN;
            x[1] = INT16_MAX;
            TAG("VTS");
            h8(k);
            h16(vt_temp.oc[0]);
            st(ac_temp_correct(&vt_temp, 1, 0, x, y));
            h16(y[0]);
            h16(y[1]);
            nl();
        }
    }
}

static VEC_STEP void vec_terms(void)
{
    vec_temp_lag();
    vec_temp_correct();
    vec_skew();
    vec_nonlin();
    vec_terms_edges();
    vec_nonlin_iterations();
    vec_temp_frac();
    vec_temp_sum_edges();
}
