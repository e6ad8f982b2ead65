"""What the chosen model leaves beyond the noise: the contract's ``unexplained``.

The residual after the model (its joint in-sample fit), in the rows the diagnosis scores,
is split into noise and a systematic part:

* noise: the scatter within static segments about their own means (the dof-weighted mean
  of the segment variances, so hand tremor and coloured noise at rest count as noise);
  without static segments, the noise floor; plus, for the static poses' samples, the
  rounding's bias of a pose's mean (:func:`~.floor.pose_rounding_var`: up to half a code
  where the noise does not dither the rounding, which the scatter within a pose on one code
  does not show); less the power of narrow spectral lines
  (:func:`spectral_lines`: a tone or a resonance is not noise however steady it is);
* systematic: the static segments' means beyond what that scatter gives a mean
  (sum of n m^2 minus the sum of the variances), plus the moving samples' energy beyond
  the scatter.

The held-out figure is then ``heldout_rms_left = sqrt(max(after^2 - noise^2, 0))`` with
``after`` the model's held-out RMS, and ``fraction = heldout_rms_left^2 / before^2``, its
share of the held-out gap's energy.  It is reported (not ``null``) when it is at least
LEFT_MIN_RATIO of the noise (the residual at least 1.118 x the noise), however small a
share of the gap: what a sensor effect of another shape (a resonance, mains pickup) or
motion the model does not follow would leave.  ``where`` names the channels, the frequency band
and the regime in which it lies, and for static data the poses.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import signal, stats
from scipy.ndimage import median_filter

from ..effects.fitdata import FitData
from .floor import pose_var_rows
from .where import where_breakdown

LEFT_MIN_RATIO = 0.5       # left at least this x the noise (the residual >= 1.118 x the noise)
LINE_NPERSEG = 256         # Welch segment (samples) of the spectral-line test, at most ...
LINE_MIN_NPERSEG = 32      # ... and at least
LINE_BACKGROUND_BINS = 17  # running-median width (bins) of the smooth spectrum a line stands out of
LINE_FALSE_ALARM = 1e-3    # chance that noise alone puts one bin over the line threshold (per channel)


def spectral_lines(D: FitData, e_after: np.ndarray) -> dict | None:
    """Narrow peaks in the residual's spectrum: tones and resonances that sit in the static
    stretches as much as in motion, where the scatter test takes them for noise.

    Per channel, the Welch spectrum (segments of LINE_NPERSEG samples within contiguous
    runs) against its running median over LINE_BACKGROUND_BINS bins; bins above the
    median by more than the chi2 quantile that noise alone exceeds with probability
    LINE_FALSE_ALARM over all bins are a line.  Returns the lines' power beyond the
    background (rms, counts) and where they are, or None."""
    fs = 1.0 / D.h
    lens = D.seg_hi - D.seg_lo
    if lens.size == 0 or lens.max() < LINE_MIN_NPERSEG:
        return None
    # Welch segments as long as the typical run allows (a power of two, LINE_MIN_NPERSEG..LINE_NPERSEG)
    L = int(min(LINE_NPERSEG, 2 ** int(math.log2(max(np.median(lens[lens >= LINE_MIN_NPERSEG]), 1)))))
    acc = None
    nseg = 0
    for a, b in zip(D.seg_lo, D.seg_hi):
        if b - a < L:
            continue
        f, P = signal.welch(e_after[a:b], fs=fs, nperseg=L, axis=0, detrend="constant")
        k = (b - a) // (L // 2) - 1
        acc = P * k if acc is None else acc + P * k
        nseg += k
    if acc is None or nseg < 2:
        return None
    P = acc / nseg                                           # (F, N) counts^2 / Hz
    # mirrored at the ends: a tone in the last (Nyquist) bin must not be its own background
    bg = median_filter(P, size=(LINE_BACKGROUND_BINS, 1), mode="mirror")
    dof = 2.0 * nseg
    ratio = stats.chi2.ppf(1.0 - LINE_FALSE_ALARM / P.shape[0], dof) / dof
    ratio /= stats.chi2.median(dof) / dof                    # the background is a median
    line = P > ratio * bg
    line[0] = False                                          # DC: offsets, not lines
    if not line.any():
        return None
    df = f[1] - f[0]
    excess = np.where(line, P - bg, 0.0).sum(axis=0) * df    # counts^2 per channel
    rms = math.sqrt(float(np.mean(excess)))
    j = np.unravel_index(np.argmax(np.where(line, P - bg, 0.0)), P.shape)
    return {"rms_counts": rms, "rms_per_channel": np.sqrt(excess).tolist(), "peak_hz": float(f[j[0]]),
            "channels": [int(i) for i in np.flatnonzero(line.any(axis=0))], "line_bins": int(line.sum())}


def _split(D: FitData, A: np.ndarray, floor2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per column of ``A`` (n, m): noise variance, systematic energy, and the moving share of it."""
    m = A.shape[1]
    dof = np.zeros(m)
    ss_in = np.zeros(m)
    sys_static = np.zeros(m)
    moving = np.ones(D.n, bool)
    for a, b in zip(D.seg_lo, D.seg_hi):
        if not D.static[a] or b - a < 3:
            continue
        x = A[a:b]
        mu = x.mean(axis=0)
        v = x.var(axis=0, ddof=1)
        L = b - a
        dof += L - 1
        ss_in += (L - 1) * v
        sys_static += L * mu * mu - v
        moving[a:b] = False
    noise2 = ss_in / dof if np.all(dof > 0) else floor2
    sys_moving = np.sum(A[moving] ** 2, axis=0) - np.count_nonzero(moving) * noise2
    return noise2, sys_static + sys_moving, sys_moving


def leftover(D: FitData, e_after: np.ndarray, before: float, after: float) -> dict | None:
    """The contract's ``unexplained`` object for the model that leaves the residual
    ``e_after`` (n, N; held-out RMS of the gap ``before`` -> ``after``, counts), or None when
    what is left is noise (see the module doc)."""
    if before <= 0:
        return None
    Ra = D.rows(e_after)
    floor2_rows = np.mean(D.sigma ** 2) * np.ones(Ra.shape[1])
    noise2, _, _ = _split(D, Ra, floor2_rows)
    # a static pose's mean is off by the rounding's bias too (up to half a code where the noise does
    # not dither it): no effect, noise of the pose's level that the scatter within it does not show
    noise2 = noise2 + pose_var_rows(D).sum(axis=0) / D.n
    noise = math.sqrt(float(np.mean(noise2)))
    lines = spectral_lines(D, e_after)                     # channel space: where the lines are
    rows_lines = lines if D.Qp is None else spectral_lines(D, Ra)   # the scored rows: how much they weigh
    tone = rows_lines["rms_counts"] if rows_lines is not None else 0.0
    noise = math.sqrt(max(noise * noise - tone * tone, 0.0))        # the scatter held the lines too
    left = math.sqrt(max(after * after - noise * noise, 0.0))
    # a line counts on its own channel: it may stand well above that channel's noise and still be
    # a small part of the average over channels
    n2c, sys_c, mov_c = _split(D, e_after, D.sigma ** 2)
    n2c = n2c + (0.0 if D.pose_var is None else D.pose_var * np.count_nonzero(D.pose >= 0) / D.n)
    line_ch = np.asarray(lines["rms_per_channel"]) if lines is not None else np.zeros(D.N)
    loud_line = bool(np.any(line_ch >= LEFT_MIN_RATIO * np.sqrt(np.maximum(n2c - line_ch ** 2, 1e-300))))
    if loud_line:
        left = max(left, tone)
    fraction = left * left / (before * before)
    if left < LEFT_MIN_RATIO * max(noise, 1e-300) and not loud_line:
        return None
    # where: by channel (channel space), band, regime, poses
    rms_left_ch = np.sqrt(np.maximum(sys_c, 0.0) / D.n)
    top = float(rms_left_ch.max())
    channels = [int(i) for i in np.argsort(-rms_left_ch) if rms_left_ch[i] >= 0.25 * top and top > 0]
    w = where_breakdown(D, e_after)
    bands = [b for b in w["frequency_bands"] if b["rms_counts"] is not None]
    ex = [b["rms_counts"] ** 2 - b["white_noise_rms_counts"] ** 2 for b in bands]
    band = bands[int(np.argmax(ex))]["label"] if bands else None
    regs = w["static_vs_rotating"]
    rex = [r["n"] * (r["rms_counts"] ** 2 - noise * noise) for r in regs]
    regime = regs[int(np.argmax(rex))]["label"] if regs else None
    if lines is not None and tone * tone >= 0.5 * left * left:
        channels = lines["channels"]
        band = f"a line at {lines['peak_hz']:.3g} Hz"
    out = {"heldout_rms_left": left, "fraction": fraction, "noise_counts": noise, "lines": lines,
           "where": {"channels": channels, "rms_left_per_channel": rms_left_ch.tolist(), "band": band,
                     "regime": regime,
                     "moving_share": float(np.sum(np.maximum(mov_c, 0)) / max(np.sum(np.maximum(sys_c, 0)), 1e-300))}}
    if "poses" in w and regime == "static":
        out["where"]["poses"] = [p["label"] for p in w["poses"][:3]]
    return out


def with_settling(left: dict | None, ring: dict | None, D: FitData, before: float) -> dict | None:
    """The ``unexplained`` object with a ringing after the stops (:mod:`.settling`) added.

    The ringing lies in samples the model does not score (the ends of the motions), so it
    has no held-out figure of its own: ``heldout_rms_left`` is then its rms in the settling
    windows (counts) and ``fraction`` its energy's share of its own plus the scored gap's
    (``before``, held-out rms over the D.n x D.R scored rows).  An existing object keeps its
    figures and ``where`` and gains the ``settling`` entry."""
    if ring is None:
        return left
    if left is not None:
        return {**left, "settling": ring}
    n_ring = ring["n_stops"] * ring["window_s"] / D.h * D.N
    e_ring = ring["rms_counts"] ** 2 * n_ring
    e_gap = before * before * D.n * D.R
    return {"heldout_rms_left": ring["rms_counts"], "fraction": e_ring / max(e_ring + e_gap, 1e-300),
            "noise_counts": float(np.sqrt(np.mean(D.sigma ** 2))), "lines": None, "settling": ring,
            "where": {"channels": ring["channels"], "rms_left_per_channel": ring["rms_per_channel"],
                      "band": f"a line at {ring['peak_hz']:.3g} Hz",
                      "regime": f"settling: the last {ring['window_s']:.2g} s before each of {ring['n_stops']} "
                                "rests (not at the motions' starts nor within the rests)",
                      "moving_share": 1.0}}
