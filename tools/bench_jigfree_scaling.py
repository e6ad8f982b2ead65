#!/usr/bin/env python3
"""Time and memory of a jig-free calibration against the number of poses.

A triad (default_triad) with seed-prototype-like errors, P static poses on a Fibonacci
lattice, 60 samples a pose (white noise, rounding): accelcal.calibrate.fit_static(...,
"full", jigfree=True).  Each size runs in its own process, once with the structured solve
(many free poses: a sparse Jacobian and each pose eliminated for the covariance, from
calibrate.settings.STRUCTURED_MIN_POSES poses on) and once with the dense one forced (the
MINPACK solve and the SVD of the whole Jacobian: O(P^3)); the table gives wall time, the
process's peak resident memory (ru_maxrss, including the interpreter and numpy/scipy,
~100 MB) and the largest offset difference between the two in units of its sigma.

Usage: python tools/bench_jigfree_scaling.py [--sizes 50,200,800,2000] [--dense-max 800]
Writes the markdown table to stdout and to build/bench_jigfree_scaling.md.
"""
from __future__ import annotations

import argparse
import importlib
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def fib_dirs(P: int) -> np.ndarray:
    """P unit vectors on a Fibonacci lattice."""
    i = np.arange(P) + 0.5
    z = 1 - 2 * i / P
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def one(P: int, dense: bool) -> dict:
    """Fit P poses in this process; returns time, peak RSS and the offsets."""
    from accelcal.io.device import default_triad
    from accelcal.readings.static import PoseSet
    from accelcal import model
    problem = importlib.import_module("accelcal.calibrate.problem")
    static_model = importlib.import_module("accelcal.calibrate.static_model")
    if dense:
        problem.STRUCTURED_MIN_POSES = 10 ** 9
    rng = np.random.default_rng(1)
    d = default_triad()
    k = d.counts_per_mps2
    S = (k * (1 + rng.uniform(-0.007, 0.036, 3)))[:, None] * d.axes + k[:, None] * rng.uniform(-0.0175, 0.0175, (3, 3))
    b = d.zero_counts + rng.uniform(-0.28, 0.28, 3) * d.gravity_mps2 * k
    F = d.gravity_mps2 * fib_dirs(P)
    clean = model.predict_counts(b, S, d.positions, F)
    n = 60
    raw = np.round(clean[:, None, :] + 0.02 * k * rng.standard_normal((P, n, 3)))
    ps = PoseSet(raw.mean(1), np.full(P, n), raw.std(1, ddof=1), np.full((P, 3), np.nan), np.full(P, np.nan))
    t = time.perf_counter()
    fit = static_model.fit_static(d, ps, "full", jigfree=True)
    dt = time.perf_counter() - t
    return {"P": P, "dense": dense, "s": dt, "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "offsets": fit.offsets.tolist(), "sigma": np.sqrt(fit.cov[:, 0, 0]).tolist(),
            "chi2_dof": fit.chi2 / fit.dof}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="50,200,400,800,2000")
    ap.add_argument("--dense-max", type=int, default=800, help="largest P also run dense (default %(default)s)")
    ap.add_argument("--one", nargs=2, metavar=("P", "DENSE"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        print(json.dumps(one(int(a.one[0]), a.one[1] == "1")))
        return 0
    rows = ["| poses | structured: time | peak RSS | dense: time | peak RSS | max offset difference / sigma |",
            "| ---: | ---: | ---: | ---: | ---: | ---: |"]
    for P in (int(v) for v in a.sizes.split(",")):
        got = {}
        for dense in ((False, True) if P <= a.dense_max else (False,)):
            out = subprocess.run([sys.executable, __file__, "--one", str(P), "1" if dense else "0"],
                                 capture_output=True, text=True, check=True, cwd=ROOT)
            got[dense] = json.loads(out.stdout.strip().splitlines()[-1])
        s = got[False]
        if True in got:
            dn = got[True]
            diff = np.max(np.abs(np.subtract(s["offsets"], dn["offsets"])) / np.asarray(dn["sigma"]))
            rows.append(f"| {P} | {s['s']:.2f} s | {s['rss_mb']:.0f} MB | {dn['s']:.2f} s | {dn['rss_mb']:.0f} MB | "
                        f"{diff:.1e} |")
        else:
            rows.append(f"| {P} | {s['s']:.2f} s | {s['rss_mb']:.0f} MB | - | - | - |")
        print(rows[-1], file=sys.stderr)
    text = "\n".join(rows) + "\n"
    print(text)
    (ROOT / "build").mkdir(exist_ok=True)
    (ROOT / "build" / "bench_jigfree_scaling.md").write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
