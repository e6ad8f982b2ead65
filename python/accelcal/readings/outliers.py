"""Poses far off a static fit: the robust rule that names them (one home for ``calibrate`` and
``diagnose``, which each fit the poses their own way and hand this rule each pose's residual
over its noise).

The rule (:func:`far_poses`): each pose's residual over its noise,
e_p = sqrt(sum_i (r_pi / sem_pi)^2), and the poses whose e_p exceeds the median of the
e_p by more than OUTLIER_K robust standard deviations (1.4826 x the median absolute
deviation of the e_p, at least 1: the noise itself).  A robust spread, because the poses to
find inflate the ordinary one; in noise units, so that a well-fitting pose set (e_p ~ 1)
names no pose within its noise.  OUTLIER_K = 8: e_p of a clean fit is at worst half-normal
(one residual dimension a pose, the jig-free triad's |f| = g), whose median + 8 robust sd
(0.67 + 8 x 0.59 sd = 5.4 sd) a pose passes with probability 7e-8, so 10,000 clean poses
name none (P = 1e-3); real hand-held poses, whose e_p spread wider than the noise, set the
yardstick by their own spread (Magneto's 178 poses: 3 at 47-51 robust sd, |f| - g = -0.74 to
-0.77 m/s^2, the next at 2.7; the suite's real recordings at most 3.0, Xsens's 40 hand-held
poses).  At most a quarter of the poses are named (more are no outliers but the
fit's), and none of fewer than MIN_OUTLIER_POSES.
"""
from __future__ import annotations

import numpy as np

from .noise import MAD_TO_STD

__all__ = ["OUTLIER_K", "MIN_OUTLIER_POSES", "OUTLIER_RULE", "far_poses"]

OUTLIER_K = 8.0            # robust sd of the poses' residual beyond their median that names a pose
MIN_OUTLIER_POSES = 8      # fewer poses give no robust spread to judge one by
OUTLIER_RULE = f"residual over the noise beyond the poses' median + {OUTLIER_K:g} robust sd (1.4826 MAD, >= 1)"


def far_poses(e: np.ndarray, k: float = OUTLIER_K) -> np.ndarray:
    """Indices of the poses far off their fit, worst first.

    Parameters
    ----------
    e : ndarray, shape (P,)
        Each pose's residual over its noise, sqrt(sum_i (r_pi / sem_pi)^2) (dimensionless).
    k : float
        Robust standard deviations beyond the median that name a pose.

    Returns
    -------
    ndarray of int
        The poses with e_p beyond median(e) + k max(1.4826 MAD(e), 1); none where more than a
        quarter of the poses would be, where there are fewer than MIN_OUTLIER_POSES, or where
        some e_p is not finite.
    """
    e = np.asarray(e, float)
    if e.size < MIN_OUTLIER_POSES or not np.all(np.isfinite(e)):
        return np.zeros(0, dtype=np.int64)
    med = float(np.median(e))
    sd = max(MAD_TO_STD * float(np.median(np.abs(e - med))), 1.0)
    out = np.flatnonzero(e > med + k * sd)
    if out.size > e.size // 4:
        return np.zeros(0, dtype=np.int64)
    return out[np.argsort(-e[out])]
