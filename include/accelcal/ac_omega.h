/*
 * accelcal -- angular rate from the accelerometers themselves (issue 36): the
 * array's maximum-likelihood omega fused with the integration of its alpha,
 * in integer arithmetic (a port of python/accelcal/estimators/omega_filter.py).
 *
 * Model (docs/angular-rate.md): with y = x - o the readings minus the residual
 * offsets, the layout gives six whitened "centripetal readings" q = Q y with
 * q = m p(w) + v, v ~ N(0, m), p(w) = (wx^2, wy^2, wz^2, wx wy, wy wz, wz wx),
 * and alpha = A y - L p(w) (A: the resolver's alpha rows, L the leak of the
 * centripetal term into alpha).  Per sample, with the state (w, P) of the
 * sample before:
 *
 *   1. prediction: alpha at w, F = I - dt L J(w), P = F P F^T + Qn;
 *      w0 = w + dt/2 (alpha[n-1] + alpha(w)); w = w + dt/2 (alpha[n-1] + alpha(w0))
 *      (the first sample after ac_omega_init has none: w = 0, P = P0);
 *   2. jump test: the per-sample ML estimate c (closed form: the column of
 *      phat = m^-1 q with the largest diagonal entry over the root of that
 *      entry, then AC_OMEGA_ML_ITER Gauss-Newton steps with a ridge), its sign
 *      the one nearer w; when cost(c) < cost(w) - jump the prior is centred
 *      on c (flag AC_OMEGA_FLAG_JUMP).  cost(x) = (x-w)^T P^-1 (x-w) +
 *      p^T m p - 2 q^T p, the difference taken as (c-w)^T P^-1 (c-w) +
 *      (p(c) - p(w))^T (m (p(c) + p(w)) - 2 q) (the costs are some q^T m^-1 q,
 *      up to 1e11, their difference a few units).  The ML is skipped when no c
 *      can pass the test: (p(w) - m^-1 q)^T m (p(w) - m^-1 q) <= jump (the
 *      cost's lower bound -q^T m^-1 q): the same result;
 *   3. AC_OMEGA_ITER Gauss-Newton steps on the cost;
 *   4. P = (P^-1 + J^T m J)^-1; alpha[n] at the new w.
 *
 * Arithmetic and scaling:
 *   - q and the uncorrected alpha: each row's coefficients in two int16 parts,
 *     t + tl 2^-AC_OMEGA_LO_BITS (about 25 significant bits: whitened q needs
 *     some 1e-5 relative at readings of 3e4 counts, one int16 gives 2e-4);
 *     sum_i t[j][i] x_i and sum_i tl[j][i] x_i, int16 x int16 into int32
 *     accumulators, exact (table invariant sum_i |t| <= 65535, the same for tl);
 *     then  row_j = acc 2^-shift[j] + acc_lo 2^-(shift[j]+12) - k[j]  in ac_xf.
 *     Units: q in whitened counts (counts / noise sd), alpha in rad/s^2.
 *   - everything after is ac_xf (30-bit mantissa, 16-bit exponent, each
 *     operation rounded to nearest): no fixed Q format spans q (up to 1e5),
 *     m (1e1..1e2), the information (1e6 per (rad/s)^2) and P (1e-7 (rad/s)^2)
 *     together, and ac_xf does, with no overflow short of 2^30000.
 *   - the square root (closed-form start, ac_omega_sigma) is 6 Newton steps
 *     on ac_xf from the exponent's half: relative error < 2^-28.
 *   - outputs: omega in rad/s as int32 Q15.16 (AC_OMEGA_Q16_FRAC, rounded
 *     half up; beyond +-32768 rad/s clipped, AC_SATURATED) and as int16 Q5.10
 *     (AC_OMEGA_FRAC, ac_resolve's input; beyond +-32 rad/s clipped,
 *     AC_SATURATED and AC_OMEGA_FLAG_SAT16).
 *
 * Overflow: none in the int32 accumulations (invariant above).  An ac_xf
 * exponent beyond +-30000 or a singular 3x3 (det == 0, e.g. P0 = 0) gives
 * AC_ERR_RANGE; the state and the outputs are then left as they were.
 *
 * Error bound (against the float reference run on this table's exact values,
 * python/accelcal/firmware/omega_table.py: omega_reference): per sample
 *     |w_fixed - w_float| <= 2^-17 rad/s + 2^-20 |w|      (each axis),
 * plus the output's rounding, 2^-17 rad/s; this holds while both take the
 * same branch of the jump test (AC_OMEGA_FLAG_JUMP), which differs only when
 * the cost difference is within rounding of the threshold.  About 1500 ac_xf
 * operations a sample at 2^-30 relative each, through 3x3 solves whose
 * condition number the information bounds; tests/python/test_omega_fixed.py
 * holds the core to it with hypothesis over whole ranges.  The table's own
 * quantisation (16-bit rows) is the larger term: python's omega_table_bound.
 *
 * Needs a layout that observes all six rate products (m invertible: the
 * 12-channel tetrahedron, triads at the origin and on the axes); the table
 * builder refuses others.  Not reentrant across states sharing nothing but
 * the table (const): several arrays may share one table.
 */
#ifndef AC_OMEGA_H
#define AC_OMEGA_H

#include "ac_config.h"
#include "ac_status.h"
#include "ac_xf.h"

#define AC_OMEGA_Q16_FRAC 16
#define AC_OMEGA_LO_BITS 12   /* the rows' low parts: 2^-12 of t's LSB */
#define AC_OMEGA_ITER 2      /* Gauss-Newton steps on the posterior (estimators.omega: iterations) */
#define AC_OMEGA_ML_ITER 4   /* Gauss-Newton steps of the per-sample ML (estimators.omega_ml) */
#define AC_OMEGA_SQRT_ITER 6 /* Newton steps of the square root */

/* per-sample flags of ac_omega_step */
#define AC_OMEGA_FLAG_JUMP 0x01u  /* the prior was centred on the ML estimate */
#define AC_OMEGA_FLAG_ML 0x02u    /* the ML estimate was computed (the skip test did not hold) */
#define AC_OMEGA_FLAG_SAT16 0x04u /* omega_q10 clipped (|omega| >= 32 rad/s) */

/* Symmetric 3x3 as six entries (00, 01, 02, 11, 12, 22); symmetric 6x6 as its
 * upper triangle row by row (21 entries: 00 01 .. 05 11 .. 15 22 .. 55). */
typedef struct ac_omega_table {
    uint16_t n;                         /* channels, 6..AC_MAX_CHANNELS */
    int8_t shift[9];                    /* rows 0..5 q, 6..8 alpha: value = (t + tl 2^-AC_OMEGA_LO_BITS) 2^-shift */
    int16_t t[9][AC_MAX_CHANNELS];      /* each row: sum |t| <= 65535 */
    int16_t tl[9][AC_MAX_CHANNELS];     /* the rows' low parts: sum |tl| <= 65535 */
    ac_xf k[9];                         /* the residual offsets through the rows */
    ac_xf m[21];                        /* m (whitened counts per (rad/s)^2 ... 6x6) */
    ac_xf minv[21];                     /* m^-1 */
    ac_xf leak[3][6];                   /* L: rad/s^2 per (rad/s)^2 */
    ac_xf qn[6];                        /* Qn: (rad/s)^2 per step */
    ac_xf p0[6];                        /* P0: (rad/s)^2 */
    ac_xf dt;                           /* s */
    ac_xf half_dt;                      /* s */
    ac_xf jump;                         /* chi^2 units */
    ac_xf ridge;                        /* the ML's ridge, per (rad/s)^2 */
} ac_omega_table;

typedef struct ac_omega_state {
    ac_xf w[3];       /* rad/s */
    ac_xf p[6];       /* (rad/s)^2 */
    ac_xf a_prev[3];  /* rad/s^2 */
    uint8_t started;
} ac_omega_state;

/* AC_OK if n and the shifts are in range and every row keeps sum |t| <= 65535,
 * AC_ERR_SIZE / AC_ERR_FORMAT if not, AC_ERR_RANGE for an invalid ac_xf. */
ac_status ac_omega_check(const ac_omega_table *t);

/* w = 0, P = P0; the next step is the first sample (no prediction). */
ac_status ac_omega_init(ac_omega_state *st, const ac_omega_table *t);

/* One sample: x[0..n-1] the pre-trimmed readings (as ac_resolve's x).
 * omega_q16[3] rad/s Q15.16; omega_q10[3] rad/s Q5.10 (for ac_resolve) or NULL;
 * flags (AC_OMEGA_FLAG_*) or NULL.  Status AC_OK, AC_SATURATED (an output
 * clipped), or an error (nothing written, state unchanged). */
ac_status ac_omega_step(ac_omega_state *st, const ac_omega_table *t, const int16_t *x,
                        int32_t *omega_q16, int16_t *omega_q10, uint8_t *flags);

/* The 1-sigma of the last step's omega (root of P's diagonal), rad/s Q15.16. */
ac_status ac_omega_sigma(const ac_omega_state *st, int32_t *sigma_q16);

#endif /* AC_OMEGA_H */
