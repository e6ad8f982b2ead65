"""The chosen effects' joint fit, and its re-linearisation about the corrected calibration.

Each effect is fitted to the residual of the model linearised about the calibration the
user gave.  Far from the truth that linearisation biases the parameters: in a jig-free
diagnosis the poses' forces are taken with the given calibration, so part of a gain error
hides in them (the real Xsens recording against its nominal calibration: gains of -0.27 to
-0.42 % where its jig-free calibration has +0.5 to +1.1 %).  :func:`relinearise` folds the
fitted calibration effects (``Effect.absorbs``: offset, gain, misalignment) into the
calibration, prepares the data again about it (new pose forces), fits the chosen effects
again and repeats until the fitted change is below RELIN_TOL of the noise (or, should the
in-sample chi2 after the joint fit grow from one point to the next, stops at the best point
reached); the parameters
reported are then those that take the given calibration to the final one, and the held-out
figures are scored at the final point.  With a reference f and only offsets and gains among
the absorbed effects there is nothing to re-linearise: their fits are exact changes of the
readings there (``Effect.exact_with_reference``), and the joint fit is the final one.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..effects.fitdata import read_only
from ..effects.fitting import Cand, block_ss
from ..effects.settings import BACKFIT_PASSES
from .floor import setup_rows
from .prepare import prepare
from .scoring import score

RELIN_MAX = 15             # re-linearisations at most (the Xsens recording from its nominal calibration: 8)
RELIN_TOL = 0.05           # stop when the absorbed effects change the prediction by < this x the noise (max)


def joint_fit(D, cands, names: list[str], e: np.ndarray, start: dict[str, Cand] | None = None,
              passes: int = BACKFIT_PASSES) -> dict[str, Cand]:
    """All-data fits of the effects ``names`` together on the residual ``e`` (backfitting:
    each refitted on what the others leave, ``passes`` times)."""
    joint = dict(start or {})
    deltas = {nm: (joint[nm].delta if nm in joint else np.zeros_like(e)) for nm in names}
    for _ in range(passes if len(names) > 1 or start is None else 1):
        for nm in names:
            others = sum((deltas[o] for o in names if o != nm), np.zeros_like(e))
            yt = e - others
            s0w, s0u = block_ss(D, D.rows(yt))
            cc = cands[nm].cv(D, yt, D.p0 + others, s0w, s0u, folds=False)
            deltas[nm] = cc.delta
            joint[nm] = cc
    return joint


def heldout_path(D, cands, names: list[str], e: np.ndarray, joint: dict[str, Cand] | None = None) -> list[Cand]:
    """The effects ``names`` added in order, each cross-validated on what the ones before
    leave (the stepwise search's figures, at this linearisation).  With ``joint`` (their fits
    together, :func:`joint_fit`), the ones before leave what their joint fits leave: an
    effect whose prediction depends on the others' (the converter's rounding after an offset)
    is scored as the model holds it, not after fits that carried part of it."""
    out = []
    y = read_only(e)
    pcur = read_only(D.p0)
    for nm in names:
        s0w, s0u = block_ss(D, D.rows(y))
        c = score(D, cands[nm].cv(D, y, pcur, s0w, s0u), s0w, s0u)
        out.append(c)
        d = joint[nm].delta if joint is not None else (c.delta if c.gain > 0 else None)
        if d is not None:
            y = y - d
            pcur = pcur + d
    return out


def relinearise(device, cal, recs, K: int, seed: int, m0: float, cands, names: list[str],
                joint: dict[str, Cand], D0) -> dict[str, Any] | None:
    """Re-linearise the chosen effects ``names`` (fits ``joint`` about ``cal``) as the module
    doc says.  Returns None when none of them is a calibration parameter, or when, with a
    reference, each one absorbed is exact there (``Effect.exact_with_reference``: an offset,
    a gain), else a dict:
    ``params`` (name -> parameters from ``cal``), ``joint`` (the final fits), ``path`` (the
    held-out stepwise figures at the final point), ``iterations``, ``converged``, ``D``, ``e``,
    ``delta`` (the final fits' change of the readings together, the sum of their deltas)."""
    absorbed = [nm for nm in names if cands[nm].absorbs and nm in joint]
    if not absorbed or (D0.mode != "jigfree" and all(cands[nm].exact_with_reference for nm in absorbed)):
        return None
    tol = RELIN_TOL * float(np.min(D0.sigma))
    cal_k = cal
    converged = False
    it = 0
    best = None
    for it in range(1, RELIN_MAX + 1):
        for nm in absorbed:
            cal_k = cands[nm].absorb(cal_k, joint[nm].params)
        D = prepare(device, cal_k, recs, K, seed, m0)
        e = D.raw - D.p0
        setup_rows(D, e)
        joint = joint_fit(D, cands, names, e)
        total = sum((joint[nm].delta for nm in names), np.zeros_like(e))
        left = float(np.sum(D.W * D.rows(e - total) ** 2))     # in-sample weighted chi2 at this point
        if best is not None and left > best[0]:
            # the iteration runs away (an effect outside the chosen ones, a ramp of 6 % of g on the
            # MPU-6050's hand-turned poses, moved the pose forces further at each step): keep the
            # best point reached
            break
        best = (left, cal_k, D, e, joint, it, total)
        change = D.rows(sum((joint[nm].delta for nm in absorbed), np.zeros_like(e)))   # what the data see
        if float(np.max(np.abs(change))) < tol:
            converged = True
            break
    _, cal_k, D, e, joint, it, total = best
    final = cal_k
    for nm in absorbed:
        final = cands[nm].absorb(final, joint[nm].params)
    params = {nm: (cands[nm].params_between(cal, final) if nm in absorbed else joint[nm].params) for nm in names}
    return {"params": params, "joint": joint, "path": heldout_path(D, cands, names, e, joint), "iterations": it,
            "converged": converged, "D": D, "e": e, "delta": total}

