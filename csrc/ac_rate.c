/* accelcal -- leaky integration of angular acceleration to angular rate. */
#include "accelcal/ac_rate.h"
#include "accelcal/ac_fixed.h"
#include "ac_internal.h"

ac_status ac_rate_init(ac_rate *st, uint16_t dt_m, uint8_t dt_shift, uint16_t leak)
{
    if (st == 0) {
        return AC_ERR_NULL;
    }
    if (dt_m == 0u || dt_shift < 16u || dt_shift > 46u) {
        return AC_ERR_RANGE;
    }
    st->dt_m = dt_m;
    st->dt_shift = dt_shift;
    st->leak = leak;
    return ac_rate_reset(st);
}

ac_status ac_rate_reset(ac_rate *st)
{
    if (st == 0) {
        return AC_ERR_NULL;
    }
    st->w[0] = 0;
    st->w[1] = 0;
    st->w[2] = 0;
    return AC_OK;
}

ac_status ac_rate_step(ac_rate *st, const int32_t *alpha, int16_t *omega)
{
    uint8_t sat = 0u;
    uint8_t a;
    if (st == 0 || alpha == 0 || omega == 0) {
        return AC_ERR_NULL;
    }
    if (st->dt_m == 0u || st->dt_shift < 16u || st->dt_shift > 46u) {
        return AC_ERR_RANGE; /* not initialised */
    }
    for (a = 0u; a < 3u; a++) {
        int32_t dec = 0, inc = 0, w;
        ac_status s;
        if (st->leak != 0u) {
            /* |w * leak / 2^16| < |w|: cannot saturate */
            (void)ac_mul32x16_shift(st->w[a], st->leak, 16u, &dec);
        }
        /* alpha [2^-OUT rad/s^2] * dt_m 2^-dt_shift [s] -> 2^-26 rad/s */
        s = ac_mul32x16_shift(alpha[a], st->dt_m,
                           (uint8_t)(st->dt_shift - (AC_RATE_STATE_FRAC - AC_OUT_FRAC)), &inc);
        if (s == AC_SATURATED) {
            sat = 1u;
        }
        w = ac_sat_sub(st->w[a], dec, &sat);
        w = ac_sat_add(w, inc, &sat);
        st->w[a] = w;
        omega[a] = ac_sat_to16(
            ac_scale_round(w, (int16_t)(AC_RATE_STATE_FRAC - AC_OMEGA_FRAC), &sat), &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}
