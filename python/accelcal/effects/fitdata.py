"""FitData: the data every effect's fit works on (the recordings laid end to end, the
model's prediction, blocks and folds for cross-validation, the noise floor), and small
helpers over it."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .settings import (AXIS_POSE_DEG, REPEAT_DEG, REPEAT_MIN_S, REPEAT_SAME_DEG, ROTATING_RADPS, TEMP_MIN_SPAN_C,
                       TEMP_MONOTONE, TEMP_TIME_BINS)


@dataclass
class FitData:
    device: Any
    cal: Any
    mode: str                     # "reference" | "jigfree"
    m0: float                     # centripetal multiplier of the model
    K: int                        # folds
    t: np.ndarray                 # (n,) recording time
    tg: np.ndarray                # (n,) strictly increasing global time (recordings laid end to end)
    rec: np.ndarray               # (n,) recording index
    seg: np.ndarray               # (n,) segment index
    seg_lo: np.ndarray            # (S,) first sample of each segment
    seg_hi: np.ndarray            # (S,) one past the last
    bstart: np.ndarray            # (B,) first sample of each block (blocks are contiguous)
    bfold: np.ndarray             # (B,) fold of each block
    bseg: np.ndarray              # (B,)
    block: np.ndarray             # (n,)
    raw: np.ndarray               # (n, N) float
    pred: np.ndarray              # (n, N) model prediction, unclipped
    p0: np.ndarray                # (n, N) clipped to the ADC range
    offset_t: np.ndarray          # (n, N) b + bias(T)
    gain_t: np.ndarray | None     # (n, N) temperature gain factor or None
    sensed: np.ndarray            # (n, N) pred - offset_t
    f: np.ndarray                 # (n, 3) reference (or estimated) specific force
    w: np.ndarray                 # (n, 3)
    dw: np.ndarray                # (n, 3)
    temp: np.ndarray              # (n,) NaN unknown
    pose: np.ndarray              # (n,) global pose index, -1 none
    pose_labels: list             # [(recording index, label)] per global pose
    pose_stated: np.ndarray       # (n,) pose with a stated (reference) f, for pose_error
    static: np.ndarray            # (n,) bool
    s: np.ndarray                 # (N, 3)
    r: np.ndarray                 # (N, 3)
    b: np.ndarray                 # (N,)
    rec_t0: np.ndarray            # (n_rec,) first sample time of each recording
    rec_info: list
    notes: list
    Qp: np.ndarray | None = None  # (P, M, N) jig-free projections per pose
    sigma: np.ndarray | None = None   # (N,) noise floor
    noise_method: str = ""
    lattice: tuple | None = None  # (step, phase, share, distinct) per channel: effects.adc.data_lattice's cache
    W: np.ndarray | None = None   # (n, R) row weights
    pose_var: np.ndarray | None = None  # (N,) variance of a pose mean's rounding bias (diagnose.floor.pose_rounding_var)
    deff: float = 1.0             # the static poses' design effect (diagnose.floor.pose_design_effect)
    unit: np.ndarray | None = None  # (B,) independent unit of each block: its pose, else the block
    h: float = 0.0                # sample period (s)

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    @property
    def N(self) -> int:
        return int(self.raw.shape[1])

    @property
    def B(self) -> int:
        return int(self.bstart.shape[0])

    def rows(self, A: np.ndarray) -> np.ndarray:
        """Channel-space array (n, N) -> the rows that are fitted and scored (n, R)."""
        if self.Qp is None:
            return A
        return np.einsum("tmn,tn->tm", self.Qp[self.pose], A)

    @property
    def R(self) -> int:
        return self.N if self.Qp is None else int(self.Qp.shape[1])

    def bsum(self, a: np.ndarray) -> np.ndarray:
        """Per-block sums along axis 0."""
        return np.add.reduceat(a, self.bstart, axis=0)


def read_only(a: np.ndarray) -> np.ndarray:
    """A read-only view of ``a`` (no copy): the first target and prediction of a search, which
    every fit only reads and every step replaces by a new array (``y - delta``), share the
    residual's and the prediction's memory; a write into them raises instead of changing them."""
    v = a.view()
    v.flags.writeable = False
    return v


def tangent_basis(d: np.ndarray) -> np.ndarray:
    """(..., 2, 3) two unit vectors across each unit row of d (..., 3)."""
    d = np.asarray(d, float)
    helper = np.where(np.abs(d[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
    e2 = np.cross(d, e1)
    return np.stack([e1, e2], axis=-2)


def unit_rows3(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def is_moving(D: FitData) -> bool:
    mv = ~D.static
    if not mv.any():
        return False
    x = D.sensed[mv]
    return bool(np.any(np.ptp(x, axis=0) > 5 * D.sigma))


def rotating_mask(D: FitData) -> np.ndarray:
    return np.linalg.norm(D.w, axis=1) > ROTATING_RADPS


def force_at(D: FitData) -> np.ndarray:
    """(n,N,3) specific force at each channel's position (model terms)."""
    f = D.f[:, None, :]
    if np.all(D.r == 0):
        return np.broadcast_to(f, (D.n, D.N, 3))
    r = D.r[None, :, :]
    a = np.cross(D.dw[:, None, :], r)
    w = D.w[:, None, :]
    c = np.cross(w, np.cross(w, r)) * D.m0
    return f + a + c


def temp_follows_time(D: FitData) -> bool:
    """Whether the recorded temperature is a monotone function of time within each recording in
    which it varies (it rises, or falls, and never comes back: the medians of TEMP_TIME_BINS
    stretches of that recording's time change by at least TEMP_MONOTONE of their total variation
    from first to last; a recording at one temperature, such as a calibration's session at 25
    degC beside a warming one, tells nothing either way).  An effect of such a temperature is
    also an effect of time: a drift can change the readings as it does, and only a temperature
    that returns to a value at a later time of one recording tells the two apart."""
    if temp_skip(D) is not None:
        return False
    seen = False
    for r in np.unique(D.rec):
        m_r = D.rec == r
        T = D.temp[m_r][np.argsort(D.tg[m_r], kind="stable")]
        if T.size < 2 or float(np.ptp(T)) < TEMP_MIN_SPAN_C:
            continue
        m = np.array([np.median(b) for b in np.array_split(T, min(TEMP_TIME_BINS, T.size))])
        tv = float(np.abs(np.diff(m)).sum())
        if not (tv > 0 and abs(float(m[-1] - m[0])) >= TEMP_MONOTONE * tv):
            return False
        seen = True
    return seen


def temp_skip(D: FitData) -> str | None:
    T = D.temp
    if not np.all(np.isfinite(T)):
        return "needs temp_c (the recordings have no temperature)" if not np.isfinite(T).any() else \
            "needs temp_c on every sample used"
    span = float(np.ptp(T))
    if span < TEMP_MIN_SPAN_C:
        return f"temp_c varies by only {span:.3g} degC (needs {TEMP_MIN_SPAN_C:g})"
    return None


def t_ref_known(D: FitData) -> float | None:
    cal = D.cal
    if cal.temp_ref_c is not None:
        return float(cal.temp_ref_c)
    poses = cal.extra.get("poses") if isinstance(cal.extra, dict) else None
    if isinstance(poses, list):
        ts = [p.get("temp_c") for p in poses if isinstance(p, dict) and isinstance(p.get("temp_c"), (int, float))]
        if ts:
            return float(np.mean(ts))
    return None


def _repeated(u: np.ndarray, t: np.ndarray, deg: float) -> np.ndarray:
    """(P, P) upper-triangle mask of pairs of unit orientations ``u`` (P, 3) within ``deg``
    of each other whose mid-times ``t`` (s) are at least REPEAT_MIN_S apart."""
    close = (u @ u.T) >= math.cos(math.radians(deg))
    apart = np.abs(t[:, None] - t[None, :]) >= REPEAT_MIN_S
    return np.triu(close & apart, 1)


def _orientation(D, m) -> tuple[np.ndarray, float]:
    """Unit mean stated or fitted f of the samples ``m`` (zero when it has none) and their
    mean global time."""
    f = np.nanmean(D.f[m], axis=0)
    nf = float(np.linalg.norm(f))
    return (f / nf if nf > 0 else np.zeros(3)), float(np.mean(D.tg[m]))


def time_separable(D) -> bool:
    """Whether the data can tell time from pose: some orientation held in two static poses
    at different times (a pose repeated later, a rest before and after a motion), or data
    taken while moving (the orientation changes continuously)."""
    if np.any(~D.static):
        return True
    P = len(D.pose_labels)
    if P < 2:
        return False
    u, t = zip(*(_orientation(D, D.pose == p) for p in range(P)))
    return bool(np.any(_repeated(np.array(u), np.array(t), REPEAT_DEG)))


def static_repeats(D) -> list[tuple[int, int]]:
    """Pairs (j, k) of static segments (indices into seg_lo/seg_hi, j < k) that hold one
    orientation (within REPEAT_SAME_DEG: a jig's repeated pose) at times at least REPEAT_MIN_S
    apart: where a change with time shows apart from an effect of the orientation, which
    reads the same at both."""
    segs = [j for j, (lo, hi) in enumerate(zip(D.seg_lo, D.seg_hi)) if D.static[lo] and hi - lo >= 3]
    if len(segs) < 2:
        return []
    u, t = zip(*(_orientation(D, slice(D.seg_lo[j], D.seg_hi[j])) for j in segs))
    ok = _repeated(np.array(u), np.array(t), REPEAT_SAME_DEG)   # a segment without f matches none
    return [(segs[a], segs[b]) for a, b in zip(*np.nonzero(ok))]


def poses_on_axes(D) -> bool:
    """Whether every static pose with a stated f holds gravity along a channel's axis (within
    AXIS_POSE_DEG): the six faces of a box.  On such poses a tilt of each pose reproduces a
    misalignment of the axes to first order (channel i tilted toward j reads +-g theta in the
    poses +-j, as those poses tilted by theta would), so the two cannot be told apart; poses
    between the axes (edges, corners) tell them."""
    stated = np.unique(D.pose_stated[D.pose_stated >= 0])
    if stated.size == 0:
        return False
    axes = unit_rows3(D.s)
    for p in stated:
        f = np.nanmean(D.f[D.pose_stated == p], axis=0)
        nf = np.linalg.norm(f)
        if not nf > 0 or np.max(np.abs(axes @ (f / nf))) < math.cos(math.radians(AXIS_POSE_DEG)):
            return False
    return True


def recording_parts(D) -> list[tuple[int, int]]:
    """Index ranges [a, b) of the data's parts that are independent places of the signal:
    each static segment whole (its blocks dwell on the same codes), each moving segment in its
    cross-validation blocks."""
    ends = np.append(D.bstart[1:], D.n)
    out = []
    for s_i, (a, b) in enumerate(zip(D.seg_lo.tolist(), D.seg_hi.tolist())):
        if D.static[a]:
            out.append((a, b))
        else:
            out += [(int(x), int(y)) for x, y in zip(D.bstart[D.bseg == s_i], ends[D.bseg == s_i])]
    return out
