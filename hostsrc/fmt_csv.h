/* accelcal -- host-only CSV formatting for the Python extension (not part of the C core:
 * built only into accelcal._core by python/accelcal/_build_core.py; hostsrc/ is outside the
 * firmware's sources: CMake and tools/tidy.sh take the .c files of csrc itself). */
#ifndef ACCELCAL_HOST_FMT_CSV_H
#define ACCELCAL_HOST_FMT_CSV_H

#include <stddef.h>
#include <stdint.h>

size_t acx_csv_rows(const char *prefix, size_t prefix_len, const double *values, size_t n_rows,
                    size_t n_cols, char *out, size_t cap);

/* Python's repr of n doubles, one a line ('\n' after each), from their shortest round-trip digits
 * as pyarrow's cast to text writes them (offsets[0..n], data: an Arrow string array's buffers);
 * returns the bytes written, or 0 when cap is short (32 bytes a value and its '\n' suffice) or a
 * text is not of that form. */
size_t acx_repr_lines(const int32_t *offsets, const char *data, size_t n, char *out, size_t cap);

#endif
