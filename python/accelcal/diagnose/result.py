"""The diagnosis: stepwise search over the effects, the verdict, the JSON object."""
from __future__ import annotations

import math
import time
from typing import Any, Sequence

import numpy as np

from ..effects import EFFECT_NAMES
from ..effects.fitdata import read_only, recording_parts
from ..effects.fitting import Cand
from ..effects.settings import BLOCK_S
from ..io.device import NOMINAL_FACTOR
from ..io.thinned import MAX_SAMPLES, check_max_samples
from ..errors import AccelcalError
from ..readings.held import distinct_recordings
from ..motions.poses import distinct_orientations
from ..readings.noise import code_lattice, fractional_grid, uneven_low_bits
from .floor import setup_rows
from .inputs import as_calibration, as_device, as_recordings, with_terms_applied
from .prepare import prepare
from .compare import Contest, model_ambiguity, time_beside_pose, time_unmodelled
from .determined import mark_not_determined
from .outliers import OUTLIER_MODES, find_outliers, outlier_entry, outlier_note, without_poses
from .parsimony import simpler_model
from .relinearise import heldout_path, joint_fit, relinearise
from .leftover import leftover, with_settling
from .scoring import rank_key, run_candidates
from .settling import settling_ringing
from .shapes import corner_unpinned, prediction_twins, shape_hints, twin_notes, unpinned
from .shifts import shift_contest
from .stepping import next_point, same_change, terms_cover
from .settings import FORMAT, MAX_STEPS, MIN_SHRINK, PENALTY_PER_PARAM, POSE_MEAN_NOTE_RATIO, T_MIN, Z_MIN
from .text import as_alone, as_model, describe, entry, separate_by, to_json
from .where import pose_mean_gap, where_breakdown
from ..effects import EFFECTS


class DiagnosisResult(dict):
    """The diagnosis JSON object (a plain dict for ``json.dump``); ``series`` holds the
    per-sample arrays (time, residual before/after, noise floor) that :func:`write_report`
    plots.  It is not part of the JSON."""

    series: dict | None = None


def diagnose(device: Any, calibration: Any, recordings: Any, *, folds: int = 5, seed: int = 0,
             candidates: Sequence[str] | None = None, max_steps: int = MAX_STEPS, model_centripetal: bool = True,
             progress: Any = None, outliers: str = "name", max_samples: int | None = MAX_SAMPLES) -> DiagnosisResult:
    """Diagnose the gap between recordings and a calibrated model (see the module doc).

    ``device``, ``calibration``: objects or JSON paths; ``recordings``: Recordings or CSV
    paths (one or several).  ``folds``: cross-validation folds; ``seed``: fold assignment.
    ``candidates``: effect names to try (default: every effect of the registry).
    ``model_centripetal``: False diagnoses a model without the omega x (omega x r) term.
    ``progress``: optional callable(name) called after each candidate is scored.
    ``outliers``: static poses far off the calibration's terms (:mod:`.outliers`): "name" them
    (``outliers`` in the JSON, with the diagnosis of the other poses and a note), "drop" them
    (the diagnosis is of the others), or "keep" them unjudged.
    ``max_samples``: a recording of more samples is diagnosed on evenly spaced windows of
    about that many (:mod:`accelcal.io.thinned`; a file read so in bounded memory; the JSON's
    ``recordings[].thinned`` and a note say what was kept); 0 or None: every sample.
    Returns the JSON object of the data contract (a dict; see :class:`DiagnosisResult`).
    Bad input raises :class:`~accelcal.errors.InputError` / AccelcalError (one line).
    """
    t_start = time.perf_counter()
    if isinstance(folds, bool) or not isinstance(folds, (int, np.integer)) or folds < 2:
        raise AccelcalError(f"diagnose: folds must be an integer >= 2, got {folds!r}")
    if outliers not in OUTLIER_MODES:
        raise AccelcalError(f"diagnose: outliers must be one of {', '.join(OUTLIER_MODES)}, got {outliers!r}")
    dev = as_device(device)
    cal, cal_src = as_calibration(calibration, dev)
    try:
        max_samples = check_max_samples(max_samples)
    except ValueError as e:
        raise AccelcalError(f"diagnose: {e}") from None
    recs, dev, thin_notes = as_recordings(recordings, dev, max_samples)
    # readings held for several rows (a logger faster than the sensor) are counted once
    recs, dev, held_notes = distinct_recordings(recs, dev)
    cal, recs, term_notes = with_terms_applied(cal, recs, dev)
    held_notes = thin_notes + held_notes + term_notes
    cands = dict(EFFECTS)
    if candidates is None:
        names = list(EFFECT_NAMES)
    else:
        names = []
        for nm in candidates:
            if nm not in cands:
                raise AccelcalError(f"diagnose: unknown candidate effect {nm!r}; effects: {', '.join(EFFECT_NAMES)}")
            names.append(nm)
    m0 = 1.0 if model_centripetal else 0.0
    D = prepare(dev, cal, recs, int(folds), int(seed), m0)
    e = D.raw - D.p0
    setup_rows(D, e)
    off_poses = find_outliers(D, e) if outliers != "keep" else None
    again = dict(folds=folds, seed=seed, candidates=candidates, max_steps=max_steps,
                 model_centripetal=model_centripetal, progress=progress, outliers="keep", max_samples=0)
    if off_poses is not None and outliers == "drop":
        res = diagnose(dev, cal, without_poses(D, recs, off_poses), **again)
        res["outliers"] = outlier_entry(D, recs, off_poses, dropped=True)
        res["notes"] = held_notes + [n for n in res["notes"] if n not in held_notes] + [
            outlier_note(res["outliers"], res["verdict"])]
        return res

    skipped = []
    active = []
    for nm in names:
        why = cands[nm].skip(D)
        if why is None:
            active.append(nm)
        else:
            skipped.append({"name": nm, "reason": why})

    # --- step 1: every candidate alone, then stepwise --------------------------------------------
    y = read_only(e)
    pcur = read_only(D.p0)
    first, _, S0u = run_candidates(D, cands, active, y, pcur, progress)
    base_rms = float(math.sqrt(S0u.sum() / (D.n * D.R)))
    steps: list[tuple[Cand, str]] = []
    stop = None                # where the step limit stopped the search
    results = first
    remaining = list(active)
    chosen: list[str] = []
    duel = None
    pools: list[dict] = []     # the round each chosen effect was picked from (shapes.prediction_twins)
    step_amb: dict[str, list[str]] = {}    # a later step's contest: the rivals it cannot be told from
    Dk = D                     # the data as linearised for the current step
    while True:
        sig = [c for c in results.values() if c.significant]
        if not sig:
            break
        best = sorted(sig, key=rank_key)[0]
        # candidates that change every reading exactly as the best one does (on a single pose, an
        # offset, a gain, a tilt and a bend all move its one |f| alike): the first in the registry's
        # order (the simplest) is the verdict, the others are listed with it
        alike = [best] + same_change(Dk, best, sig)
        best = min(alike, key=lambda c: EFFECT_NAMES.index(c.name))
        step_duel = shift_contest(Dk, cands, best, first if not chosen else results, y, pcur)
        best = step_duel.best
        if best.name in {c.name for c in alike}:
            step_duel.ambiguous += [c.name for c in alike if c.name != best.name and c.name not in step_duel.ambiguous]
        if cands[best.name].mimics_calibration(best):
            step_duel, best = terms_cover(dev, cal, recs, folds, seed, m0, cands, D, Dk, steps, results, remaining,
                                           step_duel, best, y, pcur)
        # time-dependent rivals the data cannot tell from the chosen effect are not added later
        for nm in step_duel.ambiguous:
            if cands[nm].time_dependent and nm in remaining and nm != best.name:
                remaining.remove(nm)
        if not chosen:
            duel = step_duel
        else:
            # a later step's own rivals the data cannot tell from it (a common lag of every channel is
            # also a low-pass's group delay): stated with the model, not only in the step's notes
            step_amb[best.name] = [nm for nm in step_duel.ambiguous if nm != best.name]
        if chosen and (step_duel.swapped_from or step_duel.ambiguous):
            best.notes = list(best.notes) + [f"step {len(chosen) + 1}: {step_duel.why or 'ranked first'}"
                                             + (f"; cannot be told from {', '.join(step_duel.ambiguous)}"
                                                if step_duel.ambiguous else "")]
        baseline = "the calibrated model" + ("" if not chosen else " + " + " + ".join(chosen))
        steps.append((best, baseline))
        pools.append(results)
        chosen.append(best.name)
        remaining.remove(best.name)
        if best.gain > 0:
            y = y - best.delta
            pcur = pcur + best.delta
        if not remaining:
            break
        if len(chosen) >= max_steps:
            stop = (best, Dk, y, pcur)       # scored for a next step only if something is left (below)
            break
        Dk, y, pcur = next_point(dev, cal, recs, folds, seed, m0, cands, steps, best, Dk, y, pcur)
        results, _, _ = run_candidates(Dk, cands, remaining, y, pcur, progress)

    # --- a much simpler model that, refitted as a whole, leaves less (parsimony.py)
    alt, why = simpler_model(D, cands, first, [c for c, _ in steps], e)
    if alt is not None:
        path = heldout_path(D, cands, alt, e)
        steps = [(c, "the calibrated model" + ("" if k == 0 else " + " + " + ".join(alt[:k])))
                 for k, c in enumerate(path)]
        duel = Contest(best=path[0], swapped_from=chosen[0], why=why)
        chosen = list(alt)
        pools = [first]

    # --- joint refit of the chosen effects (backfitting), re-linearised about the corrected calibration
    fitted = [c.name for c, _ in steps if c.gain > 0]
    joint: dict[str, Cand] = {c.name: c for c, _ in steps}
    if len(fitted) > 1:
        joint.update(joint_fit(D, cands, fitted, e, start={nm: joint[nm] for nm in fitted}))
    total_delta = sum((joint[nm].delta for nm in fitted), np.zeros_like(e))
    relin = relinearise(dev, cal, recs, int(folds), int(seed), m0, cands, fitted, joint, D) if fitted else None

    # --- output ------------------------------------------------------------------------------------
    effects = []
    for k, (c, baseline) in enumerate(steps):
        effects.append(entry(D, c, step=k + 1, selected=True, baseline=baseline, alone=first.get(c.name)))
    rest = sorted((c for nm, c in first.items() if nm not in chosen), key=rank_key)
    for c in rest:
        effects.append(entry(D, c, step=None, selected=False, baseline="the calibrated model"))
    verdict = steps[0][0].name if steps else "none"
    model_after = steps[-1][0].after if steps else base_rms
    model_params = {nm: joint[nm].params for nm in chosen}
    model_sigma = {nm: joint[nm].sigma for nm in chosen}
    relin_info = None
    if relin is None and len(fitted) > 1:
        # the model as it is fitted together: each effect scored after the others' joint fits
        model_after = min(model_after, heldout_path(D, cands, fitted, e, joint)[-1].after)
    if relin is not None:
        model_after = min(model_after, relin["path"][-1].after)
        model_params.update(relin["params"])
        model_sigma.update({nm: relin["joint"][nm].sigma for nm in relin["params"]})
        relin_info = {"iterations": relin["iterations"], "converged": relin["converged"],
                      "heldout_rms_after": relin["path"][-1].after,
                      "heldout_rms_after_first_linearisation": steps[-1][0].after}
    for ent in effects[:len(steps)]:
        # the chosen effects quote the model's parameters (joint, re-linearised), not the stepwise fits
        as_model(ent, model_params[ent["name"]], model_sigma[ent["name"]], D)
    floor = float(np.sqrt(np.mean(D.sigma ** 2)))
    rms_ch = np.sqrt(np.mean(e * e, axis=0))
    gap_rms = float(np.sqrt(np.mean(rms_ch ** 2)))
    notes = [f"{r.source}: {n}" for r in recs for n in r.notes] + held_notes + list(D.notes)
    if D.mode == "jigfree":
        notes.append("jig-free: the static poses with |f| = g are the reference; fitted and scored on the "
                     f"{D.R} direction(s) per sample the pose angles cannot absorb")
    if steps and len(steps) > 1:
        notes.append("effects after the first were scored on the residual left by the ones before (their in-sample "
                     "fits subtracted); 'model' gives the joint refit")
    ambiguous = list(duel.ambiguous) if duel is not None and steps else []
    reached = []
    shape_named, twins = [], []
    if steps:
        more, reached, why = model_ambiguity(cands, chosen, duel, ambiguous)
        ambiguous += more
        notes += why
        more, why = time_unmodelled(D, e, first, cands, chosen, ambiguous)
        ambiguous += more
        notes += why
        more, why = time_beside_pose(D, cands, chosen, ambiguous)
        ambiguous += more
        notes += why
        shape_named, why = unpinned(pools, chosen, ambiguous)
        ambiguous += shape_named
        notes += why
        twins = prediction_twins(D, cands, chosen, pools, e, joint)
        for t in twins:
            if t["ambiguous"] and t["with"] not in ambiguous and t["with"] not in chosen:
                ambiguous.append(t["with"])
        notes += twin_notes(twins, verdict)
        for ent in effects[1:len(steps)]:
            ent["ambiguous_with"] = list(dict.fromkeys(
                [nm for nm in step_amb.get(ent["name"], []) if nm not in chosen]
                + [t["with"] for t in twins if t["ambiguous"] and t["effect"] == ent["name"]]))
            ambiguous += [nm for nm in ent["ambiguous_with"] if nm not in ambiguous and nm != verdict]
        mark_shapes(effects[:len(steps)], joint, twins)
        effects[0]["ambiguous_with"] = ambiguous
        effects[0]["contest"] = {"first_ranked": duel.swapped_from or verdict, "rivals": duel.tests}
    if duel is not None and duel.swapped_from:
        notes.append(f"verdict {verdict} rather than {duel.swapped_from}, the larger held-out gain alone: {duel.why}")
    if ambiguous:
        notes.append(f"{verdict} and {', '.join(ambiguous)} explain the same part of the gap: the data cannot tell "
                     "them apart (separate_by says what would)")
    if "gain" in model_params:
        ratio = 1.0 + np.asarray(model_params["gain"]["scale"], float)
        far = np.flatnonzero((ratio > NOMINAL_FACTOR) | (ratio < 1.0 / NOMINAL_FACTOR))
        if far.size:
            notes.append(f"gain {', '.join(f'{100 * (ratio[i] - 1):+.0f} %' for i in far)} on channel(s) "
                         f"{', '.join(map(str, far))}: beyond what a real chip differs from its nominal "
                         f"({NOMINAL_FACTOR:g} x either way), so no error of the sensor: the calibration's or the "
                         "device file's scale is off (convert's --full-scale, --lsb), or the poses do not measure "
                         "that gain")
    turns = pose_orientations(D)
    if D.mode == "jigfree" and turns < 6:
        notes.append(f"only {turns} distinct orientation(s) among {len(D.pose_labels)} static pose(s): effects "
                     "that are constant within a pose "
                     "(offset, gain, misalignment, nonlinearity) can hardly be told apart, and their parameters are "
                     "not all determined (the poses fix a few combinations of them): the sizes given are those of the "
                     "smallest change that fits, not measurements")
    lattice = []
    parts = recording_parts(D)
    for i in range(D.N):
        q, ph, fr, nd = code_lattice(D.raw[:, i])
        ent = {"channel": i, "step": int(q), "share_on_lattice": fr, "distinct_values": int(nd)}
        grid = fractional_grid(D.raw[:, i]) if q == 1 else None
        if grid is not None:
            ent["grid_counts"] = grid
            notes.append(f"raw_{i}: the readings sit on a grid of {grid:.4g} counts, no whole number: the logger "
                         "wrote them rounded in another unit (a decimal place of m/s^2 or g) and each became the "
                         "nearest count; this grid is their resolution (not missing or doubled codes of an ADC)")
        elif q == 1:
            low = uneven_low_bits(D.raw[:, i], parts)
            if low is not None:
                ent["low_bits"] = {k: v for k, v in low.items() if k != "uneven"}
            if low is not None and low["uneven"]:
                notes.append(f"raw_{i}: {100 * low['share_of_top_residue']:.0f} % of the readings fall in one residue "
                             f"class mod {low['modulus']} ({100 / low['modulus']:.0f} % for evenly used codes), the "
                             f"same class in {100 * low['parts_agreeing']:.0f} % of {low['parts']} parts of the "
                             "recording: the lowest bits are unevenly used (missing or doubled codes: a rescaled or "
                             "differentially nonlinear ADC)")
        lattice.append(ent)
    gap_extra = pose_mean_gap(D, e)
    if relin is not None:
        left = leftover(relin["D"], relin["e"] - relin["delta"], base_rms, model_after)
    else:
        left = leftover(D, e - total_delta, base_rms, model_after)
    ring = settling_ringing(recs, dev)
    left = with_settling(left, ring, D, base_rms)
    if stop is not None and left is not None and alt is None:
        # what the step limit left out, where something is left: said, not added
        Dk, y, pcur = next_point(dev, cal, recs, folds, seed, m0, cands, steps, *stop)
        more, _, _ = run_candidates(Dk, cands, remaining, y, pcur, progress)
        beyond = min((c for c in more.values() if c.significant), key=rank_key, default=None)
        if beyond is not None:
            notes.append(f"{beyond.name} would be step {max_steps + 1} (held-out shrink {beyond.shrink:.3f} of what "
                         f"the {max_steps} effects leave; t {beyond.t:.3g}, z {beyond.z:.3g}), beyond the {max_steps} "
                         "steps the search takes: not in the model; part of what is left unexplained may be it")
            left["beyond_step_limit"] = {"name": beyond.name, "shrink": beyond.shrink, "summary": describe(
                beyond.name, beyond.params, beyond.sigma, D)}
    if ring is not None:
        notes.append(f"a ringing at {ring['peak_hz']:.3g} Hz after {ring['n_stops']} stops (channels "
                     f"{', '.join(map(str, ring['channels']))}; {ring['ratio_to_onset']:.3g} x the power at the "
                     "motions' starts): a resonance of the sensor or its mount, in samples the model does not score")
    if left is not None and not steps:
        verdict = "unexplained"
    pm = gap_extra.get("pose_mean_ratio")
    if verdict == "none" and pm is not None and pm > POSE_MEAN_NOTE_RATIO:
        notes.append(f"the static poses' means scatter {pm:.3g} x beyond their noise (its colour within the poses "
                     f"counted; {gap_extra['pose_mean_rms_counts']:.3g} counts rms over {gap_extra['n_poses']} poses), "
                     "but no effect of the table explains that scatter on held-out data: poses that moved while "
                     "held (a hand), or an error that differs from pose to pose at random; too little against the "
                     "samples' own noise to be a gap")
    result = DiagnosisResult({
        "format": FORMAT,
        "verdict": verdict,
        "device": dev.name,
        "calibration": {"source": cal_src, "method": cal.method},
        "mode": D.mode,
        "recordings": D.rec_info,
        "clipped_per_channel": np.sum([ri["clipping"]["clipped_per_channel"] for ri in D.rec_info],
                                      axis=0).astype(int).tolist(),
        "n_samples": D.n,
        "n_channels": D.N,
        "gap": {
            "rms_counts": gap_rms,
            "noise_floor_counts": floor,
            "ratio_to_noise": gap_rms / floor if floor > 0 else None,
            "heldout_rms_counts": base_rms,
            "noise_floor_per_channel": D.sigma.tolist(),
            "rms_per_channel": rms_ch.tolist(),
            "noise_method": D.noise_method,
            **gap_extra,
        },
        "effects": effects,
        "model": {
            "effects": chosen,
            "heldout_rms_before": base_rms,
            "heldout_rms_after": model_after,
            "shrink": float(max(0.0, 1.0 - model_after / base_rms)) if base_rms > 0 else 0.0,
            "params": {nm: to_json(model_params[nm]) for nm in chosen},
            "params_sigma": {nm: to_json(model_sigma[nm]) for nm in chosen},
            "relinearised": relin_info,
        },
        "ambiguous_with": ambiguous,
        "separate_by": with_shape_hints(separate_by(cands, verdict, ambiguous, tuple(reached)) if steps else "",
                                        effects[:len(steps)], shape_named, twins),
        "ambiguity_by_prediction": twins,
        "unexplained": left,
        "skipped": skipped,
        "where": to_json(where_breakdown(D, e)),
        "raw_values": lattice,
        "cv": {"folds": D.K, "blocks": D.B, "seed": int(seed), "block_s": BLOCK_S,
               "t_min": T_MIN, "z_min": Z_MIN, "penalty_per_param_chi2": PENALTY_PER_PARAM, "min_shrink": MIN_SHRINK,
               "rule": "significant: held-out chi2 gain > penalty, (block t >= t_min or chi2 z >= z_min), "
                       "shrink >= min_shrink; or proven on its own evidence whatever its gain (a lattice of codes "
                       "coarser than the device's, a pile of clipped readings: the effect's 'evidence')"},
        "notes": notes,
        "model_centripetal": bool(model_centripetal),
        "elapsed_s": time.perf_counter() - t_start,
    })
    result["where"] = to_json(result["where"])
    for ent in result["effects"]:
        mark_not_determined(D, cands, ent, result["model"]["params_sigma"] if ent["selected"] else None)
        as_alone(ent)
    result["outliers"] = None
    if off_poses is not None:
        result["outliers"] = outlier_entry(D, recs, off_poses, dropped=False, without=diagnose(
            dev, cal, without_poses(D, recs, off_poses), **again))
        notes.append(outlier_note(result["outliers"], verdict))
    result.series = {
        "tg": D.tg, "t": D.t, "rec": D.rec, "residual": e, "residual_after": e - total_delta,
        "noise_floor": D.sigma, "sources": [ri["source"] for ri in D.rec_info], "static": D.static,
    }
    return result


def pose_orientations(D) -> int:
    """How many distinct orientations (:func:`~accelcal.motions.poses.distinct_orientations`)
    the static poses of ``D`` hold: seven poses held in one orientation (a board on a desk,
    picked up and put down) fix no more than one; the diagnosis's sizes of constant effects
    are then the smallest change that fits, not measurements."""
    F = [D.f[D.pose == p].mean(axis=0) for p in range(len(D.pose_labels)) if np.any(D.pose == p)]
    F = [f for f in F if np.linalg.norm(f) > 0]
    return distinct_orientations(np.asarray(F)) if F else 0


def mark_shapes(selected: list[dict], joint: dict[str, Cand], twins: list[dict]) -> None:
    """Each chosen effect's ``shape`` (its shape parameters and whether the data pin them:
    :mod:`.shapes`): a temperature term's lag from its fit, a low-pass's corner not pinned where a
    time skew's predictions cannot be told from it (only its delay is)."""
    for ent in selected:
        c = joint.get(ent["name"])
        if c is not None and c.shape is not None:
            ent["shape"] = to_json(c.shape)
        if ent["name"] == "bandwidth":
            ent["shape"] = {"fc_hz": {"determined": not corner_unpinned(twins),
                                      "why": "the motion does not reach the corner: a low-pass and a time skew "
                                             "predict the same readings here (only the delay is determined)"
                                      if corner_unpinned(twins) else "the amplitude loss above the corner tells it "
                                      "from a time skew"}}


def with_shape_hints(text: str, selected: list[dict], shape_named: list[str], twins: list[dict]) -> str:
    """``separate_by`` with what would pin the shapes the data leave open (:data:`.shapes.SHAPE_HINTS`):
    of effects stated only in a shape not pinned, of chosen effects whose shape is not determined, and
    of a low-pass that cannot be told from a time skew."""
    names = list(shape_named)
    for ent in selected:
        if any(not v.get("determined", True) for v in (ent.get("shape") or {}).values()) and ent["name"] not in names:
            names.append(ent["name"])
    if corner_unpinned(twins) and "bandwidth" not in names:
        names.append("bandwidth")
    hints = shape_hints(names)
    if not hints:
        return text
    return (text + " " if text else "") + "To pin the shapes these data leave open, record " + "; or ".join(hints) + "."
