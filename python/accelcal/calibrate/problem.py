"""The static model as a least-squares problem: channel parameters, optional temperature
coefficients and pose directions (free, or with the jig references as priors), its
residual and analytic Jacobian, the gauge of jig-free ``full`` fits, and the
covariance (constrained inverse of the Fisher information)."""
from __future__ import annotations

import math

import numpy as np
from scipy.sparse import csr_matrix

from .settings import MIN_RCOND_JAC, STRUCTURED_MIN_POSES


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

    @property
    def structured(self) -> bool:
        """Whether solves and covariances use the block structure (:func:`structured_inverse`, a
        sparse Jacobian): many free poses and no prior rows.  The dense forms cost O(P^3): 805
        poses took 24 s and 651 MB."""
        return self.free_poses and self.prior_w is None and self.P >= STRUCTURED_MIN_POSES

    def jacobian_parts(self, x):
        """(Jc (P,N,n_ch), Jp (P,N,2) or None): the weighted reading residuals' derivatives by the
        channel parameters and by each pose's two tangent coordinates (masked ones included)."""
        P, N, q = self.P, self.N, self.q
        b, s, beta, gamma = self.unpack(x)
        F, v = self.forces(x)
        gain = np.ones((P, N)) if not self.temp else 1.0 + self.dT[:, None] * gamma[None, :]
        Jc = np.zeros((P, N, self.n_ch))
        ch = np.arange(N)
        base = ch * q
        Jc[:, ch, base] = -1.0
        if self.method == "gain":
            Jc[:, ch, base + 1] = -gain * (F @ self.dev.axes.T)
            j = 2
        elif self.method == "full":
            for k in range(3):
                Jc[:, ch, base + 1 + k] = -gain * F[:, k:k + 1]
            j = 4
        else:
            j = 1
        if self.temp:
            Jc[:, ch, base + j] = -self.dT[:, None]
            Jc[:, ch, base + j + 1] = -self.dT[:, None] * (F @ s.T)
        Jc *= self.w[:, :, None]
        if not self.free_poses:
            return Jc, None
        nv = np.linalg.norm(v, axis=1)
        fh = v / nv[:, None]
        # dF/da_k = |f|/|v| (I - fh fh^T) T_k
        dF = (self.fmag / nv)[:, None, None] * (
            self.T - np.einsum("pk,pj->pkj", np.einsum("pkj,pj->pk", self.T, fh), fh))
        ds = np.einsum("pkj,nj->pnk", dF, s) * gain[:, :, None]     # (P,N,2)
        return Jc, -ds * self.w[:, :, None]

    def pose_columns(self) -> np.ndarray:
        """(P,2) column of each pose coordinate in x (meaningful where ``mask``)."""
        return np.cumsum(self.mask.ravel()).reshape(self.P, 2) - 1 + self.n_ch

    def jacobian(self, x):
        P, N = self.P, self.N
        Jc, Jp = self.jacobian_parts(x)
        J = np.zeros((P, N, self.n_ch + self.n_pose))
        J[:, :, :self.n_ch] = Jc
        if Jp is not None and self.n_pose:
            ch = np.arange(N)
            cols = self.pose_columns()
            for k in range(2):
                pk = np.flatnonzero(self.mask[:, k])
                J[pk[:, None], ch[None, :], cols[pk, k][:, None]] = Jp[pk, :, k]
        J = J.reshape(P * N, -1)
        if self.prior_w is None:
            return J
        Jp_rows = np.zeros((self.n_pose, J.shape[1]))
        Jp_rows[:, self.n_ch:] = np.eye(self.n_pose) * self.prior_w
        return np.vstack([J, Jp_rows])

    def jacobian_sparse(self, x):
        """:meth:`jacobian` as a scipy.sparse CSR matrix (readings only: no prior rows), built
        from its blocks without the dense (P N, n_ch + 2 P) array."""
        P, N, nc = self.P, self.N, self.n_ch
        Jc, Jp = self.jacobian_parts(x)
        r = np.arange(P * N)
        rows = [np.repeat(r, nc)]
        cols = [np.tile(np.arange(nc), P * N)]
        data = [Jc.reshape(-1)]
        if Jp is not None and self.n_pose:
            pc = self.pose_columns()
            for k in range(2):
                pk = np.flatnonzero(self.mask[:, k])
                rows.append((pk[:, None] * N + np.arange(N)[None, :]).ravel())
                cols.append(np.repeat(pc[pk, k], N))
                data.append(Jp[pk, :, k].ravel())
        return csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(P * N, nc + self.n_pose))

    def determined(self, x, rtol: float = MIN_RCOND_JAC) -> bool:
        """Whether the readings determine every free parameter at x (the rank test of
        :func:`constrained_inverse`, by :func:`structured_inverse` when :attr:`structured`)."""
        if self.structured:
            Jc, Jp = self.jacobian_parts(x)
            return structured_inverse(Jc, Jp, self.mask, rtol=rtol) is not None
        return constrained_inverse(self.jacobian(x), None, rtol) is not None

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


def structured_inverse(Jc: np.ndarray, Jp: np.ndarray | None, mask: np.ndarray, C: np.ndarray | None = None,
                       rtol: float = MIN_RCOND_JAC) -> tuple[np.ndarray, np.ndarray | None] | None:
    """The channel block and each pose's 2x2 block of :func:`constrained_inverse` for the static
    problem's J = [Jc | block-diagonal Jp] (no prior rows), in O(P) instead of O(P^3): each
    pose's coordinates eliminated (Schur complement A = sum_p Jc_p^T (I - Jp_p H_p^-1 Jp_p^T) Jc_p,
    H_p = Jp_p^T Jp_p), then Sigma_c = Z (Z^T A Z)^-1 Z^T and Sigma_pp = H_p^-1 + G_p Sigma_c G_p^T
    with G_p = H_p^-1 Jp_p^T Jc_p: block inversion, the same numbers as the dense inverse.

    Parameters
    ----------
    Jc : ndarray (P, N, n_ch)
    Jp : ndarray (P, N, 2) or None
        The pose coordinates' columns (:meth:`StaticProblem.jacobian_parts`); only those in
        ``mask`` (P, 2) are free.
    C : ndarray (k, n_ch [+ anything zero]), optional
        A gauge constraint on the channel parameters (columns past n_ch must be zero).
    rtol : float
        The rank test: the column-normalised Schur complement's (and each pose block's)
        singular-value ratio, as sqrt of its eigenvalue ratio.

    Returns
    -------
    (Sigma_c (n_ch, n_ch), Sigma_poses (P, 2, 2) or None), or None when rank deficient.
    """
    P, N, nc = Jc.shape
    free = int(mask.sum()) if Jp is not None else 0
    if P * N < nc + free:
        return None
    cn = np.sqrt(np.einsum("pni,pni->i", Jc, Jc))
    if np.any(cn == 0):
        return None
    A = np.einsum("pni,pnj->ij", Jc, Jc)
    G = Hinv = None
    if Jp is not None and free:
        Jm = Jp * mask[:, None, :]
        H = np.einsum("pnk,pnl->pkl", Jm, Jm) + np.eye(2)[None] * (~mask)[:, :, None]
        d = np.sqrt(np.einsum("pkk->pk", H))
        if np.any(d == 0):
            return None
        Hn = H / (d[:, :, None] * d[:, None, :])
        ev = np.linalg.eigvalsh(Hn)
        if not np.all(ev[:, 0] > (rtol ** 2) * ev[:, -1]):
            return None
        Hinv = np.linalg.inv(H)
        G = np.einsum("pkl,pnl,pni->pki", Hinv, Jm, Jc)              # (P, 2, n_ch)
        A = A - np.einsum("pni,pnk,pkj->ij", Jc, Jm, G)
    if C is not None:
        C = np.asarray(C, float)
        if np.any(C[:, nc:] != 0):
            raise ValueError("the gauge constraint may act on the channel parameters only")
        _, _, Vt = np.linalg.svd(C[:, :nc])
        Z = Vt[C.shape[0]:].T
    else:
        Z = np.eye(nc)
    M = Z.T @ A @ Z
    zn = np.sqrt(np.sum(np.einsum("pnk,kj->pnj", Jc, Z) ** 2, axis=(0, 1)))     # column norms of J Z
    if np.any(zn == 0):
        return None
    Mn = M / np.outer(zn, zn)
    w, V = np.linalg.eigh((Mn + Mn.T) / 2.0)
    if not w[0] > (rtol ** 2) * w[-1]:
        return None
    Sc = Z @ (((V / w) @ V.T) / np.outer(zn, zn)) @ Z.T
    if G is None:
        return Sc, None
    Sp = Hinv + np.einsum("pki,ij,plj->pkl", G, Sc, G)
    return Sc, Sp


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
