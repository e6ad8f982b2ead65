"""The calibration's correctable terms, float64 reference: the truth the C core's
integer versions (include/accelcal/ac_terms.h) are held to, and what
``resolve --engine float`` applies.

Per sample n, before the resolve and in this order (docs/firmware-terms.md):

1. :func:`lag_temperature`: the temperature the offset and the gain tempcos act on, the
   recorded one T through a first-order lag (effects/temperature.py's ``tau_s``):
   ``T_s[n] = a T_s[n-1] + (1 - a) T[n]``, ``a = exp(-dt / tau)``, ``T_s[0] = T[0]``.
2. :func:`temperature_correct`: ``y = b + (raw - b - oc (T_off - t_ref)) / (1 + gc (T_gain - t_ref))``,
   the inverse of ``raw = b + oc dT + (1 + gc dT) s . f`` (calibrate's temperature model).
3. :func:`skew_correct`: channel i reads the motion at ``t + tau_i`` (effects/timing.py's
   ``time_skew``); with the delays ``j_i = m + tau_i / dt`` samples (``m`` = :func:`skew_latency`,
   the whole samples that make every j_i >= 0) each channel is interpolated linearly between
   its successive samples to the common instant ``t_n - m dt``:
   ``out_i[n] = y_i[n - k] + (j_i - k) (y_i[n - k - 1] - y_i[n - k])``, ``k = floor(j_i)``.
4. :func:`nonlinearity_invert`: the reading gained ``k2 a^2 + k3 a^3`` counts, a = (linear
   reading - b) / |s| in m/s^2 (effects/nonlinearity.py); with ``z = raw - b`` and
   ``c2 = k2 / |s|^2``, ``c3 = k3 / |s|^3`` the linear reading is found by
   K fixed-point iterations (:func:`nonlinearity_iterations`, from the contraction bound) ``z_{k+1} = z - c2 z_k^2 - c3 z_k^3``,
   ``z_0 = z``; each shrinks the error by L = max |2 c2 z + 3 c3 z^2| over the readings.

The order is the reverse of the simulator's only up to second-order terms (the gain tempco
times the nonlinearity, the interpolation of a curved reading): see docs/firmware-terms.md.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["NONLIN_ITERATIONS", "NONLIN_MAX_ITERATIONS", "NONLIN_TOLERANCE_COUNTS", "nonlinearity_iterations",
           "nonlinearity_span", "channel_values", "has_terms", "lag_coefficient", "lag_temperature", "temperature_correct",
           "skew_latency", "skew_delays", "skew_correct", "nonlinearity_coefficients", "nonlinearity_invert",
           "correct_readings"]

#: fixed-point iterations of the nonlinearity's inversion without a converter span to choose
#: them from, and the fewest chosen (AC_NONLIN_ITERATIONS)
NONLIN_ITERATIONS = 3
#: the most iterations chosen (AC_NONLIN_MAX_ITERATIONS)
NONLIN_MAX_ITERATIONS = 16
#: counts: what the float iteration may leave of the exact inverse at the span's ends
NONLIN_TOLERANCE_COUNTS = 0.25


def channel_values(arr, n: int) -> np.ndarray:
    """(n,) float: a calibration's optional per-channel array, 0 where absent (None or NaN)."""
    if arr is None:
        return np.zeros(n)
    return np.nan_to_num(np.asarray(arr, float), nan=0.0)


def has_terms(cal) -> dict:
    """Which correctable terms ``cal`` carries: {"temperature", "skew", "nonlinearity"} -> bool
    (a term whose coefficients are all absent or zero is not carried)."""
    n = cal.n_channels
    nz = lambda a: bool(np.any(channel_values(a, n) != 0))  # noqa: E731
    return {"temperature": nz(getattr(cal, "offset_tc", None)) or nz(getattr(cal, "gain_tc", None)),
            "skew": nz(getattr(cal, "time_skew_s", None)),
            "nonlinearity": nz(getattr(cal, "nonlin_k2", None)) or nz(getattr(cal, "nonlin_k3", None))}


def lag_coefficient(tau_s: float | None, dt_s: float) -> float:
    """The lag filter's weight of the new sample, 1 - exp(-dt / tau) (1: no lag, tau None or 0)."""
    if not tau_s:
        return 1.0
    return -math.expm1(-float(dt_s) / float(tau_s))


def lag_temperature(temp_c, tau_s: float | None, dt_s: float, state: float | None = None):
    """The lagged temperature T_s (degC) of the readings ``temp_c`` (n,) degC at the sample
    period ``dt_s`` (s) through a first-order lag of time constant ``tau_s`` (s; None or 0: T).

    Returns (T_s (n,), state): ``state`` the last T_s, to carry into the next call (None: the
    filter starts at the first reading, as effects.temperature.lagged does)."""
    T = np.asarray(temp_c, float)
    c = lag_coefficient(tau_s, dt_s)
    out = np.empty_like(T)
    y = float(T[0]) if state is None and T.size else state
    for n, x in enumerate(T):
        y = y + c * (float(x) - y)
        out[n] = y
    return out, (y if T.size else state)


def temperature_correct(raw, offsets, temp_ref_c, offset_tc, gain_tc, temp_offset_c, temp_gain_c) -> np.ndarray:
    """Readings (n, N) counts with the temperature's offset and gain removed:
    ``b + (raw - b - oc (T_off - t_ref)) / (1 + gc (T_gain - t_ref))``; ``temp_offset_c``,
    ``temp_gain_c`` (n,) the lagged temperatures (degC) the offset and the gain tempco act on
    (:func:`lag_temperature`); ``offset_tc`` counts/degC, ``gain_tc`` 1/degC (N,) or None."""
    raw = np.atleast_2d(np.asarray(raw, float))
    n = raw.shape[1]
    b = np.asarray(offsets, float)
    oc, gc = channel_values(offset_tc, n), channel_values(gain_tc, n)
    t_ref = float(temp_ref_c or 0.0)
    d_off = (np.asarray(temp_offset_c, float) - t_ref)[:, None]
    d_gain = (np.asarray(temp_gain_c, float) - t_ref)[:, None]
    return b + (raw - b - oc * d_off) / (1.0 + gc * d_gain)


def skew_latency(time_skew_s, dt_s: float) -> int:
    """m, the whole samples by which the common instant lags the newest sample: the least
    m >= 0 with m + tau_i / dt >= 0 for every channel (0 when no channel reads early)."""
    tau = np.asarray(time_skew_s, float)
    return int(max(0, math.ceil(-float(np.min(tau)) / float(dt_s) - 1e-12))) if tau.size else 0


def skew_delays(time_skew_s, dt_s: float) -> np.ndarray:
    """(N,) j_i = m + tau_i / dt, each channel's delay in samples (>= 0) to the common instant."""
    tau = np.nan_to_num(np.asarray(time_skew_s, float), nan=0.0)
    return np.maximum(skew_latency(tau, dt_s) + tau / float(dt_s), 0.0)


def skew_correct(x, delays, line: np.ndarray | None = None):
    """Each channel of ``x`` (n, N) delayed by ``delays`` (N,) samples (>= 0) by linear
    interpolation between its successive samples.

    Returns (out (n, N), line): ``line`` (L, N) the last L inputs (newest first; L = floor(max
    delay) + 2, or the length of the ``line`` given) to carry into the next call (None: the line
    starts filled with the first sample)."""
    x = np.atleast_2d(np.asarray(x, float))
    j = np.asarray(delays, float)
    k = np.floor(j).astype(int)
    frac = j - k
    L = int(k.max()) + 2 if k.size else 2
    if line is None:
        line = np.repeat(x[:1], L, axis=0)
    elif line.shape[0] < L:
        raise ValueError(f"skew_correct: a line of {line.shape[0]} samples for delays up to {float(j.max()):.3g}")
    L = line.shape[0]
    hist = np.concatenate([line[::-1], x], axis=0)  # oldest first; sample n of x at row L + n
    rows = np.arange(x.shape[0])[:, None] + L
    cols = np.arange(x.shape[1])[None, :]
    y0 = hist[rows - k, cols]
    y1 = hist[rows - k - 1, cols]
    out = y0 + frac * (y1 - y0)
    return out, hist[-L:][::-1].copy()


def nonlinearity_coefficients(sensitivity, k2, k3) -> tuple[np.ndarray, np.ndarray]:
    """(c2, c3) (N,): the square and cube terms per count, c2 = k2 / |s|^2 (1/counts),
    c3 = k3 / |s|^3 (1/counts^2), |s| the norm of the channel's sensitivity (counts per m/s^2)."""
    s = np.linalg.norm(np.atleast_2d(np.asarray(sensitivity, float)), axis=1)
    n = s.shape[0]
    return channel_values(k2, n) / s ** 2, channel_values(k3, n) / s ** 3


def nonlinearity_span(offsets, rails) -> float:
    """counts: the largest |raw - b| a converter with ``rails`` (raw_min, raw_max) codes can read
    about the offsets b (N,), at most 32767 (the C core's int16 reading)."""
    b = np.asarray(offsets, float)
    lo, hi = float(rails[0]), float(rails[1])
    return float(min(32767.0, np.max(np.maximum(np.abs(hi - b), np.abs(lo - b)))))


def nonlinearity_iterations(c2, c3, span: float | None) -> int:
    """The fixed-point iterations the inversion runs for coefficients c2 (1/counts), c3
    (1/counts^2) (N,) on readings |raw - b| <= ``span`` counts: the least K >= NONLIN_ITERATIONS
    with L^K e <= NONLIN_TOLERANCE_COUNTS, L = max(2 |c2| span + 3 |c3| span^2) the iteration's
    contraction bound and e = max(|c2| span^2 + |c3| span^3) the term it removes (the float
    iteration's distance to the exact inverse after K steps is at most L^K e), capped at
    NONLIN_MAX_ITERATIONS (the cap also where L >= 1: the iteration does not converge at the
    span's ends).  ``span`` None: NONLIN_ITERATIONS."""
    if span is None:
        return NONLIN_ITERATIONS
    c2, c3 = np.abs(np.asarray(c2, float)), np.abs(np.asarray(c3, float))
    z = float(span)
    L = float(np.max(2.0 * c2 * z + 3.0 * c3 * z * z, initial=0.0))
    e = float(np.max(c2 * z * z + c3 * z ** 3, initial=0.0))
    k = NONLIN_ITERATIONS
    while k < NONLIN_MAX_ITERATIONS and (L >= 1.0 or L ** k * e > NONLIN_TOLERANCE_COUNTS):
        k += 1
    return k


def nonlinearity_invert(raw, offsets, sensitivity, k2, k3, iterations: int = NONLIN_ITERATIONS) -> np.ndarray:
    """Readings (n, N) counts with ``k2 a^2 + k3 a^3`` removed by ``iterations`` fixed-point
    iterations (module notes); ``k2`` counts/(m/s^2)^2, ``k3`` counts/(m/s^2)^3 (N,) or None."""
    raw = np.atleast_2d(np.asarray(raw, float))
    b = np.asarray(offsets, float)
    c2, c3 = nonlinearity_coefficients(sensitivity, k2, k3)
    z = raw - b
    zk = z
    for _ in range(int(iterations)):
        zk = z - (c2 + c3 * zk) * zk * zk
    return b + zk


def correct_readings(cal, raw, temp_c=None, dt_s: float | None = None, rails=None) -> np.ndarray:
    """The float reference of the whole chain on a recording's readings (n, N) counts: the
    temperature (``temp_c`` (n,) degC, needed when ``cal`` has tempcos), the skew (``dt_s``
    the sample period, needed when ``cal`` has ``time_skew_s``) and the nonlinearity, in that
    order; ``rails`` (raw_min, raw_max) the converter's codes, from which the nonlinearity's
    iteration count is chosen as the header does (:func:`nonlinearity_iterations`; None: 3).  Row n of the result is the readings at t_n: the skew's latency m is taken out by
    running the stream m samples further on the last sample repeated."""
    raw = np.atleast_2d(np.asarray(raw, float))
    terms = has_terms(cal)
    y = raw
    if terms["temperature"]:
        if temp_c is None or not np.all(np.isfinite(temp_c)):
            raise ValueError("the calibration has temperature coefficients: temp_c is needed on every sample")
        t_off, _ = lag_temperature(temp_c, cal.temp_offset_tau_s, dt_s or 1.0)
        t_gain, _ = lag_temperature(temp_c, cal.temp_gain_tau_s, dt_s or 1.0)
        y = temperature_correct(y, cal.offsets, cal.temp_ref_c, cal.offset_tc, cal.gain_tc, t_off, t_gain)
    if terms["skew"]:
        if not dt_s:
            raise ValueError("the calibration has time skews: the sample period is needed")
        m = skew_latency(channel_values(cal.time_skew_s, cal.n_channels), dt_s)
        padded = np.concatenate([y, np.repeat(y[-1:], m, axis=0)], axis=0)
        y = skew_correct(padded, skew_delays(channel_values(cal.time_skew_s, cal.n_channels), dt_s))[0][m:]
    if terms["nonlinearity"]:
        c2, c3 = nonlinearity_coefficients(cal.sensitivity, cal.nonlin_k2, cal.nonlin_k3)
        k = nonlinearity_iterations(c2, c3, None if rails is None else nonlinearity_span(cal.offsets, rails))
        y = nonlinearity_invert(y, cal.offsets, cal.sensitivity, cal.nonlin_k2, cal.nonlin_k3, k)
    return y
