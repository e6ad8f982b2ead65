/* accelcal -- apply a calibration (see ac_resolve.h for the arithmetic). */
#include "accelcal/ac_resolve.h"
#include "accelcal/ac_trim.h"
#include "ac_internal.h"

/* -31 <= s <= 31 (a macro: h8300-hms-gcc 3.4 calls a static function here,
 * 12 calls a sample) */
#define SHIFT_OK(s) ((uint8_t)((s) + 31) <= 62u)

/* Cheap per-call checks; the row sums are ac_resolver_check's job (once per table). */
ac_status ac_resolver_shape(const ac_resolver *r)
{
    uint8_t j;
    if (r == 0) {
        return AC_ERR_NULL;
    }
    if (r->n < 6u || r->n > (uint16_t)AC_MAX_CHANNELS) {
        return AC_ERR_SIZE;
    }
    for (j = 0u; j < 6u; j++) {
        if (!SHIFT_OK(r->m_shift[j]) || !SHIFT_OK(r->g_shift[j])) {
            return AC_ERR_FORMAT;
        }
    }
    return AC_OK;
}

#if !AC_H8_RESOLVE_ASM
/* Output j: round((M x - k - T) 2^-m_shift) (p = 0: no rotation).  A function of
 * its own: it keeps the row's working set small (avr-gcc 5.4 at -Os misplaces
 * stack slots when the whole loop is inlined into the kernel, with the plain C
 * helpers). */
static int32_t resolve_row(const ac_resolver *r, uint8_t j, const int16_t *x, const int16_t *p,
                           int16_t d0, uint8_t *sat)
{
    /* row L1 <= 65535 and |x| <= 32768 keep every partial sum in int32 */
    int32_t acc = ac_sat_sub(ac_i_from_u(ac_dot16(0u, r->m[j], x, (uint8_t)r->n)), r->k[j], sat);
    if (p != 0) {
        /* T (units 2^(s - 2 W - g_shift) LSB) -> accumulator units 2^-m_shift LSB */
        int32_t t = ac_i_from_u(ac_dot16_sparse(0u, r->g[j], p, 6u));
        int16_t d = (int16_t)(d0 - r->g_shift[j] + r->m_shift[j]);
        uint8_t tsat = 0u;
        t = ac_scale_round(t, (int16_t)-d, &tsat);
        if (tsat != 0u) {
            /* the centripetal term alone exceeds int32 accumulator units: it
             * dominates, so the output clips in its (negated) direction */
            *sat = 1u;
            return (t > 0) ? INT32_MIN : INT32_MAX;
        }
        acc = ac_sat_sub(acc, t, sat);
    }
    return ac_scale_round(acc, r->m_shift[j], sat);
}

/* The per-sample arithmetic.  With a table that passed ac_resolver_check the
 * sums below cannot overflow; they are done in uint32 (defined wrap-around) so
 * that even an unchecked, corrupt table cannot cause undefined behaviour. */
ac_status ac_resolve_kernel(const ac_resolver *r, const int16_t *x, const int16_t *omega,
                            int32_t *out)
{
    uint8_t sat = 0u;
    uint8_t j;
    int16_t p[6];
    int16_t d0 = 0; /* s - 2 AC_OMEGA_FRAC: the exponent of p */

    if (omega != 0) {
        const int16_t wx = omega[0], wy = omega[1], wz = omega[2];
        int32_t sq[6];
        uint32_t maxsq;
        uint8_t s, q;
        sq[0] = ac_i_from_u(ac_mac16(0u, wx, wx));
        sq[1] = ac_i_from_u(ac_mac16(0u, wy, wy));
        sq[2] = ac_i_from_u(ac_mac16(0u, wz, wz));
        sq[3] = ac_i_from_u(ac_mac16(0u, wx, wy));
        sq[4] = ac_i_from_u(ac_mac16(0u, wy, wz));
        sq[5] = ac_i_from_u(ac_mac16(0u, wz, wx));
        /* |w_a w_b| <= max(w_a^2, w_b^2): one block exponent for all six */
        maxsq = (uint32_t)sq[0];
        if ((uint32_t)sq[1] > maxsq) {
            maxsq = (uint32_t)sq[1];
        }
        if ((uint32_t)sq[2] > maxsq) {
            maxsq = (uint32_t)sq[2];
        }
        s = ac_bitlen_u(maxsq);
        s = (s > 14u) ? (uint8_t)(s - 14u) : 0u;
        for (q = 0u; q < 6u; q++) {
            /* |p| <= 2^14 after rounding: fits int16 */
            p[q] = (int16_t)((s != 0u) ? ac_round_shift(sq[q], s) : sq[q]);
        }
        d0 = (int16_t)((int16_t)s - 2 * AC_OMEGA_FRAC);
    }

    for (j = 0u; j < 6u; j++) {
        out[j] = resolve_row(r, j, x, omega != 0 ? p : 0, d0, &sat);
    }
    return sat ? AC_SATURATED : AC_OK;
}
#endif /* !AC_H8_RESOLVE_ASM: the H8/300H kernel is ac_resolve_h8.c */

ac_status ac_resolve(const ac_resolver *r, const int16_t *x, const int16_t *omega, int32_t *out)
{
    ac_status st;
    if (x == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    st = ac_resolver_shape(r);
    if (st != AC_OK) {
        return st;
    }
    return ac_resolve_kernel(r, x, omega, out);
}

#if !AC_H8_RESOLVE_ASM
ac_status ac_process(const ac_resolver *r, const uint16_t *trim, const uint16_t *raw,
                     const int16_t *omega, int32_t *out)
{
    int16_t x[AC_MAX_CHANNELS];
    ac_status st, st_trim;
    if (raw == 0 || trim == 0 || out == 0) {
        return AC_ERR_NULL;
    }
    st = ac_resolver_shape(r);
    if (st != AC_OK) {
        return st;
    }
    st_trim = ac_trim_rails(raw, trim, r->n, r->raw_min, r->raw_max, x);
    if (st_trim < 0) {
        return st_trim;
    }
    return ac_merge(st_trim, ac_resolve_kernel(r, x, omega, out));
}
#endif /* !AC_H8_RESOLVE_ASM: on the H8/300H ac_process is assembly too (ac_resolve_h8.c),
        * with the checks above (ac_resolver_shape's among them) in the same order */
