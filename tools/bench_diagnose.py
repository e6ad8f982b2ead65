#!/usr/bin/env python3
"""The check on withheld effects (issue 4): does the diagnosis name the effect that is in
the data but not in the model, and does it say how much of the gap it explains?

For each effect of the registry (and for none), many datasets are simulated, each with
a random device, a random true calibration (the seed's Table 1 spreads), a random noise
level, a random motion and a random effect magnitude; the model is the true calibration
(so the effect is the only thing the model lacks); the diagnosis runs on the recording.

Dataset = one simulation of a trajectory laid out as: a jig part (static poses with pose
labels and the stated f) followed, after a 1 s gap, by a motion (rate table, pendulum,
random 6-DOF, hand-held, lane change, linear actuator), given as one recording (50 %) or as
two (jig, motion: 20 %); the motion alone (15 %); the jig alone (15 %, not for the effects
that show only while moving).  The parts keep the motions' exact evaluators (the jig held
in each pose around its samples), so time shifts are exact.
Temperature: a sine over the recording for temperature effects, else constant 25 degC in
70 % of the datasets and a sine in 30 % (so the temperature candidates also face data
without the effect).  Devices: the seed's 6-channel r = 60 mm prototype, a 16-bit triad,
the two-triad pendulum device, random arrays of 3 or 4 rotated triads.

Magnitude: a target contribution ratio rho, log-uniform in [RHO_LO, RHO_HI] (stratified: the
k-th dataset of an effect draws from the k-th of equal slices); the effect's
size parameter is scaled to it from a pilot simulation (effects that are not linear in
their size are drawn directly).  Definitions (on all samples):

* noise floor = sqrt(mean_i(sigma_i^2 + 1/12)) counts, sigma_i the simulated noise;
* contribution = RMS(pred_true - pred_base), pred_base = the diagnosis' model (true
  calibration driven by the recorded reference), pred_true = the noise-free readings with
  the effect (the simulator's clean counts; for saturation/quantization the registry's
  clip/rounding of them; for pose_error the clean counts from the true f);
  rho = contribution / noise floor;
* true shrink = 1 - RMS(raw - pred_true) / RMS(raw - pred_base).

Reported: confusion matrix (truth rows, verdict columns), top-1 accuracy (all, rho >= 3),
false-positive rate on none, |estimated - true shrink| (the true effect's entry, alone),
parameter errors against the truth, the time to diagnose 100,000 samples x 12
channels with every candidate, and the diagnosis of the real Xsens recording (jig-free) with
three models: its own jig-free calibration, a calibration from the first half applied to the
second, and the nominal calibration.

Usage: python tools/bench_diagnose.py [--per-effect N] [--per-none M] [--quick] [--seed S] [--jobs J]
       [--effects a,b,...] [--no-timing] [--rows ROWS.json] [-o OUT.md]
Writes build/bench_diagnose.md.
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np
from tqdm import tqdm

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))

sys.path.insert(0, os.path.join(ROOT, "tests", "python"))

from accelcal.calibrate import calibrate_recordings  # noqa: E402
from accelcal.io.calibration import Calibration  # noqa: E402
from accelcal.diagnose import diagnose  # noqa: E402
from accelcal.convert.xsens import load_xsens  # noqa: E402
from diag_datasets import (LABELS, MOTIONS, RHO_HI, RHO_LO, Device, concat, drift_error, make_dataset,  # noqa: E402
                           param_error, random_array, run_simulation, seed_prototype_truth, temperature_profile)
from shared_data import XSENS_ACC, shared_file  # noqa: E402

# ------------------------------------------------------------------ running
def run_one(args):
    effect, seed, rho = args
    ds = make_dataset(effect, seed, rho)
    t0 = time.perf_counter()
    res = diagnose(ds["device"], ds["cal"], ds["recordings"], seed=seed)
    dt = time.perf_counter() - t0
    entry = next((e for e in res["effects"] if e["name"] == effect), None)
    est_shrink = entry["alone"]["shrink"] if entry else 0.0
    perr = None
    if entry and ds["truth"] is not None:
        perr = (drift_error(entry["params"], ds["truth"], ds["recording"].t) if effect == "bias_drift"
                else param_error(effect, entry["params"], ds["truth"], entry["params_sigma"]))
    if effect == "none":
        est_shrink = res["effects"][0]["shrink"] if res["verdict"] != "none" else 0.0
    return {"effect": effect, "seed": seed, "verdict": res["verdict"], "rho": ds["rho"],
            "true_shrink": ds["true_shrink"] if effect != "none" else 0.0,
            "est_shrink": est_shrink,
            "param_err": perr, "time_s": dt, "n": res["n_samples"], "N": res["n_channels"],
            "chosen": res["model"]["effects"], "device": ds["device"].name,
            "motion": f"{ds['layout']}: {ds['motion'].get('jig')} + {ds['motion'].get('motion')}",
            "skipped": [s["name"] for s in res["skipped"]], "spec": ds["spec"]}


def timing_run(n: int = 100_000, seed: int = 1, effects=("time_skew:tau=0.002",)) -> dict:
    """Diagnose n samples x 12 channels with every candidate active (a jig part with 26 poses, a
    random 6-DOF motion, a temperature sine), the given effects in the data."""
    rng = np.random.default_rng(seed)
    dev = random_array(rng, 4)
    dev = Device(name=dev.name, sample_rate_hz=100.0, gravity_mps2=dev.gravity_mps2, raw_min=0, raw_max=65535,
                 positions=dev.positions, axes=dev.axes, counts_per_mps2=dev.counts_per_mps2,
                 zero_counts=dev.zero_counts, noise_mps2=2.0 / float(dev.counts_per_mps2[0]))
    cal = seed_prototype_truth(dev, rng)
    jig = MOTIONS["static_poses"](dev, rng, poses="26", samples_per_pose=200)
    mv = MOTIONS["random_6dof"](dev, rng, duration_s=(n - jig.n_samples) / 100.0 - 1.0, bandwidth_hz=1.5)
    tr = concat([jig, mv], 1.0, dev.gravity_mps2)
    tr.temp_c = temperature_profile(tr.t, "sine", temp_c=25.0, temp_amplitude_c=10.0, temp_period_s=300.0)
    sim = run_simulation(dev, tr, seed=seed, calibration=cal, effects=list(effects))
    t0 = time.perf_counter()
    res = diagnose(dev, cal, [sim.recording], seed=seed)
    dt = time.perf_counter() - t0
    return {"n": res["n_samples"], "N": res["n_channels"], "time_s": dt, "verdict": res["verdict"],
            "skipped": [s["name"] for s in res["skipped"]], "steps": res["model"]["effects"]}


def _q(x, p):
    return f"{np.percentile(x, p):.3f}" if len(x) else "-"


def _pct(m):
    return f"{100 * np.mean(m):.1f} %" if np.size(m) else "-"




def xsens_section() -> list[str]:
    """The diagnosis of the real Xsens recording (no reference: its static poses, |f| = g)."""
    xsens = shared_file(*XSENS_ACC)
    if xsens is None:
        return ["", "### Real Xsens recording", "", "(not found: ../shared/data/" + "/".join(XSENS_ACC) + ")"]
    dev, rec = load_xsens(xsens)
    half = rec.t < rec.t[0] + 0.5 * (rec.t[-1] - rec.t[0])
    r1, r2 = rec.select(half), rec.select(~half)
    r1.source, r2.source = "xsens first half", "xsens second half"
    runs = [("jig-free calibration of the whole recording", calibrate_recordings(dev, [rec], "jigfree"), rec),
            ("calibration from the first half, diagnosis of the second", calibrate_recordings(dev, [r1], "jigfree"),
             r2),
            ("the nominal calibration (zero 32768, 410.1 counts per m/s^2)", Calibration.nominal(dev), rec)]
    out = ["", "### Real Xsens recording (imu_tk; jig-free: the static poses with |f| = g are the reference)", "",
           "| model | verdict | chosen effects | held-out RMS before -> after (counts) | gap / noise floor | "
           "pose means / noise | next candidates (shrink %, z) | time |",
           "| --- | --- | --- | --- | ---: | ---: | --- | ---: |"]
    notes = []
    for title, cal, r in runs:
        t0 = time.perf_counter()
        res = diagnose(dev, cal, [r])
        dt = time.perf_counter() - t0
        g, m = res["gap"], res["model"]
        chosen = ", ".join(f"{e['name']} ({e['summary']})" for e in res["effects"] if e["selected"]) or "-"
        nxt = ", ".join(f"{e['name']} ({100 * e['shrink']:.2f}, {e['score']['z']:.3g})"
                        for e in res["effects"] if not e["selected"])[:200]
        out.append(f"| {title} | **{res['verdict']}** | {chosen} | {m['heldout_rms_before']:.3f} -> "
                   f"{m['heldout_rms_after']:.3f} | {g['ratio_to_noise']:.3f} | {g.get('pose_mean_ratio', 0):.2f} | "
                   f"{nxt} | {dt:.1f} s |")
        if not notes:
            notes = [n for n in res["notes"] if "residue" in n]
            bands = res["where"]["frequency_bands"]
            notes.append("residual by frequency band (counts; white noise at the floor in brackets): " + ", ".join(
                f"{b['label']} {b['rms_counts']:.2f} ({b['white_noise_rms_counts']:.2f})" if b["rms_counts"] is not None
                else f"{b['label']} not measurable" for b in bands))
            notes.append(f"noise floor {g['noise_floor_counts']:.2f} counts ({g['noise_method']}); "
                         f"{res['recordings'][0]['n_used']} of {res['recordings'][0]['n_samples']} samples in "
                         f"{g.get('n_poses')} static poses")
    out += [""] + [f"- {n}" for n in notes]
    return out


VERDICTS = tuple(LABELS) + ("unexplained",)     # a verdict may also say that no effect explains the gap


def summarise(rows: list[dict]) -> str:
    lines = []
    idx = {n: i for i, n in enumerate(LABELS)}
    vdx = {n: i for i, n in enumerate(VERDICTS)}

    def conf(sub):
        M = np.zeros((len(LABELS), len(VERDICTS)), int)
        for r in sub:
            M[idx[r["effect"]], vdx[r["verdict"]]] += 1
        return M

    abbrev = (("temperature_", "temp_"), ("position_error", "position"), ("misalignment", "misalign"),
              ("quantization", "quantiz"), ("nonlinearity", "nonlin"))
    short = {}
    for n in VERDICTS:
        short[n] = n
        for a, b in abbrev:
            short[n] = short[n].replace(a, b)

    def table(M, title):
        out = [f"### {title}", "", "| truth \\ verdict | " + " | ".join(short[n] for n in VERDICTS) + " |",
               "| --- | " + " | ".join("---" for _ in VERDICTS) + " |"]
        for i, n in enumerate(LABELS):
            if M[i].sum() == 0:
                continue
            out.append(f"| {n} | " + " | ".join(str(v) if v else "." for v in M[i]) + " |")
        return out

    strong = [r for r in rows if r["effect"] == "none" or r["rho"] >= 3.0]
    lines += table(conf(strong), "Confusion matrix, contribution >= 3x noise floor (and every none)") + [""]
    lines += table(conf(rows), "Confusion matrix, all datasets") + [""]
    lines += ["### Per effect", "",
              "| effect | datasets | top-1 all | datasets rho>=3 | top-1 rho>=3 | top-1 1<=rho<3 | top-1 rho<1 | "
              "|shrink err| median (rho>=3) | |shrink err| 95 % (rho>=3) | within 0.1 (rho>=3) | "
              "param rel err median (rho>=3) |",
              "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    tot_strong = tot_ok = 0
    all_err = []
    for n in LABELS:
        sub = [r for r in rows if r["effect"] == n]
        if not sub:
            continue
        s3 = [r for r in sub if n == "none" or r["rho"] >= 3]
        mid = [r for r in sub if 1 <= r["rho"] < 3]
        low = [r for r in sub if r["rho"] < 1]

        def acc(x):
            return f"{100 * np.mean([r['verdict'] == r['effect'] for r in x]):.0f} %" if x else "-"

        errs = [abs(r["est_shrink"] - r["true_shrink"]) for r in s3]
        all_err += errs if n != "none" else []
        pe = [r["param_err"] for r in s3 if r["param_err"] is not None]
        tot_strong += len(s3) if n != "none" else 0
        tot_ok += sum(r["verdict"] == n for r in s3) if n != "none" else 0
        lines.append(f"| {n} | {len(sub)} | {acc(sub)} | {len(s3)} | {acc(s3)} | {acc(mid) if n != 'none' else '-'} | "
                     f"{acc(low) if n != 'none' else '-'} | "
                     f"{_q(errs, 50)} | {_q(errs, 95)} | {_pct(np.array(errs) <= 0.1)} | {_q(pe, 50)} |")
    none = [r for r in rows if r["effect"] == "none"]
    fp = np.mean([r["verdict"] != "none" for r in none]) if none else float("nan")
    lines += ["", "### Goals", "",
              f"- top-1 accuracy, contribution >= 3x noise floor: **{100 * tot_ok / max(tot_strong, 1):.1f} %** "
              f"({tot_ok}/{tot_strong}; goal >= 95 %)",
              f"- false positives on none: **{100 * fp:.1f} %** "
              f"({sum(r['verdict'] != 'none' for r in none)}/{len(none)}; "
              "goal <= 5 %)",
              f"- |estimated - true shrink| (true effect's entry, rho >= 3): median {_q(all_err, 50)}, "
              f"95th percentile {_q(all_err, 95)}, within 0.1: "
              f"**{_pct(np.array(all_err) <= 0.1)}** (goal: within 0.1)",
              f"- diagnosis time per dataset: median {np.median([r['time_s'] for r in rows]):.2f} s, "
              f"max {np.max([r['time_s'] for r in rows]):.2f} s "
              f"(samples x channels: median {int(np.median([r['n'] * r['N'] for r in rows]))})"]
    wrong = [r for r in rows if r["verdict"] != r["effect"] and (r["effect"] == "none" or r["rho"] >= 3)]
    if wrong:
        lines += ["", "### Misses (contribution >= 3x noise floor, and false positives)", "",
                  "| truth | verdict | rho | seed | device | motion | spec |",
                  "| --- | --- | ---: | ---: | --- | --- | --- |"]
        for r in wrong[:60]:
            lines.append(f"| {r['effect']} | {r['verdict']} | {r['rho']:.2f} | {r['seed']} | {r['device']} | "
                         f"{r['motion']} | {r['spec'][:80]} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-effect", type=int, default=30, help="datasets per effect (default 30)")
    ap.add_argument("--per-none", type=int, default=100, help="datasets without an effect (default 100)")
    ap.add_argument("--quick", action="store_true", help="4 datasets per effect and for none, no Xsens or timing run")
    ap.add_argument("--seed", type=int, default=1000)
    ap.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--effects", default=",".join(LABELS), help="comma-separated subset")
    ap.add_argument("--no-timing", action="store_true")
    ap.add_argument("--timing-samples", type=int, default=100_000)
    ap.add_argument("--rows", help="also dump the per-dataset rows as JSON to this file")
    ap.add_argument("-o", "--output", default=os.path.join(ROOT, "build", "bench_diagnose.md"))
    a = ap.parse_args(argv)

    per = 4 if a.quick else a.per_effect
    per_none = 4 if a.quick else a.per_none
    effects = [e.strip() for e in a.effects.split(",") if e.strip()]
    bad = [e for e in effects if e not in LABELS]
    if bad:
        ap.error(f"unknown effect {bad[0]!r}; effects: {', '.join(LABELS)}")
    # stratified magnitudes: dataset k of an effect gets a target rho in the k-th of `per` equal
    # slices of [log RHO_LO, log RHO_HI] (position inside the slice from the seed)
    jobs = []
    for e in effects:
        for k in range(per_none if e == "none" else per):
            u = np.random.default_rng([a.seed + k, LABELS.index(e), 7]).random()
            rho = float(np.exp(np.log(RHO_LO) + (np.log(RHO_HI) - np.log(RHO_LO)) * (k + u) / per))
            jobs.append((e, a.seed + k, rho))
    rows = []
    t0 = time.perf_counter()
    if a.jobs > 1:
        import multiprocessing as mp
        with mp.get_context("fork").Pool(a.jobs) as pool:
            for r in tqdm(pool.imap_unordered(run_one, jobs), total=len(jobs), desc="datasets", file=sys.stderr):
                rows.append(r)
    else:
        for j in tqdm(jobs, desc="datasets", file=sys.stderr):
            rows.append(run_one(j))
    wall = time.perf_counter() - t0
    rows.sort(key=lambda r: (LABELS.index(r["effect"]), r["seed"]))
    if a.rows:
        import json
        with open(a.rows, "w") as f:
            json.dump(rows, f, indent=0, default=float)
    text = ["# Diagnosis benchmark (withheld effects)", "",
            f"{len(rows)} datasets ({per} per effect, {per_none} without), seed {a.seed}, {wall:.0f} s wall on {a.jobs} "
            f"process(es).  rho = true contribution / noise floor, log-uniform target in [{RHO_LO}, {RHO_HI}].", ""]
    text.append(summarise(rows))
    if not a.quick:
        text += xsens_section()
    if not (a.quick or a.no_timing):
        text += ["", "### Timing", ""]
        for effs in (("time_skew:tau=0.002",),
                     ("time_skew:tau=0.002", "offset:db=5", "temperature_gain:coeff=0.0002")):
            tr = timing_run(a.timing_samples, effects=effs)
            text.append(f"- {tr['n']} samples x {tr['N']} channels, every candidate (skipped: "
                        f"{tr['skipped'] or 'none'}), data with {', '.join(effs)}: **{tr['time_s']:.1f} s** "
                        f"(goal <= 20 s); verdict {tr['verdict']}, effects found {tr['steps']}")
    out = "\n".join(text) + "\n"
    os.makedirs(os.path.dirname(os.path.abspath(a.output)), exist_ok=True)
    with open(a.output, "w") as f:
        f.write(out)
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
