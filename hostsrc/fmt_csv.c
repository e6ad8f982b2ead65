/* accelcal -- host-only CSV formatting for the Python extension (see fmt_csv.h).
 *
 * acx_csv_rows writes n_rows lines: line i is the i-th '\n'-ended text of prefix (the cells
 * before, already formatted; none when prefix_len is 0), a ',' between cells, then each of the
 * row's n_cols values (row-major) as Python's '%.9g' % x writes it, and '\n'.  Returns the
 * bytes written, or 0 when cap (bytes of out) is short or a prefix line is missing.
 *
 * A cell is snprintf "%.9g" (glibc's is correctly rounded, as Python's is; NaN written "nan"
 * whatever its sign bit), except where g9_fast can tell the nine digits for certain, which is
 * several times faster than glibc's exact arithmetic: |x| in [1e-19, 1e35), scaled by an exact
 * power of ten in long double (64-bit mantissa: one rounding, |error| < 1e9 * 2^-64 < 6e-11)
 * to [1e8, 1e9), and rounded to an integer only when its fraction is not within 1e-6 of a half
 * (an exact or near tie: snprintf decides). */
#include "fmt_csv.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

/* the longest "%.9g": "-1.23456789e-308" (16) and the ',' before it */
#define ACX_CELL_MAX 24
/* the longest repr: "-0.00012345678901234567" (23) or "-1.2345678901234567e-308" (24) */
#define ACX_REPR_MAX 32

/* "d[0][.d[1..nd)]e(+|-)XX[X]" (the exponent e in at least two digits, as printf's %e and Python's
 * repr write it) into out; returns its length. */
static int sci_text(const char *d, int nd, int e, char *out)
{
    int n = 0;
    out[n++] = d[0];
    if (nd > 1) {
        int i;
        out[n++] = '.';
        for (i = 1; i < nd; i++) {
            out[n++] = d[i];
        }
    }
    out[n++] = 'e';
    out[n++] = e < 0 ? '-' : '+';
    e = e < 0 ? -e : e;
    if (e >= 100) {
        out[n++] = (char)('0' + e / 100);
    }
    out[n++] = (char)('0' + (e / 10) % 10);
    out[n++] = (char)('0' + e % 10);
    return n;
}

#if LDBL_MANT_DIG >= 64
/* 10^k, k = 0..27: exact in a 64-bit mantissa (5^27 < 2^63) */
static const long double POW10[28] = {
    1e0L, 1e1L, 1e2L, 1e3L, 1e4L, 1e5L, 1e6L, 1e7L, 1e8L, 1e9L, 1e10L, 1e11L, 1e12L, 1e13L,
    1e14L, 1e15L, 1e16L, 1e17L, 1e18L, 1e19L, 1e20L, 1e21L, 1e22L, 1e23L, 1e24L, 1e25L, 1e26L, 1e27L
};

/* The nine significant digits of |x| (x finite, not 0) as q in [1e8, 1e9) and its decimal
 * exponent e (|x| ~ q * 10^(e - 8)), or 0 where they are not certain. */
static int g9_digits(double x, long q_out[1], int e_out[1])
{
    double a = fabs(x);
    int e;
    int k;
    long double y;
    long double fl;
    long double frac;
    long q;
    if (!(a >= 1e-19 && a < 1e35)) {
        return 0;
    }
    (void)frexp(a, &e);                 /* a in [2^(e-1), 2^e): log10(a) within 0.302 below e*log10(2) */
    e = (int)floor((double)(e - 1) * 0.30102999566398120);   /* off by one at most: corrected below */
    k = 8 - e;
    if (k < -27 || k > 27) {
        return 0;
    }
    y = k >= 0 ? (long double)a * POW10[k] : (long double)a / POW10[-k];
    if (y >= 1e9L) {
        e += 1;
        k -= 1;
    } else if (y < 1e8L) {
        e -= 1;
        k += 1;
    } else {
        k = 99;
    }
    if (k != 99) {
        if (k < -27 || k > 27) {
            return 0;
        }
        y = k >= 0 ? (long double)a * POW10[k] : (long double)a / POW10[-k];
        if (y < 1e8L || y >= 1e9L) {
            return 0;
        }
    }
    fl = (long double)(long)y;          /* y > 0: truncation is the floor */
    frac = y - fl;
    if (fabsl(frac - 0.5L) < 1e-6L) {
        return 0;
    }
    q = (long)fl + (frac > 0.5L ? 1 : 0);
    if (q == 1000000000L) {
        q = 100000000L;
        e += 1;
    }
    q_out[0] = q;
    e_out[0] = e;
    return 1;
}

/* '%.9g' of x (finite, not 0) into out (ACX_CELL_MAX bytes), as printf writes it; returns its
 * length, or 0 where g9_digits is not certain. */
static int g9_fast(double x, char *out)
{
    long q;
    int e;
    char d[9];
    int nd = 9;
    int n = 0;
    int i;
    if (!g9_digits(x, &q, &e)) {
        return 0;
    }
    for (i = 8; i >= 0; i--) {
        d[i] = (char)('0' + (int)(q % 10));
        q /= 10;
    }
    while (nd > 1 && d[nd - 1] == '0') {
        nd--;
    }
    if (signbit(x)) {
        out[n++] = '-';
    }
    if (e >= -4 && e < 9) {
        if (e >= 0) {
            for (i = 0; i <= e; i++) {
                if (i < nd) {
                    out[n++] = d[i];
                } else {
                    out[n++] = '0';
                }
            }
            if (nd > e + 1) {
                out[n++] = '.';
                for (i = e + 1; i < nd; i++) {
                    out[n++] = d[i];
                }
            }
        } else {
            out[n++] = '0';
            out[n++] = '.';
            for (i = 0; i < -e - 1; i++) {
                out[n++] = '0';
            }
            for (i = 0; i < nd; i++) {
                out[n++] = d[i];
            }
        }
        return n;
    }
    return n + sci_text(d, nd, e, out + n);
}
#else
static int g9_fast(double x, char *out)
{
    (void)x;
    (void)out;
    return 0;
}
#endif

size_t acx_csv_rows(const char *prefix, size_t prefix_len, const double *values, size_t n_rows,
                    size_t n_cols, char *out, size_t cap)
{
    size_t pos = 0;
    size_t p = 0;
    size_t i;
    for (i = 0; i < n_rows; i++) {
        size_t j;
        int first = 1;
        if (prefix_len > 0) {
            const char *nl = memchr(prefix + p, '\n', prefix_len - p);
            size_t len;
            if (p >= prefix_len || nl == NULL) {
                return 0;
            }
            len = (size_t)(nl - (prefix + p));
            if (pos + len + n_cols * ACX_CELL_MAX + 1 > cap) {
                return 0;
            }
            memcpy(out + pos, prefix + p, len);
            pos += len;
            p += len + 1;
            first = 0;
        } else if (pos + n_cols * ACX_CELL_MAX + 1 > cap) {
            return 0;
        }
        for (j = 0; j < n_cols; j++) {
            double x = values[i * n_cols + j];
            int k;
            if (!first) {
                out[pos++] = ',';
            }
            first = 0;
            if (isnan(x)) {
                out[pos++] = 'n';
                out[pos++] = 'a';
                out[pos++] = 'n';
                continue;
            }
            if (x == 0.0) {
                if (signbit(x)) {
                    out[pos++] = '-';
                }
                out[pos++] = '0';
                continue;
            }
            k = isfinite(x) ? g9_fast(x, out + pos) : 0;
            if (k > 0) {
                pos += (size_t)k;
                continue;
            }
            k = snprintf(out + pos, ACX_CELL_MAX, "%.9g", x);
            if (k < 0 || k >= ACX_CELL_MAX) {
                return 0;
            }
            pos += (size_t)k;
        }
        out[pos++] = '\n';
    }
    return pos;
}

/* The characters of word (no NUL: a cell of a line) into out; returns their number. */
static int put_word(const char *word, char *out)
{
    int n = 0;
    while (word[n] != '\0') {
        out[n] = word[n];
        n++;
    }
    return n;
}

/* One line of acx_repr_lines: the shortest round-trip digits in src[0..len) (pyarrow's cast of a
 * double to text: "[-]digits[.digits][e(+|-)digits]", "nan", "inf") laid out as Python's repr
 * writes them, into out (ACX_REPR_MAX bytes); returns its length, or 0 for any other text. */
static int repr_line(const char *src, size_t len, char *out)
{
    char d[32];
    int nd = 0;
    int point = -1;             /* digits before the '.' (-1: no '.') */
    int exp10 = 0;
    int neg = 0;
    int lead;
    int p;
    int n = 0;
    size_t k = 0;
    if (len > 0 && src[0] == '-') {
        neg = 1;
        k = 1;
    }
    if (len - k == 3 && memcmp(src + k, "nan", 3) == 0) {
        return put_word("nan", out);
    }
    if (len - k == 3 && memcmp(src + k, "inf", 3) == 0) {
        if (neg) {
            out[n++] = '-';
        }
        return n + put_word("inf", out + n);
    }
    for (; k < len; k++) {
        char c = src[k];
        if (c >= '0' && c <= '9') {
            if (nd >= (int)sizeof d) {
                return 0;
            }
            d[nd++] = c;
        } else if (c == '.' && point < 0 && nd > 0) {
            point = nd;
        } else if (c == 'e' && nd > 0 && k + 2 < len + 1) {
            int es = 1;
            int ev = 0;
            int ed = 0;
            k++;
            if (k < len && (src[k] == '+' || src[k] == '-')) {
                es = src[k] == '-' ? -1 : 1;
                k++;
            }
            for (; k < len; k++) {
                if (src[k] < '0' || src[k] > '9' || ed >= 4) {
                    return 0;
                }
                ev = ev * 10 + (src[k] - '0');
                ed++;
            }
            if (ed == 0) {
                return 0;
            }
            exp10 = es * ev;
            break;
        } else {
            return 0;
        }
    }
    if (nd == 0) {
        return 0;
    }
    /* value = 0.d[0..nd) x 10^p */
    p = (point < 0 ? nd : point) + exp10;
    for (lead = 0; lead < nd && d[lead] == '0'; lead++) {
        p--;
    }
    while (nd > lead && d[nd - 1] == '0') {
        nd--;
    }
    if (neg) {
        out[n++] = '-';
    }
    if (nd == lead) {                   /* zero */
        return n + put_word("0.0", out + n);
    }
    if (nd - lead > 17) {
        return 0;
    }
    if (p > -4 && p <= 16) {            /* Python's repr: positional for 1e-4 <= |x| < 1e16 */
        int i;
        if (p <= 0) {
            out[n++] = '0';
            out[n++] = '.';
            for (i = 0; i < -p; i++) {
                out[n++] = '0';
            }
            for (i = lead; i < nd; i++) {
                out[n++] = d[i];
            }
        } else if (p >= nd - lead) {
            for (i = lead; i < nd; i++) {
                out[n++] = d[i];
            }
            for (i = nd - lead; i < p; i++) {
                out[n++] = '0';
            }
            out[n++] = '.';
            out[n++] = '0';
        } else {
            for (i = lead; i < lead + p; i++) {
                out[n++] = d[i];
            }
            out[n++] = '.';
            for (; i < nd; i++) {
                out[n++] = d[i];
            }
        }
        return n;
    }
    return n + sci_text(d + lead, nd - lead, p - 1, out + n);
}

size_t acx_repr_lines(const int32_t *offsets, const char *data, size_t n, char *out, size_t cap)
{
    size_t pos = 0;
    size_t i;
    for (i = 0; i < n; i++) {
        int k;
        if (offsets[i + 1] < offsets[i] || pos + ACX_REPR_MAX + 1 > cap) {
            return 0;
        }
        k = repr_line(data + offsets[i], (size_t)(offsets[i + 1] - offsets[i]), out + pos);
        if (k <= 0) {
            return 0;
        }
        pos += (size_t)k;
        out[pos++] = '\n';
    }
    return pos;
}
