"""What every estimator shares: the result object, the fixed-point input conventions
(Q formats from the compiled core through ``native.FORMATS``), the sample interval of
a recording, and the resolved f / alpha of a 6-DOF array."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import model
from ..firmware import native
from ..errors import AccelcalError, InputError
from ..firmware.native import FORMATS
from ..firmware.quantize import omega_to_fixed, quantize_calibration, round_half_up
from ..readings.noise import noise_for
from ..io.recording import check_core_input
from ..readings.static import STATIC_WINDOW_S, window_len

__all__ = ["Columns", "OUT_FRAC", "OMEGA_FRAC", "CLIP", "CLIP_LO", "dt_fixed", "clip_i16", "q_out",
           "time_span", "uniform_dt", "alpha_noise", "channel_noise", "force_noise", "force_noise_axes",
           "resolve_array"]

OUT_FRAC = FORMATS.out_frac        # AC_OUT_FRAC: f (m/s^2), alpha (rad/s^2)
OMEGA_FRAC = FORMATS.omega_frac    # AC_OMEGA_FRAC: omega (rad/s)
I16_MIN, I16_MAX = -32768, 32767
# the core clips f to int16 Q.AC_OUT_FRAC for its tests and sums: +-32 m/s^2
CLIP = I16_MAX / 2.0**OUT_FRAC
CLIP_LO = I16_MIN / 2.0**OUT_FRAC


class Columns(dict):
    """Output columns (name -> (n,) float array) in CSV order, with ``warnings``
    (one-line strings for the user: flagged, not fatal) and ``meta`` (comments)."""

    def __init__(self, *args: Any, warnings: list[str] | None = None, meta: dict | None = None, **kw: Any):
        super().__init__(*args, **kw)
        self.warnings: list[str] = list(warnings or [])
        self.meta: dict = dict(meta or {})


def dt_fixed(dt: float) -> tuple[int, int]:
    """The sample interval in the ac_rate convention.

    Parameters
    ----------
    dt : float
        Sample interval, s.

    Returns
    -------
    dt_m, dt_shift : int
        dt = dt_m 2^-dt_shift with dt_m in [2^15, 2^16) and dt_shift in 16..46
        (1/60 s -> 34953, 21).

    Raises
    ------
    AccelcalError
        dt not a positive number, or outside about 15 us .. 0.5 s.
    """
    if not (math.isfinite(dt) and dt > 0):
        raise AccelcalError(f"sample interval {dt!r} s is not a positive number")
    sh = 15 - math.floor(math.log2(dt))
    m = int(round_half_up(dt * 2.0 ** sh))
    if m >= 65536:
        sh -= 1
        m = int(round_half_up(dt * 2.0 ** sh))
    if m < 32768:
        sh += 1
        m = int(round_half_up(dt * 2.0 ** sh))
    if not 16 <= sh <= 46:
        raise AccelcalError(f"sample interval {dt:.6g} s is outside the fixed-point integrators' range "
                            "(about 15 us .. 0.5 s)")
    return m, sh


def clip_i16(x) -> np.ndarray:
    """Integers clipped to int16 (as int64): what the core's tests and sums see of its inputs."""
    return np.clip(np.asarray(x, np.int64), I16_MIN, I16_MAX)


def q_out(x) -> np.ndarray:
    """m/s^2 (or rad/s^2) -> int32 Q.AC_OUT_FRAC, rounded half up, saturating (feeds the fixed engine)."""
    return np.clip(round_half_up(np.asarray(x, float) * 2.0**OUT_FRAC), -2**31, 2**31 - 1).astype(np.int32)


def time_span(t, a: int, b: int | None = None, rec=None) -> str:
    """How a message names the time of sample ``a`` (or of samples ``a``..``b``) so that a user
    can find it: 't = 12.345 s' (ms), counted from the first sample when the stamps do not start
    at 0 ('t = 12.345 s from the start': epoch stamps, 1.62038e+09 s to 6 digits, name no place),
    and its row(s) in the file when ``rec`` was read from one.

    Parameters
    ----------
    t : array_like (n,)
        Time, s.
    a, b : int
        Sample indices (b: the span's last, inclusive).
    rec : Recording, optional
        Whose ``line`` names the rows (only when it has the file's lines).

    Returns
    -------
    str
    """
    t = np.asarray(t, float)
    t0 = float(t[0]) if t.size else 0.0
    when = f"{t[a] - t0:.3f}" + ("" if b is None else f"-{t[b] - t0:.3f}")
    out = f"t = {when} s" + (" from the start" if t0 != 0.0 else "")
    if rec is not None and getattr(rec, "lines", None) is not None:
        out += f" (row {rec.line(a)})" if b is None else f" (rows {rec.line(a)}-{rec.line(b)})"
    return out


def uniform_dt(rec) -> float:
    """The sample interval (s) of a recording, the median step.

    Raises
    ------
    InputError
        Fewer than 2 samples, or a step more than 25 % off the median (naming its row):
        the integrators need a constant rate.
    """
    t = np.asarray(rec.t, float)
    if t.size < 2:
        raise InputError(rec.source, "the recording needs at least 2 samples")
    d = np.diff(t)
    dt = float(np.median(d))
    bad = np.flatnonzero(np.abs(d - dt) > 0.25 * dt)
    if bad.size:
        i = int(bad[0])
        raise InputError(rec.source, f"sample times are not uniform (step {d[i]:.6g} s against {dt:.6g} s): "
                         "the integrators need a constant rate", row=rec.line(i + 1), column="t")
    return dt


def channel_noise(device, rec) -> np.ndarray:
    """Noise std of each channel (counts): the device's ``noise_mps2`` when it states one,
    else estimated from the recording itself (:func:`accelcal.readings.noise.noise_for`)."""
    raw = np.asarray(rec.raw)
    return noise_for(device, raw, window_len(device, STATIC_WINDOW_S, raw.shape[0]))[0]


def alpha_noise(device, cal, noise_counts=None) -> float:
    """The largest per-axis standard deviation (rad/s^2) of the resolved alpha that the
    channels' noise alone gives (``noise_counts`` (N,), default the device's, through the
    resolve matrix)."""
    pos = cal.positions_or_nominal(device)
    M = model.resolve_matrix(pos, cal.sensitivity)
    k = device.noise_counts() if noise_counts is None else np.asarray(noise_counts, float)
    return float(np.max(np.sqrt(np.sum((M[3:] * k[None, :]) ** 2, axis=1))))


def force_noise_axes(device, cal, noise_counts, channels=None) -> np.ndarray:
    """The standard deviation (m/s^2) of each body axis of f that the channels' noise
    (``noise_counts`` (N,), counts) gives: through the resolve matrix for a 6-DOF array,
    through the inverse sensitivity of the triad at ``channels`` otherwise.  (3,), zeros for a
    calibration that does not invert (reported where it is used)."""
    k = np.asarray(noise_counts, float)
    with np.errstate(all="ignore"):
        try:
            if channels is None:
                M = model.resolve_matrix(cal.positions_or_nominal(device), cal.sensitivity)[:3]
            else:
                ch = list(channels)
                M = np.zeros((3, k.size))
                M[:, ch] = np.linalg.inv(np.asarray(cal.sensitivity, float)[ch])
        except (np.linalg.LinAlgError, ValueError):
            return np.zeros(3)
        out = np.sqrt(np.sum((M * k[None, :]) ** 2, axis=1))
    return out if np.all(np.isfinite(out)) else np.zeros(3)


def force_noise(device, cal, noise_counts, channels=None) -> float:
    """The largest per-axis standard deviation (m/s^2) of f that the channels' noise
    (``noise_counts`` (N,), counts) gives (:func:`force_noise_axes`)."""
    return float(np.max(force_noise_axes(device, cal, noise_counts, channels)))


def resolve_array(device, cal, rec, engine: str, omega=None, *, with_flags: bool = False) -> tuple:
    """f and alpha of a 6-DOF array at the body origin, without the centripetal term, or with
    that of ``omega`` ((n, 3) rad/s: the array's own, :class:`accelcal.estimators.omega.ArrayOmega`'s
    ``for_resolver()``).

    Returns
    -------
    f, alpha : ndarray (n, 3)
        engine "float": m/s^2 and rad/s^2 (float reference); engine "fixed": int32
        Q.AC_OUT_FRAC from the C core with the header's tables.
    saturated : ndarray (n,) bool
        With ``with_flags``: the core's arithmetic saturated (never for "float").
    """
    if engine == "float":
        f, a = model.resolve(cal.offsets, cal.sensitivity, cal.positions_or_nominal(device), rec.raw, omega)
        return (f, a, np.zeros(len(f), bool)) if with_flags else (f, a)
    if engine != "fixed":
        raise ValueError(f"unknown engine {engine!r}")
    check_core_input(rec, device.raw_min < 0)
    t = quantize_calibration(device, cal)
    out, flags = native.process_batch(t.resolver(), t.trim, rec.raw, None if omega is None else omega_to_fixed(omega))
    f, a = out[:, :3].astype(np.int32), out[:, 3:].astype(np.int32)
    # with_flags: the core's own saturation (its rail bit is the recording's, not the arithmetic's)
    return (f, a, (flags & ~np.uint8(native.lib.AC_FLAG_AT_RAIL)) != 0) if with_flags else (f, a)
