"""Exact rigid-body kinematics: the Trajectory object and the evaluators the profiles are built from."""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import AccelcalError
from ..sensor import interp_truth, rotation_matrix
from ..spec import format_spec


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


EZ = np.array([0.0, 0.0, 1.0])


def to_body(C: np.ndarray, v: np.ndarray) -> np.ndarray:
    """C^T v for batches: C (m,3,3), v (m,3) or (3,)."""
    if v.ndim == 1:
        return np.einsum("nji,j->ni", C, v)
    return np.einsum("nji,nj->ni", C, v)


def rot_y(th: np.ndarray) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    o, z = np.ones_like(th), np.zeros_like(th)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def rot_x(th: np.ndarray) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    o, z = np.ones_like(th), np.zeros_like(th)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def rot_z(th: np.ndarray) -> np.ndarray:
    c, s = np.cos(th), np.sin(th)
    o, z = np.ones_like(th), np.zeros_like(th)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def up_attitudes(d: np.ndarray, heading: Any = 0.0) -> np.ndarray:
    """Body->world C (P, 3, 3) with C d = z (body direction d points up), by the
    smallest rotation, then turned by ``heading`` (rad) about the world vertical."""
    d = np.atleast_2d(np.asarray(d, float))
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    axis = np.cross(d, EZ)
    s = np.linalg.norm(axis, axis=1)
    c = d[:, 2]
    ok = s > 1e-12
    rv = np.where(ok[:, None], axis / np.where(ok, s, 1.0)[:, None] * np.arctan2(s, c)[:, None], 0.0)
    rv[~ok & (c < 0)] = [math.pi, 0.0, 0.0]
    heading = np.broadcast_to(np.asarray(heading, float), (d.shape[0],))
    return rot_z(heading) @ rotation_matrix(rv)


def up_attitude(d: np.ndarray, heading: float = 0.0) -> np.ndarray:
    """One pose of :func:`up_attitudes`: C (3, 3)."""
    return up_attitudes(np.asarray(d, float)[None, :], heading)[0]


def rotvecs_between(Ca: np.ndarray, Cb: np.ndarray) -> np.ndarray:
    """Body-frame rotation vectors v (P, 3) with Cb = Ca Exp(v)."""
    return Rotation.from_matrix(np.einsum("pji,pjk->pik", Ca, Cb)).as_rotvec()


def smooth_profile(u: np.ndarray, kind: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


class Segments:
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
        S, S1, S2 = smooth_profile((times - self.t0[k]) / T, self.kind)
        ang = self.angle[k]
        ax = self.axis[k]
        th = (ang * S)[:, None] * ax
        C = self.C0[k] @ rotation_matrix(th)
        omega = (ang * S1 / T)[:, None] * ax
        alpha = (ang * S2 / T**2)[:, None] * ax
        pos = self.p0[k] + S[:, None] * self.dp[k]
        acc = (S2 / T**2)[:, None] * self.dp[k]
        f = to_body(C, acc + self.g * EZ)
        return Kinematics(C, pos, f, omega, alpha)


class AxisRotation:
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
        f = a_body + to_body(C, self.g * EZ)
        pos = (self.C_start @ c) - np.einsum("nij,j->ni", C, c)
        return Kinematics(C, pos, f, omega, alpha)


FAST_BLOCK = 1024


def sincos(times: np.ndarray, w: np.ndarray, ph: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin and cos of w t + ph, (n, k).  On a uniform time grid (to 1e-11 s)
    the phases are built by angle addition from a coarse and a fine table
    (same accuracy, a fraction of the trigonometric work)."""
    n = times.size
    if n >= 4 * FAST_BLOCK:
        t0 = float(times[0])
        dt = (float(times[-1]) - t0) / (n - 1)
        j = np.arange(n)
        if dt > 0 and np.max(np.abs(times - (t0 + j * dt))) <= 1e-11:
            B = FAST_BLOCK
            M = -(-n // B)
            coarse = np.exp(1j * ((t0 + np.arange(M)[:, None] * (B * dt)) * w[None, :] + ph[None, :]))
            fine = np.exp(1j * (np.arange(B)[:, None] * dt * w[None, :]))
            e = (coarse[:, None, :] * fine[None, :, :]).reshape(M * B, -1)[:n]
            return e.imag, e.real
    arg = times[:, None] * w[None, :] + ph[None, :]
    return np.sin(arg), np.cos(arg)


def sum_of_tones(times: np.ndarray, amp: np.ndarray, w: np.ndarray, ph: np.ndarray):
    """x = sum a sin(w t + ph) and its first and second derivatives."""
    s, c = sincos(times, w, ph)
    return s @ amp, c @ (amp * w), -(s @ (amp * w * w))


def random_tones(rng: np.random.Generator, k: int, f_lo: float, f_hi: float, rms: float):
    """k random tones in [f_lo, f_hi] Hz with random phases, scaled to ``rms``."""
    f = rng.uniform(f_lo, f_hi, k)
    amp = rng.rayleigh(1.0, k)
    amp *= rms / math.sqrt(0.5 * float(np.sum(amp * amp)))
    return amp, 2.0 * math.pi * f, rng.uniform(0.0, 2.0 * math.pi, k)


#: the most samples a simulation makes (its trajectory takes ~250 bytes a sample: 2.5 GB)
MAX_SAMPLES = 10_000_000


def sample_times(seconds: float, rate: float, extra: int = 0) -> np.ndarray:
    """The sample times 0, 1/rate, ... of ``seconds`` of recording (``extra`` samples more).

    Raises
    ------
    AccelcalError
        More than MAX_SAMPLES samples (one line, before any memory is taken)."""
    n = int(math.floor(seconds * rate + 1e-9)) + extra
    if n > MAX_SAMPLES:
        raise AccelcalError(f"the motion lasts {seconds:g} s at {rate:g} Hz: {n:,} samples, more than the "
                            f"{MAX_SAMPLES:,} a simulation makes; simulate it in parts, or at a lower rate")
    return np.arange(n) / rate
