#!/usr/bin/env python3
"""Time and peak memory of ``accelcal resolve`` against the recording's length (docs/streaming.md).

For each length (``--lengths``, samples of the seed's 6-channel array, default device at 60 Hz:
a hand-held simulation tiled to the length, t = k / 60 s), three cases, each resolved with
``--engine fixed --calibration nominal --quiet`` in a fresh subprocess:

* ``csv->csv``, ``csv->parquet``, ``parquet->parquet`` (the Parquet input in row groups of
  io.parquet.BATCH_ROWS rows, as accelcal writes a recording: a reader holds a row group);

and, in the same run, the I/O anchor of each: pyarrow reading the input (pyarrow.csv.open_csv, or
ParquetFile.read_row_group one row group at a time: iter_batches holds on to memory batch after
batch) and writing a table of the output's shape (t and 7
float64 columns: f, dw, saturated) with pyarrow's CSV or Parquet writer.  Each figure is the
subprocess's own wall time for the work (imports excluded) and its peak RSS (VmHWM of
/proc/self/status: the process's own high-water mark, which ru_maxrss is not after a fork
from a large parent).  The input files are generated once into
``--dir`` (default a temporary directory) and deleted at the end (``--keep`` keeps them).
Writes build/bench_stream.md and prints it.
``--command rate|attitude --engine E``: instead, ``accelcal rate|attitude --engine E`` streamed and with ``--whole-file``,
wall time and peak RSS of each (a table row per run, printed).  ``--command rate-array``: the same for
``accelcal rate --omega array --engine float`` on a 12-channel tetrahedron array (:func:`spin_block` tiled,
t = k / 500 s); the streamed run fails if it fell back to the whole-file read, and with both runs their
outputs are compared byte for byte.  ``--command displacement``: the same for
``accelcal displacement`` (engine float, its offline form) on a rail recording (:func:`rail_block` tiled;
lengths in whole blocks of 10^4 samples); the streamed run fails if it fell back to the whole-file read.

``--command calibrate``: instead, ``accelcal calibrate`` on the static-pose recording below
(``--calibrate-kinds poses``; ``handheld``: the hand-held session without labels or reference) of about
N samples for each of ``--lengths``, CSV and Parquet, reduced while read and (unless ``--no-whole``)
the whole-file path; wall time and peak RSS of each (a table row per run, printed).

``--diagnose KINDS``: instead, ``accelcal diagnose --calibration nominal`` on the recordings KINDS
(``poses``: :func:`poses_recording`; ``handheld``: :func:`handheld_recording`) of about each of
``--lengths`` samples: wall time and peak RSS (a table row per run, printed); a run whose RSS passes
``--limit-mb`` (12,000 MB) is stopped.

``--calibrate-diagnose N``: instead, the wall time and peak RSS (VmHWM polled from /proc) of
``calibrate`` and ``diagnose`` on a static-pose recording of about N samples (24 jig poses of
10^6 / 24 samples each with reference f, w, dw, temp_c and pose, repeated with t shifted and the
poses relabelled).
"""
from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.csv as pa_csv
import pyarrow.parquet as pq

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
from accelcal.io.device import default_device, pendulum_device, save_device, tetrahedron_device  # noqa: E402
from accelcal.io.parquet import BATCH_ROWS  # noqa: E402
from accelcal.calibrate.still_reduce import reduce_unlabelled  # noqa: E402
from accelcal.io.recording import Recording, read_recording, write_recording  # noqa: E402
from accelcal.simulate import run_simulation  # noqa: E402

ROWS = 1 << 20

CASE = r"""
import json, sys, time
sys.path.insert(0, {python!r})
kind, src, out = sys.argv[1:4]
extra = sys.argv[4:]
if kind == "resolve":
    from accelcal.cli.main import main
    t0 = time.perf_counter()
    rc = main(["resolve", "--device", "default", "--calibration", "nominal", "--engine", "fixed", "--quiet",
               src, "-o", out])
    assert rc == 0
elif kind.startswith("convert"):
    from accelcal.cli.main import main
    if kind == "convert" and "--arrays-ok" not in extra:
        import importlib
        cs = importlib.import_module("accelcal.convert.stream")

        def arrays(*a, **k):
            raise AssertionError("the streamed convert fell back to the first pass's arrays")
        cs.first_pass = arrays
    extra = [x for x in extra if x != "--arrays-ok"]
    t0 = time.perf_counter()
    rc = main(["convert", src, "-o", out, "--quiet"] + extra + (["--whole-file"] if kind.endswith("-whole") else []))
    assert rc == 0
elif kind.startswith(("rate", "attitude", "displacement")):
    from accelcal.cli.main import main
    cmd = kind.split("-")[0]
    more = ["--omega", "array"] if cmd == "rate_array" else []
    if kind in ("displacement", "rate_array"):
        import accelcal.cli.estimator_command as ec

        def whole(*a, **k):
            raise AssertionError("the streamed command fell back to the whole-file read")
        ec.read_recording = whole
    t0 = time.perf_counter()
    rc = main([cmd.split("_")[0], "--device", {device!r}, "--calibration", "nominal", "--engine", {engine!r},
               "--quiet", src, "-o", out] + more + (["--whole-file"] if kind.endswith("-whole") else []))
    assert rc == 0
else:
    import numpy as np, pyarrow as pa, pyarrow.csv as pa_csv, pyarrow.parquet as pq
    t0 = time.perf_counter()
    names = ["t", "f_x", "f_y", "f_z", "dw_x", "dw_y", "dw_z", "saturated"]
    schema = pa.schema([(n, pa.float64()) for n in names])
    if src.endswith(".parquet"):
        pf = pq.ParquetFile(src)
        batches = (b for i in range(pf.metadata.num_row_groups)
                   for b in pf.read_row_group(i, use_threads=False).to_batches(max_chunksize={rows}))
    else:
        batches = pa_csv.open_csv(src, read_options=pa_csv.ReadOptions(block_size=1 << 24, skip_rows=1),
                                  parse_options=pa_csv.ParseOptions(),
                                  convert_options=pa_csv.ConvertOptions())
    writer = pq.ParquetWriter(out, schema) if out.endswith(".parquet") else pa_csv.CSVWriter(out, schema)
    for b in batches:
        t = b.column(0).to_numpy()
        cols = [pa.array(t)] + [pa.array(b.column(k % 6 + 1).to_numpy().astype(np.float64)) for k in range(7)]
        writer.write_table(pa.Table.from_arrays(cols, schema=schema))
    writer.close()
hwm = [l for l in open("/proc/self/status") if l.startswith("VmHWM:")][0].split()[1]
print(json.dumps({{"s": time.perf_counter() - t0, "mb": int(hwm) / 1024.0}}))
"""


def base_block(n: int = 1 << 16) -> np.ndarray:
    """n samples of the default device's raw readings: a hand-held session (rests and moves)."""
    dev = default_device()
    sim = run_simulation(dev, "handheld", seed=1, n_poses=60, hold_s=4.0, move_s=2.0, initial_rest_s=5.0)
    raw = sim.recording.raw
    return np.resize(raw, (n, raw.shape[1])) if raw.shape[0] < n else raw[:n]


def rail_block() -> np.ndarray:
    """10^4 samples of the default device's raw readings on a rail: 41 strokes of 0.5 m in 2 s between
    rests of 2 s (the linear actuator simulation, 9,960 samples) and 40 samples of its last rest again,
    so that a recording of whole blocks starts and ends at rest (``--command displacement``)."""
    dev = default_device()
    raw = run_simulation(dev, "linear_actuator", seed=1, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                         strokes=41).recording.raw
    return np.concatenate([raw, raw[-80:-40]])


def spin_block(device) -> np.ndarray:
    """2^16 samples of a 12-channel array's raw readings turned fast (``--command rate-array``): the
    independent generator's spins (tests/python/indep_model.py ``make_spin_array``, 40 turns up to
    40 rad/s from rest to rest, 83 s at 500 Hz), tiled."""
    sys.path.insert(0, str(ROOT / "tests" / "python"))
    import indep_model                                       # noqa: E402  (the tests' generator)
    raw = indep_model.make_spin_array(device, 1, n_turns=40)["recording"].raw
    return np.resize(raw, (1 << 16, raw.shape[1]))


def generate(n: int, d: Path, raw0: np.ndarray, hz: float = 60.0, name: str = "seed-6ch-r60") -> tuple[Path, Path]:
    """A CSV and a Parquet recording of n samples (t = k / hz s, raw tiled from raw0), both written by
    pyarrow (t in its shortest round-trip text)."""
    csv_path, pq_path = d / f"rec_{n}.csv", d / f"rec_{n}.parquet"
    names = ["t"] + [f"raw_{k}" for k in range(raw0.shape[1])]
    schema = pa.schema([("t", pa.float64())] + [(c, pa.int64()) for c in names[1:]],
                       metadata={b"device": name.encode()})
    with open(csv_path, "w") as fh:
        fh.write(f"# device: {name}\n" + ",".join(names) + "\n")
    pw = pq.ParquetWriter(pq_path, schema)
    with open(csv_path, "ab") as fh:
        for s in range(0, n, ROWS):
            k = np.arange(s, min(s + ROWS, n))
            raw = raw0[k % raw0.shape[0]]
            t = k / hz
            pw.write_table(pa.Table.from_arrays([pa.array(t)] + [pa.array(raw[:, j]) for j in range(raw.shape[1])], schema=schema),
                           row_group_size=BATCH_ROWS)
            buf = pa.BufferOutputStream()
            pa_csv.write_csv(pa.Table.from_arrays([pa.array(t)] + [pa.array(raw[:, j]) for j in range(raw.shape[1])], names=names),
                             buf, pa_csv.WriteOptions(include_header=False))
            fh.write(buf.getvalue().to_pybytes())
    pw.close()
    return csv_path, pq_path


def same_output(a: Path, b: Path) -> bool:
    """Two outputs the same: a CSV's bytes; a Parquet file's table and metadata (its bytes depend on
    how the rows were written: whole, or chunk by chunk)."""
    if b.suffix == ".parquet":
        ta, tb = pq.read_table(a), pq.read_table(b)
        return ta.schema == tb.schema and ta.schema.metadata == tb.schema.metadata and ta.equals(tb)
    return a.read_bytes() == b.read_bytes()


def run_case(kind: str, src: Path, out: Path, engine: str = "fixed", device: str = "default",
             extra: tuple = (), keep: bool = False) -> dict:
    code = CASE.format(python=str(ROOT / "python"), rows=ROWS, engine=engine, device=device)
    r = subprocess.run([sys.executable, "-c", code, kind, str(src), str(out), *extra], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{kind} {src} -> {out}: {r.stderr.strip()[-2000:]}")
    res = json.loads(r.stdout.strip().splitlines()[-1])
    if not keep:
        out.unlink(missing_ok=True)
    return res


def write_table(rows: list) -> str:
    """build/bench_stream.md from the rows so far; returns its text."""
    lines = ["| samples | case | input MB | resolve s | resolve peak MB | pyarrow I/O s | I/O peak MB | time / I/O |",
             "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for n, name, sizes, res, io in rows:
        size = sizes[1] if name.startswith("parquet") else sizes[0]
        lines.append(f"| {n:.0e} | {name} | {size:.0f} | {res['s']:.2f} | {res['mb']:.0f} | {io['s']:.2f} | "
                     f"{io['mb']:.0f} | {res['s'] / io['s']:.2f} |")
    text = "\n".join(lines) + "\n"
    out = ROOT / "build" / "bench_stream.md"
    out.parent.mkdir(exist_ok=True)
    out.write_text(text)
    return text


def poses_recording(n: int, path: Path, jigfree: bool = False) -> None:
    """A static-pose recording of about n samples: 24 jig poses of the default device with reference
    f, w, dw, temp_c and pose (10^6 samples; below that, 24 poses of n / 24 samples), repeated with t
    shifted and the poses relabelled.  ``jigfree``: t and raw only (its poses join by instant steps:
    the static detector takes them for a logger's blocks, which calibrate reads whole)."""
    dev = default_device()
    per = min(41667, max(1000, n // 24))
    rec = run_simulation(dev, "static_poses", seed=1, poses="24", samples_per_pose=per).recording
    k = max(1, round(n / rec.n_samples))
    span = rec.t[-1] - rec.t[0] + 2.0
    tiled = Recording(t=np.concatenate([rec.t + i * span for i in range(k)]), raw=np.tile(rec.raw, (k, 1)),
                      f=np.tile(rec.f, (k, 1)), w=np.tile(rec.w, (k, 1)), dw=np.tile(rec.dw, (k, 1)),
                      temp_c=np.tile(rec.temp_c, k),
                      pose=np.concatenate([np.where(rec.pose >= 0, rec.pose + 24 * i, -1) for i in range(k)]),
                      metadata=rec.metadata)
    if jigfree:
        tiled = Recording(t=tiled.t, raw=tiled.raw, metadata=rec.metadata)
    write_recording(path, tiled)


def peak_of(argv: list[str], limit_mb: float = 0.0) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB, VmHWM polled from /proc) of a command; with ``limit_mb``,
    the command is stopped once its RSS passes that (the time returned is then negative)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    peak = 0
    while p.poll() is None:
        try:
            with open(f"/proc/{p.pid}/status") as fh:
                peak = max(peak, next(int(x.split()[1]) for x in fh if x.startswith("VmHWM")))
        except (OSError, StopIteration):
            pass
        if limit_mb and peak > limit_mb * 1024:
            p.kill()
            p.wait()
            return -(time.perf_counter() - t0), peak / 1024.0
        time.sleep(0.2)
    if p.returncode:
        raise RuntimeError(f"{' '.join(argv)}: {p.stderr.read()[-2000:]}")
    return time.perf_counter() - t0, peak / 1024.0


def calibrate_diagnose(n: int, d: Path) -> None:
    """Peak memory of calibrate and diagnose on a static-pose recording of n samples."""
    rec, cal = d / f"poses_{n}.csv", d / f"cal_{n}.json"
    poses_recording(n, rec)
    cli = [sys.executable, "-c", "import sys; sys.path.insert(0, %r); from accelcal.cli.main import main; "
           "sys.exit(main(sys.argv[1:]))" % str(ROOT / "python")]
    for name, argv in (("calibrate", ["calibrate", "--device", "default", str(rec), "-o", str(cal)]),
                       ("diagnose", ["diagnose", "--device", "default", "--calibration", str(cal), str(rec),
                                     "--json", str(d / "diag.json"), "--quiet"])):
        s, mb = peak_of(cli + argv)
        print(f"{name} {n:.0e} samples: {s:.0f} s, peak {mb:.0f} MB", flush=True)


def handheld_recording(n: int, path: Path, jigfree: bool = False) -> None:
    """A recording with motion of about n samples: the hand-held session of the default device (a
    rest, then 40 poses held 4 s with 2 s moves between, reference f, w, dw, temp_c and pose;
    about 2.8x10^4 samples), repeated with t shifted and the poses relabelled.  ``jigfree``: the
    raw readings and t alone (no reference, no labels: what a hand-held logger writes)."""
    dev = default_device()
    rec = run_simulation(dev, "handheld", seed=1).recording
    k = max(1, round(n / rec.n_samples))
    span = rec.t[-1] - rec.t[0] + 2.0
    top = int(rec.pose.max()) + 1
    tiled = Recording(t=np.concatenate([rec.t + i * span for i in range(k)]), raw=np.tile(rec.raw, (k, 1)),
                      f=np.tile(rec.f, (k, 1)), w=np.tile(rec.w, (k, 1)), dw=np.tile(rec.dw, (k, 1)),
                      temp_c=np.tile(rec.temp_c, k),
                      pose=np.concatenate([np.where(rec.pose >= 0, rec.pose + top * i, -1) for i in range(k)]),
                      metadata=rec.metadata)
    if jigfree:
        tiled = Recording(t=tiled.t, raw=tiled.raw, metadata=rec.metadata)
    write_recording(path, tiled)


def diagnose_runs(n: int, d: Path, kinds: list[str], limit_mb: float, extra: list[str] = ()) -> None:
    """Wall time and peak RSS of ``accelcal diagnose --calibration nominal`` (the simulation's
    truth: no effect was simulated) on poses_recording(n) and handheld_recording(n); one table row
    each, printed.  A run whose RSS passes ``limit_mb`` is stopped (its row says so)."""
    cli = [sys.executable, "-c", "import sys; sys.path.insert(0, %r); from accelcal.cli.main import main; "
           "sys.exit(main(sys.argv[1:]))" % str(ROOT / "python")]
    for kind in kinds:
        rec = d / f"{kind}_{n}.csv"
        if kind == "poses":
            poses_recording(n, rec)
        else:
            handheld_recording(n, rec, jigfree=kind == "jigfree")
        s, mb = peak_of(cli + ["diagnose", "--device", "default", "--calibration", "nominal", str(rec),
                               "--json", str(d / f"diag_{kind}_{n}.json"), "--quiet", *extra], limit_mb)
        n_rows = sum(1 for _ in open(rec)) - 1
        what = f"{s:.1f}" if s >= 0 else f"stopped at {-s:.0f}"
        print(f"| {n_rows:.2e} | {kind} | {rec.stat().st_size / 1e6:.0f} | {what} | {mb:,.0f} |", flush=True)
        rec.unlink()


def calibrate_runs(n: int, d: Path, whole: bool, kinds: list[str], reduce_only: bool = False) -> None:
    """Wall time and peak RSS of ``accelcal calibrate`` on each of ``kinds`` of about n samples (CSV
    and Parquet): ``poses`` (:func:`poses_recording`: labelled, calibrate.pose_stream) and
    ``handheld`` (:func:`handheld_recording` with ``jigfree``: no labels, no reference, poses joined
    by 2 s moves: calibrate.still_reduce), reduced while read (the run fails where the reduced
    reader leaves a file to the whole-file path) and, with ``whole``, the whole-file path (the
    reduced reader disabled in that process; its JSON compared with the reduced run's byte for
    byte); with ``reduce_only``, instead, the reduction alone (``reduce_labelled`` or
    ``reduce_unlabelled``, no fit; it fails where the file is left whole); one table row each, printed."""
    alone = ("import sys; sys.path.insert(0, %r)\n"
             "from accelcal.io.device import default_device\n"
             "from accelcal.calibrate.pose_stream import reduce_labelled\n"
             "from accelcal.calibrate.still_reduce import reduce_unlabelled\n"
             "dev = default_device()\n"
             "r = reduce_labelled(sys.argv[1], dev) or reduce_unlabelled(sys.argv[1], dev)\n"
             "sys.exit(0 if r is not None else 'the reduced reader left it whole')" % str(ROOT / "python"))
    run = ("import sys; sys.path.insert(0, %r); import accelcal.cli.main as m; real = m.reduced_recordings\n"
           "def reduced(*a):\n    r = real(*a)\n    if r is None: sys.exit('the reduced reader left it whole')\n"
           "    return r\n"
           "m.reduced_recordings = (lambda *a: None) if sys.argv[1] == 'whole' else reduced\n"
           "sys.exit(m.main(sys.argv[2:]))" % str(ROOT / "python"))
    for name in kinds:
        csv_path, pq_path = d / f"{name}_{n}.csv", d / f"{name}_{n}.parquet"
        if name == "poses":
            poses_recording(n, csv_path)
        else:
            handheld_recording(n, csv_path, jigfree=True)
        write_recording(pq_path, read_recording(csv_path, 6))
        for src in (csv_path, pq_path):
            if reduce_only:
                s, mb = peak_of([sys.executable, "-c", alone, str(src)])
                print(f"| {n:.0e} | {name} {src.suffix[1:]} | {src.stat().st_size / 1e6:.0f} | reduce alone | "
                      f"{s:.1f} | {mb:.0f} |", flush=True)
                src.unlink()
                continue
            for kind in ("reduced",) + (("whole",) if whole else ()):
                s, mb = peak_of([sys.executable, "-c", run, kind, "calibrate", "--device", "default", str(src),
                                 "-o", str(d / f"cal_{kind}.json")])
                print(f"| {n:.0e} | {name} {src.suffix[1:]} | {src.stat().st_size / 1e6:.0f} | calibrate {kind} | "
                      f"{s:.1f} | {mb:.0f} |", flush=True)
            if whole and (d / "cal_reduced.json").read_bytes() != (d / "cal_whole.json").read_bytes():
                raise RuntimeError(f"{src}: the reduced and whole-file calibrations differ")
            src.unlink()


def fit_runs(repeats: list[int], d: Path) -> None:
    """Wall time and peak RSS of ``calibrate_recordings`` on the 10^5-sample hand-held session
    (:func:`handheld_recording` with ``jigfree``) reduced while read and its still stretches repeated
    ``k`` times for each of ``repeats`` (t shifted a second a pose): the jig-free fit's memory
    against the number of poses, apart from the reading; one table row each, printed."""
    src = d / "fit_poses.csv"
    handheld_recording(100_000, src, jigfree=True)
    code = ("import sys, dataclasses; sys.path.insert(0, %r)\n"
            "from accelcal.io.device import default_device\n"
            "from accelcal.calibrate import calibrate_recordings\n"
            "from accelcal.calibrate.still_reduce import reduce_unlabelled\n"
            "from accelcal.readings.static import PoseSet\n"
            "dev = default_device(); red = reduce_unlabelled(sys.argv[1], dev); k = int(sys.argv[2])\n"
            "ps = PoseSet.concat([red.poses] * k)\n"
            "ps.info = [dict(d, first=d['first'] + i, t_start=d['t_start'] + i) for i, d in enumerate(ps.info)]\n"
            "calibrate_recordings(dev, [dataclasses.replace(red, poses=ps, n_samples=red.n_samples * k)])\n"
            % str(ROOT / "python"))
    per = reduce_unlabelled(src, default_device()).poses.n_poses
    for k in repeats:
        s, mb = peak_of([sys.executable, "-c", code, str(src), str(k)])
        print(f"| {k} | {per * k} | {s:.1f} | {mb:.0f} |", flush=True)
    src.unlink()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lengths", default="1e5,1e6,1e7,1e8", help="samples, comma-separated")
    ap.add_argument("--dir", help="where the recordings are generated (default: a temporary directory)")
    ap.add_argument("--reuse", action="store_true",
                    help="take the recordings an earlier --keep run left in --dir (rec_N.csv, rec_N.parquet)")
    ap.add_argument("--keep", action="store_true", help="keep the generated recordings")
    ap.add_argument("--cases", default="csv->csv,csv->parquet,parquet->parquet",
                    help="which cases, in this order (comma-separated)")
    ap.add_argument("--calibrate-diagnose", metavar="N", type=float,
                    help="instead: peak memory of calibrate and diagnose on a static-pose recording of N samples")
    ap.add_argument("--command", choices=["resolve", "rate", "rate-array", "attitude", "displacement", "calibrate",
                                          "convert"],
                    default="resolve",
                    help="rate, attitude: `accelcal rate|attitude --engine ENGINE` streamed, and with --whole-file "
                    "(no I/O anchor); attitude on the two-triad pendulum device (io.device.pendulum_device), its "
                    "readings a pendulum simulation tiled; calibrate: `accelcal calibrate` on poses_recording(N) "
                    "(CSV and Parquet), reduced while read and (unless --no-whole) whole-file; convert: `accelcal convert` "
                    "of a 3-channel recording CSV (the first three channels), in chunks and (unless --no-whole) "
                    "--whole-file (case csv->csv only)")
    ap.add_argument("--diagnose", metavar="KINDS",
                    help="instead: `accelcal diagnose` on the recordings KINDS (comma-separated: poses, handheld, "
                    "jigfree: the hand-held session without reference or labels) "
                    "of each of --lengths samples: wall time and peak RSS")
    ap.add_argument("--limit-mb", type=float, default=12000.0, help="--diagnose: stop a run past this RSS (MB)")
    ap.add_argument("--diagnose-args", default="", help="--diagnose: more options of the command, such as "
                    "'--max-samples 0' (every sample; the default keeps windows of about 100,000)")
    ap.add_argument("--engine", choices=["float", "fixed"], default="fixed", help="rate's or attitude's engine")
    ap.add_argument("--convert-args", default="",
                    help="convert: options added to both runs, one string (e.g. '--full-scale 2': a stated scale; "
                    "docs/streaming.md). The streamed run fails where it falls back to the first pass's arrays "
                    "('--convert-args=--arrays-ok' allows it); the two runs' outputs are compared byte for byte")
    ap.add_argument("--no-whole", action="store_true", help="rate, attitude, calibrate: the streamed runs only")
    ap.add_argument("--fit-repeats", metavar="K,...", help="instead: the jig-free fit of the 10^5-sample hand-held "
                    "session's still stretches repeated K times (its memory against the number of poses)")
    ap.add_argument("--reduce-only", action="store_true", help="--command calibrate: instead, the reduction alone "
                    "(no fit), its time and peak RSS")
    ap.add_argument("--calibrate-kinds", default="poses", help="--command calibrate: the recordings (comma-separated: "
                    "poses, labelled; handheld, without labels or reference)")
    a = ap.parse_args()
    d = Path(a.dir or tempfile.mkdtemp(prefix="bench_stream_"))
    d.mkdir(parents=True, exist_ok=True)
    if a.calibrate_diagnose:
        calibrate_diagnose(int(a.calibrate_diagnose), d)
        return
    if a.fit_repeats:
        print("| repeats | poses | s | peak MB |\n| ---: | ---: | ---: | ---: |", flush=True)
        fit_runs([int(x) for x in a.fit_repeats.split(",")], d)
        return
    if a.diagnose:
        print("| samples | recording | CSV MB | s | peak MB |\n| ---: | --- | ---: | ---: | ---: |", flush=True)
        try:
            for n in (int(float(x)) for x in a.lengths.split(",")):
                diagnose_runs(n, d, a.diagnose.split(","), a.limit_mb, a.diagnose_args.split())
        finally:
            if not a.keep and not a.dir:
                shutil.rmtree(d, ignore_errors=True)
        return
    if a.command == "calibrate":
        print("| samples | input | MB | run | s | peak MB |\n| ---: | --- | ---: | --- | ---: | ---: |", flush=True)
        try:
            for n in (int(float(x)) for x in a.lengths.split(",")):
                calibrate_runs(n, d, not a.no_whole, a.calibrate_kinds.split(","), a.reduce_only)
        finally:
            if not a.keep and not a.dir:
                shutil.rmtree(d, ignore_errors=True)
        return
    device, hz, dev_name = "default", 60.0, "seed-6ch-r60"
    if a.command == "rate-array":
        tet = tetrahedron_device()
        device, hz, dev_name = str(d / "tetra.json"), float(tet.sample_rate_hz), tet.name
        save_device(tet, device)
        raw0 = spin_block(tet)
    elif a.command == "attitude":
        pend = pendulum_device()
        device = str(d / "pendulum.json")
        save_device(pend, device)
        raw = run_simulation(pend, "pendulum", seed=1, duration_s=600.0).recording.raw
        raw0 = np.resize(raw, (1 << 16, 6))
    elif a.command == "displacement":
        raw0 = rail_block()
    else:
        raw0 = base_block()
    rows = []
    try:
        for n in (int(float(x)) for x in a.lengths.split(",")):
            t0 = time.perf_counter()
            csv_path, pq_path = d / f"rec_{n}.csv", d / f"rec_{n}.parquet"
            if not (a.reuse and csv_path.exists() and pq_path.exists()):
                csv_path, pq_path = generate(n, d, raw0[:, :3] if a.command == "convert" else raw0, hz, dev_name)
            gen = time.perf_counter() - t0
            sizes = (csv_path.stat().st_size / 1e6, pq_path.stat().st_size / 1e6)
            cases = {"csv->csv": (csv_path, d / "o.csv"), "csv->parquet": (csv_path, d / "o.parquet"),
                     "parquet->parquet": (pq_path, d / "o.parquet")}
            for name in a.cases.split(","):
                src, out = cases[name]
                if a.command != "resolve":
                    command = a.command.replace("-", "_")
                    compare = a.command in ("convert", "rate-array")
                    for kind in (command,) + (() if a.no_whole else (command + "-whole",)):
                        extra = tuple(shlex.split(a.convert_args)) if a.command == "convert" else ()
                        res = run_case(kind, src, out, a.engine, device, extra, keep=compare)
                        what = (" ".join((kind,) + tuple(x for x in extra if x != "--arrays-ok"))
                                if a.command == "convert" else f"{kind} --engine {a.engine}")
                        if compare and kind == command and not a.no_whole:
                            out.rename(out.with_suffix(".stream"))       # compared with the whole-file run's
                        elif compare and kind != command:
                            same = same_output(out.with_suffix(".stream"), out)
                            what += f" (output {'the same' if same else 'DIFFERENT'})"
                            out.with_suffix(".stream").unlink()
                        out.unlink(missing_ok=True)
                        print(f"| {n:.0e} | {name} | {what} | {res['s']:.2f} | {res['mb']:.0f} |", flush=True)
                    continue
                io = run_case("anchor", src, out)
                res = run_case("resolve", src, out)
                rows.append((n, name, sizes, res, io))
                print(f"{n:>11,d} {name:<17} resolve {res['s']:8.2f} s {res['mb']:7.0f} MB | pyarrow I/O "
                      f"{io['s']:7.2f} s {io['mb']:7.0f} MB | x{res['s'] / io['s']:.2f}  (inputs {sizes[0]:.0f} / "
                      f"{sizes[1]:.0f} MB, made in {gen:.0f} s)", flush=True)
                write_table(rows)
            if not a.keep:
                csv_path.unlink()
                pq_path.unlink()
    finally:
        if not a.keep and not a.dir:
            shutil.rmtree(d, ignore_errors=True)
    if rows:
        print(write_table(rows))


if __name__ == "__main__":
    main()
