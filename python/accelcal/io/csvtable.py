"""Reading the data rows of a recording CSV: the header's columns classified, the cells
converted column by column -- by pyarrow's CSV reader when every row is plain (its C++
parser; :func:`fast_columns`), else vectorised with numpy on a byte table, and cell by
cell in Python only where a column needs it, which also words the error naming the row
and the column."""
from __future__ import annotations

import csv
import io
import math
import re
from typing import Any, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv

from ..errors import InputError

VECTOR_COLUMNS: dict[str, tuple[str, str, str]] = {
    "f": ("f_x", "f_y", "f_z"),
    "w": ("w_x", "w_y", "w_z"),
    "dw": ("dw_x", "dw_y", "dw_z"),
}


REFERENCE_NAMES = {c for cols in VECTOR_COLUMNS.values() for c in cols} | {"temp_c", "pose"}
RAW_RE = re.compile(r"raw_(\d+)")
# "# key: value"; the key is a bare word so that "# taken at 12:30" stays a plain comment.
META_RE = re.compile(r"#\s*([A-Za-z_][A-Za-z0-9_.\-]*)\s*:(.*)", re.S)
META_KEY_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*")
INT_RE = re.compile(r"[+-]?[0-9]+")
FLOAT_RE = re.compile(
    r"[+-]?(?:[0-9]+\.?[0-9]*(?:[eE][+-]?[0-9]+)?|\.[0-9]+(?:[eE][+-]?[0-9]+)?|nan|inf|infinity)",
    re.I,
)
NAN_WORDS = {"nan", "+nan", "-nan"}
# Widest numeric cell handled by the fixed-width fast path; wider ones go slow.
FAST_WIDTH = 32
FLOAT_BYTES = np.zeros(256, dtype=bool)
FLOAT_BYTES[list(b"0123456789+-.eEnNaAiIfFtTyY \t\x00")] = True
INT_BYTES = np.zeros(256, dtype=bool)
INT_BYTES[list(b"0123456789+- \t\x00")] = True


class CellError(Exception):
    """Bad cell at data-row index ``i`` (converted to InputError by the reader)."""

    def __init__(self, i: int, message: str) -> None:
        super().__init__(message)
        self.i = i
        self.message = message


def quote_cell(text: str) -> str:
    shown = text if len(text) <= 40 else text[:37] + "..."
    return repr(shown)


def got_text(text: str) -> str:
    return "an empty cell" if not text.strip() else quote_cell(text)


class ByteTable:
    """Data rows located in the raw bytes ``data[start:end]``: ``starts`` and
    ``ends`` are (n, m) cell offsets into ``data``."""

    def __init__(self, data: bytes, start: int, end: int, m: int, first_line: int, source: str) -> None:
        self.data = data
        self.first_line = first_line
        view = np.frombuffer(data, dtype=np.uint8, count=end - start, offset=start)
        seps = np.flatnonzero((view == 44) | (view == 10))
        is_nl = view[seps] == 10
        # The end of the data section terminates the last row.
        seps = np.append(seps, view.size) + start
        is_nl = np.append(is_nl, True)
        nl = np.flatnonzero(is_nl)
        counts = np.diff(nl, prepend=-1)
        bad = np.flatnonzero(counts != m)
        if bad.size:
            i = int(bad[0])
            line_start = start if i == 0 else int(seps[nl[i - 1]]) + 1
            text = data[line_start : int(seps[nl[i]])].decode("utf-8", "replace")
            if not text.strip():
                what = "an empty line"
            elif text.startswith("#"):
                what = "a comment (comments are only allowed before the header)"
            else:
                what = f"{int(counts[i])}"
            raise InputError(source, f"expected {m} cells as in the header, got {what}", row=first_line + i)
        self.n = int(nl.size)
        starts = np.empty(seps.size, dtype=np.int64)
        starts[0] = start
        starts[1:] = seps[:-1] + 1
        self.starts = starts.reshape(self.n, m)
        self.ends = seps.reshape(self.n, m)
        self._window: np.ndarray | None = None
        # NUL bytes are the padding of the fast path's fixed-width cells, so a
        # file that contains any is converted by the slow path only.
        self._fast = data.find(b"\x00", start, end) < 0

    def line(self, i: int) -> int:
        return self.first_line + i

    def cell(self, i: int, j: int) -> str:
        return self.data[self.starts[i, j] : self.ends[i, j]].decode("utf-8")

    def strings(self, j: int) -> list[str]:
        data = self.data
        return [data[s:e].decode("utf-8") for s, e in zip(self.starts[:, j].tolist(), self.ends[:, j].tolist())]

    def matrix(self, j: int) -> tuple[np.ndarray, np.ndarray] | None:
        """Column j as an (n, W) zero-padded byte matrix and the cell lengths;
        None when a cell is too wide for the fast path."""
        s = self.starts[:, j]
        lens = self.ends[:, j] - s
        width = int(lens.max(initial=0))
        if width > FAST_WIDTH or not self._fast:
            return None
        if self._window is None:
            # A sliding (len, FAST_WIDTH) view of the bytes: picking rows of it
            # copies each cell's bytes in one go instead of gathering bytes singly.
            # one row more than there are bytes: an empty last cell starts at len(data)
            padded = np.zeros(len(self.data) + 1 + FAST_WIDTH, dtype=np.uint8)
            padded[: len(self.data)] = np.frombuffer(self.data, dtype=np.uint8)
            self._window = np.lib.stride_tricks.as_strided(
                padded, shape=(len(self.data) + 1, FAST_WIDTH), strides=(1, 1), writeable=False
            )
        width = max(width, 3)  # room for b"nan" in empty cells
        mat = self._window[s, :width]
        mat *= np.arange(width) < lens[:, None]
        return mat, lens


class ListTable:
    """Data rows parsed by the csv module (used when a cell is quoted)."""

    def __init__(self, body: str, m: int, first_line: int, source: str) -> None:
        reader = csv.reader(io.StringIO(body, newline=""), strict=True)
        rows: list[list[str]] = []
        lines: list[int] = []
        before = 0
        try:
            for row in reader:
                line = first_line + before
                if len(row) != m:
                    what = "an empty line" if not row or row == [""] else f"{len(row)}"
                    raise InputError(source, f"expected {m} cells as in the header, got {what}", row=line)
                rows.append(row)
                lines.append(line)
                before = reader.line_num
        except csv.Error as e:
            raise InputError(source, f"bad CSV quoting: {e}", row=first_line + before) from None
        self.rows = rows
        self.lines = lines
        self.n = len(rows)

    def line(self, i: int) -> int:
        return self.lines[i]

    def cell(self, i: int, j: int) -> str:
        return self.rows[i][j]

    def strings(self, j: int) -> list[str]:
        return [r[j] for r in self.rows]

    def matrix(self, j: int) -> None:
        return None


# -- fast converters: return None whenever the slow path must decide ---------


def fast_int(mb: tuple[np.ndarray, np.ndarray] | None, empty_value: int | None) -> np.ndarray | None:
    if mb is None:
        return None
    mat, lens = mb
    # Only digits, signs and blanks: numpy's parser would also take '1_0'.
    if not INT_BYTES[mat].all():
        return None
    empty = lens == 0
    if empty.any():
        if empty_value is None:
            return None
        mat[empty, : len(str(empty_value))] = np.frombuffer(str(empty_value).encode(), dtype=np.uint8)
    strings = np.ascontiguousarray(mat).view(f"S{mat.shape[1]}").ravel()
    try:
        return strings.astype(np.int64)
    except (ValueError, OverflowError):
        return None


def fast_float(mb: tuple[np.ndarray, np.ndarray] | None, allow_empty: bool) -> np.ndarray | None:
    if mb is None:
        return None
    mat, lens = mb
    if not FLOAT_BYTES[mat].all():
        return None
    empty = lens == 0
    if empty.any():
        if not allow_empty:
            return None
        mat[empty, :3] = np.frombuffer(b"nan", dtype=np.uint8)
    strings = np.ascontiguousarray(mat).view(f"S{mat.shape[1]}").ravel()
    try:
        with np.errstate(over="ignore"):    # '1e400' is inf, as float() reads it, with no warning
            return strings.astype(np.float64)
    except (ValueError, OverflowError):
        return None


# -- slow converters: per cell, with the exact message -----------------------


def slow_int(strings: Sequence[str], empty_value: int | None, what: str) -> np.ndarray:
    out = np.empty(len(strings), dtype=np.int64)
    for i, s in enumerate(strings):
        c = s.strip()
        if not c or c.lower() in NAN_WORDS:
            if empty_value is None:
                raise CellError(i, f"expected {what}, got {got_text(s)}")
            out[i] = empty_value
            continue
        if INT_RE.fullmatch(c):
            v = int(c)
        elif FLOAT_RE.fullmatch(c):
            x = float(c)
            if not math.isfinite(x) or not x.is_integer():
                raise CellError(i, f"expected {what}, got {quote_cell(s)}")
            v = int(x)
        else:
            raise CellError(i, f"expected {what}, got {quote_cell(s)}")
        if not -(2**63) <= v < 2**63:
            raise CellError(i, f"expected {what} within 64 bits, got {quote_cell(s)}")
        out[i] = v
    return out


def slow_float(strings: Sequence[str], allow_unknown: bool) -> np.ndarray:
    out = np.empty(len(strings), dtype=np.float64)
    expect = "a finite number, or empty/nan for unknown" if allow_unknown else "a finite number"
    for i, s in enumerate(strings):
        c = s.strip()
        if not c:
            if not allow_unknown:
                raise CellError(i, f"expected {expect}, got an empty cell")
            out[i] = np.nan
            continue
        if not FLOAT_RE.fullmatch(c):
            raise CellError(i, f"expected {expect}, got {quote_cell(s)}")
        x = float(c)
        if math.isinf(x) or (math.isnan(x) and not allow_unknown):
            raise CellError(i, f"expected {expect}, got {quote_cell(s)}")
        out[i] = x
    return out


def convert_column(table: Any, j: int, kind: str) -> np.ndarray:
    """Column j of the table as numbers; kinds: raw, pose, t, ref."""
    if kind in ("raw", "pose"):
        empty_value = -1 if kind == "pose" else None
        vals = fast_int(table.matrix(j), empty_value)
        if vals is not None and (kind == "raw" or not np.any(vals < -1)):
            return vals
        what = "an integer" if kind == "raw" else "an integer pose label (>= 0, or -1/empty while moving)"
        vals = slow_int(table.strings(j), empty_value, what)
        if kind == "pose":
            bad = np.flatnonzero(vals < -1)
            if bad.size:
                i = int(bad[0])
                raise CellError(i, f"expected {what}, got {quote_cell(table.cell(i, j))}")
        return vals
    allow_unknown = kind == "ref"
    vals = fast_float(table.matrix(j), allow_unknown)
    if vals is not None:
        ok = ~np.isinf(vals) if allow_unknown else np.isfinite(vals)
        if ok.all():
            return vals
    return slow_float(table.strings(j), allow_unknown)


def data_end(data: bytes, pos: int, end: int) -> int:
    """The end of ``data[pos:end]``'s last line that is not blank (trailing blank lines are not
    rows); ``pos`` where every line is blank.  Offsets, not slices: the data may be hundreds of MB."""
    while end > pos:
        cut = data.rfind(b"\n", pos, end)
        if data[cut + 1 if cut >= 0 else pos:end].strip():
            break
        end = max(cut, pos)
    return end


def cut_short_end(data: bytes, pos: int, end: int, m: int, first: int) -> tuple[int, str | None]:
    """Where the data rows ``data[pos:end]`` end when the file's last line was cut short: a
    last line with no line end after it and fewer than ``m`` cells (split at commas, or at
    runs of blanks), or ending in an empty last cell -- what a logger stopped mid-write
    leaves -- is not a row.  Returns the
    new end and a note naming its line (``first``: the first data row's line), or ``end``
    and None.  A short line anywhere else, or one that ends its line, stays an error."""
    if b"\n" in data[end:]:
        return end, None
    cut = data.rfind(b"\n", pos, end)
    if cut < pos:
        return end, None
    text = data[cut + 1:end]
    comma = b"," in data[pos:cut]
    cells = text.count(b",") + 1 if comma else len(text.split())
    if cells > m or (cells == m and not (comma and text.rstrip().endswith(b","))):   # '1,2,3,' cut in its last cell
        return end, None
    line = first + data.count(b"\n", pos, cut + 1)
    what = f"{cells} of {m} cells" if cells < m else "its last cell empty"
    return cut, (f"line {line}, the last, is cut short ({what}, no line end after it: a logger stopped "
                 "mid-write); it is left out")


def make_table(data: bytes, pos: int, end: int, m: int, first: int, source: str) -> Any:
    """The data rows data[pos:end] of m columns (first data line ``first``): through the csv
    module when a cell is quoted (ListTable), else split as bytes (ByteTable)."""
    if data.find(b'"', pos, end) >= 0:
        return ListTable(data[pos:end].decode("utf-8"), m, first, source)
    return ByteTable(data, pos, end, m, first, source)


def convert_columns(table: Any, cols: dict[str, tuple[int, str]]) -> tuple[dict[str, np.ndarray],
                                                                           tuple[int, int, str] | None]:
    """Every column ``name -> (j, kind)`` of the table as numbers (:func:`convert_column`),
    and the earliest bad cell in the file as (row index, column, message), or None."""
    values: dict[str, np.ndarray] = {}
    errors: list[tuple[int, int, str]] = []
    for name, (j, kind) in cols.items():
        try:
            values[name] = convert_column(table, j, kind)
        except CellError as e:
            errors.append((e.i, j, e.message))
    return values, (min(errors) if errors else None)


# pyarrow's type for each kind of column (an empty cell is read as null).
ARROW_TYPES = {"raw": pa.int64(), "pose": pa.int64(), "t": pa.float64(), "ref": pa.float64()}
# What hands the data rows to the numpy/Python path, searched for in their bytes: a quote
# (cells are then split by the csv module), a lone CR (a line end to pyarrow, a blank in a
# cell to the Python path), and hexadecimal integers ('0x10') and NaN with a payload
# ('nan(1)'), which pyarrow reads and the contract does not allow.  Each key is one byte
# (a fast search); only where it occurs are its patterns searched for.
ARROW_REFUSED = {b'"': (b'"',), b"\r": (b"\r",), b"x": (b"0x",), b"X": (b"0X",), b"(": (b"n(", b"N(")}


def fast_columns(data: bytes, pos: int, end: int, m: int, cols: dict[str, tuple[int, str]]
                 ) -> dict[str, np.ndarray] | None:
    """The columns ``name -> (j, kind)`` of the data rows ``data[pos:end]`` (m cells a row)
    read by pyarrow's CSV reader, or None whenever the numpy/Python path must decide.

    Parameters
    ----------
    data : bytes
        The file's text (UTF-8, ``\\n`` line ends).
    pos, end : int
        The data rows are ``data[pos:end]``; the last one ends at ``end``.
    m : int
        Cells in every row (the header's).
    cols : dict of str to (int, str)
        The columns to read: name -> (column index, kind: raw, pose, t or ref).

    Returns
    -------
    dict of str to numpy.ndarray or None
        Each column's n values (int64 for raw and pose, float64 for t and ref; an empty
        pose cell is -1, an empty ref cell NaN), as the Python path would read them bit
        for bit; None when any row is not m cells, any cell of these columns is not what
        its kind allows in the plainest form, or the rows hold what ARROW_REFUSED lists.
        Errors and their wording are the Python path's alone.
    """
    for byte, refused in ARROW_REFUSED.items():
        if data.find(byte, pos, end) >= 0 and any(data.find(r, pos, end) >= 0 for r in refused):
            return None
    want = {f"c{j}": ARROW_TYPES[kind] for j, kind in cols.values()}
    try:
        table = pa_csv.read_csv(
            pa.py_buffer(memoryview(data)[pos:end]),
            read_options=pa_csv.ReadOptions(column_names=[f"c{j}" for j in range(m)], use_threads=False),
            parse_options=pa_csv.ParseOptions(delimiter=",", quote_char=False, escape_char=False,
                                              newlines_in_values=False, ignore_empty_lines=False),
            convert_options=pa_csv.ConvertOptions(column_types=want, include_columns=list(want), null_values=[""],
                                                  true_values=[], false_values=[]),
        )
    except pa.ArrowException:  # a row of another length, a cell it does not read
        return None
    if table.num_rows != data.count(b"\n", pos, end) + 1:
        return None
    out: dict[str, np.ndarray] = {}
    for name, (j, kind) in cols.items():
        col = table.column(f"c{j}")
        if col.null_count:
            if kind not in ("pose", "ref"):
                return None
            col = col.fill_null(-1 if kind == "pose" else np.nan)
        vals = col.to_numpy()
        if not vals.flags.writeable:  # a view of pyarrow's buffer
            vals = vals.copy()
        if kind == "pose" and np.any(vals < -1):
            return None
        if (kind == "t" and not np.isfinite(vals).all()) or (kind == "ref" and np.isinf(vals).any()):
            return None
        out[name] = vals
    return out


def split_header(line: str) -> list[str]:
    if '"' in line:
        cells = next(csv.reader([line]), [])
    else:
        cells = line.split(",")
    return [c.strip() for c in cells]


def classify_columns(
    names: list[str], n_channels: int | None, source: str, row: int
) -> dict[str, tuple[int, str]]:
    """Map known column names to (index, kind); check the header's rules."""
    seen: dict[str, int] = {}
    for j, name in enumerate(names):
        known = name == "t" or name in REFERENCE_NAMES or RAW_RE.fullmatch(name)
        # Unknown columns are never an error (contract): a repeated or empty
        # unknown name is just not kept.  A repeated known name is ambiguous.
        if known and name in seen:
            raise InputError(
                source, f"column name {name!r} appears twice (columns {seen[name] + 1} and {j + 1})", row=row
            )
        seen.setdefault(name, j)
    cols: dict[str, tuple[int, str]] = {}
    raw_idx: dict[int, int] = {}
    for j, name in enumerate(names):
        m = RAW_RE.fullmatch(name)
        if m:
            digits = m.group(1)
            if len(digits) > 1 and digits.startswith("0"):
                raise InputError(source, f"column name {name!r}: expected raw_{int(digits)} (no leading zeros)", row=row)
            raw_idx[int(digits)] = j
        elif name == "t":
            cols[name] = (j, "t")
        elif name == "pose":
            cols[name] = (j, "pose")
        elif name in REFERENCE_NAMES:
            cols[name] = (j, "ref")
    if "t" not in cols:
        hint = next((f" (found {n!r}; names are case-sensitive)" for n in names if n.strip().lower() == "t"), "")
        raise InputError(source, f"the header has no 't' column{hint}", row=row)
    if not raw_idx:
        raise InputError(source, "the header has no raw_0, raw_1, ... columns", row=row)
    if n_channels is not None:
        extra_raw = sorted(k for k in raw_idx if k >= n_channels)
        if extra_raw:
            raise InputError(
                source, f"recording has raw_{extra_raw[0]} but the device has {n_channels} channels", row=row
            )
        missing = [k for k in range(n_channels) if k not in raw_idx]
        if missing:
            raise InputError(
                source,
                f"the header has no raw_{missing[0]} column (the device has {n_channels} channels: "
                f"raw_0..raw_{n_channels - 1})",
                row=row,
            )
    else:
        top = max(raw_idx)
        missing = [k for k in range(top) if k not in raw_idx]
        if missing:
            raise InputError(
                source, f"raw columns must be contiguous: raw_{top} is present but raw_{missing[0]} is not", row=row
            )
    for k in sorted(raw_idx):
        cols[f"raw_{k}"] = (raw_idx[k], "raw")
    for comps in VECTOR_COLUMNS.values():
        present = [c for c in comps if c in cols]
        if present and len(present) < 3:
            absent = next(c for c in comps if c not in cols)
            raise InputError(
                source, f"the header has {present[0]} but no {absent} (vector columns come as a full triple)", row=row
            )
    return cols
