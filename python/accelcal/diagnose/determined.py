"""Which of an effect's parameters the data determine at all.

Jig-free the pose angles absorb the directions of channel space across each pose's force, and
what is left may fix only combinations of the per-channel parameters (a board held in one
orientation sees |f| alone: the gains of the axes that never see gravity are not measured).
The fit then reports the smallest change that fits (min-norm), and its covariance is that of
the combinations fixed, so a 1-sigma read off it for a parameter the data do not see is no
measurement (a real x-IMU's x and y gains had been -2.705 +- 0.017 %, the same figure as z's).
A parameter is *not determined* when less than half of its own direction (squared norm, in the
parameters scaled as the fit scales them) lies in the space the fit keeps (eigenvalues of the
scaled normal matrix above SEEN_MIN of the largest, as :func:`accelcal.effects.fitting.linear_fit`
keeps them); its sigma is then reported as null and the parameter named in ``not_determined``.
For the one-parameter-a-channel linear effects (``offset``, ``gain``).
"""
from __future__ import annotations

import numpy as np

from ..effects.fitdata import FitData
from ..effects.fitting import LinearCandidate, jig_rows, kept_space
from ..effects.settings import SEEN_MIN
from .text import describe

__all__ = ["DETERMINED_SHARE", "JUDGED", "not_determined", "mark_not_determined"]

DETERMINED_SHARE = 0.5     # share of a parameter's direction (squared) the kept space must hold
JUDGED = ("offset", "gain")  # one column a channel (LinearCandidate.columns)


def not_determined(D: FitData, effect) -> dict | None:
    """{param name: [channels]} of ``effect``'s parameters the data do not determine, or None
    (reference data, where each channel's parameter is fitted on its own, or an effect of
    another form)."""
    if D.Qp is None or not isinstance(effect, LinearCandidate) or effect.name not in JUDGED:
        return None
    X = effect.columns(D)
    if X.ndim != 3 or X.shape[2] != 1:
        return None
    Xr = jig_rows(D, X)                                        # (n, R, N)
    Xw = Xr * np.sqrt(D.W)[:, :, None]
    G = np.einsum("trp,trq->pq", Xw, Xw)
    _, V, keep, _ = kept_space(G, np.sqrt(np.einsum("tnk,tnk->n", X, X)), SEEN_MIN)
    share = np.sum(V[:, keep] ** 2, axis=1)
    out = np.flatnonzero(share < DETERMINED_SHARE)
    return {effect.pname: [int(i) for i in out]} if out.size else None


def mark_not_determined(D: FitData, cands, entry: dict, model_sigma: dict | None = None) -> None:
    """Null the 1-sigma of the parameters of a result entry (and of the model's, ``model_sigma``:
    {effect: {param: sigma}}) that the data do not determine, name them in
    ``entry["not_determined"]`` and say so in its summary."""
    nd = not_determined(D, cands[entry["name"]])
    if nd is None:
        return
    entry["not_determined"] = nd
    for pname, chans in nd.items():
        for sig in [entry["params_sigma"]] + ([model_sigma[entry["name"]]] if model_sigma
                                              and entry["name"] in model_sigma else []):
            s = list(sig[pname])
            for i in chans:
                s[i] = None
            sig[pname] = s
    chans = sorted({i for v in nd.values() for i in v})
    nan = {k: np.array([np.nan if x is None else x for x in v], float) for k, v in entry["params_sigma"].items()
           if k in nd}
    with np.errstate(invalid="ignore"):
        said = describe(entry["name"], {k: np.asarray(v, float) for k, v in entry["params"].items() if k in nd},
                        nan, D)
    entry["summary"] = said.replace(" +- nan", "") + (f"; not determined by these data on channel(s) {', '.join(map(str, chans))} (the poses "
                         "fix only combinations there: the figure is the smallest change that fits, no sigma)")
