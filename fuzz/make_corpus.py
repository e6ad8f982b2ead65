#!/usr/bin/env python3
"""Write the seed corpus of fuzz/fuzz_core.c into fuzz/corpus/ (deterministic).

Every file is <selector byte><mode bytes><payload>: the selector picks the
harness target (see the table at the top of fuzz_core.c), the mode bytes pick
the variants that the target reads first (valid or arbitrary tables, omega
present, geometry kind and degeneration, xf operation, ...), the payload is
pseudo-random bytes from a fixed seed.  The set covers each target's branches
once so that libFuzzer starts from every region instead of finding them;
tests/python/test_fuzz_smoke.py replays it with a plain sanitizer build.

Usage:  python3 fuzz/make_corpus.py [--out DIR]      (default fuzz/corpus)
"""
from __future__ import annotations

import argparse
import hashlib
import random
from pathlib import Path

# target selectors (fuzz_core.c)
TRIM, RESOLVE, PROCESS, BUILD, INVERT, XF, FIXED, RATE, NULLS, ROWS, TRIG, REST, ATT, DISP, TERMS, OMEGA = range(16)


def seeds(rng: random.Random):
    def payload(n: int) -> bytes:
        return bytes(rng.randrange(256) for _ in range(n))

    for n in (0, 1, 6, 12, 19):
        yield "trim", bytes([TRIM, n]) + payload(4 * n)
    # resolve: mode bits 1 valid, 2 omega, 4 edge x, 8 edge omega, 16 small omega
    for mode in (0, 1, 3, 7, 11, 19, 27, 2, 6):
        for style in (0, 1, 3, 0x19, 0x3F, 0xB5):
            yield f"resolve_m{mode}_s{style}", bytes([RESOLVE, mode, style, rng.randrange(256)]) + payload(420)
    # process / batch: mode bits 1 valid, 2 omega, 4 raw trims, 8 raw readings, 16 edge omega, 32 no flags
    for mode in (1, 3, 7, 15, 31, 33, 0, 2):
        yield f"process_m{mode}", bytes([PROCESS, mode, 8, 0, rng.randrange(256)]) + payload(700)
    # build: structured geometries (mode & 3 != 0) kind 0..5 x degeneration 0..7, raw parameters,
    # n out of range, info NULL
    for kind in range(6):
        for deg in range(8):
            pert = rng.choice((5, 12, 20, 30))
            yield f"build_k{kind}_d{deg}", bytes([BUILD, 1, kind, deg | (rng.randrange(4) << 3), 59, rng.choice((13, 13, 3, 22)), pert]) + payload(300)
    for mode in (0x00, 0x04, 0x08, 0x0C, 0x31, 0x71, 0xB1, 0xF1, 0x41, 0x02):
        yield f"build_mode{mode:02x}", bytes([BUILD, mode, 0, 0, 59, 10, 20]) + payload(400)
    # invert6: matrix kinds 0..7 (7 = raw unnormalised), cond_log2 NULL with 0x80
    for mode in (0, 8, 1, 0x31, 2, 3, 4, 5, 6, 7, 0x80):
        yield f"invert_m{mode:02x}", bytes([INVERT, mode]) + payload(300)
    # xf: operations 0..11, wide exponents with 0x80, wide frac with 0x40
    for op in range(12):
        for extra in (0x00, 0x40, 0x80):
            b = next(v for v in range(256) if v % 12 == op and (v & 0xC0) == extra)
            yield f"xf_op{op}_{extra:02x}", bytes([XF, b]) + payload(60)
    # fixed: 8 operations, wide arguments with 8
    for op in range(8):
        for extra in (0, 8):
            yield f"fixed_op{op}_{extra}", bytes([FIXED, op | extra]) + payload(16)
    # rate: init parameters in/out of range, leak, edge alphas, garbage state
    for mode in (0, 1, 2, 4, 16, 20, 0x20, 0x60, 8):
        yield f"rate_m{mode:02x}", bytes([RATE, mode]) + payload(700)
    yield "nulls", bytes([NULLS])
    for wide in (0, 1):
        yield f"rows_{wide}", bytes([ROWS, wide]) + payload(40)
    # motion estimators (ac_trig, ac_rest, ac_attitude, ac_displace)
    for op in range(16):
        yield f"trig_op{op}", bytes([TRIG, op]) + payload(24)
    for mode in (0, 2, 8, 0x42, 1, 4, 16, 32, 0x4A):
        yield f"rest_m{mode:02x}", bytes([REST, mode, 40]) + payload(900)
    for mode in (1, 3, 5, 9, 0, 2, 4, 6):
        yield f"att_m{mode}", bytes([ATT, mode, 30]) + payload(500)
    for mode in (1, 3, 0, 2, 4, 8, 12):
        yield f"disp_m{mode}", bytes([DISP, mode, 60]) + payload(700)
    # a displacement stream: rest, motion, rest (plausible config, 1-D and 3-axis)
    # (ema_shift 1 or 3: the running mean must settle on the final rest within the stream)
    for axis_sel in (0, 1, 2, 3):
        for ema in (0, 2):
            cfg = bytes([DISP, 0, 63, 10, 40, 2, ema, axis_sel])
            move = b"".join(bytes([1] + [rng.randrange(256) for _ in range(3)]) for _ in range(12))
            yield f"disp_stream{axis_sel}_e{ema}", cfg + bytes(4) * 10 + move + bytes(4) * 41
    # the correctable terms: mode bits 0-1 lag / temperature / skew / nonlinearity, 4 arbitrary table,
    # 8 in place
    for mode in range(16):
        yield f"terms_m{mode:02d}", bytes([TERMS, mode]) + payload(400)
    # ac_omega: mode bits 1 the vectors' table, 2 perturbed, 4 the vectors' readings (+ offsets), 8 NULL
    # q10 / flags, high nibble steps - 1; the vectors' readings unchanged (zero offsets) from rest and mid-turn
    for mode in (0x05 | 0xB0, 0x0D | 0x70):
        yield f"omega_m{mode:02x}_plain", bytes([OMEGA, mode]) + bytes(64)
    for mode in (0x05 | 0xF0, 0x01 | 0x30, 0x03 | 0x30, 0x07 | 0x70, 0x0B | 0x10, 0x00, 0x04 | 0x10, 0x08):
        yield f"omega_m{mode:02x}", bytes([OMEGA, mode]) + payload(1000)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "corpus")
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    for old in a.out.glob("seed_*"):
        old.unlink()
    rng = random.Random(20261122)
    n = total = 0
    for name, data in seeds(rng):
        tag = hashlib.sha1(data).hexdigest()[:8]
        (a.out / f"seed_{name}_{tag}").write_bytes(data)
        n += 1
        total += len(data)
    print(f"{n} seed files, {total} bytes, in {a.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
