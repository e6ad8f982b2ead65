/*
 * accelcal -- nonlinearity: the reading's square and cube terms removed.
 * Float reference: python/accelcal/firmware/terms.py (nonlinearity_invert).
 *
 * The channel's reading gained c2 z^2 + c3 z^3 counts, z = linear reading - b_i in counts
 * (c2 = k2 / |s_i|^2, c3 = k3 / |s_i|^3 from the calibration's nonlin_k2, nonlin_k3).  With
 * x the trimmed reading (counts about trim_i ~ b_i), K = the table's iterations fixed-point
 * iterations (0 there: AC_NONLIN_ITERATIONS = 3; at most AC_NONLIN_MAX_ITERATIONS), z_0 = x:
 *   z_{k+1} = clip16(x - C(z_k)),  y = z_K,
 *   C(z) = round(g z 2^-shift),  g = round(h z 2^-15),  h = a2 + round(a3 z 2^-15)
 * with a2[i] = c2 2^(15 + shift), a3[i] = c3 2^(30 + shift) (|a2| + |a3| <= 32767): three
 * 16 x 16 multiplies an iteration, 3 K a channel.  shift in 0..30; C's
 * rounding is a word move for shift >= 16 (the nonlinearity at the full int16 scale below half
 * the reading, |c2| 2^15 + |c3| 2^30 < 1/2: a 16-bit chip), byte moves and up to 7 one-bit
 * shifts for 8..15 (the seed's 1250 counts per g with a cube term of 0.1 % at 1 g: 15), and
 * the generic rounding below 8.
 * Convergence: each iteration shrinks the distance to the exact inverse by
 * L = max |2 c2 z + 3 c3 z^2| over the readings (L = 0.02 for 0.5 % of the reading at 1 g
 * on a +-2 g chip: after K iterations the exact inverse is within L^K C(z)).  A generated
 * header chooses K from the coefficients and the converter's span: the least K >= 3 with
 * L^K max|C| <= 0.25 count at the span, capped at AC_NONLIN_MAX_ITERATIONS (L >= 1 there: the
 * cap; the bent reading is not invertible by this iteration at the span's ends)
 * (python: accelcal.firmware.terms.nonlinearity_iterations).
 * Units: x, y and z are in 2^-k counts when the terms hand on k fraction bits (ac_temp.h's frac,
 * a generated header's <PREFIX>_TERMS_FRAC): the table's coefficients are then per 2^-k count,
 * a2 = c2 2^(15 + shift - k), a3 = c3 2^(30 + shift - 2k), and the arithmetic below is the same
 * (every count in it reads 2^-k count).
 * Error bound against the float iteration with the table's a2, a3 (z_0 = x - o there):
 *   |y - y_ref| <= D_K,  D_0 = 0.5 (o = b - trim),  D_k = E + L D_{k-1},
 *   E = 0.5 + (|z|^2 2^-16 + |z| / 2) 2^-shift   counts (C's rounding; h's and g's),
 * |z| the largest reading involved (python: accelcal.firmware.terms_fixed.nonlin_bound).
 * AC_SATURATED if a z_k clipped to int16.
 * On the H8/300H (normal mode) the function is assembly for shifts 15..30 and K = 3
 * (csrc/ac_terms_h8.c; the iterations unrolled at shifts 15 and 17..19, a loop at 16 and
 * 20..30), the same arithmetic bit for bit; the C of ac_nonlin.c everywhere else
 * (other K included: about 2,070 H8/300H states an iteration for 6 channels in C).
 */
#ifndef AC_NONLIN_H
#define AC_NONLIN_H

#include "ac_config.h"
#include "ac_status.h"

#define AC_NONLIN_ITERATIONS 3
#define AC_NONLIN_MAX_ITERATIONS 16

typedef struct ac_nonlin_table {
    uint16_t n;                   /* channels, 1..AC_MAX_CHANNELS */
    int8_t shift;                 /* 0..30 */
    int16_t a2[AC_MAX_CHANNELS];  /* c2 2^(15 + shift) */
    int16_t a3[AC_MAX_CHANNELS];  /* c3 2^(30 + shift) */
    uint8_t iterations;           /* K, 1..AC_NONLIN_MAX_ITERATIONS; 0: AC_NONLIN_ITERATIONS
                                   * (last, so that tables written without it mean 3) */
} ac_nonlin_table;

/* AC_OK if n, shift and iterations are in range and |a2| + |a3| <= 32767, else AC_ERR_SIZE /
 * AC_ERR_FORMAT. */
ac_status ac_nonlin_check(const ac_nonlin_table *t);

/* x[0..n-1] -> y[0..n-1] (may be the same array).  Per call only n, shift and iterations are checked
 * (AC_ERR_SIZE, AC_ERR_FORMAT); check a table you did not get from a generated header once
 * with ac_nonlin_check (one that breaks |a2| + |a3| <= 32767 gives wrong numbers, never
 * undefined behaviour). */
ac_status ac_nonlin_invert(const ac_nonlin_table *t, const int16_t *x, int16_t *y);

#endif /* AC_NONLIN_H */
