/*
 * accelcal -- on-device build of the resolver table (see ac_invert.h).
 *
 * Everything here runs in ac_xf (29-bit mantissa, wide exponent), so column
 * scales (counts per m/s^2 against counts per rad/s^2) cost no precision.
 * Memory: the caller's ac_build_work; the columns of M are recomputed in a
 * second pass rather than stored, so N = 12 needs no more RAM than N = 6.
 */
#include "accelcal/ac_invert.h"
#include "accelcal/ac_fixed.h"
#include "ac_internal.h"

#define TRY(expr)                                                                                  \
    do {                                                                                           \
        ac_status try_st_ = (expr);                                                                \
        if (try_st_ < 0) {                                                                         \
            return try_st_;                                                                        \
        }                                                                                          \
    } while (0)

#define PIVOT_TOL_LOG2 (-26)
#define COEF_MAX 32767L
#define ROW_L1_MAX 65535L

static const ac_xf xf_zero = {0, 0};
static const ac_xf xf_one = {0x20000000L, -29};

static ac_status xf_mac(ac_xf *acc, ac_xf a, ac_xf b) /* acc += a b */
{
    ac_xf p;
    TRY(ac_xf_mul(a, b, &p));
    return ac_xf_add(*acc, p, acc);
}

static ac_status xf_acc_abs(ac_xf *max, ac_xf *sum, ac_xf v) /* max = max(max,|v|), sum += |v| */
{
    ac_xf av;
    int8_t c;
    TRY(ac_xf_abs(v, &av));
    TRY(ac_xf_cmpabs(av, *max, &c));
    if (c > 0) {
        *max = av;
    }
    return (sum != 0) ? ac_xf_add(*sum, av, sum) : AC_OK;
}

ac_status ac_sensor_row(const ac_channel_cal *cal, ac_xf row[6])
{
    ac_xf s[3], r[3], t1, t2;
    uint8_t a;
    if (cal == 0 || row == 0) {
        return AC_ERR_NULL;
    }
    for (a = 0u; a < 3u; a++) {
        TRY(ac_xf_from_fixed(cal->sens[a], AC_SENS_FRAC, &s[a]));
        TRY(ac_xf_from_fixed(cal->pos[a], AC_POS_FRAC, &r[a]));
        row[a] = s[a];
    }
    /* r x s: the channel's response to angular acceleration */
    for (a = 0u; a < 3u; a++) {
        uint8_t b = (uint8_t)((a + 1u) % 3u), c = (uint8_t)((a + 2u) % 3u);
        TRY(ac_xf_mul(r[b], s[c], &t1));
        TRY(ac_xf_mul(r[c], s[b], &t2));
        TRY(ac_xf_sub(t1, t2, &row[3u + a]));
    }
    return AC_OK;
}

ac_status ac_centripetal_row(const ac_channel_cal *cal, ac_xf row[6])
{
    /* s.(w (w.r) - r |w|^2) over p = (wx^2, wy^2, wz^2, wx wy, wy wz, wz wx) */
    ac_xf s[3], r[3], sr = xf_zero, t1, t2;
    uint8_t a;
    if (cal == 0 || row == 0) {
        return AC_ERR_NULL;
    }
    for (a = 0u; a < 3u; a++) {
        TRY(ac_xf_from_fixed(cal->sens[a], AC_SENS_FRAC, &s[a]));
        TRY(ac_xf_from_fixed(cal->pos[a], AC_POS_FRAC, &r[a]));
        TRY(xf_mac(&sr, s[a], r[a]));
    }
    for (a = 0u; a < 3u; a++) {
        uint8_t b = (uint8_t)((a + 1u) % 3u);
        TRY(ac_xf_mul(s[a], r[a], &t1));
        TRY(ac_xf_sub(t1, sr, &row[a]));
        TRY(ac_xf_mul(s[a], r[b], &t1));
        TRY(ac_xf_mul(s[b], r[a], &t2));
        TRY(ac_xf_add(t1, t2, &row[3u + a]));
    }
    return AC_OK;
}

static ac_status norm1(ac_xf a[6][6], ac_xf *out) /* max column sum of |a| */
{
    uint8_t i, j;
    *out = xf_zero;
    for (j = 0u; j < 6u; j++) {
        ac_xf sum = xf_zero, unused = xf_zero;
        for (i = 0u; i < 6u; i++) {
            TRY(xf_acc_abs(&unused, &sum, a[i][j]));
        }
        TRY(xf_acc_abs(out, 0, sum));
    }
    return AC_OK;
}

ac_status ac_invert6(ac_xf a[6][6], int8_t perm[6], int16_t *cond_log2)
{
    ac_xf na, ninv, amax = xf_zero, tol, cond;
    uint8_t i, j, k;
    int16_t cl2;
    if (a == 0 || perm == 0) {
        return AC_ERR_NULL;
    }
    TRY(norm1(a, &na));
    for (i = 0u; i < 6u; i++) {
        for (j = 0u; j < 6u; j++) {
            TRY(xf_acc_abs(&amax, 0, a[i][j]));
        }
    }
    if (amax.m == 0) {
        return AC_ERR_SINGULAR;
    }
    TRY(ac_xf_ldexp(amax, PIVOT_TOL_LOG2, &tol));

    for (k = 0u; k < 6u; k++) {
        uint8_t p = k;
        ac_xf inv;
        int8_t c;
        for (i = (uint8_t)(k + 1u); i < 6u; i++) {
            TRY(ac_xf_cmpabs(a[i][k], a[p][k], &c));
            if (c > 0) {
                p = i;
            }
        }
        TRY(ac_xf_cmpabs(a[p][k], tol, &c));
        if (c <= 0) {
            return AC_ERR_SINGULAR;
        }
        if (p != k) {
            for (j = 0u; j < 6u; j++) {
                ac_xf t = a[k][j];
                a[k][j] = a[p][j];
                a[p][j] = t;
            }
        }
        perm[k] = (int8_t)p;
        TRY(ac_xf_div(xf_one, a[k][k], &inv));
        a[k][k] = xf_one;
        for (j = 0u; j < 6u; j++) {
            TRY(ac_xf_mul(a[k][j], inv, &a[k][j]));
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
                TRY(ac_xf_mul(f, a[k][j], &t));
                TRY(ac_xf_sub(a[i][j], t, &a[i][j]));
            }
        }
    }
    /* undo the row interchanges as column interchanges, last first */
    for (k = 6u; k-- > 0u;) {
        uint8_t p = (uint8_t)perm[k];
        if (p != k) {
            for (i = 0u; i < 6u; i++) {
                ac_xf t = a[i][k];
                a[i][k] = a[i][p];
                a[i][p] = t;
            }
        }
    }
    TRY(norm1(a, &ninv));
    TRY(ac_xf_mul(na, ninv, &cond));
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
    TRY(ac_sensor_row(cal, row));
    for (j = 0u; j < 6u; j++) {
        TRY(ac_xf_ldexp(row[j], (int16_t)-colexp[j], &row[j]));
    }
    return AC_OK;
}

/* Column i of M in output LSB per count (a holds the inverse). */
static ac_status m_column(const ac_build_work *w, const ac_channel_cal *cal, uint16_t i,
                          uint16_t n, ac_xf col[6])
{
    uint8_t j;
    if (n == 6u) {
        for (j = 0u; j < 6u; j++) {
            col[j] = w->a[j][i];
        }
    } else {
        ac_xf rt[6];
        uint8_t l;
        TRY(scaled_row(cal, w->colexp, rt));
        for (j = 0u; j < 6u; j++) {
            col[j] = xf_zero;
            for (l = 0u; l < 6u; l++) {
                TRY(xf_mac(&col[j], w->a[j][l], rt[l]));
            }
        }
    }
    for (j = 0u; j < 6u; j++) {
        TRY(ac_xf_ldexp(col[j], (int16_t)(AC_OUT_FRAC - w->colexp[j]), &col[j]));
    }
    return AC_OK;
}

/* Largest s <= 31 with vmax 2^s <= lim_each and vsum 2^s <= lim_sum (the
 * host quantizer's rule); AC_ERR_RANGE if that s is below -31. */
static ac_status largest_shift(ac_xf v, uint32_t lim, int16_t *s)
{
    uint32_t m = ac_abs_u(v.m);
    uint8_t k = 0u;
    if (m == 0u) {
        *s = 31;
        return AC_OK;
    }
    while ((lim << k) < m) { /* stops before lim << k can reach 2^31 */
        k++;
    }
    *s = (int16_t)(-(int16_t)k - v.e);
    return AC_OK;
}

static ac_status row_shift(ac_xf vmax, ac_xf vsum, uint32_t count, int8_t *out)
{
    int16_t s1, s2;
    TRY(largest_shift(vmax, (uint32_t)COEF_MAX, &s1));
    TRY(largest_shift(vsum, (uint32_t)ROW_L1_MAX - count, &s2));
    if (s2 < s1) {
        s1 = s2;
    }
    if (s1 > 31) {
        s1 = 31;
    }
    if (s1 < -31) {
        return AC_ERR_RANGE;
    }
    *out = (int8_t)s1;
    return AC_OK;
}

static ac_status to_i16(ac_xf v, int8_t shift, int16_t *out)
{
    int32_t q;
    TRY(ac_xf_to_fixed(v, shift, &q));
    if (q > COEF_MAX || q < -COEF_MAX) {
        return AC_ERR_RANGE; /* cannot happen with row_shift's shift */
    }
    *out = (int16_t)q;
    return AC_OK;
}

ac_status ac_resolver_build(const ac_channel_cal *cal, uint16_t n, ac_build_work *w,
                            ac_resolver *out, ac_build_info *info)
{
    ac_xf col[6], crow[6], o, colmax[6];
    int8_t m_shift[6], g_shift[6];
    int32_t k[6];
    int16_t cl2 = 0;
    uint16_t i;
    uint8_t j, l;

    if (cal == 0 || w == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    if (n < 6u || n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }

    /* 1. equilibrate the columns by powers of two */
    for (j = 0u; j < 6u; j++) {
        colmax[j] = xf_zero;
    }
    for (i = 0u; i < n; i++) {
        TRY(ac_sensor_row(&cal[i], col));
        for (j = 0u; j < 6u; j++) {
            TRY(xf_acc_abs(&colmax[j], 0, col[j]));
        }
    }
    for (j = 0u; j < 6u; j++) {
        if (colmax[j].m == 0) {
            return AC_ERR_SINGULAR; /* nothing senses this degree of freedom */
        }
        w->colexp[j] = (int16_t)(colmax[j].e + 30);
    }

    /* 2. the matrix to invert: R~ (N = 6) or R~^T R~ (N > 6) */
    for (j = 0u; j < 6u; j++) {
        for (l = 0u; l < 6u; l++) {
            w->a[j][l] = xf_zero;
        }
    }
    for (i = 0u; i < n; i++) {
        TRY(scaled_row(&cal[i], w->colexp, col));
        for (j = 0u; j < 6u; j++) {
            if (n == 6u) {
                w->a[i][j] = col[j];
            } else {
                for (l = 0u; l < 6u; l++) {
                    TRY(xf_mac(&w->a[j][l], col[j], col[l]));
                }
            }
        }
    }
    TRY(ac_invert6(w->a, w->perm, &cl2));
    if (info != 0) {
        info->cond_log2 = cl2;
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
        TRY(m_column(w, &cal[i], i, n, col));
        TRY(ac_centripetal_row(&cal[i], crow));
        TRY(ac_xf_from_fixed(cal[i].offset, AC_OFFSET_FRAC, &o));
        for (j = 0u; j < 6u; j++) {
            TRY(xf_acc_abs(&w->rmax[j], &w->rsum[j], col[j]));
            TRY(xf_mac(&w->k[j], col[j], o));
            for (l = 0u; l < 6u; l++) {
                TRY(xf_mac(&w->g[j][l], col[j], crow[l]));
            }
        }
    }

    /* 4. shifts and offset terms; every failure is found before out is touched */
    for (j = 0u; j < 6u; j++) {
        ac_xf gmax = xf_zero, gsum = xf_zero;
        TRY(row_shift(w->rmax[j], w->rsum[j], n, &m_shift[j]));
        if (ac_xf_to_fixed(w->k[j], m_shift[j], &k[j]) != AC_OK) {
            return AC_ERR_RANGE;
        }
        for (l = 0u; l < 6u; l++) {
            TRY(xf_acc_abs(&gmax, &gsum, w->g[j][l]));
        }
        TRY(row_shift(gmax, gsum, 6u, &g_shift[j]));
    }

    /* 5. write the table; the second pass recomputes the columns of M */
    out->n = n;
    for (j = 0u; j < 6u; j++) {
        out->m_shift[j] = m_shift[j];
        out->g_shift[j] = g_shift[j];
        out->k[j] = k[j];
        for (l = 0u; l < 6u; l++) {
            TRY(to_i16(w->g[j][l], g_shift[j], &out->g[j][l]));
        }
        for (i = n; i < (uint16_t)AC_MAX_CHANNELS; i++) {
            out->m[j][i] = 0;
        }
    }
    for (i = 0u; i < n; i++) {
        TRY(m_column(w, &cal[i], i, n, col));
        for (j = 0u; j < 6u; j++) {
            TRY(to_i16(col[j], m_shift[j], &out->m[j][i]));
        }
    }
    return AC_OK;
}
