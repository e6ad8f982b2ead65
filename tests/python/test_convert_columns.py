"""``accelcal convert`` of tables whose accelerometer columns are named by the axis alone
(``time,x (g),y (g),z (g)``: a Raspberry Pi logger's MPU-9250 at +-8 g), or not at all
(``# time tx ty tz wx ...`` over headerless rows: a tumble-calibration session), and of a
free-text title line before the header.  ``--columns X,Y,Z`` names the three.

Each file is written here in the recording's shape from known counts and times; bad files
give one line naming the file and row, exit 2, and no output.
"""
from __future__ import annotations


import numpy as np
import pytest

from accelcal.io.recording import read_recording
from cli_run import convert_ok, convert_refused, run, write_lines

LSB_G = 1.0 / 4096                      # +-8 g at 16 bits
G = 9.80665


def _counts(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.round([400.0, 180.0, 3150.0] + 6.0 * rng.standard_normal((n, 3))).astype(int)


def _convert(tmp_path, capfd, src, *args):
    rec, dev, err, said = convert_ok(tmp_path, capfd, src, *args)
    assert said.startswith("table: ")
    return rec, dev, err


def _refused(tmp_path, capfd, src, *args, name="refused"):
    err = convert_refused(tmp_path, capfd, src, *args, name=name)
    return err


def _rows(c, rate=180.0, sep=","):
    return [sep.join([repr(k / rate)] + [repr(float(v) * LSB_G) for v in r]) for k, r in enumerate(c)]


def test_axes_named_by_their_letter_and_a_unit(tmp_path, capfd):
    """'time,x (g),y (g),z (g)' had been 'cannot tell the format', and with --format table 'no
    column for axis x among the accelerometer columns (none)'.  A unit of acceleration says the
    columns are an accelerometer's; a gyroscope's 'x (deg/s)' is not taken for one."""
    c = _counts(400)
    src = write_lines(tmp_path / "start_up_data_1.csv", ["time,x (g),y (g),z (g)"] + _rows(c))
    rec, dev, _ = _convert(tmp_path, capfd, src, "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t, np.arange(400) / 180.0)
    assert dev["sample_rate_hz"] == pytest.approx(180.0)
    gyro = write_lines(tmp_path / "gyro.csv", ["time,x (deg/s),y (deg/s),z (deg/s)"] + _rows(c))
    err = _refused(tmp_path, capfd, gyro, "--format", "table", "--full-scale", "8")
    assert "no column for axis x among the header's columns (the header's columns: 'time', 'x (deg/s)', " \
           "'y (deg/s)', 'z (deg/s)'" in err and "--columns" in err


def test_bare_x_y_z_beside_a_time_column_alone(tmp_path, capfd):
    """'time,x,y,z' and nothing else: the accelerometer's, with a note (a machine survey's
    'timestamp,x,y,z' had been refused though no other sensor's columns are there)."""
    c = _counts(200, seed=1)
    src = write_lines(tmp_path / "survey.csv", ["time,x,y,z"] + _rows(c))
    rec, _, err = _convert(tmp_path, capfd, src, "--units", "g", "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    assert "the columns x, y, z beside time and no other sensor's are taken as the accelerometer's" in err


def test_a_title_line_before_the_header_is_left_out(tmp_path, capfd):
    """A sentence before the header ('Acceleration Data Collected on Level Surface. Z up.') had
    been taken for the header (refused at row 1); it is left out with a note, and row numbers
    stay the file's."""
    c = _counts(300, seed=2)
    lines = ["Acceleration Data Collected on Level Surface. Z up.", "time,x (g),y (g),z (g)"] + _rows(c)
    src = write_lines(tmp_path / "six_position.csv", lines)
    rec, _, err = _convert(tmp_path, capfd, src, "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    assert "line 1 ('Acceleration Data Collected on Level Surface. Z up.') is neither a header nor data (a title " \
           "before the header on line 2): left out" in err
    lines[10] = lines[10] + ",0.5"
    err = _refused(tmp_path, capfd, write_lines(tmp_path / "bad.csv", lines), "--full-scale", "8")
    assert "bad.csv: row 11: expected 4 cells as in the header, got 5" in err


def test_a_refusal_prints_the_notes_made_before_it(tmp_path, capfd):
    """A refused conversion had printed its error line alone: the notes made before it (a title
    line left out, the zone taken off date-times) never reached the user, though they say how
    the file was read.  They come first, as note lines, then the one error line; exit 2 and no
    output, as before."""
    c = _counts(30, seed=2)
    title = "Acceleration Data Collected on Level Surface. Z up."
    lines = [title, "time,x (g),y (g),z (g)"] + _rows(c)
    lines[10] = lines[10] + ",0.5"
    err = _refused(tmp_path, capfd, write_lines(tmp_path / "bad.csv", lines), "--full-scale", "8").splitlines()
    assert len(err) == 2 and err[0] == (f"accelcal convert: note: line 1 ({title!r}) is neither a header nor data (a "
                                        "title before the header on line 2): left out"), err
    assert err[1].startswith("accelcal convert: error: ") and err[1].endswith("row 11: expected 4 cells as in the "
                                                                              "header, got 5")
    imucal = write_lines(tmp_path / "imucal.csv", [title, "acc_x,acc_y,acc_z"] + [",".join(map(str, r)) for r in c])
    err = _refused(tmp_path, capfd, imucal, name="imucal").splitlines()
    assert len(err) == 2 and "is neither a header nor data" in err[0], err
    assert "imucal files have no time column: give the sample rate with --rate HZ" in err[1]
    stamps = [f"2019-10-16T12:09:01.{40 * min(k, 20):03d}+02:00" for k in range(30)]   # rows 22-31 repeat row 21's
    dated = write_lines(tmp_path / "dated.csv", ["timestamp,accX,accY,accZ"] + [f"{s},{a},{b},{d}"
                                                                            for s, (a, b, d) in zip(stamps, c)])
    err = _refused(tmp_path, capfd, dated, name="dated").splitlines()
    assert "'timestamp' holds ISO-8601 date-times: t is seconds since 1970-01-01 UTC (their zone, UTC+2 h, taken " \
           "off)" in err[0], err
    assert "row 23, column timestamp: time stamp" in err[-1] and "9 row(s) repeat the stamp" in err[-1]


def test_columns_names_the_accelerometer(tmp_path, capfd):
    """--columns X,Y,Z names the three columns whatever they are called (with or without the unit
    in () at a name's end, which states the unit); a name not in the header is refused listing
    the header."""
    c = _counts(200, seed=3)
    src = write_lines(tmp_path / "log.csv", ["stamp,temp,u1 (g),u2 (g),u3 (g)"] +
                 [f"{k / 100.0!r},21.5," + ",".join(repr(float(v) * LSB_G) for v in r) for k, r in enumerate(c)])
    rec, _, err = _convert(tmp_path, capfd, src, "--columns", "u1 (g),u2 (g),u3 (g)", "--full-scale", "8",
                           "--rate", "100")
    np.testing.assert_array_equal(rec.raw, c)
    # a name without its unit names the column too
    rec, _, err = _convert(tmp_path, capfd, src, "--columns", "u1,u2,u3", "--full-scale", "8", "--rate", "100")
    np.testing.assert_array_equal(rec.raw, c)
    err = _refused(tmp_path, capfd, src, "--columns", "v1,v2,v3", "--full-scale", "8")
    assert "log.csv: row 1: --columns 'v1': no such column; the columns are 'stamp', 'temp', 'u1 (g)', 'u2 (g)', " \
           "'u3 (g)'" in err
    err = _refused(tmp_path, capfd, src, "--columns", "u1 (g),u2 (g)", name="two")
    assert "expected the accelerometer's three columns X,Y,Z" in err


def test_a_comment_naming_whitespace_columns_is_the_header(tmp_path, capfd):
    """'# time tx ty tz wx wy wz ...' over headerless rows of as many numbers: the comment is the
    header (a note).  tx, ty, tz do not say they are an accelerometer's (t is also translation):
    the refusal names the triples and the option; --columns tx,ty,tz reads them."""
    c = _counts(150, seed=4)
    rows = [" ".join([f"{1535630275.9 + k / 100.0:.6f}"] + [f"{v * LSB_G * G:.10g}" for v in r] +
                     ["0.001", "-0.002", "0.003", "0", "0", "0", "0.1", "0.2", "0.3", "0.9"]) + " "
            for k, r in enumerate(c)]
    src = write_lines(tmp_path / "imu_good1.txt", ["# time tx ty tz wx wy wz mx my mz qx qy qz qw"] + rows)
    err = _refused(tmp_path, capfd, src)
    assert "imu_good1.txt: row 1: no column of this header ('# time tx ty tz wx wy wz mx my mz qx qy qz qw') says " \
           "it is an accelerometer's: if three of them are, name them with --columns tx,ty,tz (the header's " \
           "triples: tx,ty,tz; wx,wy,wz; mx,my,mz; qx,qy,qz)" in err
    rec, _, err = _convert(tmp_path, capfd, src, "--columns", "tx,ty,tz", "--units", "mps2", "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    assert "the column names are read from the comment on line 1" in err
    np.testing.assert_allclose(rec.t - rec.t[0], np.arange(150) / 100.0, atol=2e-6)


def test_a_comment_naming_a_logs_three_columns_keeps_it_a_log(tmp_path, capfd):
    """'# x y z' over lines of three numbers: still a monitor's log (--rate), not a table whose
    bare x, y, z are refused."""
    c = _counts(60, seed=5)
    src = write_lines(tmp_path / "capture.txt", ["# x y z"] + [f"{r[0]} {r[1]} {r[2]}" for r in c])
    out = tmp_path / "o.csv"
    rc, said, err, _ = run(["convert", src, "--rate", "50", "-o", out], capfd)
    assert rc == 0 and said.startswith("log: "), err
    np.testing.assert_array_equal(read_recording(out).raw, c)


def _kalibr_file(tmp_path):
    """An EuRoC IMU file in Kalibr's layout (ns stamps at 200 Hz, gyroscope columns first, the
    accelerometer in m s^-2 on an LSB of g/1200): its counts, LSB and path."""
    raw = _counts(400)
    lsb = 9.80665 / 1200
    head = ("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]")
    rows = [f"{1403636579758555392 + 5000000 * i},0.01,-0.02,0.03," + ",".join(f"{v * lsb:.10f}" for v in r)
            for i, r in enumerate(raw)]
    return raw, lsb, write_lines(tmp_path / "data.csv", [head] + rows)


def test_a_kalibr_header_s_columns_and_unit_are_read(tmp_path, capfd):
    """EuRoC's IMU files (Kalibr's layout): '#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_x
    [m s^-2],...'.  --columns a_RS_S_x,... had been 'no such column' (the names carry their unit),
    and the unit 'm s^-2' was refused; both are read now."""
    raw, lsb, src = _kalibr_file(tmp_path)
    rec, dev, err = _convert(tmp_path, capfd, src, "--columns", "a_RS_S_x,a_RS_S_y,a_RS_S_z", "--units", "mps2",
                             "--lsb", str(lsb), "--round")
    np.testing.assert_array_equal(rec.raw, raw)
    assert dev["sample_rate_hz"] == pytest.approx(200.0, rel=1e-9)


def test_a_kalibr_header_s_accelerometer_is_found_unasked(tmp_path, capfd):
    """EuRoC's IMU file without --columns: the 'a_' columns in m s^-2 are the accelerometer's, the
    'w_' columns in rad s^-1 are dropped as the gyroscope's (named in the note), the commented
    '#timestamp [ns]' is the time column in ns.  It had been refused ('no column of this header
    says it is an accelerometer's')."""
    raw, lsb, src = _kalibr_file(tmp_path)
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "mps2", "--lsb", str(lsb), "--round")
    np.testing.assert_array_equal(rec.raw, raw)
    assert dev["sample_rate_hz"] == pytest.approx(200.0, rel=1e-9)
    np.testing.assert_allclose(np.diff(rec.t), 0.005, atol=1e-6)   # t an epoch in s: float64's spacing 2.4e-7 s
    assert "dropped gyroscope columns w_RS_S_x [rad s^-1], w_RS_S_y [rad s^-1], w_RS_S_z [rad s^-1]" in err
    assert "t read in ns" in err
    # |f| at rest is the |f| written: counts over the device's scale
    f = np.linalg.norm(rec.raw.mean(axis=0)) / dev["channels"][0]["counts_per_mps2"]
    assert f == pytest.approx(np.linalg.norm(raw.mean(axis=0)) * lsb, rel=1e-6)
    # the gyro's columns in a unit of angular rate are not taken for the accelerometer's
    gyro = [line.rsplit(",", 3)[0] for line in src.read_text().splitlines()]
    err = _refused(tmp_path, capfd, write_lines(tmp_path / "gyro.csv", gyro))
    assert "w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1]" in err


def test_whole_counts_stated_as_g_are_refused_with_the_option_meant(tmp_path, capfd):
    """'--units g --lsb 0.001' over a logger's integer counts had read 1016 as 1016 g, caught
    only by the range check (and not at all with --bits 32).  Every reading a whole number, where
    one count is a thousandth of a g: they are counts, and the refusal says which option was
    meant; given so, they are read.  Readings in g on that LSB are read as before."""
    c = _counts(200)
    src = write_lines(tmp_path / "log.csv", ["t,accX,accY,accZ"] + [f"{k / 100},{a},{b},{d}"
                                                                     for k, (a, b, d) in enumerate(c)])
    err = _refused(tmp_path, capfd, src, "--units", "g", "--lsb", "0.001", "--bits", "32")
    top = np.unravel_index(np.argmax(np.abs(c)), c.shape)
    assert (f"row {top[0] + 2}, column {'accX accY accZ'.split()[top[1]]}: every reading is a whole number" in err and
            f"would be {c[top]} g) where one count is 0.001 g (the LSB stated by --lsb): they are counts -- give "
            "--units counts --lsb 0.001g (or --full-scale G) for their size; were they whole g, --lsb 1") in err, err
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "counts", "--lsb", "0.001g")
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(1000 / G)
    g = write_lines(tmp_path / "g.csv", ["t,accX,accY,accZ"] + [f"{k / 100},{a / 1000},{b / 1000},{d / 1000}"
                                                                 for k, (a, b, d) in enumerate(c)])
    rec, _, _ = _convert(tmp_path, capfd, g, "--units", "g", "--lsb", "0.001")
    np.testing.assert_array_equal(rec.raw, c)


def test_a_phone_apps_z_y_x_columns_are_read_in_x_y_z_order(tmp_path, capfd):
    """Sensor Logger's 'time,seconds_elapsed,z,y,x': in a file named AccelerometerUncalibrated.csv
    the name says they are the accelerometer's (it had been refused); each column goes to its own
    axis, raw_0 the x column.  In a file whose name says nothing, or names another sensor, they are
    refused, and the hint lists them X,Y,Z (it had said '--columns z,y,x', which, followed, put the
    file's z in raw_0: a mirrored frame)."""
    c = _counts(300, seed=2)
    rows = [f"{1699734109763076400 + k * 10_000_000},{k / 100:.6f}," + ",".join(repr(float(v) * LSB_G)
                                                                            for v in r[::-1]) for k, r in enumerate(c)]
    src = write_lines(tmp_path / "AccelerometerUncalibrated.csv", ["time,seconds_elapsed,z,y,x"] + rows)
    rec, dev, err = _convert(tmp_path, capfd, src, "--full-scale", "8", "--units", "g")
    np.testing.assert_array_equal(rec.raw, c)
    assert "the columns x, y, z are taken as the accelerometer's, as the file's name " \
           "'AccelerometerUncalibrated.csv' says" in err
    assert dev["sample_rate_hz"] == pytest.approx(100.0)
    for name in ("data.csv", "Gyroscope.csv", "Gravity.csv"):
        other = write_lines(tmp_path / name, ["time,seconds_elapsed,z,y,x"] + rows)
        err = _refused(tmp_path, capfd, other, "--full-scale", "8", "--units", "g", name=f"refused_{name}")
        assert "do not say they are an accelerometer's" in err and "give --columns x,y,z " in err, err
        rec, _, _ = _convert(tmp_path, capfd, other, "--full-scale", "8", "--units", "g", "--columns", "x,y,z")
        np.testing.assert_array_equal(rec.raw, c)


@pytest.mark.parametrize("order,mirrored", [("z,y,x", True), ("y,x,z", True), ("accX,accZ,accY", True),
                                            ("y,z,x", False), ("z,x,y", False), ("x,y,z", False)])
def test_columns_that_mirror_the_frame_are_noted(tmp_path, capfd, order, mirrored):
    """--columns over columns named for the axes: an odd permutation of them (a swap) mirrors the
    frame (left-handed), which no mounting gives: taken as stated, with a note naming the columns
    moved; a cyclic order (a sensor mounted rotated) has none."""
    c = _counts(40)
    names = ["accX", "accY", "accZ"] if "acc" in order else ["x", "y", "z"]
    src = write_lines(tmp_path / "log.csv", ["t," + ",".join(names)] +
                      [f"{k / 100!r}," + ",".join(str(int(v)) for v in r) for k, r in enumerate(c)])
    rec, _, err = _convert(tmp_path, capfd, src, "--columns", order)
    picked = [names.index(n) for n in order.split(",")]
    assert rec.raw.tolist() == c[:, picked].tolist()
    assert ("the frame is mirrored (left-handed)" in err) == mirrored, err
    if order == "z,y,x":
        assert "--columns puts column 'z' as the x axis, column 'x' as the z axis" in err, err
