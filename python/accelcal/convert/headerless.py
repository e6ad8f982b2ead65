"""Rows without a header whose first cell is a time stamp: a Garmin watch's export
(``2019-10-16T12:09:01.702+02:00;-36;620;-824``), Axivity's AX3 test files (``unix_t,x,y,z``).
Four cells a row whose first is a time stamp are read as ``t,x,y,z`` by the table path
(:mod:`accelcal.convert.named`: units, ``--round``, repeated stamps alike), with a note.

A first cell is a time stamp when the first row's is an ISO-8601 date-time
(:func:`convert_time.is_datetime`: no reading is written so), or when every row's is a
number above STAMP_MIN and they never decrease and rise over the file (a unix time in s,
ms, us or ns).  Any other first column may be a reading, and stays refused with the
header line to add.

Seven cells a row whose first is a time stamp (an Axivity AX6's export: time, the accelerometer's
x, y, z in g, the gyroscope's in deg/s) are read as ``t,ax,ay,az,c5,c6,c7``: the first three
numbers the accelerometer's (the order of such exports, the accelerometer first), the rest
ignored with a note.  Rows of another count (a time and 4, 5, 8 ... numbers) are named
``t,c2,c3,...`` (cell k is ``ck``) but left to ``--columns`` to say which three are the
accelerometer's: no rule says.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from .time import is_datetime
from ..io.textinput import CELL_NUMBER_RE, NUMBER_RE, Preamble, byte_lines, line_cells

__all__ = ["STAMP_MIN", "HEADERLESS_NAMES", "timed_rows", "stamp_rule", "headerless_names", "axes_known"]

#: numbers in a first column above this (2^24: beyond every reading of a 24-bit ADC, signed or not,
#: and any reading in g or m/s^2) that never decrease are time stamps (a unix time is above it since
#: July 1970 in seconds)
STAMP_MIN = 2.0 ** 24
#: the columns of the rows read without a header
HEADERLESS_NAMES = ("t", "x", "y", "z")
#: the columns of seven cells a row read without a header: a time, the accelerometer's three (an Axivity
#: AX6's export: then the gyroscope's, ignored)
HEADERLESS_SIX = ("t", "ax", "ay", "az", "c5", "c6", "c7")


def headerless_names(cells: int) -> tuple[str, ...]:
    """The names given to rows of ``cells`` cells without a header whose first is a time stamp:
    HEADERLESS_NAMES (4), HEADERLESS_SIX (7), else ``t, c2, c3, ...`` (cell k is ``ck``: the
    names ``--columns`` gives)."""
    if cells == len(HEADERLESS_NAMES):
        return HEADERLESS_NAMES
    if cells == len(HEADERLESS_SIX):
        return HEADERLESS_SIX
    return ("t",) + tuple(f"c{k}" for k in range(2, cells + 1))


def axes_known(cells: int) -> bool:
    """Whether rows of ``cells`` cells, the first a time stamp, say by their count alone which three
    are the accelerometer's (4: t,x,y,z; 7: t, the accelerometer's three, three more)."""
    return cells in (len(HEADERLESS_NAMES), len(HEADERLESS_SIX))


def stamp_rule(cells: int) -> str:
    """The rule in words, for the refusal of rows of ``cells`` cells that it does not take."""
    if not axes_known(cells):
        return f"a time and {cells - 1} numbers: which three are the accelerometer's no header says"
    return (f"a first column is read as time without a header only when it holds ISO-8601 date-times, or "
            f"numbers above 2^24 ({STAMP_MIN:.0f}) that never decrease")


def first_cells(data: bytes, pos: int, spaced: bool) -> list[str]:
    """The first cell of every line from byte ``pos`` on that is neither blank nor a comment."""
    out = []
    for line, _, _ in byte_lines(data, pos):
        if not line.strip() or line.startswith("#"):
            continue
        out.append(line.split(None, 1)[0] if spaced else line.split(",", 1)[0].strip())
    return out


def rising_stamps(cells: list[str]) -> bool:
    """Whether ``cells`` are numbers above STAMP_MIN that never decrease and rise from first to
    last."""
    try:
        v = np.array([float(c) for c in cells])
    except ValueError:
        return False
    return v.size > 1 and bool(np.all(v > STAMP_MIN) and np.all(np.diff(v) >= 0) and v[-1] > v[0])


def timed_rows(data: bytes, pre: Preamble) -> Preamble | None:
    """The preamble of rows without a header whose first cell is a time stamp, their columns named
    by :func:`headerless_names` (``t,x,y,z``; ``t,ax,ay,az,c5,c6,c7``; ``t,c2,...``), or None.

    Parameters
    ----------
    data : bytes
        The file's text (:func:`textinput.read_text_bytes`: ``;`` already made ``,``).
    pre : Preamble
        The file's preamble (:func:`textinput.table_preamble`), whose header line is the first
        row.

    Returns
    -------
    Preamble or None
        A copy whose ``header`` is made (the file's separator between the names), whose data
        rows start at the first row (``pos``; ``header_line`` the line before it) and whose
        ``made`` is the note saying so; None where the first line is not four or more cells, the
        others numbers, the first a time stamp (the module's rule), or where the file has a
        header (a comment naming the columns, a title before it).
    """
    if pre.header is None or pre.header_from_comment or pre.title is not None:
        return None
    cells = line_cells(pre.header)
    if len(cells) < len(HEADERLESS_NAMES) or not all(CELL_NUMBER_RE.fullmatch(c) for c in cells[1:]):
        return None
    spaced = "," not in pre.header
    if is_datetime(cells[0]):
        what = "ISO-8601 date-times"
    elif NUMBER_RE.fullmatch(cells[0]) and rising_stamps(first_cells(data, pre.header_pos, spaced)):
        what = f"numbers above 2^24 that never decrease, from {cells[0]}"
    else:
        return None
    names = (" " if spaced else ",").join(headerless_names(len(cells)))
    six = len(cells) == len(HEADERLESS_SIX)
    note = (f"no header: the {len(cells)} cells of each row are read as {names} (the first column holds {what}: time "
            + ("stamps; the next three the accelerometer's x, y, z, as an Axivity AX6's export orders them, its "
               "gyroscope's after; --columns names three others, cell k as ck" if six else "stamps") +
            "); a header line naming the columns states another layout")
    return dataclasses.replace(pre, header=names, header_line=pre.header_line - 1, pos=pre.header_pos, made=note)
