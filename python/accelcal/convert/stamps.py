"""A table's time stamps as written, before they become t: rows that repeat the row before
(a packet written twice, a sample delivered twice), stamps that repeat with other readings
(refused, or left out with ``--repeated-stamps drop``), stamps that slipped a place late
(``--repeated-stamps shift``), and a host's packet stamps (:mod:`accelcal.convert.packets`).
Used by :mod:`accelcal.convert.named`."""
from __future__ import annotations

import numpy as np

from .packets import packet_note, packet_size
from ..io.csvtable import got_text
from ..errors import InputError
from ..io.recording_checks import repeated_rows

__all__ = ["DUPLICATE_MIN_SHARE", "DUPLICATE_RATIO", "repeated_stamps", "table_time", "slipped_runs", "slipped_stamps",
           "shift_slipped", "unrepeated"]
DUPLICATE_MIN_SHARE = 0.5  # rows off the grid that repeat the row before are samples delivered twice only when
DUPLICATE_RATIO = 5.0      # at least this share of them repeat, and this x the share of the rows on the grid


def repeated_stamps(stamps: np.ndarray, rows: np.ndarray, notes: list[str], how: str = "drop") -> np.ndarray:
    """``rows`` less those whose time stamp repeats the row before's (``--repeated-stamps
    drop``, or ``shift`` for the repeats no slip explains: the readings differ --
    :func:`unrepeated` has left out the rows that repeat both), with a note counting them."""
    same = np.flatnonzero(np.diff(stamps[rows]) == 0) + 1
    if same.size:
        why = "" if how == "drop" else ": no step of two before them shows a slip"
        notes.append(f"{same.size} row(s) repeat the time stamp of the row before with other readings (a logger that "
                     f"stamps two samples with one stamp): left out (--repeated-stamps {how}{why})")
    return np.delete(rows, same)


def table_time(source: str, stamps: np.ndarray, table, rows: np.ndarray, column: str, j: int,
               others: list[str]) -> np.ndarray:
    """The time stamps of the rows read (``rows``), as written: finite and increasing.  A
    refusal for a host's packet stamps (:func:`convert_packets.packet_size`) names ``others``, the
    table's other numeric columns with a time's name.

    Raises
    ------
    InputError
        An empty or unknown stamp, or one not after the stamp before, naming its line; a
        repeated one counts the rows that repeat the stamp before and names the option that
        leaves them out.
    """
    t = stamps[rows]
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        i = int(rows[bad[0]])
        raise InputError(source, f"expected a time stamp, got {got_text(table.cell(i, j))}", row=table.line(i),
                         column=column)
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        h, i = int(rows[back[0]]), int(rows[back[0] + 1])
        same = int(np.sum(np.diff(t) == 0))
        slipped = slipped_stamps(t)
        k = packet_size(t)
        what = ("" if t[back[0] + 1] != t[back[0]] else
                f"; {packet_note(column, k)}: name a column that times each sample with --time-column NAME"
                + (f" ({', '.join(map(repr, others))})" if others else "") if k is not None else
                f"; {same} row(s) repeat the stamp of the row before with other readings (a logger that stamps two "
                "samples with one stamp)" + (f", {slipped} of them after a step of two (with steps of one between): "
                                             "stamps that slipped a place late and caught up, the samples on their "
                                             "grid (--repeated-stamps shift moves them back a step, every sample "
                                             "kept)" if slipped else "") +
                ": --repeated-stamps drop leaves them out (a sample each)")
        raise InputError(source, f"time stamp {table.cell(i, j).strip()!r} is not after {table.cell(h, j).strip()!r} "
                         f"(row {table.line(h)}): time stamps must increase{what}", row=table.line(i), column=column)
    return t


def slipped_runs(t: np.ndarray) -> list[tuple[int, int]]:
    """The stamps ``t`` (as written, any unit) that slipped a place late: for each stamp that
    repeats the one before and comes after a step of two median steps (1.5-2.5) with steps of
    one (0.5-1.5) between, the indices (first, last) of the stamps from that step to the one the
    repeat repeats -- each a step late, and the repeat catches up (a Garmin watch's export: 90 of
    its 92 repeats, 3-27 rows after such a step); the samples keep their even spacing."""
    steps = np.diff(t).astype(np.float64)
    ahead = steps[steps > 0]
    if not ahead.size:
        return []
    k = steps / float(np.median(ahead))
    runs, start = [], None
    for i, v in enumerate(k.tolist()):
        if v == 0:
            if start is not None:
                runs.append((start, i))
            start = None
        elif 1.5 <= v <= 2.5:
            start = i + 1
        elif not 0.5 <= v < 1.5:
            start = None
    return runs


def slipped_stamps(t: np.ndarray) -> int:
    """How many of the stamps ``t`` that repeat the one before catch up a slip
    (:func:`slipped_runs`)."""
    return len(slipped_runs(t))


def shift_slipped(stamps: np.ndarray, rows: np.ndarray, notes: list[str]) -> np.ndarray:
    """``stamps`` with each stamp of the rows read (``rows``) that slipped a place late
    (:func:`slipped_runs`: proved by the step of two before and the repeat after) moved back
    one median step (``--repeated-stamps shift``): every sample kept, the steps all ones where
    they were two, ones and a repeat; with a note counting them."""
    t = stamps[rows]
    runs = slipped_runs(t)
    if not runs:
        return stamps
    steps = np.diff(t)
    step = np.median(steps[steps > 0])
    step = np.round(step).astype(t.dtype) if np.issubdtype(t.dtype, np.integer) else step
    moved = t.copy()
    for first, last in runs:
        moved[first:last + 1] -= step
    out = stamps.copy()
    out[rows] = moved
    notes.append(f"{sum(b - a + 1 for a, b in runs)} time stamps in {len(runs)} run(s) slipped a place late (each run "
                 "after a step of two median steps and caught up by a repeated stamp): moved back one step "
                 "(--repeated-stamps shift), every sample kept")
    return out


def unrepeated(rows: np.ndarray, stamps: np.ndarray, readings: np.ndarray, notes: list[str]) -> np.ndarray:
    """``rows`` less the rows that repeat the row before's readings exactly, with a note for each
    kind: with its time stamp too (a packet written twice: 1.2 % of x-io's Gait-Tracking
    logs), or with a stamp less than half a median step after it (a sample delivered twice,
    off the grid: 91 rows of a Samsung S6's 100 Hz log) where such repeats stand out: at least
    DUPLICATE_MIN_SHARE of the rows off the grid, and DUPLICATE_RATIO x the share on it (readings
    that repeat by chance -- coarse steps, a quiet sensor -- do so on and off a jittered grid
    alike, and are samples).  A repeated reading on the grid (a
    step or more after the row before: a quiet sensor's) is a sample and stays; a repeated
    time stamp with other readings is left for :func:`table_time` to refuse.

    Parameters
    ----------
    rows : ndarray of int
        The rows with readings.
    stamps : ndarray (n,)
        The time column as written (float64, or int64 for an epoch in ns), any unit.
    readings : ndarray (n, 3)
        The three axis columns as written (NaN where empty).
    notes : list of str
        Appended to.
    """
    t, m = stamps[rows], readings[rows]
    repeat = np.all((m[1:] == m[:-1]) | (np.isnan(m[1:]) & np.isnan(m[:-1])), axis=1)
    steps = np.diff(t).astype(np.float64)           # exact for int64 stamps
    same = repeated_rows([t, *m.T])[1:]            # time stamp and readings: the one home of that rule
    ahead = steps[steps > 0]
    step = float(np.median(ahead)) if ahead.size else 0.0
    off = (steps > 0) & (steps < 0.5 * step)
    again = repeat & off
    # delivered twice only where repeats off the grid stand out: readings that repeat by chance
    # (coarse steps, a quiet sensor) do so on and off a jittered grid alike
    on = steps >= 0.5 * step
    p_on = float(np.mean(repeat[on])) if on.any() else 0.0
    p_off = float(np.mean(repeat[off])) if off.any() else 0.0
    if not (p_off >= DUPLICATE_MIN_SHARE and p_off >= DUPLICATE_RATIO * p_on):
        again = np.zeros_like(again)
    if same.any():
        notes.append(f"{int(same.sum())} row(s) repeat the row before, time stamp and readings (a packet written "
                     "twice): left out")
    if again.any():
        notes.append(f"{int(again.sum())} row(s) repeat the readings of the row before with a time stamp less than "
                     f"half a step after it (median step {step:.6g} in the time column's unit; a sample delivered "
                     "twice, off the grid): left out")
    if not (same.any() or again.any()):
        return rows
    return rows[np.concatenate([[True], ~(same | again)])]
