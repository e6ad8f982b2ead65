"""Lever arms: channel positions from rotation data with reference f, w and dw."""
from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..model import predict_counts
from .results import PositionFit
from .settings import POSITION_TOL_M


def calibrate_positions(device, offsets, sensitivity, raw, f, w, dw, *, segments: np.ndarray | None = None,
                        noise: np.ndarray | None = None, tol_m: float = POSITION_TOL_M,
                        source: str = "<arrays>") -> PositionFit:
    """Lever-arm corrections delta_r_i from samples with reference f, w and dw.

    raw_i - b_i - s_i . f(r_i) = s_i . (dw x dr_i + w x (w x dr_i)) + c_i,k = phi_i . dr_i + c_i,k
    with phi_i = s_i x dw + (s_i . w) w - |w|^2 s_i: linear per channel.  c_i,k is a
    constant per channel and per segment k (``segments``, e.g. one per recording),
    a nuisance that absorbs what the static calibration left in the offsets (else it
    would leak into dr through the mean of w^2).  The normal matrix of each channel
    is split into principal directions; a direction is observable when its 1-sigma
    is at most ``tol_m``; the estimate is kept only along the observable ones (zero,
    i.e. the nominal position, along the others).  ``noise``: per-sample noise of
    each channel (counts); default: from the residuals.
    """
    raw = np.asarray(raw, float)
    f, w, dw = (np.asarray(a, float) for a in (f, w, dw))
    seg = np.zeros(raw.shape[0], dtype=np.int64) if segments is None else np.asarray(segments, np.int64)
    ok = np.all(np.isfinite(f), 1) & np.all(np.isfinite(w), 1) & np.all(np.isfinite(dw), 1)
    if not ok.any():
        raise InputError(source, "no sample has f_*, w_* and dw_* all given: lever arms need rotation with a "
                         "reference", column="w_x")
    raw, f, w, dw, seg = raw[ok], f[ok], w[ok], dw[ok], seg[ok]
    b = np.asarray(offsets, float)
    S = np.asarray(sensitivity, float)
    y = raw - predict_counts(b, S, device.positions, f, dw, w)        # (n,N)
    ww = np.sum(w * w, axis=1)
    phi = (np.cross(S[None, :, :], dw[:, None, :])
           + np.einsum("nj,ij->ni", w, S)[:, :, None] * w[:, None, :]
           - ww[:, None, None] * S[None, :, :])                           # (n,N,3)
    # remove the per-segment constant (Frisch-Waugh: demean y and phi within segments)
    _, seg = np.unique(seg, return_inverse=True)
    n_seg = int(seg.max()) + 1
    cnt = np.bincount(seg, minlength=n_seg).astype(float)

    def demean(a):
        flat = a.reshape(a.shape[0], -1)
        means = np.stack([np.bincount(seg, weights=flat[:, j], minlength=n_seg) for j in range(flat.shape[1])], 1)
        return (flat - (means / cnt[:, None])[seg]).reshape(a.shape)

    y = demean(y)
    phi = demean(phi)
    N = S.shape[0]
    A = np.einsum("nik,nil->ikl", phi, phi)                           # (N,3,3)
    rhs = np.einsum("nik,ni->ik", phi, y)
    sig = np.full(N, np.nan) if noise is None else np.asarray(noise, float).copy()
    dr = np.zeros((N, 3))
    cov = np.zeros((N, 3, 3))
    dirs = np.zeros((N, 3, 3))
    sd = np.zeros((N, 3))
    obs = np.zeros((N, 3), dtype=bool)
    rms = np.zeros(N)
    n = raw.shape[0]
    for i in range(N):
        lam, V = np.linalg.eigh(A[i])
        lam = np.maximum(lam, 0.0)
        keep = lam > 1e-12 * max(float(lam.max()), 1e-300)
        coef = np.where(keep, (V.T @ rhs[i]) / np.where(keep, lam, 1.0), 0.0)
        if not np.isfinite(sig[i]):
            res = y[:, i] - phi[:, i, :] @ (V @ coef)
            sig[i] = math.sqrt(float(res @ res) / max(n - n_seg - int(keep.sum()), 1))
        var = np.where(keep, sig[i] ** 2 / np.where(keep, lam, 1.0), np.inf)
        o = np.sqrt(var) <= tol_m
        dirs[i] = V.T
        sd[i] = np.sqrt(var)
        obs[i] = o
        dr[i] = V[:, o] @ coef[o]
        cov[i] = (V[:, o] * var[o]) @ V[:, o].T
        rms[i] = math.sqrt(float(np.mean((y[:, i] - phi[:, i, :] @ dr[i]) ** 2)))
    return PositionFit(delta_r=dr, cov=cov, directions=dirs, sigma=sd, observable=obs, n_samples=int(n),
                       tol_m=tol_m, residual_rms=rms)
