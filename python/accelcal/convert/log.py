"""``accelcal convert --format log``: a serial monitor's capture of a logger.

What an Arduino or PlatformIO monitor saves while a sketch prints one reading per line
(such as FastAhrs's calibration notebooks' ``data_sample.csv``): no header and no time
column; lines of three numbers, the readings (comma, semicolon, tab or space separated);
among them the sketch's and the monitor's text -- a banner, ``>>> Type key when ready...``
before each pose -- which splits the readings into blocks.

* A line of exactly three numbers is a reading (``nan`` a reading missing: a line of three is a
  sample lost, left out by the converter with a note, the lines after keeping their places:
  :func:`accelcal.convert.rows.lost_rows`); a line with a letter in it, or of punctuation alone
  (``------``), is text; blank lines are skipped.  Any other line (two
  numbers, four, a number cut off) is refused, naming its row.
* ``blocks=True`` labels each block of readings between text lines as a pose
  (``block_1``, ``block_2``, ... in the file's order): a logger that records each pose
  after a prompt.  Without it the blocks are one stretch of samples, joined by instant
  steps, which static detection splits where the readings step.
* The sample rate is the caller's (``--rate``): the lines carry no time.
* Readings held for several rows (the monitor read the sensor faster than it updates) are
  told by :func:`accelcal.readings.held.held_runs`, the rule ``calibrate`` and ``diagnose`` use; the
  converter notes the share of repeated rows and the rate of the distinct readings.
"""
from __future__ import annotations

import re
from typing import Any

import numpy as np

from ..errors import InputError
from ..io.textinput import NUMBER_RE

__all__ = ["LOG_MIN_READINGS", "is_log", "read_log"]

LOG_MIN_READINGS = 10      # a file is told to be a log from this many reading lines among its first 200

SPLIT_RE = re.compile(r"\s*[,;\t ]\s*")
LETTER_RE = re.compile(r"[A-Za-z]")
PUNCT_RE = re.compile(r"[\W_]+")
#: a reading missing
NAN_CELLS = ("nan", "+nan", "-nan")


def _kind(text: str) -> tuple[str, list[str]]:
    """('reading', cells), ('text', []) or ('bad', cells) of one line (stripped, not blank)."""
    cells = [c for c in SPLIT_RE.split(text) if c != ""]
    if len(cells) == 3 and all(NUMBER_RE.fullmatch(c) or c.lower() in NAN_CELLS for c in cells):
        return "reading", cells
    if LETTER_RE.search(text) or PUNCT_RE.fullmatch(text):
        return "text", []
    return "bad", cells


def is_log(data: bytes) -> bool:
    """Whether ``data`` reads as a monitor capture: among its first 200 non-blank lines at
    least LOG_MIN_READINGS readings and every other line text (imu_tk's lines hold four
    numbers, a recording CSV has a header of names)."""
    n_read, n_text = 0, 0
    for raw in data.splitlines()[:400]:
        text = raw.decode("utf-8", errors="replace").strip()
        if not text or text.startswith("#"):
            continue
        kind, _ = _kind(text)
        if kind == "bad":
            return False
        n_read += kind == "reading"
        n_text += kind == "text"
        if n_read + n_text >= 200:
            break
    return n_read >= LOG_MIN_READINGS


def read_log(source: str, data: bytes) -> tuple[np.ndarray, list[int], list[str], dict[str, Any]]:
    """The readings of a monitor capture.

    Returns
    -------
    values : ndarray (n, 3) float
        The readings as printed (counts or physical units: the caller converts).
    lines : list of int
        The file's line number (1-based) of each reading.
    block : list of str
        ``block_k`` of each reading (k from 1: the k-th run of readings between text lines).
    info : dict
        ``text_lines`` (count), ``first_text`` (the first text line, shortened), ``blocks``
        (count), ``cut`` (a note on a last line cut short and left out, or None).

    Raises
    ------
    InputError
        A line that is neither a reading nor text (naming its row and what it holds), or
        no reading at all.
    """
    values: list[list[str]] = []
    lines: list[int] = []
    block: list[str] = []
    k, in_block, n_text, first_text, cut = 0, False, 0, "", None
    body = data.splitlines()
    last = len(body) if not data.endswith(b"\n") else 0     # a last line with no line end after it
    for no, raw in enumerate(body, start=1):
        text = raw.decode("utf-8", errors="replace").strip()
        if not text or text.startswith("#"):
            continue
        kind, cells = _kind(text)
        if kind == "text":
            n_text += 1
            first_text = first_text or text[:60]
            in_block = False
            continue
        if kind == "bad" and no == last and 0 < len(cells) < 3:
            cut = f"line {no}, the last, is cut short ({len(cells)} of 3 numbers, no line end after it: a logger " \
                  "stopped mid-write); it is left out"
            continue
        if kind == "bad":
            raise InputError(source, f"expected three numbers (a reading) or a line of text, got {len(cells)} "
                             f"field(s) ({text[:60]!r})", row=no)
        if not in_block:
            k, in_block = k + 1, True
        values.append(cells)
        lines.append(no)
        block.append(f"block_{k}")
    if not values:
        raise InputError(source, "no reading (a line of three numbers) in the file")
    info = {"text_lines": n_text, "first_text": first_text, "blocks": k, "cut": cut}
    return np.array(values, dtype=float), lines, block, info

