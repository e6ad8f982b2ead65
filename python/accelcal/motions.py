"""Motion profiles: exact rigid-body kinematics for the simulator.

Every motion is a function ``(device, rng, **params) -> Trajectory`` registered
in ``MOTIONS`` with its parameters (names, defaults, units, docs).  Each is
built from an analytic *evaluator* (times -> attitude, position, f, omega,
alpha), so the sampled arrays are exactly consistent with each other and the
same evaluator gives the motion at shifted times (``time_skew``).

Conventions (shared/spec/data-contract.md)
-------------------------------------------
* World frame: z up; gravity ``g_vec = (0, 0, -g)`` with ``g`` the device's
  ``gravity_mps2``.
* ``attitude`` C (n, 3, 3) rotates body to world: ``v_world = C v_body``;
  ``dC/dt = C [omega]x`` (omega in BODY axes); ``alpha = d omega / dt``.
* ``position`` (n, 3): world position of the body origin O (m), starting at 0.
* ``f`` (n, 3): specific force at O in BODY axes, ``f = C^T (a_O - g_vec)``;
  at rest ``f = C^T (0, 0, g)``, magnitude g, pointing up.
* ``pose`` (n,): label >= 0 while the body is in a static pose, -1 moving.
* ``temp_c`` (n,): degC, from the temperature profile (default constant 25).

All times in s, angles in the parameters in degrees, lengths in m unless the
name says otherwise (``_cm``, ``_mm``).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from .sensor import interp_truth, rotation_matrix
from .spec import Param, check_params, format_spec, parse_spec, with_defaults
from .errors import AccelcalError

__all__ = [
    "Trajectory",
    "Kinematics",
    "Motion",
    "MOTIONS",
    "MOTION_NAMES",
    "POSE_SETS",
    "pose_directions",
    "get_motion",
    "parse_motion_spec",
    "describe_motions",
    "temperature_profile",
]


class Kinematics(NamedTuple):
    """Exact kinematics at a set of times (shapes (m, 3, 3) and (m, 3))."""

    attitude: np.ndarray
    position: np.ndarray
    f: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray


@dataclass(eq=False)
class Trajectory:
    """Sampled truth of one motion (see the module doc for frames and units).

    ``evaluator`` (times -> Kinematics) is the exact motion between samples;
    None for a trajectory made from a recording's reference columns, in which
    case :meth:`sample` interpolates.
    """

    t: np.ndarray  # (n,) s
    attitude: np.ndarray | None  # (n, 3, 3) body -> world
    f: np.ndarray  # (n, 3) m/s^2, body axes
    omega: np.ndarray  # (n, 3) rad/s, body axes
    alpha: np.ndarray  # (n, 3) rad/s^2, body axes
    pose: np.ndarray  # (n,) int64
    temp_c: np.ndarray  # (n,) degC
    position: np.ndarray | None = None  # (n, 3) m, world
    gravity_mps2: float = 9.80665
    name: str = ""
    params: dict = field(default_factory=dict)
    # evaluator(times, position=True) -> Kinematics (position may be None when not asked for)
    evaluator: Callable[..., Kinematics] | None = None

    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if self.t.size else 0.0

    def spec(self) -> str:
        """``name:k=v,...`` of the parameters that were given."""
        return format_spec(self.name, self.params)

    def sample(self, times: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f, omega, alpha) at arbitrary times: exact with an evaluator,
        cubic-spline interpolated otherwise."""
        times = np.asarray(times, float)
        if self.evaluator is not None:
            k = self.evaluator(times, position=False)
            return k.f, k.omega, k.alpha

        return interp_truth(self, times)

    def world_acceleration(self) -> np.ndarray:
        """a_O in world axes (n, 3): C f + g_vec (needs the attitude)."""
        if self.attitude is None:
            raise ValueError("world_acceleration needs the attitude")
        return np.einsum("nij,nj->ni", self.attitude, self.f) - np.array([0.0, 0.0, self.gravity_mps2])

    @classmethod
    def from_recording(cls, rec: Any, gravity_mps2: float = 9.80665) -> "Trajectory":
        """Truth from a recording's reference columns.  Unknown values stay NaN,
        except omega and alpha of static-pose samples (pose >= 0), which are 0
        by definition of a static pose (a jig file may give f only)."""
        pose = np.asarray(rec.pose, np.int64)
        static = (pose >= 0)[:, None]
        omega = np.asarray(rec.w, float)
        alpha = np.asarray(rec.dw, float)
        omega = np.where(static & np.isnan(omega), 0.0, omega)
        alpha = np.where(static & np.isnan(alpha), 0.0, alpha)
        return cls(t=np.asarray(rec.t, float), attitude=None, f=np.asarray(rec.f, float), omega=omega,
                   alpha=alpha, pose=pose, temp_c=np.asarray(rec.temp_c, float),
                   gravity_mps2=gravity_mps2, name="recording")


# ==========================================================================
# Small kinematic helpers
# ==========================================================================

_EZ = np.array([0.0, 0.0, 1.0])


def _to_body(C: np.ndarray, v: np.ndarray) -> np.ndarray:
    """C^T v for batches: C (m,3,3), v (m,3) or (3,)."""
    if v.ndim == 1:
        return np.einsum("nji,j->ni", C, v)
    return np.einsum("nji,nj->ni", C, v)


def _rot_y(th: np.ndarray) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    o, z = np.ones_like(th), np.zeros_like(th)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def _rot_x(th: np.ndarray) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    o, z = np.ones_like(th), np.zeros_like(th)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def _rot_z(th: np.ndarray) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    o, z = np.ones_like(th), np.zeros_like(th)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def _up_attitudes(d: np.ndarray, heading: Any = 0.0) -> np.ndarray:
    """Body->world C (P, 3, 3) with C d = z (body direction d points up), by the
    smallest rotation, then turned by ``heading`` (rad) about the world vertical."""
    d = np.atleast_2d(np.asarray(d, float))
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    axis = np.cross(d, _EZ)
    s = np.linalg.norm(axis, axis=1)
    c = d[:, 2]
    ok = s > 1e-12
    rv = np.where(ok[:, None], axis / np.where(ok, s, 1.0)[:, None] * np.arctan2(s, c)[:, None], 0.0)
    rv[~ok & (c < 0)] = [math.pi, 0.0, 0.0]
    heading = np.broadcast_to(np.asarray(heading, float), (d.shape[0],))
    return _rot_z(heading) @ rotation_matrix(rv)


def _up_attitude(d: np.ndarray, heading: float = 0.0) -> np.ndarray:
    """One pose of :func:`_up_attitudes`: C (3, 3)."""
    return _up_attitudes(np.asarray(d, float)[None, :], heading)[0]


def _rotvecs_between(Ca: np.ndarray, Cb: np.ndarray) -> np.ndarray:
    """Body-frame rotation vectors v (P, 3) with Cb = Ca Exp(v)."""
    return Rotation.from_matrix(np.einsum("pji,pjk->pik", Ca, Cb)).as_rotvec()


def _profile(u: np.ndarray, kind: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rest-to-rest shape S(u), S'(u), S''(u) on u in [0, 1] (held outside)."""
    inside = (u > 0.0) & (u < 1.0)
    uc = np.clip(u, 0.0, 1.0)
    if kind == "minjerk":
        S = uc**3 * (10.0 - 15.0 * uc + 6.0 * uc * uc)
        S1 = 30.0 * uc * uc * (1.0 - uc) ** 2
        S2 = 60.0 * uc * (1.0 - uc) * (1.0 - 2.0 * uc)
    elif kind == "cycloid":
        w = 2.0 * math.pi * uc
        S = uc - np.sin(w) / (2.0 * math.pi)
        S1 = 1.0 - np.cos(w)
        S2 = 2.0 * math.pi * np.sin(w)
    else:  # pragma: no cover - guarded by the Param choices
        raise ValueError(kind)
    return S, np.where(inside, S1, 0.0), np.where(inside, S2, 0.0)


# ==========================================================================
# Evaluators
# ==========================================================================


class _Segments:
    """Piecewise motion: segment k starts at t0[k] in attitude C0[k] and world
    position p0[k], then over dur[k] turns by angle[k] about the body axis
    axis[k] and moves by dp[k] (world) with a rest-to-rest profile; it holds
    the end state until the next segment starts.  Segments with zero angle and
    zero dp are static holds."""

    def __init__(self, t0, dur, C0, axis, angle, p0, dp, label, g: float, profile: str = "minjerk"):
        self.t0 = np.asarray(t0, float)
        self.dur = np.asarray(dur, float)
        self.C0 = np.asarray(C0, float)
        self.axis = np.asarray(axis, float)
        self.angle = np.asarray(angle, float)
        self.p0 = np.asarray(p0, float)
        self.dp = np.asarray(dp, float)
        self.label = np.asarray(label, np.int64)
        self.g = float(g)
        self.kind = profile

    def _index(self, times: np.ndarray) -> np.ndarray:
        return np.clip(np.searchsorted(self.t0, times, side="right") - 1, 0, self.t0.size - 1)

    def labels(self, times: np.ndarray) -> np.ndarray:
        k = self._index(times)
        u = (times - self.t0[k]) / self.dur[k]
        moving = (np.abs(self.angle[k]) > 0) | np.any(self.dp[k] != 0, axis=1)
        return np.where(moving & (u < 1.0), -1, self.label[k])

    def __call__(self, times: np.ndarray, position: bool = True) -> Kinematics:
        times = np.asarray(times, float)
        k = self._index(times)
        T = self.dur[k]
        S, S1, S2 = _profile((times - self.t0[k]) / T, self.kind)
        ang = self.angle[k]
        ax = self.axis[k]
        th = (ang * S)[:, None] * ax
        C = self.C0[k] @ rotation_matrix(th)
        omega = (ang * S1 / T)[:, None] * ax
        alpha = (ang * S2 / T**2)[:, None] * ax
        pos = self.p0[k] + S[:, None] * self.dp[k]
        acc = (S2 / T**2)[:, None] * self.dp[k]
        f = _to_body(C, acc + self.g * _EZ)
        return Kinematics(C, pos, f, omega, alpha)


class _AxisRotation:
    """C(t) = M Exp(axis theta(t)) about a body axis through the body point
    ``center`` (fixed in the world); theta_fn(t) -> (theta, theta', theta'')."""

    def __init__(self, M, axis, center, theta_fn, g: float):
        self.M = np.asarray(M, float)
        self.axis = np.asarray(axis, float)
        self.center = np.asarray(center, float)
        self.theta_fn = theta_fn
        self.g = float(g)
        self.C_start = self.M @ rotation_matrix(self.axis * float(theta_fn(np.zeros(1))[0][0]))

    def __call__(self, times: np.ndarray, position: bool = True) -> Kinematics:
        times = np.asarray(times, float)
        th, th1, th2 = self.theta_fn(times)
        C = self.M @ rotation_matrix(th[:, None] * self.axis)
        omega = th1[:, None] * self.axis
        alpha = th2[:, None] * self.axis
        c = self.center
        # O = P - C c with P fixed: a_O (body) = -(alpha x c + omega x (omega x c))
        a_body = -(np.cross(alpha, c) + np.cross(omega, np.cross(omega, c)))
        f = a_body + _to_body(C, self.g * _EZ)
        pos = (self.C_start @ c) - np.einsum("nij,j->ni", C, c)
        return Kinematics(C, pos, f, omega, alpha)


_FAST_BLOCK = 1024


def _sincos(times: np.ndarray, w: np.ndarray, ph: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin and cos of w t + ph, (n, k).  On a uniform time grid (to 1e-11 s)
    the phases are built by angle addition from a coarse and a fine table
    (same accuracy, a fraction of the trigonometric work)."""
    n = times.size
    if n >= 4 * _FAST_BLOCK:
        t0 = float(times[0])
        dt = (float(times[-1]) - t0) / (n - 1)
        j = np.arange(n)
        if dt > 0 and np.max(np.abs(times - (t0 + j * dt))) <= 1e-11:
            B = _FAST_BLOCK
            M = -(-n // B)
            coarse = np.exp(1j * ((t0 + np.arange(M)[:, None] * (B * dt)) * w[None, :] + ph[None, :]))
            fine = np.exp(1j * (np.arange(B)[:, None] * dt * w[None, :]))
            e = (coarse[:, None, :] * fine[None, :, :]).reshape(M * B, -1)[:n]
            return e.imag, e.real
    arg = times[:, None] * w[None, :] + ph[None, :]
    return np.sin(arg), np.cos(arg)


def _sum_of_tones(times: np.ndarray, amp: np.ndarray, w: np.ndarray, ph: np.ndarray):
    """x = sum a sin(w t + ph) and its first and second derivatives."""
    s, c = _sincos(times, w, ph)
    return s @ amp, c @ (amp * w), -(s @ (amp * w * w))


def _tones(rng: np.random.Generator, k: int, f_lo: float, f_hi: float, rms: float):
    """k random tones in [f_lo, f_hi] Hz with random phases, scaled to ``rms``."""
    f = rng.uniform(f_lo, f_hi, k)
    amp = rng.rayleigh(1.0, k)
    amp *= rms / math.sqrt(0.5 * float(np.sum(amp * amp)))
    return amp, 2.0 * math.pi * f, rng.uniform(0.0, 2.0 * math.pi, k)


# ==========================================================================
# Pose sets
# ==========================================================================


def _faces() -> np.ndarray:
    return np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)


def _edges() -> np.ndarray:
    out = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        for si in (1, -1):
            for sj in (1, -1):
                v = np.zeros(3)
                v[i], v[j] = si, sj
                out.append(v / math.sqrt(2.0))
    return np.array(out)


def _corners() -> np.ndarray:
    return np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)], float) / math.sqrt(3.0)


#: Preset pose sets: the body direction that points up in each pose (f = g d).
POSE_SETS: dict[str, str] = {
    "4": "the seed's four poses (eq. 19): f along +x, +y, +z, -z",
    "6": "the six faces: f along +-x, +-y, +-z",
    "18": "six faces and twelve edges (45 deg tilts)",
    "24": "the 24 rotations of a cube: each face up, turned 0/90/180/270 deg about the vertical",
    "26": "faces, edges and corners",
}


def pose_directions(poses: Any) -> tuple[np.ndarray, np.ndarray]:
    """(up directions (P, 3) unit, headings (P,) rad) for a preset name or a list."""
    if isinstance(poses, str):
        if poses == "4":
            d = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]], float)
        elif poses == "6":
            d = _faces()
        elif poses == "18":
            d = np.vstack([_faces(), _edges()])
        elif poses == "24":
            d = np.repeat(_faces(), 4, axis=0)
            return d, np.tile(np.radians([0.0, 90.0, 180.0, 270.0]), 6)
        elif poses == "26":
            d = np.vstack([_faces(), _edges(), _corners()])
        else:
            raise AccelcalError(f"unknown pose set {poses!r}; sets: {', '.join(POSE_SETS)}")
        return d, np.zeros(d.shape[0])
    d = np.atleast_2d(np.asarray(poses, float))
    return d / np.linalg.norm(d, axis=1, keepdims=True), np.zeros(d.shape[0])


def _random_directions(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _static_segments(C: np.ndarray, period: float, g: float) -> _Segments:
    P = C.shape[0]
    t0 = np.arange(P) * period
    z3 = np.zeros((P, 3))
    return _Segments(t0, np.full(P, period), C, np.tile(_EZ, (P, 1)), np.zeros(P), z3, z3, np.arange(P), g)


def _static_times(P: int, spp: int, rate: float, dwell: float | None) -> tuple[np.ndarray, float]:
    rec = spp / rate
    period = rec + 1.0 if dwell is None else dwell
    if period < rec - 1e-12:
        raise AccelcalError(
            f"motion parameter 'dwell_s': expected at least samples_per_pose / rate = {rec:g} s, got {period:g}"
        )
    t = (np.arange(P)[:, None] * period + np.arange(spp)[None, :] / rate).ravel()
    return t, period


# ==========================================================================
# The motions
# ==========================================================================


def _static_poses(device, rng, *, poses, samples_per_pose, dwell_s, heading_deg):
    d, heads = pose_directions(poses)
    C = _up_attitudes(d, heads + math.radians(heading_deg))
    t, period = _static_times(C.shape[0], samples_per_pose, float(device.sample_rate_hz), dwell_s)
    return t, _static_segments(C, period, device.gravity_mps2)


def _random_poses(device, rng, *, n_poses, samples_per_pose, dwell_s):
    d = _random_directions(rng, n_poses)
    C = _up_attitudes(d, rng.uniform(0.0, 2.0 * math.pi, n_poses))
    t, period = _static_times(n_poses, samples_per_pose, float(device.sample_rate_hz), dwell_s)
    return t, _static_segments(C, period, device.gravity_mps2)


def _handheld(device, rng, *, n_poses, hold_s, move_s, initial_rest_s, move_cm):
    g = device.gravity_mps2
    P = n_poses + 1  # pose 0 is the initial rest, body z up
    d = np.vstack([_EZ, _random_directions(rng, n_poses)])
    C = _up_attitudes(d, rng.uniform(0.0, 2.0 * math.pi, P))
    # hand positions: random points in a ball of radius move_cm around the start
    r = 0.01 * move_cm
    pts = np.zeros((P, 3))
    if r > 0:
        v = _random_directions(rng, n_poses)
        pts[1:] = v * (r * rng.uniform(0.0, 1.0, n_poses) ** (1.0 / 3.0))[:, None]
    rv = _rotvecs_between(C[:-1], C[1:])  # move i: from pose i to pose i + 1
    ang = np.linalg.norm(rv, axis=1)
    ax = np.where(ang[:, None] > 0, rv / np.where(ang > 0, ang, 1.0)[:, None], _EZ)
    # segments: hold 0, move 0, hold 1, move 1, ..., hold P-1
    S = 2 * P - 1
    dur = np.empty(S)
    dur[0::2] = hold_s
    dur[0] = initial_rest_s
    dur[1::2] = move_s
    t0 = np.concatenate([[0.0], np.cumsum(dur)[:-1]])
    Cs = np.repeat(C, 2, axis=0)[:S]
    axes = np.tile(_EZ, (S, 1))
    axes[1::2] = ax
    angles = np.zeros(S)
    angles[1::2] = ang
    p0 = np.repeat(pts, 2, axis=0)[:S]
    dp = np.zeros((S, 3))
    dp[1::2] = pts[1:] - pts[:-1]
    labels = np.full(S, -1)
    labels[0::2] = np.arange(P)
    ev = _Segments(t0, dur, Cs, axes, angles, p0, dp, labels, g)
    rate = float(device.sample_rate_hz)
    total = float(t0[-1] + dur[-1])
    times = np.arange(int(math.floor(total * rate + 1e-9))) / rate
    return times, ev


def _rate_table(device, rng, *, axis, freq_hz, amplitude_deg, duration_s, mount, center_m, rest_s, ramp_s):
    A = math.radians(amplitude_deg)
    w = 2.0 * math.pi * freq_hz
    M = _up_attitude(axis if mount is None else mount)

    def theta(t):
        tt = t - rest_s
        on = tt > 0
        s, c = np.sin(w * tt), np.cos(w * tt)
        if ramp_s > 0:
            e, e1, e2 = _profile(tt / ramp_s, "minjerk")
            e1, e2 = e1 / ramp_s, e2 / ramp_s**2
        else:
            e, e1, e2 = np.ones_like(tt), np.zeros_like(tt), np.zeros_like(tt)
        th = A * e * s
        th1 = A * (e1 * s + e * w * c)
        th2 = A * (e2 * s + 2.0 * e1 * w * c - e * w * w * s)
        return np.where(on, th, 0.0), np.where(on, th1, 0.0), np.where(on, th2, 0.0)

    ev = _AxisRotation(M, axis, center_m, theta, device.gravity_mps2)
    rate = float(device.sample_rate_hz)
    times = np.arange(int(math.floor((rest_s + duration_s) * rate + 1e-9))) / rate
    labels = np.where(times < rest_s, 0, -1)
    return times, ev, labels


def _pendulum(device, rng, *, amplitude_deg, freq_hz, center_deg, duration_s, decay_s):
    A = math.radians(amplitude_deg)
    th0 = math.radians(center_deg)
    w = 2.0 * math.pi * freq_hz
    lam = 0.0 if decay_s == 0 else 1.0 / decay_s

    def theta(t):
        E = np.exp(-lam * t)
        c, s = np.cos(w * t), np.sin(w * t)
        th = th0 + A * E * c
        th1 = A * E * (-lam * c - w * s)
        th2 = A * E * ((lam * lam - w * w) * c + 2.0 * lam * w * s)
        return th, th1, th2

    ev = _AxisRotation(np.eye(3), np.array([0.0, 1.0, 0.0]), np.zeros(3), theta, device.gravity_mps2)
    rate = float(device.sample_rate_hz)
    times = np.arange(int(math.floor(duration_s * rate + 1e-9))) / rate
    return times, ev, np.full(times.shape, -1)


def _linear_actuator(device, rng, *, axis, distance_m, travel_s, rest_s, strokes, tilt_deg, tilt_axis, profile):
    C0 = rotation_matrix(np.asarray(tilt_axis) * math.radians(tilt_deg))
    step = C0 @ (np.asarray(axis) * distance_m)  # world displacement of one stroke
    t0, dur, Cs, ax, ang, p0, dp, lab = [], [], [], [], [], [], [], []
    t, p = 0.0, np.zeros(3)
    for k in range(strokes + 1):
        t0.append(t); dur.append(rest_s); Cs.append(C0); ax.append(_EZ); ang.append(0.0)
        p0.append(p.copy()); dp.append(np.zeros(3)); lab.append(k)
        t += rest_s
        if k < strokes:
            d = step if k % 2 == 0 else -step
            t0.append(t); dur.append(travel_s); Cs.append(C0); ax.append(_EZ); ang.append(0.0)
            p0.append(p.copy()); dp.append(d); lab.append(-1)
            t += travel_s
            p = p + d
    ev = _Segments(t0, dur, Cs, ax, ang, p0, dp, lab, device.gravity_mps2, profile)
    rate = float(device.sample_rate_hz)
    times = np.arange(int(math.floor(t * rate + 1e-9))) / rate
    return times, ev


class _LaneChange:
    """Planar vehicle, forward speed component v constant along world x, path
    y(x) = Y [S((x - x1)/L1) - S((x - x3)/L3)] (min-jerk steps); body x
    forward, z up, heading psi = atan(y')."""

    def __init__(self, v, Y, x1, L1, x3, L3, g):
        self.v, self.Y, self.x1, self.L1, self.x3, self.L3, self.g = v, Y, x1, L1, x3, L3, g

    @staticmethod
    def _step(u: np.ndarray):
        inside = (u > 0) & (u < 1)
        uc = np.clip(u, 0.0, 1.0)
        S = uc**3 * (10.0 - 15.0 * uc + 6.0 * uc * uc)
        S1 = 30.0 * uc * uc * (1.0 - uc) ** 2
        S2 = 60.0 * uc * (1.0 - uc) * (1.0 - 2.0 * uc)
        S3 = 60.0 - 360.0 * uc + 360.0 * uc * uc
        return S, np.where(inside, S1, 0.0), np.where(inside, S2, 0.0), np.where(inside, S3, 0.0)

    def __call__(self, times: np.ndarray, position: bool = True) -> Kinematics:
        times = np.asarray(times, float)
        v = self.v
        x = v * times
        a1 = self._step((x - self.x1) / self.L1)
        a3 = self._step((x - self.x3) / self.L3)
        y = self.Y * (a1[0] - a3[0])
        y1 = self.Y * (a1[1] / self.L1 - a3[1] / self.L3)
        y2 = self.Y * (a1[2] / self.L1**2 - a3[2] / self.L3**2)
        y3 = self.Y * (a1[3] / self.L1**3 - a3[3] / self.L3**3)
        q = 1.0 + y1 * y1
        psi = np.arctan(y1)
        r = v * y2 / q
        r1 = v * v * (y3 * q - 2.0 * y1 * y2 * y2) / (q * q)
        C = _rot_z(psi)
        z = np.zeros_like(times)
        omega = np.column_stack([z, z, r])
        alpha = np.column_stack([z, z, r1])
        acc = np.column_stack([z, v * v * y2, z])
        f = _to_body(C, acc + self.g * _EZ)
        pos = np.column_stack([x, y, z])
        return Kinematics(C, pos, f, omega, alpha)


def _lane_change(device, rng, *, speed_mps, offset_m, lead_m, shift_m, hold_m, return_m, exit_m):
    x1 = lead_m
    x3 = lead_m + shift_m + hold_m
    ev = _LaneChange(speed_mps, offset_m, x1, shift_m, x3, return_m, device.gravity_mps2)
    total = (x3 + return_m + exit_m) / speed_mps
    rate = float(device.sample_rate_hz)
    times = np.arange(int(math.floor(total * rate + 1e-9)) + 1) / rate
    return times, ev, np.full(times.shape, -1)


class _Random6Dof:
    """C = Rz(psi) Ry(theta) Rx(phi) with band-limited random Euler angles (sums
    of tones) and a band-limited random world acceleration of O."""

    def __init__(self, tones_angles, tones_acc, g):
        self.ta = tones_angles  # [(amp, w, ph)] for phi, theta, psi
        self.tc = tones_acc  # [(amp, w, ph)] for a_x, a_y, a_z (world)
        self.g = g

    def __call__(self, times: np.ndarray, position: bool = True) -> Kinematics:
        times = np.asarray(times, float)
        (ph, ph1, ph2), (th, th1, th2), (ps, ps1, ps2) = (_sum_of_tones(times, *k) for k in self.ta)
        sf, cf, st, ct, sp, cp = np.sin(ph), np.cos(ph), np.sin(th), np.cos(th), np.sin(ps), np.cos(ps)
        C = np.empty((times.size, 3, 3))
        C[:, 0, 0] = cp * ct
        C[:, 0, 1] = cp * st * sf - sp * cf
        C[:, 0, 2] = cp * st * cf + sp * sf
        C[:, 1, 0] = sp * ct
        C[:, 1, 1] = sp * st * sf + cp * cf
        C[:, 1, 2] = sp * st * cf - cp * sf
        C[:, 2, 0] = -st
        C[:, 2, 1] = ct * sf
        C[:, 2, 2] = ct * cf
        p = ph1 - ps1 * st
        q = th1 * cf + ps1 * ct * sf
        r = -th1 * sf + ps1 * ct * cf
        p1 = ph2 - ps2 * st - ps1 * th1 * ct
        q1 = (th2 * cf - th1 * ph1 * sf + ps2 * ct * sf - ps1 * th1 * st * sf + ps1 * ph1 * ct * cf)
        r1 = (-th2 * sf - th1 * ph1 * cf + ps2 * ct * cf - ps1 * th1 * st * cf - ps1 * ph1 * ct * sf)
        omega = np.column_stack([p, q, r])
        alpha = np.column_stack([p1, q1, r1])
        acc = np.empty((times.size, 3))
        pos = np.empty((times.size, 3)) if position else None
        for k, (amp, w, phs) in enumerate(self.tc):
            s, _ = _sincos(times, w, phs)
            acc[:, k] = s @ amp
            if position:
                # position = -sum a/w^2 sin(w t + ph), relative to t = 0
                pos[:, k] = float(np.sum(amp / (w * w) * np.sin(phs))) - s @ (amp / (w * w))
        f = _to_body(C, acc + self.g * _EZ)
        return Kinematics(C, pos, f, omega, alpha)


def _random_6dof(device, rng, *, duration_s, bandwidth_hz, angle_rms_deg, accel_rms_mps2, tones):
    lo = 0.05 * bandwidth_hz
    ta = [_tones(rng, tones, lo, bandwidth_hz, math.radians(angle_rms_deg)) for _ in range(3)]
    tc = [_tones(rng, tones, max(lo, 0.2 * bandwidth_hz), bandwidth_hz, accel_rms_mps2) for _ in range(3)]
    ev = _Random6Dof(ta, tc, device.gravity_mps2)
    rate = float(device.sample_rate_hz)
    times = np.arange(int(math.floor(duration_s * rate + 1e-9))) / rate
    return times, ev, np.full(times.shape, -1)


# ==========================================================================
# Temperature profiles
# ==========================================================================

TEMP_PROFILES = ("constant", "ramp", "sine")


def temperature_profile(t: np.ndarray, kind: str = "constant", temp_c: float = 25.0, temp_end_c: float = 45.0,
                        temp_amplitude_c: float = 5.0, temp_period_s: float = 600.0) -> np.ndarray:
    """degC at times t: constant temp_c; ramp from temp_c at the first sample to
    temp_end_c at the last; sine temp_c + amplitude sin(2 pi (t - t0) / period)."""
    t = np.asarray(t, float)
    if kind == "constant" or t.size == 0:
        return np.full(t.shape, float(temp_c))
    t0, t1 = float(t[0]), float(t[-1])
    if kind == "ramp":
        if t1 == t0:
            return np.full(t.shape, float(temp_c))
        return temp_c + (temp_end_c - temp_c) * (t - t0) / (t1 - t0)
    if kind == "sine":
        return temp_c + temp_amplitude_c * np.sin(2.0 * math.pi * (t - t0) / temp_period_s)
    raise AccelcalError(f"unknown temperature profile {kind!r}; profiles: {', '.join(TEMP_PROFILES)}")


_TEMP_PARAMS = (
    Param("temp_profile", "constant", "-", "temperature profile: constant, ramp (temp_c -> temp_end_c over the "
          "recording) or sine (temp_c +- temp_amplitude_c, period temp_period_s)", "choice", choices=TEMP_PROFILES),
    Param("temp_c", 25.0, "degC", "constant / start / mean temperature"),
    Param("temp_end_c", 45.0, "degC", "ramp: temperature at the last sample"),
    Param("temp_amplitude_c", 5.0, "degC", "sine: amplitude"),
    Param("temp_period_s", 600.0, "s", "sine: period", minimum=0.0, exclusive_min=True),
)


# ==========================================================================
# Registry
# ==========================================================================


@dataclass(frozen=True, eq=False)
class Motion:
    """A registered motion: ``motion(device, rng, **params) -> Trajectory``."""

    name: str
    summary: str
    params: tuple[Param, ...]
    build: Callable[..., tuple]

    @property
    def all_params(self) -> tuple[Param, ...]:
        return self.params + _TEMP_PARAMS

    def check(self, given: Mapping[str, Any]) -> dict[str, Any]:
        return check_params(self.all_params, given, f"motion {self.name!r}")

    def __call__(self, device: Any, rng: np.random.Generator | None = None, **params: Any) -> Trajectory:
        given = self.check(params)
        full = with_defaults(self.all_params, given)
        temp = {p.name: full.pop(p.name) for p in _TEMP_PARAMS}
        rng = np.random.default_rng(0) if rng is None else rng
        out = self.build(device, rng, **full)
        if len(out) == 2:
            times, ev = out
            labels = ev.labels(times)
        else:
            times, ev, labels = out
        if times.size < 2:
            raise AccelcalError(f"motion {self.name!r}: fewer than 2 samples at {device.sample_rate_hz:g} Hz; "
                                "make it longer")
        k = ev(times)
        T = temperature_profile(times, temp["temp_profile"], temp["temp_c"], temp["temp_end_c"],
                                temp["temp_amplitude_c"], temp["temp_period_s"])
        # (+ 0.0 turns -0.0 into 0.0, so the CSV shows no "-0")
        return Trajectory(t=times, attitude=k.attitude, f=k.f + 0.0, omega=k.omega + 0.0, alpha=k.alpha + 0.0,
                          pose=np.asarray(labels, np.int64), temp_c=T, position=k.position,
                          gravity_mps2=float(device.gravity_mps2), name=self.name, params=dict(given),
                          evaluator=ev)

    def help(self) -> str:
        lines = [f"{self.name}: {self.summary}"]
        lines += [f"    {p.help()}" for p in self.params]
        return "\n".join(lines)


_SPP = Param("samples_per_pose", 60, "samples", "samples recorded in each pose", "int", minimum=1)
_DWELL = Param("dwell_s", None, "s", "time from one pose's first sample to the next's (the jig moves, unrecorded, "
               "after the samples); auto = samples_per_pose / rate + 1 s", "float", minimum=0.0, exclusive_min=True)

_ALL = (
    Motion("static_poses", "jig poses, each held still (f = g d for the pose's up direction d)", (
        Param("poses", "6", "-", "preset 4 (seed eq. 19), 6, 18, 24, 26, or a list of up directions like "
              "[x,y,z,-z] or [[1,0,1],...]", "poses"),
        _SPP, _DWELL,
        Param("heading_deg", 0.0, "deg", "turn of every pose about the vertical"),
    ), _static_poses),
    Motion("random_poses", "static poses in random orientations (uniform on the sphere, random heading)", (
        Param("n_poses", 24, "-", "number of poses", "int", minimum=1),
        _SPP, _DWELL,
    ), _random_poses),
    Motion("handheld", "hand-held session: a rest, then random poses held still with smooth hand moves "
           "between (min-jerk rotation and translation), like imu_tk's Xsens recording", (
        Param("n_poses", 40, "-", "number of poses after the initial rest", "int", minimum=1),
        Param("hold_s", 4.0, "s", "time held still in each pose", minimum=0.0, exclusive_min=True),
        Param("move_s", 2.0, "s", "duration of each move", minimum=0.0, exclusive_min=True),
        Param("initial_rest_s", 20.0, "s", "initial static period (body z up)", minimum=0.0, exclusive_min=True),
        Param("move_cm", 5.0, "cm", "hand positions wander within a ball of this radius", minimum=0.0),
    ), _handheld),
    Motion("rate_table", "sinusoidal rotation about a body axis: theta = A sin(2 pi f t)", (
        Param("axis", "z", "-", "body rotation axis", "direction"),
        Param("freq_hz", 2.0, "Hz", "frequency", minimum=0.0, exclusive_min=True),
        Param("amplitude_deg", 10.0, "deg", "angle amplitude A"),
        Param("duration_s", 10.0, "s", "duration of the oscillation", minimum=0.0, exclusive_min=True),
        Param("mount", None, "-", "body direction that points up (auto = axis: a vertical-axis table)", "direction"),
        Param("center_m", [0.0, 0.0, 0.0], "m", "a body point on the table axis (the body origin is off-axis "
              "when non-zero)", "vector"),
        Param("rest_s", 0.0, "s", "rest before the motion starts (pose label 0)", minimum=0.0),
        Param("ramp_s", 0.0, "s", "smooth (min-jerk) amplitude ramp-in time; 0 = start at full amplitude",
              minimum=0.0),
    ), _rate_table),
    Motion("pendulum", "swing about body y with the pivot at the body origin: theta = center + A e^(-t/decay) "
           "cos(2 pi f t), gravity in body axes g (-sin theta, 0, cos theta)", (
        Param("amplitude_deg", 40.0, "deg", "swing amplitude A"),
        Param("freq_hz", 0.5, "Hz", "swing frequency", minimum=0.0, exclusive_min=True),
        Param("center_deg", 0.0, "deg", "mean attitude (0: body z up at the centre, the seed's case; 90: body x "
              "points down, a hanging arm)"),
        Param("duration_s", 20.0, "s", "duration", minimum=0.0, exclusive_min=True),
        Param("decay_s", 0.0, "s", "amplitude e-folding time (0 = undamped)", minimum=0.0),
    ), _pendulum),
    Motion("linear_actuator", "stop-to-stop travel along a body axis: rest, smooth travel, rest "
           "(strokes alternate direction)", (
        Param("axis", "x", "-", "body axis of travel", "direction"),
        Param("distance_m", 0.2, "m", "travel of one stroke"),
        Param("travel_s", 1.0, "s", "duration of one stroke", minimum=0.0, exclusive_min=True),
        Param("rest_s", 2.0, "s", "rest before, between and after strokes (pose labels 0, 1, ...)",
              minimum=0.0, exclusive_min=True),
        Param("strokes", 1, "-", "number of strokes (back and forth)", "int", minimum=1),
        Param("tilt_deg", 0.0, "deg", "rail tilt: the body is turned by this about tilt_axis"),
        Param("tilt_axis", "y", "-", "body axis of the tilt", "direction"),
        Param("profile", "minjerk", "-", "travel profile: minjerk (quintic) or cycloid (sine acceleration)",
              "choice", choices=("minjerk", "cycloid")),
    ), _linear_actuator),
    Motion("lane_change", "vehicle double lane change (ISO 3888-1-like course) at constant forward speed; "
           "body x forward, z up", (
        Param("speed_mps", 16.667, "m/s", "forward speed (60 km/h)", minimum=0.0, exclusive_min=True),
        Param("offset_m", 3.5, "m", "lateral offset of the second lane"),
        Param("lead_m", 15.0, "m", "straight before the change", minimum=0.0),
        Param("shift_m", 30.0, "m", "length of the change-over", minimum=0.0, exclusive_min=True),
        Param("hold_m", 25.0, "m", "length driven in the other lane", minimum=0.0),
        Param("return_m", 25.0, "m", "length of the return", minimum=0.0, exclusive_min=True),
        Param("exit_m", 30.0, "m", "straight after the return", minimum=0.0),
    ), _lane_change),
    Motion("random_6dof", "band-limited random rotation (Euler angles as sums of tones) and translation "
           "(world acceleration as sums of tones), attitude exactly consistent", (
        Param("duration_s", 60.0, "s", "duration", minimum=0.0, exclusive_min=True),
        Param("bandwidth_hz", 1.0, "Hz", "highest tone frequency", minimum=0.0, exclusive_min=True),
        Param("angle_rms_deg", 30.0, "deg", "rms of each Euler angle", minimum=0.0),
        Param("accel_rms_mps2", 1.0, "m/s^2", "rms of each world acceleration component", minimum=0.0),
        Param("tones", 8, "-", "tones per signal", "int", minimum=1),
    ), _random_6dof),
)

#: name -> Motion
MOTIONS: dict[str, Motion] = {m.name: m for m in _ALL}
MOTION_NAMES: tuple[str, ...] = tuple(MOTIONS)


def get_motion(name: str) -> Motion:
    if isinstance(name, Motion):
        return name
    key = str(name).strip()
    if key in MOTIONS:
        return MOTIONS[key]
    close = difflib.get_close_matches(key, MOTION_NAMES, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise AccelcalError(f"unknown motion {key!r}{hint}; motions: {', '.join(MOTION_NAMES)}")


def parse_motion_spec(spec: str) -> tuple[Motion, dict[str, Any]]:
    """``"rate_table:freq_hz=2,axis=x"`` -> (Motion, checked params)."""
    name, raw = parse_spec(spec, "motion")
    m = get_motion(name)
    return m, m.check(raw)


def describe_motions() -> str:
    """Help text: every motion with its parameters, plus the temperature parameters."""
    parts = [MOTIONS[n].help() for n in MOTION_NAMES]
    parts.append("every motion also takes:\n" + "\n".join(f"    {p.help()}" for p in _TEMP_PARAMS))
    return "\n".join(parts)
