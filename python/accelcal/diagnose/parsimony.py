"""A much simpler model that, fitted as a whole, leaves less than the stepwise one.

The stepwise search adds one effect at a time, each fitted on what the ones before it leave.
An effect whose prediction depends on the model's own reading -- the converter's rounding
(``quantization``) predicts each reading's rounding from the reading the model expects -- is
predicted from readings that an effect fitted before it got wrong: an offset fitted first
carries each pose's rounding, and the rounding then predicted from the offset misses.  A
per-pose effect (``pose_error``, two angles a pose) takes the offset and each pose's rounding
at once and wins the first step.  Refitted together (backfitting), the offset and the rounding
leave less than the per-pose effect and its companions with a tenth of the parameters.

So after the stepwise search, each significant first-step rival with at most 1/SIMPLER_K of
the verdict's parameters replaces it at the head of the model; the two models are refitted as
wholes and compared by their in-sample chi2 plus PENALTY_PER_PARAM a parameter (as the
stepwise ranking is).  The simpler one is kept where it leaves less.  Jig-free data are left
alone: there the stepwise search re-linearises about each calibration term it adds, and a
comparison at the first linearisation would not be the search's.
"""
from __future__ import annotations

import numpy as np

from ..effects.fitting import Cand, block_ss
from .relinearise import joint_fit
from .scoring import rank_key
from .settings import PENALTY_PER_PARAM

SIMPLER_K = 4        # a rival is much simpler with at most 1/SIMPLER_K of the verdict's parameters
MAX_SIMPLER = 2      # ... the best this many of them (by held-out gain less penalty) are tried


def penalised_chi2(D, cands, names: list[str], e: np.ndarray) -> tuple[float, int]:
    """In-sample weighted chi2 of the residual ``e`` less the joint fit of ``names``, plus
    PENALTY_PER_PARAM a parameter; and the parameter count."""
    joint = joint_fit(D, cands, names, e)
    total = sum((joint[nm].delta for nm in names), np.zeros_like(e))
    Sw, _ = block_ss(D, D.rows(e - total))
    k = sum(joint[nm].k for nm in names)
    return float(Sw.sum()) + PENALTY_PER_PARAM * k, k


def simpler_model(D, cands, first: dict[str, Cand], steps: list[Cand], e: np.ndarray) -> tuple[list[str] | None, str]:
    """The names of a much simpler model that leaves less than the stepwise one (``steps``, the
    chosen fits in order; ``first``, every candidate alone on ``e``), and why; (None, "") when
    there is none."""
    chosen = [c.name for c in steps if c.gain > 0]
    if D.mode == "jigfree" or not chosen or steps[0].name != chosen[0]:
        return None, ""
    k_verdict = steps[0].k
    rivals = sorted((c for nm, c in first.items()
                     if c.significant and c.gain > 0 and nm not in chosen and c.k * SIMPLER_K <= k_verdict),
                    key=rank_key)[:MAX_SIMPLER]
    if not rivals:
        return None, ""
    base, k_base = penalised_chi2(D, cands, chosen, e)
    best = None
    for r in rivals:
        names = [r.name] + chosen[1:]
        score, k = penalised_chi2(D, cands, names, e)
        # a later member the rival makes needless is dropped (each once, in order)
        for nm in list(names[1:]):
            trial = [x for x in names if x != nm]
            s2, k2 = penalised_chi2(D, cands, trial, e)
            if s2 < score:
                names, score, k = trial, s2, k2
        if score < base and (best is None or score < best[0]):
            best = (score, names, k)
    if best is None:
        return None, ""
    score, names, k = best
    why = (f"{' + '.join(names)} refitted together leave a penalised chi2 of {score:.4g} against {base:.4g} for "
           f"{' + '.join(chosen)} ({k} against {k_base} parameters)")
    if len(names) > 1:
        why += (f": fitted one after another, {names[0]} carried part of what {' and '.join(names[1:])} "
                f"explain, and {chosen[0]} took the first step")
    return names, why
