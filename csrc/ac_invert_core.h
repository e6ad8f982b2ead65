/*
 * accelcal -- what the on-device builds share (internal, not installed): the
 * soft-float on the ac_xf layout and the 6x6 inverse (ac_invert.c), the channel
 * rows (ac_invert_rows.c).  One .c per concern, so that firmware links only what
 * it calls: ac_triad_build (ac_triad_build.c) needs ac_invert.o; ac_resolver_build
 * (ac_resolver_build.c) ac_invert.o and ac_invert_rows.o; the other public
 * ac_invert.h functions are in ac_invert_api.c.
 *
 * Numbers are ac_xf, normalised (2^29 <= |m| < 2^30, or m == 0 with e == 0).
 */
#ifndef AC_INVERT_CORE_H
#define AC_INVERT_CORE_H

#include "accelcal/ac_invert.h"

#define AC_INV_EMAX 30000L
#define AC_INV_EMIN (-30000L)
#define AC_INV_XF_LO 0x20000000UL /* 2^29: smallest normalised |m| */
#define AC_INV_XF_HI 0x40000000UL /* 2^30 */
#define AC_INV_COEF_MAX 32767L    /* largest table coefficient */
#define AC_INV_ROW_L1_MAX 65535L  /* largest sum of |coefficient| + count in a row */

/* 1, normalised */
extern const ac_xf ac_inv_one;

static inline uint32_t ac_inv_mag(int32_t m)
{
    return (m < 0) ? 0u - (uint32_t)m : (uint32_t)m;
}

/* bytes of p set to 0 (no memset: the core links without libc) */
void ac_inv_clear(void *p, unsigned bytes);

/* r = (neg ? -1 : 1) * mag 2^e, normalised and rounded half away from zero */
void ac_inv_pack(ac_xf *r, unsigned neg, uint32_t mag, int32_t e);

/* v = v 2^k, normalised and rounded to 30 bits (any mantissa; below 2^-30000 it is 0);
 * the caller keeps the result's exponent at most AC_INV_EMAX. */
void ac_inv_scale(ac_xf *v, int32_t k);

/* r = v 2^-frac */
void ac_inv_from_fixed(ac_xf *r, int32_t v, int16_t frac);

/* r = r + a b, or r - a b when sub != 0, rounded once (ac_invert.c); r may alias a or b
 * only if it is not zero on entry. */
void ac_inv_mac(ac_xf *r, const ac_xf *a, const ac_xf *b, unsigned sub);

/* max = max(max, |v|); sum += |v| */
void ac_inv_acc_abs(ac_xf *max, ac_xf *sum, const ac_xf *v);

/* *out = round(v 2^s) half up; returns 1 if that does not fit int32 (*out is then not it) */
unsigned ac_inv_to_fixed(const ac_xf *v, int16_t s, int32_t *out);

/* The host quantizer's row shift: the largest s <= 31 with max |v| 2^s <= 32767 and
 * sum |v| 2^s <= 65535 - count (mm[0] = max |v|, mm[1] = sum |v|). */
int16_t ac_inv_row_shift(const ac_xf mm[2], uint16_t count);

/* ac_inv_to_fixed into int16, saturated to +-32767 */
int16_t ac_inv_to_i16(const ac_xf *v, int16_t s);

/* v[0..5] = R_i = [s_i, r_i x s_i], v[6..8] = r_i, v[9..14] = C_i (ac_invert.h);
 * ac_invert_rows.c. */
void ac_inv_rows(const ac_channel_cal *cal, ac_xf v[15]);

/* In-place Gauss-Jordan inverse with partial pivoting of normalised entries whose
 * largest is within a few binades of 1; cond_log2 is written unless singular. */
ac_status ac_inv_gauss_jordan(ac_xf a[6][6], int8_t perm[6], int16_t *cond_log2);

#endif /* AC_INVERT_CORE_H */
