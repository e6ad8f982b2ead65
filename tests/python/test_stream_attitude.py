"""attitude in chunks (accelcal.estimators.attitude_stream; docs/streaming.md): the whole-file
output byte for byte (CSV; the same table and metadata in Parquet) with chunk boundaries inside
the unsettled start, inside a gated (slow) stretch and inside a swing, both engines, and the
whole-file warnings, which count samples and stand above the rows."""
from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from accelcal.errors import InputError
from accelcal.io.calibration import Calibration
from accelcal.io.chunks import csv_chunks, csv_head
from accelcal.io.device import save_device
from accelcal.io.recording import write_recording
from accelcal.io.recording_type import Recording
from accelcal.estimators.attitude_stream import attitude_stream
from accelcal.simulate import run_simulation

from cli_run import run
from estimator_devices import adxl_pendulum_device

DEV = adxl_pendulum_device()
NOMINAL = Calibration.nominal(DEV)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A pendulum recording that starts mid-swing (its first samples unsettled), with five samples
    of one channel at its rail (|g| off there)."""
    d = tmp_path_factory.mktemp("stream_att")
    rec = run_simulation(DEV, "pendulum", seed=1, duration_s=20.0).recording
    raw = rec.raw[35:].copy()
    raw[200:205, 0] = DEV.raw_max
    rec = Recording(t=rec.t[35:], raw=raw)
    save_device(DEV, d / "dev.json")
    write_recording(d / "rec.csv", rec)
    write_recording(d / "rec.parquet", rec)
    return {"dir": d, "csv": d / "rec.csv", "parquet": d / "rec.parquet"}


def att_cli(capfd, files, rec, out, *args):
    rc, _, err, _ = run(["attitude", "--device", files["dir"] / "dev.json", "--calibration", "nominal", rec, "-o", out,
                         "--quiet", *args], capfd)
    return rc, err


def columns(path):
    text = path.read_text().splitlines()
    head = next(i for i, s in enumerate(text) if not s.startswith("#"))
    vals = np.array([[float(c) for c in s.split(",")] for s in text[head + 1:]])
    return {k: vals[:, j] for j, k in enumerate(text[head].split(","))}


@pytest.mark.parametrize("engine", ["float", "fixed"])
@pytest.mark.parametrize("block", [120, 997])
def test_chunks_give_the_whole_file_bytes_and_warnings(files, capfd, engine, block):
    d = files["dir"]
    ref = d / f"w_{engine}.csv"
    rc, err = att_cli(capfd, files, files["csv"], ref, "--engine", engine, "--whole-file")
    assert rc == 0, err
    out = d / f"s_{engine}_{block}.csv"
    warnings = attitude_stream(DEV, NOMINAL, files["csv"], out, engine=engine, block_bytes=block)
    assert warnings is not None                                         # it streamed
    assert len(warnings) >= 2 and [f"accelcal attitude: warning: {w}" for w in warnings] == err.strip().splitlines()
    cols = columns(ref)
    starts = [c.start for c in csv_chunks(files["csv"], csv_head(files["csv"], 6, None), block)][1:]
    uns, gated = cols["unsettled"], cols["gated"]
    assert any(uns[s] == 1 and uns[s - 1] == 1 for s in starts)
    assert any(gated[s] == 1 and gated[s - 1] == 1 for s in starts)
    assert any(gated[s] == 0 and gated[s - 1] == 0 and uns[s] == 0 for s in starts)
    assert out.read_bytes() == ref.read_bytes()


def test_parquet_gives_the_whole_file_table_and_metadata(files, capfd):
    d = files["dir"]
    ref, out = d / "w.parquet", d / "s.parquet"
    assert att_cli(capfd, files, files["parquet"], ref, "--engine", "fixed", "--whole-file")[0] == 0
    assert attitude_stream(DEV, NOMINAL, files["parquet"], out, engine="fixed", batch_rows=97) is not None
    a, b = pq.read_table(ref), pq.read_table(out)
    assert a.equals(b) and a.schema.metadata == b.schema.metadata
    assert b"warning_1" in b.schema.metadata


def test_cli_streams_without_reading_the_whole_file(files, capfd, monkeypatch):
    d = files["dir"]
    ref, out = d / "cw.csv", d / "cs.csv"
    rc_w, err_w = att_cli(capfd, files, files["csv"], ref, "--whole-file")

    def whole(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr("accelcal.cli.estimator_command.read_recording", whole)
    assert att_cli(capfd, files, files["csv"], out) == (rc_w, err_w)
    assert out.read_bytes() == ref.read_bytes()


@pytest.mark.parametrize("case", ["range", "lost"])
def test_bad_or_irregular_recordings_go_the_whole_file_way(files, capfd, case):
    d = files["dir"]
    rec = run_simulation(DEV, "pendulum", seed=2, duration_s=10.0).recording
    t, raw = rec.t, rec.raw.copy()
    if case == "range":
        raw[500, 4] = DEV.raw_max + 1
    else:                                           # a lost sample: filled by the whole-file command, with a warning
        t, raw = np.delete(t, 300), np.delete(raw, 300, axis=0)
    path = d / f"{case}.csv"
    write_recording(path, Recording(t=t, raw=raw))
    out = d / f"{case}_s.csv"
    if case == "range":                                       # the whole-file command's error, from the scan
        with pytest.raises(InputError, match="outside device"):
            attitude_stream(DEV, NOMINAL, path, out, block_bytes=997)
    else:
        assert attitude_stream(DEV, NOMINAL, path, out, block_bytes=997) is None
    assert not out.exists()
    ref = d / f"{case}_w.csv"
    rc_w, err_w = att_cli(capfd, files, path, ref, "--whole-file")
    assert att_cli(capfd, files, path, out) == (rc_w, err_w)
    assert rc_w == (2 if case == "range" else 0)
    if rc_w == 0:
        assert out.read_bytes() == ref.read_bytes() and "warning" in err_w
    else:
        assert not out.exists()
