/*
 * accelcal -- offset pre-trim.
 *
 * x_i = raw_i - trim_i, clipped to int16.  The seed firmware did this on the
 * MCU so that chip offsets of up to ~28 % of g do not eat the dynamic range
 * of the 16-bit pipeline; trim_i is the channel's zero reading rounded to a
 * whole count (the generated header's AC_CAL_TRIM table).
 */
#ifndef AC_TRIM_H
#define AC_TRIM_H

#include "ac_config.h"
#include "ac_status.h"

/* n channels; AC_SATURATED if any x_i was clipped. */
ac_status ac_trim(const uint16_t *raw, const uint16_t *trim, uint16_t n, int16_t *x);

/* The same for a chip with signed (two's complement) output, such as the MPU-6050,
 * ADXL345, LSM6 or BMI families: raw and trim int16 counts, x_i = raw_i - trim_i
 * clipped to int16 (|raw_i - trim_i| can reach 65535), AC_SATURATED if any was.
 * Identical to ac_trim on the offset-binary codes raw + 32768, trim + 32768. */
ac_status ac_trim_s16(const int16_t *raw, const int16_t *trim, uint16_t n, int16_t *x);

#endif /* AC_TRIM_H */
