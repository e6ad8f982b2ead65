/*
 * accelcal -- rest detector from the calibrated signal, shared by the
 * stop-to-stop displacement (ac_displace) and the rate integrator's reset.
 *
 * Per sample, with f the calibrated specific force (int32 Q.AC_OUT_FRAC m/s^2,
 * each component clipped to int16 for the test: +-32 m/s^2) and m a running
 * mean of f (exponential, weight 2^-ema_shift per sample):
 *
 *   quiet  =  max_k |f_k - m_k| <= dev_max               (nothing changes)
 *         and g2_lo <= |f|^2 <= g2_hi                     (|f| is about g)
 *         and max_k |alpha_k| <= alpha_max  (alpha given) (no rotation)
 *         and max_k |f_k - ref_k| <= ref_max (ref given)   (f is back at a known rest value)
 *   m     += floor((f - m) 2^-ema_shift)                  (after the test)
 *   at rest  after hold consecutive quiet samples; any non-quiet sample ends it.
 *
 * The reference test is what tells a rest from a constant acceleration: a smooth
 * motion holds f nearly still around each acceleration peak for a few tenths of a
 * second, which the running mean alone would take for rest.  ac_displace passes
 * the mean f of the first rest (the body does not rotate on a rail).
 * The deviation is taken against the mean *before* this sample updates it.
 * The first sample after init/reset starts the mean at f (so it has zero deviation).
 * A motion with a slowly changing constant acceleration below dev_max, or a
 * rotation at constant rate about the vertical through the sensor (alpha = 0,
 * |f| = g), looks like rest: no accelerometer-only detector can tell.
 *
 * Formats: m and ref are int32 Q.(AC_OUT_FRAC + AC_REST_EXTRA_FRAC) = Q.18 m/s^2;
 * dev_max, ref_max, alpha_max Q.AC_OUT_FRAC; g2_lo, g2_hi Q.(2 AC_OUT_FRAC) (m/s^2)^2 as uint32
 * (0 and UINT32_MAX switch the |f| test off, e.g. for a single-axis sensor fed as
 * (a, 0, 0)).  Every test is exact integer arithmetic on the clipped input except
 * m (the reference test is exact too), whose floor rounding keeps it within 2^ema_shift LSB of Q.18
 * (2^(ema_shift-18) m/s^2) of the exact exponential mean: the float twin
 * (python/accelcal/estimators.py: rest_detect) decides the same except where its
 * deviation lies within that of dev_max (the property tests hold it to this).
 */
#ifndef AC_REST_H
#define AC_REST_H

#include "ac_config.h"
#include "ac_status.h"
#include "ac_rate.h"

#define AC_REST_EXTRA_FRAC 8

/* flags written by ac_rest_step */
#define AC_REST_QUIET 0x01u    /* this sample passed every test */
#define AC_REST_AT_REST 0x02u  /* at rest after this sample */
#define AC_REST_ENTER 0x04u    /* rest was declared at this sample */
#define AC_REST_LEAVE 0x08u    /* rest ended at this sample */
#define AC_REST_CLIP 0x10u     /* a component of f was clipped to int16 for the test */

typedef struct ac_rest_cfg {
    int32_t dev_max;   /* Q.AC_OUT_FRAC m/s^2, >= 0 */
    uint32_t g2_lo;    /* Q.(2 AC_OUT_FRAC) (m/s^2)^2 */
    uint32_t g2_hi;
    int32_t alpha_max; /* Q.AC_OUT_FRAC rad/s^2, >= 0; used only when alpha is given */
    int32_t ref_max;   /* Q.AC_OUT_FRAC m/s^2, >= 0; used only when ref is given */
    uint16_t hold;     /* 1..65534 samples */
    uint8_t ema_shift; /* 1..12 */
} ac_rest_cfg;

typedef struct ac_rest {
    ac_rest_cfg cfg;
    int32_t m[3];  /* running mean, Q.(AC_OUT_FRAC + AC_REST_EXTRA_FRAC) */
    uint16_t run;  /* consecutive quiet samples (saturates at 65535) */
    uint8_t started;
    uint8_t at_rest;
} ac_rest;

/* AC_ERR_RANGE for a parameter outside the ranges above (or g2_lo > g2_hi). */
ac_status ac_rest_init(ac_rest *st, const ac_rest_cfg *cfg);
ac_status ac_rest_reset(ac_rest *st);
/* f: 3 x int32 Q.AC_OUT_FRAC; alpha: 3 x int32 Q.AC_OUT_FRAC or NULL; flags: AC_REST_*. */
ac_status ac_rest_step(ac_rest *st, const int32_t *f, const int32_t *alpha, uint8_t *flags);
/* The same with a reference (3 x int32 Q.18, or NULL = ac_rest_step). */
ac_status ac_rest_step_ref(ac_rest *st, const int32_t *f, const int32_t *alpha, const int32_t *ref,
                           uint8_t *flags);
/* count samples (f, alpha: count x 3 row-major, alpha may be NULL), flags count bytes. */
ac_status ac_rest_batch(ac_rest *st, const int32_t *f, const int32_t *alpha, uint32_t count,
                        uint8_t *flags);

/* Angular rate from alpha with reset on rest (the seed's high-pass + integration):
 * ac_rest_step(rest, f, alpha), then ac_rate_step(rate, alpha, omega); when the
 * sample is at rest the rate state is reset and omega is written as 0.  omega:
 * 3 x int16 Q.AC_OMEGA_FRAC.  AC_SATURATED if either step clipped. */
ac_status ac_rest_rate_step(ac_rest *rest, ac_rate *rate, const int32_t *f, const int32_t *alpha,
                            int16_t *omega, uint8_t *flags);

#endif /* AC_REST_H */
