/* accelcal -- offset pre-trim. */
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

ac_status ac_trim(const uint16_t *raw, const uint16_t *trim, uint16_t n, int16_t *x)
{
    uint8_t sat = 0u;
    uint16_t i;
    if (raw == 0 || trim == 0 || x == 0) {
        return AC_ERR_NULL;
    }
    if (n == 0u) {
        return AC_ERR_SIZE;
    }
#if AC_H8_RESOLVE_ASM
    (void)i;
    sat = ac_h8_trim(raw, trim, n, x);
#else
    for (i = 0u; i < n; i++) {
        /* in 16 bits (one register pair on 8- and 16-bit cores): the
         * difference is in int16 iff it is below 2^15 in magnitude */
        uint16_t r = raw[i], t = trim[i];
        if (r >= t) {
            uint16_t d = (uint16_t)(r - t);
            if (d > 32767u) {
                d = 32767u;
                sat = 1u;
            }
            x[i] = (int16_t)d;
        } else {
            uint16_t d = (uint16_t)(t - r);
            if (d > 32768u) {
                d = 32768u;
                sat = 1u;
            }
            /* -d = -(d - 1) - 1, where d - 1 <= 32767 fits int16 */
            x[i] = (int16_t)(-(int16_t)(d - 1u) - 1);
        }
    }
#endif
    return sat ? AC_SATURATED : AC_OK;
}
