/* accelcal -- nonlinearity inversion (see ac_nonlin.h for the arithmetic and its bound). */
#include "accelcal/ac_nonlin.h"
#include "ac_internal.h"
#include "ac_terms_impl.h"

ac_status ac_nonlin_check(const ac_nonlin_table *t)
{
    uint8_t i;
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    if (t->shift < 0 || t->shift > 30 || t->iterations > (uint8_t)AC_NONLIN_MAX_ITERATIONS) {
        return AC_ERR_FORMAT;
    }
    for (i = 0u; i < (uint8_t)t->n; i++) {
        if (ac_abs_u(t->a2[i]) + ac_abs_u(t->a3[i]) > 32767u) {
            return AC_ERR_FORMAT;
        }
    }
    return AC_OK;
}

ac_status AC_NONLIN_INVERT_C(const ac_nonlin_table *t, const int16_t *x, int16_t *y)
{
    uint8_t sat = 0u;
    uint8_t i, it, sh, nit;
    int32_t bias;
    int32_t off;
    if (x == 0 || y == 0) {
        return AC_ERR_NULL;
    }
    /* per call the cheap checks (n, shift); |a2| + |a3| <= 32767 is ac_nonlin_check's, once per
     * table: a table that breaks it gives wrong numbers, never undefined behaviour */
    if (t == 0) {
        return AC_ERR_NULL;
    }
    if (t->n < 1u || t->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    if (t->shift < 0 || t->shift > 30 || t->iterations > (uint8_t)AC_NONLIN_MAX_ITERATIONS) {
        return AC_ERR_FORMAT;
    }
    nit = (t->iterations == 0u) ? (uint8_t)AC_NONLIN_ITERATIONS : t->iterations;
    /* shift >= 8: C = round(p 2^-shift) = floor((p + 2^(shift-1) + 2^30) 2^-16 2^-(shift-16))
     * - 2^(30-shift) (or 2^-8 2^-(shift-8)): the bias makes the sum non-negative (|p| <= 2^30),
     * the shift by 16 is a word move, by 8 byte moves */
    sh = (uint8_t)t->shift;
    bias = (sh >= 8u) ? (int32_t)(0x40000000UL + ((uint32_t)1u << (uint8_t)(sh - 1u))) : 0;
    off = (sh >= 8u) ? (int32_t)((uint32_t)1u << (uint8_t)(30u - sh)) : 0;
    for (i = 0u; i < (uint8_t)t->n; i++) {
        const int16_t a2 = t->a2[i], a3 = t->a3[i];
        const int16_t x0 = x[i];
        int16_t z = x0;
        for (it = 0u; it < nit; it++) {
            /* |h| <= |a2| + |a3| <= 32767, |g| <= |h|, |g z| <= 2^30 */
            int16_t h = (int16_t)(a2 + (int16_t)AC_R15(AC_MUL16(a3, z)));
            int16_t g = (int16_t)AC_R15(AC_MUL16(h, z));
            int32_t c;
            if (sh >= 16u) {
                uint16_t q = (uint16_t)(((uint32_t)AC_MUL16(g, z) + (uint32_t)bias) >> 16);
                c = (int32_t)(uint16_t)(q >> (uint8_t)(sh - 16u)) - off;
            } else if (sh >= 8u) {
                /* the same with a shift by 8 (byte moves) and at most 7 more */
                uint32_t q = (uint32_t)((uint32_t)AC_MUL16(g, z) + (uint32_t)bias) >> 8;
                c = (int32_t)(q >> (uint8_t)(sh - 8u)) - off;
            } else {
                /* a nonlinearity 128 times the reading at the int16 scale: the generic rounding */
                c = ac_scale_round(AC_MUL16(g, z), (int16_t)sh, &sat);
            }
            int32_t v = (int32_t)x0 - c;
            if (v > INT16_MAX) {
                z = INT16_MAX;
                sat = 1u;
            } else if (v < INT16_MIN) {
                z = INT16_MIN;
                sat = 1u;
            } else {
                z = (int16_t)v;
            }
        }
        y[i] = z;
    }
    return sat ? AC_SATURATED : AC_OK;
}
