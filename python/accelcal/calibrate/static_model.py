"""The nonlinear static fit (jig-free poses, jig-accuracy priors, temperature), solved
by ``scipy.optimize.least_squares`` on the problem of :mod:`.problem`."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy.optimize import least_squares

from ..errors import InputError
from ..readings.static import PoseSet, QUANT_VAR
from .checks import (as_means, bare_poses, birge_ratio, check_identifiable, initial_forces,
                     jig_accuracy_rad, min_poses, missing_direction, pose_label)
from .problem import (StaticProblem, channel_cov, constrained_inverse, gauge_constraint, gauge_rotation,
                      structured_inverse)
from .results import StaticFit, to_calibration
from ..motions.poses import SAME_ORIENTATION_DEG, distinct_orientations
from .settings import ADD_POSES, JIG_ACCURACY_DEG, METHODS, MIN_RCOND, MIN_RCOND_JAC


def fit_static(device, poses: PoseSet, method: str = "full", *, jigfree: bool, temperature: bool = False,
               sigma: np.ndarray | None = None, f_init: np.ndarray | None = None,
               min_rcond: float = MIN_RCOND, jig_accuracy_deg: float = JIG_ACCURACY_DEG) -> StaticFit:
    """Nonlinear static fit: channel parameters (``method``), optionally temperature
    coefficients beta_i (counts/degC) and gamma_i (1/degC) about T0 = mean pose
    temperature, and, with ``jigfree``, the pose directions under |f| = g (gauge:
    see the module notes).  Known poses use ``poses.f_ref``; with ``jig_accuracy_deg``
    theta > 0 the pose directions are estimated too, with the references as priors
    of rms rotation theta (module notes: jig accuracy; ignored jig-free).
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    jig = 0.0 if jigfree else jig_accuracy_rad(jig_accuracy_deg)
    m = as_means(device, poses.means)
    P, N = m.shape
    # bare means (no within-pose scatter, no sigma): equal weights, covariance from the residuals
    # (with a stated jig accuracy: the rounding floor as the noise, and the Birge rule)
    sigma_known = sigma is not None or bool(np.any(poses.n > 1))
    sig = np.asarray(sigma, float) if sigma is not None else (poses.sem() if sigma_known else np.ones((P, N)))
    if jig > 0 and not sigma_known:
        sig = np.full((P, N), math.sqrt(QUANT_VAR))
        sigma_known = True
    dT = None
    T0 = None
    if temperature:
        if not np.all(np.isfinite(poses.temp)):
            p = int(np.flatnonzero(~np.isfinite(poses.temp))[0])
            raise InputError("<poses>", f"{pose_label(poses.info, p)} has no temp_c; temperature fit needs it on "
                             "every pose", field="temp_c")
        T0 = float(np.mean(poses.temp))
        dT = poses.temp - T0
    need = min_poses(device, method, temperature) if jigfree else 0
    if jigfree:
        F0 = initial_forces(device, m)
        distinct = distinct_orientations(F0)
        if 1 < distinct < need or (distinct == 1 and P < need):   # one orientation: said below, more closely
            same = (f" ({P} poses, {distinct} orientations: poses within {SAME_ORIENTATION_DEG:g} deg of each other "
                    "count once)" if distinct < P else "")
            aside = (f" ({len(poses.set_aside)} more set aside: their readings clip)" if poses.set_aside else "")
            raise InputError("<poses>", f"jig-free '{method}' calibration of {N} channels needs at least {need} static "
                             f"poses in different orientations, got {distinct}{same}{aside}{ADD_POSES} (e.g. f "
                             f"along {missing_direction(device, F0)})", field="poses")
    if not jigfree:
        F = np.asarray(poses.f_ref, float)
        if not np.all(np.isfinite(F)):
            p = int(np.flatnonzero(~np.all(np.isfinite(F), axis=1))[0])
            raise InputError("<poses>", f"{pose_label(poses.info, p)} has no reference f; use the jig-free "
                             "method", field="f_ref")
        check_identifiable(device, method, F, min_rcond)
        if jig > 0 and np.any(np.linalg.norm(F, axis=1) <= 0.0):
            p = int(np.flatnonzero(np.linalg.norm(F, axis=1) <= 0.0)[0])
            raise InputError("<poses>", f"{pose_label(poses.info, p)} has reference f = 0, which has no direction "
                             "for a jig accuracy to rotate; state jig accuracy 0 or give the pose's f", field="f_ref")
    else:
        F = initial_forces(device, m) if f_init is None else np.asarray(f_init, float)
        fh = F / np.linalg.norm(F, axis=1, keepdims=True)
        spread = float(np.degrees(np.arcsin(min(1.0, np.max(np.linalg.norm(np.cross(fh[0], fh), axis=1))))))
        if spread < 5.0:
            raise InputError("<poses>", f"the {P} static poses all have about the same orientation (within "
                             f"{spread:.1f} deg of each other); jig-free calibration needs poses spread over the "
                             f"sphere{ADD_POSES} (e.g. f along {missing_direction(device, F)})", field="poses")
    gauge = jigfree and method == "full"
    b0 = device.nominal_offsets()
    s0 = device.nominal_sensitivity()
    prob = StaticProblem(device, method, m, sig, dT, jigfree, None if jigfree else F)
    if jigfree:
        if method != "offset":
            # start: offsets and gains along the nominal axes with free poses (no gauge
            # needed), which takes out the large offsets before the full model
            b0, s0, F = refine_start(device, m, sig, F, b0, s0)
        prob.set_pose_frame(F, gauge)

    def undetermined() -> InputError:
        return InputError("<poses>", f"the {P} poses do not determine every parameter of the "
                          f"{'jig-free ' if jigfree else ''}'{method}'{' + temperature' if temperature else ''} model"
                          f"{ADD_POSES} in other orientations (e.g. f along {missing_direction(device, F)})"
                          + ("" if not temperature else " and at other temperatures"), field="poses")

    def not_converged(message: str) -> InputError:
        return InputError("<poses>", f"the {'jig-free ' if jigfree else ''}'{method}' fit did not converge "
                          f"(scipy least_squares: {message.rstrip('.')}): the static poses do not fit the model "
                          "(moving poses, or another device?)", field="poses")

    x0 = prob.pack(b0, s0)
    if not prob.determined(x0):                                  # gauge already fixed in prob
        raise undetermined()
    x, converged, message = solve_problem(prob, x0)
    if not converged:
        raise not_converged(message)
    if jig > 0:
        # the references as priors: start from the fit with the poses at their references
        prob, x, converged, message = prior_solve(device, method, m, sig, dT, F, jig, prob.unpack(x))
        if not converged:
            raise not_converged(message)
    b, s, beta, gamma = prob.unpack(x)
    F, _ = prob.forces(x)
    if gauge:
        R = gauge_rotation(device, s)
        s = s @ R.T
        F = F @ R.T
    # covariance in the final gauge: every pose free (2 tangent coordinates), gauge constraint if needed;
    # with the prior, at the solution in the reference's linearisation (prior rows included)
    cov_prob = prob if jig > 0 else StaticProblem(device, method, m, sig, dT, jigfree, F, gauge=False)
    xf = x if jig > 0 else cov_prob.pack(b, s, beta, gamma)
    r = cov_prob.residual(xf)
    chi2 = float(r @ r)
    n_cols = cov_prob.n_ch + cov_prob.n_pose
    n_par = n_cols - (3 if gauge else 0)
    dof = P * N + cov_prob.n_prior - n_par
    gc = gauge_constraint(device, s, n_cols, cov_prob.q) if gauge else None
    pose_cov = None
    if cov_prob.structured:
        got = structured_inverse(*cov_prob.jacobian_parts(xf), cov_prob.mask, gc)
        if got is None:
            raise undetermined()
        C, pose_cov = got
    else:
        # with the prior the rank was checked with the poses fixed (the prior rows make the pose
        # coordinates full rank), and pose directions the readings barely see are normal there:
        # only an exactly singular system is refused
        C = constrained_inverse(cov_prob.jacobian(xf), gc, rtol=1e-13 if jig > 0 else MIN_RCOND_JAC)
        if C is None:
            raise undetermined()
        if cov_prob.free_poses:
            idx = cov_prob.n_ch + np.arange(2 * P).reshape(P, 2)
            pose_cov = C[idx[:, :, None], idx[:, None, :]]      # tangent coordinates are radians
    scale = birge_ratio(chi2, dof) if sigma_known else (chi2 / dof if dof > 0 else np.nan)
    C = C * scale
    cov = channel_cov(device, method, temperature, C, cov_prob.q)
    if pose_cov is not None:
        pose_cov = pose_cov * scale
    resid = cov_prob.reading_residual(r)
    return StaticFit(method=method, jigfree=jigfree, offsets=b, sensitivity=s, f=F, cov=cov, residual=resid,
                     chi2=chi2, dof=int(dof), poses=poses, temp_ref_c=T0,
                     offset_tc=None if beta is None else np.array(beta),
                     gain_tc=None if gamma is None else np.array(gamma), pose_cov=pose_cov,
                     jig_accuracy_deg=math.degrees(jig), n_prior=int(cov_prob.n_prior))


def prior_solve(device, method, m, sig, dT, F, jig, start, x_start=None):
    """The known-pose model with the references F as priors of rms rotation ``jig``
    (rad): (problem, x, converged, message), started from channel parameters ``start`` =
    (b, s, beta, gamma) with the poses at their references, or from ``x_start`` (a
    previous solution of the same parameterisation)."""
    prob = StaticProblem(device, method, m, sig, dT, True, F, prior_rad=jig)
    x0 = prob.pack(*start) if x_start is None else x_start
    x, converged, message = solve_least_squares(prob.residual, prob.jacobian, x0)
    return prob, x, converged, message


def solve_least_squares(fun, jac, x0: np.ndarray, max_iter: int = 100,
                        tol: float = 1e-12) -> tuple[np.ndarray, bool, str]:
    """Minimise |fun(x)|^2 with ``scipy.optimize.least_squares`` (MINPACK's
    Levenberg-Marquardt, analytic Jacobian).

    Parameters
    ----------
    fun, jac : callable
        Residual vector and its Jacobian at x.
    x0 : ndarray
        Start.
    max_iter : int
        Bound on the Jacobian evaluations, as iterations (``max_nfev`` is this many
        times len(x0) + 1, MINPACK's count of function calls).
    tol : float
        Relative tolerance on the cost (``ftol``) and the step (``xtol``, its square root).

    Returns
    -------
    x : ndarray
    converged : bool
        scipy's ``status`` > 0 (a tolerance was met).
    message : str
        scipy's ``message``, for the error a caller raises when not converged.
    """
    res = least_squares(fun, np.asarray(x0, float), jac=jac, method="lm", ftol=tol, xtol=math.sqrt(tol),
                        gtol=tol, x_scale="jac", max_nfev=max_iter * (len(x0) + 1))
    return res.x, bool(res.status > 0), str(res.message)


def solve_problem(prob: StaticProblem, x0: np.ndarray, max_iter: int = 100,
                  tol: float = 1e-12) -> tuple[np.ndarray, bool, str]:
    """:func:`solve_least_squares` on a StaticProblem: MINPACK's Levenberg-Marquardt on the
    dense Jacobian, or, for a :attr:`~StaticProblem.structured` one (many free poses), scipy's
    trust-region reflective solver with LSMR on the sparse Jacobian (805 poses: the dense
    solve's O(P^3) QR took most of 24 s)."""
    if not prob.structured:
        return solve_least_squares(prob.residual, prob.jacobian, x0, max_iter, tol)
    res = least_squares(prob.residual, np.asarray(x0, float), jac=prob.jacobian_sparse, method="trf",
                        tr_solver="lsmr", ftol=tol, xtol=math.sqrt(tol), gtol=tol, x_scale="jac",
                        max_nfev=max_iter * 10)
    return res.x, bool(res.status > 0), str(res.message)


def refine_start(device, m, sig, F, b0, s0):
    """Starting point for a jig-free solve: fit offsets and gains along the nominal
    axes with free poses (no gauge needed), which removes the large offsets."""
    P, N = m.shape
    prob = StaticProblem(device, "gain", m, sig, None, True, F)
    if P * N < prob.n_ch + prob.n_pose:
        return b0, s0, F
    x, _, _ = solve_problem(prob, prob.pack(b0, s0), max_iter=30, tol=1e-8)
    b, s, _, _ = prob.unpack(x)
    F, _ = prob.forces(x)
    return b, s, F


def calibrate_jigfree(device, means, method: str = "full", *, sigma: np.ndarray | None = None,
                      temperature: bool = False):
    """Jig-free calibration -> Calibration: unknown pose directions under |f| = g
    (gauge: see the module notes).  ``means``: a PoseSet (e.g. from
    :func:`poses_from_recording`) or a (P,N) array of pose means in counts (then
    ``sigma`` (P,N), or equal weights with the covariance from the residuals)."""
    poses = means if isinstance(means, PoseSet) else bare_poses(as_means(device, means))
    fit = fit_static(device, poses, method, jigfree=True, temperature=temperature, sigma=sigma)
    return to_calibration(device, fit, "jigfree")


def fit_temperature(device, poses: PoseSet, method: str = "full", *, f: np.ndarray | None = None,
                    sigma: np.ndarray | None = None, jig_accuracy_deg: float = JIG_ACCURACY_DEG) -> StaticFit:
    """Offset and gain against temperature (first order about the mean pose
    temperature) jointly with the channel parameters, for known pose forces
    ``f`` (default ``poses.f_ref``; pass a jig-free fit's ``f`` for hand-held data),
    uncertain by ``jig_accuracy_deg`` (see :func:`fit_known_poses`)."""
    ps = poses if f is None else replace(poses, f_ref=np.asarray(f, float))
    return fit_static(device, ps, method, jigfree=False, temperature=True, sigma=sigma,
                      jig_accuracy_deg=jig_accuracy_deg)
