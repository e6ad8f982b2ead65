"""``accelcal convert`` of tables with named columns (format ``table``): phyphox, x-io's
NGIMU, a LORD/MicroStrain log, a logger's ``time_ms,accX,accY,accZ``.

Each file is written here from known counts (and times), so the expected recording is
those counts; bad files give one line naming the file, row and column, exit 2, and no
output.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from accelcal.convert.formats import axis_column, convert_file, detect_format
from accelcal.errors import InputError
from accelcal.io.recording import read_recording
from cli_run import one_refusal, run

G = 9.80665
LSB_G = 4.0 / 2 ** 16        # --full-scale 2, 16 bits: 1/16384 g


def _counts(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.round([100.0, -50.0, 16384.0] + 40.0 * rng.standard_normal((n, 3))).astype(int)


def _write(path, header, rows, comments=()):
    path.write_text("".join(f"{c}\n" for c in comments) + header + "\n" + "".join(r + "\n" for r in rows))
    return path


def _convert(tmp_path, capfd, src, *args):
    out, dev = tmp_path / "o.csv", tmp_path / "d.json"
    rc, said, err, _ = run(["convert", src, *args, "-o", out, "--device-out", dev], capfd)
    assert rc == 0, err
    assert len(said.splitlines()) == 1 and said.startswith("table: ")
    return read_recording(out), json.loads(dev.read_text()), err


def _refused(tmp_path, capfd, src, *args):
    out = tmp_path / "out"
    out.mkdir()
    rc, _, err, _ = run(["convert", src, *args, "-o", out / "o.csv"], capfd)
    assert rc == 2 and one_refusal(err) and "Traceback" not in err, err
    assert not list(out.iterdir())
    assert str(src.name) in err
    return err


def _cells(values):
    return ",".join(repr(float(v)) for v in values)


# ---- each header style -------------------------------------------------------------

def test_phyphox(tmp_path, capfd):
    c, rate = _counts(200), 100.0
    rows = [f"{k / rate:.4f},{_cells(r * LSB_G * G)},{float(np.linalg.norm(r * LSB_G * G)):.6g}"
            for k, r in enumerate(c)]
    src = _write(tmp_path / "Raw Data.csv", '"Time (s)","Acceleration x (m/s^2)","Acceleration y (m/s^2)",'
                 '"Acceleration z (m/s^2)","Absolute acceleration (m/s^2)"', rows)
    assert detect_format(src) == "table"
    rec, dev, err = _convert(tmp_path, capfd, src, "--full-scale", "2")
    assert np.array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t, np.arange(200) / rate, atol=1e-9)
    assert dev["sample_rate_hz"] == pytest.approx(rate)
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(16384 / G)
    assert "ignored column Absolute acceleration (m/s^2)" in err
    assert rec.metadata["source_format"] == "table"


def test_ngimu_gait_tracking(tmp_path, capfd):
    c, rate = _counts(150, seed=1), 100.0
    rows = [f"{k / rate:.6f},0.5,-0.25,1,{_cells(r * LSB_G)}" for k, r in enumerate(c)]
    src = _write(tmp_path / "short_walk.csv", "Time (s),Gyroscope X (deg/s),Gyroscope Y (deg/s),Gyroscope Z (deg/s),"
                 "Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)", rows)
    rec, dev, err = _convert(tmp_path, capfd, src, "--full-scale", "2")
    assert np.array_equal(rec.raw, c) and dev["sample_rate_hz"] == pytest.approx(rate)
    assert err.count("\n") == 1 and "dropped gyroscope columns Gyroscope X (deg/s)" in err
    # the same with the unit stated by the options too (they agree)
    rec2, _, _ = _convert(tmp_path, capfd, src, "--units", "g", "--lsb", repr(LSB_G))
    assert np.array_equal(rec2.raw, c)


def lord_file(path, c, rate=500.0, t0=1_700_000_000_000_000_000, comments=()):
    """A LORD/MicroStrain log as AirbrakesV2 writes it: each IMU row followed by an estimate
    row whose accelerometer cells are empty."""
    step = int(1e9 / rate)
    rows = []
    for k, r in enumerate(c):
        rows.append(f"{t0 + k * step},,{_cells(r * LSB_G)},0.01,-0.02,,,")
        rows.append(f"{t0 + k * step + step // 2},,,,,,,0.1,0.2,0.3")
    return _write(path, "timestamp,invalid_fields,scaledAccelX,scaledAccelY,scaledAccelZ,scaledGyroX,scaledGyroY,"
                  "estLinearAccelX,estLinearAccelY,estLinearAccelZ", rows, comments)


def test_lord_rows_without_readings_are_skipped(tmp_path, capfd):
    c = _counts(300, seed=2)
    src = lord_file(tmp_path / "log.csv", c)
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "g", "--full-scale", "2")
    assert np.array_equal(rec.raw, c)
    assert "300 row(s) whose readings (scaledAccelX, scaledAccelY, scaledAccelZ) are all missing (empty or nan), " \
        "the first row 3: left out (other packets' rows, or samples lost)" in err
    assert "t read in ns" in err and "ignored columns invalid_fields, estLinearAccelX" in err
    # the epoch in ns read as integers (as float64 each stamp kept 256 ns: the rate 1e-4 off)
    assert dev["sample_rate_hz"] == pytest.approx(500.0, rel=1e-9)
    np.testing.assert_allclose(rec.t - rec.t[0], np.arange(300) / 500.0, atol=1e-6)


def test_lord_without_units_reads_counts_and_names_the_fraction(tmp_path, capfd):
    src = lord_file(tmp_path / "log.csv", _counts(20, seed=3), comments=["# a comment", ""])
    err = _refused(tmp_path, capfd, src, "--full-scale", "2")
    assert "row 4, column scaledAccelX" in err and "not a whole count" in err


@pytest.mark.parametrize("header, unit, factor", [("time_ms,accX,accY,accZ", "ms", 1e3),
                                                  ("timestamp_us,acc_x,acc_y,acc_z", "us", 1e6),
                                                  ("t,Accel_X,Accel_Y,Accel_Z", None, 1.0)])
def test_generic_counts_with_time(tmp_path, capfd, header, unit, factor):
    c, rate = _counts(100, seed=4), 200.0
    rows = [f"{k / rate * factor:.3f},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(c)]
    src = _write(tmp_path / "logger.csv", header, rows)
    # imucal's acc_x columns beside a time column: a table (imucal's files have no time column)
    rec, dev, err = _convert(tmp_path, capfd, src)
    assert np.array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t, np.arange(100) / rate, atol=1e-9)
    assert dev["sample_rate_hz"] == pytest.approx(rate)
    assert (f"t read in {unit}" in err) == (unit is not None)


def test_units_in_brackets_with_the_lsb_from_a_comment(tmp_path, capfd):
    c, rate = _counts(80, seed=5), 50.0
    rows = [f"{k / rate:.4f},{_cells(r * LSB_G)}" for k, r in enumerate(c)]
    src = _write(tmp_path / "g.csv", "Time (s),AccX [g],AccY [g],AccZ [g]", rows, [f"# lsb: {LSB_G!r}"])
    rec, dev, _ = _convert(tmp_path, capfd, src)
    assert np.array_equal(rec.raw, c) and dev["sample_rate_hz"] == pytest.approx(rate)
    assert rec.metadata["source_scale"].startswith("g / ")


def test_whitespace_table_without_time_needs_a_rate(tmp_path, capfd):
    c = _counts(40, seed=6)
    src = _write(tmp_path / "w.txt", "accX  accY\taccZ  temp", [f"{a}  {b}\t{d}  21.5" for a, b, d in c])
    err = _refused(tmp_path, capfd, src, "--format", "table")
    assert "no time column" in err and "--rate" in err
    rec, dev, err = _convert(tmp_path, capfd, src, "--format", "table", "--rate", "25")
    assert np.array_equal(rec.raw, c) and np.allclose(rec.t, np.arange(40) / 25)
    assert "ignored column temp" in err and dev["raw_min"] == -32768


# ---- refusals ------------------------------------------------------------------------

def _phyphox_g(tmp_path, header="Time (s),Acceleration x (g),Acceleration y (g),Acceleration z (g)"):
    c = _counts(30, seed=7)
    return _write(tmp_path / "p.csv", header, [f"{k / 100:.2f},{_cells(r * LSB_G)}" for k, r in enumerate(c)],
                  ["# phone export"])


def test_units_stated_by_the_options_override_the_names(tmp_path, capfd):
    """A logger whose header says ``aX (g)`` over readings it printed in m/s^2 (an MPU-6050
    sketch's raw * 9.81 / 16384): --units mps2 had been refused as contradicting the header, so
    the only way was to edit the file.  The options' unit is taken, with a note; g readings
    taken as counts stay refused (not whole counts)."""
    c = _counts(30, seed=7)
    src = _write(tmp_path / "p.csv", "Time (s),aX (g),aY (g),aZ (g)",
                 [f"{k / 100:.2f},{_cells(r * LSB_G * G)}" for k, r in enumerate(c)])
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "mps2", "--full-scale", "2")
    np.testing.assert_array_equal(rec.raw, c)
    assert "--units mps2 overrides the unit the header's columns state, g (aX (g), aY (g), aZ (g))" in err, err
    err = _refused(tmp_path, capfd, _phyphox_g(tmp_path), "--units", "counts")
    assert "whole" in err, err


def test_a_comment_that_contradicts_the_names_is_refused(tmp_path, capfd):
    src = _phyphox_g(tmp_path)
    src.write_text("# units: mps2\n" + src.read_text())
    err = _refused(tmp_path, capfd, src, "--full-scale", "2")
    assert "row 1" in err and "'# units: mps2' contradicts" in err


def test_physical_units_without_an_lsb_are_refused(tmp_path, capfd):
    err = _refused(tmp_path, capfd, _phyphox_g(tmp_path))
    assert "row 2" in err and "in g" in err and "no LSB" in err and "--full-scale" in err and "--round" in err


def test_a_partly_empty_row_is_refused_naming_its_file_row(tmp_path, capfd):
    c = _counts(10, seed=8)
    src = lord_file(tmp_path / "log.csv", c, comments=["# logger v2", "# units: g"])
    lines = src.read_text().splitlines()
    # data rows start at line 4: IMU rows on lines 4, 6, 8, ...; blank y on the 4th IMU row (line 10)
    cells = lines[9].split(",")
    cells[3] = ""
    lines[9] = ",".join(cells)
    src.write_text("\n".join(lines) + "\n")
    err = _refused(tmp_path, capfd, src, "--units", "g", "--full-scale", "2")
    assert "row 10, column scaledAccelY" in err and "an empty cell" in err


def test_a_time_stamp_going_back_is_refused(tmp_path, capfd):
    src = _write(tmp_path / "t.csv", "t,accX,accY,accZ", ["0.00,1,2,3", "0.01,1,2,3", "0.01,1,2,4"])
    err = _refused(tmp_path, capfd, src)
    assert "row 4, column t" in err and "increase" in err


@pytest.mark.parametrize("header, named", [("t,accX,accY,accZ,AccelX (g)", "'accX', 'AccelX (g)'"),
                                           ("t,accX,accY,gyroZ", "no column for axis z")])
def test_ambiguous_or_missing_axis_columns_are_refused(tmp_path, capfd, header, named):
    src = _write(tmp_path / "a.csv", header, ["0,1,2,3,4", "1,1,2,3,4"] if header.count(",") == 4 else ["0,1,2,3"])
    err = _refused(tmp_path, capfd, src)
    assert "row 1" in err and named in err


def test_linear_acceleration_is_refused(tmp_path, capfd):
    src = _phyphox_g(tmp_path, '"Time (s)","Linear Acceleration x (m/s^2)","Linear Acceleration y (m/s^2)",'
                     '"Linear Acceleration z (m/s^2)"')
    err = _refused(tmp_path, capfd, src, "--full-scale", "2")
    assert "row 2" in err and "linear acceleration" in err and "not an accelerometer's specific force" in err


def test_a_bad_cell_names_row_and_column(tmp_path, capfd):
    src = _write(tmp_path / "b.csv", "time_ms,accX,accY,accZ", ["0,1,2,3", "10,1,x,3"], ["# c"])
    err = _refused(tmp_path, capfd, src)
    assert "row 4, column accY" in err


# ---- names and detection ---------------------------------------------------------------

@pytest.mark.parametrize("name, axis, unit, virtual", [
    ("Acceleration x (m/s^2)", "x", "m/s^2", False), ("Accelerometer Y (g)", "y", "g", False),
    ("scaledAccelZ", "z", None, False), ("AccX [g]", "x", "g", False), ("acc_y_mps2", "y", "mps2", False),
    ("rawAccelX", "x", None, False), ("accel z (m/s\u00b2)", "z", "m/s\u00b2", False),
    ("Linear Acceleration x (m/s^2)", "x", "m/s^2", True), ("estLinearAccelY", "y", None, True),
    ("gravityAccZ", "z", None, True)])
def test_axis_names(name, axis, unit, virtual):
    c = axis_column(name)
    assert (c.axis, c.unit, c.virtual) == (axis, unit, virtual)


@pytest.mark.parametrize("name", ["Absolute acceleration (m/s^2)", "estCompensatedAccelX", "Gyroscope X (deg/s)",
                                  "accel", "max", "acc_x_filtered", "alpha_x", "gx"])
def test_not_axis_names(name):
    assert axis_column(name) is None


@pytest.mark.parametrize("text, fmt", [
    ("t,raw_0,raw_1,raw_2\n0,1,2,3\n", "csv"), ("acc_x,acc_y,acc_z\n1,2,3\n", "imucal"),
    ("Fs,100\nax,ay,az\n1,2,3\n", "mpu6050"),
    ("ax,ay,az,gx,gy,gz\n1,2,3,4,5,6\n", "mpu6050"), ("0.01 1 2 3\n0.02 1 2 3\n", "imu_tk"),
    ("accX,accY,accZ\n" + "1,2,3\n" * 20, "log"), ("time,accX,accY,accZ\n0,1,2,3\n", "table"),
    # a time column beside imucal's or the MPU-6050 logger's axis names: a user's table (neither has one)
    ("timestamp,acc_x,acc_y,acc_z\n0,1,2,3\n", "table"), ("t,ax,ay,az\n0,1,2,3\n", "table"),
    ("time_ms,ax,ay,az,gx,gy,gz\n0,1,2,3,4,5,6\n", "table"), ("t\tax\tay\taz\n0\t1\t2\t3\n", "table")])
def test_existing_formats_are_told_as_before(tmp_path, text, fmt):
    (tmp_path / "f").write_text(text)
    assert detect_format(tmp_path / "f") == fmt


def test_nothing_like_an_axis_still_cannot_be_told(tmp_path):
    (tmp_path / "f").write_text("time,speed,heading\n0,1,2\n")
    with pytest.raises(InputError, match="cannot tell the format"):
        convert_file(tmp_path / "f")


def test_calibrated_floats_on_no_grid_are_rounded_when_asked(tmp_path, capfd):
    """x-io's NGIMU writes calibrated g with 7 significant digits, on no grid of any LSB:
    refused as not whole counts, and read with --round to the LSB chosen, with a note of how
    far the readings were off (at most half an LSB)."""
    rng = np.random.default_rng(8)
    g = np.array([0.0123, -0.4937, 0.8312]) + 0.003 * rng.standard_normal((150, 3))
    rows = [f"{k / 400.0:.7g},{','.join(f'{v:.7g}' for v in r)}" for k, r in enumerate(g)]
    src = _write(tmp_path / "ngimu.csv", "Time (s),Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)", rows)
    err = _refused(tmp_path, capfd, src, "--units", "g", "--lsb", "1e-6", "--bits", "26")
    assert "not a whole number" in err and "--round rounds them to the LSB that --lsb states" in err
    err = _refused_again(tmp_path, capfd, "fs", src, "--units", "g", "--full-scale", "4")
    assert "--round rounds them to the LSB that --full-scale states" in err and "--lsb" not in err
    commented = _write(tmp_path / "c.csv", "Time (s),Accelerometer X (g),Accelerometer Y (g),Accelerometer Z (g)",
                       rows, comments=("# lsb: 1e-6",))
    err = _refused_again(tmp_path, capfd, "comment", commented, "--bits", "26")
    assert "--round rounds them to the LSB that '# lsb:' (row 1) states" in err
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "g", "--lsb", "1e-6", "--bits", "26", "--round")
    printed = np.array([[float(f"{v:.7g}") for v in r] for r in g])
    np.testing.assert_array_equal(rec.raw, np.round(printed / 1e-6).astype(int))
    off = np.abs(printed / 1e-6 - np.round(printed / 1e-6))
    assert f"rounded to whole LSBs of 1e-06 g (--round): up to {off.max():.3g} of an LSB off" in err
    assert dev["sample_rate_hz"] == pytest.approx(400.0)


def test_a_packet_written_twice_is_left_out_once(tmp_path, capfd):
    """A row that repeats the one before, time stamp and readings alike, is left out with a
    note; the same time stamp with other readings is refused naming its row."""
    c, rate = _counts(60, seed=9), 100.0
    rows = [f"{k / rate:.4f},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(c)]
    twice = rows[:10] + [rows[9]] + rows[10:30] + [rows[29]] + rows[30:]
    src = _write(tmp_path / "log.csv", "t,accX,accY,accZ", twice)
    rec, _, err = _convert(tmp_path, capfd, src)
    np.testing.assert_array_equal(rec.raw, c)
    assert "2 row(s) repeat the row before" in err
    bad = rows[:10] + [rows[9].rsplit(",", 1)[0] + ",7"] + rows[10:]
    err = _refused(tmp_path, capfd, _write(tmp_path / "bad.csv", "t,accX,accY,accZ", bad))
    assert "row 12" in err and "not after" in err


def test_a_sample_delivered_twice_off_the_grid_is_left_out(tmp_path, capfd):
    """A phone log (Oxford-step-counter's Samsung S6 at 100 Hz, t in ns) where a row repeats
    the row before's readings exactly with a stamp 3.4 ms later: left out with a note.  A
    repeated reading a whole step later (a quiet sensor's real sample), or with other
    readings 3.4 ms later, stays."""
    c, step = _counts(80, seed=11), 10_000_000
    ns = 1012461540465 + step * np.arange(80)
    c[40] = c[39]                                    # a real sample equal to the one before: on the grid
    rows = [f"{t},{r[0]},{r[1]},{r[2]}" for t, r in zip(ns, c)]
    again = rows[:20] + [f"{ns[19] + 3_384_480},{c[19][0]},{c[19][1]},{c[19][2]}"] + rows[20:60] + \
        [f"{ns[59] + 3_000_000},{c[59][0]},{c[59][1]},{c[59][2]}"] + rows[60:]
    src = _write(tmp_path / "phone.csv", "timestamp_ns,accx,accy,accz", again)
    rec, dev, err = _convert(tmp_path, capfd, src)
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t - rec.t[0], np.arange(80) / 100.0, rtol=0, atol=1e-9)
    assert ("2 row(s) repeat the readings of the row before with a time stamp less than half a step after it "
            "(median step 1e+07 in the time column's unit; a sample delivered twice, off the grid): left out") in err
    other = rows[:20] + [f"{ns[19] + 3_384_480},{c[19][0] + 1},{c[19][1]},{c[19][2]}"] + rows[20:]
    rec, _, err = _convert(tmp_path, capfd, _write(tmp_path / "jitter.csv", "timestamp_ns,accx,accy,accz", other))
    assert rec.n_samples == 81 and "left out" not in err


def test_readings_that_repeat_by_chance_on_a_jittered_grid_stay(tmp_path, capfd):
    """A host-stamped 100 Hz log (stamps jitter 0-7 ms) of readings in g with two decimals: a
    sensor at rest repeats its readings by chance, off the grid as often as on it.  Those rows
    are samples: all 3,000 stay at 100 Hz (30 had been left out as "delivered twice", 99.01 Hz)."""
    rng = np.random.default_rng(3)
    n = 3000
    ts = np.sort(np.arange(n) * 0.01 + rng.uniform(0, 0.007, n))
    g = np.column_stack([0.004 * rng.normal(size=n), 0.004 * rng.normal(size=n),
                         1 + 0.004 * rng.normal(size=n)]).round(2)
    src = _write(tmp_path / "jit.csv", "time,accX,accY,accZ",
                 [f"{t:.4f},{r[0]:.2f},{r[1]:.2f},{r[2]:.2f}" for t, r in zip(ts, g)])
    rc, out, err, _ = run(["convert", src, "--units", "g", "--lsb", "0.01", "-o", tmp_path / "o.csv",
                           "--device-out", tmp_path / "o.json"], capfd)
    assert rc == 0 and "left out" not in err, err
    assert out.startswith("table: 3000 rows"), out
    assert json.loads((tmp_path / "o.json").read_text())["sample_rate_hz"] == pytest.approx(100.0, rel=1e-4)


@pytest.mark.parametrize("lead", [1, 3])
def test_leading_zero_readings_before_the_first_value_are_left_out(tmp_path, capfd, lead):
    """A phone's log whose first row(s) read 0.0,0.0,0.0 (the sensor had delivered nothing yet)
    and then gravity-sized vectors in m/s^2: those rows are left out with a note.  Zeros
    further on, or a recording near 0 throughout (counts of no stated LSB), stay."""
    c = _counts(60, seed=12)
    lsb = LSB_G * G
    rows = [f"{k * 10},0.0,0.0,0.0" for k in range(lead)] + \
        [f"{(k + lead) * 10},{_cells(r * lsb)}" for k, r in enumerate(c)]
    src = _write(tmp_path / "phone.csv", "time_ms,accX,accY,accZ", rows)
    rec, _, err = _convert(tmp_path, capfd, src, "--units", "mps2", "--full-scale", "2")
    np.testing.assert_array_equal(rec.raw, c)
    assert rec.t[0] == pytest.approx(lead * 0.01)
    where = "row 2" if lead == 1 else f"rows 2-{lead + 1}"
    norm = float(np.linalg.norm(c[0] * lsb))
    assert (f"the first {lead} row(s) ({where}) read exactly 0, 0, 0 where the next row's |reading| is "
            f"{norm:.4g} m/s^2 ({norm / G:.3g} g) and the median") in err
    assert "a placeholder before the sensor's first value, left out" in err
    later = [f"{k * 10},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(np.vstack([c[:5], [[0, 0, 0]], c[5:]]))]
    rec, _, err = _convert(tmp_path, capfd, _write(tmp_path / "later.csv", "time_ms,accX,accY,accZ", later))
    assert rec.n_samples == 61 and "placeholder" not in err
    quiet = [f"{k * 10},0,0,0" for k in range(lead)] + [f"{(k + lead) * 10},3,-2,5" for k in range(20)]
    rec, _, err = _convert(tmp_path, capfd, _write(tmp_path / "quiet.csv", "time_ms,accX,accY,accZ", quiet))
    assert rec.n_samples == 20 + lead and "placeholder" not in err


def test_a_headerless_csv_names_the_format_to_use(tmp_path, capfd):
    """--format csv on a file without a header (Oxford-step-counter's phone logs) named
    'accelcal convert', the command being run; it names the formats that read such files."""
    src = _write(tmp_path / "user1_hand.csv", "1012461540465,0.0,0.0,0.0,0,0,0", ["1012471532132,0.5,2.5,5.0,0,0,0"])
    err = _refused(tmp_path, capfd, src, "--format", "csv")
    assert ("row 1: the first line is numbers, not a header (expected 't,raw_0,raw_1,...'): imu_tk's whitespace "
            "'t ax ay az' in counts is read by 'accelcal convert --format imu_tk'; another table needs a first line "
            "naming its columns (such as 't,accX,accY,accZ'), then 'accelcal convert --format table'") in err
    assert "is read by 'accelcal convert')" not in err


def test_a_count_beyond_64_bits_is_one_line_naming_it(tmp_path, capfd):
    src = _write(tmp_path / "h.csv", "t,accX,accY,accZ", ["0.00,99999999999999999999,3,4", "0.01,1,3,4"])
    err = _refused(tmp_path, capfd, src)
    assert "row 2, column accX" in err and "1e+20 does not fit a count of 64 bits" in err


# ---- which column is the time column -----------------------------------------------

def _refused_again(tmp_path, capfd, name, src, *args):
    """:func:`_refused` once more in the same test (its own empty output directory)."""
    (tmp_path / name).mkdir()
    return _refused(tmp_path / name, capfd, src, *args)


TW_HEADER = "Date(MM/DD/YYYY),Time(hh:mm:ss),Timestamp(Ms),Temp(Raw),ACCELX,ACCELY,ACCELZ,MAGX,MAGY,MAGZ"


def _twlogger(path, n=120, step_ms=16):
    """A TWLogger-shaped table (JustinPringle/TWLogger's header): a date, a clock time, a
    millis() stamp, then the axes; the stamps and counts known."""
    c = _counts(n, seed=5)
    stamps = 15225 + step_ms * np.arange(n)
    rows = [f"07/11/2018,05:34:{44 + k // 50:02d},{s},0,{r[0]}.00,{r[1]}.00,{r[2]}.00,89.00,-10.00,-327.00"
            for k, (s, r) in enumerate(zip(stamps, c))]
    return _write(path, TW_HEADER, rows), c, stamps


def test_the_numeric_time_column_is_chosen_over_a_clock_time(tmp_path, capfd):
    """'Time(hh:mm:ss)' comes first and matches the time-column names, but its cells are a
    clock time: 'Timestamp(Ms)' (numbers, a unit in its name) is the time column, with a
    note naming both; --time-unit and --rate read the same column."""
    src, c, stamps = _twlogger(tmp_path / "T1D0711-00.CSV")
    rec, dev, err = _convert(tmp_path, capfd, src)
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t, stamps / 1e3, rtol=0, atol=1e-9)
    assert dev["sample_rate_hz"] == pytest.approx(62.5)
    assert ("time column 'Timestamp(Ms)' used (its name states a unit); passed over 'Time(hh:mm:ss)' "
            "(row 2: '05:34:44'), not a number") in err
    rec, _, _ = _convert(tmp_path, capfd, src, "--format", "table", "--time-unit", "ms")
    np.testing.assert_allclose(rec.t, stamps / 1e3, rtol=0, atol=1e-9)


def test_of_two_numeric_time_columns_the_one_stating_a_unit_is_used(tmp_path, capfd):
    c = _counts(50)
    rows = [f"{k},{10 * k},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(c)]
    src = _write(tmp_path / "two.csv", "t,time_ms,accX,accY,accZ", rows)
    rec, dev, err = _convert(tmp_path, capfd, src)
    np.testing.assert_allclose(rec.t, np.arange(50) / 100.0, atol=1e-12)
    assert "time column 'time_ms' used (its name states a unit); passed over 't', numeric" in err
    rec, dev, err = _convert(tmp_path, capfd, src, "--time-column", "t", "--time-unit", "s")
    np.testing.assert_allclose(rec.t, np.arange(50), atol=1e-12)
    assert "passed over" not in err


def test_time_column_option(tmp_path, capfd):
    """--time-column names the column (any name: 'millis'); an unknown name is one line
    listing the columns; a clock time named is refused naming its row; a name that is an
    axis, or --time-column on another format, is refused."""
    c = _counts(40)
    rows = [f"05:00:{k:02d},{20 * k},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(c)]
    src = _write(tmp_path / "m.csv", "time,millis,accX,accY,accZ", rows)
    rec, dev, _ = _convert(tmp_path, capfd, src, "--time-column", "millis", "--time-unit", "ms")
    assert dev["sample_rate_hz"] == pytest.approx(50.0)
    np.testing.assert_array_equal(rec.raw, c)
    err = _refused(tmp_path, capfd, src, "--time-column", "stamp")
    assert ("row 1: --time-column 'stamp': no such column; the columns are 'time', 'millis', 'accX', 'accY', "
            "'accZ'") in err
    err = _refused_again(tmp_path, capfd, 'r0', src, "--time-column", "time")
    assert "row 2, column time" in err and "'05:00:00'" in err
    err = _refused_again(tmp_path, capfd, 'r1', src, "--time-column", "accY")
    assert "is an accelerometer column" in err
    imucal = _write(tmp_path / "i.csv", "acc_x,acc_y,acc_z", ["1,2,3", "1,2,3"])
    err = _refused_again(tmp_path, capfd, 'r2', imucal, "--time-column", "t", "--rate", "100")
    assert "--time-column names a table's time column (--format table)" in err


def test_no_numeric_time_column_needs_a_rate(tmp_path, capfd):
    """Candidates that all hold clock times or dates: refused naming each without --rate;
    with --rate, read at that rate with a note."""
    c = _counts(30)
    rows = [f"05:00:{k:02d},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(c)]
    src = _write(tmp_path / "clock.csv", "Time(hh:mm:ss),accX,accY,accZ", rows)
    err = _refused(tmp_path, capfd, src)
    assert ("row 1: no time column holds numbers: 'Time(hh:mm:ss)' (row 2: '05:00:00') is a clock time or a "
            "date, not time stamps: give the sample rate with --rate HZ") in err
    rec, dev, err = _convert(tmp_path, capfd, src, "--rate", "10")
    np.testing.assert_allclose(rec.t, np.arange(30) / 10.0)
    assert "no time column holds numbers ('Time(hh:mm:ss)' (row 2: '05:00:00'): clock times or dates" in err


def test_a_header_written_as_a_comment_is_the_header(tmp_path, capfd):
    """Altus Metrum's AltOS CSV starts with '#version,serial,...,accel_x,accel_y,accel_z,...'
    and rows that hold a state's name among the numbers: the comment names the columns (it had
    been "cannot tell the format").  A comment that names other counts of columns, or a
    '# key: value' line, stays a comment."""
    c = _counts(40, seed=21)
    rows = [f"6,6583,{k / 10:.2f},{'pad' if k < 20 else 'boost'},{_cells(r * LSB_G)}" for k, r in enumerate(c)]
    src = _write(tmp_path / "altos.csv", "#version,serial,time,state_name,accel_x,accel_y,accel_z", rows)
    rc, out, err, _ = run(["convert", src, "--units", "g", "--lsb", repr(LSB_G), "-o", tmp_path / "o.csv",
                           "--device-out", tmp_path / "o.json"], capfd)
    assert rc == 0, err
    assert "the column names are read from the comment on line 1" in err and out.startswith("table: 40 rows"), out
    rec = read_recording(tmp_path / "o.csv")
    np.testing.assert_array_equal(rec.raw, c)
    short = _write(tmp_path / "short.csv", "#version,serial", rows)
    rc, _, err, _ = run(["convert", short, "--units", "g", "--lsb", repr(LSB_G), "-o", tmp_path / "p.csv"], capfd)
    assert rc == 2 and "comment" not in err


def test_a_rate_stated_in_a_comment_serves_a_table_without_a_time_column(tmp_path, capfd):
    """PicoQuake writes '# Config: data_rate = 2000.0 Hz, filter = 488 Hz, ...' above a table of
    a sample counter and readings in g: the rate is the comment's, with a note (it had been "no
    time column"); --rate states another; without such a comment, the old refusal."""
    c = _counts(30, seed=5)
    rows = [f"{k},{_cells(r * LSB_G)}" for k, r in enumerate(c)]
    src = _write(tmp_path / "pq.csv", "count,a_x,a_y,a_z", rows,
                 comments=("# PLab PicoQuake Data",
                           "# Config: data_rate = 2000.0 Hz, filter = 488 Hz, acc_range = 4 g"))
    rc, out, err, _ = run(["convert", src, "--units", "g", "--lsb", repr(LSB_G), "-o", tmp_path / "o.csv"], capfd)
    assert rc == 0 and "the rate is the 2000 Hz the file's comment '# Config' states" in err, err
    assert "2000 Hz" in out
    rc, out, err, _ = run(["convert", src, "--units", "g", "--lsb", repr(LSB_G), "--rate", "1000", "-o",
                           tmp_path / "p.csv"], capfd)
    assert rc == 0 and "1000 Hz" in out and "comment" not in err
    bare = _write(tmp_path / "bare.csv", "count,a_x,a_y,a_z", rows)
    rc, _, err, _ = run(["convert", bare, "--units", "g", "--lsb", repr(LSB_G), "-o", tmp_path / "q.csv"], capfd)
    assert rc == 2 and "no time column" in err
    # the counter named as the time column is no time (read in ms it had given the 2 kHz log 1 kHz)
    rc, _, err, _ = run(["convert", src, "--units", "g", "--lsb", repr(LSB_G), "--time-column", "count", "-o",
                         tmp_path / "r.csv"], capfd)
    assert rc == 2 and "the time column 'count' counts the samples (0, 1, ...)" in err, err
    assert not (tmp_path / "r.csv").exists()


def test_robotics_and_phone_exports_are_read(tmp_path, capfd):
    """Three common exports: ROS's `rostopic echo -p` of sensor_msgs/Imu (linear_acceleration
    is the specific force, gravity in: it had been refused as a phone's virtual sensor; the
    message's own header.stamp in ns before the bag's %time), PX4's ulog2csv sensor_combined
    (accelerometer_m_s2[0..2], t in us: "cannot tell the format"), and phyphox's tab-separated
    export with quoted names ("Time (s)" had been split at its blank)."""
    c = _counts(50, seed=31)
    mps2 = LSB_G * G
    stamp = 1_500_000_000_000_000_000 + 10_000_000 * np.arange(50)
    ros = [f"{st + 3_000_000 + 1000 * (k % 7)},{k},{st},imu,{_cells(r * mps2)},0.1" for k, (st, r) in
           enumerate(zip(stamp, c))]
    src = _write(tmp_path / "imu.csv", "%time,field.header.seq,field.header.stamp,field.header.frame_id,"
                 "field.linear_acceleration.x,field.linear_acceleration.y,field.linear_acceleration.z,"
                 "field.angular_velocity.x", ros)
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "mps2", "--lsb", repr(mps2))
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["sample_rate_hz"] == pytest.approx(100.0, rel=1e-9)
    assert "time column 'field.header.stamp' used (the message's own stamp)" in err, err
    px4 = [f"{21312085 + 4000 * k},0.1,0.2,0.3,{_cells(r * mps2)},7" for k, r in enumerate(c)]
    src = _write(tmp_path / "px4.csv", "timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2],accelerometer_m_s2[0],"
                 "accelerometer_m_s2[1],accelerometer_m_s2[2],magnetometer_ga[0]", px4)
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "mps2", "--lsb", repr(mps2))
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["sample_rate_hz"] == pytest.approx(250.0, rel=1e-9) and "timestamp read in us, PX4's unit" in err
    tab = "\n".join(f"{k / 200:.9E}\t{r[0] * mps2:.9E}\t{r[1] * mps2:.9E}\t{r[2] * mps2:.9E}" for k, r in enumerate(c))
    (tmp_path / "raw.csv").write_text('"Time (s)"\t"Acceleration x (m/s^2)"\t"Acceleration y (m/s^2)"\t'
                                      '"Acceleration z (m/s^2)"\n' + tab + "\n")
    rec, dev, err = _convert(tmp_path, capfd, tmp_path / "raw.csv", "--units", "mps2", "--lsb", repr(mps2), "--round")
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["sample_rate_hz"] == pytest.approx(200.0, rel=1e-6)


def test_px4_sensor_accel_export_is_read_by_its_file_name(tmp_path, capfd):
    """PX4's sensor_accel topic, as ulog2csv writes it (<log>_sensor_accel_0.csv), has bare x, y,
    z columns in m/s^2 and stamps in us (timestamp_sample, the sample's time, beside timestamp,
    the publication's): it had been "cannot tell the format", and a log of 1 Hz (the logger's
    interval) was read in ns as 1 kHz.  The same columns in a file whose name says no topic are
    refused, since PX4's gyro and magnetometer topics are exported alike."""
    c = _counts(40, seed=37)
    mps2 = LSB_G * G
    head = ("timestamp,timestamp_sample,device_id,x,y,z,temperature,error_count,clip_counter[0],clip_counter[1],"
            "clip_counter[2],samples")
    for step_us, rate in ((1_000_000, 1.0), (1000, 1000.0)):
        rows = [f"{1710773351242000 + step_us * k + 90},{1710773351242000 + step_us * k},1310988,{_cells(r * mps2)},"
                f"41.5,0,0,0,0,1" for k, r in enumerate(c)]
        src = _write(tmp_path / "flight_sensor_accel_0.csv", head, rows)
        rec, dev, err = _convert(tmp_path, capfd, src, "--units", "mps2", "--lsb", repr(mps2))
        np.testing.assert_array_equal(rec.raw, c)
        assert dev["sample_rate_hz"] == pytest.approx(rate, rel=1e-9), err
        assert "'timestamp_sample' used" in err and "timestamp_sample read in us, PX4's unit" in err
    err = _refused(tmp_path, capfd, _write(tmp_path / "gyro.csv", head, rows))
    assert "gyro.csv: row 1: the columns x, y, z do not say they are an accelerometer's" in err, err


def test_readings_held_for_two_rows_give_the_device_the_sensor_s_rate(tmp_path, capfd):
    """A LORD/MicroStrain SensorConnect export writes a 40 Hz sensor's readings twice, at 80 rows/s:
    the device file had stated the rows' 80 Hz without a word.  Now a note counts the held rows
    and the device states the distinct readings' 40 Hz; the recording keeps every row (t strictly
    increasing, one row per line of the file), which calibrate and diagnose count once."""
    c = np.repeat(_counts(400, seed=4), 2, axis=0)
    rows = [f"{1777931640000 + round(k * 12.5)},{','.join(f'{v * LSB_G:.10g}' for v in r)}" for k, r in enumerate(c)]
    src = _write(tmp_path / "SensorConnectData.csv", "Time,scaledAccelX,scaledAccelY,scaledAccelZ", rows)
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "g", "--full-scale", "2")
    np.testing.assert_array_equal(rec.raw, c)
    assert rec.n_samples == 800 and np.all(np.diff(rec.t) > 0)
    assert dev["sample_rate_hz"] == pytest.approx(40.0, rel=1e-3)
    assert "each reading held for 2 rows" in err and "400 distinct readings come at about 40 Hz" in err, err
    assert f"the device's rate is {dev['sample_rate_hz']:.6g} Hz, the distinct readings'" in err, err


@pytest.mark.parametrize("step, said", [(16, "(a 12-bit reading left-justified in 16 bits"), (3, "")])
def test_counts_on_a_coarser_step_are_noted(tmp_path, step, said):
    """A 12-bit chip left-justified in 16 bits (a LIS3DH: every count a multiple of 16) had been
    converted without a word; a note now gives the step and that the chip's resolution is the
    step, not one count.  Counts of every value get no note."""
    rng = np.random.default_rng(5)
    a = np.rint([-450, -5, 912] + rng.normal(0, 6, (400, 3))).astype(int)
    src = tmp_path / "lj.csv"
    src.write_text("t_ms,ax,ay,az\n" + "".join(f"{13 * i},{x * step},{y * step},{z * step}\n"
                                                for i, (x, y, z) in enumerate(a)))
    notes = convert_file(src).notes
    assert any(n.startswith(f"every count is a multiple of {step} {said}".rstrip()) and
               f"the chip's resolution is {step} counts" in n for n in notes), notes
    src.write_text("t_ms,ax,ay,az\n" + "".join(f"{13 * i},{x},{y},{z}\n" for i, (x, y, z) in enumerate(a)))
    assert not any("multiple of" in n for n in convert_file(src).notes)
