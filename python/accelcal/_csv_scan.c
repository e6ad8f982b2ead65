/* accelcal -- host-side fast path for recording CSV rows (see _csv_scan.h). */
#include "_csv_scan.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CELL_MAX 63 /* longer numbers go the slow way */

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* The digits of [p, e) from *q on: their count, *q moved past them. */
static size_t digits(const char *e, const char **q)
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
    if (digits(e, &q) - 1u >= 18u || q != e) { /* none, more than 18, or anything after */
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
    int neg = 0, n_sig = 0, k = 0, ek = 0, eneg = 0, seen_point = 0;
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
    char buf[CELL_MAX + 1];
    const char *q = p;
    size_t n = (size_t)(e - p);
    if (n == 0u || n > CELL_MAX) {
        return 0;
    }
    if (*q == '+' || *q == '-') {
        q++;
    }
    if (digits(e, &q) != 0u) {
        if (q < e && *q == '.') {
            q++;
            (void)digits(e, &q);
        }
    } else if (q < e && *q == '.') {
        q++;
        if (digits(e, &q) == 0u) {
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
        if (digits(e, &q) == 0u) {
            return 0;
        }
    }
    if (q != e) {
        return 0;
    }
    if (!fast_decimal(p, e, out)) {
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
