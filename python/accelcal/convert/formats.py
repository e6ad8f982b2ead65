"""``accelcal convert``: the data contract's recording (and a nominal device) from the
files other tools write.

Formats (``detect_format`` tells them from the first line that is not a comment):

- ``imu_tk``: imu_tk's text, no header, whitespace-separated ``t ax ay az`` (s, counts),
  read by :func:`accelcal.convert.xsens.load_xsens`.
- ``imucal``: imucal's CSV, columns ``acc_x, acc_y, acc_z`` (m/s^2 or g with a stated
  LSB, or counts), no time column (``--rate``; an index column ``n_samples`` or
  ``samples`` gives each row's sample number), poses from a JSON of ``{name: {start,
  end}}`` sample ranges (end excluded) or from a ``part`` column.
- ``mpu6050``: the MPU-6050 logger's CSV: ``key,value`` lines (``Fs,100`` the rate), then
  ``ax,ay,az,gx,gy,gz`` in signed counts, no time column.
- ``csv``: a recording per the contract (or any form ``read_recording`` takes: compressed,
  whitespace, physical units), rewritten as plain CSV in counts.
- ``log``: a serial monitor's capture: lines of three numbers among the logger's text
  (prompts, banners), no header, no time column (``--rate``); with ``blocks`` each run of
  readings between text lines is a pose (:mod:`accelcal.convert.log`).
- ``table``: a CSV or whitespace table with named columns (phyphox, x-io's NGIMU, a
  LORD/MicroStrain log, a logger's ``time_ms,accX,accY,accZ``): one column per axis named
  acc/accel/accelerometer/acceleration (optionally scaled/raw) and x, y or z, with an
  optional unit (``Accelerometer X (g)``, ``AccX [g]``, ``acc_x_mps2``) that states the
  readings' unit; the axis letter alone with a unit of acceleration (``x (g)``), or bare
  ``x, y, z`` beside nothing but a time column; ``--columns X,Y,Z`` names the three
  otherwise; an optional time column (``t``, ``Time (s)``, ``timestamp_us``), else
  ``--rate``.  Rows whose three readings are all empty (another packet's) are skipped.
  Told last, after the formats above.  A line of free text before the header (a title) is
  passed over with a note (:func:`textinput.table_preamble`).  Rows without a header of four
  cells whose first is a time stamp (an ISO-8601 date-time, or numbers above 2^24 that never
  decrease: a Garmin watch's, an Axivity AX3's export) are read as ``t,x,y,z``, with a note; of
  seven (an Axivity AX6's: the time, the accelerometer's x, y, z, the gyroscope's) the first three
  numbers are the accelerometer's, the rest ignored; another count is left to ``--columns c2,c3,c4``
  (cell k is ``ck``) (:mod:`accelcal.convert.headerless`).
- ``e4``: an Empatica E4's ``ACC.csv``: row 1 the session's start (unix s) and row 2 the
  sample rate, each repeated in the three columns, then ``x,y,z`` in counts of 1/64 g
  (:mod:`accelcal.convert.e4`).

On every path a logger's leading ``0, 0, 0`` placeholder is left out, and so is a row whose
readings are all missing (a sample lost; a table's other packet), each with a note
(:mod:`accelcal.convert.rows`); a lost sample's place is kept (its time, from the stamps or
the rate), a gap the estimators fill on their time grid.  A table's rows after its last reading
whose time cells run back or hold text (a spreadsheet's scratch below the data) are no samples:
left out with a note that says so (:func:`convert_rows.trailer_note`).  Gyroscope columns are dropped (one
note).  Pose regions named ``x_p, x_a, y_p, y_a, z_p,
z_a`` (imucal's: that axis pointing up, or down) can state the reference specific force
(``stated_f``): +-g along that axis, making a known-pose (``full``) calibration possible.
Regions whose name ends in ``_rot`` are motions, not poses.
"""
from __future__ import annotations

import re
from functools import cache, partial
from typing import Any, Callable

import numpy as np

from .common import (INDEX_COLUMNS, NUMBER_RE, Converted, Options, drop_note, exact_time, find_column,
                             finish, header_cells, is_gyro, read_columns, whole_counts)
from .e4 import convert_e4, is_e4
from .headerless import HEADERLESS_NAMES, axes_known, stamp_rule, timed_rows
from .log import is_log, read_log
from .mat import convert_mat, is_mat
from .axes import BARE_AXES, axis_column, axis_triples, columns_hint
from .named import convert_named
from .regions import (MEANS_HINT, MEANS_RATE_HZ, MEANS_TIME, POSE_DIRECTIONS, means_note, read_regions,
                              rows_are_poses, table_labels)
from .rows import LOST_SAMPLES, lost_rows
from .time import is_datetime, is_time_name, unit_in_name
from ..errors import InputError, notes_on_refusal
from ..readings.held import held_runs, held_share
from ..io.recording import read_recording
from ..io.parquet import is_parquet
from ..io.textinput import (CELL_NUMBER_RE, is_whitespace_header, preamble_notes, read_preamble, read_text_bytes,
                        table_preamble)
from ..io.units import Scale, file_scale, in_file_unit
from ..io.units_counts import to_counts
from .xsens import load_xsens
from .stream import convert_csv_chunked
from ..io.chunks import BLOCK_BYTES, Fallback

__all__ = ["FORMATS", "POSE_DIRECTIONS", "Converted", "detect_format", "convert_file", "read_regions", "axis_column",
           "unit_in_name"]

FORMATS = ("auto", "imu_tk", "imucal", "mpu6050", "csv", "log", "table", "mat", "e4")
ACC = {"imucal": ("acc_x", "acc_y", "acc_z"), "mpu6050": ("ax", "ay", "az")}


# ---- detection ---------------------------------------------------------------------

def detect_format(path: Any, data: bytes | None = None) -> str:
    """The format of a file (its text ``data`` when already read), from its first line that
    is not a comment.  Without a header: four whitespace-separated numbers a row are imu_tk's
    text, three a line (whitespace or commas) a log, four whose first is a time stamp a table
    of ``t,x,y,z``, seven ``t,ax,ay,az`` and three ignored (:func:`convert_headerless.timed_rows`).

    Raises
    ------
    InputError
        Unreadable, empty, or none of the formats, quoting the line as the file holds it;
        rows of numbers (the first maybe a date-time) without a header say so, how many a
        row, and the header line to add.
    """
    source, data = read_text_bytes(path) if data is None else (str(path), data)
    pre = table_preamble(data)
    return told_format(path, source, data, pre, cache(partial(timed_rows, data, pre)))


def told_format(path: Any, source: str, data: bytes, pre, timed: Callable[[], Any]) -> str:
    """:func:`detect_format` of a file whose text ``data`` and preamble ``pre``
    (:func:`textinput.table_preamble`) are read; ``timed()`` is its
    :func:`convert_headerless.timed_rows` (called where the header may be rows, and cached by
    the caller: ``convert_file`` reads a table by it)."""
    if pre.header is None:
        raise InputError(source, "the file is empty (nothing but comments and blank lines)")
    cells = header_cells(pre.header)
    low = {c.strip().lower() for c in cells}
    if pre.header_from_comment and is_log(data):
        return "log"              # a comment naming a log's three columns ('# x y z') before its readings
    if "t" in cells and "raw_0" in cells:
        return "csv"
    if any(is_time_name(c) for c in cells) and any(axis_column(c) for c in cells):
        # a time column beside the axes: neither imucal's nor the MPU-6050 logger's (they have none)
        return "table"
    if set(ACC["imucal"]) <= low:
        return "imucal"
    if set(ACC["mpu6050"]) <= low or cells[0].strip().lower() == "fs":
        return "mpu6050"
    spaced = is_whitespace_header(pre.header)
    if spaced and len(cells) == 4 and (all(NUMBER_RE.fullmatch(c) for c in cells) or pre.header_from_comment):
        return "imu_tk"           # (under a comment that names its four columns)
    if is_e4(data):
        return "e4"
    if is_log(data):
        return "log"
    if any(axis_column(c) for c in cells) or set(BARE_AXES) <= low or timed() is not None and axes_known(len(cells)):
        return "table"            # (rows without a header whose first cell is a time stamp: t,x,y,z; t and 6)
    line = file_line(path, pre.header_line, pre.header)
    if len(cells) > 1 and all(CELL_NUMBER_RE.fullmatch(c.strip()) or is_datetime(c) for c in cells):
        dated = " (the first a date-time)" if is_datetime(cells[0]) else ""
        hints = ("imu_tk's text needs 4 (t ax ay az); " if spaced else "") + \
            ("for three readings a line give --format log --rate HZ; " if spaced or len(cells) == 3 else "") + \
            (f"{stamp_rule(len(cells))}: --columns c2,c3,c4 reads cells 2-4 as its x, y, z (cell k is ck, the "
             "first the time); " if timed() is not None else
             f"{stamp_rule(len(cells))}; " if len(cells) == len(HEADERLESS_NAMES) and not spaced or
             len(cells) > len(HEADERLESS_NAMES) and is_datetime(cells[0]) else "")
        raise InputError(source, f"{len(cells)} {'whitespace-separated ' if spaced else ''}numbers a row{dated} and no "
                         f"header ({line[:60]!r}): {hints}for other layouts add a header line naming the columns "
                         f"({header_example(cells, spaced)}; a time column t, time or timestamp, else --rate HZ)", row=pre.header_line)
    if axis_triples(cells):
        raise InputError(source, f"no column of this header ({line[:60]!r}) says it is an accelerometer's: if three "
                         f"of them are, name them with {columns_hint(cells)}", row=pre.header_line)
    raise InputError(source, f"cannot tell the format from this line ({line[:60]!r}): expected a "
                     "recording CSV (t, raw_0, ...), imucal's acc_x/acc_y/acc_z, the MPU-6050 log (Fs,... "
                     "then ax,ay,az,...), imu_tk's 't ax ay az' text, a monitor's log (lines of three "
                     "numbers among text) or a table with accelerometer columns (accX, 'Acceleration y "
                     "(m/s^2)', 'x (g)', ...; --columns X,Y,Z names them); give --format", row=pre.header_line)


def file_line(path: Any, line: int, fallback: str) -> str:
    """Line ``line`` of the file as it holds it (a semicolon-separated export's own ``;``,
    which :func:`textinput.semicolons_to_commas` made commas), for quoting; ``fallback``
    where the file cannot be read again."""
    try:
        text = read_text_bytes(path, semicolons=False)[1].split(b"\n")
    except (InputError, OSError, TypeError):
        return fallback
    return text[line - 1].decode("utf-8") if 0 < line <= len(text) else fallback


def header_example(cells: list[str], spaced: bool) -> str:
    """A header line naming a row of ``cells`` (numbers, the first maybe a date-time) as
    accelcal reads them: ``t,ax,ay,az,gx,gy,gz`` and ``extra`` beyond (blanks between the
    names of whitespace text)."""
    names = (["t"] if is_datetime(cells[0]) or len(cells) in (4, 7) else []) + ["ax", "ay", "az"]
    names += ["gx", "gy", "gz"][:max(0, len(cells) - len(names))]
    names += [f"extra{k + 1}" for k in range(len(cells) - len(names))]
    return (" " if spaced else ",").join(names[:len(cells)])


# ---- the formats -----------------------------------------------------------------------

def convert_table(source: str, data: bytes, pre, fmt: str, opts: Options, metadata: dict[str, str],
                  label: str | None = None) -> Converted:
    """imucal's CSV or the MPU-6050 log's rows (after its key,value lines); ``label``: the format
    the recording's source_format names (default ``fmt``)."""
    label = label or fmt
    names = [c.strip() for c in header_cells(pre.header)]
    acc = [find_column(names, a) for a in ACC[fmt]]
    if None in acc:
        missing = ACC[fmt][acc.index(None)]
        raise InputError(source, f"the header has no {missing} column (expected {', '.join(ACC[fmt])})",
                         row=pre.header_line)
    scale = file_scale(opts.scale, pre.metadata, pre.metadata_lines, source)
    converts = scale is not None and scale.converts
    want = {a: ("t" if converts else "raw") for a in acc}
    index_column = next((n for n in names if n.lower() in INDEX_COLUMNS), None)
    if index_column:
        want[index_column] = "raw"
    part_column = find_column(names, "part") if opts.regions is None else None
    if part_column:
        want[part_column] = "text"
    names, values, table = read_columns(source, data, pre, want)
    matrix = np.column_stack([values[a] for a in acc])

    def locate(i: int, j: int) -> tuple[int, str]:
        return table.line(i), acc[j]

    shifted: list[str] = []
    labels: list[str] = []
    with notes_on_refusal(lambda: preamble_notes(pre) + labels + shifted):
        raw = to_counts(matrix, scale, source, locate, notes=shifted) if converts else matrix.astype(np.int64)
        used = set(want)
        dropped = [c for c in names if c and c not in used and is_gyro(c)]
        free = [c for c in names if c and c not in used and c not in dropped]
        label_column, part, kept, hint = (part_column, values[part_column], None, None) if part_column else \
            table_labels(source, names, free, table, list(range(table.n)), opts.regions is not None, opts.stated_f,
                         labels)
        rate = opts.rate_hz
        if rate is None and rows_are_poses(part, None if kept is None else kept[0]):
            rate = MEANS_RATE_HZ           # pose means carry no time: t counts the rows
            labels.append(means_note(label_column, raw.shape[0]))
            metadata = {**metadata, "table.time": MEANS_TIME}
        elif rate is None:
            timed = next((n for n in names if is_time_name(n)), None)
            hint = f" (--format table reads the time column {timed!r})" if timed else ""
            raise InputError(source, f"{label} files have no time column: give the sample rate with --rate HZ{hint} "
                             f"({MEANS_HINT})")
    index = values[index_column] if index_column else np.arange(raw.shape[0])
    ignored = [c for c in free if c != label_column]
    if label != fmt:
        metadata = {**metadata, "table.columns": ", ".join(acc)}
    return finish(source, label, raw, index, None, part, opts, scale, True, rate, metadata,
                  preamble_notes(pre) + drop_note(dropped, ignored) + labels + shifted +
                  ([table.cut_note] if table.cut_note else []), locate,
                  index_column, kept=kept, label_hint=hint)


def mpu6050_preamble(source: str, data: bytes, pre) -> tuple[Any, dict[str, str], float | None]:
    """The logger's ``key,value`` lines before the header ``ax,ay,az,...``: (the header's
    preamble, metadata ``mpu6050.<key>``, the rate from ``Fs``)."""
    meta, rate = {}, None
    while pre.header is not None and find_column(header_cells(pre.header), "ax") is None:
        cells = [c.strip() for c in pre.header.split(",")]
        if len(cells) != 2 or not cells[0]:
            raise InputError(source, f"expected a 'key,value' line (such as 'Fs,100') or the header 'ax,ay,az,...', "
                             f"got {pre.header[:60]!r}", row=pre.header_line)
        key = re.sub(r"[^A-Za-z0-9_.-]+", "_", cells[0].lower()).strip("_") or "key"
        meta[f"mpu6050.{key}"] = cells[1]
        if key == "fs":
            try:
                rate = float(cells[1])
            except ValueError:
                rate = float("nan")
            if not (np.isfinite(rate) and rate > 0):
                raise InputError(source, f"Fs {cells[1]!r}: expected a sample rate in Hz > 0", row=pre.header_line)
        rest = read_preamble(data[pre.pos:])
        rest.header_line += pre.header_line
        rest.header_pos += pre.pos
        rest.pos += pre.pos
        rest.metadata, rest.metadata_lines = pre.metadata, pre.metadata_lines
        pre = rest
    if pre.header is None:
        raise InputError(source, "no header 'ax,ay,az,...' after the logger's key,value lines")
    return pre, meta, rate


def convert_log(source: str, data: bytes, opts: Options, blocks: bool) -> Converted:
    """A serial monitor's capture (:mod:`accelcal.convert.log`).  A refusal carries the notes made
    before it (:func:`errors.notes_on_refusal`)."""
    if is_e4(data):
        raise InputError(source, "rows 1-2 are one value repeated, a start time and a rate, as an Empatica E4's "
                         "export begins: read it with --format e4 (or auto), or remove the two rows and give --rate HZ",
                         row=1)
    values, lines, block, info = read_log(source, data)
    notes = [f"{info['text_lines']} line(s) of text (the first: {info['first_text']!r}) split the readings into "
             f"{info['blocks']} block(s)" + ("; each block is a pose" if blocks else
                                            "; --blocks labels each as a pose")] if info["text_lines"] else []
    notes += [info["cut"]] if info["cut"] else []       # a last line cut short, left out
    with notes_on_refusal(lambda: notes):
        keep = lost_rows(source, values, lambda i: lines[i], lambda j: f"field {j + 1}",
                         lambda i, j: repr(float(values[i, j])), notes, LOST_SAMPLES)
        values, lines, block = values[keep], [lines[i] for i in keep.tolist()], [block[i] for i in keep.tolist()]

        def locate(i: int, j: int) -> tuple[int, str]:
            return lines[i], f"field {j + 1}"

        scale = file_scale(opts.scale, {}, {}, source)      # (--round over counts refused)
        raw = to_counts(values, scale, source, locate, notes=notes) if scale is not None and scale.converts else \
            whole_counts(values, source, locate)
        if opts.rate_hz is None:
            raise InputError(source, "log files (lines of three numbers, no header) have no time column: give the "
                             "sample rate with --rate HZ")
        if blocks and opts.regions is not None:
            raise InputError(source, "--blocks and --regions both label the poses: give one")
        share = held_share(held_runs(raw)[1], raw.shape[0])    # (the note on held readings is finish's)
        meta = {"log.text_lines": str(info["text_lines"]), "log.blocks": str(info["blocks"]),
                "log.held_share": f"{share:.4f}"}
        return finish(source, "log", raw, keep, None, block if blocks else None, opts, scale,
                      bool(np.any(raw < 0)), opts.rate_hz, meta, notes, locate, None)


def convert_file(path: Any, fmt: str = "auto", *, scale: Scale | None = None, rate_hz: float | None = None,
                 regions: Any = None, stated_f: bool = False, gravity_mps2: float | None = None,
                 bits: int = 16, blocks: bool = False, time_unit: str = "auto", variable: str | None = None,
                 time_column: str | None = None, repeated_stamps: str = "refuse",
                 columns: str | None = None, stream: bool = False, block_bytes: int = BLOCK_BYTES,
                 progress: Callable[[Any, str], Any] | None = None) -> Converted:
    """Read another tool's file as a contract recording of a triad.

    Parameters
    ----------
    path : str or os.PathLike
        The file (compressed or not: gzip, bzip2, xz, zstd, a zip of one file).
    fmt : {"auto", "imu_tk", "imucal", "mpu6050", "csv", "log", "table", "mat", "e4"}
        ``auto`` tells it from the first line (:func:`detect_format`; a log from its lines).
    scale : units.Scale, optional
        The readings' unit and LSB (``--units``/``--lsb``/``--full-scale``), or the
        file's ``# units:``/``# lsb:`` comments, else counts; stated by both, they must
        agree (:func:`units.file_scale`).  A table's axis names may state the unit
        (``Accelerometer X (g)``): the same rule, the names taken as the file's unit; a
        ``--full-scale`` or ``--lsb`` without ``--units`` (``scale.unit_stated`` False) is read
        in the names' unit, a ``--units`` that names another overrides them (a note).
    rate_hz : float, optional
        Sample rate, Hz, for files without a time column (imucal, log, a table without one;
        the MPU-6050 log's ``Fs`` otherwise); with a time column (csv, table), the device's
        rate where t's steps do not give it (a host's time stamps).  A table of pose means
        (every row a labelled pose of its own: :func:`convert_regions.rows_are_poses`) needs
        none: its means carry no time, and t counts its rows at MEANS_RATE_HZ (a note says so).
    regions : path, optional
        JSON ``{name: {"start": s, "end": e}}`` of sample numbers (end excluded): pose labels.
    stated_f : bool
        Give each pose named ``x_p ... z_a`` the reference f = +-g (m/s^2) along its axis.
    gravity_mps2 : float, optional
        g for the stated f and the device (default 9.80665; imu_tk: 9.81744).
    bits : int
        The ADC's bits: the device's range, and the readings must fit it.
    blocks : bool
        log: each block of readings between text lines is a pose (``block_1``, ...).
    time_unit : str
        The time column's unit (csv, imu_tk, table): s, ms, us, ns, or a tick of a chip's clock,
        a number of one (``25us``; :func:`convert_time.time_factor`).  ``auto``: the unit its name states, else
        seconds, except time stamps whose steps in seconds would give under
        MIN_PLAUSIBLE_HZ (then the smallest of ms, us, ns that gives more; a note says so).
        Whole-number stamps past float64's 2**53 (an epoch in ns; csv, table) are read as
        integers, their steps exactly.  The recording's t is written in seconds; the device's
        rate is from t's median step, or where its mean step disagrees (bursts of a host's stamps)
        from the samples between the bursts' stamps (:func:`convert_time.burst_rate`; a note).
    variable : str, optional
        A MATLAB file's array of readings (:mod:`accelcal.convert.mat`), where it holds
        more than one of 3 or 4 columns.
    time_column : str, optional
        A table's time column (its stamps in the unit ``time_unit`` gives).  Default: of the
        names TIME_COLUMN_RE matches, then those with a time word among others (``unix_timestamp``,
        ``epoch``) that state a unit or hold an epoch's stamps, those whose cells are numbers (a clock time or a date
        is no time stamp), the first whose name states a unit, else the first; a note names
        the one used and those passed over.  A host's packet stamps (most rows repeat the stamp
        before: :func:`convert_packets.packet_size`) give way to another numeric one that times
        every sample, its unit, where its name states none, measured against them.
    repeated_stamps : {"refuse", "drop", "shift"}
        A table's rows whose time stamp repeats the row before's with other readings (a watch
        that stamps two samples with one stamp: 93 of a Garmin export's 10,000 rows): refused,
        the message counting them and those after a step of two median steps
        (:func:`convert_stamps.slipped_stamps`: the stamps slipped a place late and caught up;
        the samples keep their grid, and ``drop`` loses one each), or left out with a note
        (``drop``); ``shift`` moves each stamp that slipped back one step
        (:func:`convert_stamps.shift_slipped`: every sample kept) and leaves out the other
        repeats as ``drop`` does.  Rows that repeat the stamp and the readings are left out
        either way.
    stream : bool
        A recording CSV (``csv``) in two passes over chunks of ``block_bytes`` of text, never
        whole (:mod:`accelcal.convert.stream`; the result's ``write`` reads it again), where that
        path takes the file; else, and by default, read whole.
    block_bytes : int
        The chunks' bytes of text (``stream``).
    progress : callable, optional
        ``progress(total, unit)`` -> a progress bar for each pass (``stream``).

    Returns
    -------
    Converted

    Raises
    ------
    InputError
        One line naming the file and the row and column (or JSON field) at fault.
    """
    if fmt in ("auto", "mat") and is_mat(path):
        if time_column is not None or columns is not None:
            raise InputError(str(path), "--time-column and --columns name a table's columns: a MATLAB file's array is "
                             "named by --variable NAME (its time column the first of 4), or --variable X,Y,Z (T,X,Y,Z) "
                             "for one vector per channel")
        if regions is not None or stated_f or blocks:
            raise InputError(str(path), "a MATLAB file's poses are not labelled: --regions, --stated-f and --blocks "
                             "do not apply")
        return convert_mat(str(path), path, Options(scale, rate_hz, None, None, False, gravity_mps2, bits, time_unit),
                           variable)
    if fmt == "mat":
        raise InputError(str(path), "--format mat: the file does not begin with a MATLAB header ('MATLAB 5.0 MAT-file' "
                         "or 'MATLAB 7.3 MAT-file')")
    if variable is not None:
        raise InputError(str(path), "--variable names an array of a MATLAB file")
    if is_parquet(path):
        raise InputError(str(path), "a .parquet file is read as a contract recording, which every command takes as it "
                         "is: convert reads other tools' files (its output may be .parquet)")
    if stream and fmt in ("auto", "csv") and columns is None and time_column is None and \
            repeated_stamps == "refuse" and not blocks:
        opts = Options(scale, rate_hz, None, None, stated_f, gravity_mps2, bits, time_unit)
        try:
            if regions is not None:
                opts.regions, opts.regions_source = read_regions(regions), str(regions)
            return convert_csv_chunked(path, opts, scale, block_bytes, progress)
        except (Fallback, InputError):
            pass    # the whole-file command: the same output, or its refusal with its notes in its order
    source, data = read_text_bytes(path)
    pre = table_preamble(data)
    timed = cache(partial(timed_rows, data, pre))     # (detection and a table's reading: computed once)
    told = fmt == "auto"
    if told:
        fmt = "table" if columns is not None else told_format(source, source, data, pre, timed)
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}")
    if repeated_stamps != "refuse" and fmt != "table":
        raise InputError(source, f"--repeated-stamps applies to a table's time column (--format table): this file is "
                         f"told as {fmt}")
    for option, given, what in (("--time-column", time_column, "time column"),
                                ("--columns", columns, "accelerometer columns")):
        if given is not None and fmt != "table":
            raise InputError(source, f"{option} names a table's {what} (--format table): this file is told as {fmt}")
    opts = Options(scale, rate_hz, None, None, stated_f, gravity_mps2, bits, time_unit, time_column, repeated_stamps,
                   columns)
    if regions is not None:
        opts.regions, opts.regions_source = read_regions(regions), str(regions)
    if blocks and fmt != "log":
        raise InputError(source, f"--blocks: {fmt} files have no blocks (it labels a log's poses)")
    if fmt == "log":
        return convert_log(source, data, opts, blocks)
    if time_unit != "auto" and fmt not in ("imu_tk", "csv", "table"):
        raise InputError(source, f"--time-unit: {fmt} files have no time column (--rate states their rate)")
    if fmt == "e4":
        if not is_e4(data):
            raise InputError(source, "--format e4: rows 1-2 are not an Empatica E4's start time and sample rate "
                             "(each one value repeated in three columns, the first a unix time)", row=1)
        return convert_e4(source, data, opts)
    if fmt in ("imu_tk", "csv"):
        if rate_hz is not None and fmt == "imu_tk":
            raise InputError(source, "--rate: the file was read as imu_tk's text (4 numbers a row and no header: t ax "
                             "ay az), whose time column gives the rate; for another layout add a header line naming "
                             "the columns (ax ay az ...)" if told else
                             "--rate: imu_tk files have a time column and their own rate")
        if fmt == "imu_tk" and scale is not None and scale.converts:
            raise InputError(source, "imu_tk's readings are counts: --units mps2|g and --lsb do not apply")
        if fmt == "imu_tk":
            file_scale(scale, {}, {}, source)                   # (--round over counts refused)
            device, rec = load_xsens(path)
            device = device if scale is None or scale.lsb_g is None else None  # a stated full scale: the nominal device from it
        else:
            device, rec = None, read_recording(path, scale=scale)   # (its refusals carry its notes)
            scale = in_file_unit(scale, rec.metadata.get("source_units"), source)  # as read_recording took it
        with notes_on_refusal(lambda: list(rec.notes)):
            if rec.n_channels != 3:
                raise InputError(source, f"{rec.n_channels} raw channels: convert makes a triad's recording (3)")
            kept = (rec.pose, rec.f) if fmt == "csv" and opts.regions is None else None
            if kept is not None and stated_f:
                raise InputError(source, "--stated-f: a recording's poses are its own; give --regions to name them")
            t = rec.t if fmt != "csv" else exact_time(      # an epoch in ns, which float64 rounds, as int64
                rec.t, lambda: read_columns(source, data, read_preamble(data), {"t": "text"})[1]["t"])
        signed = fmt == "csv" and bool(np.any(rec.raw < 0))
        return finish(source, fmt, rec.raw, np.arange(rec.n_samples), t, None, opts, scale, signed, None,
                      dict(rec.metadata), list(rec.notes), lambda i, j: (rec.line(i), f"raw_{j}"), None, device, kept,
                      time_column="t" if fmt == "csv" else None)
    if pre.header is None:
        raise InputError(source, "the file is empty (nothing but comments and blank lines)")
    if fmt == "table":
        return convert_named(source, data, timed() or pre, opts)
    meta: dict[str, str] = {}
    with notes_on_refusal(lambda: preamble_notes(pre)):     # a title passed over, before a refusal
        label = fmt
        if fmt == "mpu6050":
            pre, meta, fs = mpu6050_preamble(source, data, pre)
            opts.rate_hz = rate_hz if rate_hz is not None else fs
            # the logger's key,value lines (Fs, ...) say it is the MPU-6050 logger's; a bare header ax,ay,az,...
            # (such as a headerless file's, as the refusal suggests) says only that it is a table
            label = "mpu6050" if meta or not told else "table"
        return convert_table(source, data, pre, fmt, opts, meta, label)
