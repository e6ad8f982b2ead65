/*
 * accelcal -- host-side fast path for the data rows of a recording CSV
 * (python/accelcal/recording.py).  Not firmware: it uses libc (strtod) and
 * double, and is compiled only into the Python extension.
 *
 * It converts only what is certainly valid and leaves every decision about
 * anything else -- and every error message -- to the Python reader: it stops at
 * the first row it does not convert and returns that row's index, and the
 * caller then reads the file the slow way.
 */
#ifndef ACCELCAL_CSV_SCAN_H
#define ACCELCAL_CSV_SCAN_H

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

#endif /* ACCELCAL_CSV_SCAN_H */
