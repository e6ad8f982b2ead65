/*
 * accelcal -- target 15 of fuzz/fuzz_core.c (included by it): the array's own omega
 * (ac_omega.h).
 *
 * Mode byte: bit 0 the vectors' table (tests/c/vectors_omega_data.h, the r = 50 mm
 * tetrahedron's), else every field from the input; bit 1 a few of its fields replaced from the
 * input; bit 2 the vectors' readings plus an input offset (else input and edge values; with a
 * random table: wide exponents); bit 3 omega_q10 and flags NULL; bits 4-7 the steps - 1 (1..16).
 * Properties:
 *   - ac_omega_check equals the documented rules (n, shifts, row sums, normalised ac_xf);
 *   - init and step fail with check's status on a bad table, writing nothing; a step's
 *     AC_ERR_RANGE leaves the state and the outputs unwritten;
 *   - on success the state stays normalised, the flags are AC_OMEGA_FLAG_* with JUMP only
 *     with ML, omega_q10 is omega_q16 / 64 within 1 LSB or clipped (SAT16 exactly then),
 *     AC_SATURATED exactly when an output clipped;
 *   - a step is a function of (state, x): a copy of the state gives the same outputs;
 *   - sigma >= 0; NULL arguments give AC_ERR_NULL.
 */

/* the r = 50 mm tetrahedron's table and readings of the vectors (written by
 * tests/python/omega_vectors_gen.py) */
#ifndef AC_ROM
#define AC_ROM
#endif
#include "../tests/c/vectors_omega_data.h"

#define OM_XF_BAD (-32767 - 1) /* ac_xf_core.h's AC_XF_BAD */

static void om_xf_slots(ac_omega_table *t, ac_xf **dst) /* VO_NXF slots, the vectors' order */
{
    uint16_t i, k = 0u;
    for (i = 0u; i < 9u; i++) {
        dst[k++] = &t->k[i];
    }
    for (i = 0u; i < 21u; i++) {
        dst[k++] = &t->m[i];
    }
    for (i = 0u; i < 21u; i++) {
        dst[k++] = &t->minv[i];
    }
    for (i = 0u; i < 18u; i++) {
        dst[k++] = &t->leak[i / 6u][i % 6u];
    }
    for (i = 0u; i < 6u; i++) {
        dst[k++] = &t->qn[i];
    }
    for (i = 0u; i < 6u; i++) {
        dst[k++] = &t->p0[i];
    }
    dst[k++] = &t->dt;
    dst[k++] = &t->half_dt;
    dst[k++] = &t->jump;
    dst[k++] = &t->ridge;
}

static void om_vectors_table(ac_omega_table *t)
{
    ac_xf *dst[VO_NXF];
    uint16_t i, j;
    memset(t, 0, sizeof *t);
    t->n = (uint16_t)VO_N;
    for (j = 0u; j < 9u; j++) {
        t->shift[j] = vo_shift[j];
        for (i = 0u; i < VO_N; i++) {
            t->t[j][i] = vo_t[j * VO_N + i];
            t->tl[j][i] = vo_tl[j * VO_N + i];
        }
    }
    om_xf_slots(t, dst);
    for (i = 0u; i < VO_NXF; i++) {
        dst[i]->m = vo_xm[i];
        dst[i]->e = vo_xe[i];
    }
}

/* ac_omega_check's documented rules, independently */
static ac_status om_check_ref(const ac_omega_table *t)
{
    ac_xf *dst[VO_NXF];
    uint16_t i, j;
    if (t->n < 6u || t->n > AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    for (j = 0u; j < 9u; j++) {
        long sum = 0, suml = 0;
        if (t->shift[j] < -31 || t->shift[j] > 31) {
            return AC_ERR_FORMAT;
        }
        for (i = 0u; i < t->n; i++) {
            sum += labs((long)t->t[j][i]);
            suml += labs((long)t->tl[j][i]);
        }
        if (sum > 65535L || suml > 65535L) {
            return AC_ERR_FORMAT;
        }
    }
    om_xf_slots((ac_omega_table *)t, dst);
    for (i = 0u; i < VO_NXF; i++) {
        if (dst[i]->e == OM_XF_BAD || !xf_normal(*dst[i])) {
            return AC_ERR_RANGE;
        }
    }
    return AC_OK;
}

static int om_state_normal(const ac_omega_state *s)
{
    uint8_t i;
    for (i = 0u; i < 3u; i++) {
        if (!xf_normal(s->w[i]) || s->w[i].e == OM_XF_BAD || !xf_normal(s->a_prev[i]) ||
            s->a_prev[i].e == OM_XF_BAD) {
            return 0;
        }
    }
    for (i = 0u; i < 6u; i++) {
        if (!xf_normal(s->p[i]) || s->p[i].e == OM_XF_BAD) {
            return 0;
        }
    }
    return 1;
}

/* mode: bit 0 the vectors' table (else every field from the input), bit 1 a few
 * of its fields replaced from the input, bit 2 the readings are the vectors'
 * plus an input offset (else input / edge values), bit 3 omega_q10 and flags
 * NULL, bits 4-7 the number of steps - 1 (1..16).
 * Properties: ac_omega_check == the documented rules; init and step fail with
 * check's status on a bad table and leave the state and outputs unwritten; on a
 * step error (AC_ERR_RANGE) the same; on success the state stays normalised,
 * flags within AC_OMEGA_FLAG_*, JUMP only with ML, omega_q10 = omega_q16
 * rescaled within 1 LSB and SAT16 only at the clip, AC_SATURATED exactly when
 * an output clipped; the step is a function of (state, x): a copy of the state
 * gives the same outputs; sigma >= 0; NULL arguments give AC_ERR_NULL. */
static void target_omega(rd *r)
{
    ac_omega_table *t = xmalloc(sizeof *t);
    ac_omega_state st, st2, before;
    uint8_t mode = rd_u8(r);
    uint8_t steps = (uint8_t)(1u + (mode >> 4));
    int nulls = (mode & 8u) != 0u;
    ac_status cs, is;
    int16_t x[AC_MAX_CHANNELS];
    uint8_t k, i;
    uint16_t vo_rows = 0u;
    for (k = 0u; k < VO_NSTRETCH; k++) {
        vo_rows = (uint16_t)(vo_rows + vo_len[k]);
    }
    if (mode & 1u) {
        om_vectors_table(t);
        if (mode & 2u) {
            ac_xf *dst[VO_NXF];
            uint8_t nrep = (uint8_t)(rd_u8(r) % 4u);
            om_xf_slots(t, dst);
            for (k = 0u; k < nrep; k++) {
                uint8_t what = rd_u8(r);
                if (what & 0x80u) {
                    t->t[(what >> 4) % 9u][what % VO_N] = rd_i16_edge(r);
                } else if (what & 0x40u) {
                    t->shift[what % 9u] = rd_i8(r);
                } else {
                    *dst[what % VO_NXF] = (what & 0x20u) ? rd_xf_raw(r) : rd_xf(r, 0);
                }
            }
        }
    } else {
        ac_xf *dst[VO_NXF];
        memset(t, 0, sizeof *t);
        t->n = (uint16_t)(rd_u8(r) % (AC_MAX_CHANNELS + 3u));
        for (k = 0u; k < 9u; k++) {
            t->shift[k] = (int8_t)((int8_t)rd_u8(r) % 40);
            for (i = 0u; i < AC_MAX_CHANNELS; i++) {
                t->t[k][i] = (int16_t)(rd_i16(r) / 8);
                t->tl[k][i] = (int16_t)(rd_i16(r) / 8);
            }
        }
        om_xf_slots(t, dst);
        for (k = 0u; k < VO_NXF; k++) {
            *dst[k] = rd_xf(r, 0);
            /* exponents near the table's own (a few powers of two around 2^-30), else wide */
            if ((mode & 4u) == 0u && dst[k]->m != 0) {
                dst[k]->e = (int16_t)(-60 + (dst[k]->e % 60));
            }
        }
    }
    cs = ac_omega_check(t);
    CHECK_STATUS(cs);
    CHECK(cs == om_check_ref(t), "ac_omega_check %d, the documented rules %d", (int)cs, (int)om_check_ref(t));
    fill_sentinel(&st, sizeof st);
    is = ac_omega_init(&st, t);
    CHECK(is == cs, "ac_omega_init %d, check %d", (int)is, (int)cs);
    CHECK(ac_omega_init(0, t) == AC_ERR_NULL && ac_omega_init(&st2, 0) == AC_ERR_NULL, "init NULL");
    if (is != AC_OK) {
        int32_t w[3];
        CHECK(is_sentinel(&st, sizeof st), "ac_omega_init wrote the state on error %d", (int)is);
        memset(x, 0, sizeof x);
        fill_sentinel(w, sizeof w);
        fill_sentinel(&st, sizeof st);
        CHECK(ac_omega_step(&st, t, x, w, 0, 0) == cs, "ac_omega_step on a bad table: not check's status");
        CHECK(is_sentinel(w, sizeof w) && is_sentinel(&st, sizeof st), "ac_omega_step wrote on a bad table");
        free(t);
        return;
    }
    CHECK(om_state_normal(&st), "ac_omega_init: state not normalised");
    for (k = 0u; k < steps; k++) {
        int32_t w[3], w2[3], sg[3];
        int16_t w10[3], w10b[3];
        uint8_t fl, fl2;
        ac_status s, s2, ss;
        int16_t off = (int16_t)(rd_i16(r) % 4096);
        for (i = 0u; i < AC_MAX_CHANNELS; i++) {
            if ((mode & 4u) && (mode & 1u) && i < VO_N) {
                uint16_t row = (uint16_t)((k + (uint16_t)(mode >> 4) * 3u) % vo_rows);
                x[i] = (int16_t)(vo_x[row * VO_N + i] + ((i % 3u) == (k % 3u) ? off : 0));
            } else {
                x[i] = rd_i16_edge(r);
            }
        }
        before = st;
        st2 = st;
        fill_sentinel(w, sizeof w);
        fill_sentinel(w10, sizeof w10);
        fill_sentinel(&fl, sizeof fl);
        s = ac_omega_step(&st, t, x, w, nulls ? 0 : w10, nulls ? 0 : &fl);
        CHECK_STATUS(s);
        CHECK(s == AC_OK || s == AC_SATURATED || s == AC_ERR_RANGE, "ac_omega_step status %d", (int)s);
        if (s < 0) {
            CHECK(memcmp(&st, &before, sizeof st) == 0, "ac_omega_step changed the state on error %d", (int)s);
            CHECK(is_sentinel(w, sizeof w) && is_sentinel(w10, sizeof w10) && is_sentinel(&fl, 1),
                  "ac_omega_step wrote its outputs on error %d", (int)s);
            break;
        }
        CHECK(om_state_normal(&st), "ac_omega_step: state not normalised (step %u)", (unsigned)k);
        s2 = ac_omega_step(&st2, t, x, w2, w10b, &fl2);
        CHECK(memcmp(&st, &st2, sizeof st) == 0 && memcmp(w, w2, sizeof w) == 0,
              "ac_omega_step is not a function of (state, x)");
        if (!nulls) {
            CHECK(fl == fl2 && memcmp(w10, w10b, sizeof w10) == 0, "ac_omega_step: q10 / flags differ on a replay");
        }
        CHECK((fl2 & ~7u) == 0u && (!(fl2 & AC_OMEGA_FLAG_JUMP) || (fl2 & AC_OMEGA_FLAG_ML)),
              "ac_omega_step flags 0x%02x", (unsigned)fl2);
        {
            int q16sat = 0, q10sat = 0;
            for (i = 0u; i < 3u; i++) {
                i128 r10 = floor_div_p2((i128)w2[i] + 32, 6); /* q16 rescaled to Q.10 */
                int edge16 = w2[i] == INT32_MAX || w2[i] == INT32_MIN;
                int clip = w10b[i] == 32767 || w10b[i] == -32768;
                if (edge16) {
                    q16sat = 1; /* clipped, or exactly at the edge: allowed either way below */
                }
                if (r10 > 32767 + 1 || r10 < -32768 - 1) {
                    CHECK(clip && ((r10 > 0) == (w10b[i] > 0)) && (fl2 & AC_OMEGA_FLAG_SAT16),
                          "omega_q10 %d does not clip q16 %ld", (int)w10b[i], (long)w2[i]);
                } else if (r10 <= 32767 - 1 && r10 >= -32768 + 1) {
                    CHECK(abs128(r10 - w10b[i]) <= 1, "omega_q10 %d vs q16 %ld / 64", (int)w10b[i], (long)w2[i]);
                }
                if (clip && (fl2 & AC_OMEGA_FLAG_SAT16)) {
                    q10sat = 1;
                }
            }
            CHECK(!(fl2 & AC_OMEGA_FLAG_SAT16) || q10sat, "SAT16 without a clipped omega_q10");
            CHECK(s2 == AC_SATURATED || !q10sat, "omega_q10 clipped, status %d", (int)s2);
            CHECK(s2 == AC_OK || q10sat || q16sat, "AC_SATURATED with no clipped output");
            if (nulls) {
                /* without omega_q10 its clip is no saturation */
                CHECK(s == AC_OK || q16sat, "AC_SATURATED from the Q5.10 clip without omega_q10");
            }
        }
        fill_sentinel(sg, sizeof sg);
        ss = ac_omega_sigma(&st, sg);
        CHECK(ss == AC_OK || ss == AC_SATURATED || ss == AC_ERR_RANGE, "ac_omega_sigma status %d", (int)ss);
        if (ss >= 0) {
            CHECK(sg[0] >= 0 && sg[1] >= 0 && sg[2] >= 0, "sigma < 0: %ld %ld %ld", (long)sg[0], (long)sg[1],
                  (long)sg[2]);
        } else {
            CHECK(is_sentinel(sg, sizeof sg), "ac_omega_sigma wrote on error");
        }
    }
    {
        int32_t w[3], sg[3];
        CHECK(ac_omega_step(0, t, x, w, 0, 0) == AC_ERR_NULL && ac_omega_step(&st, 0, x, w, 0, 0) == AC_ERR_NULL &&
                  ac_omega_step(&st, t, 0, w, 0, 0) == AC_ERR_NULL && ac_omega_step(&st, t, x, 0, 0, 0) == AC_ERR_NULL,
              "ac_omega_step NULL");
        CHECK(ac_omega_sigma(0, sg) == AC_ERR_NULL && ac_omega_sigma(&st, 0) == AC_ERR_NULL, "ac_omega_sigma NULL");
    }
    free(t);
}
