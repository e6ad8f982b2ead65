"""``accelcal convert`` of the shapes watch, phone and logger exports come in (a tester's
public recordings: a Garmin watch's and a machine survey's ISO-8601 stamps, an Axivity
AX6's formatted stamps, an Empatica E4's two-row preamble, headerless whitespace text).

Each file is written here in the recording's shape from known counts and times, so the
expected recording is those counts and times; bad files give one line naming the file and
row, exit 2, and no output.
"""
from __future__ import annotations

import datetime as dt

import numpy as np
import pytest

from cli_run import convert_ok, convert_refused, write_lines

G = 9.80665


def _counts(n, seed=0, mean=(-36.0, 620.0, -824.0), sd=4.0):
    rng = np.random.default_rng(seed)
    return np.round(np.asarray(mean) + sd * rng.standard_normal((n, 3))).astype(int)


def _convert(tmp_path, capfd, src, *args):
    rec, dev, err, said = convert_ok(tmp_path, capfd, src, *args)
    assert len(said.splitlines()) == 1
    return rec, dev, err, said


def _refused(tmp_path, capfd, src, *args, name="refused"):
    err = convert_refused(tmp_path, capfd, src, *args, name=name)
    assert src.name in err
    return err


def _stamp(when, form):
    """``when`` (an aware datetime) written as an ISO-8601 date-time of the form ``form``."""
    if form == "T+zone":
        return when.isoformat(timespec="milliseconds")
    if form == "space, no zone":
        return when.replace(tzinfo=None).isoformat(sep=" ", timespec="milliseconds")
    if form == "no fraction":
        return when.replace(tzinfo=None).isoformat(timespec="seconds")
    if form == "Z, us":
        return when.astimezone(dt.timezone.utc).replace(tzinfo=None).isoformat(timespec="microseconds") + "Z"
    raise ValueError(form)


# ---- ISO-8601 date-time stamps --------------------------------------------------------

@pytest.mark.parametrize("form,rate", [("T+zone", 25.0), ("space, no zone", 100.0), ("no fraction", 1.0),
                                       ("Z, us", 9.342)])
def test_iso_datetime_stamps_are_time_stamps(tmp_path, capfd, form, rate):
    """A Garmin watch's ``2019-10-16T12:09:01.702+02:00``, an AX6's ``2019-12-23
    21:04:06.690``, a survey logger's ``2021-05-07T10:29:56.172``: full date-times are time
    stamps (they had been refused as 'a clock time or a date'), read to the ns, the zone
    taken off; the stamp machinery gives the rate and reports the pause (50 steps here)."""
    n = 400
    zone = dt.timezone(dt.timedelta(hours=2))
    start = dt.datetime(2019, 10, 16, 12, 9, 1, 702000, tzinfo=zone)
    step_us = round(1e6 / rate)
    if form == "no fraction":
        start = start.replace(microsecond=0)
    if form == "T+zone" or form == "space, no zone":
        step_us = round(step_us / 1000) * 1000            # the stamps keep ms
    offs_us = np.arange(n) * step_us + np.where(np.arange(n) >= 250, 50 * step_us, 0)
    whens = [start + dt.timedelta(microseconds=int(u)) for u in offs_us]
    c = _counts(n)
    src = write_lines(tmp_path / "acc.csv", ["timestamp,accX,accY,accZ"] +
                 [f"{_stamp(w, form)},{a},{b},{d}" for w, (a, b, d) in zip(whens, c)])
    rec, dev, err, said = _convert(tmp_path, capfd, src)
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t - rec.t[0], offs_us / 1e6, rtol=0, atol=1e-6)
    epoch = whens[0].timestamp()
    if form in ("space, no zone", "no fraction"):
        epoch = whens[0].replace(tzinfo=dt.timezone.utc).timestamp()       # the clock's time, taken for UTC
        assert "state no zone" in err
    else:
        assert "UTC" in err and "state no zone" not in err
    assert rec.t[0] == pytest.approx(epoch, abs=1e-6)
    assert dev["sample_rate_hz"] == pytest.approx(1e6 / step_us, rel=1e-6)     # the device keeps 6 decimals
    assert "t has 1 step longer than 1.8 x its median step" in err and "clock time or a date" not in err


def test_a_zone_change_is_converted_to_utc_and_a_missing_zone_refused(tmp_path, capfd):
    """A clock put forward within a file (+01:00 to +02:00): every stamp in UTC, the steps
    even, a note naming the row.  A date-time without a zone among ones with a zone cannot
    be put on the same clock: refused naming its row.  A --time-unit is refused (date-times
    carry theirs); a clock time without a date stays refused as before."""
    n = 60
    utc = [dt.datetime(2020, 3, 29, 0, 59, 58, tzinfo=dt.timezone.utc) + dt.timedelta(milliseconds=50 * k)
           for k in range(n)]
    zoned = [w.astimezone(dt.timezone(dt.timedelta(hours=1 if k < 40 else 2))) for k, w in enumerate(utc)]
    c = _counts(n, seed=2)
    lines = [f"{w.isoformat(timespec='milliseconds')},{a},{b},{d}" for w, (a, b, d) in zip(zoned, c)]
    src = write_lines(tmp_path / "dst.csv", ["time,accX,accY,accZ"] + lines)
    rec, dev, err, _ = _convert(tmp_path, capfd, src)
    np.testing.assert_allclose(np.diff(rec.t), 0.05, atol=1e-6)
    assert rec.t[0] == pytest.approx(utc[0].timestamp(), abs=1e-6)
    assert "zone changes at row 42 (UTC+1 h to UTC+2 h" in err
    lines[10] = lines[10].replace("+01:00", "")
    bad = write_lines(tmp_path / "mixed.csv", ["time,accX,accY,accZ"] + lines)
    err = _refused(tmp_path, capfd, bad)
    assert "row 12, column time" in err and "states no zone where the first row's" in err
    err = _refused(tmp_path, capfd, src, "--time-unit", "ms", name="unit")
    assert "holds date-times, which carry their unit" in err
    clock = write_lines(tmp_path / "clock.csv", ["time,accX,accY,accZ"] + [f"12:09:{k:02d},1,2,3" for k in range(10)])
    err = _refused(tmp_path, capfd, clock, name="clock")
    assert "'12:09:00') is a clock time or a date, not time stamps" in err


def test_repeated_stamps_are_counted_and_can_be_left_out(tmp_path, capfd):
    """A Garmin export stamps two samples with one stamp now and then (93 of 10,000 rows:
    steps 80, 40, 40, 0 ms): refused at the first, the message counting them, saying how many
    follow a step of two (stamps a place late that catch up, not two samples at one instant) and
    naming --repeated-stamps drop, which leaves them out with a note (the rate stays 25 Hz)."""
    n = 200
    ms = 40 * np.arange(n)
    for k in (50, 120, 170):                 # a slot skipped, and two steps on one stamp given twice
        ms[k:k + 2] += 40
        ms[k + 2] = ms[k + 1]
    ms[91] = ms[90]                          # and one repeat after steps of one only
    c = _counts(n, seed=3)
    start = dt.datetime(2019, 10, 16, 12, 9, 1, 702000, tzinfo=dt.timezone(dt.timedelta(hours=2)))
    stamps = [(start + dt.timedelta(milliseconds=int(v))).isoformat(timespec="milliseconds") for v in ms]
    src = write_lines(tmp_path / "acc.csv", ["timestamp;accX;accY;accZ"] +
                 [f"{s};{a};{b};{d}" for s, (a, b, d) in zip(stamps, c)])
    err = _refused(tmp_path, capfd, src)
    assert "row 54, column timestamp" in err and "time stamps must increase; 4 row(s) repeat the stamp" in err
    assert ("(a logger that stamps two samples with one stamp), 3 of them after a step of two (with steps of one "
            "between): stamps that slipped a place late and caught up, the samples on their grid (--repeated-stamps "
            "shift moves them back a step, every sample kept): --repeated-stamps drop leaves them out (a sample "
            "each)") in err, err
    rec, dev, err, _ = _convert(tmp_path, capfd, src, "--repeated-stamps", "drop")
    keep = np.delete(np.arange(n), [52, 91, 122, 172])
    np.testing.assert_array_equal(rec.raw, c[keep])
    assert dev["sample_rate_hz"] == pytest.approx(25.0, rel=1e-9)
    assert "4 row(s) repeat the time stamp of the row before with other readings" in err
    err = _refused(tmp_path, capfd, write_lines(tmp_path / "r.csv", ["t,raw_0,raw_1,raw_2", "0,1,2,3", "1,1,2,3"]),
                   "--repeated-stamps", "drop", name="csv")
    assert "--repeated-stamps applies to a table's time column" in err


@pytest.mark.parametrize("kind", ["iso", "seconds"])
def test_slipped_stamps_can_be_shifted_back(tmp_path, capfd, kind):
    """--repeated-stamps shift: where a step of two and a repeat after steps of one prove that the
    stamps between slipped a place late (a Garmin export: 399 stamps in 90 runs of its 10,000 rows),
    each is moved back one step: every one of those samples is kept on its true stamp, t strictly
    increasing; a repeat no step of two explains is left out as by drop, with its own note."""
    n = 200
    ms = 40 * np.arange(n)
    true = ms.copy()
    for k, run in ((50, 2), (120, 5), (170, 3)):     # a slot skipped, then `run` stamps late, caught up
        ms[k:k + run] += 40
        ms[k + run] = ms[k + run - 1]
    ms[91] = ms[90]                                   # a repeat after steps of one only
    c = _counts(n, seed=4)
    if kind == "iso":
        start = dt.datetime(2019, 10, 16, 12, 9, 1, 702000, tzinfo=dt.timezone(dt.timedelta(hours=2)))
        stamps = [(start + dt.timedelta(milliseconds=int(v))).isoformat(timespec="milliseconds") for v in ms]
        t0 = start.timestamp()
    else:
        stamps, t0 = [repr(float(v) / 1000 + 0.5) for v in ms], 0.5
    src = write_lines(tmp_path / "acc.csv", ["timestamp;accX;accY;accZ"] +
                      [f"{s};{a};{b};{d}" for s, (a, b, d) in zip(stamps, c)])
    rec, dev, err, _ = _convert(tmp_path, capfd, src, "--repeated-stamps", "shift")
    keep = np.delete(np.arange(n), [91])
    np.testing.assert_array_equal(rec.raw, c[keep])
    np.testing.assert_allclose(rec.t - t0, true[keep] / 1000, atol=1e-6)
    assert np.all(np.diff(rec.t) > 0) and dev["sample_rate_hz"] == pytest.approx(25.0, rel=1e-9)
    assert "10 time stamps in 3 run(s) slipped a place late" in err and "every sample kept" in err, err
    assert "1 row(s) repeat the time stamp of the row before with other readings (a logger that stamps two samples " \
           "with one stamp): left out (--repeated-stamps shift: no step of two before them shows a slip)" in err, err


# ---- the nominal scale a device file gets from the readings ----------------------------

def _watch(n_rest_s=4.0, rate=25.0, per_g=1000.0, seed=4):
    """A wrist watch's counts (1 mg each): still poses whose z never points up, joined by 1 s
    turns, each pose's direction of f known."""
    rng = np.random.default_rng(seed)
    dirs = np.array([[0, 0, -1], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -0.7071, -0.7071], [0.7071, 0, -0.7071],
                     [0, 0.8, 0.2], [-0.6, 0.6, -0.529]])
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    parts = []
    for a, b in zip(dirs, np.vstack([dirs[1:], dirs[:1]])):
        parts.append(np.repeat(a[None], int(n_rest_s * rate), axis=0))
        s = np.linspace(0, 1, int(rate))[:, None]
        turn = (1 - s) * a + s * b + 0.1 * np.sin(np.pi * s) * rng.standard_normal(3)
        parts.append(turn / np.linalg.norm(turn, axis=1)[:, None] * (1 + 0.1 * np.sin(2 * np.pi * s)))
    f = np.vstack(parts)
    return np.round(per_g * f + 3.0 * rng.standard_normal(f.shape)).astype(int)


def test_the_nominal_scale_is_taken_from_the_still_stretches(tmp_path, capfd):
    """A watch on a wrist: its z never points up, so half the 1-99 % spread (which assumes every
    axis turned through +-1 g) said 74 counts per m/s^2 for a Garmin's 105.8.  The still
    stretches read |f| = g whatever the orientation: their median |reading| over g is the
    scale (1000 counts per g here), with a note saying so."""
    c = _watch()
    src = write_lines(tmp_path / "watch.csv", ["accX,accY,accZ"] + [f"{a},{b},{d}" for a, b, d in c])
    rec, dev, err, _ = _convert(tmp_path, capfd, src, "--rate", "25")
    k = dev["channels"][0]["counts_per_mps2"]
    assert k == pytest.approx(1000.0 / G, rel=0.005), err
    lo, hi = np.percentile(c, [1, 99], axis=0)
    assert np.mean(hi - lo) / 2 / G < 0.85 * k              # what the spread had given
    assert "is the median |reading| of 8 still stretches over g (|f| = g at rest" in err


def test_without_a_still_stretch_the_spread_gives_the_scale(tmp_path, capfd):
    """A recording that never holds still (a device tumbling the whole time): the spread gives
    the scale, and the note says it assumes each axis turned through +-1 g."""
    n, rate = 1500, 50.0
    t = np.arange(n) / rate
    f = np.column_stack([np.cos(2.1 * t) * np.cos(0.7 * t), np.sin(2.1 * t) * np.cos(0.7 * t), np.sin(0.7 * t)])
    c = np.round(500.0 * f + 2.0 * np.random.default_rng(5).standard_normal(f.shape)).astype(int)
    src = write_lines(tmp_path / "tumble.csv", ["accX,accY,accZ"] + [f"{a},{b},{d}" for a, b, d in c])
    rec, dev, err, _ = _convert(tmp_path, capfd, src, "--rate", "50")
    lo, hi = np.percentile(c, [1, 99], axis=0)
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(round(np.mean(hi - lo) / 2 / G, 1))
    assert "taken from the readings' spread, 1st to 99th percentile, as if every axis turned through +-1 g" in err


# ---- files without a header -------------------------------------------------------------

def test_headerless_whitespace_rows_say_what_was_seen_and_what_to_do(tmp_path, capfd):
    """An MPU-6050's tab-separated 'ax ay az gx gy gz' without a header had been taken for
    imu_tk's text ('expected 4 cells as in the header', with no header); three numbers a line
    (Magneto's input) are a log like their comma-separated kin; four are imu_tk's, and --rate
    then says the file was read so rather than blaming imu_tk files the user never named."""
    c = _counts(40, mean=(608, -372, 15556))
    six = write_lines(tmp_path / "sample_data.txt", [f"{a}\t{b}\t{d}\t-374\t166\t-77" for a, b, d in c])
    err = _refused(tmp_path, capfd, six)
    first = "\\t".join(str(v) for v in c[0])
    assert f"sample_data.txt: row 1: 6 whitespace-separated numbers a row and no header ('{first}\\t-374" in err
    assert ("imu_tk's text needs 4 (t ax ay az); for three readings a line give --format log --rate HZ; for other "
            "layouts add a header line naming the columns (ax ay az gx gy gz;") in err
    assert "as in the header" not in err
    three = write_lines(tmp_path / "acceldata.txt", [f"{a}\t{b}\t{d}" for a, b, d in c])
    rec, dev, err, said = _convert(tmp_path, capfd, three, "--rate", "10")
    np.testing.assert_array_equal(rec.raw, c)
    assert said.startswith("log: 40 rows")
    err = _refused(tmp_path, capfd, three, name="norate")
    assert "(lines of three numbers, no header) have no time column: give the sample rate with --rate HZ" in err
    four = write_lines(tmp_path / "xsens.txt", [f"{k / 100:.2f} {a} {b} {d}" for k, (a, b, d) in enumerate(c)])
    err = _refused(tmp_path, capfd, four, "--rate", "100", name="four")
    assert "--rate: the file was read as imu_tk's text (4 numbers a row and no header: t ax ay az)" in err


def test_headerless_csv_rows_are_quoted_as_the_file_holds_them(tmp_path, capfd):
    """A headerless export with ';' between its cells whose first column is no time stamp (a
    logger's millis() since boot): the message had quoted the line with ',' (the file's text
    after its rewrite as CSV).  It quotes the file's own line, says that there is no header,
    which one to add and when a first column is read as time without one."""
    c = _counts(30)
    src = write_lines(tmp_path / "acc.csv", [f"{1200 + 40 * k};{a};{b};{d}" for k, (a, b, d) in enumerate(c)])
    err = _refused(tmp_path, capfd, src)
    assert (f"acc.csv: row 1: 4 numbers a row and no header ('1200;{';'.join(str(v) for v in c[0])}'): a first "
            "column is read as time without a header only when it holds ISO-8601 date-times, or numbers above 2^24 "
            "(16777216) that never decrease; for other layouts add a header line naming the columns (t,ax,ay,az;") \
        in err, err
    back = write_lines(tmp_path / "back.csv", [f"{1551178506 + k / 100 - (k == 20):.4f},0.5,0.25,-1" for k in range(30)])
    assert "row 1: 4 numbers a row and no header ('1551178506.0000,0.5," in _refused(tmp_path, capfd, back, name="b")
    seven = write_lines(tmp_path / "seven.csv", [f"{1200 + 40 * k},0.5,0.25,-1,0.2,-0.5,15.7" for k in range(30)])
    err = _refused(tmp_path, capfd, seven, name="seven")
    assert ("7 numbers a row and no header ('1200,0.5,0.25,-1,0.2,-0.5,15.7'): for other layouts add a header line "
            "naming the columns (t,ax,ay,az,gx,gy,gz;") in err, err


def test_headerless_rows_of_a_time_and_two_triads_read_the_first_as_the_accelerometer(tmp_path, capfd):
    """An Axivity AX6's export: no header, a date-time, the accelerometer's x, y, z in g ('%.6f'),
    the gyroscope's in deg/s.  It had been refused ('which three are the accelerometer's no header
    says').  Cells 2-4 are read as the accelerometer's, cells 5-7 ignored, each with a note; a
    time and another count of numbers (5) stays refused, the refusal naming the --columns that
    reads it, and that reads it."""
    c = _counts(60, mean=(15.0, 146.0, 2048.0))
    g = c / 2048.0
    stamps = [f"2019-12-23 21:04:{6 + k // 100:02d}.{10 * (k % 100):03d}" for k in range(60)]
    rows = [f"{s},{a:.6f},{b:.6f},{d:.6f},0.274658,-0.503540,15.769958" for s, (a, b, d) in zip(stamps, g)]
    ax6 = write_lines(tmp_path / "ax6.csv", rows)
    rec, dev, err, said = _convert(tmp_path, capfd, ax6, "--units", "g", "--lsb", str(1 / 2048))
    np.testing.assert_array_equal(rec.raw, c)
    assert said.startswith("table: 60 rows, 3 channels (g / 0.00048828125 g per count), 100 Hz")
    assert ("no header: the 7 cells of each row are read as t,ax,ay,az,c5,c6,c7 (the first column holds ISO-8601 "
            "date-times: time stamps; the next three the accelerometer's x, y, z, as an Axivity AX6's export orders "
            "them, its gyroscope's after; --columns names three others, cell k as ck)") in err
    assert "ignored columns c5, c6, c7" in err
    five = write_lines(tmp_path / "five.csv", [r.rsplit(",", 2)[0] for r in rows])
    first = rows[0].rsplit(",", 2)[0]
    err = _refused(tmp_path, capfd, five, "--units", "g", "--lsb", str(1 / 2048), name="five")
    assert (f"5 numbers a row (the first a date-time) and no header ('{first[:60]}'): a time and 4 numbers: which "
            "three are the accelerometer's no header says: --columns c2,c3,c4 reads cells 2-4 as its x, y, z (cell k "
            "is ck, the first the time);") in err, err
    rec, _, err, _ = _convert(tmp_path, capfd, five, "--units", "g", "--lsb", str(1 / 2048), "--columns", "c2,c3,c4")
    np.testing.assert_array_equal(rec.raw, c)
    assert "ignored column c5" in err


def test_headerless_rows_with_a_time_stamp_first_are_read_as_t_x_y_z(tmp_path, capfd):
    """A Garmin watch's export (no header, ';', ISO-8601 stamps, counts) and an Axivity AX3's
    (no header, unix s, readings in g) had been refused with the header line to add.  Four
    cells whose first is a date-time, or numbers above 2^24 that never decrease, are t,x,y,z,
    with a note, and then read as the same rows under that header are: units, the zone."""
    c = _counts(60)
    rows = [f"2019-10-16T12:09:{1 + k // 25:02d}.{40 * (k % 25):03d}+02:00;{a};{b};{d}"
            for k, (a, b, d) in enumerate(c)]
    src = write_lines(tmp_path / "acc.csv", rows)
    rec, dev, err, said = _convert(tmp_path, capfd, src)
    assert said.startswith("table: 60 rows, 3 channels, 25 Hz")
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t - rec.t[0], np.arange(60) * 0.04, atol=1e-6)   # epoch s: ~0.2 us
    assert rec.t[0] == pytest.approx(1571220541.0, abs=1e-6)          # 12:09:01+02:00 in UTC
    assert ("no header: the 4 cells of each row are read as t,x,y,z (the first column holds ISO-8601 date-times: "
            "time stamps); a header line naming the columns states another layout") in err
    headed, _, _, _ = _convert(tmp_path, capfd, write_lines(tmp_path / "h.csv", ["t;x;y;z"] + rows))
    np.testing.assert_array_equal(headed.t, rec.t)
    g = c / 64.0
    ax3 = write_lines(tmp_path / "ax3.csv", ["# an AX3 export"] + [f"{1551178506 + k / 100:.4f},{a:.6f},{b:.6f},{d:.6f}"
                                                             for k, (a, b, d) in enumerate(g)])
    err = _refused(tmp_path, capfd, ax3)
    assert f"ax3.csv: row 2, column x: reading {g[0, 0]:g} is not a whole count (readings in m/s^2 or g: state " \
           "--units" in err
    rec, dev, err, said = _convert(tmp_path, capfd, ax3, "--units", "g", "--lsb", "0.015625")
    np.testing.assert_array_equal(rec.raw, c)
    assert said.startswith("table: 60 rows, 3 channels (g / 0.015625 g per count), 100 Hz")
    assert "(the first column holds numbers above 2^24 that never decrease, from 1551178506.0000: time stamps)" in err
    spaced = write_lines(tmp_path / "sp.txt", [r.replace(";", " ") for r in rows])
    rec, _, err, _ = _convert(tmp_path, capfd, spaced)
    np.testing.assert_array_equal(rec.raw, c)
    assert "read as t x y z" in err


# ---- an Empatica E4's export ----------------------------------------------------------

def test_an_empatica_e4_export_is_read_with_its_start_and_rate(tmp_path, capfd):
    """An E4's ACC.csv: row 1 the start as unix time and row 2 the rate, each repeated in the
    three columns, then x,y,z in signed 8-bit counts of 1/64 g.  Row 1 had been read as a
    reading ('1560279825 counts is outside signed 8-bit ... (state --bits N)').  Now: t from
    the start at row 2's rate, the device 64 counts per g in 8 bits; --format log names the
    layout; a row 2 that is no rate is one line saying what to do."""
    c = _counts(300, seed=6, mean=(-61, 25, 6), sd=2.0)
    pre = ["1560279825.000000, 1560279825.000000, 1560279825.000000", "32.000000, 32.000000, 32.000000"]
    src = write_lines(tmp_path / "ACC.csv", pre + [f"{a},{b},{d}" for a, b, d in c])
    rec, dev, err, said = _convert(tmp_path, capfd, src)
    assert said.startswith("e4: 300 rows, 3 channels, 32 Hz")
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t, 1560279825.0 + np.arange(300) / 32.0, rtol=0, atol=1e-6)
    assert dev["sample_rate_hz"] == 32.0 and (dev["raw_min"], dev["raw_max"]) == (-128, 127)
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(64.0 / G)
    assert "rows 1-2 are an Empatica E4's session start (1560279825.000000 unix s) and sample rate (32 Hz)" in err
    rec, dev, err, said = _convert(tmp_path, capfd, src, "--rate", "32", "--full-scale", "2", "--bits", "8")
    np.testing.assert_array_equal(rec.raw, c)
    err = _refused(tmp_path, capfd, src, "--format", "log", "--rate", "32", "--bits", "8")
    assert "row 1: rows 1-2 are one value repeated, a start time and a rate, as an Empatica E4's export" in err
    assert "--bits" not in err
    bad = write_lines(tmp_path / "bad.csv", [pre[0], "0.000000, 0.000000, 0.000000"] + [f"{a},{b},{d}" for a, b, d in c])
    err = _refused(tmp_path, capfd, bad, name="bad")
    assert "row 2: rows 1-2 look like an Empatica E4's start time (1560279825, unix s) and sample rate, but row 2's " \
           "'0.000000' is no rate in Hz: remove the two rows and give --rate HZ" in err


def test_bare_x_y_z_columns_are_refused_in_words_that_fit_any_logger(tmp_path, capfd):
    """Bare 'x,y,z' beside other columns than time (a temperature, a device id: PX4's gyro and
    magnetometer topics are written alike), or in a file named for another sensor: the refusal
    says what the names lack, lists the header and names the option that states them, PX4's
    file name last.  (Beside a time column alone they are read: test_convert_columns.)"""
    rows = [f"2021-05-07T10:29:{k:02d}.172,0.05,-0.05,-0.98,21.5" for k in range(20)]
    src = write_lines(tmp_path / "survey.csv", ["timestamp,x,y,z,temperature"] + rows)
    err = _refused(tmp_path, capfd, src)
    assert ("the columns x, y, z do not say they are an accelerometer's (a gyroscope's or a magnetometer's are "
            "written alike; the header's columns: 'timestamp', 'x', 'y', 'z', 'temperature'): if they are, give "
            "--columns x,y,z (a PX4") in err
    gyro = write_lines(tmp_path / "log_sensor_gyro_0.csv", ["timestamp,x,y,z"] + [r.rsplit(",", 1)[0] for r in rows])
    assert "do not say they are an accelerometer's" in _refused(tmp_path, capfd, gyro, name="gyro")


def _phone(n, gravity, seed=5):
    """A phone's acceleration in m/s^2 at 100 Hz: 2 s held still (noise 0.02 m/s^2), then a
    swing of 1-3 m/s^2 on every axis; ``gravity``: the specific force (g along -z, tilted), else
    the user acceleration a phone app writes with gravity taken out."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    a = 0.02 * rng.standard_normal((n, 3))
    a[200:] += np.column_stack([np.sin(k[200:] / 7.0), 3 * np.cos(k[200:] / 11.0), 2 * np.sin(k[200:] / 5.0)])
    if gravity:
        a += G * np.array([0.1, -0.3, -0.95]) / np.linalg.norm([0.1, -0.3, -0.95])
    return np.round(a, 3)


@pytest.mark.parametrize("gravity", [False, True])
def test_gravity_removed_readings_are_named(tmp_path, capfd, gravity):
    """Sensor Logger's Accelerometer.csv is user acceleration, gravity removed: |f| near 0 where
    the phone is still.  It had been converted without a word, and every later command then blamed
    something else (no static pose, the calibration's scale).  convert notes it, naming the still
    rows and the export to use; the same phone with gravity in (TotalAcceleration.csv) has no such
    note.  The counts are the readings' either way."""
    a = _phone(600, gravity)
    rows = [f"{1740240343434371300 + 10_000_000 * i},{i / 100:.6f}," + ",".join(f"{v:.3f}" for v in r[::-1])
            for i, r in enumerate(a)]
    src = write_lines(tmp_path / "Accelerometer.csv", ["time,seconds_elapsed,z,y,x"] + rows)
    rec, _, err, _ = _convert(tmp_path, capfd, src, "--units", "mps2", "--lsb", "0.001")
    np.testing.assert_array_equal(rec.raw, np.round(a / 0.001).astype(int))
    said = [ln for ln in err.splitlines() if "gravity looks removed" in ln]
    if gravity:
        assert not said, err
    else:
        assert len(said) == 1 and "rows 2-" in said[0] and "TotalAcceleration.csv" in said[0], err
        f_g = float(said[0].split("|f| = ")[1].split(" g")[0])
        assert f_g < 0.01, said
