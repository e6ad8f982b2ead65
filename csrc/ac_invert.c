/*
 * accelcal -- on-device build of the resolver table (see ac_invert.h).
 *
 * Everything here runs in ac_xf (29-bit mantissa, wide exponent), so column
 * scales (counts per m/s^2 against counts per rad/s^2) cost no precision.  It
 * uses the pointer-based core (ac_xf_core.h) with a sticky invalid value,
 * checked where results leave the xf domain.  Memory: the caller's
 * ac_build_work; the columns of M are recomputed in a second pass rather than
 * stored, so N = 12 needs no more RAM than N = 6.
 */
#include "accelcal/ac_invert.h"
#include "ac_xf_core.h"
#include "ac_internal.h"

#define PIVOT_TOL_LOG2 (-26)
#define COEF_MAX 32767L
#define ROW_L1_MAX 65535L

static const ac_xf xf_zero = {0, 0};
static const ac_xf xf_one = {0x20000000L, -29};

static ac_status valid(const ac_xf *v, uint8_t count)
{
    while (count-- != 0u) {
        if (v[count].e == AC_XF_BAD) {
            return AC_ERR_RANGE;
        }
    }
    return AC_OK;
}

static void load_channel(const ac_channel_cal *cal, ac_xf s[3], ac_xf r[3])
{
    uint8_t a;
    for (a = 0u; a < 3u; a++) {
        ac_xfp_from_fixed(&s[a], cal->sens[a], AC_SENS_FRAC);
        ac_xfp_from_fixed(&r[a], cal->pos[a], AC_POS_FRAC);
    }
}

ac_status ac_sensor_row(const ac_channel_cal *cal, ac_xf row[6])
{
    ac_xf s[3], r[3], t;
    uint8_t a;
    if (cal == 0 || row == 0) {
        return AC_ERR_NULL;
    }
    load_channel(cal, s, r);
    for (a = 0u; a < 3u; a++) {
        /* r x s: the channel's response to angular acceleration */
        uint8_t b = (uint8_t)((a + 1u) % 3u), c = (uint8_t)((a + 2u) % 3u);
        row[a] = s[a];
        ac_xfp_mul(&row[3u + a], &r[b], &s[c]);
        ac_xfp_mul(&t, &r[c], &s[b]);
        ac_xfp_sub(&row[3u + a], &row[3u + a], &t);
    }
    return valid(row, 6u);
}

ac_status ac_centripetal_row(const ac_channel_cal *cal, ac_xf row[6])
{
    /* s.(w (w.r) - r |w|^2) over p = (wx^2, wy^2, wz^2, wx wy, wy wz, wz wx) */
    ac_xf s[3], r[3], sr = xf_zero, t;
    uint8_t a;
    if (cal == 0 || row == 0) {
        return AC_ERR_NULL;
    }
    load_channel(cal, s, r);
    for (a = 0u; a < 3u; a++) {
        ac_xfp_mac(&sr, &s[a], &r[a]);
    }
    for (a = 0u; a < 3u; a++) {
        uint8_t b = (uint8_t)((a + 1u) % 3u);
        ac_xfp_mul(&row[a], &s[a], &r[a]);
        ac_xfp_sub(&row[a], &row[a], &sr);
        ac_xfp_mul(&row[3u + a], &s[a], &r[b]);
        ac_xfp_mul(&t, &s[b], &r[a]);
        ac_xfp_add(&row[3u + a], &row[3u + a], &t);
    }
    return valid(row, 6u);
}

static void norm1(ac_xf a[6][6], ac_xf *out) /* max column sum of |a| */
{
    uint8_t i, j;
    *out = xf_zero;
    for (j = 0u; j < 6u; j++) {
        ac_xf sum = xf_zero, unused = xf_zero;
        for (i = 0u; i < 6u; i++) {
            ac_xfp_acc_abs(&unused, &sum, &a[i][j]);
        }
        ac_xfp_acc_abs(out, 0, &sum);
    }
}

static void swap_xf(ac_xf *a, ac_xf *b)
{
    ac_xf t = *a;
    *a = *b;
    *b = t;
}

ac_status ac_invert6(ac_xf a[6][6], int8_t perm[6], int16_t *cond_log2)
{
    ac_xf na, ninv, amax = xf_zero, cond;
    uint8_t i, j, k;
    int16_t cl2;
    if (a == 0 || perm == 0) {
        return AC_ERR_NULL;
    }
    for (i = 0u; i < 6u; i++) {
        for (j = 0u; j < 6u; j++) {
            ac_xfp_normalize(&a[i][j]); /* the caller's values may be in any form */
        }
    }
    norm1(a, &na);
    for (i = 0u; i < 6u; i++) {
        for (j = 0u; j < 6u; j++) {
            ac_xfp_acc_abs(&amax, 0, &a[i][j]);
        }
    }
    if (valid(&amax, 1u) != AC_OK || valid(&na, 1u) != AC_OK) {
        return AC_ERR_RANGE;
    }
    if (amax.m == 0) {
        return AC_ERR_SINGULAR;
    }
    ac_xfp_ldexp(&amax, PIVOT_TOL_LOG2); /* amax is the pivot tolerance from here on */

    for (k = 0u; k < 6u; k++) {
        uint8_t p = k;
        ac_xf inv;
        for (i = (uint8_t)(k + 1u); i < 6u; i++) {
            if (ac_xfp_cmpabs(&a[i][k], &a[p][k]) > 0) {
                p = i;
            }
        }
        if (valid(&a[p][k], 1u) != AC_OK) {
            return AC_ERR_RANGE;
        }
        if (ac_xfp_cmpabs(&a[p][k], &amax) <= 0) {
            return AC_ERR_SINGULAR;
        }
        if (p != k) {
            for (j = 0u; j < 6u; j++) {
                swap_xf(&a[k][j], &a[p][j]);
            }
        }
        perm[k] = (int8_t)p;
        ac_xfp_div(&inv, &xf_one, &a[k][k]);
        a[k][k] = xf_one;
        for (j = 0u; j < 6u; j++) {
            ac_xfp_mul(&a[k][j], &a[k][j], &inv);
        }
        for (i = 0u; i < 6u; i++) {
            ac_xf f;
            if (i == k || a[i][k].m == 0) {
                continue;
            }
            f = a[i][k];
            a[i][k] = xf_zero;
            for (j = 0u; j < 6u; j++) {
                ac_xf t;
                ac_xfp_mul(&t, &f, &a[k][j]);
                ac_xfp_sub(&a[i][j], &a[i][j], &t);
            }
        }
    }
    /* undo the row interchanges as column interchanges, last first */
    for (k = 6u; k-- > 0u;) {
        uint8_t p = (uint8_t)perm[k];
        if (p != k) {
            for (i = 0u; i < 6u; i++) {
                swap_xf(&a[i][k], &a[i][p]);
            }
        }
    }
    norm1(a, &ninv);
    ac_xfp_mul(&cond, &na, &ninv);
    if (valid(&cond, 1u) != AC_OK) {
        return AC_ERR_RANGE;
    }
    /* cond = m 2^e with 2^29 <= m < 2^30 */
    cl2 = (int16_t)(cond.e + ((cond.m == 0x20000000L) ? 29 : 30));
    if (cond_log2 != 0) {
        *cond_log2 = cl2;
    }
    return (cl2 > AC_COND_LOG2_MAX) ? AC_ERR_ILL_COND : AC_OK;
}

/* Row i of R with columns scaled by 2^-colexp (equilibrated). */
static ac_status scaled_row(const ac_channel_cal *cal, const int16_t colexp[6], ac_xf row[6])
{
    uint8_t j;
    ac_status st = ac_sensor_row(cal, row);
    for (j = 0u; j < 6u; j++) {
        ac_xfp_ldexp(&row[j], (int16_t)-colexp[j]);
    }
    return st;
}

/* Column i of M in output LSB per count (a holds the inverse). */
static ac_status m_column(const ac_build_work *w, const ac_channel_cal *cal, uint16_t i,
                          uint16_t n, ac_xf col[6])
{
    uint8_t j;
    ac_status st = AC_OK;
    if (n == 6u) {
        for (j = 0u; j < 6u; j++) {
            col[j] = w->a[j][i];
        }
    } else {
        ac_xf rt[6];
        uint8_t l;
        st = scaled_row(cal, w->colexp, rt);
        for (j = 0u; j < 6u; j++) {
            col[j] = xf_zero;
            for (l = 0u; l < 6u; l++) {
                ac_xfp_mac(&col[j], &w->a[j][l], &rt[l]);
            }
        }
    }
    for (j = 0u; j < 6u; j++) {
        ac_xfp_ldexp(&col[j], (int16_t)(AC_OUT_FRAC - w->colexp[j]));
    }
    return (st != AC_OK) ? st : valid(col, 6u);
}

/* Largest s with |v| 2^s <= lim (the host quantizer's rule); 31 for v == 0. */
static int16_t largest_shift(const ac_xf *v, uint32_t lim)
{
    uint32_t m = ac_abs_u(v->m);
    uint8_t k = 0u;
    if (m == 0u) {
        return 31;
    }
    while ((lim << k) < m) { /* stops before lim << k can reach 2^31 */
        k++;
    }
    return (int16_t)(-(int16_t)k - v->e);
}

/* min(31, shift for the largest entry, shift for the row sum); AC_ERR_RANGE below -31 */
static ac_status row_shift(const ac_xf *vmax, const ac_xf *vsum, uint32_t count, int8_t *out)
{
    int16_t s1 = largest_shift(vmax, (uint32_t)COEF_MAX);
    int16_t s2 = largest_shift(vsum, (uint32_t)ROW_L1_MAX - count);
    if (s2 < s1) {
        s1 = s2;
    }
    if (s1 > 31) {
        s1 = 31;
    }
    if (s1 < -31 || valid(vmax, 1u) != AC_OK || valid(vsum, 1u) != AC_OK) {
        return AC_ERR_RANGE;
    }
    *out = (int8_t)s1;
    return AC_OK;
}

static ac_status to_i16(const ac_xf *v, int8_t shift, int16_t *out)
{
    int32_t q;
    if (ac_xfp_to_fixed(v, shift, &q) != AC_OK || q > COEF_MAX || q < -COEF_MAX - 1) {
        return AC_ERR_RANGE; /* cannot happen with row_shift's shift */
    }
    *out = (int16_t)q;
    return AC_OK;
}

ac_status ac_resolver_build(const ac_channel_cal *cal, uint16_t n, ac_build_work *w,
                            ac_resolver *out, ac_build_info *info)
{
    ac_xf col[6], crow[6], o;
    int8_t m_shift[6], g_shift[6];
    int32_t k[6];
    int16_t cl2 = 0;
    uint16_t i;
    uint8_t j, l;
    ac_status st;

    if (cal == 0 || w == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    if (n < 6u || n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }

    /* 1. equilibrate the columns by powers of two (rmax holds the column maxima) */
    for (j = 0u; j < 6u; j++) {
        w->rmax[j] = xf_zero;
    }
    for (i = 0u; i < n; i++) {
        st = ac_sensor_row(&cal[i], col);
        if (st != AC_OK) {
            return st;
        }
        for (j = 0u; j < 6u; j++) {
            ac_xfp_acc_abs(&w->rmax[j], 0, &col[j]);
        }
    }
    for (j = 0u; j < 6u; j++) {
        if (w->rmax[j].m == 0) {
            return AC_ERR_SINGULAR; /* nothing senses this degree of freedom */
        }
        w->colexp[j] = (int16_t)(w->rmax[j].e + 30);
    }

    /* 2. the matrix to invert: R~ (N = 6) or R~^T R~ (N > 6) */
    for (j = 0u; j < 6u; j++) {
        for (l = 0u; l < 6u; l++) {
            w->a[j][l] = xf_zero;
        }
    }
    for (i = 0u; i < n; i++) {
        (void)scaled_row(&cal[i], w->colexp, col); /* valid: checked in step 1 */
        for (j = 0u; j < 6u; j++) {
            if (n == 6u) {
                w->a[i][j] = col[j];
            } else {
                for (l = 0u; l < 6u; l++) {
                    ac_xfp_mac(&w->a[j][l], &col[j], &col[l]);
                }
            }
        }
    }
    st = ac_invert6(w->a, w->perm, &cl2);
    if (info != 0) {
        info->cond_log2 = cl2;
    }
    if (st != AC_OK) {
        return st;
    }

    /* 3. first pass over the columns of M: row scales, M o and M C */
    for (j = 0u; j < 6u; j++) {
        w->rmax[j] = xf_zero;
        w->rsum[j] = xf_zero;
        w->k[j] = xf_zero;
        for (l = 0u; l < 6u; l++) {
            w->g[j][l] = xf_zero;
        }
    }
    for (i = 0u; i < n; i++) {
        st = m_column(w, &cal[i], i, n, col);
        if (st == AC_OK) {
            st = ac_centripetal_row(&cal[i], crow);
        }
        if (st != AC_OK) {
            return st;
        }
        ac_xfp_from_fixed(&o, cal[i].offset, AC_OFFSET_FRAC);
        for (j = 0u; j < 6u; j++) {
            ac_xfp_acc_abs(&w->rmax[j], &w->rsum[j], &col[j]);
            ac_xfp_mac(&w->k[j], &col[j], &o);
            for (l = 0u; l < 6u; l++) {
                ac_xfp_mac(&w->g[j][l], &col[j], &crow[l]);
            }
        }
    }

    /* 4. shifts and offset terms; every failure is found before out is touched */
    for (j = 0u; j < 6u; j++) {
        ac_xf gmax = xf_zero, gsum = xf_zero;
        st = row_shift(&w->rmax[j], &w->rsum[j], n, &m_shift[j]);
        if (st != AC_OK) {
            return st;
        }
        if (ac_xfp_to_fixed(&w->k[j], m_shift[j], &k[j]) != AC_OK) {
            return AC_ERR_RANGE;
        }
        for (l = 0u; l < 6u; l++) {
            ac_xfp_acc_abs(&gmax, &gsum, &w->g[j][l]);
        }
        st = row_shift(&gmax, &gsum, 6u, &g_shift[j]);
        if (st != AC_OK) {
            return st;
        }
    }

    /* 5. write the table; the second pass recomputes the columns of M */
    out->n = n;
    for (j = 0u; j < 6u; j++) {
        out->m_shift[j] = m_shift[j];
        out->g_shift[j] = g_shift[j];
        out->k[j] = k[j];
        for (l = 0u; l < 6u; l++) {
            if (to_i16(&w->g[j][l], g_shift[j], &out->g[j][l]) != AC_OK) {
                return AC_ERR_RANGE;
            }
        }
        for (i = n; i < (uint16_t)AC_MAX_CHANNELS; i++) {
            out->m[j][i] = 0;
        }
    }
    for (i = 0u; i < n; i++) {
        st = m_column(w, &cal[i], i, n, col);
        for (j = 0u; j < 6u && st == AC_OK; j++) {
            st = to_i16(&col[j], m_shift[j], &out->m[j][i]);
        }
        if (st != AC_OK) {
            return st;
        }
    }
    return AC_OK;
}
