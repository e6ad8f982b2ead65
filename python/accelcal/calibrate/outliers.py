"""Poses far off a static fit: found by a robust rule, named with how far off they are, and
the fit without them, so that the user can see what they change and decide (``calibrate
--drop-outliers`` leaves them out).

The rule (:func:`outlier_poses`): each pose's residual over its noise,
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

from ..noise import MAD_TO_STD
from ..static import PoseSet
from .checks import static_force

__all__ = ["OUTLIER_K", "MIN_OUTLIER_POSES", "pose_chi", "outlier_poses", "norm_error", "subset", "outlier_report"]

OUTLIER_K = 8.0            # robust sd of the poses' residual beyond their median that names a pose
MIN_OUTLIER_POSES = 8      # fewer poses give no robust spread to judge one by


def pose_chi(fit) -> np.ndarray:
    """(P,) each pose's residual over its noise, sqrt(sum_i (r_pi / sem_pi)^2) (dimensionless)."""
    return np.sqrt(np.sum((fit.residual / fit.poses.sem()) ** 2, axis=1))


def outlier_poses(fit, k: float = OUTLIER_K) -> np.ndarray:
    """Indices of the poses far off ``fit`` (a StaticFit), worst first: e_p = :func:`pose_chi`
    beyond median(e) + k max(1.4826 MAD(e), 1); none where more than a quarter of the poses
    would be, or the fit has fewer than MIN_OUTLIER_POSES."""
    e = pose_chi(fit)
    if e.size < MIN_OUTLIER_POSES or not np.all(np.isfinite(e)):
        return np.zeros(0, dtype=np.int64)
    med = float(np.median(e))
    sd = max(MAD_TO_STD * float(np.median(np.abs(e - med))), 1.0)
    out = np.flatnonzero(e > med + k * sd)
    if out.size > e.size // 4:
        return np.zeros(0, dtype=np.int64)
    return out[np.argsort(-e[out])]


def norm_error(device, fit) -> np.ndarray:
    """(P,) |f| of each pose mean read with the fit's offsets and sensitivities, less the
    magnitude the fit holds it at (g jig-free, |f_ref| with references), m/s^2."""
    fh = static_force(fit.offsets, fit.sensitivity, fit.poses.means, fit.poses.sem())
    return np.linalg.norm(fh, axis=1) - np.linalg.norm(fit.f, axis=1)


def subset(poses: PoseSet, keep: np.ndarray) -> PoseSet:
    """The poses ``keep`` (indices) of a PoseSet, with its set-aside list."""
    keep = np.asarray(keep, dtype=np.int64)
    return PoseSet(means=poses.means[keep], n=poses.n[keep], std=poses.std[keep], f_ref=poses.f_ref[keep],
                   temp=poses.temp[keep], info=[poses.info[p] for p in keep], set_aside=list(poses.set_aside),
                   colour_r2=None if poses.colour_r2 is None else poses.colour_r2[keep])


def outlier_report(device, fit, out: np.ndarray, names: list, without=None) -> dict:
    """The calibration's ``extra["outliers"]``: the rule, each pose named (name, residual over its
    noise, |f| error in m/s^2), the worst |f| error of the others, and, with ``without`` (the fit
    of the other poses, or None where they determine none), how the offsets (counts) and gains
    (fractions) move and the chi2/dof without them."""
    e = pose_chi(fit)
    d = norm_error(device, fit)
    rest = np.setdiff1d(np.arange(e.size), out)
    rep = {
        "rule": f"residual over the noise beyond the poses' median + {OUTLIER_K:g} robust sd (1.4826 MAD, >= 1)",
        "poses": [{"name": names[p], "residual_over_noise": float(e[p]), "norm_error_mps2": float(d[p]),
                   **({"t_start_s": float(fit.poses.info[p]["t_start"])} if "t_start" in fit.poses.info[p] else {})}
                  for p in out],
        "others_worst_norm_error_mps2": float(d[rest][np.argmax(np.abs(d[rest]))]) if rest.size else None,
        "chi2_dof": float(fit.chi2 / fit.dof) if fit.dof > 0 else None,
        "dropped": False,
    }
    if without is not None:
        g0 = np.linalg.norm(fit.sensitivity, axis=1)
        g1 = np.linalg.norm(without.sensitivity, axis=1)
        rep["without"] = {"offset_change_counts": [float(v) for v in without.offsets - fit.offsets],
                          "gain_change": [float(v) for v in g1 / g0 - 1.0],
                          "chi2_dof": float(without.chi2 / without.dof) if without.dof > 0 else None}
    return rep
