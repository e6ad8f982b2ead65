"""The jig's accuracy from the data: empirical Bayes on the known poses' priors.

A jig holds pose p rotated from its reference by a small error whose two tangent-plane
components a_p have rms tau = theta / sqrt(3) each (theta: the rms rotation angle, the
jig accuracy of :mod:`accelcal.calibrate`).  Linearised about the fit with the poses at
their references, the whitened pose means (readings over their sigma) are

    y_p = X_p beta + J_p a_p + e_p,      a_p ~ N(0, tau^2 I_2),   e_p ~ N(0, I_N)

(X_p: the channel parameters' columns, J_p: the pose's two tangent coordinates', both of
:class:`accelcal.calibrate.problem.StaticProblem`).  Integrating the pose errors out, the
pose means are Gaussian with covariance V_p = I + tau^2 J_p J_p^T; integrating the channel
parameters out too (a flat prior: restricted maximum likelihood, REML, which does not
count the scatter the channel terms absorb as noise) gives the marginal likelihood of
theta alone,

    -2 l(theta) = sum_p log det V_p + log det (sum_p X_p^T V_p^-1 X_p) + r^T V^-1 r,

r the generalised-least-squares residual.  theta-hat maximises it (``scipy.optimize.
minimize_scalar`` on log theta after a grid).  Whether the jig has an error at all is the
likelihood-ratio test of theta = 0: LR = 2 (l(theta-hat) - l(0)), whose null distribution,
theta = 0 being the boundary of the parameter space, is the 50:50 mixture of chi2_0 and
chi2_1 (Self and Liang 1987; Stram and Lee 1994 for one variance component), so
p = P(chi2_1 > LR) / 2.  Below TEST_LEVEL the estimate is used; otherwise theta = 0 (the
references exact: ordinary weighted least squares).  The interval is the profile
likelihood's: every theta with 2 (l(theta-hat) - l(theta)) <= chi2_1(INTERVAL_LEVEL).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq, minimize_scalar
from scipy.stats import chi2 as chi2_dist

from ..readings.static import PoseSet
from .checks import MAX_JIG_ACCURACY_DEG
from .known_poses import fit_known_poses
from .problem import StaticProblem
from .results import StaticFit
from .static_model import fit_static

#: the test of theta = 0 (a perfect jig): the estimate is used when the mixture likelihood-ratio
#: test rejects it at this level (the conventional 5 %: a perfect jig keeps ordinary least squares
#: in 95 % of sessions)
TEST_LEVEL = 0.05
#: the profile-likelihood interval's coverage
INTERVAL_LEVEL = 0.95
#: the grid the maximiser starts from (deg, log-spaced up to MAX_JIG_ACCURACY_DEG; a 6-channel array of
#: 34 poses with 0.01-count noise already tells 1e-3 deg from 0)
GRID_MIN_DEG = 1e-5
GRID_POINTS = 41


@dataclass
class JigEstimate:
    """The jig accuracy estimated from the poses' scatter (deg, rms rotation angle).

    deg : float
        The accuracy the fit uses: ``mle_deg`` when the test rejects a perfect jig, else 0.
    mle_deg : float
        The restricted-likelihood maximiser (0 when the likelihood is highest at 0).
    interval_deg : (float, float or None)
        The profile-likelihood interval at INTERVAL_LEVEL (None as its upper end: beyond
        MAX_JIG_ACCURACY_DEG).
    lr : float
        2 (l(mle) - l(0)).
    p_value : float
        The mixture test's p-value for a perfect jig.
    used : bool
        Whether the estimate is used (p_value < TEST_LEVEL and the maximiser inside the range
        the priors take).
    reason : str
        In words, why it is used or not.
    """

    deg: float
    mle_deg: float
    interval_deg: tuple
    lr: float
    p_value: float
    used: bool
    reason: str

    def to_json(self) -> dict:
        """The calibration's ``extra["fit"]["jig_accuracy_estimate"]``."""
        lo, hi = self.interval_deg
        return {"deg": float(self.deg), "mle_deg": float(self.mle_deg),
                "interval_deg": [float(lo), None if hi is None else float(hi)],
                "interval_level": INTERVAL_LEVEL, "lr": float(self.lr), "p_value": float(self.p_value),
                "test_level": TEST_LEVEL, "used": bool(self.used), "reason": self.reason,
                "method": "empirical Bayes: restricted (REML) marginal likelihood of the pose means over the jig "
                          "accuracy, the channel parameters and pose errors integrated out; a perfect jig "
                          "rejected by the likelihood-ratio test (1/2 chi2_0 + 1/2 chi2_1)"}


def linearised(device, method, means, sigma, F, dT, start):
    """The whitened residual y (P,N), the channel columns X (P,N,n_ch) and each pose's tangent
    columns J (P,N,2) of the known-pose model at channel parameters ``start`` = (b, s, beta,
    gamma) with every pose at its reference F."""
    prob = StaticProblem(device, method, means, sigma, dT, True, F, prior_rad=1.0)
    x = prob.pack(*start)
    Jc, Jp = prob.jacobian_parts(x)
    y = prob.residual(x)[: prob.P * prob.N].reshape(prob.P, prob.N)
    return y, Jc, Jp


def restricted_loglik(y: np.ndarray, X: np.ndarray, J: np.ndarray, deg: float) -> float:
    """The restricted (REML) log-likelihood (up to a constant) of jig accuracy ``deg`` for the
    whitened linear model of the module notes: y (P,N), X (P,N,q), J (P,N,2)."""
    tau2 = (math.radians(deg) / math.sqrt(3.0)) ** 2
    P, N = y.shape
    V = np.eye(N)[None] + tau2 * np.einsum("pnk,pmk->pnm", J, J)
    sign, logdet = np.linalg.slogdet(V)
    Vi = np.linalg.inv(V)
    ViX = np.einsum("pnm,pmq->pnq", Vi, X)
    A = np.einsum("pnq,pnr->qr", X, ViX)
    c = np.einsum("pnq,pn->q", ViX, y)
    sA, logdetA = np.linalg.slogdet(A)
    if sA <= 0:
        return -math.inf
    beta = np.linalg.solve(A, c)
    r = y - np.einsum("pnq,q->pn", X, beta)
    quad = float(np.einsum("pn,pnm,pm->", r, Vi, r))
    return -0.5 * (float(np.sum(logdet)) + float(logdetA) + quad)


def estimate_from_linear(y: np.ndarray, X: np.ndarray, J: np.ndarray) -> JigEstimate:
    """Maximise :func:`restricted_loglik` over the jig accuracy (0..MAX_JIG_ACCURACY_DEG), test a
    perfect jig and give the profile interval (module notes)."""
    def ll(d):
        return restricted_loglik(y, X, J, d)

    l0 = ll(0.0)
    grid = np.geomspace(GRID_MIN_DEG, MAX_JIG_ACCURACY_DEG, GRID_POINTS)
    vals = np.array([ll(d) for d in grid])
    k = int(np.argmax(vals))
    if vals[k] <= l0:
        mle, lmax = 0.0, l0
    else:
        lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
        res = minimize_scalar(lambda u: -ll(math.exp(u)), bounds=(math.log(lo), math.log(hi)), method="bounded",
                              options={"xatol": 1e-6})
        mle, lmax = (math.exp(res.x), -float(res.fun)) if -res.fun >= vals[k] else (float(grid[k]), float(vals[k]))
    lr = max(0.0, 2.0 * (lmax - l0))
    p = 0.5 * float(chi2_dist.sf(lr, 1)) if lr > 0 else 1.0
    cut = float(chi2_dist.ppf(INTERVAL_LEVEL, 1))

    def excess(d):
        return 2.0 * (lmax - ll(d)) - cut

    lower = 0.0 if mle == 0.0 or excess(0.0) <= 0 else brentq(excess, 0.0, mle, xtol=1e-9)
    upper = None
    if excess(MAX_JIG_ACCURACY_DEG) > 0:
        upper = brentq(excess, mle, MAX_JIG_ACCURACY_DEG, xtol=1e-9)
    at_edge = mle >= 0.999 * MAX_JIG_ACCURACY_DEG
    used = p < TEST_LEVEL and not at_edge
    if at_edge:
        reason = (f"the scatter would need a jig error beyond {MAX_JIG_ACCURACY_DEG:g} deg, more than the poses' "
                  "small-angle priors take: not a jig's error; the references are taken as exact")
    elif used:
        reason = (f"the poses scatter about the fit beyond their noise as a jig error would (likelihood-ratio "
                  f"test of a perfect jig: {p_text(p)} < {TEST_LEVEL:g})")
    else:
        reason = (f"the poses' scatter about the fit is within their noise (likelihood-ratio test of a perfect "
                  f"jig: {p_text(p)} >= {TEST_LEVEL:g}): the references are taken as exact")
    return JigEstimate(deg=mle if used else 0.0, mle_deg=mle, interval_deg=(lower, upper), lr=lr, p_value=p,
                       used=used, reason=reason)


def p_text(p: float) -> str:
    """A p-value in words: "p = 0.031", or "p < 1e-12" below what double precision tells."""
    return "p < 1e-12" if p < 1e-12 else f"p = {p:.2g}"


def estimate_jig_accuracy(device, method: str, means, sigma, F, start, dT=None) -> JigEstimate:
    """The jig accuracy (rms rotation angle, deg) the known poses' scatter implies.

    Parameters
    ----------
    device : Device
    method : {"offset", "gain", "full"}
    means : ndarray (P, N)
        Pose means, counts.
    sigma : ndarray (P, N)
        1-sigma of each mean (counts): the noise the scatter is judged against.
    F : ndarray (P, 3)
        The reference specific forces, m/s^2.
    start : tuple
        (b, s, beta, gamma): the fit with the poses at their references (the linearisation point).
    dT : ndarray (P,), optional
        Pose temperatures about T0 (degC) when temperature coefficients are fitted.

    Returns
    -------
    JigEstimate
    """
    y, X, J = linearised(device, method, np.asarray(means, float), np.asarray(sigma, float),
                         np.asarray(F, float), dT, start)
    return estimate_from_linear(y, X, J)


#: why a set of pose means, one row each, gets no estimate
ONE_ROW = ("each pose is one row (a file of pose means): the poses' noise is unknown, so their scatter cannot be "
           "split into noise and jig error; the references are taken as exact (--jig-accuracy states one)")


def fit_estimating_jig(device, poses: PoseSet, method: str = "full", *, temperature: bool = False) -> StaticFit:
    """The known-pose fit with the jig accuracy estimated from the poses' scatter (the default of
    :func:`accelcal.calibrate.calibrate_recordings`).

    The fit with the references exact (ordinary weighted least squares, weights the poses'
    ``sem()``; with ``temperature``, the temperature coefficients too) is the linearisation point
    of :func:`estimate_jig_accuracy`; where the test rejects a perfect jig, the fit is repeated
    with the references as priors of the estimated accuracy (:func:`accelcal.calibrate.
    fit_known_poses` / :func:`accelcal.calibrate.fit_static` with ``jig_accuracy_deg``), else
    the ordinary fit is returned.  Poses of one row each (no within-pose scatter: the noise is
    unknown) are not estimated: the ordinary fit, ONE_ROW as the reason.

    Parameters
    ----------
    device : Device
    poses : PoseSet
        Known poses (``f_ref`` on every pose).
    method : {"offset", "gain", "full"}
    temperature : bool
        Fit temperature coefficients (first order about the mean pose temperature).

    Returns
    -------
    StaticFit
        With ``jig_estimate`` (:meth:`JigEstimate.to_json`, or ``{"deg": 0, "used": False,
        "reason": ONE_ROW}``) and ``jig_accuracy_deg`` the accuracy used (0: ordinary least squares).
    """
    sig = poses.sem()

    def fit(deg: float, hint: bool = True) -> StaticFit:
        if temperature:
            return fit_static(device, poses, method, jigfree=False, temperature=True, sigma=sig, jig_accuracy_deg=deg)
        return fit_known_poses(device, poses.means, poses.f_ref, method, sig, poses=poses, jig_accuracy_deg=deg,
                               hint=hint)

    if not np.any(poses.n > 1):
        plain = fit(0.0)
        plain.jig_estimate = {"deg": 0.0, "used": False, "reason": ONE_ROW}
        return plain
    plain = fit(0.0, hint=False)
    dT = None if plain.temp_ref_c is None else poses.temp - plain.temp_ref_c
    est = estimate_jig_accuracy(device, method, poses.means, sig, poses.f_ref,
                                (plain.offsets, plain.sensitivity, plain.offset_tc, plain.gain_tc), dT)
    out = fit(est.deg) if est.used else plain
    out.jig_accuracy_deg = est.deg         # as estimated (the fit's own is through radians and back)
    out.jig_estimate = est.to_json()
    return out
