/*
 * accelcal -- attitude of a swinging body from two 3-axis accelerometers
 * (seed 3), without integrating anything for the angle.
 *
 * Geometry (docs/data-contract.md, `attitude`): body origin = pivot;
 * triad 1 at r1 x^, triad 2 at r2 x^ (r1 != r2), each measuring body x, y, z;
 * the body swings about body y; theta = rotation about y from the pose with
 * body z up, so gravity's specific force in body axes is g (-sin th, 0, cos th);
 * omega = (0, w, 0), alpha = (0, a, 0) right-handed.  From
 * f(r) = f + alpha x r + omega x (omega x r) with r = r x^:
 *
 *   f_x(r) = -g sin th - w^2 r,     f_z(r) = g cos th - a r
 *
 * so, with s = sign(r2 - r1):
 *
 *   theta = atan2( s (r1 f2x - r2 f1x), s (r2 f1z - r1 f2z) )        (seed eq. 1, full circle)
 *   w^2   = (f2x - f1x) / (r1 - r2)                                   (seed eq. 2)
 *   a     = (f2z - f1z) / (r1 - r2)                                   (seed eq. 3, sign flipped:
 *                                                  the seed's theta2 turns the other way, theta2'' = -a)
 *
 * The rate w: the square root gives |w| only, and is noise-dominated near zero
 * (its error is sigma(w^2) / 2|w|).  The estimator predicts w by integrating a
 * (trapezoid) and corrects it with the measured magnitude, signed like the
 * prediction (continuity):
 *
 *   wp = w[n-1] + dt (a[n-1] + a[n]) / 2          (wp = 0 on the first sample)
 *   if w^2 < w2_gate (including w^2 < 0, noise near rest):   w = wp (1 - leak)      [GATED]
 *   else:  m = sqrt(w^2),  wm = sign(wp) m  (+m if wp = 0),
 *          K = min(1, gain dt m),  w = wp + K (wm - wp)
 *
 * K = gain dt |w| is the steady-state Kalman gain for a random-walk prediction
 * with per-step noise sigma_a dt corrected by a measurement of noise
 * sigma(w^2) / 2|w|, when sigma_a = sigma(w^2) (both are a difference of two
 * channels over |r1 - r2|, so this holds for equal channel noise): gain = 2.
 * Sign resolution: a wrong sign can only come from the start.  Started inside the
 * gated band (at rest, at a turning point) w is the integral of a from a small
 * known rate and is settled at once.  Started outside it, the first sample takes
 * w = +m (wp = 0: a guess) with K = 1, and AC_ATT_UNSETTLED is set: the sign is
 * right from the first pass through the band on (there w is carried by the
 * integral of a alone and the true rate crosses 0), and on leaving the band the
 * magnitude is taken once with K = 1 (a mirrored start would otherwise leave an
 * error of about 2 sqrt(w2_gate) to decay); from then on the flag is clear.
 * A body at rest: w^2 is noise around 0, gated, and the leak pulls w to 0
 * (time constant dt 2^16 / leak).
 *
 * ---- Formats and rounding (half up everywhere) --------------------------------
 *   f1, f2 in:     int32 Q.AC_OUT_FRAC m/s^2, each component clipped to int16
 *                  (+-32 m/s^2; AC_ATT_SAT)
 *   theta out:     int16 Q2.13 rad (AC_ANGLE_FRAC, 1 LSB = 0.0070 deg), ac_atan2 of
 *                  y = c1 f2x - c2 f1x, x = c2 f1z - c1 f2z (exact int32), with
 *                  c_i = round(s r_i 2^14 / max|r|) (int16 Q.14)
 *   dw out:        int32 Q.AC_OUT_FRAC rad/s^2 = round(P 2^-k_shift), P = (f2z - f1z) k_m (exact)
 *   w2 out:        int32 Q.20 (rad/s)^2 = round(P' 2^-(k_shift - 10)), P' = (f2x - f1x) k_m
 *                  (1/(r1 - r2) = k_m 2^-k_shift 1/m, |k_m| in [2^14, 2^15))
 *   m:             round(sqrt(max(w2, 0))), Q.10 rad/s (ac_isqrt32)
 *   w state:       int32 Q.20 rad/s;  w out: int16 Q.AC_OMEGA_FRAC rad/s (+-32 rad/s)
 *   inc:           round((a[n-1] + a[n]) dt_m 2^-(dt_shift - 9))            Q.20
 *   K:             min(2^16, round(m kdt_m 2^-kdt_shift)) Q.16, kdt = gain_q8 dt_m 2^-(8+dt_shift)
 *                  reduced to 16 bits (kdt_m 2^-kdt_shift with m in Q.10 gives K in Q.16)
 *   w update:      wp + round((wm - wp) K 2^-16)  or  wp - round(wp leak 2^-16)
 *   gmag out:      int32 Q.AC_OUT_FRAC m/s^2, |g| seen by the pair (hypot(x, y) rescaled):
 *                  far from g means the pivot moves, r1/r2 are wrong or a channel clipped
 *
 * ---- Error bounds against the float twin (estimators.attitude_twin, fed the same
 * clipped inputs and the constants as stored here, and the same decisions GATED /
 * sign), held by the property tests:
 *   theta:  |theta - atan2(y, x)|          <= AC_ATAN2_BOUND_LSB = 1 LSB (0.0070 deg)
 *   dw:     |dw - (f2z - f1z) k|           <= 0.5 LSB (1 LSB = 0.98e-3 rad/s^2)
 *   w2:     |w2 - (f2x - f1x) k|           <= 0.5 LSB of Q.20
 *   w:      |w_out - w_twin| <= 0.5 LSB(Q.10) + E_n, E_n in rad/s by the recursion
 *             d = 2^-21 + dt 2^-11           (inc rounding, and dw rounded to Q.10 in it)
 *             gated:     E_n = (1 - leak 2^-16) (E_{n-1} + d) + 2^-21
 *             corrected: E_n = (1 - K) (E_{n-1} + d) + K e_m + |wm' - wp'| e_K + 2^-21
 *             e_m = 2^-11 + min(sqrt(2^-21), 2^-21 / m')  (isqrt rounding; w2 rounding)
 *             e_K = 2^-17 + kdt e_m,  K the core's gain  (K = 1: E_n = e_m)
 *           which stays within about 1.5 LSB of Q.10 (1.5e-3 rad/s) in practice
 *           (python: estimators.attitude_rate_bound).
 *   The decisions agree with the twin's own except where the twin's w^2 lies within
 *   2^-21 of w2_gate, or its wp within E_{n-1} + d of 0.
 * Against the exact geometry the constants add: c_i relative 2^-15, k_m relative 2^-15.
 */
#ifndef AC_ATTITUDE_H
#define AC_ATTITUDE_H

#include "ac_config.h"
#include "ac_status.h"
#include "ac_trig.h"

/* ---- one 3-axis sensor: raw -> calibrated specific force at its point ---------
 *   x_i = raw_i - trim_i clipped to int16 (ac_trim);
 *   f_j = round( (sum_i m[j][i] x_i - k[j]) 2^-shift[j] ), Q.AC_OUT_FRAC m/s^2,
 * the triad's 3x3 inverse sensitivity folded like an ac_resolver row (the host's
 * estimators.quantize_triad makes it; rows obey sum_i |m[j][i]| <= 65535, shifts
 * in -31..31; check a table you did not make once with ac_triad_check: one that
 * breaks the row sums gives wrong numbers, never undefined behaviour).  Exact before
 * the final rounding: |f - exact| <= 0.5 LSB.
 * raw_min, raw_max: the converter's rails as uint16 codes (offset binary for a signed chip,
 * like trim); ac_triad_apply flags a reading <= raw_min or >= raw_max with the status bit
 * AC_AT_RAIL (ac_trim_rails): the chip clipped it, f is not a measurement.  raw_min >=
 * raw_max (0, 0: a zeroed table, one ac_triad_build made): rails unknown, nothing flagged;
 * the generated header fills them from the device. */
typedef struct ac_triad {
    uint16_t trim[3];
    int8_t shift[3];
    int32_t k[3];
    int16_t m[3][3];
    uint16_t raw_min;
    uint16_t raw_max;
} ac_triad;

ac_status ac_triad_check(const ac_triad *t);
/* Pre-trim (t->trim) and resolve one sample: raw[3] counts -> f[3].  Status: AC_SATURATED
 * if the pre-trim or f clipped, the bit AC_AT_RAIL if a reading sits at a rail (t->raw_min,
 * t->raw_max), AC_AT_RAIL_SATURATED for both. */
ac_status ac_triad_apply(const ac_triad *t, const uint16_t *raw, int32_t *f);
/* Resolve readings already pre-trimmed (x[3] = raw - trim, e.g. by ac_trim_rails_s16 for
 * a chip with signed output, which flags its rails) -> f[3]; t->trim and the rails are not
 * used (no reading here: the rail test is the pre-trim's). */
ac_status ac_triad_resolve(const ac_triad *t, const int16_t *x, int32_t *f);

/* ---- the pendulum estimator ---------------------------------------------------- */

#define AC_ATT_W_FRAC 20  /* rate state, rad/s */
#define AC_ATT_W2_FRAC 20 /* w^2, (rad/s)^2 */

/* flags in ac_att_out */
#define AC_ATT_GATED 0x01u      /* |w| not measurable (w^2 < gate): integrated, with leak */
#define AC_ATT_W2_NEG 0x02u     /* measured w^2 < 0 (noise near rest), treated as 0 */
#define AC_ATT_UNSETTLED 0x04u  /* no pass through the gated band yet: sign of w is a guess */
#define AC_ATT_NO_GRAVITY 0x08u /* the pair sees no gravity (x = y = 0): theta undefined (0) */
#define AC_ATT_SAT 0x10u        /* an input or an output was clipped */
#define AC_ATT_SIGN_NEG 0x20u   /* the magnitude was applied with a negative sign */

typedef struct ac_att_cfg {
    int16_t c1, c2;    /* s r_i / max|r|, Q.14 */
    int16_t k_m;       /* 1/(r1 - r2) = k_m 2^-k_shift  [1/m] */
    int8_t k_shift;
    uint16_t gs_m;     /* max|r| / |r1 - r2| = gs_m 2^-gs_shift */
    int8_t gs_shift;
    uint8_t dt_shift;  /* dt = dt_m 2^-dt_shift s, dt_shift 16..46 */
    uint16_t dt_m;
    uint16_t kdt_m;    /* K (Q.16) = m (Q.10) kdt_m 2^-kdt_shift */
    uint8_t kdt_shift;
    uint16_t leak;     /* Q.16 per gated step */
    int32_t w2_gate;   /* Q.20 (rad/s)^2, >= 0 */
} ac_att_cfg;

typedef struct ac_att {
    ac_att_cfg cfg;
    int32_t w;      /* Q.20 rad/s */
    int32_t a_prev; /* Q.AC_OUT_FRAC rad/s^2 */
    uint8_t started;
    uint8_t settled; /* 0 sign guessed, 1 in the band after a guess, 2 settled */
} ac_att;

typedef struct ac_att_out {
    int16_t theta; /* Q.13 rad */
    int16_t w;     /* Q.AC_OMEGA_FRAC rad/s */
    int32_t dw;    /* Q.AC_OUT_FRAC rad/s^2 */
    int32_t w2;    /* Q.20 (rad/s)^2, as measured (may be < 0) */
    int32_t gmag;  /* Q.AC_OUT_FRAC m/s^2 */
    uint8_t flags; /* AC_ATT_* */
} ac_att_out;

/* r1, r2: triad positions on body x, m, Q.AC_POS_FRAC, |r| <= 2^30 LSB (1024 m);
 * dt as ac_rate (dt_m != 0, dt_shift 16..46); gain_q8: K = gain dt |w|, gain in Q.8
 * (512 = 2.0, the default); w2_gate: Q.20 (rad/s)^2 >= 0; leak: Q.16 per gated step.
 * AC_ERR_SINGULAR if r1 == r2; AC_ERR_ILL_COND if max|r| / |r1 - r2| > 2^10 (theta's
 * noise gain sqrt(r1^2 + r2^2) / |r1 - r2| too large); AC_ERR_RANGE otherwise bad. */
ac_status ac_att_init(ac_att *st, int32_t r1, int32_t r2, uint16_t dt_m, uint8_t dt_shift,
                      uint16_t gain_q8, int32_t w2_gate, uint16_t leak);
ac_status ac_att_reset(ac_att *st);
/* One sample: f1, f2 = 3 x int32 Q.AC_OUT_FRAC.  AC_SATURATED with AC_ATT_SAT. */
ac_status ac_att_step(ac_att *st, const int32_t *f1, const int32_t *f2, ac_att_out *out);
/* count samples; f is count x 6 (f1x f1y f1z f2x f2y f2z) row-major. */
ac_status ac_att_batch(ac_att *st, const int32_t *f, uint32_t count, ac_att_out *out);

#endif /* AC_ATTITUDE_H */
