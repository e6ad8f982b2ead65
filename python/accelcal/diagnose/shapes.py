"""Say only what the data determine: shapes they do not pin, and models whose predictions they
cannot tell apart (issue 33, items 2 and 3).

* **Shapes the data do not pin.**  An effect with a shape parameter is fitted in its nested form
  where the data do not pin the parameter (``Cand.shape``; a temperature term's lag:
  :meth:`accelcal.effects.temperature.TemperatureFit._lag_interval`), and the shaped fit rides
  along as ``Cand.shaped``, scored beside it (:func:`~.scoring.run_candidates`).  Where the shaped form is
  significant and its effect is not in the model (the nested form did not earn a step), the
  effect goes into ``ambiguous_with`` (:func:`unpinned`): the data cannot tell the model from
  that shape, and ``separate_by`` says what recording would (:data:`SHAPE_HINTS`).
* **Predictions the noise cannot separate.**  For each member of the model and each rival that
  was significant in the round the member was chosen from (at least RIVAL_GAIN_SHARE of its
  gain), the model with the member replaced by the rival is refitted jointly
  (:func:`~.relinearise.joint_fit`) and the two models' predictions are compared on these data
  (:func:`prediction_twins`): the weighted energy of their difference, in units of the noise
  (the residual's excess over the floor and the poses' design effect), less the parameters the
  two swapped members fit to the noise, below (2 SEPARATE_T)^2 means that no recording like this
  one tells them apart at SEPARATE_T standard errors (the log-likelihood ratio of two models
  whose predictions differ by d has mean |d|^2 and standard deviation 2 |d| in these units), so
  both are stated, whatever their ranking.  A low-pass and a time skew are told apart by the
  amplitude loss at high frequency; where the motion does not reach it this is where
  ``bandwidth`` joins a skew (and the corner is not pinned: :func:`corner_unpinned`).
"""
from __future__ import annotations

import math

import numpy as np

from ..effects.fitting import Cand, LinearCandidate
from ..effects.settings import BACKFIT_PASSES
from .compare import HOLDS_LEFT, RIVAL_GAIN_SHARE, SEPARATE_T
from .relinearise import joint_fit

MAX_TWIN_MEMBERS = 3       # the model's first members whose rivals are compared by their predictions ...
MAX_TWIN_RIVALS = 2        # ... each with at most this many rivals (by held-out gain)
TWIN_TOL = 0.1            # ... until a pass changes the prediction by less than this (chi2, noise units)
TWIN_PASSES = 20          # backfitting passes of the other model (effects that take each other's parts converge slowly)

#: what recording tells a shape from its nested form (separate_by), per effect whose shape was not pinned
SHAPE_HINTS = {
    "temperature_offset": "a pose held while the temperature changes slowly, over longer than the lag "
                          "(the lag shows as the offset trailing the temperature); or a recording at the "
                          "calibration's temperature (no temperature effect there, whatever its lag)",
    "temperature_gain": "each axis up and down held while the temperature changes slowly, over longer than the "
                        "lag; or a recording at the calibration's temperature",
    "bandwidth": "motion above the corner frequency (fast turns, a shake or a tap: a low-pass loses "
                 "amplitude there, a time skew only delays)",
    "nonlinearity": "poses between the axes and at several tilts between -g and +g on each axis (a cube bends "
                    "the reading there unlike a square; at +-g along an axis it is a gain)",
    "bias_drift": "a pose repeated several times through the recording (a path's turns show between the "
                  "repeats; a ramp changes them evenly)",
    "time_skew": "fast motion with a sharp start and stop on every channel's axis (a skew shifts the edge by "
                 "its delay; a delay within the noise leaves no edge apart)",
}


def shape_entry(c: Cand) -> dict | None:
    """The JSON ``shape`` of a candidate: {param: {value, interval, determined, ...}} or None."""
    return None if c.shape is None else dict(c.shape)


def unpinned(pools: list[dict], chosen: list[str], ambiguous: list[str]) -> tuple[list[str], list[str]]:
    """Effects whose shaped form (not pinned by the data) is significant but which are not in the
    model: they explain the gap too, in a shape the data cannot fix, so the model cannot be told
    from them.  Returns (names to add to ``ambiguous_with``, notes)."""
    add, notes = [], []
    for pool in pools:
        for nm, c in pool.items():
            sh = c.shaped
            if sh is None or not sh.significant or nm in chosen or nm in ambiguous or nm in add:
                continue
            add.append(nm)
            info = next(iter((c.shape or {}).values()), {})
            lo, hi = info.get("interval_s", [0.0, math.inf])
            span = f"{hi:.3g} s" if math.isfinite(hi) else "beyond what the data reach"
            notes.append(f"{nm} with a thermal lag explains the gap too (shrink {sh.shrink:.3f} alone), but the lag is "
                         f"not determined by these data (best {info.get('value', 0.0):.3g} s, interval {lo:.3g} s to "
                         f"{span}, the longest recording {info.get('span_s', 0.0):.3g} s) and without a lag it "
                         f"explains too little (shrink {c.shrink:.3f}): not named, stated as ambiguous")
    return add, notes


def _chi2(D, d: np.ndarray) -> float:
    return float(np.sum(D.W * D.rows(d) ** 2))


def prediction_twins(D, cands, chosen: list[str], pools: list[dict], e: np.ndarray,
                     joint: dict[str, Cand]) -> list[dict]:
    """For each of the model's first MAX_TWIN_MEMBERS members (``chosen``, fitted together in
    ``joint`` on the residual ``e``) and each of its rivals (significant in ``pools[j]``, the round
    member j was chosen from, with at least RIVAL_GAIN_SHARE of its gain, not in the model): the
    model with the member replaced by the rival, refitted jointly, and how far the two models'
    predictions differ on these data (the rival also with the levels it reaches since the
    calibration, ``Effect.reaches_level_of``: a ramp's level when the recording began is an
    offset).  Returns one dict per pair (``effect``, ``with``, ``model`` (the other model),
    ``separation`` = the difference's energy in noise units less the swapped members' parameters,
    ``needed`` = (2 SEPARATE_T)^2, ``ambiguous``)."""
    fitted = [nm for nm in chosen if nm in joint]
    if not fitted:
        return []
    pred = sum((joint[nm].delta for nm in fitted), np.zeros_like(e))
    rows = max(D.n * D.R, 1)
    s2 = max(1.0, _chi2(D, e - pred) / rows)
    unit = s2 * float(getattr(D, "deff", 1.0) or 1.0)
    needed = (2.0 * SEPARATE_T) ** 2
    out = []
    for j, m in enumerate(fitted[:MAX_TWIN_MEMBERS]):
        pool = pools[j] if j < len(pools) else {}
        own = pool.get(m)
        floor_gain = RIVAL_GAIN_SHARE * own.gain if own is not None and own.gain > 0 else 0.0
        rivals = sorted((c for nm, c in pool.items() if nm not in chosen and c.significant and c.gain > 0
                         and c.gain >= floor_gain), key=lambda c: -c.gain)[:MAX_TWIN_RIVALS]
        for c in rivals:
            # first the two fits on the residual the member was chosen on (no refit): where they
            # already predict alike, so do the models
            tries = []
            if own is not None:
                tries.append((_chi2(D, own.delta - c.delta) / unit - own.k - c.k, [c.name]))
            if j == 0 and (not tries or tries[0][0] >= needed):
                # the verdict: the model with the rival in its place, refitted together, and with the
                # levels the rival reaches since the calibration (``Effect.reaches_level_of``: a
                # ramp's level when the recording began is an offset; not the member itself, which
                # would nest the model)
                swap = [c.name if nm == m else nm for nm in fitted]
                alts = [swap] if len(swap) > 1 else []
                # (nor a level that cannot be fitted here, or that holds the member's change: a shift
                # per recording holds an offset, and would nest the model just as well)
                more = [nm for nm in cands[c.name].reaches_level_of if nm in cands and nm not in swap and nm != m
                        and not cands[nm].skip(D) and not _holds_change(D, cands, nm, joint[m].delta)]
                if more:
                    alts.append(swap + more)
                for names in alts:
                    if not all(isinstance(cands[nm], LinearCandidate) for nm in names):
                        # a member fitted by a search (a lag, a delay, per-pose angles) is refitted
                        # at every pass: on 100,000 samples that had taken minutes
                        continue
                    alt, alt_pred = backfit(D, cands, names, e, joint, unit)
                    # the parameters the two models do not share fit the noise each its own way
                    k = (sum(joint[nm].k for nm in fitted if nm not in names)
                         + sum(alt[nm].k for nm in names if nm not in fitted))
                    tries.append((_chi2(D, pred - alt_pred) / unit - k, names))
            if not tries:
                continue
            sep, names = min(tries, key=lambda x: x[0])
            out.append({"effect": m, "with": c.name, "model": names, "separation": float(sep), "needed": needed,
                        "ambiguous": bool(sep < needed)})
    return out


def _holds_change(D, cands, name: str, change: np.ndarray) -> bool:
    """Whether ``name``'s form, fitted to ``change`` alone (no noise), leaves at most HOLDS_LEFT of
    its weighted energy (:func:`~.compare.holds` for a change that is no candidate's fit)."""
    total = _chi2(D, change)
    if total <= 0.0:
        return True
    fit = joint_fit(D, cands, [name], change, passes=1)[name]
    return _chi2(D, change - fit.delta) <= HOLDS_LEFT * total


def backfit(D, cands, names: list[str], e: np.ndarray, start: dict[str, Cand], unit: float):
    """All-data fits of ``names`` together on ``e`` (backfitting, as :func:`~.relinearise.joint_fit`;
    the members also in ``start`` start from their fits there) until a pass changes the prediction
    by less than TWIN_TOL chi2 in noise units, at most TWIN_PASSES passes where every member is
    linear in its parameters (a ramp, an offset and a gain on six poses take each other's parts and
    converge slowly), else BACKFIT_PASSES (the model's own joint fit's).
    Returns (fits, prediction)."""
    fits = {nm: start[nm] for nm in names if nm in start}
    # a member fitted by a search (a lag, a delay, per-pose angles) is dear: as many passes as the
    # model's own joint fit takes
    passes = TWIN_PASSES if all(isinstance(cands[nm], LinearCandidate) for nm in names) else BACKFIT_PASSES
    deltas = {nm: (fits[nm].delta if nm in fits else np.zeros_like(e)) for nm in names}
    pred = sum(deltas.values(), np.zeros_like(e))
    for _ in range(passes):
        old = pred
        for nm in names:
            others = pred - deltas[nm]
            one = joint_fit(D, cands, [nm], e - others, passes=1)[nm]
            deltas[nm] = one.delta
            fits[nm] = one
            pred = others + one.delta
        if len(names) == 1 or _chi2(D, pred - old) / unit < TWIN_TOL:
            break
    return fits, pred


def corner_unpinned(twins: list[dict]) -> bool:
    """Whether a low-pass in the model or beside a skew cannot be told from a pure delay here."""
    return any(t["ambiguous"] and {t["effect"], t["with"]} == {"bandwidth", "time_skew"} for t in twins)


def twin_notes(twins: list[dict], verdict: str) -> list[str]:
    """One note per pair of models whose predictions the noise cannot separate."""
    out = []
    for t in twins:
        if not t["ambiguous"]:
            continue
        where = "the verdict" if t["effect"] == verdict else f"the model's {t['effect']}"
        out.append(f"{t['with']} in place of {where}: the two models' predictions on these data differ by "
                   f"{max(t['separation'], 0.0):.3g} in chi2 beyond what their parameters fit to the noise, less "
                   f"than the {t['needed']:.3g} that tell two models apart at {SEPARATE_T:g} standard errors: "
                   "both are stated")
    return out


def shape_hints(names: list[str]) -> list[str]:
    """The separate_by hints (:data:`SHAPE_HINTS`) of effects stated for a shape not pinned."""
    return [SHAPE_HINTS[nm] for nm in names if nm in SHAPE_HINTS]
