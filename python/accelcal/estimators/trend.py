"""The trend test of the rests: a rest holds no steady change of f (:func:`rest_without_trend`),
tested per axis against that axis's noise, widened by the noise's correlation as the rests show it
(:func:`rest_widening`)."""
from __future__ import annotations

import math
import warnings

import numpy as np

from .rest import RestParams

__all__ = ["TREND_BLOCK_HOLDS", "TREND_FALSE_ALARM", "CORR_CHUNK_BLOCKS", "trend_bound", "noise_correlation",
           "part_correlation", "median_correlation", "nan_median", "correlation_from_median",
           "rest_parts",
           "rest_correlation", "rest_widening", "trend_widening", "rest_without_trend"]


#: a rest is tested for a trend in blocks of this many hold lengths (1 s at the default 0.25 s)
TREND_BLOCK_HOLDS = 4
#: the chance (per block of a rest) of a rest's noise taken for a trend that the test is held to
#: (:func:`rest_without_trend`)
TREND_FALSE_ALARM = 1e-4
#: the noise's correlation is estimated over stretches of this many trend blocks of a rest (the median
#: of their estimates taken)
CORR_CHUNK_BLOCKS = 4


def trend_bound(n: int, sigma, widen=1.0):
    """5 sigma of the change (m/s^2) over ``n`` samples of the least-squares line through noise of
    ``sigma`` (m/s^2, per axis: a float or an array): for white noise the slope's sigma per sample,
    sigma sqrt(12 / (n (n^2 - 1))), times n - 1 samples; sigma sqrt(12 / n) for large n.  Noise whose
    neighbouring samples are correlated changes a fitted line more: its variance by ``widen``
    (:func:`trend_widening`, per axis like ``sigma``)."""
    n = int(n)
    if n < 2:
        return np.full(np.shape(sigma), math.inf) if np.ndim(sigma) else math.inf
    out = 5.0 * np.asarray(sigma, float) * np.sqrt(np.asarray(widen, float)) * (n - 1) * math.sqrt(
        12.0 / (n * (n * n - 1.0)))
    return out if np.ndim(out) else float(out)


def noise_correlation(parts, maxlag: int) -> np.ndarray:
    """The autocorrelation of the noise of still stretches ``parts`` (each (m, 3), m/s^2), per
    axis, at lags 0 .. ``maxlag`` - 1.

    Each stretch less the straight line fitted to it (its level, and a slow drift it holds), its
    lagged products over their count divided by its mean square; the median over the stretches at
    each lag (a slow motion within one stretch -- the trend the test looks for -- does not pass for
    the noise's correlation: pooled over a 20 s rest of white noise, one 1 s ramp of twice the test
    widened it 3.1 x); cut at the first lag whose median falls within the band white noise's
    estimates keep to, 2 / sqrt(N) for N samples in all (Bartlett's standard error of a sample
    autocorrelation of white noise, 1 / sqrt(N): Box, Jenkins and Reinsel, Time Series Analysis,
    section 6.2.2): past it the estimate is noise.  (Summing on while the estimates stay positive --
    Geyer's initial positive sequence -- widened the trend test of 300 samples of white noise by
    16 % or more on one axis in ten.)

    Returns
    -------
    ndarray (maxlag, 3)
        rho[0] = 1; white noise (1, 0, 0, ...) without a stretch of 3 samples or more, or on a
        constant axis.
    """
    L = max(int(maxlag), 1)
    est, N = [], 0
    for x in parts:
        c = part_correlation(x, L)
        if c is not None:
            est.append(c)
            N += np.asarray(x).shape[0]
    return median_correlation(est, N, L)


def part_correlation(x, maxlag: int) -> np.ndarray | None:
    """One still stretch's estimate for :func:`noise_correlation` (``x`` (m, 3), m/s^2): its lagged
    products less the fitted line over their count, over its mean square, per axis at lags 0 ..
    ``maxlag`` - 1 (NaN past m - 1 and on a constant axis); None for fewer than 3 samples.  A
    recording read in chunks keeps these per stretch (accelcal.estimators.displacement_stream)."""
    L = max(int(maxlag), 1)
    x = np.asarray(x, float)
    m = x.shape[0]
    if m < 3:
        return None
    t = np.arange(m, dtype=float)
    r = x - np.polynomial.polynomial.polyval(t, np.polynomial.polynomial.polyfit(t, x, 1)).T
    c = np.full((L, 3), np.nan)
    c[:min(L, m)] = [np.einsum("ij,ij->j", r[:m - k], r[k:]) / (m - k) for k in range(min(L, m))]
    # an axis constant over the stretch (noise below the code step) leaves only the line fit's
    # rounding, ~1e-15 of its level and smooth (it read as correlation 0.998): no estimate
    c[:, c[0] <= (1e-12 * max(1.0, float(np.max(np.abs(x))))) ** 2] = np.nan
    with np.errstate(divide="ignore", invalid="ignore"):
        return c / c[0]


def median_correlation(est, N: int, maxlag: int) -> np.ndarray:
    """:func:`noise_correlation` from its stretches' estimates ``est`` (:func:`part_correlation`,
    each (maxlag, 3)) over ``N`` samples in all: the median at each lag, cut where it falls within
    2 / sqrt(N)."""
    L = max(int(maxlag), 1)
    if not len(est):
        return correlation_from_median(None, N, L)
    return correlation_from_median(nan_median(np.array(est)), N, L)


def nan_median(est: np.ndarray) -> np.ndarray:
    """The median over the stretches' estimates ``est`` ((K, ...)) of each of their values, NaN
    left out (all NaN: NaN), without numpy's warning."""
    with np.errstate(all="ignore"), warnings.catch_warnings():
        # a constant axis (noise below the code step) has no estimate at any lag: white, below
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(est, axis=0)


def correlation_from_median(med, N: int, maxlag: int) -> np.ndarray:
    """:func:`median_correlation` from the median ``med`` ((maxlag, 3), or None: no estimate) of
    the stretches' estimates over ``N`` samples."""
    L = max(int(maxlag), 1)
    rho = np.zeros((L, 3))
    rho[0] = 1.0
    if med is None:
        return rho
    for j in range(3):
        cj = med[:, j]
        if not np.isfinite(cj[0]):
            continue
        stop = np.flatnonzero(~(cj[1:] >= 2.0 / math.sqrt(N)))
        k = 1 + int(stop[0]) if stop.size else L
        rho[:k, j] = cj[:k]
    return rho


def rest_parts(s: int, e: int, size: int, n: int, trim: int) -> list[np.ndarray]:
    """The samples of the rest run [s, e) of a recording of ``size`` samples that
    :func:`rest_correlation` takes for its ``n``-lag estimate: less ``trim`` at an end next to a
    motion, cut in stretches of about CORR_CHUNK_BLOCKS x n samples (none when shorter than n)."""
    s, e = s + (int(trim) if s > 0 else 0), e - (int(trim) if e < size else 0)
    if e - s < n:
        return []
    return list(np.array_split(np.arange(s, e), max(1, (e - s) // (CORR_CHUNK_BLOCKS * n))))


def rest_correlation(at, f, n: int, trim: int = 0) -> np.ndarray:
    """The noise's autocorrelation as the rests show it, per axis, at lags 0 .. ``n`` - 1
    (:func:`noise_correlation`): each run of at-rest samples ``at`` of f ((N, 3), m/s^2) of n samples
    or more, less ``trim`` samples at an end next to a motion (a rest dated back from its declaration
    holds the first samples of a slow start: a rocket's boost, whose rise read as correlation 0.2 at
    lag 1), cut in stretches of about CORR_CHUNK_BLOCKS x n samples.  White noise's (1, 0, 0, ...)
    when no run is n samples long.  The line fitted to each stretch takes some of a slow noise with
    it: AR(1) noise with phi = 0.9 over blocks of 100 samples (20 s rests) reads a widening of
    10.3-11.7 of its 13.8 (the test's sigma 0.86-0.92 x the truth).  A slow motion within a rest is
    the correlation's only where it lies in half the stretches or more.

    Returns
    -------
    ndarray (n, 3)
    """
    at = np.asarray(at, bool)
    f = np.asarray(f, float)
    n = max(int(n), 2)
    edges = np.diff(np.concatenate(([0], at.astype(np.int8), [0])))
    parts = []
    for s, e in zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()):
        parts += [f[k] for k in rest_parts(s, e, at.size, n, trim)]
    return noise_correlation(parts, n)


def rest_widening(at, f, n: int, trim: int = 0) -> np.ndarray:
    """How much more (in variance) a line fitted to ``n`` samples of the noise at rest changes than
    one fitted to white noise of the same sigma, per axis (:func:`trend_widening`), from the rests
    themselves (:func:`rest_correlation`).  Ones when no rest is n samples long."""
    return trend_widening(rest_correlation(at, f, n, trim), n)


def trend_widening(rho, n: int) -> np.ndarray:
    """How much more (in variance) a line fitted to ``n`` samples of noise with the autocorrelation
    ``rho`` ((L, 3), :func:`noise_correlation`) changes than one fitted to white noise of the same
    sigma, per axis: the slope's variance sum_ij w_i w_j rho(|i - j|) / sum_i w_i^2 (w the samples'
    places less their mean; the effective sample count's idea, for a slope).  At least 1: an
    estimate below white noise's is not taken (it would narrow the test by its own error).  AR(1)
    noise with phi = 0.9 over 100 samples: 13.8."""
    rho = np.asarray(rho, float)
    n = int(n)
    if n < 2:
        return np.ones(rho.shape[1])
    w = np.arange(n) - 0.5 * (n - 1)
    a = np.correlate(w, w, "full")[n - 1:] / float(np.dot(w, w))       # (n,), a[0] = 1
    k = min(n, rho.shape[0])
    out = 1.0 + 2.0 * (a[1:k, None] * rho[1:k]).sum(axis=0)
    return np.maximum(out, 1.0)


def rest_without_trend(at, f, p: RestParams, sigma) -> tuple[np.ndarray, list[tuple[int, int, float, float, float]]]:
    """The rests less their stretches in which f changes steadily.

    The detector's test, max |f - mean| <= dev_max about a running mean, holds a slow steady
    change when dev_max is wide (vibration: a rocket's 0.67 m/s^2, whose slow change of f
    through |f| = g mid-flight was taken as a rest): its mean follows the trend.  A rest holds no
    trend: each declared rest is cut in blocks of TREND_BLOCK_HOLDS hold lengths (the last one
    aligned to the rest's end; a shorter rest is one block), and a block in which the straight
    line fitted to an axis of f changes by more than :func:`trend_bound` for that axis (5 sigma of
    that change for its noise ``sigma``, widened by the noise's correlation as the rests show it:
    :func:`rest_widening`) is not at rest; what is left of a rest shorter than ``p.hold`` is no
    rest either.  (The firmware's streaming detector cannot look back: a host check of its
    decisions.)  The last ``p.hold`` samples of a rest that a motion follows are the motion's start,
    which the detector lets through: not tested.  A block of a rest is taken for a trend with a
    chance of at most TREND_FALSE_ALARM: for white Gaussian noise 5.7e-7 per axis (two-sided 5
    sigma); more where the correlation's estimate falls short of the truth (AR(1) noise with
    phi = 0.9 over blocks of 100 samples, 20 s rests: the change's rms 1.09 of the test's sigma,
    1 block in 6000 beyond 5 -- tests/python/test_rest_trend.py).

    Parameters
    ----------
    at : array_like (n,) bool
        The detector's at-rest decisions (as declared).
    f : array_like (n, 3)
        Specific force, m/s^2.
    p : RestParams
        hold (samples).
    sigma : float or array_like (3,)
        The noise of f, m/s^2, per axis (one figure: the same for all).

    Returns
    -------
    at : ndarray (n,) bool
        At rest, without the stretches of a trend.
    trends : list of (int, int, float, float, float)
        Each block taken out: first sample, end (exclusive), and, on its axis furthest beyond its
        bound, the change of the line over the block (m/s^2), that bound (m/s^2) and that axis's
        noise sigma (m/s^2).
    """
    at = np.array(at, bool)
    f = np.asarray(f, float)
    sig = np.broadcast_to(np.asarray(sigma, float), (3,))
    edges = np.diff(np.concatenate(([0], at.astype(np.int8), [0])))
    L = max(2, TREND_BLOCK_HOLDS * int(p.hold))
    widen = {L: rest_widening(at, f, L, int(p.hold))}      # per block length (a short rest is one block)
    declared = at.copy()
    trends = []
    for s, end in zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()):
        # a rest that a motion follows ends with the motion's first hold samples, which the
        # detector lets through (within dev_max of its mean): not tested (a rocket's boost begun)
        e = end - int(p.hold) if end < at.size and end - s > 2 * int(p.hold) else end
        starts = list(range(s, e, L))
        if len(starts) > 1 and e - starts[-1] < L:
            starts[-1] = e - L
        cut = False
        for b in starts:
            c = min(b + L, e)
            if c - b < 2:
                continue
            slope = np.polyfit(np.arange(c - b, dtype=float), f[b:c], 1)[0]     # per sample, each axis
            change = np.abs(slope) * (c - b - 1)
            if c - b not in widen:
                widen[c - b] = rest_widening(declared, f, c - b, int(p.hold))
            bound = trend_bound(c - b, sig, widen[c - b])
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(bound > 0, change / bound, np.where(change > 0, np.inf, 0.0))
            j = int(np.argmax(ratio))
            if ratio[j] > 1.0:
                at[b:c if c < e else end] = False
                trends.append((b, c, float(change[j]), float(bound[j]), float(sig[j])))
                cut = True
        if cut:
            left = np.diff(np.concatenate(([0], at[s:end].astype(np.int8), [0])))
            for i, j in zip(np.flatnonzero(left == 1), np.flatnonzero(left == -1)):
                if j - i < p.hold:
                    at[s + i:s + j] = False
    return at, trends
