/* accelcal -- offset pre-trim. */
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

#if !AC_H8_RESOLVE_ASM
/* x = r - t clipped to int16 (*sat = 1 when clipped), in 16 bits (one register
 * pair on 8- and 16-bit cores): the difference is in int16 iff it is below 2^15
 * in magnitude */
AC_ALWAYS_INLINE int16_t trim_one(uint16_t r, uint16_t t, uint8_t *sat)
{
    uint16_t d;
    if (r >= t) {
        d = (uint16_t)(r - t);
        if (d > 32767u) {
            d = 32767u;
            *sat = 1u;
        }
        return (int16_t)d;
    }
    d = (uint16_t)(t - r);
    if (d > 32768u) {
        d = 32768u;
        *sat = 1u;
    }
    /* -d = -(d - 1) - 1, where d - 1 <= 32767 fits int16 */
    return (int16_t)(-(int16_t)(d - 1u) - 1);
}
#endif

ac_status ac_trim(const uint16_t *raw, const uint16_t *trim, uint16_t n, int16_t *x)
{
#if AC_H8_RESOLVE_ASM
    /* the assembly loop alone (ac_trim_rails adds a C loop over the rails) */
    if (raw == 0 || trim == 0 || x == 0) {
        return AC_ERR_NULL;
    }
    if (n == 0u) {
        return AC_ERR_SIZE;
    }
    return ac_h8_trim(raw, trim, n, x) ? AC_SATURATED : AC_OK;
#else
    /* the rails unknown (raw_min >= raw_max): the pre-trim alone */
    return ac_trim_rails(raw, trim, n, 0u, 0u, x);
#endif
}

ac_status ac_trim_rails(const uint16_t *raw, const uint16_t *trim, uint16_t n, uint16_t raw_min,
                        uint16_t raw_max, int16_t *x)
{
    uint8_t sat = 0u, rail = 0u;
    uint16_t i;
    if (raw == 0 || trim == 0 || x == 0) {
        return AC_ERR_NULL;
    }
    if (n == 0u) {
        return AC_ERR_SIZE;
    }
#if AC_H8_RESOLVE_ASM
    /* the rails in C, then the assembly pre-trim */
    for (i = 0u; i < n; i++) {
        if (raw[i] <= raw_min || raw[i] >= raw_max) {
            rail = 1u;
        }
    }
    sat = ac_h8_trim(raw, trim, n, x);
#else
    for (i = 0u; i < n; i++) {
        uint16_t r = raw[i];
        if (r <= raw_min || r >= raw_max) {
            rail = 1u;
        }
        x[i] = trim_one(r, trim[i], &sat);
    }
#endif
    /* raw_min >= raw_max (rails unknown): every reading passed a test, none counts */
    if (raw_min >= raw_max) {
        rail = 0u;
    }
    return (ac_status)((sat ? (unsigned)AC_SATURATED : 0u) | (rail ? (unsigned)AC_AT_RAIL : 0u));
}
