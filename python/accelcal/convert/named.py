"""``accelcal convert``'s ``table`` format: a CSV or whitespace table with named columns
(phyphox, x-io's NGIMU, a LORD/MicroStrain log, a logger's ``time_ms,accX,accY,accZ``): one
column per accelerometer axis, the unit its name states, an optional time column, rows
whose three readings are all empty (another packet's) skipped."""
from __future__ import annotations

import re

import numpy as np

from .axes import AxisColumn, find_named, mirrored_note, names_unit, px4_export, stated_axes, table_axes
from .common import (Converted, Options, drop_note, exact_time, finish, read_columns, header_cells,
                             is_gyro, whole_counts)
from .packets import host_tick, numeric_stamps, packet_note, packet_size, steady_column
from .stamps import repeated_stamps, shift_slipped, table_time, unrepeated
from .regions import MEANS_HINT, MEANS_RATE_HZ, MEANS_TIME, means_note, rows_are_poses, table_labels
from .time import TIME_COLUMN_RE, datetime_stamps, epoch_like, is_datetime, is_time_name, unit_in_name
from ..io.csvtable import convert_columns, got_text, slow_float
from ..errors import InputError, notes_on_refusal
from .rows import lost_rows, trailer_note, trailer_start
from ..io.textinput import preamble_notes
from ..io.units import UNIT_TEXT, Scale, file_scale, in_file_unit
from ..io.units_counts import to_counts

__all__ = ["stated_time_column", "choose_time_column", "convert_named"]
#: rows whose first non-empty time cell tells a numeric time column from a clock time or a date
TIME_PROBE_ROWS = 100
#: names of a sample counter, not a time
INDEX_NAME_RE = re.compile(r"(?:count|counter|index|idx|sample|samples|sample[ _]?(?:no|nr|number|index)|n|i|#)",
                           re.I)
#: a sample rate in a comment: "data_rate = 2000.0 Hz", "Sample rate: 100 Hz", "ODR: 400Hz"
RATE_COMMENT_RE = re.compile(r"(?:data[ _]?rate|sampl(?:e|ing)[ _]?(?:rate|frequency)|odr|rate)\s*[=:]\s*"
                             r"([0-9]+(?:\.[0-9]*)?)\s*hz\b", re.I)


def table_scale(source: str, pre, option: Scale | None, unit: str | None, axes: list[AxisColumn],
                notes: list[str]) -> Scale | None:
    """The Scale of a table's readings: the unit its axis names state weighed against the
    options and the ``# units:``/``# lsb:`` comments by :func:`units.file_scale` (the names'
    unit taken as the file's ``units``); ``--full-scale`` without ``--units``
    (``option.unit_stated`` False) is read in the names' unit.  ``--units`` stated with another unit
    than the names' overrides them, with a note appended to ``notes`` (a logger's header that
    says ``aX (g)`` over readings it printed in m/s^2).

    Raises
    ------
    InputError
        A contradiction (options or comment against the names), or readings in m/s^2 or g
        with no LSB stated anywhere.
    """
    meta, lines = dict(pre.metadata), dict(pre.metadata_lines)
    cols = ", ".join(c.name for c in axes)
    if unit is not None and option is not None and option.unit_stated and option.units != unit:
        notes.append(f"--units {option.units} overrides the unit the header's columns state, {UNIT_TEXT[unit]} "
                     f"({cols})")
        unit = None
    if unit is None:
        return file_scale(option, meta, lines, source)
    said = meta.get("units")
    if said is not None and said != unit:
        raise InputError(source, f"the comment '# units: {said}' contradicts the unit the header's columns state, "
                         f"{UNIT_TEXT[unit]} ({cols}): state the unit once", row=lines.get("units"))
    option = in_file_unit(option, unit, source)       # --full-scale or --lsb alone: in the names' unit
    sized = any(k in meta for k in ("lsb", "full_scale_g")) or (option is not None and bool(option.lsb or option.lsb_g))
    if unit != "counts" and not sized and (option is None or option.units == unit):
        raise InputError(source, f"the readings are in {UNIT_TEXT[unit]} (the header's {cols}) and no LSB is "
                         "stated: give --full-scale G (or --units {0} --lsb VALUE, or a '# lsb:' comment) to "
                         "make them counts, and --round where they are a calibrated logger's floats on no LSB's "
                         "grid".format(unit), row=pre.header_line)
    meta["units"], lines["units"] = unit, pre.header_line
    return file_scale(option, meta, lines, source,
                      unit_source=f"the unit the header's columns state, {UNIT_TEXT[unit]} ({cols}),")


def present_rows(source: str, matrix: np.ndarray, table, axes: list[AxisColumn], js: list[int],
                 notes: list[str]) -> np.ndarray:
    """The indices of the rows with readings (``matrix``: the three axis columns, NaN where
    empty; ``js``: their indices in the table); rows whose three readings are all empty (a
    LORD log's other packets, or samples lost) are skipped with a note
    (:func:`convert_rows.lost_rows`): a time column keeps the rows after at their stamps;
    without one the rows close up, as another packet's rows have no place of the sensor's.

    Raises
    ------
    InputError
        A row with one or two of its readings empty, naming its line and the column.
    """
    return lost_rows(source, matrix, table.line, lambda j: axes[j].name,
                     lambda i, j: got_text(table.cell(i, js[j])), notes, "other packets' rows, or samples lost")


def stated_time_column(source: str, names: list[str], acc: list[str], stated: str, row: int) -> str:
    """The column ``--time-column`` names (:func:`convert_axes.find_named`).

    Raises
    ------
    InputError
        No such column (listing the header's columns), or one of the accelerometer's.
    """
    found = find_named(source, names, stated, "--time-column", row)
    if found in acc:
        raise InputError(source, f"--time-column {stated!r} is an accelerometer column ({', '.join(acc)})", row=row)
    return found


def sample_index(source: str, name: str, stamps: np.ndarray, rate_hz: float | None, row: int) -> None:
    """Refuse a time column that is a sample counter: a name such as ``count``, ``index``,
    ``sample`` (INDEX_NAME_RE) over the whole numbers 0, 1, 2, ... or 1, 2, 3, ... (PicoQuake's
    ``count``, which read in ms gave its 2 kHz log 1 kHz), unless ``--rate`` states the rate
    (then the column is still taken for time: the caller's)."""
    if rate_hz is not None or not INDEX_NAME_RE.fullmatch(name.strip()) or stamps.size < 2:
        return
    v = np.asarray(stamps, float)
    if v[0] in (0.0, 1.0) and np.all(np.diff(v) == 1.0):
        raise InputError(source, f"the time column {name!r} counts the samples ({v[0]:g}, {v[1]:g}, ...), it does "
                         "not time them: give the sample rate with --rate HZ", row=row, column=name)


def first_cell(table, j: int, rows: np.ndarray) -> tuple[int, str] | None:
    """The first of the first TIME_PROBE_ROWS ``rows`` whose cell in column j is not empty
    or nan: (row index, its text), or None."""
    for i in rows[:TIME_PROBE_ROWS].tolist():
        text = table.cell(i, j).strip()
        if text and text.lower() != "nan":
            return i, text
    return None


def is_number(text: str) -> bool:
    try:
        return np.isfinite(float(text))
    except ValueError:
        return False


def comment_rate(metadata: dict[str, str]) -> tuple[float, str] | None:
    """The sample rate a logger's ``# key: value`` comments state (PicoQuake's ``# Config:
    data_rate = 2000.0 Hz, ...``; ``# Sample rate: 100 Hz``; ``# ODR: 400Hz``), Hz, and the key;
    None when none does."""
    for key, value in metadata.items():
        m = RATE_COMMENT_RE.search(f"{key}: {value}")
        if m and float(m.group(1)) > 0:
            return float(m.group(1)), key
    return None


def choose_time_column(source: str, names: list[str], acc: list[str], table, rows: np.ndarray, rate_stated: bool,
                       header_row: int, notes: list[str], readings: np.ndarray
                       ) -> tuple[str | None, str | None]:
    """The table's time column among the names TIME_COLUMN_RE matches (``Time (s)``,
    ``timestamp_us``, ``Time(hh:mm:ss)``), then those with a time word among others
    (:func:`convert_time.is_broad_time_name`: ``unix_timestamp``, ``epoch``) whose name states a
    unit or whose first stamp is an epoch's (:func:`convert_time.epoch_like`): those whose cells are numbers or full ISO-8601
    date-times (:func:`convert_time.is_datetime`; a clock time ``05:34:44`` or a date alone
    is no time stamp), and of those the first whose name states a
    unit (``Timestamp(Ms)``), else the first.  A note names the column used and those passed
    over when there was a choice.  None when there is no candidate, or (``rate_stated``: the
    rate is given) when none is numeric, with a note.

    Parameters
    ----------
    rows : ndarray of int
        The rows with readings; the first non-empty cell among them tells a column.
    readings : ndarray (n, 3)
        The three axis columns as written: a column chosen whose stamps are a host's packet
        stamps (:func:`convert_packets.packet_size`) gives way to another numeric one that
        times every sample (:func:`convert_packets.steady_column`: the chip's own clock), with a note.

    Raises
    ------
    InputError
        Candidates, none numeric, and no ``--rate``: naming each with the text it holds.
    """
    cands = [n for n in names if n and n not in acc and TIME_COLUMN_RE.fullmatch(n)]
    seen = {n: first_cell(table, names.index(n), rows) for n in names if n and n not in acc and is_time_name(n)}
    # a time word among others (unix_timestamp, epoch): a time column where the name states a unit or the
    # stamps are an epoch's (a gyroscope's stamps are not the accelerometer's)
    cands += [n for n in seen if n not in cands and not is_gyro(n) and
              (unit_in_name(n) is not None or seen[n] is not None and (epoch_like(seen[n][1]) or is_datetime(seen[n][1])))]
    if not cands:
        return None, None
    numeric = [n for n in cands if seen[n] is None or is_number(seen[n][1]) or is_datetime(seen[n][1])]

    def holds(n: str) -> str:
        i, text = seen[n]
        return f"{n!r} (row {table.line(i)}: {text!r})"

    if not numeric:
        said = ", ".join(holds(n) for n in cands)
        if not rate_stated:
            raise InputError(source, f"no time column holds numbers: {said} "
                             f"{'is a clock time or a date' if len(cands) == 1 else 'are clock times or dates'}, not "
                             "time stamps: give the sample rate with --rate HZ, or name a numeric column with "
                             "--time-column NAME", row=header_row)
        notes.append(f"no time column holds numbers ({said}: clock times or dates, not time stamps): t is from "
                     "--rate")
        return None, None
    # a message's own stamp (ROS header.stamp: the sensor's time) before the log's receipt time (%time)
    # (and PX4's timestamp_sample, the sample's time, before its timestamp, the publication's)
    stamp = [n for n in numeric if n.lower().endswith("header.stamp") or n.lower() == "timestamp_sample"]
    chosen = stamp[0] if stamp else next((n for n in numeric if unit_in_name(n) is not None), numeric[0])
    plain = [n for n in numeric if seen[n] is None or not is_datetime(seen[n][1])]
    if chosen in plain and len(plain) > 1:
        stamps = numeric_stamps(table, names, plain, rows)
        k = packet_size(stamps[chosen])
        steady = None if k is None else steady_column({n: v for n, v in stamps.items() if n != chosen}, readings[rows])
        if steady is not None:
            notes.append(f"time column {steady!r} used: {packet_note(chosen, k)}; {steady!r} times every sample "
                         "(--time-column NAME states another)")
            return steady, None if unit_in_name(steady) else host_tick(source, chosen, stamps, steady, notes)
    over = [n for n in cands if n != chosen]
    if over:
        why = [f"{holds(n)}, not a number" if n not in numeric else f"{n!r}, numeric" for n in over]
        notes.append(f"time column {chosen!r} used" + (" (its name states a unit)" if unit_in_name(chosen) else
                                                       " (the message's own stamp)" if stamp else "")
                     + f"; passed over {'; '.join(why)} (--time-column NAME states it)")
    return chosen, None


def dated_stamps(source: str, table, rows: np.ndarray, column: str, j: int, opts: Options,
                 notes: list[str]) -> np.ndarray:
    """The time column ``column`` (index ``j``) of ISO-8601 date-times as int64 ns since the
    epoch (:func:`convert_time.datetime_stamps`; 0 in the rows not read), and ``opts.time_unit``
    set to ns.

    Raises
    ------
    InputError
        ``--time-unit`` stated (a date-time carries its unit), or a bad date-time.
    """
    if opts.time_unit != "auto":
        raise InputError(source, f"--time-unit {opts.time_unit}: the time column {column!r} holds date-times, which "
                         "carry their unit", column=column)
    stamps = np.zeros(table.n, dtype=np.int64)
    stamps[rows] = datetime_stamps([table.cell(i, j) for i in rows.tolist()], source,
                                   [table.line(i) for i in rows.tolist()], column, notes)
    opts.time_unit = "ns"
    return stamps


def convert_named(source: str, data: bytes, pre, opts: Options) -> Converted:
    """A table with named columns: the three accelerometer axes (:func:`table_axes`), their
    unit (:func:`table_scale`), an optional time column (else ``--rate``); rows without
    readings skipped (:func:`present_rows`).  A refusal carries the notes made before it
    (:func:`errors.notes_on_refusal`)."""
    notes: list[str] = []
    with notes_on_refusal(lambda: preamble_notes(pre) + notes):
        return named_table(source, data, pre, opts, notes)


def named_table(source: str, data: bytes, pre, opts: Options, notes: list[str]) -> Converted:
    """:func:`convert_named`, appending its notes to ``notes`` as it goes."""
    names = [c.strip() for c in header_cells(pre.header)]
    axes = stated_axes(source, names, opts.columns, pre.header_line) if opts.columns is not None else \
        table_axes(source, names, pre.header_line, notes)
    notes += mirrored_note(axes) if opts.columns is not None else []
    acc = [c.name for c in axes]
    scale = table_scale(source, pre, opts.scale, names_unit(source, axes, pre.header_line), axes, notes)
    if opts.time_column is not None:
        time_column = stated_time_column(source, names, acc, opts.time_column, pre.header_line)
    want = {a: "ref" for a in acc}
    names, values, table = read_columns(source, data, pre, want)
    js = [names.index(a) for a in acc]
    readings = np.column_stack([values[a] for a in acc])
    at = len(notes)               # where the note on rows without readings is (:func:`trailer_note` may change it)
    rows = present_rows(source, readings, table, axes, js, notes)
    said = len(notes) - at
    if rows.size == 0:
        raise InputError(source, f"no row has readings in {', '.join(acc)}", row=pre.header_line)
    if opts.time_column is None:
        time_column, tick = choose_time_column(source, names, acc, table, rows, opts.rate_hz is not None,
                                               pre.header_line, notes, readings)
        opts.time_unit = tick if tick is not None and opts.time_unit == "auto" else opts.time_unit
    labelled, means = None, False
    if time_column is None and opts.rate_hz is None and comment_rate(pre.metadata) is None:
        # (no time: the rows' labels are read here; a row a pose of its own needs none)
        free = [c for c in names if c and c not in want and not is_gyro(c)]
        labelled = table_labels(source, names, free, table, rows.tolist(), opts.regions is not None, opts.stated_f,
                                notes)
        means = rows_are_poses(labelled[1], None if labelled[2] is None else labelled[2][0])
    if means:
        opts.rate_hz = MEANS_RATE_HZ
        notes.append(means_note(labelled[0], rows.size))
    elif time_column is None and opts.rate_hz is None:
        stated = comment_rate(pre.metadata)
        if stated is None:
            named = [n for n in names if n and n not in acc and is_time_name(n) and not is_gyro(n)]
            hint = f"; {', '.join(map(repr, named))} has a time's name but neither a unit in it nor an epoch's " \
                "stamps: --time-column NAME (and --time-unit) reads it" if named else ""
            raise InputError(source, "the table has no time column (t, time, timestamp, 'Time (s)', time_ms, "
                             "unix_timestamp, ...): give the sample rate with --rate HZ (or name its column with "
                             f"--time-column NAME; {MEANS_HINT}){hint}", row=pre.header_line)
        opts.rate_hz, key = stated
        notes.append(f"no time column: the rate is the {opts.rate_hz:g} Hz the file's comment '# {key}' states "
                     "(--rate HZ states another)")
    if time_column is not None and opts.time_unit == "auto" and px4_export(source, axes) and \
            time_column.lower() in ("timestamp", "timestamp_sample"):
        opts.time_unit = "us"
        notes.append(f"{time_column} read in us, PX4's unit (--time-unit states another)")
    if time_column is None and opts.time_unit != "auto":
        raise InputError(source, "--time-unit: the table has no time column (--rate states its rate)")
    stamps = None
    if time_column is not None:
        jt = names.index(time_column)
        want[time_column] = "ref"
        probe = first_cell(table, jt, rows)
        if probe is not None and is_datetime(probe[1]):
            stamps = dated_stamps(source, table, rows, time_column, jt, opts, notes)
        else:
            end = trailer_start(readings)
            trailer = trailer_note(end, table.n, int(rows[-1]), lambda i: table.cell(i, jt), table.line)
            if trailer is not None:       # rows after the last reading whose time cells are no stamps of it
                lost: list[str] = []
                present_rows(source, readings[:end], table, axes, js, lost)
                notes[at:at + said] = lost + [trailer]
            numbers, err = convert_columns(table, {time_column: (jt, "ref")})
            if err is not None and (trailer is None or err[0] < end):
                raise InputError(source, err[2], row=table.line(err[0]), column=time_column)
            stamps = numbers[time_column] if err is None else \
                np.concatenate([slow_float(table.strings(jt)[:end], True), np.full(table.n - end, np.nan)])
            stamps = exact_time(stamps, lambda: table.strings(jt), rows)   # an epoch in ns: int64
        sample_index(source, time_column, stamps[rows], opts.rate_hz, pre.header_line)
        rows = unrepeated(rows, stamps, readings, notes)
        if opts.repeated_stamps == "shift":
            stamps = shift_slipped(stamps, rows, notes)
        if opts.repeated_stamps != "refuse":
            rows = repeated_stamps(stamps, rows, notes, opts.repeated_stamps)
    matrix = readings[rows]

    def locate(i: int, j: int) -> tuple[int, str]:
        return table.line(int(rows[i])), acc[j]

    converts = scale is not None and scale.converts
    raw = to_counts(matrix, scale, source, locate, notes=notes) if converts else whole_counts(matrix, source, locate)
    others = [] if stamps is None else \
        [n for n in numeric_stamps(table, names, [n for n in names if n and n not in acc and n != time_column and
                                                 is_time_name(n) and not is_gyro(n)], rows)]
    t = None if stamps is None else table_time(source, stamps, table, rows, time_column, jt, others)
    used = set(want)
    dropped = [c for c in names if c and c not in used and is_gyro(c)]
    free = [c for c in names if c and c not in used and c not in dropped]
    label_column, part, kept, hint = labelled or table_labels(source, names, free, table, rows.tolist(),
                                                              opts.regions is not None, opts.stated_f, notes)
    ignored = [c for c in free if c != label_column]
    meta = {"table.columns": ", ".join(acc + ([time_column] if time_column else []))}
    if means:
        meta["table.time"] = MEANS_TIME
    return finish(source, "table", raw, np.arange(rows.size), t, part, opts, scale, converts or bool(np.any(raw < 0)),
                  opts.rate_hz, meta,
                  preamble_notes(pre) + drop_note(dropped, ignored) + notes +
                  ([table.cut_note] if table.cut_note else []),
                  locate, None, kept=kept, time_column=time_column, label_hint=hint)
