/*
 * accelcal -- build a resolver table on the device from calibrated channel
 * parameters, with no host: after a field recalibration firmware re-derives
 * M (the 6x6 inverse for N = 6, the least-squares pseudo-inverse
 * (R^T R)^-1 R^T for 6 < N <= AC_MAX_CHANNELS), the offset term and the
 * centripetal table, in integer arithmetic (a compact private soft-float on
 * the ac_xf layout, csrc/ac_invert.c: 30-bit mantissas, 32-bit integer and
 * 16 x 16 multiplies only), and quantises them with the same rule as the
 * host's quantizer (python/accelcal/quantize.py).  Firmware that calls only
 * ac_resolver_build links ac_resolver_build.o, ac_invert_rows.o, ac_invert.o
 * and ac_ops64.o's exact multiply (no ac_xf.o, no ac_invert_api.o, no
 * ac_triad_build.o); one that calls only ac_triad_build links ac_triad_build.o
 * and ac_invert.o.
 *
 * Columns of R are equilibrated by powers of two; Gauss-Jordan elimination
 * uses partial pivoting.  A pivot below 2^-26 of the largest matrix entry
 * gives AC_ERR_SINGULAR; a 1-norm condition number above 2^AC_COND_LOG2_MAX
 * gives AC_ERR_ILL_COND.  On error the output table is left untouched.
 */
#ifndef AC_INVERT_H
#define AC_INVERT_H

#include "ac_config.h"
#include "ac_status.h"
#include "ac_xf.h"
#include "ac_resolve.h"
#include "ac_attitude.h"

/* One channel's calibration in fixed point (see ac_config.h for formats). */
typedef struct ac_channel_cal {
    int32_t sens[3]; /* s_i, counts per m/s^2, Q.AC_SENS_FRAC */
    int32_t pos[3];  /* r_i, m, Q.AC_POS_FRAC */
    int32_t offset;  /* b_i - trim_i, counts, Q.AC_OFFSET_FRAC */
} ac_channel_cal;

/* Caller-owned scratch memory for ac_resolver_build (may live in a union
 * with other buffers; nothing in it is needed afterwards).  Its layout is
 * private to the build. */
typedef struct ac_build_work {
    ac_xf a[6][6];   /* R (N = 6) or R^T R (N > 6), equilibrated, then its inverse */
    ac_xf acc[6][9]; /* per output row j: (M C)_j. [0..5], (M o)_j [6], max_i |.| [7], sum_i |.| [8] */
    int16_t colexp[6];
    int8_t perm[6];
} ac_build_work;

/* ceil(log2(cond_1)) of the matrix inverted, written when info is not NULL. */
typedef struct ac_build_info {
    int16_t cond_log2;
} ac_build_info;

ac_status ac_resolver_build(const ac_channel_cal *cal, uint16_t n, ac_build_work *work,
                            ac_resolver *out, ac_build_info *info);

/* The same for one 3-axis sensor (f only): cal[0..2] (pos unused), the trim codes of
 * the ac_triad (uint16; offset binary, trim + 32768, for a chip with signed output)
 * -> out = S^-1 folded as estimators' quantize_triad does (python/accelcal/triad.py).
 * AC_ERR_SINGULAR when the three axes do not span 3-D, AC_ERR_ILL_COND above
 * 2^AC_COND_LOG2_MAX, AC_ERR_RANGE when the offset term does not fit; out untouched
 * on error. */
ac_status ac_triad_build(const ac_channel_cal *cal, const uint16_t *trim, ac_build_work *work, ac_triad *out);

/* Row i of the sensor matrix, [s_i, r_i x s_i] (counts per m/s^2, counts per rad/s^2),
 * and the centripetal row C_i with c_i(omega) = sum_q C_iq p_q (counts per (rad/s)^2). */
ac_status ac_sensor_row(const ac_channel_cal *cal, ac_xf row[6]);
ac_status ac_centripetal_row(const ac_channel_cal *cal, ac_xf row[6]);

/* In-place inverse of the 6x6 matrix a by Gauss-Jordan with partial pivoting
 * (the build's own elimination, on a scaled by a power of two so that its
 * largest entry is about 1); cond_log2 (may be NULL) receives
 * ceil(log2(||a||_1 ||a^-1||_1)).  Exponents of a must be within +-30000
 * (AC_ERR_RANGE otherwise, and when the inverse would leave that range). */
ac_status ac_invert6(ac_xf a[6][6], int8_t perm[6], int16_t *cond_log2);

#endif /* AC_INVERT_H */
