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

/* ac_trim and, in the same pass, the converter's rails: also AC_AT_RAIL (the status bit,
 * so AC_AT_RAIL_SATURATED with a clip) if any raw_i <= raw_min or raw_i >= raw_max: the
 * chip clipped that reading, and what is made of it is not a measurement (the host's
 * `clipped` column, accelcal.clipping.at_rails, is the same test).  raw_min >= raw_max
 * (e.g. 0, 0: rails unknown) flags nothing.  x is as ac_trim's either way.  Cost: two
 * compares a channel; measured on the per-sample paths (tools/bench_core.py, bench_h8.py),
 * ac_process with omega, 6 channels: +40 host x86-64 instructions (1482 -> 1522), +77 / +70
 * AVR cycles at -Os / -O2 (5810 -> 5887, 5304 -> 5374), +92 H8/300H states (4308 -> 4400,
 * the assembly's 12 a channel); ac_triad_apply: +29 instructions, +60 AVR cycles. */
ac_status ac_trim_rails(const uint16_t *raw, const uint16_t *trim, uint16_t n, uint16_t raw_min,
                        uint16_t raw_max, int16_t *x);

/* The same for a chip with signed (two's complement) output, such as the MPU-6050,
 * ADXL345, LSM6 or BMI families: raw and trim int16 counts, x_i = raw_i - trim_i
 * clipped to int16 (|raw_i - trim_i| can reach 65535), AC_SATURATED if any was.
 * Identical to ac_trim on the offset-binary codes raw + 32768, trim + 32768. */
ac_status ac_trim_s16(const int16_t *raw, const int16_t *trim, uint16_t n, int16_t *x);

/* ac_trim_s16 and, in the same pass, the converter's rails in the chip's own signed counts
 * (e.g. -2048, 2047 for a 12-bit chip; the generated header's <PREFIX>_RAW_MIN / _RAW_MAX):
 * also AC_AT_RAIL if any raw_i <= raw_min or raw_i >= raw_max, as ac_trim_rails on the
 * offset-binary codes (raw_min >= raw_max: unknown, nothing flagged).  x is as
 * ac_trim_s16's either way.  The signed chip's per-sample path is this, then ac_resolve or
 * ac_triad_resolve. */
ac_status ac_trim_rails_s16(const int16_t *raw, const int16_t *trim, uint16_t n, int16_t raw_min,
                            int16_t raw_max, int16_t *x);

#endif /* AC_TRIM_H */
