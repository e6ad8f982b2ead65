"""The files users have (issue 14, item 3): gzip-compressed and whitespace-separated
recordings, readings in physical units with a stated LSB, and ``accelcal convert`` from
imu_tk's text, imucal's CSV (+ JSON pose regions) and the MPU-6050 logger's CSV."""
from __future__ import annotations

import gzip

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal.errors import AccelcalError, InputError
from accelcal.recording import read_recording, recording_from_arrays, write_recording
from accelcal.units import Scale, scale_from_options, to_counts

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

@FAST
@given(seed=st.integers(0, 10 ** 6), name=st.sampled_from(["rec.csv.gz", "rec.csv", "rec", "rec.gz.txt"]))
def test_gzip_reads_the_same(tmp_path, seed, name):
    rec = a_recording(seed=seed)
    write_recording(tmp_path / "plain.csv", rec)
    (tmp_path / name).write_bytes(gzip.compress((tmp_path / "plain.csv").read_bytes()))
    assert read_recording(tmp_path / name) == read_recording(tmp_path / "plain.csv")


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


@pytest.mark.parametrize("kw,frag", [
    (dict(units="mps2"), "--lsb VALUE"),
    (dict(lsb=0.1), "--units mps2|g"),
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
