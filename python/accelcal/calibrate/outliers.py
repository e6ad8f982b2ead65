"""Poses far off a static fit, named with how far off they are and the fit without them, so
that the user can see what they change and decide (``calibrate --drop-outliers`` leaves them
out).  The rule itself (median + OUTLIER_K robust sd of the poses' residual over their noise)
lives in :mod:`accelcal.readings.outliers`, which ``diagnose`` uses too; here it is applied to a
StaticFit's pose residuals.
"""
from __future__ import annotations

import numpy as np

from ..readings.outliers import MIN_OUTLIER_POSES, OUTLIER_K, OUTLIER_RULE, far_poses
from ..readings.static import PoseSet
from .checks import static_force

__all__ = ["OUTLIER_K", "MIN_OUTLIER_POSES", "pose_chi", "outlier_poses", "norm_error", "subset", "outlier_report"]


def pose_chi(fit) -> np.ndarray:
    """(P,) each pose's residual over its noise, sqrt(sum_i (r_pi / sem_pi)^2) (dimensionless)."""
    return np.sqrt(np.sum((fit.residual / fit.poses.sem()) ** 2, axis=1))


def outlier_poses(fit, k: float = OUTLIER_K) -> np.ndarray:
    """Indices of the poses far off ``fit`` (a StaticFit), worst first: :func:`accelcal.readings.outliers.far_poses`
    of e_p = :func:`pose_chi` (none where more than a quarter of the poses would be, or the fit
    has fewer than MIN_OUTLIER_POSES)."""
    return far_poses(pose_chi(fit), k)


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
                   colour_r2=None if poses.colour_r2 is None else poses.colour_r2[keep],
                   step=None if poses.step is None else poses.step[keep])


def outlier_report(device, fit, out: np.ndarray, names: list, without=None) -> dict:
    """The calibration's ``extra["outliers"]``: the rule, each pose named (name, residual over its
    noise, |f| error in m/s^2), the worst |f| error of the others, and, with ``without`` (the fit
    of the other poses, or None where they determine none), how the offsets (counts) and gains
    (fractions) move and the chi2/dof without them."""
    e = pose_chi(fit)
    d = norm_error(device, fit)
    rest = np.setdiff1d(np.arange(e.size), out)
    rep = {
        "rule": OUTLIER_RULE,
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
