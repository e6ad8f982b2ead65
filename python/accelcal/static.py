"""Static intervals and pose means: the one detector the calibration, the diagnosis and
the estimators' host forms use.

A recording's static poses come from its ``pose`` labels, or from
:func:`detect_static` (windowed std against each channel's noise).  The noise is the
device's ``noise_mps2`` when given, else estimated from the recording itself
(:func:`estimate_noise`).  :func:`pose_means` reduces each pose to its mean, sample
count and within-pose scatter, refusing clipped readings and poses that move.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .errors import InputError
from .recording import check_for_device


STATIC_WINDOW_S = 0.5      # window over which the moving std is taken


STATIC_THRESHOLD = 2.0     # static while every channel's window std <= this x its noise


MIN_POSE_S = 1.0           # shortest static interval kept as a pose


EDGE_SIGMA = 4.0           # static interval ends: the nearest samples this x noise off the median


MOVE_FACTOR = 3.0          # a labelled pose "moves" when a channel's std > this x its noise


QUANT_VAR = 1.0 / 12.0    # variance of rounding to integer counts


@dataclass
class PoseSet:
    """Static poses reduced to their means.

    means (P,N) counts; n (P,) samples; std (P,N) within-pose sample std (counts);
    f_ref (P,3) reference specific force (NaN = unknown); temp (P,) mean degC (NaN
    = unknown); info: one dict a pose (source, label, first/last sample, t range).
    """

    means: np.ndarray
    n: np.ndarray
    std: np.ndarray
    f_ref: np.ndarray
    temp: np.ndarray
    info: list[dict] = field(default_factory=list)

    @property
    def n_poses(self) -> int:
        return int(self.means.shape[0])

    def channel_noise(self) -> np.ndarray:
        """(N,) pooled within-pose std per channel (counts), floored at rounding noise."""
        dof = np.maximum(self.n - 1, 0).astype(float)
        if dof.sum() <= 0:
            return np.full(self.means.shape[1], math.sqrt(QUANT_VAR))
        var = (dof[:, None] * self.std ** 2).sum(0) / dof.sum()
        return np.sqrt(np.maximum(var, QUANT_VAR))

    def sem(self) -> np.ndarray:
        """(P,N) standard error of each pose mean from the pooled channel noise."""
        return self.channel_noise()[None, :] / np.sqrt(np.maximum(self.n, 1))[:, None]

    @staticmethod
    def concat(sets: Sequence["PoseSet"]) -> "PoseSet":
        return PoseSet(
            means=np.concatenate([s.means for s in sets]),
            n=np.concatenate([s.n for s in sets]),
            std=np.concatenate([s.std for s in sets]),
            f_ref=np.concatenate([s.f_ref for s in sets]),
            temp=np.concatenate([s.temp for s in sets]),
            info=[d for s in sets for d in s.info],
        )


def window_std(raw: np.ndarray, w: int) -> tuple[np.ndarray, int, int]:
    """Std of windows of about w samples at a stride: blocks of h = max(1, w // 4)
    samples, windows of k = ceil(w / h) blocks (L = k h samples, population std).

    Returns (ws (n_windows, N), h, k); window j covers samples [j h, (j + k) h).
    One pass over the data for the block sums, then cumulative sums over blocks."""
    raw = np.asarray(raw)
    n, N = raw.shape
    h = max(1, w // 4)
    k = max(1, -(-w // h))
    nb = n // h
    if nb < k:
        return np.zeros((0, N)), h, k
    ref = np.median(raw[:: max(1, n // 1000)], axis=0)       # keep the sums small
    x = (raw[: nb * h] - ref).reshape(nb, h, N)
    s1 = x.sum(axis=1, dtype=float)
    s2 = np.einsum("bhn,bhn->bn", x, x, dtype=float)
    c1 = np.concatenate([np.zeros((1, N)), np.cumsum(s1, axis=0)])
    c2 = np.concatenate([np.zeros((1, N)), np.cumsum(s2, axis=0)])
    L = k * h
    S1 = c1[k:] - c1[:-k]
    S2 = c2[k:] - c2[:-k]
    return np.sqrt(np.maximum((S2 - S1 * S1 / L) / L, 0.0)), h, k


def window_len(device, window_s: float, n: int) -> int:
    w = int(round(window_s * device.sample_rate_hz))
    return max(3, min(w, n))


def estimate_noise(raw: np.ndarray, window: int) -> np.ndarray:
    """Per-channel noise (counts) estimated robustly from the data.

    The std of windows of about ``window`` samples is taken (see window_std); static
    windows form the low cluster.  With s10 the 10th percentile of the window stds,
    the noise is the median of the windows whose std is below 2 x s10, times
    sqrt(L/(L-1)).  This needs at least about 10 % of the recording to be static.
    """
    ws, h, k = window_std(raw, window)
    if ws.shape[0] == 0:
        return np.full(np.asarray(raw).shape[1], math.sqrt(QUANT_VAR))
    s10 = np.percentile(ws, 10, axis=0)
    out = np.empty(ws.shape[1])
    for i in range(ws.shape[1]):
        col = ws[:, i]
        out[i] = np.median(col[col <= 2.0 * s10[i]]) if s10[i] > 0 else 0.0
    L = h * k
    out *= math.sqrt(L / max(L - 1, 1))
    return np.maximum(out, math.sqrt(QUANT_VAR))


def noise_for(device, raw: np.ndarray, window: int) -> tuple[np.ndarray, str]:
    k = np.asarray(device.noise_counts(), float)
    if np.all(k > 0):
        return np.sqrt(k ** 2 + QUANT_VAR), "device noise_mps2"
    return estimate_noise(raw, window), "estimated from the data (robust window std)"


def detect_static(rec, device, *, window_s: float = STATIC_WINDOW_S, threshold: float = STATIC_THRESHOLD,
                  min_s: float = MIN_POSE_S, noise: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Static intervals of a continuous recording, as sample index pairs [start, stop).

    1. Windows of about ``window_s`` seconds, taken at a stride of a quarter window
       (window_std), are quiet when the std of every channel in them is at most
       ``threshold`` times that channel's noise; the blocks a quiet window covers are
       static.
    2. Each run of static blocks is refined to the sample: with med the median of the
       run, its ends move to the nearest samples (searching one window beyond and a
       block inside the run, never into a neighbouring run) at which some channel is
       more than EDGE_SIGMA x noise away from med.  The window test alone would admit
       an edge sample up to about sqrt(3 w) x noise off.
    3. Intervals shorter than ``min_s`` (or one window) are dropped.

    The noise is the device's ``noise_mps2`` (plus rounding) when it is given for
    every channel, else estimated from the data (:func:`estimate_noise`), unless
    ``noise`` (counts, per channel) is passed.
    """
    raw = np.asarray(rec.raw)
    n = raw.shape[0]
    w = window_len(device, window_s, n)
    if n < w:
        return []
    sig = np.asarray(noise, float) if noise is not None else noise_for(device, raw, w)[0]
    ws, h, k = window_std(raw, w)
    nw = ws.shape[0]
    if nw == 0:
        return []
    quiet = np.all(ws <= threshold * sig[None, :], axis=1).astype(np.int64)
    # block b is static if a quiet window j with j <= b <= j + k - 1 covers it
    c = np.concatenate([[0], np.cumsum(quiet)])
    blk = np.arange(nw + k - 1)
    static = (c[np.clip(blk + 1, 0, nw)] - c[np.clip(blk - k + 1, 0, nw)]) > 0
    edges = np.diff(np.concatenate([[0], static.astype(np.int8), [0]]))
    runs = list(zip(np.flatnonzero(edges == 1) * h, np.flatnonzero(edges == -1) * h))
    min_n = max(w, int(math.ceil(min_s * device.sample_rate_hz)))
    ext = k * h
    out: list[tuple[int, int]] = []
    for r, (a, b) in enumerate(runs):
        lo_lim = max(out[-1][1] if out else 0, runs[r - 1][1] if r else 0)
        hi_lim = runs[r + 1][0] if r + 1 < len(runs) else n
        lo, hi = max(lo_lim, a - ext), min(hi_lim, b + ext)
        med = np.median(raw[a:b:max(1, (b - a) // 2000)], axis=0)
        lim = EDGE_SIGMA * sig
        left = np.flatnonzero(np.any(np.abs(raw[lo:a + h] - med) > lim, axis=1))
        start = lo + (int(left[-1]) + 1 if left.size else 0)
        right = np.flatnonzero(np.any(np.abs(raw[b - h:hi] - med) > lim, axis=1))
        stop = b - h + int(right[0]) if right.size else hi
        if stop - start >= min_n:
            out.append((int(start), int(stop)))
    return out


def sample_where(rec, i: int) -> str:
    return f"sample {int(i)} (t = {float(rec.t[i]):.6g} s)"


def pose_means(rec, intervals: Sequence[Any], device, *, labels: Sequence[Any] | None = None,
               noise: np.ndarray | None = None, check_motion: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, sample count and within-pose std of each static pose.

    ``intervals``: (start, stop) sample index pairs, or index arrays (a labelled pose
    may be split).  Checks (each an InputError naming the recording and where):
    no reading of a pose sits at raw_min/raw_max; with ``check_motion``, no channel's
    std in a pose exceeds MOVE_FACTOR x its noise (the pose would not be static).
    Returns means (P,N), counts (P,), std (P,N).
    """
    raw = np.asarray(rec.raw)
    n, N = raw.shape
    P = len(intervals)
    idx_list = [np.arange(int(iv[0]), int(iv[1])) if is_pair(iv) else np.asarray(iv, dtype=np.int64)
                for iv in intervals]
    names = [f"pose {labels[p]}" if labels is not None else f"static interval {p}" for p in range(P)]
    cnt = np.array([len(ix) for ix in idx_list], dtype=np.int64)
    if P == 0:
        return np.zeros((0, N)), cnt, np.zeros((0, N))
    if np.any(cnt == 0):
        raise InputError(rec.source, f"{names[int(np.argmin(cnt))]} has no samples")
    # one gather, then per-pose reductions; integer arithmetic about a reference is exact
    x = raw[np.concatenate(idx_list)]
    offs = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    lo, hi = np.minimum.reduceat(x, offs, axis=0), np.maximum.reduceat(x, offs, axis=0)
    bad = np.argwhere((lo <= device.raw_min) | (hi >= device.raw_max))
    if bad.size:
        p, c = (int(v) for v in bad[0])
        seg = raw[idx_list[p], c]
        k = int(np.flatnonzero((seg <= device.raw_min) | (seg >= device.raw_max))[0])
        i = int(idx_list[p][k])
        lim = "raw_max" if raw[i, c] >= device.raw_max else "raw_min"
        raise InputError(rec.source, f"{names[p]}: raw_{c} = {int(raw[i, c])} at {sample_where(rec, i)} sits at the "
                         f"ADC limit {lim} = {getattr(device, lim)} (clipped readings cannot be calibrated)",
                         column=f"raw_{c}")
    ref = x[0].copy()
    x -= ref
    s1 = np.add.reduceat(x, offs, axis=0).astype(float)
    s2 = np.add.reduceat(x * x, offs, axis=0).astype(float)
    cf = cnt.astype(float)[:, None]
    mean = s1 / cf
    var = np.maximum(s2 - s1 * mean, 0.0) / np.maximum(cf - 1, 1)
    std = np.sqrt(var)
    mean += ref
    if check_motion:
        if noise is None:
            noise = noise_for(device, raw, window_len(device, STATIC_WINDOW_S, n))[0]
        ratio = std / np.asarray(noise, float)[None, :]
        ratio[cnt < 3] = 0.0
        if np.any(ratio > MOVE_FACTOR):
            p, c = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
            idx = idx_list[p]
            raise InputError(rec.source, f"{names[p]} ({sample_where(rec, idx[0])} to {sample_where(rec, idx[-1])}) is labelled "
                             f"static but moves: raw_{c} varies by {std[p, c]:.3g} counts rms, its noise is "
                             f"{noise[c]:.3g} counts", column="pose" if labels is not None else f"raw_{c}")
    return mean, cnt, std


def is_pair(iv: Any) -> bool:
    return isinstance(iv, tuple) and len(iv) == 2 and np.isscalar(iv[0])


def poses_from_recording(rec, device, *, use_labels: bool | None = None, required: bool = True) -> PoseSet:
    """The static poses of one recording: its ``pose`` labels when it has them (and
    ``use_labels`` is not False), else :func:`detect_static`.  The reference
    specific force and temperature of a pose are the means of f_* and temp_c over it.
    With ``required`` False a recording without static poses gives an empty set."""
    check_for_device(rec, device)
    labelled = rec.has_pose() if use_labels is None else bool(use_labels)
    n = rec.n_samples
    w = window_len(device, STATIC_WINDOW_S, n)
    noise = noise_for(device, rec.raw, w)[0]
    if labelled:
        labs = rec.pose_labels()
        order = np.argsort(rec.pose, kind="stable")
        sorted_lab = rec.pose[order]
        bounds = np.searchsorted(sorted_lab, labs), np.searchsorted(sorted_lab, labs, side="right")
        intervals = [np.sort(order[a:b]) for a, b in zip(*bounds)]
        labels = [int(v) for v in labs]
    else:
        intervals = detect_static(rec, device, noise=noise)
        labels = None
    if not intervals and not required:
        return PoseSet(np.zeros((0, device.n_channels)), np.zeros(0, dtype=np.int64),
                       np.zeros((0, device.n_channels)), np.zeros((0, 3)), np.zeros(0), [])
    if not intervals:
        raise InputError(rec.source, "no static pose found (no 'pose' labels, and no interval of at least "
                         f"{MIN_POSE_S:g} s in which every channel is within {STATIC_THRESHOLD:g} x its noise)")
    means, cnt, std = pose_means(rec, intervals, device, labels=labels, noise=noise, check_motion=True)
    P = len(intervals)
    f_ref = np.full((P, 3), np.nan)
    temp = np.full(P, np.nan)
    info = []
    for p, iv in enumerate(intervals):
        idx = np.arange(iv[0], iv[1]) if is_pair(iv) else iv
        fr = rec.f[idx]
        ok = np.all(np.isfinite(fr), axis=1)
        if ok.any():
            if not ok.all():
                i = int(idx[int(np.argmin(ok))])
                raise InputError(rec.source, f"pose {labels[p] if labels else p}: f_x, f_y, f_z given on some of "
                                 f"its samples but not at {sample_where(rec, i)}", column="f_x")
            f_ref[p] = fr.mean(0)
        tc = rec.temp_c[idx]
        if np.isfinite(tc).any():
            temp[p] = float(np.nanmean(tc))
        info.append({
            "source": rec.source,
            "label": labels[p] if labels is not None else None,
            "first": int(idx[0]), "last": int(idx[-1]),
            "t_start": float(rec.t[idx[0]]), "t_stop": float(rec.t[idx[-1]]),
            "n": int(cnt[p]),
        })
    return PoseSet(means=means, n=cnt, std=std, f_ref=f_ref, temp=temp, info=info)
