"""The noise floor: estimated from the data (static stretches, else robust differences)."""
from __future__ import annotations

import math

import numpy as np

from ..effects.adc import data_lattice
from ..effects.fitdata import FitData, tangent_basis, unit_rows3
from ..noise import MAD_TO_STD
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


def setup_rows(D: FitData, e: np.ndarray) -> None:
    """The data's noise floor and row weights (D.sigma, D.W, and jig-free the per-pose
    projections D.Qp), from the residual e of the model."""
    sig, how = noise_floor(D, e)
    D.sigma, D.noise_method = sig, how
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
