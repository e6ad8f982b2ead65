/*
 * accelcal -- the correctable terms' per-sample kernels for the H8/300H in normal mode, in
 * assembly (selected by AC_H8_RESOLVE_ASM, ac_internal.h: __H8300H__ with __NORMAL_MODE__ and
 * no AC_NO_ASM, as ac_resolve_h8.c; the C of ac_nonlin.c is the reference and the code on every
 * other target and for the shifts the kernel does not take).  Same results bit for bit, status
 * and saturation flag included (tools/run_h8_tests.sh: tests/c/vectors.c at -Os and -O2
 * against the host).
 *
 * Why assembly: h8300-hms-gcc 3.4 keeps the nonlinearity's iteration state on the stack and
 * shifts the rounding one bit a loop pass: ac_nonlin_invert took 6,212 states (-Os) for six
 * channels and three iterations, 4.1x its 54 multiplies x 28 states (tools/bench_h8.py).
 *
 * ac_h8_nonlin (r0 = t, r1 = x, r2 = y; returns 1 in r0 if a z_k clipped, else 0): the
 * iterations of ac_nonlin.h for a table with 15 <= shift <= 30 (the C wrapper checks n,
 * shift and the pointers and calls it only then).  Per channel x0 in e1, z in r1, a2 in r2,
 * a3 in e2; the iteration count in r3l (r3h its start), shift - 16 in e3, the channel count
 * in e4, the flag in e5; a2 through er4 (post-increment, a3 at a fixed distance), x through
 * er5, y through r6.  One iteration:
 *   h = a2 + round(a3 z 2^-15):  MULXS.W, ADD.L #0x4000, SHLL.L: the high word is
 *       floor((a3 z + 2^14) 2^-15) mod 2^16, which is the C's (int16_t)AC_R15 (|a3 z| <= 2^30);
 *   g = round(h z 2^-15) the same way;
 *   C = round(g z 2^-shift): shift 15: the same with SHAL.L, whose V flags the one product
 *       that leaves the high word (g = z = -32768: g z = 2^30, C = 2^15, out of line);
 *       shift 16..30: floor(g z 2^-15) (SHAL.L, the same case out of line: C = 2^(30 -
 *       shift)) then shift - 16 SHAR.W and one more whose carry is added
 *       (floor((w + 2^(m-1)) 2^-m) = floor((floor(w 2^-(m-1)) + 1) / 2), m = shift - 15);
 *       for shift >= 15 |C| <= 2^15 and C fits int16 but for that one case;
 *   z = x0 - C: SUB.W, its V the clip (to 0x7FFF if the wrapped result is negative, else
 *       0x8000, and the flag), out of line.
 * Addresses: normal mode uses the low 16 bits of a register, so e1..e5 hold data while
 * r4, r5, r6 point (no array reaches 0x10000: a post-increment never carries into them).
 */
#include "ac_internal.h"
#include "ac_terms_impl.h"

#if AC_H8_RESOLVE_ASM
#include <stddef.h>

#define AC_H8T_STR(x) #x
#define AC_H8T_XSTR(x) AC_H8T_STR(x)

AC_STATIC_ASSERT(h8t_nl_shift, offsetof(ac_nonlin_table, shift) == 2);
AC_STATIC_ASSERT(h8t_nl_a2, offsetof(ac_nonlin_table, a2) == 4);
AC_STATIC_ASSERT(h8t_nl_a3, offsetof(ac_nonlin_table, a3) == 4 + 2 * AC_MAX_CHANNELS);
AC_STATIC_ASSERT(h8t_nl_it, AC_NONLIN_ITERATIONS >= 1 && AC_NONLIN_ITERATIONS <= 255);

__asm__(
    "\t.equ\tNL_A3D, 2*" AC_H8T_XSTR(AC_MAX_CHANNELS) "-2\n"
    "\t.equ\tNL_IT, " AC_H8T_XSTR(AC_NONLIN_ITERATIONS) "\n"
    "\t.section .text\n"
    "\t.align 1\n"
    "\t.global\t_ac_h8_nonlin\n"
    "_ac_h8_nonlin:\n"
    "\tmov.l\ter4,@-er7\n"
    "\tmov.l\ter5,@-er7\n"
    "\tmov.l\ter6,@-er7\n"
    "\tmov.w\tr1,r5\n"
    "\tmov.w\tr2,r6\n"
    "\tmov.w\t@er0,e4\n"
    "\tsub.w\te5,e5\n"
    "\tmov.b\t#NL_IT,r3h\n"
    "\tmov.w\tr0,r4\n"
    "\tadds\t#4,er4\n"
    "\tmov.b\t@(2,er0),r0l\n"
    "\textu.w\tr0\n"
    "\tadd.w\t#-16,r0\n"
    "\tmov.w\tr0,e3\n"
    "\tbpl\t.Lnl_b_ch:16\n"
    /* ---- shift 15 */
    ".Lnl_a_ch:\n"
    "\tmov.w\t@er5+,e1\n"
    "\tmov.w\te1,r1\n"
    "\tmov.w\t@er4+,r2\n"
    "\tmov.w\t@(NL_A3D,er4),e2\n"
    "\tmov.b\tr3h,r3l\n"
    ".Lnl_a_it:\n"
    "\tmov.w\te2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\t#0x4000,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tadd.w\tr2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\t#0x4000,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\t#0x4000,er0\n"
    "\tshal.l\ter0\n"
    "\tbvs\t.Lnl_a_edge\n"
    "\tmov.w\te1,r1\n"
    "\tsub.w\te0,r1\n"
    "\tbvs\t.Lnl_a_clip\n"
    ".Lnl_a_next:\n"
    "\tdec.b\tr3l\n"
    "\tbne\t.Lnl_a_it\n"
    "\tmov.w\tr1,@er6\n"
    "\tadds\t#2,er6\n"
    "\tdec.w\t#1,e4\n"
    "\tbne\t.Lnl_a_ch\n"
    "\tbra\t.Lnl_done:16\n"
    /* g z = 2^30: C = 2^15, z = x0 - 2^15 (clipped for x0 < 0) */
    ".Lnl_a_edge:\n"
    "\tmov.w\te1,r1\n"
    "\tbmi\t1f\n"
    "\tadd.w\t#0x8000,r1\n"
    "\tbra\t.Lnl_a_next\n"
    "1:\tmov.w\t#0x8000,r1\n"
    "\tmov.w\t#1,e5\n"
    "\tbra\t.Lnl_a_next\n"
    ".Lnl_a_clip:\n"
    "\tbmi\t1f\n"
    "\tmov.w\t#0x8000,r1\n"
    "\tmov.w\t#1,e5\n"
    "\tbra\t.Lnl_a_next\n"
    "1:\tmov.w\t#0x7fff,r1\n"
    "\tmov.w\t#1,e5\n"
    "\tbra\t.Lnl_a_next\n"
    /* ---- shift 16..30 */
    ".Lnl_b_ch:\n"
    "\tmov.w\t@er5+,e1\n"
    "\tmov.w\te1,r1\n"
    "\tmov.w\t@er4+,r2\n"
    "\tmov.w\t@(NL_A3D,er4),e2\n"
    "\tmov.b\tr3h,r3l\n"
    ".Lnl_b_it:\n"
    "\tmov.w\te2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\t#0x4000,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tadd.w\tr2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\t#0x4000,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tshal.l\ter0\n"
    "\tbvs\t.Lnl_b_edge\n"
    "\tmov.w\te0,r0\n"
    "\tmov.w\te3,e0\n"
    "\tbeq\t2f\n"
    "1:\tshar.w\tr0\n"
    "\tdec.w\t#1,e0\n"
    "\tbne\t1b\n"
    "2:\tshar.w\tr0\n"
    "\tbcc\t.Lnl_b_v\n"
    "\tinc.w\t#1,r0\n"
    ".Lnl_b_v:\n"
    "\tmov.w\te1,r1\n"
    "\tsub.w\tr0,r1\n"
    "\tbvs\t.Lnl_b_clip\n"
    ".Lnl_b_next:\n"
    "\tdec.b\tr3l\n"
    "\tbne\t.Lnl_b_it\n"
    "\tmov.w\tr1,@er6\n"
    "\tadds\t#2,er6\n"
    "\tdec.w\t#1,e4\n"
    "\tbne\t.Lnl_b_ch\n"
    "\tbra\t.Lnl_done\n"
    /* g z = 2^30: C = 2^(30 - shift) = 2^14 >> (shift - 16) */
    ".Lnl_b_edge:\n"
    "\tmov.w\t#0x4000,r0\n"
    "\tmov.w\te3,e0\n"
    "\tbeq\t.Lnl_b_v\n"
    "1:\tshlr.w\tr0\n"
    "\tdec.w\t#1,e0\n"
    "\tbne\t1b\n"
    "\tbra\t.Lnl_b_v\n"
    ".Lnl_b_clip:\n"
    "\tbmi\t1f\n"
    "\tmov.w\t#0x8000,r1\n"
    "\tmov.w\t#1,e5\n"
    "\tbra\t.Lnl_b_next\n"
    "1:\tmov.w\t#0x7fff,r1\n"
    "\tmov.w\t#1,e5\n"
    "\tbra\t.Lnl_b_next\n"
    ".Lnl_done:\n"
    "\tmov.w\te5,r0\n"
    "\tmov.l\t@er7+,er6\n"
    "\tmov.l\t@er7+,er5\n"
    "\tmov.l\t@er7+,er4\n"
    "\trts\n");

#else
/* ISO C forbids an empty translation unit */
typedef int ac_terms_h8_unused;
#endif /* AC_H8_RESOLVE_ASM */
