"""displacement in chunks (accelcal.estimators.displacement_stream, displacement_motions;
docs/streaming.md): the whole-file output byte for byte with chunk boundaries inside rests and inside
motions, from chunks of one row to one larger than the file; rows held bounded by a motion and its
rests; the whole-file command, its output and its words, where the recording warns or is refused."""
from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from accelcal.errors import InputError
from accelcal.estimators import displacement_motions, displacement_stream as ds
from accelcal.estimators.common import resolve_array
from accelcal.estimators.displacement import DispFloat, DisplaceParams, displace_stream
from accelcal.estimators.rest import RestThresholds, default_rest_params
from accelcal.estimators.displacement_stream import displacement_stream
from accelcal.io.calibration import Calibration
from accelcal.io.chunks import csv_chunks, csv_head
from accelcal.io.device import Device, default_device, default_triad, save_device
from accelcal.io.recording import read_recording, write_recording
from accelcal.io.recording_type import Recording
from accelcal.simulate import run_simulation

from cli_run import run

DEV = default_device()
NOMINAL = Calibration.nominal(DEV)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A rail recording of the default device: 4 strokes of 0.5 m in 2 s between rests of 2 s."""
    d = tmp_path_factory.mktemp("stream_disp")
    sim = run_simulation(DEV, "linear_actuator", seed=2, distance_m=0.5, travel_s=2.0, rest_s=2.0, strokes=4)
    write_recording(d / "rec.csv", sim.recording)
    write_recording(d / "rec.parquet", sim.recording)
    return {"dir": d, "rec": sim.recording, "csv": d / "rec.csv", "parquet": d / "rec.parquet"}


def disp_cli(capfd, rec, out, *args, device="default"):
    rc, _, err, _ = run(["displacement", "--device", device, "--calibration", "nominal", rec, "-o", out, "--quiet",
                         *args], capfd)
    return rc, err


def columns(path):
    text = path.read_text().splitlines()
    head = next(i for i, s in enumerate(text) if not s.startswith("#"))
    names = text[head].split(",")
    vals = np.array([[float(c) for c in s.split(",")] for s in text[head + 1:]])
    return {k: vals[:, j] for j, k in enumerate(names)}


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
@pytest.mark.parametrize("block", [1, 120, 997, 4099, 1 << 30])
def test_chunks_give_the_whole_file_bytes(files, capfd, block, engine, form):
    d = files["dir"]
    ref = d / f"whole_{engine}_{form}.csv"
    assert disp_cli(capfd, files["csv"], ref, "--whole-file", "--engine", engine, "--form", form) == (0, "")
    out = d / f"s_{block}_{engine}_{form}.csv"
    assert displacement_stream(DEV, NOMINAL, files["csv"], out, engine=engine, form=form,
                               block_bytes=block) == []    # it streamed
    assert out.read_bytes() == ref.read_bytes()
    starts = [c.start for c in csv_chunks(files["csv"], csv_head(files["csv"], 6, None), block)]
    cols = columns(ref)
    assert cols["corrected"].any() and ref.read_text().count("# zero_point_mps2: (") == 1
    if block < 1 << 20:
        rest, moving = cols["rest"], cols["corrected"] == 1
        # boundaries inside a rest and inside a motion (the detector's and the integration's state carried)
        assert any(rest[s] == 1 and rest[s - 1] == 1 for s in starts[1:])
        assert any(moving[s] and moving[s - 1] for s in starts[1:])
    else:
        assert starts == [0]                                   # one chunk larger than the file


@pytest.mark.parametrize("engine", ["float", "fixed"])
@pytest.mark.parametrize("rows", [1, 7, 250])
def test_parquet_in_rows_of_one_and_parquet_out(files, capfd, rows, engine):
    d = files["dir"]
    ref = d / f"whole_pq_{engine}.csv"
    assert disp_cli(capfd, files["parquet"], ref, "--whole-file", "--engine", engine)[0] == 0
    out = d / f"pq_{rows}_{engine}.csv"
    assert displacement_stream(DEV, NOMINAL, files["parquet"], out, engine=engine, batch_rows=rows) == []
    assert out.read_bytes() == ref.read_bytes()
    if rows == 7:
        refp, outp = d / "w.parquet", d / "s.parquet"
        assert disp_cli(capfd, files["parquet"], refp, "--whole-file")[0] == 0
        assert displacement_stream(DEV, NOMINAL, files["parquet"], outp, batch_rows=rows) == []
        a, b = pq.read_table(refp), pq.read_table(outp)
        assert a.schema == b.schema and a.equals(b) and a.schema.metadata == b.schema.metadata


@pytest.mark.parametrize("args", [("--axis", "x"), ("--omega", "none")])
def test_options_passed_on_give_the_whole_file_bytes(files, capfd, args):
    d = files["dir"]
    ref, out = d / "ow.csv", d / "os.csv"
    assert disp_cli(capfd, files["csv"], ref, *args, "--whole-file")[0] == 0
    kw = {"axis": args[1]} if args[0] == "--axis" else {"omega": args[1]}
    assert displacement_stream(DEV, NOMINAL, files["csv"], out, block_bytes=333, **kw) == []
    assert out.read_bytes() == ref.read_bytes()


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_a_triad_device_streams_the_whole_file_bytes(tmp_path, capfd, engine):
    tri = default_triad()
    save_device(tri, tmp_path / "tri.json")
    rec = run_simulation(tri, "linear_actuator", seed=22, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                         strokes=3).recording
    write_recording(tmp_path / "r.csv", rec)
    ref, out = tmp_path / "w.csv", tmp_path / "s.csv"
    assert disp_cli(capfd, tmp_path / "r.csv", ref, "--whole-file", "--engine", engine,
                    device=tmp_path / "tri.json")[0] == 0
    assert displacement_stream(tri, Calibration.nominal(tri), tmp_path / "r.csv", out, engine=engine,
                               block_bytes=500) == []
    assert out.read_bytes() == ref.read_bytes()


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_cli_streams_without_reading_the_whole_file(files, capfd, monkeypatch, engine):
    """Fails on the code before: displacement read the recording whole."""
    d = files["dir"]
    ref, out = d / f"cw_{engine}.csv", d / f"cs_{engine}.csv"
    assert disp_cli(capfd, files["csv"], ref, "--whole-file", "--engine", engine)[0] == 0

    def whole(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr("accelcal.cli.estimator_command.read_recording", whole)
    rc, err = disp_cli(capfd, files["csv"], out, "--engine", engine)
    assert rc == 0, err
    assert out.read_bytes() == ref.read_bytes()


def test_rows_held_are_a_motion_and_its_rests_not_the_recording(tmp_path, monkeypatch):
    """16 strokes (3,960 rows): the third pass holds at most the rows from one motion's end to the
    next motion's closing rest (a rest, a stroke, a rest and a stroke: 4 x 120 rows), the hold (15 rows)
    a rest is declared after, and a chunk; the second pass one rest and a chunk."""
    rec = run_simulation(DEV, "linear_actuator", seed=5, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                         strokes=16).recording
    write_recording(tmp_path / "r.parquet", rec)
    held = {"motion": 0, "rest": 0}
    feed_m, feed_r = displacement_motions.MotionPass.feed, ds.RestPass.feed

    def motion(self, *a):
        feed_m(self, *a)
        held["motion"] = max(held["motion"], self.f.shape[0])

    def rest(self, f):
        feed_r(self, f)
        held["rest"] = max(held["rest"], self.F.shape[0] + f.shape[0])
    monkeypatch.setattr(displacement_motions.MotionPass, "feed", motion)
    monkeypatch.setattr(ds.RestPass, "feed", rest)
    assert displacement_stream(DEV, NOMINAL, tmp_path / "r.parquet", tmp_path / "o.csv", batch_rows=10) == []
    assert rec.n_samples == 3960
    assert 240 < held["motion"] <= 4 * 120 + 15 + 10, held
    assert 0 < held["rest"] <= 120 + 2 * 10, held


def test_a_progress_bar_per_pass(files, tmp_path):
    bars = []

    class Bar:
        def __init__(self, total, unit):
            self.n = 0
            bars.append(self)

        def update(self, k):
            self.n += k

        def close(self):
            pass
    assert displacement_stream(DEV, NOMINAL, files["csv"], tmp_path / "o.csv", block_bytes=997, progress=Bar) == []
    size = files["csv"].stat().st_size
    assert len(bars) == 3 and all(0 < b.n <= size for b in bars) and len({b.n for b in bars}) == 1


def edited(files, name, keep):
    rec = files["rec"]
    path = files["dir"] / name
    write_recording(path, Recording(t=rec.t[keep], raw=rec.raw[keep]))
    return path


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
@pytest.mark.parametrize("block", [1, 997, 1 << 30])
def test_a_last_motion_not_ending_at_rest_is_left_out_in_chunks_too(files, capfd, engine, form, block):
    """The commonest warning (a recording stopped before the body was set down): the output ends in
    the rest before that motion, with the whole-file command's line, in the comments and on stderr."""
    path = edited(files, "open_end.csv", files["rec"].t < 15.0)      # in the 4th stroke
    ref, out = files["dir"] / f"oe_w_{engine}_{form}.csv", files["dir"] / f"oe_s_{engine}_{form}_{block}.csv"
    rc_w, err_w = disp_cli(capfd, path, ref, "--whole-file", "--engine", engine, "--form", form)
    assert rc_w == 0 and err_w.count("warning") == 1 and "does not end at rest" in err_w
    got = displacement_stream(DEV, NOMINAL, path, out, engine=engine, form=form, block_bytes=block)
    assert got == [err_w.strip().split("warning: ", 1)[1]]
    assert out.read_bytes() == ref.read_bytes()
    rc, err = disp_cli(capfd, path, out, "--engine", engine, "--form", form)
    assert (rc, err) == (rc_w, err_w)


@pytest.mark.parametrize("case", ["short_last_rest", "moving_start", "one_stroke_open"])
def test_what_warns_goes_the_whole_file_way_with_its_words(files, capfd, case):
    """A last rest shorter than a trend block (its test widened from the rests at its own length: not
    kept while reading), a recording that does not start at rest (warned), one whose only motion does
    not end at rest (refused): the whole-file command, its output and its lines; the chunked pass
    writes nothing."""
    t = files["rec"].t
    keep = {"short_last_rest": t < 12.9, "moving_start": t > 3.0, "one_stroke_open": t < 3.0}[case]
    path = edited(files, f"{case}.csv", keep)
    out = files["dir"] / f"{case}_s.csv"
    assert displacement_stream(DEV, NOMINAL, path, out, block_bytes=997) is None
    assert not out.exists()
    ref = files["dir"] / f"{case}_w.csv"
    rc_w, err_w = disp_cli(capfd, path, ref, "--whole-file")
    rc, err = disp_cli(capfd, path, out)
    assert (rc, err) == (rc_w, err_w) and ("displacement" in err) == (case != "short_last_rest")
    if rc == 0:
        assert out.read_bytes() == ref.read_bytes()
    else:
        assert rc == 2 and not out.exists() and "no motion can be reported" in err


def test_a_turned_recording_is_refused_in_the_same_words(tmp_path, capfd):
    rec = run_simulation(DEV, "handheld", seed=3, n_poses=3, hold_s=2.0, move_s=1.0, initial_rest_s=2.0).recording
    write_recording(tmp_path / "h.csv", rec)
    rc_w, err_w = disp_cli(capfd, tmp_path / "h.csv", tmp_path / "w.csv", "--whole-file")
    rc, err = disp_cli(capfd, tmp_path / "h.csv", tmp_path / "s.csv")
    assert (rc, err) == (rc_w, err_w) and rc == 2 and "turned" in err
    assert not (tmp_path / "s.csv").exists()


def test_bad_rows_are_refused_by_the_scan_in_the_whole_file_words(files, capfd, monkeypatch):
    rec = read_recording(files["csv"], 6)
    raw = rec.raw.copy()
    raw[700, 2] = 20000                                       # outside the device's range, in the 3rd stroke
    path = files["dir"] / "range.csv"
    write_recording(path, Recording(t=rec.t, raw=raw))
    ref, out = files["dir"] / "rw.csv", files["dir"] / "rs.csv"
    rc_w, err_w = disp_cli(capfd, path, ref, "--whole-file")
    with pytest.raises(InputError, match="outside device"):
        displacement_stream(DEV, NOMINAL, path, out, block_bytes=997)

    def whole(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr("accelcal.cli.estimator_command.read_recording", whole)
    rc, err = disp_cli(capfd, path, out)
    assert (rc, err) == (rc_w, err_w) and rc == 2 and not out.exists() and not ref.exists()


def test_a_row_written_twice_is_left_to_the_whole_file_reader(files, capfd):
    """displacement's reader leaves out a row written twice (with a note), which the chunked reader
    refuses as t not increasing: the whole-file command runs, with its note."""
    lines = files["csv"].read_text().splitlines(keepends=True)
    head = next(i for i, x in enumerate(lines) if not x.startswith("#"))
    path = files["dir"] / "twice.csv"
    path.write_text("".join(lines[:head + 500] + [lines[head + 499]] + lines[head + 500:]))
    assert displacement_stream(DEV, NOMINAL, path, files["dir"] / "tw_s.csv", block_bytes=997) is None
    ref, out = files["dir"] / "tw_w.csv", files["dir"] / "tw_c.csv"
    rc_w, err_w = disp_cli(capfd, path, ref, "--whole-file")
    rc, err = disp_cli(capfd, path, out)
    assert (rc, err) == (rc_w, err_w) and rc == 0 and out.read_bytes() == ref.read_bytes()
    assert "note" in err


@pytest.mark.parametrize("args", [("--resample",), ("--keep-turned",)])
def test_the_options_not_built_for_chunks_read_the_whole_file(files, capfd, args):
    d = files["dir"]
    ref, out = d / "nw.csv", d / "ns.csv"
    rc_w, err_w = disp_cli(capfd, files["csv"], ref, *args, "--whole-file")
    assert (rc_w, err_w) == disp_cli(capfd, files["csv"], out, *args) and rc_w == 0
    assert out.read_bytes() == ref.read_bytes()


def test_the_median_of_the_rests_estimates_read_back_in_small_groups(files, capfd, monkeypatch):
    """The rests' correlation estimates are read back from their file a few values at a time
    (MEDIAN_BYTES): the same median, the same bytes."""
    d = files["dir"]
    ref, out = d / "mw.csv", d / "ms.csv"
    assert disp_cli(capfd, files["csv"], ref, "--whole-file")[0] == 0
    monkeypatch.setattr(ds, "MEDIAN_BYTES", 200)
    assert displacement_stream(DEV, NOMINAL, files["csv"], out, block_bytes=997) == []
    assert out.read_bytes() == ref.read_bytes()


@pytest.mark.parametrize("size", [1, 2, 37, 500])
def test_the_detector_and_the_float_integrator_in_chunks_are_the_whole_recordings(files, size):
    """RestDetector (the offline form's rest decisions) and DispFloat (the float streaming form) fed
    in chunks give displace_core's flags and outputs over the whole recording."""
    rec = files["rec"]
    f = resolve_array(DEV, NOMINAL, rec, "float")[0]
    p = DisplaceParams(dt=1 / 60, rest=default_rest_params(DEV, 60.0, f_sigma=0.02))
    whole = displace_stream(f, p)
    det, core = ds.RestDetector(p), DispFloat(p.dt, None, RestThresholds.of(p.rest))
    parts = [(det.step(f[i:i + size]), core.step(f[i:i + size])) for i in range(0, len(f), size)]
    assert np.array_equal(np.concatenate([a for a, _ in parts]), whole["rest"])
    for k in ("v", "p", "zp", "flags", "nseg", "rest"):
        assert np.array_equal(np.concatenate([b[k] for _, b in parts]), whole[k]), k
    assert len(core.segments) == len(whole["segments"]) == 4
    for a, b in zip(core.segments, whole["segments"]):
        assert a[:2] == b[:2] and np.array_equal(a[2], b[2])


def _tipped_stroke(tmp_path, tip_deg):
    """A level triad stating its noise (0.02 m/s^2) at 100 Hz: 2 s at rest, 0.5 m along x with one sine
    period of acceleration in 2 s, 2 s at rest; with ``tip_deg`` the body then tips about y (0.5 s)
    and holds still to the end, 2.5 s (test_displacement_checks' stroke, not tipped back)."""
    g, rate = 9.80665, 100.0
    d = Device(name="triad", sample_rate_hz=rate, gravity_mps2=g, raw_min=-32768, raw_max=32767,
               positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 16384 / g),
               zero_counts=np.zeros(3), noise_mps2=0.02)
    t = np.arange(int((6.0 if tip_deg == 0.0 else 9.0) * rate)) / rate
    a = np.where((t >= 2.0) & (t < 4.0), 0.5 * 2 * np.pi / 4.0 * np.sin(np.pi * (t - 2.0)), 0.0)
    up = np.clip((t - 6.0) / 0.5, 0.0, 1.0)
    th = np.radians(tip_deg) * (3 * up**2 - 2 * up**3)
    body = np.column_stack([a * np.cos(th) - g * np.sin(th), np.zeros_like(t), a * np.sin(th) + g * np.cos(th)])
    raw = np.round((body + 0.02 * np.random.default_rng(1).standard_normal(body.shape)) * d.counts_per_mps2)
    save_device(d, tmp_path / "d.json")
    write_recording(tmp_path / "r.csv", Recording(t=t, raw=raw.astype(np.int64)))
    return d


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_a_body_still_but_turned_is_seen_while_reading(tmp_path, capfd, engine):
    """The still blocks are checked as the rows go by (HeldStretches), after the output's end too: a
    body tipped by 10 deg after its stroke and held to the end (a last motion that does not end at
    rest, which alone streams) is warned of by the whole-file command, which runs (the chunked pass
    writes nothing); the stroke alone streams."""
    for tip, streams in ((0.0, True), (10.0, False)):
        d = _tipped_stroke(tmp_path, tip)
        out, ref = tmp_path / f"s{tip}.csv", tmp_path / f"w{tip}.csv"
        got = displacement_stream(d, Calibration.nominal(d), tmp_path / "r.csv", out, engine=engine, block_bytes=700)
        rc_w, err_w = disp_cli(capfd, tmp_path / "r.csv", ref, "--whole-file", "--engine", engine,
                               device=tmp_path / "d.json")
        assert rc_w == 0 and ("turned from the first rest" in err_w) == (not streams), err_w
        if streams:
            assert got == [] and out.read_bytes() == ref.read_bytes()
        else:
            assert got is None and not out.exists()
            assert disp_cli(capfd, tmp_path / "r.csv", out, "--engine", engine, device=tmp_path / "d.json") == \
                (rc_w, err_w)
            assert out.read_bytes() == ref.read_bytes()
