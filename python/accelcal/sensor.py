"""The sensor model's prediction: channel state, context and the noise-free readings.

The channel state (:class:`ChannelState`) is everything the sensor equation needs::

    counts_i(t) = b_i + bias_i(t) + gain_i(t) * c_sensed_i(t + tau_i)
    c_sensed_i  = s_i . ( f + alpha x r_i + m_i * omega x (omega x r_i) )

with ``b`` offsets (counts), ``s`` sensitivity vectors (counts per m/s^2), ``r``
positions (m), ``m`` the centripetal multiplier (1 = physics), ``tau`` per-channel
time skews (s), ``bias`` a time-varying extra offset (counts) and ``gain`` a
time-varying gain factor (1 = none).  :func:`evaluate` computes it from a truth
(``t, f, omega, alpha`` in body axes, a trajectory or a recording's reference
columns); :func:`true_state` builds the state of a calibration or of the device's
nominal values.  The simulator and the diagnosis both predict readings through
this module; the effects change the state or the readings (``accelcal.effects``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace as _dc_replace
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import lfilter
from scipy.spatial.transform import Rotation

from .errors import AccelcalError
from .model import centripetal_matrix, omega_products

__all__ = ["ChannelState", "Context", "make_context", "evaluate", "true_state", "interp_truth",
           "lowpass_first_order", "lowpass_butterworth2", "BUTTER2_MODE", "rotation_matrix",
           "calibration_arrays"]


def rotation_matrix(rotvec: Any) -> np.ndarray:
    """Rotation matrices (..., 3, 3) from rotation vectors (..., 3) (rad), by
    ``scipy.spatial.transform.Rotation``."""
    v = np.asarray(rotvec, dtype=float)
    flat = v.reshape(-1, 3)
    return Rotation.from_rotvec(flat).as_matrix().reshape(v.shape[:-1] + (3, 3))


@dataclass(frozen=True, eq=False)
class ChannelState:
    """Everything the sensor equation needs per channel (see the module doc).

    offsets (N,) counts; sensitivity (N, 3) counts per m/s^2; positions (N, 3) m;
    centripetal (N,) multiplier of the omega x (omega x r) term (1 = physics,
    0 = a model that leaves it out); tau (N,) s, channel i sampled at t + tau_i;
    bias (n, N) counts or None, a time-varying offset added to ``offsets``;
    gain (n, N) or None, a time-varying factor on the sensed part.
    """

    offsets: np.ndarray
    sensitivity: np.ndarray
    positions: np.ndarray
    centripetal: np.ndarray
    tau: np.ndarray
    bias: np.ndarray | None = None
    gain: np.ndarray | None = None

    @property
    def n_channels(self) -> int:
        return int(self.offsets.shape[0])

    def replace(self, **kw: Any) -> "ChannelState":
        return _dc_replace(self, **kw)

    def total_offset(self) -> np.ndarray:
        """b_i + bias_i(t): (n, N) if a bias is set, else (N,)."""
        return self.offsets if self.bias is None else self.offsets + self.bias

    @classmethod
    def from_parameters(cls, offsets: Any, sensitivity: Any, positions: Any, centripetal: Any = 1.0) -> "ChannelState":
        b = np.array(offsets, dtype=float).reshape(-1)
        n = b.shape[0]
        s = np.array(sensitivity, dtype=float).reshape(n, 3)
        r = np.array(positions, dtype=float).reshape(n, 3)
        m = np.broadcast_to(np.asarray(centripetal, dtype=float), (n,)).copy()
        return cls(offsets=b, sensitivity=s, positions=r, centripetal=m, tau=np.zeros(n))


@dataclass(frozen=True, eq=False)
class Context:
    """The truth, the device, the channel state and the current noise-free
    readings ``counts`` (n, N) float.  ``truth`` needs ``t, f, omega, alpha,
    temp_c, pose`` (and ``sample(times)`` for exact time shifts; otherwise the
    arrays are interpolated).  Build one with :func:`make_context`."""

    device: Any
    truth: Any
    state: ChannelState
    counts: np.ndarray

    def replace(self, **kw: Any) -> "Context":
        return _dc_replace(self, **kw)

    @property
    def n_samples(self) -> int:
        return int(np.asarray(self.truth.t).shape[0])

    @property
    def n_channels(self) -> int:
        return self.state.n_channels

    def g_counts(self) -> np.ndarray:
        """(N,) one g in counts for each channel, from the state's |s_i|."""
        return self.device.gravity_mps2 * np.linalg.norm(self.state.sensitivity, axis=1)


def make_context(device: Any, truth: Any, offsets: Any = None, sensitivity: Any = None,
                 positions: Any = None, centripetal: Any = 1.0) -> Context:
    """Context with the given channel parameters (device nominal ones where None)
    and ``counts`` evaluated from ``truth``.  ``centripetal`` 1 means the model
    has the omega x (omega x r) term, 0 that it leaves it out."""
    state = ChannelState.from_parameters(
        device.nominal_offsets() if offsets is None else offsets,
        device.nominal_sensitivity() if sensitivity is None else sensitivity,
        device.positions if positions is None else positions,
        centripetal,
    )
    return Context(device=device, truth=truth, state=state, counts=evaluate(truth, state))


def interp_truth(truth: Any, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """f, omega, alpha at ``times`` by cubic-spline (or, with gaps, linear) interpolation."""
    t = np.asarray(truth.t, float)
    out = []
    for name in ("f", "omega", "alpha"):
        arr = np.asarray(getattr(truth, name), float)
        if np.all(np.isfinite(arr)) and t.size >= 4:
            out.append(CubicSpline(t, arr, axis=0, extrapolate=True)(np.clip(times, t[0], t[-1])))
        else:
            out.append(np.column_stack([np.interp(times, t, arr[:, k]) for k in range(3)]))
    return out[0], out[1], out[2]


def _sample_truth(truth: Any, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    sample = getattr(truth, "sample", None)
    if callable(sample):
        return sample(times)
    return interp_truth(truth, times)


def _sensed(f: np.ndarray, alpha: np.ndarray | None, omega: np.ndarray | None,
            s: np.ndarray, r: np.ndarray, m: np.ndarray) -> np.ndarray:
    out = f @ s.T
    if alpha is not None:
        out += alpha @ np.cross(r, s).T  # s . (alpha x r) = alpha . (r x s)
    if omega is not None and np.any(m != 0):
        out += omega_products(omega) @ (centripetal_matrix(r, s) * m[:, None]).T
    return out


def evaluate(truth: Any, state: ChannelState, f: np.ndarray | None = None) -> np.ndarray:
    """Noise-free, unrounded readings (n, N) of ``state`` driven by ``truth``
    (the module doc's equation).  ``f`` (n, 3) replaces the truth's specific
    force (for a channel with a time skew, the replacement's difference to the
    truth is added to the shifted truth)."""
    t = np.asarray(truth.t, float)
    f_truth = np.asarray(truth.f, float)
    f_use = f_truth if f is None else np.asarray(f, float)
    alpha = None if truth.alpha is None else np.asarray(truth.alpha, float)
    omega = None if truth.omega is None else np.asarray(truth.omega, float)
    s, r, m, tau = state.sensitivity, state.positions, state.centripetal, state.tau
    n, N = t.shape[0], state.n_channels
    if not np.any(tau):
        sensed = _sensed(f_use, alpha, omega, s, r, m)
    else:
        sensed = np.empty((n, N))
        for u in np.unique(tau):
            idx = np.flatnonzero(tau == u)
            if u == 0:
                fs, ws, as_ = f_use, omega, alpha
            else:
                fs, ws, as_ = _sample_truth(truth, t + u)
                if f is not None:
                    fs = fs + (f_use - f_truth)
            sensed[:, idx] = _sensed(fs, as_, ws, s[idx], r[idx], m[idx])
    if state.gain is not None:
        sensed = sensed * state.gain
    return sensed + state.total_offset()


def lowpass_first_order(t: np.ndarray, x: np.ndarray, fc_hz: Any, pole: complex = 1.0) -> np.ndarray:
    """First-order low-pass y' = 2 pi fc (x - y), sampled at ``t``.

    Parameters
    ----------
    t : ndarray, shape (n,)
        Sample times (s), strictly increasing, any spacing.
    x : ndarray, shape (n, N)
        Input per channel.
    fc_hz : array_like, shape (N,) or scalar
        Cut-off (Hz); inf or <= 0 passes the channel through.

    Returns
    -------
    ndarray, shape (n, N)
        Exact for an input linear between samples (first-order hold):
        y_k = a y_{k-1} + (beta - a) x_{k-1} + (1 - beta) x_k with a = exp(-w h),
        beta = (1 - a) / (w h); steady state at the first sample (y_0 = x_0).
        Uniform spacing (every step within 1e-9 of the mean) runs through
        ``scipy.signal.lfilter``; other spacings use the same recursion in closed
        form, blockwise (cumulative sums scaled by exp(w t)).
    pole : complex, optional
        The rate is w = 2 pi fc pole (Re pole > 0; default 1): a complex pole gives one
        complex mode of a higher-order filter (:func:`lowpass_butterworth2`), and the result
        is then complex.
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    fc = np.broadcast_to(np.asarray(fc_hz, float), (x.shape[1],))
    y = x.astype(np.result_type(x, pole))
    if x.shape[0] < 2:
        return y
    active = np.isfinite(fc) & (fc > 0)
    steps = np.diff(t)
    h = float(np.mean(steps))
    uniform = bool(np.all(np.abs(steps - h) <= 1e-9 * h))
    for f_c in np.unique(fc[active]):
        idx = np.flatnonzero(fc == f_c)
        w = 2.0 * math.pi * float(f_c) * pole
        y[:, idx] = _lowpass_uniform(x[:, idx], w, h) if uniform else _lowpass_any(t, x[:, idx], w)
    return y


#: a second-order Butterworth low-pass of angular cut-off w is 2 Re(c z), z the first-order
#: low-pass of complex rate w BUTTER2_MODE[0] (its pole), c = BUTTER2_MODE[1]: the partial
#: fraction w^2 / (s^2 + sqrt(2) w s + w^2) = 2 Re(c q / (s + q)), q = w (1 - j) / sqrt(2)
BUTTER2_MODE = ((1.0 - 1.0j) / math.sqrt(2.0), (1.0 - 1.0j) / 2.0)


def lowpass_butterworth2(t: np.ndarray, x: np.ndarray, fc_hz: Any) -> np.ndarray:
    """Second-order Butterworth low-pass y'' + sqrt(2) w y' + w^2 y = w^2 x, w = 2 pi fc,
    sampled at ``t`` (the analog filter of a MEMS chip's or an anti-alias stage's response; a
    pure delay of sqrt(2) / w to second order in the frequency).

    Parameters and conventions as :func:`lowpass_first_order`: exact for an input linear
    between samples, steady state at the first sample, any spacing.  Computed as the real part
    of one complex first-order mode (:data:`BUTTER2_MODE`; a channel with fc = inf comes back
    as it is, 2 Re(c) = 1).
    """
    q, c = BUTTER2_MODE
    return 2.0 * np.real(c * lowpass_first_order(t, x, fc_hz, pole=q))


def _lowpass_uniform(x: np.ndarray, w: complex, h: float) -> np.ndarray:
    a = np.exp(-w * h)
    beta = -np.expm1(-w * h) / (w * h)
    b0, b1 = 1.0 - beta, beta - a
    y = np.empty(x.shape, np.result_type(x, a))
    y[0] = x[0]
    if x.shape[0] > 1:
        zi = (b1 * x[0] + a * y[0])[None, :]
        y[1:] = lfilter([b0, b1], [1.0, -a], x[1:], axis=0, zi=zi)[0]
    return y


_BLOCK_PHASE = 400.0  # exp(400) ~ 5e173: the closed form stays far from overflow


def _lowpass_any(t: np.ndarray, x: np.ndarray, w: complex) -> np.ndarray:
    h = np.diff(t)
    xh = w * h
    a = np.exp(-xh)
    beta = -np.expm1(-xh) / xh
    x = x.astype(np.result_type(x, a))
    c = np.empty_like(x)
    c[0] = 0.0
    c[1:] = (beta - a)[:, None] * x[:-1] + (1.0 - beta)[:, None] * x[1:]
    phase = w * (t - t[0])
    y = np.empty_like(x)
    y_prev = x[0].copy()  # state before sample 0's update: steady state
    start, n = 0, x.shape[0]
    while start < n:
        # block [start, stop): phase span below _BLOCK_PHASE
        stop = int(np.searchsorted(phase.real, phase[start].real + _BLOCK_PHASE, side="right"))
        stop = max(stop, start + 1)
        ph = phase[start:stop] - phase[start]
        e = np.exp(ph)[:, None]
        cc = c[start:stop].copy()
        if start == 0:
            cc[0] = x[0]  # y_0 = x_0
            z = np.cumsum(cc * e, axis=0)
        else:
            a0 = a[start - 1]
            cc[0] = a0 * y_prev + cc[0]  # y_start, computed directly
            z = np.cumsum(cc * e, axis=0)
        y[start:stop] = z / e
        y_prev = y[stop - 1]
        start = stop
    return y


def calibration_arrays(device: Any, cal: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    offsets = np.asarray(cal.offsets, float).reshape(-1)
    if offsets.shape[0] != device.n_channels:
        raise AccelcalError(
            f"the calibration has {offsets.shape[0]} channels but device {device.name!r} has {device.n_channels}"
        )
    sens = np.asarray(cal.sensitivity, float).reshape(-1, 3)
    pos = getattr(cal, "positions", None)
    if pos is None:
        pos = np.array(device.positions, float)
    else:
        pos = np.asarray(pos, float)
        known = np.all(np.isfinite(pos), axis=1)
        pos = np.where(known[:, None], pos, device.positions)
    if not (np.all(np.isfinite(offsets)) and np.all(np.isfinite(sens))):
        raise AccelcalError("the calibration has non-finite offsets or sensitivities")
    return offsets, sens, pos


def true_state(device: Any, calibration: Any = None, temp_c: np.ndarray | None = None) -> ChannelState:
    """The true channel state: ``calibration`` (anything with ``offsets``,
    ``sensitivity`` and optionally ``positions``) or the device's nominal
    values; centripetal multiplier 1.  With ``temp_c`` (n,) and a calibration
    that has temperature coefficients (``offset_tc``, ``gain_tc``,
    ``temp_ref_c``), the time-varying bias and gain they imply are included."""
    if calibration is None:
        b, s, r = device.nominal_offsets(), device.nominal_sensitivity(), np.array(device.positions, float)
    else:
        b, s, r = calibration_arrays(device, calibration)
    state = ChannelState.from_parameters(b, s, r, 1.0)
    if calibration is None or temp_c is None:
        return state
    ref = getattr(calibration, "temp_ref_c", None)
    otc = getattr(calibration, "offset_tc", None)
    gtc = getattr(calibration, "gain_tc", None)
    if ref is None or (otc is None and gtc is None):
        return state
    dT = (np.asarray(temp_c, float) - float(ref))[:, None]
    if otc is not None:
        state = state.replace(bias=dT * np.nan_to_num(np.asarray(otc, float))[None, :])
    if gtc is not None:
        state = state.replace(gain=1.0 + dT * np.nan_to_num(np.asarray(gtc, float))[None, :])
    return state
