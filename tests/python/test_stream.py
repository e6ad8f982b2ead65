"""resolve in chunks (accelcal.resolve_stream, io/chunks, io/parquet): the whole-file result byte for
byte at any chunk size, the whole-file errors, Parquet in and out (docs/streaming.md)."""
from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from accelcal.io.calibration import Calibration
from accelcal.io.device import default_device
from accelcal.io.chunks import csv_chunks, csv_head
from accelcal.io.recording import read_recording, write_recording
from accelcal.resolve import resolve_recording
from accelcal.resolve_stream import resolve_stream
from accelcal.simulate import run_simulation

from cli_run import one_refusal, run

DEV = default_device()


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A hand-held recording (rests and moves, reference w) of the default device, its device
    calibration (nominal), and the whole-file outputs of both engines."""
    d = tmp_path_factory.mktemp("stream")
    sim = run_simulation(DEV, "handheld", seed=3, n_poses=3, hold_s=2.0, move_s=1.0, initial_rest_s=2.0)
    rec = sim.recording
    write_recording(d / "rec.csv", rec)
    return {"dir": d, "rec": rec, "csv": d / "rec.csv"}


def whole(capfd, rec_path, out, *args):
    rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", rec_path, "-o", out,
                         "--whole-file", *args], capfd)
    return rc, err


def chunk_starts(path, block):
    return [c.start for c in csv_chunks(path, csv_head(path, DEV.n_channels, None), block)]


@pytest.mark.parametrize("engine", ["float", "fixed"])
@pytest.mark.parametrize("block", [120, 997, 4099])
def test_chunks_give_the_whole_file_bytes(files, capfd, engine, block):
    ref = files["dir"] / f"whole_{engine}.csv"
    assert whole(capfd, files["csv"], ref, "--engine", engine)[0] == 0
    out = files["dir"] / f"s_{engine}_{block}.csv"
    res = resolve_stream(DEV, Calibration.nominal(DEV), files["csv"], out, engine=engine, block_bytes=block)
    assert res is not None                                   # it streamed, not the whole-file way
    starts = chunk_starts(files["csv"], block)
    assert len(starts) > 3
    pose = files["rec"].pose
    # chunk boundaries inside a rest (a pose held: the previous sample the same pose) and inside a motion
    assert any(pose[s] >= 0 and pose[s - 1] == pose[s] for s in starts[1:])
    assert any(pose[s] < 0 and pose[s - 1] < 0 for s in starts[1:])
    assert out.read_bytes() == ref.read_bytes()


def test_cli_streams_the_same_bytes(files, capfd):
    ref, out = files["dir"] / "w.csv", files["dir"] / "c.csv"
    assert whole(capfd, files["csv"], ref, "--engine", "fixed")[0] == 0
    rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", files["csv"], "-o", out,
                         "--engine", "fixed", "--quiet"], capfd)
    assert rc == 0, err
    assert out.read_bytes() == ref.read_bytes()


def test_parquet_out_is_parquet_with_the_whole_file_values(files, capfd):
    out = files["dir"] / "o.parquet"
    rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", files["csv"], "-o", out,
                         "--engine", "fixed"], capfd)
    assert rc == 0, err
    assert out.read_bytes()[:4] == b"PAR1"                    # before: CSV under that name
    table = pq.read_table(out)
    f, a, flags = resolve_recording(DEV, Calibration.nominal(DEV), read_recording(files["csv"], 6), "fixed")
    assert np.array_equal(table.column("f_y").to_numpy(), f[:, 1])
    assert np.array_equal(table.column("dw_z").to_numpy(), a[:, 2])
    assert np.array_equal(table.column("saturated").to_numpy(), flags)
    assert table.schema.metadata[b"engine"] == b"fixed"


@pytest.mark.parametrize("whole_file", [False, True])
def test_parquet_recording_reads_back_and_resolves_the_same(files, capfd, whole_file):
    rec = files["rec"]
    pq_in = files["dir"] / "rec.parquet"
    write_recording(pq_in, rec)
    back = read_recording(pq_in, 6)
    for name in ("t", "raw", "f", "w", "dw", "temp_c", "pose"):
        assert np.array_equal(getattr(back, name), getattr(rec, name), equal_nan=True), name
    assert back.metadata == rec.metadata
    out_pq, out_csv = files["dir"] / f"pp{whole_file}.parquet", files["dir"] / f"pc{whole_file}.csv"
    extra = ["--whole-file"] if whole_file else []
    for out in (out_pq, out_csv):
        rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", pq_in, "-o", out,
                             "--engine", "fixed", *extra], capfd)
        assert rc == 0, err
    ref = files["dir"] / "ref_fixed.csv"
    assert whole(capfd, files["csv"], ref, "--engine", "fixed")[0] == 0
    assert out_csv.read_bytes() == ref.read_bytes()
    f, _, _ = resolve_recording(DEV, Calibration.nominal(DEV), rec, "fixed")
    assert np.array_equal(pq.read_table(out_pq).column("f_x").to_numpy(), f[:, 0])


def test_a_csv_named_parquet_is_refused(files, capfd):
    fake = files["dir"] / "fake.parquet"
    fake.write_bytes(files["csv"].read_bytes())
    out = files["dir"] / "never.csv"
    rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", fake, "-o", out], capfd)
    assert rc == 2 and one_refusal(err) and "not a Parquet file" in err, err
    assert not out.exists()


def bad_copy(files, name, edit):
    lines = files["csv"].read_text().splitlines()
    first = next(i for i, s in enumerate(lines) if s.startswith("t,"))
    edit(lines, first)
    p = files["dir"] / name
    p.write_text("\n".join(lines) + "\n")
    return p


@pytest.mark.parametrize("case", ["cell", "t_then_cell", "range_then_t", "range"])
def test_bad_rows_mid_stream_give_the_whole_file_error(files, capfd, case):
    def edit(lines, first):
        n = len(lines) - first - 1
        row = lambda k: first + 1 + k  # noqa: E731
        if case in ("cell", "t_then_cell"):
            lines[row(n - 5)] = lines[row(n - 5)].replace(",", ",x", 1)      # a bad cell near the end
        if case == "t_then_cell":
            lines[row(n // 2)] = lines[row(n // 2 - 1)]                        # t repeats mid-file
        if case in ("range_then_t", "range"):
            cells = lines[row(40)].split(",")
            cells[2] = "70000"                                                 # raw_1 beyond the device
            lines[row(40)] = ",".join(cells)
        if case == "range_then_t":
            lines[row(n - 3)] = lines[row(n - 4)]
    bad = bad_copy(files, f"bad_{case}.csv", edit)
    out_w, out_s = files["dir"] / f"bw_{case}.csv", files["dir"] / f"bs_{case}.csv"
    rc_w, err_w = whole(capfd, bad, out_w)
    from accelcal.errors import InputError
    with pytest.raises(InputError) as e:
        resolve_stream(DEV, Calibration.nominal(DEV), bad, out_s, block_bytes=500)
    assert rc_w == 2 and err_w.strip() == f"accelcal resolve: error: {e.value}"
    assert not out_s.exists() and not out_w.exists()
    assert not list(files["dir"].glob(".bs_*"))                 # no temp file left behind


def test_rails_add_the_clipped_column_as_the_whole_file_does(files, capfd):
    def edit(lines, first):
        for k in (30, 400, 401):
            cells = lines[first + 1 + k].split(",")
            cells[1] = str(DEV.raw_max)
            lines[first + 1 + k] = ",".join(cells)
    rail = bad_copy(files, "rail.csv", edit)
    ref, out = files["dir"] / "rw.csv", files["dir"] / "rs.csv"
    rc, err_w = whole(capfd, rail, ref, "--engine", "fixed")
    assert rc == 0 and "ADC's rail" in err_w
    res = resolve_stream(DEV, Calibration.nominal(DEV), rail, out, engine="fixed", block_bytes=700)
    assert res is not None and res.clip_warnings[0] in err_w
    assert out.read_bytes() == ref.read_bytes()
    assert ",clipped" in out.read_text().splitlines()[2]


def test_milliseconds_go_the_whole_file_way_with_the_same_result(files, capfd):
    rec = files["rec"]
    ms = files["dir"] / "ms.csv"
    rec2 = read_recording(files["csv"], 6)
    rec2.t = rec.t * 1000.0
    write_recording(ms, rec2)
    ref, out = files["dir"] / "msw.csv", files["dir"] / "mss.csv"
    assert whole(capfd, ms, ref)[0] == 0
    assert resolve_stream(DEV, Calibration.nominal(DEV), ms, out, block_bytes=900) is None
    rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", ms, "-o", out], capfd)
    assert rc == 0 and "milliseconds" in err
    assert out.read_bytes() == ref.read_bytes()


@pytest.mark.parametrize("side", ["high", "low"])
def test_a_pile_inside_the_range_gives_the_whole_file_column_and_warning(files, capfd, side):
    """A channel piled at a level inside the range, above (its largest readings) or below (its
    smallest): the streamed extremes and their counts (from the code histograms) find it as the
    whole file does."""
    rec = read_recording(files["csv"], 6)
    if side == "high":
        level = int(np.percentile(rec.raw[:, 2], 93))
        rec.raw[:, 2] = np.minimum(rec.raw[:, 2], level)      # raw_2 clips at a level inside the range
    else:
        level = int(np.percentile(rec.raw[:, 2], 7))
        rec.raw[:, 2] = np.maximum(rec.raw[:, 2], level)
    pile = files["dir"] / f"pile_{side}.csv"
    write_recording(pile, rec)
    ref, out = files["dir"] / f"pw_{side}.csv", files["dir"] / f"ps_{side}.csv"
    rc, err_w = whole(capfd, pile, ref, "--engine", "fixed")
    assert rc == 0 and f"raw_2: {int(np.count_nonzero(rec.raw[:, 2] == level))} at {level}" in err_w
    res = resolve_stream(DEV, Calibration.nominal(DEV), pile, out, engine="fixed", block_bytes=2000)
    assert res is not None and len(res.clip_warnings) == 1 and res.clip_warnings[0] in err_w
    assert out.read_bytes() == ref.read_bytes()


@pytest.mark.parametrize("seed", range(6))
def test_clip_levels_from_counts_are_clip_levels(seed):
    from accelcal.readings.clipping import clip_levels, clip_levels_counts
    from accelcal.readings.noise import noise_for
    rng = np.random.default_rng(seed)
    raw = rng.normal(30000, rng.uniform(1, 400), size=(5000, 6)).round().astype(np.int64)
    raw[:, seed % 6] = np.minimum(raw[:, seed % 6], np.percentile(raw[:, seed % 6], rng.uniform(80, 100)))
    raw[:, (seed + 1) % 6] = np.maximum(raw[:, (seed + 1) % 6], np.percentile(raw[:, (seed + 1) % 6], 3))
    noise = noise_for(DEV, raw, 30)[0]
    want = clip_levels(raw, DEV, noise, 30)
    got = clip_levels_counts([np.unique(raw[:, j], return_counts=True) for j in range(6)], DEV, noise)
    assert got is not None
    for k in ("lo", "hi", "inside_lo", "inside_hi"):
        assert np.array_equal(getattr(got, k), getattr(want, k)), k
    assert want.any_inside()


def test_simulate_and_rate_write_parquet_by_name(files, capfd):
    d = files["dir"]
    for out in (d / "sim.parquet", d / "sim.csv"):
        rc, _, err, _ = run(["simulate", "--device", "default", "--motion", "rate_table", "--seed", "2", "-o", out], capfd)
        assert rc == 0, err
    assert (d / "sim.parquet").read_bytes()[:4] == b"PAR1"
    a, b = read_recording(d / "sim.parquet", 6), read_recording(d / "sim.csv", 6)
    assert np.array_equal(a.raw, b.raw) and np.array_equal(a.t, b.t) and a.metadata == b.metadata
    for out in (d / "rate.parquet", d / "rate.csv"):
        rc, _, err, _ = run(["rate", "--device", "default", "--calibration", "nominal", d / "sim.parquet", "-o", out],
                            capfd)
        assert rc == 0, err
    table = pq.read_table(d / "rate.parquet")
    text = (d / "rate.csv").read_text().splitlines()
    header = next(i for i, s in enumerate(text) if not s.startswith("#"))
    csv_vals = np.array([[float(c) for c in s.split(",")] for s in text[header + 1:]])
    assert text[header].split(",") == table.column_names
    pq_vals = np.column_stack([table.column(c).to_numpy() for c in table.column_names])
    assert np.array_equal(pq_vals[:, 0], csv_vals[:, 0])
    assert np.allclose(pq_vals, csv_vals, rtol=1e-8, atol=1e-12, equal_nan=True)
    comments = dict(s[2:].split(": ", 1) for s in text[:header])
    assert {k.decode(): v.decode() for k, v in table.schema.metadata.items()} == comments


class _Tty:
    """A text stream that says it is a terminal (tqdm draws on it)."""

    def __init__(self, tty: bool) -> None:
        self.text, self.tty = [], tty

    def write(self, s):
        self.text.append(s)

    def flush(self):
        pass

    def isatty(self):
        return self.tty


@pytest.mark.parametrize("tty", [True, False])
def test_progress_bar_on_a_terminal_only(files, monkeypatch, tty):
    from accelcal.resolve_stream import progress_factory
    err = _Tty(tty)
    monkeypatch.setattr("sys.stderr", err)
    out = files["dir"] / f"bar{tty}.csv"
    assert resolve_stream(DEV, Calibration.nominal(DEV), files["csv"], out, block_bytes=2000,
                          progress=progress_factory("resolve", delay=0.0)) is not None
    assert ("resolve" in "".join(err.text)) == tty


def test_parquet_in_small_batches_gives_the_whole_file_bytes(files, capfd):
    pq_in = files["dir"] / "rec_b.parquet"
    write_recording(pq_in, files["rec"])
    ref, out = files["dir"] / "bw.csv", files["dir"] / "bs.csv"
    assert whole(capfd, pq_in, ref)[0] == 0          # the Parquet file's w are the simulation's, not 9 digits
    n = files["rec"].n_samples
    assert resolve_stream(DEV, Calibration.nominal(DEV), pq_in, out, batch_rows=n // 2 - 1) is not None  # a last batch of 2
    assert out.read_bytes() == ref.read_bytes()
    assert resolve_stream(DEV, Calibration.nominal(DEV), pq_in, out, batch_rows=(n - 1) // 3) is not None
    assert out.read_bytes() == ref.read_bytes()


def test_chunked_read_is_the_whole_file_read(files):
    """read_recording reads a plain CSV in chunks (calibrate, diagnose and the estimators read so):
    every array and the metadata are the whole-file reader's."""
    rec = read_recording(files["csv"], 6)
    assert any(s.startswith("t,") and s.endswith(",pose") for s in files["csv"].read_text().splitlines()[:12])
    ref = read_recording(files["csv"], 6, whole=True)
    for name in ("t", "raw", "f", "w", "dw", "temp_c", "pose"):
        a, b = getattr(rec, name), getattr(ref, name)
        assert a.dtype == b.dtype and np.array_equal(a, b, equal_nan=True), name
    assert rec.metadata == ref.metadata and rec.line(17) == ref.line(17) and rec.notes == ref.notes == []
    from accelcal.io.chunks import read_chunked
    small = read_chunked(files["csv"], 6, None, block_bytes=333)
    assert np.array_equal(small.raw, ref.raw) and np.array_equal(small.f, ref.f, equal_nan=True)


def test_convert_writes_parquet_and_refuses_parquet_input(files, capfd):
    d = files["dir"]
    rng = np.random.default_rng(1)
    lines = ["t,raw_0,raw_1,raw_2"] + [f"{k / 100!r},{int(rng.normal(0, 30))},{int(rng.normal(0, 30))},"
                                        f"{int(16384 + rng.normal(0, 30))}" for k in range(600)]
    (d / "tri.csv").write_text("\n".join(lines) + "\n")
    for out in (d / "tri.parquet", d / "tri_o.csv"):
        rc, _, err, _ = run(["convert", d / "tri.csv", "-o", out, "--device-out", d / "tri.json"], capfd)
        assert rc == 0, err
    assert (d / "tri.parquet").read_bytes()[:4] == b"PAR1"
    a, b = read_recording(d / "tri.parquet"), read_recording(d / "tri_o.csv")
    assert np.array_equal(a.raw, b.raw) and np.array_equal(a.t, b.t) and a.metadata == b.metadata
    rc, _, err, _ = run(["convert", d / "tri.parquet", "-o", d / "again.csv"], capfd)
    assert rc == 2 and one_refusal(err) and "contract recording" in err and not (d / "again.csv").exists()


def test_stderr_is_the_whole_file_commands(files, capfd):
    """An ignored column and the core's saturation: the same lines on stderr, streamed or not."""
    lines = files["csv"].read_text().splitlines()
    first = next(i for i, s in enumerate(lines) if s.startswith("t,"))
    lines[first] += ",note"
    for i in range(first + 1, len(lines)):
        lines[i] += ",x"
    p = files["dir"] / "extra.csv"
    p.write_text("\n".join(lines) + "\n")
    outs = []
    for extra in ([], ["--whole-file"]):
        out = files["dir"] / f"e{len(extra)}.csv"
        rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", p, "-o", out, "--quiet",
                             "--engine", "fixed", *extra], capfd)
        assert rc == 0, err
        outs.append((err, out.read_bytes()))
    assert "ignored column note" in outs[0][0]
    assert outs[0] == outs[1]


@pytest.mark.parametrize("wide", [False, True])
def test_fixed_engine_refuses_what_the_core_cannot_take_as_the_whole_file_does(files, capfd, wide):
    """The fixed engine's checks: a reading beyond the device's range (its error first), and, for a
    device whose range is wider than the core's uint16 input, a reading inside the device's range the
    core cannot take (the streamed loop looks at every reading only where a chunk's extremes say so)."""
    import dataclasses
    from accelcal.io.device import save_device
    dev = dataclasses.replace(DEV, raw_max=100000) if wide else DEV
    dev_path = files["dir"] / f"dev_{wide}.json"
    save_device(dev, dev_path)

    def edit(lines, first):
        n = len(lines) - first - 1
        cells = lines[first + 1 + n - 40].split(",")
        cells[3] = "70000"                                        # raw_2, late in the file
        lines[first + 1 + n - 40] = ",".join(cells)
    bad = bad_copy(files, f"core_{wide}.csv", edit)
    out_w, out_s = files["dir"] / f"cw_{wide}.csv", files["dir"] / f"cs_{wide}.csv"
    rc, _, err_w, _ = run(["resolve", "--device", str(dev_path), "--calibration", "nominal", str(bad), "-o",
                           str(out_w), "--whole-file", "--engine", "fixed"], capfd)
    assert rc == 2 and not out_w.exists()
    if wide:    # the core's tables refuse the device: the whole-file command words it, nothing streamed
        assert resolve_stream(dev, Calibration.nominal(dev), bad, out_s, engine="fixed", block_bytes=700) is None
        assert "does not fit the C core's uint16 input" in err_w
        rc, _, err_s, _ = run(["resolve", "--device", str(dev_path), "--calibration", "nominal", str(bad), "-o",
                               str(out_s), "--engine", "fixed"], capfd)
        assert rc == 2 and err_s == err_w and not out_s.exists()
        return
    from accelcal.errors import InputError
    with pytest.raises(InputError) as e:
        resolve_stream(dev, Calibration.nominal(dev), bad, out_s, engine="fixed", block_bytes=700)
    assert err_w.strip() == f"accelcal resolve: error: {e.value}" and "is outside device" in str(e.value)
    assert not out_s.exists()
