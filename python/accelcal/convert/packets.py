"""Packet stamps in a table's time column: a host that stamps each packet of samples it receives
with one time (an LSM6DSOX logger's ``pkt_time_ns``: one epoch in ns for each 12 samples, beside
the chip's own clock ``timestamp``).  Most rows repeat the stamp of the row before, in runs of
one size; such a column times the packets, not the samples, and another numeric time column
that increases every row (the chip's clock) is preferred (:func:`steady_column`)."""
from __future__ import annotations

import numpy as np

from .common import exact_time
from .time import time_in_seconds
from ..io.csvtable import convert_columns
from ..io.recording_checks import repeated_rows

__all__ = ["packet_size", "steady_stamps", "steady_column", "packet_note", "packet_tick",
           "numeric_stamps", "host_tick"]


def packet_size(t: np.ndarray) -> int | None:
    """The packet size k when the stamps ``t`` (the rows read, in order, any unit) are a
    host's packet stamps: more than half the rows repeat the stamp of the row before (no clock
    of the samples does), k >= 2 the most common number of rows a stamp holds (a packet
    written twice and left out, a packet cut by the file's start or end, hold other numbers);
    else None."""
    t = np.asarray(t)
    if t.size < 3:
        return None
    same = np.diff(t) == 0
    if np.mean(same) <= 0.5:
        return None
    starts = np.flatnonzero(np.concatenate([[True], ~same]))
    sizes, counts = np.unique(np.diff(np.append(starts, t.size)), return_counts=True)
    k = int(sizes[np.argmax(counts)])
    return k if k >= 2 else None


def steady_stamps(t: np.ndarray, readings: np.ndarray) -> bool:
    """Whether the stamps ``t`` (the rows read) are finite, never go back, and repeat the stamp
    of the row before only where the row repeats its readings too (a packet written twice,
    which the converter leaves out): a clock that times every sample.

    Parameters
    ----------
    t : ndarray (n,)
        The column's stamps, any unit.
    readings : ndarray (n, 3)
        The three axis columns as written (NaN where empty).
    """
    t = np.asarray(t)
    if t.size < 2 or (t.dtype.kind == "f" and not np.all(np.isfinite(t))):
        return False
    steps = np.diff(t)
    if np.any(steps < 0):
        return False
    twice = repeated_rows([t, *np.asarray(readings).T])[1:]
    return not np.any((steps == 0) & ~twice)


def steady_column(columns: dict[str, np.ndarray], readings: np.ndarray) -> str | None:
    """The first of ``columns`` (name -> stamps of the rows read) whose stamps time every sample
    (:func:`steady_stamps`), or None."""
    return next((n for n, t in columns.items() if steady_stamps(t, readings)), None)


def packet_note(column: str, k: int) -> str:
    """What a packet-stamped column is, for a note or a refusal."""
    return (f"{column!r} repeats its stamp in packets of {k} rows (one stamp a packet: the time a host received "
            "it, no sample's time)")


def packet_tick(packets: np.ndarray, clock: np.ndarray) -> float | None:
    """The length of one unit of the clock ``clock`` (a chip's ticks, the rows read) in seconds,
    measured against a host's packet stamps ``packets`` (the same rows, s from the first): each
    packet's stamp against the tick of its first sample, and of its last (the host stamps a
    packet as it begins or as it arrives), fitted by least squares, the fit with the smaller
    residual taken.  Pauses and lost samples advance both clocks alike, so the line spans them
    (an LSM6DSOX's 25 us tick is 25.40 us on the host's clock over a 3.5-minute log with
    pauses of 27 s).  None with fewer than three packets or a line that does not rise."""
    clock = np.asarray(clock)
    rel = (clock - clock[0]).astype(np.float64)          # exact for int64 ticks
    starts = np.flatnonzero(np.concatenate([[True], np.diff(packets) != 0]))
    if starts.size < 3:
        return None
    ends = np.append(starts[1:] - 1, packets.size - 1)
    fits = []
    for anchor in (starts, ends):
        slope, icpt = np.polyfit(rel[anchor], packets[starts], 1)
        fits.append((float(np.sum((packets[starts] - icpt - slope * rel[anchor]) ** 2)), float(slope)))
    slope = min(fits)[1]
    return slope if slope > 0 else None


def numeric_stamps(table, names: list[str], columns: list[str], rows: np.ndarray) -> dict[str, np.ndarray]:
    """The stamps of the rows read (``rows``) in each of ``columns`` that reads as numbers
    (an epoch in ns as int64: :func:`convert_common.exact_time`); a column that does not is left out."""
    numbers, _ = convert_columns(table, {n: (names.index(n), "ref") for n in columns})
    return {n: exact_time(v, lambda n=n: table.strings(names.index(n)), rows)[rows] for n, v in numbers.items()}


def host_tick(source: str, packets: str, stamps: dict[str, np.ndarray], clock: str, notes: list[str]) -> str | None:
    """The unit of the column ``clock`` (a chip's ticks, its name stating none) measured against
    the packet stamps of the column ``packets`` (:func:`convert_packets.packet_tick`; ``stamps``:
    each column's stamps of the rows read), as a ``--time-unit`` in seconds, with a note; None
    when the fit fails."""
    scratch: list[str] = []
    _, rel = time_in_seconds(stamps[packets], "auto", packets, source, scratch)
    tick = packet_tick(rel, stamps[clock])
    if tick is None:
        return None
    steps = np.diff(stamps[clock]).astype(np.float64)
    step = float(np.median(steps[steps > 0]))
    notes.append(f"{clock!r} states no unit: measured against {packets!r} (the host's clock), its unit is "
                 f"{tick * 1e6:.5g} us and its median step {step:.6g} gives {1.0 / (tick * step):.6g} Hz "
                 "(--time-unit states its unit: s, ms, us, ns or a tick, a number of one: 25us)")
    return f"{tick:.6g}s"
