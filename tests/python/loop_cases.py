"""The closed loop of issue 35 on the independent generator (tests/python/indep_model.py):
a sensor with an effect -> calibrate -> diagnose recording 1 -> refine -> header -> the fixed
engine on a fresh recording 2 (other seed, other temperature path), against the truth.

The sensor is built with indep_model's own pieces (Scene, its trajectories, analog, adc and
draw_effect), never the package's effect registry.  What indep_model lacks is added here, in
functions of this module: a per-channel time skew on every channel (indep_model skews one),
a temperature gain with a thermal lag (indep_model has the offset only), a square-law
nonlinearity (indep_model's is cubic or cubic + square), lever arms off the nominal ones,
and a 9-channel array (three 3-axis chips on a 60 mm circle).

Units: counts, m/s^2, s, degC (indep_model's).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import indep_model as im
from accelcal.io.calibration import Calibration
from accelcal.io.device import Device
from accelcal.io.recording import recording_from_arrays

G0 = im.G0


def array9(rate_hz: float = 100.0) -> Device:
    """Three 3-axis chips (x, y, z each) at 0, 120, 240 deg on an r = 60 mm circle: 9 channels,
    1250 counts per g, zero 5000, 0..10000 (the seed's converter)."""
    pos, axes = [], []
    for k in range(3):
        phi = math.radians(120.0 * k)
        p = [0.06 * math.cos(phi), 0.06 * math.sin(phi), 0.0]
        for ax in np.eye(3):
            pos.append(p)
            axes.append(ax)
    return Device(name="indep-array9", sample_rate_hz=rate_hz, gravity_mps2=G0, raw_min=0, raw_max=10000,
                  positions=np.array(pos), axes=np.array(axes), counts_per_mps2=np.full(9, 1250.0 / G0),
                  zero_counts=np.full(9, 5000.0))


DEVICES = {"seed6": lambda: im.seed6(100.0), "adxl12": lambda: im.adxl12(50.0), "array9": array9,
           "triad16": lambda: im.triad16(100.0)}

#: effects that are the sensor's own (present when it was calibrated); the others changed since
#: (the calibration was made on a recording without them)
PROPERTY = ("nonlinearity", "temperature_offset", "temperature_gain", "time_skew", "lever_arms")


@dataclass
class Case:
    """One loop case: its effects (names), the device and the effects' sizes (a multiple of the
    noise floor, indep_model's ``ratio``)."""

    name: str
    effects: tuple
    device: str
    ratio: float = 15.0
    noise_mps2: float = 0.02


CASES = (
    Case("offset", ("offset",), "seed6"),
    Case("gain", ("gain",), "seed6"),
    Case("misalignment", ("misalignment",), "seed6"),
    Case("lever arms", ("lever_arms",), "seed6"),
    Case("nonlinearity (square law)", ("nonlinearity",), "seed6"),
    Case("nonlinearity (cube + square)", ("nonlinearity3",), "seed6"),
    Case("temperature offset + gain", ("temperature_offset", "temperature_gain"), "adxl12", noise_mps2=0.01),
    Case("time skew", ("time_skew",), "array9"),
    Case("offset + gain", ("offset", "gain"), "seed6"),
    Case("nonlinearity + time skew", ("nonlinearity", "time_skew"), "array9"),
    Case("nonlinearity + temperature offset", ("nonlinearity", "temperature_offset"), "adxl12", noise_mps2=0.01),
)


def draw_sensor(case: Case, seed: int):
    """The true sensor: device, true parameters (indep_model.true_parameters) and the effects'
    parameters, sized on a pilot session (recording 1's scene)."""
    rng = np.random.default_rng(seed)
    dev = DEVICES[case.device]()
    p = im.true_parameters(dev, rng)
    return dev, p, rng


def _temperature(t, rng, temperature):
    return im._temperature(t, rng) if temperature else None


def session(dev, p, eff, seed: int, *, temperature: bool, motion: bool, noise_mps2: float, hold=(3.0, 5.0)):
    """One jig session of the true sensor: 26 stated poses (faces, edges, corners) held ``hold`` s
    (8-12 s with a temperature column), then a 20 s moving part with its reference f, w, dw;
    the effects ``eff`` applied (indep_model's and this module's).  Returns (Scene, Recording,
    raw without the effects)."""
    rng = np.random.default_rng(seed)
    dirs = im.FACES + im.EDGES + im.CORNERS
    dirs = [dirs[k] for k in rng.permutation(len(dirs))]
    traj = im.jig_trajectory(dev.gravity_mps2, dirs, rng, hold_s=(8.0, 12.0) if temperature else hold)
    t_motion = None
    if motion:
        t_motion = traj.end
        traj.move_to(traj.R_end, 1.0)
        im.append_motion(traj, 20.0, rng)
    t = im._sample_times(traj, dev.sample_rate_hz)
    sc = im.Scene(dev=dev, p=p, traj=traj, t=t, noise_mps2=noise_mps2,
                  noise=rng.normal(size=(t.size, dev.n_channels)), temp_amb=_temperature(t, rng, temperature))
    lab, stated = traj.labels_and_stated(t)
    raw = im.adc(sc, analog(sc, eff), {})
    clean = im.adc(sc, analog(sc, {}), {})
    F, W, DW = traj.evaluate(t)
    f = stated.copy()
    w = np.where(np.isnan(f[:, :1]), np.nan, 0.0) * np.ones((1, 3))
    dw = w.copy()
    if motion:
        m = t >= t_motion
        f[m], w[m], dw[m] = F[m], W[m], DW[m]
    rec = recording_from_arrays(t, raw, f=f, w=w, dw=dw, temp_c=sc.temp_amb, pose=lab,
                                metadata={"generator": "tests/python/loop_cases.py"})
    return sc, rec, clean


def analog(sc, eff: dict) -> np.ndarray:
    """indep_model.analog with this module's additions: ``time_skew`` per channel (``tau`` (N,),
    no jitter), ``temperature_gain`` (``gamma`` (N,) per degC of the sensor's lagged temperature,
    ``tau_s``, ``t_ref_c``: the input u scaled by 1 + gamma (T_s - t_ref)), ``nonlinearity`` as
    indep_model's (k2 u^2 + k3 u^3 of the input u in counts), ``lever_arms`` (``dr`` (N, 3) m: the
    true positions are the nominal ones + dr)."""
    base = {k: v for k, v in eff.items() if k not in ("temperature_gain", "lever_arms")}
    if "time_skew" in base:
        base["time_skew"] = {"tau": base["time_skew"]["tau"], "jitter": np.zeros(sc.t.size)}
    p0 = sc.p
    if "lever_arms" in eff:
        sc.p = dict(p0, r=p0["r"] + eff["lever_arms"]["dr"])
        sc.cache.pop("fww", None)
    try:
        x = im.analog(sc, base) if base else im.analog(sc, {}).copy()
        if "temperature_gain" in eff:
            tg = eff["temperature_gain"]
            u = im.channel_input(sc, {k: v for k, v in base.items() if k in ("gain", "misalignment", "time_skew")})
            Ts = im.sensor_temperature(sc, tg["tau_s"])
            x = x + np.outer(Ts - tg["t_ref_c"], tg["gamma"]) * u
    finally:
        sc.p = p0
        sc.cache.clear()
    return x


def draw_effects(case: Case, sc, rng) -> dict:
    """The effects' parameters, each sized for ``case.ratio`` x the noise floor on ``sc``
    (indep_model.draw_effect where it has the effect; this module's draws otherwise)."""
    target = case.ratio * sc.floor
    eff = {}
    N = sc.dev.n_channels
    for name in case.effects:
        if name in ("offset", "gain", "misalignment", "temperature_offset"):
            eff[name] = im.draw_effect(sc, name, target, rng)
        elif name in ("nonlinearity", "nonlinearity3"):
            U = sc.dev.gravity_mps2 * np.linalg.norm(sc.p["S"], axis=1)
            k2 = rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N) / U
            k3 = (rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N) / U ** 2 if name == "nonlinearity3"
                  else np.zeros(N))
            eff["nonlinearity"] = _scale(sc, "nonlinearity", {"k2": k2, "k3": k3}, ("k2", "k3"), target)
        elif name == "temperature_gain":
            unit = {"gamma": rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N) * 1e-3,
                    "tau_s": rng.uniform(30.0, 120.0), "t_ref_c": float(sc.temp_amb[0])}
            eff[name] = _scale(sc, name, unit, ("gamma",), target, cap=1e-3)   # at most 1000 ppm/degC
        elif name == "time_skew":
            h = 1.0 / sc.dev.sample_rate_hz
            unit = {"tau": rng.uniform(-0.45, 0.45, N) * h}
            eff[name] = _scale(sc, name, unit, ("tau",), target, cap=0.45 * h)
        elif name == "lever_arms":
            d = rng.normal(size=(N, 3))
            eff[name] = _scale(sc, name, {"dr": d / np.linalg.norm(d, axis=1, keepdims=True)}, ("dr",), target,
                               cap=0.02)
        else:
            raise ValueError(name)
    return eff


def _scale(sc, name, unit, keys, target, cap=None):
    """``unit`` with ``keys`` scaled so that the effect's RMS change of the readings is ``target``
    counts (linear in the size; ``cap``: the largest |value| allowed)."""
    base = analog(sc, {})
    c1 = float(np.sqrt(np.mean((analog(sc, {name: unit}) - base) ** 2)))
    k = target / c1 if c1 > 0 else 0.0
    if cap is not None:
        k = min(k, cap / max(float(np.max(np.abs(unit[keys[0]]))), 1e-300))
    out = dict(unit)
    for key in keys:
        out[key] = np.asarray(unit[key]) * k
    return out


def true_terms(dev, p, eff) -> dict:
    """The calibration fields of the true effects (the package's parameterisation)."""
    s = np.linalg.norm(p["S"], axis=1)
    out = {}
    if "nonlinearity" in eff:
        out.update(nonlin_k2=eff["nonlinearity"]["k2"] * s ** 2, nonlin_k3=eff["nonlinearity"]["k3"] * s ** 3)
    if "temperature_offset" in eff:
        te = eff["temperature_offset"]
        out.update(offset_tc=te["beta"], temp_ref_c=te["t_ref_c"], temp_offset_tau_s=te["tau_s"])
    if "temperature_gain" in eff:
        tg = eff["temperature_gain"]
        out.update(gain_tc=tg["gamma"], temp_ref_c=tg["t_ref_c"], temp_gain_tau_s=tg["tau_s"])
    if "time_skew" in eff:
        out.update(time_skew_s=eff["time_skew"]["tau"])
    return out


def truth_calibration(dev, p, eff=None) -> Calibration:
    """The true calibration (with the lever arms the effect moved)."""
    r = p["r"] + (eff["lever_arms"]["dr"] if eff and "lever_arms" in eff else 0.0)
    return Calibration(device=dev.name, method="truth", offsets=p["b"], sensitivity=p["S"], positions=r)


def with_full_reference(sc, rec):
    """Recording 2 for the resolve: f, w, dw of the trajectory on every sample (the centripetal
    correction needs w everywhere; the f error is scored against f)."""
    F, W, DW = sc.traj.evaluate(sc.t)
    return recording_from_arrays(rec.t, rec.raw, f=F, w=W, dw=DW, temp_c=rec.temp_c), F


def build(case: Case, seed: int):
    """Recording 0 (the calibration's: clean where the effect came after the calibration), 1
    (diagnosed and refined) and 2 (fresh: another seed and temperature path), their scenes, the
    effects and the true parameters."""
    dev, p, rng = draw_sensor(case, seed)
    temperature = any(e.startswith("temperature") for e in case.effects)
    kw = dict(temperature=temperature, noise_mps2=case.noise_mps2)
    sc1, _, _ = session(dev, p, {}, seed + 1, motion=True, **kw)
    eff = draw_effects(case, sc1, rng)
    sc1, rec1, _ = session(dev, p, eff, seed + 1, motion=True, **kw)
    own = {k: v for k, v in eff.items() if k in PROPERTY}     # the sensor's own: there at the calibration
    sc0, rec0, _ = session(dev, p, own, seed + 2, motion=False, **kw)
    sc2, rec2, clean2 = session(dev, p, eff, seed + 3, motion=True, **kw)
    return dict(device=dev, params=p, effects=eff, rec0=rec0, rec1=rec1, rec2=rec2, clean2=clean2, sc1=sc1, sc2=sc2)
