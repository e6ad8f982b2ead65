/*
 * accelcal -- the public ac_invert.h functions other than ac_resolver_build:
 * the channel rows and the 6x6 inverse, over the build's own arithmetic
 * (ac_invert_core.h), so that they test exactly what the build runs.
 */
#include "ac_invert_core.h"

#define XF_BAD (-32767 - 1) /* the invalid exponent of ac_xf.h */

static ac_status row_out(const ac_channel_cal *cal, ac_xf row[6], unsigned first)
{
    ac_xf v[15];
    unsigned j;
    if (cal == 0 || row == 0) {
        return AC_ERR_NULL;
    }
    ac_inv_rows(cal, v);
    for (j = 0u; j < 6u; j++) {
        row[j] = v[first + j];
    }
    return AC_OK;
}

ac_status ac_sensor_row(const ac_channel_cal *cal, ac_xf row[6])
{
    return row_out(cal, row, 0u);
}

ac_status ac_centripetal_row(const ac_channel_cal *cal, ac_xf row[6])
{
    return row_out(cal, row, 9u);
}

ac_status ac_invert6(ac_xf a[6][6], int8_t perm[6], int16_t *cond_log2)
{
    int32_t sh = AC_INV_EMIN;
    int16_t cl2 = 0;
    unsigned i, j;
    ac_status st;
    if (a == 0 || perm == 0) {
        return AC_ERR_NULL;
    }
    /* normalise the caller's values (any form) and find the largest exponent */
    for (i = 0u; i < 6u; i++) {
        for (j = 0u; j < 6u; j++) {
            ac_xf *v = &a[i][j];
            if (v->e == XF_BAD || (v->m != 0 && v->e > AC_INV_EMAX)) {
                return AC_ERR_RANGE;
            }
            ac_inv_scale(v, 0);
            if (v->m != 0 && v->e > sh) {
                sh = v->e;
            }
        }
    }
    /* A 2^-sh has its largest entry in [1/2, 1); its inverse is A^-1 2^sh */
    sh += 30;
    for (i = 0u; i < 6u; i++) {
        for (j = 0u; j < 6u; j++) {
            ac_inv_scale(&a[i][j], -sh);
        }
    }
    st = ac_inv_gauss_jordan(a, perm, &cl2);
    if (st == AC_ERR_SINGULAR) {
        return st;
    }
    if (cond_log2 != 0) {
        *cond_log2 = cl2;
    }
    for (i = 0u; i < 6u; i++) {
        for (j = 0u; j < 6u; j++) {
            if (a[i][j].m != 0 && a[i][j].e - sh > AC_INV_EMAX) {
                return AC_ERR_RANGE;
            }
            ac_inv_scale(&a[i][j], -sh);
        }
    }
    return st;
}
