"""Reading ahead and writing behind (accelcal.io.pipeline), and resolve's use of them: order,
errors where the plain loop meets them, nothing written after a failure, no thread left."""
import threading
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from accelcal.errors import InputError
from accelcal.io import pipeline
from accelcal.io.parquet import ParquetSink
from accelcal.io.pipeline import WriteBehind, read_ahead
from accelcal.cli.main import main


def _threads(prefix):
    return [t for t in threading.enumerate() if t.name.startswith(prefix)]


def test_read_ahead_in_order_and_an_error_after_the_items_before_it():
    def items():
        for i in range(50):
            if i == 37:
                raise InputError("rec.csv", "bad cell", row=38, column="raw_0")
            yield i

    got = []
    with pytest.raises(InputError, match="row 38"):
        for i in read_ahead(items(), depth=2):
            got.append(i)
    assert got == list(range(37))
    assert not _threads("accelcal-read-ahead")


def test_read_ahead_stops_and_closes_its_source_when_the_consumer_stops():
    closed = []
    made = []

    def items():
        try:
            for i in range(10_000):
                made.append(i)
                yield i
        finally:
            closed.append(True)

    for i in read_ahead(items(), depth=1):
        if i == 5:
            break
    assert closed == [True]
    assert len(made) <= 5 + 3          # the one in hand, the queue's one, the one being put
    assert not _threads("accelcal-read-ahead")


class _Sink:
    def __init__(self, fail_at=None, delay=0.0):
        self.items, self.closed, self.fail_at, self.delay = [], False, fail_at, delay
        self.thread_names = set()

    def write(self, item):
        self.thread_names.add(threading.current_thread().name)
        time.sleep(self.delay)
        if item == self.fail_at:
            raise OSError("disk full")
        self.items.append(item)

    def close(self):
        self.closed = True


def test_write_behind_writes_in_order_in_its_thread_then_closes():
    sink = _Sink()
    with WriteBehind(sink, depth=2) as out:
        for i in range(200):
            out.write(i)
    assert sink.items == list(range(200)) and sink.closed
    assert sink.thread_names == {"accelcal-write-behind"}
    assert not _threads("accelcal-write-behind")


@pytest.mark.parametrize("where", ["in a write", "in the loop"])
def test_after_a_failure_nothing_is_written_and_the_sink_is_not_closed(where):
    """A write's error is raised in the caller's thread; an error of the loop drops what is queued."""
    sink = _Sink(fail_at=7) if where == "in a write" else _Sink(delay=0.01)
    with pytest.raises(OSError if where == "in a write" else RuntimeError, match="disk full|stop"):
        with WriteBehind(sink, depth=3) as out:
            for i in range(100 if where == "in a write" else 10):
                out.write(i)
            raise RuntimeError("stop")
    n = len(sink.items)
    time.sleep(0.1)
    assert len(sink.items) == n and not sink.closed
    assert sink.items == (list(range(7)) if where == "in a write" else list(range(n))) and n < 10
    assert not _threads("accelcal-write-behind")


def _recording(path, n=5000, bad_row=None):
    rng = np.random.default_rng(3)
    raw = 5000 + rng.integers(-3000, 3000, (n, 6))
    lines = ["# device: seed-6ch-r60", "t," + ",".join(f"raw_{k}" for k in range(6))]
    for i in range(n):
        cells = [repr(i / 60.0)] + [str(v) for v in raw[i]]
        if i + 1 == bad_row:
            cells[3] = "x7"          # raw_2 of the file's line bad_row + 2
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def test_resolve_writes_behind_in_a_thread_with_the_same_bytes(tmp_path, monkeypatch):
    src = tmp_path / "rec.csv"
    _recording(src)
    args = ["resolve", "--device", "default", "--calibration", "nominal", "--engine", "fixed", "--quiet", str(src)]
    seen = set()
    write = ParquetSink.write

    def spy(self, cols):
        seen.add(threading.current_thread().name)
        return write(self, cols)

    monkeypatch.setattr(ParquetSink, "write", spy)
    assert main(args + ["-o", str(tmp_path / "a.parquet")]) == 0
    assert seen == {"accelcal-write-behind"}
    # the same result as with the plain loop (no threads)
    assert main(args + ["-o", str(tmp_path / "a.csv")]) == 0
    monkeypatch.setattr("accelcal.resolve_stream.read_ahead", lambda it: it)
    monkeypatch.setattr("accelcal.resolve_stream.WriteBehind", _Plain)
    assert main(args + ["-o", str(tmp_path / "b.csv")]) == 0
    assert main(args + ["-o", str(tmp_path / "b.parquet")]) == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    assert pq.read_table(tmp_path / "a.parquet").equals(pq.read_table(tmp_path / "b.parquet"))


class _Plain:
    def __init__(self, sink):
        self.sink = sink

    def write(self, cols):
        self.sink.write(cols)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        if kind is None:
            self.sink.close()


def test_resolve_refuses_a_late_bad_cell_with_no_output_and_no_thread_left(tmp_path, capsys):
    src = tmp_path / "rec.csv"
    _recording(src, n=20000, bad_row=19000)
    out = tmp_path / "r.csv"
    rc = main(["resolve", "--device", "default", "--calibration", "nominal", "--engine", "fixed", "--quiet",
               str(src), "-o", str(out)])
    assert rc == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith("row 19002, column raw_2: expected an integer, got 'x7'"), err
    assert not out.exists() and not list(tmp_path.glob(".r.csv.*"))
    assert not _threads("accelcal-")


def test_result_parquet_floats_byte_stream_split_and_zstd(tmp_path):
    src = tmp_path / "rec.csv"
    _recording(src, n=3000)
    out = tmp_path / "r.parquet"
    assert main(["resolve", "--device", "default", "--calibration", "nominal", "--engine", "fixed", "--quiet",
                 str(src), "-o", str(out)]) == 0
    md = pq.ParquetFile(out).metadata
    cols = {md.schema.column(i).name: md.row_group(0).column(i) for i in range(md.num_columns)}
    for name in ("t", "f_x", "dw_z"):
        assert "BYTE_STREAM_SPLIT" in cols[name].encodings and cols[name].compression == "ZSTD", name
    assert "RLE_DICTIONARY" in cols["saturated"].encodings
    assert pipeline.DEPTH >= 1
