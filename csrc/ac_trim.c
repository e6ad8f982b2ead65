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
    for (i = 0u; i < n; i++) {
        /* int32 keeps the difference exact where int is 16 bits */
        x[i] = ac_sat_to16((int32_t)raw[i] - (int32_t)trim[i], &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}
