"""``accelcal convert`` of pose-means tables and slow loggers (a tester's public recordings: a
ground station's six-position result ``Position,AvgX,AvgY,AvgZ``, one row per pose).

Each file is written here in the recording's shape from known values, so the expected
recording is those values; bad files give one line naming the file and row, exit 2, and no
output.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_run import convert_ok, convert_refused, write_lines

G = 9.80665
#: six poses, each axis up then down, as a six-position calibration holds them
SIX = [("+X UP", (1, 0, 0)), ("-X UP", (-1, 0, 0)), ("+Y UP", (0, 1, 0)), ("-Y UP", (0, -1, 0)),
       ("+Z UP", (0, 0, 1)), ("-Z UP", (0, 0, -1))]


def _means(scale=(1.002, 0.997, 1.004), offset=(0.03, -0.07, 0.02)):
    """The six poses' mean readings, m/s^2: |f| 0.99-1.01 g each (gains and offsets off)."""
    return np.array([np.asarray(u) * G * np.asarray(scale) + np.asarray(offset) for _, u in SIX])


@pytest.mark.parametrize("regions", [False, True])
def test_pose_means_are_not_told_gravity_removed(tmp_path, capfd, regions):
    """A file of six pose means (one row each, |f| about 1 g) read at --rate 1 had been told
    'gravity looks removed': the stillest window spanned three poses and the magnitude of their
    mean vector, 0.33 g, was taken for |f|.  Each row's own |f| is now averaged, within one pose
    where regions label them."""
    m = _means()
    src = write_lines(tmp_path / "means.csv", ["ax,ay,az"] + [",".join(f"{v:.6f}" for v in r) for r in m])
    args = ["--units", "mps2", "--lsb", "0.000001", "--bits", "32", "--rate", "1"]
    if regions:
        reg = tmp_path / "regions.json"
        reg.write_text(json.dumps({n: {"start": k, "end": k + 1} for k, n in
                                   enumerate(["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"])}))
        args += ["--regions", str(reg), "--stated-f"]
    rec, _, err, _ = convert_ok(tmp_path, capfd, src, *args)
    np.testing.assert_array_equal(rec.raw, np.round(m / 1e-6).astype(np.int64))
    assert "gravity looks removed" not in err, err


def test_slow_logger_turned_between_rows_is_not_told_gravity_removed(tmp_path, capfd):
    """A logger stamping every 2 s (0.5 Hz), turned to another face between rows: a window of
    three rows spans three poses; |f| = 1 g in every row, so no note.  (Readings with gravity taken out still get it:
    test_convert_exports.test_gravity_removed_readings_are_named.)"""
    rng = np.random.default_rng(3)
    u = np.tile(np.array([d for _, d in SIX], float), (2, 1))
    m = np.round(u * G + 0.01 * rng.standard_normal(u.shape), 3)
    src = write_lines(tmp_path / "slow.csv", ["t,ax,ay,az"] + [f"{2 * k},{a:.3f},{b:.3f},{c:.3f}" for k, (a, b, c)
                                                               in enumerate(m)])
    _, _, err, _ = convert_ok(tmp_path, capfd, src, "--units", "mps2", "--lsb", "0.001", "--time-unit", "s")
    assert "gravity looks removed" not in err, err


def _rows(m):
    return [",".join(f"{v:.6f}" for v in r) for r in m]


@pytest.mark.parametrize("header", ["pose,ax,ay,az", "t,pose,acc_x,acc_y,acc_z"])
def test_a_pose_column_is_kept_as_the_recordings_pose_labels(tmp_path, capfd, header):
    """The contract's own ``pose`` column (calibrate's recipe for a file of pose means: 'give
    every row its own label in a pose column') had been 'ignored' by convert, and calibrate then
    found no pose.  Its whole numbers are kept as written, -1 or empty while moving."""
    m = np.repeat(_means(), 3, axis=0)
    labels = [5, 5, 5, -1, 3, 3, 4, 4, 4, None, 0, 0, 1, 1, 1, 2, 2, 2]
    cells = ["" if p is None else str(p) for p in labels]
    timed = header.startswith("t,")
    lines = [(f"{k / 10:.1f}," if timed else "") + f"{p}," + r for k, (p, r) in enumerate(zip(cells, _rows(m)))]
    src = write_lines(tmp_path / "poses.csv", [header] + lines)
    rec, _, err, _ = convert_ok(tmp_path, capfd, src, "--units", "mps2", "--lsb", "0.000001", "--bits", "32",
                                *([] if timed else ["--rate", "10"]))
    np.testing.assert_array_equal(rec.pose, [-1 if p is None else p for p in labels])
    assert "ignored column" not in err, err


def test_axis_and_sign_labels_are_read_as_poses_and_state_f(tmp_path, capfd):
    """A pose-means table labelled ``Position`` = ``+X UP`` ... ``-Z UP`` (a ground station's
    six-position result): the labels had been ignored and --stated-f refused 'no pose regions'.
    They are read as x_p ... z_a (the signed axis that points up), with a note, and --stated-f
    gives f = +-g along that axis."""
    m = _means()
    src = write_lines(tmp_path / "accel_calibration.csv", ["Position,ax,ay,az"] +
                      [f"{n}," + r for (n, _), r in zip(SIX, _rows(m))])
    rec, _, err, said = convert_ok(tmp_path, capfd, src, "--units", "mps2", "--lsb", "0.000001", "--bits", "32",
                                   "--rate", "1", "--stated-f")
    np.testing.assert_array_equal(rec.pose, np.arange(6))
    np.testing.assert_allclose(rec.f, np.array([u for _, u in SIX]) * G)
    assert "6 poses (x_p, x_a, y_p, y_a, z_p, z_a), reference f stated" in said, said
    assert "pose labels from column Position (+X UP = x_p, -X UP = x_a," in err, err
    assert "ignored column" not in err, err


@pytest.mark.parametrize("label", ["pose", "where"])
def test_stated_f_without_directions_names_the_column(tmp_path, capfd, label):
    """--stated-f over labels that state no direction: whole numbers in a ``pose`` column, or a
    text column that names no axis (``flat``, ``side``): refused, naming the column."""
    m = _means()
    cells = [str(k) for k in range(6)] if label == "pose" else ["flat", "upside", "left", "right", "nose", "tail"]
    src = write_lines(tmp_path / "means.csv", [f"{label},ax,ay,az"] + [f"{c}," + r for c, r in zip(cells, _rows(m))])
    err = convert_refused(tmp_path, capfd, src, "--units", "mps2", "--lsb", "0.000001", "--bits", "32", "--rate", "1",
                          "--stated-f")
    assert "--stated-f" in err and (f"column {label}" in err), err


def test_clipped_readings_are_noted(tmp_path, capfd):
    """A fan's vibration in g on a +-8 g 12-bit grid (1/256 g), some shocks beyond the range
    written as -8.000 or 7.996 g (raw_min, raw_max): convert had passed them without a word.
    The note counts them per column and end (clipping.clip_levels' rule)."""
    rng = np.random.default_rng(7)
    n = 3000
    k = np.arange(n)
    a = np.column_stack([5.0 * np.sin(k / 3.0), 4.0 * np.cos(k / 5.0), 1.0 + 0.3 * np.sin(k / 7.0)])
    a += 0.05 * rng.standard_normal(a.shape)
    a[rng.choice(n, 12, replace=False), 0] = 9.5          # shocks beyond +8 g
    a[rng.choice(n, 5, replace=False), 1] = -11.0         # ... and below -8 g
    counts = np.clip(np.round(a * 256), -2048, 2047).astype(int)
    src = write_lines(tmp_path / "fan.csv", ["x,y,z"] + [",".join(f"{v / 256:.3f}" for v in r) for r in counts])
    rec, _, err, _ = convert_ok(tmp_path, capfd, src, "--rate", "100", "--units", "g", "--full-scale", "8",
                                "--bits", "12", "--columns", "x,y,z")
    np.testing.assert_array_equal(rec.raw, counts)
    hi, lo = int(np.sum(counts[:, 0] == 2047)), int(np.sum(counts[:, 1] == -2048))
    said = [ln for ln in err.splitlines() if "clipped" in ln]
    assert len(said) == 1 and f"{hi + lo} reading(s) sit at the ends of the range" in said[0], err
    assert f"x {hi} at 2047 (raw_max)" in said[0] and f"y {lo} at -2048 (raw_min)" in said[0], said


@pytest.mark.parametrize("preamble", [False, True])
def test_the_format_named_is_the_one_read(tmp_path, capfd, preamble):
    """A headerless 6-column float log given the header the refusal suggests (ax,ay,az,gx,gy,gz)
    had been labelled source_format 'mpu6050' though nothing says it is one: it is a table.  The
    MPU-6050 logger's own file (its 'Fs,100' key,value line first) keeps its name."""
    rng = np.random.default_rng(2)
    counts = np.round(np.array([100.0, -50.0, 16000.0]) + 5 * rng.standard_normal((40, 3))).astype(int)
    lines = (["Fs,100"] if preamble else []) + ["ax,ay,az,gx,gy,gz"] + [f"{a},{b},{c},1,2,3" for a, b, c in counts]
    src = write_lines(tmp_path / "imu_data.csv", lines)
    rec, _, _, said = convert_ok(tmp_path, capfd, src, *([] if preamble else ["--rate", "100"]))
    np.testing.assert_array_equal(rec.raw, counts)
    fmt = "mpu6050" if preamble else "table"
    assert rec.metadata["source_format"] == fmt and said.startswith(f"{fmt}: 40 rows"), (rec.metadata, said)


@pytest.mark.parametrize("units,factor,said", [("mps2", 1000.0, "readings in mm/s^2 read as m/s^2?"),
                                               ("g", 1.0, "readings in m/s^2 read as g?"), ("mps2", 1.0, None)])
def test_readings_a_unit_off_are_noted(tmp_path, capfd, units, factor, said):
    """Klipper's ACCELEROMETER_MEASURE writes mm/s^2; stated as m/s^2 they read |f| = 1000 g at
    rest, and convert had passed them without a word (its note was for |f| below g/2 only).  A
    note names the likely misreading (mm/s^2 as m/s^2, m/s^2 as g); readings in their own unit
    get none.  (``factor``: 1000 where the file's readings are mm/s^2, else 1.)"""
    rng = np.random.default_rng(4)
    u = np.array([0.17, 0.985, 0.02]) / np.linalg.norm([0.17, 0.985, 0.02])
    lsb = 0.019142581 * factor
    counts = np.round(u * G / 0.019142581 + 2.5 * rng.standard_normal((400, 3))).astype(int)
    rows = [f"{k / 394:.6f}," + ",".join(f"{v * lsb:.6f}" for v in r) for k, r in enumerate(counts)]
    src = write_lines(tmp_path / "lis2dw-0.csv", ["#time,accel_x,accel_y,accel_z"] + rows)
    rec, _, err, _ = convert_ok(tmp_path, capfd, src, "--units", units, "--lsb", f"{lsb:.9g}")
    np.testing.assert_array_equal(rec.raw, counts)
    notes = [ln for ln in err.splitlines() if "where anything at rest reads 1 g" in ln]
    assert (len(notes) == 1 and said in notes[0]) if said else not notes, err


def test_klipper_mm_per_s2_are_read_with_their_unit(tmp_path, capfd):
    """Klipper's ACCELEROMETER_MEASURE files are always mm/s^2 (a LIS2DW on 19.142581 mm/s^2); there
    was no unit for them, and the only way in was dividing every value by 1000 by hand.  `--units
    mmps2 --lsb 19.142581` reads the counts exactly with the nominal scale 1000 / 19.142581 counts
    per m/s^2, no note of a unit off; the same LSB as a suffix (`19.142581mmps2`) states integer
    counts' size; the note for readings stated as m/s^2 names the unit to give."""
    rng = np.random.default_rng(7)
    u = np.array([0.17, 0.985, 0.02]) / np.linalg.norm([0.17, 0.985, 0.02])
    counts = np.round(u * G * 1000 / 19.142581 + 2.5 * rng.standard_normal((400, 3))).astype(int)
    rows = [f"{k / 394:.6f}," + ",".join(f"{v * 19.142581:.6f}" for v in r) for k, r in enumerate(counts)]
    src = write_lines(tmp_path / "lis2dw-0.csv", ["#time,accel_x,accel_y,accel_z"] + rows)
    rec, dev, err, _ = convert_ok(tmp_path, capfd, src, "--units", "mmps2", "--lsb", "19.142581")
    np.testing.assert_array_equal(rec.raw, counts)
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(1000 / 19.142581, rel=1e-9)
    assert "where anything at rest reads 1 g" not in err, err
    whole = write_lines(tmp_path / "counts.csv", ["t,ax,ay,az"] + [f"{k / 394:.6f}," + ",".join(map(str, r))
                                                                   for k, r in enumerate(counts)])
    (tmp_path / "c").mkdir()
    rec2, dev2, _, _ = convert_ok(tmp_path / "c", capfd, whole, "--units", "counts", "--lsb", "19.142581mmps2")
    np.testing.assert_array_equal(rec2.raw, counts)
    assert dev2["channels"][0]["counts_per_mps2"] == pytest.approx(1000 / 19.142581, rel=1e-9)
    (tmp_path / "m").mkdir()
    _, _, err, _ = convert_ok(tmp_path / "m", capfd, src, "--units", "mps2", "--lsb", "19.142581")
    assert "--units mmps2" in err, err


def test_a_logger_in_mg_is_read_with_its_unit(tmp_path, capfd):
    """An LSM303 at +-16 g logged as mg floats (11.72 mg a count, millis() stamps: HPMR-24-25/Vanguard-RTOS's
    SensorAnalysis files). 'mg' was no choice of --units, and the way round it, --units g --lsb 11.72,
    wrote a device 1000 x off (0.0087 counts per m/s^2). `--units mg --lsb 11.72` reads the counts
    exactly, sized 1 / (11.72e-3 g) per m/s^2; readings in g stated as mg are named so."""
    rng = np.random.default_rng(0)
    counts = np.round(np.array([-10.0, 6.3, 81.5]) + rng.normal(0, [1.1, 1.4, 1.0], (600, 3))).astype(int)
    rows = [",".join(f"{np.float32(v * 11.72):.6f}" for v in r) + f",{431218 + 4 * k}" for k, r in enumerate(counts)]
    src = write_lines(tmp_path / "lsm303.csv", ["accelX,accelY,accelZ,timestamp"] + rows)
    rec, dev, err, _ = convert_ok(tmp_path, capfd, src, "--units", "mg", "--lsb", "11.72")
    np.testing.assert_array_equal(rec.raw, counts)
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(1 / (11.72e-3 * G), rel=1e-9)
    assert "where anything at rest reads 1 g" not in err, err
    in_g = write_lines(tmp_path / "g.csv", ["accelX,accelY,accelZ,timestamp"] + [
        ",".join(f"{v * 11.72e-3:.5f}" for v in r) + f",{431218 + 4 * k}" for k, r in enumerate(counts)])
    (tmp_path / "g").mkdir()
    _, _, err, _ = convert_ok(tmp_path / "g", capfd, in_g, "--units", "mg", "--lsb", "0.01172")
    assert "readings in g read as mg" in err, err


@pytest.mark.parametrize("header, label", [("Position,ax,ay,az", "axes"), ("Position,accX,accY,accZ", "axes"),
                                           ("pose,acc_x,acc_y,acc_z", "numbers")])
def test_pose_means_convert_without_a_rate_and_calibrate(tmp_path, capfd, header, label):
    """A file of pose means (one row a pose, labelled, three means, no time column) had been
    refused without --rate ('no time column: give the sample rate'), although its means carry no
    time and calibrate needs none from them: it takes each labelled pose's mean.  Now t counts
    the rows (0, 1, 2, ... at a placeholder 1 Hz, which a note and the table.time metadata say),
    the device's scale is the median |mean| over g (it had been the readings' percentile spread),
    and calibrate takes the six poses -- with --stated-f, the known-pose 'full' calibration, the
    same as with --rate 1.  Rows that are samples (no labels, or a label over several rows) still
    need the rate, and the refusal says what a pose-means file needs instead."""
    from accelcal.io.calibration import load_calibration
    from accelcal.cli.main import main
    from accelcal.io.device import load_device
    m = _means()
    labels = [n for n, _ in SIX] if label == "axes" else [str(k) for k in range(6)]
    src = write_lines(tmp_path / "means.csv", [header] + [f"{n}," + r for n, r in zip(labels, _rows(m))])
    units = ["--units", "mps2", "--lsb", "0.000001", "--bits", "32"] + (["--stated-f"] if label == "axes" else [])
    rec, dev, err, said = convert_ok(tmp_path, capfd, src, *units)
    np.testing.assert_array_equal(rec.raw, np.round(m / 1e-6).astype(np.int64))
    np.testing.assert_array_equal(rec.t, np.arange(6.0))
    np.testing.assert_array_equal(rec.pose, np.arange(6))
    assert dev["sample_rate_hz"] == 1.0 and "t is the row's number" in rec.metadata["table.time"]
    assert "pose means, which carry no time; t counts the rows" in err, err
    assert "6 poses" in said, said
    out = tmp_path / "o.csv"
    assert main(["calibrate", "--device", str(tmp_path / "d.json"), str(out), "-o", str(tmp_path / "c.json")]) == 0
    cal = load_calibration(tmp_path / "c.json", load_device(tmp_path / "d.json"))
    assert cal.method == ("full" if label == "axes" else "jigfree")
    if label == "axes":          # the LSB is stated: the device's scale is the LSB's, and f is known
        rated = tmp_path / "rated"
        rated.mkdir()
        assert main(["convert", str(src), *units, "--rate", "1", "-o", str(rated / "o.csv"), "--device-out",
                     str(rated / "d.json")]) == 0
        assert main(["calibrate", "--device", str(rated / "d.json"), str(rated / "o.csv"), "-o",
                     str(rated / "c.json")]) == 0
        other = load_calibration(rated / "c.json", load_device(rated / "d.json"))
        np.testing.assert_allclose(cal.sensitivity, other.sensitivity, rtol=1e-12)
        np.testing.assert_allclose(cal.offsets, other.offsets, rtol=1e-12, atol=1e-9)
    # rows that are samples: two rows a pose, or no labels at all, still need a rate
    twice = write_lines(tmp_path / "twice.csv", [header] + [f"{n}," + r for n, r in zip(labels * 2, _rows(m) * 2)])
    err = convert_refused(tmp_path, capfd, twice, *units, name="twice")
    assert "--rate HZ" in err and "label each row in a 'pose' column" in err, err
    bare = write_lines(tmp_path / "bare.csv", [header.split(",", 1)[1]] + _rows(m))
    err = convert_refused(tmp_path, capfd, bare, "--units", "mps2", "--lsb", "0.000001", "--bits", "32", name="bare")
    assert "--rate HZ" in err and "label each row in a 'pose' column" in err, err


def test_pose_means_give_the_device_their_scale(tmp_path, capfd):
    """Pose means in counts without a stated LSB: the nominal scale is the median |mean| over g
    (each row is at rest), 1670 counts per m/s^2 for means of 16,380 counts; the readings'
    1st-99th percentile spread of six rows had given 1587."""
    c = np.round(np.array([u for _, u in SIX]) * 16380 + [[40, -25, 60]]).astype(int)
    src = write_lines(tmp_path / "m.csv", ["Position,ax,ay,az"] + [f"{n},{a},{b},{d}" for (n, _), (a, b, d)
                                                                     in zip(SIX, c)])
    _, dev, err, _ = convert_ok(tmp_path, capfd, src, "--rate", "1")
    k = dev["channels"][0]["counts_per_mps2"]
    assert k == pytest.approx(float(f"{np.median(np.linalg.norm(c, axis=1)) / G:.4g}")), err
    assert "median |reading| of the 6 pose means over g" in err, err
