/*
 * accelcal -- the channel rows of the on-device 6-DOF build (ac_inv_rows,
 * ac_invert_core.h): R_i = [s_i, r_i x s_i] and the centripetal row C_i, the products
 * of s and r exact in 64 bits (ac_ops64) and rounded once.  Used by ac_resolver_build
 * and by ac_sensor_row / ac_centripetal_row (ac_invert_api.c); the triad's build does
 * not need them.
 */
#include "ac_invert_core.h"
#include "ac_internal.h"

typedef ac_xf xf;

/* ---- rows of the sensor and centripetal matrices ---------------------------------- */

/* r = (neg ? -1 : 1) (hi 2^32 + lo) 2^e, rounded once: the bits below the 32 kept do not
 * matter to pack's rounding (half away from zero looks at the half bit only) */
static void pack64(xf *r, unsigned neg, uint32_t hi, uint32_t lo, int32_t e)
{
    unsigned k = 0u;
    while (k < 32u && (hi >> k) != 0u) {
        k++;
    }
    if (k == 32u) {
        lo = hi;
    } else if (k != 0u) {
        lo = (hi << (32u - k)) | (lo >> k);
    }
    ac_inv_pack(r, neg, lo, e + (int32_t)k);
}

/* The rows' products of s and r, each destination the sum of two signed products of the
 * channel's integers (sens Q.AC_SENS_FRAC, pos Q.AC_POS_FRAC), computed exactly in 64 bits and
 * rounded once -- so that r x s is 0 for r parallel to s, and a small cross product keeps
 * its digits however large the products it is the difference of (equilibration would
 * magnify their rounding otherwise).  Pairs (d, sub, a, b): v[d] +- v[a] v[b], v = 0 but
 * for s (v[0..2]) and r (v[6..8]):
 *   R_i[3..5] = r x s          (r_b s_c - r_c s_b)
 *   C_i[0..2] = s_a r_a - s.r  (= -(s_b r_b + s_c r_c))
 *   C_i[3..5] = s_a r_b + s_b r_a,  (a, b, c) = (0, 1, 2), (1, 2, 0), (2, 0, 1) */
#define OP(d, sub, a, b) (unsigned char)((d) + 16 * (sub)), (unsigned char)((a) + 16 * (b))
static const unsigned char row_program[36] = {
    OP(3, 0, 7, 2),  OP(3, 1, 8, 1),  OP(4, 0, 8, 0),  OP(4, 1, 6, 2),
    OP(5, 0, 6, 1),  OP(5, 1, 7, 0),  OP(9, 1, 1, 7),  OP(9, 1, 2, 8),
    OP(10, 1, 0, 6), OP(10, 1, 2, 8), OP(11, 1, 0, 6), OP(11, 1, 1, 7),
    OP(12, 0, 0, 7), OP(12, 0, 1, 6), OP(13, 0, 1, 8), OP(13, 0, 2, 7),
    OP(14, 0, 2, 6), OP(14, 0, 0, 8)};
#undef OP

static int32_t chan_int(const ac_channel_cal *cal, unsigned k)
{
    return (k < 3u) ? cal->sens[k] : cal->pos[k - 6u];
}

void ac_inv_rows(const ac_channel_cal *cal, xf v[15])
{
    const unsigned char *p;
    unsigned a;
    ac_inv_clear(v, 15u * sizeof *v);
    for (a = 0u; a < 3u; a++) {
        ac_inv_from_fixed(&v[a], cal->sens[a], AC_SENS_FRAC);
        ac_inv_from_fixed(&v[6u + a], cal->pos[a], AC_POS_FRAC);
    }
    for (p = row_program; p < row_program + sizeof row_program; p += 4) {
        ac_u64 m[2];
        unsigned neg[2], q;
        for (q = 0u; q < 2u; q++) {
            const unsigned char *op = (q != 0u) ? p + 2 : p;
            int32_t x = chan_int(cal, op[1] & 15u), y = chan_int(cal, (unsigned)op[1] >> 4);
            m[q] = ac_mul32u(ac_inv_mag(x), ac_inv_mag(y)); /* < 2^62 */
            neg[q] = (unsigned)(x < 0) ^ (unsigned)(y < 0) ^ ((unsigned)op[0] >> 4);
        }
        if (neg[0] == neg[1]) {
            m[0] = ac_u64_add(m[0], m[1]); /* < 2^63 */
        } else { /* the difference, with the sign of the larger */
            if (ac_u64_lt(m[0], m[1])) {
                ac_u64 t = m[0];
                m[0] = m[1];
                m[1] = t;
                neg[0] = neg[1];
            }
            m[0] = ac_u64_sub(m[0], m[1]);
        }
        pack64(&v[p[0] & 15u], neg[0], m[0].hi, m[0].lo, -(int32_t)(AC_SENS_FRAC + AC_POS_FRAC));
    }
}
