"""calibrate on a recording without pose labels reduced while it is read (accelcal.calibrate.still_reduce;
docs/streaming.md, "calibrate reduced while read"): the static detector's still stretches found over
passes in chunks, reduced to their sums, against the whole-file path (poses_from_recording and the
CLI's bytes).

The recordings: the independent generator's seed6 device (tests/python/test_stream_calibrate.py's
poses at Fibonacci directions joined by swings, here without their labels), its triad16 jig
(make_jig: known poses, 1 s turns), a hand-held session (make_handheld) and real recordings from
../shared/data (imucal's six-pose session, imu_tk's Xsens log).  The reduced path is checked to run
(a spy on the CLI's reduced_recordings, or the reducer's own result): on the code before it, an
unlabelled recording always went the whole-file way, and these tests fail there."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from accelcal.calibrate import still_reduce
from accelcal.calibrate.recordings import short_stretches
from accelcal.calibrate.still_reduce import reduce_unlabelled
from accelcal.cli import main as cli_main
from accelcal.io.device import save_device
from accelcal.io.recording import read_recording, recording_from_arrays, write_recording
from accelcal.readings import still_stream
from accelcal.readings.static import poses_from_recording

from cli_run import spy
from indep_model import load_real, make_handheld, make_jig, triad16
from shared_data import shared_file
from test_stream_calibrate import device, labelled


def unlabelled(dev, seed, *, ref=False, temps=True, noise_stated=True, hold=(150, 300)):
    """test_stream_calibrate's poses (held 2.5-5 s at 60 Hz, 23-sample swings) without their labels;
    ``noise_stated`` False: the device without noise_mps2 (the noise estimated from the data)."""
    rec = labelled(dev, np.random.default_rng(seed), hold=hold, ref=ref, temps=temps)
    return recording_from_arrays(rec.t, rec.raw, f=rec.f if ref else None, temp_c=rec.temp_c if temps else None)


def estimated(dev):
    return dataclasses.replace(dev, noise_mps2=0.0)


def same_poses(got, whole, temp_rtol=0.0):
    """Every field of two PoseSets equal (temp within ``temp_rtol`` relative)."""
    assert got.n_poses == whole.n_poses > 0
    for name in ("means", "n", "std", "step", "colour_r2", "f_ref"):
        assert np.array_equal(getattr(got, name), getattr(whole, name), equal_nan=True), name
    np.testing.assert_allclose(got.temp, whole.temp, rtol=temp_rtol, atol=0)
    assert got.info == whole.info
    assert got.set_aside == whole.set_aside


@pytest.mark.parametrize("block", [300, 1000, 4096, 1 << 20])
@pytest.mark.parametrize("stated", [True, False])
def test_reduced_stretches_equal_the_whole_file_ones(tmp_path, block, stated):
    """Every pose field bit for bit (temp and the colour ratios too: each stretch held while read),
    and the short stretches the detector leaves out; chunks of 300 B (about 7 rows: boundaries inside
    the stretches and inside the swings) to the whole file; the noise stated or estimated."""
    dev = device() if stated else estimated(device())
    rec = unlabelled(dev, 5, ref=True)
    path = tmp_path / "u.csv"
    write_recording(path, rec)
    red = reduce_unlabelled(path, dev, block_bytes=block, min_s=3.0)
    assert red is not None and not red.has_pose()
    whole_rec = read_recording(path, 6)
    same_poses(red.poses, poses_from_recording(whole_rec, dev, min_s=3.0))
    assert red.short == short_stretches(dev, [whole_rec], 3.0) and red.short
    assert red.n_samples == rec.n_samples


def test_long_stretches_take_a_fifth_pass(tmp_path, monkeypatch):
    """Runs of static blocks and stretches longer than MAX_STILL_ROWS (150 rows here; 2^18 by default)
    are not held: the detector's LongRun, the colour from the batch sums and a fifth pass adding the
    squared deviations row after row (bit for bit); temp summed in chunks (numpy adds a column
    pairwise: within 4.4e-16 relative, measured 2.2e-16)."""
    for mod in (still_stream, still_reduce):
        monkeypatch.setattr(mod, "MAX_STILL_ROWS", 150)
    spread = []
    real = still_reduce.IntervalSums.spread

    def counted(self, ch):
        spread.append(ch.n)
        return real(self, ch)

    monkeypatch.setattr(still_reduce.IntervalSums, "spread", counted)
    dev = device()
    rec = unlabelled(dev, 5)
    rec = recording_from_arrays(rec.t, rec.raw, temp_c=rec.temp_c + 0.37 * np.sin(np.arange(rec.n_samples)))
    path = tmp_path / "u.csv"
    write_recording(path, rec)
    red = reduce_unlabelled(path, dev, block_bytes=5000)
    assert red is not None and sum(spread) == rec.n_samples
    same_poses(red.poses, poses_from_recording(read_recording(path, 6), dev), temp_rtol=4.4e-16)


def test_a_stretch_off_gravity_is_set_aside(tmp_path, capsys, monkeypatch):
    """A still stretch read at 0.2 g (a coast, free fall) and without f: set aside "not at rest"
    with its |f| / g, as the whole-file path sets it aside; the CLI's bytes the whole-file ones."""
    dev = device()
    rec = unlabelled(dev, 7, temps=False)
    raw = rec.raw.copy()
    b = dev.nominal_offsets()
    raw[700:900] = np.rint(b + 0.2 * (raw[700:900] - b)).astype(np.int64)
    path = tmp_path / "g.csv"
    write_recording(path, recording_from_arrays(rec.t, raw))
    red = reduce_unlabelled(path, dev, block_bytes=2000)
    assert red is not None and [d["reason"] for d in red.poses.set_aside] == ["not at rest"]
    same_poses(red.poses, poses_from_recording(read_recording(path, 6), dev))
    calls, got = cli_against_whole(tmp_path, capsys, monkeypatch, dev, {"g.csv": read_recording(path, 6)})
    reduced_ran(calls, 1)
    assert got[0] == 0 and "set aside (not at rest)" in got[1]


def test_a_clipped_stretch_is_set_aside(tmp_path, capsys, monkeypatch):
    """A channel at the rail through a pose: its still stretch set aside "clipped" with its clipped
    rows, channel and level, as the whole-file path sets it aside; the CLI's bytes the whole-file
    ones (the summary names it)."""
    dev = device()
    lab = labelled(dev, np.random.default_rng(11), hold=(150, 300), temps=False)
    raw = lab.raw.copy()
    raw[lab.pose == 3, 1] = dev.raw_max
    rec = recording_from_arrays(lab.t, raw)
    path = tmp_path / "c.csv"
    write_recording(path, rec)
    red = reduce_unlabelled(path, dev, block_bytes=700)
    assert red is not None and [d["reason"] for d in red.poses.set_aside] == ["clipped"]
    same_poses(red.poses, poses_from_recording(read_recording(path, 6), dev))
    calls, got = cli_against_whole(tmp_path, capsys, monkeypatch, dev, {"c.csv": rec})
    reduced_ran(calls, 1)
    assert got[0] == 0 and "raw_1 at 10000" in got[1] + got[2]


def run_cli(args, capsys):
    code = cli_main.main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


def cli_against_whole(tmp_path, capsys, monkeypatch, dev, recs: dict, extra=()) -> tuple[list, tuple]:
    """``accelcal calibrate`` on the recordings ``recs`` (name -> Recording, written as named) with the
    reduced reader, then with it disabled: the same exit code, stdout (the output's name aside),
    stderr and written JSON.  Returns what reduced_recordings gave and the reduced run's
    (code, stdout, stderr)."""
    dpath = tmp_path / "dev.json"
    save_device(dev, dpath)
    paths = []
    for name, rec in recs.items():
        write_recording(tmp_path / name, rec)
        paths.append(str(tmp_path / name))
    calls = spy(monkeypatch, cli_main, "reduced_recordings")
    args = ["calibrate", "--device", str(dpath), *paths, *extra]
    got = run_cli(args + ["-o", str(tmp_path / "r.json")], capsys)
    monkeypatch.setattr(cli_main, "reduced_recordings", lambda *args: None)
    whole = run_cli(args + ["-o", str(tmp_path / "w.json")], capsys)
    assert got[0] == whole[0]
    assert got[1].replace("r.json", "w.json") == whole[1] and got[2] == whole[2]
    if whole[0] == 0:
        assert (tmp_path / "r.json").read_bytes() == (tmp_path / "w.json").read_bytes()
    return calls, got


def reduced_ran(calls, n: int) -> None:
    assert calls and calls[0] is not None and len(calls[0]) == n
    assert not any(r.has_pose() for r in calls[0])


#: name -> (f given, temp_c, noise stated, files, options, exit code, seed)
CASES = {
    "jigfree csv, noise stated": (False, False, True, ("u.csv",), (), 0, 20),
    "known poses parquet": (True, False, True, ("u.parquet",), (), 0, 20),
    "known poses, temp_c: too few poses": (True, True, True, ("u.csv",), (), 2, 20),
    "jigfree, noise estimated, temp_c": (False, True, False, ("u.csv",), (), 0, 20),
    "csv and parquet together": (False, False, True, ("a.csv", "b.parquet"), (), 0, 20),
    "min-static 3 s, temp_c": (False, True, True, ("u.csv",), ("--min-static", "3"), 0, 5),
}


@pytest.mark.parametrize("case", list(CASES))
def test_cli_bytes_equal_the_whole_file_ones(tmp_path, capsys, monkeypatch, case):
    """The reduced path runs (every recording reduced, none labelled) and the JSON, stdout and stderr
    are the whole-file command's byte for byte: jig-free and known poses, CSV and Parquet, the noise
    stated or estimated, several recordings, --min-static (the detector's short stretches named in
    the jig-free model's fallback); a refusal (12 poses do not determine the temperature model) with
    the detector's clause."""
    ref, temps, stated, names, extra, code, seed = CASES[case]
    dev = device() if stated else estimated(device())
    recs = {name: unlabelled(dev, seed + k, ref=ref, temps=temps) for k, name in enumerate(names)}
    calls, got = cli_against_whole(tmp_path, capsys, monkeypatch, dev, recs, extra)
    reduced_ran(calls, len(names))
    assert got[0] == code
    if code:
        assert "the static detector takes a pose from a still stretch" in got[2]
    if extra:
        assert "shorter than 3 s, were left out" in got[2]


def jig_stated(seed: int):
    """The independent generator's triad16 jig without labels, its stated f carried through each turn
    from the pose before (a jig's log of the orientation it was set to), and as given (none in the
    turns)."""
    rec = make_jig(seed=seed, device="triad16", rate=100.0, motion=False)["recording"]
    have = np.all(np.isfinite(rec.f), axis=1)
    last = np.maximum.accumulate(np.where(have, np.arange(rec.n_samples), 0))
    carried = rec.f[np.where(have[last], last, int(np.argmax(have)))]
    return recording_from_arrays(rec.t, rec.raw, f=carried), recording_from_arrays(rec.t, rec.raw, f=rec.f)


@pytest.mark.parametrize("kind", ["jig", "handheld"])
def test_cli_triad_jig_and_handheld(tmp_path, capsys, monkeypatch, kind):
    """The independent generator's triad16 jig (known poses, f carried through the 1 s turns) and a
    hand-held session (jig-free, smooth turns), their labels dropped: reduced, the whole-file bytes."""
    if kind == "jig":
        rec = jig_stated(3)[0]
    else:
        rec = make_handheld(seed=4, device="triad16", rate=100.0, labels=False)["recording"]
        rec = recording_from_arrays(rec.t, rec.raw)
    dev = dataclasses.replace(triad16(100.0), noise_mps2=0.0)
    calls, got = cli_against_whole(tmp_path, capsys, monkeypatch, dev, {"t.csv": rec})
    reduced_ran(calls, 1)
    assert got[0] == 0


@pytest.mark.parametrize("name", ["imucal", "xsens"])
def test_real_recordings_reduced(shared_data, tmp_path, capsys, monkeypatch, name):
    """imucal's six-pose session (3 poses each side, 10,376 rows) and imu_tk's Xsens log (40 still
    stretches, 51,175 rows) as contract CSVs without labels or reference (indep_model.load_real):
    reduced while read, the whole-file JSON, stdout and stderr byte for byte."""
    dev, rec, _ = load_real(name, shared_file)
    calls, got = cli_against_whole(tmp_path, capsys, monkeypatch, dev,
                                   {f"{name}.csv": recording_from_arrays(rec.t, rec.raw)}, ("--min-static", "1"))
    reduced_ran(calls, 1)
    assert got[0] == 0


def fallback_recordings(dev):
    """name -> (device, recording) that the reduced reader leaves to the whole-file path."""
    rng = np.random.default_rng(9)
    base = unlabelled(dev, 11, temps=False)
    out = {}
    dirs = np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 0, -1], [0, -1, 0], [-1, 0, 0]], float)
    tri = dataclasses.replace(triad16(100.0), noise_mps2=0.0)
    # a logger's static blocks joined by instant steps (the detector's block_log_intervals take the samples)
    blocks = 32768 + np.repeat(dirs[np.arange(12) % 6] * 16000, 300, axis=0) + rng.normal(0, 6, (3600, 3))
    out["blocks"] = (tri, recording_from_arrays(np.arange(3600) / 100.0, np.rint(blocks).astype(np.int64)))
    # a triad whose still stretches hold less than half the rows (the pose-means hint takes every row)
    moving = 32768 + 16000 * np.column_stack([np.sin(np.arange(4000) / 90.0), np.cos(np.arange(4000) / 90.0),
                                              0.1 * np.sin(np.arange(4000) / 50.0)])
    still = 32768 + np.repeat(dirs * 16000, 250, axis=0)
    mix = np.rint(np.vstack([still, moving]) + rng.normal(0, 6, (5500, 3))).astype(np.int64)
    out["mostly motion"] = (tri, recording_from_arrays(np.arange(5500) / 100.0, mix))
    # a tone at half the rate on one channel (the detector averages it out of the samples)
    raw = base.raw.copy()
    raw[:, 0] += np.where(np.arange(raw.shape[0]) % 2 == 0, 40, -40)
    out["tone"] = (dev, recording_from_arrays(base.t, raw))
    # f on part of a still stretch (none in the turns): the whole-file path refuses it, naming the sample
    out["f on part of a stretch"] = (tri, jig_stated(3)[1])
    return out


@pytest.mark.parametrize("case", ["blocks", "mostly motion", "tone", "f on part of a stretch"])
def test_fallbacks_give_the_whole_file_output(tmp_path, capsys, monkeypatch, case):
    """Where the reduced reader cannot give the whole-file path's answer (a logger's blocks,
    stretches holding less than half a triad's rows, a tone at half the rate, f given on part of a
    stretch), reduced_recordings gives None and the output is the whole-file command's."""
    dev, rec = fallback_recordings(device())[case]
    calls, _ = cli_against_whole(tmp_path, capsys, monkeypatch, dev, {"f.csv": rec})
    assert calls == [None]
