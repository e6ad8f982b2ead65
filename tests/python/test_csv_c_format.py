"""The C formatter of result columns (hostsrc/fmt_csv.c through io.csvformat.c_float_rows): the
text Python's ``repr`` and ``'%.9g' %`` write, cell for cell, over any double (subnormals, inf,
NaN of either sign, negative zero, exact and near ties of the ninth digit), and csv_rows taking it
for the result columns' formats."""
from __future__ import annotations

import math
import struct

import numpy as np
from hypothesis import given, settings, strategies as st

from accelcal.io import csvformat
from accelcal.io.csvformat import G9, REPR, c_float_rows, csv_rows
from accelcal.io.result_sink import ColumnSink


def python_text(t, v):
    row = ",".join(([REPR] if t is not None else []) + [G9] * v.shape[1]) + "\n"
    cols = ([t.tolist()] if t is not None else []) + [v[:, j].tolist() for j in range(v.shape[1])]
    return "".join(map(row.__mod__, zip(*cols)))


any_double = st.integers(0, 2 ** 64 - 1).map(lambda b: struct.unpack("<d", struct.pack("<Q", b))[0])
ties = st.integers(10 ** 8, 10 ** 9 - 1).flatmap(lambda n: st.sampled_from([
    n * 10 + 5.0, n + 0.5, n / 2 ** 1, float(math.ldexp(2 * n + 1, -1))])).flatmap(
    lambda x: st.sampled_from([x, -x, math.nextafter(x, math.inf), math.nextafter(x, -math.inf)]))
special = st.sampled_from([0.0, -0.0, math.inf, -math.inf, math.nan, -math.nan, 5e-324, -5e-324, 2.2250738585072014e-308,
                           1.7976931348623157e308, 1e-19, 1e35, 9.999999995e34, 0.0001, 0.00009999999995, 1e9,
                           999999999.5, 123456789.0, 1e-5, 1e16, 1e8])
doubles = st.one_of(any_double, ties, special, st.floats(allow_nan=True, allow_infinity=True),
                    st.floats(min_value=-1e-300, max_value=1e-300))


@settings(max_examples=400, deadline=None)
@given(st.lists(st.lists(doubles, min_size=3, max_size=3), min_size=1, max_size=40), st.booleans())
def test_c_rows_are_pythons(rows, with_t):
    assert csvformat.C_ROWS is not None             # (the extension built with hostsrc/fmt_csv.c)
    v = np.array(rows, dtype=np.float64)
    t = np.arange(v.shape[0]) / 60.0 + 1e9 if with_t else None
    assert c_float_rows(t, v) == python_text(t, v)


def test_many_doubles_at_once():
    """1.8x10^5 doubles of every exponent (random bits, scaled normals, ties of the ninth digit, powers of
    ten and their neighbours, multiples of 2^-10)."""
    rng = np.random.default_rng(37)
    n = rng.integers(10 ** 8, 10 ** 9, 20000)
    v = np.concatenate([rng.integers(0, 2 ** 64, 40000, dtype=np.uint64).view(np.float64),
                        rng.normal(0, 10, 20000) * 10.0 ** rng.integers(-25, 36, 20000),
                        (n * 10 + 5).astype(float) * 10.0 ** rng.integers(-12, 12, 20000), n + 0.5,
                        np.nextafter(10.0 ** rng.integers(-70, 120, 20000), np.inf),      # powers of ten and beside
                        np.nextafter(10.0 ** rng.integers(-70, 120, 20000), -np.inf),
                        10.0 ** rng.integers(-70, 120, 20000),
                        np.round(rng.normal(0, 10, 20000) * 1024) / 1024]).reshape(-1, 4)       # the fixed core's steps
    assert c_float_rows(np.arange(v.shape[0]) / 7.0, v) == python_text(np.arange(v.shape[0]) / 7.0, v)


def test_csv_rows_and_the_sink_take_it(tmp_path, monkeypatch):
    """csv_rows of t and '%.9g' columns is the C text (and the Python text: same bytes), in chunks."""
    rng = np.random.default_rng(3)
    t, v = np.arange(1000) / 60.0, rng.normal(0, 9.81, (1000, 4))
    v[::7, 2] = np.nan
    calls = []
    real = csvformat.c_float_rows
    monkeypatch.setattr(csvformat, "c_float_rows", lambda *a: calls.append(1) or real(*a))
    text = "".join(csv_rows([t] + [v[:, j] for j in range(4)], [REPR] + [G9] * 4, chunk_rows=300))
    assert text == python_text(t, v) and len(calls) == 4
    with open(tmp_path / "o.csv", "w") as f:
        sink = ColumnSink(f, ["t", "a", "b", "c", "d"], {"k": "v"}, False)
        sink.write([t] + [v[:, j] for j in range(4)])
    assert (tmp_path / "o.csv").read_text() == "# k: v\nt,a,b,c,d\n" + python_text(t, v)


def python_repr_lines(x):
    return ("\n".join(map(repr, x.tolist())) + "\n").encode("ascii") if x.size else b""


@settings(max_examples=300, deadline=None)
@given(st.lists(doubles, min_size=1, max_size=60))
def test_repr_lines_are_pythons(xs):
    """pyarrow's shortest digits laid out by the C: Python's repr, line for line, over any double."""
    assert csvformat.C_REPR is not None             # (the extension built with acx_repr_lines)
    x = np.array(xs, dtype=np.float64)
    assert csvformat.repr_lines(x) == python_repr_lines(x)


def test_repr_lines_over_a_million_doubles():
    """Random bit patterns (every exponent, NaN and inf included), time stamps k / 60 and k / 1000
    and their neighbours, the layout's edges (1e-4, 1e16 and their neighbours, powers of ten and two,
    integers up to 2^54): Python's repr, byte for byte."""
    rng = np.random.default_rng(7)
    bits = rng.integers(0, 2 ** 63, 400_000, dtype=np.uint64) * np.uint64(2) + rng.integers(0, 2, 400_000).astype(np.uint64)
    k = np.arange(200_000, dtype=np.float64)
    edges = np.array([10.0 ** e for e in range(-30, 31)] + [2.0 ** e for e in range(-60, 70)]
                     + [1e-4, 1e16, 9.999999999999999e15, 1e15, 0.0001, 9.99999999999e-5])
    x = np.concatenate([bits.view(np.float64), k / 60.0, k / 1000.0 + 1.7e9, np.nextafter(k / 60.0, np.inf),
                        edges, np.nextafter(edges, np.inf), np.nextafter(edges, -np.inf), -edges,
                        np.arange(2 ** 53 - 1000, 2 ** 53 + 1000, dtype=np.float64),
                        rng.integers(-10 ** 6, 10 ** 6, 100_000).astype(np.float64)])
    got = csvformat.repr_lines(x).split(b"\n")
    want = python_repr_lines(x).split(b"\n")
    bad = [i for i, (a, b) in enumerate(zip(got, want)) if a != b]
    assert len(got) == len(want) and not bad, [(x[i], got[i], want[i]) for i in bad[:5]]


def test_repr_lines_fall_back_to_python_without_the_c(monkeypatch):
    x = np.array([0.1, -0.0, 1e16, np.nan])
    monkeypatch.setattr(csvformat, "C_REPR", None)
    assert csvformat.repr_lines(x) == python_repr_lines(x)
