/*
 * accelcal -- host-side fast paths for the data rows of CSV files
 * (python/accelcal/recording.py, estimators.py).  Not firmware: it uses libc
 * (strtod, snprintf) and double, and is compiled only into the Python extension.
 *
 * Reading: acx_scan_rows converts only what is certainly valid and leaves every
 * decision about anything else -- and every error message -- to the Python
 * reader: it stops at the first row it does not convert, and the caller then
 * reads the file the slow way.
 *
 * Writing: acx_format_rows writes exactly the text Python's str(), repr() and
 * '%.<p>g' % x give (the tests compare them byte for byte).
 */
#ifndef ACCELCAL_CSV_FAST_H
#define ACCELCAL_CSV_FAST_H

#include <stddef.h>
#include <stdint.h>

/* What a column holds (kind[j]); slot[j] is its column in ints or floats. */
#define ACX_SKIP 0        /* an unknown column: any cell without a quote */
#define ACX_INT 1         /* [+-]?[0-9]{1,18} */
#define ACX_INT_OR_EMPTY 2 /* the same, or empty (stored as -1); -1 is the least value taken */
#define ACX_FLOAT 3       /* a finite decimal number (no nan/inf words) */
#define ACX_FLOAT_OR_EMPTY 4 /* the same, or empty (stored as NaN) */

/* Rows are data[0..len), separated by '\n', n_rows of them, each of m cells
 * separated by ','.  Column j goes to ints[slot[j] * n_rows + i] or
 * floats[slot[j] * n_rows + i] (one contiguous array a column).  Returns n_rows
 * when every row was converted and the data end with the last; otherwise a
 * smaller number (the index of the first row not converted, or n_rows - 1 when
 * data are left after n_rows rows), and the outputs are partial. */
int64_t acx_scan_rows(const char *data, size_t len, int64_t n_rows, int m, const int8_t *kind,
                      const int16_t *slot, int64_t *ints, double *floats);

/* Column kinds of acx_format_rows (kind[j]); prec[j] is the precision of ACX_G*. */
#define ACX_OUT_INT 1    /* int64: str(v) */
#define ACX_OUT_REPR 2   /* double: repr(x), the shortest text that reads back to x */
#define ACX_OUT_G 3      /* double: '%.<p>g' % x, and an empty cell for NaN */
#define ACX_OUT_G_NAN 4  /* double: '%.<p>g' % x, 'nan' / 'inf' / '-inf' as Python writes them */
#define ACX_CELL_MAX 32  /* the longest cell any kind writes (24 characters), rounded up */

/* Rows [row0, row0 + n) of the m columns cols[j] (int64 or double arrays of
 * at least row0 + n values), cells separated by ',' and every row ended by '\n',
 * into buf.  cap must be at least n * m * (ACX_CELL_MAX + 1); returns the
 * number of bytes written, -1 for a bad kind or precision (1..17), or -2 (nothing
 * written) while the C library's numeric locale has a decimal point other than '.'
 * (acx_scan_rows then converts no row either). */
int64_t acx_format_rows(int64_t row0, int64_t n, int m, const int8_t *kind, const int8_t *prec,
                        const void *const *cols, char *buf, size_t cap);

#endif /* ACCELCAL_CSV_FAST_H */
