"""Held readings: a logger that reads the sensor faster than the sensor updates writes each
reading several times in a row (a serial monitor at 400 lines/s of a 100 Hz sensor: every
row four times).  Its rows are then not independent samples, and every figure that counts
them -- a pose mean's uncertainty, a calibration's chi2, a diagnosis's held-out chi2 --
would take each reading as several.

:func:`held_runs` tells such a recording from one whose rows repeat by chance (a sensor
quieter than a code in all channels at rest): held rows come in runs of one length, the
ratio of the two rates; chance repeats in runs whose most common length is 1 (a geometric
law).  :func:`distinct_rows` keeps the first row of each run, so that the statistical
commands (calibrate, diagnose) count each reading once.  The per-sample commands (resolve,
attitude, displacement, rate) keep every row: their output is one line per input row.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .recording import Recording
from .recording_checks import RATE_TOL, rate_for

__all__ = ["HELD_MODAL_SHARE", "HELD_MAX", "HELD_MIN_RUNS", "held_runs", "held_factor", "distinct_rows",
           "distinct_recordings"]

HELD_MODAL_SHARE = 0.8     # rows are held when at least this share of the runs of identical rows
                           # share one length >= 2 ...
HELD_MAX = 16              # ... of at most this many rows (a pose on one code of every channel is a
                           # run as long as the pose) ...
HELD_MIN_RUNS = 50         # ... over at least this many runs


def held_runs(raw: np.ndarray) -> tuple[int, np.ndarray]:
    """(k, first): how many rows each reading is held for -- the most common length k of the
    runs of identical rows when it is 2..HELD_MAX and at least HELD_MODAL_SHARE of at least
    HELD_MIN_RUNS runs have it, else 1 (rows not held; a coarsely quantised jig that holds
    every channel on one code through poses of one length makes runs as long as its poses)
    -- and the first row of each run."""
    raw = np.asarray(raw)
    new = np.ones(raw.shape[0], bool)
    new[1:] = np.any(raw[1:] != raw[:-1], axis=1)
    first = np.flatnonzero(new)
    lengths = np.diff(np.append(first, raw.shape[0]))
    if lengths.size == 0:
        return 1, first
    counts = np.bincount(lengths)
    k = int(np.argmax(counts))
    held = 2 <= k <= HELD_MAX and lengths.size >= HELD_MIN_RUNS and counts[k] >= HELD_MODAL_SHARE * lengths.size
    return (k if held else 1), first


def held_factor(raw: np.ndarray) -> int:
    """How many rows each reading is held for (:func:`held_runs`; 1: not held)."""
    return held_runs(raw)[0]


def _distinct(rec: Recording) -> tuple[Recording, int, str | None]:
    k, first = held_runs(rec.raw)
    if k == 1:
        return rec, 1, None
    span = float(rec.t[-1] - rec.t[0]) if rec.n_samples > 1 else 0.0
    rate = f", about {(first.size - 1) / span:.4g} Hz" if span > 0 else ""
    note = (f"{rec.source}: each reading is held for {k} rows (the logger read the sensor faster than it "
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
    their time stamps give where its own is off (:func:`~accelcal.recording_checks.rate_for`).
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
            notes.append(f"the device's {device.sample_rate_hz * k:g} Hz is taken as {device.sample_rate_hz:g} Hz, "
                         "the rate of the distinct readings")
    return out, device, notes


def _rows_rate(recordings: list[Recording]) -> float | None:
    """The rows' rate, Hz, from the median step of t over the recordings (None without steps)."""
    steps = np.concatenate([np.diff(np.asarray(r.t, float)) for r in recordings]) if recordings else np.zeros(0)
    steps = steps[steps > 0]
    return 1.0 / float(np.median(steps)) if steps.size else None
