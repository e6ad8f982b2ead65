"""Can the data tell the verdict from its nearest rivals?  Nested held-out tests.

Two candidates A and B that both shrink the gap may explain the same part of it (a table
tilt and a drift on six poses each held once) or different parts (two effects at once).
The data tell them apart only through what one explains and the other cannot, so each is
scored on the residual the other leaves (:func:`conditional`, the same held-out test as
the stepwise search):

* A after B significant, B after A not, and A alone as large as B (within OCCAM_SHRINK,
  :func:`as_far`): A explains all B does and more; A is the verdict, unless B has fewer
  parameters, shrinks the gap as far and A's form holds B's change (the rule below, which
  does not hang on which of the two ranked first: an offset and a temperature through its
  lag at 0.516 each, the temperature's "more" each pose's rounding).  Two more exceptions: where both follow time and B is tied to a recorded covariate and A to
  time alone (:func:`tied`: a temperature through its lag against a drift's path, which also
  takes what the lag model misses), B stays the first step and A's rest is the next step's;
  and a path through many knots (``Effect.takes_pose_levels``) displaces B only where what it
  adds beyond B changes with time within the poses and at a repeated orientation (else its
  "more" is each pose's level: the ADC's rounding per pose).
* neither significant after the other, and their held-out gains alone within the
  uncertainty of each other (:func:`separable`): they explain the same thing; the data
  cannot tell them apart (``ambiguous_with``), and ``separate_by`` names the poses or
  motions that would (each effect's ``tell_apart``); the one with fewer parameters is the
  verdict when its held-out shrink alone is as large (within OCCAM_SHRINK).  A drift's path
  through many knots yields so to a simpler rival even where the gains are separable.
* both significant after the other: both act; the stepwise search names both.
* neither significant after the other, both following time, B tied to a recorded covariate
  and A to time alone (:func:`tied`): one change; B, the measured cause, is the verdict.
* B after A not significant, A after B significant, B with fewer parameters as large
  alone (within OCCAM_SHRINK), and A's form holds B's change (:func:`holds`): A is B plus
  more, so B is the first step and what A adds beyond it is the next step's to claim (a
  drift's path that also took an offset, a temperature-dependent gain that took a gain).
  Where A's form cannot hold B's, A explains all B does and more, and stays; so it does
  where both follow time and each holds the other's (:func:`one_change`: one change,
  described better by A, such as a temperature through its lag and a ramp), unless B is
  tied to a recorded covariate and A to time alone (:func:`tied`: the temperature that a
  drift's path follows is the measured cause, and the first step).

On data that cannot tell time from pose (:func:`time_separable`: static poses only, no
orientation held twice at different times), a time-dependent effect (drift, temperature)
is not claimed over a rival that varies by
pose (gain, misalignment, nonlinearity, pose_error; not offset, which is constant)
unless the data within the poses bear out the change it claims there
(:func:`within_pose_support`): six poses each held once let a drift take each pose's
level, so there a drift rests on what a table tilt explains too, and only the slope it
claims within each pose can tell them apart.  The verdict then
goes to the pose-dependent rival and the time-dependent effect is listed in
``ambiguous_with``; it is not added later in the stepwise search either.  Nor does a
time-dependent rival displace, by the nested test, a verdict that does not follow time (a
clip of one pose, which a drift's path takes as that pose's level) unless the poses bear
out its slope.  The same holds on data with a static orientation held twice at different
times (there the two holds' readings count as evidence too, :func:`within_pose_support`:
an effect of the orientation reads the same at both), and on any data for a drift fitted as a
path through many knots (``Effect.takes_pose_levels``), also against an offset: the path
takes each pose's level visited in turn, so what it adds beyond an offset may be a pattern
over the poses (a quantiser's error per pose).

A verdict tied to a recorded covariate whose readings change within the poses at least
1 / WITHIN_MIN times as much as it says lists the effects of time alone in ``ambiguous_with``
(a random-walk drift that a temperature through its lag follows only roughly).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..effects.fitdata import static_repeats, time_separable
from ..effects.fitting import Cand, block_ss
from .scoring import score, unit_sums

OCCAM_SHRINK = 0.02        # ... and the one with fewer parameters is chosen when it shrinks the gap as far (to this)
SEPARATE_T = 3.0           # paired block t of two candidates' held-out chi2 that tells them apart
RIVAL_GAIN_SHARE = 0.5     # rivals: significant candidates with at least this share of the best one's gain
MAX_RIVALS = 3             # ... at most this many, by gain
WITHIN_MIN = 0.5           # a time-dependent fit is borne out within the poses at >= this share of its claim ...
WITHIN_Z = 3.0             # ... and this many standard errors above 0
TIME_SHOWS = 0.2           # the readings change with time within the poses when a drift's path, fitted
                           # alone, is met there with a slope of either sign this large (and WITHIN_Z
                           # standard errors): a path that only took the poses' levels meets ~0 there
HOLDS_LEFT = 0.1           # one form holds another's change when it leaves at most this share of it


@dataclass
class Contest:
    """The outcome for the verdict: the chosen candidate, the rivals the data cannot tell
    from it, and the nested test of each rival (``tests``: name -> (rival after best
    significant, best after rival significant, their shrinks))."""

    best: Cand
    ambiguous: list[str] = field(default_factory=list)
    tests: dict = field(default_factory=dict)
    swapped_from: str | None = None
    why: str = ""
    #: the swap gave the first step to a simpler rival and left what the first-ranked adds beyond it
    #: to the next steps
    deferred: bool = False


def separable(D, a: Cand, b: Cand) -> bool:
    """Whether the held-out gains of ``a`` and ``b`` (first round, same blocks) differ beyond
    their uncertainty: the paired differences of their held-out chi2 have a t statistic of at
    least SEPARATE_T, over the same independent units as each gain's own t
    (:func:`~.scoring.unit_sums`: the blocks of one static pose summed).  Counted block by
    block, a pose's rounding, the same in all its blocks, had made an offset and a temperature
    offset through its lag (0.465 and 0.475, the temperature's "more" each pose's rounding)
    separable at t 3.11 (1.28 over the poses)."""
    d = unit_sums(D, np.asarray(b.Sw, float) - np.asarray(a.Sw, float))
    if d.size < 2:
        return False
    sd = float(np.std(d, ddof=1))
    if sd == 0.0:
        return bool(np.any(d != 0))
    return abs(float(np.mean(d))) / (sd / math.sqrt(d.size)) >= SEPARATE_T


def conditional(D, cands, name: str, given: Cand, y, pcur) -> Cand:
    """Candidate ``name`` scored on the residual ``y`` after ``given``'s in-sample fit."""
    yb = y - given.delta
    pb = pcur + given.delta
    S0w, S0u = block_ss(D, D.rows(yb))
    return score(D, cands[name].cv(D, yb, pb, S0w, S0u), S0w, S0u)


def within_pose_support(D, y, best: Cand, rival: Cand, repeats=(),
                        rival_at_repeats: bool = False) -> tuple[float, float]:
    """How far the data bear out a time-dependent fit where a pattern fixed per pose cannot
    stand in for it.

    The fit's change ``best.delta`` is compared with the residual left by the ``rival`` where
    a change with time shows apart from one with the pose: within each static segment (both
    less their segment means: the shape the fit claims there), and between the two static
    segments of each pair in ``repeats`` (:func:`static_repeats`: one orientation held at
    different times; the difference of their means, weighted by n1 n2 / (n1 + n2) samples;
    there the residual ``y`` itself, as an effect of the orientation reads the same at both
    and a rival fitted per hold, a tilt, would take the difference the drift claims; with
    ``rival_at_repeats`` the rival's residual there too, for a rival that follows time
    itself).  Returns the weighted slope ``a`` of the residual on the change (1: the data
    change there as the fit says; 0: they do not change at all) and its standard error.  A
    drift's path that took each pose's level (a table tilt, a quantiser's error per pose,
    identical at a repeat) has no slope there."""
    r = D.rows(y - rival.delta)
    r_rep = r if rival_at_repeats else D.rows(y)
    d = D.rows(best.delta)
    W = D.W
    num = den = 0.0
    for lo, hi in zip(D.seg_lo, D.seg_hi):
        if not D.static[lo] or hi - lo < 3:
            continue
        rw = r[lo:hi] - r[lo:hi].mean(axis=0)
        dw = d[lo:hi] - d[lo:hi].mean(axis=0)
        num += float(np.sum(W[lo:hi] * rw * dw))
        den += float(np.sum(W[lo:hi] * dw * dw))
    if len(repeats):
        # each segment's means once (a survey logger's 231 poses held 26,000 pairs of repeats)
        J, Kk = np.asarray(repeats, np.int64).T
        n = (D.seg_hi - D.seg_lo).astype(float)
        starts = D.seg_lo

        def seg_mean(A):
            return np.add.reduceat(A, starts, axis=0) / n[:, None]

        Wm, rm, dm = seg_mean(W), seg_mean(r_rep), seg_mean(d)
        w = 0.5 * (Wm[J] + Wm[Kk]) * (n[J] * n[Kk] / (n[J] + n[Kk]))[:, None]
        dd = dm[Kk] - dm[J]
        num += float(np.sum(w * (rm[Kk] - rm[J]) * dd))
        den += float(np.sum(w * dd * dd))
    if den <= 0:
        return 0.0, math.inf
    return num / den, 1.0 / math.sqrt(den)


def ruled_out(a: float, sa: float, repeats=()) -> bool:
    """Whether the data within the poses (and at the repeated orientations ``repeats``) rule out
    the change a time-dependent fit claims there: its slope on them ``a`` (:func:`within_pose_support`,
    with its standard error ``sa``) is below WITHIN_MIN by more than WITHIN_Z standard errors, with an orientation held
    again among the data (without one, a change made in the unrecorded turns between poses is
    not ruled out).  A drift that is not borne out is ambiguous with the verdict only where the
    data cannot rule it out (poses each held once); a tumble session that holds -x three times and -z twice met a
    drift's claim with -0.00 +- 0.00, and had been told to repeat a pose at the end."""
    if not len(repeats):
        # the slopes within the poses alone do not rule out a change made while the sensor was
        # turned between them (a step in the unrecorded turns): only an orientation held again does
        return False
    return a + WITHIN_Z * sa < WITHIN_MIN


def claims_time(D, y, best: Cand, rival: Cand, share: float = WITHIN_MIN, repeats=(),
                rival_at_repeats: bool = False) -> tuple[bool, str]:
    """A time-dependent fit ``best`` is claimed over a pose-dependent ``rival`` when the
    data within the poses (and at the repeated orientations ``repeats``) bear out its
    change there: slope >= ``share`` and >= WITHIN_Z standard errors
    (:func:`within_pose_support`).  ``share`` 0 asks only whether the data change within the
    poses as the fit does at all (its size then comes from a joint fit)."""
    return judged(best.name, *within_pose_support(D, y, best, rival, repeats, rival_at_repeats), share, repeats)


def judged(name: str, a: float, sa: float, share: float = WITHIN_MIN, repeats=()) -> tuple[bool, str]:
    """:func:`claims_time`'s verdict and words from the slope ``a`` (with its standard error
    ``sa``) that :func:`within_pose_support` found for the fit of effect ``name``."""
    ok = a >= share and a >= WITHIN_Z * sa
    where = "within the poses" + (" and at a repeated orientation" if len(repeats) else "")
    return ok, f"{where} the data change by {a:.2f} +- {sa:.2f} of what {name} claims there"


def contest(D, cands, best: Cand, first: dict[str, Cand], y, pcur) -> Contest:
    """Test ``best`` against its rivals among the first-round results ``first``."""
    rivals = sorted((c for c in first.values() if c.name != best.name and c.significant and c.gain > 0
                     and c.gain >= RIVAL_GAIN_SHARE * best.gain), key=lambda c: -c.gain)[:MAX_RIVALS]
    out = Contest(best=best)
    if best.gain <= 0:
        return out
    # without a repeated orientation (or motion) a drift can take each pose's level: then a
    # time-dependent effect must earn its claim beyond a pose-dependent rival where its change
    # shows apart from a pattern per pose (within_pose_support).  Where a static orientation is
    # held twice at different times, that is evidence of its own for any time-dependent claim (a
    # temperature term that took a gain and a pattern over the poses reads the same at both); and
    # a path through many knots is judged so on any data (it can take each pose's level)
    reps = static_repeats(D)
    judge_time = not time_separable(D) or bool(reps)
    b_path = cands[best.name].time_dependent and cands[best.name].takes_pose_levels(best)
    b_time = cands[best.name].time_dependent and (judge_time or b_path)
    b_pose = cands[best.name].varies_by_pose
    swap = None
    for c in rivals:
        c_after = conditional(D, cands, c.name, best, y, pcur)
        b_after = conditional(D, cands, best.name, c, y, pcur)
        out.tests[c.name] = {"rival_after_verdict": {"significant": c_after.significant, "shrink": c_after.shrink,
                                                     "gain_chi2": c_after.gain},
                             "verdict_after_rival": {"significant": b_after.significant, "shrink": b_after.shrink,
                                                     "gain_chi2": b_after.gain}}
        c_time = cands[c.name].time_dependent and (judge_time or cands[c.name].takes_pose_levels(c))
        c_pose = cands[c.name].varies_by_pose
        # a path is judged against a constant rival too: what it adds beyond an offset may be a
        # pattern over the poses (a quantiser's error per pose).  Where the data bear the time term
        # out, the nested tests below decide as for any two effects
        if b_time and (c_pose or (b_path and not cands[c.name].time_dependent)):
            ok, how = claims_time(D, y, best, c, repeats=reps)
            out.tests[c.name]["within_poses"] = how
            if not ok:
                # the time-dependent verdict rests on what a pose-dependent rival explains too; the
                # verdict goes to the strongest rival that does not follow time (an offset the drift
                # took along with each pose's level may be larger than the tilt)
                to = next(r for r in rivals if not cands[r.name].time_dependent)
                out.ambiguous.append(c.name if to.name == c.name else best.name)
                if swap is None:
                    swap = (to.name, f"{best.name} changes with time, but {how}: a time-dependent effect is not "
                                     f"claimed from data that cannot tell it from {c.name} (fixed per pose)")
                continue
        elif c_time and (b_pose or not cands[best.name].time_dependent):
            # a drift's path takes each pose's level: it does not displace a verdict that does not
            # follow time (a tilt, a clip of one pose) unless the poses bear out its slope
            a, sa = within_pose_support(D, y, c, best, reps)
            ok, how = judged(c.name, a, sa, repeats=reps)
            out.tests[c.name]["within_poses"] = how
            if not ok:
                if ruled_out(a, sa, reps):
                    out.tests[c.name]["ruled_out"] = True
                else:
                    out.ambiguous.append(c.name)
                continue
            if c_after.significant and not b_after.significant and swap is None and as_far(c, best):
                swap = (c.name, f"{c.name} explains all that {best.name} does and more, and {how}")
                continue
        if c_after.significant and not b_after.significant and swap is None and as_far(c, best):
            if tied(cands, best, c):
                # one change over time, the verdict tied to its measured cause (a temperature through
                # its lag) and the rival to time alone (a drift's path, which also takes what the lag
                # model misses): the measured cause is the first step, the path's rest the next one's
                continue
            if c_time and cands[c.name].takes_pose_levels(c):
                # a path's "more" may be each pose's level (a quantiser's or the ADC's rounding per
                # pose): it displaces the verdict only where what it adds changes with time there
                ok, how = claims_time(D, y, c_after, best, repeats=reps, rival_at_repeats=True)
                out.tests[c.name]["what_it_adds"] = how
                if not ok:
                    continue
            if (best.k < c.k and as_far(best, c) and holds(D, cands, c, best, pcur)
                    and not one_change(D, cands, best, c, pcur)):
                # the verdict is the simpler and shrinks the gap as far: it stays the first step and
                # what the rival adds beyond it is the next step's (as where the rival had ranked
                # first, below: the outcome does not hang on which of the two ranked first)
                continue
            swap = (c.name, f"{c.name} explains all that {best.name} does and more ({best.name} adds nothing "
                            "significant after it)")
        elif (not c_after.significant and b_after.significant and c.k < best.k
              and as_far(c, best) and swap is None and holds(D, cands, best, c, pcur)
              and not one_change(D, cands, c, best, pcur)):
            # the simpler rival explains as much alone and nothing beyond it is left to it: it is the
            # first step, and what the verdict adds beyond it is the next step's to claim (a drift's
            # path that also took an offset, or the temperature that a path follows)
            swap = (c.name, f"{c.name} explains as much of the gap alone with fewer parameters ({c.k} against "
                            f"{best.k}); what {best.name} adds beyond it is tested after it")
            out.deferred = True
        elif not c_after.significant and not b_after.significant and swap is None and tied(cands, c, best):
            # one change over time, neither adding anything after the other: the description tied to
            # its measured cause is the verdict (a drift's path that follows a temperature through
            # its lag, fitting it a little closer than the lag model)
            swap = (c.name, f"{c.name} and {best.name} describe one change (neither adds anything after the "
                            f"other); {c.name} follows the recorded {cands[c.name].covariate}, {best.name} time alone")
        elif not c_after.significant and not b_after.significant and (b_path or not separable(D, best, c)):
            # neither adds anything after the other: the same part of the gap (named together unless
            # their held-out gains differ beyond their uncertainty), and the simpler is the verdict
            # when it shrinks the gap as far; so for a path through many knots even where its gain
            # differs by a hair (a path that took an offset and a trace of the real Xsens
            # recording's own slow wander: 0.800 against 0.799)
            if not separable(D, best, c):
                out.ambiguous.append(c.name)
            if c.k < best.k and as_far(c, best) and swap is None:
                swap = (c.name, f"{c.name} explains the same part of the gap with fewer parameters "
                                f"({c.k} against {best.k})")
    if swap is None and cands[best.name].time_dependent and cands[best.name].covariate is not None:
        # a verdict tied to a recorded covariate (a temperature through its lag) whose readings change
        # within the poses far more than it says: what changes with time is not the covariate's
        # alone, and an effect of time alone (a drift) may be the cause
        a, sa = within_pose_support(D, y, best, Given(np.zeros_like(best.delta)))
        if a >= 1.0 / WITHIN_MIN and a - 1.0 >= WITHIN_Z * sa:
            how = f"within the poses the data change by {a:.2f} +- {sa:.2f} of what {best.name} claims there"
            for nm, eff in cands.items():
                if eff.time_dependent and eff.covariate is None and nm in first and nm not in out.ambiguous:
                    out.ambiguous.append(nm)
                    out.tests.setdefault(nm, {})["verdict_within_poses"] = how
    if swap is not None:
        name, why = swap
        out.swapped_from, out.why = best.name, why
        out.best = first[name]
        amb = [n for n in out.ambiguous if n != name]
        if name in out.ambiguous:
            amb = [best.name] + amb
        out.ambiguous = amb
    out.ambiguous = list(dict.fromkeys(out.ambiguous))
    v = out.best
    for nm, eff in cands.items():
        # effects that, on these data, cannot be told from the verdict beyond what the test shows
        if nm != v.name and nm not in out.ambiguous and v.name in eff.looks_like(D):
            out.ambiguous.append(nm)
    for nm in cands[v.name].alike(D, v):
        # ... or whose signature the verdict's fitted parameters have
        if nm in cands and nm != v.name and nm not in out.ambiguous:
            out.ambiguous.append(nm)
    return out


@dataclass
class Given:
    """A fitted change to condition on (:func:`conditional` reads only its delta)."""

    delta: np.ndarray


def as_far(c: Cand, best: Cand) -> bool:
    """Whether ``c`` alone shrinks the gap as far as ``best`` (within OCCAM_SHRINK).  Asked of
    a simpler rival before it takes the first step, and of a rival that explains "all the
    verdict does and more" by the nested tests: one that explains clearly less on its
    own (a temperature-dependent gain at 0.85 against the gain's 0.91) has taken part of
    the verdict's change and added something small; it is the next step's, not the verdict."""
    return c.shrink >= best.shrink - OCCAM_SHRINK


def tied(cands, a: Cand, b: Cand) -> bool:
    """Whether both follow time, ``a`` a recorded covariate (``Effect.covariate``:
    temperature) and ``b`` time alone (a drift): of two descriptions of one change, the one
    tied to a measurement is the more specific."""
    ea, eb = cands[a.name], cands[b.name]
    return ea.time_dependent and eb.time_dependent and ea.covariate is not None and eb.covariate is None


def one_change(D, cands, simple: Cand, best: Cand, pcur) -> bool:
    """Whether the time-dependent ``simple`` and ``best`` describe one change, ``best`` the
    better: each holds the other's (:func:`holds`), and ``simple`` is not the one tied to a
    measurement (:func:`tied`).  Then the simpler does not take the first step (a ramp
    against the temperature through its lag)."""
    return (cands[simple.name].time_dependent and cands[best.name].time_dependent
            and not tied(cands, simple, best) and holds(D, cands, simple, best, pcur))


def holds(D, cands, big: Cand, small: Cand, pcur) -> bool:
    """Whether ``big``'s form can take ``small``'s fitted change: ``big`` fitted to
    ``small.delta`` alone (no noise) leaves at most HOLDS_LEFT of its weighted energy.  A
    drift's path holds an offset; a temperature term through its lag does not hold a ramp
    (unless the temperature itself is one)."""
    target = small.delta
    total = float(np.sum(D.W * D.rows(target) ** 2))
    if total <= 0.0:
        return True
    fit = cands[big.name].refit(D, target, pcur, big)
    left = float(np.sum(D.W * D.rows(target - fit.delta) ** 2))
    return left <= HOLDS_LEFT * total


def model_ambiguity(cands, chosen: list[str], duel: Contest, ambiguous: list[str]):
    """What the whole stepwise model says about the verdict ``chosen[0]`` beyond its contest
    ``duel``: returns (names to add to ``ambiguous_with``, those of them ambiguous only as the
    level reached since the calibration, notes).

    * an effect in the model too, or one that the first contest found acting beside the
      verdict (significant after it in the nested test, where the verdict ranked first, and the
      change it claims with time not ruled out by the data: :func:`ruled_out`), whose
      level when the recording began makes the verdict's constant change
      (``Effect.reaches_level_of``: a drift since the calibration reads as an offset): the
      data do not say which the constant part is;
    * a first-ranked effect that yielded the first step to the simpler verdict
      (``Contest.deferred``), what it adds left to the next steps, and that is not in the model
      in the end: the model explains the gap as it alone does."""
    verdict, later = chosen[0], chosen[1:]
    add, reached, notes = [], [], []
    # (the nested tests are the verdict's own only where it ranked first; after a swap they are the
    # first-ranked's: a bend's rival drift, which an offset plus a gain would then list)
    beside = [] if duel.swapped_from else \
        [r for r, t in duel.tests.items() if t.get("rival_after_verdict", {}).get("significant")
         and not t.get("ruled_out")]
    for nm in later + beside:
        if verdict in cands[nm].reaches_level_of and nm not in ambiguous and nm not in add:
            add.append(nm)
            reached.append(nm)
            notes.append(f"{nm} " + ("is in the model too" if nm in later else f"acts beside {verdict} in the nested "
                                     "tests") + f": its level when the recording began reads as {verdict}, so the data "
                         f"cannot say how much of the {verdict} is {nm} reached since the calibration (a recording "
                         "that begins right after the calibration would)")
    a = duel.swapped_from
    if duel.deferred and a not in chosen and a not in ambiguous and a not in add:
        add.append(a)
        notes.append(f"{a} alone shrinks the gap as far as {verdict} and adds to it in the nested test, but what it "
                     "adds " + (f"went to {', '.join(later)}" if later else "was not significant as a later step")
                     + f": the data do not tell {' + '.join(chosen)} from {a}")
    return add, reached, notes


def time_unmodelled(D, y, first: dict[str, Cand], cands, chosen: list[str], ambiguous: list[str]):
    """Effects of time that the model leaves out although the readings change with time
    within the poses: returns (names to add to ``ambiguous_with``, notes).

    Where the model holds no term that follows time, each time-dependent effect that is
    significant alone is set against the verdict within the poses
    (:func:`within_pose_support` on the first residual ``y``).  A path that took only the
    poses' levels (what a pose-dependent verdict explains as well) meets a slope of ~0
    there; a slope of at least TIME_SHOWS of either sign, WITHIN_Z standard errors from 0,
    says that the readings do change with time inside the poses, and that the verdict may
    have taken the levels such a change left from pose to pose (on poses each held once, a
    bend's square term or an offset reads a drift's level per pose)."""
    if not chosen or any(cands[nm].time_dependent for nm in chosen):
        return [], []
    verdict = first.get(chosen[0])
    if verdict is None:
        return [], []
    add, notes = [], []
    for nm, c in first.items():
        if not cands[nm].time_dependent or not c.significant or c.gain <= 0 or nm in ambiguous:
            continue
        a, sa = within_pose_support(D, y, c, verdict)
        if abs(a) >= TIME_SHOWS and abs(a) >= WITHIN_Z * sa:
            add.append(nm)
            notes.append(f"the readings change with time within the poses ({nm} alone is met there with a slope of "
                         f"{a:.2f} +- {sa:.2f} of its path) but the model holds no term that follows time: "
                         f"{chosen[0]} may have taken the levels such a change left from pose to pose")
    return add, notes


def time_beside_pose(D, cands, chosen: list[str], ambiguous: list[str]):
    """Effects of time later in the model beside a verdict that varies by pose, on data that
    cannot tell time from pose (:func:`~accelcal.effects.fitdata.time_separable`: static poses
    only, no orientation held twice): returns (names to add to ``ambiguous_with``, notes).

    On poses each held once, the level a change with time reached at each pose is a pattern
    over the poses, which a verdict that varies by pose can take (a bend's square term took a
    drift's ramp through the MPU-6050's hand-turned poses, with the drift only third in the
    model); the drift's being in the model says the readings do change with time, so how much
    of the verdict's pattern is the drift's the data do not say."""
    if len(chosen) < 2 or not cands[chosen[0]].varies_by_pose or time_separable(D):
        return [], []
    add = [nm for nm in chosen[1:] if cands[nm].time_dependent and nm not in ambiguous]
    notes = [f"{nm} is in the model too, and no orientation is held twice: on poses each held once the level "
             f"{nm} reached at each pose is a pattern over the poses that {chosen[0]} can take, so the data do "
             f"not say how much of {chosen[0]} is {nm}" for nm in add]
    return add, notes

