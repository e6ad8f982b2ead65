"""A recording file as a source of chunks, CSV or Parquet by its name, for the commands that
stream (:mod:`accelcal.resolve_stream`, :mod:`accelcal.estimators.stream_scan`)."""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from .chunks import BLOCK_BYTES, Chunk, Fallback, Head, csv_chunks, csv_head
from .parquet import BATCH_ROWS, is_parquet, parquet_chunks, parquet_head
from .units import Scale

__all__ = ["ChunkSource", "open_chunks"]


@dataclass
class ChunkSource:
    """A recording's head and a way to read its rows in chunks, as often as needed.

    Attributes
    ----------
    head : Head
        The columns and metadata.
    total : int
        The progress bar's total: bytes of rows (CSV) or rows (Parquet).
    unit : str
        "B" or " rows".
    """

    head: Head
    total: int
    unit: str
    read: Callable[[Callable[[int], None] | None], Iterator[Chunk]]

    def chunks(self, progress: Callable[[int], None] | None = None) -> Iterator[Chunk]:
        """The rows from the first, in chunks (``progress`` called with each chunk's bytes or rows)."""
        return self.read(progress)


def open_chunks(path: Any, n_channels: int | None, scale: Scale | None, block_bytes: int = BLOCK_BYTES,
                batch_rows: int = BATCH_ROWS) -> ChunkSource:
    """A recording (CSV, or Parquet by its name) opened for reading in chunks.

    Raises
    ------
    InputError
        The head's error, as the whole-file reader words it.
    Fallback
        A CSV the chunked reader leaves to the whole-file reader.
    """
    if is_parquet(path):
        if scale is not None and scale.converts:
            raise Fallback("units stated for a Parquet recording")   # refused by the whole-file reader
        head, pf = parquet_head(path, n_channels)
        return ChunkSource(head, pf.metadata.num_rows, " rows", lambda tick: parquet_chunks(pf, head, batch_rows, tick))
    head = csv_head(path, n_channels, scale)
    return ChunkSource(head, max(os.path.getsize(path) - head.pos, 0), "B",
                       lambda tick: csv_chunks(path, head, block_bytes, tick))
