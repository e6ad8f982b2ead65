/*
 * accelcal -- ac_process and ac_resolve_kernel for the H8/300H in normal mode,
 * in assembly (selected by AC_H8_RESOLVE_ASM, ac_internal.h: __H8300H__ with
 * __NORMAL_MODE__ and no AC_NO_ASM; the C in ac_resolve.c is the reference and
 * the code on every other target).  Same results bit for bit, status,
 * saturation flag and untouched out on an error included
 * (tools/run_h8_tests.sh: tests/c/vectors.c at -Os and -O2 against the host).
 *
 * Why assembly: h8300-hms-gcc 3.4 made the C kernel call the rounding helpers
 * (4,509 states a sample) and spill the row state: ac_process with omega took
 * 12,280 states (-O2), 5.6x its multiply floor of 2,184.  With the kernel alone
 * in assembly it took 4,819 (2.21x), 716 of them in the C ac_process and
 * ac_resolver_shape around it and the kernel's own entry; with ac_process here
 * too it takes 4,308 at -Os and -O2 (1.97x; tools/bench_h8.py, profile in
 * build/h8bench/, by section: the labels ac_h8_pass1, ac_h8_omega, ac_h8_pass2).
 *
 * ac_process (r0 = r, r1 = trim, r2 = raw, omega @(4,sp), out @(8,sp)): the
 * C's checks in the C's order, before anything is written: trim, raw, out or r
 * NULL -> AC_ERR_NULL; n outside 6..AC_MAX_CHANNELS -> AC_ERR_SIZE; a shift
 * outside -31..31 -> AC_ERR_FORMAT.  The 12 shift checks are branch-free: for
 * each byte s, s + 31 then + 0xC1 carries iff s + 31 (mod 256) >= 63, and
 * ROTXL.W gathers the carries into e5 above n - 6 (e5 = 0 iff n = 6 and every
 * shift is valid; 132 states against 262 + the call for ac_resolver_shape).
 * n = 6: the pre-trim (x = raw - trim clipped to int16: in range iff the
 * borrow equals the sign; the clips out of line) goes straight into the x
 * registers of pass 1, and the kernel's frame is the only one.  n > 6: the
 * pre-trim into a stack buffer and a call of ac_resolve_kernel.
 * The rails (ac_trim_rails): each raw reading is compared with raw_min (e1) and
 * raw_max (e6) as it is loaded, two CMP.W and two Bcc, 12 states a channel; a
 * reading at a rail branches out of line, where raw_min >= raw_max (rails
 * unknown) flags nothing.
 * Status: AC_SATURATED if the pre-trim or the kernel clipped, AC_AT_RAIL if a
 * reading sits at a rail, both bits for both, as the C.  n = 6 keeps the rail
 * bit in the flag word's high byte (the kernel writes 1 into its low byte),
 * and the exit ORs the two bytes.
 *
 * ac_resolve_kernel (r0 = r, r1 = x, r2 = omega, out @(4,sp)): the C calling
 * convention of h8300-hms-gcc -mh -mn; status (AC_OK / AC_SATURATED) in r0;
 * er4-er6 saved, er0-er3 clobbered.  Needs a table that passed
 * ac_resolver_shape (6 <= n <= AC_MAX_CHANNELS, shifts in -31..31).
 * Frame (both entries, n = 6 in ac_process): er4-er6 (12 bytes), then 8 bytes
 * of locals: @(0) the flags (a word: the low byte the saturation flag, 0 or 1;
 * the high byte 2 for a reading at a rail, n = 6 only; their OR is the status), @(2)
 * omega, @(4) r, @(6) out; 2 more in the cold paths.  ac_process with omega
 * uses 28 bytes of stack with its return address (n > 6: a 2 AC_MAX_CHANNELS
 * buffer and the kernel's frame more).
 *
 * Scaling (as ac_resolve.h): x Q15 counts, m and k in 2^-m_shift output LSB,
 * out Q21.10.  Three passes:
 *  1. out[j] = sat(sum_i m[j][i] x[i] - k[j]).  n = 6: x0..x5 in e4 r4 e5 r5
 *     e2 e3, the row through r2 by displacement (m[j][0] via @er2), k through
 *     er6 (post-increment), out through r3, the row count in e6; acc er0,
 *     product er1.  Each term MOV.W + MULXS.W + ADD.L, 32 states (floor 28).
 *     n > 6: x from memory (base e4, through r4), the column count in e3.
 *     The sum wraps in uint32 like the C's (a checked table cannot overflow:
 *     row L1 <= 65535).
 *  2. omega: the squares and cross products (MULXS.W) in er0..er5, the block
 *     exponent s = max(0, bitlen(max w_a^2) - 14) (a 16-entry nibble table),
 *     p_q = round(sq_q 2^-s) half up: a byte move per register for 8 bits,
 *     then SHAR.L of all six a bit, the last bit's carry added; p0..p5 in
 *     e2 e3 e4 e5 r4 r5 (|p| <= 2^14).
 *  3. per row: t = sum_q g[j][q] p_q (g through er2+, 32 states a term);
 *     t = scale_round(t, g_shift - m_shift + 2 AC_OMEGA_FRAC - s): e6 holds
 *     2 AC_OMEGA_FRAC - s - 1 in its low byte and the row count in its high
 *     byte, er6 points at m_shift[j]; the shift less one, in -60..81, is in
 *     range iff it is below 31 unsigned; then out[j] = scale_round(sat(out[j]
 *     - t), m_shift[j]).  With omega = NULL: only the final rounding (a local
 *     subroutine).
 *
 * Rounding shifts (v in er0/er1, count n in 1..31): n >= 17 starts with a
 * word move (MOV.W e,r; EXTS.L); the rest is a jump into a chain of 16
 * SHAR.L (2 states a bit): n - 1 arithmetic shifts, then one more whose
 * carry is added (round half up = floor(v 2^-(n-1)) + 1 >> 1, no overflow).
 * Overflow behaviour as the C: a sum or difference that leaves int32 (V set)
 * clips to INT32_MAX / INT32_MIN in the true result's direction (the wrapped
 * result's sign inverted) and sets the flag; a left shift (negative shift)
 * that overflows (SHAL.L sets V) clips by the operand's sign; a shift > 31
 * gives 0; a centripetal term that clips alone gives out[j] = INT32_MIN if
 * t > 0 else INT32_MAX, flagged, without the final rounding.
 * Addresses: normal mode uses the low 16 bits of a register, so e2, e3 and e6
 * hold data while r2, r3 and r6 point (no array reaches 0x10000, so a
 * post-increment never carries into them while they are live); no load goes
 * into the upper half of its own address register.
 */
#include "ac_internal.h"

#if AC_H8_RESOLVE_ASM
#include <stddef.h>

#define AC_H8_STR(x) #x
#define AC_H8_XSTR(x) AC_H8_STR(x)

/* the structure offsets the assembly uses */
AC_STATIC_ASSERT(h8_off_ms, offsetof(ac_resolver, m_shift) == 2);
AC_STATIC_ASSERT(h8_off_gs, offsetof(ac_resolver, g_shift) == 8);
AC_STATIC_ASSERT(h8_off_k, offsetof(ac_resolver, k) == 16);
AC_STATIC_ASSERT(h8_off_m, offsetof(ac_resolver, m) == 40);
AC_STATIC_ASSERT(h8_off_g, offsetof(ac_resolver, g) == 40 + 12 * AC_MAX_CHANNELS);
AC_STATIC_ASSERT(h8_off_rlo, offsetof(ac_resolver, raw_min) == 40 + 12 * AC_MAX_CHANNELS + 72);
AC_STATIC_ASSERT(h8_off_rhi, offsetof(ac_resolver, raw_max) == 40 + 12 * AC_MAX_CHANNELS + 74);
AC_STATIC_ASSERT(h8_ptr16, sizeof(const int16_t *) == 2);
/* the per-row shift g_shift - m_shift + 2 AC_OMEGA_FRAC - s must fit a signed byte */
AC_STATIC_ASSERT(h8_omega_frac, AC_OMEGA_FRAC >= 0 && AC_OMEGA_FRAC <= 32);
/* the status codes the assembly returns (the saturation flag word is the status) */
AC_STATIC_ASSERT(h8_st_ok, AC_OK == 0 && AC_SATURATED == 1 && AC_AT_RAIL == 2);
AC_STATIC_ASSERT(h8_st_err, AC_ERR_NULL == -1 && AC_ERR_SIZE == -2 && AC_ERR_FORMAT == -6);

__asm__(
    "\t.equ\tOFF_MS, 2\n"
    "\t.equ\tOFF_K, 16\n"
    "\t.equ\tOFF_M, 40\n"
    "\t.equ\tMAXCH, " AC_H8_XSTR(AC_MAX_CHANNELS) "\n"
    "\t.equ\tMSTRIDE, 2*MAXCH\n"
    "\t.equ\tOFF_G, OFF_M+6*MSTRIDE\n"
    "\t.equ\tOFF_RLO, OFF_G+72\n"
    "\t.equ\tOFF_RHI, OFF_G+74\n"
    "\t.equ\tW2F, 2*" AC_H8_XSTR(AC_OMEGA_FRAC) "\n"
    "\t.equ\tSATB, 1\n"
    "\t.equ\tOMEGA, 2\n"
    "\t.equ\tRPTR, 4\n"
    "\t.equ\tOUTL, 6\n"
    "\t.section .text\n"
    "\t.align 1\n"
    /* error returns of ac_process (er4-er6 saved) */
    "ac_h8_process_err:\n"
    ".Lpr_null:\n"
    "\tmov.w\t#0xffff,r0\n"
    "\tbra\t.Lpr_ret\n"
    ".Lpr_size:\n"
    "\tmov.w\t#0xfffe,r0\n"
    "\tbra\t.Lpr_ret\n"
    ".Lpr_fmt:\n"
    "\tmov.w\t#0xfffa,r0\n"
    ".Lpr_ret:\n"
    "\tmov.l\t@er7+,er6\n"
    "\tmov.l\t@er7+,er5\n"
    "\tmov.l\t@er7+,er4\n"
    "\trts\n"
    /* ---- ac_process: r0 = r, r1 = trim, r2 = raw, omega @(4,sp), out @(8,sp) */
    "\t.global\t_ac_process\n"
    "_ac_process:\n"
    "\tmov.l\ter4,@-er7\n"
    "\tmov.l\ter5,@-er7\n"
    "\tmov.l\ter6,@-er7\n"
    "\tmov.w\tr1,r1\n"
    "\tbeq\t.Lpr_null\n"
    "\tmov.w\tr2,r2\n"
    "\tbeq\t.Lpr_null\n"
    "\tmov.w\t@(20,er7),r3\n"
    "\tbeq\t.Lpr_null\n"
    "\tmov.w\tr0,r0\n"
    "\tbeq\t.Lpr_null\n"
    /* the table's shape (as ac_resolver_shape): n in 6..AC_MAX_CHANNELS, then the */
    /* 12 shifts: s + 31 (mod 256) >= 63 sets the carry of the add of 0xC1, rotated */
    /* into e5 above n - 6 (so e5 = 0 iff n = 6 and every shift is in -31..31; n - 6 must */
    /* fit 4 bits, so with AC_MAX_CHANNELS > 21 it is made 1 first) */
    "\tmov.w\t@er0,e5\n"
    "\tadd.w\t#-6,e5\n"
    "\tcmp.w\t#MAXCH-6,e5\n"
    "\tbhi\t.Lpr_size\n"
    "\t.if\tMAXCH > 21\n"
    "\tbeq\t1f\n"
    "\tmov.w\t#1,e5\n"
    "1:\n"
    "\t.endif\n"
    "\t.irp\toff,2,4,6,8,10,12\n"
    "\tmov.w\t@(\\off,er0),r4\n"
    "\tadd.b\t#31,r4h\n"
    "\tadd.b\t#0xc1,r4h\n"
    "\trotxl.w\te5\n"
    "\tadd.b\t#31,r4l\n"
    "\tadd.b\t#0xc1,r4l\n"
    "\trotxl.w\te5\n"
    "\t.endr\n"
    /* the rails (raw_min in e1, raw_max in e6) for both pre-trims; e0 the flags: 1 a clip, */
    /* 0x200 a rail (the flag word's high byte, merged into the status at the exit) */
    "\tsub.w\te0,e0\n"
    "\tmov.w\t@(OFF_RLO,er0),e1\n"
    "\tmov.w\t@(OFF_RHI,er0),e6\n"
    "\tmov.w\te5,e5\n"
    "\tbeq\t.Lpr_trim\n"
    "\tmov.w\te5,r4\n"
    "\tand.w\t#0xfff,r4\n"
    "\tbne\t.Lpr_fmt:16\n"
    "\tbra\t.Lpr_gen:16\n"
    /* clipped pre-trim differences (out of line; e0 = 1) */
    "\t.irp\tx,e4,r4,e5,r5,e2,e3\n"
    ".Lpt_b_\\x:\n"
    "\tbmi\t.Lpt_ok_\\x\n"
    "\tmov.w\t#0x8000,\\x\n"
    "\tbra\t.Lpt_s_\\x\n"
    ".Lpt_h_\\x:\n"
    "\tmov.w\t#0x7fff,\\x\n"
    ".Lpt_s_\\x:\n"
    "\tor.w\t#1,e0\n"
    "\tbra\t.Lpt_ok_\\x\n"
    "\t.endr\n"
    /* n = 6: the pre-trim into x0..x5 = e4 r4 e5 r5 e2 e3 (raw through r6, trim through r1) */
    ".Lpr_trim:\n"
    "\tmov.w\tr2,r6\n"
    "\t.irp\tx,e4,r4,e5,r5,e2,e3\n"
    "\tmov.w\t@er6+,\\x\n"
    "\tcmp.w\te1,\\x\n"
    "\tbls\t.Lpt_r_\\x\n"
    "\tcmp.w\te6,\\x\n"
    "\tbhs\t.Lpt_r_\\x\n"
    ".Lpt_c_\\x:\n"
    "\tmov.w\t@er1+,r2\n"
    "\tsub.w\tr2,\\x\n"
    "\tbcs\t.Lpt_b_\\x\n"
    "\tbmi\t.Lpt_h_\\x\n"
    ".Lpt_ok_\\x:\n"
    "\t.endr\n"
    "\tbra\t.Lpt_done\n"
    /* a reading at a rail (raw <= raw_min or >= raw_max, out of line): flagged unless the */
    /* rails are unknown (raw_min >= raw_max) */
    "\t.irp\tx,e4,r4,e5,r5,e2,e3\n"
    ".Lpt_r_\\x:\n"
    "\tcmp.w\te6,e1\n"
    "\tbhs\t.Lpt_c_\\x\n"
    "\tor.w\t#0x200,e0\n"
    "\tbra\t.Lpt_c_\\x\n"
    "\t.endr\n"
    ".Lpt_done:\n"
    /* the locals: @(0) the saturation flag (a word, 0 or 1: the status), @(2) omega, @(4) r, @(6) out */
    "\tmov.w\tr3,@-er7\n"
    "\tmov.w\tr0,@-er7\n"
    "\tmov.w\t@(20,er7),r6\n"
    "\tmov.w\tr6,@-er7\n"
    "\tmov.w\te0,@-er7\n"
    /* ---- pass 1, n = 6: r0 = r, r3 = out, x in registers */
    "ac_h8_pass1:\n"
    ".Lrk_p1_init:\n"
    "\tmov.w\tr0,r6\n"
    "\tadd.w\t#OFF_K,r6\n"
    "\tmov.w\tr0,r2\n"
    "\tadd.w\t#OFF_M,r2\n"
    "\tmov.w\t#6,e6\n"
    ".Lrk_p1_row:\n"
    "\tmov.w\t@er2,r0\n"
    "\tmulxs.w\te4,er0\n"
    "\tmov.w\t@(2,er2),r1\n"
    "\tmulxs.w\tr4,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@(4,er2),r1\n"
    "\tmulxs.w\te5,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@(6,er2),r1\n"
    "\tmulxs.w\tr5,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@(8,er2),r1\n"
    "\tmulxs.w\te2,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@(10,er2),r1\n"
    "\tmulxs.w\te3,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.l\t@er6+,er1\n"
    "\tsub.l\ter1,er0\n"
    "\tbvc\t.Lrk_p1_st\n"
    "\tbsr\t.Lrk_sat_er0:16\n"
    ".Lrk_p1_st:\n"
    "\tmov.l\ter0,@er3\n"
    "\tadds\t#4,er3\n"
    "\tadd.w\t#MSTRIDE,r2\n"
    "\tdec.w\t#1,e6\n"
    "\tbne\t.Lrk_p1_row\n"
    "ac_h8_omega:\n"
    ".Lrk_p1_done:\n"
    "\tmov.w\t@(OMEGA,er7),r2\n"
    "\tbeq\t.Lrk_f0:16\n"
    /* ---- omega: p = the six products rounded to 14 bits with one exponent s */
    "\tmov.w\t@er2,r3\n"
    "\tmov.w\t@(2,er2),r4\n"
    "\tmov.w\t@(4,er2),r5\n"
    "\tmov.w\tr3,r0\n"
    "\tmulxs.w\tr3,er0\n"
    "\tmov.w\tr4,r1\n"
    "\tmulxs.w\tr4,er1\n"
    "\tmov.w\tr5,r2\n"
    "\tmulxs.w\tr5,er2\n"
    "\tmov.l\ter0,er6\n"
    "\tcmp.l\ter1,er6\n"
    "\tbhs\t1f\n"
    "\tmov.l\ter1,er6\n"
    "1:\tcmp.l\ter2,er6\n"
    "\tbhs\t1f\n"
    "\tmov.l\ter2,er6\n"
    /* s = max(0, bitlen(er6) - 14), er6 <= 2^30 */
    "1:\tmov.w\te6,e6\n"
    "\tbne\t2f\n"
    "\tsub.w\te6,e6\n"
    "\tbtst\t#7,r6h\n"
    "\tbne\t3f\n"
    "\tbtst\t#6,r6h\n"
    "\tbeq\t5f\n"
    "\tinc.w\t#1,e6\n"
    "\tbra\t5f\n"
    "3:\tmov.w\t#2,e6\n"
    "\tbra\t5f\n"
    "2:\tmov.w\te6,r6\n"
    "\tmov.w\t#2,e6\n"
    "\tmov.b\tr6h,r6h\n"
    "\tbeq\t1f\n"
    "\tmov.b\tr6h,r6l\n"
    "\tadd.w\t#8,e6\n"
    "1:\tcmp.b\t#16,r6l\n"
    "\tblo\t1f\n"
    "\tshlr.b\tr6l\n"
    "\tshlr.b\tr6l\n"
    "\tshlr.b\tr6l\n"
    "\tshlr.b\tr6l\n"
    "\tadd.w\t#4,e6\n"
    "1:\textu.w\tr6\n"
    "\tmov.b\t@(.Lrk_bl4,er6),r6l\n"
    "\textu.w\tr6\n"
    "\tadd.w\tr6,e6\n"
    /* e6 = s (0..17); the cross products */
    "5:\tmov.w\tr3,r6\n"
    "\tmulxs.w\tr4,er3\n"
    "\tmulxs.w\tr5,er4\n"
    "\tmulxs.w\tr6,er5\n"
    "\tmov.w\te6,r6\n"
    "\tbeq\t7f:16\n"
    "\tdec.b\tr6l\n"
    "\tbeq\t6f\n"
    "\tcmp.b\t#8,r6l\n"
    "\tblo\t1f\n"
    /* eight bits at once: a byte move each (r6 the temporary) */
    "\t.irp\tn,0,1,2,3,4,5\n"
    "\tmov.b\tr\\n\\()h,r\\n\\()l\n"
    "\tmov.w\te\\n,r6\n"
    "\tmov.b\tr6l,r\\n\\()h\n"
    "\tmov.b\tr6h,r6l\n"
    "\texts.w\tr6\n"
    "\tmov.w\tr6,e\\n\n"
    "\t.endr\n"
    "\tmov.w\te6,r6\n"
    "\tadd.b\t#-9,r6l\n"
    "\tbeq\t6f\n"
    "1:\tshar.l\ter0\n"
    "\tshar.l\ter1\n"
    "\tshar.l\ter2\n"
    "\tshar.l\ter3\n"
    "\tshar.l\ter4\n"
    "\tshar.l\ter5\n"
    "\tdec.b\tr6l\n"
    "\tbne\t1b\n"
    "6:\tshar.l\ter0\n"
    "\tbcc\t1f\n"
    "\tadds\t#1,er0\n"
    "1:\tshar.l\ter1\n"
    "\tbcc\t1f\n"
    "\tadds\t#1,er1\n"
    "1:\tshar.l\ter2\n"
    "\tbcc\t1f\n"
    "\tadds\t#1,er2\n"
    "1:\tshar.l\ter3\n"
    "\tbcc\t1f\n"
    "\tadds\t#1,er3\n"
    "1:\tshar.l\ter4\n"
    "\tbcc\t1f\n"
    "\tadds\t#1,er4\n"
    "1:\tshar.l\ter5\n"
    "\tbcc\t7f\n"
    "\tadds\t#1,er5\n"
    /* p0..p5 -> e2 e3 e4 e5 r4 r5; e6 = 0xFA00 + W2F - s - 1 (the row count in its */
    /* high byte, the shift of t less one in its low byte before g_shift - m_shift) */
    "7:\tmov.w\tr2,e4\n"
    "\tmov.w\tr3,e5\n"
    "\tmov.w\tr0,e2\n"
    "\tmov.w\tr1,e3\n"
    "\tneg.w\te6\n"
    "\tadd.w\t#0xFA00+W2F-1,e6\n"
    "\tmov.w\t@(RPTR,er7),r6\n"
    "\tmov.w\tr6,r2\n"
    "\tadd.w\t#OFF_G,r2\n"
    "\tadds\t#OFF_MS,er6\n"
    "\tmov.w\t@(OUTL,er7),r3\n"
    /* ---- pass 2: t = g . p, aligned (scale_round by g_shift - m_shift + W2F - s), */
    /* out = round((acc - t) 2^-m_shift) */
    "ac_h8_pass2:\n"
    ".Lrk_a_row:\n"
    "\tmov.w\t@er2+,r0\n"
    "\tmulxs.w\te2,er0\n"
    "\tmov.w\t@er2+,r1\n"
    "\tmulxs.w\te3,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@er2+,r1\n"
    "\tmulxs.w\te4,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@er2+,r1\n"
    "\tmulxs.w\te5,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@er2+,r1\n"
    "\tmulxs.w\tr4,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\t@er2+,r1\n"
    "\tmulxs.w\tr5,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tmov.w\te6,r1\n"
    "\tmov.b\t@(6,er6),r1h\n"
    "\tadd.b\tr1h,r1l\n"
    "\tmov.b\t@er6,r1h\n"
    "\tsub.b\tr1h,r1l\n"
    "\tcmp.b\t#31,r1l\n"
    "\tbhs\t.Lrk_a_cold\n"
    "\tcmp.b\t#16,r1l\n"
    "\tblo\t1f\n"
    "\tmov.w\te0,r0\n"
    "\texts.l\ter0\n"
    "\tadd.b\t#-16,r1l\n"
    "1:\textu.w\tr1\n"
    "\tadd.w\tr1,r1\n"
    "\tneg.w\tr1\n"
    "\tadd.w\t#.Lrk_a_end-2,r1\n"
    "\tjmp\t@er1\n"
    /* t's shift outside 1..31 (r1l = the shift - 1; the shift is in -59..82) */
    ".Lrk_a_cold:\n"
    "\tinc.b\tr1l\n"
    "\tbeq\t.Lrk_a_t\n"
    "\tbpl\t.Lrk_a_zero\n"
    "\tmov.l\ter0,er0\n"
    "\tbeq\t.Lrk_a_t\n"
    "\tneg.b\tr1l\n"
    "\tcmp.b\t#31,r1l\n"
    "\tbhi\t.Lrk_a_tsat_sign:16\n"
    "1:\tshal.l\ter0\n"
    "\tbvs\t.Lrk_a_tsat_flip:16\n"
    "\tdec.b\tr1l\n"
    "\tbne\t1b\n"
    "\tbra\t.Lrk_a_t\n"
    ".Lrk_a_zero:\n"
    "\tsub.l\ter0,er0\n"
    "\tbra\t.Lrk_a_t\n"
    "\t.rept\t16\n"
    "\tshar.l\ter0\n"
    "\t.endr\n"
    ".Lrk_a_end:\n"
    "\tbcc\t.Lrk_a_t\n"
    "\tadds\t#1,er0\n"
    ".Lrk_a_t:\n"
    "\tmov.l\t@er3,er1\n"
    "\tsub.l\ter0,er1\n"
    "\tbvs\t.Lrk_a_sat\n"
    ".Lrk_a_r:\n"
    "\tmov.b\t@er6,r0l\n"
    "\tble\t.Lrk_a_rcold\n"
    "\tcmp.b\t#17,r0l\n"
    "\tblo\t1f\n"
    "\tmov.w\te1,r1\n"
    "\texts.l\ter1\n"
    "\tadd.b\t#-16,r0l\n"
    "1:\textu.w\tr0\n"
    "\tadd.w\tr0,r0\n"
    "\tneg.w\tr0\n"
    "\tadd.w\t#.Lrk_a_rend,r0\n"
    "\tjmp\t@er0\n"
    "\t.rept\t16\n"
    "\tshar.l\ter1\n"
    "\t.endr\n"
    ".Lrk_a_rend:\n"
    "\tbcc\t.Lrk_a_st\n"
    "\tadds\t#1,er1\n"
    ".Lrk_a_st:\n"
    "\tmov.l\ter1,@er3\n"
    "\tadds\t#4,er3\n"
    "\tadds\t#1,er6\n"
    "\tadd.w\t#0x100,e6\n"
    "\tbcc\t.Lrk_a_row:16\n"
    ".Lrk_exit:\n"
    "\tmov.w\t@er7+,r0\n"
    "\tor.b\tr0h,r0l\n"
    "\textu.w\tr0\n"
    "\tadd.w\t#6,r7\n"
    "\tmov.l\t@er7+,er6\n"
    "\tmov.l\t@er7+,er5\n"
    "\tmov.l\t@er7+,er4\n"
    "\trts\n"
    "ac_h8_cold:\n"
    ".Lrk_a_sat:\n"
    "\tmov.l\ter1,er0\n"
    "\tbsr\t.Lrk_sat_er0:16\n"
    "\tmov.l\ter0,er1\n"
    "\tbra\t.Lrk_a_r\n"
    ".Lrk_a_rcold:\n"
    "\tbsr\t.Lrk_final_cold:16\n"
    "\tbra\t.Lrk_a_st\n"
    ".Lrk_a_tsat_sign:\n"
    "\tmov.l\ter0,er0\n"
    "\tbpl\t.Lrk_a_tmin\n"
    "\tbra\t.Lrk_a_tmax\n"
    /* N = the opposite of t's sign */
    ".Lrk_a_tsat_flip:\n"
    "\tbmi\t.Lrk_a_tmin\n"
    ".Lrk_a_tmax:\n"
    "\tmov.l\t#0x7fffffff,er1\n"
    "\tbra\t1f\n"
    ".Lrk_a_tmin:\n"
    "\tmov.l\t#0x80000000,er1\n"
    "1:\tmov.b\t#1,r0l\n"
    "\tmov.b\tr0l,@(SATB,er7)\n"
    "\tbra\t.Lrk_a_st\n"
    /* ---- no omega: out = round(acc 2^-m_shift) */
    "ac_h8_no_omega:\n"
    ".Lrk_f0:\n"
    "\tmov.w\t@(RPTR,er7),r6\n"
    "\tadds\t#OFF_MS,er6\n"
    "\tmov.w\t@(OUTL,er7),r3\n"
    "\tmov.b\t#6,r5l\n"
    ".Lrk_f0_row:\n"
    "\tmov.l\t@er3,er1\n"
    "\tmov.b\t@er6+,r0l\n"
    "\tbsr\t.Lrk_final\n"
    "\tmov.l\ter1,@er3\n"
    "\tadds\t#4,er3\n"
    "\tdec.b\tr5l\n"
    "\tbne\t.Lrk_f0_row\n"
    "\tbra\t.Lrk_exit\n"
    /* er1 = scale_round(er1, r0l) for -31 <= r0l <= 31; clobbers er0 */
    ".Lrk_final:\n"
    "\tmov.b\tr0l,r0l\n"
    "\tble\t.Lrk_final_cold\n"
    "\tcmp.b\t#17,r0l\n"
    "\tblo\t2f\n"
    "\tmov.w\te1,r1\n"
    "\texts.l\ter1\n"
    "\tadd.b\t#-16,r0l\n"
    "2:\textu.w\tr0\n"
    "\tadd.w\tr0,r0\n"
    "\tneg.w\tr0\n"
    "\tadd.w\t#.Lrk_f_end,r0\n"
    "\tjmp\t@er0\n"
    "\t.rept\t16\n"
    "\tshar.l\ter1\n"
    "\t.endr\n"
    ".Lrk_f_end:\n"
    "\tbcc\t3f\n"
    "\tadds\t#1,er1\n"
    "3:\trts\n"
    /* shift r0l in -31..0, flags set from it */
    ".Lrk_final_cold:\n"
    "\tbeq\t3b\n"
    "\tneg.b\tr0l\n"
    "\tmov.l\ter1,er1\n"
    "\tbeq\t3b\n"
    "1:\tshal.l\ter1\n"
    "\tbvs\t2f\n"
    "\tdec.b\tr0l\n"
    "\tbne\t1b\n"
    "\trts\n"
    "2:\tbmi\t1f\n"
    "\tmov.l\t#0x80000000,er1\n"
    "\tbra\t2f\n"
    "1:\tmov.l\t#0x7fffffff,er1\n"
    "2:\tmov.b\t#1,r0l\n"
    "\tmov.b\tr0l,@(SATB+2,er7)\n"
    "\trts\n"
    /* after a sub.l that overflowed (V = 1): er0 = the clip in the true result's */
    /* direction (the wrapped result's sign is the opposite), the flag set */
    ".Lrk_sat_er0:\n"
    "\tbmi\t1f\n"
    "\tmov.l\t#0x80000000,er0\n"
    "\tbra\t2f\n"
    "1:\tmov.l\t#0x7fffffff,er0\n"
    "2:\tmov.b\t#1,r1l\n"
    "\tmov.b\tr1l,@(SATB+2,er7)\n"
    "\trts\n"
    /* ---- ac_process, 6 < n <= AC_MAX_CHANNELS: the pre-trim into a stack buffer, then */
    /* the kernel called as a function (r0 = r, r1 = trim, r2 = raw, r3 = out) */
    "ac_h8_process_n:\n"
    ".Lpr_gen:\n"
    "\tmov.w\t@er0,r5\n"
    "\tadd.w\t#-2*MAXCH,r7\n"
    "\tmov.w\tr7,r6\n"
    "\tsub.w\te5,e5\n"
    "1:\tmov.w\t@er2+,r4\n"
    "\tcmp.w\te1,r4\n"
    "\tbls\t7f\n"
    "\tcmp.w\te6,r4\n"
    "\tbhs\t7f\n"
    "8:\tmov.w\t@er1+,e4\n"
    "\tsub.w\te4,r4\n"
    "\tbcs\t3f\n"
    "\tbmi\t4f\n"
    "2:\tmov.w\tr4,@er6\n"
    "\tadds\t#2,er6\n"
    "\tdec.w\t#1,r5\n"
    "\tbne\t1b\n"
    "\tbra\t6f\n"
    "3:\tbmi\t2b\n"
    "\tmov.w\t#0x8000,r4\n"
    "\tbra\t5f\n"
    "4:\tmov.w\t#0x7fff,r4\n"
    "5:\tor.w\t#1,e5\n"
    "\tbra\t2b\n"
    "7:\tcmp.w\te6,e1\n"
    "\tbhs\t8b\n"
    "\tor.w\t#2,e5\n"
    "\tbra\t8b\n"
    "6:\tmov.l\ter3,@-er7\n"
    "\tmov.w\tr7,r1\n"
    "\tadds\t#4,er1\n"
    "\tmov.w\t@(4+2*MAXCH+16,er7),r2\n"
    "\tjsr\t@_ac_resolve_kernel\n"
    "\tadds\t#4,er7\n"
    "\tadd.w\t#2*MAXCH,r7\n"
    "\tor.w\te5,r0\n"
    "\tbra\t.Lpr_ret:16\n"
    /* ---- ac_resolve_kernel: r0 = r, r1 = x, r2 = omega, out @(4,sp) */
    "\t.global\t_ac_resolve_kernel\n"
    "_ac_resolve_kernel:\n"
    "\tmov.l\ter4,@-er7\n"
    "\tmov.l\ter5,@-er7\n"
    "\tmov.l\ter6,@-er7\n"
    "\tmov.w\t@(16,er7),r3\n"
    "\tmov.w\tr3,@-er7\n"
    "\tmov.w\tr0,@-er7\n"
    "\tmov.w\tr2,@-er7\n"
    "\tsub.w\tr4,r4\n"
    "\tmov.w\tr4,@-er7\n"
    "\tmov.w\t@er0,r5\n"
    "\tcmp.w\t#6,r5\n"
    "\tbne\t.Lrk_p1g\n"
    "\tmov.l\t@er1,er4\n"
    "\tmov.l\t@(4,er1),er5\n"
    "\tmov.w\t@(8,er1),e2\n"
    "\tmov.w\t@(10,er1),e3\n"
    "\tbra\t.Lrk_p1_init:16\n"
    /* ---- pass 1, 6 < n <= AC_MAX_CHANNELS: x from memory (base e4, through r4), n in e5 */
    "ac_h8_pass1_n:\n"
    ".Lrk_p1g:\n"
    "\tmov.w\tr1,e4\n"
    "\tmov.w\tr5,e5\n"
    "\tmov.w\t#MSTRIDE,e2\n"
    "\tsub.w\tr5,e2\n"
    "\tsub.w\tr5,e2\n"
    "\tmov.w\tr0,r6\n"
    "\tadd.w\t#OFF_K,r6\n"
    "\tmov.w\tr0,r2\n"
    "\tadd.w\t#OFF_M,r2\n"
    "\tmov.w\t#6,e6\n"
    ".Lrk_p1g_row:\n"
    "\tsub.l\ter0,er0\n"
    "\tmov.w\te4,r4\n"
    "\tmov.w\te5,e3\n"
    ".Lrk_p1g_col:\n"
    "\tmov.w\t@er2+,r1\n"
    "\tmov.w\t@er4+,r5\n"
    "\tmulxs.w\tr5,er1\n"
    "\tadd.l\ter1,er0\n"
    "\tdec.w\t#1,e3\n"
    "\tbne\t.Lrk_p1g_col\n"
    "\tmov.l\t@er6+,er1\n"
    "\tsub.l\ter1,er0\n"
    "\tbvc\t.Lrk_p1g_st\n"
    "\tbsr\t.Lrk_sat_er0:16\n"
    ".Lrk_p1g_st:\n"
    "\tmov.l\ter0,@er3\n"
    "\tadds\t#4,er3\n"
    "\tadd.w\te2,r2\n"
    "\tdec.w\t#1,e6\n"
    "\tbne\t.Lrk_p1g_row\n"
    "\tbra\t.Lrk_p1_done:16\n"
    ".Lrk_bl4:\n"
    "\t.byte\t0,1,2,2,3,3,3,3,4,4,4,4,4,4,4,4\n"
    "\t.align 1\n"
);

#else
/* ISO C forbids an empty translation unit */
typedef int ac_resolve_h8_unused;
#endif
