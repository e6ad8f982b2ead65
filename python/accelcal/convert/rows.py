"""Rows of another tool's file that are no samples of the sensor, one rule for every format
``accelcal convert`` reads: a logger's ``0, 0, 0`` placeholder before the sensor's first value
(:func:`placeholder_lead`), and rows whose readings are all missing -- a sample the logger lost,
or another packet's row -- (:func:`lost_rows`), and the rows after a table's last reading whose
time cells do not continue its stamps (:func:`trailer_note`)."""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import InputError
from ..io.units import UNIT_TEXT, Scale

__all__ = ["PLACEHOLDER_G", "PLACEHOLDER_COUNTS", "LOST_SAMPLES", "placeholder_lead", "lost_rows", "trailer_start",
           "trailer_note"]

#: leading rows of readings all exactly 0 are a placeholder when the next row's |reading| is at
#: least this share of g (and the median |reading| after them twice that)
PLACEHOLDER_G = 0.25
#: ... or, where g in counts is unknown, of the median |reading|, which must be this many counts
PLACEHOLDER_COUNTS = 64
#: what a row of missing readings is in a file of samples only (a MATLAB array, a monitor's log), for the note
LOST_SAMPLES = ("samples the logger lost: the rows after keep their places in time, leaving a gap of a sample each, "
                "which the estimators fill on their time grid")


def placeholder_lead(raw: np.ndarray, scale: Scale | None, gravity: float, line: Callable[[int], int],
                     notes: list[str]) -> int:
    """How many leading rows of ``raw`` read exactly 0, 0, 0 where the rows after are far from 0
    (a logger that writes 0, 0, 0 before the sensor's first value: a phone's log, a robot lab's
    MATLAB file), with a note naming them; else 0.

    Far from 0: the next row's |reading| at least PLACEHOLDER_G of g and the median |reading|
    after the zeros at least twice that, g in counts from the stated LSB; in counts of no
    stated LSB, the next row's |reading| at least PLACEHOLDER_G of that median, and the median
    at least PLACEHOLDER_COUNTS.  An accelerometer reads 0, 0, 0 only in free fall.

    Parameters
    ----------
    raw : ndarray (n, 3) of int
        The readings in counts, in the file's order.
    scale : units.Scale or None
        The readings' unit and LSB (the note gives |reading| in the file's unit).
    gravity : float
        g, m/s^2.
    line : callable
        ``line(i)``: the file's row of reading i, for the note.
    notes : list of str
        Appended to.
    """
    if raw.shape[0] < 2:
        return 0
    zero = np.all(raw == 0, axis=1)
    if not zero[0] or zero.all():
        return 0
    lead = int(np.argmin(zero))
    units = scale.units if scale is not None and scale.converts else "counts"
    m = raw[lead:].astype(float) * (scale.lsb if units != "counts" else 1.0)
    norms = np.linalg.norm(m, axis=1)
    median = float(np.median(norms))
    k = scale.counts_per_mps2(gravity) if scale is not None else None
    g = {"g": 1.0, "mps2": gravity}.get(units, k * gravity if k else None)
    least = PLACEHOLDER_G * (g if g is not None else median)
    if norms[0] < least or median < 2 * least or (g is None and median < PLACEHOLDER_COUNTS):
        return 0
    where = f"rows {line(0)}-{line(lead - 1)}" if lead > 1 else f"row {line(0)}"
    size = f"{norms[0]:.4g} {UNIT_TEXT[units]}" + (f" ({norms[0] / g:.3g} g)" if g is not None and units != "g" else "")
    notes.append(f"the first {lead} row(s) ({where}) read exactly 0, 0, 0 where the next row's |reading| is {size} "
                 f"and the median {median:.4g} {UNIT_TEXT[units]}: a placeholder before the sensor's first value, "
                 "left out")
    return lead


def lost_rows(source: str, values: np.ndarray, line: Callable[[int], int], column: Callable[[int], str],
              cell: Callable[[int, int], str], notes: list[str], why: str) -> np.ndarray:
    """The indices of the rows of ``values`` that hold readings: rows whose readings are all
    missing (NaN: an empty or ``nan`` cell) are left out with a note counting them and naming
    the first (``why``: what they are, for the note).  Whether the rows after keep their places
    is the caller's: a lost sample's does (the later rows keep their sample numbers, so their
    time from a rate, leaving a gap the estimators fill on their time grid; closing it would
    put every later sample a period early), another packet's row in a table has none.

    Parameters
    ----------
    source : str
        The file, for messages.
    values : ndarray (n, 3)
        The readings as read, NaN where missing.
    line, column, cell : callable
        The file's row of reading i; the name of column j; the text of cell (i, j), for the
        refusal.
    notes : list of str
        Appended to.
    why : str
        What such rows are (``a sample the logger lost``), for the note.

    Raises
    ------
    InputError
        A row with one or two of its readings missing, naming its row and the column.
    """
    empty = np.isnan(values)
    gone = empty.all(axis=1)
    partly = np.flatnonzero(empty.any(axis=1) & ~gone)
    if partly.size:
        i = int(partly[0])
        j = int(np.flatnonzero(empty[i])[0])
        others = [column(k) for k in range(values.shape[1]) if not empty[i, k]]
        raise InputError(source, f"expected a reading, got {cell(i, j)} where {' and '.join(others)} "
                         f"{'has' if len(others) == 1 else 'have'} one (a row's three readings are all given, or "
                         "all missing: a sample lost, another packet's row)", row=line(i), column=column(j))
    if gone.any():
        first = int(np.flatnonzero(gone)[0])
        names = ", ".join(column(k) for k in range(values.shape[1]))
        notes.append(f"{int(gone.sum())} row(s) whose readings ({names}) are all missing (empty or nan), the first "
                     f"row {line(first)}: left out ({why})")
    return np.flatnonzero(~gone)


def trailer_start(values: np.ndarray) -> int:
    """The index of the first row of ``values`` (n, 3; NaN where missing) after the last that holds
    a reading: the rows from there on (none: n) hold no readings."""
    held = np.flatnonzero(~np.isnan(values).all(axis=1))
    return int(held[-1]) + 1 if held.size else 0


def trailer_note(start: int, n: int, last_row: int, cell: Callable[[int], str], line: Callable[[int], int]) -> str | None:
    """The note for the rows ``start..n-1`` after a table's last reading (row index ``last_row``)
    whose time cells do not continue the stamps: a stamp not after the one before (they run back:
    a spreadsheet's scratch below the data, stamps in another unit) or text.  They are no samples,
    and none was lost: they are left out, and the note says so, quoting the first such cell.  None
    where every such time cell is empty or a stamp after the one before (samples lost at the end:
    :func:`lost_rows`'s).

    Parameters
    ----------
    start, n : int
        The first row after the last reading (:func:`trailer_start`), and the table's rows.
    cell, line : callable
        The text of row i's time cell; the file's line of row i.
    """
    def stamp(i: int) -> float:
        try:
            return float(cell(i))
        except ValueError:
            return float("nan")

    prev, odd = last_row, None
    for i in range(start, n):
        text = cell(i).strip()
        if not text or text.lower() == "nan":
            continue
        if not np.isfinite(stamp(i)) or not stamp(i) > stamp(prev):
            odd = i
            break
        prev = i
    if odd is None:
        return None
    what = (f"{cell(odd).strip()!r} is not after {cell(prev).strip()!r} (row {line(prev)}): the stamps run back"
            if np.isfinite(stamp(odd)) else f"{cell(odd).strip()!r} is no time stamp")
    rows = f"rows {line(start)}-{line(n - 1)}" if n - start > 1 else f"row {line(start)}"
    return (f"the last {n - start} row(s) ({rows}) hold no readings, and their time cells do not continue the time "
            f"stamps (row {line(odd)}: {what}): they are no samples, none lost; left out")
