/*
 * accelcal -- temperature terms: the lagged temperature and the per-channel
 * offset and gain correction it drives.  Float reference:
 * python/accelcal/firmware/terms.py (lag_temperature, temperature_correct).
 *
 * Lag (ac_temp_lag_step), one filter per tempco kind (offset, gain), per sample:
 *   T_s[n] = T_s[n-1] + c (T[n] - T_s[n-1]),  c = 1 - exp(-dt / tau) = k 2^-shift,
 *   T_s[0] = T[0] (the first step fills the state).
 *   T: degC, int16 Q7.8 (AC_TEMP_FRAC; 1 LSB = 1/256 degC, range +-128 degC); the
 *   caller converts its thermometer's reading to it.  State: int32 Q.(AC_TEMP_FRAC + 16).
 *   Each step rounds the update once (half up, ac_mul32x16_shift: two 16 x 16 multiplies).
 *   Error bound against the float filter with the exact c, fed the same T, over any run:
 *     |T_s - T_s,ref| <= 2^-9 + 2^-25 / c + |c~ - c| / c~ * span(T)   degC
 *   (output rounding; the update's rounding accumulated; the coefficient's rounding,
 *   |c~ - c| / c <= 2^-16 as the quantizer picks k in 32768..65535 unless c = 1).
 *   The state clips (AC_SATURATED) only if T jumps by more than 128 degC.
 *
 * Correction (ac_temp_correct), x the trimmed readings (ac_trim, counts about trim_i):
 *   y_i = o_i + (x_i - o_i - oc_i dTo) / (1 + gc_i dTg)
 *   dTo = T_s,off - t_ref, dTg = T_s,gain - t_ref (Q.AC_TEMP_FRAC, clipped to int16);
 *   o_i = b_i - trim_i (Q.AC_OFFSET_FRAC), oc_i = oc[i] 2^-AC_TEMP_OC_FRAC counts/degC
 *   (|oc| < 128 counts/degC), gc_i = gc[i] 2^-AC_TEMP_GC_FRAC 1/degC (|gc| < 1.95e-3 /degC).
 *   Integer steps (5 multiplies 16 x 16 a channel; every shift a constant):
 *     w  = x 2^16 - o 2^8 - oc dTo                      Q.16 counts (int32, exact unless it clips)
 *     e  = round(gc dTg 2^-13), |e| <= AC_TEMP_E_MAX    Q.19
 *     e2 = round(e e 2^-19), e3 = round(e2 e 2^-19),  r = -e + e2 - e3   (Q.19, 1/(1+e) - 1)
 *     y  = round((w + round(round(w 2^-16) r 2^-3) + o 2^8) 2^-(16 - k)), clipped to int16
 *   k = the table's frac (0..AC_TEMP_MAX_OUT_FRAC): y in 2^-k counts (Q.k), the fractional bits the
 *   terms hand on to ac_skew_step (scale-free), ac_nonlin_invert and the resolver (ac_resolve,
 *   ac_triad_resolve), whose tables a generated header builds for input in 2^-k counts
 *   (<PREFIX>_TERMS_FRAC; k = 0: whole counts, today's arithmetic bit for bit).  Without the
 *   fraction rint(x + c(T)) is off by the same fraction on every sample of a static pose.
 *   Error bound against the float y with the table's coefficients, the same x, dTo, dTg:
 *     |y 2^-k - y_ref| <= 2^-(k+1) + 2^-8 + 0.54 |e| + (max(|x|, |y_ref|) + 1) (2^-18 + |e|^4 / (1 - |e|))   counts
 *   (2^-(k+1) the final rounding; the series' truncation e^4; the roundings of e, e2, e3, w r).
 *   |e| is held to AC_TEMP_E_MAX 2^-19 = 5.47 % (a larger gain change clips, AC_SATURATED).
 * On the H8/300H (normal mode) ac_temp_correct and ac_temp_lag_step are assembly
 * (csrc/ac_terms_h8.c), the same arithmetic bit for bit (frac 0..AC_TEMP_MAX_OUT_FRAC); the C of
 * ac_temp.c everywhere else.
 */
#ifndef AC_TEMP_H
#define AC_TEMP_H

#include "ac_config.h"
#include "ac_status.h"

#define AC_TEMP_FRAC 8
#define AC_TEMP_LAG_EXTRA 16
#define AC_TEMP_GAIN_FRAC 19
#define AC_TEMP_E_MAX 28672
#define AC_TEMP_OC_FRAC 8
#define AC_TEMP_GC_FRAC 24
#define AC_TEMP_MAX_OUT_FRAC 8

typedef struct ac_temp_lag {
    int32_t y;     /* Q.(AC_TEMP_FRAC + AC_TEMP_LAG_EXTRA) degC */
    uint16_t k;    /* c = k 2^-shift, k <= 2^shift */
    uint8_t shift; /* 0..47 */
    uint8_t started;
} ac_temp_lag;

typedef struct ac_temp_table {
    uint16_t n;                    /* channels, 1..AC_MAX_CHANNELS */
    int16_t t_ref;                 /* Q.AC_TEMP_FRAC degC */
    int16_t oc[AC_MAX_CHANNELS];   /* offset tempco, counts/degC Q.AC_TEMP_OC_FRAC */
    int16_t gc[AC_MAX_CHANNELS];   /* gain tempco, 1/degC Q.AC_TEMP_GC_FRAC */
    int16_t o[AC_MAX_CHANNELS];    /* b_i - trim_i, Q.AC_OFFSET_FRAC counts, |o| <= 128 */
    uint8_t frac;                  /* k: y in 2^-k counts (Q.k), 0..AC_TEMP_MAX_OUT_FRAC; 0: whole
                                    * counts (last, so that tables written without it mean 0) */
} ac_temp_table;

/* A filter of weight k 2^-shift (k <= 2^shift, shift <= 47; k = 1, shift = 0: no lag);
 * the next step starts it at its input.  AC_ERR_RANGE for other k, shift. */
ac_status ac_temp_lag_init(ac_temp_lag *f, uint16_t k, uint8_t shift);

/* One sample: temp (Q.AC_TEMP_FRAC degC) -> *lagged (the same format). */
ac_status ac_temp_lag_step(ac_temp_lag *f, int16_t temp, int16_t *lagged);

/* AC_OK if the table's n is in range, |o| <= 128 and frac <= AC_TEMP_MAX_OUT_FRAC, AC_ERR_SIZE /
 * AC_ERR_FORMAT if not. */
ac_status ac_temp_check(const ac_temp_table *t);

/* x[0..n-1] -> y[0..n-1] (may be the same array) with t_off, t_gain the lagged temperatures
 * (Q.AC_TEMP_FRAC degC) of the offset and the gain; x whole counts, y in 2^-frac counts;
 * AC_SATURATED if a value clipped.  Per call only n and frac are checked (AC_ERR_SIZE, AC_ERR_FORMAT); check a table you did not get from a generated header once
 * with ac_temp_check (one with |o| > 128 gives wrong numbers, never undefined behaviour). */
ac_status ac_temp_correct(const ac_temp_table *t, int16_t t_off, int16_t t_gain, const int16_t *x,
                          int16_t *y);

#endif /* AC_TEMP_H */
