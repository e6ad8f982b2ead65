"""Recordings: raw channel readings over time plus optional reference columns,
read from and written to CSV per the data contract.  The in-memory type, ``Recording``, and
``recording_from_arrays`` live in :mod:`accelcal.io.recording_type` and are re-exported here.

Reading goes through pyarrow's CSV reader when every row is plain (the common
case).  Anything else -- quotes, '123.0' as an integer, a bad cell -- is read by
the numpy/Python path: the data section tokenised once with numpy (cell
boundaries from the positions of ',' and '\\n'), numeric columns converted as
fixed-width byte matrices, and a column re-scanned cell by cell in Python only
when it holds something those do not handle (spaces, 'nan', a bad cell); that
scan also produces the error message that names the row and column.
"""

from __future__ import annotations

import csv
import math
from typing import Any

import numpy as np

from .csvformat import INT, REPR, TEXT, csv_cell, csv_rows
from .csvtable import (FLOAT_RE, META_KEY_RE, RAW_RE, VECTOR_COLUMNS, ByteTable, ListTable, classify_columns,
                       convert_columns, cut_short_end, data_end, fast_columns, make_table, quote_cell, split_header)
from ..errors import InputError, atomic_write, notes_on_refusal
from .chunks import Fallback, read_chunked, reader_checks
from .parquet import is_parquet, read_parquet_recording, write_parquet_columns, write_parquet_recording
from .recording_checks import check_core_input, check_for_device, repeated_rows, repeats_note
from .recording_type import Recording, check_content, recording_from_arrays
from .textinput import is_whitespace_header, read_preamble, read_text_bytes, split_whitespace_header, whitespace_to_commas
from .units import Scale, converted_metadata, file_scale
from .units_counts import to_counts

__all__ = ["Recording", "check_for_device", "check_core_input", "read_recording", "write_recording", "write_columns_csv",
           "recording_from_arrays", "recording_layout", "VECTOR_COLUMNS"]


# --------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------


def read_recording(path: Any, n_channels: int | None = None, *, scale: Scale | None = None,
                   columns: list[str] | None = None, repeats: bool = False, whole: bool = False) -> Recording:
    """Read a recording (see the data contract and its extensions).

    Parameters
    ----------
    path : str or os.PathLike
        A CSV file, or text whose header has no comma and whose cells are separated by
        runs of blanks or tabs; either may be compressed (gzip, bzip2, xz, zstd or a zip
        of one file, told by its first bytes).
    n_channels : int, optional
        The device's channel count; raw_0..raw_{N-1} must then be present and no other
        raw_k.  Without it, N is the number of contiguous raw_k columns.
    scale : units.Scale, optional
        The raw_k readings' unit and LSB as stated by options (:mod:`accelcal.io.units`):
        m/s^2 or g become counts exactly or not at all.  The file's ``# units:``/``# lsb:``
        comments state them too; where both do, they must agree (:func:`units.file_scale`:
        a contradiction is an InputError naming the comment's line).
    columns : list of str, optional
        The column names of a file without a header row (its first non-comment line is data).
    repeats : bool
        Leave out the rows that repeat the row before exactly, time stamp and readings
        (:func:`.recording_checks.repeated_rows`), with a note; else they are refused (t increases).
    whole : bool
        Read the file's text whole first.  By default a plain CSV is read in chunks into its
        arrays (:func:`accelcal.io.chunks.read_chunked`: the same Recording, the same errors, a
        third of the memory); ``whole`` is the reference it is tested against.

    Raises
    ------
    InputError
        Any violation, naming the file, the line (of the decompressed text) and the column.
    """
    if is_parquet(path):       # by its name: Parquet, or refused (io.parquet)
        if columns is not None or (scale is not None and scale.converts):
            raise InputError(str(path), "a Parquet recording holds counts under the contract's column names "
                             "(no --units conversion, no header-less columns)")
        return read_parquet_recording(path, n_channels, reader_checks)
    if not whole and columns is None and not repeats:
        try:
            return read_chunked(path, n_channels, scale)
        except Fallback:
            pass
    source, data = read_text_bytes(path)
    pre = read_preamble(data)
    metadata, header, pos = pre.metadata, pre.header, pre.pos
    if header is None:
        what = "the file is empty" if not data.strip() else "no header row after the comments"
        raise InputError(source, f"{what} (expected a header such as 't,raw_0,raw_1,...')")
    header_line = pre.header_line
    spaced = is_whitespace_header(header)
    if columns is not None:
        names, pos, header_line = list(columns), pre.header_pos, pre.header_line - 1
    elif spaced:
        names = split_whitespace_header(header)
    else:
        try:
            names = split_header(header)
        except csv.Error as e:
            raise InputError(source, f"the header cannot be split into columns ({e})", row=header_line) from None
    if columns is None and all(FLOAT_RE.fullmatch(c) for c in names):
        raise InputError(source, "the first line is numbers, not a header (expected 't,raw_0,raw_1,...'): "
                         "imu_tk's whitespace 't ax ay az' in counts is read by 'accelcal convert --format imu_tk'; "
                         "another table needs a first line naming its columns (such as 't,accX,accY,accZ'), then "
                         "'accelcal convert --format table'", row=header_line)
    cols = classify_columns(names, n_channels, source, header_line)
    scale = file_scale(scale, metadata, pre.metadata_lines, source)
    if scale is not None and scale.converts:  # raw_k as finite numbers, then counts
        cols = {k: (j, "t" if kind == "raw" else kind) for k, (j, kind) in cols.items()}

    # Trailing blank lines are not rows; blank lines inside the data are errors.
    # (Offsets, not slices: the data may be hundreds of MB.)
    end = data_end(data, pos, len(data))
    if end <= pos:
        raise InputError(source, "no data rows after the header", row=header_line)
    end, cut_note = cut_short_end(data, pos, end, len(names), header_line + 1)
    read_notes = [cut_note] if cut_note else []
    with notes_on_refusal(lambda: read_notes):     # a refusal after a note: it goes with it
        if spaced:
            data = whitespace_to_commas(data, pos, end, names, header_line + 1, source)
            end = len(data)
        m = len(names)
        first = header_line + 1
        table: Any = None
        values = fast_columns(data, pos, end, m, cols)
        if values is None:
            # Anything pyarrow's reader did not take (quotes, '1.0' as an integer, an
            # error): the numpy/Python path decides, with the exact message.
            table = make_table(data, pos, end, m, first, source)
            # Convert every column; report the earliest bad cell in the file.
            values, err = convert_columns(table, cols)
            if err is not None:
                i, j, msg = err
                raise InputError(source, msg, row=table.line(i), column=names[j])
        n = len(values["t"])

        def located() -> Any:
            """The table that locates cells and lines; after pyarrow's reader (no quotes in
            the file) built only when a message or an extra column needs it."""
            nonlocal table
            if table is None:
                table = ByteTable(data, pos, end, m, first, source)
            return table

        t = values["t"]
        same = repeated_rows(values.values()) if repeats else np.zeros(n, bool)
        dt_bad = np.flatnonzero(~(np.diff(t) > 0) & ~same[1:])
        if dt_bad.size:
            i = int(dt_bad[0]) + 1
            jt = cols["t"][0]
            raise InputError(
                source,
                f"t must be strictly increasing, got {quote_cell(located().cell(i, jt).strip())} "
                f"after {quote_cell(located().cell(i - 1, jt).strip())}",
                row=located().line(i),
                column="t",
            )

        n_raw = sum(1 for name in cols if RAW_RE.fullmatch(name))
        if scale is not None and scale.converts:
            raw = to_counts(np.column_stack([values[f"raw_{k}"] for k in range(n_raw)]), scale, source,
                            lambda i, k: (located().line(i), f"raw_{k}"), notes=read_notes)
            metadata = converted_metadata(metadata, scale)
        else:
            raw = np.empty((n, n_raw), dtype=np.int64)
            for k in range(n_raw):
                raw[:, k] = values[f"raw_{k}"]
        vecs: dict[str, np.ndarray | None] = {}
        for vec, comps in VECTOR_COLUMNS.items():
            if comps[0] not in values:
                vecs[vec] = None
                continue
            arr = np.column_stack([values[c] for c in comps])
            fin = np.isfinite(arr)
            part = np.flatnonzero(fin.any(axis=1) & ~fin.all(axis=1))
            if part.size:
                i = int(part[0])
                given = comps[int(np.flatnonzero(fin[i])[0])]
                missing = comps[int(np.flatnonzero(~fin[i])[0])]
                raise InputError(
                    source,
                    f"{given} is given but {missing} is not (give all of {', '.join(comps)} or none)",
                    row=located().line(i),
                    column=missing,
                )
            vecs[vec] = arr
        extra: dict[str, list[str]] = {}
        for j, name in enumerate(names):
            if name and name not in cols and name not in extra:
                extra[name] = located().strings(j)
        rec = Recording(
            t=t,
            raw=raw,
            f=vecs["f"],
            w=vecs["w"],
            dw=vecs["dw"],
            temp_c=values.get("temp_c"),
            pose=values.get("pose"),
            metadata=metadata,
            extra=extra,
            source=source,
            lines=first if not isinstance(table, ListTable) else table.lines,
        )
        if same.any():
            rec = rec.select(~same)
            read_notes.append(repeats_note(int(same.sum()), located().line(int(np.argmax(same)))))
        rec.notes.extend(read_notes)
        return rec


def write_recording(path: Any, rec: Recording, float_format: str = "%.9g") -> None:
    """Write ``rec`` as CSV, atomically.

    Columns: t (shortest exact repr), raw_0..raw_{N-1}, then only the
    reference columns with any known value (NaN as an empty cell), then the
    extra columns.  Metadata become ``# key: value`` comments.  A path ending in .parquet
    is written as Parquet (:func:`accelcal.io.parquet.write_parquet_recording`).

    Parameters
    ----------
    path : str or os.PathLike
        The file to write (written to a temporary file and renamed: no partial file).
    rec : Recording
    float_format : str
        printf-style format of the reference columns' values (t is written exactly).
    """
    check_content(rec)
    if is_parquet(path):
        write_parquet_recording(path, rec)
        return
    lines, columns, formats = recording_layout(rec, float_format)

    def write(f: Any) -> None:
        f.write("\n".join(lines))
        f.write("\n")
        for chunk in csv_rows(columns, formats, [""] * len(columns)):
            f.write(chunk)

    atomic_write(path, write)


def recording_layout(rec: Recording, float_format: str = "%.9g", like: Recording | None = None
                     ) -> tuple[list[str], list[Any], list[str]]:
    """What :func:`write_recording` writes: the comment and header lines, the columns and their
    csv_rows formats.  ``like`` (default ``rec``) decides which reference, temp_c and pose columns
    are written (a writer in chunks: the whole recording's, each chunk's values from ``rec``)."""
    like = rec if like is None else like
    try:
        probe = float(float_format % 0.1)
    except (TypeError, ValueError):
        raise ValueError(f"float_format {float_format!r} does not format a float readably") from None
    if not math.isfinite(probe) or "," in float_format % 0.1:
        raise ValueError(f"float_format {float_format!r} does not format a float readably")
    lines: list[str] = []
    for k, v in like.metadata.items():
        if not META_KEY_RE.fullmatch(k):
            raise ValueError(f"metadata key {k!r}: expected a word of letters, digits, '_', '.', '-'")
        if "\n" in v or "\r" in v:
            raise ValueError(f"metadata {k!r}: the value must be one line")
        lines.append(f"# {k}: {v.strip()}")
    names = ["t"] + [f"raw_{k}" for k in range(rec.n_channels)]
    # every column and how it is written (csv_rows' formats; NaN as an empty cell);
    # repr() is the shortest text that reads back to the same float
    columns: list[Any] = [rec.t] + [rec.raw[:, k] for k in range(rec.n_channels)]
    formats = [REPR] + [INT] * rec.n_channels
    for vec, comps in VECTOR_COLUMNS.items():
        if np.isfinite(getattr(like, vec)).any():
            arr = getattr(rec, vec)
            names += list(comps)
            columns += [arr[:, c] for c in range(3)]
            formats += [float_format] * 3
    if like.has_temp():
        names.append("temp_c")
        columns.append(rec.temp_c)
        formats.append(float_format)
    if like.has_pose():
        names.append("pose")
        columns.append(rec.pose)
        formats.append(INT)
    for name in like.extra:
        vals = rec.extra[name]
        if not name.strip() or name.strip() != name:
            raise ValueError(f"extra column name {name!r}: expected a non-empty name without surrounding spaces")
        if any("\n" in v or "\r" in v for v in vals):
            raise ValueError(f"extra column {name!r}: values must not contain line breaks")
        names.append(name)
        columns.append(list(map(csv_cell, vals)))
        formats.append(TEXT)
    lines.append(",".join(map(csv_cell, names)))
    return lines, columns, formats


# ---- result columns and the C core's input range (moved from estimators.py / resolve.py) ----

def write_columns_csv(path: Any, columns: Any, meta: dict | None = None) -> None:
    """Write result columns as CSV, atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Destination file; replaced only once the whole text is written.
    columns : mapping of str to array_like
        Column name -> (n,) values, in output order (any unit; written as ``'%.9g' % x``
        per cell, NaN as ``nan``, as ``numpy.savetxt(fmt="%.9g")`` writes them; the time
        column ``t`` exactly, as :func:`write_recording` does: an epoch in seconds needs 16
        digits).
    meta : dict, optional
        Written first, one ``# key: value`` comment line per item.

    A path ending in .parquet is written as Parquet, the comments as its key-value metadata
    (:func:`accelcal.io.parquet.write_parquet_columns`).
    """
    if is_parquet(path):
        write_parquet_columns(path, columns, meta)
        return
    names = list(columns)
    arrays = [np.asarray(columns[k], float) for k in names]

    def write(f: Any) -> None:
        for k, v in (meta or {}).items():
            f.write(f"# {k}: {v}\n")
        f.write(",".join(names) + "\n")
        for chunk in csv_rows(arrays, [REPR if k == "t" else "%.9g" for k in names]):
            f.write(chunk)

    atomic_write(path, write)


