"""Angular rate from the accelerometers themselves (issue 36): the maximum-likelihood omega of
an array with more than six channels, fused with the integration of its alpha.

The model is the project's (:mod:`accelcal.model`): channel i reads
``b_i + s_i . (f + alpha x r_i + omega x (omega x r_i))`` plus white noise of sd k_i counts.
Once [f; alpha] is fitted (weighted least squares for a given omega), what is left of one
sample's readings is ``q = m p(omega) + v``, v of covariance m, where p(omega) are the six rate
products (:func:`accelcal.model.centripetal_split`): the concentrated likelihood of Skog,
Nilsson, Haendel and Nehorai (IEEE Trans. Signal Process. 64(16), 2016).  Its Fisher
information is ``J^T m J`` (J = dp/domega), which grows with |omega|^2 and the array's size
squared, and p is even in omega: the sign of omega is not in one sample's readings.

* :func:`omega_ml` -- per sample, vectorised: Gauss-Newton on the concentrated likelihood
  from a start (the closed form where all six products are observed: the leading eigenvector
  of the symmetric matrix p, else the integrated alpha's prediction); fixed iterations.
* :func:`array_omega` -- the fused estimate, sample by sample: the prediction
  omega[n-1] + dt (alpha[n-1] + alpha[n]) / 2 (trapezoid) with its covariance (the alpha
  noise through the resolver, plus a model term), then Gauss-Newton on the posterior (prior
  + concentrated likelihood) from the prediction, or from the ML estimate with the sign
  nearer the prediction where that lowers the posterior's cost by more than
  :data:`omega_filter.JUMP_CHI2` (an iterated EKF; :mod:`.omega_filter`).  At small |omega|
  the likelihood carries little information and the result is the integration; the sign
  follows by continuity.  The 1-sigma is from the posterior information.
* :func:`omega_observability` -- what a layout observes, in one line.

Recording form: :func:`omega_from_recording`; :func:`choose_omega` is ``resolve --omega``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import model
from ..errors import InputError
from ..io.recording import check_for_device
from .common import channel_noise, uniform_dt
from .omega_filter import fuse

__all__ = ["OMEGA_SOURCES", "OmegaObservability", "ArrayOmega", "omega_observability", "omega_ml",
           "row_products", "resolve_rows", "FusedOmega", "array_omega", "omega_from_recording", "choose_omega",
           "wants_array_omega", "omega_columns", "omega_crb"]

#: ``resolve --omega``: the recording's w columns, none, the array's own estimate, or auto
OMEGA_SOURCES = ("auto", "reference", "none", "array")
#: relative size below which an eigenvalue of m or of the information counts as zero
RANK_RTOL = 1e-9
#: the prediction's model term: the trapezoid's error per step, snap dt^3 / 12 (rad/s), for an alpha whose
#: second derivative reaches SNAP rad/s^4 (a 2-revolution quintic turn in 0.5 s: 1.1e5)
SNAP = 3.0e5
_AXES = ("w_x", "w_y", "w_z")
_SUGGEST = ("a layout that observes omega: 12 channels as four triads on a tetrahedron "
            "(accelcal.io.device.tetrahedron_device) or triads at the origin and on the three axes (axes_device)")


@dataclass(frozen=True)
class OmegaObservability:
    """What a layout's accelerometers say of omega (generic omega, any noise).

    Attributes
    ----------
    axes : tuple of bool
        Whether omega's body x, y, z components are observable.
    products : int
        How many of the six rate products the readings fix (6: omega up to its sign; fewer:
        up to mirror solutions too, chosen by continuity with the integrated alpha).
    line : str
        The one-line statement.
    """

    axes: tuple
    products: int
    line: str

    @property
    def full(self) -> bool:
        return all(self.axes)


def _directions() -> np.ndarray:
    d = np.random.default_rng(36).normal(size=(24, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def omega_observability(positions, axes) -> OmegaObservability:
    """Whether a layout (channel positions (N, 3) m and axes (N, 3)) observes omega.

    The information ``J^T m J`` of unit-noise channels at 24 generic rates: the directions no
    rate informs are not observable; a body axis is when it has no part in them.

    Returns
    -------
    OmegaObservability
    """
    pos = np.asarray(positions, float)
    ax = np.asarray(axes, float)
    ax = ax / np.linalg.norm(ax, axis=1, keepdims=True)
    n = pos.shape[0]
    size = float(np.max(np.linalg.norm(pos, axis=1), initial=0.0))
    if n < 6 or size == 0.0 or np.linalg.matrix_rank(model.sensor_matrix(pos / size, ax), 1e-9) < 6:
        return OmegaObservability((False,) * 3, 0, f"omega is not observable: this layout's {n} channels do not "
                                  f"resolve alpha (its sensor matrix has rank < 6); {_SUGGEST}")
    split = model.centripetal_split(pos / size, ax, np.ones(n))
    scale = float(np.sum(model.centripetal_matrix(pos / size, ax) ** 2))
    lam = np.linalg.eigvalsh(split.m)
    products = int(np.sum(lam > RANK_RTOL * scale))
    if products == 0:
        why = ("six channels fix f and alpha exactly, nothing is left for the centripetal term" if n == 6 else
               "what the channels read beyond f and alpha has no centripetal part")
        return OmegaObservability((False,) * 3, 0, f"omega is not observable from this layout's {n} channels: "
                                  f"{why}; {_SUGGEST}")
    info = np.sum(model.omega_information(split.m, _directions()), axis=0)
    w, V = np.linalg.eigh(info)
    null = V[:, w <= RANK_RTOL * max(float(w[-1]), scale)]
    seen = tuple(bool(np.linalg.norm(null[k]) < 1e-6) for k in range(3))
    mirror = "up to its sign" if products == 6 else \
        f"{products} of the 6 rate products: up to its sign and mirror solutions"
    if all(seen):
        return OmegaObservability(seen, products, f"omega is observable on all three axes from this layout's {n} "
                                  f"channels ({mirror}, chosen by continuity with the integrated alpha)")
    named = [a for a, s in zip(_AXES, seen) if s]
    if not named:
        dirs = "; ".join("(" + ", ".join(f"{x:+.2f}" for x in v) + ")" for v in null.T)
        return OmegaObservability(seen, products, f"omega is observable only partly from this layout's {n} "
                                  f"channels: no body axis on its own (not along {dirs}); {_SUGGEST}")
    rest = [a for a, s in zip(_AXES, seen) if not s]
    return OmegaObservability(seen, products, f"omega is observable only on {', '.join(named)} from this layout's "
                              f"{n} channels ({', '.join(rest)} from the integrated alpha alone); {_SUGGEST}")


def _products_matrix(p: np.ndarray) -> np.ndarray:
    """The symmetric (..., 3, 3) omega omega^T whose entries are the products p."""
    xx, yy, zz, xy, yz, zx = (p[..., k] for k in range(6))
    return np.stack([np.stack([xx, xy, zx], -1), np.stack([xy, yy, yz], -1), np.stack([zx, yz, zz], -1)], -2)


def omega_ml(q, m, start=None, iterations: int = 4, ridge: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample maximum-likelihood omega (up to its sign) from the centripetal readings.

    Parameters
    ----------
    q : array_like (n, 6)
        ``qmap @ (raw - b)`` (:class:`accelcal.model.CentripetalSplit`).
    m : array_like (6, 6)
    start : array_like (n, 3), optional
        rad/s: where Gauss-Newton starts.  Default: the closed form (the leading eigenvector
        of the symmetric matrix of products ``m^-1 q``), which needs all six products.
    iterations : int
        Gauss-Newton steps (fixed).
    ridge : float, optional
        Added to the normal matrix's diagonal, per (rad/s)^2 (default ``RANK_RTOL trace(m)``).

    Returns
    -------
    omega : ndarray (n, 3)
        rad/s.
    information : ndarray (n, 3, 3)
        Fisher information at omega, per (rad/s)^2.
    """
    q = np.atleast_2d(np.asarray(q, float))
    m = np.asarray(m, float)
    if start is None:    # m^-1 q (lstsq's cutoff), each row on its own (row_products)
        minv = np.linalg.pinv(m, rcond=np.finfo(float).eps * 6)
        lam, V = np.linalg.eigh(_products_matrix(row_products(q, minv)))
        w = V[..., :, -1] * np.sqrt(np.maximum(lam[..., -1], 0.0))[..., None]
    else:
        w = np.array(start, float)
    ridge = (RANK_RTOL * max(float(np.trace(m)), 1e-300) if ridge is None else float(ridge)) * np.eye(3)
    for _ in range(iterations):
        J = model.product_jacobian(w)
        Jt = np.swapaxes(J, -1, -2)
        g = (Jt @ (q - row_products(model.omega_products(w), m))[..., None])[..., 0]
        w = w + np.linalg.solve(Jt @ m @ J + ridge, g[..., None])[..., 0]
    return w, model.omega_information(m, w)


@dataclass
class ArrayOmega:
    """The array's own omega, per sample.

    Attributes
    ----------
    w, sigma : ndarray (n, 3)
        The fused estimate and its 1-sigma, rad/s.
    f, alpha : ndarray (n, 3)
        m/s^2 and rad/s^2 resolved with that omega's centripetal term.
    w_ml : ndarray (n, 3)
        The accelerometers' maximum-likelihood omega alone, its sign the fused estimate's.
    info_ml : ndarray (n, 3, 3)
        Its Fisher information, per (rad/s)^2.
    observability : OmegaObservability
    w_core : ndarray (n, 3) or None
        The C core's Q5.10 rate for its resolver (rad/s, clipped to +-32 rad/s; ``engine="fixed"``
        only): what firmware passes from ``ac_omega_step`` to ``ac_resolve``.
    """

    w: np.ndarray
    sigma: np.ndarray
    f: np.ndarray
    alpha: np.ndarray
    w_ml: np.ndarray
    info_ml: np.ndarray
    observability: OmegaObservability
    w_core: np.ndarray | None = None

    def for_resolver(self) -> np.ndarray:
        """The rate the resolver's centripetal term takes: the core's Q5.10 output where there is
        one (engine "fixed"), else w."""
        return self.w if self.w_core is None else self.w_core


def row_products(x, a) -> np.ndarray:
    """``x @ a.T`` (n, J) row by row in a fixed order: each row's sum over k taken k = 0, 1, ...
    whatever the other rows are (BLAS's sums depend on the rows around one: a lone row at the end
    of a block, or the split between threads, rounds otherwise), so that a recording in chunks
    gives the numbers of the whole (docs/streaming.md).

    Parameters
    ----------
    x : array_like (n, K)
    a : array_like (J, K)
    """
    x = np.atleast_2d(np.asarray(x, float))
    a = np.asarray(a, float)
    out = x[:, :1] * a[:, 0]
    for k in range(1, a.shape[1]):
        out = out + x[:, k:k + 1] * a[:, k]
    return out


def resolve_rows(offsets, sensitivity, positions, raw, omega) -> tuple[np.ndarray, np.ndarray]:
    """:func:`accelcal.model.resolve` with omega's centripetal term, each row's sums in a fixed order
    (:func:`row_products`): f (n, 3) m/s^2 and alpha (n, 3) rad/s^2 of raw counts (n, N) and omega
    (n, 3) rad/s, the same numbers whole or in chunks."""
    y = np.atleast_2d(np.asarray(raw, float)) - np.asarray(offsets, float)
    y = y - row_products(model.omega_products(np.atleast_2d(omega)), model.centripetal_matrix(positions, sensitivity))
    out = row_products(y, model.resolve_matrix(positions, sensitivity))
    return out[:, :3], out[:, 3:]


class FusedOmega:
    """The fused omega's per-sample filter (:func:`array_omega`), run on a recording whole or chunk
    by chunk with its state carried (:mod:`accelcal.estimators.rate_stream`,
    :mod:`~accelcal.estimators.attitude_stream`): the same numbers.

    Parameters as :func:`array_omega` (without ``raw``).
    """

    def __init__(self, offsets, sensitivity, positions, dt: float, noise_counts, *, iterations: int = 2,
                 snap: float = SNAP, omega0=None, sigma0: float = 0.01) -> None:
        self.split = split = model.centripetal_split(positions, sensitivity, noise_counts)
        self.obs = omega_observability(positions, sensitivity)
        self.offsets = np.asarray(offsets, float)
        self.dt, self.iterations = float(dt), iterations
        self.Q = dt * dt * split.cov[3:, 3:] + (snap * dt ** 3 / 12.0) ** 2 * np.eye(3)
        self.x0 = np.zeros(3) if omega0 is None else np.asarray(omega0, float)
        self.P0 = sigma0 ** 2 * np.eye(3)
        self.state: dict = {}
        self.a_last: np.ndarray | None = None   # the ML start's integrated alpha: the last row and sum
        self.a_sum = np.zeros(3)

    def readings(self, raw) -> tuple[np.ndarray, np.ndarray]:
        """The centripetal readings q (n, 6) and the alpha rows' [f; alpha] before the centripetal
        term, lin (n, 6), of raw counts (n, N)."""
        y = np.atleast_2d(np.asarray(raw, float)) - self.offsets
        return row_products(y, self.split.qmap), row_products(y, self.split.lin)

    def step(self, q, lin) -> tuple[np.ndarray, np.ndarray]:
        """The next samples' fused omega (n, 3) rad/s and its covariance (n, 3, 3) (rad/s)^2."""
        m = self.split.m
        if self.obs.products == 6:
            w_ml, _ = omega_ml(q, m)
        else:   # the integrated alpha (no centripetal correction) as the start, its sum carried
            a0 = lin[:, 3:]
            prev = a0[:1] if self.a_last is None else self.a_last
            d = (a0 + np.vstack([prev, a0[:-1]])) * (self.dt / 2.0)
            start = np.cumsum(np.vstack([self.a_sum[None], d]), axis=0)[1:] if self.a_last is not None else \
                np.cumsum(d, axis=0)
            if len(a0):
                self.a_last, self.a_sum = a0[-1:], start[-1]
            w_ml, _ = omega_ml(q, m, start)
        return fuse(q, lin[:, 3:], self.split.leak[3:], self.Q, m, w_ml, self.dt, self.x0, self.P0,
                    self.iterations, state=self.state)


def array_omega(offsets, sensitivity, positions, raw, dt: float, noise_counts, *, iterations: int = 2,
                snap: float = SNAP, omega0=None, sigma0: float = 0.01) -> ArrayOmega:
    """The fused omega of an array (float reference), sample by sample.

    Parameters
    ----------
    offsets : array_like (N,)
        counts.
    sensitivity : array_like (N, 3)
        counts per m/s^2.
    positions : array_like (N, 3)
        m.
    raw : array_like (n, N)
        counts.
    dt : float
        Sample interval, s.
    noise_counts : array_like (N,)
        Each channel's noise sd, counts (rounding included).
    iterations : int
        Gauss-Newton steps on the posterior per sample (fixed).
    snap : float
        rad/s^4: the prediction's model term beyond the alpha noise, the trapezoid's error per
        step ``snap dt^3 / 12`` rad/s (sd).
    omega0 : array_like (3,), optional
        rad/s at the first sample (default 0: the recording starts at rest).
    sigma0 : float
        Its sd, rad/s.  Small: a broad prior at rest lets the posterior's mode follow the noise
        of the centripetal readings (their ML at rest is noise of some 0.3 rad/s); a recording
        that starts turning is caught by the ML start (:data:`omega_filter.JUMP_CHI2`).

    Returns
    -------
    ArrayOmega
    """
    fo = FusedOmega(offsets, sensitivity, positions, dt, noise_counts, iterations=iterations, snap=snap,
                    omega0=omega0, sigma0=sigma0)
    q, lin = fo.readings(raw)
    w, cov = fo.step(q, lin)
    theta = lin - row_products(model.omega_products(w), fo.split.leak)
    # the accelerometers' ML alone on the fused estimate's branch (its sign, its mirror solution)
    w_ml, info_ml = omega_ml(q, fo.split.m, w)
    sigma = np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
    return ArrayOmega(w, sigma, theta[:, :3], theta[:, 3:], w_ml, info_ml, fo.obs)


def omega_from_recording(device, cal, rec, **options) -> ArrayOmega:
    """:func:`array_omega` of a recording: the calibration's offsets, sensitivities and
    positions, each channel's noise (the device's ``noise_mps2`` or the recording's own) with
    the rounding's 1/12 count^2, dt from the time column.

    Raises
    ------
    InputError
        A layout that does not observe omega on every axis (the observability line), a
        recording that does not fit the device or has non-uniform time.
    """
    check_for_device(rec, device, min_samples=2)
    pos = cal.positions_or_nominal(device)
    obs = omega_observability(pos, cal.sensitivity)
    if not obs.full:
        raise InputError(device.name, obs.line)
    dt = uniform_dt(rec)
    noise = np.sqrt(np.asarray(channel_noise(device, rec), float) ** 2 + 1.0 / 12.0)
    return array_omega(cal.offsets, cal.sensitivity, pos, rec.raw, dt, noise, **options)


def wants_array_omega(device, cal, rec, source: str) -> bool:
    """``resolve --omega``: whether the array's own omega is used: for "array", and for "auto"
    when the recording has no complete w columns and the layout observes omega on every axis.

    Raises
    ------
    ValueError
        An unknown source.
    """
    if source not in OMEGA_SOURCES:
        raise ValueError(f"unknown omega source {source!r}")
    if source == "array":
        return True
    if source != "auto" or device.is_triad() or rec.n_samples < 2:
        return False
    if rec.w is not None and np.all(np.isfinite(rec.w)):
        return False
    return omega_observability(cal.positions_or_nominal(device), cal.sensitivity).full


def choose_omega(device, cal, rec, source: str) -> ArrayOmega | None:
    """``resolve --omega``: the array's own omega (float) where :func:`wants_array_omega`, else
    None (the caller takes the w columns or none).

    Raises
    ------
    InputError
        "array" on a layout that does not observe omega (the observability line).
    """
    return omega_from_recording(device, cal, rec) if wants_array_omega(device, cal, rec, source) else None


def omega_columns(est: ArrayOmega) -> dict:
    """The output columns of the array's omega: w_x, w_y, w_z and their 1-sigma w_x_sigma,
    w_y_sigma, w_z_sigma (rad/s)."""
    cols = {a: est.w[:, k] for k, a in enumerate(_AXES)}
    cols.update({f"{a}_sigma": est.sigma[:, k] for k, a in enumerate(_AXES)})
    return cols


def omega_crb(m, omega) -> np.ndarray:
    """The per-sample Cramer-Rao bound (n, 3, 3) of omega from the accelerometers alone,
    (rad/s)^2 (infinite where the information is singular: at omega = 0)."""
    info = model.omega_information(np.asarray(m, float), np.atleast_2d(np.asarray(omega, float)))
    out = np.full(info.shape, math.inf)
    ok = np.linalg.cond(info) < 1e12
    out[ok] = np.linalg.inv(info[ok])
    return out
