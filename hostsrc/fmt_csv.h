/* accelcal -- host-only CSV formatting for the Python extension (not part of the C core:
 * built only into accelcal._core by python/accelcal/_build_core.py; hostsrc/ is outside the
 * firmware's sources: CMake and tools/tidy.sh take the .c files of csrc itself). */
#ifndef ACCELCAL_HOST_FMT_CSV_H
#define ACCELCAL_HOST_FMT_CSV_H

#include <stddef.h>

size_t acx_csv_rows(const char *prefix, size_t prefix_len, const double *values, size_t n_rows,
                    size_t n_cols, char *out, size_t cap);

#endif
