/*
 * accelcal -- angular rate from angular acceleration: leaky integration.
 *
 *   w[n] = w[n-1] - w[n-1] * leak / 2^16 + dt * alpha[n]
 *
 * leak = 0 integrates plainly; leak > 0 forgets with time constant
 * tau = dt * 2^16 / leak, which is the high-pass the seed paper applied
 * before integrating alpha to omega (a leaky integrator is an integrator
 * followed by a first-order high-pass at f_c = 1 / (2 pi tau)).  Reset on a
 * detected rest with ac_rate_reset.
 *
 * dt = dt_m * 2^-dt_shift s (dt_m normalised to 15-16 significant bits by the
 * host, e.g. 1/60 s = 34953 * 2^-21, error 1.4e-5).  alpha: rad/s^2 Q.AC_OUT_FRAC
 * (ac_resolve's out[3..5]); omega out: rad/s Q.AC_OMEGA_FRAC, clipped to int16.
 * State: rad/s, int32 Q5.26.  Each step rounds twice by at most 2^-27 rad/s.
 */
#ifndef AC_RATE_H
#define AC_RATE_H

#include "ac_config.h"
#include "ac_status.h"

#define AC_RATE_STATE_FRAC 26

typedef struct ac_rate {
    int32_t w[3];
    uint16_t dt_m;
    uint8_t dt_shift;
    uint16_t leak;
} ac_rate;

/* dt_shift in 16..46 (dt = dt_m 2^-dt_shift s). */
ac_status ac_rate_init(ac_rate *st, uint16_t dt_m, uint8_t dt_shift, uint16_t leak);
ac_status ac_rate_reset(ac_rate *st);
ac_status ac_rate_step(ac_rate *st, const int32_t *alpha, int16_t *omega);

#endif /* AC_RATE_H */
