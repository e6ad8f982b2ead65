/*
 * accelcal -- apply a calibration: raw channels -> specific force f and
 * angular acceleration alpha, with the centripetal term removed.
 *
 *   [f; alpha] = M (x - o - c(omega)),   c_i(omega) = s_i . (omega x (omega x r_i))
 *
 * x are the pre-trimmed readings (ac_trim), o the residual offsets, M the
 * (pseudo-)inverse of the calibrated sensor matrix (row i = [s_i, r_i x s_i]).
 * The offset and centripetal terms are folded through M once, when the table
 * is made, so a sample costs 6N + 6 + 36 multiplies of 16 x 16 bits:
 *
 *   out_j = round( (sum_i m[j][i] x_i  -  k[j]  -  T_j(omega)) * 2^-m_shift[j] )
 *   T_j   = align( sum_q g[j][q] p_q ),   p = (wx^2, wy^2, wz^2, wx wy, wy wz, wz wx)
 *
 * Units and formats:
 *   out[0..2] = f_x, f_y, f_z in m/s^2, out[3..5] = alpha_x..z in rad/s^2,
 *     int32 Q21.10 (AC_OUT_FRAC), rounded half up (ties towards +inf).
 *   omega: rad/s, int16 Q5.10 (AC_OMEGA_FRAC); NULL means no rotation.
 *   m[j][i] * 2^-(m_shift[j] + AC_OUT_FRAC) = M[j][i] in output units per count;
 *   k[j]    * 2^-(m_shift[j] + AC_OUT_FRAC) = (M o)_j in output units;
 *   g[j][q] * 2^-(g_shift[j] + AC_OUT_FRAC) = (M C)_jq in output units per (rad/s)^2.
 *
 * Table invariants (ac_resolver_check): 6 <= n <= AC_MAX_CHANNELS; each row of m
 * and of g has sum |.| <= 65535, which keeps every accumulation inside int32 for
 * any int16 input; shifts in -31..31.
 *
 * Saturation: an output beyond int32 clips to INT32_MIN/MAX with AC_SATURATED.
 * If an intermediate clips first (acc - k, or a centripetal term that alone
 * exceeds the int32 accumulator), the output is the clip in the direction of
 * the clipped term, also flagged; flagged outputs are limits, not values.
 *
 * Accuracy: the linear part is exact before the final rounding.  The squared
 * rates p_q are kept to 14 significant bits (a block exponent s shared by the
 * sample, s = max(0, bitlen(max_a w_a^2) - 14)), and T_j is rounded once more
 * when it is aligned to the accumulator (d = s - 2*AC_OMEGA_FRAC - g_shift[j]
 * + m_shift[j] < 0), so  |out_j - exact_j| <= 0.5 LSB + E_j  with
 *   E_j = [s > 0] sum_q |g[j][q]| 2^(s-1-2*AC_OMEGA_FRAC-g_shift[j]) + [d < 0] 2^(-1-m_shift[j]).
 * s = 0 (p exact) whenever |omega_a| < 0.125 rad/s on every axis.
 * python/accelcal/quantize.py computes the same bound; the tests hold the core to it.
 */
#ifndef AC_RESOLVE_H
#define AC_RESOLVE_H

#include "ac_config.h"
#include "ac_status.h"

typedef struct ac_resolver {
    uint16_t n;
    int8_t m_shift[6];
    int8_t g_shift[6];
    int32_t k[6];
    int16_t m[6][AC_MAX_CHANNELS];
    int16_t g[6][6];
    /* The converter's rails, uint16 codes (offset binary raw + 32768 for a chip with
     * signed output): ac_process flags a reading <= raw_min or >= raw_max (AC_AT_RAIL).
     * raw_min >= raw_max (0, 0 in a zeroed table, one ac_resolver_build made, or one from
     * a header older than the field): rails unknown, nothing flagged.  The generated
     * header fills them from the device's raw_min / raw_max; after an on-device build,
     * copy them in from there. */
    uint16_t raw_min;
    uint16_t raw_max;
} ac_resolver;

/* Per-sample flags written by ac_resolve_batch. */
#define AC_FLAG_TRIM_SAT 0x01u    /* a channel clipped in the pre-trim */
#define AC_FLAG_OUT_SAT 0x02u     /* an output or the centripetal term clipped */
#define AC_FLAG_AT_RAIL 0x04u     /* a raw reading at the converter's rail (raw_min / raw_max) */

/* AC_OK if the table keeps every invariant above, AC_ERR_SIZE / AC_ERR_FORMAT if not. */
ac_status ac_resolver_check(const ac_resolver *r);

/* One sample of trimmed readings x[0..n-1] -> out[0..5].
 * Per call only n and the shifts are checked (cheap); check a table you did not
 * make with ac_resolver_build or a generated header once with ac_resolver_check.
 * An unchecked table that breaks the row-sum invariant gives wrong numbers but
 * never undefined behaviour.  ac_process_batch runs the full check itself. */
ac_status ac_resolve(const ac_resolver *r, const int16_t *x, const int16_t *omega, int32_t *out);

/* Pre-trim and resolve one sample of raw readings (what firmware calls per sample).
 * Status: AC_SATURATED as ac_resolve (or the pre-trim clipped), and the bit AC_AT_RAIL when
 * a raw reading sits at a rail of the table (ac_trim_rails with r->raw_min, r->raw_max: the
 * chip clipped it, so out is not a measurement); AC_AT_RAIL_SATURATED for both.  Cost of
 * the rail test: see ac_trim_rails (H8/300H assembly: 12 states a channel, 92 a sample). */
ac_status ac_process(const ac_resolver *r, const uint16_t *trim, const uint16_t *raw,
                     const int16_t *omega, int32_t *out);

/* count samples: raw is count x n (row-major), omega count x 3 or NULL, out count x 6,
 * flags count bytes (AC_FLAG_*) or NULL.  The status bits of every sample together:
 * AC_SATURATED if any sample clipped (AC_FLAG_TRIM_SAT, AC_FLAG_OUT_SAT), AC_AT_RAIL if
 * any read a rail (AC_FLAG_AT_RAIL). */
ac_status ac_process_batch(const ac_resolver *r, const uint16_t *trim, const uint16_t *raw,
                           uint32_t count, const int16_t *omega, int32_t *out, uint8_t *flags);

#endif /* AC_RESOLVE_H */
