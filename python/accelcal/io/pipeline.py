"""Reading ahead and writing behind: a streamed command's three stages in three threads.

A streamed command (:mod:`accelcal.resolve_stream`) reads a chunk (pyarrow's CSV parser or
Parquet reader), computes it (numpy, the C core) and writes it (the C formatter of CSV rows, or
pyarrow's Parquet writer).  Much of the reading and writing runs in C with Python's GIL
released, so with the reading one chunk ahead in one thread (:func:`read_ahead`) and the writing
one chunk behind in another (:class:`WriteBehind`), the three stages overlap on a machine of two
or more cores.  The order of the chunks, what is written and the errors raised are those of the
plain loop: each stage takes its chunks in order, an exception of the reader is raised where the
loop would have met it, one of the writer at the next ``write`` or at ``close``, and nothing is
written after a failure (the caller's :func:`accelcal.errors.atomic_write` then removes the file).

Memory: up to ``depth`` + 1 chunks more in each stage (``DEPTH`` = 1: two blocks of CSV text and
their arrays, or two batches of Parquet rows and their row group).

Time (``python3 tools/bench_stream.py``; docs/streaming.md "Time and memory of resolve").
"""
from __future__ import annotations

import queue
import threading
from typing import Any, Callable, Iterable, Iterator, TypeVar

__all__ = ["read_ahead", "WriteBehind", "DEPTH"]

#: chunks held in each queue (one more is being read, and one written: 2 gave resolve 294 MB against
#: 287 MB at 3x10^6 Parquet rows, and 287 against 278 MB from CSV)
DEPTH = 1
#: how often (s) a blocked thread looks whether it is told to stop
_POLL_S = 0.05
_END = object()

T = TypeVar("T")


def _put(q: queue.Queue, item: Any, go_on: Callable[[], bool]) -> bool:
    """Put ``item`` while ``go_on()`` holds (looked at every _POLL_S while the queue is full); True
    when put."""
    while go_on():
        try:
            q.put(item, timeout=_POLL_S)
            return True
        except queue.Full:
            continue
    return False


def read_ahead(items: Iterable[T], depth: int = DEPTH) -> Iterator[T]:
    """``items`` in order, read by a thread of their own up to ``depth`` items ahead.

    An exception of ``items`` is raised here after the items before it.  When the consumer stops
    early (an exception, ``break``, the generator closed) the thread stops at its next item and
    ``items`` is closed; both before this generator returns.

    Parameters
    ----------
    items : iterable
        Read in the thread (it must not share state with the consumer but through its items).
    depth : int, optional
        Items held ahead, at least 1.

    Yields
    ------
    Each item of ``items``.
    """
    q: queue.Queue = queue.Queue(maxsize=max(int(depth), 1))
    stop = threading.Event()
    go_on = lambda: not stop.is_set()  # noqa: E731

    def run() -> None:
        it = iter(items)
        try:
            for item in it:
                if not _put(q, (item, None), go_on):
                    return
            _put(q, (_END, None), go_on)
        except BaseException as e:  # noqa: BLE001 - handed to the consumer, in order
            _put(q, (_END, e), go_on)
        finally:
            close = getattr(it, "close", None)
            if close is not None:
                close()

    thread = threading.Thread(target=run, name="accelcal-read-ahead", daemon=True)
    thread.start()
    try:
        while True:
            item, error = q.get()
            if error is not None:
                raise error
            if item is _END:
                return
            yield item
    finally:
        stop.set()
        thread.join()


class WriteBehind:
    """A sink whose ``write`` calls run in a thread of their own, in order, up to ``depth`` behind.

    Use it as a context manager around the loop that writes: on leaving the block normally the
    queued writes finish and ``sink.close()`` is called (``close``); on an exception the queued
    writes are dropped, the thread stops and ``sink`` is not closed but aborted (``abort``), so
    that nothing is written to the file after the failure.

    Parameters
    ----------
    sink : object
        With ``write(columns)`` and ``close()`` (:class:`accelcal.io.parquet.ParquetSink`,
        :class:`accelcal.resolve_stream.CsvSink`).  The items written must not be changed after.
    depth : int, optional
        Writes queued at most, at least 1.
    """

    def __init__(self, sink: Any, depth: int = DEPTH) -> None:
        self.sink = sink
        self._q: queue.Queue = queue.Queue(maxsize=max(int(depth), 1))
        self._stop = threading.Event()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="accelcal-write-behind", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            try:
                item = self._q.get(timeout=_POLL_S)
            except queue.Empty:
                if self._stop.is_set():
                    return
                continue
            if item is _END or self._stop.is_set():
                return
            try:
                self.sink.write(item)
            except BaseException as e:  # noqa: BLE001 - raised in the caller's thread
                self._error = e
                return

    def _raise(self) -> None:
        if self._error is not None:
            error, self._error = self._error, None
            raise error

    def write(self, columns: Any) -> None:
        """Queue ``columns`` for ``sink.write`` (an earlier write's exception is raised here)."""
        self._raise()
        if not _put(self._q, columns, self._thread.is_alive):
            self._raise()
            raise RuntimeError("WriteBehind: the writer has stopped")  # pragma: no cover - close()d before

    def close(self) -> None:
        """Finish the queued writes, then ``sink.close()`` (a write's exception is raised here)."""
        _put(self._q, _END, self._thread.is_alive)
        self._thread.join()
        self._raise()
        self.sink.close()

    def abort(self) -> None:
        """Drop the queued writes and stop the thread; ``sink.abort()`` where it has one (not
        ``close``)."""
        self._stop.set()
        self._thread.join()
        release = getattr(self.sink, "abort", None)
        if release is not None:
            release()

    def __enter__(self) -> "WriteBehind":
        return self

    def __exit__(self, kind: Any, value: Any, tb: Any) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()
