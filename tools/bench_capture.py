#!/usr/bin/env python3
"""Benchmark of ``accelcal capture``: poses and simulated time to the default target (1 mg on
every offset, 0.1 % on every gain), the guided plan against a fixed plan (six faces, then six
random directions, repeated), for a triad and for the seed's 6-channel array.

The sensor and the person are the tests' simulation (tests/python/capture_sim.py: the
independent generator's devices and true parameters; the person lands 2-5 deg off the
requested orientation at a random heading, reacts in 0.3-0.8 s, turns in 1-2 s with the hand
moving 5-15 cm).  Each run is the capture loop in-process, as on a port (same loop, same fit),
without the pseudo-terminal.  Also printed: the share of the stated 1-sigma the actual errors
stay within 3 of (offsets and gains, all runs).

    python3 tools/bench_capture.py [--seeds 5] [--jobs 1]
"""
from __future__ import annotations

import argparse
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "python"), str(ROOT / "tests" / "python")]

from accelcal.capture import CaptureLoop, Events  # noqa: E402
from capture_sim import fixed_plan, make_setup, run_in_process  # noqa: E402

CASES = (("triad16", 0.02), ("triad16", 0.1), ("triad16", 0.2), ("seed6", 0.02), ("seed6", 0.06), ("seed6", 0.15))


def one(args):
    """(poses, seconds, reached, z values) of one run."""
    device, noise, seed, plan = args
    dev, truth, rng = make_setup(device, seed)
    p = fixed_plan(np.random.default_rng(seed + 100), rounds=8) if plan == "fixed" else None
    loop, secs = run_in_process(CaptureLoop, Events, dev, truth, rng, noise, plan=p, max_poses=60)
    z = []
    if loop.fit is not None and loop.model == "full":
        g = dev.gravity_mps2
        kt = np.linalg.norm(truth["S"], axis=1)
        k = np.linalg.norm(loop.fit.sensitivity, axis=1)
        z = list((loop.fit.offsets - truth["b"]) / kt / g * 1000.0 / loop.offset_sigma_mg) + \
            list((k / kt - 1.0) * 100.0 / loop.gain_sigma_pct)
    return loop.n_poses, secs, loop.done_reason == "target", z


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args()
    jobs = [(d, n, s, plan) for d, n in CASES for plan in ("guided", "fixed") for s in range(a.seeds)]
    if a.jobs > 1:
        with ProcessPoolExecutor(a.jobs) as ex:
            res = list(ex.map(one, jobs))
    else:
        res = [one(j) for j in jobs]
    by = {}
    for j, r in zip(jobs, res):
        by.setdefault(j[:2], {}).setdefault(j[3], []).append(r)
    print(f"poses and simulated time to the default target (1 mg, 0.1 %), {a.seeds} seeds each "
          "(mean, [min-max]); guided vs fixed (six faces + six random, repeated)\n")
    print("| device | noise (m/s^2 rms) | guided poses | fixed poses | guided time (s) | fixed time (s) | reached (guided / fixed) |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    zs = []
    for (d, n), plans in by.items():
        cells = []
        for key in (0, 1):
            for plan in ("guided", "fixed"):
                v = [r[key] for r in plans[plan]]
                cells.append(f"{np.mean(v):.1f} [{min(v):.0f}-{max(v):.0f}]")
        cells = [cells[0], cells[1], cells[2], cells[3]]
        reached = " / ".join(f"{sum(r[2] for r in plans[p])} of {len(plans[p])}" for p in ("guided", "fixed"))
        print(f"| {d} | {n:g} | " + " | ".join(cells) + f" | {reached} |")
        zs += [z for plan in plans.values() for r in plan for z in r[3]]
    zs = np.array(zs)
    print(f"\nhonesty: {np.mean(np.abs(zs) <= 3):.3f} of {zs.size} errors within 3 stated sigma; "
          f"rms of error/sigma {np.sqrt(np.mean(zs ** 2)):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
