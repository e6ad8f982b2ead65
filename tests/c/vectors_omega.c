/*
 * accelcal -- test vectors of the array's own omega (ac_omega.h).  Included by
 * tests/c/vectors.c (its output and pseudo-random helpers), so every build of the
 * vector program (host, AVR, H8/300H) runs them unchanged.
 *
 * The table and the readings are the r = 50 mm tetrahedron's
 * (tests/c/vectors_omega_data.h, written by tests/python/omega_vectors_gen.py):
 * a start at rest, a start mid-turn (the jump test), a stretch past 32 rad/s
 * (the Q5.10 output clips), then random and extreme readings, and the errors.
 */
#include "vectors_omega_data.h"

/* The table (about 1 KB with AC_MAX_CHANNELS 12) and the state live on vec_omega's stack,
 * not in static RAM: ac_omega needs more RAM than a 2 KB part has (the table, its state and
 * some 0.9 KB of stack in ac_omega_step), so the AVR run exercises it on the simulated
 * ATmega1284P's 16 KB; run_avr_tests.sh's 2 KB check is of the static RAM only. */
#define vo_tab (*vo_tabp)
#define vo_st (*vo_stp)
static ac_omega_table *vo_tabp;
static ac_omega_state *vo_stp;

static void vo_load(void)
{
    uint16_t i, j, k = 0u;
    ac_xf *dst[VO_NXF];
    vo_tab.n = (uint16_t)VO_N;
    for (j = 0u; j < 9u; j++) {
        vo_tab.shift[j] = (int8_t)AC_ROM_U8(&vo_shift[j]);
        for (i = 0u; i < AC_MAX_CHANNELS; i++) {
            vo_tab.t[j][i] = (i < VO_N) ? (int16_t)AC_ROM_U16(&vo_t[j * VO_N + i]) : (int16_t)0;
            vo_tab.tl[j][i] = (i < VO_N) ? (int16_t)AC_ROM_U16(&vo_tl[j * VO_N + i]) : (int16_t)0;
        }
    }
    for (i = 0u; i < 9u; i++) {
        dst[k++] = &vo_tab.k[i];
    }
    for (i = 0u; i < 21u; i++) {
        dst[k++] = &vo_tab.m[i];
    }
    for (i = 0u; i < 21u; i++) {
        dst[k++] = &vo_tab.minv[i];
    }
    for (i = 0u; i < 18u; i++) {
        dst[k++] = &vo_tab.leak[i / 6u][i % 6u];
    }
    for (i = 0u; i < 6u; i++) {
        dst[k++] = &vo_tab.qn[i];
    }
    for (i = 0u; i < 6u; i++) {
        dst[k++] = &vo_tab.p0[i];
    }
    dst[k++] = &vo_tab.dt;
    dst[k++] = &vo_tab.half_dt;
    dst[k++] = &vo_tab.jump;
    dst[k++] = &vo_tab.ridge;
    for (i = 0u; i < k; i++) {
        dst[i]->m = (int32_t)AC_ROM_U32(&vo_xm[i]);
        dst[i]->e = (int16_t)AC_ROM_U16(&vo_xe[i]);
    }
}

static void vo_step(const int16_t *x)
{
    int32_t w[3], sg[3];
    int16_t w10[3];
    uint8_t fl = 0u, a;
    TAG("VOM");
    st(ac_omega_step(&vo_st, &vo_tab, x, w, w10, &fl));
    h8(fl);
    for (a = 0u; a < 3u; a++) {
        h32(w[a]);
        h16(w10[a]);
    }
    st(ac_omega_sigma(&vo_st, sg));
    for (a = 0u; a < 3u; a++) {
        h32(sg[a]);
    }
    nl();
}

static VEC_STEP void vec_omega(void)
{
    ac_omega_table tab;
    ac_omega_state state;
    int16_t x[AC_MAX_CHANNELS];
    int32_t w[3];
    uint16_t s, k, i, row = 0u;
    vo_tabp = &tab;
    vo_stp = &state;
    vo_load();
    TAG("VOC");
    st(ac_omega_check(&vo_tab));
    nl();
    for (s = 0u; s < VO_NSTRETCH; s++) {
        uint8_t len = AC_ROM_U8(&vo_len[s]);
        TAG("VOS");
        st(ac_omega_init(&vo_st, &vo_tab));
        nl();
        for (k = 0u; k < len; k++) {
            for (i = 0u; i < VO_N; i++) {
                x[i] = (int16_t)AC_ROM_U16(&vo_x[(row + k) * VO_N + i]);
            }
            vo_step(x);
        }
        /* random readings after the stretch (the state far from them), and the int16 extremes */
        for (k = 0u; k < 6u; k++) {
            for (i = 0u; i < VO_N; i++) {
                uint8_t kind = (uint8_t)(rnd() & 3UL);
                x[i] = (kind == 0u) ? (int16_t)((rnd() & 1UL) ? 32767 : (-32767 - 1)) : rnd_i16();
            }
            vo_step(x);
        }
        row = (uint16_t)(row + len);
    }
    /* errors: NULLs, sizes, shifts, row sums, an unnormalised or invalid ac_xf, singular P0 */
    TAG("VOE");
    st(ac_omega_init(0, &vo_tab));
    st(ac_omega_step(&vo_st, &vo_tab, 0, w, 0, 0));
    st(ac_omega_sigma(&vo_st, 0));
    vo_tab.n = 5u;
    st(ac_omega_check(&vo_tab));
    vo_tab.n = (uint16_t)(AC_MAX_CHANNELS + 1u);
    st(ac_omega_check(&vo_tab));
    vo_tab.n = (uint16_t)VO_N;
    vo_tab.shift[3] = 32;
    st(ac_omega_check(&vo_tab));
    vo_tab.shift[3] = (int8_t)AC_ROM_U8(&vo_shift[3]);
    vo_tab.t[2][0] = 32767;
    vo_tab.t[2][1] = 32767;
    vo_tab.t[2][2] = 32767;
    st(ac_omega_check(&vo_tab));
    vo_load();
    vo_tab.m[4].m = 5; /* unnormalised */
    st(ac_omega_check(&vo_tab));
    vo_load();
    vo_tab.jump.e = -32767 - 1; /* the invalid value */
    st(ac_omega_step(&vo_st, &vo_tab, x, w, 0, 0));
    vo_load();
    for (i = 0u; i < 6u; i++) {
        vo_tab.p0[i].m = 0;
        vo_tab.p0[i].e = 0;
    }
    st(ac_omega_init(&vo_st, &vo_tab));
    st(ac_omega_step(&vo_st, &vo_tab, x, w, 0, 0));
    nl();
}
