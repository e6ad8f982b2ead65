/*
 * accelcal -- definitions of the internal 64-bit helpers (unsigned 64-bit
 * values as two 32-bit halves, built from 16 x 16 partial products); the
 * same inclusion scheme as ac_ops_impl.h, kept apart so that firmware using
 * only the per-sample path does not link them (their one external copy,
 * for old compilers, is ac_ops64.c).
 */
#ifndef AC_U64_IMPL_H
#define AC_U64_IMPL_H

/* The external copies come in two objects, so that old-compiler firmware links only
 * what it calls: the arithmetic (ac_ops64.c, AC_U64_ARITH_ONLY) and the shifts
 * (ac_ops64_shift.c, AC_U64_SHIFTS_ONLY); inlined, both parts are here. */
#ifndef AC_U64_SHIFTS_ONLY

/* 16 x 16 -> 32 unsigned: the widening multiply every target has. */
AC_HELPER uint32_t ac_mul16u(uint16_t a, uint16_t b)
{
    return (uint32_t)a * (uint32_t)b;
}


/* a * b exactly, four 16 x 16 partial products. */
AC_HELPER ac_u64 ac_mul32u(uint32_t a, uint32_t b)
{
    uint16_t al = (uint16_t)(a & 0xFFFFu), ah = (uint16_t)(a >> 16);
    uint16_t bl = (uint16_t)(b & 0xFFFFu), bh = (uint16_t)(b >> 16);
    uint32_t ll = ac_mul16u(al, bl);
    uint32_t lh = ac_mul16u(al, bh);
    uint32_t hl = ac_mul16u(ah, bl);
    uint32_t hh = ac_mul16u(ah, bh);
    ac_u64 r;
    uint32_t t;
    r.lo = ll;
    r.hi = hh + (lh >> 16) + (hl >> 16);
    t = r.lo + (lh << 16);
    if (t < r.lo) {
        r.hi++;
    }
    r.lo = t;
    t = r.lo + (hl << 16);
    if (t < r.lo) {
        r.hi++;
    }
    r.lo = t;
    return r;
}

AC_HELPER ac_u64 ac_u64_add(ac_u64 a, ac_u64 b)
{
    ac_u64 r;
    r.lo = a.lo + b.lo;
    r.hi = a.hi + b.hi + ((r.lo < a.lo) ? 1u : 0u);
    return r;
}

AC_HELPER ac_u64 ac_u64_sub(ac_u64 a, ac_u64 b) /* requires a >= b */
{
    ac_u64 r;
    r.lo = a.lo - b.lo;
    r.hi = a.hi - b.hi - ((a.lo < b.lo) ? 1u : 0u);
    return r;
}

AC_HELPER int ac_u64_lt(ac_u64 a, ac_u64 b)
{
    return (a.hi < b.hi) || (a.hi == b.hi && a.lo < b.lo);
}

#endif /* !AC_U64_SHIFTS_ONLY */

#ifndef AC_U64_ARITH_ONLY
AC_HELPER ac_u64 ac_u64_shl(ac_u64 a, uint8_t n) /* n <= 63 */
{
    ac_u64 r;
    if (n == 0u) {
        return a;
    }
    if (n >= 32u) {
        r.hi = a.lo << (uint8_t)(n - 32u);
        r.lo = 0u;
    } else {
        r.hi = (a.hi << n) | (a.lo >> (uint8_t)(32u - n));
        r.lo = a.lo << n;
    }
    return r;
}

AC_HELPER ac_u64 ac_u64_shr(ac_u64 a, uint8_t n) /* n <= 63 */
{
    ac_u64 r;
    if (n == 0u) {
        return a;
    }
    if (n >= 32u) {
        r.lo = a.hi >> (uint8_t)(n - 32u);
        r.hi = 0u;
    } else {
        r.lo = (a.lo >> n) | (a.hi << (uint8_t)(32u - n));
        r.hi = a.hi >> n;
    }
    return r;
}

#endif /* !AC_U64_ARITH_ONLY */

#endif /* AC_U64_IMPL_H */
