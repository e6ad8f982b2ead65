"""A recording CSV read in chunks of rows, for the commands that go sample by sample
(``resolve``: :mod:`accelcal.resolve_stream`).

The file is read in blocks of whole lines (:data:`BLOCK_BYTES`), and each block's rows go
through the very functions :func:`accelcal.io.recording.read_recording` uses on the whole
file: pyarrow's CSV reader (:func:`accelcal.io.csvtable.fast_columns`) for plain rows, else
the numpy/Python path (:func:`accelcal.io.csvtable.make_table`,
:func:`accelcal.io.csvtable.convert_columns`), which words the error naming file, row and
column.  So every value is the one the whole-file reader gives, and a bad cell is the same
one-line error.

What the chunked reader does not reproduce line for line it leaves to the whole-file
reader (:class:`Fallback`): compressed files, a byte-order mark, CR line ends, a
semicolon-separated export, blank-separated text, quoted cells, readings in physical units
(``--units``), a header not within the first :data:`HEAD_BYTES`, a file of blank lines
after its rows.
"""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Iterator

import numpy as np

from .csvtable import (FLOAT_RE, RAW_RE, VECTOR_COLUMNS, ByteTable, classify_columns, convert_columns,
                        cut_short_end, data_end, fast_columns, make_table, quote_cell, split_header)
from ..errors import InputError
from .recording_type import Recording
from .textinput import COMPRESSIONS, is_whitespace_header, read_preamble
from .units import Scale, file_scale

__all__ = ["BLOCK_BYTES", "HEAD_BYTES", "Fallback", "Head", "Chunk", "csv_head", "csv_chunks", "reader_checks",
           "read_chunked", "gather_rows", "recording_of"]

#: bytes of text read at a time (whole lines; a block holds at least one line)
BLOCK_BYTES = 1 << 21
#: the comments and header must lie within this many bytes for the chunked reader
HEAD_BYTES = 1 << 20


class Fallback(Exception):
    """The chunked reader does not reproduce this file line for line: read it whole."""


@dataclass
class Head:
    """What precedes the rows: the columns and the metadata.

    Attributes
    ----------
    source : str
        The path as given, for messages.
    names : list of str
        The header's cells.
    cols : dict of str to (int, str)
        Known column name -> (index, kind) (:func:`accelcal.io.csvtable.classify_columns`).
    metadata : dict of str to str
        The ``# key: value`` comments.
    first_line : int
        The first data row's line (1-based).
    pos : int
        Its byte offset.
    extra : list of str
        The columns that are not the contract's (ignored by the model).
    n_raw : int
        raw_k columns.
    """

    source: str
    names: list[str]
    cols: dict[str, tuple[int, str]]
    metadata: dict[str, str]
    first_line: int
    pos: int
    extra: list[str] = field(default_factory=list)
    n_raw: int = 0


@dataclass
class Chunk:
    """Consecutive rows of a recording as the whole-file reader reads them.

    Attributes
    ----------
    start : int
        Index of the first sample in the recording.
    t : ndarray (n,) float64
        s (as written; :func:`accelcal.io.recording_checks.seconds` may rescale).
    raw : ndarray (n, N) int64
        Counts.
    vecs : dict of str to ndarray (n, 3) or None
        f, w, dw (NaN where unknown), None where the file has no such columns.
    line : callable
        Row index within the chunk -> the file's line (1-based), for messages.
    cell : callable
        (row index within the chunk, column index) -> the cell's text, for messages.
    other : dict of str to ndarray
        temp_c (float64, NaN unknown) and pose (int64, -1 unknown) where the file has them.
    """

    start: int
    t: np.ndarray
    raw: np.ndarray
    vecs: dict[str, np.ndarray | None]
    line: Callable[[int], int]
    cell: Callable[[int, int], str]
    other: dict[str, np.ndarray] = field(default_factory=dict)     # temp_c, pose where the file has them

    @property
    def n(self) -> int:
        return len(self.t)


def csv_head(path: Any, n_channels: int | None, scale: Scale | None) -> Head:
    """The comments and header of a recording CSV that the chunked reader takes.

    Raises
    ------
    Fallback
        A file the whole-file reader must read (see the module doc).
    InputError
        A header the whole-file reader refuses, with its message (it comes before any row).
    """
    source = os.fspath(path) if not isinstance(path, str) else path
    try:
        with open(path, "rb") as fh:
            head = fh.read(HEAD_BYTES)
            whole = len(head) < HEAD_BYTES or not fh.read(1)
    except OSError:
        raise Fallback("unreadable") from None                     # the whole-file reader words it
    if any(test(head) for _, test, _ in COMPRESSIONS) or head.startswith(b"\xef\xbb\xbf") or b"\r" in head:
        raise Fallback("compressed, a byte-order mark or CR line ends")
    if not whole:
        head = head[:head.rfind(b"\n") + 1]
    try:
        head.decode("utf-8")
    except UnicodeDecodeError:
        raise Fallback("not UTF-8") from None
    pre = read_preamble(head)
    if pre.header is None or (not whole and pre.pos >= len(head)):
        raise Fallback("no header in the head")
    header = pre.header
    if is_whitespace_header(header) or (";" in header and "," not in header):
        raise Fallback("blank- or semicolon-separated")
    try:
        names = split_header(header)
    except csv.Error:
        raise Fallback("header") from None
    if all(FLOAT_RE.fullmatch(c) for c in names):
        raise Fallback("numbers as header")
    cols = classify_columns(names, n_channels, source, pre.header_line)
    scale = file_scale(scale, pre.metadata, pre.metadata_lines, source)
    if scale is not None and scale.converts:
        raise Fallback("readings in physical units")
    if _cut_short(path, len(names)):
        raise Fallback("a last line cut short")   # its note goes with any refusal: the whole-file reader
    extra: list[str] = []
    for name in names:
        if name and name not in cols and name not in extra:
            extra.append(name)
    return Head(source=source, names=names, cols=cols, metadata=dict(pre.metadata), first_line=pre.header_line + 1,
                pos=pre.pos, extra=extra, n_raw=sum(1 for c in cols if RAW_RE.fullmatch(c)))


def _cut_short(path: Any, m: int) -> bool:
    """Whether the file's last line is cut short (:func:`accelcal.io.csvtable.cut_short_end`),
    from its last 64 KiB."""
    with open(path, "rb") as fh:
        size = fh.seek(0, os.SEEK_END)
        fh.seek(max(size - (1 << 16), 0))
        tail = fh.read()
    start = tail.find(b"\n") + 1 if size > (1 << 16) else 0
    end = data_end(tail, start, len(tail))
    return end > start and cut_short_end(tail, start, end, m, 1)[1] is not None


def read_chunked(path: Any, n_channels: int | None, scale: Scale | None, block_bytes: int = BLOCK_BYTES) -> Recording:
    """A whole recording CSV read chunk by chunk into its arrays: the
    :class:`accelcal.io.recording_type.Recording` the whole-file reader gives, without the file's
    text and pyarrow's table beside the arrays (a third of the whole-file reader's peak memory).

    Raises
    ------
    Fallback
        A file the whole-file reader must read (see the module doc; also extra columns, kept as text).
    InputError
        The whole-file reader's error.
    """
    head = csv_head(path, n_channels, scale)
    if head.extra:
        raise Fallback("extra columns")
    cols, _, _ = gather_rows(head, csv_chunks(path, head, block_bytes))
    return recording_of(head, cols, head.first_line)


def gather_rows(head: Head, chunks: Iterable[Chunk], keep: Callable[[int, int], np.ndarray] | None = None,
                visit: Callable[[Chunk, bool], None] | None = None
                ) -> tuple[dict[str, np.ndarray], np.ndarray | None, int]:
    """The rows of a recording's chunks gathered into whole columns, every row checked as the
    whole-file reader checks it (:func:`reader_checks`; the first error by rank, then row, raised
    after the last chunk).

    Parameters
    ----------
    head : Head
    chunks : iterable of Chunk
    keep : callable, optional
        ``keep(start, n)`` -> (n,) bool: the rows of the chunk starting at row ``start`` to keep
        (default: every row).
    visit : callable, optional
        ``visit(chunk, clean)`` on each chunk (``clean``: no reader error so far), for a check of
        the caller's own.

    Returns
    -------
    columns : dict of str to ndarray
        t, raw and each vector and other column the file has, of the rows kept.
    lines : ndarray (n_kept,) int64 or None
        The kept rows' file lines (None without ``keep``).
    n : int
        Rows read.
    """
    parts: dict[str, list[np.ndarray]] = {}
    lines: list[np.ndarray] = []
    errors: list[tuple[int, int, InputError]] = []
    prev = None
    n = 0
    for ch in chunks:
        errors += [(rank, ch.start, e) for rank, e in reader_checks(head, ch, prev)]
        if visit is not None:
            visit(ch, not errors)
        idx = None if keep is None else np.flatnonzero(keep(ch.start, ch.n))
        for name, arr in (("t", ch.t), ("raw", ch.raw), *ch.vecs.items(), *ch.other.items()):
            if arr is not None:
                parts.setdefault(name, []).append(arr if idx is None else arr[idx])
        if idx is not None:
            lines.append(np.array([ch.line(int(i)) for i in idx], dtype=np.int64))
        n += ch.n
        prev = ch
    if errors:
        raise min(errors, key=lambda x: (x[0], x[1]))[2]
    cols = {}
    for name in list(parts):
        cols[name] = np.concatenate(parts.pop(name))
    return cols, (np.concatenate(lines) if keep is not None else None), n


def recording_of(head: Head, cols: dict[str, np.ndarray], lines: Any) -> Recording:
    """The Recording of columns gathered by :func:`gather_rows` (``lines``: its first line, or
    each row's)."""
    return Recording(t=cols["t"], raw=cols["raw"], f=cols.get("f"), w=cols.get("w"), dw=cols.get("dw"),
                     temp_c=cols.get("temp_c"), pose=cols.get("pose"), metadata=head.metadata, source=head.source,
                     lines=lines)


def _blocks(path: Any, pos: int, block_bytes: int) -> Iterator[tuple[bytes, bool]]:
    """The file's text from byte ``pos`` in blocks of whole lines, and whether each is the last."""
    with open(path, "rb") as fh:
        fh.seek(pos)
        rest = b""
        nxt = None
        while True:
            buf = fh.read(block_bytes)
            data = rest + buf
            if not buf:
                block, rest = data, b""
            else:
                cut = data.rfind(b"\n")
                if data.count(b"\n", 0, cut) < 1:     # two lines at least (a chunk of one row: resolve_stream)
                    rest = data
                    continue
                block, rest = data[:cut + 1], data[cut + 1:]
            if nxt is not None:
                yield nxt, not block
            if not buf:
                if block:
                    yield block, True
                return
            nxt = block


def csv_chunks(path: Any, head: Head, block_bytes: int = BLOCK_BYTES,
               progress: Callable[[int], None] | None = None) -> Iterator[Chunk]:
    """The rows of a recording CSV in chunks (see the module doc).

    Parameters
    ----------
    path : str or os.PathLike
    head : Head
        From :func:`csv_head`.
    block_bytes : int
        Bytes of text per chunk (at least one line; tests use a few hundred).
    progress : callable, optional
        Called with the bytes of each block read.

    Raises
    ------
    InputError
        The first bad cell of the file, as the whole-file reader words it.
    Fallback
        Text the chunked reader leaves to the whole-file reader.
    """
    source, m, cols = head.source, len(head.names), head.cols
    line, start, any_rows = head.first_line, 0, False
    for data, last in _blocks(path, head.pos, block_bytes):
        if progress is not None:
            progress(len(data))
        if b"\r" in data or b'"' in data:
            raise Fallback("CR line ends or quoted cells")
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:
            raise Fallback("not UTF-8") from None
        end = len(data)
        notes: list[str] = []
        if last:  # trailing blank lines are not rows; a last line cut short is left out (read_recording)
            end = data_end(data, 0, end)
            if end <= 0:
                if not any_rows:
                    raise Fallback("no data rows")
                if data.strip():
                    raise Fallback("blank lines")
                return
            end, note = cut_short_end(data, 0, end, m, line)
            notes = [note] if note else []
            if notes:
                raise Fallback("a last line cut short")
        elif data.endswith(b"\n"):
            end -= 1
        if end <= 0 or not data[:end].strip():
            raise Fallback("blank lines")
        values = fast_columns(data, 0, end, m, cols)
        table: Any = None
        if values is None:
            table = make_table(data, 0, end, m, line, source)
            values, err = convert_columns(table, cols)
            if err is not None:
                i, j, msg = err
                raise InputError(source, msg, row=table.line(i), column=head.names[j])
        if table is None:
            table = ByteTableLazy(data, end, m, line, source)
        n = len(values["t"])
        raw = np.empty((n, head.n_raw), dtype=np.int64)
        for k in range(head.n_raw):
            raw[:, k] = values[f"raw_{k}"]
        vecs: dict[str, np.ndarray | None] = {}
        for vec, comps in VECTOR_COLUMNS.items():
            vecs[vec] = np.column_stack([values[c] for c in comps]) if comps[0] in values else None
        yield Chunk(start=start, t=values["t"], raw=raw, vecs=vecs, line=table.line, cell=table.cell,
                    other={k: values[k] for k in ("temp_c", "pose") if k in values})
        any_rows = True
        start += n
        line += data.count(b"\n")
    if not any_rows:
        raise Fallback("no data rows")


class ByteTableLazy:
    """A :class:`accelcal.io.csvtable.ByteTable` built only when a message needs a cell."""

    def __init__(self, data: bytes, end: int, m: int, first: int, source: str) -> None:
        self.args = (data, 0, end, m, first, source)
        self.first = first
        self.table: Any = None

    def line(self, i: int) -> int:
        return self.first + i

    def cell(self, i: int, j: int) -> str:
        if self.table is None:
            self.table = ByteTable(*self.args)
        return self.table.cell(i, j)


def reader_checks(head: Head, chunk: Chunk, prev: Chunk | None) -> list[tuple[int, InputError]]:
    """The whole-file reader's checks of rows, on one chunk (with the chunk before it):
    t strictly increasing (rank 1), a vector given in part (rank 2); each as (rank, error),
    the chunk's first of each.  Raised by rank, then row, they give the whole-file reader's
    error (which checks t over the whole file first, then f, w and dw in turn: ranks 2, 3, 4)."""
    out: list[tuple[int, InputError]] = []
    t = chunk.t
    jt = head.cols["t"][0]
    steps = np.diff(t)
    bad = np.flatnonzero(~(steps > 0))
    i = None
    if prev is not None and prev.n and not (t[0] - prev.t[-1] > 0):
        i = 0
    elif bad.size:
        i = int(bad[0]) + 1
    if i is not None:
        before = prev.cell(prev.n - 1, jt) if i == 0 else chunk.cell(i - 1, jt)
        out.append((1, InputError(head.source, f"t must be strictly increasing, got "
                                  f"{quote_cell(chunk.cell(i, jt).strip())} after {quote_cell(before.strip())}",
                                  row=chunk.line(i), column="t")))
    for rank, (vec, comps) in enumerate(VECTOR_COLUMNS.items(), 2):
        arr = chunk.vecs.get(vec)
        if arr is None:
            continue
        fin = np.isfinite(arr)
        part = np.flatnonzero(fin.any(axis=1) & ~fin.all(axis=1))
        if part.size:
            i = int(part[0])
            given = comps[int(np.flatnonzero(fin[i])[0])]
            missing = comps[int(np.flatnonzero(~fin[i])[0])]
            out.append((rank, InputError(head.source, f"{given} is given but {missing} is not (give all of "
                                         f"{', '.join(comps)} or none)", row=chunk.line(i), column=missing)))
    return out
