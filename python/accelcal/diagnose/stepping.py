"""One step of the diagnosis's stepwise search: the candidates the data cannot tell from the best
one (:func:`same_change`), a verdict that may take the calibration's terms at once measured
against them (:func:`terms_cover`), and the point the next step is scored on (:func:`next_point`)."""
from __future__ import annotations

import numpy as np

from ..effects import EFFECT_NAMES
from ..effects.fitting import Cand
from .compare import OCCAM_SHRINK, Contest, Given, claims_time, conditional, separable
from .relinearise import heldout_path, joint_fit, relinearise
from .scoring import rank_key
from .settings import TERMS_PASSES

__all__ = ["same_change", "terms_cover", "next_point"]


def terms_cover(dev, cal, recs, folds, seed, m0, cands, D, Dk, steps, results, remaining, duel, best, y, pcur):
    """A verdict whose fit can take parts of the calibration's terms at once
    (``Effect.mimics_calibration``: a cube of the input takes a part of a gain, of an offset
    and of a drift together, so it can rank above each of them alone) must explain something
    that the significant calibration candidates of this step (offset, gain, misalignment)
    cannot explain together, with the time-dependent candidates whose change the data within
    the poses bear out (:func:`~.compare.claims_time`: a long rest that shows a drift's slope;
    not the others: a drift's path through poses visited in turn can take any pattern over
    the poses, a bend too).  Jig-free the chosen
    effects and the terms are folded into the calibration (:func:`relinearise`: far from the
    truth the residual holds the calibration's error to second order, which the bend takes
    too); with a reference the terms are fitted together (:func:`joint_fit`, TERMS_PASSES
    passes).  Returns the contest and the verdict, swapped to the strongest calibration term
    when they leave nothing significant to it, or, with a time-dependent candidate among
    them or a verdict with a freedom of its own per pose (``Effect.free_per_pose``: a tilt of
    each pose takes the other channels' offsets and a misalignment at once), when they shrink
    the held-out gap as far as it does (within OCCAM_SHRINK): then they are the first step and
    what the verdict adds beyond them is the next step's to claim."""
    terms = sorted((c for c in results.values() if c.name != best.name and c.significant and c.gain > 0
                    and c.name in remaining and cands[c.name].absorbs), key=rank_key)
    if not terms:
        return duel, best
    # a time-dependent candidate joins them where the data within the poses change as it does
    # (a long rest that shows a drift's slope; its size comes from the joint fit): then the bend
    # cannot claim the drift's part either
    timed = []
    beside = None
    for c in sorted(results.values(), key=rank_key):
        if not (c.name != best.name and c.significant and c.gain > 0 and c.name in remaining
                and cands[c.name].time_dependent):
            continue
        ok = claims_time(Dk, y, c, best, share=0.0)[0]
        if not ok:
            # fitted alone, a drift's ramp over poses visited in turn also takes the pattern a
            # gain leaves over them, and its change within the poses can then run against the
            # data's (the MPU-6050's 6 %-of-g ramp beside a gain: -0.25 of what it claimed);
            # fitted beside the terms, it is asked again
            if beside is None:
                pre = joint_fit(Dk, cands, [t.name for t in terms], y, start={t.name: t for t in terms},
                                passes=TERMS_PASSES)
                beside = Given(sum((f.delta for f in pre.values()), np.zeros_like(y)))
            c2 = conditional(Dk, cands, c.name, beside, y, pcur)
            ok = c2.significant and c2.gain > 0 and claims_time(Dk, y, c2, beside, share=0.0)[0]
        if ok:
            timed.append(c)
    joined = terms + timed
    start = {c.name: c for c in joined}
    names = list(start)
    # the terms fitted together: each one's fit alone took the same part of the gap, and folding
    # all of them into the calibration at once overshoots (a 14 % gain on the MPU-6050 recording:
    # the re-linearisation ran away to 70 x the gap)
    together_fit = joint_fit(Dk, cands, names, y, start=start, passes=TERMS_PASSES)
    # where the bend is judged: jig-free, about the calibration corrected by the chosen effects
    # and the terms (re-linearised); where that re-linearisation did not converge (kept at its
    # best point, still off: the MPU-6050's 6 %-of-g ramp beside a gain, 1,578 counts held out
    # before it and 5,033 after) also at this step's linearisation, as with a reference.  The
    # bend keeps the step only where it holds at every point judged
    points = []
    if Dk.mode == "jigfree":
        fits = {c.name: c for c, _ in steps}
        fits.update(together_fit)
        rl = relinearise(dev, cal, recs, int(folds), int(seed), m0, cands,
                         [c.name for c, _ in steps if c.gain > 0] + names, fits, D)  # terms absorb: not None
        after = conditional(rl["D"], cands, best.name, Given(rl["delta"]), rl["e"], rl["D"].p0)
        points.append((after, rl["path"][-1].after))
    if Dk.mode != "jigfree" or not rl["converged"]:
        done = sum((together_fit[nm].delta for nm in names), np.zeros_like(y))
        after = conditional(Dk, cands, best.name, Given(done), y, pcur)
        points.append((after, heldout_path(Dk, cands, names, y)[-1].after))
    # with a drift among them, the terms' own held-out figure (with the steps before, at the final
    # linearisation): as far as the verdict goes, they are the first step, and what it adds beyond
    # them comes later (a bend that took a drift's pattern over the poses along with a gain); without
    # one, a bend that adds anything significant beyond the terms is a bend (a cube is mostly a gain)
    together = ' and '.join(c.name for c in joined)
    for after, terms_after in points:
        terms_shrink = 1.0 - terms_after / best.before if best.before > 0 else 0.0
        if not after.significant or ((timed or cands[best.name].free_per_pose)
                                     and terms_shrink >= best.shrink - OCCAM_SHRINK):
            break
    else:
        return duel, best
    if after.significant:
        why = (f"{together} together shrink the gap as far (held-out {terms_shrink:.3f} against "
               f"{best.shrink:.3f} for {best.name}); what {best.name} adds beyond them "
               f"({after.shrink:.3f}) is tested after them")
    else:
        why = (f"{together} together leave nothing significant to {best.name} "
               f"(held-out shrink {after.shrink:.3f} after them)")
    tests = dict(duel.tests, together={"terms": [c.name for c in joined], "verdict_after_them": after.shrink})
    # nothing significant left to the verdict after the terms: on these poses the data cannot tell
    # the two descriptions apart (a cube on poses near the axes is a gain)
    amb = [best.name] if not after.significant else []
    # the step goes to the strongest term -- or to a term with fewer parameters that shrinks the gap
    # as far (within OCCAM_SHRINK), the others the data cannot tell from it named with it (a real
    # x-IMU in one orientation, |f| 2.7 % short: a tilt of one axis by 35.6 deg had outranked an
    # offset and a gain by 0.00007 of shrink) -- unless a candidate proven on its own evidence (a
    # lattice of coarse steps, a pile of clipped readings) ranks above it: the MPU-6050 with
    # 512-count steps, whose lattice ranked between the bend and the offset
    nxt = terms[0]
    simpler = [c for c in terms if c.k < nxt.k and c.shrink >= nxt.shrink - OCCAM_SHRINK]
    if simpler:
        nxt = min(simpler, key=lambda c: (c.k, EFFECT_NAMES.index(c.name)))
        amb += [c.name for c in terms if c is not nxt and c.shrink >= nxt.shrink - OCCAM_SHRINK
                and not separable(Dk, nxt, c) and c.name not in amb]
    proven = min((c for c in results.values() if c.proof and c.significant and c.gain > 0 and c.name != best.name
                  and c.name in remaining), key=rank_key, default=None)
    if proven is not None and rank_key(proven) < rank_key(nxt):
        nxt = proven
        why += f"; {nxt.name}, proven by {nxt.evidence}, ranks above them"
    return Contest(best=nxt, ambiguous=amb, swapped_from=best.name, why=why, tests=tests), nxt


def next_point(dev, cal, recs, folds, seed, m0, cands, steps, best, Dk, y, pcur):
    """The data, residual and prediction the next step is scored on: jig-free, after a change of
    the calibration itself (``Effect.absorbs``), about the corrected calibration (new pose
    forces), not on the first linearisation's residual; else as they are."""
    if Dk.mode == "jigfree" and best.gain > 0 and cands[best.name].absorbs:
        now = [c.name for c, _ in steps if c.gain > 0]
        rl = relinearise(dev, cal, recs, int(folds), int(seed), m0, cands, now, {c.name: c for c, _ in steps}, Dk)
        return rl["D"], rl["e"] - rl["delta"], rl["D"].p0 + rl["delta"]
    return Dk, y, pcur


def same_change(D, best: Cand, cands: list[Cand], rtol: float = 1e-6) -> list[Cand]:
    """The candidates (other than ``best``) whose in-sample change of every reading, as the data
    see it (``D.rows``: jig-free, the directions the poses' angles cannot absorb), is ``best``'s
    within ``rtol`` of its size: the data cannot tell them apart at all.  (Jig-free on one
    orientation an offset, a gain, a bend and a tilt of the axes all move |f| alike; compared
    before the projection their changes differ where the data do not look, and a real x-IMU's
    2.7 % short |f| had come out as a 35.6 deg tilt of one axis, with no rival named.)"""
    rb = D.rows(best.delta)
    size = float(np.linalg.norm(rb))
    if size == 0.0:
        return []
    return [c for c in cands if c is not best and c.delta.shape == best.delta.shape
            and float(np.linalg.norm(D.rows(c.delta) - rb)) <= rtol * size]
