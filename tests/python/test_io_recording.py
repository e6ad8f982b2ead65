"""Recording CSV: parsing rules, error messages (file, line, column), writing,
round trips, and fuzzed corruptions that must give InputError only."""

import math
import os
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st

from accelcal.errors import InputError
from accelcal.io.csvformat import INT, REPR, csv_rows
from accelcal.io.csvtable import ByteTable, CellError, ListTable, convert_column, fast_columns
from accelcal.io.recording import (
    Recording,
    read_recording,
    recording_from_arrays,
    write_recording,
)

HEADER = "t,raw_0,raw_1,raw_2"

# Properties that touch files: capped so that the CI profile (10,000 examples)
# stays within the CI time budget.
IO = settings(max_examples=min(settings().max_examples, 1000))


def write(tmp_path, text, name="rec.csv"):
    p = tmp_path / name
    p.write_bytes(text.encode() if isinstance(text, str) else text)
    return p


def expect_error(tmp_path, text, row, column, *fragments, n_channels=None):
    """Read ``text``; the one-line message names the file, the line and the column."""
    p = write(tmp_path, text)
    with pytest.raises(InputError) as ei:
        read_recording(p, n_channels)
    e = ei.value
    msg = str(e)
    assert msg.startswith(str(p) + ": "), msg
    assert "\n" not in msg
    assert e.row == row, msg
    if row is not None:
        assert f"row {row}" in msg
    assert e.column == column, msg
    if column is not None:
        assert f"column {column}:" in msg
    for frag in fragments:
        assert frag in msg, msg
    return msg


def body(*rows):
    return "\n".join([HEADER, *rows]) + "\n"


# ---------------------------------------------------------------- good files


def test_basic_read(tmp_path):
    p = write(tmp_path, "# device: seed-6ch-r60\n# operator : Ann Lee \n# taken at 12:30\n" + body("0,1,2,3", "0.5,4,5,6"))
    r = read_recording(p)
    assert r.source == str(p)
    assert r.t.tolist() == [0.0, 0.5] and r.t.dtype == np.float64
    assert r.raw.tolist() == [[1, 2, 3], [4, 5, 6]] and r.raw.dtype == np.int64
    assert r.metadata == {"device": "seed-6ch-r60", "operator": "Ann Lee"}
    assert r.n_samples == 2 and r.n_channels == 3
    assert np.isnan(r.f).all() and r.f.shape == (2, 3) and np.isnan(r.w).all() and np.isnan(r.dw).all()
    assert np.isnan(r.temp_c).all() and r.pose.tolist() == [-1, -1] and r.pose.dtype == np.int64
    assert not (r.has_f() or r.has_omega() or r.has_alpha() or r.has_temp() or r.has_pose())
    assert r.extra == {}


def test_column_order_free_and_references(tmp_path):
    text = (
        "pose,raw_1,f_z,f_y,f_x,t,note,raw_0,temp_c,w_x,w_y,w_z,dw_x,dw_y,dw_z\n"
        "3,10,9.8,0,0,0.0,hello,20,21.5,,,,1,2,3\n"
        ",11,,,,0.1, spaced ,21,nan,0.1,0.2,0.3,NaN,nan,\n"
        "-1,12,,,,0.2,,22,,,,,,,\n"
    )
    r = read_recording(write(tmp_path, text), n_channels=2)
    assert r.raw.tolist() == [[20, 10], [21, 11], [22, 12]]
    assert r.pose.tolist() == [3, -1, -1] and r.pose_labels().tolist() == [3]
    assert r.f[0].tolist() == [0, 0, 9.8] and np.isnan(r.f[1:]).all()
    assert np.isnan(r.w[0]).all() and r.w[1].tolist() == [0.1, 0.2, 0.3]
    assert r.dw[0].tolist() == [1, 2, 3] and np.isnan(r.dw[1:]).all()
    assert r.temp_c[0] == 21.5 and np.isnan(r.temp_c[1:]).all()
    assert r.extra == {"note": ["hello", " spaced ", ""]}
    assert r.has_f() and r.has_omega() and r.has_alpha() and r.has_temp() and r.has_pose()


@pytest.mark.parametrize("cell,value", [("123", 123), ("123.0", 123), (" 7 ", 7), ("+5", 5), ("-3", -3), ("1e3", 1000), ("0", 0)])
def test_raw_integer_forms_accepted(tmp_path, cell, value):
    r = read_recording(write(tmp_path, body(f"0,1,2,{cell}")))
    assert r.raw[0, 2] == value


def test_crlf_bom_and_no_final_newline(tmp_path):
    text = "\ufeff# a: b\r\n" + HEADER + "\r\n0,1,2,3\r\n1,4,5,6"
    r = read_recording(write(tmp_path, text))
    assert r.metadata == {"a": "b"} and r.raw.tolist() == [[1, 2, 3], [4, 5, 6]]


def test_trailing_blank_lines_ignored(tmp_path):
    r = read_recording(write(tmp_path, body("0,1,2,3") + "\n\n  \n"))
    assert r.n_samples == 1


def test_blank_lines_before_header(tmp_path):
    r = read_recording(write(tmp_path, "\n# k: v\n\n" + body("0,1,2,3")))
    assert r.metadata == {"k": "v"}


def test_quoted_cells(tmp_path):
    text = 't,raw_0,"note, with comma",raw_1\n0,1,"a, ""b""",2\n1,3,plain,4\n'
    r = read_recording(write(tmp_path, text))
    assert r.raw.tolist() == [[1, 2], [3, 4]]
    assert r.extra == {"note, with comma": ['a, "b"', "plain"]}


def test_n_channels_given(tmp_path):
    r = read_recording(write(tmp_path, body("0,1,2,3")), n_channels=3)
    assert r.n_channels == 3


def test_nonascii_extra(tmp_path):
    r = read_recording(write(tmp_path, "t,raw_0,où\n0,1,élan\n"))
    assert r.extra == {"où": ["élan"]}


# ---------------------------------------------------------------- bad files


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="nope.csv: cannot read the file"):
        read_recording(tmp_path / "nope.csv")


def test_empty_file(tmp_path):
    expect_error(tmp_path, "", None, None, "the file is empty")


def test_only_comments(tmp_path):
    expect_error(tmp_path, "# a: b\n# c\n\n", None, None, "no header row")


def test_header_only(tmp_path):
    expect_error(tmp_path, "# a: b\n" + HEADER + "\n", 2, None, "no data rows")


def test_header_then_blank_lines(tmp_path):
    expect_error(tmp_path, HEADER + "\n\n\n", 1, None, "no data rows")


def test_not_utf8_names_row(tmp_path):
    text = (body("0,1,2,3") + "1,4,5,6\n").encode() + b"2,\xff,5,6\n"
    expect_error(tmp_path, text, 4, None, "not valid UTF-8")


def test_duplicate_column(tmp_path):
    expect_error(tmp_path, "# c\nt,raw_0,raw_1,raw_0\n0,1,2,3\n", 2, None, "'raw_0' appears twice (columns 2 and 4)")


def test_duplicate_reference_column(tmp_path):
    expect_error(tmp_path, "t,raw_0,temp_c,temp_c\n0,1,2,3\n", 1, None, "'temp_c' appears twice (columns 3 and 4)")


def test_unknown_columns_never_an_error(tmp_path):
    # contract: unknown columns are kept or ignored; empty names (a trailing
    # comma from a spreadsheet) and repeated unknown names are ignored
    r = read_recording(write(tmp_path, "t,raw_0,,note,note,\n0,1,a,b,c,\n"))
    assert r.raw.tolist() == [[1]] and r.extra == {"note": ["b"]}


def test_no_t_column(tmp_path):
    expect_error(tmp_path, "time,raw_0\n0,1\n", 1, None, "no 't' column")


def test_no_t_column_case_hint(tmp_path):
    expect_error(tmp_path, "T,raw_0\n0,1\n", 1, None, "found 'T'")


def test_semicolon_separated_is_read(tmp_path):
    # a spreadsheet's export where the decimal mark is the comma (textinput.semicolons_to_commas)
    (tmp_path / "eu.csv").write_text("t;raw_0\n0;1\n0,5;2\n")
    rec = read_recording(tmp_path / "eu.csv")
    assert rec.t.tolist() == [0.0, 0.5] and rec.raw[:, 0].tolist() == [1, 2]


def test_no_raw_columns(tmp_path):
    expect_error(tmp_path, "t,x\n0,1\n", 1, None, "no raw_0")


def test_raw_gap(tmp_path):
    expect_error(tmp_path, "t,raw_0,raw_2\n0,1,2\n", 1, None, "raw_2 is present but raw_1 is not")


def test_raw_leading_zero(tmp_path):
    expect_error(tmp_path, "t,raw_0,raw_01\n0,1,2\n", 1, None, "'raw_01'")


def test_raw_beyond_device(tmp_path):
    text = "t," + ",".join(f"raw_{k}" for k in range(7)) + "\n0" + ",1" * 7 + "\n"
    expect_error(tmp_path, text, 1, None, "recording has raw_6 but the device has 6 channels", n_channels=6)


def test_raw_missing_for_device(tmp_path):
    expect_error(tmp_path, body("0,1,2,3"), 1, None, "no raw_3 column", n_channels=6)


def test_header_partial_vector(tmp_path):
    expect_error(tmp_path, "t,raw_0,f_x,f_z\n0,1,2,3\n", 1, None, "has f_x but no f_y")


@pytest.mark.parametrize("row,got", [("0,1,2", "got 3"), ("0,1,2,3,4", "got 5")])
def test_wrong_cell_count(tmp_path, row, got):
    expect_error(tmp_path, "# c\n" + body("0,1,2,3", row), 4, None, "expected 4 cells as in the header", got)


def test_wrong_cell_count_quoted_path(tmp_path):
    text = 't,raw_0,"q"\n0,1,a\n1,2\n'
    expect_error(tmp_path, text, 3, None, "expected 3 cells", "got 2")


def test_blank_line_inside_data(tmp_path):
    expect_error(tmp_path, body("0,1,2,3", "", "2,1,2,3"), 3, None, "got an empty line")


def test_comment_inside_data(tmp_path):
    expect_error(tmp_path, body("0,1,2,3", "# late comment"), 3, None, "comments are only allowed before the header")


@pytest.mark.parametrize("cell", ["abc", "1.5", "nan", "inf", "-inf", "", " ", "1_0", "0x10", "1,", "12a"])
def test_raw_not_integer(tmp_path, cell):
    text = "# one\n# two\n" + body("0,1,2,3", "0.1,4,5,6", f"0.2,7,{cell},9")
    if cell == "1,":
        expect_error(tmp_path, text, 6, None, "expected 4 cells")
        return
    expect_error(tmp_path, text, 6, "raw_1", "expected an integer, got")


def test_raw_message_exact(tmp_path):
    msg = expect_error(tmp_path, body("0,1,2,3", "1,2,abc,4"), 3, "raw_1")
    assert msg.endswith("rec.csv: row 3, column raw_1: expected an integer, got 'abc'")


def test_raw_overflow(tmp_path):
    expect_error(tmp_path, body("0,1,2,99999999999999999999"), 2, "raw_2", "within 64 bits")


@pytest.mark.parametrize("cell,frag", [("nan", "'nan'"), ("inf", "'inf'"), ("", "an empty cell"), ("x", "'x'")])
def test_t_not_finite(tmp_path, cell, frag):
    expect_error(tmp_path, body("0,1,2,3", f"{cell},1,2,3"), 3, "t", "expected a finite number, got " + frag)


@pytest.mark.parametrize("t2", ["1", "0.5"])
def test_t_not_increasing(tmp_path, t2):
    msg = expect_error(tmp_path, body("0,1,2,3", "1,1,2,3", f"{t2},1,2,3"), 4, "t", "strictly increasing")
    assert f"'{t2}' after '1'" in msg


@pytest.mark.parametrize("cell,frag", [("abc", "'abc'"), ("inf", "'inf'"), ("-Infinity", "'-Infinity'"), ("1e999", "'1e999'")])
def test_reference_bad(tmp_path, cell, frag):
    text = "t,raw_0,temp_c\n0,1,20\n1,2,\n2,3,nan\n3,4," + cell + "\n"
    expect_error(tmp_path, text, 5, "temp_c", "expected a finite number, or empty/nan for unknown, got " + frag)


@pytest.mark.parametrize("cell,frag", [("1.5", "'1.5'"), ("x", "'x'"), ("-2", "'-2'"), ("inf", "'inf'")])
def test_pose_bad(tmp_path, cell, frag):
    text = "t,raw_0,pose\n0,1,0\n1,2,\n2,3,nan\n3,4,-1\n4,5," + cell + "\n"
    expect_error(tmp_path, text, 6, "pose", "expected an integer pose label", frag)


def test_pose_integral_float_ok(tmp_path):
    r = read_recording(write(tmp_path, "t,raw_0,pose\n0,1,2.0\n1,2,\n"))
    assert r.pose.tolist() == [2, -1]


def test_partial_vector_row(tmp_path):
    text = "t,raw_0,f_x,f_y,f_z\n0,1,0,0,9.8\n1,2,,,\n2,3,0.1,,9.8\n"
    msg = expect_error(tmp_path, text, 4, "f_y", "f_x is given but f_y is not")
    assert "f_x, f_y, f_z" in msg


def test_nul_byte(tmp_path):
    expect_error(tmp_path, body("0,1,2,3", "1,4,5\x00,6"), 3, "raw_1", "expected an integer")


def test_earliest_error_reported(tmp_path):
    # raw_2 breaks on line 4, raw_0 on line 3: line 3 wins regardless of column order
    expect_error(tmp_path, body("0,1,2,3", "1,x,2,3", "2,1,2,y"), 3, "raw_0")


def test_same_row_leftmost_column(tmp_path):
    expect_error(tmp_path, body("0,1,2,3", "1,x,y,3"), 3, "raw_0")


def test_row_numbers_in_quoted_path_with_multiline_cell(tmp_path):
    text = 't,raw_0,note\n0,1,"two\nlines"\n1,x,plain\n'
    expect_error(tmp_path, text, 4, "raw_0", "expected an integer")


def test_bad_quoting(tmp_path):
    expect_error(tmp_path, 't,raw_0,note\n0,1,"ab"c\n', 2, None, "bad CSV quoting")
    expect_error(tmp_path, 't,raw_0,note\n0,1,x\n1,2,"open\n', 3, None, "bad CSV quoting")


# ---------------------------------------------------------------- writing


def make_rec(n=5, N=3, seed=0, refs=True):
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.001, 0.1, n))
    raw = rng.integers(-5000, 70000, (n, N))
    kw = {}
    if refs:
        f = rng.normal(size=(n, 3))
        f[1] = np.nan
        kw = dict(f=f, temp_c=np.where(np.arange(n) % 2, np.nan, 20.0 + np.arange(n)), pose=np.arange(n) % 3 - 1)
    return recording_from_arrays(t, raw, metadata={"device": "x", "note": "a b: c"}, **kw)


def test_write_layout(tmp_path):
    rec = make_rec()
    rec.extra = {"note": ["a", "b,c", 'q"', "", "x"]}
    p = tmp_path / "out.csv"
    write_recording(p, rec)
    lines = p.read_text().splitlines()
    assert lines[0] == "# device: x" and lines[1] == "# note: a b: c"
    assert lines[2] == "t,raw_0,raw_1,raw_2,f_x,f_y,f_z,temp_c,pose,note"  # no w, dw columns
    cells = lines[4].split(",")
    assert cells[4:7] == ["", "", ""]  # NaN -> empty cell
    back = read_recording(p)
    assert np.array_equal(back.t, rec.t) and np.array_equal(back.raw, rec.raw)
    assert np.allclose(back.f, rec.f, rtol=1e-8, equal_nan=True)
    assert back.extra == rec.extra and back.metadata == rec.metadata
    assert np.array_equal(back.pose, rec.pose)


def test_write_exact_round_trip(tmp_path):
    rec = make_rec(50, 6, seed=3)
    p = tmp_path / "out.csv"
    write_recording(p, rec, float_format="%.17g")
    assert read_recording(p, 6) == rec


def test_write_no_refs(tmp_path):
    rec = make_rec(refs=False)
    p = tmp_path / "out.csv"
    write_recording(p, rec)
    assert p.read_text().splitlines()[2] == "t,raw_0,raw_1,raw_2"


def test_write_is_atomic(tmp_path):
    p = tmp_path / "out.csv"
    p.write_text("old\n")
    rec = make_rec()
    rec.f[0, 0] = np.inf  # not representable in a recording
    with pytest.raises(ValueError):
        write_recording(p, rec)
    rec = make_rec()
    rec.metadata = {"bad key": "v"}
    with pytest.raises(ValueError):
        write_recording(p, rec)
    rec = make_rec()
    rec.extra = {"e": ["a\nb"] + [""] * 4}
    with pytest.raises(ValueError):
        write_recording(p, rec)
    assert p.read_text() == "old\n" and os.listdir(tmp_path) == ["out.csv"]


def test_write_bad_float_format(tmp_path):
    with pytest.raises(ValueError):
        write_recording(tmp_path / "o.csv", make_rec(), float_format="%d,%d")


# ---------------------------------------------------------------- in-memory API


def test_recording_from_arrays_checks():
    t = np.arange(4.0)
    raw = np.zeros((4, 2), dtype=int)
    r = recording_from_arrays(t, raw)
    assert r.n_channels == 2 and r.f.shape == (4, 3)
    assert recording_from_arrays(t, raw.astype(float)).raw.dtype == np.int64
    bad = [
        dict(t=t[::-1], raw=raw),
        dict(t=np.array([0, 1, np.nan, 3]), raw=raw),
        dict(t=t, raw=raw[:3]),
        dict(t=t, raw=raw[:, 0]),
        dict(t=t, raw=raw + 0.5),
        dict(t=t, raw=raw, f=np.zeros((4, 2))),
        dict(t=t, raw=raw, f=np.array([[0, 0, 1], [0, np.nan, 1], [0, 0, 1], [0, 0, 1.0]])),
        dict(t=t, raw=raw, w=np.full((4, 3), np.inf)),
        dict(t=t, raw=raw, pose=np.array([0, -2, 1, 1])),
        dict(t=t, raw=raw, temp_c=np.zeros(3)),
        dict(t=t[:0], raw=raw[:0]),
    ]
    for kw in bad:
        with pytest.raises(ValueError):
            recording_from_arrays(**kw)


def test_select():
    rec = make_rec(6)
    rec.extra = {"e": list("abcdef")}
    sub = rec.select(rec.pose >= 0)
    assert sub.n_samples == int((rec.pose >= 0).sum())
    assert sub.extra["e"] == [c for c, p in zip("abcdef", rec.pose) if p >= 0]
    assert np.array_equal(sub.raw, rec.raw[rec.pose >= 0])
    assert rec.select(np.array([0, 2])).t.tolist() == rec.t[[0, 2]].tolist()
    with pytest.raises(ValueError):
        rec.select(np.array([2, 0]))
    with pytest.raises(ValueError):
        rec.select(np.ones(3, bool))


# ---------------------------------------------------------------- properties

cell_text = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\r\n\x00\x85\u2028\u2029"), max_size=8)


@st.composite
def recordings(draw):
    n = draw(st.integers(1, 25))
    N = draw(st.integers(1, 7))
    steps = draw(st.lists(st.floats(1e-6, 1e3), min_size=n, max_size=n))
    t0 = draw(st.floats(-1e6, 1e6))
    t = t0 + np.cumsum(steps)
    assume(np.all(np.diff(t) > 0))
    raw = np.array(draw(st.lists(st.lists(st.integers(-(2**63), 2**63 - 1), min_size=N, max_size=N), min_size=n, max_size=n)))
    fin = st.floats(allow_nan=False, allow_infinity=False)

    def vec():
        if not draw(st.booleans()):
            return None
        rows = draw(st.lists(st.one_of(st.just([math.nan] * 3), st.lists(fin, min_size=3, max_size=3)), min_size=n, max_size=n))
        return np.array(rows, dtype=float)

    f, w, dw = vec(), vec(), vec()
    temp = np.array(draw(st.lists(fin | st.just(math.nan), min_size=n, max_size=n))) if draw(st.booleans()) else None
    pose = np.array(draw(st.lists(st.integers(-1, 2**40), min_size=n, max_size=n))) if draw(st.booleans()) else None
    meta = draw(st.dictionaries(st.from_regex(r"[A-Za-z_][A-Za-z0-9_.\-]{0,6}", fullmatch=True), cell_text.map(str.strip), max_size=3))
    rec = recording_from_arrays(t, raw, f=f, w=w, dw=dw, temp_c=temp, pose=pose, metadata=meta)
    names = draw(st.lists(cell_text.filter(lambda s: s.strip() == s and s and s not in ("t", "pose", "temp_c")
                                           and not s.startswith(("raw_", "f_", "w_", "dw_", "#"))), max_size=2, unique=True))
    rec.extra = {k: draw(st.lists(cell_text, min_size=n, max_size=n)) for k in names}
    return rec


@IO
@given(recordings())
def test_property_round_trip(tmp_path_factory, rec):
    p = tmp_path_factory.getbasetemp() / "test_io_recording_rt_r.csv"
    write_recording(p, rec, float_format="%.17g")
    back = read_recording(p, rec.n_channels)
    assert back == rec, (rec, back)


numeric_cell = st.one_of(
    st.integers(-(10**20), 10**20).map(str),
    st.floats(allow_nan=False).map(lambda x: "%.17g" % x),
    st.from_regex(r"[+-]?[0-9]{0,18}\.?[0-9]{0,18}([eE][+-]?[0-9]{1,3})?", fullmatch=True),
    st.floats().map(repr),
    st.floats(allow_nan=False).map(lambda x: "%.9g" % x),
    st.sampled_from(["", " ", "nan", "NaN", "+nan", "inf", "-Infinity", "1.", ".5", "+.5e-3", "1e", "--1", "1_0",
                     "0x10", " 12 ", "1.0", "-0", "1e400", "\t3", "5e-324", "2.5e+22", "9007199254740993"]),
    st.text("0123456789+-.eEnaif x_", max_size=6),
)


@pytest.mark.parametrize("kind", ["raw", "pose", "t", "ref"])
@IO
@given(cells=st.lists(numeric_cell, min_size=1, max_size=12))
def test_property_fast_and_slow_paths_agree(kind, cells):
    """The vectorised byte path and the per-cell csv path accept exactly the
    same cells and give the same numbers."""
    text = "\n".join(c + ",0" for c in cells)
    data = text.encode()
    fast = ByteTable(data, 0, len(data), 2, 2, "x")
    slow = ListTable(text + "\n", 2, 2, "x")
    results = []
    for table in (fast, slow):
        try:
            results.append(("ok", convert_column(table, 0, kind)))
        except CellError as e:
            results.append(("err", e.i, e.message))
    if results[0][0] == "ok" and results[1][0] == "ok":
        assert np.array_equal(results[0][1], results[1][1], equal_nan=True)
    else:
        assert results[0] == results[1]


@pytest.mark.parametrize("kind", ["t", "ref"])
def test_a_number_beyond_float_range_reads_as_the_slow_path_without_a_warning(kind):
    """'1e400' is inf to Python's float(), refused as no finite number; the byte path refuses it
    alike, and its cast warns of nothing."""
    text = "1e400,0\n-1e400,0"
    data = text.encode()
    results = []
    for table in (ByteTable(data, 0, len(data), 2, 2, "x"), ListTable(text + "\n", 2, 2, "x")):
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            try:
                results.append(("ok", list(convert_column(table, 0, kind))))
            except CellError as e:
                results.append(("err", e.i, e.message))
    assert results[0] == results[1]
    assert results[0][0] == "err" and "finite" in results[0][2]


def same_numbers(a, b):
    """Equal arrays, bit for bit (the sign of zero included), NaN where NaN."""
    a, b = np.asarray(a), np.asarray(b)
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.kind == "f":
        nan = np.isnan(a)
        return bool(np.array_equal(nan, np.isnan(b)) and np.array_equal(a[~nan].view(np.int64), b[~nan].view(np.int64)))
    return bool(np.array_equal(a, b))


@pytest.mark.parametrize("kind", ["raw", "pose", "t", "ref"])
@IO
@given(cells=st.lists(numeric_cell, min_size=1, max_size=12), last=st.booleans())
def test_property_fast_path_takes_only_valid_cells(kind, cells, last):
    """pyarrow's reader (fast_columns) converts a column only if the per-cell
    Python path accepts every cell, and then to the same numbers, bit for bit;
    it never decides an error itself (it hands the file back)."""
    rows = [(f"0,{c}" if last else f"{c},0") for c in cells]
    text = "\n".join(rows)
    j = 1 if last else 0
    fast = fast_columns(text.encode(), 0, len(text.encode()), 2, {"c": (j, kind)})
    try:
        slow = convert_column(ListTable(text + "\n", 2, 2, "x"), j, kind)
    except CellError:
        slow = None
    if fast is not None:
        assert slow is not None, cells
        assert same_numbers(fast["c"], slow), (cells, fast["c"], slow)


@IO
@given(recordings())
def test_property_fast_path_reads_as_the_python_path(tmp_path_factory, rec):
    """Whole files: read through pyarrow's reader and with it switched off, the same
    Recording, bit for bit."""
    p = tmp_path_factory.getbasetemp() / "test_io_recording_scan_r.csv"
    write_recording(p, rec, float_format="%.17g")
    a = read_recording(p, rec.n_channels)
    with pytest.MonkeyPatch.context() as m:
        m.setattr("accelcal.io.recording.fast_columns", lambda *args: None)
        b = read_recording(p, rec.n_channels)
    assert a == b
    for name in ("t", "raw", "f", "w", "dw", "temp_c", "pose"):
        va, vb = getattr(a, name), getattr(b, name)
        assert (va is None) == (vb is None) and (va is None or same_numbers(va, vb)), name


@IO
@given(x=st.lists(st.floats(), min_size=1, max_size=40), v=st.data(), p=st.integers(1, 17),
       chunk=st.integers(1, 50))
def test_property_csv_rows_writes_each_cell_as_python_does(x, v, p, chunk):
    """csv_rows gives repr(x), '%.<p>g' % x (NaN empty or 'nan'), str(i) and text as given,
    byte for byte, over every double (subnormals, signed zeros, the extremes) and int64, in
    chunks of any size."""
    n = len(x)
    ints = v.draw(st.lists(st.integers(-(2**63), 2**63 - 1), min_size=n, max_size=n))
    words = v.draw(st.lists(st.text("ab%s,", max_size=4), min_size=n, max_size=n))
    xf = np.array(x, dtype=float)
    fin = np.where(np.isfinite(xf), xf, 0.0)
    g = f"%.{p}g"
    text = "".join(csv_rows([fin, xf, xf, np.array(ints, dtype=np.int64), words], [REPR, g, g, INT, "%s"],
                            [None, "", None, None, None], chunk_rows=chunk))
    want = "".join(f"{a!r},{'' if math.isnan(b) else g % b},{g % b},{i},{w}\n"
                   for a, b, i, w in zip(fin.tolist(), xf.tolist(), ints, words))
    assert text == want


@IO
@given(recordings(), st.sampled_from(["%.9g", "%.17g", "%.3g", "%.4f", "%.6e"]))
def test_property_written_file_is_its_definition(tmp_path_factory, rec, fmt):
    """write_recording's text, byte for byte: the comments, the header, then per row t as
    repr(t), raw_k and pose as str, the reference columns through the float format (NaN
    as an empty cell), the extra columns quoted as CSV needs."""
    p = tmp_path_factory.getbasetemp() / "test_io_recording_text.csv"
    write_recording(p, rec, float_format=fmt)

    def quoted(v):
        return '"' + v.replace('"', '""') + '"' if any(ch in v for ch in ',"') or v != v.strip() else v

    names = ["t"] + [f"raw_{k}" for k in range(rec.n_channels)]
    cols = [list(map(repr, rec.t.tolist()))] + [list(map(str, rec.raw[:, k].tolist())) for k in range(rec.n_channels)]
    for vec, comps in (("f", ("f_x", "f_y", "f_z")), ("w", ("w_x", "w_y", "w_z")), ("dw", ("dw_x", "dw_y", "dw_z"))):
        arr = getattr(rec, vec)
        if np.isfinite(arr).any():
            names += comps
            cols += [["" if math.isnan(x) else fmt % x for x in arr[:, c].tolist()] for c in range(3)]
    if rec.has_temp():
        names.append("temp_c")
        cols.append(["" if math.isnan(x) else fmt % x for x in rec.temp_c.tolist()])
    if rec.has_pose():
        names.append("pose")
        cols.append(list(map(str, rec.pose.tolist())))
    for name, vals in rec.extra.items():
        names.append(name)
        cols.append(list(map(quoted, vals)))
    head = "".join(f"# {k}: {v.strip()}\n" for k, v in rec.metadata.items()) + ",".join(map(quoted, names)) + "\n"
    assert p.read_bytes() == (head + "".join(",".join(row) + "\n" for row in zip(*cols))).encode("utf-8")


def test_csv_under_a_comma_decimal_locale(tmp_path):
    """A program that sets LC_NUMERIC to a locale with a decimal comma (C's strtod and
    snprintf follow it; pyarrow's reader, Python's float() and '%' do not) reads and writes
    the same numbers and the same text."""
    import os
    import shutil
    import subprocess
    import sys
    src = "/usr/share/i18n/locales/de_DE"
    if shutil.which("localedef") is None or not os.path.exists(src):
        if os.environ.get("CI"):
            pytest.fail("localedef and the Debian package locales are required in CI (tools/test_all.sh installs them)")
        pytest.skip("localedef / locales not installed")
    loc = tmp_path / "loc"
    loc.mkdir()
    subprocess.run(["localedef", "-i", "de_DE", "-f", "UTF-8", str(loc / "de_DE.UTF-8")], check=True,
                   capture_output=True)
    rec = make_rec(50)
    write_recording(tmp_path / "ref.csv", rec)
    code = (
        "import locale, sys\n"
        "locale.setlocale(locale.LC_NUMERIC, 'de_DE.UTF-8')\n"
        "assert locale.localeconv()['decimal_point'] == ','\n"
        "from accelcal.io.recording import read_recording, write_recording\n"
        "r = read_recording(sys.argv[1])\n"
        "write_recording(sys.argv[2], r)\n"
    )
    env = dict(os.environ, LOCPATH=str(loc))
    r = subprocess.run([sys.executable, "-c", code, str(tmp_path / "ref.csv"), str(tmp_path / "out.csv")], env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "out.csv").read_bytes() == (tmp_path / "ref.csv").read_bytes()
    assert read_recording(tmp_path / "out.csv") == read_recording(tmp_path / "ref.csv")


def test_fast_path_hands_back_irregular_rows():
    """Quotes, a missing or an extra cell, an empty line, a lone CR, words, '2.0' as an
    integer, hexadecimal, NaN with a payload: pyarrow's reader is not used and the Python
    path decides."""
    cols = {"t": (0, "t"), "raw_0": (1, "raw")}
    for text in ["1,2\n2,3,4", "1,2\n2", '1,"2"', "nan,2", "inf,2", "1,2\n\n3,4", "1,2\r", "1\r,2", "1,2.0", "1,2\n",
                 "1,0x10", "1,0X10", "1,", ",2", "1,+2", "1,2,3"]:
        assert fast_columns(text.encode(), 0, len(text), 2, cols) is None, text
    ref = {"t": (0, "t"), "f_x": (1, "ref"), "pose": (2, "pose")}
    for text in ["1,nan(1),0", "1,NaN(),0", "1,inf,0", "1,2,-2", "1,2,x"]:
        assert fast_columns(text.encode(), 0, len(text), 3, ref) is None, text
    good = fast_columns(b"1,2\n2.5e-1,-3", 0, 13, 2, cols)
    assert good["t"].tolist() == [1.0, 0.25] and good["raw_0"].tolist() == [2, -3]
    holes = fast_columns(b"1,,\n2, 3.5 ,7\n3,nan,-1", 0, 22, 3, ref)
    assert holes["pose"].tolist() == [-1, 7, -1] and holes["pose"].dtype == np.int64
    assert np.array_equal(holes["f_x"], [np.nan, 3.5, np.nan], equal_nan=True) and holes["f_x"].flags.writeable


@IO
@given(st.data())
def test_property_corruption_gives_input_error(tmp_path_factory, data):
    rec = data.draw(recordings())
    p = tmp_path_factory.getbasetemp() / "test_io_recording_bad_r.csv"
    write_recording(p, rec)
    blob = bytearray(p.read_bytes())
    for _ in range(data.draw(st.integers(1, 3))):
        pos = data.draw(st.integers(0, max(len(blob) - 1, 0)))
        action = data.draw(st.sampled_from(["replace", "insert", "delete"]))
        junk = data.draw(st.sampled_from([b",", b"\n", b"x", b".", b"-", b"nan", b'"', b"\x00", b"\xff", b"#", b"\r", b" ", b"9", b"inf"]))
        if action == "replace" and blob:
            blob[pos : pos + 1] = junk
        elif action == "insert":
            blob[pos:pos] = junk
        elif blob:
            del blob[pos]
    p.write_bytes(bytes(blob))
    n_channels = data.draw(st.sampled_from([None, rec.n_channels]))
    try:
        back = read_recording(p, n_channels)
    except InputError as e:
        msg = str(e)
        assert msg.startswith(str(p) + ": ") and "\n" not in msg
        return
    assert isinstance(back, Recording) and back.n_samples >= 1


def test_header_with_stray_carriage_return_and_quote_is_one_line_error(tmp_path):
    # found by the corruption property: the csv module refuses a CR inside an unquoted cell
    p = tmp_path / "cr.csv"
    p.write_bytes(b't,raw\r_0,"raw_1"\n0,1,2\n')
    with pytest.raises(InputError) as ei:
        read_recording(p)
    msg = str(ei.value)
    assert msg.startswith(str(p) + ": ") and "\n" not in msg and "header" in msg


@settings(max_examples=60, deadline=None)
@given(st.integers(3, 40), st.data(), st.sampled_from(["plain", "quoted", "spaced"]))
def test_a_last_line_cut_short_is_left_out_with_a_note(tmp_path_factory, n, data, form):
    """A logger stopped mid-write leaves a last line with fewer cells and no line end after
    it: the rows before it are read as they are, and a note names the line; the same short
    line followed by a line end stays an error naming its row."""
    tmp = tmp_path_factory.mktemp("cut")
    rng = np.random.default_rng(n)
    raw = rng.integers(0, 4096, (n, 3))
    t = np.arange(n) / 100.0
    sep = " " if form == "spaced" else ","
    names = ["t", "raw_0", "raw_1", "raw_2"]
    head = sep.join(f'"{c}"' if form == "quoted" else c for c in names)
    lines = [head] + [sep.join([repr(float(a))] + [str(int(v)) for v in r]) for a, r in zip(t, raw)]
    last = lines[-1]
    cut = data.draw(st.integers(1, last.rfind(sep)))           # before the last separator: short
    body = "\n".join(lines[:-1]) + "\n" + last[:cut].rstrip()
    (tmp / "a.csv").write_text("# a log\n" + body)
    rec = read_recording(tmp / "a.csv")
    np.testing.assert_array_equal(rec.raw, raw[:-1])
    assert len(rec.notes) == 1 and f"line {n + 2}, the last, is cut short" in rec.notes[0]
    (tmp / "b.csv").write_text("# a log\n" + body + "\n")
    with pytest.raises(InputError) as ei:
        read_recording(tmp / "b.csv")
    assert ei.value.row == n + 2


def test_a_last_line_cut_in_its_last_cell_is_left_out(tmp_path):
    """'0.30,12,3,' with no line end: the writer stopped after the separator."""
    (tmp_path / "a.csv").write_text("t,raw_0,raw_1,raw_2\n0.1,1,2,3\n0.2,4,5,6\n0.3,12,3,")
    rec = read_recording(tmp_path / "a.csv")
    assert rec.n_samples == 2 and "its last cell empty" in rec.notes[0]
