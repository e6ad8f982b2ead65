"""Checks of a recording against what a consumer needs: a device's channels and range
(:func:`check_for_device`), its time stamps in seconds (:func:`seconds`), the C core's input
types (:func:`check_core_input`), rows a logger wrote twice (:func:`repeated_rows`) and how many rows
repeat by chance (:func:`chance_repeats`)."""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from scipy.stats import poisson

from ..errors import InputError

__all__ = ["GAP_STEPS", "regular_step", "check_for_device", "check_raw_range", "check_core_input", "seconds", "even_steps", "rate_for", "TIME_UNITS", "TIME_UNIT_TOL",
           "RATE_TOL", "repeated_rows", "repeats_note", "CHANCE_REPEAT_P", "chance_repeats"]

#: time stamps in these units are read as such (a logger's millis() or micros()) ...
TIME_UNITS = ((1e3, "milliseconds"), (1e6, "microseconds"), (1e9, "nanoseconds"))
#: ... when t's median step is the unit times the device's sample period within this share
TIME_UNIT_TOL = 0.2
#: a device rate more than this share off the recordings' own (from t) gives way to theirs
RATE_TOL = 0.2


def seconds(rec: Any, device) -> str | None:
    """Time stamps in milliseconds, microseconds or nanoseconds read as such.

    The data contract's t is in seconds.  When the median step of ``rec.t`` is 10^3, 10^6 or
    10^9 times the device's sample period (``1 / sample_rate_hz``) within TIME_UNIT_TOL, t is
    divided by that factor in place and a note is added to ``rec.notes`` and returned; any
    other step leaves t alone (None).  A second call finds seconds and does nothing."""
    if rec.n_samples < 3:
        return None
    steps = np.diff(rec.t)
    step = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 0.0
    ratio = step * float(device.sample_rate_hz)
    for k, unit in TIME_UNITS:
        if abs(ratio / k - 1.0) <= TIME_UNIT_TOL:
            rec.t = rec.t / k
            note = (f"t read as {unit}: its median step {step:.6g} is {ratio:.4g} times the device's "
                    f"sample period ({1.0 / device.sample_rate_hz:.4g} s at {device.sample_rate_hz:g} Hz); "
                    "the data contract's t is in seconds")
            rec.notes.append(note)
            return note
    return None


#: a step longer than this x the median step is a pause or samples lost, not a sample period
#: (a host's jitter of up to 0.7 of a step makes steps of up to 1.7; a sample lost, ~2)
GAP_STEPS = 1.8


def regular_step(t: np.ndarray) -> tuple[float, int, float]:
    """The sample period t's steps give (s): the steps up to GAP_STEPS x the median step, over
    their time -- not the median step, which a clock that catches up now and then with a short
    step does not keep (a host stamping a 100 Hz sensor 10.24 ms apart, with a 5 ms step every
    ~20 samples: median 10.24 ms, period 10.00 ms; an x-IMU3 whose clock steps 10.079 ms with a
    correction now and then runs at 100.004 Hz).

    Returns
    -------
    step : float
        s (the median step where no step is positive).
    gaps : int
        Steps longer than GAP_STEPS x the median (pauses, samples lost).
    median : float
        The median step, s.
    """
    steps = np.diff(np.asarray(t, float))
    median = float(np.median(steps)) if steps.size else 0.0
    regular = steps[(steps > 0) & (steps <= GAP_STEPS * median)]
    gaps = int(np.sum(steps > GAP_STEPS * median)) if median > 0 else 0
    return (float(regular.sum()) / regular.size if regular.size else median), gaps, median


def even_steps(t: np.ndarray, share: float) -> bool:
    """Whether t's median step and its mean step (duration over samples) are both positive
    and agree within ``share``: no bursts of host stamps, no long pauses."""
    if t.size < 2:
        return False
    median = float(np.median(np.diff(t)))
    mean = float(t[-1] - t[0]) / (t.size - 1)
    return median > 0 and mean > 0 and abs(mean / median - 1.0) <= share


def rate_for(recordings: list, device) -> tuple[Any, str | None]:
    """The device with the rate the recordings' time stamps give, where that is not its own.

    Windows and grids in samples (static detection, the diagnosis's blocks) take the
    device's ``sample_rate_hz``; a recording decimated by its user (every 4th row of a
    100 Hz log) or a device file of another setting would have them span 4 x the time they
    mean.  When every recording's median step and mean step agree within RATE_TOL (no
    bursts of host stamps, no long pauses), and the recordings agree with each other, but
    the device's rate is more than RATE_TOL off theirs, a copy of the device with their rate
    is returned with a note; else the device itself and None.  Time stamps in ms, us or ns
    are first read as such (:func:`seconds`)."""
    rates = []
    for rec in recordings:
        if rec.n_samples >= 3 and np.all(np.diff(rec.t) > 0):
            seconds(rec, device)
        t = np.asarray(rec.t, float)
        if t.size < 3 or not even_steps(t, RATE_TOL):
            return device, None
        rates.append(1.0 / float(np.median(np.diff(t))))
    if not rates or max(rates) > (1.0 + RATE_TOL) * min(rates):
        return device, None
    rate = float(np.median(rates))
    if abs(device.sample_rate_hz / rate - 1.0) <= RATE_TOL:
        return device, None
    rate = float(f"{rate:.6g}")
    note = (f"the device's {device.sample_rate_hz:g} Hz is taken as {rate:g} Hz, the rate the recordings' time "
            "stamps give (a recording decimated, or a device file of another setting)")
    return dataclasses.replace(device, sample_rate_hz=rate), note


def check_for_device(rec: Any, device, *, min_samples: int = 1) -> None:
    """One check, for every command, that a recording can be used with a device:
    its raw channel count, at least ``min_samples`` samples, finite strictly
    increasing t (in milliseconds, microseconds or nanoseconds read as such: :func:`seconds`),
    and every raw reading inside the device's [raw_min, raw_max]
    (the device clips there, so a reading outside means the wrong device file
    or a damaged recording).  InputError names the file, row and column."""
    if rec.n_channels != device.n_channels:
        raise InputError(rec.source, f"the recording has {rec.n_channels} raw channels "
                         f"(raw_0..raw_{rec.n_channels - 1}) but device {device.name!r} has {device.n_channels}",
                         column=f"raw_{min(rec.n_channels, device.n_channels)}")
    if rec.n_samples < min_samples:
        raise InputError(rec.source, f"{rec.n_samples} sample(s), at least {min_samples} needed")
    bad = np.flatnonzero(~np.isfinite(rec.t))
    if bad.size:
        raise InputError(rec.source, "t is not finite", row=rec.line(int(bad[0])), column="t")
    bad = np.flatnonzero(~(np.diff(rec.t) > 0))
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(rec.source, f"t must be strictly increasing: t = {float(rec.t[i]):.6g} s follows "
                         f"t = {float(rec.t[i - 1]):.6g} s", row=rec.line(i), column="t")
    seconds(rec, device)
    check_raw_range(rec, device)


def check_raw_range(rec: Any, device) -> None:
    """:func:`check_for_device`'s range check alone: every raw reading inside the device's
    [raw_min, raw_max] (``rec``: anything with raw, source and line(i), such as a chunk)."""
    out = (rec.raw < device.raw_min) | (rec.raw > device.raw_max)
    if out.any():
        i, c = (int(v) for v in np.argwhere(out)[0])
        raise InputError(rec.source, f"raw reading {int(rec.raw[i, c])} is outside device {device.name!r}'s "
                         f"[raw_min, raw_max] = [{device.raw_min}, {device.raw_max}]",
                         row=rec.line(i), column=f"raw_{c}")


def check_core_input(rec: Any, signed: bool = False) -> None:
    """Refuse raw counts the C core cannot take: uint16 (0..65535), or int16
    (-32768..32767) for a chip with signed output (``signed``, the device's raw_min < 0).

    Raises
    ------
    InputError
        For the first reading outside the range (counts), naming its row and column;
        nothing is ever clipped.
    """
    lo, hi = (-32768, 32767) if signed else (0, 65535)
    bad = np.argwhere((rec.raw < lo) | (rec.raw > hi))
    if bad.size:
        r, c = (int(v) for v in bad[0])
        kind = "int16" if signed else "uint16"
        raise InputError(rec.source, f"raw reading {int(rec.raw[r, c])} does not fit the C core's {kind} input "
                         f"({lo}..{hi})", row=rec.line(r), column=f"raw_{c}")


def repeated_rows(columns) -> np.ndarray:
    """The rows that repeat the row before exactly, time stamp and every reading (a logger that
    writes a sample twice): (n,) bool, True on each copy (NaN taken as equal to NaN).

    Parameters
    ----------
    columns : iterable of ndarray (n,)
        The columns read (t among them), in any unit.
    """
    same = None
    for c in columns:
        c = np.asarray(c)
        eq = c[1:] == c[:-1]
        if c.dtype.kind == "f":
            eq |= np.isnan(c[1:]) & np.isnan(c[:-1])
        same = eq if same is None else same & eq
    return np.concatenate([[False], same]) if same is not None else np.zeros(0, bool)


def repeats_note(count: int, first_line: int) -> str:
    """The note of ``count`` rows left out as exact copies of the row before, the first on
    line ``first_line`` of the file."""
    return (f"{count} row(s) repeat the row before exactly, time stamp and readings (a sample written twice), "
            f"the first at row {first_line}: left out")


#: rows that repeat the row before are evidence of samples delivered twice only when at least as many
#: would come by chance with a probability below this
CHANCE_REPEAT_P = 1e-3


def chance_repeats(raw) -> tuple[int, float, float]:
    """How many rows repeat every reading of the row before, against chance.

    On a coarse grid, or from a quiet sensor, each channel repeats its reading from one row to
    the next now and then; rows alike on every channel then come by chance, at about the product
    of the channels' own repeat rates (a LIS2DW's 1.95 mg grid with 2.5 counts of noise: 0.103 x
    0.117 x 0.084 of the rows, 4.0 in 3,971).  Only a count far beyond that is evidence of a logger
    that delivers samples twice.

    Parameters
    ----------
    raw : array_like (n, m)
        The readings, counts.

    Returns
    -------
    count : int
        Rows alike with the row before on every channel.
    expected : float
        The count expected by chance: (n - 1) x the product over channels of the share of rows
        whose reading on that channel repeats the row before's.
    p : float
        The probability of at least ``count`` such rows by chance (Poisson with mean ``expected``);
        below CHANCE_REPEAT_P the repeats are not chance.
    """
    raw = np.asarray(raw)
    if raw.shape[0] < 2:
        return 0, 0.0, 1.0
    eq = raw[1:] == raw[:-1]
    count = int(np.count_nonzero(np.all(eq, axis=1)))
    expected = float(eq.shape[0] * np.prod(np.mean(eq, axis=0)))
    return count, expected, float(poisson.sf(count - 1, expected)) if count else 1.0
