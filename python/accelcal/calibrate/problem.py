"""The static model as a least-squares problem: channel parameters, optional temperature
coefficients and pose directions (free, or with the jig references as priors), its
residual and analytic Jacobian, the gauge of jig-free ``full`` fits, and the
covariance (constrained inverse of the Fisher information)."""
from __future__ import annotations

import math

import numpy as np

from .settings import MIN_RCOND_JAC


def tangent_basis(d: np.ndarray) -> np.ndarray:
    """(P,2,3) orthonormal basis of the plane perpendicular to each unit d (P,3)."""
    a = np.where(np.abs(d[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(d, e1)
    return np.stack([e1, e2], axis=1)


def gauge_rotation(device, sensitivity: np.ndarray) -> np.ndarray:
    """Rotation R (3,3) that puts ``sensitivity`` into the jig-free gauge: the
    orthogonal-Procrustes rotation mapping the directions s_i/|s_i| onto the nominal
    axes u_i, so that R s_i satisfies sum_i u_i x (R s_i/|s_i|) = 0.  Apply R to the
    s_i and to the pose forces alike (the readings do not change)."""
    s = np.asarray(sensitivity, float)
    sh = s / np.linalg.norm(s, axis=1, keepdims=True)
    H = device.axes.T @ sh                    # sum u_i sh_i^T
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


class StaticProblem:
    """Residuals and Jacobian of m_pi = b_i + beta_i dT_p + (1 + gamma_i dT_p) s_i . f_p,
    weighted by 1/sigma_pi, over channel parameters and (optionally) pose tangent coordinates.

    ``prior_rad`` (known poses with a stated jig accuracy theta, radians): the pose
    directions are free about the reference forces F (magnitude |F_p| kept) and
    2 rows a pose are appended, the tangent coordinates a_p / (theta / sqrt(3))
    (the prior: each component of a pose's rotation error has rms theta/sqrt(3))."""

    def __init__(self, device, method, means, sigma, dT, free_poses, F=None, gauge=False, prior_rad=None):
        self.dev = device
        self.method = method
        self.m = means
        self.w = 1.0 / sigma
        self.dT = dT                       # (P,) or None
        self.temp = dT is not None
        self.g = device.gravity_mps2
        self.P, self.N = means.shape
        self.free_poses = free_poses or prior_rad is not None
        self.prior_w = None if prior_rad is None else math.sqrt(3.0) / prior_rad
        self.q = {"offset": 1, "gain": 2, "full": 4}[method] + (2 if self.temp else 0)
        self.n_ch = self.q * self.N
        self.n_pose = 0
        self.F_fixed = None if self.free_poses else np.asarray(F, float)
        self.fmag = np.full(self.P, self.g)
        if self.free_poses and F is not None:
            if prior_rad is not None:
                self.fmag = np.linalg.norm(np.asarray(F, float), axis=1)
            self.set_pose_frame(F, gauge and prior_rad is None)

    @property
    def n_prior(self) -> int:
        return self.n_pose if self.prior_w is not None else 0

    def set_pose_frame(self, F: np.ndarray, gauge: bool) -> None:
        """Linearise the pose directions about F: f_p = |f_p| (d_p + T_p a_p)/|..|, a_p free
        where ``mask``.  With ``gauge``, the common rotation is held fixed during the
        solve: pose 0 entirely, and the pose most perpendicular to it may only move
        in the plane it spans with pose 0 (3 constraints)."""
        d = F / np.linalg.norm(F, axis=1, keepdims=True)
        T = tangent_basis(d)
        mask = np.ones((self.P, 2), dtype=bool)
        if gauge:
            c = int(np.argmax(np.linalg.norm(np.cross(d[0], d), axis=1)))
            nrm = np.cross(d[0], d[c])
            nrm /= np.linalg.norm(nrm)
            T[c] = np.stack([np.cross(nrm, d[c]), nrm])
            mask[0] = False
            mask[c, 1] = False
        self.d, self.T, self.mask = d, T, mask
        self.n_pose = int(mask.sum())

    def pack(self, b, s, beta=None, gamma=None) -> np.ndarray:
        cols = [b[:, None]]
        if self.method == "gain":
            cols.append(np.sum(s * self.dev.axes, axis=1)[:, None])
        elif self.method == "full":
            cols.append(s)
        if self.temp:
            cols += [np.zeros((self.N, 1)) if beta is None else beta[:, None],
                     np.zeros((self.N, 1)) if gamma is None else gamma[:, None]]
        x = np.hstack(cols).ravel()
        return np.concatenate([x, np.zeros(self.n_pose)])

    def unpack(self, x):
        c = x[: self.n_ch].reshape(self.N, self.q)
        b = c[:, 0]
        if self.method == "offset":
            s = self.dev.nominal_sensitivity()
            j = 1
        elif self.method == "gain":
            s = c[:, 1:2] * self.dev.axes
            j = 2
        else:
            s = c[:, 1:4]
            j = 4
        beta = c[:, j] if self.temp else None
        gamma = c[:, j + 1] if self.temp else None
        return b, s, beta, gamma

    def forces(self, x):
        """(P,3) pose forces and v (P,3) unnormalised directions."""
        if not self.free_poses:
            return self.F_fixed, None
        a = np.zeros((self.P, 2))
        a[self.mask] = x[self.n_ch:]
        v = self.d + np.einsum("pk,pkj->pj", a, self.T)
        return self.fmag[:, None] * v / np.linalg.norm(v, axis=1, keepdims=True), v

    def residual(self, x):
        b, s, beta, gamma = self.unpack(x)
        F, _ = self.forces(x)
        sf = F @ s.T                                   # (P,N)
        pred = b[None, :] + sf
        if self.temp:
            pred = pred + self.dT[:, None] * (beta[None, :] + gamma[None, :] * sf)
        r = ((self.m - pred) * self.w).ravel()
        if self.prior_w is None:
            return r
        return np.concatenate([r, x[self.n_ch:] * self.prior_w])

    def jacobian(self, x):
        P, N, q = self.P, self.N, self.q
        b, s, beta, gamma = self.unpack(x)
        F, v = self.forces(x)
        gain = np.ones((P, N)) if not self.temp else 1.0 + self.dT[:, None] * gamma[None, :]
        J = np.zeros((P, N, self.n_ch + self.n_pose))
        ch = np.arange(N)
        base = ch * q
        J[:, ch, base] = -1.0
        if self.method == "gain":
            J[:, ch, base + 1] = -gain * (F @ self.dev.axes.T)
            j = 2
        elif self.method == "full":
            for k in range(3):
                J[:, ch, base + 1 + k] = -gain * F[:, k:k + 1]
            j = 4
        else:
            j = 1
        if self.temp:
            J[:, ch, base + j] = -self.dT[:, None]
            J[:, ch, base + j + 1] = -self.dT[:, None] * (F @ s.T)
        if self.free_poses and self.n_pose:
            nv = np.linalg.norm(v, axis=1)
            fh = v / nv[:, None]
            # dF/da_k = |f|/|v| (I - fh fh^T) T_k
            dF = (self.fmag / nv)[:, None, None] * (
                self.T - np.einsum("pk,pj->pkj", np.einsum("pkj,pj->pk", self.T, fh), fh))
            ds = np.einsum("pkj,nj->pnk", dF, s) * gain[:, :, None]     # (P,N,2)
            cols = np.cumsum(self.mask.ravel()).reshape(P, 2) - 1 + self.n_ch
            for k in range(2):
                pk = np.flatnonzero(self.mask[:, k])
                J[pk[:, None], ch[None, :], cols[pk, k][:, None]] = -ds[pk, :, k]
        J *= self.w[:, :, None]
        J = J.reshape(P * N, -1)
        if self.prior_w is None:
            return J
        Jp = np.zeros((self.n_pose, J.shape[1]))
        Jp[:, self.n_ch:] = np.eye(self.n_pose) * self.prior_w
        return np.vstack([J, Jp])

    def reading_residual(self, r: np.ndarray) -> np.ndarray:
        """(P,N) reading residuals in counts from a residual vector (prior rows dropped)."""
        return r[: self.P * self.N].reshape(self.P, self.N) / self.w


def gauge_constraint(device, s: np.ndarray, n_par: int, q: int) -> np.ndarray:
    """(3, n_par) Jacobian of sum_i u_i x (s_i/|s_i|) w.r.t. the parameters (full method;
    channel i's s_i at columns i q + 1 .. i q + 3, nothing else enters)."""
    C = np.zeros((3, n_par))
    for i in range(device.n_channels):
        ns = np.linalg.norm(s[i])
        sh = s[i] / ns
        dsh = (np.eye(3) - np.outer(sh, sh)) / ns
        u = device.axes[i]
        ux = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        C[:, i * q + 1: i * q + 4] = ux @ dsh
    return C


def constrained_inverse(J: np.ndarray, C: np.ndarray | None, rtol: float = MIN_RCOND_JAC) -> np.ndarray | None:
    """(J^T J)^-1, or Z (Z^T J^T J Z)^-1 Z^T with Z spanning null(C) when a gauge
    constraint C is given; None when rank deficient (a parameter not determined)."""
    if C is None:
        Z = None
        A = J
    else:
        _, _, Vt = np.linalg.svd(C)
        Z = Vt[C.shape[0]:].T
        A = J @ Z
    # scale columns so the rank test does not depend on units
    cn = np.linalg.norm(A, axis=0)
    if np.any(cn == 0):
        return None
    if A.shape[0] < A.shape[1]:
        return None
    _, sv, Vt = np.linalg.svd(A / cn, full_matrices=False)
    if not sv[-1] > rtol * sv[0]:
        return None
    Ci = ((Vt.T / sv ** 2) @ Vt) / np.outer(cn, cn)
    return Ci if Z is None else Z @ Ci @ Z.T


def channel_cov(device, method, temperature, C, q) -> np.ndarray:
    """Map the per-channel blocks of C to [b, s_x, s_y, s_z, beta, gamma] (N,6,6)."""
    N = device.n_channels
    out = np.zeros((N, 6, 6))
    for i in range(N):
        blk = C[i * q:(i + 1) * q, i * q:(i + 1) * q]
        if method == "offset":
            Jm = np.zeros((6, q))
            Jm[0, 0] = 1
            j = 1
        elif method == "gain":
            Jm = np.zeros((6, q))
            Jm[0, 0] = 1
            Jm[1:4, 1] = device.axes[i]
            j = 2
        else:
            Jm = np.zeros((6, q))
            Jm[:4, :4] = np.eye(4)
            j = 4
        if temperature:
            Jm[4, j] = 1
            Jm[5, j + 1] = 1
        out[i] = Jm @ blk @ Jm.T
    return out
