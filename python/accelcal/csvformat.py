"""Writing CSV rows: integer columns as str(v), floats as repr(x) or '%.<p>g' % x, text
exactly as those Python expressions give (the extension's C formatter, with a Python
definition of the same text for a comma-decimal locale)."""
from __future__ import annotations

import math
import re
from typing import Any, Iterator, Sequence

import numpy as np

from ._core import ffi, lib


def float_strings(values: np.ndarray, fmt: str) -> list[str]:
    strs = list(map(fmt.__mod__, values.tolist()))
    if np.isnan(values).any():
        # NaN is written as an empty cell; dict.get keeps this a C-level map.
        blank = {fmt % math.nan: ""}
        strs = list(map(blank.get, strs, strs))
    return strs


G_FORMAT_RE = re.compile(r"%\.([1-9]|1[0-7])g")
FORMAT_CHUNK_ROWS = 65536
# _csv_fast.h: ACX_OUT_INT, ACX_OUT_REPR, ACX_OUT_G (NaN: empty cell), ACX_OUT_G_NAN (NaN: 'nan'), ACX_CELL_MAX
CSV_INT, CSV_REPR, CSV_G, CSV_G_NAN = 1, 2, 3, 4
CELL_MAX = 32


def csv_rows(columns: Sequence[np.ndarray], kinds: Sequence[int], precision: int = 9) -> Iterator[str]:
    """The CSV rows of equal-length columns, in chunks of text (each ending with a newline):
    CSV_INT columns as str(v), CSV_REPR as repr(x), CSV_G as '%.<precision>g' % x with NaN as
    an empty cell, CSV_G_NAN likewise with NaN as 'nan'.  Formatted by the extension's C
    (_csv_fast.c), which writes exactly what those Python expressions give."""
    m = len(columns)
    arrs = [np.ascontiguousarray(c, dtype=np.int64 if k == CSV_INT else np.float64) for c, k in zip(columns, kinds)]
    n = arrs[0].shape[0] if arrs else 0
    kind = np.asarray(kinds, dtype=np.int8)
    prec = np.full(m, precision, dtype=np.int8)
    ptrs = ffi.new("void *[]", [ffi.from_buffer(a) for a in arrs])
    kp = ffi.cast("const int8_t *", ffi.from_buffer(kind))
    pp = ffi.cast("const int8_t *", ffi.from_buffer(prec))
    rows = min(n, FORMAT_CHUNK_ROWS)
    cap = max(rows, 1) * m * (CELL_MAX + 1)
    buf = ffi.new("char[]", cap)
    for row0 in range(0, n, FORMAT_CHUNK_ROWS):
        k = min(FORMAT_CHUNK_ROWS, n - row0)
        size = lib.acx_format_rows(row0, k, m, kp, pp, ptrs, buf, cap)
        if size == -2:  # a program set a numeric locale without '.': Python's own formatting
            yield python_rows(arrs, kinds, precision, row0, k)
            continue
        if size < 0:
            raise ValueError("csv_rows: bad column kind or precision")
        yield ffi.unpack(buf, size).decode("ascii")


def python_rows(arrs: Sequence[np.ndarray], kinds: Sequence[int], precision: int, row0: int, k: int) -> str:
    """What acx_format_rows writes, in Python (locale-independent): the definition it follows."""
    def cell(kind: int, v: Any) -> str:
        if kind == CSV_INT:
            return str(v)
        if kind == CSV_REPR:
            return repr(v)
        return "" if kind == CSV_G and math.isnan(v) else "%.*g" % (precision, v)

    cols = [[cell(kd, v) for v in a[row0 : row0 + k].tolist()] for a, kd in zip(arrs, kinds)]
    return "".join(",".join(row) + "\n" for row in zip(*cols))


def csv_cell(text: str) -> str:
    if any(ch in text for ch in ',"') or text != text.strip():
        return '"' + text.replace('"', '""') + '"'
    return text
