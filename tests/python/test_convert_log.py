"""A serial monitor's capture (``accelcal convert --format log``) and readings held for several
rows by a logger faster than its sensor (``accelcal.readings.held``).

The captures are written here from the shape such files have (FastAhrs's calibration
notebooks' data_sample*.csv, which carry no licence and are not used): a banner, a prompt
before each pose, three readings a line in m/s^2 on the chip's LSB, each reading printed on
four lines because the monitor reads 400 lines/s of a 100 Hz sensor.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from accelcal.calibrate import calibrate_recordings
from accelcal.convert.formats import convert_file, detect_format
from accelcal.io.device import load_device
from accelcal.diagnose import diagnose
from accelcal.readings.held import distinct_recordings, distinct_rows, held_factor, held_runs, held_text
from accelcal.io.recording import read_recording
from accelcal.io.units import scale_from_options
from cli_run import one_refusal, run

G = 9.80665
LSB = 0.000244 * G                      # m/s^2 per count (0.244 mg, +-8 g)
ZERO = np.array([112.0, -135.0, 236.0])  # counts


def _scale():
    return scale_from_options("mps2", LSB, None, 16, None)


def capture(path, seed=0, poses=8, distinct=100, hold=4, noise=3.0, jitter=0.0):
    """Write a capture; returns the counts of every row (n, 3) and each row's pose."""
    rng = np.random.default_rng(seed)
    F = Rotation.random(poses, random_state=seed).apply([0.0, 0.0, G])
    rows, lab = [], []
    lines = ["--- Available filters and text transformations: colorize, debug, default",
             "--- More details at http://bit.ly/pio-monitor-filters", ">>> Place accelerometer on flat surface!"]
    for p in range(poses):
        lines += [">>> Type key when ready...", ">>> Gathering data for 10 seconds..."]
        c = np.round(ZERO + F[p] / LSB + noise * rng.standard_normal((distinct, 3)))
        reps = np.full(distinct, hold)
        if jitter:
            odd = rng.random(distinct) < jitter
            reps[odd] += rng.choice([-1, 1], odd.sum())
        c = np.repeat(c, reps, axis=0)
        rows.append(c)
        lab.append(np.full(c.shape[0], p))
        lines += [", ".join(f"{v * LSB:.10f}" for v in r) for r in c]
    path.write_text("\n".join(lines) + "\n")
    return np.concatenate(rows).astype(np.int64), np.concatenate(lab)


def test_a_monitor_capture_converts_with_a_pose_per_block(tmp_path, capfd):
    src = tmp_path / "data_sample.csv"
    counts, lab = capture(src)
    assert detect_format(src) == "log"
    rc, out, err, _ = run(["convert", src, "--units", "mps2", "--lsb", repr(LSB), "--rate", "400", "--blocks",
                           "-o", tmp_path / "r.csv", "--device-out", tmp_path / "d.json"], capfd)
    assert rc == 0, err
    assert out.startswith("log: 3200 rows, 3 channels") and "8 poses (block_1, " in out
    assert "split the readings into 8 block(s); each block is a pose" in err
    assert "100 % of the rows repeat" not in err and "held for 4 rows" in err and "about 100 Hz" in err
    rec = read_recording(tmp_path / "r.csv")
    np.testing.assert_array_equal(rec.raw, counts)
    np.testing.assert_array_equal(rec.pose, lab)
    assert rec.t[1] - rec.t[0] == pytest.approx(1 / 400)
    # without --blocks: one stretch, the blocks joined by instant steps, no labels
    conv = convert_file(src, scale=_scale(), rate_hz=400.0)
    assert conv.format == "log" and not conv.recording.has_pose()


def test_held_rows_count_once_in_a_calibration_and_a_diagnosis(tmp_path, capfd):
    src = tmp_path / "data_sample.csv"
    capture(src, seed=3, poses=12, jitter=0.1)
    conv = convert_file(src, "log", scale=_scale(), rate_hz=400.0, blocks=True)
    rec, dev = conv.recording, conv.device
    assert held_factor(rec.raw) == 4
    once, note = distinct_rows(rec)
    assert note and "held for 4 rows" in note and 1150 <= once.n_samples <= 1250
    cal = calibrate_recordings(dev, [rec], method="jigfree")
    ref = calibrate_recordings(dev, [once], method="jigfree")
    assert any("held for 4 rows" in n for n in cal.extra["notes"])
    np.testing.assert_allclose(cal.offsets, ref.offsets, atol=1e-9)
    assert cal.extra["fit"]["chi2"] == pytest.approx(ref.extra["fit"]["chi2"], rel=1e-9)
    np.testing.assert_allclose(cal.offsets, ZERO, atol=3.0)
    res = diagnose(dev, cal, [rec])
    assert res["n_samples"] <= once.n_samples and any("held for 4 rows" in n for n in res["notes"])
    # rows read once: nothing held to note (the 400 Hz device gives way to the distinct rows' 100 Hz)
    notes = calibrate_recordings(dev, [once], method="jigfree").extra.get("notes")
    assert not any("held" in n for n in notes) and any("taken as 100 Hz" in n for n in notes)


def test_held_rows_with_a_device_at_the_sensor_s_rate_keep_that_rate(tmp_path):
    """The device file may state the sensor's own rate (100 Hz) while the rows come at 400 Hz:
    that rate stands (it was divided again, to 25 Hz, and the static windows then spanned 4 x
    their time: 16 poses and a residual 7x larger on a real MPU-6050 log held 4 times); with
    the rows' rate in the device file it is divided as before.  Both calibrate alike."""
    import dataclasses
    src = tmp_path / "data_sample.csv"
    capture(src, seed=3, poses=12, jitter=0.1)
    conv = convert_file(src, "log", scale=_scale(), rate_hz=400.0, blocks=True)
    rec, dev400 = conv.recording, conv.device
    dev100 = dataclasses.replace(dev400, sample_rate_hz=100.0)
    _, d, notes = distinct_recordings([rec], dev100)
    assert d.sample_rate_hz == 100.0 and any("is the rate of the distinct readings" in n for n in notes)
    _, d, notes = distinct_recordings([rec], dev400)
    assert d.sample_rate_hz == 100.0 and any("is taken as 100 Hz" in n for n in notes)
    a = calibrate_recordings(dev100, [rec], method="jigfree")
    b = calibrate_recordings(dev400, [rec], method="jigfree")
    np.testing.assert_allclose(a.offsets, b.offsets, atol=1e-9)


@pytest.mark.parametrize("factor", [4, 2])
def test_a_decimated_recording_takes_the_rate_of_its_time_stamps(tmp_path, factor):
    """Every 2nd or 4th row of a 100 Hz log, read with the 100 Hz device:
    the device's rate gives way to the one the time stamps give, with a note, and the
    calibration is that with a device at that rate (with 100 Hz the static windows spanned
    4 x their time: 5 poses instead of 10 on a real MPU-6050 log).  Read whole, no note."""
    import dataclasses
    src = tmp_path / "data_sample.csv"
    capture(src, seed=5, poses=12, hold=1, distinct=400)
    conv = convert_file(src, "log", scale=_scale(), rate_hz=100.0, blocks=True)
    rec, dev = conv.recording, conv.device
    sub = rec.select(np.arange(0, rec.n_samples, factor))
    _, d, notes = distinct_recordings([sub], dev)
    assert d.sample_rate_hz == pytest.approx(100.0 / factor) and any("taken as" in n for n in notes)
    a = calibrate_recordings(dev, [sub], method="jigfree")
    sub2 = rec.select(np.arange(0, rec.n_samples, factor))
    b = calibrate_recordings(dataclasses.replace(dev, sample_rate_hz=100.0 / factor), [sub2], method="jigfree")
    np.testing.assert_allclose(a.offsets, b.offsets, atol=1e-9)
    _, d, notes = distinct_recordings([rec], dev)
    assert d.sample_rate_hz == 100.0 and not notes


def test_chance_repeats_are_not_held():
    """A sensor quieter than a code repeats rows by chance: runs of geometric lengths, whose
    most common length is 1."""
    rng = np.random.default_rng(5)
    quiet = np.round(1000 + 0.25 * rng.standard_normal((5000, 3))).astype(np.int64)
    same = np.mean(np.all(quiet[1:] == quiet[:-1], axis=1))
    assert same > 0.5                       # most rows repeat the one before
    assert held_factor(quiet) == 1
    held = np.repeat(np.round(1000 + 3 * rng.standard_normal((1000, 3))), 3, axis=0).astype(np.int64)
    assert held_factor(held) == 3 and held_factor(held[:1]) == 1
    # a static jig on a coarse lattice: 60 poses of 200 rows, each on one code of every channel
    poses = np.repeat(64 * rng.integers(-200, 200, (60, 3)), 200, axis=0)
    assert held_factor(poses) == 1


def test_readings_held_for_uneven_runs_are_held(tmp_path, capfd):
    """A sensor whose rate is no whole fraction of the logger's (a real LSM303 polled at 10 Hz,
    hu-zza/uBot_firmware: runs of 4-10 rows, no length shared by 80 % of them) holds its
    readings too: a still recording of 63 runs had been calibrated from "58 static poses" and a
    slide cut into 25 "rests".  Runs of one length (3) and chance repeats (geometric: single
    rows the most common; here also with a mean of 8 rows) keep the old verdicts."""
    import dataclasses
    from accelcal.io.device import save_device, default_triad
    from accelcal.io.calibration import Calibration, save_calibration
    from accelcal.io.recording import recording_from_arrays, write_recording
    rng = np.random.default_rng(11)
    lengths = rng.integers(5, 11, 60)
    vals = np.round(1000 + 30 * np.cumsum(rng.standard_normal((60, 3)), axis=0)).astype(np.int64)
    raw = np.repeat(vals, lengths, axis=0)
    k, first = held_runs(raw)
    assert k == int(round(float(np.mean(lengths[1:-1])))) and first.size == 60
    assert held_text(k, first, raw.shape[0]) == \
        f"{lengths[1:-1].min()}-{lengths[1:-1].max()} rows ({np.mean(lengths[1:-1]):.1f} on average)"
    # chance repeats with a mean run of 8 rows (p = 7/8 that all three channels repeat)
    chance = np.cumsum(rng.random((4000, 1)) > 7 / 8, axis=0) * np.array([[1, 1, 1]]) + 1000
    assert held_factor(chance) == 1
    # a noiseless slow ramp of one channel (0.3 counts a row, the others still): runs of 3-4 rows,
    # but only one channel changes where a run ends -- no new reading
    ramp = np.column_stack([np.floor(1000 + 0.3 * np.arange(3000)), np.full(3000, 20), np.full(3000, -7)])
    assert held_factor(ramp.astype(np.int64)) == 1
    # the distinct readings' rate is the rows' over the mean run, not over its rounding
    _, d_u, notes_u = distinct_recordings([recording_from_arrays(np.arange(raw.shape[0]) / 10.0, raw)],
                                          dataclasses.replace(default_triad(), sample_rate_hz=10.0))
    assert d_u.sample_rate_hz == pytest.approx(10.0 / np.mean(lengths[1:-1]), rel=1e-9), notes_u
    # a still sensor logged so: the poses and rests count its readings once, and the estimators say it
    d = default_triad()
    save_device(d, tmp_path / "d.json")
    g = d.counts_per_mps2 * d.gravity_mps2
    still = np.repeat(np.round(d.zero_counts + np.array([0, 0, 1.0]) * g
                               + 2.0 * rng.standard_normal((60, 3))).astype(np.int64), lengths, axis=0)
    rec = recording_from_arrays(np.arange(still.shape[0]) / d.sample_rate_hz, still)
    write_recording(tmp_path / "r.csv", rec)
    once, note = distinct_rows(rec)
    assert once.n_samples == 60 and note and f"held for {held_text(k, first, raw.shape[0])}" in note
    cal = Calibration(device=d.name, method="full", offsets=d.nominal_offsets(), sensitivity=d.nominal_sensitivity())
    save_calibration(cal, tmp_path / "c.json")
    rc, _, err, _ = run(["displacement", "--device", tmp_path / "d.json", "--calibration", tmp_path / "c.json",
                         tmp_path / "r.csv", "-o", tmp_path / "o.csv"], capfd)
    assert "warning: each reading is held for" in err and "a rest found within one is no rest" in err, err


@pytest.mark.parametrize("body,args,where", [
    ("banner\n0.1, 0.2, 0.3\n" * 6 + "0.1, 0.2\n", ["--rate", "100"], "row 13"),
    ("banner\n" + "1, 2, 3\n" * 12, [], "--rate"),
    ("banner\n" + "1, 2, 3\n" * 12 + "1.5, 2, 3\n", ["--rate", "100"], "row 14, column field 1"),
    ("banner\n" + "1, 2, 3\n" * 12, ["--rate", "100", "--blocks", "--regions", "{r}"], "--blocks and --regions"),
])
def test_bad_logs_are_one_line_naming_the_row(tmp_path, capfd, body, args, where):
    src = tmp_path / "cap.txt"
    src.write_text(body)
    (tmp_path / "r.json").write_text('{"a": {"start": 0, "end": 5}}')
    args = [a.replace("{r}", str(tmp_path / "r.json")) for a in args]
    rc, out, err, _ = run(["convert", src, "--format", "log", *args, "-o", tmp_path / "o.csv"], capfd)
    assert rc == 2 and where in err.splitlines()[-1] and one_refusal(err), err   # (the notes made before it)
    assert not (tmp_path / "o.csv").exists()


def test_blocks_is_for_logs(tmp_path, capfd):
    src = tmp_path / "cap.txt"
    capture(src, poses=2, distinct=10)
    dev_path = tmp_path / "d.json"
    rc, _, err, _ = run(["convert", src, "--units", "mps2", "--lsb", repr(LSB), "--rate", "400", "-o",
                         tmp_path / "r.csv", "--device-out", dev_path], capfd)
    assert rc == 0, err
    assert load_device(dev_path).sample_rate_hz == 400.0
    rc, _, err, _ = run(["convert", tmp_path / "r.csv", "--blocks", "-o", tmp_path / "o.csv"], capfd)
    assert rc == 2 and "--blocks: csv files have no blocks" in err


def test_a_capture_cut_short_in_its_last_line_is_read_with_a_note(tmp_path, capfd):
    """A monitor stopped mid-line: its last line holds one or two numbers and no line end;
    the readings before it are read, with a note.  The same line inside the file is refused."""
    src = tmp_path / "data_sample.csv"
    counts, _ = capture(src, poses=2, distinct=30, hold=1)
    src.write_text(src.read_text() + "0.4354937077, -0.32")
    conv = convert_file(src, "log", scale=_scale(), rate_hz=100.0)
    np.testing.assert_array_equal(conv.recording.raw, counts)
    assert any("the last, is cut short (2 of 3 numbers" in n for n in conv.notes)
    src.write_text(src.read_text() + "\n0.1, 0.2, 0.3\n")
    rc, _, err, _ = run(["convert", src, "--format", "log", "--units", "mps2", "--lsb", repr(LSB), "--rate", "100",
                         "-o", tmp_path / "o.csv"], capfd)
    assert rc == 2 and "got 2 field(s)" in err
