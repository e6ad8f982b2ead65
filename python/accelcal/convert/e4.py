"""``accelcal convert``'s ``e4`` format: an Empatica E4 wristband's ``ACC.csv`` export.

Row 1 is the session's start as unix time (s), repeated in every column; row 2 the sample
rate (Hz), likewise; then one row ``x,y,z`` a sample in signed 8-bit counts of 1/64 g (+-2 g).
Every E4 signal file is laid out so (EDA, TEMP, BVP with one column); ``ACC.csv`` has three.
"""
from __future__ import annotations

import numpy as np

from .common import Converted, Options, finish, whole_counts
from .log import read_log
from .rows import LOST_SAMPLES, lost_rows
from ..errors import InputError, notes_on_refusal
from ..io.units import Scale, file_scale
from ..io.units_counts import to_counts

__all__ = ["E4_LSB_G", "E4_BITS", "e4_preamble", "is_e4", "convert_e4"]

#: the E4's accelerometer: one count is 1/64 g, signed 8 bits (+-2 g)
E4_LSB_G = 1.0 / 64.0
E4_BITS = 8
#: row 1's value is a start time when at least this many seconds since 1970 (1973-03-03)
E4_MIN_EPOCH_S = 1e8
#: row 2's value is a sample rate when in (0, this] Hz
E4_MAX_RATE_HZ = 1e4


def e4_preamble(data: bytes) -> tuple[float, str] | None:
    """Row 1's start time (unix s) and row 2's text where the file's first two lines are an
    E4's preamble: three comma-separated cells each, one value repeated in each row, row 1's
    at least E4_MIN_EPOCH_S (no accelerometer reads 1e8 on all three axes); else None."""
    lines = data.split(b"\n", 2)
    if len(lines) < 3:
        return None
    rows = []
    for line in lines[:2]:
        cells = [c.strip() for c in line.decode("utf-8", "replace").split(",")]
        try:
            values = {float(c) for c in cells}
        except ValueError:
            return None
        if len(cells) != 3 or len(values) != 1:
            return None
        rows.append((values.pop(), cells[0]))
    (start, _), (_, rate_text) = rows
    return (start, rate_text) if np.isfinite(start) and start >= E4_MIN_EPOCH_S else None


def is_e4(data: bytes) -> bool:
    """Whether the text is an Empatica E4 ``ACC.csv`` (:func:`e4_preamble`)."""
    return e4_preamble(data) is not None


def convert_e4(source: str, data: bytes, opts: Options) -> Converted:
    """An E4 ``ACC.csv``: t from row 1's start at row 2's rate (``--rate`` overrides it, with a
    note), the readings in counts of 1/64 g unless a scale is stated, 8 bits unless ``--bits``
    states other than its default 16.

    Raises
    ------
    InputError
        Row 2 no sample rate; a row of the readings that is not three numbers (naming it).  A
        refusal after the first note carries the notes (:func:`errors.notes_on_refusal`).
    """
    start, rate_text = e4_preamble(data)
    try:
        file_rate = float(rate_text)
    except ValueError:
        file_rate = float("nan")
    if not (0 < file_rate <= E4_MAX_RATE_HZ):
        raise InputError(source, f"rows 1-2 look like an Empatica E4's start time ({start:.0f}, unix s) and sample "
                         f"rate, but row 2's {rate_text!r} is no rate in Hz: remove the two rows and give --rate HZ", row=2)
    cut = data.index(b"\n", data.index(b"\n") + 1)
    values, lines, _, info = read_log(source, b"\n\n" + data[cut + 1:])     # lines keep their numbers
    notes = [f"rows 1-2 are an Empatica E4's session start ({start:.6f} unix s) and sample rate ({file_rate:g} Hz): "
             "t is seconds since 1970-01-01 UTC from that start"]
    if info["text_lines"]:
        notes.append(f"{info['text_lines']} line(s) of text among the readings (the first: {info['first_text']!r}) "
                     "are left out")
    with notes_on_refusal(lambda: notes + ([info["cut"]] if info["cut"] else [])):
        rate = file_rate
        if opts.rate_hz is not None and opts.rate_hz != file_rate:
            rate = opts.rate_hz
            notes.append(f"--rate {rate:g} Hz is used for the {file_rate:g} Hz row 2 states")
        scale = file_scale(opts.scale, {}, {}, source)      # (--round over counts refused)
        if scale is None:
            scale = Scale("counts", None, lsb_g=E4_LSB_G, how="the Empatica E4's")
            notes.append("the readings are counts of 1/64 g, the E4's (--full-scale G states another)")
        if opts.bits == 16:
            opts.bits = E4_BITS

        keep = lost_rows(source, values, lambda i: lines[i], lambda j: "xyz"[j], lambda i, j: repr(float(values[i, j])),
                         notes, LOST_SAMPLES)
        values, lines = values[keep], [lines[i] for i in keep.tolist()]

        def locate(i: int, j: int) -> tuple[int, str]:
            return lines[i], "xyz"[j]

        raw = to_counts(values, scale, source, locate, notes=notes) if scale.converts else \
            whole_counts(values, source, locate)
        meta = {"e4.start_unix_s": f"{start:.6f}", "e4.rate_hz": f"{file_rate:g}"}
        return finish(source, "e4", raw, keep, None, None, opts, scale, True, rate, meta,
                      notes + ([info["cut"]] if info["cut"] else []), locate, None, t0=start)
