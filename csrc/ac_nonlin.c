/* accelcal -- nonlinearity inversion (see ac_nonlin.h for the arithmetic and its bound). */
#include "accelcal/ac_nonlin.h"
#include "ac_internal.h"

ac_status ac_nonlin_check(const ac_nonlin_table *t)
{
    uint8_t i;
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    if (t->shift < 0 || t->shift > 31) {
        return AC_ERR_FORMAT;
    }
    for (i = 0u; i < (uint8_t)t->n; i++) {
        if (ac_abs_u(t->a2[i]) + ac_abs_u(t->a3[i]) > 32767u) {
            return AC_ERR_FORMAT;
        }
    }
    return AC_OK;
}

#define MUL16(a, b) ac_i_from_u(ac_mac16(0u, (int16_t)(a), (int16_t)(b)))

ac_status ac_nonlin_invert(const ac_nonlin_table *t, const int16_t *x, int16_t *y)
{
    uint8_t sat = 0u;
    uint8_t i, it, sh;
    ac_status st;
    if (x == 0 || y == 0) {
        return AC_ERR_NULL;
    }
    st = ac_nonlin_check(t);
    if (st != AC_OK) {
        return st;
    }
    sh = (uint8_t)t->shift;
    for (i = 0u; i < (uint8_t)t->n; i++) {
        const int16_t a2 = t->a2[i], a3 = t->a3[i];
        const int16_t x0 = x[i];
        int16_t z = x0;
        for (it = 0u; it < (uint8_t)AC_NONLIN_ITERATIONS; it++) {
            /* |h| <= |a2| + |a3| <= 32767, |g| <= |h|, |g z| <= 2^30 */
            int16_t h = (int16_t)(a2 + (int16_t)ac_round_shift(MUL16(a3, z), 15u));
            int16_t g = (int16_t)ac_round_shift(MUL16(h, z), 15u);
            int32_t c = MUL16(g, z);
            if (sh != 0u) {
                c = ac_round_shift(c, sh);
            }
            z = ac_sat_to16((int32_t)x0 - c, &sat);
        }
        y[i] = z;
    }
    return sat ? AC_SATURATED : AC_OK;
}
