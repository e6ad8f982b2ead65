/*
 * accelcal -- build configuration and portable integer types.
 *
 * Override any AC_* value by defining AC_CONFIG_USER to the name of a header
 * of your own (e.g. -DAC_CONFIG_USER='"my_ac_config.h"'); it is included
 * first, and every default below is guarded with #ifndef.
 *
 * The library needs exact-width 8/16/32-bit integers only.  Compilers without
 * <stdint.h> (h8300-hms-gcc 3.4.6 ships no libc) get them from <limits.h>,
 * which every freestanding C implementation provides.
 */
#ifndef AC_CONFIG_H
#define AC_CONFIG_H

#ifdef AC_CONFIG_USER
#include AC_CONFIG_USER
#endif

/* ---- integer types ------------------------------------------------------ */
#if !defined(AC_NO_STDINT) && (defined(__H8300__) || defined(__H8300H__) || \
                               defined(__H8300S__))
#define AC_NO_STDINT 1 /* the H8 cross compiler has no libc headers */
#endif

#if defined(AC_NO_STDINT)
#include <limits.h>
typedef signed char int8_t;
typedef unsigned char uint8_t;
#if SHRT_MAX == 32767
typedef short int16_t;
typedef unsigned short uint16_t;
#else
#error "accelcal: no 16-bit integer type"
#endif
#if INT_MAX == 2147483647
typedef int int32_t;
typedef unsigned int uint32_t;
#elif LONG_MAX == 2147483647L
typedef long int32_t;
typedef unsigned long uint32_t;
#else
#error "accelcal: no 32-bit integer type"
#endif
#define INT16_MAX 32767
#define INT16_MIN (-32767 - 1)
#define UINT16_MAX 65535U
#define INT32_MAX 2147483647L
#define INT32_MIN (-2147483647L - 1L)
#define UINT32_MAX 4294967295UL
#else
#include <stdint.h>
#endif

/* Compile-time checks of the widths everything below relies on. */
#define AC_STATIC_ASSERT(name, cond) typedef char ac_static_assert_##name[(cond) ? 1 : -1]
AC_STATIC_ASSERT(int8_width, sizeof(int8_t) == 1);
AC_STATIC_ASSERT(int16_width, sizeof(int16_t) == 2);
AC_STATIC_ASSERT(int32_width, sizeof(int32_t) == 4);
AC_STATIC_ASSERT(uint32_width, sizeof(uint32_t) == 4);
AC_STATIC_ASSERT(int_at_least_16, sizeof(int) >= 2);

/* ---- sizes -------------------------------------------------------------- */
/* Largest channel count a resolver holds (6 for the seed array; 9 and 12 for
 * redundant layouts).  RAM per resolver is about 12 * AC_MAX_CHANNELS + 130
 * bytes. */
#ifndef AC_MAX_CHANNELS
#define AC_MAX_CHANNELS 12
#endif
#if AC_MAX_CHANNELS < 6 || AC_MAX_CHANNELS > 64
#error "AC_MAX_CHANNELS must be in 6..64"
#endif

/* ---- fixed-point formats (fractional bits) -------------------------------
 * These are part of the data format shared with generated headers and the
 * Python quantizer: a header records the values it was made for and refuses
 * to compile against a core built with others. */

/* Resolved outputs: f in m/s^2 and alpha in rad/s^2, int32, Q21.10
 * (1 LSB = 1/1024 = 0.98e-3 m/s^2 or rad/s^2). */
#ifndef AC_OUT_FRAC
#define AC_OUT_FRAC 10
#endif
/* Angular rate omega in rad/s, int16, Q5.10 (range +-32 rad/s,
 * 1 LSB = 0.98e-3 rad/s = 0.056 deg/s). */
#ifndef AC_OMEGA_FRAC
#define AC_OMEGA_FRAC 10
#endif
/* Calibration inputs for on-device inversion (int32):
 * sensitivity s_i in counts per m/s^2, Q15.16;
 * position r_i in m, Q11.20 (1 LSB = 0.95 um);
 * residual offset b_i - trim_i in counts, Q23.8. */
#ifndef AC_SENS_FRAC
#define AC_SENS_FRAC 16
#endif
#ifndef AC_POS_FRAC
#define AC_POS_FRAC 20
#endif
#ifndef AC_OFFSET_FRAC
#define AC_OFFSET_FRAC 8
#endif

/* On-device inversion refuses geometries whose 1-norm condition number
 * (of the column-equilibrated sensor matrix for N = 6, of its normal matrix
 * for N > 6) exceeds 2^AC_COND_LOG2_MAX. */
#ifndef AC_COND_LOG2_MAX
#define AC_COND_LOG2_MAX 16
#endif

#endif /* AC_CONFIG_H */
