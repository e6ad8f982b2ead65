/*
 * accelcal -- the parts of the on-device build (ac_invert.c) that the other
 * public ac_invert.h functions (ac_invert_api.c) share (internal, not
 * installed).  Firmware that only calls ac_resolver_build links ac_invert.o
 * alone.
 *
 * Numbers are ac_xf, normalised (2^29 <= |m| < 2^30, or m == 0 with e == 0).
 */
#ifndef AC_INVERT_CORE_H
#define AC_INVERT_CORE_H

#include "accelcal/ac_invert.h"

#define AC_INV_EMAX 30000L
#define AC_INV_EMIN (-30000L)

/* v = v 2^k, normalised and rounded to 30 bits (any mantissa; below 2^-30000 it is 0);
 * the caller keeps the result's exponent at most AC_INV_EMAX. */
void ac_inv_scale(ac_xf *v, int32_t k);

/* v[0..5] = R_i = [s_i, r_i x s_i], v[6..8] = r_i, v[9..14] = C_i (ac_invert.h). */
void ac_inv_rows(const ac_channel_cal *cal, ac_xf v[15]);

/* In-place Gauss-Jordan inverse with partial pivoting of normalised entries whose
 * largest is within a few binades of 1; cond_log2 is written unless singular. */
ac_status ac_inv_gauss_jordan(ac_xf a[6][6], int8_t perm[6], int16_t *cond_log2);

#endif /* AC_INVERT_CORE_H */
