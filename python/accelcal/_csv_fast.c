/* accelcal -- host-side fast paths for CSV rows (see _csv_fast.h). */
#include "_csv_fast.h"

#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CELL_MAX 63 /* longer numbers go the slow way */

/* strtod and snprintf follow the C library's numeric locale: the fast paths run
 * only while its decimal point is '.', as in the "C" locale (a program may have
 * set another; Python itself never depends on it). */
static int c_numeric_locale(void)
{
    const char *d = localeconv()->decimal_point;
    return d[0] == '.' && d[1] == '\0';
}

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* The digits of [p, e) from *q on: their count, *q moved past them. */
static size_t skip_digits(const char *e, const char **q)
{
    const char *s = *q;
    while (*q < e && is_digit(**q)) {
        (*q)++;
    }
    return (size_t)(*q - s);
}

/* [+-]?[0-9]{1,18} exactly */
static int parse_int(const char *p, const char *e, int64_t *out)
{
    int neg = 0;
    int64_t v = 0;
    const char *q;
    if (p < e && (*p == '+' || *p == '-')) {
        neg = *p == '-';
        p++;
    }
    q = p;
    if (skip_digits(e, &q) - 1u >= 18u || q != e) { /* none, more than 18, or anything after */
        return 0;
    }
    for (; p < e; p++) {
        v = v * 10 + (*p - '0');
    }
    *out = neg ? -v : v;
    return 1;
}

/* Clinger's fast path for a cell already known to be in the grammar below: with
 * at most 15 significant digits (mantissa < 2^53) and a power of ten within
 * 10^+-22 (exact in double), mantissa * 10^k or mantissa / 10^-k is one
 * correctly rounded operation on exact operands -- the value strtod gives.
 * Returns 0 (strtod decides) otherwise. */
static int fast_decimal(const char *p, const char *e, double *out)
{
    static const double pow10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                     1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                     1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
    uint64_t mant = 0u;
    int neg = 0, n_sig = 0, k = 0, seen_point = 0;
    if (*p == '+' || *p == '-') {
        neg = *p == '-';
        p++;
    }
    for (; p < e && *p != 'e' && *p != 'E'; p++) {
        if (*p == '.') {
            seen_point = 1;
            continue;
        }
        if (mant != 0u || *p != '0') { /* leading zeros are not significant */
            if (++n_sig > 15) {
                return 0;
            }
            mant = mant * 10u + (uint64_t)(*p - '0');
        }
        if (seen_point) {
            k--;
        }
    }
    if (p < e) { /* the exponent */
        int ek = 0, eneg = 0;
        p++;
        if (*p == '+' || *p == '-') {
            eneg = *p == '-';
            p++;
        }
        for (; p < e; p++) {
            if (ek > 1000) {
                return 0;
            }
            ek = ek * 10 + (*p - '0');
        }
        k += eneg ? -ek : ek;
    }
    if (k < -22 || k > 22) {
        return 0;
    }
    *out = (k >= 0) ? (double)mant * pow10[k] : (double)mant / pow10[-k];
    if (neg) {
        *out = -*out;
    }
    return 1;
}

/* The decimal grammar of recording.py's _FLOAT_RE without its words:
 * [+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?, finite. */
static int parse_float(const char *p, const char *e, double *out)
{
    const char *q = p;
    size_t n = (size_t)(e - p);
    if (n == 0u || n > CELL_MAX) {
        return 0;
    }
    if (*q == '+' || *q == '-') {
        q++;
    }
    if (skip_digits(e, &q) != 0u) {
        if (q < e && *q == '.') {
            q++;
            (void)skip_digits(e, &q);
        }
    } else if (q < e && *q == '.') {
        q++;
        if (skip_digits(e, &q) == 0u) {
            return 0;
        }
    } else {
        return 0;
    }
    if (q < e && (*q == 'e' || *q == 'E')) {
        q++;
        if (q < e && (*q == '+' || *q == '-')) {
            q++;
        }
        if (skip_digits(e, &q) == 0u) {
            return 0;
        }
    }
    if (q != e) {
        return 0;
    }
    if (!fast_decimal(p, e, out)) {
        char buf[CELL_MAX + 1];
        memcpy(buf, p, n);
        buf[n] = '\0';
        *out = strtod(buf, NULL); /* correctly rounded, as Python's float() */
    }
    return isfinite(*out);
}

int64_t acx_scan_rows(const char *data, size_t len, int64_t n_rows, int m, const int8_t *kind,
                      const int16_t *slot, int64_t *ints, double *floats)
{
    const char *p = data, *end = data + len;
    int64_t i;
    if (!c_numeric_locale()) {
        return 0;
    }
    for (i = 0; i < n_rows; i++) {
        int j;
        for (j = 0; j < m; j++) {
            const char *e = p;
            while (e < end && *e != ',' && *e != '\n' && *e != '"') {
                e++;
            }
            if ((e < end && *e == '"') || (j < m - 1 && (e == end || *e != ','))
                || (j == m - 1 && e < end && *e != '\n')) {
                return i; /* a quote, or not m cells in this row */
            }
            switch (kind[j]) {
            case ACX_SKIP:
                break;
            case ACX_INT:
            case ACX_INT_OR_EMPTY: {
                const int empty_ok = kind[j] == ACX_INT_OR_EMPTY; /* the pose column: -1 while moving */
                int64_t v = -1;
                if (!(empty_ok && e == p) && (!parse_int(p, e, &v) || (empty_ok && v < -1))) {
                    return i;
                }
                ints[slot[j] * n_rows + i] = v;
                break;
            }
            case ACX_FLOAT:
            case ACX_FLOAT_OR_EMPTY: {
                double x = NAN;
                if (!(kind[j] == ACX_FLOAT_OR_EMPTY && e == p) && !parse_float(p, e, &x)) {
                    return i;
                }
                floats[slot[j] * n_rows + i] = x;
                break;
            }
            default:
                return i;
            }
            p = (e < end) ? e + 1 : e;
        }
    }
    return (p == end) ? n_rows : n_rows - 1; /* rows left over: the caller counted wrong */
}

/* ---- writing ------------------------------------------------------------------------ */

static char *put_int(char *o, int64_t v)
{
    char tmp[24];
    int k = 0;
    uint64_t u = (v < 0) ? (uint64_t)0 - (uint64_t)v : (uint64_t)v;
    if (v < 0) {
        *o++ = '-';
    }
    do {
        tmp[k++] = (char)('0' + (int)(u % 10u));
        u /= 10u;
    } while (u != 0u);
    while (k > 0) {
        *o++ = tmp[--k];
    }
    return o;
}

static char *put_text(char *o, const char *t)
{
    while (*t != '\0') {
        *o++ = *t++;
    }
    return o;
}

/* The p-digit decimal next to the one in sci ("[-]d.ddde[+-]X", p digits) in the
 * direction dir (+1 up, -1 down in magnitude), written back into sci. */
static void next_decimal(char *sci, int p, int dir)
{
    char digits[20];
    char *q = sci;
    int i, exp10, neg = *q == '-', nd = 0;
    if (neg) {
        q++;
    }
    for (; *q != 'e'; q++) {
        if (*q != '.') {
            digits[nd++] = *q;
        }
    }
    exp10 = atoi(q + 1);
    for (i = nd - 1; i >= 0; i--) { /* add or subtract one unit in the last place */
        if (dir > 0 && digits[i] == '9') {
            digits[i] = '0';
        } else if (dir < 0 && digits[i] == '0') {
            digits[i] = '9';
        } else {
            digits[i] = (char)(digits[i] + dir);
            break;
        }
    }
    if (i < 0) { /* 9.99 -> 10.0: one digit more in front */
        memmove(digits + 1, digits, (size_t)(nd - 1));
        digits[0] = '1';
        exp10++;
    } else if (digits[0] == '0') { /* 1.00 -> 0.99: the leading digit became zero */
        memmove(digits, digits + 1, (size_t)(nd - 1));
        digits[nd - 1] = '9';
        exp10--;
    }
    q = sci;
    if (neg) {
        q++;
    }
    (void)snprintf((char *)q, 40, "%c%s%.*se%+03d", digits[0], (p > 1) ? "." : "", p - 1, digits + 1, exp10);
}

/* repr(x) for finite x: the shortest digits that read back to x, the nearer to x
 * of the two decimals of that length around it (as Python picks), laid out as
 * Python does: positional for 1e-4 <= |x| < 1e16 with ".0" on whole numbers,
 * else d.ddde+XX.  Lengths are tried from 15 digits up (a shorter form that
 * reads back is the 15-digit rounding with its zeros dropped, for a normal
 * double), from 1 for subnormals.  The correctly rounded decimal is tried first;
 * at a power of two, where the interval that reads back is lopsided, also its
 * neighbour on the other side of x, which may read back when the nearer does not
 * (elsewhere the interval is symmetric and the nearer decimal decides). */
static char *put_repr(char *o, double x)
{
    char sci[48], digits[20];
    int p, nd = 0, exp10;
    const char *q;
    int e2;
    /* only at a power of two can the farther decimal read back when the nearer does not */
    const int lopsided = fabs(frexp(x, &e2)) == 0.5;
    for (p = (x != 0.0 && fabs(x) < DBL_MIN) ? 1 : 15; p < 17; p++) {
        double y;
        (void)snprintf(sci, sizeof sci, "%.*e", p - 1, x);
        y = strtod(sci, NULL);
        if (y == x) {
            break;
        }
        if (lopsided) {
            next_decimal(sci, p, ((y < x) == (x > 0)) ? 1 : -1);
            if (strtod(sci, NULL) == x) {
                break;
            }
        }
    }
    if (p == 17) {
        (void)snprintf(sci, sizeof sci, "%.16e", x); /* 17 digits always read back */
    }
    q = sci;
    if (*q == '-') {
        *o++ = '-';
        q++;
    }
    for (; *q != 'e'; q++) {
        if (*q != '.') {
            digits[nd++] = *q;
        }
    }
    exp10 = atoi(q + 1);
    while (nd > 1 && digits[nd - 1] == '0') {
        nd--;
    }
    if (exp10 >= -4 && exp10 < 16) {
        int i;
        if (exp10 < 0) {
            *o++ = '0';
            *o++ = '.';
            for (i = 0; i < -exp10 - 1; i++) {
                *o++ = '0';
            }
            for (i = 0; i < nd; i++) {
                *o++ = digits[i];
            }
            return o;
        }
        for (i = 0; i <= exp10; i++) {
            *o++ = (i < nd) ? digits[i] : '0';
        }
        *o++ = '.';
        if (nd <= exp10 + 1) {
            *o++ = '0';
        }
        for (i = exp10 + 1; i < nd; i++) {
            *o++ = digits[i];
        }
        return o;
    }
    *o++ = digits[0];
    if (nd > 1) {
        *o++ = '.';
        memcpy(o, digits + 1, (size_t)(nd - 1));
        o += nd - 1;
    }
    *o++ = 'e';
    *o++ = (exp10 < 0) ? '-' : '+';
    if (exp10 < 0) {
        exp10 = -exp10;
    }
    if (exp10 < 10) {
        *o++ = '0';
    }
    return put_int(o, exp10);
}

int64_t acx_format_rows(int64_t row0, int64_t n, int m, const int8_t *kind, const int8_t *prec,
                        const void *const *cols, char *buf, size_t cap)
{
    char *o = buf;
    int64_t i;
    int j;
    if (n < 0 || m < 1 || (size_t)n * (size_t)m * (ACX_CELL_MAX + 1u) > cap) {
        return -1;
    }
    if (!c_numeric_locale()) {
        return -2;
    }
    for (j = 0; j < m; j++) {
        if (kind[j] < ACX_OUT_INT || kind[j] > ACX_OUT_G_NAN
            || (kind[j] >= ACX_OUT_G && (prec[j] < 1 || prec[j] > 17))) {
            return -1;
        }
    }
    for (i = row0; i < row0 + n; i++) {
        for (j = 0; j < m; j++) {
            if (kind[j] == ACX_OUT_INT) {
                o = put_int(o, ((const int64_t *)cols[j])[i]);
            } else {
                const double x = ((const double *)cols[j])[i];
                if (isnan(x)) {
                    o = (kind[j] == ACX_OUT_G_NAN) ? put_text(o, "nan") : o;
                } else if (isinf(x)) {
                    o = put_text(o, (x < 0) ? "-inf" : "inf");
                } else if (kind[j] == ACX_OUT_REPR) {
                    o = put_repr(o, x);
                } else {
                    o += snprintf(o, ACX_CELL_MAX, "%.*g", (int)prec[j], x);
                }
            }
            *o++ = (j == m - 1) ? '\n' : ',';
        }
    }
    return (int64_t)(o - buf);
}
