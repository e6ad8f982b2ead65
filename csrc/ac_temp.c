/* accelcal -- temperature terms (see ac_temp.h for the arithmetic and its bounds). */
#include "accelcal/ac_temp.h"
#include "accelcal/ac_fixed.h"
#include "ac_internal.h"
#include "ac_terms_impl.h"

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

ac_status AC_TEMP_LAG_STEP_C(ac_temp_lag *f, int16_t temp, int16_t *lagged)
{
    uint8_t sat = 0u;
    int32_t x, inc = 0;
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
        int32_t d = ac_sat_sub(x, f->y, &sat);
        if (f->shift >= 17u && d < 0x40000000L && d > -0x40000000L) {
            /* round(d k 2^-shift) with d = dh 2^16 + dl: A = dh k + floor(dl k 2^-16) is
             * floor(d k 2^-16), and (the dropped fraction being < 1) the result is
             * floor((A + 2^(shift-17)) 2^-(shift-16)); |A| < 2^30 + 2^16: no overflow */
            const int16_t dh = (int16_t)((int32_t)((uint32_t)(d + 0x40000000L) >> 16) - 0x4000L);
            const uint16_t dl = (uint16_t)((uint32_t)d & 0xFFFFu);
            const uint32_t ph = ac_mul16u((uint16_t)(dh < 0 ? -dh : dh), f->k); /* |dh| <= 2^14 */
            int32_t a = (dh < 0) ? -(int32_t)ph : (int32_t)ph;
            a += (int32_t)(ac_mul16u(dl, f->k) >> 16);
            inc = ac_floor_shift(a + ((int32_t)1 << (uint8_t)(f->shift - 17u)), (uint8_t)(f->shift - 16u));
        } else if (ac_mul32x16_shift(d, f->k, f->shift, &inc) != AC_OK) {
            sat = 1u;
        }
        f->y = ac_sat_add(f->y, inc, &sat);
    }
    /* y within x's range (|y| <= 2^31 - 2^16) unless it clipped: AC_R16 applies */
    if (f->y >= 0x7FFF8000L) {
        *lagged = INT16_MAX;
    } else {
        *lagged = AC_R16(f->y);
    }
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_temp_check(const ac_temp_table *t)
{
    uint8_t i;
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    for (i = 0u; i < (uint8_t)t->n; i++) {
        if (t->o[i] > 128 || t->o[i] < -128) {
            return AC_ERR_FORMAT;
        }
    }
    if (t->frac > (uint8_t)AC_TEMP_MAX_OUT_FRAC) {
        return AC_ERR_FORMAT;
    }
    return AC_OK;
}

/* the largest |gc dTg| (Q.32) that rounds to |e| <= AC_TEMP_E_MAX */
#define E32_MAX ((int32_t)AC_TEMP_E_MAX * 8192L + 4095L)

ac_status AC_TEMP_CORRECT_C(const ac_temp_table *t, int16_t t_off, int16_t t_gain, const int16_t *x,
                          int16_t *y)
{
    uint8_t sat = 0u;
    uint8_t i;
    int16_t dto, dtg;
    if (x == 0 || y == 0) {
        return AC_ERR_NULL;
    }
    /* per call only n; |o| <= 128 is ac_temp_check's, once per table (a table that breaks it
     * gives wrong numbers, never undefined behaviour: every sum below saturates) */
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    if (t->frac > (uint8_t)AC_TEMP_MAX_OUT_FRAC) {
        return AC_ERR_FORMAT;
    }
    dto = ac_sat_to16((int32_t)t_off - (int32_t)t->t_ref, &sat);
    dtg = ac_sat_to16((int32_t)t_gain - (int32_t)t->t_ref, &sat);
    for (i = 0u; i < (uint8_t)t->n; i++) {
        const int32_t o8 = (int32_t)t->o[i] * (int32_t)256; /* Q.16 */
        int32_t e32 = AC_MUL16(t->gc[i], dtg);        /* Q.32 */
        int32_t w, g;
        int16_t e, e2, e3, r, w16;
        /* |o 2^8 + oc dTo| <= 2^15 + 2^30: one subtraction from x 2^16, clipped only when w
         * itself leaves int32 */
        w = ac_sat_sub((int32_t)x[i] * (int32_t)65536L, o8 + AC_MUL16(t->oc[i], dto), &sat);
        if (e32 > E32_MAX) {
            e = AC_TEMP_E_MAX;
            sat = 1u;
        } else if (e32 < -E32_MAX) {
            e = -AC_TEMP_E_MAX;
            sat = 1u;
        } else {
            e = (int16_t)AC_R13(e32);
        }
        /* |e| <= 28672: |e2| <= 1568, |e3| <= 86, |r| <= 30326 */
        e2 = (int16_t)AC_R19(AC_MUL16(e, e));
        e3 = (int16_t)AC_R19(AC_MUL16(e2, e));
        r = (int16_t)(e2 - e - e3);
        if (w >= 0x7FFF8000L) {
            w16 = INT16_MAX;
            sat = 1u;
        } else {
            w16 = AC_R16(w);
        }
        g = AC_R3(AC_MUL16(w16, r)); /* |w16 r| < 2^30 */
        w = ac_sat_add(w, g, &sat);
        w = ac_sat_add(w, o8, &sat);
#if !AC_H8_RESOLVE_ASM
        /* (on the H8/300H the assembly takes frac 1..AC_TEMP_MAX_OUT_FRAC and this C only the
         * errors: the branch would be dead code there) */
        if (t->frac != 0u) {
            /* Q.frac: round(w 2^-(16 - frac)), clipped to int16 */
            y[i] = ac_sat_to16(ac_round_shift(w, (uint8_t)(16u - t->frac)), &sat);
        } else
#endif
        if (w >= 0x7FFF8000L) {
            y[i] = INT16_MAX;
            sat = 1u;
        } else {
            y[i] = AC_R16(w);
        }
    }
    return sat ? AC_SATURATED : AC_OK;
}
