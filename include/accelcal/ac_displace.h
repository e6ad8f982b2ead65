/*
 * accelcal -- stop-to-stop displacement (seed 4), streaming: fixed memory, one
 * sample at a time, nothing of the motion stored.
 *
 * A motion between two rests (ac_rest) is integrated twice from the last rest
 * sample (v = 0 there) by the trapezoid rule.  Over the T seconds from that
 * anchor to the sample where the next rest is declared, a constant zero-point
 * error a makes v(T) = a T instead of 0, so when the rest is declared
 *
 *   zp = v(T) / T,     p(T) <- p(T) - zp T^2 / 2 = p(T) - v(T) T / 2,     v <- 0
 *
 * (the seed's correction, applied to the end point).  The path in between is
 * corrected on the host from zp (v(t) - zp t', p(t) - zp t'^2 / 2, t' from the
 * anchor): firmware that needs only the stop positions never stores it.
 * The rest is declared after ac_rest's hold quiet samples: they are part of T.
 * From the end of the first rest on, the rest test also requires f within
 * rest.ref_max of that rest's mean (ac_rest_step_ref): a constant acceleration
 * cannot pass for rest.  So the first rest must be a true rest of the body in
 * the attitude it keeps (a rail), and a zero-point drift larger than ref_max
 * between rests makes the later rests invisible (the motion is then open and
 * flagged, not silently corrected).
 *
 * Modes (cfg.axis):
 *   0, 1, 2  1-D (the seed's case): a = f[axis], nothing removed; the result is in
 *            component axis of v and p (the others stay 0).  The axis should be
 *            level; any gravity along it is a zero-point error the correction removes.
 *   -1       3-axis on a tilted rail: the mean g of f over the first rest (up to
 *            AC_DISP_GSUM_MAX samples of it) gives the frame of the first rest
 *            (ac_tilt_frame: z up, x the horizontal projection of body x, or of
 *            body y when body x is within 30 deg of vertical), and
 *            a = R (f - g)  in that frame.  The body must not rotate between
 *            rests (a rail): a tilt error is a constant bias while it does not,
 *            and the correction removes it.
 * Before the first rest is declared nothing is estimated (AC_DISP_NO_REF, v = p = 0).
 *
 * Formats (rounding half up):
 *   f in:   int32 Q.AC_OUT_FRAC m/s^2 (clipped to int16 for the rest test and the sums)
 *   g:      int32 Q.16 m/s^2 = round(sum f 2^6 / count)        (exact mean to 0.5 LSB), both modes
 *   R:      int16 Q.14, entries within 2 LSB of the exact rotation of g
 *   a:      int32 Q.16 m/s^2: 3-axis round(R f 2^-8) - round(R g 2^-14); 1-D f[axis] 2^6 (exact)
 *   v:      int32 Q.24 m/s (+-128 m/s; the p step adds two velocities, so |v| < 64 m/s
 *           is the working range, beyond it the step saturates with AC_DISP_SAT)
 *                                         v += round((a' + a) dt_m 2^-(dt_shift - 7))
 *   p:      int32 Q.20 m  (+-2048 m)     p += round((v' + v) dt_m 2^-(dt_shift + 5))
 *   T:      round(n dt 2^16) s Q.16; p -= round(v T 2^-21); zp = round(v 2^8 / T) Q.16 m/s^2
 *   dt = dt_m 2^-dt_shift s as ac_rate (dt_shift 16..46).
 *
 * Error bound against the float twin (estimators.displace_twin: the same recurrence
 * in float64 on the same clipped inputs, with this g, R, round(R g) and the same
 * rest decisions), held by the property tests, after n integration steps of a segment:
 *   |a - a'|  <= e_a = 2^-17 (3-axis) or 0 (1-D)                        m/s^2
 *   |v - v'|  <= E_v(n) = n (dt e_a + 2^-25)                            m/s
 *   |p - p'|  <= E_p(n) = E_p(n-1) + dt (E_v(n-1) + E_v(n)) / 2 + 2^-21  (E_p(0) = error carried in)
 *   at a segment end (T = n dt) p adds E_v(n) T / 2 + |v| 2^-17 + 2^-21, and
 *   |zp - zp'| <= E_v(n) / T + |zp'| 2^-17 / T + 2^-17  (T rounded to Q.16 s, zp to Q.16).
 * E.g. a 4 s motion at 100 Hz, 3-axis: |v - v'| <= 4.2e-5 m/s, |p - p'| <= 2.8e-4 m
 * (290 LSB of Q.20); 1-D: 1.2e-5 m/s, 2.1e-4 m.  The twin itself follows the float
 * reference except for the quantisation of g and R (ac_tilt_frame: each entry within 2 LSB
 * of Q.14, the two that are products of two entries within 4.5, from the roundings; 1.2 LSB
 * typical in the tests, 2.06 the largest product found; a tilt error is a constant bias
 * while the body does not rotate, which the correction removes).  (python: estimators.displace_error_bound)
 * Streams longer than 65535 samples per motion are not corrected (AC_DISP_LONG).
 */
#ifndef AC_DISPLACE_H
#define AC_DISPLACE_H

#include "ac_config.h"
#include "ac_status.h"
#include "ac_rest.h"

#define AC_DISP_A_FRAC 16
#define AC_DISP_V_FRAC 24
#define AC_DISP_P_FRAC 20
#define AC_DISP_ROT_FRAC 14
#define AC_DISP_G_FRAC 16
#ifndef AC_DISP_GSUM_MAX
#define AC_DISP_GSUM_MAX 4096u /* samples of the first rest averaged for g (sum fits int32) */
#endif
#if AC_DISP_GSUM_MAX > 65535 || AC_DISP_GSUM_MAX < 1
#error "AC_DISP_GSUM_MAX must be in 1..65535"
#endif

/* flags in ac_disp_out */
#define AC_DISP_NO_REF 0x0001u  /* before the first rest is declared: nothing estimated */
#define AC_DISP_REST 0x0002u    /* at rest: v = 0, p held */
#define AC_DISP_MOVING 0x0004u  /* integrating (uncorrected until the next rest) */
#define AC_DISP_SEG_END 0x0008u /* a motion ended here: p is the corrected end point, zp set */
#define AC_DISP_LONG 0x0010u    /* that motion was longer than 65535 samples: NOT corrected */
#define AC_DISP_SAT 0x0020u     /* something was clipped */
#define AC_DISP_OPEN 0x0040u    /* (ac_disp_finish) the stream ended in motion: last one uncorrected */
#define AC_DISP_NO_REST 0x0080u /* (ac_disp_finish) no rest was ever detected */
#define AC_DISP_REF_SET 0x0100u /* the first rest ended here: g and R fixed */
#define AC_DISP_BAD_REF 0x0200u /* the first rest's mean f has no direction: waiting for another */

typedef struct ac_disp_cfg {
    ac_rest_cfg rest;
    uint16_t dt_m;
    uint8_t dt_shift;
    int8_t axis; /* -1: 3-axis, gravity removed; 0..2: 1-D along that body axis */
} ac_disp_cfg;

typedef struct ac_disp {
    ac_disp_cfg cfg;
    ac_rest rest;
    int32_t gsum[3];    /* sum of clipped f over the first rest, Q.AC_OUT_FRAC */
    int32_t g[3];       /* its mean, Q.16 m/s^2 */
    int32_t gref[3];    /* the same in Q.18, the rest test's reference */
    int32_t c[3];       /* round(R g), Q.16 */
    int32_t a_prev[3];  /* Q.16 */
    int32_t v[3];       /* Q.24 */
    int32_t p[3];       /* Q.20 */
    int16_t rot[3][3];  /* body -> frame of the first rest, Q.14 */
    int16_t f_prev[3];
    uint16_t gcount;
    uint16_t nseg;      /* integration steps in the current motion */
    uint8_t phase;      /* 0 waiting for the first rest, 1 at rest, 2 moving */
    uint8_t have_ref;
    uint8_t long_seg;
} ac_disp;

typedef struct ac_disp_out {
    int32_t v[3];   /* Q.24 m/s */
    int32_t p[3];   /* Q.20 m */
    int32_t zp[3];  /* Q.16 m/s^2, at AC_DISP_SEG_END (else 0) */
    uint16_t nseg;  /* integration steps of the current (or just ended) motion */
    uint16_t flags; /* AC_DISP_* */
    uint8_t rest;   /* the rest detector's AC_REST_* flags of this sample */
} ac_disp_out;

/* AC_ERR_RANGE for bad dt, axis or rest parameters. */
ac_status ac_disp_init(ac_disp *st, const ac_disp_cfg *cfg);
ac_status ac_disp_reset(ac_disp *st);
/* f: 3 x int32 Q.AC_OUT_FRAC. */
ac_status ac_disp_step(ac_disp *st, const int32_t *f, ac_disp_out *out);
/* End of stream: the current state with AC_DISP_OPEN (in motion) or AC_DISP_NO_REST. */
ac_status ac_disp_finish(const ac_disp *st, ac_disp_out *out);
/* count samples, f count x 3; AC_SATURATED if any sample clipped. */
ac_status ac_disp_batch(ac_disp *st, const int32_t *f, uint32_t count, ac_disp_out *out);

/* The frame of a rest from its mean specific force g (Q.16, pointing up):
 * rows of rot (Q.14) are the frame's x, y, z in body axes; z = g / |g|,
 * x = horizontal projection of body x (if |g_x| <= (sqrt 3 / 2)|g|, i.e.
 * rho^2 = (g_y^2 + g_z^2) / |g|^2 >= 1/4, decided on g scaled to 15 bits),
 * otherwise y = horizontal projection of body y.  AC_ERR_SINGULAR for g = 0. */
ac_status ac_tilt_frame(const int32_t *g, int16_t rot[3][3]);

#endif /* AC_DISPLACE_H */
