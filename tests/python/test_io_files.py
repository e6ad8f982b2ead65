"""The files users have (issue 14, item 3): compressed (gzip, bzip2, xz, zstd, a zip of one
file) and whitespace-separated
recordings, readings in physical units with a stated LSB, and ``accelcal convert`` from
imu_tk's text, imucal's CSV (+ JSON pose regions) and the MPU-6050 logger's CSV."""
from __future__ import annotations

import bz2
import contextlib
import gzip
import io
import json
import lzma
import re
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest
import zstandard
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from accelcal.io.device import default_triad, save_device
from accelcal.errors import AccelcalError, InputError
from accelcal.io.recording import read_recording, recording_from_arrays, write_recording
from accelcal.io.units import Scale, in_file_unit, scale_from_options
from accelcal.io.units_counts import to_counts
from cli_run import one_refusal, run

FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                         HealthCheck.too_slow])


def a_recording(n=40, channels=3, seed=0, signed=True):
    rng = np.random.default_rng(seed)
    lo = -32768 if signed else 0
    raw = rng.integers(lo, lo + 65536, size=(n, channels))
    pose = np.repeat(np.arange(n // 10), 10)[:n]
    pose[::7] = -1
    f = np.where(pose[:, None] >= 0, rng.normal(size=(n, 3)), np.nan)
    return recording_from_arrays(np.cumsum(rng.uniform(0.001, 0.02, n)), raw, f=f, pose=pose,
                                 metadata={"device": "x"})


def as_whitespace(text: str, rng) -> str:
    """The CSV text with every comma a run of blanks/tabs, lines indented at random."""
    out = []
    for line in text.splitlines():
        if line.startswith("#"):
            out.append(line)
            continue
        cells = line.split(",")
        seps = [rng.choice([" ", "  ", "\t", " \t "]) for _ in cells[1:]]
        # an empty cell (unknown f) has no whitespace form: write it as nan
        cells = [c if c else "nan" for c in cells]
        out.append(rng.choice(["", " ", "\t"]) + cells[0] + "".join(s + c for s, c in zip(seps, cells[1:]))
                   + rng.choice(["", " "]))
    return "\n".join(out) + "\n"


# ---- gzip and whitespace -------------------------------------------------------

def zipped(data: bytes, names=("rec.csv",)) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("data/", b"")                    # a directory entry is not a file
        for nm in names:
            z.writestr(nm, data)
    return buf.getvalue()


#: every compression a recording may come in (textinput.COMPRESSIONS), by the stdlib or the
#: zstandard package's own compressor
COMPRESS = {"gzip": gzip.compress, "bzip2": bz2.compress, "xz": lzma.compress,
            "zstd": lambda d: zstandard.ZstdCompressor().compress(d), "zip": zipped}


@FAST
@given(seed=st.integers(0, 10 ** 6), name=st.sampled_from(["rec.csv.gz", "rec.csv", "rec", "rec.gz.txt"]),
       form=st.sampled_from(sorted(COMPRESS)))
def test_compressed_reads_the_same(tmp_path, seed, name, form):
    rec = a_recording(seed=seed)
    write_recording(tmp_path / "plain.csv", rec)
    (tmp_path / name).write_bytes(COMPRESS[form]((tmp_path / "plain.csv").read_bytes()))
    assert read_recording(tmp_path / name) == read_recording(tmp_path / "plain.csv")


def test_zstd_frames_without_a_content_size_and_several_frames(tmp_path):
    text = b"t,raw_0\n0,1\n0.1,2\n0.2,3\n"
    (tmp_path / "plain.csv").write_bytes(text)
    streamed = io.BytesIO()
    with zstandard.ZstdCompressor().stream_writer(streamed, closefd=False) as w:
        w.write(text)                                # a stream: no content size in the frame
    two = zstandard.ZstdCompressor().compress(text[:12]) + zstandard.ZstdCompressor().compress(text[12:])
    for data in (streamed.getvalue(), two):
        (tmp_path / "r.zst").write_bytes(data)
        assert read_recording(tmp_path / "r.zst") == read_recording(tmp_path / "plain.csv")


@pytest.mark.parametrize("form", sorted(COMPRESS))
def test_a_damaged_compressed_file_is_one_line(tmp_path, form):
    whole = COMPRESS[form](b"t,raw_0\n0,1\n0.1,2\n")
    e = read_error(tmp_path, whole[:-6])
    assert f"starts as {form} but cannot be decompressed" in str(e) or (form == "zip" and "zip" in str(e)), str(e)


def test_a_zip_of_several_files_is_refused_naming_them(tmp_path):
    e = read_error(tmp_path, zipped(b"t,raw_0\n0,1\n", ("a.csv", "b.csv")))
    assert "a zip archive of 2 files (a.csv, b.csv): give one recording" in str(e), str(e)


@FAST
@given(seed=st.integers(0, 10 ** 6), compress=st.booleans())
def test_whitespace_text_reads_the_same(tmp_path, seed, compress):
    rec = a_recording(seed=seed)
    write_recording(tmp_path / "plain.csv", rec)
    text = as_whitespace((tmp_path / "plain.csv").read_text(), np.random.default_rng(seed))
    data = gzip.compress(text.encode()) if compress else text.encode()
    (tmp_path / "rec.txt").write_bytes(data)
    back = read_recording(tmp_path / "rec.txt", 3)
    assert back == read_recording(tmp_path / "plain.csv")


def as_semicolons(text: str) -> str:
    """A spreadsheet's export where the decimal mark is the comma: cells split by ';'."""
    return "\n".join(line if line.startswith("#") else line.replace(",", ";").replace(".", ",")
                     for line in text.split("\n"))


@FAST
@given(seed=st.integers(0, 10 ** 6), compress=st.booleans())
def test_semicolons_and_decimal_commas_read_the_same(tmp_path, seed, compress):
    rec = a_recording(seed=seed)
    write_recording(tmp_path / "plain.csv", rec)
    text = as_semicolons((tmp_path / "plain.csv").read_text())
    (tmp_path / "eu.csv").write_bytes(gzip.compress(text.encode()) if compress else text.encode())
    assert read_recording(tmp_path / "eu.csv") == read_recording(tmp_path / "plain.csv")


def test_semicolon_errors_name_row_and_column(tmp_path):
    e = read_error(tmp_path, "t;raw_0;raw_1\n0;1;2\n0,1;2;x\n")
    assert (e.row, e.column) == (3, "raw_1") and "'x'" in str(e), str(e)
    e = read_error(tmp_path, "# a comment; with a semicolon\nt;raw_0\n0,0;1\n0,0;2\n")
    assert (e.row, e.column) == (4, "t") and "strictly increasing" in str(e), str(e)


def read_error(tmp_path, data, **kw) -> InputError:
    p = tmp_path / "bad.txt"
    p.write_bytes(data if isinstance(data, bytes) else data.encode())
    with pytest.raises(InputError) as ei:
        read_recording(p, **kw)
    msg = str(ei.value)
    assert msg.startswith(str(p) + ": ") and "\n" not in msg
    return ei.value


@pytest.mark.parametrize("text,row,column,frag", [
    ("t raw_0 raw_1\n0 1 2\n0.1 2,3 4\n", 3, "raw_0", "a comma in whitespace-separated text"),
    ("t raw_0 raw_1\n0 1 2\n0.1 2 \"4\"\n", 3, "raw_1", "a double quote"),
    ("t\traw_0\traw_1\n0\t1\t2\n0.1\t2\n", 3, None, "expected 3 cells"),
    ("t raw_0 raw_1\n0 1 2\n0.1 2 x\n", 3, "raw_1", "expected an integer, got 'x'"),
    ("t raw_0\n0 1\n   \n0.2 3\n", 3, None, "an empty line"),
    ("# a comment\n  t  raw_0\n0 1\n0 2\n", 4, "t", "strictly increasing"),
    ("1 2 3 4\n5 6 7 8\n", 1, None, "the first line is numbers, not a header"),
])
def test_whitespace_errors_name_row_and_column(tmp_path, text, row, column, frag):
    e = read_error(tmp_path, text)
    assert (e.row, e.column) == (row, column) and frag in str(e), str(e)
    # the same, gzip-compressed: the rows are those of the decompressed text
    e = read_error(tmp_path, gzip.compress(text.encode()))
    assert (e.row, e.column) == (row, column) and frag in str(e), str(e)


def test_damaged_gzip_is_one_line(tmp_path):
    whole = gzip.compress(b"t,raw_0\n0,1\n0.1,2\n")
    assert "cannot be decompressed" in str(read_error(tmp_path, whole[:-6]))
    assert "cannot be decompressed" in str(read_error(tmp_path, whole[:10] + b"\x00" * 8 + whole[18:]))
    e = read_error(tmp_path, gzip.compress(b"t,raw_0\n0,1\n0.1,\xff\n"))
    assert e.row == 3 and "decompressed" in str(e)


def test_headerless_columns(tmp_path):
    (tmp_path / "x.txt").write_text("# c\n 0.1  33108  3.3329000e+04\n 0.2 33096 33336\n")
    rec = read_recording(tmp_path / "x.txt", columns=["t", "raw_0", "raw_1"])
    assert rec.raw.tolist() == [[33108, 33329], [33096, 33336]] and rec.line(1) == 3


# ---- physical units ------------------------------------------------------------

LSBS = [("mps2", 9.81 / 2048), ("mps2", 9.80665 / 16384), ("g", 1 / 16384), ("g", 2 * 16 / 65536),
        ("mps2", 0.0047900390625), ("g", 0.0039), ("mps2", 0.01)]


@FAST
@given(seed=st.integers(0, 10 ** 6), which=st.sampled_from(LSBS), metadata=st.booleans())
def test_physical_units_exact(tmp_path, seed, which, metadata):
    units, lsb = which
    rec = a_recording(seed=seed)
    write_recording(tmp_path / "counts.csv", rec)
    lines = (tmp_path / "counts.csv").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    rows = [ln.split(",") for ln in lines[k + 1:]]
    for r in rows:
        for j in (1, 2, 3):
            r[j] = repr(int(r[j]) * lsb)
    meta = [f"# units: {units}", f"# lsb: {lsb!r}"] if metadata else []
    (tmp_path / "phys.csv").write_text("\n".join(lines[:k] + meta + [lines[k]] + [",".join(r) for r in rows]) + "\n")
    scale = None if metadata else scale_from_options(units, lsb)
    back = read_recording(tmp_path / "phys.csv", scale=scale)
    assert np.array_equal(back.raw, rec.raw)
    assert back.metadata["source_scale"].startswith({"mps2": "m/s^2", "g": "g"}[units])
    assert "units" not in back.metadata and "lsb" not in back.metadata
    # written again, the file is counts: read back the same (no second division)
    write_recording(tmp_path / "again.csv", back)
    assert np.array_equal(read_recording(tmp_path / "again.csv").raw, rec.raw)
    # one value off by a third of an LSB: refused, that row and column named
    i, j = seed % len(rows), 1 + seed % 3
    rows[i][j] = repr((int(lines[k + 1 + i].split(",")[j]) + 1 / 3) * lsb)
    (tmp_path / "phys.csv").write_text("\n".join(lines[:k] + meta + [lines[k]] + [",".join(r) for r in rows]) + "\n")
    e = read_error(tmp_path, (tmp_path / "phys.csv").read_bytes(), scale=scale)
    assert e.row == k + len(meta) + 2 + i and e.column == f"raw_{j - 1}", str(e)
    assert "not a whole number" in str(e)


def test_full_scale_gives_the_lsb():
    s = scale_from_options("mps2", full_scale_g=16, gravity_mps2=9.81)
    assert s.lsb == 9.81 / 2048 and s.lsb_g == 1 / 2048
    assert scale_from_options("g", full_scale_g=2, bits=16).lsb == 1 / 16384
    s = scale_from_options(None, full_scale_g=2)
    assert not s.converts and s.counts_per_mps2(9.80665) == pytest.approx(16384 / 9.80665)
    assert scale_from_options() is None and scale_from_options("counts") is None
    # --lsb alone: in the unit the file states, else refused (naming --units)
    s = scale_from_options(None, lsb=0.1)
    assert not s.unit_stated and in_file_unit(s, "g", "f").lsb == 0.1
    with pytest.raises(InputError, match="--units mps2[|]g"):
        in_file_unit(s, None, "f")


@pytest.mark.parametrize("kw,frag", [
    (dict(units="mps2"), "--lsb VALUE"),
    (dict(units="mps2", lsb=0.1, full_scale_g=2), "both given"),
    (dict(units="g", lsb="nan"), "--lsb 'nan'"),
    (dict(units="g", lsb=0), "> 0"),
    (dict(units="g", full_scale_g=2, bits=40), "--bits"),
    (dict(units="kg", lsb=1), "--units 'kg'"),
])
def test_bad_options_one_line(kw, frag):
    with pytest.raises(AccelcalError) as ei:
        scale_from_options(**kw)
    assert frag in str(ei.value) and "\n" not in str(ei.value)


def test_to_counts_names_the_first_bad_value():
    vals = np.array([[0.5, 1.0], [1.5, 1.75], [2.2, 0.0]])
    with pytest.raises(InputError) as ei:
        to_counts(vals, Scale("g", 0.5, 0.5, "--lsb"), "f", lambda i, j: (10 + i, "abc"[j]))
    assert (ei.value.row, ei.value.column) == (11, "b")
    assert to_counts(vals[:1], Scale("g", 0.5, 0.5), "f", None).tolist() == [[1, 2]]
    with pytest.raises(InputError):
        to_counts(np.array([[1e300]]), Scale("g", 1e-30, 1e-30), "f", lambda i, j: (1, "x"))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(-32768, 32767), min_size=20, max_size=200), st.sampled_from(["%g", "%.6g", "%.7g", "%.6f"]))
def test_to_counts_takes_values_printed_with_few_digits(counts, fmt):
    """A logger that prints g with '%g' (six significant digits, trailing zeros dropped: -0.14209
    for -2328 / 16384 = -0.14208984375) leaves each value up to half a unit in its last place off
    its count (here <= 0.08 of a count): each is the count it rounds to.  So does one that prints
    six decimal places ('%.6f', an Axivity export: 0.000305 g for 5 counts, 4.997; had been
    refused, the tolerance taken from the significant digits alone).  The same values with a
    wrong LSB (1/12000 g) are still refused."""
    n = np.array(counts, float).reshape(-1, 1)
    # the column must show how it was printed: a column of zeros and one value 0.2229 (3652 counts
    # by '%g') could as well be '%.4f', which leaves 0.82 of a count unresolved
    assume(np.unique(n[n != 0]).size >= 5)
    printed = np.array([[float(fmt % (c / 16384.0))] for c in n[:, 0]])
    got = to_counts(printed, Scale("g", 1 / 16384, 1 / 16384, "--lsb"), "f", lambda i, j: (i + 1, "ax"))
    assert np.array_equal(got[:, 0], n[:, 0].astype(np.int64))
    off = np.abs(printed[:, 0] * 12000.0 - np.round(printed[:, 0] * 12000.0))
    if np.any(off > 0.25):   # a count of 1/12000 g that is also a whole count of 1/16384: not a test
        with pytest.raises(InputError, match="not a whole number"):
            to_counts(printed, Scale("g", 1 / 12000, 1 / 12000, "--lsb"), "f", lambda i, j: (i + 1, "ax"))


# ---- accelcal convert ----------------------------------------------------------

def convert_then_calibrate(src, tmp_path, capfd, convert_args, method):
    rec, dev, cal = tmp_path / "rec.csv", tmp_path / "dev.json", tmp_path / "cal.json"
    rc, out, err, _ = run(["convert", src, *convert_args, "-o", rec, "--device-out", dev], capfd)
    assert rc == 0, err
    assert len(out.splitlines()) == 1 and str(rec) in out
    rc, cout, cerr, _ = run(["calibrate", "--device", dev, rec, "--method", method, "-o", cal], capfd)
    assert rc == 0, cerr
    return out, err, read_recording(rec), json.loads(cal.read_text()), json.loads(dev.read_text())


def test_convert_xsens_then_jigfree(shared_data, tmp_path, capfd):
    out, err, rec, cal, dev = convert_then_calibrate(shared_data / "imu_tk_xsens" / "xsens_acc.txt.gz", tmp_path,
                                                     capfd, [], "jigfree")
    assert "imu_tk: 51175 rows, 3 channels, 100 Hz" in out and not err
    assert dev["raw_min"] == 0 and dev["raw_max"] == 65535 and dev["gravity_mps2"] == 9.81744
    # the same offsets as imu_tk's bias, near 32768 +- a few hundred counts
    assert all(abs(ch["offset_counts"] - 32768) < 1000 for ch in cal["channels"])
    assert len(cal["poses_used"]) >= 30


def test_convert_mpu6050_then_jigfree(shared_data, tmp_path, capfd):
    src = shared_data / "mpu6050_tomisuarez" / "example_data_calibration.csv.gz"
    out, err, rec, cal, dev = convert_then_calibrate(src, tmp_path, capfd, ["--full-scale", "2"], "jigfree")
    assert "mpu6050: 10245 rows, 3 channels, 100 Hz" in out
    # the README: every accelerometer value is a multiple of 4 counts (its two lowest bits always 0)
    assert err.count("\n") == 2 and "dropped gyroscope columns gx, gy, gz" in err
    assert "every count is a multiple of 4 (a 14-bit reading left-justified in 16 bits)" in err, err
    assert dev["raw_min"] == -32768 and dev["channels"][0]["zero_counts"] == 0
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(16384 / 9.80665)
    assert rec.metadata["mpu6050.fs"] == "100" and rec.raw.min() < 0
    # the data README's 6-parameter fit: offsets about +701, -359, -1834 counts
    off = [ch["offset_counts"] for ch in cal["channels"]]
    assert off == pytest.approx([701, -359, -1834], abs=40)


@pytest.mark.parametrize("which", ["ferraris", "annotated"])
def test_convert_imucal_then_full(shared_data, tmp_path, capfd, which):
    d = shared_data / "imucal"
    if which == "ferraris":
        src, args = d / "example_ferraris_session.csv", ["--units", "mps2", "--lsb", "0.0047900390625", "--rate",
                                                         "102.4", "--regions", d / "example_ferraris_session_list.json"]
    else:  # counts, poses from the part column, rows out of sample order
        src, args = d / "annotated_session.csv", ["--full-scale", "16", "--rate", "204.8"]
    out, err, rec, cal, dev = convert_then_calibrate(src, tmp_path, capfd, args + ["--stated-f", "--gravity", "9.81"],
                                                     "full")
    assert "6 poses (x_p, x_a, y_p, y_a, z_p, z_a), reference f stated" in out
    assert "dropped gyroscope columns gyr_x, gyr_y, gyr_z" in err
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(2048 / 9.81)
    assert rec.pose_labels().tolist() == list(range(6)) and np.all(np.diff(rec.t) > 0)
    # the stated f points along the axis named up: x_p's readings are large and positive on x
    for k, axis, sign in ((0, 0, 1), (1, 0, -1), (4, 2, 1)):
        sel = rec.pose == k
        assert np.all(rec.f[sel, axis] == sign * 9.81) and sign * rec.raw[sel, axis].mean() > 1800
    # the data README: gains -0.3 %, +0.2 %, +2.3 % on x, y, z (ferraris)
    gains = [np.linalg.norm(ch["sensitivity"]) * 9.81 / 2048 - 1 for ch in cal["channels"]]
    assert gains[2] == pytest.approx(0.023, abs=0.01) and abs(gains[0]) < 0.01
    if which == "ferraris":
        raw = np.loadtxt(src, delimiter=",", skiprows=1)[:, 4:7]
        assert np.array_equal(rec.raw, np.round(raw * 2048 / 9.81).astype(int))
    else:
        assert "rows put in sample order" in out


def imucal_text(rec, lsb, units="mps2"):
    """An imucal-style CSV of a recording's readings (n_samples, gyro, acc in physical units)."""
    rows = ["n_samples,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"]
    for i, r in enumerate(rec.raw.tolist()):
        rows.append(f"{i},0.5,-0.25,1.0," + ",".join(repr(v * lsb) for v in r))
    return "\n".join(rows) + "\n"


def test_convert_imucal_style_round_trip(tmp_path, capfd):
    rec = a_recording(n=60, seed=3)
    lsb = 9.81 / 2048
    (tmp_path / "s.csv").write_text(imucal_text(rec, lsb))
    regions = {"z_p": {"start": 5, "end": 20}, "x_rot": {"start": 20, "end": 30}, "y_a": {"start": 30, "end": 50}}
    (tmp_path / "r.json").write_text(json.dumps(regions))
    rc, out, err, _ = run(["convert", tmp_path / "s.csv", "--units", "mps2", "--lsb", repr(lsb), "--rate", "50",
                           "--regions", tmp_path / "r.json", "--stated-f", "-o", tmp_path / "o.csv"], capfd)
    assert rc == 0, err
    back = read_recording(tmp_path / "o.csv")
    assert np.array_equal(back.raw, rec.raw) and np.allclose(back.t, np.arange(60) / 50)
    assert back.pose[5:20].tolist() == [0] * 15 and back.pose[30:50].tolist() == [1] * 20
    assert np.all(back.pose[20:30] == -1) and np.all(np.isnan(back.f[20:30]))
    assert np.all(back.f[5:20] == [0, 0, 9.80665]) and np.all(back.f[30:50] == [0, -9.80665, 0])
    assert back.metadata["pose_names"] == "0=z_p 1=y_a"


def test_convert_csv_keeps_the_recording(tmp_path, capfd):
    rec = a_recording(seed=4)
    write_recording(tmp_path / "a.csv", rec)
    (tmp_path / "a.txt.gz").write_bytes(gzip.compress(as_whitespace((tmp_path / "a.csv").read_text(),
                                                                    np.random.default_rng(1)).encode()))
    rc, out, err, _ = run(["convert", tmp_path / "a.txt.gz", "-o", tmp_path / "o.csv"], capfd)
    assert rc == 0 and out.startswith("csv: 40 rows, 3 channels"), err
    back, rec = read_recording(tmp_path / "o.csv"), read_recording(tmp_path / "a.csv")
    assert np.array_equal(back.raw, rec.raw) and np.array_equal(back.pose, rec.pose)
    assert np.array_equal(back.f, rec.f, equal_nan=True) and np.array_equal(back.t, rec.t)
    assert back.metadata["device"] == "x" and back.metadata["source_format"] == "csv"


# ---- bad files for the new forms: one line, exit 2, nothing written ----------------

def check_rejected(rc, err, caught, out_dir, what):
    assert rc == 2, f"{what}: exit {rc}: {err!r}"
    assert one_refusal(err) and "Traceback" not in err, f"{what}: {err!r}"
    assert not caught, f"{what}: {caught}"
    assert not list(out_dir.iterdir()), f"{what}: left {list(out_dir.iterdir())}"


MPU_GOOD = "Fs,100\nLogging Type,0\nInitialization time,1\nWaiting time,3\nax,ay,az,gx,gy,gz\n" + "".join(
    f"{-12 + 4 * i},{-812 + 8 * i},{15032 - 4 * i},{i},{-i},3\n" for i in range(30))
IMUTK_GOOD = "".join(f"   {0.01 * (i + 1):.7e}   {33108 + i:.7e}   3.3329000e+04   3.6429000e+04\n" for i in range(30))


@st.composite
def bad_text(draw, good: str, kind: str):
    """A damaged copy of a good file: a cell made bad, a row cut short or lengthened, a
    non-number, a huge or fractional count, the header broken, a truncated compressed stream
    (any form of textinput.COMPRESSIONS), garbage after a compression's magic bytes."""
    lines = good.splitlines()
    first = next(i for i, ln in enumerate(lines) if re.match(r"[-\s\d]", ln) and not ln.startswith("Fs"))
    r = draw(st.integers(first, len(lines) - 1))
    sep = "," if "," in lines[r] else None
    cells = lines[r].split(sep)
    how = draw(st.sampled_from(["cell", "short", "long", "header", "gz_cut", "garbage", "empty_line"]))
    j = draw(st.integers(0, len(cells) - 1))
    if how == "cell":
        cells[j] = draw(st.sampled_from(["x", "", "1e999", "nan", "0x10", "1.5", "99999999999", "--3", "1,5" if not sep
                                         else "1 5"]))
        if kind == "imu_tk" and cells[j] == "":
            cells[j] = "?"
        lines[r] = (sep or "  ").join(cells)
    elif how == "short":
        lines[r] = (sep or " ").join(cells[:draw(st.integers(1, len(cells) - 1))])
    elif how == "long":
        lines[r] = lines[r] + (sep or " ") + "7"
    elif how == "header":
        k = first - 1 if first else 0
        lines[k] = draw(st.sampled_from(["", "Fs,", "a,b,c,d", "ax;ay;az", "t raw"])) if kind != "imu_tk" \
            else "hello there"
    elif how == "empty_line":  # inside the data (blank lines before the first row are allowed)
        lines.insert(max(r, first + 1), "")
    text = "\n".join(lines) + "\n"
    form = draw(st.sampled_from(sorted(COMPRESS)))
    if how == "gz_cut":
        return COMPRESS[form](text.encode())[:-draw(st.integers(1, 12))]
    if how == "garbage":
        magic = {"gzip": b"\x1f\x8b", "bzip2": b"BZh91AY&SY", "xz": b"\xfd7zXZ\x00", "zstd": b"\x28\xb5\x2f\xfd",
                 "zip": b"PK\x03\x04"}[form]
        return magic + draw(st.binary(min_size=0, max_size=40))
    return COMPRESS[form](text.encode()) if draw(st.booleans()) else text.encode()


@contextlib.contextmanager
def scratch():
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        (d / "out").mkdir()
        yield d, d / "out"


@pytest.mark.parametrize("kind", ["mpu", "imu_tk", "imucal"])
@FAST
@given(data=st.data())
def test_convert_bad_files(kind, data, capfd):
    good = {"mpu": MPU_GOOD, "imu_tk": IMUTK_GOOD,
            "imucal": imucal_text(a_recording(n=30, seed=2), 9.81 / 2048)}[kind]
    blob = data.draw(bad_text(good, kind), label="file")
    args = {"mpu": [], "imu_tk": [], "imucal": ["--units", "mps2", "--lsb", repr(9.81 / 2048), "--rate", "50"]}[kind]
    with scratch() as (d, out):
        (d / "in").write_bytes(blob)
        rc, _, err, caught = run(["convert", d / "in", *args, "-o", out / "o.csv", "--device-out", out / "d.json"],
                                 capfd)
        if rc == 0:  # a damaged gyroscope cell: the column is dropped unread; a time cell that still
            # reads as a later time (imu_tk's 1.5 s after 0.29 s) is a pause or lost samples, noted
            assert (out / "o.csv").exists() and (out / "d.json").exists()
            assert kind != "imu_tk" or "note: t has 1 step longer" in err, err
        else:
            check_rejected(rc, err, caught, out, repr(blob[:200]))


@FAST
@given(data=st.data())
def test_convert_bad_regions_and_options(data, capfd):
    rec = a_recording(n=30, seed=5)
    good = {"x_p": {"start": 0, "end": 10}, "z_a": {"start": 12, "end": 20}}
    how = data.draw(st.sampled_from(["json", "field", "stated", "units", "lsb", "rate", "bits", "fraction"]))
    regions, args = json.dumps(good), ["--units", "mps2", "--lsb", repr(9.81 / 2048), "--rate", "50"]
    if how == "json":
        regions = data.draw(st.sampled_from(["", "{", "[]", "{\"x_p\": 3}", "{\"x_p\": {\"start\": NaN, \"end\": 2}}",
                                             "{}", "{\"x_p\": {\"start\": 0, \"end\": 1}, \"x_p\": {}}"]))
    elif how == "field":
        key = data.draw(st.sampled_from(["start", "end"]))
        good["x_p"][key] = data.draw(st.sampled_from([-1, 1.5, "3", None, 500, 0]))
        if key == "start" and good["x_p"][key] == 0:
            good["x_p"]["end"] = 0
        regions = json.dumps(good)
    elif how == "stated":
        good["pose_a"] = {"start": 22, "end": 25}
        regions = json.dumps(good)
    elif how == "units":  # counts (stated or by default): the floats are refused
        args = data.draw(st.sampled_from([["--units", "counts"], []])) + args[4:]
    elif how == "lsb":
        args[3] = data.draw(st.sampled_from(["0", "-1", "nan", "abc", repr(9.80665 / 2048)]))
    elif how == "rate":
        args = args[:4] + data.draw(st.sampled_from([[], ["--rate", "0"], ["--rate", "inf"]]))
    elif how == "bits":
        args += ["--bits", data.draw(st.sampled_from(["1", "40", "x", "8"]))]
    else:
        args += ["--full-scale", "16"]
    with scratch() as (d, out):
        (d / "s.csv").write_text(imucal_text(rec, 9.81 / 2048))
        (d / "r.json").write_text(regions)
        rc, _, err, caught = run(["convert", d / "s.csv", *args, "--regions", d / "r.json", "--stated-f",
                                  "-o", out / "o.csv", "--device-out", out / "d.json"], capfd)
        check_rejected(rc, err, caught, out, f"{how}: {args} {regions}")


@pytest.mark.parametrize("form", ["gzip", "whitespace", "units"])
@FAST
@given(data=st.data())
def test_calibrate_refuses_bad_new_forms(form, data, capfd, tmp_path_factory):
    """calibrate on a damaged gzip / whitespace / physical-units recording: one line, exit 2."""
    rec = a_recording(n=30, seed=6, signed=False)
    base = tmp_path_factory.getbasetemp()
    dev = base / "triad.json"
    if not dev.exists():
        save_device(default_triad(), dev)
    write_recording(base / "ok.csv", rec)
    text = (base / "ok.csv").read_text()
    lines = text.splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    r = data.draw(st.integers(k + 1, len(lines) - 1))
    if form == "gzip":
        blob = gzip.compress(text.encode())
        blob = blob[:data.draw(st.integers(2, len(blob) - 1))]
    elif form == "whitespace":
        ws = as_whitespace(text, np.random.default_rng(r)).splitlines()
        ws[r] = ws[r] + data.draw(st.sampled_from([" 5", ",5", " \"q\"", "x"]))
        blob = ("\n".join(ws) + "\n").encode()
    else:
        rows = [ln.split(",") for ln in lines[k + 1:]]
        for row in rows:
            for j in (1, 2, 3):
                row[j] = repr(int(row[j]) / 16384)
        rows[r - k - 1][1 + r % 3] = data.draw(st.sampled_from(["0.1", "x", "", "1e999"]))
        blob = ("\n".join(lines[:k] + ["# units: g", "# lsb: " + repr(1 / 16384), lines[k]]
                          + [",".join(row) for row in rows]) + "\n").encode()
    with scratch() as (d, out):
        (d / "rec").write_bytes(blob)
        rc, _, err, caught = run(["calibrate", "--device", dev, d / "rec", "-o", out / "cal.json"], capfd)
        check_rejected(rc, err, caught, out, repr(blob[:200]))


def test_readme_convert_examples_run(shared_data, tmp_path, capfd, monkeypatch):
    """The "Files from other tools" page's commands (docs/files-from-other-tools.md, once the
    README's section) run as written (input names found in shared/data): convert and calibrate
    with the summary lines it quotes, then header and resolve --engine fixed (a triad header;
    signed readings for the MPU-6050)."""
    section = (Path(__file__).resolve().parents[2] / "docs" / "files-from-other-tools.md").read_text()
    blocks = re.findall(r"```sh\n(.*?)```", section, re.S)
    assert len(blocks) == 2
    monkeypatch.chdir(tmp_path)
    inputs = {p.name: p for d in ("imucal", "mpu6050_tomisuarez") for p in (shared_data / d).iterdir()}
    ran = ran_fw = 0
    for block in blocks:
        lines = block.replace("\\\n", " ").splitlines()
        for i, line in enumerate(lines):
            cmd = line.split("#")[0].split()
            if cmd[:2] in (["accelcal", "header"], ["accelcal", "resolve"]):
                rc, out, err, _ = run([str(inputs.get(a, a)) for a in cmd[1:]], capfd)
                assert rc == 0, err
                ran_fw += 1
                continue
            if cmd[:2] not in (["accelcal", "convert"], ["accelcal", "calibrate"]):
                continue
            rc, out, err, _ = run([str(inputs.get(a, a)) for a in cmd[1:]], capfd)
            assert rc == 0, err
            quoted = [ln.lstrip("# ").strip() for ln in lines[i + 1:i + 3] if ln.startswith("#")]
            said = " ".join(q for q in quoted if not q.startswith("accelcal convert: note"))
            first = said.split("...")[0].split("(")[0].strip()
            assert first and first in out, (first, out)
            ran += 1
    assert ran == 4 and ran_fw == 3
    # triad headers for signed readings (both chips give int16 counts)
    for name in ("imucal_cal.h", "mpu_cal.h"):
        text = (tmp_path / name).read_text()
        assert "ac_triad_resolve(&AC_CAL_TRIAD" in text and "const int16_t AC_CAL_TRIM[3]" in text
    rows = [ln.split(",") for ln in (tmp_path / "mpu_f.csv").read_text().splitlines() if not ln.startswith("#")]
    f = np.array([[float(v) for v in r[1:4]] for r in rows[1:3000]])          # the first 30 s at rest
    assert abs(np.linalg.norm(f.mean(axis=0)) - 9.80665) < 0.01


@pytest.mark.parametrize("shift", [0.5, 0.25, -0.3])
def test_a_column_on_a_shifted_grid_is_read_with_a_note(tmp_path, capfd, shift):
    """A phone's axis written after an offset of a fraction of an LSB (the LIS3DH x axis of
    a public recording sits on a grid shifted by half a step): every reading of that column is
    a whole count plus one fraction; it is read as counts less it, with a note; the other
    columns as they are.  A wrong LSB, whose fractions scatter, is still refused."""
    lsb = 9.80665 / 256
    rng = np.random.default_rng(3)
    c = rng.integers(-300, 300, (200, 3))
    vals = c * lsb
    vals[:, 0] += shift * lsb
    src = tmp_path / "phone.csv"
    src.write_text("acc_x,acc_y,acc_z\n" + "\n".join(",".join(f"{v:.9g}" for v in r) for r in vals) + "\n")
    rc, _, err, _ = run(["convert", src, "--units", "mps2", "--lsb", repr(lsb), "--rate", "100", "-o",
                         tmp_path / "o.csv"], capfd)
    assert rc == 0, err
    assert f"column acc_x: every reading is a whole number of LSBs plus {shift:+.3f}" in err
    np.testing.assert_array_equal(read_recording(tmp_path / "o.csv").raw, c)
    rc, _, err, _ = run(["convert", src, "--units", "mps2", "--lsb", repr(lsb * 1.37), "--rate", "100", "-o",
                         tmp_path / "p.csv"], capfd)
    assert rc == 2 and "not a whole number" in err


def test_a_column_of_a_few_values_is_not_taken_for_a_shifted_grid():
    """One or two values sit on a grid of any shift: they are refused as not whole, as before."""
    from accelcal.io.units import Scale
    from accelcal.io.units_counts import to_counts
    vals = np.tile([[3.5, 1.0, 2.0], [7.5, 1.0, 2.0]], (20, 1)) * 0.01
    with pytest.raises(InputError, match="not a whole number"):
        to_counts(vals, Scale("g", 0.01, 0.01, "--lsb"), "f", lambda i, j: (i + 1, "c"), notes=[])


def test_an_lsb_comment_without_a_units_comment_is_refused(tmp_path):
    """'# lsb: 0.001' with no '# units:' states no unit for the readings it divides (an option's bare
    --lsb takes the unit the file states; a comment has none to take).  It had become counts without
    a word when --lsb alone learnt to take the file's unit."""
    path = tmp_path / "r.csv"
    path.write_text("# lsb: 0.001\nt,raw_0,raw_1,raw_2\n0,1,2,3\n0.01,1,2,3\n")
    with pytest.raises(InputError, match=r"row 1: '# lsb:' 0.001: state the unit of the readings it divides with "
                                         r"'# units:' mps2\|g"):
        read_recording(path, 3)
