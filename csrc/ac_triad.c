/* accelcal -- one 3-axis sensor's per-sample path: pre-trim and the 3x3 table
 * (ac_triad_apply, ac_triad_resolve, ac_triad_check; see ac_attitude.h).  Its own
 * translation unit, so that firmware for a triad links this, ac_trim.o and the
 * rounding helpers, not the pendulum estimator of ac_attitude.c. */
#include "accelcal/ac_attitude.h"
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

ac_status ac_triad_check(const ac_triad *t)
{
    uint8_t j, i;
    if (t == 0) {
        return AC_ERR_NULL;
    }
    for (j = 0u; j < 3u; j++) {
        uint32_t l1 = 0u;
        if (t->shift[j] < -31 || t->shift[j] > 31) {
            return AC_ERR_FORMAT;
        }
        for (i = 0u; i < 3u; i++) {
            l1 += ac_abs_u((int32_t)t->m[j][i]);
        }
        if (l1 > 65535u) {
            return AC_ERR_FORMAT;
        }
    }
    return AC_OK;
}

ac_status ac_triad_resolve(const ac_triad *t, const int16_t *x, int32_t *f)
{
    uint8_t sat = 0u, j;
    if (t == 0 || x == 0 || f == 0) {
        return AC_ERR_NULL;
    }
    for (j = 0u; j < 3u; j++) {
        if (t->shift[j] < -31 || t->shift[j] > 31) {
            return AC_ERR_FORMAT;
        }
    }
    for (j = 0u; j < 3u; j++) {
        /* within int32 when the row-sum invariant holds (ac_triad_check); a table that
         * breaks it gives wrong numbers (the sum wraps in uint32), never undefined behaviour */
        int32_t acc = ac_i_from_u(
            ac_mac16(ac_mac16(ac_mac16(0u, t->m[j][0], x[0]), t->m[j][1], x[1]), t->m[j][2], x[2]));
        acc = ac_sat_sub(acc, t->k[j], &sat);
        f[j] = ac_scale_round(acc, (int16_t)t->shift[j], &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}

ac_status ac_triad_apply(const ac_triad *t, const uint16_t *raw, int32_t *f)
{
    int16_t x[3];
    ac_status s, r;
    if (t == 0 || raw == 0 || f == 0) {
        return AC_ERR_NULL;
    }
    s = ac_trim_rails(raw, t->trim, 3u, t->raw_min, t->raw_max, x);
    if (s < 0) {
        return s;
    }
    r = ac_triad_resolve(t, x, f);
    return r < 0 ? r : ac_merge(s, r);
}
