#!/usr/bin/env python3
"""The check on withheld effects (issue 4): does the diagnosis name the effect that is in
the data but not in the model, and does it say how much of the gap it explains?

For each effect of the registry (and for none), many datasets are simulated, each with
a random device, a random true calibration (the seed's Table 1 spreads), a random noise
level, a random motion and a random effect magnitude; the model is the true calibration
(so the effect is the only thing the model lacks); the diagnosis runs on the recording.

Dataset = one simulation of a trajectory laid out as: a jig part (static poses with pose
labels and the stated f) followed, after a 1 s gap, by a motion (rate table, pendulum,
random 6-DOF, hand-held, lane change, linear actuator), given as one recording (50 %) or as
two (jig, motion: 20 %); the motion alone (15 %); the jig alone (15 %, not for the effects
that show only while moving).  The parts keep the motions' exact evaluators (the jig held
in each pose around its samples), so time shifts are exact.
Temperature: a sine over the recording for temperature effects, else constant 25 degC in
70 % of the datasets and a sine in 30 % (so the temperature candidates also face data
without the effect).  Devices: the seed's 6-channel r = 60 mm prototype, a 16-bit triad,
the two-triad pendulum device, random arrays of 3 or 4 rotated triads.

Magnitude: a target contribution ratio rho, log-uniform in [RHO_LO, RHO_HI] (stratified: the
k-th dataset of an effect draws from the k-th of equal slices); the effect's
size parameter is scaled to it from a pilot simulation (effects that are not linear in
their size are drawn directly).  Definitions (on all samples):

* noise floor = sqrt(mean_i(sigma_i^2 + 1/12)) counts, sigma_i the simulated noise;
* contribution = RMS(pred_true - pred_base), pred_base = the diagnosis' model (true
  calibration driven by the recorded reference), pred_true = the noise-free readings with
  the effect (the simulator's clean counts; for saturation/quantization the registry's
  clip/rounding of them; for pose_error the clean counts from the true f);
  rho = contribution / noise floor;
* true shrink = 1 - RMS(raw - pred_true) / RMS(raw - pred_base).

Reported: confusion matrix (truth rows, verdict columns), top-1 accuracy (all, rho >= 3),
false-positive rate on none, |estimated - true shrink| (the true effect's entry, alone),
parameter errors against the truth, the time to diagnose 100,000 samples x 12
channels with every candidate, and the diagnosis of the real Xsens recording (jig-free) with
three models: its own jig-free calibration, a calibration from the first half applied to the
second, and the nominal calibration.

Usage: python tools/bench_diagnose.py [--per-effect N] [--per-none M] [--quick] [--seed S] [--jobs J]
       [--effects a,b,...] [--no-timing] [--rows ROWS.json] [-o OUT.md]
Writes build/bench_diagnose.md.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))

from accelcal.device import Device, default_device, default_triad, pendulum_device  # noqa: E402
from accelcal.effects import EFFECT_NAMES, EFFECTS, random_walk  # noqa: E402
from accelcal.motions import MOTIONS, Kinematics, Trajectory, temperature_profile  # noqa: E402
from accelcal.sensor import evaluate, rotation_matrix, true_state  # noqa: E402
from accelcal.simulate import run_simulation, seed_prototype_truth  # noqa: E402
from accelcal.spec import format_spec  # noqa: E402

LABELS = tuple(EFFECT_NAMES) + ("none",)
RHO_LO, RHO_HI = 0.05, 30.0
GAP_S = 1.0


# ------------------------------------------------------------------ devices, motions
def random_array(rng: np.random.Generator, n_triads: int) -> Device:
    pos, axes = [], []
    for _ in range(n_triads):
        d = rng.standard_normal(3)
        d /= np.linalg.norm(d)
        p = d * rng.uniform(0.03, 0.12)
        R = rotation_matrix(rng.standard_normal(3))
        for k in range(3):
            pos.append(p)
            axes.append(R[:, k])
    N = 3 * n_triads
    k = rng.uniform(100.0, 2000.0)
    return Device(name=f"array-{N}ch", sample_rate_hz=float(rng.choice([50.0, 100.0, 200.0])), gravity_mps2=9.80665,
                  raw_min=0, raw_max=65535, positions=np.array(pos), axes=np.array(axes),
                  counts_per_mps2=np.full(N, k), zero_counts=np.full(N, 32768.0), noise_mps2=0.01)


def random_device(rng: np.random.Generator, need_lever: bool = False) -> Device:
    kinds = ["seed", "array3", "array4", "pendulum"] + ([] if need_lever else ["triad"])
    kind = kinds[int(rng.integers(len(kinds)))]
    if kind == "seed":
        dev = default_device()
    elif kind == "triad":
        dev = default_triad()
    elif kind == "pendulum":
        dev = pendulum_device(rng.uniform(0.05, 0.15), rng.uniform(0.2, 0.4))
    else:
        dev = random_array(rng, 3 if kind == "array3" else 4)
    # noise: 0.5 .. 3 counts rms (at least a few counts of dynamic range per noise sigma)
    k = float(np.mean(dev.counts_per_mps2))
    noise_counts = rng.uniform(0.7, 3.0)
    return Device(name=dev.name, sample_rate_hz=dev.sample_rate_hz, gravity_mps2=dev.gravity_mps2,
                  raw_min=dev.raw_min, raw_max=dev.raw_max, positions=dev.positions, axes=dev.axes,
                  counts_per_mps2=dev.counts_per_mps2, zero_counts=dev.zero_counts, noise_mps2=noise_counts / k)


class _Concat:
    """Evaluator of trajectories laid end to end (time offsets), for exact time shifts.

    A part made only of static poses with unrecorded jig moves between them (static_poses,
    random_poses: their evaluators jump to the next pose right after a pose's last sample) is
    held in each pose: a query time is clamped to the sample times of the pose of the nearest
    sample, so a time-skewed channel sees the pose, not the unrecorded jump."""

    def __init__(self, parts, offsets, ends):
        self.parts, self.offsets, self.ends = parts, offsets, ends
        self.hold = []
        for tr in parts:
            if np.all(tr.pose >= 0):
                lab = tr.pose
                brk = np.flatnonzero(np.r_[True, lab[1:] != lab[:-1]])
                ends = np.append(brk[1:], len(tr.t)) - 1
                seg = np.repeat(np.arange(brk.size), np.diff(np.append(brk, len(tr.t))))
                self.hold.append((tr.t, tr.t[brk][seg], tr.t[ends][seg]))
            else:
                self.hold.append(None)

    def __call__(self, times, position=False):
        times = np.asarray(times, float)
        which = np.searchsorted(self.ends, times, side="left")
        which = np.clip(which, 0, len(self.parts) - 1)
        out = None
        for k, (tr, off) in enumerate(zip(self.parts, self.offsets)):
            m = which == k
            if not m.any():
                continue
            tq = times[m] - off
            if self.hold[k] is not None:
                ts, lo, hi = self.hold[k]
                j = np.clip(np.searchsorted(ts, tq), 1, ts.size - 1)
                j = np.where(np.abs(ts[j - 1] - tq) <= np.abs(ts[j] - tq), j - 1, j)
                tq = np.clip(tq, lo[j], hi[j])
            kin = tr.evaluator(tq, position=False)
            if out is None:
                out = [np.zeros((times.size, 3, 3)), None, np.zeros((times.size, 3)), np.zeros((times.size, 3)),
                       np.zeros((times.size, 3))]
            out[0][m] = kin.attitude
            out[2][m] = kin.f
            out[3][m] = kin.omega
            out[4][m] = kin.alpha
        return Kinematics(out[0], None, out[2], out[3], out[4])


def concat(trajs: list[Trajectory], gap_s: float, g: float) -> Trajectory:
    ts, offs, ends, poses = [], [], [], []
    t0 = 0.0
    lab0 = 0
    for tr in trajs:
        off = t0 - tr.t[0]
        ts.append(tr.t + off)
        offs.append(off)
        p = tr.pose.copy()
        p[p >= 0] += lab0
        lab0 = int(p.max()) + 1 if np.any(p >= 0) else lab0
        poses.append(p)
        t0 = ts[-1][-1] + gap_s
        ends.append(ts[-1][-1] + gap_s / 2)
    ev = _Concat(trajs, offs, np.array(ends[:-1] + [math.inf]))
    t = np.concatenate(ts)
    return Trajectory(t=t, attitude=np.concatenate([tr.attitude for tr in trajs]),
                      f=np.concatenate([tr.f for tr in trajs]), omega=np.concatenate([tr.omega for tr in trajs]),
                      alpha=np.concatenate([tr.alpha for tr in trajs]), pose=np.concatenate(poses),
                      temp_c=np.full(t.size, 25.0), gravity_mps2=g, name="bench", evaluator=ev)


MOTION_EFFECTS = ("position_error", "centripetal", "time_skew", "bandwidth")   # show only while moving
ROTATION_EFFECTS = ("position_error", "centripetal")                             # need rotation


def random_motion(dev: Device, rng: np.random.Generator, effect: str) -> tuple[Trajectory, str]:
    """A trajectory and its layout: 'jig+motion' (one recording), 'split' (the same, given as two
    recordings: jig, motion), 'motion' (motion only) or 'jig' (static poses only)."""
    g = dev.gravity_mps2
    rate = dev.sample_rate_hz
    u = rng.random()
    layout = "jig+motion" if u < 0.5 else "split" if u < 0.7 else "motion" if u < 0.85 else "jig"
    if layout == "jig" and effect in MOTION_EFFECTS:
        layout = "jig+motion"
    kinds = ["rate_table", "pendulum", "random_6dof", "handheld", "lane_change", "linear_actuator"]
    if effect in ROTATION_EFFECTS:
        kinds = ["rate_table", "pendulum", "random_6dof", "handheld"]
    if layout == "motion" and effect == "pose_error":
        kinds = ["handheld"]                      # the only motion with labelled static poses
    kind = kinds[int(rng.integers(len(kinds)))]
    parts = []
    if layout != "motion":
        if rng.random() < 0.5:
            parts.append(MOTIONS["static_poses"](dev, rng, poses=str(rng.choice(["6", "18", "24", "26"])),
                                                 samples_per_pose=int(rng.integers(30, 80))))
        else:
            parts.append(MOTIONS["random_poses"](dev, rng, n_poses=int(rng.integers(8, 20)),
                                                 samples_per_pose=int(rng.integers(30, 80))))
    if layout != "jig":
        dur = float(rng.uniform(6.0, 12.0)) * (60.0 / rate) ** 0.5
        if kind == "rate_table":
            ax = rng.standard_normal(3)
            mv = MOTIONS["rate_table"](dev, rng, axis=ax / np.linalg.norm(ax), freq_hz=float(rng.uniform(0.5, 2.5)),
                                       amplitude_deg=float(rng.uniform(10, 45)), duration_s=dur,
                                       mount=_random_unit(rng), ramp_s=0.5, rest_s=float(rng.choice([0.0, 1.0])))
        elif kind == "pendulum":
            mv = MOTIONS["pendulum"](dev, rng, amplitude_deg=float(rng.uniform(15, 50)),
                                     freq_hz=float(rng.uniform(0.4, 1.5)), duration_s=dur,
                                     center_deg=float(rng.uniform(-30, 30)))
        elif kind == "random_6dof":
            mv = MOTIONS["random_6dof"](dev, rng, duration_s=dur, bandwidth_hz=float(rng.uniform(0.5, 2.0)),
                                        angle_rms_deg=float(rng.uniform(10, 40)),
                                        accel_rms_mps2=float(rng.uniform(0.3, 2)))
        elif kind == "handheld":
            mv = MOTIONS["handheld"](dev, rng, n_poses=int(rng.integers(3, 6)), hold_s=1.0, move_s=1.0,
                                     initial_rest_s=1.0)
        elif kind == "lane_change":
            mv = MOTIONS["lane_change"](dev, rng, speed_mps=float(rng.uniform(10, 20)))
        else:
            ax = _random_unit(rng)
            mv = MOTIONS["linear_actuator"](dev, rng, axis=ax, distance_m=float(rng.uniform(0.1, 0.5)),
                                            travel_s=float(rng.uniform(0.5, 1.5)), rest_s=1.0,
                                            strokes=int(rng.integers(2, 5)), tilt_deg=float(rng.uniform(0, 30)),
                                            tilt_axis=_random_unit(rng))
        parts.append(mv)
    tr = concat(parts, GAP_S, g)
    tr.params = {"layout": layout, "motion": kind if layout != "jig" else "-",
                 "jig": parts[0].name if layout != "motion" else "-"}
    temp_effect = effect.startswith("temperature")
    if temp_effect or rng.random() < 0.3:
        T = tr.t[-1] - tr.t[0]
        tr.temp_c = temperature_profile(tr.t, "sine", temp_c=float(25 + rng.uniform(-8, 8)),
                                        temp_amplitude_c=float(rng.uniform(3, 15)),
                                        temp_period_s=float(T / rng.uniform(0.7, 2.5)))
    return tr, layout


def _random_unit(rng):
    v = rng.standard_normal(3)
    return v / np.linalg.norm(v)


# ------------------------------------------------------------------ effects
def _fmt(v):
    return [float(x) for x in np.asarray(v, float)]


def effect_spec(name: str, m: float, z: np.ndarray, aux: dict) -> tuple[str, dict]:
    """Spec (name, params) of size m with per-channel normal draws z."""
    if name == "offset":
        return name, {"db": _fmt(m * z)}
    if name == "gain":
        return name, {"scale": _fmt(m * z)}
    if name == "misalignment":
        return name, {"angle_deg": _fmt(m * np.abs(z))}
    if name == "position_error":
        return name, {"mm": _fmt(m * np.abs(z))}
    if name == "centripetal":
        return name, {"scale": float(1.0 - min(m, 1.0))}
    if name == "time_skew":
        return name, {"tau": _fmt(m * z)}
    if name == "bandwidth":
        d = m * aux["u"]
        return name, {"fc_hz": _fmt(1.0 / (2 * math.pi * d))}
    if name == "nonlinearity":
        return name, {"k2": _fmt(m * z)}
    if name in ("temperature_offset", "temperature_gain"):
        return name, {"coeff": _fmt(m * z)}
    if name == "bias_drift":
        if aux.get("walk"):  # a random walk (rw counts/sqrt(s)) instead of a ramp
            return name, {"rate": _fmt(0.0 * z), "rw": _fmt(m * np.abs(z))}
        return name, {"rate": _fmt(m * z)}
    if name == "pose_error":
        return name, {"angle_deg": float(m)}
    raise KeyError(name)


REF_SIZE = {"offset": 1.0, "gain": 1e-3, "misalignment": 0.1, "position_error": 1.0, "centripetal": 1.0,
            "time_skew": 1e-3, "bandwidth": 1e-3, "nonlinearity": 0.01, "temperature_offset": 0.1,
            "temperature_gain": 1e-5, "bias_drift": 0.05, "pose_error": 0.1}


def _pred_base(dev, cal, rec):
    traj = Trajectory.from_recording(rec, dev.gravity_mps2)
    st = true_state(dev, cal, None)
    return np.clip(evaluate(traj, st), dev.raw_min, dev.raw_max)


def _pred_true(dev, sim, name):
    """The readings the true effect predicts from the clean ones.  Quantization: its expected
    error given the simulated noise before the quantiser (the best prediction there is; the
    noise-free sawtooth overstates it once the step is within a few noise floors)."""
    clean = sim.clean_counts
    if name == "saturation":
        clean = EFFECTS[name].apply_signal(clean, sim.effects[name], sim.context)
    elif name == "quantization":
        step = np.broadcast_to(np.asarray(sim.effects[name]["step"], float), (dev.n_channels,))
        clean = clean + EFFECTS[name].expected_error(clean, step, np.zeros(dev.n_channels), dev.noise_counts())
    return np.clip(clean, dev.raw_min, dev.raw_max)


def _quantization_step(clean, sigma, target):
    """The smallest step (>= 2 counts) whose predictable error, the expected error of the
    quantiser given the noise before it, has rms >= target on the clean readings (bisection:
    it grows with the step, towards step / sqrt(12) once the noise no longer dithers)."""
    N = clean.shape[1]
    eff = EFFECTS["quantization"]

    def contrib(q):
        return float(np.sqrt(np.mean(eff.expected_error(clean, np.full(N, float(q)), np.zeros(N), sigma) ** 2)))
    hi = 2
    while contrib(hi) < target and hi < 4096:
        hi *= 2
    lo = hi // 2
    if hi == 2:
        return 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if contrib(mid) < target:
            lo = mid
        else:
            hi = mid
    return hi


def make_dataset(effect: str, seed: int, rho: float | None = None, walk: bool | None = None) -> dict:
    """One benchmark dataset: device, truth calibration, recording, effect truth and figures.
    bias_drift is a random walk for odd seeds and a ramp for even ones (``walk`` overrides)."""
    rng = np.random.default_rng([seed, LABELS.index(effect), 0xD1A6])
    need_lever = effect in ("centripetal",)
    dev = random_device(rng, need_lever=need_lever)
    cal = seed_prototype_truth(dev, rng)
    traj, layout = random_motion(dev, rng, effect)
    N = dev.n_channels
    z = rng.standard_normal(N)
    sim_seed = int(rng.integers(0, 2**31 - 1))
    noise = float(np.sqrt(np.mean(dev.noise_counts() ** 2 + 1.0 / 12.0)))
    if rho is None:
        rho = float(np.exp(rng.uniform(np.log(RHO_LO), np.log(RHO_HI))))
    sim0 = run_simulation(dev, traj, seed=sim_seed, calibration=cal)
    base_clean = np.clip(sim0.clean_counts, dev.raw_min, dev.raw_max)
    specs = []
    if effect == "none":
        pass
    elif effect == "quantization":
        specs = [("quantization", {"step": float(_quantization_step(base_clean, dev.noise_counts(), rho * noise))})]
    elif effect == "saturation":
        S = np.asarray(cal.sensitivity)
        amax = (np.max(np.abs(base_clean - np.asarray(cal.offsets)), axis=0)
                / (dev.gravity_mps2 * np.linalg.norm(S, axis=1)))
        chans = np.sort(rng.choice(N, size=int(rng.integers(1, N + 1)), replace=False))
        lim = amax * (1.0 - np.exp(rng.uniform(np.log(0.002), np.log(0.45), N)))
        specs = [("saturation", {"limit_g": _fmt(lim[chans]), "channel": [int(c) for c in chans]})]
    else:
        aux = {"u": rng.uniform(0.6, 1.4, N),
               "walk": effect == "bias_drift" and (seed % 2 == 1 if walk is None else walk)}
        m_ref = REF_SIZE[effect]
        sim1 = run_simulation(dev, traj, seed=sim_seed, calibration=cal, effects=[effect_spec(effect, m_ref, z, aux)])
        if effect == "pose_error":
            c_ref = np.sqrt(np.mean((sim1.clean_counts - _pred_base(dev, cal, sim1.recording)) ** 2))
        else:
            c_ref = np.sqrt(np.mean((sim1.clean_counts - sim0.clean_counts) ** 2))
        if c_ref <= 0:
            m = m_ref
        else:
            m = m_ref * rho * noise / c_ref
        if effect == "centripetal":
            m = min(m, 1.0)
        if effect == "bandwidth":
            m = min(m, 0.2)      # fc >= ~0.8 Hz
        specs = [effect_spec(effect, m, z, aux)]
    sim = run_simulation(dev, traj, seed=sim_seed, calibration=cal, effects=specs)
    rec = sim.recording
    rec.source = f"bench-{effect}-{seed}"
    pb = _pred_base(dev, cal, rec)
    pt = pb if effect == "none" else _pred_true(dev, sim, effect)
    raw = rec.raw.astype(float)
    recs = [rec]
    if layout == "split":
        cut = int(np.flatnonzero(np.diff(rec.t) > 0.5 * GAP_S)[-1]) + 1
        recs = [rec.select(np.arange(cut)), rec.select(np.arange(cut, rec.n_samples))]
        for k, r in enumerate(recs):
            r.source = f"bench-{effect}-{seed}-{'jig' if k == 0 else 'motion'}"
    contrib = float(np.sqrt(np.mean((pt - pb) ** 2)))
    r0 = float(np.sqrt(np.mean((raw - pb) ** 2)))
    r1 = float(np.sqrt(np.mean((raw - pt) ** 2)))
    return {"effect": effect, "seed": seed, "device": dev, "cal": cal, "recording": rec, "recordings": recs,
            "sim": sim, "layout": layout,
            "truth": sim.effects.get(effect), "noise": noise, "rho": contrib / noise,
            "true_shrink": 1.0 - r1 / r0 if r0 > 0 else 0.0, "motion": traj.params,
            "spec": "; ".join(format_spec(n, p) for n, p in specs) or "none"}


# ------------------------------------------------------------------ parameter errors
def _arr(v):
    a = np.asarray([np.inf if x == "inf" else (-np.inf if x == "-inf" else (np.nan if x is None else x))
                    for x in np.asarray(v, dtype=object).ravel()], float)
    return a.reshape(np.shape(v)) if np.ndim(v) else a


def _drift(p: dict, t: np.ndarray) -> np.ndarray:
    """(n, N) bias change of bias_drift params (the registry's formula: ramp + seeded walk + path)."""
    rate = _arr(p["rate"])
    out = (t - float(p["t0"]))[:, None] * rate[None, :]
    rw = _arr(p.get("rw", np.zeros_like(rate)))
    if np.any(rw):
        out = out + random_walk(t, rw, int(p["seed"]))
    knots = _arr(p.get("path_t", [])).ravel()
    if knots.size:
        path = _arr(p["path"]).reshape(-1, knots.size)
        out = out + np.stack([np.interp(t, knots, v) for v in path], axis=1)
    return out


def drift_error(est: dict, truth: dict, t: np.ndarray) -> float | None:
    """bias_drift (ramp or random walk): RMS of the fitted minus the true bias change over the
    recording, relative to the RMS of the true change."""
    try:
        e, tr = _drift(est, t), _drift(truth, t)
    except (KeyError, ValueError, TypeError):
        return None
    nt = float(np.sqrt(np.mean(tr ** 2)))
    return None if nt == 0 else float(np.sqrt(np.mean((e - tr) ** 2)) / nt)


def param_error(name: str, est: dict, truth: dict, sig: dict | None = None) -> float | None:
    """Relative error of the effect's size parameter, |est - true| / |true| over the entries the
    data determine (1-sigma below a tenth of the truth's RMS); saturation: median |level error|
    in counts; quantization: share of channels with the wrong step."""
    try:
        if name in ("offset",):
            e, t = _arr(est["db"]), np.asarray(truth["db"], float)
        elif name in ("gain",):
            e, t = _arr(est["scale"]), np.asarray(truth["scale"], float)
        elif name == "centripetal":
            e, t = 1.0 - _arr(est["scale"]), 1.0 - np.asarray(truth["scale"], float)
        elif name == "misalignment":
            e, t = _arr(est["rot"]), np.asarray(truth["rot"], float)
        elif name == "position_error":
            e, t = _arr(est["dr"]), np.asarray(truth["dr"], float)
            if sig is not None:      # compare on the directions the motion makes observable
                sd = _arr(sig["dr"])
                ok = np.all(sd > 0, axis=1) & np.all(sd <= 1e-3, axis=1)
                e, t = e[ok], t[ok]
        elif name == "time_skew":
            e, t = _arr(est["tau"]), np.asarray(truth["tau"], float)
        elif name == "bandwidth":
            fe, ft = _arr(est["fc_hz"]), np.asarray(truth["fc_hz"], float)
            e = np.where(np.isfinite(fe), 1 / (2 * np.pi * fe), 0.0)
            t = np.where(np.isfinite(ft), 1 / (2 * np.pi * ft), 0.0)
        elif name == "nonlinearity":
            e, t = _arr(est["k2"]), np.asarray(truth["k2"], float)
        elif name in ("temperature_offset", "temperature_gain"):
            e, t = _arr(est["coeff"]), np.asarray(truth["coeff"], float)
        elif name == "bias_drift":
            e, t = _arr(est["rate"]), np.asarray(truth["rate"], float)
        elif name == "pose_error":
            lab_e = list(_arr(est["labels"]).astype(int))
            te = np.asarray(truth["rot"], float)
            lab_t = list(np.asarray(truth["labels"]).astype(int))
            re = _arr(est["rot"]).reshape(-1, 3)
            e = np.array([re[lab_e.index(L)] if L in lab_e else np.zeros(3) for L in lab_t])
            t = te
        elif name == "quantization":
            e, t = _arr(est["step"]), np.asarray(truth["step"], float)
            return float(np.mean(np.abs(e - t) > 0))
        elif name == "saturation":
            lo_e, hi_e = _arr(est["lo"]), _arr(est["hi"])
            lo_t, hi_t = np.asarray(truth["lo"], float), np.asarray(truth["hi"], float)
            errs = []
            for a, b in ((lo_e, lo_t), (hi_e, hi_t)):
                m = np.isfinite(b) & np.isfinite(a)
                errs += list(np.abs(a[m] - b[m]))
            return float(np.median(errs)) if errs else None
        else:
            return None
        # compare where the data determine the parameter: entries whose 1-sigma is below a tenth of
        # the truth's RMS (a channel that barely sees the effect has a wide, uninformative estimate)
        skey = {"offset": "db", "gain": "scale", "centripetal": "scale", "misalignment": "rot", "time_skew": "tau",
                "nonlinearity": "k2", "temperature_offset": "coeff", "temperature_gain": "coeff",
                "bias_drift": "rate"}.get(name)
        if sig is not None and skey in sig and name != "position_error":
            sd = _arr(sig[skey])
            if sd.shape == e.shape:
                rt = float(np.sqrt(np.mean(t ** 2)))
                ok = np.isfinite(sd) & (sd <= 0.1 * rt)
                if e.ndim == 2:
                    ok = np.all(ok, axis=1)
                e, t = e[ok], t[ok]
    except (KeyError, ValueError, TypeError):
        return None
    nt = float(np.linalg.norm(t))
    if nt == 0:
        return None
    return float(np.linalg.norm(e - t) / nt)


# ------------------------------------------------------------------ running
def run_one(args):
    effect, seed, rho = args
    from accelcal.diagnose import diagnose
    ds = make_dataset(effect, seed, rho)
    t0 = time.perf_counter()
    res = diagnose(ds["device"], ds["cal"], ds["recordings"], seed=seed)
    dt = time.perf_counter() - t0
    entry = next((e for e in res["effects"] if e["name"] == effect), None)
    est_shrink = entry["alone"]["shrink"] if entry else 0.0
    perr = None
    if entry and ds["truth"] is not None:
        perr = (drift_error(entry["params"], ds["truth"], ds["recording"].t) if effect == "bias_drift"
                else param_error(effect, entry["params"], ds["truth"], entry["params_sigma"]))
    if effect == "none":
        est_shrink = res["effects"][0]["shrink"] if res["verdict"] != "none" else 0.0
    return {"effect": effect, "seed": seed, "verdict": res["verdict"], "rho": ds["rho"],
            "true_shrink": ds["true_shrink"] if effect != "none" else 0.0,
            "est_shrink": est_shrink,
            "param_err": perr, "time_s": dt, "n": res["n_samples"], "N": res["n_channels"],
            "chosen": res["model"]["effects"], "device": ds["device"].name,
            "motion": f"{ds['layout']}: {ds['motion'].get('jig')} + {ds['motion'].get('motion')}",
            "skipped": [s["name"] for s in res["skipped"]], "spec": ds["spec"]}


def timing_run(n: int = 100_000, seed: int = 1, effects=("time_skew:tau=0.002",)) -> dict:
    """Diagnose n samples x 12 channels with every candidate active (a jig part with 26 poses, a
    random 6-DOF motion, a temperature sine), the given effects in the data."""
    from accelcal.diagnose import diagnose
    rng = np.random.default_rng(seed)
    dev = random_array(rng, 4)
    dev = Device(name=dev.name, sample_rate_hz=100.0, gravity_mps2=dev.gravity_mps2, raw_min=0, raw_max=65535,
                 positions=dev.positions, axes=dev.axes, counts_per_mps2=dev.counts_per_mps2,
                 zero_counts=dev.zero_counts, noise_mps2=2.0 / float(dev.counts_per_mps2[0]))
    cal = seed_prototype_truth(dev, rng)
    jig = MOTIONS["static_poses"](dev, rng, poses="26", samples_per_pose=200)
    mv = MOTIONS["random_6dof"](dev, rng, duration_s=(n - jig.n_samples) / 100.0 - 1.0, bandwidth_hz=1.5)
    tr = concat([jig, mv], 1.0, dev.gravity_mps2)
    tr.temp_c = temperature_profile(tr.t, "sine", temp_c=25.0, temp_amplitude_c=10.0, temp_period_s=300.0)
    sim = run_simulation(dev, tr, seed=seed, calibration=cal, effects=list(effects))
    t0 = time.perf_counter()
    res = diagnose(dev, cal, [sim.recording], seed=seed)
    dt = time.perf_counter() - t0
    return {"n": res["n_samples"], "N": res["n_channels"], "time_s": dt, "verdict": res["verdict"],
            "skipped": [s["name"] for s in res["skipped"]], "steps": res["model"]["effects"]}


def _q(x, p):
    return f"{np.percentile(x, p):.3f}" if len(x) else "-"


def _pct(m):
    return f"{100 * np.mean(m):.1f} %" if np.size(m) else "-"


XSENS = os.path.join(os.path.dirname(ROOT), "shared", "data", "imu_tk_xsens", "xsens_acc.txt.gz")
if not os.path.exists(XSENS):
    XSENS = "/work/shared/data/imu_tk_xsens/xsens_acc.txt.gz"


def xsens_section() -> list[str]:
    """The diagnosis of the real Xsens recording (no reference: its static poses, |f| = g)."""
    from accelcal.calibrate import calibrate_recordings
    from accelcal.calibration import Calibration
    from accelcal.diagnose import diagnose
    from accelcal.xsens import load_xsens
    if not os.path.exists(XSENS):
        return ["", "### Real Xsens recording", "", f"(not found: {XSENS})"]
    dev, rec = load_xsens(XSENS)
    half = rec.t < rec.t[0] + 0.5 * (rec.t[-1] - rec.t[0])
    r1, r2 = rec.select(half), rec.select(~half)
    r1.source, r2.source = "xsens first half", "xsens second half"
    runs = [("jig-free calibration of the whole recording", calibrate_recordings(dev, [rec], "jigfree"), rec),
            ("calibration from the first half, diagnosis of the second", calibrate_recordings(dev, [r1], "jigfree"),
             r2),
            ("the nominal calibration (zero 32768, 410.1 counts per m/s^2)", Calibration.nominal(dev), rec)]
    out = ["", "### Real Xsens recording (imu_tk; jig-free: the static poses with |f| = g are the reference)", "",
           "| model | verdict | chosen effects | held-out RMS before -> after (counts) | gap / noise floor | "
           "pose means / noise | next candidates (shrink %, z) | time |",
           "| --- | --- | --- | --- | ---: | ---: | --- | ---: |"]
    notes = []
    for title, cal, r in runs:
        t0 = time.perf_counter()
        res = diagnose(dev, cal, [r])
        dt = time.perf_counter() - t0
        g, m = res["gap"], res["model"]
        chosen = ", ".join(f"{e['name']} ({e['summary']})" for e in res["effects"] if e["selected"]) or "-"
        nxt = ", ".join(f"{e['name']} ({100 * e['shrink']:.2f}, {e['score']['z']:.3g})"
                        for e in res["effects"] if not e["selected"])[:200]
        out.append(f"| {title} | **{res['verdict']}** | {chosen} | {m['heldout_rms_before']:.3f} -> "
                   f"{m['heldout_rms_after']:.3f} | {g['ratio_to_noise']:.3f} | {g.get('pose_mean_ratio', 0):.2f} | "
                   f"{nxt} | {dt:.1f} s |")
        if not notes:
            notes = [n for n in res["notes"] if "residue" in n]
            bands = res["where"]["frequency_bands"]
            notes.append("residual by frequency band (counts; white noise at the floor in brackets): " + ", ".join(
                f"{b['label']} {b['rms_counts']:.2f} ({b['white_noise_rms_counts']:.2f})" for b in bands))
            notes.append(f"noise floor {g['noise_floor_counts']:.2f} counts ({g['noise_method']}); "
                         f"{res['recordings'][0]['n_used']} of {res['recordings'][0]['n_samples']} samples in "
                         f"{g.get('n_poses')} static poses")
    out += [""] + [f"- {n}" for n in notes]
    return out


def summarise(rows: list[dict]) -> str:
    lines = []
    idx = {n: i for i, n in enumerate(LABELS)}

    def conf(sub):
        M = np.zeros((len(LABELS), len(LABELS)), int)
        for r in sub:
            M[idx[r["effect"]], idx[r["verdict"]]] += 1
        return M

    abbrev = (("temperature_", "temp_"), ("position_error", "position"), ("misalignment", "misalign"),
              ("quantization", "quantiz"), ("nonlinearity", "nonlin"))
    short = {}
    for n in LABELS:
        short[n] = n
        for a, b in abbrev:
            short[n] = short[n].replace(a, b)

    def table(M, title):
        out = [f"### {title}", "", "| truth \\ verdict | " + " | ".join(short[n] for n in LABELS) + " |",
               "| --- | " + " | ".join("---" for _ in LABELS) + " |"]
        for i, n in enumerate(LABELS):
            if M[i].sum() == 0:
                continue
            out.append(f"| {n} | " + " | ".join(str(v) if v else "." for v in M[i]) + " |")
        return out

    strong = [r for r in rows if r["effect"] == "none" or r["rho"] >= 3.0]
    lines += table(conf(strong), "Confusion matrix, contribution >= 3x noise floor (and every none)") + [""]
    lines += table(conf(rows), "Confusion matrix, all datasets") + [""]
    lines += ["### Per effect", "",
              "| effect | datasets | top-1 all | datasets rho>=3 | top-1 rho>=3 | top-1 1<=rho<3 | top-1 rho<1 | "
              "|shrink err| median (rho>=3) | |shrink err| 95 % (rho>=3) | within 0.1 (rho>=3) | "
              "param rel err median (rho>=3) |",
              "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    tot_strong = tot_ok = 0
    all_err = []
    for n in LABELS:
        sub = [r for r in rows if r["effect"] == n]
        if not sub:
            continue
        s3 = [r for r in sub if n == "none" or r["rho"] >= 3]
        mid = [r for r in sub if 1 <= r["rho"] < 3]
        low = [r for r in sub if r["rho"] < 1]

        def acc(x):
            return f"{100 * np.mean([r['verdict'] == r['effect'] for r in x]):.0f} %" if x else "-"

        errs = [abs(r["est_shrink"] - r["true_shrink"]) for r in s3]
        all_err += errs if n != "none" else []
        pe = [r["param_err"] for r in s3 if r["param_err"] is not None]
        tot_strong += len(s3) if n != "none" else 0
        tot_ok += sum(r["verdict"] == n for r in s3) if n != "none" else 0
        lines.append(f"| {n} | {len(sub)} | {acc(sub)} | {len(s3)} | {acc(s3)} | {acc(mid) if n != 'none' else '-'} | "
                     f"{acc(low) if n != 'none' else '-'} | "
                     f"{_q(errs, 50)} | {_q(errs, 95)} | {_pct(np.array(errs) <= 0.1)} | {_q(pe, 50)} |")
    none = [r for r in rows if r["effect"] == "none"]
    fp = np.mean([r["verdict"] != "none" for r in none]) if none else float("nan")
    lines += ["", "### Goals", "",
              f"- top-1 accuracy, contribution >= 3x noise floor: **{100 * tot_ok / max(tot_strong, 1):.1f} %** "
              f"({tot_ok}/{tot_strong}; goal >= 95 %)",
              f"- false positives on none: **{100 * fp:.1f} %** "
              f"({sum(r['verdict'] != 'none' for r in none)}/{len(none)}; "
              "goal <= 5 %)",
              f"- |estimated - true shrink| (true effect's entry, rho >= 3): median {_q(all_err, 50)}, "
              f"95th percentile {_q(all_err, 95)}, within 0.1: "
              f"**{_pct(np.array(all_err) <= 0.1)}** (goal: within 0.1)",
              f"- diagnosis time per dataset: median {np.median([r['time_s'] for r in rows]):.2f} s, "
              f"max {np.max([r['time_s'] for r in rows]):.2f} s "
              f"(samples x channels: median {int(np.median([r['n'] * r['N'] for r in rows]))})"]
    wrong = [r for r in rows if r["verdict"] != r["effect"] and (r["effect"] == "none" or r["rho"] >= 3)]
    if wrong:
        lines += ["", "### Misses (contribution >= 3x noise floor, and false positives)", "",
                  "| truth | verdict | rho | seed | device | motion | spec |",
                  "| --- | --- | ---: | ---: | --- | --- | --- |"]
        for r in wrong[:60]:
            lines.append(f"| {r['effect']} | {r['verdict']} | {r['rho']:.2f} | {r['seed']} | {r['device']} | "
                         f"{r['motion']} | {r['spec'][:80]} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-effect", type=int, default=30, help="datasets per effect (default 30)")
    ap.add_argument("--per-none", type=int, default=100, help="datasets without an effect (default 100)")
    ap.add_argument("--quick", action="store_true", help="4 datasets per effect and for none, no Xsens or timing run")
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--effects", default=",".join(LABELS), help="comma-separated subset")
    ap.add_argument("--no-timing", action="store_true")
    ap.add_argument("--timing-samples", type=int, default=100_000)
    ap.add_argument("--rows", help="also dump the per-dataset rows as JSON to this file")
    ap.add_argument("-o", "--output", default=os.path.join(ROOT, "build", "bench_diagnose.md"))
    a = ap.parse_args(argv)
    from tqdm import tqdm
    per = 4 if a.quick else a.per_effect
    per_none = 4 if a.quick else a.per_none
    effects = [e.strip() for e in a.effects.split(",") if e.strip()]
    bad = [e for e in effects if e not in LABELS]
    if bad:
        ap.error(f"unknown effect {bad[0]!r}; effects: {', '.join(LABELS)}")
    # stratified magnitudes: dataset k of an effect gets a target rho in the k-th of `per` equal
    # slices of [log RHO_LO, log RHO_HI] (position inside the slice from the seed)
    jobs = []
    for e in effects:
        for k in range(per_none if e == "none" else per):
            u = np.random.default_rng([a.seed + k, LABELS.index(e), 7]).random()
            rho = float(np.exp(np.log(RHO_LO) + (np.log(RHO_HI) - np.log(RHO_LO)) * (k + u) / per))
            jobs.append((e, a.seed + k, rho))
    rows = []
    t0 = time.perf_counter()
    if a.jobs > 1:
        import multiprocessing as mp
        with mp.get_context("fork").Pool(a.jobs) as pool:
            for r in tqdm(pool.imap_unordered(run_one, jobs), total=len(jobs), desc="datasets", file=sys.stderr):
                rows.append(r)
    else:
        for j in tqdm(jobs, desc="datasets", file=sys.stderr):
            rows.append(run_one(j))
    wall = time.perf_counter() - t0
    rows.sort(key=lambda r: (LABELS.index(r["effect"]), r["seed"]))
    if a.rows:
        import json
        with open(a.rows, "w") as f:
            json.dump(rows, f, indent=0, default=float)
    text = ["# Diagnosis benchmark (withheld effects)", "",
            f"{len(rows)} datasets ({per} per effect, {per_none} without), seed {a.seed}, {wall:.0f} s wall on {a.jobs} "
            f"process(es).  rho = true contribution / noise floor, log-uniform target in [{RHO_LO}, {RHO_HI}].", ""]
    text.append(summarise(rows))
    if not a.quick:
        text += xsens_section()
    if not (a.quick or a.no_timing):
        text += ["", "### Timing", ""]
        for effs in (("time_skew:tau=0.002",),
                     ("time_skew:tau=0.002", "offset:db=5", "temperature_gain:coeff=0.0002")):
            tr = timing_run(a.timing_samples, effects=effs)
            text.append(f"- {tr['n']} samples x {tr['N']} channels, every candidate (skipped: "
                        f"{tr['skipped'] or 'none'}), data with {', '.join(effs)}: **{tr['time_s']:.1f} s** "
                        f"(goal <= 20 s); verdict {tr['verdict']}, effects found {tr['steps']}")
    out = "\n".join(text) + "\n"
    os.makedirs(os.path.dirname(os.path.abspath(a.output)), exist_ok=True)
    with open(a.output, "w") as f:
        f.write(out)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
