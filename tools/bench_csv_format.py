#!/usr/bin/env python3
"""Time of writing result columns as CSV text per 10^6 cells (docs/streaming.md): t as ``repr`` and
7 float64 columns as ``'%.9g'`` (resolve's output shape), by the C formatter
(:func:`accelcal.io.csvformat.c_float_rows`, hostsrc/fmt_csv.c) and by Python's ``%`` of a row
template (the path :func:`accelcal.io.csvformat.csv_rows` takes for other formats); the best of
``--repeat`` runs over ``--rows`` rows, in chunks of CHUNK_ROWS, and whether the texts are equal."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from accelcal.io.csvformat import CHUNK_ROWS, REPR, c_float_rows  # noqa: E402


def python_rows(t: np.ndarray, v: np.ndarray) -> str:
    row = ",".join([REPR] + ["%.9g"] * v.shape[1]) + "\n"
    return "".join(map(row.__mod__, zip(t.tolist(), *[v[:, j].tolist() for j in range(v.shape[1])])))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=float, default=1e6)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    n = int(a.rows)
    rng = np.random.default_rng(1)
    t = np.arange(n) / 60.0
    v = rng.normal(0.0, 9.81, (n, 7))
    v[::97, 3] = np.nan
    cells = n * 8
    for name, fun in (("C (c_float_rows)", c_float_rows), ("Python (%)", python_rows)):
        best = float("inf")
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            text = [fun(t[s:s + CHUNK_ROWS], v[s:s + CHUNK_ROWS]) for s in range(0, n, CHUNK_ROWS)]
            best = min(best, time.perf_counter() - t0)
        print(f"{name:18s} {best / cells * 1e6:.3f} s per 10^6 cells ({n} rows x 8 columns: {best:.2f} s)")
        if name.startswith("C"):
            c_text = text
    print("texts equal:", c_text == [python_rows(t[s:s + CHUNK_ROWS], v[s:s + CHUNK_ROWS])
                                     for s in range(0, n, CHUNK_ROWS)])


if __name__ == "__main__":
    main()
