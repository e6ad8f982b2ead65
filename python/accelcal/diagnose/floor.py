"""The noise floor: estimated from the data (static stretches, else robust differences)."""
from __future__ import annotations

import math

import numpy as np

from ..effects.adc import data_lattice
from ..effects.fitdata import FitData, tangent_basis, unit_rows3
from ..readings.noise import MAD_TO_STD, mean_rounding_var
from .settings import MIN_NOISE_DOF


def noise_floor(D: FitData, e: np.ndarray) -> tuple[np.ndarray, str]:
    """Per-channel noise (counts) of the residual e, and how it was found.  At least the rounding
    noise q/sqrt(12) of the converter's code step q (effects.adc.data_lattice; 1 count when the readings
    show none): a channel that sits on one code through each pose shows no spread within the
    poses, yet its readings are off the true value by up to q/2, differently at each pose."""
    N = D.N
    step = data_lattice(D)[0]
    rounding = np.maximum(step, 1.0) / math.sqrt(12.0)
    st = [(a, b) for a, b in zip(D.seg_lo, D.seg_hi) if D.static[a] and b - a >= 3]
    if st:
        var = np.array([np.var(e[a:b], axis=0, ddof=1) for a, b in st])      # (S, N)
        nu = np.array([b - a - 1 for a, b in st], float)
        dof = int(nu.sum())
        if dof >= MIN_NOISE_DOF:
            # the dof-weighted median of the segment variances (robust to a few segments that drift
            # or flip between quantisation levels), corrected by the median of chi2_nu / nu
            corr = (1.0 - 2.0 / (9.0 * nu)) ** 3
            v = var / corr[:, None]
            sig = np.empty(N)
            for i in range(N):
                o = np.argsort(v[:, i])
                cw = np.cumsum(nu[o])
                sig[i] = math.sqrt(v[o[np.searchsorted(cw, 0.5 * cw[-1])], i])
            return (np.maximum(sig, rounding),
                    f"median within-segment std of the residual over {len(st)} static segments ({dof} dof)")
    # fourth differences inside segments
    ok = np.zeros(D.n, bool)
    for a, b in zip(D.seg_lo, D.seg_hi):
        if b - a >= 5:
            ok[a + 2:b - 2] = True
    idx = np.flatnonzero(ok)
    if idx.size < 10:
        return np.maximum(rounding, float(np.std(e)) if e.size else 1.0), "residual std (too few samples)"
    d = e[idx - 2] - 4 * e[idx - 1] + 6 * e[idx] - 4 * e[idx + 1] + e[idx + 2]
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    sig = MAD_TO_STD * mad / math.sqrt(70.0)
    return np.maximum(sig, rounding), f"robust (MAD) fourth differences of the residual ({idx.size} samples)"


def pose_rounding_var(D: FitData, e: np.ndarray) -> np.ndarray:
    """(N,) variance (counts^2) of the bias the converter's rounding leaves in a static pose's
    mean, per channel: where the noise before the rounding is below its code step q, a pose's
    mean is off its true level by up to q/2 (on one code), the same in every sample of the pose.
    ``mean_rounding_var(s, q)`` with s the residual ``e``'s pooled scatter within the static
    poses' segments (:func:`accelcal.readings.noise.mean_rounding_var`, as the calibration's pose sems);
    q the readings' code step (1 where they show none); 0 without static poses.  0.3 counts of noise on a 1-count step leave 0.0015, one code q^2/12."""
    st = [(a, b) for a, b in zip(D.seg_lo, D.seg_hi) if D.static[a] and D.pose[a] >= 0 and b - a >= 2]
    if not st:
        return np.zeros(D.N)
    var = sum(np.var(e[a:b], axis=0, ddof=1) * (b - a - 1) for a, b in st) / sum(b - a - 1 for a, b in st)
    q = np.maximum(data_lattice(D)[0], 1.0)
    return np.asarray(mean_rounding_var(np.sqrt(var), q), float)


def pose_var_rows(D: FitData) -> np.ndarray:
    """(n_static, R) the rounding bias's variance (:func:`pose_rounding_var`, D.pose_var) in the
    scored rows of the samples of the static poses (jig-free: through each pose's projection)."""
    on = D.pose >= 0
    v = np.zeros(D.N) if D.pose_var is None else D.pose_var
    if D.Qp is None:
        return np.broadcast_to(v, (int(on.sum()), D.N))
    return (D.Qp[D.pose[on]] ** 2) @ v


def pose_design_effect(D: FitData) -> float:
    """How many times the rows' chi2 overstates what the static poses tell (D.W, D.pose_var and,
    jig-free, D.Qp set).  A pose's level error shared by all its samples (the rounding's bias,
    :func:`pose_rounding_var`) is in every fold: an effect that changes the poses' levels fits
    it on the training folds and keeps it on the held-out ones.  The n_p samples of pose p then
    carry one draw, worth 1 + (n_p - 1) rho in chi2, rho = v w (v the bias's variance in the
    row, w its weight; at most 1).  Returned: that design effect averaged over the rows (1 for
    rows outside the poses, and where the noise dithers the rounding)."""
    P = len(D.pose_labels)
    on = D.pose >= 0
    if P == 0 or not on.any():
        return 1.0
    n_p = np.bincount(D.pose[on], minlength=P).astype(float)
    rho = np.minimum(pose_var_rows(D) * D.W[on], 1.0)
    deff = 1.0 + (n_p[D.pose[on]][:, None] - 1.0) * rho
    return float((deff.sum() + (D.n - on.sum()) * D.R) / (D.n * D.R))


def independent_units(D: FitData) -> np.ndarray:
    """(B,) the unit each cross-validation block belongs to: its static pose (blocks of one pose
    share the pose's level error: the rounding's bias, a placement's tilt), else the block
    itself."""
    P = len(D.pose_labels)
    pose = D.pose[D.seg_lo[D.bseg]]
    return np.where(pose >= 0, pose, P + np.arange(D.B))


def setup_rows(D: FitData, e: np.ndarray) -> None:
    """The data's noise floor and row weights (D.sigma, D.W, and jig-free the per-pose
    projections D.Qp), the rounding bias of a pose's mean D.pose_var (:func:`pose_rounding_var`),
    the poses' design effect D.deff (:func:`pose_design_effect`) and the
    blocks' independent units D.unit (:func:`independent_units`), from the residual e of the
    model."""
    sig, how = noise_floor(D, e)
    D.sigma, D.noise_method = sig, how
    D.unit = independent_units(D)
    if D.mode == "jigfree":
        P = len(D.pose_labels)
        M = D.N - 2
        Qp = np.zeros((P, M, D.N))
        Wp = np.zeros((P, M))
        for p in range(P):
            sel = np.flatnonzero(D.pose == p)
            fp = unit_rows3(D.f[sel[0]])
            E = tangent_basis(fp)                       # (2,3)
            J = D.s @ E.T                                # (N,2)
            U, _, _ = np.linalg.svd(J, full_matrices=True)
            Q = U[:, 2:].T                               # (M,N)
            Qp[p] = Q
            Wp[p] = 1.0 / np.maximum(Q ** 2 @ sig ** 2, 1e-300)
        D.Qp = Qp
        D.W = Wp[D.pose]
    else:
        D.W = np.broadcast_to(1.0 / sig ** 2, (D.n, D.N))
    D.pose_var = pose_rounding_var(D, e)
    D.deff = pose_design_effect(D)

