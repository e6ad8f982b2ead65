"""Writing CSV rows: the one writer of every CSV the package writes (recordings, result
columns).  Integers are written as ``str(v)``, floats as ``repr(x)`` or through a
%-format such as ``'%.9g'`` (NaN as an empty cell or as the format writes it), text as
given; all by Python's own formatting, which no locale changes, a chunk of rows at a
time: each row is one ``%`` of a row template over the chunk's Python values."""
from __future__ import annotations

from typing import Any, Iterator, Sequence

import numpy as np

__all__ = ["INT", "REPR", "TEXT", "CHUNK_ROWS", "csv_rows", "csv_cell"]

INT = "%d"  # an integer column: str(v)
REPR = "%r"  # a float column: repr(x), the shortest text that reads back to x
TEXT = "%s"  # a column of text cells, written as given (quote them first: csv_cell)
# Rows formatted per chunk: bounds the memory of the Python values and the text.
CHUNK_ROWS = 65536


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
