#!/usr/bin/env python3
"""Angular rate from the accelerometers (docs/angular-rate.md): the estimators against the
per-sample Cramer-Rao bound, in bands of |omega|.

Cases from the independent generator (tests/python/indep_model.py, make_spin_array):
back-to-back quintic turns about random axes with peak rates drawn log-uniformly in
0.3-40 rad/s (each turn crosses every |omega| below its peak), the origin moving 2-10 cm per
turn, true channel parameters drawn about the nominal (offsets, gains, axes off by up to
1.5 deg), white noise of the device's 0.01 m/s^2 rms, rounding to counts; the estimators are
given the true calibration and the device's noise.

Per band of the true |omega| (rad/s):
* CRB: sqrt of the mean trace of the per-sample Cramer-Rao bound of omega from one sample's
  readings ([f; alpha] unknown), at the true omega;
* ML: the accelerometers' maximum-likelihood omega alone (per sample, no time);
* fused: the estimate of ``resolve --omega array`` (ML fused with the integrated alpha), its
  RMS and the ratio to the CRB and to the posterior CRB of the fused problem (the recursion
  J[n] = ((J[n-1])^-1 + dt^2 Sigma_alpha)^-1 + I(omega[n]) at the true omega: the bound for an
  estimator that also has the integrated alpha);
* wrong sign: share of samples whose fused omega points away from the truth (omega . truth < 0);
* fixed: ``resolve --engine fixed --omega array``, the integer C core (ac_omega.h) on the table
  ``accelcal header`` writes (layouts that fix all six rate products; "-" otherwise), its RMS,
  ratio to the CRB and wrong sign;
* integration: the trapezoid integration of alpha from rest, each alpha resolved with the
  centripetal term of the TRUE omega (an oracle: the best the integration can do; with its own
  integrated omega in the centripetal term instead the integration diverges on these layouts
  within seconds, the alpha error growing with omega^2);
* rate: ``accelcal rate`` (leaky integration of alpha, tau 5 s, reset on rest, alpha resolved
  without the centripetal term, as that command does with no w columns);
* gyro: a gyro of 0.014 deg/s/sqrt(Hz) (a BMI088-class MEMS gyro) read at the same rate with
  a bandwidth of half of it: sqrt(3) x its per-axis sd (it saturates at 2000 deg/s = 35 rad/s).

Usage: python3 tools/bench_omega.py [--seeds 5] [--turns 20] [--jobs 1]
Writes build/bench_omega.md and prints it.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "python"), str(ROOT / "tests" / "python")]
from accelcal import model  # noqa: E402
from accelcal.io.device import axes_device, tetrahedron_device  # noqa: E402
from accelcal.calibrate import calibrate_recordings  # noqa: E402
from accelcal.errors import InputError  # noqa: E402
from accelcal.estimators import omega_crb, omega_fixed_from_recording, omega_from_recording, rate_from_recording  # noqa: E402
import indep_model as im  # noqa: E402

BANDS = ((0.0, 1.0), (1.0, 3.0), (3.0, 10.0), (10.0, 30.0), (30.0, math.inf))
GYRO_DPS_RTHZ = 0.014
# name -> (device, calibrated): calibrated cases give the estimators the calibration that
# `calibrate` makes from a session of the 18 jig poses and 12 reference turns (make_array_calibration,
# its own seed) instead of the truth; the bounds stay the truth's
CASES = {"tetrahedron 12 ch, r = 50 mm": (lambda: tetrahedron_device(0.05), False),
         "tetrahedron, calibrated (poses + turns)": (lambda: tetrahedron_device(0.05), True),
         "axes + origin 12 ch, r = 50 mm": (lambda: axes_device(0.05), False),
         "axes 9 ch, r = 50 mm": (lambda: axes_device(0.05, origin=False), False)}
KEYS = ("n", "crb", "ml", "fused", "pcrb", "wrong", "integ", "rate", "gyro", "fixed", "fwrong")


def posterior_bound(m, Q, w, sigma0=0.01) -> np.ndarray:
    """Trace of the posterior CRB per sample (see the module's text)."""
    info = model.omega_information(m, w)
    J = np.eye(3) / sigma0 ** 2
    out = np.empty(len(w))
    for k in range(len(w)):
        J = (np.linalg.inv(np.linalg.inv(J) + Q) if k else J) + info[k]
        out[k] = np.trace(np.linalg.inv(J))
    return out


def one(args) -> dict:
    name, seed, turns = args
    make, calibrated = CASES[name]
    dev = make()
    d = im.make_spin_array(dev, seed, n_turns=turns)
    rec, cal, w = d["recording"], d["cal"], d["w"]
    used = cal
    if calibrated:    # the same true parameters (make_spin_array's seed) seen through a calibration session
        sess = im.make_array_calibration(dev, seed, rotations=True, true_params=d["params"])
        used = calibrate_recordings(dev, [sess["recording"]])
    t0 = time.perf_counter()
    est = omega_from_recording(dev, used, rec)
    secs = time.perf_counter() - t0
    try:    # the C core on the header's table (layouts that fix all six rate products)
        w_fix = omega_fixed_from_recording(dev, used, rec).w
    except InputError:
        w_fix = np.full_like(w, np.nan)
    rate = rate_from_recording(dev, used, rec)
    w_rate = np.stack([rate["w_x"], rate["w_y"], rate["w_z"]], axis=1)
    noise = np.sqrt((dev.noise_mps2 * np.linalg.norm(cal.sensitivity, axis=1)) ** 2 + 1.0 / 12.0)
    split = model.centripetal_split(cal.positions_or_nominal(dev), cal.sensitivity, noise)
    dt = 1.0 / d["rate_hz"]
    alpha = model.resolve(cal.offsets, cal.sensitivity, cal.positions_or_nominal(dev), rec.raw, w)[1]
    integ = np.vstack([np.zeros(3), np.cumsum((alpha[1:] + alpha[:-1]) * (dt / 2.0), axis=0)])
    crb = np.trace(omega_crb(split.m, w), axis1=1, axis2=2)
    pcrb = posterior_bound(split.m, dt * dt * split.cov[3:, 3:], w)
    gyro = 3.0 * (math.radians(GYRO_DPS_RTHZ) * math.sqrt(d["rate_hz"] / 2.0)) ** 2
    mag = np.linalg.norm(w, axis=1)
    out = {"secs": secs, "samples": len(w)}
    for b, (lo, hi) in enumerate(BANDS):
        s = (mag >= lo) & (mag < hi)
        out[b] = {"n": int(s.sum()), "crb": float(np.sum(crb[s])),
                  "ml": float(np.sum((est.w_ml[s] - w[s]) ** 2)), "fused": float(np.sum((est.w[s] - w[s]) ** 2)),
                  "pcrb": float(np.sum(pcrb[s])), "wrong": int(np.sum(np.sum(est.w[s] * w[s], axis=1) < 0.0)),
                  "integ": float(np.sum((integ[s] - w[s]) ** 2)), "rate": float(np.sum((w_rate[s] - w[s]) ** 2)), "gyro": gyro * float(s.sum()),
                  "fixed": float(np.sum((w_fix[s] - w[s]) ** 2)), "fwrong": int(np.sum(np.sum(w_fix[s] * w[s], axis=1) < 0.0))}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--turns", type=int, default=20)
    ap.add_argument("--jobs", type=int, default=1)
    a = ap.parse_args(argv)
    jobs = [(name, seed, a.turns) for name in CASES for seed in range(1, a.seeds + 1)]
    with ProcessPoolExecutor(a.jobs) as ex:
        results = list(ex.map(one, jobs))
    lines = [f"Angular rate from the accelerometers: `python3 tools/bench_omega.py --seeds {a.seeds} --turns {a.turns}` "
             f"({a.seeds} recordings of {a.turns} turns per case, 500 Hz, 0.01 m/s^2 rms per channel). RMS of the "
             "vector error, rad/s.", "",
             "| case | abs(omega) rad/s | samples | CRB | ML | ML / CRB | fused | fused / CRB | fused / posterior CRB "
             "| wrong sign | fixed (C core) | fixed / CRB | fixed wrong sign | integration | accelcal rate "
             "| gyro 0.014 deg/s/rtHz |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name in CASES:
        mine = [r for (nm, _, _), r in zip(jobs, results) if nm == name]
        secs = sum(r["secs"] for r in mine) / sum(r["samples"] for r in mine)
        for b, (lo, hi) in enumerate(BANDS):
            tot = {k: sum(r[b][k] for r in mine) for k in KEYS}
            n = max(tot["n"], 1)
            rm = {k: math.sqrt(tot[k] / n) for k in ("crb", "ml", "fused", "pcrb", "integ", "rate", "gyro", "fixed")}
            band = f"{lo:g}-{hi:g}" if math.isfinite(hi) else f">= {lo:g}"
            ratio = (lambda x: f"{x / rm['crb']:.3g}") if math.isfinite(rm["crb"]) and b else (lambda x: "-")
            crb = f"{rm['crb']:.3g}" if math.isfinite(rm["crb"]) and b else "inf"
            fixed = (f"{rm['fixed']:.3g} | {ratio(rm['fixed'])} | {100.0 * tot['fwrong'] / n:.3g} %"
                     if math.isfinite(rm["fixed"]) else "- | - | -")
            lines.append(f"| {name} | {band} | {tot['n']} | {crb} | {rm['ml']:.3g} | {ratio(rm['ml'])} | "
                         f"{rm['fused']:.3g} | {ratio(rm['fused'])} | {rm['fused'] / rm['pcrb']:.3g} | "
                         f"{100.0 * tot['wrong'] / n:.3g} % | {fixed} | {rm['integ']:.3g} | {rm['rate']:.3g} | {rm['gyro']:.3g} |")
        lines.append(f"| {name} | float time | | | | | {1e6 * secs:.0f} us per sample | | | | | | | | | |")
    text = "\n".join(lines) + "\n"
    (ROOT / "build").mkdir(exist_ok=True)
    (ROOT / "build" / "bench_omega.md").write_text(text, encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
