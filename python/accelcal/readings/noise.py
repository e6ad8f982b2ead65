"""The noise of a recording, estimated from the recording itself.

Every threshold that depends on the sensor's noise (static-interval detection, the
"labelled pose moves" check, the estimators' rest test) takes its noise from here
unless the device file states ``noise_mps2`` (an optional override).

How (:func:`estimate_noise`): the standard deviation of windows of about half a second
is taken at a stride of a quarter window (:func:`window_std`).  Windows at rest form the
low cluster of log(std), motion the high one; the two are split where the between-class
variance of log(std) is largest (Otsu's threshold), and the noise is the median of the
low class.  When the two classes are less than NOISE_SPLIT_RATIO apart the recording is
one regime (all at rest, say) and the median of every window is taken.  Unlike a low
percentile this follows the typical static window, also when the noise is coloured and
uneven from pose to pose (hand-held tremor), and it needs no fixed share of the recording
at rest.

Quantization (:func:`code_lattice`): integer readings whose values all sit on a lattice
of step q (coarse converters, or low bits always 0) dither between neighbouring codes at
rest; a reading that sits on one code has a window std of 0 and one that flips between
two codes up to q/2.  Such a dither is noise of order q/sqrt(12), not motion, so the
noise of an integer channel is sqrt(sigma^2 + q^2/12) (q = 1 for plain integers: the
rounding to counts).

A tone at half the sampling rate (:func:`nyquist_tone`: mains aliased by a 100 Hz logger)
is no motion; :func:`without_nyquist_tone` takes it out before the static detector's windows.
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from scipy.optimize import brentq


NOISE_SPLIT_RATIO = 3.0    # rest and motion classes of window std at least this far apart (ratio of medians)


ONE_REGIME_RATIO = 3.0     # a recording with no rest/motion split: its window std level, at most this x
                           # the white noise level (the rest/motion ratio: more is motion throughout)


NYQUIST_RATIO = 1.5        # a channel carries a tone at half the sampling rate when its mean |lag-1 difference|
                           # is this x its mean |lag-2 difference| (white noise: 1; smooth motion: < 1)


MAD_TO_STD = 1.4826        # std of a normal distribution per unit of median absolute deviation


QUANT_MIN_FRAC = 0.99      # a lattice must hold this share of the readings (a few strays allowed)


QUANT_MAX_STEP = 256       # largest lattice step searched for (beyond the exact gcd)


def fractional_grid(v: np.ndarray) -> float | None:
    """The step, in counts, of a grid that is no whole number of counts on which integer
    readings sit (a logger that printed m/s^2 to two decimals: 0.01 m/s^2 = 16.7 counts of
    an MPU-6050 at +-2 g, each reading rounded to the nearest count), or None.

    The distinct readings' neighbouring differences are floor(q) or ceil(q) apart where most
    grid points are used; within each run of readings no more than 3 grid points apart (a
    pose's cluster) the points are numbered from the differences, and q is one least-squares
    step for all runs with an intercept each (the grid need not line up across clusters a g
    apart); it must hold QUANT_MIN_FRAC of the readings within rounding (half a count).  None for readings that use
    neighbouring counts, for a whole-number step (:func:`code_lattice` finds those), or for
    fewer than 6 distinct values.
    """
    u, cnt = np.unique(np.asarray(v).astype(np.int64), return_counts=True)
    if u.size < 6:
        return None
    du = np.diff(u)
    d0 = float(np.median(du))
    if d0 < 2.0 or np.mean(du == 1) > 0.3:
        return None
    small = du[du <= d0 + 1]                 # neighbouring grid points (a gap of unused ones left out)
    if small.size < 5 or np.ptp(small) > 1:
        return None
    # runs of readings whose neighbours are at most 3 grid points apart (a pose's cluster); within
    # each, the grid points' numbers from the differences, and one step for all by least squares
    # with an intercept per run (clusters a g apart do not tie the grid across them)
    q0 = float(small.mean())
    run = np.concatenate([[0], np.cumsum(du > 3.5 * q0)])
    k = np.concatenate([[0.0], np.cumsum(np.where(du > 3.5 * q0, 0.0, np.round(du / q0)))])
    w = cnt.astype(float)
    kc, xc = k.copy(), u.astype(float)
    for r in np.unique(run):
        m = run == r
        kc[m] -= np.average(k[m], weights=w[m])
        xc[m] -= np.average(xc[m], weights=w[m])
    den = float(np.sum(w * kc * kc))
    if den <= 0:
        return None
    q = float(np.sum(w * kc * xc)) / den
    if abs(q - round(q)) < 0.05:
        return None
    on = np.abs(xc - q * kc) <= 0.5 + 0.05
    return q if float(w[on].sum()) / float(w.sum()) >= QUANT_MIN_FRAC else None


def code_lattice(v: np.ndarray) -> tuple[int, float, float, int]:
    """The lattice of integer readings.

    Parameters
    ----------
    v : array_like of int
        Readings of one channel (counts).

    Returns
    -------
    step : int
        Lattice step (counts); 1 when the readings use every count (or too few distinct
        values, < 6, to tell).
    phase : float
        The readings' common residue modulo ``step``.
    share : float
        Share of the readings on the lattice (1.0 for an exact lattice).
    distinct : int
        Distinct values on the lattice.
    """
    u, cnt = np.unique(np.asarray(v).astype(np.int64), return_counts=True)
    return code_lattice_counts(u, cnt)


def code_lattice_counts(u: np.ndarray, cnt: np.ndarray) -> tuple[int, float, float, int]:
    """:func:`code_lattice` from the distinct readings ``u`` (int64, ascending) and their counts
    (a reader that goes through a recording in chunks keeps these)."""
    tot = float(cnt.sum())
    best = (1, 0.0, 1.0, int(u.size))
    if u.size < 6:
        return best
    span = int(u[-1] - u[0])
    gq = int(np.gcd.reduce(np.diff(u)))           # exact lattice: the gcd of the differences
    if gq >= 2:
        return (gq, float(u[0] % gq), 1.0, int(u.size))
    # robust: a lattice that holds for QUANT_MIN_FRAC of the readings; dense readings (most
    # neighbouring values one count apart) are on none
    if np.mean(np.diff(u) == 1) > 0.3:
        return best
    for q in range(2, min(QUANT_MAX_STEP, max(span // 3, 2)) + 1):
        res = u % q
        bc = np.bincount(res, weights=cnt, minlength=q)
        ph = int(np.argmax(bc))
        frac = bc[ph] / tot
        if frac >= QUANT_MIN_FRAC:
            nd = int(np.count_nonzero(res == ph))
            if nd >= 6:
                best = (q, float(ph), float(frac), nd)
    return best


LOW_BITS_EXCESS = 0.1      # uneven low bits: the most used residue class mod 2-4 above its even share by this ...
LOW_BITS_UNITS = 5         # ... in at least this many parts of the recording (static poses, blocks of motion) ...
LOW_BITS_AGREE = 0.9       # ... of which this share over-use the same class
LOW_BITS_MIN_PART = 50     # a part holds at least this many samples


def uneven_low_bits(v: np.ndarray, parts: Sequence[tuple[int, int]]) -> dict | None:
    """Uneven use of a channel's lowest bits (missing or doubled codes of an ADC), or None.

    The residue class mod m (2, 3 or 4) that the readings fall in most, against the 1/m of
    evenly used codes.  A signal that dwells on a few codes (an 8-bit sensor holding still:
    2-4 codes a pose) also over-uses some class, but a different one from pose to pose; an
    ADC's defect sits at the same codes wherever the signal is.  So the excess counts only
    where the same class is over-used in at least LOW_BITS_AGREE of LOW_BITS_UNITS or more
    ``parts`` (index ranges [a, b) of at least LOW_BITS_MIN_PART samples: each static pose
    one, motion in blocks).  A real Xsens recording: class 1 mod 2 in 14 of 14 parts; an
    Empatica E4 at rest on 2-4 codes a pose: 40-75 %.

    Parameters
    ----------
    v : array_like (n,) of int
        Readings (counts).
    parts : sequence of (int, int)
        Index ranges of the recording's parts.

    Returns
    -------
    dict or None
        ``modulus``, ``share_of_top_residue``, ``uniform_share``, ``parts`` (counted),
        ``parts_agreeing`` (share of them over-using the same class), ``uneven`` (bool: the
        excess reaches LOW_BITS_EXCESS and the parts agree); None for fewer than 6 distinct
        values (too few codes to tell).
    """
    v = np.asarray(v).astype(np.int64)
    if np.unique(v).size < 6:
        return None
    best = None
    for m in (2, 3, 4):
        share = np.bincount(v % m, minlength=m) / v.size
        c = int(np.argmax(share))
        if best is None or share[c] - 1.0 / m > best[1] - 1.0 / best[0]:
            best = (m, float(share[c]), c)
    m, share, c = best
    use = [(a, b) for a, b in parts if b - a >= LOW_BITS_MIN_PART]
    agree = float(np.mean([np.mean(v[a:b] % m == c) > 1.0 / m for a, b in use])) if use else 0.0
    return {"modulus": m, "share_of_top_residue": share, "uniform_share": 1.0 / m, "parts": len(use),
            "parts_agreeing": agree,
            "uneven": bool(share - 1.0 / m > LOW_BITS_EXCESS and len(use) >= LOW_BITS_UNITS
                           and agree >= LOW_BITS_AGREE)}


def code_step(v: np.ndarray) -> int:
    """The code step of integer readings: the gcd of the differences of their distinct
    values (exact, from two values on), else :func:`code_lattice`'s robust step; 1 for a
    single value."""
    u = np.unique(np.asarray(v).astype(np.int64))
    if u.size < 2:
        return 1
    g = int(np.gcd.reduce(np.diff(u)))
    return g if g >= 2 else code_lattice(v)[0]



def window_std(x: np.ndarray, w: int) -> tuple[np.ndarray, int, int]:
    """Population std of windows of about ``w`` samples, at a stride of a quarter window.

    Blocks of h = max(1, w // 4) samples; windows of k = ceil(w / h) blocks (L = k h
    samples).  One pass over the data for the block sums, then cumulative sums over
    blocks.

    Parameters
    ----------
    x : array_like (n, N)
        Readings (counts or physical units).
    w : int
        Window length (samples).

    Returns
    -------
    ws : ndarray (n_windows, N)
        Window std, in the units of ``x``; window j covers samples [j h, (j + k) h).
    h, k : int
        Block length (samples) and blocks per window.
    """
    x = np.asarray(x)
    n, N = x.shape
    h = max(1, w // 4)
    k = max(1, -(-w // h))
    nb = n // h
    if nb < k:
        return np.zeros((0, N)), h, k
    ref = np.median(x[:: max(1, n // 1000)], axis=0)       # keep the sums small
    d = (x[: nb * h] - ref).reshape(nb, h, N)
    s1 = d.sum(axis=1, dtype=float)
    s2 = np.einsum("bhn,bhn->bn", d, d, dtype=float)
    c1 = np.concatenate([np.zeros((1, N)), np.cumsum(s1, axis=0)])
    c2 = np.concatenate([np.zeros((1, N)), np.cumsum(s2, axis=0)])
    L = k * h
    S1 = c1[k:] - c1[:-k]
    S2 = c2[k:] - c2[:-k]
    return np.sqrt(np.maximum((S2 - S1 * S1 / L) / L, 0.0)), h, k


def rest_level(ws: np.ndarray) -> tuple[float, bool]:
    """The typical window std at rest: the median of the low class of log(std) (Otsu's
    split), or of every window when the classes are less than NOISE_SPLIT_RATIO apart.

    Parameters
    ----------
    ws : array_like (n_windows,)
        Window stds of one channel (>= 0).

    Returns
    -------
    level : float
        0.0 when every window is exactly constant.
    split : bool
        Whether a rest class apart from a motion class was found.
    """
    v = np.sort(np.asarray(ws, float)[np.isfinite(ws)])
    if v.size == 0 or v[-1] <= 0.0:
        return 0.0, False
    pos = v[v > 0]
    x = np.log(np.maximum(v, 0.1 * pos[0]))      # a window on one code: a tenth of the least dither
    n = x.size
    if n < 4:
        return float(np.median(v)), False
    c = np.cumsum(x)
    k = np.arange(1, n)
    m0 = c[:-1] / k
    m1 = (c[-1] - c[:-1]) / (n - k)
    between = k * (n - k) * (m1 - m0) ** 2
    between[x[1:] == x[:-1]] = -1.0               # split only between distinct values
    j = int(np.argmax(between)) + 1
    lo, hi = v[:j], v[j:]
    if between[j - 1] <= 0 or np.median(hi) < NOISE_SPLIT_RATIO * max(np.median(lo), 1e-300):
        return float(np.median(v)), False
    return float(np.median(lo)), True


def white_noise(v: np.ndarray) -> float:
    """The white part of the noise of one channel: the robust (MAD) std of its fourth
    differences over sqrt(70).  Smooth motion hardly reaches it (a sine of period T
    sampled at dt is scaled by (2 pi dt / T)^4); coloured noise is underestimated."""
    v = np.asarray(v, float)
    if v.size < 10:
        return 0.0
    d = v[:-4] - 4 * v[1:-3] + 6 * v[2:-2] - 4 * v[3:-1] + v[4:]
    return float(MAD_TO_STD * np.median(np.abs(d - np.median(d))) / math.sqrt(70.0))


def estimate_noise(x: np.ndarray, window: int, *, integer: bool | None = None) -> np.ndarray:
    """Per-channel noise std estimated from the data (see the module doc).

    Parameters
    ----------
    x : array_like (n, N)
        Readings: integer counts (quantization-aware) or floats (physical units).
    window : int
        Window length in samples (about half a second).
    integer : bool, optional
        Treat the readings as integer codes (default: when ``x`` has an integer dtype).

    Returns
    -------
    ndarray (N,)
        Noise std in the units of ``x``; for integer readings at least the rounding
        noise q/sqrt(12) of their lattice step q.
    """
    x = np.asarray(x)
    N = x.shape[1]
    if integer is None:
        integer = np.issubdtype(x.dtype, np.integer)
    ws, h, k = window_std(x, window)
    L = h * k
    q = np.array([code_step(x[:, i]) for i in range(N)], float) if integer else np.zeros(N)
    out = np.zeros(N)
    first = x[np.arange(ws.shape[0]) * h]
    for i in range(N if ws.shape[0] else 0):
        col = ws[:, i]
        if integer:
            # a window held on the channel's extreme value is clipped, not at rest (a window on one
            # code elsewhere is a rest quieter than the code step)
            held = (col == 0) & ((first[:, i] == x[:, i].max()) | (first[:, i] == x[:, i].min()))
            col = col[~held]
        out[i], split = rest_level(col)
        out[i] *= math.sqrt(L / max(L - 1, 1))
        if not split:
            # one regime: all at rest, or never at rest (a rate table turning throughout); in the
            # latter the windows hold the motion, which the white noise level shows up
            out[i] = min(out[i], ONE_REGIME_RATIO * white_noise(x[:, i]))
    return np.sqrt(out ** 2 + q ** 2 / 12.0)


def nyquist_tone(raw: np.ndarray) -> np.ndarray:
    """Channels that carry a tone at half the sampling rate.

    50 Hz mains picked up by a logger sampling at 100 Hz aliases to the last bin of the
    spectrum; the sampling clock and the mains drift apart, so the sampled tone's amplitude
    swells and fades over seconds to minutes, and a window std test takes its quiet
    stretches for rest and the rest for motion.  Such a tone alternates sign from sample to
    sample: it is in every difference of neighbours and in no difference of samples two
    apart.

    Parameters
    ----------
    raw : array_like (n, N)
        Readings (counts).

    Returns
    -------
    ndarray (N,) of bool
        Mean |x[k+1] - x[k]| >= NYQUIST_RATIO x mean |x[k+2] - x[k]|.
    """
    x = np.asarray(raw, float)
    if x.shape[0] < 8:
        return np.zeros(x.shape[1], bool)
    d1 = np.mean(np.abs(np.diff(x, axis=0)), axis=0)
    d2 = np.mean(np.abs(x[2:] - x[:-2]), axis=0)
    return (d1 > 0) & (d1 >= NYQUIST_RATIO * d2)


def without_nyquist_tone(raw: np.ndarray, tone: np.ndarray, sig: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """The readings with the channels ``tone`` averaged over neighbouring pairs (a zero at half
    the sampling rate; slower content, motion included, is kept), and those channels' noise
    estimated again from the averaged readings (counts).  The static detector's windows and
    interval ends are then taken on them."""
    x = np.asarray(raw, float).copy()
    x[1:, tone] = 0.5 * (x[1:, tone] + x[:-1, tone])
    s = np.asarray(sig, float).copy()
    s[tone] = estimate_noise(x[:, tone], w, integer=False)
    return x, s


def noise_for(device, raw: np.ndarray, window: int) -> tuple[np.ndarray, str]:
    """The noise (counts, per channel) the thresholds use: the device's ``noise_mps2``
    (plus rounding) when it states one for every channel, else :func:`estimate_noise`.

    Returns
    -------
    sigma : ndarray (N,)
        Counts.
    how : str
        Where it came from, for messages and reports.
    """
    if states_noise(device):
        return np.sqrt(np.asarray(device.noise_counts(), float) ** 2 + 1.0 / 12.0), "device noise_mps2"
    return estimate_noise(raw, window, integer=True), "estimated from the data (window std at rest)"


def states_noise(device) -> bool:
    """Whether the device file states ``noise_mps2`` for every channel (else the thresholds
    take the noise from the data: :func:`noise_for`)."""
    return bool(np.all(np.asarray(device.noise_counts(), float) > 0))


COLOUR_BATCHES = 8         # a pose mean's own noise: the scatter of the means of this many batches of it ...
COLOUR_MIN_RATIO2 = 1.5    # ... over the white-noise sem^2 (median over the poses); used above this (white
                           # noise: chi2_7/7, median 0.91; real hand-held poses 1.4-3.5, a tremor's 7-16) ...
COLOUR_MIN_POSES = 5       # ... where at least this many poses tell (3 poses of white noise: 7.6 % of channels
                           # widened by chance, by ~1.28x; 5: the median of 5 chi2_7/7 above 1.5 in ~2 %)


def pose_colour(raw: np.ndarray, poses: Sequence[np.ndarray]) -> np.ndarray:
    """(P,N) each pose's var(means of COLOUR_BATCHES batches) x batch length / var(samples):
    how far its mean wanders beyond white noise's sem, squared (white noise: chi2_7/7, mean 1;
    NaN for a pose of fewer than 2 COLOUR_BATCHES samples; 1 for a constant channel).
    ``poses``: each pose's sample indices."""
    raw = np.asarray(raw)
    N = raw.shape[1]
    B = COLOUR_BATCHES
    out = np.full((len(poses), N), np.nan)
    for p, idx in enumerate(poses):
        idx = np.asarray(idx, dtype=np.int64)
        L = idx.size // B
        if L < 2:
            continue
        x = raw[idx[: B * L]].astype(float).reshape(B, L, N)
        var = x.reshape(B * L, N).var(axis=0, ddof=1)
        ok = var > 0
        out[p] = np.where(ok, x.mean(axis=1).var(axis=0, ddof=1) * L / np.where(ok, var, 1.0), 1.0)
    return out


def colour_factor(r2: np.ndarray) -> np.ndarray:
    """(N,) the noise's colour within poses, from :func:`pose_colour`'s (P,N) ratios: sqrt of
    their median over the poses that tell, where at least COLOUR_MIN_POSES do and it exceeds
    COLOUR_MIN_RATIO2, else 1.  Real poses' noise is coloured -- a hand's slow tremor, 1/f
    noise -- and a pose mean then wanders more than white noise lets it (real hand-held
    sessions: 1.2-2 x in the median pose, up to 6 x; a Cramer-Rao weighting with the white sem
    took that for a model error: chi2/dof 8.8 on an LSM303 session).  Pooled over the poses of
    every recording (one file per pose counts alike)."""
    r2 = np.asarray(r2, float)
    N = r2.shape[1]
    ok = np.all(np.isfinite(r2), axis=1)
    if np.count_nonzero(ok) < COLOUR_MIN_POSES:
        return np.ones(N)
    med = np.median(r2[ok], axis=0)
    return np.where(med > COLOUR_MIN_RATIO2, np.sqrt(med), 1.0)


ROUNDING_HARMONICS = 256   # terms of the rounding bias's Fourier series summed (those beyond: 0.2 % of q^2/12)


def rounding_bias_var(sigma, q):
    """Variance, over where a level falls between two codes, of the bias that rounding to a code
    step ``q`` leaves in the mean of many readings with Gaussian noise ``sigma`` before it
    (counts): round(x) - x is a sawtooth, sum_k (-1)^k q/(pi k) sin(2 pi k x / q), and the noise
    damps its k-th term by exp(-2 pi^2 k^2 sigma^2 / q^2), so the variance is
    sum_k q^2 / (2 pi^2 k^2) exp(-4 pi^2 k^2 sigma^2 / q^2): q^2/12 for a level on one code
    (sigma = 0: averaging does not remove it), 0.0015 q^2 at sigma = 0.3 q."""
    sigma, q = np.broadcast_arrays(np.asarray(sigma, float), np.asarray(q, float))
    k = np.arange(1, ROUNDING_HARMONICS + 1, dtype=float).reshape((-1,) + (1,) * q.ndim)
    r = np.divide(sigma, q, out=np.zeros(q.shape), where=q > 0)
    return np.sum(q ** 2 / (2 * math.pi ** 2 * k ** 2) * np.exp(-4 * math.pi ** 2 * k ** 2 * r ** 2), axis=0)


def noise_before_rounding(s, q):
    """The Gaussian noise (counts) before a rounding to step ``q`` that gives readings of std
    ``s`` about their level: the root of sigma^2 + q^2/12 - rounding_bias_var(sigma, q) = s^2
    (Sheppard's correction, with the part of the rounding that stays in the mean taken out:
    readings on one code have s = 0 and sigma 0), elementwise."""
    s, q = np.broadcast_arrays(np.asarray(s, float), np.asarray(q, float))
    out = np.zeros(s.shape)
    for i in np.ndindex(s.shape):
        si, qi = float(s[i]), float(q[i])
        if si <= 0 or qi <= 0:
            out[i] = si if qi <= 0 else 0.0
            continue
        # q^2/12 as the series sums it (its truncation at sigma = 0), so that sigma = 0 is the root at s = 0
        whole = float(rounding_bias_var(0.0, qi))
        fun = lambda x: x * x + whole - float(rounding_bias_var(x, qi)) - si * si  # noqa: E731
        # a scatter far below the step (a few flips between two coarse codes): the bias's variance at
        # si is q^2/12 to rounding, f(si) <= 0, and the root is si itself
        out[i] = si if fun(si) <= 0.0 else brentq(fun, 0.0, si)
    return out


def mean_rounding_var(s, q):
    """Variance (counts^2) of the bias rounding to step ``q`` leaves in a pose's mean whose readings
    scatter by ``s`` (counts, their pooled std about the pose's level): :func:`rounding_bias_var` at
    the noise before the rounding that gives that scatter (:func:`noise_before_rounding`).  The
    calibration's pose sems and the diagnosis's pose level errors both take it; elementwise."""
    return rounding_bias_var(noise_before_rounding(s, q), q)
