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
 *       shift 17..19: s 17..19 add 2^(s-17) to the high word and shift it s - 16 SHAR.W (19: the
 *       add after two of its shifts, as + 1), the
 *       iterations unrolled as at shift 15 (the channel loop NLU 15, 17, 18, 19; the seed's
 *       coefficients per 2^-2 count are at 17..19, 18 for its 0.5 % square + 0.1 % cube);
 *       shift 16 and 20..30 (the iterations a loop, e3 the count): a jump through e5 (set once a
 *       call) to the shift's block, C = floor((g z + 2^(s-1)) 2^-s) with no edge (g z +
 *       2^(s-1) < 2^31): s 16 adds 0x8000 (er6 twice), s 20..30 shift the high word s - 17
 *       SHAR.W (a loop, s - 16 in the flag word's low byte) and once more, adding the carry
 *       (floor((w + 1) / 2) = floor(w/2) + the carry, w = floor(g z 2^-(s-1)));
 *       for shift >= 15 |C| <= 2^15 and C fits int16 but for g z = 2^30 at shift 15;
 *   z = x0 - C: SUB.W, its V the clip (to 0x7FFF if the wrapped result is negative, else
 *       0x8000, and the flag), out of line.
 * ac_temp_correct: the channel loop twice (the assembler macro TCCH): for a table with frac 0
 * and, with a final round(w 2^-(16-k)) by w + (o 2^8 + 2^(15-k)) (the bias computed once a call,
 * kept in a stack word, the SHAL.L loop's count) and k SHAL.L (V: the clip), for frac
 * 1..8 (issue 35's hand-off in 2^-k counts); the clips are subroutines both share.
 * Addresses: normal mode uses the low 16 bits of a register, so e1..e5 hold data while
 * r4, r5, r6 point (no array reaches 0x10000: a post-increment never carries into them).
 */
#include "ac_internal.h"
#include "ac_terms_impl.h"
#include "accelcal/ac_temp.h"

#if AC_H8_RESOLVE_ASM
#include <stddef.h>

#define AC_H8T_STR(x) #x
#define AC_H8T_XSTR(x) AC_H8T_STR(x)

AC_STATIC_ASSERT(h8t_nl_shift, offsetof(ac_nonlin_table, shift) == 2);
AC_STATIC_ASSERT(h8t_nl_a2, offsetof(ac_nonlin_table, a2) == 4);
AC_STATIC_ASSERT(h8t_nl_a3, offsetof(ac_nonlin_table, a3) == 4 + 2 * AC_MAX_CHANNELS);
AC_STATIC_ASSERT(h8t_nl_it, AC_NONLIN_ITERATIONS >= 1 && AC_NONLIN_ITERATIONS <= 32767);
AC_STATIC_ASSERT(h8t_nl_k, offsetof(ac_nonlin_table, iterations) == 4 + 4 * AC_MAX_CHANNELS);

AC_STATIC_ASSERT(h8t_st, AC_OK == 0 && AC_SATURATED == 1);

__asm__(
    "\t.equ\tNL_MAXCH, " AC_H8T_XSTR(AC_MAX_CHANNELS) "\n"
    "\t.equ\tNL_A3D, 2*NL_MAXCH-2\n"
    "\t.equ\tNL_KOFF, 4+4*NL_MAXCH\n"
    "\t.equ\tNL_IT, " AC_H8T_XSTR(AC_NONLIN_ITERATIONS) "\n"
    /* one iteration at the shift S, unrolled (z r1, x0 e1, a2 r2, a3 e2, 0x4000 in er6); \e, \c the
     * out-of-line stubs of the product 2^30 (shift 15 only) and of the clip, \n the label after it.
     * C = round(g z 2^-S): S 15 by SHAL.L (its V the product 2^30); S 16..19 as the loop's blocks
     * below (|g z| <= 2^30: no edge): + 0x8000 (er6 twice) and the high word at 16, + 2^(S-17) to
     * the high word and S - 16 SHAR.W at 17..19 (at 19 as two SHAR.W, + 1, one SHAR.W: floor((floor(v/4)
 * + 1) / 2) = floor((v + 4) / 8), INC.W where ADD.W #4 is a longer instruction) */
    "\t.macro\tNLA S, e, c, n\n"
    "\tmov.w\te2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\ter6,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tadd.w\tr2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\ter6,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\t.if\t\\S == 15\n"
    "\tadd.l\ter6,er0\n"
    "\tshal.l\ter0\n"
    "\tbvs\t\\e\n"
    "\t.elseif\t\\S == 16\n"
    "\tadd.l\ter6,er0\n"
    "\tadd.l\ter6,er0\n"
    "\t.elseif\t\\S == 17\n"
    "\tinc.w\t#1,e0\n"
    "\tshar.w\te0\n"
    "\t.elseif\t\\S == 18\n"
    "\tinc.w\t#2,e0\n"
    "\tshar.w\te0\n"
    "\tshar.w\te0\n"
    "\t.elseif\t\\S == 19\n"
    "\tshar.w\te0\n"
    "\tshar.w\te0\n"
    "\tinc.w\t#1,e0\n"
    "\tshar.w\te0\n"
    "\t.else\n"
    "\t.error\t\"NLA: shift 15..19 only\"\n"
    "\t.endif\n"
    "\tmov.w\te1,r1\n"
    "\tsub.w\te0,r1\n"
    "\tbvs\t\\c\n"
    "\\n:\n"
    "\t.endm\n"
    /* the stubs of one NLA */
    "\t.macro\tNLAS S, e, c, n\n"
    "\t.if\t\\S == 15\n"
    "\\e:\tbsr\t.Lnl_a_edge:16\n"
    "\tbra\t\\n\n"
    "\t.endif\n"
    "\\c:\tbsr\t.Lnl_clip:16\n"
    "\tbra\t\\n\n"
    "\t.endm\n"
    /* the channel loop at the shift S with the iterations unrolled (entered at .Lnl_ch<S>) */
    "\t.macro\tNLU S\n"
    "\tNLAS\t\\S, .Lnl_e1_\\S, .Lnl_c1_\\S, .Lnl_n1_\\S\n"
    "\tNLAS\t\\S, .Lnl_e2_\\S, .Lnl_c2_\\S, .Lnl_n2_\\S\n"
    ".Lnl_ch\\S:\n"
    "\tmov.w\t@er5+,e1\n"
    "\tmov.w\te1,r1\n"
    "\tmov.w\t@er4+,r2\n"
    "\tmov.w\t@(NL_A3D,er4),e2\n"
    "\t.if\tNL_IT == 3\n"
    "\tNLA\t\\S, .Lnl_e1_\\S, .Lnl_c1_\\S, .Lnl_n1_\\S\n"
    "\tNLA\t\\S, .Lnl_e2_\\S, .Lnl_c2_\\S, .Lnl_n2_\\S\n"
    "\tNLA\t\\S, .Lnl_e3_\\S, .Lnl_c3_\\S, .Lnl_n3_\\S\n"
    "\t.else\n"
    "\tmov.w\t#NL_IT,e3\n"
    ".Lnl_it\\S:\n"
    "\tNLA\t\\S, .Lnl_e3_\\S, .Lnl_c3_\\S, .Lnl_n3_\\S\n"
    "\tdec.w\t#1,e3\n"
    "\tbne\t.Lnl_it\\S:16\n"
    "\t.endif\n"
    "\tmov.w\tr1,@er3\n"
    "\tadds\t#2,er3\n"
    "\tdec.w\t#1,e4\n"
    "\tbne\t.Lnl_ch\\S:16\n"
    "\tbra\t.Lnl_done:16\n"
    "\tNLAS\t\\S, .Lnl_e3_\\S, .Lnl_c3_\\S, .Lnl_n3_\\S\n"
    "\t.endm\n"
    "\t.section .text\n"
    "\t.align 1\n"
    /* ---- shift 15 and the unrolled shifts (ac_h8_nonlin: a symbol for the profiles) */
    "ac_h8_nonlin:\n"
    "\tNLU\t15\n"
    "\tNLU\t18\n"
    "\tNLU\t17\n"
    "\tNLU\t19\n"
    /* g z = 2^30 at shift 15 (a subroutine): C = 2^15.  z = -32768 there, and z reaches -32768 only
     * as x0 or as a clip below, both with x0 < 0: z = x0 - 2^15 clips to -32768, flagged */
    ".Lnl_a_edge:\n"
    "\tmov.w\t#0x8000,r1\n"
    "\tbra\t2f\n"
    /* z = x0 - C overflowed (V, a subroutine): 0x7FFF if the wrapped result is negative, else
     * 0x8000; the flag (bit 0 of the byte at the caller's @er7) */
    ".Lnl_clip:\n"
    "\tbmi\t1f\n"
    "\tmov.w\t#0x8000,r1\n"
    "\tbra\t2f\n"
    "1:\tmov.w\t#0x7fff,r1\n"
    "2:\tmov.w\t@(2,er7),r0\n"
    "\tor.w\t#0x100,r0\n"
    "\tmov.w\tr0,@(2,er7)\n"
    "\trts\n"
    /* ---- shift 16..30 (a loop over the iterations) */
    ".Lnl_b_ch:\n"
    "\tmov.w\t@er5+,e1\n"
    "\tmov.w\te1,r1\n"
    "\tmov.w\t@er4+,r2\n"
    "\tmov.w\t@(NL_A3D,er4),e2\n"
    "\tmov.w\t#NL_IT,e3\n"
    ".Lnl_b_it:\n"
    "\tmov.w\te2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\ter6,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tadd.w\tr2,r0\n"
    "\tmulxs.w\tr1,er0\n"
    "\tadd.l\ter6,er0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r0\n"
    "\tmulxs.w\tr1,er0\n"
    /* C = floor((g z + 2^(s-1)) 2^-s) (|g z| <= 2^30: no overflow, no edge): a jump (e5) to the
     * block of the shift s (16, or 20..30 falling through; 17..19 run unrolled, NLU) */
    "\tmov.w\te5,r1\n"
    "\tjmp\t@er1\n"
    /* s 16: + 0x8000 (er6 twice), the high word */
    ".Lnl_k16:\n"
    "\tadd.l\ter6,er0\n"
    "\tadd.l\ter6,er0\n"
    "\tbra\t.Lnl_b_v\n"
    /* s 20..30: floor(g z 2^-(s-1)) by s - 17 SHAR.W of the high word (s - 16 in the flag word's
     * low byte), one more whose carry is added */
    ".Lnl_kg:\n"
    "\tmov.b\t@(1,er7),r1l\n"
    "\tdec.b\tr1l\n"
    "1:\tshar.w\te0\n"
    "\tdec.b\tr1l\n"
    "\tbne\t1b\n"
    "\tshar.w\te0\n"
    "\tbcc\t.Lnl_b_v\n"
    "\tinc.w\t#1,e0\n"
    ".Lnl_b_v:\n"
    "\tmov.w\te1,r1\n"
    "\tsub.w\te0,r1\n"
    "\tbvs\t.Lnl_b_clip\n"
    ".Lnl_b_next:\n"
    "\tdec.w\t#1,e3\n"
    "\tbne\t.Lnl_b_it\n"
    "\tmov.w\tr1,@er3\n"
    "\tadds\t#2,er3\n"
    "\tdec.w\t#1,e4\n"
    "\tbne\t.Lnl_b_ch\n"
    /* the exit: the status (0 or 1) from the flag word */
    ".Lnl_done:\n"
    "\tmov.w\t@er7+,r0\n"
    "\tmov.b\tr0h,r0l\n"
    "\tsub.b\tr0h,r0h\n"
    "\tmov.l\t@er7+,er6\n"
    "\tmov.l\t@er7+,er5\n"
    "\tmov.l\t@er7+,er4\n"
    "\trts\n"
    ".Lnl_b_clip:\n"
    "\tbsr\t.Lnl_clip:16\n"
    "\tbra\t.Lnl_b_next\n"
    ".Lnl_c:\n"
    "\tjmp\t@_ac_nonlin_invert_c\n"
    /* ---- ac_nonlin_invert: r0 = t, r1 = x, r2 = y; the C for NULL, a bad n, a table's iteration
     * count other than 0 or AC_NONLIN_ITERATIONS, a shift below 15 or above 30 (the C's checks and
     * error codes) */
    "\t.global\t_ac_nonlin_invert\n"
    "_ac_nonlin_invert:\n"
    "\tmov.w\tr1,r1\n"
    "\tbeq\t.Lnl_c\n"
    "\tmov.w\tr2,r2\n"
    "\tbeq\t.Lnl_c\n"
    "\tmov.w\tr0,r0\n"
    "\tbeq\t.Lnl_c\n"
    "\tmov.w\t@er0,r3\n"
    "\tbeq\t.Lnl_c\n"
    "\tcmp.w\t#NL_MAXCH,r3\n"
    "\tbhi\t.Lnl_c\n"
    "\tmov.w\tr3,e3\n"
    "\tmov.b\t@(NL_KOFF:16,er0),r3l\n"
    "\tbeq\t3f\n"
    "\tcmp.b\t#NL_IT,r3l\n"
    "\tbne\t.Lnl_c\n"
    "3:\tmov.b\t@(2,er0),r3l\n"
    "\tcmp.b\t#15,r3l\n"
    "\tblt\t.Lnl_c\n"
    "\tcmp.b\t#30,r3l\n"
    "\tbgt\t.Lnl_c\n"
    "\tmov.l\ter4,@-er7\n"
    "\tmov.l\ter5,@-er7\n"
    "\tmov.l\ter6,@-er7\n"
    "\tmov.w\te3,e4\n"
    "\textu.w\tr3\n"
    "\tadd.w\t#-16,r3\n"
    "\tmov.w\tr3,e5\n"
    "\tmov.w\tr2,r3\n"
    "\tmov.w\tr1,r5\n"
    "\tmov.w\tr0,r4\n"
    "\tadds\t#4,er4\n"
    "\tmov.l\t#0x4000,er6\n"
    /* the flag word: 0 in its high byte, shift - 16 in its low byte (.Lnl_kg's count); e5 the
     * block of the shift at 16..30 */
    "\tmov.w\te5,r0\n"
    "\tbmi\t4f\n"
    "\tmov.w\tr0,@-er7\n"
    "\tcmp.b\t#18-16,r0l\n"
    "\tbeq\t.Lnl_ch18:16\n"
    "\tcmp.b\t#17-16,r0l\n"
    "\tbeq\t.Lnl_ch17:16\n"
    "\tcmp.b\t#19-16,r0l\n"
    "\tbeq\t.Lnl_ch19:16\n"
    "\tmov.w\t#.Lnl_k16,r1\n"
    "\tcmp.b\t#0,r0l\n"
    "\tbeq\t5f\n"
    "\tmov.w\t#.Lnl_kg,r1\n"
    "5:\tmov.w\tr1,e5\n"
    "\tbra\t.Lnl_b_ch:16\n"
    "4:\tsub.w\tr0,r0\n"
    "\tmov.w\tr0,@-er7\n"
    "\tbra\t.Lnl_ch15:16\n");

/* the structure offsets and limits the temperature kernels use */
AC_STATIC_ASSERT(h8t_tl_y, offsetof(ac_temp_lag, y) == 0);
AC_STATIC_ASSERT(h8t_tl_k, offsetof(ac_temp_lag, k) == 4);
AC_STATIC_ASSERT(h8t_tl_sh, offsetof(ac_temp_lag, shift) == 6);
AC_STATIC_ASSERT(h8t_tl_st, offsetof(ac_temp_lag, started) == 7);
AC_STATIC_ASSERT(h8t_tc_ref, offsetof(ac_temp_table, t_ref) == 2);
AC_STATIC_ASSERT(h8t_tc_oc, offsetof(ac_temp_table, oc) == 4);
AC_STATIC_ASSERT(h8t_tc_gc, offsetof(ac_temp_table, gc) == 4 + 2 * AC_MAX_CHANNELS);
AC_STATIC_ASSERT(h8t_tc_o, offsetof(ac_temp_table, o) == 4 + 4 * AC_MAX_CHANNELS);
AC_STATIC_ASSERT(h8t_tc_fr, offsetof(ac_temp_table, frac) == 4 + 6 * AC_MAX_CHANNELS);
AC_STATIC_ASSERT(h8t_tc_e, AC_TEMP_E_MAX == 28672 && AC_TEMP_LAG_EXTRA == 16);

__asm__(
    "\t.equ\tTC_MAXCH, " AC_H8T_XSTR(AC_MAX_CHANNELS) "\n"
    "\t.equ\tTC_OD, 4*TC_MAXCH\n"
    "\t.equ\tTC_GD, 2*TC_MAXCH-2\n"
    "\t.equ\tTC_FR, 4+6*TC_MAXCH\n"
    "\t.equ\tTC_E32, 28672*8192+4095\n"
    "\t.section .text\n"
    "\t.align 1\n"
    /* the channel loop of ac_temp_correct, once for whole counts (K 0: y = round(w 2^-16)) and once
     * for a table with frac k = 1..8 (K 1: y = round(w 2^-(16-k)): w + 2^(15-k), then k SHAL.L whose V
     * is the clip, the high word; the bias in a word below the flag word at @er7, set once a
     * call, and the loop's count: shifted left with w, it turns negative after k).  The clips are
     * subroutines both share (BVC over a BSR: the same states as the BVS they replace when nothing
     * clips; the flag is then 2 bytes up, above the return address) */
    "\t.macro\tTCCH S, K\n"
    ".Ltc_pro\\S:\n"
    "\tmov.l\ter4,@-er7\n"
    "\tmov.l\ter5,@-er7\n"
    "\tmov.l\ter6,@-er7\n"
    "\tmov.w\tr3,e6\n"
    "\t.if\t\\K\n"
    /* the bias 2^(15-k), once a call, in a word below the flag word */
    "\tmov.b\t@(TC_FR,er0),r3l\n"
    "\tmov.w\t#0x8000,e3\n"
    "1:\n"
    "\tshlr.w\te3\n"
    "\tdec.b\tr3l\n"
    "\tbne\t1b\n"
    "\tmov.w\te3,@-er7\n"
    "\t.else\n"
    "\tsub.w\tr3,r3\n"
    "\t.endif\n"
    "\tmov.w\tr3,@-er7\n"
    "\tmov.w\t@(2,er0),r3\n"
    "\tsub.w\tr3,r1\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_dto:16\n"
    "1:\n"
    "\tmov.w\tr1,e4\n"
    "\tsub.w\tr3,r2\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_dtg:16\n"
    "1:\n"
    "\tmov.w\tr2,e5\n"
    "\tmov.w\t@(18+2*\\K,er7),r5\n"
    "\tmov.w\t@(22+2*\\K,er7),r6\n"
    "\tmov.w\tr0,r4\n"
    "\tadds\t#4,er4\n"
    ".Ltc_ch\\S:\n"
    /* o 2^8 in er2 */
    "\tmov.w\t@(TC_OD,er4),r2\n"
    "\tmov.w\tr2,r0\n"
    "\tmov.b\tr0h,r0l\n"
    "\texts.w\tr0\n"
    "\tmov.w\tr0,e2\n"
    "\tmov.b\tr2l,r2h\n"
    "\tsub.b\tr2l,r2l\n"
    /* w = x 2^16 - (o 2^8 + oc dTo) in er1 */
    "\tmov.w\t@er4+,r0\n"
    "\tmulxs.w\te4,er0\n"
    "\tadd.l\ter2,er0\n"
    "\tmov.w\t@er5+,e1\n"
    "\tsub.w\tr1,r1\n"
    "\tsub.l\ter0,er1\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_clip1:16\n"
    "1:\n"
    /* e = round(gc dTg 2^-13) in r3, clipped */
    "\tmov.w\t@(TC_GD,er4),r0\n"
    "\tmulxs.w\te5,er0\n"
    /* t = gc dTg + E32 in 0..2 E32 (unsigned) iff no clip; then e = floor((t + 1) 2^-13) - 28672 */
    "\tadd.l\t#TC_E32,er0\n"
    "\tcmp.l\t#2*TC_E32,er0\n"
    "\tbls\t1f\n"
    "\tbsr\t.Ltc_eclip:16\n"
    "\tbra\t2f\n"
    "1:\n"
    "\tadds\t#1,er0\n"
    "\tshll.l\ter0\n"
    "\tshll.l\ter0\n"
    "\tshll.l\ter0\n"
    "\tmov.w\te0,r3\n"
    "\tadd.w\t#-28672,r3\n"
    "2:\n"
    /* e2 = round(e e 2^-19) in e3, e3 = round(e2 e 2^-19) in r0, r = e2 - e - e3 in e3 */
    "\tmov.w\tr3,r0\n"
    "\tmulxs.w\tr3,er0\n"
    "\tmov.w\te0,r0\n"
    "\tadds\t#4,er0\n"
    "\tshar.w\tr0\n"
    "\tshar.w\tr0\n"
    "\tshar.w\tr0\n"
    "\tmov.w\tr0,e3\n"
    "\tmulxs.w\tr3,er0\n"
    "\tmov.w\te0,r0\n"
    "\tadds\t#4,er0\n"
    "\tshar.w\tr0\n"
    "\tshar.w\tr0\n"
    "\tshar.w\tr0\n"
    "\tsub.w\tr3,e3\n"
    "\tsub.w\tr0,e3\n"
    /* w16 = round(w 2^-16) (0x7FFF, flagged, for w >= 0x7FFF8000) */
    "\tmov.l\ter1,er0\n"
    "\tadd.l\t#0x8000,er0\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_w16:16\n"
    "1:\n"
    "\tmov.w\te0,r0\n"
    /* w += round(w16 r 2^-3); w += o 2^8; y = round(w 2^-(16 - k)) */
    "\tmulxs.w\te3,er0\n"
    "\tadds\t#4,er0\n"
    "\tshar.l\ter0\n"
    "\tshar.l\ter0\n"
    "\tshar.l\ter0\n"
    "\tadd.l\ter0,er1\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_clip1:16\n"
    "1:\n"
    "\t.if\t\\K\n"
    /* w + (o 2^8 + 2^(15-k)): one sum, one V test (the bias from its word, then the loop's count:
     * shifted left once a SHAL.L, it reaches 0x8000, negative, after k).  The C saturates
     * w + o 2^8 first; the fused sum gives the same y and flag: y clips wherever w + o 2^8 or
     * the sum is within 2^15 of int32's ends (|y| >= 2^(31-k) 2^-(16-k) = 2^15 there), and the
     * sum's V (the wrapped sign gives the direction) or the first SHAL.L's V (a sum below
     * -2^30 or at or above 2^30) catches each such case; not so at frac 0, where w + o 2^8 just
     * below INT32_MIN rounds to -32768 (the VTS vectors).  The clips out of line, after the rts */
    "\tmov.w\t@(2,er7),r0\n"
    "\textu.l\ter0\n"
    "\tadd.l\ter0,er2\n"
    "\tadd.l\ter2,er1\n"
    "\tbvs\t3f\n"
    "2:\n"
    "\tshal.l\ter1\n"
    "\tbvs\t3f\n"
    "\tshll.w\tr0\n"
    "\tbpl\t2b\n"
    "4:\n"
    "\t.else\n"
    "\tadd.l\ter2,er1\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_clip1:16\n"
    "1:\n"
    "\tadd.l\t#0x8000,er1\n"
    "\tbvc\t1f\n"
    "\tbsr\t.Ltc_y:16\n"
    "1:\n"
    "\t.endif\n"
    "\tmov.w\te1,@er6\n"
    "\tadds\t#2,er6\n"
    "\tdec.w\t#1,e6\n"
    "\tbne\t.Ltc_ch\\S:16\n"
    "\tmov.w\t@er7+,r0\n"
    "\t.if\t\\K\n"
    "\tadds\t#2,er7\n"
    "\t.endif\n"
    "\tmov.b\tr0h,r0l\n"
    "\tsub.b\tr0h,r0h\n"
    "\tmov.l\t@er7+,er6\n"
    "\tmov.l\t@er7+,er5\n"
    "\tmov.l\t@er7+,er4\n"
    "\trts\n"
    "\t.if\t\\K\n"
    /* w + 2^(15-k) or a SHAL.L overflowed (V): the result's sign is the true one's inverted
     * (the bias is positive: an overflowing sum is negative, e1 = 0x7FFF, as the clip of w) */
    "3:\n"
    "\tbsr\t.Ltc_vclip:16\n"
    "\tbra\t4b\n"
    "\t.endif\n"
    "\t.endm\n"
    "ac_h8_temp:\n"
    /* the clips, as subroutines: the flag word is at @(2,er7) (above the return address) */
    /* er1 overflowed (V): the true result's direction is the wrapped sign inverted */
    ".Ltc_clip1:\n"
    "\tbmi\t1f\n"
    "\tmov.l\t#0x80000000,er1\n"
    "\tbra\t.Ltc_flag\n"
    "1:\tmov.l\t#0x7fffffff,er1\n"
    "\tbra\t.Ltc_flag\n"
    /* y's rounding overflowed (w >= 0x7FFF8000): e1 = 0x7FFF */
    ".Ltc_y:\n"
    "\tmov.w\t#0x7fff,e1\n"
    "\tbra\t.Ltc_flag\n"
    /* k SHAL.L overflowed: e1 = 0x7FFF if the result is negative (it was positive), else 0x8000 */
    ".Ltc_vclip:\n"
    "\tbmi\t1f\n"
    "\tmov.w\t#0x8000,e1\n"
    "\tbra\t.Ltc_flag\n"
    "1:\tmov.w\t#0x7fff,e1\n"
    "\tbra\t.Ltc_flag\n"
    /* w16 = 0x7FFF (w >= 0x7FFF8000): in e0 (moved to r0 after the return) */
    ".Ltc_w16:\n"
    "\tmov.w\t#0x7fff,e0\n"
    "\tbra\t.Ltc_flag3\n"
    /* t > 2 E32: gc dTg > E32 (t < 2^31) or < -E32 (t negative): e = +-28672 in r3 */
    ".Ltc_eclip:\n"
    "\tmov.w\t#28672,r3\n"
    "\tmov.l\ter0,er0\n"
    "\tbpl\t.Ltc_flag\n"
    "\tmov.w\t#-28672,r3\n"
    "\tbra\t.Ltc_flag\n"
    /* dTo, dTg beyond int16 (V of the subtraction): the clip in r1, r2 */
    ".Ltc_dto:\n"
    "\tbmi\t1f\n"
    "\tmov.w\t#0x8000,r1\n"
    "\tbra\t.Ltc_flage\n"
    "1:\tmov.w\t#0x7fff,r1\n"
    "\tbra\t.Ltc_flage\n"
    ".Ltc_dtg:\n"
    "\tbmi\t1f\n"
    "\tmov.w\t#0x8000,r2\n"
    "\tbra\t.Ltc_flage\n"
    "1:\tmov.w\t#0x7fff,r2\n"
    /* the flag through e0 (r0 holds the table pointer in the prologue) */
    ".Ltc_flage:\n"
    "\tmov.w\t@(2,er7),e0\n"
    "\tor.w\t#0x100,e0\n"
    "\tmov.w\te0,@(2,er7)\n"
    "\trts\n"
    /* the flag (bit 0 of the flag word's high byte), through r0 or, where e0 is live, r3 */
    ".Ltc_flag:\n"
    "\tmov.w\t@(2,er7),r0\n"
    "\tor.w\t#0x100,r0\n"
    "\tmov.w\tr0,@(2,er7)\n"
    "\trts\n"
    ".Ltc_flag3:\n"
    "\tmov.w\t@(2,er7),r3\n"
    "\tor.w\t#0x100,r3\n"
    "\tmov.w\tr3,@(2,er7)\n"
    "\trts\n"
    /* a table with frac k > 0: k <= 8 (else the C, which refuses it), n in range */
    ".Ltc_k:\n"
    "\tcmp.b\t#8,r3l\n"
    "\tbhi\t.Ltc_c\n"
    "\tmov.w\t@er0,r3\n"
    "\tbeq\t.Ltc_c\n"
    "\tcmp.w\t#TC_MAXCH,r3\n"
    "\tbhi\t.Ltc_c\n"
    "\tbra\t.Ltc_pro1:16\n"
    ".Ltc_c:\n"
    "\tjmp\t@_ac_temp_correct_c\n"
    /* ---- ac_temp_correct: r0 = t, r1 = t_off, r2 = t_gain, x @(4,sp), y @(8,sp) */
    "\t.global\t_ac_temp_correct\n"
    "_ac_temp_correct:\n"
    "\tmov.w\t@(4,er7),r3\n"
    "\tbeq\t.Ltc_c\n"
    "\tmov.w\t@(8,er7),r3\n"
    "\tbeq\t.Ltc_c\n"
    "\tmov.w\tr0,r0\n"
    "\tbeq\t.Ltc_c\n"
    "\tmov.b\t@(TC_FR,er0),r3l\n"
    "\tbne\t.Ltc_k\n"
    "\tmov.w\t@er0,r3\n"
    "\tbeq\t.Ltc_c\n"
    "\tcmp.w\t#TC_MAXCH,r3\n"
    "\tbhi\t.Ltc_c\n"
    "\tTCCH\t0, 0\n"
    "\tTCCH\t1, 1\n"
    /* ---- ac_temp_lag_step: r0 = f, r1 = temp, r2 = lagged; the C for a first step, a shift
     * below 17 or above 47, a difference |d| >= 2^30, NULL */
    /* the C for what the assembly does not take; temp is rebuilt from d + y (er1 held y) */
    ".Ltl_cp:\n"
    "\tmov.l\t@er0,er1\n"
    "\tadd.l\ter3,er1\n"
    "\tmov.w\te1,r1\n"
    ".Ltl_c:\n"
    "\tjmp\t@_ac_temp_lag_step_c\n"
    /* ---- ac_temp_lag_step: r0 = f, r1 = temp, r2 = lagged; the C for NULL, a first step, a
     * shift below 17 or above 47, a difference that clips or has |d| >= 2^30.  No register saved:
     * shift - 17 in e0, y then a in er1, d in er3, k in e2 (then the flag) */
    "\t.global\t_ac_temp_lag_step\n"
    "_ac_temp_lag_step:\n"
    "\tmov.w\tr0,r0\n"
    "\tbeq\t.Ltl_c\n"
    "\tmov.w\tr2,r2\n"
    "\tbeq\t.Ltl_c\n"
    "\tmov.w\t@(6,er0),r3\n"
    "\tmov.b\tr3l,r3l\n"
    "\tbeq\t.Ltl_c\n"
    "\tcmp.b\t#17,r3h\n"
    "\tblo\t.Ltl_c\n"
    "\tcmp.b\t#47,r3h\n"
    "\tbhi\t.Ltl_c\n"
    "\tmov.b\tr3h,r3l\n"
    "\textu.w\tr3\n"
    "\tadd.w\t#-17,r3\n"
    "\tmov.w\tr3,e0\n"
    "\tmov.w\tr1,e3\n"
    "\tsub.w\tr3,r3\n"
    "\tmov.l\t@er0,er1\n"
    "\tsub.l\ter1,er3\n"
    "\tbvs\t.Ltl_cp\n"
    /* |d| < 2^30: dh = d's high word in -2^14..2^14-1 (dh + 2^14 not negative), and not
     * d = -2^30 (dh = -2^14 with dl = 0, out of line) */
    "\tmov.w\te3,r1\n"
    "\tadd.w\t#0x4000,r1\n"
    "\tbmi\t.Ltl_cp\n"
    "\tbeq\t.Ltl_lo\n"
    ".Ltl_in:\n"
    /* a = sign(dh) |dh| k + floor(dl k 2^-16) in er1, d = dh 2^16 + dl in er3 */
    "\tmov.w\t@(4,er0),e2\n"
    "\tmov.w\te3,r1\n"
    "\tbpl\t1f\n"
    "\tneg.w\tr1\n"
    "1:\tmulxu.w\te2,er1\n"
    "\tmov.w\te3,e3\n"
    "\tbpl\t2f\n"
    "\tneg.l\ter1\n"
    "2:\tmulxu.w\te2,er3\n"
    "\tmov.w\te3,r3\n"
    "\textu.l\ter3\n"
    "\tadd.l\ter3,er1\n"
    /* inc = round(a 2^-(shift - 16)): shift - 17 arithmetic shifts (16 of them a word move, the
     * rest a jump into a chain), then one whose carry is added */
    "\tmov.w\te0,r3\n"
    "\tcmp.b\t#16,r3l\n"
    "\tblo\t3f\n"
    "\tmov.w\te1,r1\n"
    "\texts.l\ter1\n"
    "\tadd.b\t#-16,r3l\n"
    "3:\tshll.b\tr3l\n"
    "\tmov.w\tr3,e3\n"
    "\tmov.w\t#.Ltl_end,r3\n"
    "\tsub.w\te3,r3\n"
    "\tjmp\t@er3\n"
    "\t.rept\t15\n"
    "\tshar.l\ter1\n"
    "\t.endr\n"
    ".Ltl_end:\n"
    "\tshar.l\ter1\n"
    "\tbcc\t4f\n"
    "\tadds\t#1,er1\n"
    "4:\tsub.w\te2,e2\n"
    "\tmov.l\t@er0,er3\n"
    "\tadd.l\ter1,er3\n"
    "\tbvs\t.Ltl_sat\n"
    ".Ltl_st:\n"
    "\tmov.l\ter3,@er0\n"
    "\tadd.l\t#0x8000,er3\n"
    "\tbvs\t.Ltl_max\n"
    "\tmov.w\te3,@er2\n"
    ".Ltl_ret:\n"
    "\tmov.w\te2,r0\n"
    "\trts\n"
    ".Ltl_max:\n"
    "\tmov.w\t#0x7fff,r1\n"
    "\tmov.w\tr1,@er2\n"
    "\tbra\t.Ltl_ret\n"
    ".Ltl_lo:\n"
    "\tmov.w\tr3,r3\n"
    "\tbne\t.Ltl_in\n"
    "\tbra\t.Ltl_cp:16\n"
    ".Ltl_sat:\n"
    "\tbmi\t1f\n"
    "\tmov.l\t#0x80000000,er3\n"
    "\tbra\t2f\n"
    "1:\tmov.l\t#0x7fffffff,er3\n"
    "2:\tmov.w\t#1,e2\n"
    "\tbra\t.Ltl_st\n");

#else
/* ISO C forbids an empty translation unit */
typedef int ac_terms_h8_unused;
#endif /* AC_H8_RESOLVE_ASM */
