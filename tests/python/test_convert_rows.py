"""Rows of another tool's file that are no samples, one rule on every path of ``accelcal
convert``: a logger's leading ``0, 0, 0`` placeholder (a robot lab's MATLAB files start so),
and rows whose readings are all missing (NaN: a sample the logger lost; one in 1,984 had made
a file unusable).  The rows after a lost sample keep their places in time, so the estimators
fill the gap on their grid.  Files are written here from known counts."""
from __future__ import annotations


import numpy as np
import pytest
import scipy.io

from cli_run import convert_ok, convert_refused

LSB_G = 1e-4


def _counts(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.round([30.0, -40.0, 9950.0] + 25.0 * rng.standard_normal((n, 3))).astype(int)


def _convert(tmp_path, capfd, src, *args):
    return convert_ok(tmp_path, capfd, src, *args)[:3]


def _mat(tmp_path, a):
    src = tmp_path / "MPU6050RM3100.mat"
    scipy.io.savemat(src, {"SENSacc": np.asarray(a).T})       # 3xN, as the robot lab's files hold them
    return src


GIVE = ("--units", "g", "--lsb", repr(LSB_G), "--rate", "100")


def test_a_leading_placeholder_is_left_out_on_every_path(tmp_path, capfd):
    """The table path left out a leading 0,0,0 row; a MATLAB file's and a log's had been kept
    without a word (|f| = 0 there: displacement then missed the initial rest).  The sample
    after keeps its time (1/rate)."""
    c = _counts(200)
    a = np.vstack([[0.0, 0.0, 0.0], c * LSB_G])
    rec, dev, err = _convert(tmp_path, capfd, _mat(tmp_path, a), *GIVE)
    np.testing.assert_array_equal(rec.raw, c)
    assert rec.t[0] == pytest.approx(0.01)
    assert "the first 1 row(s) (row 1) read exactly 0, 0, 0 where the next row's |reading| is" in err
    assert "a placeholder before the sensor's first value, left out" in err
    log = tmp_path / "capture.txt"
    log.write_text("MPU6050 ready\n0,0,0\n" + "".join(f"{r[0]},{r[1]},{r[2]}\n" for r in c))
    rec, _, err = _convert(tmp_path, capfd, log, "--format", "log", "--rate", "100", "--full-scale", "4")
    np.testing.assert_array_equal(rec.raw, c)
    assert "the first 1 row(s) (row 2) read exactly 0, 0, 0" in err


def test_a_lost_sample_is_left_out_and_keeps_its_place(tmp_path, capfd):
    """A NaN row of a MATLAB array had been 'row 369, column SENSacc(:,1): nan is not a finite
    number'.  It is a sample lost: left out with a note naming the row, the rows after at their
    own times (a gap of one sample, not every later sample a period early).  A row with only
    some readings NaN stays refused, naming its row and column."""
    c = _counts(400, seed=1)
    a = (c * LSB_G).astype(float)
    a[368] = np.nan
    a[369] = np.nan
    rec, dev, err = _convert(tmp_path, capfd, _mat(tmp_path, a), *GIVE)
    keep = np.r_[0:368, 370:400]
    np.testing.assert_array_equal(rec.raw, c[keep])
    np.testing.assert_allclose(rec.t, keep / 100.0)
    assert dev["sample_rate_hz"] == 100.0
    assert "2 row(s) whose readings (SENSacc(:,1), SENSacc(:,2), SENSacc(:,3)) are all missing (empty or nan), the " \
           "first row 369: left out (samples the logger lost: the rows after keep their places in time" in err
    a[368, 1:] = c[368, 1:] * LSB_G
    err = convert_refused(tmp_path, capfd, _mat(tmp_path, a), *GIVE)
    assert "row 369, column SENSacc(:,1): expected a reading, got nan where SENSacc(:,2) and SENSacc(:,3) have one" \
        in err


def test_a_lost_sample_of_a_timed_array_and_of_a_log(tmp_path, capfd):
    """t, x, y, z with a row all NaN (its time too): the stamps around it keep the gap; a log's
    'nan,nan,nan' line (it had been taken for text and split the readings into blocks) is a
    sample lost the same way."""
    c = _counts(150, seed=2)
    t = np.arange(150) / 50.0
    a = np.column_stack([t, c * LSB_G])
    a[70] = np.nan
    src = tmp_path / "timed.mat"
    scipy.io.savemat(src, {"buf": a})
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "g", "--lsb", repr(LSB_G))
    np.testing.assert_array_equal(rec.raw, np.delete(c, 70, axis=0))
    np.testing.assert_allclose(rec.t, np.delete(t, 70))
    assert dev["sample_rate_hz"] == pytest.approx(50.0) and "the first row 71" in err
    lines = [f"{r[0]},{r[1]},{r[2]}" for r in c]
    lines[40] = "nan,nan,nan"
    log = tmp_path / "capture.txt"
    log.write_text("MPU6050 ready\n" + "".join(line + "\n" for line in lines))
    rec, _, err = _convert(tmp_path, capfd, log, "--format", "log", "--rate", "50", "--full-scale", "4")
    np.testing.assert_array_equal(rec.raw, np.delete(c, 40, axis=0))
    np.testing.assert_allclose(rec.t, np.delete(np.arange(150), 40) / 50.0)
    assert "the first row 42: left out" in err and "split the readings into 1 block(s)" in err


def test_every_path_keeps_its_notes_on_a_refusal(tmp_path, capfd):
    """A refusal after notes were made prints them ahead of its error line on every path (one
    mechanism, errors.notes_on_refusal).  The log, E4, csv and MATLAB paths had dropped them: a log
    with a sample lost and no --rate, an E4 export with a reading that is no whole count, a
    recording whose last line was cut short with two channels, or whose t runs back, a MATLAB
    array with a lost sample and no --rate."""
    c = _counts(60, seed=3)
    lines = [f"{r[0]},{r[1]},{r[2]}" for r in c]
    lines[20] = "nan,nan,nan"
    log = tmp_path / "capture.txt"
    log.write_text("MPU6050 ready\n" + "".join(line + "\n" for line in lines))
    err = convert_refused(tmp_path, capfd, log, "--format", "log", name="log")
    assert "split the readings into 1 block(s)" in err and "the first row 22: left out" in err
    assert err.splitlines()[-1].endswith("give the sample rate with --rate HZ")
    e4 = tmp_path / "ACC.csv"
    e4.write_text("1495437325.000000, 1495437325.000000, 1495437325.000000\n32.000000, 32.000000, 32.000000\n" +
                  "".join(f"{r[0] // 100},{r[1] // 100},{r[2] // 100}\n" for r in c[:20]) + "1.5,2,3\n")
    err = convert_refused(tmp_path, capfd, e4, name="e4")
    assert "rows 1-2 are an Empatica E4's session start" in err and "row 23, column x" in err.splitlines()[-1]
    rec = ["t,raw_0,raw_1"] + [f"{k / 100},{r[0]},{r[1]}" for k, r in enumerate(c)] + ["0.6,12"]
    csv = tmp_path / "rec.csv"
    csv.write_text("\n".join(rec))                       # the last line cut short, no newline after it
    err = convert_refused(tmp_path, capfd, csv, name="csv")
    assert "the last, is cut short" in err and "2 raw channels" in err.splitlines()[-1]
    back = ["t,raw_0,raw_1,raw_2"] + [f"{k / 100 if k != 30 else 0.1},{r[0]},{r[1]},{r[2]}" for k, r in enumerate(c)]
    csv.write_text("\n".join(back + ["0.6,12"]))
    err = convert_refused(tmp_path, capfd, csv, name="back")
    assert "the last, is cut short" in err and "t must be strictly increasing" in err.splitlines()[-1]
    a = (c * LSB_G).astype(float)
    a[10] = np.nan
    err = convert_refused(tmp_path, capfd, _mat(tmp_path, a), "--units", "g", "--lsb", repr(LSB_G), name="mat")
    assert "the first row 11: left out" in err and "give the sample rate with --rate HZ" in err.splitlines()[-1]


def test_stamps_that_run_back_after_the_last_reading_are_said_so_not_lost(tmp_path, capfd):
    """A table whose last rows hold no readings and time stamps that run back (a spreadsheet's
    scratch below EuRoC's data: the stamps again in s under a column in ns, then a line of text)
    had been '7 row(s) ... left out (other packets' rows, or samples lost)', or refused at the
    text.  The recording's t is strictly increasing either way and no sample is lost: they are
    left out with a note that says the stamps run back, naming the row.  Stamps that do continue
    after the last reading are samples lost, as before; a stamp that runs back among the readings
    is still refused."""
    c = _counts(100, seed=4)
    lsb = 0.001
    head = "#timestamp [ns],a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"
    rows = [f"{1403636579758555392 + 5000000 * k}," + ",".join(f"{v * lsb:.3f}" for v in r) for k, r in enumerate(c)]
    src = tmp_path / "data.csv"
    src.write_text("\n".join([head] + rows + [",,,", "1403636580.253,,,", "1403636580.248,,,", "Step: 0.005,,,"]) + "\n")
    args = ("--units", "mps2", "--lsb", repr(lsb))
    rec, dev, err = _convert(tmp_path, capfd, src, *args)
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["sample_rate_hz"] == pytest.approx(200.0)
    assert ("the last 4 row(s) (rows 102-105) hold no readings, and their time cells do not continue the time stamps "
            f"(row 103: '1403636580.253' is not after '{1403636579758555392 + 5000000 * 99}' (row 101): the stamps "
            "run back): they are no samples, none lost; left out") in err
    assert "lost" not in err.replace("none lost", "")
    later = [f"{1403636579758555392 + 5000000 * k},,," for k in (100, 101)]
    src.write_text("\n".join([head] + rows + later) + "\n")
    rec, dev, err = _convert(tmp_path, capfd, src, *args)
    assert "2 row(s) whose readings" in err and "samples lost" in err and "run back" not in err
    rows[50] = rows[50].replace(str(1403636579758555392 + 5000000 * 50), "1403636580.0")
    src.write_text("\n".join([head] + rows) + "\n")
    err = convert_refused(tmp_path, capfd, src, *args)
    assert "row 52, column timestamp [ns]: time stamp '1403636580.0' is not after" in err.splitlines()[-1]
