/*
 * accelcal -- the arithmetic of the on-device builds and their 6x6 inverse
 * (ac_invert_core.h), shared by ac_resolver_build (ac_resolver_build.c, with the
 * channel rows of ac_invert_rows.c), ac_triad_build (ac_triad_build.c) and the
 * other public ac_invert.h functions (ac_invert_api.c).
 *
 * Self-contained and small (the H8/300H budget): a private soft-float on the
 * ac_xf layout (value m 2^e, 2^29 <= |m| < 2^30, or m == 0 and e == 0) with
 * only what the build needs -- normalise-and-round, accumulate, multiply,
 * reciprocal, compare -- in 32-bit integers and 16 x 16 -> 32 multiplies (no
 * 64-bit C type; nothing from ac_xf.c, ac_ops.c or ac_ops64.c here: the rows'
 * exact 32 x 32 products, in ac_invert_rows.c, use ac_ops64.c).
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
 */
#include "ac_invert_core.h"

#define PIVOT_TOL_LOG2 (-26)

typedef ac_xf xf;

/* ---- arithmetic -------------------------------------------------------------------- */

void ac_inv_clear(void *p, unsigned bytes)
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
void ac_inv_pack(xf *r, unsigned neg, uint32_t mag_, int32_t e)
{
    if (mag_ != 0u) {
        unsigned k = 0u;
        while ((mag_ >> k) >= AC_INV_XF_HI) {
            k++;
        }
        if (k != 0u) {
            mag_ = ((mag_ >> (k - 1u)) + 1u) >> 1; /* < 2^30, or 2^30 after a carry */
            e += (int32_t)k;
        }
        while (mag_ < AC_INV_XF_LO) {
            mag_ <<= 1;
            e--;
        }
        if (mag_ == AC_INV_XF_HI) {
            mag_ = AC_INV_XF_LO;
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
    ac_inv_pack(v, v->m < 0, ac_inv_mag(v->m), (int32_t)v->e + k);
}

void ac_inv_from_fixed(xf *r, int32_t v, int16_t frac)
{
    ac_inv_pack(r, v < 0, ac_inv_mag(v), -frac);
}

const xf ac_inv_one = {0x20000000L, -29};

/* r = r + a b, or r - a b when sub != 0.  The product is kept to 31 bits
 * (floor(|a||b| / 2^28) from four 16 x 16 products, halved if it reaches 2^31),
 * r to 31 bits (one guard bit); the sum is rounded once.  r may alias a or b
 * only if it is not zero on entry (use mul() for r = a b). */
void ac_inv_mac(xf *r, const xf *a, const xf *b, unsigned sub)
{
    uint32_t x = ac_inv_mag(a->m), y = ac_inv_mag(b->m), z = ac_inv_mag(r->m) << 1;
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
    ac_inv_pack(r, sz, z, ez);
}

/* y[0..5] += alpha x[0..5] */
static unsigned gtabs(const xf *a, const xf *b)
{
    uint32_t x = ac_inv_mag(a->m), y = ac_inv_mag(b->m);
    if (x != 0u && y != 0u && a->e != b->e) {
        return a->e > b->e;
    }
    return x > y;
}

/* max = max(max, |v|); sum += |v| */
void ac_inv_acc_abs(xf *max, xf *sum, const xf *v)
{
    if (gtabs(v, max)) {
        *max = *v;
        max->m = (int32_t)ac_inv_mag(max->m);
    }
    ac_inv_mac(sum, v, &ac_inv_one, v->m < 0);
}

/* round(v 2^s) half up (floor(x + 1/2)); 1 if that does not fit int32 */
unsigned ac_inv_to_fixed(const xf *v, int16_t s, int32_t *out)
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
int16_t ac_inv_row_shift(const xf mm[2], uint16_t count)
{
    int16_t best = 31;
    unsigned q;
    for (q = 0u; q < 2u; q++) {
        uint32_t m = ac_inv_mag(mm[q].m);
        uint32_t lim = (q != 0u) ? (uint32_t)AC_INV_ROW_L1_MAX - count : (uint32_t)AC_INV_COEF_MAX;
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
int16_t ac_inv_to_i16(const xf *v, int16_t s)
{
    int32_t q = 0;
    (void)ac_inv_to_fixed(v, s, &q);
    return (int16_t)((q > AC_INV_COEF_MAX) ? AC_INV_COEF_MAX : ((q < -AC_INV_COEF_MAX) ? -AC_INV_COEF_MAX : q));
}

/* ---- the 6x6 inverse -------------------------------------------------------------- */

/* norm = max column sum of |a|; amax = max(amax, max |a_ij|) */
static void norm1(xf a[6][6], xf *norm, xf *amax)
{
    unsigned i, j;
    ac_inv_clear(norm, sizeof *norm);
    for (j = 0u; j < 6u; j++) {
        xf sum[2]; /* the column's sum, and a sum of sums nobody needs */
        const xf *p = &a[0][j];
        ac_inv_clear(sum, sizeof sum);
        for (i = 0u; i < 6u; i++, p += 6) {
            ac_inv_acc_abs(amax, &sum[0], p);
        }
        ac_inv_acc_abs(norm, &sum[1], &sum[0]);
    }
}

ac_status ac_inv_gauss_jordan(xf a[6][6], int8_t perm[6], int16_t *cond_log2)
{
    xf na, ninv, tol;
    unsigned i, k;
    ac_inv_clear(&tol, sizeof tol);
    norm1(a, &na, &tol);
    tol.e = (int16_t)(tol.e + PIVOT_TOL_LOG2);
    for (k = 0u; k < 6u; k++) {
        xf *rk = a[k], *piv = &rk[k], *best = piv, *c = piv, inv;
        unsigned p = k;
        uint32_t n = AC_INV_XF_LO, d, q = 0u;
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
        d = ac_inv_mag(piv->m);
        for (i = 0u; i < 32u; i++) {
            q <<= 1;
            if (n >= d) {
                n -= d;
                q |= 1u;
            }
            n <<= 1;
        }
        ac_inv_pack(&inv, piv->m < 0, q, (int32_t)-60 - piv->e);
        *piv = ac_inv_one;
        for (i = 0u; i < 6u; i++) {
            xf t = rk[i];
            ac_inv_clear(&rk[i], sizeof t);
            ac_inv_mac(&rk[i], &t, &inv, 0u);
        }
        for (i = 0u; i < 6u; i++) {
            xf *ri = a[i], f = ri[k];
            if (i != k) {
                ac_inv_clear(&ri[k], sizeof f);
                for (p = 0u; p < 6u; p++) {
                    ac_inv_mac(&ri[p], &f, &rk[p], 1u);
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
    ac_inv_clear(&tol, sizeof tol);
    ac_inv_mac(&tol, &na, &ninv, 0u);
    na = tol;
    /* cond = m 2^e with 2^29 <= m < 2^30: ceil(log2) is e + 29 for m == 2^29, else e + 30 */
    *cond_log2 = (int16_t)(na.e + ((na.m == (int32_t)AC_INV_XF_LO) ? 29 : 30));
    return (*cond_log2 > AC_COND_LOG2_MAX) ? AC_ERR_ILL_COND : AC_OK;
}
