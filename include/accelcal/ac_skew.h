/*
 * accelcal -- time skew: each channel delayed by its own fractional number of
 * samples, by linear interpolation between its successive samples, so that every
 * channel reads the same instant.  Float reference: python/accelcal/firmware/terms.py
 * (skew_correct).
 *
 * Channel i's sample is taken tau_i late (it reads the motion at t + tau_i); with the
 * latency m (whole samples, AC_CAL_SKEW_LATENCY in a generated header: the least m >= 0
 * with m + tau_i / dt >= 0 for all i) the delay j_i = m + tau_i / dt = whole[i] + frac[i] 2^-15
 * samples takes every channel to the common instant t_n - m dt:
 *   y_i[n] = v0 + round(frac[i] (v1 - v0) 2^-15),  v0 = x_i[n - whole[i]], v1 = x_i[n - whole[i] - 1]
 * (one 16 x 16 multiply a channel; the result lies between v0 and v1, so it never clips).
 * Scale-free: x and y in the unit the terms hand on (2^-k counts, ac_temp.h's frac).
 * Error bound against the float interpolation with the table's delay: 0.5 of that unit (the
 * rounding, 2^-(k+1) counts); against the unquantised delay add 2^-16 |v1 - v0|.
 *
 * The delay line is the caller's: len x n int16 (len = whole_max + 2 samples a channel,
 * AC_CAL_SKEW_LEN), e.g. `static int16_t line[AC_CAL_SKEW_LEN * AC_CAL_N_CHANNELS];`,
 * handed to ac_skew_init; the first ac_skew_step fills it with its input.
 */
#ifndef AC_SKEW_H
#define AC_SKEW_H

#include "ac_config.h"
#include "ac_status.h"

#define AC_SKEW_FRAC 15
#ifndef AC_SKEW_MAX_LEN
#define AC_SKEW_MAX_LEN 64
#endif

typedef struct ac_skew_table {
    uint16_t n;                       /* channels, 1..AC_MAX_CHANNELS */
    uint16_t len;                     /* samples kept a channel, 2..AC_SKEW_MAX_LEN */
    uint8_t whole[AC_MAX_CHANNELS];   /* floor(j_i), 0..len - 2 */
    uint16_t frac[AC_MAX_CHANNELS];   /* (j_i - whole) 2^AC_SKEW_FRAC, 0..32767 */
} ac_skew_table;

typedef struct ac_skew_line {
    int16_t *buf;     /* the caller's len x n values, slot-major */
    uint16_t n;
    uint16_t len;
    uint16_t pos;     /* the newest slot */
    uint8_t started;
} ac_skew_line;

/* AC_OK if the table is in range, AC_ERR_SIZE / AC_ERR_FORMAT if not. */
ac_status ac_skew_check(const ac_skew_table *t);

/* Attach the caller's buffer of buf_values int16 (>= t->len * t->n) to the line. */
ac_status ac_skew_init(ac_skew_line *line, const ac_skew_table *t, int16_t *buf, uint16_t buf_values);

/* One sample: x[0..n-1] in, y[0..n-1] (the common instant) out. */
ac_status ac_skew_step(const ac_skew_table *t, ac_skew_line *line, const int16_t *x, int16_t *y);

#endif /* AC_SKEW_H */
