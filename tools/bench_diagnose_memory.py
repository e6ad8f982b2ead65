"""Where ``diagnose``'s memory goes: the traced numpy memory (tracemalloc) at the entry of each
phase of :func:`accelcal.diagnose.diagnose`, its peak inside and what it keeps, and the same for
each effect's fit (the first time it is fitted).

    python3 tools/bench_diagnose_memory.py REC.csv [--device default] [--calibration nominal]

The recording is read as ``accelcal diagnose`` reads it (``read_recording``, in chunks for a plain
CSV).  MiB of traced memory (the interpreter and the imports are not traced); divide by the
samples for bytes a sample.  tracemalloc slows the run about 2x.
"""
from __future__ import annotations

import argparse
import functools
import sys
import tracemalloc
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))
from accelcal.diagnose import result as R  # noqa: E402
from accelcal.effects import EFFECTS  # noqa: E402
from accelcal.io.calibration import load_calibration  # noqa: E402
from accelcal.io.device import default_device, load_device  # noqa: E402
from accelcal.io.recording import read_recording  # noqa: E402

MB = float(1 << 20)
PHASES = ("prepare", "setup_rows", "find_outliers", "run_candidates", "shift_contest", "next_point",
          "simpler_model", "joint_fit", "relinearise", "heldout_path", "prediction_twins", "leftover",
          "settling_ringing", "where_breakdown", "pose_mean_gap", "time_unmodelled")


STACK: list[list[int]] = [[0]]     # the peak seen in each open phase (the outermost: the whole run)


def traced(label: str, f, once: set | None = None):
    """f, printing the traced MiB at its entry, its peak inside and what it keeps (the peak of a
    phase includes those of the phases inside it: tracemalloc has one peak, reset at each entry)."""
    @functools.wraps(f)
    def g(*a, **kw):
        cur0, pk0 = tracemalloc.get_traced_memory()
        for fr in STACK:
            fr[0] = max(fr[0], pk0)
        tracemalloc.reset_peak()
        STACK.append([cur0])
        try:
            out = f(*a, **kw)
        finally:
            cur, pk = tracemalloc.get_traced_memory()
            top = max(STACK.pop()[0], pk)
            for fr in STACK:
                fr[0] = max(fr[0], top)
        if once is None or label not in once:
            print(f"| {label} | {cur0 / MB:.1f} | {(top - cur0) / MB:+.1f} | {(cur - cur0) / MB:+.1f} |", flush=True)
            if once is not None:
                once.add(label)
        return out
    return g


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recording")
    ap.add_argument("--device", default="default")
    ap.add_argument("--calibration", default="nominal")
    a = ap.parse_args()
    dev = default_device() if a.device == "default" else load_device(a.device)
    tracemalloc.start()
    for nm in PHASES:
        setattr(R, nm, traced(nm, getattr(R, nm)))
    seen: set = set()
    for nm, c in EFFECTS.items():
        c.cv = traced("fit: " + nm, c.cv, seen)
    print("| phase | MiB at entry | peak inside | kept |\n| --- | ---: | ---: | ---: |")
    rec = read_recording(a.recording, dev.n_channels)
    cur, pk = tracemalloc.get_traced_memory()
    STACK[0][0] = pk
    print(f"| read_recording ({rec.n_samples} samples) | 0 | {pk / MB:+.1f} | {cur / MB:+.1f} |", flush=True)
    res = R.diagnose(dev, load_calibration(a.calibration, dev), [rec])
    top = max(STACK[0][0], tracemalloc.get_traced_memory()[1])
    print(f"verdict {res['verdict']}; peak of the whole run {top / MB:.1f} MiB ({top / rec.n_samples:.0f} bytes a "
          "sample)")

if __name__ == "__main__":
    main()
