"""What the chosen model leaves beyond the noise: the contract's ``unexplained``.

The residual after the model (its joint in-sample fit), in the rows the diagnosis scores,
is split into noise and a systematic part:

* noise: the scatter within static segments about their own means (the dof-weighted mean
  of the segment variances, so hand tremor and coloured noise at rest count as noise);
  without static segments, the noise floor;
* systematic: the static segments' means beyond what that scatter gives a mean
  (sum of n m^2 minus the sum of the variances), plus the moving samples' energy beyond
  the scatter.

The held-out figure is then ``heldout_rms_left = sqrt(max(after^2 - noise^2, 0))`` with
``after`` the model's held-out RMS, and ``fraction = heldout_rms_left^2 / before^2``, its
share of the held-out gap's energy.  It is reported (not ``null``) when it is at least
LEFT_MIN_RATIO of the noise (the residual at least 1.118 x the noise), however small a
share of the gap: what a sensor effect of another shape (a resonance, mains pickup) or
motion the model does not follow would leave.  ``where`` names the channels, the frequency band
and the regime in which it lies, and for static data the poses.
"""
from __future__ import annotations

import math

import numpy as np

from ..effects.fitdata import FitData
from .where import where_breakdown

LEFT_MIN_RATIO = 0.5       # left at least this x the noise (the residual >= 1.118 x the noise)


def _split(D: FitData, A: np.ndarray, floor2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per column of ``A`` (n, m): noise variance, systematic energy, and the moving share of it."""
    m = A.shape[1]
    dof = np.zeros(m)
    ss_in = np.zeros(m)
    sys_static = np.zeros(m)
    moving = np.ones(D.n, bool)
    for a, b in zip(D.seg_lo, D.seg_hi):
        if not D.static[a] or b - a < 3:
            continue
        x = A[a:b]
        mu = x.mean(axis=0)
        v = x.var(axis=0, ddof=1)
        L = b - a
        dof += L - 1
        ss_in += (L - 1) * v
        sys_static += L * mu * mu - v
        moving[a:b] = False
    noise2 = ss_in / dof if np.all(dof > 0) else floor2
    sys_moving = np.sum(A[moving] ** 2, axis=0) - np.count_nonzero(moving) * noise2
    return noise2, sys_static + sys_moving, sys_moving


def leftover(D: FitData, e: np.ndarray, e_after: np.ndarray, before: float, after: float) -> dict | None:
    """The contract's ``unexplained`` object for the model that leaves ``e_after`` (n, N)
    of the residual ``e`` (held-out RMS ``before`` -> ``after``, counts), or None when what
    is left is noise (see the module doc)."""
    if before <= 0:
        return None
    Ra = D.rows(e_after)
    floor2_rows = np.mean(D.sigma ** 2) * np.ones(Ra.shape[1])
    noise2, _, _ = _split(D, Ra, floor2_rows)
    noise = math.sqrt(float(np.mean(noise2)))
    left = math.sqrt(max(after * after - noise * noise, 0.0))
    fraction = left * left / (before * before)
    if left < LEFT_MIN_RATIO * noise:
        return None
    # where: by channel (channel space), band, regime, poses
    n2c, sys_c, mov_c = _split(D, e_after, D.sigma ** 2)
    rms_left_ch = np.sqrt(np.maximum(sys_c, 0.0) / D.n)
    top = float(rms_left_ch.max())
    channels = [int(i) for i in np.argsort(-rms_left_ch) if rms_left_ch[i] >= 0.25 * top and top > 0]
    w = where_breakdown(D, e_after)
    bands = w["frequency_bands"]
    ex = [b["rms_counts"] ** 2 - b["white_noise_rms_counts"] ** 2 for b in bands]
    band = bands[int(np.argmax(ex))]["label"] if bands else None
    regs = w["static_vs_rotating"]
    rex = [r["n"] * (r["rms_counts"] ** 2 - noise * noise) for r in regs]
    regime = regs[int(np.argmax(rex))]["label"] if regs else None
    out = {"heldout_rms_left": left, "fraction": fraction, "noise_counts": noise,
           "where": {"channels": channels, "rms_left_per_channel": rms_left_ch.tolist(), "band": band,
                     "regime": regime,
                     "moving_share": float(np.sum(np.maximum(mov_c, 0)) / max(np.sum(np.maximum(sys_c, 0)), 1e-300))}}
    if "poses" in w and regime == "static":
        out["where"]["poses"] = [p["label"] for p in w["poses"][:3]]
    return out
