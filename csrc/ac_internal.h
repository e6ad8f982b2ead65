/*
 * accelcal -- internal helpers shared by the core's modules (not installed).
 *
 * Defined once, in ac_ops.c (old compilers such as h8300-hms-gcc 3.4 would
 * otherwise emit a copy of every helper in every object).  The public
 * ac_fixed.h functions are status-returning wrappers around them.
 * Rules kept here: no "*" on two 32-bit values, no "/" or "%" on 32-bit
 * values (the H8/300H toolchain has no libgcc), no ">>" on negative signed
 * values (implementation-defined), no signed overflow.
 */
#ifndef AC_INTERNAL_H
#define AC_INTERNAL_H

#include "accelcal/ac_config.h"
#include "accelcal/ac_status.h"
#include "accelcal/ac_fixed.h"
#include "accelcal/ac_resolve.h"

/* Unsigned 64-bit value as two halves. */
typedef struct ac_u64 {
    uint32_t hi;
    uint32_t lo;
} ac_u64;

/* Inline the helpers where the compiler does it well; otherwise declare the
 * single external copy that ac_ops.c defines. */
#ifndef AC_INLINE_HELPERS
#if (defined(__GNUC__) && __GNUC__ >= 4) || defined(__clang__)
#define AC_INLINE_HELPERS 1
#else
#define AC_INLINE_HELPERS 0
#endif
#endif

/* Small helpers on the per-sample path are always inlined where the compiler
 * can be told so: avr-gcc otherwise calls them (and spills around the call)
 * once a function uses them twice. */
#if defined(__GNUC__) && __GNUC__ >= 4
#define AC_ALWAYS_INLINE static inline __attribute__((always_inline))
#else
#define AC_ALWAYS_INLINE static inline
#endif

#if AC_INLINE_HELPERS
#define AC_HELPER AC_ALWAYS_INLINE
#include "ac_ops_impl.h"
#include "ac_u64_impl.h"
#else
/* Combine two statuses: the first error wins, otherwise any saturation. */
ac_status ac_merge(ac_status a, ac_status b);

int32_t ac_i_from_u(uint32_t u);

/* |v| as uint32 (exact for INT32_MIN). */
uint32_t ac_abs_u(int32_t v);

/* u >> n for 0 <= n <= 31, in whole-byte and whole-word steps first: 8-bit
 * cores (AVR) have no barrel shifter and shift 32-bit values one bit a loop. */
uint32_t ac_shr_u(uint32_t u, uint8_t n);

/* floor(v / 2^n), 0 <= n <= 31 */
int32_t ac_floor_shift(int32_t v, uint8_t n);


/* round(v / 2^n) half up, 1 <= n <= 31, without overflow. */
int32_t ac_round_shift(int32_t v, uint8_t n);

int32_t ac_sat_add(int32_t a, int32_t b, uint8_t *sat);

int32_t ac_sat_sub(int32_t a, int32_t b, uint8_t *sat);

int16_t ac_sat_to16(int32_t v, uint8_t *sat);

/* v * 2^-shift, half up for shift > 0, exact (saturating) for shift <= 0. */
int32_t ac_scale_round(int32_t v, int16_t shift, uint8_t *sat);

/* ---- ac_ops64.c (ac_u64_impl.h) ---- */

/* 16 x 16 -> 32 unsigned: the widening multiply every target has. */
uint32_t ac_mul16u(uint16_t a, uint16_t b);

/* a * b exactly, four 16 x 16 partial products. */
ac_u64 ac_mul32u(uint32_t a, uint32_t b);

ac_u64 ac_u64_add(ac_u64 a, ac_u64 b);

ac_u64 ac_u64_sub(ac_u64 a, ac_u64 b); /* requires a >= b */

int ac_u64_lt(ac_u64 a, ac_u64 b);

ac_u64 ac_u64_shl(ac_u64 a, uint8_t n); /* n <= 63 */

ac_u64 ac_u64_shr(ac_u64 a, uint8_t n); /* n <= 63 */

/* number of significant bits of an unsigned 32-bit value */
uint8_t ac_bitlen_u(uint32_t u);

#endif /* AC_INLINE_HELPERS */

#if defined(__AVR__) && defined(__AVR_HAVE_MUL__) && !defined(AC_NO_ASM)
/* The Atmel AVR201 signed 16 x 16 multiply-accumulate into a 32-bit
 * register operand [acc], with operands [a], [b] in r16..r23 (muls/mulsu
 * need them there) and a zero register [z]; clobbers r0, r1. */
#define AC_AVR_MAC16                  \
    "muls %B[a], %B[b]      \n\t"     \
    "add  %C[acc], r0       \n\t"     \
    "adc  %D[acc], r1       \n\t"     \
    "mul  %A[a], %A[b]      \n\t"     \
    "add  %A[acc], r0       \n\t"     \
    "adc  %B[acc], r1       \n\t"     \
    "adc  %C[acc], %[z]     \n\t"     \
    "adc  %D[acc], %[z]     \n\t"     \
    "mulsu %B[a], %A[b]     \n\t"     \
    "sbc  %D[acc], %[z]     \n\t"     \
    "add  %B[acc], r0       \n\t"     \
    "adc  %C[acc], r1       \n\t"     \
    "adc  %D[acc], %[z]     \n\t"     \
    "mulsu %B[b], %A[a]     \n\t"     \
    "sbc  %D[acc], %[z]     \n\t"     \
    "add  %B[acc], r0       \n\t"     \
    "adc  %C[acc], r1       \n\t"     \
    "adc  %D[acc], %[z]     \n\t"
#endif

/* acc + a * b (16 x 16 -> 32, wrapping in uint32).  On AVR the multiply-
 * accumulate is the Atmel AVR201 sequence (muls/mulsu/mul into the accumulator),
 * about a third of the cycles of avr-gcc's __mulhisi3 call plus a 32-bit add;
 * elsewhere plain C, which compilers turn into one widening multiply. */
AC_ALWAYS_INLINE uint32_t ac_mac16(uint32_t acc, int16_t a, int16_t b)
{
#if defined(__AVR__) && defined(__AVR_HAVE_MUL__) && !defined(AC_NO_ASM)
    uint8_t zero;
    __asm__("clr  %[z]         \n\t"
            AC_AVR_MAC16
            "clr  r1           \n\t"
            : [acc] "+r"(acc), [z] "=&r"(zero)
            : [a] "a"(a), [b] "a"(b)
            : "r0", "r1");
    return acc;
#else
    return acc + (uint32_t)((int32_t)a * b);
#endif
}

/* acc + sum_{i<n} a[i] b[i] (16 x 16 -> 32 each, wrapping in uint32), n >= 1.
 * On AVR the whole loop is one asm block around the AVR201 multiply-
 * accumulate: operands stream through X and Z with post-increment, nothing
 * is spilled, about 33 cycles an element against ~60 for the C loop that
 * avr-gcc makes of ac_mac16.  Elsewhere plain C. */
AC_ALWAYS_INLINE uint32_t ac_dot16(uint32_t acc, const int16_t *a, const int16_t *b, uint8_t n)
{
#if defined(__AVR__) && defined(__AVR_HAVE_MUL__) && !defined(AC_NO_ASM)
    uint8_t zero;
    int16_t ta, tb; /* the asm operands [a], [b]: the current pair */
    __asm__("clr  %[z]          \n\t"
            "1:                 \n\t"
            "ld   %A[a], X+    \n\t"
            "ld   %B[a], X+    \n\t"
            "ld   %A[b], Z+    \n\t"
            "ld   %B[b], Z+    \n\t"
            AC_AVR_MAC16
            "dec  %[n]          \n\t"
            "brne 1b            \n\t"
            "clr  r1            \n\t"
            : [acc] "+r"(acc), [n] "+r"(n), [z] "=&r"(zero), [a] "=&a"(ta), [b] "=&a"(tb),
              "+x"(a), "+z"(b)
            :
            : "r0", "r1", "memory");
    return acc;
#elif defined(__H8300H__) && !defined(AC_NO_ASM)
    /* H8/300H: operands stream through two address registers with
     * post-increment into a MULXS.W (16 x 16 -> 32 signed) and a 32-bit add,
     * 44 states an element against ~70 for the loop h8300-hms-gcc 3.4 makes of
     * the C (it reloads the array bases from the stack every element).  The
     * same wrapping uint32 sum as the C below (tests: tools/run_h8_tests.sh). */
    int32_t prod; /* low word: b[i]; then the product */
    int16_t ta;
    __asm__("1:                          \n\t"
            "mov.w  @%S[pa]+,%T[ta]      \n\t"
            "mov.w  @%S[pb]+,%T[prod]    \n\t"
            "mulxs.w %T[ta],%S[prod]     \n\t"
            "add.l  %S[prod],%S[acc]     \n\t"
            "dec.b  %s[n]                \n\t"
            "bne    1b                   \n\t"
            : [acc] "+r"(acc), [n] "+r"(n), [pa] "+r"(a), [pb] "+r"(b), [ta] "=&r"(ta),
              [prod] "=&r"(prod)
            :
            : "memory", "cc");
    return acc;
#else
    uint8_t i;
    for (i = 0u; i < n; i++) {
        acc = ac_mac16(acc, a[i], b[i]);
    }
    return acc;
#endif
}

/* ac_dot16 that skips the terms whose a[i] is zero: the centripetal table of
 * a planar layout (the seed's) has whole zero columns, a third of its terms.
 * Elsewhere the plain loop (a branch there costs more than it saves). */
AC_ALWAYS_INLINE uint32_t ac_dot16_sparse(uint32_t acc, const int16_t *a, const int16_t *b,
                                          uint8_t n)
{
#if defined(__AVR__) && defined(__AVR_HAVE_MUL__) && !defined(AC_NO_ASM)
    uint8_t zero;
    int16_t ta, tb; /* the asm operands [a], [b]: the current pair */
    __asm__("clr  %[z]          \n\t"
            "1:                 \n\t"
            "ld   %A[a], X+    \n\t"
            "ld   %B[a], X+    \n\t"
            "mov  r0, %A[a]    \n\t"
            "or   r0, %B[a]    \n\t"
            "brne 2f            \n\t"
            "adiw r30, 2        \n\t"
            "rjmp 3f            \n\t"
            "2:                 \n\t"
            "ld   %A[b], Z+    \n\t"
            "ld   %B[b], Z+    \n\t"
            AC_AVR_MAC16
            "3:                 \n\t"
            "dec  %[n]          \n\t"
            "brne 1b            \n\t"
            "clr  r1            \n\t"
            : [acc] "+r"(acc), [n] "+r"(n), [z] "=&r"(zero), [a] "=&a"(ta), [b] "=&a"(tb),
              "+x"(a), "+z"(b)
            :
            : "r0", "r1", "memory");
    return acc;
#else
    return ac_dot16(acc, a, b, n);
#endif
}

/* ac_resolve_kernel in H8/300H assembly (ac_resolve_h8.c) instead of the C
 * of ac_resolve.c: normal mode (16-bit pointers, the h8300-hms-gcc -mh -mn
 * calling convention) only; -DAC_NO_ASM gives the C on the H8 too. */
#if defined(__H8300H__) && defined(__NORMAL_MODE__) && !defined(__H8300S__) && !defined(AC_NO_ASM)
#define AC_H8_RESOLVE_ASM 1
#else
#define AC_H8_RESOLVE_ASM 0
#endif

#if AC_H8_RESOLVE_ASM
/* ac_trim's loop on the H8/300H: x[i] = raw[i] - trim[i] clipped to int16,
 * n >= 1; returns 1 if any channel clipped.  The 16-bit difference is in
 * int16 iff its borrow (C) equals its sign (N): one branch on each.  34-38
 * states a channel against ~72 for the loop h8300-hms-gcc 3.4 makes of the C
 * (it reloads raw from the stack and indexes every element); ac_process calls
 * it inline, without ac_trim's call and checks.  Same results as the C of
 * ac_trim.c (tests: tools/run_h8_tests.sh). */
AC_ALWAYS_INLINE uint8_t ac_h8_trim(const uint16_t *raw, const uint16_t *trim, uint16_t n,
                                    int16_t *x)
{
    uint32_t cs = n; /* low word: channels left; high word: 1 once one clipped */
    int16_t a, b;
    __asm__("1: mov.w  @%S[raw]+,%T[a]     \n\t"
            "mov.w  @%S[trim]+,%T[b]        \n\t"
            "sub.w  %T[b],%T[a]             \n\t"
            "bcs    3f                      \n\t"
            "bmi    4f                      \n\t"
            "2: mov.w %T[a],@%S[x]          \n\t"
            "adds   #2,%S[x]                \n\t"
            "dec.w  #1,%T[cs]               \n\t"
            "bne    1b                      \n\t"
            "bra    6f                      \n\t"
            "3: bmi 2b                      \n\t"
            "mov.w  #0x8000,%T[a]           \n\t"
            "bra    5f                      \n\t"
            "4: mov.w #0x7fff,%T[a]         \n\t"
            "5: mov.w #1,%e[cs]             \n\t"
            "bra    2b                      \n\t"
            "6:                             \n\t"
            : [raw] "+r"(raw), [trim] "+r"(trim), [x] "+r"(x), [cs] "+r"(cs), [a] "=&r"(a),
              [b] "=&r"(b)
            :
            : "memory", "cc");
    return (uint8_t)(cs >> 16);
}
#endif

/* ac_mul32x16.c: the int32 with sign neg and 64-bit magnitude hi 2^32 + lo,
 * clipped to int32 (then AC_SATURATED); shared with ac_fixed.c's multiply. */
ac_status ac_from_sign_mag(int neg, uint32_t hi, uint32_t lo, int32_t *out);

/* ac_resolve.c: AC_OK if the table's n and shifts are in range (the cheap
 * part of ac_resolver_check, done on every call). */
ac_status ac_resolver_shape(const ac_resolver *r);

/* ac_resolve.c's per-sample arithmetic on trimmed readings, for a table whose
 * shape (n, shifts) has been checked; shared with ac_resolve_batch.c. */
ac_status ac_resolve_kernel(const ac_resolver *r, const int16_t *x, const int16_t *omega,
                            int32_t *out);

#endif /* AC_INTERNAL_H */
