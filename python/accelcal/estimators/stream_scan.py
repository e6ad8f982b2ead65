"""The first pass of a per-sample estimator in chunks (``rate``; docs/streaming.md): what the
whole-file command takes from the whole recording, reduced to sums while the chunks go by.

The whole-file command checks the recording against the device (:func:`check_for_device`), puts
it on its uniform time grid (:func:`accelcal.estimators.timegrid.on_uniform_grid`), takes the
median step as dt (:func:`accelcal.estimators.common.uniform_dt`), the channels' noise
(:func:`accelcal.estimators.common.channel_noise`) and warns of readings held for several rows
(:func:`accelcal.readings.held.held_runs`).  :func:`scan` gives dt exactly (the median from the
counts of the distinct steps), raises the whole-file command's error for bad rows (ranked as
:mod:`accelcal.resolve_stream` ranks them) and proves the rest needs nothing of the samples: it
raises :class:`~accelcal.io.chunks.Fallback` -- the whole-file command then runs and words what it
finds -- for a non-finite t, t in another unit than seconds, a device that states no noise
(estimated from the data), readings held for several rows, more than :data:`MAX_STEP_VALUES`
distinct steps; and :func:`on_grid` (the second pass, chunk by chunk) for any sample more than
:data:`GRID_MARGIN` of a step off the straight line through the first and the last stamps (far
inside what :func:`on_uniform_grid` leaves alone: jitter 0.05 of a step, nothing late or lost).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, Callable, NoReturn

import numpy as np

from ..errors import InputError
from ..io.chunk_source import ChunkSource
from ..io.chunks import Fallback, reader_checks
from ..io.recording_checks import TIME_UNIT_TOL, TIME_UNITS, check_core_input, check_raw_range
from ..readings.held import RunCounts, order_stat
from ..readings.noise import noise_for, states_noise
from ..readings.noise_stream import add_counts, median_of_counts

#: ranks of the checks after the reader's (1-4: io.chunks.reader_checks), as in the whole-file command
RANK_RANGE, RANK_CORE = 10, 12

__all__ = ["RANK_RANGE", "RANK_CORE", "Deferred", "raise_deferred", "MAX_STEP_VALUES", "GRID_MARGIN", "RunCounts", "Scan", "scan", "scan_with_bar", "on_grid"]

#: distinct time steps kept for the exact median (more: the whole-file command)
MAX_STEP_VALUES = 1 << 16
#: a sample this far (steps) off the line through the first and the last stamps: the whole-file command
GRID_MARGIN = 0.005


@dataclass
class Scan:
    """What the whole-file command takes from the whole recording.

    Attributes
    ----------
    n : int
        Samples.
    t0, t1 : float
        The first and the last stamps, s.
    dt : float
        The median step, s (:func:`accelcal.estimators.common.uniform_dt`'s).
    noise : ndarray (N,)
        The channels' noise, counts (:func:`accelcal.estimators.common.channel_noise`'s).
    """

    n: int
    t0: float
    t1: float
    dt: float
    noise: np.ndarray


def scan_with_bar(device, source: ChunkSource, *, fixed: bool, progress=None, defer_from: int | None = None) -> Scan:
    """:func:`scan` with a progress bar from ``progress(total, unit)`` (None: none), closed after."""
    bar = progress(source.total, source.unit) if progress is not None else None
    out = scan(device, source, fixed=fixed, progress=None if bar is None else bar.update, defer_from=defer_from)
    if bar is not None:
        bar.close()
    return out


def scan(device, source: ChunkSource, *, fixed: bool, progress: Callable[[int], None] | None = None,
         defer_from: int | None = None) -> Scan:
    """The first pass (see the module doc).

    ``defer_from``: an error of this rank or after (:data:`RANK_RANGE`, :data:`RANK_CORE`) raises
    :class:`Deferred` instead (a command that looks at the time grid before the device's range:
    :func:`raise_deferred`).

    Raises
    ------
    InputError
        The whole-file command's error (the reader's, a reading outside the device's range or,
        ``fixed``, the C core's input), as it words it: the first of the lowest rank, once the
        whole file has been read (a bad cell at once: it is the file's first).
    Fallback
        Where the whole-file command must run (t in another unit also under a range error: the
        whole-file command notes it before the error).
    """
    if not states_noise(device):
        raise Fallback("the noise is estimated from the data")
    head = source.head
    if head.n_raw != device.n_channels:
        raise Fallback("channels")
    steps: dict = {}
    runs = RunCounts()
    prev = None
    n, t0, t1 = 0, math.nan, math.nan
    signed = device.raw_min < 0
    pending: tuple[int, InputError] | None = None
    for ch in source.chunks(progress):           # a bad cell: the file's first, the whole-file reader's error
        if not np.all(np.isfinite(ch.t)):
            raise Fallback("t not finite")
        errs = reader_checks(head, ch, prev)
        rec = SimpleNamespace(raw=ch.raw, source=head.source, line=ch.line)
        for rank, check in ((RANK_RANGE, lambda: check_raw_range(rec, device)),
                            (RANK_CORE, lambda: check_core_input(rec, signed) if fixed else None)):
            try:
                check()
            except InputError as e:
                errs.append((rank, e))
        for rank, e in errs:                      # the whole-file command's order: rank, then row
            if pending is None or rank < pending[0]:
                pending = (rank, e)
        n += ch.n
        # the steps and stamps also under a range error: the whole-file command notes t's unit first
        if pending is None or pending[0] >= RANK_RANGE:
            d = np.diff(ch.t) if prev is None else np.diff(np.concatenate(([prev.t[-1]], ch.t)))
            add_counts(steps, d)
            if len(steps) > MAX_STEP_VALUES:
                raise Fallback("steps of too many values")
            if pending is None:
                runs.add(ch.raw)
            if prev is None and ch.n:
                t0 = float(ch.t[0])
            if ch.n:
                t1 = float(ch.t[-1])
        prev = ch
    if n < 3:
        raise Fallback("too few samples")
    if pending is not None and pending[0] < RANK_RANGE:
        raise pending[1]                          # the reader's: before the whole-file command notes t's unit
    dt = median_of_counts(steps)
    ratio = dt * float(device.sample_rate_hz)
    if any(abs(ratio / k - 1.0) <= TIME_UNIT_TOL for k, _ in TIME_UNITS):
        raise Fallback("t in another unit")       # the whole-file command's note, then what it finds
    sc = Scan(n=n, t0=t0, t1=t1, dt=dt, noise=noise_for(device, np.zeros((0, device.n_channels), np.int64), 1)[0])
    if pending is not None:
        if defer_from is not None and pending[0] >= defer_from:
            raise Deferred(pending[1], sc)
        raise pending[1]
    if runs.held(device.n_channels) != 1:
        raise Fallback("held readings")
    return sc


class Deferred(Fallback):
    """An error of the device's range (or the C core's input) that a command whose whole-file form puts t
    on its grid first (``rate --omega array``) names only where the grid leaves t alone:
    :func:`raise_deferred`.

    Attributes
    ----------
    error : InputError
    scan : Scan
        The first pass's figures (n, the first and last stamps, dt).
    """

    def __init__(self, error: InputError, scan: Scan) -> None:
        super().__init__("an error the whole-file command ranks after the time grid")
        self.error, self.scan = error, scan


def raise_deferred(source: ChunkSource, deferred: Deferred) -> NoReturn:
    """Read the stamps again: on the grid (:func:`on_grid`, every chunk), raise the deferred error (the
    whole-file command's, as it words it); else Fallback (the whole-file command decides)."""
    for ch in source.chunks():
        on_grid(deferred.scan, ch.start, ch.t)
    raise deferred.error


def on_grid(sc: Scan, start: int, t: np.ndarray) -> None:
    """The second pass's time check of a chunk (samples ``start``.. of the recording).

    Raises
    ------
    Fallback
        A stamp more than GRID_MARGIN of a step off the line through the first and the last.
    """
    step = (sc.t1 - sc.t0) / (sc.n - 1)
    i = np.arange(start, start + t.size, dtype=float)
    if t.size and float(np.max(np.abs(t - sc.t0 - i * step))) > GRID_MARGIN * step:
        raise Fallback("stamps off the uniform grid")
