#!/usr/bin/env python3
"""Speed of the recording CSV reader and writer (the README's figures).

Writes and reads 10^6 rows (``--rows``) through the package's own functions
(write_recording: Python's formatting, csvformat.csv_rows; read_recording: pyarrow's
CSV reader for plain rows, csvtable.fast_columns):

* ``full``: t, raw_0..raw_5, f_x, f_y, f_z (10 columns, every cell a number);
* ``holes``: the same and a pose column, with f empty and pose -1 on every other row
  (11 columns; empty reference cells are what most simulated and real files have).

Also times, on the same data rows, the readers that were weighed against the package's:
``numpy.loadtxt`` (its own C parser; a structured dtype, int64 for raw_k and pose,
float64 for t and f, empty cells given as ``nan`` first since loadtxt has no per-column
missing value), the package's numpy/Python path that words the errors (what every file
the fast path hands back costs), and ``pandas.read_csv`` where pandas is installed.
Every time is the best of ``--repeat`` runs in a warm process, in seconds; the import
time of each library is measured in a fresh interpreter.
Writes build/bench_csv.md and prints it.
"""
from __future__ import annotations

import argparse
import io
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
from accelcal.io.csvtable import classify_columns, convert_columns, make_table  # noqa: E402
from accelcal.io.recording import Recording, read_recording, write_recording  # noqa: E402

N_RAW = 6


def best_of(fn: Callable[[], Any], repeat: int) -> float:
    """The shortest of ``repeat`` wall-clock times of ``fn()``, in seconds."""
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def recordings(n: int) -> dict[str, Recording]:
    """The two benchmark recordings of n rows (seeded): ``full`` and ``holes``."""
    rng = np.random.default_rng(12)
    t = np.arange(n) * 0.01 + 0.123456789  # 16-17 significant digits, as repr writes them
    raw = rng.integers(-32768, 32768, size=(n, N_RAW))
    f = rng.normal(size=(n, 3)) * 9.81  # m/s^2
    moving = np.arange(n) % 2 == 0
    pose = np.where(moving, -1, (np.arange(n) // 1000) % 24)
    return {"full": Recording(t=t, raw=raw, f=f),
            "holes": Recording(t=t, raw=raw, f=np.where(moving[:, None], np.nan, f), pose=pose)}


def data_rows(path: Path) -> tuple[list[str], bytes]:
    """The header's names and the data rows (bytes) of a file written by write_recording."""
    data = path.read_bytes()
    cut = data.index(b"\n") + 1
    return data[: cut - 1].decode().split(","), data[cut:]


def loadtxt_rows(names: list[str], body: bytes) -> np.ndarray:
    """The data rows through numpy.loadtxt, empty cells first replaced by 'nan' (a pose
    cell never is empty in these files)."""
    if b",," in body or b",\n" in body:
        body = body.replace(b",,", b",nan,").replace(b",,", b",nan,").replace(b",\n", b",nan\n")
    dtype = np.dtype([(k, np.float64 if k == "t" or k.startswith("f_") else np.int64) for k in names])
    return np.loadtxt(io.BytesIO(body), delimiter=",", comments=None, quotechar=None, dtype=dtype, ndmin=1)


def python_path_rows(names: list[str], body: bytes) -> None:
    """The data rows through the package's numpy/Python path (the one that words errors)."""
    cols = classify_columns(names, None, "bench", 1)
    table = make_table(body, 0, len(body) - 1, len(names), 2, "bench")
    _, err = convert_columns(table, cols)
    assert err is None


def import_seconds(module: str) -> float | None:
    """Seconds to import ``module`` in a fresh interpreter after numpy (None: not installed)."""
    code = ("import time, numpy; t0 = time.perf_counter(); import " + module
            + "; print(time.perf_counter() - t0)")
    path = os.pathsep.join(filter(None, [str(ROOT / "python"), os.environ.get("PYTHONPATH")]))
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=path))
    return float(r.stdout) if r.returncode == 0 else None


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    lines: list[str] = []

    def emit(s: str = "") -> None:
        print(s)
        lines.append(s)

    emit(f"## Recording CSV, {args.rows:,} rows (best of {args.repeat}, warm process)")
    emit()
    emit("| file | columns | MB | write_recording [s] | read_recording [s] | numpy.loadtxt [s] "
         "| numpy/Python path [s] | pandas.read_csv [s] |")
    emit("|---|---|---|---|---|---|---|---|")
    try:
        import pandas
    except ImportError:
        pandas = None
    with tempfile.TemporaryDirectory() as tmp:
        for name, rec in recordings(args.rows).items():
            path = Path(tmp) / f"{name}.csv"
            t_write = best_of(lambda: write_recording(path, rec), args.repeat)
            back = read_recording(path)  # t and raw exactly; f as '%.9g' wrote it
            assert np.array_equal(back.t, rec.t) and np.array_equal(back.raw, rec.raw), name
            t_read = best_of(lambda: read_recording(path), args.repeat)
            names, body = data_rows(path)
            t_loadtxt = best_of(lambda: loadtxt_rows(names, body), args.repeat)
            t_python = best_of(lambda: python_path_rows(names, body), args.repeat)
            t_pandas = "-"
            if pandas is not None:
                t_pandas = f"{best_of(lambda: pandas.read_csv(io.BytesIO(body), header=None), args.repeat):.2f}"
            emit(f"| {name} | {len(names)} | {os.path.getsize(path) / 1e6:.0f} | {t_write:.2f} | {t_read:.2f} "
                 f"| {t_loadtxt:.2f} | {t_python:.2f} | {t_pandas} |")
    emit()
    emit("Import time after numpy, fresh interpreter [s]: "
         + ", ".join(f"{m} {'not installed' if s is None else f'{s:.2f}'}"
                     for m in ("accelcal.io.recording", "pyarrow.csv", "pandas") for s in [import_seconds(m)]))
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    emit()
    emit(f"(machine: {os.cpu_count()} cores, load average {load:.1f} when measured; numpy {np.__version__})")
    out = ROOT / "build" / "bench_csv.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"\nwritten {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
