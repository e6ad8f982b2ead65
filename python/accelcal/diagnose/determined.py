"""Which of an effect's parameters the data determine at all.

Jig-free the pose angles absorb the directions of channel space across each pose's force, and
what is left may fix only combinations of the parameters (a board held in one orientation sees
|f| alone: the gains of the axes that never see gravity are not measured; six face poses see no
misalignment at all, and any set of poses no common rotation of the axes).  With a reference a
column the poses never excite fixes nothing either (on poses along the axes alone a cube is a
gain, and the fit carries no cube there; a channel's tilt toward an axis no pose's force has a
component along).  The fit then reports the smallest change that fits (min-norm), and its
covariance is that of the combinations fixed, so a 1-sigma read off it for a parameter the data
do not see is no measurement (a real x-IMU's x and y gains had been -2.705 +- 0.017 %, the same
figure as z's; a cube held at 0 +- 0).

One rule for every parameter of every linear effect (``LinearCandidate.param_columns``: the
columns its fit solved for and the map from their coefficients to each reported value): a value
is *not determined* when less than DETERMINED_SHARE of its own direction (squared norm, in the
parameters scaled as the fit scales them) lies in the space the data see
(:func:`accelcal.effects.fitting.seen_space`: kept by the fit's cut and, jig-free, keeping at
least SEEN_MIN of its change through the poses' projection).  Its sigma is then reported as null
and the value named in ``not_determined``.
"""
from __future__ import annotations

import re

import numpy as np

from ..effects.base import as_float_array
from ..effects.fitdata import FitData
from ..effects.fitting import LinearCandidate, seen_space
from .text import describe

__all__ = ["DETERMINED_SHARE", "not_determined", "mark_not_determined"]

#: share of a value's direction (squared) the seen space must hold.  Not a half: jig-free the poses
#: absorb a common rotation of the axes, which takes about half of each single tilt (0.38-0.63 of
#: them on 24 general poses): a half would name some of a set of equally undetermined tilts and not
#: the others.  At 0.9 at most a tenth of a determined value's direction is one the data do not see
DETERMINED_SHARE = 0.9


def not_determined(D: FitData, effect, params: dict) -> dict | None:
    """{param name: [channels]} (or [[channel, component]] for a parameter with several values a
    channel, as ``rot``) of the values of ``effect``'s fit ``params`` the data do not determine,
    or None (none, or an effect whose fit is no linear least squares).  A value the effect's form
    fixes (a tilt's part along the axis itself: a map of zeros) is no parameter and not judged."""
    got = _judged(D, effect, params)
    if got is None:
        return None
    out = {pname: bad for pname, (bad, _) in got.items() if bad}
    return out or None


def _judged(D: FitData, effect, params: dict) -> dict | None:
    """{param name: (values not determined, values judged)} as :func:`not_determined` lists
    them, or None for an effect whose fit is no linear least squares."""
    if not isinstance(effect, LinearCandidate):
        return None
    got = effect.param_columns(D, params)
    if got is None:
        return None
    X, maps = got
    k = X.shape[2]
    V, seen, d = seen_space(D, X)
    per_channel = D.Qp is None
    out = {}
    for pname, A in maps.items():
        A3 = A[:, :, None] if A.ndim == 2 else A                      # (N, k, m)
        bad, judged = [], []
        for i in range(D.N):
            g, lo = (i, 0) if per_channel else (0, i * k)
            Vs = V[g][:, seen[g]]
            for c in range(A3.shape[2]):
                w = np.zeros(V.shape[1])
                w[lo:lo + k] = A3[i, :, c] / d[g, lo:lo + k]         # the value as a functional of the scaled fit
                ww = float(w @ w)
                if ww == 0.0:
                    continue
                where = i if A.ndim == 2 else [i, c]
                judged.append(where)
                if float(np.sum((Vs.T @ w) ** 2)) < DETERMINED_SHARE * ww:
                    bad.append(where)
        out[pname] = (bad, judged)
    return out


def _null(sig: list, where: list) -> list:
    """``sig`` (a JSON list, one value or one list of values a channel) with the sigmas at
    ``where`` (channels, or [channel, component]) set to None."""
    s = [list(v) if isinstance(v, list) else v for v in sig]
    for w in where:
        if isinstance(w, list):
            s[w[0]][w[1]] = None
        else:
            s[w] = None
    return s


def mark_not_determined(D: FitData, cands, entry: dict, model_sigma: dict | None = None) -> None:
    """Null the 1-sigma of the parameters of a result entry (and of the model's, ``model_sigma``:
    {effect: {param: sigma}}) that the data do not determine, name them in
    ``entry["not_determined"]`` and say so in its summary.  The summary's figure is then that of
    the values the data determine (the others set to 0 for it); where they determine none, the
    summary begins with that and gives the figure as what it is: the smallest change that fits
    (min-norm), no measurement."""
    got = _judged(D, cands[entry["name"]], entry["params"])
    nd = None if got is None else {pname: bad for pname, (bad, _) in got.items() if bad}
    if not nd:
        return
    entry["not_determined"] = nd
    sigmas = [entry["params_sigma"]] + ([model_sigma[entry["name"]]] if model_sigma and entry["name"] in model_sigma
                                        else [])
    for sig in sigmas:
        for pname, where in nd.items():
            sig[pname] = _null(sig[pname], where)
    which = "; ".join(f"{p} on channel(s) {', '.join(map(str, _once(where)))}" for p, where in nd.items())
    none_seen = all(len(bad) == len(judged) for bad, judged in got.values())
    params = _floats(entry["params"])
    if not none_seen:
        params = {k: _zeroed(v, nd[k]) if k in nd else v for k, v in params.items()}
    with np.errstate(invalid="ignore"):
        said = re.sub(r" ?\(\+- nan\)| \+- nan", "", describe(entry["name"], params, _floats(entry["params_sigma"]), D))
    if none_seen:
        entry["summary"] = (f"not determined by these data: {which} (the poses fix at most combinations there, no "
                            f"sigma); the fit's figure, no measurement (the smallest change that fits where the data fix "
                            f"nothing): {said}")
    else:
        entry["summary"] = (f"{said}; not determined by these data: {which} (the poses fix at most combinations "
                            "there: left out of the figure, no sigma)")


def _zeroed(v: np.ndarray, where: list) -> np.ndarray:
    """``v`` (one value or one row of values a channel) with the values at ``where`` (channels,
    or [channel, component]) set to 0."""
    v = np.array(v, float)
    for w in where:
        v[tuple(w) if isinstance(w, list) else w] = 0.0
    return v


def _floats(p: dict) -> dict:
    """A JSON parameter dict with its lists as float arrays (null as NaN) for the prose."""
    return {k: as_float_array(v) if isinstance(v, list) else v for k, v in p.items()}


def _once(where: list) -> list:
    """The channels of ``where`` (channels or [channel, component]), each once, in order."""
    seen = []
    for w in where:
        c = w[0] if isinstance(w, list) else w
        if c not in seen:
            seen.append(c)
    return seen
