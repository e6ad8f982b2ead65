#!/usr/bin/env python3
"""``diagnose`` on a long recording: every sample against what ``--max-samples`` keeps
(:mod:`accelcal.io.thinned`: evenly spaced windows with a reference f, every k-th sample
jig-free), on recordings of the independent generator (tests/python/indep_model.py; not the
package's own simulator or effect registry): ``--source jig``, ``make_jig`` with each pose held
``--hold-s``; ``--source handheld``, ``make_handheld`` with 60 poses held 2-4 s, no labels.

For each effect of the table (and ``none``) and seed: the diagnosis of every sample
(``max_samples=0``) and of the windows kept for each ``--max-samples`` value; the verdict,
whether it is right (tools/bench_diagnose_indep.py's ``score``), the time and the samples used.

    python3 tools/bench_thinned.py [--effects a,b] [--seeds 2] [--hold-s 300] [--max-samples 50000,20000]
                                   [--ratio R] [--source jig|handheld] [--jobs 1] [-o build/bench_thinned.md]
"""
from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import sys
import time

from tqdm import tqdm

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
sys.path.insert(0, os.path.join(ROOT, "tools"))

from accelcal.diagnose import diagnose  # noqa: E402
import indep_model as im  # noqa: E402
from bench_diagnose_indep import score, truth_of  # noqa: E402

EFFECTS = ("none", "offset", "gain", "misalignment", "nonlinearity", "bias_drift", "temperature_offset",
           "saturation", "quantization", "pose_error", "time_skew", "bandwidth")


def run(job: tuple) -> dict:
    effect, seed, hold_s, budgets, ratio, source = job
    names = list(truth_of(effect))
    ratios = {nm: ratio for nm in names} if ratio else None
    if source == "handheld":
        ds = im.make_handheld(names, seed, n_poses=60, labels=False, ratio=ratios)
    else:
        ds = im.make_jig(names, seed, hold_s=hold_s, ratio=ratios)
    rec = ds["recordings"]
    row = {"effect": effect, "seed": seed, "n": sum(r.n_samples for r in rec), "mode": None,
           "device": f"{ds['device'].name} {ds['rate_hz']:.0f} Hz", "runs": []}
    for b in (0, *budgets):
        m = int(b * row["n"]) if 0 < b < 1 else int(b)
        t0 = time.perf_counter()
        res = diagnose(ds["device"], ds["cal"], rec, seed=seed, max_samples=m)
        sc = score(effect, res)
        row["mode"] = res["mode"]
        row["runs"].append({"max_samples": m, "used": res["n_samples"], "verdict": res["verdict"],
                            "right": bool(sc["right"]), "wrong": bool(sc["wrong"]), "s": time.perf_counter() - t0})
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--effects", default=",".join(EFFECTS))
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--seed0", type=int, default=0)
    ap.add_argument("--hold-s", type=float, default=300.0, help="each pose held this long (s)")
    ap.add_argument("--max-samples", default="50000,20000")
    ap.add_argument("--ratio", type=float, default=None,
                    help="each effect's RMS contribution / the per-sample noise floor (default: drawn 3-30)")
    ap.add_argument("--source", choices=("jig", "handheld"), default="jig",
                    help="jig: make_jig (labelled poses held --hold-s, a reference f: windows); handheld: "
                    "make_handheld (60 poses held 2-4 s, jig-free, no labels: every k-th sample)")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("-o", "--output", default=os.path.join(ROOT, "build", "bench_thinned.md"))
    a = ap.parse_args(argv)
    budgets = tuple(float(x) for x in a.max_samples.split(","))     # below 1: a share of the recording
    effects = [e for e in a.effects.split(",") if a.source == "jig" or e not in im.MOVING_ONLY + ("pose_error",)]
    jobs = [(e, a.seed0 + s, a.hold_s, budgets, a.ratio, a.source) for e in effects for s in range(a.seeds)]
    rows = []
    with mp.Pool(a.jobs) if a.jobs > 1 else _Serial() as pool:
        for row in tqdm(pool.imap(run, jobs), total=len(jobs), desc="cases"):
            rows.append(row)
    head = "| effect | seed | device | samples | " + " | ".join(
        "every sample" if m == 0 else _budget(m) for m in (0, *budgets)) + " |"
    lines = [head, "|" + " --- |" * (4 + 1 + len(budgets))]
    for r in rows:
        cells = [f"{u['verdict']} ({'right' if u['right'] else 'WRONG' if u['wrong'] else 'not right'}; "
                 f"{u['used']:,} used, {u['s']:.0f} s)" for u in r["runs"]]
        lines.append(f"| {r['effect']} | {r['seed']} | {r['device']} | {r['n']:,} | " + " | ".join(cells) + " |")
    agree = [sum(r["runs"][k]["verdict"] == r["runs"][0]["verdict"] for r in rows) for k in range(1, len(budgets) + 1)]
    right = [sum(r["runs"][k]["right"] for r in rows) for k in range(len(budgets) + 1)]
    lines.append("")
    lines.append(f"right: every sample {right[0]}/{len(rows)}; " + "; ".join(
        f"{_budget(m)} {right[k + 1]}/{len(rows)} (same verdict as every sample {agree[k]}/{len(rows)})"
        for k, m in enumerate(budgets)))
    text = "\n".join(lines)
    print(text)
    os.makedirs(os.path.dirname(a.output), exist_ok=True)
    with open(a.output, "w") as fh:
        fh.write(text + "\n")
    with open(os.path.splitext(a.output)[0] + ".json", "w") as fh:
        json.dump(rows, fh, indent=1)
    return 0


def _budget(m: float) -> str:
    return f"max {m:.3g} x n" if m < 1 else f"max {int(m):,}"


class _Serial:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def imap(self, f, jobs):
        return map(f, jobs)


if __name__ == "__main__":
    raise SystemExit(main())
