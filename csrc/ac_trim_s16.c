/* accelcal -- offset pre-trim of signed (two's complement) readings, and their rail test.
 * Its own object so that firmware for an unsigned chip does not link it (the H8
 * toolchain links whole objects). */
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

ac_status ac_trim_s16(const int16_t *raw, const int16_t *trim, uint16_t n, int16_t *x)
{
    /* the rails unknown (raw_min >= raw_max): the pre-trim alone */
    return ac_trim_rails_s16(raw, trim, n, 0, 0, x);
}

ac_status ac_trim_rails_s16(const int16_t *raw, const int16_t *trim, uint16_t n, int16_t raw_min,
                            int16_t raw_max, int16_t *x)
{
    uint8_t sat = 0u, rail = 0u;
    uint16_t i;
    if (raw == 0 || trim == 0 || x == 0) {
        return AC_ERR_NULL;
    }
    if (n == 0u) {
        return AC_ERR_SIZE;
    }
    for (i = 0u; i < n; i++) {
        int16_t r = raw[i];
        /* in 32 bits (an add on every target, no library call): |raw - trim| <= 65535 */
        int32_t d = (int32_t)r - (int32_t)trim[i];
        if (r <= raw_min || r >= raw_max) {
            rail = 1u;
        }
        if (d > 32767L) {
            d = 32767L;
            sat = 1u;
        } else if (d < -32768L) {
            d = -32768L;
            sat = 1u;
        }
        x[i] = (int16_t)d;
    }
    /* raw_min >= raw_max (rails unknown): every reading passed a test, none counts */
    if (raw_min >= raw_max) {
        rail = 0u;
    }
    return (ac_status)((sat ? (unsigned)AC_SATURATED : 0u) | (rail ? (unsigned)AC_AT_RAIL : 0u));
}
