/*
 * accelcal -- on-device build of the resolver table (see ac_invert.h).
 *
 * Self-contained and small (the H8/300H budget): a private soft-float on the
 * ac_xf layout (value m 2^e, 2^29 <= |m| < 2^30, or m == 0 and e == 0) with
 * only what the build needs -- normalise-and-round, accumulate, multiply,
 * reciprocal, compare -- in 32-bit integers and 16 x 16 -> 32 multiplies (no
 * 64-bit C type; nothing from ac_xf.c or ac_ops.c, and from ac_ops64.c only the
 * exact 32 x 32 multiply with its add, subtract and compare, for the rows).
 * Every result is rounded to 30 bits, to nearest (ties away from zero); a
 * difference whose smaller operand is more than one binade below the larger may
 * be off by one more half unit (one guard bit).  The products of s and r in a
 * channel's rows (r x s and the centripetal terms) are exact, as 64-bit
 * magnitudes in two 32-bit halves (ac_u64), and rounded once: a cross product
 * that is small next to its two products keeps its digits, which equilibrating
 * its column would otherwise magnify (found by the fuzzer: r parallel to s on
 * some channels, a tiny column elsewhere).
 *
 * Exponents stay far inside +-30000: the build's inputs are int32 fixed point
 * and its matrix is equilibrated, and ac_invert6 scales its input so that the
 * largest entry is about 1 (and the inverse back), so pivots are at least
 * 2^-27 and nothing can overflow.  Values below 2^-30000 flush to zero.
 * Memory: the caller's ac_build_work; the columns of M are recomputed in a
 * second pass rather than stored, so N = 12 needs no more RAM than N = 6.
 */
#include "ac_invert_core.h"
#include "ac_internal.h"

#define XF_LO 0x20000000UL /* 2^29: smallest normalised |m| */
#define XF_HI 0x40000000UL /* 2^30 */
#define PIVOT_TOL_LOG2 (-26)
#define COEF_MAX 32767L
#define ROW_L1_MAX 65535L

typedef ac_xf xf;

/* ---- arithmetic -------------------------------------------------------------------- */

static uint32_t mag(int32_t m)
{
    return (m < 0) ? 0u - (uint32_t)m : (uint32_t)m;
}

static void clear(void *p, unsigned bytes)
{
    unsigned char *c = (unsigned char *)p;
    while (bytes-- != 0u) {
        c[bytes] = 0u;
    }
}

static void swap(void *a, void *b, unsigned bytes)
{
    unsigned char *x = (unsigned char *)a, *y = (unsigned char *)b;
    while (bytes-- != 0u) {
        unsigned char t = x[bytes];
        x[bytes] = y[bytes];
        y[bytes] = t;
    }
}

/* r = (neg ? -1 : 1) * mag 2^e, normalised and rounded half away from zero */
static void pack(xf *r, unsigned neg, uint32_t mag_, int32_t e)
{
    if (mag_ != 0u) {
        unsigned k = 0u;
        while ((mag_ >> k) >= XF_HI) {
            k++;
        }
        if (k != 0u) {
            mag_ = ((mag_ >> (k - 1u)) + 1u) >> 1; /* < 2^30, or 2^30 after a carry */
            e += (int32_t)k;
        }
        while (mag_ < XF_LO) {
            mag_ <<= 1;
            e--;
        }
        if (mag_ == XF_HI) {
            mag_ = XF_LO;
            e++;
        }
    }
    if (e < AC_INV_EMIN) {
        mag_ = 0u;
    }
    r->m = (int32_t)mag_;
    if (neg) {
        r->m = -r->m;
    }
    r->e = (int16_t)((mag_ == 0u) ? 0 : e);
}

void ac_inv_scale(xf *v, int32_t k)
{
    pack(v, v->m < 0, mag(v->m), (int32_t)v->e + k);
}

static void from_fixed(xf *r, int32_t v, int16_t frac)
{
    pack(r, v < 0, mag(v), -frac);
}

static const xf xf_one = {0x20000000L, -29};

/* r = r + a b, or r - a b when sub != 0.  The product is kept to 31 bits
 * (floor(|a||b| / 2^28) from four 16 x 16 products, halved if it reaches 2^31),
 * r to 31 bits (one guard bit); the sum is rounded once.  r may alias a or b
 * only if it is not zero on entry (use mul() for r = a b). */
static void mac(xf *r, const xf *a, const xf *b, unsigned sub)
{
    uint32_t x = mag(a->m), y = mag(b->m), z = mag(r->m) << 1;
    uint16_t xh = (uint16_t)(x >> 16), xl = (uint16_t)x, yh = (uint16_t)(y >> 16), yl = (uint16_t)y;
    uint32_t p = (uint32_t)xh * yl + (uint32_t)xl * yh + (((uint32_t)xl * yl) >> 16);
    unsigned sp = (unsigned)(a->m < 0) ^ (unsigned)(b->m < 0) ^ sub, sz = r->m < 0;
    int32_t ep = (int32_t)a->e + b->e + 28, ez = (int32_t)r->e - 1, d;
    p = (((uint32_t)xh * yh) << 4) + (p >> 12);
    if (p >= 0x80000000UL) {
        p >>= 1;
        ep++;
    }
    if (p == 0u) {
        ep = ez;
    }
    if (z == 0u) {
        ez = ep;
    }
    d = ez - ep; /* shift the one with the smaller exponent */
    if (d >= 0) {
        p >>= (d > 31) ? 31u : (unsigned)d;
    } else {
        z >>= (d < -31) ? 31u : (unsigned)-d;
        ez = ep;
    }
    if (sp == sz) {
        z += p; /* < 2^32 */
    } else if (z >= p) {
        z -= p;
    } else {
        z = p - z;
        sz = sp;
    }
    pack(r, sz, z, ez);
}

/* y[0..5] += alpha x[0..5] */
static void axpy(xf *y, const xf *alpha, const xf *x)
{
    unsigned j;
    for (j = 0u; j < 6u; j++) {
        mac(&y[j], alpha, &x[j], 0u);
    }
}

/* |a| > |b| */
static unsigned gtabs(const xf *a, const xf *b)
{
    uint32_t x = mag(a->m), y = mag(b->m);
    if (x != 0u && y != 0u && a->e != b->e) {
        return a->e > b->e;
    }
    return x > y;
}

/* max = max(max, |v|); sum += |v| */
static void acc_abs(xf *max, xf *sum, const xf *v)
{
    if (gtabs(v, max)) {
        *max = *v;
        max->m = (int32_t)mag(max->m);
    }
    mac(sum, v, &xf_one, v->m < 0);
}

/* round(v 2^s) half up (floor(x + 1/2)); 1 if that does not fit int32 */
static unsigned to_fixed(const xf *v, int16_t s, int32_t *out)
{
    int32_t k = (v->m == 0) ? (int32_t)-31 : (int32_t)v->e + s; /* v 2^s = m 2^k */
    uint32_t u;
    unsigned n;
    if (k >= 0) {
        *out = (k != 0) ? v->m + v->m : v->m; /* |m| 2 < 2^31 */
        return k > 1;
    }
    n = (k < -31) ? 31u : (unsigned)-k; /* below 2^-31 |m| < 2^-2 rounds to 0 */
    /* floor((m + 2^(n-1)) / 2^n), offset by 2^31 to stay unsigned */
    u = (uint32_t)v->m + ((uint32_t)1 << (n - 1u)) + (uint32_t)0x80000000UL;
    *out = (int32_t)(u >> n) - (int32_t)((uint32_t)0x80000000UL >> n);
    return 0u;
}

/* The host quantizer's rule: the largest s <= 31 with max |v| 2^s <= 32767 and
 * sum |v| 2^s <= 65535 - count (mm[0] = max |v|, mm[1] = sum |v|). */
static int16_t row_shift(const xf mm[2], uint16_t count)
{
    int16_t best = 31;
    unsigned q;
    for (q = 0u; q < 2u; q++) {
        uint32_t m = mag(mm[q].m), lim = (q != 0u) ? (uint32_t)ROW_L1_MAX - count : (uint32_t)COEF_MAX;
        int16_t s = (int16_t)-mm[q].e;
        if (m != 0u) {
            while (lim < m) { /* lim < 2^16, m < 2^30: 15 steps at most */
                lim <<= 1;
                s--;
            }
            if (s < best) {
                best = s;
            }
        }
    }
    return best;
}

/* to_fixed into int16, saturated (the shifts make it fit) */
static int16_t to_i16(const xf *v, int16_t s)
{
    int32_t q = 0;
    (void)to_fixed(v, s, &q);
    return (int16_t)((q > COEF_MAX) ? COEF_MAX : ((q < -COEF_MAX) ? -COEF_MAX : q));
}

/* ---- rows of the sensor and centripetal matrices ---------------------------------- */

/* r = (neg ? -1 : 1) (hi 2^32 + lo) 2^e, rounded once: the bits below the 32 kept do not
 * matter to pack's rounding (half away from zero looks at the half bit only) */
static void pack64(xf *r, unsigned neg, uint32_t hi, uint32_t lo, int32_t e)
{
    unsigned k = 0u;
    while (k < 32u && (hi >> k) != 0u) {
        k++;
    }
    if (k == 32u) {
        lo = hi;
    } else if (k != 0u) {
        lo = (hi << (32u - k)) | (lo >> k);
    }
    pack(r, neg, lo, e + (int32_t)k);
}

/* The rows' products of s and r, each destination the sum of two signed products of the
 * channel's integers (sens Q.AC_SENS_FRAC, pos Q.AC_POS_FRAC), computed exactly in 64 bits and
 * rounded once -- so that r x s is 0 for r parallel to s, and a small cross product keeps
 * its digits however large the products it is the difference of (equilibration would
 * magnify their rounding otherwise).  Pairs (d, sub, a, b): v[d] +- v[a] v[b], v = 0 but
 * for s (v[0..2]) and r (v[6..8]):
 *   R_i[3..5] = r x s          (r_b s_c - r_c s_b)
 *   C_i[0..2] = s_a r_a - s.r  (= -(s_b r_b + s_c r_c))
 *   C_i[3..5] = s_a r_b + s_b r_a,  (a, b, c) = (0, 1, 2), (1, 2, 0), (2, 0, 1) */
#define OP(d, sub, a, b) (unsigned char)((d) + 16 * (sub)), (unsigned char)((a) + 16 * (b))
static const unsigned char row_program[36] = {
    OP(3, 0, 7, 2),  OP(3, 1, 8, 1),  OP(4, 0, 8, 0),  OP(4, 1, 6, 2),
    OP(5, 0, 6, 1),  OP(5, 1, 7, 0),  OP(9, 1, 1, 7),  OP(9, 1, 2, 8),
    OP(10, 1, 0, 6), OP(10, 1, 2, 8), OP(11, 1, 0, 6), OP(11, 1, 1, 7),
    OP(12, 0, 0, 7), OP(12, 0, 1, 6), OP(13, 0, 1, 8), OP(13, 0, 2, 7),
    OP(14, 0, 2, 6), OP(14, 0, 0, 8)};
#undef OP

static int32_t chan_int(const ac_channel_cal *cal, unsigned k)
{
    return (k < 3u) ? cal->sens[k] : cal->pos[k - 6u];
}

void ac_inv_rows(const ac_channel_cal *cal, xf v[15])
{
    const unsigned char *p;
    unsigned a;
    clear(v, 15u * sizeof *v);
    for (a = 0u; a < 3u; a++) {
        from_fixed(&v[a], cal->sens[a], AC_SENS_FRAC);
        from_fixed(&v[6u + a], cal->pos[a], AC_POS_FRAC);
    }
    for (p = row_program; p < row_program + sizeof row_program; p += 4) {
        ac_u64 m[2];
        unsigned neg[2], q;
        for (q = 0u; q < 2u; q++) {
            const unsigned char *op = (q != 0u) ? p + 2 : p;
            int32_t x = chan_int(cal, op[1] & 15u), y = chan_int(cal, (unsigned)op[1] >> 4);
            m[q] = ac_mul32u(mag(x), mag(y)); /* < 2^62 */
            neg[q] = (unsigned)(x < 0) ^ (unsigned)(y < 0) ^ ((unsigned)op[0] >> 4);
        }
        if (neg[0] == neg[1]) {
            m[0] = ac_u64_add(m[0], m[1]); /* < 2^63 */
        } else { /* the difference, with the sign of the larger */
            if (ac_u64_lt(m[0], m[1])) {
                ac_u64 t = m[0];
                m[0] = m[1];
                m[1] = t;
                neg[0] = neg[1];
            }
            m[0] = ac_u64_sub(m[0], m[1]);
        }
        pack64(&v[p[0] & 15u], neg[0], m[0].hi, m[0].lo, -(int32_t)(AC_SENS_FRAC + AC_POS_FRAC));
    }
}

/* ---- the 6x6 inverse -------------------------------------------------------------- */

/* norm = max column sum of |a|; amax = max(amax, max |a_ij|) */
static void norm1(xf a[6][6], xf *norm, xf *amax)
{
    unsigned i, j;
    clear(norm, sizeof *norm);
    for (j = 0u; j < 6u; j++) {
        xf sum[2]; /* the column's sum, and a sum of sums nobody needs */
        const xf *p = &a[0][j];
        clear(sum, sizeof sum);
        for (i = 0u; i < 6u; i++, p += 6) {
            acc_abs(amax, &sum[0], p);
        }
        acc_abs(norm, &sum[1], &sum[0]);
    }
}

ac_status ac_inv_gauss_jordan(xf a[6][6], int8_t perm[6], int16_t *cond_log2)
{
    xf na, ninv, tol;
    unsigned i, k;
    clear(&tol, sizeof tol);
    norm1(a, &na, &tol);
    tol.e = (int16_t)(tol.e + PIVOT_TOL_LOG2);
    for (k = 0u; k < 6u; k++) {
        xf *rk = a[k], *piv = &rk[k], *best = piv, *c = piv, inv;
        unsigned p = k;
        uint32_t n = XF_LO, d, q = 0u;
        for (i = k + 1u; i < 6u; i++) {
            c += 6;
            if (gtabs(c, best)) {
                best = c;
                p = i;
            }
        }
        if (!gtabs(best, &tol)) { /* also when a == 0 */
            return AC_ERR_SINGULAR;
        }
        perm[k] = (int8_t)p;
        swap(rk, a[p], sizeof a[0]);
        /* 1 / pivot: restoring division floor(2^29 2^31 / |m|), n < 2 |m| throughout */
        d = mag(piv->m);
        for (i = 0u; i < 32u; i++) {
            q <<= 1;
            if (n >= d) {
                n -= d;
                q |= 1u;
            }
            n <<= 1;
        }
        pack(&inv, piv->m < 0, q, (int32_t)-60 - piv->e);
        *piv = xf_one;
        for (i = 0u; i < 6u; i++) {
            xf t = rk[i];
            clear(&rk[i], sizeof t);
            mac(&rk[i], &t, &inv, 0u);
        }
        for (i = 0u; i < 6u; i++) {
            xf *ri = a[i], f = ri[k];
            if (i != k) {
                clear(&ri[k], sizeof f);
                for (p = 0u; p < 6u; p++) {
                    mac(&ri[p], &f, &rk[p], 1u);
                }
            }
        }
    }
    /* undo the row interchanges as column interchanges, last first */
    while (k-- != 0u) {
        xf *x = &a[0][k], *y = &a[0][(unsigned)perm[k]];
        for (i = 0u; i < 6u; i++, x += 6, y += 6) {
            swap(x, y, sizeof *x);
        }
    }
    norm1(a, &ninv, &tol);
    clear(&tol, sizeof tol);
    mac(&tol, &na, &ninv, 0u);
    na = tol;
    /* cond = m 2^e with 2^29 <= m < 2^30: ceil(log2) is e + 29 for m == 2^29, else e + 30 */
    *cond_log2 = (int16_t)(na.e + ((na.m == (int32_t)XF_LO) ? 29 : 30));
    return (*cond_log2 > AC_COND_LOG2_MAX) ? AC_ERR_ILL_COND : AC_OK;
}

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
    clear(w, sizeof *w);
    clear(e, sizeof e);

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
                clear(&r[7], 2u * sizeof *r);
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
                clear(gm, sizeof gm);
                for (l = 0u; l < 6u; l++) {
                    acc_abs(&gm[0], &gm[1], &r[l]);
                }
                ms = row_shift(&r[7], n);
                gs = row_shift(gm, 6u);
                if (ms < -31 || gs < -31 || to_fixed(&r[6], ms, &k[j]) != 0u) {
                    return AC_ERR_RANGE;
                }
                m_shift[j] = (int8_t)ms;
                g_shift[j] = (int8_t)gs;
            }
            clear(out->m, sizeof out->m);
            out->n = n;
        }
        for (i = 0u; i < n; i++) {
            const xf *u = v;
            ac_inv_rows(&cal[i], v);
            if (n == 6u) {
                e[i].m = (int32_t)XF_LO; /* 1 */
                e[i].e = -29;
                u = e;
            }
            from_fixed(&o, cal[i].offset, AC_OFFSET_FRAC);
            for (j = 0u; j < 6u; j++) {
                xf *r = w->acc[j], *aj = w->a[j];
                if (pass == 0u) {
                    acc_abs(&r[7], &r[8], &v[j]);
                    axpy(aj, &u[j], v);
                    continue;
                }
                clear(&c, sizeof c);
                for (l = 0u; l < 6u; l++) {
                    mac(&c, &aj[l], &u[l], 0u);
                }
                if (pass == 1u) {
                    acc_abs(&r[7], &r[8], &c);
                    mac(&r[6], &c, &o, 0u);
                    axpy(r, &c, &v[9]);
                } else {
                    out->m[j][i] = to_i16(&c, m_shift[j]);
                    out->m_shift[j] = m_shift[j];
                    out->g_shift[j] = g_shift[j];
                    out->k[j] = k[j];
                    for (l = 0u; l < 6u; l++) {
                        out->g[j][l] = to_i16(&r[l], g_shift[j]);
                    }
                }
            }
            clear(e, sizeof e);
        }
    }
    return AC_OK;
}

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
    clear(w, sizeof *w);
    /* a = [[S, 0], [0, I]] (S's rows the s_i), S's columns equilibrated by powers of two */
    for (i = 0u; i < 3u; i++) {
        for (l = 0u; l < 3u; l++) {
            from_fixed(&w->a[i][l], cal[i].sens[l], AC_SENS_FRAC);
            acc_abs(&w->acc[l][7], &w->acc[l][8], &w->a[i][l]);
        }
    }
    for (l = 0u; l < 3u; l++) {
        if (w->acc[l][7].m == 0) {
            return AC_ERR_SINGULAR;
        }
        w->colexp[l] = (int16_t)(w->acc[l][7].e + 30);
        w->a[3u + l][3u + l] = xf_one;
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
        clear(mm, sizeof mm);
        clear(&c, sizeof c);
        for (l = 0u; l < 3u; l++) {
            ac_inv_scale(&w->a[j][l], (int32_t)AC_OUT_FRAC - w->colexp[j]);
            acc_abs(&mm[0], &mm[1], &w->a[j][l]);
            from_fixed(&o, cal[l].offset, AC_OFFSET_FRAC);
            mac(&c, &w->a[j][l], &o, 0u);
        }
        s = row_shift(mm, 3u);
        if (s < -31 || to_fixed(&c, s, &k[j]) != 0u) {
            return AC_ERR_RANGE;
        }
        shift[j] = (int8_t)s;
    }
    for (j = 0u; j < 3u; j++) {
        out->trim[j] = trim[j];
        out->shift[j] = shift[j];
        out->k[j] = k[j];
        for (l = 0u; l < 3u; l++) {
            out->m[j][l] = to_i16(&w->a[j][l], shift[j]);
        }
    }
    return AC_OK;
}
