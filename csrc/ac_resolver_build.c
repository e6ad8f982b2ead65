/*
 * accelcal -- on-device build of the resolver table, ac_resolver_build (see
 * ac_invert.h): equilibrated normal equations of the channel rows (ac_invert_rows.c)
 * inverted by the build's soft-float (ac_invert.c, ac_invert_core.h).  Firmware that
 * calls it links ac_resolver_build.o, ac_invert_rows.o, ac_invert.o and the exact
 * 32 x 32 multiply of ac_ops64.o.
 * Memory: the caller's ac_build_work; the columns of M are recomputed in a
 * second pass rather than stored, so N = 12 needs no more RAM than N = 6.
 */
#include "ac_invert_core.h"

typedef ac_xf xf;

static void axpy(xf *y, const xf *alpha, const xf *x)
{
    unsigned j;
    for (j = 0u; j < 6u; j++) {
        ac_inv_mac(&y[j], alpha, &x[j], 0u);
    }
}

/* |a| > |b| */
/* ---- the table build ---------------------------------------------------------------- */

static const int16_t no_exp[6] = {0, 0, 0, 0, 0, 0};

/* a_jl *= 2^(off - re_j - ce_l) with re = ce = colexp for N > 6; for N = 6
 * re = 0 when off == 0 (R~ = R 2^-colexp), ce = 0 otherwise (M = 2^(off - colexp) R~^-1) */
static void rescale(ac_build_work *w, uint16_t n, int16_t off)
{
    const int16_t *re = w->colexp, *ce = w->colexp;
    unsigned j, l;
    if (n == 6u) {
        if (off != 0) {
            ce = no_exp;
        } else {
            re = no_exp;
        }
    }
    for (j = 0u; j < 6u; j++) {
        for (l = 0u; l < 6u; l++) {
            ac_inv_scale(&w->a[j][l], (int32_t)off - re[j] - ce[l]);
        }
    }
}

ac_status ac_resolver_build(const ac_channel_cal *cal, uint16_t n, ac_build_work *w,
                            ac_resolver *out, ac_build_info *info)
{
    xf v[15], e[6], c, o;
    int8_t m_shift[6], g_shift[6];
    int32_t k[6];
    int16_t cl2 = 0;
    uint16_t i;
    unsigned j, l, pass;
    ac_status st;

    if (cal == 0 || w == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    if (n < 6u || n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    ac_inv_clear(w, sizeof *w);
    ac_inv_clear(e, sizeof e);

    /* Three passes over the channels, with u = R_i for N > 6 and u = e_i for N = 6:
     *  0: a = R (N = 6) or R^T R (N > 6), as a_j += u_j R_i; column maxima of R;
     *  1: after the inverse, M_ji = (a^-1 u)_j scaled (rescale): the row scales,
     *     M o and M C;
     *  2: with the shifts known, the table. */
    for (pass = 0u; pass < 3u; pass++) {
        if (pass == 1u) {
            /* equilibrate the columns of R by powers of two (exactly) */
            for (j = 0u; j < 6u; j++) {
                xf *r = w->acc[j];
                if (r[7].m == 0) {
                    return AC_ERR_SINGULAR; /* nothing senses this degree of freedom */
                }
                w->colexp[j] = (int16_t)(r[7].e + 30);
                ac_inv_clear(&r[7], 2u * sizeof *r);
            }
            rescale(w, n, 0);
            st = ac_inv_gauss_jordan(w->a, w->perm, &cl2);
            if (info != 0) {
                info->cond_log2 = cl2;
            }
            if (st != AC_OK) {
                return st;
            }
            rescale(w, n, AC_OUT_FRAC);
        }
        if (pass == 2u) {
            /* shifts and offset terms: every failure is found before out is touched */
            for (j = 0u; j < 6u; j++) {
                xf *r = w->acc[j], gm[2];
                int16_t ms, gs;
                ac_inv_clear(gm, sizeof gm);
                for (l = 0u; l < 6u; l++) {
                    ac_inv_acc_abs(&gm[0], &gm[1], &r[l]);
                }
                ms = ac_inv_row_shift(&r[7], n);
                gs = ac_inv_row_shift(gm, 6u);
                if (ms < -31 || gs < -31 || ac_inv_to_fixed(&r[6], ms, &k[j]) != 0u) {
                    return AC_ERR_RANGE;
                }
                m_shift[j] = (int8_t)ms;
                g_shift[j] = (int8_t)gs;
            }
            ac_inv_clear(out->m, sizeof out->m);
            out->n = n;
            out->raw_min = 0u; /* the rails are the converter's: unknown here (ac_resolve.h) */
            out->raw_max = 0u;
        }
        for (i = 0u; i < n; i++) {
            const xf *u = v;
            ac_inv_rows(&cal[i], v);
            if (n == 6u) {
                e[i].m = (int32_t)AC_INV_XF_LO; /* 1 */
                e[i].e = -29;
                u = e;
            }
            ac_inv_from_fixed(&o, cal[i].offset, AC_OFFSET_FRAC);
            for (j = 0u; j < 6u; j++) {
                xf *r = w->acc[j], *aj = w->a[j];
                if (pass == 0u) {
                    ac_inv_acc_abs(&r[7], &r[8], &v[j]);
                    axpy(aj, &u[j], v);
                    continue;
                }
                ac_inv_clear(&c, sizeof c);
                for (l = 0u; l < 6u; l++) {
                    ac_inv_mac(&c, &aj[l], &u[l], 0u);
                }
                if (pass == 1u) {
                    ac_inv_acc_abs(&r[7], &r[8], &c);
                    ac_inv_mac(&r[6], &c, &o, 0u);
                    axpy(r, &c, &v[9]);
                } else {
                    out->m[j][i] = ac_inv_to_i16(&c, m_shift[j]);
                    out->m_shift[j] = m_shift[j];
                    out->g_shift[j] = g_shift[j];
                    out->k[j] = k[j];
                    for (l = 0u; l < 6u; l++) {
                        out->g[j][l] = ac_inv_to_i16(&r[l], g_shift[j]);
                    }
                }
            }
            ac_inv_clear(e, sizeof e);
        }
    }
    return AC_OK;
}
