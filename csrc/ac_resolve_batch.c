/* accelcal -- the once-per-table check and the batch entry of ac_resolve.h.
 * An object of their own: firmware that calls only ac_process per sample
 * does not link them. */
#include "accelcal/ac_resolve.h"
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

#define ROW_L1_MAX 65535L

ac_status ac_resolver_check(const ac_resolver *r)
{
    uint8_t j;
    uint16_t i;
    ac_status st = ac_resolver_shape(r);
    if (st != AC_OK) {
        return st;
    }
    for (j = 0u; j < 6u; j++) {
        int32_t l1 = 0;
        for (i = 0u; i < r->n; i++) {
            l1 += (int32_t)ac_abs_u(r->m[j][i]);
        }
        if (l1 > ROW_L1_MAX) {
            return AC_ERR_FORMAT;
        }
        l1 = 0;
        for (i = 0u; i < 6u; i++) {
            l1 += (int32_t)ac_abs_u(r->g[j][i]);
        }
        if (l1 > ROW_L1_MAX) {
            return AC_ERR_FORMAT;
        }
    }
    return AC_OK;
}

ac_status ac_process_batch(const ac_resolver *r, const uint16_t *trim, const uint16_t *raw,
                           uint32_t count, const int16_t *omega, int32_t *out, uint8_t *flags)
{
    int16_t x[AC_MAX_CHANNELS];
    ac_status st;
    unsigned any = 0u;
    uint32_t k;
    if (raw == 0 || trim == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    st = ac_resolver_check(r);
    if (st != AC_OK) {
        return st;
    }
    for (k = 0u; k < count; k++) {
        uint8_t f = 0u;
        ac_status s1 = ac_trim_rails(raw, trim, r->n, r->raw_min, r->raw_max, x);
        ac_status s2 = ac_resolve_kernel(r, x, omega, out);
        if (((unsigned)s1 & (unsigned)AC_SATURATED) != 0u) {
            f |= AC_FLAG_TRIM_SAT;
        }
        if (((unsigned)s1 & (unsigned)AC_AT_RAIL) != 0u) {
            f |= AC_FLAG_AT_RAIL;
        }
        if (s2 == AC_SATURATED) {
            f |= AC_FLAG_OUT_SAT;
        }
        any |= (unsigned)s1 | (unsigned)s2;
        if (flags != 0) {
            flags[k] = f;
        }
        raw += r->n;
        out += 6;
        if (omega != 0) {
            omega += 3;
        }
    }
    return (ac_status)any;
}
