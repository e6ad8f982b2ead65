#!/usr/bin/env python3
"""Cost of the C core on the seed's own CPU: H8/300H states per call, from the
instructions a simulated H8/300H executes, weighted by the manual's states.

What it does
------------
1. Builds tools/h8sim/bench_h8.c with the whole core for the H8/300H in normal mode
   (h8300-hms-gcc -mh -mn -fomit-frame-pointer) at -Os and at -O2 and runs it on the
   patched GNU simulator (tools/build_h8sim.sh) with ``H8SIM_PROFILE`` set: the
   simulator counts every executed instruction by address, separately for each
   profile region.
2. How a call is delimited: bench_h8.c brackets each measured call with
   ``jsr @@0xcd`` (the patch's region switch, r0 = region before the call's argument
   set-up, r0 = 0 after its return).  The region counts the argument set-up, the call,
   the callee and everything it calls, and the closing switch; the same bracket around
   nothing (region ``empty``) is subtracted once per entry.  A region is entered with
   16 different inputs (the batch: twice 8 samples) and the result is the mean per
   sample.
3. States: each executed instruction (disassembled by h8300-hms-objdump at its
   address) is weighted by the H8/300H Programming Manual's "No. of states" for
   on-chip memory (all on-chip ROM/RAM accesses take 2 states, an internal operation
   1), i.e. the manual's I/J/K/L/M/N model: 2 states per instruction word fetched,
   2 per byte/word data access (a longword is two), 2 per stack access, plus the
   internal states (2 for @ERn+ / @-ERn, 20 for MULXS.W / MULXU.W / DIVXS.W /
   DIVXU.W, 12 for the .B forms, 2 for 16-bit branches and 24-bit jumps).  Checked
   against the manual's own per-instruction tables (Hitachi H8/300H Series Programming
   Manual, ADE-602-053; page numbers as printed): MULXS.B Rs,Rd 16 states (p. 128),
   MULXS.W Rs,ERd 24 (p. 129), MULXU.B 14 (p. 130), Bcc d:8 4 and d:16 6 (p. 53),
   RTS 8 in normal mode (p. 160); ``check_manual_values`` asserts them at every run.
   The simulator's own cycle total is not used (its opcode table is approximate).
4. Multiply floor of a per-sample function: its 16 x 16 multiplies (the algorithm's
   count where the AVR table states it -- 36 for ac_process without omega, 78 with,
   12 for ac_rate_step, 9 for ac_triad_apply (3x3) -- else the MULXS.W/MULXU.W the H8 code executes) times
   (24 states of MULXS.W + 4 of the cheapest load of one operand, MOV.W @ERs,Rd).
5. RAM: static .data + .bss of the two firmware links of tools/build_h8.sh (per-sample
   path; with the on-device build) plus the stack: fw_main's frame (from its
   prologue) + its return address + the deepest stack use measured on the simulator
   over the calls that firmware makes (painted stack, bench_h8.c), against 2 KB.
6. Flash: text of the two firmware links (tools/build_h8.sh at -O2 and -Os).

Env: H8_EXTRA_CFLAGS adds compiler flags to the benchmark build (experiments; the
firmware sizes always come from tools/build_h8.sh's own flags).
Writes the table to build/h8bench/bench_h8.md and per-instruction profiles to
build/h8bench/profile_<opt>_<region>.txt.  Usage: python3 tools/bench_h8.py
"""
import os
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "build" / "h8bench"
CROSS = "h8300-hms-"
OPTS = ("Os", "O2")
CLOCK_HZ = 16_000_000
FRAME_HZ = 60
RAM_BYTES = 2048
SIZES = {}  # sizeof on the H8/300H of the terms' state, from bench_h8.c's SIZE lines
MULXS_W_STATES = 24
MIN_LOAD_STATES = 4  # MOV.W @ERs,Rd: one word fetched, one word read
ALGORITHM_MULS = {"ac_process": 36, "ac_process_omega": 78, "ac_resolve_omega": 78,
                  "ac_rate_step": 12, "ac_process_batch_omega": 78, "ac_triad_apply": 9,
                  # the correctable terms (6 channels; their headers): a lag step 2 (32 x 16),
                  # ac_temp_correct 5 a channel, ac_skew_step 1, ac_nonlin_invert 3 an iteration x 3
                  "ac_temp_lag_step": 2, "ac_temp_correct": 30, "ac_skew_step": 6, "ac_nonlin_invert": 54,
                  "terms_temp_nonlin": 2 * 2 + 30 + 54, "terms_full_path": 2 * 2 + 30 + 6 + 54 + 78,
                  "ac_temp_correct_k2": 30, "terms_temp_nonlin_k2": 2 * 2 + 30 + 54,
                  "ac_nonlin_invert_k2": 54, "ac_nonlin_invert_s16": 54, "ac_nonlin_invert_s17": 54,
                  "ac_nonlin_invert_s19": 54}
PER_SAMPLE = ("ac_trim", "ac_process", "ac_process_omega", "ac_resolve_omega", "ac_rate_step",
              "ac_att_step", "ac_disp_step", "ac_process_batch_omega", "ac_triad_apply",
              "ac_temp_lag_step", "ac_temp_correct", "ac_skew_step", "ac_nonlin_invert", "terms_temp_nonlin",
              "terms_full_path")
# the array's own omega (ac_omega.h, 12 channels; docs/angular-rate.md): its multiply floor is the
# MULXS.W/MULXU.W it executes (ac_xf's partial products and the 2 x 9 x 12 of its rows)
PER_SAMPLE += ("ac_omega_step_rest", "ac_omega_step_turn")
# the terms' tables with the hand-off in 2^-2 counts (the seed's converter: AC_CAL_TERMS_FRAC 2)
PER_SAMPLE += ("ac_temp_correct_k2", "terms_temp_nonlin_k2", "ac_nonlin_invert_k2")
# the same coefficients at the shifts next to 18 (a 2^-2-count table's is 17..19, 16 for k = 1)
PER_SAMPLE += ("ac_nonlin_invert_s16", "ac_nonlin_invert_s17", "ac_nonlin_invert_s19")
LABELS = {
    "ac_trim": "`ac_trim` (6 channels)",
    "ac_process": "`ac_process`, omega = NULL (pre-trim + apply)",
    "ac_process_omega": "`ac_process` with omega (+ centripetal)",
    "ac_resolve_omega": "`ac_resolve` with omega (no pre-trim)",
    "ac_rate_step": "`ac_rate_step` (3 axes)",
    "ac_att_step": "`ac_att_step` (attitude, two triads)",
    "ac_disp_step": "`ac_disp_step` (displacement, 3-axis)",
    "ac_process_batch_omega": "`ac_process_batch` with omega, per sample (8 per call)",
    "ac_resolver_build": "`ac_resolver_build` (6 channels, on-device table build)",
    "ac_triad_apply": "`ac_triad_apply` (3-axis sensor: pre-trim + 3x3 apply)",
    "ac_triad_build": "`ac_triad_build` (3-axis sensor, on-device table build)",
    "ac_temp_lag_step": "`ac_temp_lag_step` (one lag filter)",
    "ac_temp_correct": "`ac_temp_correct` (6 channels, offset + gain)",
    "ac_skew_step": "`ac_skew_step` (6 channels)",
    "ac_nonlin_invert": "`ac_nonlin_invert` (6 channels, 3 iterations)",
    "terms_temp_nonlin": "terms with nonlinearity and temperature: 2 lag steps + `ac_temp_correct` + `ac_nonlin_invert`",
    "ac_omega_step_rest": "`ac_omega_step` (12 channels, at rest: the ML skipped)",
    "ac_omega_step_turn": "`ac_omega_step` (12 channels, turning: the ML each sample)",
    "ac_temp_correct_k2": "`ac_temp_correct` (6 channels, offset + gain, output in 2^-2 counts, frac 2)",
    "terms_temp_nonlin_k2": "terms with nonlinearity and temperature, the hand-off in 2^-2 counts (frac 2, nonlinearity shift 18)",
    "ac_nonlin_invert_k2": "`ac_nonlin_invert` (6 channels, 3 iterations) at shift 18 (coefficients per 2^-2 count)",
    "ac_nonlin_invert_s16": "`ac_nonlin_invert` (6 channels, 3 iterations), the shift-18 coefficients at shift 16",
    "ac_nonlin_invert_s17": "`ac_nonlin_invert` (6 channels, 3 iterations), the shift-18 coefficients at shift 17",
    "ac_nonlin_invert_s19": "`ac_nonlin_invert` (6 channels, 3 iterations), the shift-18 coefficients at shift 19",
    "terms_full_path": "the whole per-sample path with every term: `ac_trim_rails` + 2 lags + temperature + "
                       "skew + nonlinearity + `ac_resolve` with omega",
}

BRANCHES = {"bra", "brn", "bt", "bf", "bhi", "bls", "bcc", "bhs", "bcs", "blo", "bne", "beq",
            "bvc", "bvs", "bpl", "bmi", "bge", "blt", "bgt", "ble"}
REG_ONLY_2 = {"add", "addx", "sub", "subx", "cmp", "and", "or", "xor", "not", "neg", "inc", "dec",
              "adds", "subs", "exts", "extu", "shll", "shlr", "shal", "shar", "rotl", "rotr",
              "rotxl", "rotxr", "daa", "das", "nop", "sleep", "andc", "orc", "xorc"}
BIT_RMW = {"bset", "bclr", "bnot", "bst", "bist"}
BIT_READ = {"btst", "bld", "bild", "band", "biand", "bor", "bior", "bxor", "bixor"}
MULDIV = {"mulxu.b": 12, "mulxs.b": 12, "divxu.b": 12, "divxs.b": 12,
          "mulxu.w": 20, "mulxs.w": 20, "divxu.w": 20, "divxs.w": 20}


def states(mnemonic, operands, length):
    """H8/300H states of one instruction (normal mode, on-chip memory)."""
    base, _, size = mnemonic.partition(".")
    words = length // 2
    fetch = 2 * words
    mem = "@" in operands
    incdec = "+" in operands or "@-" in operands
    if mnemonic in MULDIV:
        return fetch + MULDIV[mnemonic]
    if base in BRANCHES:
        return 4 if length == 2 else 6
    if base == "rts":
        return 8  # I=2, K=1 (normal mode: 16-bit PC), N=2
    if base == "bsr":
        return 6 if length == 2 else 8
    if base in ("jsr", "jmp"):
        stack = 2 if base == "jsr" else 0
        if "@@" in operands:
            return 4 + 2 + stack  # I=2, J=1 (a word in normal mode)
        if operands.startswith("@er"):
            return 4 + stack
        return 4 + stack + 2  # @aa:24: N=2
    if base == "mov" or base in ("ldc", "stc"):
        if not mem:
            return fetch
        access = 4 if size == "l" else 2
        return fetch + access + (2 if incdec else 0)
    if base in BIT_RMW or base in BIT_READ:
        if not mem:
            return fetch
        return fetch + (4 if base in BIT_RMW else 2)
    if base in REG_ONLY_2 and not mem:
        return fetch
    raise ValueError(f"no state model for '{mnemonic} {operands}' ({length} bytes)")


def check_manual_values():
    """The model against values printed in the manual's instruction pages."""
    cases = [("mulxs.w", "r1,er2", 4, 24, "p. 129"), ("mulxs.b", "r1l,r2", 4, 16, "p. 128"),
             ("mulxu.b", "r1l,r2", 2, 14, "p. 130"),
             ("bne", ".+4", 2, 4, "p. 53"), ("bne", ".+400", 4, 6, "p. 53"),
             ("rts", "", 2, 8, "p. 160")]
    for mn, ops, length, want, page in cases:
        got = states(mn, ops, length)
        if got != want:
            raise SystemExit(f"bench_h8: state model gives {got} for {mn} {ops}, manual {page}: {want}")


def run(cmd, **kw):
    r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if r.returncode != 0:
        raise SystemExit(f"bench_h8: {' '.join(map(str, cmd[:3]))} ... failed ({r.returncode}): "
                         f"{(r.stderr or r.stdout).strip().splitlines()[-1:]}")
    return r.stdout


def disassemble(coff):
    """address -> (mnemonic, operands, length, function)."""
    text = run([CROSS + "objdump", "-d", str(coff)])
    insns, func = [], "?"
    for line in text.splitlines():
        m = re.match(r"^[0-9a-f]+ <([^>]+)>:", line)
        if m:
            func = m.group(1)
            continue
        m = re.match(r"^\s+([0-9a-f]+):\t([0-9a-f ]+)\t(\S+)\s*(.*)$", line)
        if m:
            insns.append([int(m.group(1), 16), m.group(3), m.group(4).strip(), None,
                          func if not func.startswith(".") else None])
    table, last_func = {}, "?"
    for i, ins in enumerate(insns):
        if ins[4] is not None:
            last_func = ins[4]
        nxt = insns[i + 1][0] if i + 1 < len(insns) else ins[0] + 2
        table[ins[0]] = (ins[1], ins[2], nxt - ins[0], last_func)
    return table


def build_and_profile(opt, sim):
    d = OUT / opt
    d.mkdir(parents=True, exist_ok=True)
    cflags = ["-mh", "-mn", f"-{opt}", "-fomit-frame-pointer", "-std=c99", "-Wall", "-Wextra",
              "-Werror", f"-I{ROOT / 'include'}", *os.environ.get("H8_EXTRA_CFLAGS", "").split()]
    objs = []
    for src in sorted((ROOT / "csrc").glob("*.c")) + [ROOT / "tools/h8sim/bench_h8.c"]:
        obj = d / (src.stem + ".o")
        run([CROSS + "gcc", *cflags, "-c", "-o", str(obj), str(src)])
        objs.append(str(obj))
    run([CROSS + "gcc", "-mh", "-mn", "-c", "-o", str(d / "crt0.o"), str(ROOT / "tools/h8sim/crt0.s")])
    coff, elf, prof = d / "bench.coff", d / "bench.elf", d / "profile.txt"
    run([CROSS + "gcc", "-mh", "-mn", "-nostdlib", "-nostartfiles", "-Wl,-e,_start", "-o", str(coff),
         str(d / "crt0.o"), *objs])
    run([sys.executable, str(ROOT / "tools/h8sim/elfwrap.py"), str(coff), str(elf)])
    env = {"H8SIM_PROFILE": str(prof), "PATH": "/usr/bin:/bin"}
    out = subprocess.run(["timeout", "120", sim, str(elf)], capture_output=True, text=True, env=env)
    if out.returncode != 0 or not out.stdout.rstrip().endswith("END bench"):
        raise SystemExit(f"bench_h8: -{opt} bench run failed (status {out.returncode}): "
                         f"{out.stderr.strip()[:200]}")
    regions, stack = {}, {}
    for line in out.stdout.splitlines():
        f = line.split()
        if f[:1] == ["SIZE"]:
            SIZES[f[1]] = int(f[2])
        if f[:1] == ["REGION"]:
            regions[int(f[1])] = (f[2], int(f[3]), int(f[4]))
        elif f[:1] == ["STACK"]:
            stack[int(f[1])] = int(f[2])
    counts = defaultdict(dict)
    for line in prof.read_text().splitlines():
        r, a, c = line.split()
        counts[int(r)][int(a, 16)] = int(c)
    return regions, stack, counts, disassemble(coff)


def region_cost(counts, table):
    st = ins = muls = 0
    for addr, c in counts.items():
        mn, ops, length, _ = table[addr]
        st += c * states(mn, ops, length)
        ins += c
        muls += c if mn in ("mulxs.w", "mulxu.w") else 0
    return st, ins, muls


def write_profile(path, counts, table, per):
    by_func, rows = defaultdict(int), []
    for addr, c in counts.items():
        mn, ops, length, func = table[addr]
        s = states(mn, ops, length)
        by_func[func] += c * s
        rows.append((c * s, addr, func, mn, ops, c, s))
    lines = ["# states per sample by function"]
    for func, s in sorted(by_func.items(), key=lambda kv: -kv[1]):
        lines.append(f"{s / per:10.1f}  {func}")
    lines.append("# by instruction: states/sample  address  function  instruction  count/sample  states")
    for tot, addr, func, mn, ops, c, s in sorted(rows, reverse=True):
        lines.append(f"{tot / per:10.1f}  {addr:04x}  {func:28s} {mn:8s} {ops:24s} {c / per:8.2f} {s}")
    path.write_text("\n".join(lines) + "\n")


def firmware_sizes():
    run(["bash", str(ROOT / "tools/build_h8.sh")])
    sizes = {}
    for opt, sub in (("O2", ""), ("Os", "Os")):
        for line in (ROOT / "build/h8" / sub / "firmware_sizes.txt").read_text().splitlines()[1:]:
            f = line.split()
            sizes[(opt, f[5])] = (int(f[0]), int(f[1]), int(f[2]))
        for fw in ("sample", "full"):
            dis = run([CROSS + "objdump", "-d", str(ROOT / "build/h8" / sub / f"fw_main_{fw}.o")])
            frame = 0
            for line in dis.split("<_main>:")[1].splitlines()[1:12]:
                m = re.search(r"add\.w\s+#0x([0-9a-f]+),r7", line)
                if m and int(m.group(1), 16) >= 0x8000:
                    frame += 0x10000 - int(m.group(1), 16)
                elif re.search(r"mov\.l\s+er\d,@-er7", line):
                    frame += 4
                elif re.search(r"mov\.w\s+r\d,@-er7", line):
                    frame += 2
                elif "jsr" in line:
                    break
            sizes[(opt, f"frame_{fw}")] = frame
    return sizes


def main():
    check_manual_values()
    sim = run(["bash", str(ROOT / "tools/build_h8sim.sh")]).strip().splitlines()[-1]
    OUT.mkdir(parents=True, exist_ok=True)
    res = {}
    for opt in OPTS:
        regions, stack, counts, table = build_and_profile(opt, sim)
        ids = {name: rid for rid, (name, _, _) in regions.items()}
        e_states, e_ins, _ = region_cost(counts[ids["empty"]], table)
        e_entries = regions[ids["empty"]][1]
        for rid, (name, entries, samples) in regions.items():
            if name == "empty":
                continue
            st, ins, muls = region_cost(counts[rid], table)
            per = entries * samples
            res[(opt, name)] = ((st - e_states / e_entries * entries) / per,
                                (ins - e_ins / e_entries * entries) / per, muls / per, stack[rid])
            write_profile(OUT / f"profile_{opt}_{name}.txt", counts[rid], table, per)
    fw = firmware_sizes()
    frame_states = CLOCK_HZ / FRAME_HZ

    def pair(fn, fmt="{:,.0f}"):
        return " / ".join(fmt.format(fn(o)) for o in OPTS)

    rows = ["| measure (H8/300H, 16 MHz, normal mode; -Os / -O2) | value |", "| --- | ---: |"]
    for name in PER_SAMPLE + ("ac_resolver_build", "ac_triad_build"):
        rows.append(f"| states, {LABELS[name]} | {pair(lambda o: res[(o, name)][0])} |")
    rows.append(f"| instructions, `ac_process` with omega | {pair(lambda o: res[(o, 'ac_process_omega')][1])} |")
    for name in PER_SAMPLE:
        if name == "ac_trim":
            continue
        alg = ALGORITHM_MULS.get(name)
        n = {o: (alg if alg is not None else round(res[(o, name)][2])) for o in OPTS}
        floor = {o: n[o] * (MULXS_W_STATES + MIN_LOAD_STATES) for o in OPTS}
        src = "algorithm" if alg is not None else "executed MULXS.W/MULXU.W"
        rows.append(f"| multiply floor, {LABELS[name]}: {pair(lambda o: n[o])} x (24 + 4) states "
                    f"({src}; executed {pair(lambda o: res[(o, name)][2], '{:.1f}')}); measured/floor | "
                    f"{pair(lambda o: floor[o])}; {pair(lambda o: res[(o, name)][0] / floor[o], '{:.2f}')} |")
    rows.append("| share of the 60 Hz frame (266,667 states), one 6-channel sample: `ac_process` with "
                f"omega + `ac_rate_step` | {pair(lambda o: 100 * (res[(o, 'ac_process_omega')][0] + res[(o, 'ac_rate_step')][0]) / frame_states, '{:.2f} %')} |")
    rows.append("| share of the 60 Hz frame, the on-device table build | "
                f"{pair(lambda o: 100 * res[(o, 'ac_resolver_build')][0] / frame_states, '{:.0f} %')} |")
    rows.append("| share of the 60 Hz frame, the triad's on-device table build | "
                f"{pair(lambda o: 100 * res[(o, 'ac_triad_build')][0] / frame_states, '{:.0f} %')} |")
    terms_calls = ("terms_full_path",)
    for fwname, calls, label in (("sample", ("ac_trim", "ac_process_omega", "ac_rate_step") + terms_calls,
                                  "per-sample path with every term (fw_sample)"),
                                 ("full", ("ac_trim", "ac_process_omega", "ac_rate_step", "ac_resolver_build")
                                  + terms_calls, "per-sample path with every term + on-device build (fw_full)")):
        def ram(o, fwname=fwname, calls=calls):
            text, data, bss = fw[(o, f"fw_{fwname}.out")]
            stk = fw[(o, f"frame_{fwname}")] + 2 + max(res[(o, c)][3] for c in calls)
            return data + bss, stk, RAM_BYTES - data - bss - stk
        rows.append(f"| RAM, {label}: static .data+.bss + stack (fw_main frame + return address + deepest "
                    f"call, painted) = used; left of 2,048 B | "
                    + " / ".join(f"{s} + {k} = {s + k}; {left}" for s, k, left in (ram(o) for o in OPTS)) + " |")
        rows.append(f"| flash, {label}: text bytes | {pair(lambda o: fw[(o, f'fw_{fwname}.out')][0])} |")
    lag, line, buf = SIZES["ac_temp_lag"], SIZES["ac_skew_line"], SIZES["skew_buf"]
    rows.append(f"| RAM of the terms (in fw_sample's .bss above): 2 lag states x {lag} B, the skew's delay line "
                f"(caller-owned: 3 samples x 6 channels x 2 B) {buf} B and its state {line} B; the tables are "
                f"const (ROM) | {2 * lag + buf + line} B |")
    rows.append("| deepest stack (painted, incl. return address), " + ", ".join(
        f"`{n}` {pair(lambda o: res[(o, n)][3])}" for n in ("ac_trim", "ac_process_omega", "ac_rate_step",
                                                         "ac_att_step", "ac_disp_step", "ac_resolver_build",
                                                         "ac_triad_apply", "ac_triad_build", "terms_full_path"))
                + " | bytes |")
    rows.append(f"| RAM of the array's omega: `ac_omega_table` {SIZES['ac_omega_table']} B (const: ROM from a header), "
                f"`ac_omega_state` {SIZES['ac_omega_state']} B; deepest stack of `ac_omega_step` | "
                f"{pair(lambda o: res[(o, 'ac_omega_step_turn')][3])} B |")
    table_md = "\n".join(rows) + "\n"
    (OUT / "bench_h8.md").write_text(table_md)
    print(table_md)
    print(f"per-instruction profiles: {OUT}/profile_<opt>_<region>.txt")


if __name__ == "__main__":
    main()
