"""Known poses: per-channel linear least squares on the references (seed paper eqs.
16-19), and the joint fit with the poses when a jig accuracy is stated."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import InputError
from ..readings.static import PoseSet, QUANT_VAR
from .checks import as_means, bare_poses, birge_ratio, check_identifiable, design, jig_accuracy_rad, pose_label
from .results import StaticFit, to_calibration
from .settings import JIG_ACCURACY_DEG, JIG_HINT_CHI2, METHODS, MIN_RCOND
from .static_model import fit_static, prior_solve


def calibrate_known_poses(device, means, f_ref=None, method: str = "full", sigma=None, *,
                          min_rcond: float = MIN_RCOND, jig_accuracy_deg: float = JIG_ACCURACY_DEG):
    """Known-pose calibration (seed paper eqs. 16-19; seed doc 2's 1- and 3-pose
    methods as ``offset`` and ``gain``) -> Calibration.

    ``means``: a PoseSet (its f_ref is used when ``f_ref`` is None, its within-pose
    scatter for the weights) or a (P,N) array of pose means in counts with ``f_ref``
    (P,3) m/s^2.  ``jig_accuracy_deg``: rms rotation angle of the pose errors (see
    the module notes).  See :func:`fit_known_poses`."""
    poses = means if isinstance(means, PoseSet) else None
    m = poses.means if poses is not None else means
    F = poses.f_ref if (poses is not None and f_ref is None) else f_ref
    if F is None:
        raise ValueError("calibrate_known_poses: f_ref is required with a means array")
    fit = fit_known_poses(device, m, F, method, sigma, poses=poses, min_rcond=min_rcond,
                          jig_accuracy_deg=jig_accuracy_deg)
    return to_calibration(device, fit, method)


def fit_known_poses(device, means, f_ref, method: str = "full", sigma=None, *,
                    poses: PoseSet | None = None, min_rcond: float = MIN_RCOND,
                    jig_accuracy_deg: float = JIG_ACCURACY_DEG, hint: bool = True) -> StaticFit:
    """Per-channel weighted least squares for b_i (and k_i or s_i) from P known poses.

    means (P,N) counts, f_ref (P,3) m/s^2, sigma (P,N) 1-sigma of each mean (counts;
    default: ``poses.sem()`` when ``poses`` is given, else equal weights and the
    covariance from the residuals).  ``jig_accuracy_deg`` (theta, default
    JIG_ACCURACY_DEG = 0): the references are uncertain by a pose rotation of rms
    angle theta; the pose directions are then estimated jointly with every
    channel's parameters, each with its reference as a prior of that accuracy
    (:func:`fit_static`; module notes), and ``StaticFit.f`` holds the estimated pose
    forces.  Without sigma the noise is then the rounding floor 1/12 count^2 and
    the covariance is inflated by chi2/dof when > 1.  ``hint`` (jig accuracy 0):
    with chi2/dof > JIG_HINT_CHI2, find the jig accuracy that brings it to 1
    (``StaticFit.jig_hint_deg``; False where the caller estimates the accuracy itself,
    :mod:`accelcal.calibrate.jig_estimate`).  Raises InputError (which pose to add)
    when the poses cannot determine a free parameter.  Returns a :class:`StaticFit`.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    jig = jig_accuracy_rad(jig_accuracy_deg)
    m = as_means(device, means)
    F = np.asarray(f_ref, float)
    if F.shape != (m.shape[0], 3):
        raise InputError("<arrays>", f"expected shape ({m.shape[0]}, 3), got {F.shape}", field="f_ref")
    bad = np.argwhere(~np.isfinite(F))
    if bad.size:
        p = int(bad[0][0])
        raise InputError("<arrays>", f"{pose_label(poses.info if poses else None, p)} has no reference "
                         "specific force (f_x, f_y, f_z); use the jig-free method", field=f"f_ref[{p}]")
    if sigma is None and poses is not None:
        sigma = poses.sem()
    check_identifiable(device, method, F, min_rcond)
    P, N = m.shape
    if jig > 0:
        # the references as priors of the stated accuracy: the nonlinear model with free poses
        # (with a stated jig accuracy the variance model is absolute even without sigma: the
        # rounding floor as the noise, so chi2 counts and the covariance gets the Birge rule)
        sig = np.asarray(sigma, float) if sigma is not None else np.full((P, N), math.sqrt(QUANT_VAR))
        ps = bare_poses(m, F) if poses is None else replace(poses, means=m, f_ref=F)
        return fit_static(device, ps, method, jigfree=False, temperature=False, sigma=sig, min_rcond=min_rcond,
                          jig_accuracy_deg=jig_accuracy_deg)
    sigma_known = sigma is not None
    sig = np.asarray(sigma, float) if sigma_known else None
    k_nom = device.counts_per_mps2
    offsets = np.empty(N)
    sens = np.empty((N, 3))
    cov = np.zeros((N, 6, 6))
    resid = np.empty((P, N))
    chi2_tot, dof_tot = 0.0, 0
    for i in range(N):
        A = design(method, device, i, F)
        y = m[:, i].copy()
        if method == "offset":
            y -= F @ (k_nom[i] * device.axes[i])
        w = np.ones(P) if sig is None else 1.0 / sig[:, i]
        Aw = A * w[:, None]
        x, *_ = np.linalg.lstsq(Aw, y * w, rcond=None)
        r = y - A @ x
        q = A.shape[1]
        dof = P - q
        chi2 = float(np.sum((r * w) ** 2))
        C = np.linalg.inv(Aw.T @ Aw)
        if not sigma_known:
            C *= chi2 / dof if dof > 0 else np.nan
        else:
            C *= birge_ratio(chi2, dof)
            chi2_tot += chi2
            dof_tot += dof
        offsets[i] = x[0]
        if method == "offset":
            sens[i] = k_nom[i] * device.axes[i]
            cov[i, 0, 0] = C[0, 0]
        elif method == "gain":
            sens[i] = x[1] * device.axes[i]
            J = np.zeros((4, 2))
            J[0, 0] = 1.0
            J[1:, 1] = device.axes[i]
            cov[i, :4, :4] = J @ C @ J.T
        else:
            sens[i] = x[1:]
            cov[i, :4, :4] = C
        resid[:, i] = r
    ps = poses if poses is not None else bare_poses(m, F)
    implied = None
    if hint and sigma_known and dof_tot > 0 and chi2_tot / dof_tot > JIG_HINT_CHI2:
        implied = implied_jig_deg(device, method, m, F, sig, (offsets, sens, None, None))
    return StaticFit(method=method, jigfree=False, offsets=offsets, sensitivity=sens, f=F.copy(), cov=cov,
                     residual=resid, chi2=chi2_tot, dof=dof_tot, poses=ps, jig_accuracy_deg=0.0, jig_hint_deg=implied)


def implied_jig_deg(device, method, m, F, sig, start) -> float | None:
    """The jig accuracy (deg) at which the known-pose fit with the references as
    priors of that accuracy has chi2/dof = 1: what pose errors alone would explain
    the scatter of the poses about the fit (bisection on a log scale, each fit
    started from the previous one; None when even 30 deg leaves chi2/dof > 1, i.e.
    not a jig error)."""
    P, N = m.shape
    q = {"offset": 1, "gain": 2, "full": 4}[method]
    dof = P * N - q * N
    x_prev = [None]

    def chi2_per_dof(deg: float) -> float:
        prob, x, _, _ = prior_solve(device, method, m, sig, None, F, math.radians(deg), start, x_prev[0])
        x_prev[0] = x
        r = prob.residual(x)
        return float(r @ r) / dof

    lo, hi = 1e-4, 30.0
    if chi2_per_dof(hi) > 1.0:
        return None
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        if chi2_per_dof(mid) > 1.0:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.01:
            break
    return float(math.sqrt(lo * hi))
