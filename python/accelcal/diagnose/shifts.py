"""A change between recordings against a temperature effect (issue 33).

Where the recordings differ in temperature (the calibration's session at 25 degC, the diagnosed
one warmer) a constant shift of the diagnosed recording and a temperature effect read alike: the
temperature term takes the shift as its coefficient times the difference in temperature, and a
lag far beyond the recording's length makes it nearly constant within the recording.  What
tells them apart is change *within* a recording: a temperature effect follows the temperature
there, a shift between sessions does not.  So the nested held-out test decides
(:func:`shift_contest`): the temperature effect is scored on the residual the per-recording
shift leaves (:func:`~.compare.conditional`: the shift's in-sample fit removed, each recording's
own level and gain with it, against the noise floor's weights of the held-out test).  Where it
adds something significant there, it is preferred and the shift is the next step's to claim;
otherwise the shift is the verdict and the temperature effect is listed in ``ambiguous_with``
(``separate_by``: a pose held while the temperature changes slowly, or a recording at the
calibration's temperature).  The other rivals are judged by :func:`~.compare.contest` as ever.
"""
from __future__ import annotations

from ..effects.fitting import Cand
from .compare import RIVAL_GAIN_SHARE, Contest, as_far, conditional, contest


def between_recordings(eff) -> bool:
    """An effect that is one constant change per recording (``session_offset``, ``session_gain``)."""
    return bool(getattr(eff, "between_recordings", False))


def follows_covariate(eff) -> bool:
    """A time-dependent effect tied to a recorded covariate (the temperature effects)."""
    return bool(eff.time_dependent and eff.covariate is not None)


def shift_contest(D, cands, best: Cand, first: dict[str, Cand], y, pcur) -> Contest:
    """:func:`~.compare.contest`, with the rule above where the verdict is a shift between
    recordings or a temperature effect and the other is a significant rival; the test of each
    temperature effect after the shift is in ``tests`` (``after_shift``)."""
    eb = cands[best.name]
    shifts = sorted((c for c in first.values() if between_recordings(cands[c.name]) and c.significant
                     and c.gain > 0), key=lambda c: -c.gain)
    temps = [c for c in first.values() if follows_covariate(cands[c.name]) and c.significant and c.gain > 0
             and c.gain >= RIVAL_GAIN_SHARE * best.gain and c.name != best.name]
    if follows_covariate(eb):
        temps = [best] + temps
    if not shifts or not temps or not (between_recordings(eb) or follows_covariate(eb)):
        return contest(D, cands, best, first, y, pcur)
    shift = best if between_recordings(eb) else shifts[0]
    if follows_covariate(eb) and not any(as_far(c, best) for c in shifts):
        # every shift alone explains clearly less than the temperature effect: the general rules decide
        return contest(D, cands, best, first, y, pcur)
    tests, held, within = {}, [], []
    for tc in temps:
        # after each significant shift (an offset shift may take a drift's level, not a gain's change):
        # the temperature explains change within the recordings only where significant after all of them
        afters = [(sh, conditional(D, cands, tc.name, sh, y, pcur)) for sh in shifts]
        sh, after = min(afters, key=lambda a: (a[1].significant, a[1].gain))
        tests[tc.name] = {"after_shift": {"shift": sh.name, "significant": after.significant,
                                          "shrink": after.shrink, "gain_chi2": after.gain}}
        (within if after.significant else held).append(tc)
        if tc is best:
            shift = sh      # the shift that holds the temperature verdict's change
    if within:
        # a temperature effect explains change within the recordings beyond the shift: it is preferred
        # (the verdict if it ranked first, else the strongest such), the shifts are tested after it
        top = best if best in within else max(within, key=lambda c: c.gain)
        out = contest(D, cands, top, {k: v for k, v in first.items() if not between_recordings(cands[k])}, y, pcur)
        if top.name != best.name and out.swapped_from is None:
            out.swapped_from = best.name
            out.why = (f"{top.name} explains change within the recordings beyond {shift.name} (one shift per "
                       f"recording); what {shift.name} adds is tested after it")
    else:
        out = contest(D, cands, shift, {k: v for k, v in first.items() if k not in {c.name for c in held}}, y,
                      pcur)
        if shift.name != best.name and out.swapped_from is None:
            out.swapped_from = best.name
            out.why = (f"{best.name} explains nothing within the recordings beyond {shift.name} (one shift per "
                       f"recording): the change is between the recordings, and the temperature differs between "
                       f"them too")
        for tc in held:
            if tc.name != out.best.name and tc.name not in out.ambiguous:
                out.ambiguous.append(tc.name)
    for nm, t in tests.items():
        out.tests.setdefault(nm, {}).update(t)
    return out
