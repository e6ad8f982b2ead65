/*
 * accelcal -- on-device build of one 3-axis sensor's table, ac_triad_build (see
 * ac_invert.h): S^-1 by the build's soft-float and 6x6 inverse (ac_invert.c,
 * ac_invert_core.h) on [[S, 0], [0, I]].  Firmware that calls it links
 * ac_triad_build.o and ac_invert.o only (not the 6-DOF build's channel rows and
 * table code).
 */
#include "ac_invert_core.h"

typedef ac_xf xf;

/* ---- one triad (f only) ------------------------------------------------------------- */

ac_status ac_triad_build(const ac_channel_cal *cal, const uint16_t *trim, ac_build_work *w, ac_triad *out)
{
    xf o, c, mm[2];
    int8_t shift[3];
    int32_t k[3];
    int16_t cl2 = 0;
    unsigned i, j, l;
    ac_status st;
    if (cal == 0 || trim == 0 || w == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    ac_inv_clear(w, sizeof *w);
    /* a = [[S, 0], [0, I]] (S's rows the s_i), S's columns equilibrated by powers of two */
    for (i = 0u; i < 3u; i++) {
        for (l = 0u; l < 3u; l++) {
            ac_inv_from_fixed(&w->a[i][l], cal[i].sens[l], AC_SENS_FRAC);
            ac_inv_acc_abs(&w->acc[l][7], &w->acc[l][8], &w->a[i][l]);
        }
    }
    for (l = 0u; l < 3u; l++) {
        if (w->acc[l][7].m == 0) {
            return AC_ERR_SINGULAR;
        }
        w->colexp[l] = (int16_t)(w->acc[l][7].e + 30);
        w->a[3u + l][3u + l] = ac_inv_one;
        for (i = 0u; i < 3u; i++) {
            ac_inv_scale(&w->a[i][l], -(int32_t)w->colexp[l]);
        }
    }
    st = ac_inv_gauss_jordan(w->a, w->perm, &cl2);
    if (st != AC_OK) {
        return st;
    }
    /* M = S^-1 in output LSB per count: row j of the inverse times 2^(AC_OUT_FRAC - colexp_j);
     * its shift by the host quantizer's rule, k = round((M o) 2^shift) */
    for (j = 0u; j < 3u; j++) {
        int16_t s;
        ac_inv_clear(mm, sizeof mm);
        ac_inv_clear(&c, sizeof c);
        for (l = 0u; l < 3u; l++) {
            ac_inv_scale(&w->a[j][l], (int32_t)AC_OUT_FRAC - w->colexp[j]);
            ac_inv_acc_abs(&mm[0], &mm[1], &w->a[j][l]);
            ac_inv_from_fixed(&o, cal[l].offset, AC_OFFSET_FRAC);
            ac_inv_mac(&c, &w->a[j][l], &o, 0u);
        }
        s = ac_inv_row_shift(mm, 3u);
        if (s < -31 || ac_inv_to_fixed(&c, s, &k[j]) != 0u) {
            return AC_ERR_RANGE;
        }
        shift[j] = (int8_t)s;
    }
    out->raw_min = 0u; /* the rails are the converter's: unknown here (ac_attitude.h) */
    out->raw_max = 0u;
    for (j = 0u; j < 3u; j++) {
        out->trim[j] = trim[j];
        out->shift[j] = shift[j];
        out->k[j] = k[j];
        for (l = 0u; l < 3u; l++) {
            out->m[j][l] = ac_inv_to_i16(&w->a[j][l], shift[j]);
        }
    }
    return AC_OK;
}
