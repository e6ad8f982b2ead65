"""rate in chunks (accelcal.estimators.rate_stream, stream_scan; docs/streaming.md): the whole-file
output byte for byte with chunk boundaries inside rests and inside motions, both engines; the
whole-file command where only the whole recording tells (stamps off the grid, held readings, bad
rows), with its output and its message."""
from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from accelcal.errors import InputError
from accelcal.io.calibration import Calibration
from accelcal.io.device import default_device
from accelcal.io.chunks import csv_chunks, csv_head
from accelcal.io.recording import read_recording, write_recording
from accelcal.io.recording_type import Recording
from accelcal.estimators.rate_stream import rate_stream
from accelcal.readings.noise_stream import median_of_counts
from accelcal.readings.held import held_runs
from accelcal.cli.main import main
from accelcal.resolve_stream import progress_factory
from accelcal.simulate import run_simulation

from cli_run import edited_copy, run

DEV = default_device()
NOMINAL = Calibration.nominal(DEV)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A hand-held recording of the default device (rests and moves)."""
    d = tmp_path_factory.mktemp("stream_rate")
    sim = run_simulation(DEV, "handheld", seed=3, n_poses=3, hold_s=2.0, move_s=1.0, initial_rest_s=2.0)
    write_recording(d / "rec.csv", sim.recording)
    return {"dir": d, "rec": sim.recording, "csv": d / "rec.csv"}


def rate_cli(capfd, rec, out, *args):
    rc, _, err, _ = run(["rate", "--device", "default", "--calibration", "nominal", rec, "-o", out, "--quiet",
                         *args], capfd)
    return rc, err


def columns(path):
    text = path.read_text().splitlines()
    head = next(i for i, s in enumerate(text) if not s.startswith("#"))
    names = text[head].split(",")
    vals = np.array([[float(c) for c in s.split(",")] for s in text[head + 1:]])
    return {k: vals[:, j] for j, k in enumerate(names)}


@pytest.mark.parametrize("engine", ["float", "fixed"])
@pytest.mark.parametrize("block", [120, 997, 4099])
def test_chunks_give_the_whole_file_bytes(files, capfd, engine, block):
    d = files["dir"]
    ref = d / f"whole_{engine}.csv"
    assert rate_cli(capfd, files["csv"], ref, "--engine", engine, "--whole-file")[0] == 0
    out = d / f"s_{engine}_{block}.csv"
    assert rate_stream(DEV, NOMINAL, files["csv"], out, engine=engine, block_bytes=block) == []   # it streamed
    starts = [c.start for c in csv_chunks(files["csv"], csv_head(files["csv"], 6, None), block)]
    assert len(starts) > 3
    cols = columns(ref)
    rest, moving = cols["rest"], np.abs(cols["w_x"]) + np.abs(cols["w_y"]) + np.abs(cols["w_z"]) > 0
    # boundaries inside a rest and inside a motion (the integrator's state carried over)
    assert any(rest[s] == 1 and rest[s - 1] == 1 for s in starts[1:])
    assert any(rest[s] == 0 and rest[s - 1] == 0 and moving[s] and moving[s - 1] for s in starts[1:])
    assert out.read_bytes() == ref.read_bytes()


def test_cli_streams_without_reading_the_whole_file(files, capfd, monkeypatch):
    d = files["dir"]
    ref, out = d / "cw.csv", d / "cs.csv"
    assert rate_cli(capfd, files["csv"], ref, "--whole-file")[0] == 0

    def whole(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr("accelcal.cli.estimator_command.read_recording", whole)
    rc, err = rate_cli(capfd, files["csv"], out)
    assert rc == 0, err
    assert out.read_bytes() == ref.read_bytes()


def test_parquet_in_and_out_stream_the_whole_file_values(files, capfd):
    d = files["dir"]
    rec_pq = d / "rec.parquet"
    write_recording(rec_pq, files["rec"])
    ref, out = d / "pw.parquet", d / "ps.parquet"
    assert rate_cli(capfd, rec_pq, ref, "--engine", "fixed", "--whole-file")[0] == 0
    assert rate_stream(DEV, NOMINAL, rec_pq, out, engine="fixed", batch_rows=100) == []
    a, b = pq.read_table(ref), pq.read_table(out)
    assert a.schema == b.schema and a.equals(b)


def edited(files, name, edit):
    return edited_copy(files["csv"], 6, files["dir"] / name, edit)


def drop_sample(t, raw):
    keep = np.ones(t.size, bool)
    keep[300] = False
    return t[keep], raw[keep]


def hold_rows(t, raw):
    return t, np.repeat(raw[::2], 2, axis=0)[:t.size]


def bad_range(t, raw):
    raw[400, 2] = 20000
    return t, raw


@pytest.mark.parametrize("case, edit", [("lost", drop_sample), ("held", hold_rows), ("range", bad_range)])
def test_what_the_whole_recording_tells_goes_the_whole_file_way(files, capfd, case, edit):
    path = edited(files, f"{case}.csv", edit)
    out = files["dir"] / f"{case}_s.csv"
    if case == "range":                                       # the whole-file command's error, from the scan
        with pytest.raises(InputError, match="outside device"):
            rate_stream(DEV, NOMINAL, path, out, block_bytes=997)
    else:
        assert rate_stream(DEV, NOMINAL, path, out, block_bytes=997) is None
    assert not out.exists()                                   # nothing written
    ref = files["dir"] / f"{case}_w.csv"
    rc_w, err_w = rate_cli(capfd, path, ref, "--whole-file")
    rc, err = rate_cli(capfd, path, out)
    assert (rc, err) == (rc_w, err_w)
    if rc == 0:
        assert out.read_bytes() == ref.read_bytes()
        assert "warning" in err                               # the lost sample filled, the held readings
    else:
        assert rc == 2 and not out.exists()


@pytest.mark.parametrize("seed", range(5))
def test_median_of_counts_is_the_median(seed):
    rng = np.random.default_rng(seed)
    x = rng.choice(rng.normal(size=7), size=int(rng.integers(1, 60)))
    vals, counts = np.unique(x, return_counts=True)
    assert median_of_counts(dict(zip(vals.tolist(), counts.tolist()))) == float(np.median(x))


class _Tty:
    """A text stream that says whether it is a terminal (tqdm draws only on one)."""

    def __init__(self, tty: bool) -> None:
        self.text, self.tty = [], tty

    def write(self, s):
        self.text.append(s)

    def flush(self):
        pass

    def isatty(self):
        return self.tty


@pytest.mark.parametrize("tty, quiet", [(True, False), (False, False), (True, True)])
def test_progress_bar_on_a_terminal_unless_quiet(files, monkeypatch, tty, quiet):
    monkeypatch.setattr("accelcal.cli.estimator_command.progress_factory", lambda kind: progress_factory(kind, 0.0))
    err = _Tty(tty)
    monkeypatch.setattr("sys.stderr", err)
    out = files["dir"] / f"bar{tty}{quiet}.csv"
    assert main(["rate", "--device", "default", "--calibration", "nominal", str(files["csv"]), "-o", str(out)]
                + (["--quiet"] if quiet else [])) == 0
    assert ("rate" in "".join(err.text)) == (tty and not quiet)


def held_patterns(rng):
    noisy = rng.integers(4990, 5010, (400, 6))
    yield noisy
    yield np.repeat(noisy, 2, axis=0)                                   # held 2 rows
    yield np.repeat(noisy, 3, axis=0)[:1000]
    yield np.repeat(noisy, rng.integers(2, 5, 400), axis=0)             # uneven holds
    one = noisy.copy()
    one[:, 1:] = 5000                                                   # one channel moves
    yield np.repeat(one, rng.integers(1, 4, 400), axis=0)
    yield np.repeat(noisy[:30], rng.integers(1, 40, 30), axis=0)        # long runs
    yield np.full((50, 6), 5000)


@pytest.mark.parametrize("seed", range(4))
def test_run_counts_over_chunks_are_held_runs(seed):
    from accelcal.estimators.stream_scan import RunCounts
    rng = np.random.default_rng(seed)
    ks = []
    for raw in held_patterns(rng):
        k, _ = held_runs(raw)
        ks.append(k)
        cuts = np.sort(rng.choice(np.arange(1, raw.shape[0]), size=5, replace=False))
        runs = RunCounts()
        for part in np.split(raw, cuts):
            runs.add(part)
        got = runs.held(raw.shape[1])
        assert got == k or (got is None and k > 1)          # None: the whole-file command decides
    assert 1 in ks and any(k > 1 for k in ks)


def test_units_stated_for_a_parquet_recording_are_the_whole_file_error(files, capfd):
    d = files["dir"]
    rec_pq = d / "units.parquet"
    write_recording(rec_pq, files["rec"])
    rc_w, err_w = rate_cli(capfd, rec_pq, d / "uw.csv", "--whole-file", "--units", "g", "--lsb", "0.001")
    rc, err = rate_cli(capfd, rec_pq, d / "us.csv", "--units", "g", "--lsb", "0.001")
    assert rc_w == 2 and (rc, err) == (rc_w, err_w) and not (d / "us.csv").exists()


def test_resolve_refuses_units_stated_for_a_parquet_recording_as_the_whole_file_command(files, capfd):
    d = files["dir"]
    rec_pq = d / "units_r.parquet"
    write_recording(rec_pq, files["rec"])
    outs = []
    for out, extra in ((d / "rw.csv", ["--whole-file"]), (d / "rs.csv", [])):
        rc, _, err, _ = run(["resolve", "--device", "default", "--calibration", "nominal", rec_pq, "-o", out,
                             "--units", "g", "--lsb", "0.001", *extra], capfd)
        outs.append((rc, err.replace("--whole-file", "")))
        assert not out.exists()
    assert outs[0][0] == 2 and outs[0] == outs[1]            # before: resolved in chunks, the units ignored


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_bad_rows_are_the_whole_file_error_without_reading_it_whole(files, capfd, monkeypatch, engine):
    rec = read_recording(files["csv"], 6)
    t, raw = rec.t.copy(), rec.raw.copy()
    raw[-20, 3] = 20000                                       # out of the device's range, near the end
    path = files["dir"] / f"bad_{engine}.csv"
    write_recording(path, Recording(t=t, raw=raw))
    lines = path.read_text().splitlines(keepends=True)
    a, b = lines[-41].split(",", 1), lines[-40].split(",", 1)
    lines[-40] = a[0] + "," + b[1]                            # and t not increasing before it: the reader's first
    path.write_text("".join(lines))
    rc_w, err_w = rate_cli(capfd, path, files["dir"] / "bw.csv", "--whole-file", "--engine", engine)
    assert rc_w == 2 and "strictly increasing" in err_w

    def whole(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr("accelcal.cli.estimator_command.read_recording", whole)
    out = files["dir"] / "bs.csv"
    assert rate_cli(capfd, path, out, "--engine", engine) == (rc_w, err_w)
    assert not out.exists()
