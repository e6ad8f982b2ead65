"""An independent forward model of accelerometer recordings, written from the data contract
(docs/data-contract.md) alone, and semi-synthetic injection into real recordings.

Nothing here comes from accelcal's simulator, effect registry, sensor model or motion
generators: only the user-facing types are imported (Device, Calibration,
recording_from_arrays, load_xsens), to hand the data to the diagnosis.  The effects are
given shapes that differ on purpose from a simple registry's (second-order low-pass,
cubic nonlinearity, random-walk drift, timing jitter, thermal lag, table tilt, ...), and
three effects that are not in the contract's table at all (mechanical resonance,
electrical crosstalk, 50 Hz mains pickup).

Conventions (the contract's):

* body frame B, SI units; specific force at the origin O ``f = a_O - g_vec`` (m/s^2),
  ``|f| = g`` at rest pointing up; ω (rad/s), α = dω/dt (rad/s^2);
* channel i reads ``raw_i = b_i + s_i . (f + α x r_i + ω x (ω x r_i))`` counts, plus white
  noise before the ADC, rounded to integers and clipped to [raw_min, raw_max];
  ``b_i`` (counts), ``s_i`` (counts per m/s^2), ``r_i`` (m).

Units in this module: time s, rate Hz, specific force m/s^2, angles rad unless a name
ends in ``_deg``, readings and offsets counts, ``noise_mps2`` m/s^2 rms per channel
(white, before the ADC), temperatures degC.

The size of an effect is chosen so that its RMS contribution (the noise-free readings
with the effect minus those without, over every sample and channel, before the ADC's
rounding except for the ADC effects themselves) is a target multiple ``ratio`` of the
noise floor ``sqrt(mean_i(sigma_i^2) + 1/12)`` counts (sigma_i the white noise of channel i
in counts; 1/12 the rounding).  The ratio reached is measured and stated in the dataset
dict (``ratio``).

Entry points: :func:`make_jig`, :func:`make_handheld`, :func:`make_six_pose` (the
independent simulator) and :func:`load_real`, :func:`inject` (semi-synthetic).
"""
from __future__ import annotations

import csv
import gzip
import json
import math
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import signal

from accelcal.io.calibration import Calibration
from accelcal.io.device import Device
from accelcal.io.recording import recording_from_arrays
from accelcal.convert.xsens import load_xsens

G0 = 9.80665  # standard gravity, m/s^2

IN_TABLE = ("offset", "gain", "misalignment", "bandwidth", "nonlinearity", "bias_drift", "time_skew",
            "temperature_offset", "saturation", "quantization", "pose_error")
OUT_OF_TABLE = ("resonance", "crosstalk", "mains")
PAIRS = (("offset", "gain"), ("bias_drift", "gain"), ("quantization", "offset"))
MOVING_ONLY = ("bandwidth", "time_skew")  # show only while the body moves: need a reference motion
RATIO_LO, RATIO_HI = 3.0, 30.0


# =============================================================================== devices
def triad16(rate_hz: float = 100.0) -> Device:
    """A 16-bit triad at the origin: ~1670 counts per m/s^2 (+-2 g), zero 32768, 0..65535."""
    return Device(name="indep-triad16", sample_rate_hz=rate_hz, gravity_mps2=G0, raw_min=0, raw_max=65535,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1670.0),
                  zero_counts=np.full(3, 32768.0))


def adxl12(rate_hz: float = 100.0) -> Device:
    """A 12-bit analog ADXL-like triad (0..4095, zero 2048): 300 mV/g on a 3.0 V 12-bit ADC is
    409.6 counts per g, 41.8 counts per m/s^2 (about +-5 g to the rails)."""
    return Device(name="indep-adxl12", sample_rate_hz=rate_hz, gravity_mps2=G0, raw_min=0, raw_max=4095,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 41.8),
                  zero_counts=np.full(3, 2048.0))


def seed6(rate_hz: float = 60.0) -> Device:
    """The seed's 6-channel array: three dual-axis chips on an r = 60 mm circle at 0, 120,
    240 deg; chip k's channels along the tangent (-sin phi, cos phi, 0) and along +z;
    1250 counts per g (127.5 counts per m/s^2), zero 5000, 0..10000."""
    r = 0.06
    pos, axes = [], []
    for k in range(3):
        phi = math.radians(120.0 * k)
        p = [r * math.cos(phi), r * math.sin(phi), 0.0]
        pos += [p, p]
        axes += [[-math.sin(phi), math.cos(phi), 0.0], [0.0, 0.0, 1.0]]
    return Device(name="indep-seed6", sample_rate_hz=rate_hz, gravity_mps2=G0, raw_min=0, raw_max=10000,
                  positions=np.array(pos), axes=np.array(axes), counts_per_mps2=np.full(6, 1250.0 / G0),
                  zero_counts=np.full(6, 5000.0))


DEVICES = {"triad16": triad16, "adxl12": adxl12, "seed6": seed6}


def true_parameters(dev: Device, rng) -> dict:
    """A true calibration drawn about the nominal: offsets +-2 % of full scale (counts),
    gains +-3 %, axis directions off by up to 1.5 deg; positions nominal.
    Returns arrays b (N,) counts, S (N, 3) counts per m/s^2, r (N, 3) m."""
    N = dev.n_channels
    span = dev.raw_max - dev.raw_min
    b = dev.zero_counts + rng.uniform(-0.02, 0.02, N) * span
    S = np.empty((N, 3))
    for i in range(N):
        u = dev.axes[i]
        S[i] = dev.counts_per_mps2[i] * (1.0 + rng.uniform(-0.03, 0.03)) * small_rotate(u, rng, 1.5)
    return {"b": b, "S": S, "r": np.array(dev.positions, dtype=float)}


def as_calibration(dev: Device, p: dict, method: str = "truth") -> Calibration:
    """The true parameters as a Calibration (the model the diagnosis is given)."""
    return Calibration(device=dev.name, method=method, offsets=p["b"], sensitivity=p["S"], positions=p["r"])


# =============================================================================== rotations
def skew(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def expm_so3(v) -> np.ndarray:
    """Rotation matrix of the rotation vector v (rad), Rodrigues."""
    th = float(np.linalg.norm(v))
    if th < 1e-12:
        return np.eye(3) + skew(v)
    k = skew(np.asarray(v) / th)
    return np.eye(3) + math.sin(th) * k + (1.0 - math.cos(th)) * k @ k


def logm_so3(R) -> np.ndarray:
    """Rotation vector (rad) of a rotation matrix."""
    c = max(-1.0, min(1.0, (np.trace(R) - 1.0) / 2.0))
    th = math.acos(c)
    if th < 1e-9:
        return np.zeros(3)
    if th > math.pi - 1e-6:
        w, V = np.linalg.eigh((R + R.T) / 2.0)
        ax = V[:, np.argmax(w)]
        return ax * th
    return th / (2.0 * math.sin(th)) * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])


def small_rotate(u, rng, max_deg: float) -> np.ndarray:
    """u (unit) rotated by an angle up to max_deg about a random axis across it."""
    u = np.asarray(u, float) / np.linalg.norm(u)
    a = np.cross(u, rng.normal(size=3))
    a /= np.linalg.norm(a)
    return expm_so3(a * math.radians(rng.uniform(0.0, max_deg))) @ u


def random_rotation(rng) -> np.ndarray:
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def rotation_for_direction(d, yaw: float) -> np.ndarray:
    """World-from-body rotation R with the body direction d (unit) pointing up (R d = z),
    then turned by ``yaw`` (rad) about the vertical: f = R^T g z = g d at rest."""
    d = np.asarray(d, float) / np.linalg.norm(d)
    z = np.array([0.0, 0.0, 1.0])
    ax = np.cross(d, z)
    s = np.linalg.norm(ax)
    if s < 1e-12:
        R = np.eye(3) if d[2] > 0 else expm_so3(np.array([math.pi, 0.0, 0.0]))
    else:
        R = expm_so3(ax / s * math.atan2(s, float(d @ z)))
    return expm_so3(z * yaw) @ R


# 26 jig directions: 6 faces (the axes), 12 edges (45 deg between two axes), 8 corners
FACES = [np.array(v, float) for v in ([1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1])]
EDGES = [np.array(v, float) / math.sqrt(2) for v in
         ([1, 1, 0], [1, -1, 0], [-1, 1, 0], [-1, -1, 0], [1, 0, 1], [1, 0, -1], [-1, 0, 1], [-1, 0, -1],
          [0, 1, 1], [0, 1, -1], [0, -1, 1], [0, -1, -1])]
CORNERS = [np.array([sx, sy, sz], float) / math.sqrt(3) for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)]


# =============================================================================== trajectory
def _h(s):
    """Quintic smooth step on [0, 1] and its first two derivatives (zero at both ends)."""
    s = np.clip(s, 0.0, 1.0)
    return (10 * s ** 3 - 15 * s ** 4 + 6 * s ** 5, 30 * s ** 2 - 60 * s ** 3 + 30 * s ** 4,
            60 * s - 180 * s ** 2 + 120 * s ** 3)


@dataclass
class Trajectory:
    """Piecewise rigid-body motion, exact at any time.

    Segment k spans [t0[k], t0[k] + dur[k]): orientation ``R(t) = R0[k] expm(e[k] phi[k] h(s))``
    (world from body; e[k] a unit body axis, h the quintic step of s = (t - t0)/dur), so
    ω = e phi h'/dur and α = e phi h''/dur^2 in the body frame; the origin moves by
    ``d[k] h(s)`` (world, m).  A hold is a segment with phi = 0 and d = 0.
    ``label[k]``: the pose label of a hold (-1 while moving); ``stated[k]``: the
    specific force the jig states for that hold (m/s^2, body frame) or NaN."""

    g: float
    t0: list = field(default_factory=list)
    dur: list = field(default_factory=list)
    R0: list = field(default_factory=list)
    e: list = field(default_factory=list)
    phi: list = field(default_factory=list)
    d: list = field(default_factory=list)
    label: list = field(default_factory=list)
    stated: list = field(default_factory=list)

    @property
    def end(self) -> float:
        return self.t0[-1] + self.dur[-1] if self.t0 else 0.0

    @property
    def R_end(self) -> np.ndarray:
        return self.R0[-1] @ expm_so3(self.e[-1] * self.phi[-1])

    def hold(self, R, dur, label=-1, stated=None):
        self._add(R, dur, np.array([1.0, 0.0, 0.0]), 0.0, np.zeros(3), label,
                  np.full(3, np.nan) if stated is None else np.asarray(stated, float))

    def move_to(self, R_next, dur, d=None):
        R = self.R_end
        v = logm_so3(R.T @ R_next)
        phi = float(np.linalg.norm(v))
        e = v / phi if phi > 1e-12 else np.array([1.0, 0.0, 0.0])
        self._add(R, dur, e, phi, np.zeros(3) if d is None else np.asarray(d, float), -1, np.full(3, np.nan))

    def _add(self, R, dur, e, phi, d, label, stated):
        self.t0.append(self.end)
        self.dur.append(float(dur))
        self.R0.append(np.asarray(R, float))
        self.e.append(np.asarray(e, float))
        self.phi.append(float(phi))
        self.d.append(np.asarray(d, float))
        self.label.append(int(label))
        self.stated.append(stated)

    def segment(self, t):
        t0 = np.asarray(self.t0)
        return np.clip(np.searchsorted(t0, t, side="right") - 1, 0, len(t0) - 1)

    def evaluate(self, t):
        """f (n, 3) m/s^2, ω (n, 3) rad/s, α (n, 3) rad/s^2 in the body frame at times t (s)."""
        t = np.asarray(t, float)
        k = self.segment(t)
        t0, dur = np.asarray(self.t0)[k], np.asarray(self.dur)[k]
        phi, e, d = np.asarray(self.phi)[k], np.asarray(self.e)[k], np.asarray(self.d)[k]
        h, h1, h2 = _h((t - t0) / dur)
        th = phi * h
        w = e * (phi * h1 / dur)[:, None]
        dw = e * (phi * h2 / dur ** 2)[:, None]
        acc = d * (h2 / dur ** 2)[:, None]  # world, m/s^2
        up = acc + np.array([0.0, 0.0, self.g])  # a - g_vec, world
        f = np.empty((t.size, 3))
        R0 = np.asarray(self.R0)
        for j in np.unique(k):
            m = k == j
            # R = R0 expm(e th): body vector = expm(-e th) R0^T up (Rodrigues, vectorised over th)
            v = up[m] @ R0[j]
            ej = np.asarray(self.e[j])
            c, s = np.cos(th[m])[:, None], np.sin(th[m])[:, None]
            f[m] = v * c - np.cross(ej, v) * s + np.outer(v @ ej, ej) * (1 - c)
        return f, w, dw

    def labels_and_stated(self, t):
        """Per-sample pose label (-1 while moving) and stated f (NaN where none)."""
        k = self.segment(t)
        lab = np.asarray(self.label)[k]
        st = np.asarray(self.stated)[k]
        # a hold's first and last 0.1 s are not labelled (the jig settles)
        t0, dur = np.asarray(self.t0)[k], np.asarray(self.dur)[k]
        edge = (t - t0 < 0.1) | (t0 + dur - t < 0.1)
        lab = np.where(edge, -1, lab)
        st = np.where((lab < 0)[:, None], np.nan, st)
        return lab, st


def jig_trajectory(g, directions, rng, hold_s=(2.0, 4.0), move_s=1.0, yaw=True, tilt=None, pose_err_deg=0.0,
                   lead_s=1.0):
    """A jig visiting ``directions`` (body unit vectors pointing up) in order, each held
    hold_s seconds (a range draws uniformly) with 1 s turns between them.  ``tilt``
    (rotation vector, rad, world frame): the table is tilted, so every pose is off its
    stated direction by that common world rotation; ``pose_err_deg``: each pose is
    further off by a random rotation of that rms angle (about a random axis).  The stated
    f is the nominal g * direction; the true one follows the tilted/perturbed pose."""
    tr = Trajectory(g=g)
    T = np.eye(3) if tilt is None else expm_so3(tilt)
    for p, dvec in enumerate(directions):
        Rs = rotation_for_direction(dvec, rng.uniform(0, 2 * math.pi) if yaw else 0.0)
        Rt = T @ Rs
        if pose_err_deg > 0:
            ax = rng.normal(size=3)
            Rt = Rt @ expm_so3(ax / np.linalg.norm(ax) * math.radians(pose_err_deg) * abs(rng.normal()))
        hs = rng.uniform(*hold_s) if np.ndim(hold_s) else float(hold_s)
        if p == 0:
            tr.hold(Rt, lead_s)  # unlabelled lead-in
        else:
            tr.move_to(Rt, move_s)
        tr.hold(Rt, hs, label=p, stated=g * dvec / np.linalg.norm(dvec))
    return tr


def handheld_trajectory(g, n_poses, rng, hold_s=(2.0, 4.0), move_s=(0.5, 1.0)):
    """Hand-held, jig-free: random orientations (uniform on rotations) held 2-4 s, smooth
    turns of 0.5-1 s between them, with the hand moving the device by 5-20 cm during each
    turn.  Labels are set on the holds (the caller may drop them); no stated f."""
    tr = Trajectory(g=g)
    for p in range(n_poses):
        R = random_rotation(rng)
        if p == 0:
            tr.hold(R, 1.0)
        else:
            dvec = rng.normal(size=3)
            tr.move_to(R, rng.uniform(*move_s), d=dvec / np.linalg.norm(dvec) * rng.uniform(0.05, 0.2))
        tr.hold(R, rng.uniform(*hold_s), label=p)
    return tr


def append_motion(tr: Trajectory, duration_s, rng):
    """A moving part with full reference (f, ω, α known): back-to-back turns of 30-120 deg
    about random axes, 0.3-0.8 s each, with translations of 2-10 cm, for ``duration_s``."""
    stop = tr.end + duration_s
    while tr.end < stop:
        ax = rng.normal(size=3)
        R = tr.R_end @ expm_so3(ax / np.linalg.norm(ax) * math.radians(rng.uniform(30, 120)))
        dvec = rng.normal(size=3)
        tr.move_to(R, rng.uniform(0.3, 0.8), d=dvec / np.linalg.norm(dvec) * rng.uniform(0.02, 0.1))
    tr.hold(tr.R_end, 1.0)


# =============================================================================== the sensor
@dataclass
class Scene:
    """Everything the readings depend on.  ``eff``: effect name -> parameters (below)."""

    dev: Device
    p: dict  # true parameters b, S, r
    traj: Trajectory
    t: np.ndarray  # (n,) s, nominal sample times
    noise_mps2: float
    noise: np.ndarray  # (n, N) standard normal draws
    temp_amb: np.ndarray | None = None  # (n,) degC, the ambient (the recording's temp_c)
    eff: dict = field(default_factory=dict)
    cache: dict = field(default_factory=dict, repr=False)

    @property
    def sigma_counts(self) -> np.ndarray:
        return self.noise_mps2 * np.linalg.norm(self.p["S"], axis=1)

    @property
    def floor(self) -> float:
        return float(math.sqrt(np.mean(self.sigma_counts ** 2) + 1.0 / 12.0))


def channel_input(sc: Scene, eff: dict) -> np.ndarray:
    """u (n, N) counts: s_i . f(r_i) at each channel's own sampling instant, with the
    sensitivity effects (gain, misalignment, crosstalk is electrical: not here) and the
    mechanical ones (resonance)."""
    S = sc.p["S"].copy()
    if "gain" in eff:
        S *= (1.0 + eff["gain"]["delta"])[:, None]
    if "misalignment" in eff:
        for i, v in enumerate(eff["misalignment"]["rotvec"]):
            S[i] = expm_so3(v) @ S[i]
    N = S.shape[0]
    u = np.empty((sc.t.size, N))
    ts = eff.get("time_skew")
    for i in range(N):
        ti = sc.t if ts is None else sc.t + ts["tau"][i] + ts["jitter"]
        if ts is not None:
            f, w, dw = sc.traj.evaluate(ti)
        elif i == 0:
            if "fww" not in sc.cache:
                sc.cache["fww"] = sc.traj.evaluate(sc.t)
            f, w, dw = sc.cache["fww"]
        r = sc.p["r"][i]
        fr = f + np.cross(dw, r) + np.cross(w, np.cross(w, r))
        u[:, i] = fr @ S[i]
    if "resonance" in eff:
        rs = eff["resonance"]
        vib = np.zeros(sc.t.size)
        for te in rs["t_excite"]:
            dt = sc.t - te
            m = dt >= 0
            vib[m] += np.exp(-dt[m] / rs["tau"]) * np.sin(2 * math.pi * rs["freq"] * dt[m])
        u += rs["amp"] * vib[:, None] * (S @ rs["dir"])[None, :]
    return u


def sensor_temperature(sc: Scene, tau):
    """First-order thermal lag of the sensor behind the ambient: dT_s/dt = (T_a - T_s)/tau."""
    Ta = sc.temp_amb
    Ts = np.empty_like(Ta)
    Ts[0] = Ta[0]
    a = np.exp(-np.diff(sc.t) / tau)
    for k in range(1, Ta.size):  # exact for a piecewise-constant ambient between samples
        Ts[k] = Ta[k - 1] + (Ts[k - 1] - Ta[k - 1]) * a[k - 1]
    return Ts


def analog(sc: Scene, eff: dict) -> np.ndarray:
    """Noise-free analog reading x (n, N) in counts, before the ADC."""
    if not eff and "x0" in sc.cache:
        return sc.cache["x0"]
    u = channel_input(sc, eff)
    if "nonlinearity" in eff:
        nl = eff["nonlinearity"]
        u = u + nl["k3"][None, :] * u ** 3 + nl["k2"][None, :] * u ** 2
    if "bandwidth" in eff:
        bw = eff["bandwidth"]
        sos = signal.butter(int(bw.get("order", 2)), bw["fc_hz"], fs=sc.dev.sample_rate_hz, output="sos")
        zi = signal.sosfilt_zi(sos)
        for i in bw["channels"]:
            u[:, i], _ = signal.sosfilt(sos, u[:, i], zi=zi * u[0, i])
    x = sc.p["b"][None, :] + u
    if "offset" in eff:
        x = x + eff["offset"]["delta"][None, :]
    if "bias_drift" in eff:
        x = x + eff["bias_drift"]["path"]
    if "temperature_offset" in eff:
        te = eff["temperature_offset"]
        Ts = sensor_temperature(sc, te["tau_s"])
        x = x + np.outer(Ts - te["t_ref_c"], te["beta"])
    if "mains" in eff:
        mn = eff["mains"]
        x = x + mn["amp"][None, :] * np.sin(2 * math.pi * mn["freq"] * sc.t[:, None] + mn["phase"][None, :])
    if not eff:
        sc.cache["x0"] = x
    return x


def adc(sc: Scene, x: np.ndarray, eff: dict, noisy: bool = True) -> np.ndarray:
    """Noise (white, before the ADC), crosstalk (electrical, noise included), rounding to
    the code step, clipping at the saturation levels and at [raw_min, raw_max]."""
    y = x + (sc.noise * sc.sigma_counts[None, :] if noisy else 0.0)
    if "crosstalk" in eff:
        ct = eff["crosstalk"]
        y = y.copy()
        y[:, ct["i"]] += ct["c"] * (y[:, ct["j"]] - sc.dev.zero_counts[ct["j"]])
    q = eff.get("quantization", {}).get("step", 1)
    y = q * np.round(y / q)
    lo, hi = float(sc.dev.raw_min), float(sc.dev.raw_max)
    if "saturation" in eff:
        s = eff["saturation"]
        y = np.clip(y, np.maximum(lo, s["lo"])[None, :], np.minimum(hi, s["hi"])[None, :])
    return np.clip(y, lo, hi).astype(np.int64)


def contribution(sc: Scene, name: str, params: dict) -> float:
    """RMS over samples and channels of the noise-free reading with the effect minus
    without (counts); ADC effects compare the ADC outputs (noise-free); pose_error is
    measured against the stated f (the model's input)."""
    if name == "pose_error":
        return float(params["contribution"])
    base = analog(sc, {})
    x = analog(sc, {name: params})
    if name in ("quantization", "saturation", "crosstalk"):
        return float(np.sqrt(np.mean((adc(sc, x, {name: params}, noisy=False).astype(float)
                                      - adc(sc, base, {}, noisy=False)) ** 2)))
    return float(np.sqrt(np.mean((x - base) ** 2)))


# =============================================================================== effects
def _scaled(sc, name, unit_params, scale_keys, target):
    """Effects linear in their size: one pilot at unit size, then scaled to the target."""
    c1 = contribution(sc, name, unit_params)
    k = target / c1 if c1 > 0 else 0.0
    out = dict(unit_params)
    for key in scale_keys:
        out[key] = unit_params[key] * k
    return out


def _bisect(fun, lo, hi, target, increasing=True, iters=24, log=True):
    """x in [lo, hi] with fun(x) ~ target for a monotone fun (clamped at the ends)."""
    a, b = lo, hi
    for _ in range(iters):
        m = math.sqrt(a * b) if log else 0.5 * (a + b)
        if (fun(m) < target) == increasing:
            a = m
        else:
            b = m
    return math.sqrt(a * b) if log else 0.5 * (a + b)


def draw_effect(sc: Scene, name: str, target: float, rng, shape: str | None = None) -> dict:
    """Parameters of effect ``name`` sized for a contribution of ``target`` counts RMS.

    offset: ``delta`` (N,) counts, on one channel.  gain: ``delta`` (N,) fractional
    change of |s_i|, random signs on every channel.  misalignment: ``rotvec`` (N, 3) rad,
    small rotations of s_i across it.  bandwidth: ``fc_hz``, a 2nd-order Butterworth
    low-pass on every channel's input (statics are unchanged).  nonlinearity: ``k3``
    (N,) counts^-2 and ``k2`` (N,) counts^-1 (k2 = 0 unless shape 'cubic+quadratic'),
    the term k3 u^3 + k2 u^2 of the input u in counts.  bias_drift: ``path`` (n, N)
    counts; shape 'random_walk' (default, Brownian on every channel) or 'warmup'
    (A_i exp(-t/tau), tau 20-120 s) or 'ramp' (linear).  time_skew: ``tau`` (N,) s (one
    channel skewed) and ``jitter`` (n,) s (per-sample timing jitter, 20-200 us rms, every
    channel).  temperature_offset: ``beta`` (N,) counts per degC of the sensor's own
    temperature, ``tau_s`` its lag behind the ambient (30-120 s), ``t_ref_c``.
    saturation: ``hi``/``lo`` (N,) counts, an in-range clip level on one channel.
    quantization: ``step`` counts (2-16).  pose_error: table 'tilt' or per-pose (set
    through the trajectory; see make_jig).  resonance: ``freq`` 20-80 Hz, ``tau`` s,
    ``amp`` m/s^2, ``dir``, excited at the end of every turn.  crosstalk: ``c`` 0.5-2 %,
    channel j leaks into i.  mains: ``freq`` 50 Hz, ``amp`` (N,) counts, ``phase``."""
    N, n = sc.dev.n_channels, sc.t.size
    if name == "offset":
        d = np.zeros(N)
        d[rng.integers(N)] = rng.choice([-1.0, 1.0])
        return _scaled(sc, name, {"delta": d}, ["delta"], target)
    if name == "gain":
        return _scaled(sc, name, {"delta": rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N)}, ["delta"], target)
    if name == "misalignment":
        rv = np.zeros((N, 3))
        for i in range(N):
            a = np.cross(sc.p["S"][i], rng.normal(size=3))
            rv[i] = a / np.linalg.norm(a) * rng.uniform(0.5, 1.0) * 0.01
        return _scaled(sc, name, {"rotvec": rv}, ["rotvec"], target)
    if name == "nonlinearity":
        U = sc.dev.gravity_mps2 * np.linalg.norm(sc.p["S"], axis=1)  # counts at 1 g
        k3 = rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N) / U ** 2
        k2 = (rng.choice([-1.0, 1.0], N) * rng.uniform(0.2, 0.5, N) / U if shape == "cubic+quadratic"
              else np.zeros(N))
        return _scaled(sc, name, {"k3": k3, "k2": k2, "shape": shape or "cubic"}, ["k3", "k2"], target)
    if name == "bias_drift":
        shape = shape or "random_walk"
        if shape == "random_walk":
            path = np.cumsum(rng.normal(size=(n, N)) * np.sqrt(np.diff(sc.t, prepend=sc.t[0]))[:, None], axis=0)
        elif shape == "warmup":
            tau = rng.uniform(20.0, 120.0)
            path = np.outer(np.exp(-(sc.t - sc.t[0]) / tau), rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1, N))
        else:  # ramp
            path = np.outer((sc.t - sc.t[0]) / (sc.t[-1] - sc.t[0]), rng.choice([-1.0, 1.0], N) *
                            rng.uniform(0.5, 1, N))
        return _scaled(sc, name, {"path": path, "shape": shape}, ["path"], target)
    if name == "time_skew":
        tau = np.zeros(N)
        tau[rng.integers(N)] = rng.choice([-1.0, 1.0])
        jitter = rng.normal(size=n) * rng.uniform(20e-6, 200e-6)
        c_j = contribution(sc, name, {"tau": np.zeros(N), "jitter": jitter})
        c_1 = contribution(sc, name, {"tau": tau * 1e-3, "jitter": np.zeros(n)}) / 1e-3  # linear in tau
        s = math.sqrt(max(target ** 2 - c_j ** 2, 0.0)) / c_1 if c_1 > 0 else 0.0
        return {"tau": tau * s, "jitter": jitter, "jitter_rms_s": float(np.std(jitter))}
    if name == "bandwidth":
        fs = sc.dev.sample_rate_hz
        fc = _bisect(lambda f: contribution(sc, name, {"fc_hz": f, "channels": range(N)}), 0.2, 0.45 * fs,
                     target, increasing=False)
        return {"fc_hz": fc, "channels": list(range(N)), "order": 2}
    if name == "temperature_offset":
        beta = rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N)
        unit = {"beta": beta, "tau_s": rng.uniform(30.0, 120.0), "t_ref_c": float(sc.temp_amb[0])}
        return _scaled(sc, name, unit, ["beta"], target)
    if name == "saturation":
        i = int(rng.integers(N))
        x = analog(sc, {})
        hi_side = rng.random() < 0.5
        top = x[:, i].max() if hi_side else x[:, i].min()
        mid = float(np.median(x[:, i]))

        def make(frac):
            lv = mid + frac * (top - mid)
            hi, lo = np.full(N, np.inf), np.full(N, -np.inf)
            (hi if hi_side else lo)[i] = round(lv)
            return {"hi": hi, "lo": lo, "channel": i}
        frac = _bisect(lambda a: contribution(sc, name, make(a)), 0.3, 0.999, target, increasing=False, log=False)
        return make(frac)
    if name == "quantization":
        best = min(range(2, 17), key=lambda q: abs(math.log(max(contribution(sc, name, {"step": q}), 1e-9) / target)))
        return {"step": best}
    if name == "resonance":
        ends = [t0 + d for t0, d, ph in zip(sc.traj.t0, sc.traj.dur, sc.traj.phi) if ph > 0]
        fs = sc.dev.sample_rate_hz
        freq = rng.uniform(20.0, min(80.0, 0.4 * fs))
        dvec = rng.normal(size=3)
        unit = {"freq": freq, "tau": rng.uniform(0.1, 0.4), "amp": 1.0, "dir": dvec / np.linalg.norm(dvec),
                "t_excite": ends}
        return _scaled(sc, name, unit, ["amp"], target)
    if name == "crosstalk":
        i, j = rng.choice(N, 2, replace=False)
        c = _bisect(lambda c: contribution(sc, name, {"i": int(i), "j": int(j), "c": c}), 0.005, 0.02, target)
        return {"i": int(i), "j": int(j), "c": c}
    if name == "mains":
        unit = {"freq": 50.0, "amp": rng.uniform(0.5, 1.0, N), "phase": rng.uniform(0, 2 * math.pi, N)}
        return _scaled(sc, name, unit, ["amp"], target)
    raise ValueError(f"unknown effect {name!r}")


# =============================================================================== datasets
def _draw_setup(rng, device=None, rate=None, noise=None, effects=(), temperature=False):
    name = device or rng.choice(list(DEVICES))
    if rate is None:
        rate = float(rng.choice([50.0, 100.0, 200.0, 500.0, 1000.0]))
        if temperature:  # minutes of recording
            rate = float(rng.choice([50.0, 100.0]))
        if {"resonance", "mains"} & set(effects):
            rate = float(rng.choice([200.0, 500.0]))
    if noise is None:
        noise = math.exp(rng.uniform(math.log(0.002), math.log(0.05)))
        if "quantization" in effects:  # a coarse step only stands out of a quiet channel
            noise = math.exp(rng.uniform(math.log(0.002), math.log(0.006)))
    return DEVICES[name](rate), rate, noise


def _draw_session(rng, effects, device, rate, noise, temperature):
    """A session's temperature column (default: with temperature_offset, else in 30 % of the
    sessions, never with the fast-sampled out-of-table cases: minutes at 200-500 Hz), device,
    rate, noise and true channel parameters."""
    if temperature is None:
        temperature = "temperature_offset" in effects or (rng.random() < 0.3
                                                          and not {"resonance", "mains"} & set(effects))
    dev, rate, noise = _draw_setup(rng, device, rate, noise, effects, temperature)
    return temperature, dev, rate, noise, true_parameters(dev, rng)


def _sample_times(traj, rate):
    return np.arange(int(traj.end * rate)) / rate


def _temperature(t, rng):
    """Ambient temperature (degC): a step of 10-25 degC at a random time in the first
    third, smoothed over 10 s (an oven door, a room heater)."""
    T0 = rng.uniform(15.0, 30.0)
    dT = rng.choice([-1.0, 1.0]) * rng.uniform(10.0, 25.0)
    ts = t[0] + rng.uniform(0.1, 0.35) * (t[-1] - t[0])
    return T0 + dT * (0.5 + 0.5 * np.tanh((t - ts) / 5.0))


def _finish(sc, effects, rng, ratio, shapes):
    """Draw every effect's parameters (each sized alone), simulate, package the dataset."""
    ratio = dict(ratio or {})
    eff = {}
    for nm in effects:
        if nm == "pose_error":
            continue
        target = ratio.get(nm) or math.exp(rng.uniform(math.log(RATIO_LO), math.log(RATIO_HI)))
        eff[nm] = draw_effect(sc, nm, target * sc.floor, rng, shapes.get(nm))
    sc.eff = eff
    x = analog(sc, eff)
    raw = adc(sc, x, eff)
    measured = {nm: contribution(sc, nm, eff[nm]) / sc.floor for nm in eff}
    return raw, measured


def _recording(sc, raw, with_labels, stated, lab, ref_motion):
    t = sc.t
    f = w = dw = None
    if stated is not None:
        f = stated.copy()
        if ref_motion is not None:
            F, W, DW = sc.traj.evaluate(t)
            w = np.where(np.isnan(f[:, :1]), np.nan, 0.0) * np.ones((1, 3))
            dw = w.copy()
            f[ref_motion] = F[ref_motion]
            w[ref_motion] = W[ref_motion]
            dw[ref_motion] = DW[ref_motion]
            # static poses: ω = α = 0 is known (the jig stands still)
            w[lab >= 0] = 0.0
            dw[lab >= 0] = 0.0
    return recording_from_arrays(t, raw, f=f, w=w, dw=dw, temp_c=sc.temp_amb,
                                 pose=lab if with_labels else None,
                                 metadata={"generator": "tests/python/indep_model.py"})


def make_jig(effects=(), seed=0, *, device=None, rate=None, noise=None, n_poses=None, repeats=True,
             motion=None, ratio=None, shapes=None, temperature=None, pose_err_deg=None, directions=None,
             tilt_deg=None, hold_s=None):
    """A jig calibration recording with the given effects (names from IN_TABLE + OUT_OF_TABLE).

    K static poses (12-26 directions of the cube's faces, edges and corners: always the six
    faces, 45-degree edges, then corners), each labelled and with its stated f (m/s^2),
    held 2-4 s (shorter at high rates), 1 s turns between them (f unknown, pose -1); with
    ``repeats`` the first half of the poses is visited again at the end (new labels).
    ``motion`` (default: for bandwidth, time_skew and resonance, and at random in 40 % of
    the rest): a 6-12 s moving part with its reference f, ω, α appended.  Temperature
    ambient column for temperature_offset (and in 30 % of the others); recordings with it
    hold each pose 3x longer (the ambient's step and the lag need minutes).
    pose_error: each pose off its stated direction by a rotation of ``pose_err_deg``
    (0.3-2 deg, drawn to reach the ratio when not given) about a random axis; with
    ``tilt_deg`` the table is tilted instead (one world rotation for every pose).

    Returns a dict: device, cal (true Calibration, the model), params (b, S, r arrays),
    recordings [Recording], recording, effects (name -> parameters), ratio (name -> the
    contribution / noise floor reached), noise_mps2, rate_hz, floor_counts, layout."""
    rng = np.random.default_rng(seed)
    shapes = dict(shapes or {})
    effects = list(effects)
    temperature, dev, rate, noise, p = _draw_session(rng, effects, device, rate, noise, temperature)
    if directions is None:
        K = n_poses or int(rng.integers(12, 27))
        directions = FACES + EDGES + CORNERS
        directions = directions[:6] + [directions[6 + k] for k in rng.permutation(20)]
        directions = directions[:K]
        order = rng.permutation(K)
        directions = [directions[k] for k in order]
        if repeats:
            directions = directions + [directions[k] for k in rng.permutation(K)[: K // 2]]
    if hold_s is None:
        hold_s = (2.0, 4.0) if rate <= 200 else (1.0, 2.0)
        if temperature:
            hold_s = (8.0, 12.0)
    # pose_error: the angle reaching the target ratio, clamped to 0.3-2 deg
    tilt = None
    perr = 0.0
    if "pose_error" in effects:
        kcount = float(np.mean(np.linalg.norm(p["S"], axis=1)))
        floor = math.sqrt(np.mean((noise * np.linalg.norm(p["S"], axis=1)) ** 2) + 1 / 12)
        target = (ratio or {}).get("pose_error") or math.exp(rng.uniform(math.log(RATIO_LO), math.log(RATIO_HI)))
        # a rotation by theta moves f by g theta; per channel on average sqrt(2/3) of it
        ang = math.degrees(target * floor / (dev.gravity_mps2 * kcount * math.sqrt(2.0 / 3.0)))
        ang = min(2.0, max(0.3, ang))
        if tilt_deg is not None or shapes.get("pose_error") == "tilt":
            ang = tilt_deg if tilt_deg is not None else ang
            ax = rng.normal(size=3)
            ax[2] = 0.0
            tilt = ax / np.linalg.norm(ax) * math.radians(ang)
        else:
            perr = pose_err_deg if pose_err_deg is not None else ang
    traj = jig_trajectory(dev.gravity_mps2, directions, rng, hold_s=hold_s, tilt=tilt, pose_err_deg=perr)
    if motion is None:
        motion = bool({"bandwidth", "time_skew", "resonance"} & set(effects)) or rng.random() < 0.4
    t_motion = None
    if motion:
        t_motion = traj.end
        traj.move_to(traj.R_end, 1.0)
        append_motion(traj, rng.uniform(6.0, 12.0), rng)
    t = _sample_times(traj, rate)
    sc = Scene(dev=dev, p=p, traj=traj, t=t, noise_mps2=noise, noise=rng.normal(size=(t.size, dev.n_channels)),
               temp_amb=_temperature(t, rng) if temperature else None)
    lab, stated = traj.labels_and_stated(t)
    ref_motion = None
    if motion:
        ref_motion = t >= t_motion
    raw, measured = _finish(sc, effects, rng, ratio, shapes)
    if "pose_error" in effects:
        F, _, _ = traj.evaluate(t)
        m = lab >= 0
        d = (F[m] - stated[m]) @ p["S"].T
        c = float(np.sqrt(np.sum(d ** 2) / (t.size * dev.n_channels)))
        sc.eff["pose_error"] = {"angle_deg": float(math.degrees(np.linalg.norm(tilt))) if tilt is not None else perr,
                                "kind": "tilt" if tilt is not None else "per-pose", "contribution": c}
        measured["pose_error"] = c / sc.floor
    rec = _recording(sc, raw, True, stated, lab, ref_motion)
    return {"device": dev, "cal": as_calibration(dev, p), "params": p, "recordings": [rec], "recording": rec,
            "effects": sc.eff, "ratio": measured, "noise_mps2": noise, "rate_hz": rate, "floor_counts": sc.floor,
            "layout": f"jig {len(directions)} holds" + (" + motion" if motion else "") +
                      (" + temperature" if temperature else ""), "scene": sc}


def make_six_pose(kind: str, seed=0, *, device="triad16", noise=None, ratio=None):
    """The ambiguous case: six poses +-x, +-y, +-z each held once (no pose repeated), with
    ``kind`` = 'pose_error' (the table tilted by 0.3-2 deg) or 'bias_drift' (a linear drift
    on every channel).  Returns make_jig's dict."""
    rng = np.random.default_rng(seed + 7919)
    dirs = [FACES[k] for k in rng.permutation(6)]
    if kind == "pose_error":
        return make_jig(["pose_error"], seed, device=device, noise=noise, directions=dirs, motion=False,
                        temperature=False, shapes={"pose_error": "tilt"}, ratio=ratio, rate=100.0)
    return make_jig(["bias_drift"], seed, device=device, noise=noise, directions=dirs, motion=False,
                    temperature=False, shapes={"bias_drift": "ramp"}, ratio=ratio, rate=100.0)


def make_handheld(effects=(), seed=0, *, device=None, rate=None, noise=None, n_poses=None, labels=None,
                  ratio=None, shapes=None, temperature=None):
    """A hand-held, jig-free session: 12-30 random orientations held 2-4 s (8-12 s with a
    temperature column), smooth turns of 0.5-1 s between them; no reference f; pose labels
    in half of the sessions (``labels``).  Same dict as make_jig."""
    rng = np.random.default_rng(seed + 104729)
    shapes = dict(shapes or {})
    effects = list(effects)
    temperature, dev, rate, noise, p = _draw_session(rng, effects, device, rate, noise, temperature)
    K = n_poses or int(rng.integers(12, 31))
    traj = handheld_trajectory(dev.gravity_mps2, K, rng, hold_s=(8.0, 12.0) if temperature else (2.0, 4.0))
    t = _sample_times(traj, rate)
    sc = Scene(dev=dev, p=p, traj=traj, t=t, noise_mps2=noise, noise=rng.normal(size=(t.size, dev.n_channels)),
               temp_amb=_temperature(t, rng) if temperature else None)
    if labels is None:
        labels = rng.random() < 0.5
    lab, _ = traj.labels_and_stated(t)
    raw, measured = _finish(sc, effects, rng, ratio, shapes)
    rec = _recording(sc, raw, labels, None, lab, None)
    return {"device": dev, "cal": as_calibration(dev, p), "params": p, "recordings": [rec], "recording": rec,
            "effects": sc.eff, "ratio": measured, "noise_mps2": noise, "rate_hz": rate, "floor_counts": sc.floor,
            "layout": f"hand-held {K} poses" + (" labelled" if labels else "") +
                      (" + temperature" if temperature else ""), "scene": sc}


# =============================================================================== real recordings
def load_imucal(path) -> tuple[Device, object]:
    """imucal's example_ferraris_session.csv: accelerometer columns acc_x..acc_z in m/s^2,
    exact multiples of 9.81/2048 (a +-16 g range at 2048 counts per g); sample index only,
    102.4 Hz.  Raw counts = round(acc * 2048 / 9.81); device: triad, zero 0, signed 16-bit.
    The six static poses of example_ferraris_session_list.json (x_p: x up, x_a: x down, ...)
    are labelled 0..5 and carry the stated f = +-9.81 m/s^2 along that axis (hand-placed on a
    table: the real poses are off by the table's tilt and the hand)."""
    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    acc = np.array([[float(r["acc_x"]), float(r["acc_y"]), float(r["acc_z"])] for r in rows])
    raw = np.round(acc * 2048.0 / 9.81).astype(np.int64)
    n = np.array([int(float(r["n_samples"])) for r in rows])
    rate = 102.4
    dev = Device(name="imucal-16g", sample_rate_hz=rate, gravity_mps2=9.81, raw_min=-32768, raw_max=32767,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 2048.0 / 9.81),
                 zero_counts=np.zeros(3))
    pose = np.full(n.size, -1, dtype=np.int64)
    f = np.full((n.size, 3), np.nan)
    lst = Path(str(path).replace(".csv", "_list.json"))
    if lst.is_file():
        regions = json.loads(lst.read_text())
        for k, key in enumerate(("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")):
            m = (n >= regions[key]["start"]) & (n < regions[key]["end"])
            pose[m] = k
            f[m] = 0.0
            f[m, k // 2] = 9.81 if key.endswith("_p") else -9.81
    rec = recording_from_arrays((n - n[0]) / rate, raw, f=f, pose=pose, metadata={"source": str(path)})
    rec.source = str(path)
    return dev, rec


def load_mpu6050(path) -> tuple[Device, object]:
    """tomisuarez2/ImuCalibration's MPU-6050 log (gzip): 4 metadata lines (Fs, ...), the
    header ax..gz, signed int16 counts; no time column: t = row / Fs.  Device: triad at
    +-2 g (16384 counts per g), zero 0, raw -32768..32767."""
    opener = gzip.open if str(path).endswith(".gz") else open
    with opener(path, "rt") as fh:
        lines = fh.read().splitlines()
    fs = float(lines[0].split(",")[1])
    hdr = lines[4].split(",")
    data = np.array([[int(v) for v in ln.split(",")] for ln in lines[5:] if ln.strip()])
    raw = data[:, [hdr.index("ax"), hdr.index("ay"), hdr.index("az")]].astype(np.int64)
    dev = Device(name="mpu6050", sample_rate_hz=fs, gravity_mps2=G0, raw_min=-32768, raw_max=32767,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 16384.0 / G0),
                 zero_counts=np.zeros(3))
    rec = recording_from_arrays(np.arange(raw.shape[0]) / fs, raw, metadata={"source": str(path)})
    rec.source = str(path)
    return dev, rec


REAL = {
    "xsens": (("imu_tk_xsens", "xsens_acc.txt.gz"), lambda p: load_xsens(p), 1),
    "imucal": (("imucal", "example_ferraris_session.csv"), load_imucal, 1),
    "mpu6050": (("mpu6050_tomisuarez", "example_data_calibration.csv.gz"), load_mpu6050, 4),
}
"""name -> (path parts under shared/data, loader, the native code step of the raw counts)."""


def load_real(name: str, shared_file) -> tuple[Device, object, int] | None:
    """(device, recording, code step) of a real recording, or None when its file is missing.
    ``shared_file``: tests/python/shared_data.shared_file."""
    parts, loader, step = REAL[name]
    path = shared_file(*parts)
    if path is None:
        return None
    dev, rec = loader(path)
    return dev, rec, step


def static_mask(raw: np.ndarray, rate: float, k: float = 3.0, min_s: float = 1.0) -> np.ndarray:
    """Samples in still intervals (own detector): 0.5 s centred moving std of every channel
    below k x the recording's median moving std, runs of at least min_s seconds."""
    w = max(5, int(0.5 * rate))
    x = raw.astype(float)
    ker = np.ones(w) / w
    m1 = np.stack([np.convolve(x[:, i], ker, "same") for i in range(x.shape[1])], 1)
    m2 = np.stack([np.convolve(x[:, i] ** 2, ker, "same") for i in range(x.shape[1])], 1)
    sd = np.sqrt(np.maximum(m2 - m1 ** 2, 0.0))
    still = np.all(sd <= k * np.median(sd, axis=0)[None, :], axis=1)
    out = np.zeros_like(still)
    i = 0
    n = still.size
    while i < n:
        if still[i]:
            j = i
            while j < n and still[j]:
                j += 1
            if (j - i) >= min_s * rate:
                out[i:j] = True
            i = j
        else:
            i += 1
    return out


def real_noise(raw: np.ndarray, rate: float) -> np.ndarray:
    """Per-channel white noise (counts) of a real recording: the median over its still
    intervals' 1 s blocks of the block std."""
    st = static_mask(raw, rate)
    w = max(10, int(rate))
    sds = []
    i = 0
    n = raw.shape[0]
    while i + w <= n:
        if st[i:i + w].all():
            sds.append(raw[i:i + w].astype(float).std(axis=0))
        i += w
    return np.median(np.array(sds), axis=0) if sds else raw.astype(float).std(axis=0)


def inject(dev: Device, cal: Calibration, rec, effect, seed=0, *, ratio=None, step=1):
    """Semi-synthetic: the effect(s) added to the raw counts of a real recording.

    ``effect``: a name or a tuple of names (pairs).  The calibration ``cal`` (the model,
    e.g. the recording's own jig-free calibration) gives the offsets b and the sensitivity
    S through which the body's specific force is estimated per sample,
    f = S^+ (raw - b), so that sensitivity effects act on it.  Sizes reach ``ratio`` x the
    noise floor (sqrt(mean sigma^2 + 1/12), sigma from the still intervals; drawn in
    [3, 30] when not given).  Shapes: offset a constant step on one channel; gain a
    change of |s_i| on every channel (random signs); misalignment small rotations of s_i;
    nonlinearity the cubic k3 (raw - b)^3; bias_drift a linear ramp over the recording;
    temperature_offset an ambient step (the added temp_c column) seen through a 30-120 s
    thermal lag; pose_error (recordings with stated f only) the stated f of each labelled
    pose turned by 0.3-2 deg about a random axis; saturation a clip at 90 % of the largest
    excursion from b of one axis in the still intervals (so that a pose clips; the ratio is
    what it is); quantization the native step times a power of two whose rounding noise is 0.5-4 x the floor;
    crosstalk 0.5-2 % of channel j into i; mains 50 Hz; resonance a damped 20-45 Hz
    sinusoid at the start of every still interval.  The result is rounded to the
    native code step.  Returns (recording, effects' parameters, ratio reached by each)."""
    names = (effect,) if isinstance(effect, str) else tuple(effect)
    rng = np.random.default_rng([seed] + [zlib.crc32(nm.encode()) for nm in names])
    raw0 = rec.raw.astype(float)
    t = rec.t
    n, N = raw0.shape
    b = cal.offsets
    S = cal.sensitivity
    fb = np.linalg.lstsq(S, (raw0 - b).T, rcond=None)[0].T  # (n, 3) m/s^2, noisy
    sigma = real_noise(rec.raw, dev.sample_rate_hz)
    floor = float(math.sqrt(np.mean(sigma ** 2) + 1.0 / 12.0))
    rate = dev.sample_rate_hz
    still = static_mask(rec.raw, rate)
    temp = None
    params = {}
    measured = {}
    x = raw0.copy()
    for nm in names:
        target = ((ratio or {}).get(nm) if isinstance(ratio, dict) else ratio) or \
            math.exp(rng.uniform(math.log(RATIO_LO), math.log(RATIO_HI)))
        target *= floor
        if nm == "offset":
            i = int(rng.integers(N))
            d = np.zeros((n, N))
            d[:, i] = rng.choice([-1.0, 1.0]) * target * math.sqrt(N)
            params[nm] = {"channel": i, "delta": float(d[0, i])}
        elif nm in ("gain", "misalignment", "nonlinearity"):
            if nm == "gain":
                unit = S * (rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N))[:, None]
                d = fb @ unit.T
            elif nm == "misalignment":
                unit = np.array([np.cross(_unit_across(S[i], rng), S[i]) for i in range(N)])
                d = fb @ unit.T
            else:
                u = fb @ S.T
                U = dev.gravity_mps2 * np.linalg.norm(S, axis=1)
                d = u ** 3 / U[None, :] ** 2 * rng.choice([-1.0, 1.0], N)[None, :]
            k = target / float(np.sqrt(np.mean(d ** 2)))
            d = d * k
            params[nm] = {"scale": k}
        elif nm == "bias_drift":
            d = np.outer((t - t[0]) / (t[-1] - t[0]), rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N))
            d *= target / float(np.sqrt(np.mean(d ** 2)))
            params[nm] = {"shape": "ramp", "end_counts": d[-1].tolist()}
        elif nm == "temperature_offset":
            temp = _temperature(t, rng)
            tau = rng.uniform(30.0, 120.0)
            Ts = np.empty_like(temp)
            Ts[0] = temp[0]
            a = np.exp(-np.diff(t) / tau)
            for j in range(1, n):
                Ts[j] = temp[j - 1] + (Ts[j - 1] - temp[j - 1]) * a[j - 1]
            d = np.outer(Ts - temp[0], rng.choice([-1.0, 1.0], N) * rng.uniform(0.5, 1.0, N))
            d *= target / float(np.sqrt(np.mean(d ** 2)))
            params[nm] = {"tau_s": tau, "beta": (d[-1] / (Ts[-1] - temp[0])).tolist()}
        elif nm == "resonance":
            starts = np.flatnonzero(np.diff(still.astype(int)) == 1) + 1
            freq = rng.uniform(20.0, min(45.0, 0.4 * rate))
            tau = rng.uniform(0.1, 0.4)
            vib = np.zeros(n)
            for s0 in starts:
                dt = t[s0:] - t[s0]
                vib[s0:] += np.exp(-dt / tau) * np.sin(2 * math.pi * freq * dt)
            dvec = rng.normal(size=3)
            d = np.outer(vib, S @ (dvec / np.linalg.norm(dvec)))
            d *= target / float(np.sqrt(np.mean(d ** 2)))
            params[nm] = {"freq": freq, "tau": tau, "n_excite": int(starts.size)}
        elif nm == "mains":
            d = np.sin(2 * math.pi * 50.0 * t[:, None] + rng.uniform(0, 2 * math.pi, N)[None, :]) * \
                rng.uniform(0.5, 1.0, N)[None, :]
            d *= target / float(np.sqrt(np.mean(d ** 2)))
            params[nm] = {"freq": 50.0}
        elif nm == "crosstalk":
            i, j = (int(v) for v in rng.choice(N, 2, replace=False))
            d = np.zeros((n, N))
            base = raw0[:, j] - b[j]
            c = min(0.02, max(0.005, target / float(np.sqrt(np.mean(base ** 2) / N))))
            d[:, i] = c * base
            params[nm] = {"i": i, "j": j, "c": c}
        elif nm == "pose_error":  # the stated f of every labelled pose turned by 0.3-2 deg
            if rec.f is None or rec.pose is None:
                raise ValueError("inject: pose_error needs a recording with stated f on labelled poses")
            f_new = np.array(rec.f, dtype=float)
            angles = {}
            for lab in np.unique(rec.pose[rec.pose >= 0]):
                m = rec.pose == lab
                ax = rng.normal(size=3)
                ang = rng.uniform(0.3, 2.0)
                f_new[m] = f_new[m] @ expm_so3(ax / np.linalg.norm(ax) * math.radians(ang)).T
                angles[int(lab)] = ang
            ok = np.all(np.isfinite(f_new), axis=1)
            dd = np.zeros((n, N))
            dd[ok] = (rec.f[ok] - f_new[ok]) @ S.T  # the model's prediction moves by this
            measured[nm] = float(np.sqrt(np.mean(dd ** 2))) / floor
            params[nm] = {"angles_deg": angles}
            continue
        elif nm in ("saturation", "quantization"):
            continue  # ADC effects: below, after the others
        else:
            raise ValueError(f"inject: no semi-synthetic shape for {nm!r} (bandwidth and time_skew need a "
                             "reference motion)")
        x = x + d
        measured[nm] = float(np.sqrt(np.mean(d ** 2))) / floor
    y = step * np.round(x / step)
    if "quantization" in names:
        # a coarser converter: the native step times a power of two whose rounding noise
        # (q / sqrt 12) is 0.5-4 x the floor (the MPU-6050's floor of ~60 counts would hide
        # any step of 4-16 counts: such a step explains no gap, and none is the right answer)
        pows = [step * 2 ** k for k in range(1, 16)]
        choices = [q for q in pows if 0.5 <= q / math.sqrt(12.0) / floor <= 4.0] or \
            [min(pows, key=lambda q: abs(math.log(q / math.sqrt(12.0) / floor)))]
        q = int(rng.choice(choices))
        yq = q * np.round(x / q)
        measured["quantization"] = float(np.sqrt(np.mean((yq - y) ** 2))) / floor
        y = yq
        params["quantization"] = {"step": q}
    if "saturation" in names:
        i = int(rng.integers(N))
        ex = (x[:, i] - b[i])[still]  # the largest reading of a still interval: a pose clips
        side = 1.0 if ex.max() >= -ex.min() else -1.0
        lvl = b[i] + 0.9 * (ex.max() if side > 0 else ex.min())
        ys = y.copy()
        if side > 0:
            ys[:, i] = np.minimum(y[:, i], step * math.floor(lvl / step))
        else:
            ys[:, i] = np.maximum(y[:, i], step * math.ceil(lvl / step))
        measured["saturation"] = float(np.sqrt(np.mean((ys - y) ** 2))) / floor
        params["saturation"] = {"channel": i, "level": float(lvl), "side": "high" if side > 0 else "low"}
        y = ys
    y = np.clip(y, dev.raw_min, dev.raw_max).astype(np.int64)
    out = recording_from_arrays(t, y, f=f_new if "pose_error" in names else rec.f, w=rec.w, dw=rec.dw,
                                temp_c=temp if temp is not None else rec.temp_c,
                                pose=rec.pose, metadata={"injected": ",".join(names)})
    out.source = f"{rec.source} + {'+'.join(names)}"
    return out, params, measured


def _unit_across(s, rng):
    """A random unit vector across s, scaled by 0.01 (a 0.01 rad rotation axis)."""
    a = np.cross(s, rng.normal(size=3))
    return a / np.linalg.norm(a) * 0.01


def real_model(name: str, shared_file):
    """(device, recording, native step, its own calibration) or None when the file is missing.
    The calibration is jig-free (static intervals, |f| = g) except for imucal, whose six
    orientations cannot fix a jig-free 'full' fit (it needs 9 in general position; it does
    not converge): there the known-pose 'full' fit of the six labelled poses with their
    stated +-g (imucal's own Ferraris setting)."""
    got = load_real(name, shared_file)
    if got is None:
        return None
    from accelcal.calibrate import calibrate_recordings
    dev, rec, step = got
    cal = calibrate_recordings(dev, [rec], "full" if name == "imucal" else "jigfree")
    return dev, rec, step, cal


def as_posed(rec, cal):
    """The recording with the stated f of each labelled pose replaced by what the
    calibration reads for that pose's mean, f_k = S^+ (mean raw_k - b): the poses as they
    really were (a hand-placed pose is off by the table's tilt and the hand), so that the
    model holds the real tilt as a jig-free fit holds each pose's orientation.  Unlabelled
    samples keep their stated f (NaN where none)."""
    if rec.f is None or rec.pose is None:
        raise ValueError("as_posed: the recording has no labelled poses with stated f")
    f = np.array(rec.f, dtype=float)
    for lab in np.unique(rec.pose[rec.pose >= 0]):
        m = rec.pose == lab
        f[m] = np.linalg.lstsq(cal.sensitivity, rec.raw[m].mean(axis=0) - cal.offsets, rcond=None)[0]
    out = recording_from_arrays(rec.t, rec.raw, f=f, w=rec.w, dw=rec.dw, temp_c=rec.temp_c, pose=rec.pose,
                                metadata=dict(getattr(rec, "metadata", None) or {}, stated_f="as posed"))
    out.source = f"{rec.source} (stated f as posed)"
    return out


def shared_paths():
    """{name: path parts} of the real recordings this module reads."""
    return {k: v[0] for k, v in REAL.items()}


# =============================================================================== shapes (issue 33)
# Shape parameters the data may or may not pin: a thermal lag from 5 s to 10 x the recording, first-
# and second-order low-passes (with a temperature offset beside them: the case), and two six-pose
# datasets built to give the same pose means (a table tilt with per-pose headings, and a bias ramp).

def _with_raw(ds: dict, eff: dict, layout: str) -> dict:
    """``ds`` (make_jig's dict, effect-free) re-simulated with the effects ``eff`` (name -> the
    parameters of :func:`analog` / :func:`adc`): its scene's noise draws, trajectory and reference."""
    sc = ds["scene"]
    sc.eff = dict(eff)
    raw = adc(sc, analog(sc, eff), eff)
    rec = ds["recording"]
    out = recording_from_arrays(rec.t, raw, f=rec.f, w=rec.w, dw=rec.dw, temp_c=rec.temp_c, pose=rec.pose,
                                metadata={"generator": "tests/python/indep_model.py"})
    ratio = {nm: contribution(sc, nm, p) / sc.floor for nm, p in eff.items()}
    return dict(ds, recordings=[out], recording=out, effects=dict(eff), ratio=ratio,
                layout=ds["layout"] + "; " + layout)


def make_temperature_lag(seed=0, *, lag=None, lag_spans=None, device=None, noise=None, ratio=None) -> dict:
    """A jig recording with a temperature column (the ambient's smoothed step of 10-25 degC in the
    first third) and an offset that follows the sensor's temperature through a first-order lag.
    ``lag``: seconds (a number) or a multiple of the recording's length (a string such as '10x');
    with ``lag_spans`` (lo, hi) drawn log-uniformly between those multiples of the recording's length
    (at least 5 s); default drawn log-uniformly from 5 s to 10 x the recording.  The temperature effect's
    ``tau_s`` and ``span_s`` (the recording's length) are in ``effects``.  Same dict as make_jig."""
    rng = np.random.default_rng(seed + 613)
    ds = make_jig([], seed, device=device, noise=noise, temperature=True, motion=False)
    sc = ds["scene"]
    span = float(sc.t[-1] - sc.t[0])
    if lag_spans is not None:
        tau = max(5.0, span * math.exp(rng.uniform(math.log(lag_spans[0]), math.log(lag_spans[1]))))
    elif lag is None:
        tau = math.exp(rng.uniform(math.log(5.0), math.log(10.0 * span)))
    elif isinstance(lag, str) and lag.endswith("x"):
        tau = float(lag[:-1]) * span
    else:
        tau = float(lag)
    target = (ratio or math.exp(rng.uniform(math.log(RATIO_LO), math.log(RATIO_HI)))) * sc.floor
    beta = rng.choice([-1.0, 1.0], sc.dev.n_channels) * rng.uniform(0.5, 1.0, sc.dev.n_channels)
    te = _scaled(sc, "temperature_offset", {"beta": beta, "tau_s": tau, "t_ref_c": float(sc.temp_amb[0])},
                 ["beta"], target)
    te["span_s"] = span
    return _with_raw(ds, {"temperature_offset": te}, f"thermal lag {tau:.0f} s ({tau / span:.2f} x the recording)")


def make_lowpass(order: int, seed=0, *, fc_hz=None, temperature=False, device=None, noise=None, rate=None,
                 ratio=None, n_poses=None) -> dict:
    """A jig recording with a moving part (reference f, w, dw) whose every channel responds through
    a Butterworth low-pass of ``order`` (1 or 2; the contract's bandwidth is first order) of cut-off
    ``fc_hz`` (default: drawn so that its contribution is 3-30 x the floor), with ``temperature``
    also a temperature offset through a lag of 30-120 s (the issue's case: a first-order 40 Hz
    low-pass and a temperature offset, at 200 Hz).  Same dict as make_jig."""
    rng = np.random.default_rng(seed + 4241)
    if rate is None:
        rate = 200.0 if fc_hz is not None else float(rng.choice([100.0, 200.0, 500.0]))
    ds = make_jig([], seed, device=device, noise=noise, rate=rate, temperature=bool(temperature), motion=True,
                  n_poses=n_poses)
    sc = ds["scene"]
    N = sc.dev.n_channels
    eff = {}
    target = (ratio or math.exp(rng.uniform(math.log(RATIO_LO), math.log(RATIO_HI)))) * sc.floor
    if fc_hz is None:
        fc_hz = _bisect(lambda f: contribution(sc, "bandwidth", {"fc_hz": f, "channels": range(N), "order": order}),
                        0.2, 0.45 * rate, target, increasing=False)
    eff["bandwidth"] = {"fc_hz": float(fc_hz), "channels": list(range(N)), "order": int(order)}
    if temperature:
        eff["temperature_offset"] = draw_effect(sc, "temperature_offset", target, rng)
    return _with_raw(ds, eff, f"order-{order} low-pass {fc_hz:.3g} Hz" + (" + temperature offset" if temperature else ""))


#: the six-pose twins: one face pose held at each of these times from the middle of the recording
#: (s; each axis's two faces at -T and +T), holds of TWIN_HOLD_S, an unlabelled rest in the middle
TWIN_T_S = (32.0, 39.0, 46.0)
TWIN_HOLD_S = 1.0


def make_six_pose_twin(kind: str, seed=0, *, tilt_deg=0.3, noise=0.006, device="triad16") -> dict:
    """Six face poses of a triad, each held once, built so that a table tilt of ``tilt_deg`` and a
    bias ramp give the same pose means.

    Each axis's two faces are held TWIN_T_S seconds before and after the middle of the recording.
    The ramp ``r (t - t_mid)`` (m/s^2 per s in the body frame, read through S) moves pose p's mean
    by ``r tau_p``: across the pose's up direction that is a vector of one length at every pose
    (r is chosen so), which the tilt gives through the pose's heading (the yaw that turns the tilt
    into that vector, solved numerically); along it, ``r_k tau_p`` makes |f| of both faces of axis
    k larger by the same amount: a gain change of channel k, which the tilt dataset carries too.
    ``kind`` 'pose_error': the tilted table (+ those gains); 'bias_drift': the ramp, poses as
    stated.  The pose means of the two agree to second order in the tilt (checked by the tests);
    within a pose the ramp moves by r x TWIN_HOLD_S, below the noise at the default noise.
    Same dict as make_jig, plus ``twin`` (the other kind's name)."""
    from scipy.optimize import minimize_scalar
    if kind not in ("pose_error", "bias_drift"):
        raise ValueError(kind)
    rng = np.random.default_rng(seed + 31337)
    dev = DEVICES[device](100.0)
    p = true_parameters(dev, rng)
    g = dev.gravity_mps2
    th = math.radians(tilt_deg)
    ax = rng.normal(size=3)
    ax[2] = 0.0
    tilt = ax / np.linalg.norm(ax) * th
    T = expm_so3(tilt)
    z = np.array([0.0, 0.0, 1.0])
    size = float(np.linalg.norm(T.T @ z * g - z * g - ((T.T @ z * g - z * g) @ z) * z))  # |df| across up
    Tk = np.array(TWIN_T_S)
    axes = rng.permutation(3)                   # axis held at +-Tk[j]
    Tax = np.empty(3)
    Tax[axes] = Tk
    C = size ** 2
    r2 = 0.5 * C * np.sum(1.0 / Tax ** 2)
    rk = np.sqrt(np.maximum(r2 - C / Tax ** 2, 0.0)) * rng.choice([-1.0, 1.0], 3)
    sign = rng.choice([-1.0, 1.0], 3)           # face +e_k at tau = sign_k T_k
    poses = []
    for k in range(3):
        for s_face in (1.0, -1.0):
            u = np.zeros(3)
            u[k] = s_face
            poses.append((s_face * sign[k] * Tax[k], u))
    poses.sort(key=lambda q: q[0])
    tr = Trajectory(g=g)
    t_mid = None
    for j, (tau, u) in enumerate(poses):
        want = rk * tau - (rk * tau @ u) * u    # the ramp's change across the pose's up direction

        def miss(yaw, u=u, want=want):
            R = rotation_for_direction(u, yaw)
            df = (T @ R).T @ z * g - g * u if kind == "pose_error" else np.zeros(3)
            return float(np.sum((df - (df @ u) * u - want) ** 2))
        yaws = np.linspace(0, 2 * math.pi, 73)
        y0 = yaws[int(np.argmin([miss(y) for y in yaws]))]
        yaw = minimize_scalar(miss, bounds=(y0 - 0.1, y0 + 0.1), method="bounded", options={"xatol": 1e-10}).x
        R = rotation_for_direction(u, yaw)
        Rt = T @ R if kind == "pose_error" else R
        if j == 0:
            tr.hold(Rt, 1.0)
        elif j == 3:                            # the middle: an unlabelled rest between the two halves
            gap = (tau - poses[2][0]) - TWIN_HOLD_S - 2.0
            tr.move_to(R if kind == "bias_drift" else Rt, 1.0)
            tr.hold(tr.R_end, gap)
            tr.move_to(Rt, 1.0)
        else:
            tr.move_to(Rt, (tau - poses[j - 1][0]) - TWIN_HOLD_S)
        tr.hold(Rt, TWIN_HOLD_S, label=j, stated=g * u)
        if j == 2:
            t_mid = tr.end + 0.5 * ((poses[3][0] - poses[2][0]) - TWIN_HOLD_S)
    rate = dev.sample_rate_hz
    t = _sample_times(tr, rate)
    # pose j's middle sits at tau_j from t_mid: the holds are placed so
    sc = Scene(dev=dev, p=p, traj=tr, t=t, noise_mps2=noise, noise=rng.normal(size=(t.size, dev.n_channels)))
    lab, stated = tr.labels_and_stated(t)
    eff = {}
    if kind == "bias_drift":
        path = np.outer(t - t_mid, p["S"] @ rk)
        eff["bias_drift"] = {"path": path, "shape": "ramp", "rate_mps2_per_s": rk}
    else:
        # |f| along each axis grows by r_k tau at both faces: a gain of channel k (triad: channel k, axis k)
        gam = np.array([rk[k] * sign[k] * Tax[k] / g for k in range(3)])
        eff["gain"] = {"delta": gam}
    x = analog(sc, eff)
    raw = adc(sc, x, eff)
    rec = recording_from_arrays(t, raw, f=stated, temp_c=None, pose=lab,
                                metadata={"generator": "tests/python/indep_model.py"})
    ratio = {nm: contribution(sc, nm, pp) / sc.floor for nm, pp in eff.items()}
    if kind == "pose_error":
        m = lab >= 0
        F, _, _ = tr.evaluate(t)
        c = float(np.sqrt(np.sum(((F[m] - stated[m]) @ p["S"].T) ** 2) / (t.size * dev.n_channels)))
        eff["pose_error"] = {"angle_deg": tilt_deg, "kind": "tilt", "contribution": c}
        ratio["pose_error"] = c / sc.floor
    return {"device": dev, "cal": as_calibration(dev, p), "params": p, "recordings": [rec], "recording": rec,
            "effects": eff, "ratio": ratio, "noise_mps2": noise, "rate_hz": rate, "floor_counts": sc.floor,
            "layout": f"six-pose twin ({kind})", "scene": sc, "t_mid": t_mid,
            "twin": "bias_drift" if kind == "pose_error" else "pose_error"}
# =============================================================================== shifts between sessions
#: kinds of make_sessions (issue 33): an offset or a gain of the diagnosed session that differs from the
#: calibration session's, constant in time, alone and beside a drift or a time skew of that session;
#: with the temperature column varying in the diagnosed session ("varying") or constant there ("constant")
SESSION_KINDS = ("session_offset", "session_gain", "session_gain+bias_drift", "time_skew+session_offset")
SESSION_TEMPS = ("varying", "constant")
#: the independent model's effect that makes each session kind's change in the diagnosed session
SESSION_AS = {"session_offset": "offset", "session_gain": "gain"}
#: the control: a true temperature effect (an offset through a 30-120 s lag, zero at the calibration's
#: temperature), which must still be named where the temperature varies within the diagnosed session
SESSION_CONTROLS = ("temperature_offset",)


def _shift_params(sc: Scene, name: str, target: float, rng) -> dict:
    """An offset shift on every channel, all one sign (9-17 counts in the proportions of a
    turn-on repeatability), or a gain shift of random signs on every channel, sized to
    ``target`` counts RMS in the session ``sc``."""
    N = sc.dev.n_channels
    if name == "offset":
        return _scaled(sc, name, {"delta": rng.choice([-1.0, 1.0]) * rng.uniform(9.0, 17.0, N)}, ["delta"], target)
    return draw_effect(sc, name, target, rng)


def make_sessions(kind: str, seed=0, *, temperature: str = "varying", device=None, rate=None, noise=None,
                  ratio=None, cal_temp_c: float = 25.0):
    """Two sessions of one sensor: the calibration's and the diagnosed one (issue 33).

    Session 1: a jig of 12-20 stated poses (faces, edges, corners) held 2-4 s, at a constant
    ``cal_temp_c`` degC, nothing but noise: the true calibration fits it.  Session 2:
    ordinary motion with its reference, 8-14 stated poses held 2-4 s and 15-25 s of turns and
    shaking between them and at the end; its temperature column rises from 18 to 42 degC
    through the recording (``temperature`` "varying") or stays at one value drawn from
    18-42 degC ("constant").  The session kind's change (``SESSION_KINDS``: a shift of every
    channel's offset, or of every channel's gain, constant in time; with a drift path or a
    per-channel time skew and jitter of session 2) acts in session 2 only; no effect follows
    the temperature, except in the control kind ``temperature_offset`` (``SESSION_CONTROLS``: an
    offset through the sensor's 30-120 s thermal lag, zero at ``cal_temp_c``).

    Returns make_jig's dict with ``recordings`` [session 1, session 2] and ``cal`` the true
    calibration with ``temp_ref_c`` = ``cal_temp_c`` (what a calibration of session 1 states)."""
    names = kind.split("+")
    if temperature not in SESSION_TEMPS or not set(names) <= set(SESSION_AS) | {"bias_drift", "time_skew",
                                                                                 *SESSION_CONTROLS}:
        raise ValueError(f"unknown session kind {kind!r} / temperature {temperature!r}")
    rng = np.random.default_rng([int(seed), 0x5E55])
    name = device or str(rng.choice(list(DEVICES)))
    rate = float(rate or rng.choice([50.0, 100.0, 200.0]))
    noise = noise or math.exp(rng.uniform(math.log(0.002), math.log(0.05)))
    dev = DEVICES[name](rate)
    p = true_parameters(dev, rng)
    g = dev.gravity_mps2
    allp = FACES + EDGES + CORNERS
    # session 1: the calibration's jig, constant temperature, no effect
    dirs = [allp[k] for k in rng.permutation(len(allp))[:int(rng.integers(12, 21))]]
    tr1 = jig_trajectory(g, FACES + [d for d in dirs if not any(np.allclose(d, f) for f in FACES)], rng)
    t1 = _sample_times(tr1, rate)
    sc1 = Scene(dev=dev, p=p, traj=tr1, t=t1, noise_mps2=noise, noise=rng.normal(size=(t1.size, dev.n_channels)),
                temp_amb=np.full(t1.size, float(cal_temp_c)))
    lab1, st1 = tr1.labels_and_stated(t1)
    raw1 = adc(sc1, analog(sc1, {}), {})
    rec1 = _recording(sc1, raw1, True, st1, lab1, None)
    # session 2: poses with motion between and after them, the reference throughout
    tr2 = jig_trajectory(g, [allp[k] for k in rng.permutation(len(allp))[:int(rng.integers(8, 15))]], rng)
    t_motion = tr2.end
    tr2.move_to(tr2.R_end, 1.0)
    append_motion(tr2, rng.uniform(15.0, 25.0), rng)
    t2 = _sample_times(tr2, rate)
    if temperature == "varying":
        s = (t2 - t2[0]) / max(t2[-1] - t2[0], 1e-9)
        T2 = 18.0 + 24.0 * (0.5 - 0.5 * np.cos(math.pi * s))
    else:
        T2 = np.full(t2.size, float(rng.uniform(18.0, 42.0)))
    sc2 = Scene(dev=dev, p=p, traj=tr2, t=t2, noise_mps2=noise, noise=rng.normal(size=(t2.size, dev.n_channels)),
                temp_amb=T2)
    ratio = dict(ratio or {})
    eff, measured = {}, {}
    for nm in names:
        key = SESSION_AS.get(nm, nm)
        target = ratio.get(nm) or math.exp(rng.uniform(math.log(RATIO_LO), math.log(RATIO_HI)))
        eff[key] = _shift_params(sc2, key, target * sc2.floor, rng) if nm in SESSION_AS else \
            draw_effect(sc2, key, target * sc2.floor, rng)
        if key == "temperature_offset":
            # zero at the calibration's temperature (session 1 reads none of it), resized to the target
            eff[key]["t_ref_c"] = float(cal_temp_c)
            c = contribution(sc2, key, eff[key])
            eff[key]["beta"] = eff[key]["beta"] * (target * sc2.floor / c if c > 0 else 1.0)
        measured[nm] = contribution(sc2, key, eff[key]) / sc2.floor
    sc2.eff = eff
    raw2 = adc(sc2, analog(sc2, eff), eff)
    lab2, st2 = tr2.labels_and_stated(t2)
    rec2 = _recording(sc2, raw2, True, st2, lab2, t2 >= t_motion)
    cal = as_calibration(dev, p)
    cal.temp_ref_c = float(cal_temp_c)
    return {"device": dev, "cal": cal, "params": p, "recordings": [rec1, rec2], "recording": rec2,
            "effects": eff, "ratio": measured, "noise_mps2": noise, "rate_hz": rate, "floor_counts": sc2.floor,
            "layout": f"calibration jig {len(tr1.t0)} segments at {cal_temp_c:g} degC + session of "
                      f"{t2[-1]:.0f} s with motion, temperature {temperature} "
                      f"{float(T2.min()):.1f}-{float(T2.max()):.1f} degC", "scenes": (sc1, sc2)}


__all__ = ["IN_TABLE", "OUT_OF_TABLE", "PAIRS", "MOVING_ONLY", "DEVICES", "triad16", "adxl12", "seed6",
           "true_parameters", "as_calibration", "make_jig", "make_handheld", "make_six_pose", "load_real",
           "load_imucal", "load_mpu6050", "inject", "real_model", "as_posed", "static_mask", "real_noise", "Trajectory",
           "contribution", "make_temperature_lag", "make_lowpass", "make_six_pose_twin",
           "SESSION_KINDS", "SESSION_TEMPS", "SESSION_CONTROLS", "make_sessions"]


# =============================================================================== arrays that turn fast
def spin_trajectory(g, rng, n_turns=20, max_rate=40.0, min_rate=0.3, lead_s=1.0):
    """Back-to-back quintic turns about random axes, each of peak rate drawn log-uniformly in
    [min_rate, max_rate] rad/s over 0.3-1.5 s (so up to several revolutions: the angle
    phi = peak * dur / 1.875), the origin moving 2-10 cm in each; a rest of ``lead_s`` first
    and 0.5 s last.  Every |omega| from 0 to the peak is crossed in each turn."""
    tr = Trajectory(g=g)
    tr.hold(random_rotation(rng), lead_s)
    for _ in range(n_turns):
        ax = rng.normal(size=3)
        peak = math.exp(rng.uniform(math.log(min_rate), math.log(max_rate)))
        dur = rng.uniform(0.3, 1.5)
        dvec = rng.normal(size=3)
        # not move_to: a turn of more than pi is meant (move_to takes the shortest rotation)
        tr._add(tr.R_end, dur, ax / np.linalg.norm(ax), peak * dur / 1.875,
                dvec / np.linalg.norm(dvec) * rng.uniform(0.02, 0.1), -1, np.full(3, np.nan))
    tr.hold(tr.R_end, 0.5)
    return tr


def make_spin_array(device: Device, seed=0, *, n_turns=20, max_rate=40.0, min_rate=0.3, noise=None,
                    rate=None, with_w=False):
    """An array (any Device, e.g. accelcal.io.device.tetrahedron_device()) turned fast
    (:func:`spin_trajectory`), true channel parameters drawn about the nominal
    (:func:`true_parameters`: offsets, gains, axes off by up to 1.5 deg; positions nominal),
    white noise ``noise`` m/s^2 (default the device's), rounding and clipping.  The recording
    has no w columns unless ``with_w``.

    Returns a dict: device, cal (the true Calibration), recording, w, dw, f (the true body
    omega rad/s, alpha rad/s^2, f m/s^2 per sample), noise_mps2, rate_hz."""
    rng = np.random.default_rng(seed + 36)
    rate = float(rate or device.sample_rate_hz)
    noise = float(device.noise_mps2 if noise is None else noise)
    p = true_parameters(device, rng)
    traj = spin_trajectory(device.gravity_mps2, rng, n_turns, max_rate, min_rate)
    t = _sample_times(traj, rate)
    sc = Scene(dev=device, p=p, traj=traj, t=t, noise_mps2=noise, noise=rng.normal(size=(t.size, device.n_channels)))
    raw = adc(sc, analog(sc, {}), {})
    f, w, dw = traj.evaluate(t)
    rec = recording_from_arrays(t, raw, w=w if with_w else None, metadata={"generator": "tests/python/indep_model.py"})
    return {"device": device, "cal": as_calibration(device, p), "params": p, "recording": rec, "w": w, "dw": dw,
            "f": f, "noise_mps2": noise, "rate_hz": rate}


def make_array_calibration(device: Device, seed=0, *, rotations=True, n_turns=12, max_rate=20.0, true_params=None):
    """A 12-channel user's calibration session: the jig's 18 poses (faces and edges, each held
    1-2 s with its stated f), then with ``rotations`` a turning part with its reference f,
    omega and alpha (a turntable or a gyro beside the array: :func:`spin_trajectory`'s turns).
    ``true_params`` (b, S, r): the device's true channel parameters (default: drawn).
    Returns make_jig's keys device, cal (the truth), recording."""
    rng = np.random.default_rng(seed + 3636)
    p = true_parameters(device, rng)
    if true_params is not None:
        p = true_params
    traj = jig_trajectory(device.gravity_mps2, FACES + EDGES, rng, hold_s=(1.0, 2.0))
    t_motion = traj.end
    if rotations:
        spin = spin_trajectory(device.gravity_mps2, rng, n_turns, max_rate, 1.0, lead_s=0.5)
        traj.move_to(spin.R0[0], 1.0)
        for k in range(1, len(spin.t0)):
            traj._add(traj.R_end, spin.dur[k], spin.e[k], spin.phi[k], spin.d[k], -1, np.full(3, np.nan))
    t = _sample_times(traj, device.sample_rate_hz)
    sc = Scene(dev=device, p=p, traj=traj, t=t, noise_mps2=device.noise_mps2,
               noise=rng.normal(size=(t.size, device.n_channels)))
    lab, stated = traj.labels_and_stated(t)
    raw = adc(sc, analog(sc, {}), {})
    rec = _recording(sc, raw, True, stated, lab, (t >= t_motion) if rotations else None)
    return {"device": device, "cal": as_calibration(device, p), "recording": rec}
