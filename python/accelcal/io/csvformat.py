"""Writing CSV rows: the one writer of every CSV the package writes (recordings, result
columns).  Integers are written as ``str(v)``, floats as ``repr(x)`` or through a
%-format such as ``'%.9g'`` (NaN as an empty cell or as the format writes it), text as
given; by Python's own formatting, which no locale changes, a chunk of rows at a time: each
row is one ``%`` of a row template over the chunk's Python values.  Rows of ``'%.9g'`` columns
(NaN as ``nan``) after at most one ``repr`` column (the result columns: t, then f, alpha, ...)
are formatted by the host-only C of the extension instead (hostsrc/fmt_csv.c: glibc's
``snprintf("%.9g")``, correctly rounded as Python's is; NaN as ``nan``), the same text,
while the C locale's decimal point is ``'.'`` (:func:`c_float_rows`)."""
from __future__ import annotations

import locale
from typing import Any, Iterator, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc

from .._core import ffi, lib

#: the C formatter, where the built extension has it (an extension built before it: the Python path)
C_ROWS = getattr(lib, "acx_csv_rows", None)
#: the C layout of repr from pyarrow's shortest digits (:func:`repr_lines`), where built
C_REPR = getattr(lib, "acx_repr_lines", None)
#: bytes of one repr line at most, its '\n' included (fmt_csv.c's ACX_REPR_MAX)
REPR_MAX = 32

__all__ = ["INT", "REPR", "TEXT", "CHUNK_ROWS", "G9", "C_ROWS", "csv_rows", "csv_cell", "c_float_rows", "repr_lines"]

INT = "%d"  # an integer column: str(v)
REPR = "%r"  # a float column: repr(x), the shortest text that reads back to x
TEXT = "%s"  # a column of text cells, written as given (quote them first: csv_cell)
# Rows formatted per chunk: bounds the memory of the Python values and the text.
CHUNK_ROWS = 65536
G9 = "%.9g"  # the result columns' float format, which the C formatter writes
#: bytes of one '%.9g' cell at most ("-1.23456789e-308") and its ',' (fmt_csv.c's ACX_CELL_MAX)
CELL_MAX = 24


def csv_rows(columns: Sequence[Any], formats: Sequence[str], nan_cells: Sequence[str | None] | None = None,
             chunk_rows: int = CHUNK_ROWS) -> Iterator[str]:
    """The CSV rows of equal-length columns, in chunks of text each ending with a newline.

    Parameters
    ----------
    columns : sequence of array_like or list of str
        The columns, each of n values in any unit (written as they are).
    formats : sequence of str
        Per column: ``INT`` (int64, ``str(v)``), ``REPR`` (float64, ``repr(x)``), ``TEXT``
        (str, as given), or a %-format of one float such as ``'%.9g'`` (float64).
    nan_cells : sequence of str or None, optional
        Per column, the cell written for NaN in a float-format column (``''``: an empty
        cell), or None for what the format writes (``'nan'``).  Default: None for all.
    chunk_rows : int, optional
        Rows formatted at a time.

    Yields
    ------
    str
        The rows of one chunk, cells separated by ``','``, each row ended by ``'\\n'``;
        nothing when there are no rows or no columns.
    """
    if not columns:
        return
    nan_cells = [None] * len(columns) if nan_cells is None else list(nan_cells)
    cols: list[Any] = [list(c) if fmt == TEXT else np.asarray(c, dtype=np.int64 if fmt == INT else np.float64)
                       for c, fmt in zip(columns, formats)]
    n = len(cols[0])
    lead = 1 if formats[0] == REPR else 0
    if len(formats) > lead and all(f == G9 for f in formats[lead:]) and all(v is None for v in nan_cells[lead:]) \
            and C_ROWS is not None and locale.localeconv()["decimal_point"] == ".":
        for row0 in range(0, n, chunk_rows):
            part = [c[row0:row0 + chunk_rows] for c in cols]
            yield c_float_rows(part[0] if lead else None, np.column_stack(part[lead:]))
        return
    for row0 in range(0, n, chunk_rows):
        values = []
        cell_formats = []
        for c, fmt, nan in zip(cols, formats, nan_cells):
            part = c[row0 : row0 + chunk_rows]
            if fmt == TEXT:
                values.append(part)
            elif nan is not None and fmt not in (INT, REPR) and np.isnan(part).any():
                # NaN gets its own text: the column is formatted here and goes in as text
                values.append(float_strings(part, fmt, nan))
                fmt = TEXT
            else:
                values.append(part.tolist())
            cell_formats.append(fmt)
        row = ",".join(cell_formats) + "\n"
        yield "".join(map(row.__mod__, zip(*values)))


def c_float_rows(t: np.ndarray | None, values: np.ndarray) -> str:
    """The CSV rows of ``t`` (``repr``; None: no such column) and the columns of ``values``
    (k, m) float64, each ``'%.9g' % x``, NaN as ``nan``, written by the C formatter
    (hostsrc/fmt_csv.c): the text :func:`csv_rows`'s Python path writes."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    k, m = values.shape
    prefix = repr_lines(t) if t is not None and k else b""
    cap = len(prefix) + k * (m * CELL_MAX + 1) + 1
    buf = ffi.new("char[]", cap)
    wrote = C_ROWS(prefix, len(prefix), ffi.cast("double *", ffi.from_buffer(values)), k, m, buf, cap)
    if k and not wrote:
        raise RuntimeError("acx_csv_rows: the buffer was short")   # (a bug: cap is the C's bound)
    return ffi.buffer(buf, wrote)[:].decode("ascii")


def repr_lines(values: np.ndarray) -> bytes:
    """``repr(x)`` of each float64, a line each (``'\\n'`` after each), as bytes.

    pyarrow's cast of a double to text writes its shortest round-trip digits (the digits Python's
    repr writes: the shortest that read back to x, the nearest to x among them, a tie to the even
    one), in C++ with Python's GIL released; the host C (fmt_csv.c's ``acx_repr_lines``) lays them
    out as repr does (positional for 1e-4 <= abs(x) < 1e16 with at least one decimal, else
    ``d.ddde+XX``; ``nan``, ``inf``, ``-0.0``).  Python's ``repr`` where the extension has no
    such function or pyarrow writes other text.  3x10^6 time stamps: 1.13 s against 2.85 s for
    ``'\\n'.join(map(repr, ...))`` on the idle machine, without the GIL (docs/streaming.md).
    """
    values = np.asarray(values, dtype=np.float64)
    n = values.size
    if C_REPR is not None and n:
        text = pc.cast(pa.array(values.ravel(), pa.float64()), pa.string())
        offsets = np.frombuffer(text.buffers()[1], np.int32)[text.offset:text.offset + n + 1]
        buf = ffi.new("char[]", REPR_MAX * n + 1)
        wrote = C_REPR(ffi.from_buffer("int32_t[]", offsets), ffi.from_buffer(text.buffers()[2]), n, buf,
                       REPR_MAX * n + 1)
        if wrote:
            return ffi.buffer(buf, wrote)[:]
    return ("\n".join(map(repr, values.ravel().tolist())) + "\n").encode("ascii") if n else b""


def float_strings(values: np.ndarray, fmt: str, nan: str) -> list[str]:
    """``fmt % x`` for each float, and ``nan`` where x is NaN (only the others formatted)."""
    known = ~np.isnan(values)
    cells = np.full(values.shape, nan, dtype=object)
    cells[known] = list(map(fmt.__mod__, values[known].tolist()))
    return cells.tolist()


def csv_cell(text: str) -> str:
    """``text`` as one CSV cell: quoted (``"`` doubled) when it holds a comma or a quote or
    has blanks around it, else as it is."""
    if any(ch in text for ch in ',"') or text != text.strip():
        return '"' + text.replace('"', '""') + '"'
    return text
