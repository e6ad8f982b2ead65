"""The result's JSON entries, the one-line prose of each effect, and the sentence that says what
would tell the verdict from its rivals (``separate_by``)."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..effects import EFFECTS
from ..effects.fitdata import FitData
from ..effects.fitting import Cand


def to_json(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): to_json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [to_json(x) for x in v]
    if isinstance(v, np.ndarray):
        return to_json(v.tolist())
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        x = float(v)
        if math.isfinite(x):
            return x
        return "inf" if x > 0 else "-inf" if x < 0 else None
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def units_of(name: str) -> dict:
    return {fp.name: fp.unit for fp in EFFECTS[name].fit}


def entry(D: FitData, c: Cand, *, step: int | None, selected: bool, baseline: str, alone: Cand | None = None) -> dict:
    e = {
        "name": c.name,
        "shrink": c.shrink,
        "heldout_rms_before": c.before,
        "heldout_rms_after": c.after,
        "params": to_json(c.params),
        "params_sigma": to_json(c.sigma),
        "units": units_of(c.name),
        "n_params": int(c.k),
        "significant": bool(c.significant),
        "selected": bool(selected),
        "step": step,
        "baseline": baseline,
        "score": {"gain_chi2": c.gain, "penalty_chi2": c.penalty, "penalised_gain_chi2": c.gain - c.penalty,
                  "t": c.t if math.isfinite(c.t) else 1e9, "z": c.z, "evidence": c.evidence},
        "summary": describe(c.name, c.params, c.sigma, D),
    }
    if c.notes:
        e["notes"] = list(c.notes)
    if c.shape is not None:
        e["shape"] = to_json(c.shape)
    a = alone if alone is not None else c
    e["alone"] = {"shrink": a.shrink, "heldout_rms_before": a.before, "heldout_rms_after": a.after}
    return e


def as_model(e: dict, params: dict, sigma: dict, D: FitData) -> None:
    """Make a chosen effect's entry ``e`` quote the model's parameters ``params`` / ``sigma``
    (the chosen effects refitted jointly and re-linearised about the corrected calibration) in
    ``params``, ``params_sigma`` and ``summary``; the stepwise fit (about the given calibration,
    on what the earlier steps left: far from the truth part of a gain hides in the poses'
    forces) moves to ``params_stepwise``."""
    e["params_stepwise"] = e["params"]
    e["params"] = to_json(params)
    e["params_sigma"] = to_json(sigma)
    e["summary"] = describe(e["name"], params, sigma, D)


def as_alone(e: dict) -> None:
    """Say in the summary of an effect the model leaves out (``e["selected"]`` false) what its
    figure is: that effect alone fitted against the model before it, taking whatever of the
    gap it can (a bend of -12 % had read as a finding against a nominal calibration whose error
    it absorbed).  Not for the converter's effects (``stage`` "adc": a clip level or a code step
    is read from the raw values, not fitted to the gap)."""
    if not e["selected"] and EFFECTS[e["name"]].stage != "adc":
        e["summary"] += (f" -- not in the model: this effect alone, fitted against {e['baseline']}, taking what "
                         "it can of the gap there; no finding")


def describe(name: str, p: dict, s: dict, D: FitData) -> str:
    """One line in physical units for the summary: the effect's own prose
    (``Effect.describe``), or its name when its parameters do not fit the prose."""
    try:
        return EFFECTS[name].describe(p, s, D)
    except (KeyError, ValueError, IndexError):
        return name


def separate_by(cands, verdict: str, ambiguous: list[str], reached: tuple[str, ...] = ()) -> str:
    """One sentence: the poses or motions that would tell ``verdict`` from ``ambiguous``;
    ``reached``: those of them ambiguous only as the level they reached since the calibration
    (``Effect.reaches_level_of``), which a recording that begins right after it tells."""
    if not ambiguous:
        return ""
    hints = []
    if any(nm not in reached for nm in ambiguous):
        names = [verdict] + [nm for nm in ambiguous if nm not in reached]
        if all(cands[nm].time_dependent for nm in names) and any(cands[nm].covariate for nm in names):
            # changes of time alone and of a recorded covariate: only the covariate apart from time
            # tells them (a pose repeated later changes with both)
            names = [nm for nm in names if cands[nm].covariate]
        for nm in pair_hinted(cands, names):
            h = cands[nm].tell_apart
            # one hint per pose or motion (an offset's and a gain's both ask for each axis up and
            # down, each with its own why: said once)
            if h and h.split(" (")[0] not in [x.split(" (")[0] for x in hints]:
                hints.append(h)
    if any(nm in reached for nm in ambiguous):
        hints.append("from right after the calibration (a drift has then reached nothing yet)")
    return (f"To tell {verdict} from {' or '.join(ambiguous)}, record " + "; or ".join(hints) + ".")


def pair_hinted(cands, names: list[str]) -> list[str]:
    """Of ``names`` (the verdict first), those whose ``tell_apart`` speaks to another of them
    (``Effect.tells_from`` names it, or is empty); all of them where none does."""
    def speaks(nm):
        tf = cands[nm].tells_from
        return not tf or any(o in tf for o in names if o != nm)
    kept = [nm for nm in names if cands[nm].tell_apart and speaks(nm)]
    return kept or names
