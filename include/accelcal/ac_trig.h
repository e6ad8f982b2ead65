/*
 * accelcal -- integer square root, division and atan2 for
 * the motion estimators (no libm, no libgcc: shifts, adds and 16 x 16-bit
 * multiplies only).
 *
 * Formats and error bounds (the property tests in tests/python/test_estimators.py
 * hold the code to exactly these):
 *
 *   ac_isqrt32   out = round(sqrt(v)) (half up; a tie cannot occur for integer v):
 *                exact, i.e. |out - sqrt(v)| <= 0.5.  v > 4294901760 saturates
 *                to 65535 (AC_SATURATED).
 *   ac_udiv64    q = round(num / den) half up, num = num_hi 2^32 + num_lo:
 *                exact; q > UINT32_MAX saturates; den == 0 is AC_ERR_RANGE.
 *   ac_atan2     angle = atan2(y, x) in rad, int16 Q2.13 (AC_ANGLE_FRAC;
 *                1 LSB = 2^-13 rad = 1.22e-4 rad = 0.0070 deg), range
 *                -pi..pi (pi = 25736 LSB; y = 0, x < 0 gives +pi).
 *                CORDIC vectoring with AC_ATAN2_ITERS (16) rotations on operands
 *                normalised to 2^28..2^29, angle accumulated in Q.28:
 *                |angle - atan2(y, x)| <= 0.5 LSB (final rounding)
 *                                        + atan(2^-(AC_ATAN2_ITERS-1)) (0.25 LSB for 16)
 *                                        + 2^-10 LSB (table and shift truncation)
 *                                      < 0.76 LSB = 9.3e-5 rad = 0.0053 deg   (AC_ATAN2_BOUND_LSB = 1).
 *                mag (may be NULL) = sqrt(x^2 + y^2) in the units of x and y,
 *                |mag - hypot| <= 2^-14 hypot + 1.
 *                x = y = 0 gives angle 0, mag 0 and AC_OK (the caller decides;
 *                ac_att flags it).
 */
#ifndef AC_TRIG_H
#define AC_TRIG_H

#include "ac_config.h"
#include "ac_status.h"
#include "ac_fixed.h" /* ac_mul32x16_shift, which the estimators use, lives there */

/* Angles: rad, int16 Q2.13. */
#ifndef AC_ANGLE_FRAC
#define AC_ANGLE_FRAC 13
#endif
#if AC_ANGLE_FRAC != 13
#error "ac_trig: AC_ANGLE_FRAC must be 13 (pi must fit int16 with the stated bound)"
#endif

/* CORDIC rotations in ac_atan2 (12..28).  Each one costs two variable shifts. */
#ifndef AC_ATAN2_ITERS
#define AC_ATAN2_ITERS 16
#endif
#if AC_ATAN2_ITERS < 12 || AC_ATAN2_ITERS > 28
#error "AC_ATAN2_ITERS must be in 12..28"
#endif

/* Stated bound of ac_atan2 in LSB of Q.AC_ANGLE_FRAC (for AC_ATAN2_ITERS >= 15). */
#define AC_ATAN2_BOUND_LSB 1

/* pi in Q.AC_ANGLE_FRAC (round(pi 2^13)) and in the Q.28 accumulator. */
#define AC_PI_Q13 25736
#define AC_PI_Q28 843314857L

ac_status ac_isqrt32(uint32_t v, uint16_t *out);
ac_status ac_udiv64(uint32_t num_hi, uint32_t num_lo, uint32_t den, uint32_t *q);
ac_status ac_atan2(int32_t y, int32_t x, int16_t *angle, uint32_t *mag);

#endif /* AC_TRIG_H */
