"""Float64 reference model: the truth the C core and the estimators are held to.

Conventions (docs/data-contract.md): body frame, SI units; specific force
at a point r is f + alpha x r + omega x (omega x r); channel i reads
raw_i = b_i + s_i . f(r_i).  Arrays broadcast over leading sample axes.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

# Order of the squared-rate products used by the centripetal table (and the C core).
OMEGA_PRODUCTS = ("wx*wx", "wy*wy", "wz*wz", "wx*wy", "wy*wz", "wz*wx")


def sensor_matrix(positions: np.ndarray, sensitivity: np.ndarray) -> np.ndarray:
    """R (N,6): row i = [s_i, r_i x s_i]; counts = R [f; alpha] + c(omega) + b."""
    s = np.asarray(sensitivity, float)
    r = np.asarray(positions, float)
    return np.hstack([s, np.cross(r, s)])


def centripetal_matrix(positions: np.ndarray, sensitivity: np.ndarray) -> np.ndarray:
    """C (N,6) with c_i(omega) = s_i . (omega x (omega x r_i)) = C_i . omega_products(omega)."""
    s = np.asarray(sensitivity, float)
    r = np.asarray(positions, float)
    sr = np.sum(s * r, axis=1)
    diag = s * r - sr[:, None]
    cross = np.stack(
        [s[:, 0] * r[:, 1] + s[:, 1] * r[:, 0],
         s[:, 1] * r[:, 2] + s[:, 2] * r[:, 1],
         s[:, 2] * r[:, 0] + s[:, 0] * r[:, 2]], axis=1)
    return np.hstack([diag, cross])


def omega_products(omega: np.ndarray) -> np.ndarray:
    """(..., 6): wx^2, wy^2, wz^2, wx wy, wy wz, wz wx."""
    w = np.asarray(omega, float)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    return np.stack([x * x, y * y, z * z, x * y, y * z, z * x], axis=-1)


def specific_force_at(f: np.ndarray, alpha: np.ndarray | None, omega: np.ndarray | None,
                      r: np.ndarray) -> np.ndarray:
    """f(r) = f + alpha x r + omega x (omega x r); f, alpha, omega (...,3), r (3,) or (...,3)."""
    out = np.array(f, float, copy=True)
    if alpha is not None:
        out = out + np.cross(alpha, r)
    if omega is not None:
        out = out + np.cross(omega, np.cross(omega, r))
    return out


def predict_counts(offsets: np.ndarray, sensitivity: np.ndarray, positions: np.ndarray,
                   f: np.ndarray, alpha: np.ndarray | None = None,
                   omega: np.ndarray | None = None) -> np.ndarray:
    """Noise-free, unrounded readings (n, N) = b + R [f; alpha] + C p(omega)."""
    f = np.atleast_2d(np.asarray(f, float))
    R = sensor_matrix(positions, sensitivity)
    out = f @ R[:, :3].T + np.asarray(offsets, float)
    if alpha is not None:
        out = out + np.atleast_2d(alpha) @ R[:, 3:].T
    if omega is not None:
        out = out + omega_products(np.atleast_2d(omega)) @ centripetal_matrix(positions, sensitivity).T
    return out


def product_jacobian(omega: np.ndarray) -> np.ndarray:
    """d omega_products / d omega, (..., 6, 3), in the order of OMEGA_PRODUCTS."""
    w = np.asarray(omega, float)
    x, y, z = w[..., 0], w[..., 1], w[..., 2]
    o = np.zeros_like(x)
    rows = [(2 * x, o, o), (o, 2 * y, o), (o, o, 2 * z), (y, x, o), (o, z, y), (z, o, x)]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


class CentripetalSplit(NamedTuple):
    """The readings of an array split, with each channel weighted by its noise, into the part
    that resolves [f; alpha] and the part only the centripetal term can explain.

    ``[f; alpha] = lin @ (raw - b) - leak @ p(omega)`` (the weighted least squares for a given
    omega, ``cov`` its covariance from the noise); ``q = qmap @ (raw - b) = m p(omega) + v``
    with v of covariance ``m``: the centripetal readings left over once [f; alpha] is fitted
    (independent of the [f; alpha] estimate's noise).  The Fisher information of omega is
    ``J(omega)^T m J(omega)`` (J = :func:`product_jacobian`); m = 0 for six channels."""

    lin: np.ndarray    # (6, N) per count
    leak: np.ndarray   # (6, 6)
    cov: np.ndarray    # (6, 6) (m/s^2, rad/s^2)^2
    qmap: np.ndarray   # (6, N)
    m: np.ndarray      # (6, 6) per (rad/s)^4


def centripetal_split(positions: np.ndarray, sensitivity: np.ndarray, noise_counts: np.ndarray) -> CentripetalSplit:
    """:class:`CentripetalSplit` of a layout (positions m, sensitivity counts per m/s^2, each
    channel's noise sd in counts); LinAlgError when the sensor matrix has rank < 6."""
    k = np.asarray(noise_counts, float)
    R = sensor_matrix(positions, sensitivity) / k[:, None]
    C = centripetal_matrix(positions, sensitivity) / k[:, None]
    if R.shape[0] < 6 or np.linalg.matrix_rank(R) < 6:
        raise np.linalg.LinAlgError("sensor matrix has rank < 6")
    Rp = np.linalg.pinv(R)
    A = C - R @ (Rp @ C)
    return CentripetalSplit(Rp / k[None, :], Rp @ C, Rp @ Rp.T, A.T / k[None, :], A.T @ A)


def omega_information(m: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """Fisher information (..., 3, 3) of omega (per (rad/s)^2) from one sample's readings,
    [f; alpha] unknown: J^T m J with m from :func:`centripetal_split`."""
    J = product_jacobian(omega)
    return np.swapaxes(J, -1, -2) @ m @ J


def resolve_matrix(positions: np.ndarray, sensitivity: np.ndarray) -> np.ndarray:
    """M (6,N): the inverse (N = 6) or least-squares pseudo-inverse of R."""
    R = sensor_matrix(positions, sensitivity)
    if R.shape[0] < 6 or np.linalg.matrix_rank(R) < 6:
        raise np.linalg.LinAlgError("sensor matrix has rank < 6")
    return np.linalg.pinv(R)


def resolve(offsets: np.ndarray, sensitivity: np.ndarray, positions: np.ndarray,
            counts: np.ndarray, omega: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """[f; alpha] = M (counts - b - c(omega)); returns f (n,3), alpha (n,3)."""
    y = np.atleast_2d(np.asarray(counts, float)) - np.asarray(offsets, float)
    if omega is not None:
        y = y - omega_products(np.atleast_2d(omega)) @ centripetal_matrix(positions, sensitivity).T
    out = y @ resolve_matrix(positions, sensitivity).T
    return out[:, :3], out[:, 3:]


def rate_integrate(alpha: np.ndarray, dt: float, leak: float = 0.0,
                   omega0: np.ndarray | None = None) -> np.ndarray:
    """Leaky integration w[n] = (1 - leak) w[n-1] + dt alpha[n] (the C core's recurrence,
    leak as a fraction per step); alpha (n,3) -> omega (n,3)."""
    a = np.atleast_2d(np.asarray(alpha, float))
    lam = 1.0 - leak
    w = np.zeros(3) if omega0 is None else np.asarray(omega0, float).copy()
    out = np.empty_like(a)
    if lam == 1.0:
        return np.cumsum(a * dt, axis=0) + w
    # closed form of the recurrence: w_n = lam^n w_0 + sum_k lam^(n-k) dt a_k, done blockwise
    # to stay vectorised without overflowing lam^-n
    block = max(1, int(min(4096, 30.0 / max(-np.log(lam), 1e-300))))
    for start in range(0, len(a), block):
        seg = a[start:start + block] * dt
        k = np.arange(len(seg))
        pw = lam ** (-k.astype(float))
        acc = np.cumsum(seg * pw[:, None], axis=0)
        out[start:start + block] = (lam ** k)[:, None] * (w * lam + acc)
        w = out[start + len(seg) - 1]
    return out
