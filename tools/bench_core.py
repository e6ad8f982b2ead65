#!/usr/bin/env python3
"""Firmware cost of the C core's per-sample path (the README's figures).

* AVR (atmega328p, 16-bit int): exact cycles from Timer1 under simavr.
* Host x86-64: instructions per call from valgrind --tool=callgrind.
* H8/300H (h8300-hms-gcc -mh -mn -O2): text/data/bss per module and for the
  firmware subset (pre-trim + apply + centripetal + inversion).
* Host throughput of the C batch path through cffi against numpy float64.
Writes build/bench_core.md.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "build" / "bench"
CSRC = sorted((ROOT / "csrc").glob("*.c"))
INC = ROOT / "include"


def make_header():
    from accelcal.device import default_device
    from accelcal.header import render_header
    from accelcal.quantize import quantize
    d = default_device()
    rng = np.random.default_rng(7)
    s = d.nominal_sensitivity() * (1 + rng.uniform(-0.007, 0.036, (6, 1))) + \
        d.counts_per_mps2[:, None] * rng.normal(0, 0.0175, (6, 3))
    b = d.zero_counts + rng.uniform(-0.28, 0.28, 6) * 9.80665 * d.counts_per_mps2
    BUILD.mkdir(parents=True, exist_ok=True)
    (BUILD / "cal.h").write_text(render_header(quantize(b, s, d.positions, d.name)))
    return d, quantize(b, s, d.positions, d.name), b, s


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw)


def parse_bench(text):
    text = re.sub(r"\x1b\[[0-9;]*m", "", text)
    m = re.search(r"BENCH ([^\n]*?)\.?\s*$", text, re.M)
    if not m:
        raise RuntimeError(f"no BENCH line in: {text[-500:]}")
    return {k: int(v) for k, v in (kv.split("=") for kv in m.group(1).split())}


def avr_cycles(opt="-Os"):
    elf = BUILD / f"bench{opt}.elf"
    run(["avr-gcc", "-mmcu=atmega328p", opt, "-ffunction-sections", "-Wl,--gc-sections", "-std=c99", "-Wall", "-Wextra", "-DF_CPU=16000000UL",
         f"-I{INC}", f"-I{ROOT / 'csrc'}", f"-I{BUILD}", str(ROOT / "tools/bench/bench_main.c"),
         *map(str, CSRC), "-o", str(elf)])
    res = subprocess.run(["simavr", "-m", "atmega328p", "-f", "16000000", str(elf)],
                         capture_output=True, text=True, timeout=120)
    return parse_bench(res.stdout + res.stderr)


def host_instructions():
    exe = BUILD / "bench_host"
    reps = 1000
    run(["gcc", "-O2", "-std=c99", f"-DBENCH_REPEAT={reps}", f"-I{INC}", f"-I{ROOT / 'csrc'}",
         f"-I{BUILD}", str(ROOT / "tools/bench/bench_main.c"), *map(str, CSRC), "-o", str(exe)])
    out = BUILD / "callgrind.out"
    run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", str(exe)])
    ann = run(["callgrind_annotate", "--inclusive=yes", str(out)]).stdout
    counts = {}
    for line in ann.splitlines():
        m = re.match(r"^\s*([\d,]+)\s+\([^)]*\)\s+(\S+)", line)
        if m:
            name = m.group(2).split(":")[-1]
            counts.setdefault(name, int(m.group(1).replace(",", "")))
    calls = reps + 2  # the repeat loop plus the two timed calls
    return {"ac_process": counts.get("ac_process", 0) / calls,
            "ac_resolver_build": counts.get("ac_resolver_build", 0),
            "ac_rate_step": counts.get("ac_rate_step", 0)}


def h8_sizes():
    sizes = {}
    objs = []
    for c in CSRC:
        o = BUILD / f"h8_{c.stem}.o"
        run(["h8300-hms-gcc", "-mh", "-mn", "-O2", "-std=c99", f"-I{INC}", f"-I{ROOT / 'csrc'}",
             "-c", str(c), "-o", str(o)])
        objs.append(o)
        txt = run(["h8300-hms-size", str(o)]).stdout.splitlines()[1].split()
        sizes[c.stem] = tuple(int(v) for v in txt[:3])
    undefined = run(["h8300-hms-nm", "-u", *map(str, objs)]).stdout
    libcalls = sorted(set(re.findall(r"U (___\w+)", undefined)))
    return sizes, libcalls


def throughput(d, t, b, s):
    from accelcal import model, native
    n = 1_000_000
    rng = np.random.default_rng(0)
    raw = np.clip(np.round(model.predict_counts(b, s, d.positions, rng.normal(0, 9.8, (n, 3)),
                                                rng.normal(0, 30, (n, 3)))), 0, 10000).astype(np.uint16)
    w = rng.integers(-3000, 3000, (n, 3)).astype(np.int16)
    r = t.resolver()
    native.process_batch(r, t.trim, raw[:1000], w[:1000])
    t0 = time.perf_counter()
    native.process_batch(r, t.trim, raw, w)
    tc = time.perf_counter() - t0
    t0 = time.perf_counter()
    model.resolve(b, s, d.positions, raw, w / 1024.0)
    tf = time.perf_counter() - t0
    return n, tc, tf


def main():
    sys.path.insert(0, str(ROOT / "python"))
    d, t, b, s = make_header()
    lines = ["| measure | value | goal |", "| --- | --- | --- |"]
    if shutil.which("simavr") and shutil.which("avr-gcc"):
        c, c2 = avr_cycles("-Os"), avr_cycles("-O2")
        lines += [f"| AVR cycles (-Os / -O2), 6-ch sample, pre-trim + apply + centripetal (`ac_process`) | "
                  f"{c['process_omega']} / {c2['process_omega']} | <= 3000 |",
                  f"| AVR cycles (-Os / -O2), same without rotation (omega = NULL) | "
                  f"{c['process_no_omega']} / {c2['process_no_omega']} | |",
                  f"| AVR cycles (-Os / -O2), `ac_rate_step` (3 axes) | {c['rate_step']} / {c2['rate_step']} | |",
                  f"| AVR cycles (-Os / -O2), `ac_resolver_build` (6x6 inverse + tables) | "
                  f"{c['resolver_build']} / {c2['resolver_build']} | |"]
    if shutil.which("valgrind"):
        h = host_instructions()
        lines += [f"| host x86-64 instructions, `ac_process` per sample | {h['ac_process']:.0f} | |",
                  f"| host x86-64 instructions, `ac_resolver_build` | {h['ac_resolver_build']} | |"]
    if shutil.which("h8300-hms-gcc"):
        sizes, libcalls = h8_sizes()
        # the objects each firmware subset links (nothing else is pulled in)
        per_sample = ["ac_ops", "ac_trim", "ac_resolve"]
        with_build = per_sample + ["ac_xf", "ac_invert"]
        for m, (tx, da, bs) in sizes.items():
            lines.append(f"| H8/300H {m}.o text/data/bss (bytes) | {tx}/{da}/{bs} | |")
        lines.append(f"| H8/300H text, pre-trim + apply + centripetal (per-sample path) | "
                     f"{sum(sizes[m][0] for m in per_sample)} | |")
        lines.append(f"| H8/300H text, pre-trim + apply + centripetal + inversion | "
                     f"{sum(sizes[m][0] for m in with_build)} | <= 3072 |")
        lines.append(f"| H8/300H libgcc / soft-float symbols needed | {', '.join(libcalls) or 'none'} | none |")
    n, tc, tf = throughput(d, t, b, s)
    lines += [f"| host C batch resolve via cffi, 6-ch samples/s | {n / tc:,.0f} ({6 * n / tc / 1e6:.1f} M channel-samples/s) | >= 20 M ch-samples/s |",
              f"| numpy float64 reference, samples/s | {n / tf:,.0f} (C/numpy = {tf / tc:.2f}) | |"]
    table = "\n".join(lines)
    print(table)
    (ROOT / "build").mkdir(exist_ok=True)
    (ROOT / "build" / "bench_core.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
