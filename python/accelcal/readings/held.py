"""Held readings: a logger that reads the sensor faster than the sensor updates writes each
reading several times in a row (a serial monitor at 400 lines/s of a 100 Hz sensor: every
row four times).  Its rows are then not independent samples, and every figure that counts
them -- a pose mean's uncertainty, a calibration's chi2, a diagnosis's held-out chi2 --
would take each reading as several.

:func:`held_runs` tells such a recording from one whose rows repeat by chance (a sensor
quieter than a code in all channels at rest): held rows come in runs of one length, the
ratio of the two rates, or, where the sensor's rate is no whole fraction of the logger's
(an LSM303 polled at 10 Hz: runs of 4-10 rows), of a few lengths none of which is 1; chance
repeats come in runs whose most common length is 1 (a geometric law: runs of one row are
1/mean of them, over 1/HELD_MAX for runs short enough to be held).  :func:`distinct_rows`
keeps the first row of each run, so that the statistical
commands (calibrate, diagnose) count each reading once.  The per-sample commands (resolve,
attitude, displacement, rate) keep every row: their output is one line per input row.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..io.recording import Recording
from ..io.recording_checks import RATE_TOL, rate_for
from .noise_stream import add_counts

__all__ = ["RunCounts", "order_stat",
           "HELD_MODAL_SHARE", "HELD_MAX", "HELD_MIN_RUNS", "HELD_SINGLE_SHARE", "HELD_MIN_RUNS_UNEVEN",
           "HELD_CHANGED_SHARE", "held_runs", "held_factor", "held_share", "held_text", "readings_rate", "distinct_rows",
           "distinct_recordings"]

HELD_MODAL_SHARE = 0.8     # rows are held when at least this share of the runs of identical rows
                           # share one length >= 2 ...
HELD_MAX = 16              # ... of at most this many rows (a pose on one code of every channel is a
                           # run as long as the pose) ...
HELD_MIN_RUNS = 50         # ... over at least this many runs
HELD_SINGLE_SHARE = 0.05   # or, runs of uneven lengths: at most this share of single rows, ...
HELD_MIN_RUNS_UNEVEN = 20  # ... over at least this many runs, 90 % of them at most HELD_MAX rows long,
HELD_CHANGED_SHARE = 0.5   # ... and at least this share of the channels changing where a run ends


def held_runs(raw: np.ndarray) -> tuple[int, np.ndarray]:
    """(k, first): how many rows each reading is held for, and the first row of each run of
    identical rows.

    k is the most common length of the runs when it is 2..HELD_MAX and at least
    HELD_MODAL_SHARE of at least HELD_MIN_RUNS runs have it; else, for runs of uneven
    lengths (a sensor rate that is no whole fraction of the logger's), their mean length
    rounded when at most HELD_SINGLE_SHARE of at least HELD_MIN_RUNS_UNEVEN runs are single
    rows and 90 % of them at most HELD_MAX rows long; else 1 (rows not held: chance repeats of
    a sensor quieter than a code are runs of a geometric law, single rows the most common; a
    coarsely quantised jig that holds every channel on one code through its poses makes runs
    as long as the poses)."""
    raw = np.asarray(raw)
    new = np.ones(raw.shape[0], bool)
    new[1:] = np.any(raw[1:] != raw[:-1], axis=1)
    first = np.flatnonzero(new)
    lengths = np.diff(np.append(first, raw.shape[0]))
    if lengths.size == 0:
        return 1, first
    counts = np.bincount(lengths)
    k = int(np.argmax(counts))
    if 2 <= k <= HELD_MAX and lengths.size >= HELD_MIN_RUNS and counts[k] >= HELD_MODAL_SHARE * lengths.size:
        return k, first
    inner = lengths[1:-1]                   # the first and last runs may be cut by the recording's ends
    if (inner.size >= HELD_MIN_RUNS_UNEVEN and np.mean(inner == 1) <= HELD_SINGLE_SHARE
            and np.percentile(inner, 90) <= HELD_MAX):
        # a new reading changes most channels at once (noise on each); a slow ramp of one
        # channel under a code, the others still, changes one
        changed = np.mean(raw[first[1:]] != raw[first[1:] - 1])
        if changed >= HELD_CHANGED_SHARE:
            return max(2, int(round(float(np.mean(inner))))), first
    return 1, first


def inner_runs(first: np.ndarray, n: int) -> np.ndarray:
    """The lengths of the runs of identical rows starting at ``first`` over ``n`` rows, less the
    first and the last (the recording's ends may cut them)."""
    return np.diff(np.append(first, n))[1:-1]


def uneven(k: int, inner: np.ndarray) -> bool:
    """Whether held runs (``inner``: :func:`inner_runs`) are of uneven lengths: fewer than
    HELD_MODAL_SHARE of them ``k`` rows long."""
    return bool(inner.size) and float(np.mean(inner == k)) < HELD_MODAL_SHARE


def held_share(first: np.ndarray, n: int) -> float:
    """The share of the rows that repeat the row before in every reading (:func:`held_runs`'s
    ``first`` over ``n`` rows: each run's rows after its first), of the ``n - 1`` that could; 0
    for one row."""
    return (n - first.size) / (n - 1) if n > 1 else 0.0


def held_text(k: int, first: np.ndarray, n: int) -> str:
    """How long readings are held, for notes: "4 rows", or "4-10 rows (8 on average)" for runs
    of uneven lengths (:func:`held_runs`'s k and first over ``n`` rows)."""
    inner = inner_runs(first, n)
    lo, hi = (int(inner.min()), int(inner.max())) if inner.size else (k, k)
    if lo == hi or not uneven(k, inner):
        return f"{k} rows"
    return f"{lo}-{hi} rows ({float(np.mean(inner)):.1f} on average)"


def readings_rate(rec: Recording, first: np.ndarray) -> float | None:
    """The rate of the distinct readings that start at rows ``first``, Hz: how many follow the
    first over the recording's span (None for a span of 0)."""
    span = float(rec.t[-1] - rec.t[0]) if rec.n_samples > 1 else 0.0
    return (first.size - 1) / span if span > 0 else None


def held_factor(raw: np.ndarray) -> int:
    """How many rows each reading is held for (:func:`held_runs`; 1: not held)."""
    return held_runs(raw)[0]


def _distinct(rec: Recording) -> tuple[Recording, float, str | None]:
    k, first = held_runs(rec.raw)
    if k == 1:
        return rec, 1, None
    inner = inner_runs(first, rec.n_samples)
    text = held_text(k, first, rec.n_samples)
    if uneven(k, inner):
        k = float(np.mean(inner))            # runs of uneven lengths: the rows per reading on average
    hz = readings_rate(rec, first)
    rate = f", about {hz:.4g} Hz" if hz is not None else ""
    note = (f"{rec.source}: each reading is held for {text} (the logger read the sensor faster than it "
            f"updates): the {first.size} distinct readings of the {rec.n_samples} rows are used{rate}")
    return rec.select(first), k, note


def distinct_rows(rec: Recording) -> tuple[Recording, str | None]:
    """``rec`` with only the first row of each run of identical rows when its readings are
    held (:func:`held_runs`), and a note saying so; else ``rec`` itself and None."""
    out, _, note = _distinct(rec)
    return out, note


def distinct_recordings(recordings: list[Recording], device) -> tuple[list[Recording], object, list[str]]:
    """:func:`distinct_rows` of each recording, and the device with the rate its distinct
    readings come at when every recording holds its readings for the same k rows (the
    device's windows and grids in samples then span the times they mean): its own rate when
    that is the rows' rate (from t) / k within RATE_TOL -- the device file states the
    sensor's rate --, else ``sample_rate_hz`` / k.  Rows not held: the device with the rate
    their time stamps give where its own is off (:func:`~accelcal.io.recording_checks.rate_for`).
    Returns (recordings, device, notes)."""
    done = [_distinct(r) for r in recordings]
    out = [r for r, _, _ in done]
    notes = [note for _, _, note in done if note]
    factors = {k for _, k, _ in done}
    if factors == {1}:
        device, note = rate_for(out, device)
        return out, device, notes + ([note] if note else [])
    if len(factors) == 1 and min(factors) > 1:
        k = min(factors)
        rows_hz = _rows_rate(recordings)
        if rows_hz is not None and abs(device.sample_rate_hz * k / rows_hz - 1.0) <= RATE_TOL:
            # the device file states the sensor's own rate (the rows come k times as fast): it stands
            notes.append(f"the device's {device.sample_rate_hz:g} Hz is the rate of the distinct readings (the rows "
                         f"come at {rows_hz:.4g} Hz)")
        else:
            device = dataclasses.replace(device, sample_rate_hz=device.sample_rate_hz / k)
            notes.append(f"the device's {device.sample_rate_hz * k:.6g} Hz is taken as {device.sample_rate_hz:.6g} "
                         "Hz, the rate of the distinct readings")
    return out, device, notes


def _rows_rate(recordings: list[Recording]) -> float | None:
    """The rows' rate, Hz, from the median step of t over the recordings (None without steps)."""
    steps = np.concatenate([np.diff(np.asarray(r.t, float)) for r in recordings]) if recordings else np.zeros(0)
    steps = steps[steps > 0]
    return 1.0 / float(np.median(steps)) if steps.size else None


@dataclass
class RunCounts:
    """Runs of identical rows, as :func:`accelcal.readings.held.held_runs` counts them."""

    hist: dict = field(default_factory=dict)     # run length -> runs
    first_len: int | None = None                 # the first run's length, once it has ended
    open_len: int = 0                            # the run still going on
    changed: int = 0                             # channels changed where a run ends (summed)
    last: Any = None                             # the last row seen

    def add(self, raw: np.ndarray) -> None:
        if raw.shape[0] == 0:
            return
        new = np.ones(raw.shape[0], bool)
        new[1:] = np.any(raw[1:] != raw[:-1], axis=1)
        if self.last is not None:
            new[0] = bool(np.any(raw[0] != self.last))
            self.changed += int(np.count_nonzero(raw[0] != self.last))
        self.changed += int(np.count_nonzero(raw[1:][new[1:]] != raw[:-1][new[1:]]))
        starts = np.flatnonzero(new)
        if starts.size == 0:
            self.open_len += raw.shape[0]
        else:
            if self.last is not None and starts[0] == 0:
                self._close(self.open_len)
            elif self.last is not None:
                self._close(self.open_len + int(starts[0]))
            lengths = np.diff(starts)
            if lengths.size:
                if self.first_len is None:
                    self.first_len = int(lengths[0])
                add_counts(self.hist, lengths)
            self.open_len = raw.shape[0] - int(starts[-1])
        self.last = raw[-1].copy()

    def _close(self, length: int) -> None:
        if self.first_len is None:
            self.first_len = length
        self.hist[length] = self.hist.get(length, 0) + 1

    def held(self, n_channels: int) -> int | None:
        """held_runs' k, or None where only the samples tell (the 90th percentile at HELD_MAX)."""
        hist = dict(self.hist)
        hist[self.open_len] = hist.get(self.open_len, 0) + 1
        runs = sum(hist.values())
        top = max(hist.values())
        k = min(length for length, c in hist.items() if c == top)      # np.argmax of the bincount: the first
        if 2 <= k <= HELD_MAX and runs >= HELD_MIN_RUNS and top >= HELD_MODAL_SHARE * runs:
            return k
        if runs < 3:
            return 1
        inner = dict(hist)
        for length in (self.first_len, self.open_len):
            inner[length] -= 1
        m = sum(inner.values())
        if not (m >= HELD_MIN_RUNS_UNEVEN and inner.get(1, 0) / m <= HELD_SINGLE_SHARE):
            return 1
        idx = 0.9 * (m - 1)
        lo, hi = order_stat(inner, math.floor(idx)), order_stat(inner, math.ceil(idx))
        if lo > HELD_MAX:
            return 1
        if hi > HELD_MAX:
            return None
        boundaries = runs - 1
        if self.changed / (boundaries * n_channels) >= HELD_CHANGED_SHARE:
            return None                                                   # held: the whole-file command warns
        return 1


def order_stat(hist: dict, i: int) -> int:
    """The i-th smallest (0-based) of values counted in ``hist`` (value -> count)."""
    seen = 0
    for length in sorted(hist):
        seen += hist[length]
        if seen > i:
            return length
    raise IndexError(i)  # pragma: no cover
