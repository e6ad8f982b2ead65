"""What every estimator shares: the result object, the fixed-point input conventions
(Q formats from the compiled core through ``native.FORMATS``), the sample interval of
a recording, and the resolved f / alpha of a 6-DOF array."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import model, native
from ..errors import AccelcalError, InputError
from ..native import FORMATS
from ..quantize import quantize_calibration, round_half_up
from ..noise import noise_for
from ..recording import Recording, check_core_input
from ..static import STATIC_WINDOW_S, window_len

__all__ = ["Columns", "OUT_FRAC", "OMEGA_FRAC", "CLIP", "CLIP_LO", "dt_fixed", "clip_i16", "q_out",
           "uniform_dt", "on_uniform_grid", "alpha_noise", "channel_noise", "force_noise", "resolve_array"]

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


#: dropped samples are filled (linear interpolation) up to this many in one gap ...
MAX_FILL_SAMPLES = 10
#: ... and this share of the recording; longer or more gaps are refused
MAX_FILL_SHARE = 0.05
#: time stamps may stray this far (in steps) from a uniform grid: jitter of the stamps, not the samples
#: (within a quarter step each, every step rounds to its whole number of steps)
MAX_JITTER_STEPS = 0.25
#: ... and below this they are not worth a word (nor a new grid)
JITTER_NOTE_STEPS = 0.05
#: a sample stamped late by up to this (steps), the next one on time, was delivered late: its place
#: is on the grid (a phone's log: 0.66 of a step late, the next 0.34 of a step after it)
MAX_LATE_STEPS = 0.75


def on_uniform_grid(rec) -> tuple[Any, np.ndarray, str | None]:
    """A recording whose time stamps jitter or whose logger dropped samples, on its
    uniform time grid.

    Each sample's place on the grid is counted in median steps from the one before (a step
    of k median steps, k >= 2, is k - 1 dropped samples; a step of 1 + a then one of 1 - a,
    a up to MAX_LATE_STEPS, is a sample stamped late, one step each); the grid's step is the least-squares
    fit of t on those places.  Every time stamp must lie within MAX_JITTER_STEPS of its place
    (jitter of the stamps, as a host or a coarse clock gives, not of the samples).  Dropped
    samples, up to MAX_FILL_SAMPLES in one gap and MAX_FILL_SHARE of the whole, are filled by
    linear interpolation of the counts (rounded to whole counts), so that the integrators run
    at their constant rate.

    Returns
    -------
    rec : Recording
        The recording itself when its stamps are uniform to JITTER_NOTE_STEPS and nothing
        was dropped, else a new one (t and raw only, t on the grid: the time base the
        integrators use).
    filled : ndarray of bool, shape (n,)
        True on the interpolated samples.
    note : str or None
        What was done, for the user.

    Raises
    ------
    InputError
        Time stamps that stray further from the grid (naming the first), or gaps beyond the
        limits (naming the row after the longest).
    """
    t = np.asarray(rec.t, float)
    if t.size < 2:
        raise InputError(rec.source, "the recording needs at least 2 samples")
    d = np.diff(t)
    dt = float(np.median(d))
    r = d / dt
    # whole steps, a step of exactly k + 1/2 taken as k (two stamps each a quarter step off)
    k = np.maximum(np.ceil(r - 0.5 - 1e-9), 1.0)
    # a sample stamped late (a host that stamps on delivery): a step of 1 + a, then one of 1 - a,
    # a up to MAX_LATE_STEPS -- one step each, the sample between them late by a
    pair = np.flatnonzero((r[:-1] > 1.0 + MAX_JITTER_STEPS) & (r[:-1] <= 1.0 + MAX_LATE_STEPS)
                          & (r[1:] < 1.0 - MAX_JITTER_STEPS) & (np.abs(r[:-1] + r[1:] - 2.0) <= 2 * MAX_JITTER_STEPS))
    late = np.zeros(t.size, bool)
    late[pair + 1] = True
    k[pair] = 1.0
    k[pair + 1] = 1.0
    off = np.abs(r - k) > 2.5 * MAX_JITTER_STEPS       # two stamps' jitter, and the median's own error
    off[pair] = off[pair + 1] = False
    odd = np.flatnonzero(off)
    if odd.size:
        i = int(odd[0]) + 1
        raise InputError(rec.source, f"sample times are not uniform: the step to t = {t[i]:.6g} s is {d[i - 1]:.6g} s, "
                         f"{d[i - 1] / dt:.3g} of the median step {dt:.6g} s (time stamps up to {MAX_JITTER_STEPS:g} of a "
                         "step off a uniform grid are taken as jitter): the integrators need a constant rate",
                         row=rec.line(i), column="t")
    at = np.concatenate([[0], np.cumsum(k).astype(np.int64)])     # each sample's place on the grid
    on = ~late
    slope, icpt = np.polyfit(at[on].astype(float), t[on], 1) if np.count_nonzero(on) > 2 else (dt, float(t[0]))
    resid = t - (icpt + slope * at)
    # the fitted grid is itself a little off the true one: a quarter of a step of room beside the jitter's
    room = np.where(late, MAX_LATE_STEPS + 0.25 * MAX_JITTER_STEPS, 1.25 * MAX_JITTER_STEPS) * slope
    stray = np.flatnonzero((resid > room) | (resid < -1.25 * MAX_JITTER_STEPS * slope))
    if stray.size:
        i = int(stray[0])
        raise InputError(rec.source, f"sample times are not uniform: t = {t[i]:.6g} s is {resid[i] / slope:+.2f} "
                         f"steps off a uniform grid of {slope:.6g} s (at most {MAX_JITTER_STEPS:g} is taken as jitter "
                         "of the time stamps): the integrators need a constant rate", row=rec.line(i), column="t")
    missing = k.astype(np.int64) - 1
    total = int(missing.sum())
    jitter = float(np.max(np.abs(resid[on]))) / slope
    if total == 0 and jitter <= JITTER_NOTE_STEPS and not late.any():
        return rec, np.zeros(t.size, bool), None
    notes = []
    if late.any():
        notes.append(f"{int(late.sum())} sample(s) stamped late by up to {float(np.max(resid[late])) / slope:.2f} of a "
                     "step (each followed by one stamped on time: a host that stamps on delivery) are taken at "
                     "their place on the grid")
    if jitter > JITTER_NOTE_STEPS:
        notes.append(f"the time stamps stray by up to {jitter:.2f} of a step from a uniform {1.0 / slope:.6g} Hz grid: "
                     "taken as jitter of the stamps, the samples as uniform (t is written on that grid)")
    if total:
        i = int(np.argmax(missing))
        if missing[i] > MAX_FILL_SAMPLES or total > MAX_FILL_SHARE * (t.size + total):
            raise InputError(rec.source, f"sample times are not uniform: {total} sample(s) missing in "
                             f"{int(np.count_nonzero(missing))} gap(s), "
                             f"the longest {int(missing[i])} ({d[i]:.6g} s against {dt:.6g} s): the integrators "
                             f"need a constant rate, and at most {MAX_FILL_SAMPLES} in one gap and "
                             f"{100 * MAX_FILL_SHARE:g} % of the recording are filled by interpolation",
                             row=rec.line(i + 1), column="t")
        notes.append(f"{total} dropped sample(s) in {int(np.count_nonzero(missing))} gap(s) (the longest "
                     f"{int(missing[i])}, after t = {t[i]:.6g} s) filled by linear interpolation of the counts; "
                     "column filled = 1 there")
    grid = icpt + slope * np.arange(at[-1] + 1)
    kept = np.zeros(grid.size, bool)
    kept[at] = True
    raw = np.asarray(rec.raw, float)
    full = np.rint(np.column_stack([np.interp(grid, grid[at], raw[:, j]) for j in range(raw.shape[1])]))
    full = full.astype(np.int64)
    full[kept] = np.asarray(rec.raw, np.int64)
    out = Recording(t=grid, raw=full, metadata=dict(rec.metadata), source=rec.source)
    return out, ~kept, "; ".join(notes)


def channel_noise(device, rec) -> np.ndarray:
    """Noise std of each channel (counts): the device's ``noise_mps2`` when it states one,
    else estimated from the recording itself (:func:`accelcal.noise.noise_for`)."""
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


def force_noise(device, cal, noise_counts, channels=None) -> float:
    """The largest per-axis standard deviation (m/s^2) of f that the channels' noise
    (``noise_counts`` (N,), counts) gives: through the resolve matrix for a 6-DOF array,
    through the inverse sensitivity of the triad at ``channels`` otherwise."""
    k = np.asarray(noise_counts, float)
    with np.errstate(all="ignore"):      # a degenerate calibration is reported where it is used
        try:
            if channels is None:
                M = model.resolve_matrix(cal.positions_or_nominal(device), cal.sensitivity)[:3]
            else:
                ch = list(channels)
                M = np.zeros((3, k.size))
                M[:, ch] = np.linalg.inv(np.asarray(cal.sensitivity, float)[ch])
        except (np.linalg.LinAlgError, ValueError):
            return 0.0
        out = float(np.max(np.sqrt(np.sum((M * k[None, :]) ** 2, axis=1))))
    return out if math.isfinite(out) else 0.0


def resolve_array(device, cal, rec, engine: str) -> tuple[np.ndarray, np.ndarray]:
    """f and alpha of a 6-DOF array at the body origin, without the centripetal term.

    Returns
    -------
    f, alpha : ndarray (n, 3)
        engine "float": m/s^2 and rad/s^2 (float reference); engine "fixed": int32
        Q.AC_OUT_FRAC from the C core with the header's tables.
    """
    if engine == "float":
        return model.resolve(cal.offsets, cal.sensitivity, cal.positions_or_nominal(device), rec.raw, None)
    if engine != "fixed":
        raise ValueError(f"unknown engine {engine!r}")
    check_core_input(rec, device.raw_min < 0)
    t = quantize_calibration(device, cal)
    out, _ = native.process_batch(t.resolver(), t.trim, rec.raw, None)
    return out[:, :3].astype(np.int32), out[:, 3:].astype(np.int32)
