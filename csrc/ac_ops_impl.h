/*
 * accelcal -- definitions of the internal helpers (included, never compiled on
 * its own).  ac_internal.h includes it with AC_HELPER = "static inline" where
 * the compiler inlines well (GCC >= 4, clang), so the per-sample code pays no
 * calls; older compilers (h8300-hms-gcc 3.4 emits a separate copy of every
 * static inline function in every object) get one external copy from ac_ops.c.
 */
#ifndef AC_OPS_IMPL_H
#define AC_OPS_IMPL_H

/* Combine two statuses: the first error wins, otherwise the warnings of both
 * (the bits AC_SATURATED and AC_AT_RAIL). */
AC_HELPER ac_status ac_merge(ac_status a, ac_status b)
{
    if (a < 0) {
        return a;
    }
    if (b < 0) {
        return b;
    }
    return (ac_status)((unsigned)a | (unsigned)b);
}

AC_HELPER int32_t ac_i_from_u(uint32_t u)
{
    if (u <= (uint32_t)INT32_MAX) {
        return (int32_t)u;
    }
    /* u >= 2^31: value u - 2^32 = -(~u) - 1, and ~u <= INT32_MAX */
    return -(int32_t)(~u) - 1;
}

/* |v| as uint32 (exact for INT32_MIN). */
AC_HELPER uint32_t ac_abs_u(int32_t v)
{
    return (v < 0) ? (uint32_t)0u - (uint32_t)v : (uint32_t)v;
}

/* u >> n for 0 <= n <= 31, in whole-word and whole-byte steps first: 8-bit
 * cores (AVR) have no barrel shifter and shift 32-bit values one bit a loop
 * (on AVR written out, as avr-gcc pays a call and spills for the C form). */
AC_HELPER uint32_t ac_shr_u(uint32_t u, uint8_t n)
{
#if defined(__AVR__) && !defined(AC_NO_ASM)
    __asm__("sbrs %[n], 4          \n\t"
            "rjmp 1f               \n\t"
            "movw %A[u], %C[u]     \n\t"
            "clr  %C[u]            \n\t"
            "clr  %D[u]            \n\t"
            "1: sbrs %[n], 3       \n\t"
            "rjmp 2f               \n\t"
            "mov  %A[u], %B[u]     \n\t"
            "mov  %B[u], %C[u]     \n\t"
            "mov  %C[u], %D[u]     \n\t"
            "clr  %D[u]            \n\t"
            "2: andi %[n], 7       \n\t"
            "breq 4f               \n\t"
            "3: lsr %D[u]          \n\t"
            "ror  %C[u]            \n\t"
            "ror  %B[u]            \n\t"
            "ror  %A[u]            \n\t"
            "dec  %[n]             \n\t"
            "brne 3b               \n\t"
            "4:                    \n\t"
            : [u] "+r"(u), [n] "+d"(n));
    return u;
#else
    if ((n & 16u) != 0u) {
        u >>= 16;
    }
    if ((n & 8u) != 0u) {
        u >>= 8;
    }
    return u >> (n & 7u);
#endif
}

/* floor(v / 2^n), 0 <= n <= 31: for v < 0 the bits of -1 - v = ~v are
 * shifted, so the unsigned shift serves both signs. */
AC_HELPER int32_t ac_floor_shift(int32_t v, uint8_t n)
{
    uint32_t sign = (v < 0) ? 0xFFFFFFFFu : 0u;
    return ac_i_from_u(ac_shr_u((uint32_t)v ^ sign, n) ^ sign);
}

/* round(v / 2^n) half up, 1 <= n <= 31, without overflow: with
 * a = floor(v / 2^(n-1)), the result is floor((a + 1) / 2) = floor(a / 2) plus
 * the low bit of a, which cannot overflow because |a| <= 2^30 for n >= 2 and
 * floor(a / 2) < 2^30 for n = 1.  The plain C shifts the bits of ~v = -1 - v
 * for v < 0 (an unsigned shift serves both signs); AVR: one arithmetic shift
 * written out, whole bytes first (a third of avr-gcc's cycles for the C form). */
AC_HELPER int32_t ac_round_shift(int32_t v, uint8_t n)
{
#if defined(__AVR__) && !defined(AC_NO_ASM)
    uint8_t sign;
    __asm__("dec  %[n]             \n\t"
            "mov  %[s], %D[v]      \n\t"
            "lsl  %[s]             \n\t"
            "sbc  %[s], %[s]       \n\t"
            "sbrs %[n], 4          \n\t"
            "rjmp 1f               \n\t"
            "movw %A[v], %C[v]     \n\t"
            "mov  %C[v], %[s]      \n\t"
            "mov  %D[v], %[s]      \n\t"
            "1: sbrs %[n], 3       \n\t"
            "rjmp 2f               \n\t"
            "mov  %A[v], %B[v]     \n\t"
            "mov  %B[v], %C[v]     \n\t"
            "mov  %C[v], %D[v]     \n\t"
            "mov  %D[v], %[s]      \n\t"
            "2: andi %[n], 7       \n\t"
            "breq 4f               \n\t"
            "3: asr %D[v]          \n\t"
            "ror  %C[v]            \n\t"
            "ror  %B[v]            \n\t"
            "ror  %A[v]            \n\t"
            "dec  %[n]             \n\t"
            "brne 3b               \n\t"
            "4: asr %D[v]          \n\t"
            "ror  %C[v]            \n\t"
            "ror  %B[v]            \n\t"
            "ror  %A[v]            \n\t"
            "adc  %A[v], __zero_reg__ \n\t"
            "adc  %B[v], __zero_reg__ \n\t"
            "adc  %C[v], __zero_reg__ \n\t"
            "adc  %D[v], __zero_reg__ \n\t"
            : [v] "+r"(v), [n] "+d"(n), [s] "=&r"(sign));
    return v;
#else
    uint32_t sign = (v < 0) ? 0xFFFFFFFFu : 0u;
    uint32_t w = ac_shr_u((uint32_t)v ^ sign, (uint8_t)(n - 1u));
    return ac_i_from_u(((w >> 1) ^ sign) + ((w ^ sign) & 1u));
#endif
}

AC_HELPER int32_t ac_sat_add(int32_t a, int32_t b, uint8_t *sat)
{
    if (b > 0 && a > INT32_MAX - b) {
        *sat = 1u;
        return INT32_MAX;
    }
    if (b < 0 && a < INT32_MIN - b) {
        *sat = 1u;
        return INT32_MIN;
    }
    return a + b;
}

AC_HELPER int32_t ac_sat_sub(int32_t a, int32_t b, uint8_t *sat)
{
    if (b < 0 && a > INT32_MAX + b) {
        *sat = 1u;
        return INT32_MAX;
    }
    if (b > 0 && a < INT32_MIN + b) {
        *sat = 1u;
        return INT32_MIN;
    }
    return a - b;
}

AC_HELPER int16_t ac_sat_to16(int32_t v, uint8_t *sat)
{
    if (v > INT16_MAX) {
        *sat = 1u;
        return INT16_MAX;
    }
    if (v < INT16_MIN) {
        *sat = 1u;
        return INT16_MIN;
    }
    return (int16_t)v;
}

/* v * 2^-shift, half up for shift > 0, exact (saturating) for shift <= 0. */
AC_HELPER int32_t ac_scale_round(int32_t v, int16_t shift, uint8_t *sat)
{
    if (shift > 0) {
        if (shift > 31) {
            return 0; /* |v| / 2^shift < 1/2 */
        }
        return ac_round_shift(v, (uint8_t)shift);
    }
    if (shift < 0) {
        uint8_t k;
        if (v == 0) {
            return 0;
        }
        if (shift < -31) {
            *sat = 1u;
            return (v > 0) ? INT32_MAX : INT32_MIN;
        }
        k = (uint8_t)(-shift);
        if (v > (int32_t)ac_shr_u((uint32_t)INT32_MAX, k)) {
            *sat = 1u;
            return INT32_MAX;
        }
        if (v < ac_floor_shift(INT32_MIN, k)) {
            *sat = 1u;
            return INT32_MIN;
        }
        return ac_i_from_u((uint32_t)v << k);
    }
    return v;
}

/* number of significant bits of an unsigned 32-bit value: the top non-zero
 * byte is found first, so at most 8 one-bit steps (on 8 bits) follow. */
AC_HELPER uint8_t ac_bitlen_u(uint32_t u)
{
    uint8_t n, top;
    if ((u >> 16) != 0u) {
        u >>= 16;
        n = 16u;
    } else {
        n = 0u;
    }
    if ((u >> 8) != 0u) {
        top = (uint8_t)(u >> 8);
        n = (uint8_t)(n + 8u);
    } else {
        top = (uint8_t)u;
    }
    while (top != 0u) {
        n++;
        top >>= 1;
    }
    return n;
}

#endif /* AC_OPS_IMPL_H */
