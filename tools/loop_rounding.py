#!/usr/bin/env python3
"""The fixed engine's whole-count hand-off on a loop case's recording 2 (docs/refine.md).

The true terms of a case of tests/python/loop_cases.py are applied to recording 2 by their float
reference (accelcal.firmware.terms.correct_readings); the hand-off's error is rint(y) - y.  Prints
its RMS per channel (counts), the RMS over the poses of its mean within each pose, its median
within-pose sd, and the standard error of a pose's mean from the noise.

Usage: python tools/loop_rounding.py "temperature offset + gain" [--seed 11]
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))

from accelcal.firmware.terms import correct_readings  # noqa: E402
import loop_cases as lc  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case")
    ap.add_argument("--seed", type=int, default=11)
    a = ap.parse_args(argv)
    case = next(c for c in lc.CASES if c.name == a.case)
    b = lc.build(case, a.seed)
    dev = b["device"]
    kw = dict(lc.true_terms(dev, b["params"], b["effects"]))
    zero = np.zeros(dev.n_channels)
    if "offset_tc" in kw and "gain_tc" not in kw:
        kw.update(gain_tc=zero, temp_gain_tau_s=kw["temp_offset_tau_s"])
    if "gain_tc" in kw and "offset_tc" not in kw:
        kw.update(offset_tc=zero, temp_offset_tau_s=kw["temp_gain_tau_s"])
    cal = dataclasses.replace(lc.truth_calibration(dev, b["params"]), **kw)
    r = b["rec2"]
    y = correct_readings(cal, r.raw, r.temp_c, 1.0 / dev.sample_rate_hz, (dev.raw_min, dev.raw_max))
    e = np.rint(y) - y
    pose = np.asarray(r.pose)
    labels = [p for p in np.unique(pose) if p not in ("", None) and not (isinstance(p, (int, np.integer)) and p < 0)]
    means = np.array([e[pose == p].mean(axis=0) for p in labels])
    sds = np.array([e[pose == p].std(axis=0) for p in labels])
    n = np.median([(pose == p).sum() for p in labels])
    noise = case.noise_mps2 * np.linalg.norm(b["params"]["S"], axis=1)
    f = lambda v: "[" + ", ".join(f"{x:.3f}" for x in v) + "]"  # noqa: E731
    print(f"{a.case}, seed {a.seed}, recording 2, the true terms; counts per channel")
    print(f"hand-off error RMS {f(np.sqrt(np.mean(e ** 2, axis=0)))}")
    print(f"its mean within a pose, RMS over {len(labels)} poses {f(np.sqrt(np.mean(means ** 2, axis=0)))}")
    print(f"its sd within a pose (median) {f(np.median(sds, axis=0))}")
    print(f"the noise {f(noise)}; standard error of a pose's mean ({n:.0f} samples) {f(noise / np.sqrt(n))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
