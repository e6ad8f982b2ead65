"""Scoring a candidate's held-out gain against the noise, and running the candidates."""
from __future__ import annotations

import math

import numpy as np

from ..effects.fitdata import FitData
from ..effects.fitting import Cand, block_ss
from .settings import MIN_SHRINK, PENALTY_PER_PARAM, T_MIN, Z_MIN


def unit_sums(D: FitData, gb: np.ndarray) -> np.ndarray:
    """Per-block figures ``gb`` (B,) (held-out chi2 gains, or two candidates' paired
    differences) summed over each independent unit D.unit (:func:`~.floor.independent_units`:
    the blocks of one static pose, which share the pose's level error, are one unit); ``gb``
    itself where the units are not set."""
    gb = np.asarray(gb, float)
    if D.unit is None or D.unit.size != gb.size:
        return gb
    return np.bincount(np.unique(D.unit, return_inverse=True)[1], weights=gb)


def score(D: FitData, c: Cand, S0w: np.ndarray, S0u: np.ndarray) -> Cand:
    """The held-out gain of ``c`` against the noise (``Cand``'s score fields).  Static poses'
    level errors shared by all their samples (the rounding's bias where the noise does not
    dither it) are fitted on the training folds and kept on the held-out ones, so the blocks
    of a pose are one unit of the t statistic (D.unit) and the penalty and the null spread
    of z grow by the poses' design effect D.deff (:func:`~.floor.pose_design_effect`)."""
    gb = S0w - c.Sw
    c.gain = float(gb.sum())
    deff = D.deff
    c.penalty = PENALTY_PER_PARAM * c.k * deff
    gb = unit_sums(D, gb)
    nb = gb.size
    sd = float(np.std(gb, ddof=1)) if nb > 1 else 0.0
    c.t = float(np.mean(gb) / (sd / math.sqrt(nb))) if sd > 0 else (math.inf if c.gain > 0 else 0.0)
    rows = D.n * D.R
    c.before = float(math.sqrt(max(S0u.sum(), 0.0) / rows))
    c.after = float(math.sqrt(max(c.Su.sum(), 0.0) / rows))
    c.shrink = float(max(0.0, 1.0 - c.after / c.before)) if c.before > 0 else 0.0
    # chi2 route: under the null (noise only) the held-out gain has mean ~ -k K/(K-1) and spread
    # ~ 2 sqrt(k K/(K-1)) in chi2 units; s2 >= 1 scales it up when the residual left is larger than
    # the noise floor says (a low floor, correlated noise, other unmodelled effects), and by the
    # poses' design effect: the chi2 a row left, times deff, is what a pose's level error is worth
    # (below the floor where the model holds most of the rounding: a quantiser in it).
    s2 = max(1.0, float(c.Sw.sum()) / rows * deff)
    kk = max(c.k, 1) * D.K / (D.K - 1)
    c.z = float(c.gain / (2.0 * s2 * math.sqrt(kk)))
    c.significant = bool(c.proof or (c.gain - c.penalty > 0 and (c.t >= T_MIN or c.z >= Z_MIN)
                                     and c.shrink >= MIN_SHRINK))
    return c


def run_candidates(D, cands, names, y, pcur, progress):
    Rr = D.rows(y)
    S0w, S0u = block_ss(D, Rr)
    out = {}
    for nm in names:
        c = cands[nm].cv(D, y, pcur, S0w, S0u)
        out[nm] = score(D, c, S0w, S0u)
        if c.shaped is not None:
            # a shape the data do not pin: the shaped fit is scored beside the nested one (diagnose.shapes)
            score(D, c.shaped, S0w, S0u)
        if progress is not None:
            progress(nm)
    return out, S0w, S0u


def rank_key(c: Cand):
    return (-(c.gain - c.penalty), c.k)
