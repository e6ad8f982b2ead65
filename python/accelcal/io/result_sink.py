"""Result columns written chunk by chunk (the streamed estimators; docs/streaming.md), as
:func:`accelcal.io.recording.write_columns_csv` writes them whole: CSV (``repr`` for t,
``'%.9g'`` for the rest, the ``# key: value`` comments first) or Parquet by the name."""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pyarrow.parquet as pq

from ..errors import atomic_write
from .csvformat import REPR, csv_rows
from .parquet import ParquetSink, is_parquet

__all__ = ["ColumnSink", "write_deferred"]


class ColumnSink:
    """Result columns written chunk by chunk into an open file (text for CSV, binary for Parquet).

    Parameters
    ----------
    f : file
    names : list of str
        The columns, in order.
    meta : dict or None
        The comments (CSV: written first; Parquet: the key-value metadata). None: a CSV body
        without comments and header.
    parquet : bool
    """

    def __init__(self, f: Any, names: list[str], meta: dict | None, parquet: bool) -> None:
        self.sink = ParquetSink(f, names, meta) if parquet else None
        if self.sink is None and meta is not None:
            for k, v in meta.items():
                f.write(f"# {k}: {v}\n")
            f.write(",".join(names) + "\n")
        self.f = f
        self.formats = [REPR if k == "t" else "%.9g" for k in names]

    def write(self, columns: list[np.ndarray]) -> None:
        if self.sink is not None:
            self.sink.write(columns)
            return
        for text in csv_rows([np.asarray(c, float) for c in columns], self.formats):
            self.f.write(text)

    def close(self) -> None:
        if self.sink is not None:
            self.sink.close()


def write_deferred(output: Any, names: list[str], produce: Callable[[ColumnSink], dict]) -> None:
    """Write result columns whose comments are known only once every row is written (warnings that
    count samples): the rows into a temporary file beside the output, then the comments and the
    rows copied after them (a Parquet file row group by row group), atomically.

    Parameters
    ----------
    output : str or os.PathLike
        Parquet by the name .parquet, else CSV.
    names : list of str
    produce : callable
        ``produce(sink)`` writes the rows through ``sink.write`` and returns the comments.
    """
    parquet = is_parquet(output)
    folder = Path(output).resolve().parent
    with tempfile.TemporaryFile(mode="w+b" if parquet else "w+", dir=folder) as body:
        sink = ColumnSink(body, names, {} if parquet else None, parquet)
        meta = produce(sink)
        sink.close()
        body.seek(0)

        def write(f: Any) -> None:
            if not parquet:
                for k, v in meta.items():
                    f.write(f"# {k}: {v}\n")
                f.write(",".join(names) + "\n")
                shutil.copyfileobj(body, f, 1 << 20)
                return
            pf = pq.ParquetFile(body)
            final = ColumnSink(f, names, meta, True)
            for i in range(pf.metadata.num_row_groups):
                table = pf.read_row_group(i, use_threads=False)
                final.write([table.column(k).to_numpy() for k in names])
            final.close()

        atomic_write(output, write, mode="wb" if parquet else "w")
