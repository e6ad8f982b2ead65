/* accelcal -- offset pre-trim. */
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

/* r - t clipped to int16 (r, t unsigned 16-bit codes), *sat set on a clip.  In 16 bits
 * (one register pair on 8- and 16-bit cores): the difference is in int16 iff it is
 * below 2^15 in magnitude. */
static int16_t trim_one(uint16_t r, uint16_t t, uint8_t *sat)
{
    if (r >= t) {
        uint16_t d = (uint16_t)(r - t);
        if (d > 32767u) {
            d = 32767u;
            *sat = 1u;
        }
        return (int16_t)d;
    } else {
        uint16_t d = (uint16_t)(t - r);
        if (d > 32768u) {
            d = 32768u;
            *sat = 1u;
        }
        /* -d = -(d - 1) - 1, where d - 1 <= 32767 fits int16 */
        return (int16_t)(-(int16_t)(d - 1u) - 1);
    }
}

/* A signed reading as an offset-binary code: v + 32768 in 0..65535, order kept, so that
 * (a + 32768) - (b + 32768) = a - b.  Each branch stays within int16 / uint16 (a 16-bit
 * int never overflows). */
static uint16_t offset_binary(int16_t v)
{
    if (v < 0) {
        return (uint16_t)((v + 32767) + 1); /* -32768..-1 -> 0..32767 */
    }
    return (uint16_t)((uint16_t)v + 32768u); /* 0..32767 -> 32768..65535 */
}

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
        x[i] = trim_one(raw[i], trim[i], &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_trim_s16(const int16_t *raw, const int16_t *trim, uint16_t n, int16_t *x)
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
        x[i] = trim_one(offset_binary(raw[i]), offset_binary(trim[i]), &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}
