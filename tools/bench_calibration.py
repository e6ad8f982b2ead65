#!/usr/bin/env python3
"""Accuracy and speed benchmark of accelcal.calibrate (issue 3).

Simulated data shaped like the seed prototype (default_device: 6 channels on an
r = 60 mm circle, 127.5 counts per m/s^2): per channel gain error uniform in
-0.7 ... +3.6 %, cross-axis sensitivity uniform in +-1.75 % of k on each of the
two axes across the nominal one, offsets uniform in +-28 % of g; white noise
0.02 m/s^2 rms, rounding to counts; 60 samples a pose.  Each trial draws a new
device.  Pose sets: 4 = +x, +y, +z, -z (the paper's example); 6 = +-x, +-y,
+-z; 12 and 24 = Fibonacci lattices on the sphere.  Jig-free needs at least 9
poses in general position (calibrate.checks.min_poses), so it has no 4- or 6-pose row.

Cramer-Rao bound: the Fisher information of the reading model itself, built
here independently of calibrate.py by central differences of
accelcal.model.predict_counts w.r.t. (b_i, s_i) and, for jig-free, two tangent
angles per pose; noise variance sigma^2 + 1/12 count^2 (rounding as uniform
noise).  Jig-free: the information restricted to the gauge (null space of the
linearised gauge constraint sum_i u_i x s_i/|s_i| = 0), and the truth rotated
into that gauge before errors are taken.

"param RMS / CRB" = sqrt(mean squared error) / sqrt(mean CRB variance), per
parameter group (offsets in counts, sensitivity components in counts per m/s^2)
over all channels and trials.  Post-calibration errors are in % of 1 g: offset
|db|/(k g); gain |s_hat|/|s| - 1; axis = angle between s_hat and s (x100).

Usage: python tools/bench_calibration.py [--trials N] [--quick]
Writes build/bench_calibration.md.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from tqdm import tqdm

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))

from accelcal import model  # noqa: E402
from accelcal.calibrate import (PoseSet, calibrate_recordings, fit_known_poses, fit_static,  # noqa: E402
                                gauge_rotation, poses_from_recording, static_force)
from accelcal.io.device import default_device  # noqa: E402
from accelcal.io.recording import recording_from_arrays  # noqa: E402
from accelcal.convert.xsens import load_xsens  # noqa: E402

sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
from shared_data import XSENS_ACC, SHARED_DATA  # noqa: E402

XSENS = SHARED_DATA.joinpath(*XSENS_ACC)  # the real recordings stay in ../shared/data
N_PER_POSE = 60


# ------------------------------------------------------------------ simulation
def draw_truth(dev, rng):
    N = dev.n_channels
    k = dev.counts_per_mps2
    g = dev.gravity_mps2
    gain = rng.uniform(-0.007, 0.036, N)
    cross = rng.uniform(-0.0175, 0.0175, (N, 3))
    cross -= np.sum(cross * dev.axes, axis=1, keepdims=True) * dev.axes      # across the axis only
    S = (k * (1 + gain))[:, None] * dev.axes + k[:, None] * cross
    b = dev.zero_counts + rng.uniform(-0.28, 0.28, N) * g * k
    return b, S


def fib_dirs(P):
    i = np.arange(P) + 0.5
    z = 1 - 2 * i / P
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)


POSE_SETS = {
    4: np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1.0]]),
    6: np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]]),
    12: fib_dirs(12),
    24: fib_dirs(24),
}


def random_rotations(P, deg, rng):
    """P rotation matrices by exactly ``deg`` degrees about random axes."""
    ax = rng.normal(size=(P, 3))
    ax /= np.linalg.norm(ax, axis=1, keepdims=True)
    th = np.radians(deg)
    K = np.zeros((P, 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -ax[:, 2], ax[:, 1], -ax[:, 0]
    K = K - K.transpose(0, 2, 1)
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def sample_poses(dev, b, S, F, rng, n=N_PER_POSE):
    """(P, n, N) raw readings: model + Gaussian noise, rounded and clipped."""
    sig = dev.noise_mps2 * dev.counts_per_mps2
    clean = model.predict_counts(b, S, dev.positions, F)
    x = clean[:, None, :] + rng.normal(size=(len(F), n, dev.n_channels)) * sig
    return np.clip(np.round(x), dev.raw_min, dev.raw_max)


def to_poseset(raw, F_ref=None):
    P, n, N = raw.shape
    return PoseSet(raw.mean(1), np.full(P, n), raw.std(1, ddof=1),
                   np.full((P, 3), np.nan) if F_ref is None else F_ref, np.full(P, np.nan),
                   [{"label": p} for p in range(P)])


# ------------------------------------------------------------------ Cramer-Rao bound
def _tangent(d):
    a = np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return np.stack([e1, np.cross(d, e1)], 1)


def crb(dev, b, S, F, jigfree, n=N_PER_POSE, prior_deg=0.0):
    """CRB covariance of the channel parameters [b_i, s_i] (N*4, N*4), by finite
    differences of model.predict_counts (independent of calibrate.py).

    ``prior_deg`` > 0 (known poses with a jig error): the bound for a jig whose
    poses are off by a random rotation of that rms angle, i.e. the Bayesian
    (Van Trees) bound: the pose directions are unknowns too (two tangent angles a
    pose, as jig-free) with the prior information 3/prior^2 (rad) on each angle,
    no gauge (the prior fixes the frame), in the jig's frame."""
    N = dev.n_channels
    P = len(F)
    g = np.linalg.norm(F, axis=1)
    d = F / g[:, None]
    T = _tangent(d)
    sig2 = (dev.noise_mps2 * dev.counts_per_mps2) ** 2 + 1 / 12

    free = jigfree or prior_deg > 0

    def fwd(th):
        c = th[:4 * N].reshape(N, 4)
        Fp = F
        if free:
            a = th[4 * N:].reshape(P, 2)
            v = d + np.einsum("pk,pkj->pj", a, T)
            Fp = g[:, None] * v / np.linalg.norm(v, axis=1, keepdims=True)
        return (model.predict_counts(c[:, 0], c[:, 1:], dev.positions, Fp) / np.sqrt(sig2)).ravel()

    th0 = np.concatenate([np.hstack([b[:, None], S]).ravel(), np.zeros(2 * P if free else 0)])
    J = np.empty((P * N, th0.size))
    for j in range(th0.size):
        h = 1e-6 * max(1.0, abs(th0[j]))
        tp, tm = th0.copy(), th0.copy()
        tp[j] += h
        tm[j] -= h
        J[:, j] = (fwd(tp) - fwd(tm)) / (2 * h)
    info = n * J.T @ J
    if prior_deg > 0 and not jigfree:
        info[4 * N:, 4 * N:] += np.eye(2 * P) * 3.0 / np.radians(prior_deg) ** 2
        return np.linalg.inv(info)[:4 * N, :4 * N]
    if not jigfree:
        return np.linalg.inv(info)

    def gauge(th):
        s = th[:4 * N].reshape(N, 4)[:, 1:]
        sh = s / np.linalg.norm(s, axis=1, keepdims=True)
        return np.sum(np.cross(dev.axes, sh), axis=0)

    C = np.empty((3, th0.size))
    for j in range(th0.size):
        h = 1e-6 * max(1.0, abs(th0[j]))
        tp, tm = th0.copy(), th0.copy()
        tp[j] += h
        tm[j] -= h
        C[:, j] = (gauge(tp) - gauge(tm)) / (2 * h)
    Z = np.linalg.svd(C)[2][3:].T
    cov = Z @ np.linalg.inv(Z.T @ info @ Z) @ Z.T
    return cov[:4 * N, :4 * N]


# ------------------------------------------------------------------ one study
def study(dev, P, jigfree, trials, rng, pose_err_deg=0.0, desc="", jig_accuracy_deg=0.0):
    """Monte Carlo: returns dict with RMS errors, CRB, ratios, post-cal % errors.
    ``jig_accuracy_deg``: the jig accuracy the known-pose fit is told (0: exact references)."""
    g = dev.gravity_mps2
    F_nom = g * POSE_SETS[P]
    errs_b, errs_s, crb_b, crb_s, crbj_b, crbj_s = [], [], [], [], [], []
    off_pct, gain_pct, axis_pct = [], [], []
    for _ in tqdm(range(trials), desc=desc, leave=False, file=sys.stderr):
        b, S = draw_truth(dev, rng)
        F_true = F_nom if pose_err_deg == 0 else np.einsum("pij,pj->pi", random_rotations(P, pose_err_deg, rng), F_nom)
        raw = sample_poses(dev, b, S, F_true, rng)
        if jigfree:
            fit = fit_static(dev, to_poseset(raw), jigfree=True)
            R = gauge_rotation(dev, S)
            S_ref, F_ref = S @ R.T, F_true @ R.T
        else:
            ps = to_poseset(raw, F_nom)
            fit = fit_known_poses(dev, ps.means, F_nom, "full", ps.sem(), poses=ps, jig_accuracy_deg=jig_accuracy_deg)
            S_ref, F_ref = S, F_true
        C = crb(dev, b, S_ref, F_ref, jigfree)
        var = np.diag(C).reshape(dev.n_channels, 4)
        if pose_err_deg > 0 and not jigfree:
            # the bound at the nominal poses (the true ones differ by the jig error: second order)
            Cj = crb(dev, b, S_ref, F_nom, False, prior_deg=pose_err_deg)
            vj = np.diag(Cj).reshape(dev.n_channels, 4)
            crbj_b.append(vj[:, 0])
            crbj_s.append(vj[:, 1:])
        errs_b.append(fit.offsets - b)
        errs_s.append(fit.sensitivity - S_ref)
        crb_b.append(var[:, 0])
        crb_s.append(var[:, 1:])
        k = dev.counts_per_mps2
        off_pct.append(np.abs(fit.offsets - b) / (k * g) * 100)
        ns, nt = np.linalg.norm(fit.sensitivity, axis=1), np.linalg.norm(S_ref, axis=1)
        gain_pct.append(np.abs(ns / nt - 1) * 100)
        cosang = np.sum(fit.sensitivity * S_ref, axis=1) / (ns * nt)
        axis_pct.append(np.arccos(np.clip(cosang, -1, 1)) * 100)
    eb, es = np.array(errs_b), np.array(errs_s)
    cb, cs = np.array(crb_b), np.array(crb_s)
    out = {
        "rms_b": np.sqrt(np.mean(eb ** 2)), "crb_b": np.sqrt(np.mean(cb)),
        "rms_s": np.sqrt(np.mean(es ** 2)), "crb_s": np.sqrt(np.mean(cs)),
    }
    out["ratio_b"] = out["rms_b"] / out["crb_b"]
    out["ratio_s"] = out["rms_s"] / out["crb_s"]
    if crbj_b:
        out["crbj_b"] = np.sqrt(np.mean(crbj_b))
        out["crbj_s"] = np.sqrt(np.mean(crbj_s))
        out["ratioj_b"] = out["rms_b"] / out["crbj_b"]
        out["ratioj_s"] = out["rms_s"] / out["crbj_s"]
    for name, arr in (("off", off_pct), ("gain", gain_pct), ("axis", axis_pct)):
        a = np.concatenate(arr)
        out[f"{name}_rms"] = float(np.sqrt(np.mean(a ** 2)))
        out[f"{name}_p95"] = float(np.percentile(a, 95))
        out[f"{name}_max"] = float(np.max(a))
    return out


# ------------------------------------------------------------------ recordings for timing
def long_recording(dev, b, S, F_true, n_total, rng, labelled):
    """A continuous recording of n_total samples: static poses joined by 1 s moves."""
    P = len(F_true)
    rate = dev.sample_rate_hz
    move = int(rate)
    hold = n_total // P - move
    sig = dev.noise_mps2 * dev.counts_per_mps2
    segs_f, pose = [], []
    for p in range(P):
        segs_f.append(np.repeat(F_true[p][None], hold, 0))
        pose.append(np.full(hold, p))
        q = F_true[(p + 1) % P]
        u = np.linspace(0, 1, move)[:, None]
        mv = (1 - u) * F_true[p] + u * q + 3.0 * np.sin(np.pi * u) * np.array([1.0, -1.0, 0.5])
        segs_f.append(mv)
        pose.append(np.full(move, -1))
    F = np.vstack(segs_f)[:n_total]
    pose = np.concatenate(pose)[:n_total]
    n = len(F)
    raw = model.predict_counts(b, S, dev.positions, F) + rng.normal(size=(n, dev.n_channels)) * sig
    raw = np.clip(np.round(raw), dev.raw_min, dev.raw_max).astype(np.int64)
    t = np.arange(n) / rate
    if labelled:
        f_ref = np.where((pose >= 0)[:, None], F, np.nan)
        return recording_from_arrays(t, raw, f=f_ref, pose=pose)
    return recording_from_arrays(t, raw)


# ------------------------------------------------------------------ main
def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--quick", action="store_true", help="60 trials (smoke run)")
    ap.add_argument("--seed", type=int, default=20240601)
    a = ap.parse_args(argv)
    trials = 60 if a.quick else a.trials
    rng = np.random.default_rng(a.seed)
    dev = default_device()
    lines: list[str] = []

    def emit(s=""):
        print(s)
        lines.append(s)

    emit("# accelcal calibration benchmark")
    emit()
    emit(f"Device: {dev.name} (N = {dev.n_channels}, k = {dev.counts_per_mps2[0]:.2f} counts per m/s^2, "
         f"noise {dev.noise_mps2} m/s^2); {N_PER_POSE} samples a pose; {trials} trials a row, a new "
         "device each trial (gain -0.7..+3.6 %, axis +-1.75 %, offsets +-28 % of g).")
    emit()
    emit("## Known poses (method full) and jig-free, exact poses")
    emit()
    hdr = ("| method | poses | offset RMS err [counts] | offset CRB | ratio | sens RMS err [counts/(m/s^2)] "
           "| sens CRB | ratio | offset err % g (rms / p95 / max) | gain err % (rms / p95 / max) "
           "| axis err % (rms / p95 / max) |")
    emit(hdr)
    emit("|" + "---|" * 11)

    def row(name, P, r):
        emit(f"| {name} | {P} | {r['rms_b']:.4f} | {r['crb_b']:.4f} | {r['ratio_b']:.3f} | {r['rms_s']:.5f} "
             f"| {r['crb_s']:.5f} | {r['ratio_s']:.3f} | {r['off_rms']:.4f} / {r['off_p95']:.4f} / {r['off_max']:.4f} "
             f"| {r['gain_rms']:.4f} / {r['gain_p95']:.4f} / {r['gain_max']:.4f} "
             f"| {r['axis_rms']:.4f} / {r['axis_p95']:.4f} / {r['axis_max']:.4f} |")

    for P in (4, 6, 24):
        row("known-pose full", P, study(dev, P, False, trials, rng, desc=f"known {P}"))
    for P in (12, 24):
        row("jig-free full", P, study(dev, P, True, trials, rng, desc=f"jigfree {P}"))
    emit()
    emit("## Pose errors: every pose off by the given angle about a random axis (24 poses)")
    emit()
    emit("Known-pose uses the nominal pose directions; jig-free ignores them.  Ratio = RMS error / the "
         "method's own noise-only CRB.  \"jig accuracy stated\": fit_known_poses(..., jig_accuracy_deg=...) "
         "told the true pose error (the pose directions estimated jointly, the references as priors of that "
         "accuracy); the last rows state 0.5 deg for a perfect jig (the cost of a nonzero default).  \"jig "
         "CRB\": the bound for a jig whose poses are off by a random rotation of the given rms angle (the "
         "Bayesian bound with that prior on the pose directions, in the jig's frame): no estimator that is "
         "told the jig's accuracy can do better on average; n/a for jig-free (own gauge) and for a perfect jig "
         "(the bound is the CRB).")
    emit()
    emit("| pose error | method | offset RMS err | ratio to CRB | ratio to jig CRB | sens RMS err | ratio to CRB "
         "| ratio to jig CRB | offset err % g (rms / max) | gain err % (rms / max) | axis err % (rms / max) |")
    emit("|" + "---|" * 11)

    def jrow(tag, name, r):
        jb = f"{r['ratioj_b']:.2f}" if "ratioj_b" in r else "n/a"
        js = f"{r['ratioj_s']:.2f}" if "ratioj_s" in r else "n/a"
        emit(f"| {tag} | {name} | {r['rms_b']:.4f} | {r['ratio_b']:.2f} | {jb} | {r['rms_s']:.5f} "
             f"| {r['ratio_s']:.2f} | {js} | {r['off_rms']:.4f} / {r['off_max']:.4f} "
             f"| {r['gain_rms']:.4f} / {r['gain_max']:.4f} | {r['axis_rms']:.4f} / {r['axis_max']:.4f} |")

    for deg in (0.5, 1.0, 2.0):
        # the stated-jig-accuracy row draws from its own generator, so the other rows are as before
        for name, jf, jig, r_ in (("known-pose full", False, 0.0, rng), ("jig-free full", True, 0.0, rng),
                                  (f"known-pose full, jig accuracy {deg:g} deg stated", False, deg,
                                   np.random.default_rng(a.seed + int(10 * deg)))):
            r = study(dev, 24, jf, trials, r_, pose_err_deg=deg, desc=f"{name} {deg} deg", jig_accuracy_deg=jig)
            jrow(f"{deg:.1f} deg", name, r)
    # the cost of stating a jig accuracy for a perfect jig (own generator, as above)
    for P in (6, 24):
        r = study(dev, P, False, trials, np.random.default_rng(a.seed + 100 + P), desc=f"perfect jig, 0.5 stated, {P}",
                  jig_accuracy_deg=0.5)
        jrow(f"0 deg ({P} poses)", "known-pose full, jig accuracy 0.5 deg stated", r)

    # ---------------- Xsens
    emit()
    emit("## Real data: imu_tk Xsens recording (jig-free)")
    emit()
    xdev, xrec = load_xsens(XSENS)
    ps = poses_from_recording(xrec, xdev)
    g = xdev.gravity_mps2

    def norm_rms(b, S, idx=None):
        f = static_force(b, S, ps.means)
        e = np.linalg.norm(f, axis=1) - g
        return float(np.sqrt(np.mean(e ** 2))), float(np.max(np.abs(e)))

    full = fit_static(xdev, ps, "full", jigfree=True)
    gain = fit_static(xdev, ps, "gain", jigfree=True)
    # seed doc 2, 3-pose: the detected poses nearest +x, +y, +z, assumed exactly aligned
    f_nom = static_force(xdev.nominal_offsets(), xdev.nominal_sensitivity(), ps.means)
    fh = f_nom / np.linalg.norm(f_nom, axis=1, keepdims=True)
    pick = [int(np.argmax(fh[:, k])) for k in range(3)]
    three = fit_known_poses(xdev, ps.means[pick], g * np.eye(3), "gain")
    off_axis = [float(np.degrees(np.arccos(np.clip(fh[p, k], -1, 1)))) for k, p in enumerate(pick)]
    # leave-one-pose-out check of the full jig-free model
    loo = []
    for p in tqdm(range(ps.n_poses), desc="xsens leave-one-out", leave=False, file=sys.stderr):
        keep = np.arange(ps.n_poses) != p
        sub = PoseSet(ps.means[keep], ps.n[keep], ps.std[keep], ps.f_ref[keep], ps.temp[keep],
                      [ps.info[i] for i in np.flatnonzero(keep)])
        fp = fit_static(xdev, sub, "full", jigfree=True)
        f = static_force(fp.offsets, fp.sensitivity, ps.means[p:p + 1])
        loo.append(np.linalg.norm(f) - g)
    loo = np.array(loo)
    noise = ps.channel_noise()
    emit(f"Static poses detected: {ps.n_poses} (samples a pose {int(ps.n.min())}..{int(ps.n.max())}; "
         f"noise estimated from the data {np.round(noise, 2).tolist()} counts).  Nominal scale "
         f"{xdev.counts_per_mps2[0]} counts per m/s^2, g = {g}.")
    emit()
    emit("| model (same poses) | params | RMS(abs(f) - g) [m/s^2] | max abs [m/s^2] | chi2/dof |")
    emit("|---|---|---|---|---|")
    r, mx = norm_rms(full.offsets, full.sensitivity)
    emit(f"| jig-free full (offset + sensitivity vector) | 9 + 2/pose | {r:.5f} | {mx:.5f} | {full.chi2 / full.dof:.1f} |")
    emit(f"| same, leave-one-pose-out | | {np.sqrt(np.mean(loo ** 2)):.5f} | {np.max(np.abs(loo)):.5f} | |")
    r, mx = norm_rms(gain.offsets, gain.sensitivity)
    emit(f"| jig-free offset + gain (3-pose model) | 6 + 2/pose | {r:.5f} | {mx:.5f} | {gain.chi2 / gain.dof:.1f} |")
    r, mx = norm_rms(three.offsets, three.sensitivity)
    emit(f"| seed 3-pose formula on the poses nearest +x, +y, +z (poses {pick}, "
         f"{', '.join(f'{a:.1f}' for a in off_axis)} deg off the axes) | 6 | {r:.5f} | {mx:.5f} | |")
    emit()
    emit("Jig-free full result (counts; sensitivity in counts per m/s^2, gauge: Procrustes to the nominal axes):")
    emit()
    for i in range(3):
        emit(f"- channel {i}: b = {full.offsets[i]:.2f} +- {full.offset_sigma[i]:.2f}, "
             f"s = [{', '.join(f'{v:.3f}' for v in full.sensitivity[i])}] +- "
             f"[{', '.join(f'{v:.3f}' for v in full.sensitivity_sigma[i])}]")

    # ---------------- timing
    emit()
    emit("## Speed: 1,000,000-sample 6-channel recording (in memory, warm process)")
    emit()
    tb, tS = draw_truth(dev, rng)
    emit("| recording | poses found | calibrate_recordings, in memory [s] | CLI end to end [s] | of which CSV read [s] |")
    emit("|---|---|---|---|---|")
    import subprocess
    import tempfile
    from accelcal.io.device import save_device
    from accelcal.io.recording import read_recording, write_recording
    with tempfile.TemporaryDirectory() as tmp:
        dev_path = os.path.join(tmp, "dev.json")
        save_device(dev, dev_path)
        for labelled in (True, False):
            rec = long_recording(dev, tb, tS, dev.gravity_mps2 * POSE_SETS[24], 1_000_000, rng, labelled)
            calibrate_recordings(dev, [rec])  # warm-up (imports, caches)
            best = np.inf
            for _ in range(3):
                t0 = time.perf_counter()
                cal = calibrate_recordings(dev, [rec])
                best = min(best, time.perf_counter() - t0)
            csv = os.path.join(tmp, "rec.csv")
            write_recording(csv, rec)
            t0 = time.perf_counter()
            read_recording(csv, dev.n_channels)
            t_read = time.perf_counter() - t0
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "accelcal.cli.main", "calibrate", "--device", dev_path, csv,
                            "-o", os.path.join(tmp, "cal.json")], check=True)
            t_cli = time.perf_counter() - t0
            kind = "labelled poses + f reference (known poses)" if labelled else "no reference (detection + jig-free)"
            emit(f"| {kind} | {len(cal.poses_used)} | {best:.3f} | {t_cli:.2f} | {t_read:.2f} |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    emit()
    emit(f"(machine: {os.cpu_count()} cores, load average {load:.1f} when measured)")
    os.makedirs(os.path.join(ROOT, "build"), exist_ok=True)
    out = os.path.join(ROOT, "build", "bench_calibration.md")
    with open(out, "w", encoding="utf-8") as f:
        f.write("\n".join(lines) + "\n")
    print(f"\nwritten {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
