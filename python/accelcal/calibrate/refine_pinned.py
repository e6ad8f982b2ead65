"""Which of ``refine``'s terms the recordings determine (docs/refine.md, "Only what the
recordings pin").

A term the recordings do not pin is a value the fit could move far without the residual
noticing: a temperature coefficient where the temperature hardly changes, a square law where
the readings stay near zero, a skew where nothing moves.  ``scipy``'s pseudo-inverse reads such a
direction of the fit as a 1-sigma of 0 (and keeps the start value, e.g. the diagnosis's); here
the covariance marks it infinite, and a term whose 1-sigma moves the readings by more than the
channel's 1 g across the recordings (the rule of ``calibrate``'s tempcos,
:func:`accelcal.calibrate.checks.undetermined_tempcos`) is left out of the refined calibration.
"""
from __future__ import annotations

import numpy as np

from .settings import TEMP_UNDETERMINED_G, TEMP_UNDETERMINED_GAIN

#: a direction of the column-normalised Jacobian whose singular value is below this fraction of
#: the largest is not determined at all (float64 rounding of an exact degeneracy: ~1e-16..1e-12)
NULL_RCOND = 1e-9
#: a time skew is determined when its 1-sigma is below this many sample periods (the fit's range
#: is +-4)
SKEW_SIGMA_PERIODS = 1.0

#: the groups of refine's parameter vector that are added terms, and their names in the text
TERM_GROUPS = {"k2": ("nonlinearity", "square term"), "k3": ("nonlinearity", "cube term"),
               "oc": ("temperature_offset", "offset tempco"), "gc": ("temperature_gain", "gain tempco"),
               "skew": ("time_skew", "time skew")}
#: each thermal lag and the tempco it belongs to
LAGS = {"tau_off": "oc", "tau_gain": "gc"}


def covariance(J, scale: float) -> np.ndarray:
    """(J^T J)^-1 times ``scale`` from the Jacobian ``J`` (dense or sparse), with an infinite
    variance on every parameter the Jacobian does not determine: a zero column, or a share of a
    direction whose singular value (columns normalised) is below NULL_RCOND of the largest."""
    J = J.toarray() if hasattr(J, "toarray") else np.asarray(J, float)
    norm = np.linalg.norm(J, axis=0)
    live = norm > 0
    cov = np.zeros((J.shape[1], J.shape[1]))
    var_inf = ~live
    if live.any():
        _, s, vt = np.linalg.svd(J[:, live] / norm[live], full_matrices=False)
        keep = s > NULL_RCOND * s[0]
        v = vt[keep].T / s[keep]
        sub = (v @ v.T) / np.outer(norm[live], norm[live])
        idx = np.flatnonzero(live)
        cov[np.ix_(idx, idx)] = sub
        if not keep.all():
            share = np.sum(vt[~keep] ** 2, axis=0)
            var_inf[idx[share > 1e-6]] = True
    cov *= scale
    cov[var_inf, var_inf] = np.inf
    return cov


def unpinned(model, x, sigma, free) -> dict:
    """The added terms' entries the recordings do not pin: {group: (bool mask over its entries,
    [reason per entry])}, only for the free entries of ``x``.

    A channel's offset tempco when its 1-sigma times the temperature's span exceeds
    TEMP_UNDETERMINED_G of the channel's 1 g; a gain tempco when it moves the gain by more than
    TEMP_UNDETERMINED_GAIN; a square or cube term when its 1-sigma at the channel's largest
    reading (m/s^2) moves it by more than 1 g; a skew whose 1-sigma exceeds SKEW_SIGMA_PERIODS
    sample periods; any entry with an infinite 1-sigma (not determined at all)."""
    L, rows, dev = model.L, model.rows, model.device
    use = rows.use
    one_g = np.abs(np.asarray(dev.counts_per_mps2, float)) * float(dev.gravity_mps2)
    b = L.get(x, "b")
    a = np.abs(rows.raw[use] - b) / np.abs(np.asarray(dev.counts_per_mps2, float))
    a_max = a.max(axis=0) if a.size else np.zeros(L.N)
    span_t = float(np.ptp(rows.temp[use])) if rows.temp is not None and use.any() else 0.0
    h = 1.0 / float(dev.sample_rate_hz)
    out = {}
    sigma = np.where(np.isfinite(sigma), sigma, np.inf)
    for name in TERM_GROUPS:
        if name not in L.groups:
            continue
        sl = L.groups[name][0]
        sd, fr = sigma[sl], free[sl]
        chans = L.per_channel[name]
        ch = np.arange(L.N) if chans is None else np.asarray(chans)
        if name in ("oc", "gc"):
            scale, what = span_t, ("counts over the temperature span" if name == "oc" else "of the gain over the span")
            limit = TEMP_UNDETERMINED_G * one_g[ch] if name == "oc" else np.full(ch.size, TEMP_UNDETERMINED_GAIN)
        elif name in ("k2", "k3"):
            scale, limit, what = a_max[ch] ** (2 if name == "k2" else 3), one_g[ch], "counts at the largest reading"
        else:
            scale, limit, what = 1.0, np.full(ch.size, SKEW_SIGMA_PERIODS * h), "s"
        with np.errstate(invalid="ignore"):     # an infinite 1-sigma times a zero span or reading
            moved = sd * scale
        moved = np.where(np.isfinite(sd), moved, np.inf)
        bad = fr & (moved > limit)
        if bad.any():
            reasons = [f"channel {int(c)}: 1-sigma moves it by {m:.3g} {what}" if np.isfinite(m) else ""
                       for c, m in zip(ch, moved)]
            out[name] = (bad, reasons)
    return out


def drop(model, unpin: dict, free, x0, given):
    """``free`` and ``x0`` with the unpinned entries fixed at ``given`` (the calibration's own
    value of a term it carries, else 0: no term), and each thermal lag fixed where its tempco's
    every channel is fixed."""
    free, x0 = free.copy(), x0.copy()
    L = model.L
    for name, (bad, _) in unpin.items():
        idx = np.arange(L.groups[name][0].start, L.groups[name][0].stop)[bad]
        free[idx] = False
        x0[idx] = given[idx]
    for lag, coeff in LAGS.items():
        if lag in L.groups and coeff in L.groups and not free[L.groups[coeff][0]].any():
            sl = L.groups[lag][0]
            free[sl] = False
            x0[sl] = given[sl]
    return free, x0


def describe(model, dropped: dict) -> str:
    """The sentence naming what was left out, or ""."""
    if not dropped:
        return ""
    parts = []
    for name, (bad, reasons) in dropped.items():
        chans = model.L.per_channel[name]
        ch = np.arange(model.L.N) if chans is None else np.asarray(chans)
        null = [str(int(c)) for c, r, b in zip(ch, reasons, bad) if b and not r]
        said = [r for r, b in zip(reasons, bad) if b and r]
        if null:
            said.insert(0, f"channel{'s' if len(null) > 1 else ''} {', '.join(null)}: not determined at all")
        parts.append(f"{TERM_GROUPS[name][1]} ({'; '.join(said)})")
    return (" Not determined by these recordings, so not fitted (the calibration's own value kept, else none): "
            + "; ".join(parts) + ".")
