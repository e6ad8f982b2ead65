/*
 * accelcal -- libFuzzer harness for the host-side CSV fast paths
 * (python/accelcal/_csv_fast.c: what reads and writes the recordings that
 * come from outside).  Built and run by tools/fuzz.sh with ASan + UBSan.
 *
 * Input: byte 0 picks the number of columns m (1..8), bytes 1..m their kinds,
 * the rest is CSV text.  Properties (a failure aborts with "property failed"):
 *   - acx_scan_rows returns a row count in [0, n_rows] and reads nothing
 *     outside the text (ASan);
 *   - every number it converted, written back with acx_format_rows (repr for
 *     doubles, str for ints) and scanned again, is the same number, bit for bit;
 *   - any 8 bytes of the input as a double, written as repr and scanned, give
 *     that double back (finite values), and '%.17g' reads back too.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "_csv_fast.h"

#define MAX_COLS 8

static void fail(const char *what)
{
    fprintf(stderr, "property failed: %s\n", what);
    abort();
}

/* scan one cell of text (a single row, one column) as a double or an int64 */
static int scan1(const char *text, size_t len, int8_t kind, double *x, int64_t *v)
{
    const int16_t slot = 0;
    return acx_scan_rows(text, len, 1, 1, &kind, &slot, v, x) == 1;
}

static void check_round_trip_double(double x)
{
    char buf[2 * (ACX_CELL_MAX + 1)];
    const void *cols[1];
    const int8_t kinds[2] = {ACX_OUT_REPR, ACX_OUT_G};
    const int8_t prec[2] = {0, 17};
    double y = 0.0;
    int64_t unused = 0;
    int k;
    if (!isfinite(x)) {
        return;
    }
    cols[0] = &x;
    for (k = 0; k < 2; k++) {
        int64_t n = acx_format_rows(0, 1, 1, &kinds[k], &prec[k], cols, buf, sizeof buf);
        if (n < 2 || buf[n - 1] != '\n') {
            fail("format gave no row");
        }
        if (!scan1(buf, (size_t)(n - 1), ACX_FLOAT, &y, &unused)) {
            fail("a formatted double does not scan");
        }
        if (memcmp(&x, &y, sizeof x) != 0) {
            fail("a double does not read back bit for bit");
        }
    }
}

static void check_round_trip_int(int64_t v)
{
    char buf[ACX_CELL_MAX + 1];
    const void *cols[1];
    const int8_t kind = ACX_OUT_INT, prec = 0;
    int64_t w = 0;
    double unused = 0.0;
    int64_t n;
    cols[0] = &v;
    n = acx_format_rows(0, 1, 1, &kind, &prec, cols, buf, sizeof buf);
    if (n < 2) {
        fail("format gave no row");
    }
    /* the scanner takes up to 18 digits; longer ones are the Python reader's */
    if (scan1(buf, (size_t)(n - 1), ACX_INT, &unused, &w) && w != v) {
        fail("an int does not read back");
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    int8_t kind[MAX_COLS];
    int16_t slot[MAX_COLS];
    int m, j, n_int = 0, n_float = 0;
    int64_t n_rows = 1, done, i;
    const char *text;
    size_t len, k;
    int64_t *ints;
    double *floats;
    if (size < 1) {
        return 0;
    }
    m = 1 + data[0] % MAX_COLS;
    if (size < (size_t)(1 + m)) {
        return 0;
    }
    for (j = 0; j < m; j++) {
        kind[j] = (int8_t)(data[1 + j] % 5); /* ACX_SKIP .. ACX_FLOAT_OR_EMPTY */
        slot[j] = (int16_t)((kind[j] == ACX_INT || kind[j] == ACX_INT_OR_EMPTY) ? n_int++ : n_float++);
    }
    text = (const char *)data + 1 + m;
    len = size - 1 - (size_t)m;
    for (k = 0; k < len; k++) {
        n_rows += text[k] == '\n';
    }
    /* an exact-size copy, so that ASan sees any read past the end */
    {
        char *copy = (char *)malloc(len ? len : 1);
        if (copy == NULL) {
            return 0;
        }
        memcpy(copy, text, len);
        ints = (int64_t *)calloc((size_t)(n_int ? n_int : 1) * (size_t)n_rows, sizeof *ints);
        floats = (double *)calloc((size_t)(n_float ? n_float : 1) * (size_t)n_rows, sizeof *floats);
        if (ints == NULL || floats == NULL) {
            free(copy);
            free(ints);
            free(floats);
            return 0;
        }
        done = acx_scan_rows(copy, len, n_rows, m, kind, slot, ints, floats);
        free(copy);
    }
    if (done < 0 || done > n_rows) {
        fail("scan returned a row count out of range");
    }
    for (i = 0; i < done; i++) {
        for (j = 0; j < m; j++) {
            if (kind[j] == ACX_INT || kind[j] == ACX_INT_OR_EMPTY) {
                check_round_trip_int(ints[slot[j] * n_rows + i]);
            } else if (kind[j] != ACX_SKIP) {
                check_round_trip_double(floats[slot[j] * n_rows + i]);
            }
        }
    }
    free(ints);
    free(floats);
    for (k = 0; k + 8 <= size; k += 8) {
        double x;
        int64_t v;
        memcpy(&x, data + k, sizeof x);
        memcpy(&v, data + k, sizeof v);
        check_round_trip_double(x);
        check_round_trip_int(v);
    }
    return 0;
}
