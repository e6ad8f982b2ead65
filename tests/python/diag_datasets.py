"""Datasets for the withheld-effect check of the diagnosis, and how an estimate is scored.

For each effect of the registry (and for none), a dataset is a simulation with a random
device, a random true calibration (the seed's Table 1 spreads), a random noise level, a
random motion and a random effect magnitude; the model is the true calibration, so the
effect is the only thing the model lacks.  See tools/bench_diagnose.py (which imports this
module) for the layout, the definitions of rho and the true shrink, and the figures.

Used by tests/python/test_diagnose.py and tools/bench_diagnose.py.
"""
from __future__ import annotations

import math

import numpy as np

from accelcal.io.device import Device, default_device, default_triad, pendulum_device
from accelcal.effects import EFFECT_NAMES, EFFECTS
from accelcal.effects.base import as_list
from accelcal.motions import MOTIONS, Kinematics, Trajectory, temperature_profile
from accelcal.sensor import evaluate, rotation_matrix, true_state
from accelcal.simulate import run_simulation, seed_prototype_truth
from accelcal.spec import format_spec

#: the effects and none; the changes between recordings (issue 33) last, so that every other label keeps
#: its index (each dataset's random stream is keyed by it)
LABELS = tuple(n for n in EFFECT_NAMES if not n.startswith("session_")) + ("none",) + \
    tuple(n for n in EFFECT_NAMES if n.startswith("session_"))
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
SESSION_EFFECTS = ("session_offset", "session_gain")     # act in the second recording only (issue 33)


def random_motion(dev: Device, rng: np.random.Generator, effect: str) -> tuple[Trajectory, str]:
    """A trajectory and its layout: 'jig+motion' (one recording), 'split' (the same, given as two
    recordings: jig, motion), 'motion' (motion only) or 'jig' (static poses only)."""
    g = dev.gravity_mps2
    rate = dev.sample_rate_hz
    u = rng.random()
    layout = "jig+motion" if u < 0.5 else "split" if u < 0.7 else "motion" if u < 0.85 else "jig"
    if layout == "jig" and effect in MOTION_EFFECTS:
        layout = "jig+motion"
    if effect in SESSION_EFFECTS:
        layout = "split"        # a change between recordings needs two: the jig (the calibration's) and the motion
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
def effect_spec(name: str, m: float, z: np.ndarray, aux: dict) -> tuple[str, dict]:
    """Spec (name, params) of size m with per-channel normal draws z: the effect's own."""
    return name, EFFECTS[name].bench_spec(m, z, aux)



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


def _split_at(rec) -> int:
    """The first sample of the split layout's second recording (after the last gap)."""
    return int(np.flatnonzero(np.diff(rec.t) > 0.5 * GAP_S)[-1]) + 1


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
        specs = [("saturation", {"limit_g": as_list(lim[chans]), "channel": [int(c) for c in chans]})]
    else:
        aux = {"u": rng.uniform(0.6, 1.4, N),
               "walk": effect == "bias_drift" and (seed % 2 == 1 if walk is None else walk)}
        m_ref = EFFECTS[effect].bench_size
        sim1 = run_simulation(dev, traj, seed=sim_seed, calibration=cal, effects=[effect_spec(effect, m_ref, z, aux)])
        if effect == "pose_error":
            c_ref = np.sqrt(np.mean((sim1.clean_counts - _pred_base(dev, cal, sim1.recording)) ** 2))
        else:
            dc = sim1.clean_counts - sim0.clean_counts
            if effect in SESSION_EFFECTS:      # the change is in the second recording only
                dc[:_split_at(sim0.recording)] = 0.0
            c_ref = np.sqrt(np.mean(dc ** 2))
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
        cut = _split_at(rec)
        recs = [rec.select(np.arange(cut)), rec.select(np.arange(cut, rec.n_samples))]
        if effect in SESSION_EFFECTS:
            # the jig is the calibration's session, without the change: the same simulation (same
            # noise) without the effect
            recs[0] = sim0.recording.select(np.arange(cut))
            pt, raw = pt.copy(), raw.copy()
            pt[:cut] = pb[:cut]
            raw[:cut] = sim0.recording.raw[:cut]
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
def drift_error(est: dict, truth: dict, t: np.ndarray) -> float | None:
    """bias_drift (ramp or random walk): the effect's path error."""
    return EFFECTS["bias_drift"].path_error(est, truth, t)


def param_error(name: str, est: dict, truth: dict, sig: dict | None = None) -> float | None:
    """The effect's own measure of how far its fitted parameters are from the truth."""
    return EFFECTS[name].param_error(est, truth, sig)
