/* accelcal -- temperature terms (see ac_temp.h for the arithmetic and its bounds). */
#include "accelcal/ac_temp.h"
#include "accelcal/ac_fixed.h"
#include "ac_internal.h"

#define LAG_FRAC (AC_TEMP_FRAC + AC_TEMP_LAG_EXTRA)

ac_status ac_temp_lag_init(ac_temp_lag *f, uint16_t k, uint8_t shift)
{
    if (f == 0) {
        return AC_ERR_NULL;
    }
    if (shift > 47u || (shift < 16u && (uint32_t)k > ((uint32_t)1u << shift))) {
        return AC_ERR_RANGE;
    }
    f->y = 0;
    f->k = k;
    f->shift = shift;
    f->started = 0u;
    return AC_OK;
}

ac_status ac_temp_lag_step(ac_temp_lag *f, int16_t temp, int16_t *lagged)
{
    uint8_t sat = 0u;
    int32_t x, d, inc = 0;
    if (f == 0 || lagged == 0) {
        return AC_ERR_NULL;
    }
    if (f->shift > 47u) {
        return AC_ERR_RANGE;
    }
    x = ac_i_from_u((uint32_t)(int32_t)temp << AC_TEMP_LAG_EXTRA);
    if (f->started == 0u) {
        f->y = x;
        f->started = 1u;
    } else {
        d = ac_sat_sub(x, f->y, &sat);
        if (ac_mul32x16_shift(d, f->k, f->shift, &inc) != AC_OK) {
            sat = 1u;
        }
        f->y = ac_sat_add(f->y, inc, &sat);
    }
    *lagged = ac_sat_to16(ac_round_shift(f->y, AC_TEMP_LAG_EXTRA), &sat);
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_temp_check(const ac_temp_table *t)
{
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    if (t->oc_shift < 0 || t->oc_shift > 31 || t->gc_shift < 11 || t->gc_shift > 31) {
        return AC_ERR_FORMAT;
    }
    return AC_OK;
}

/* 16 x 16 -> 32 signed product */
#define MUL16(a, b) ac_i_from_u(ac_mac16(0u, (int16_t)(a), (int16_t)(b)))

ac_status ac_temp_correct(const ac_temp_table *t, int16_t t_off, int16_t t_gain, const int16_t *x,
                          int16_t *y)
{
    uint8_t sat = 0u;
    uint8_t i, os, gs;
    int16_t dto, dtg;
    ac_status st;
    if (x == 0 || y == 0) {
        return AC_ERR_NULL;
    }
    st = ac_temp_check(t);
    if (st != AC_OK) {
        return st;
    }
    dto = ac_sat_to16((int32_t)t_off - (int32_t)t->t_ref, &sat);
    dtg = ac_sat_to16((int32_t)t_gain - (int32_t)t->t_ref, &sat);
    os = (uint8_t)t->oc_shift;
    gs = (uint8_t)(t->gc_shift + AC_TEMP_FRAC - AC_TEMP_GAIN_FRAC); /* >= 0 by the check */
    for (i = 0u; i < (uint8_t)t->n; i++) {
        int32_t c = MUL16(t->oc[i], dto);
        int32_t e32 = MUL16(t->gc[i], dtg);
        int32_t w, g;
        int16_t e, e2, e3, r, w16;
        if (os != 0u) {
            c = ac_round_shift(c, os);
        }
        if (gs != 0u) {
            e32 = ac_round_shift(e32, gs);
        }
        if (e32 > AC_TEMP_E_MAX) {
            e32 = AC_TEMP_E_MAX;
            sat = 1u;
        } else if (e32 < -AC_TEMP_E_MAX) {
            e32 = -AC_TEMP_E_MAX;
            sat = 1u;
        }
        e = (int16_t)e32;
        /* |e| <= 28672: |e2| <= 1568, |e3| <= 86, |r| <= 30326 */
        e2 = (int16_t)ac_round_shift(MUL16(e, e), AC_TEMP_GAIN_FRAC);
        e3 = (int16_t)ac_round_shift(MUL16(e2, e), AC_TEMP_GAIN_FRAC);
        r = (int16_t)(-e + e2 - e3);
        /* |x 2^8| <= 2^23, |o| <= 2^15 in a checked table's use, |c| <= 2^30 */
        w = ac_sat_sub(ac_i_from_u((uint32_t)(int32_t)x[i] << AC_OFFSET_FRAC) - (int32_t)t->o[i], c, &sat);
        w16 = ac_sat_to16(ac_round_shift(w, AC_OFFSET_FRAC), &sat);
        g = ac_round_shift(MUL16(w16, r), (uint8_t)(AC_TEMP_GAIN_FRAC - AC_OFFSET_FRAC));
        w = ac_sat_add(w, g, &sat);
        w = ac_sat_add(w, (int32_t)t->o[i], &sat);
        y[i] = ac_sat_to16(ac_round_shift(w, AC_OFFSET_FRAC), &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}
