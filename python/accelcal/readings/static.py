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

from .clipping import ClipLevels, clip_levels
from ..errors import InputError
from .no_rest import REST_NOISE_MAX, gravity_removed_clause, no_rest_clause, noise_share, tonal
from .noise import (code_step, colour_factor, mean_rounding_var, noise_for, nyquist_tone, pose_colour, window_std,
                    without_nyquist_tone)
from ..io.recording import check_for_device
from .steps import MOVE_PARTS, MOVE_RANGE, MOVE_STD, block_log_intervals, part_spread
from .still_pieces import long_enough, refine_pieces, run_pieces, static_runs


STATIC_WINDOW_S = 0.5      # window over which the moving std is taken


STATIC_THRESHOLD = 2.0     # static while every channel's window std <= this x its noise


MIN_POSE_S = 1.0           # shortest static interval kept as a pose where an end is a motion (a pause in
                           # a movement is no pose); a piece whose ends are both instant steps (or the
                           # recording's ends) needs one window only: no motion touches it


EDGE_SIGMA = 4.0           # static interval ends: the nearest samples this x noise off the median


QUANT_VAR = 1.0 / 12.0    # variance of rounding to integer counts




REST_F_RANGE = (0.5, 2.0)  # a static interval with no reference reads |f| within this x g (device file's scale) ...
REST_F_AGREE = 0.1         # ... or within this of the median ratio of >= 3 such intervals (one wrong scale for
                           # all: a +-8 g log read as +-2 g); else it is no rest (a rocket coasting: 0.03-0.34 g)


@dataclass
class PoseSet:
    """Static poses reduced to their means.

    means (P,N) counts; n (P,) samples; std (P,N) within-pose sample std (counts);
    f_ref (P,3) reference specific force (NaN = unknown); temp (P,) mean degC (NaN
    = unknown); info: one dict a pose (source, label, first/last sample, t range);
    set_aside: one dict a pose left out (source, label, t range, reason, clipped
    samples and the channels and levels they sit at); colour_r2 (P,N) or None: each pose's
    batch-means variance over the white-noise sem^2 (:func:`pose_colour`; NaN for a pose too
    short to tell), pooled over every pose of the set by :meth:`sem`; step (P,N) or None: the
    code step of each pose's channel (counts; None: 1, whole counts).
    """

    means: np.ndarray
    n: np.ndarray
    std: np.ndarray
    f_ref: np.ndarray
    temp: np.ndarray
    info: list[dict] = field(default_factory=list)
    set_aside: list[dict] = field(default_factory=list)
    colour_r2: np.ndarray | None = None
    step: np.ndarray | None = None

    @property
    def n_poses(self) -> int:
        return int(self.means.shape[0])

    def pooled_var(self) -> np.ndarray | None:
        """(N,) the dof-weighted within-pose variance per channel (counts^2), None where no pose
        has two samples."""
        dof = np.maximum(self.n - 1, 0).astype(float)
        if dof.sum() <= 0:
            return None
        return (dof[:, None] * self.std ** 2).sum(0) / dof.sum()

    def channel_noise(self) -> np.ndarray:
        """(N,) pooled within-pose std per channel (counts), floored at rounding noise."""
        var = self.pooled_var()
        if var is None:
            return np.full(self.means.shape[1], math.sqrt(QUANT_VAR))
        return np.sqrt(np.maximum(var, QUANT_VAR))

    def sem_scale(self) -> np.ndarray:
        """(N,) how far the poses' means wander beyond the white-noise sem, per channel: sqrt
        of the median over the poses of ``colour_r2`` where at least COLOUR_MIN_POSES poses tell
        and it exceeds COLOUR_MIN_RATIO2, else 1 (:func:`colour_factor`)."""
        N = self.means.shape[1]
        if self.colour_r2 is None:
            return np.ones(N)
        return colour_factor(self.colour_r2)

    def sem(self) -> np.ndarray:
        """(P,N) standard error of each pose mean: the pooled within-pose std over sqrt(n), times
        :meth:`sem_scale` (noise coloured within the poses: a hand's slow tremor, 1/f noise), and
        the rounding's bias, which averaging does not remove where the noise before the rounding
        is below the code step (:func:`accelcal.readings.noise.rounding_bias_var`; a pose on one code is
        off by up to half a step: q/sqrt(12) rms)."""
        N = self.means.shape[1]
        var = self.pooled_var()
        var = np.zeros(N) if var is None else var
        q = np.ones(N) if self.step is None or not self.step.size else self.step.max(axis=0)
        bias = mean_rounding_var(np.sqrt(var), q)
        white = var[None, :] * self.sem_scale()[None, :] ** 2 / np.maximum(self.n, 1)[:, None]
        return np.sqrt(white + bias[None, :])

    @staticmethod
    def concat(sets: Sequence["PoseSet"]) -> "PoseSet":
        return PoseSet(
            means=np.concatenate([s.means for s in sets]),
            n=np.concatenate([s.n for s in sets]),
            std=np.concatenate([s.std for s in sets]),
            f_ref=np.concatenate([s.f_ref for s in sets]),
            temp=np.concatenate([s.temp for s in sets]),
            info=[d for s in sets for d in s.info],
            set_aside=[d for s in sets for d in s.set_aside],
            colour_r2=(None if all(s.colour_r2 is None for s in sets) else np.concatenate(
                [np.full_like(s.means, np.nan) if s.colour_r2 is None else s.colour_r2 for s in sets])),
            step=(None if all(s.step is None for s in sets) else np.concatenate(
                [np.ones_like(s.means) if s.step is None else s.step for s in sets])),
        )


def window_len(device, window_s: float, n: int) -> int:
    w = int(round(window_s * device.sample_rate_hz))
    return max(3, min(w, n))


def detect_static(rec, device, *, window_s: float = STATIC_WINDOW_S, threshold: float = STATIC_THRESHOLD,
                  min_s: float = MIN_POSE_S, noise: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Static intervals of a continuous recording, as sample index pairs [start, stop).

    1. Windows of about ``window_s`` seconds, taken at a stride of a quarter window
       (window_std), are quiet when the std of every channel in them is at most
       ``threshold`` times that channel's noise; the blocks a quiet window covers are
       static.
    2. A run of static blocks is cut where the readings step (two poses joined by an
       instant change, no samples in between): where the means of the quarter windows
       either side differ by more than STEP_SIGMA x noise.
    3. Each piece is refined to the sample: with med its median, its ends move to the
       nearest samples (searching one window beyond and a block inside, never into a
       neighbouring piece) at which some channel is more than EDGE_SIGMA x noise away
       from med.  The window test alone would admit an edge sample up to about
       sqrt(3 w) x noise off.
    4. Intervals shorter than ``min_s`` are dropped, except that a piece whose two ends
       are instant steps or the recording's ends (a logger that records only static
       blocks) needs one window only: no motion touches it, so it is no pause in a
       movement.
    5. A recording made of static blocks alone (:func:`accelcal.readings.steps.logger_steps`: its
       large changes are nearly all isolated steps) gives its blocks whose means hold
       still, however much a hand trembles in them (:func:`accelcal.readings.steps.block_log_intervals`),
       in place of the intervals found in them above; a block holding two of those intervals
       at different levels spans a motion and is dropped (:func:`holds_two_levels`).

    The noise is the device's ``noise_mps2`` (plus rounding) when it is given for
    every channel, else estimated from the data (:func:`accelcal.readings.noise.estimate_noise`),
    unless ``noise`` (counts, per channel) is passed.  Where it is beyond REST_NOISE_MAX of
    the readings' |f| on a channel (:func:`noise_share`) the recording has no rest in it and
    no interval is returned.
    """
    raw = np.asarray(rec.raw)
    n = raw.shape[0]
    w = window_len(device, window_s, n)
    if n < w:
        return []
    sig = np.asarray(noise, float) if noise is not None else noise_for(device, raw, w)[0]
    tone = nyquist_tone(raw)
    if np.any(tone):
        raw, sig = without_nyquist_tone(raw, tone, sig, w)
    noisy = noise_share(raw, device, sig) > REST_NOISE_MAX
    if noisy.any() and np.any(noisy & ~tonal(raw, device.sample_rate_hz, w)):
        return []     # no rest in it (a line's noise, mains aliased to Nyquist or not, is no scatter)
    sig = np.maximum(sig, 1e-9)
    ws, h, k = window_std(raw, w)
    nw = ws.shape[0]
    if nw == 0:
        return []
    quiet = np.all(ws <= threshold * sig[None, :], axis=1)
    runs = [p for a, b in static_runs(quiet, k) for p in run_pieces(raw, a * h, b * h, h, sig)]
    out: list[tuple[int, int]] = []
    refine_pieces(raw, runs, out, w, h, k * h, EDGE_SIGMA * sig, 0, n)
    min_n = max(w, int(math.ceil(min_s * device.sample_rate_hz)))
    out = [iv for iv, keep in zip(out, long_enough(out, n, min_n)) if keep]
    # a recording of static blocks alone: its blocks whose means hold still, tremor or not,
    # and the intervals above that none of them overlaps; a block that holds two of those
    # intervals at different levels spans a motion and is not one
    blocks = [bl for bl in block_log_intervals(raw, sig, w, h) if not holds_two_levels(raw, bl, out, sig)]
    if blocks:
        free = [iv for iv in out if not any(iv[0] < b and a < iv[1] for a, b in blocks)]
        out = sorted(blocks + free)
    return out


def holds_two_levels(raw: np.ndarray, block: tuple[int, int], intervals: Sequence[tuple[int, int]],
                     sig: np.ndarray) -> bool:
    """Whether a logger's block (:func:`accelcal.readings.steps.block_log_intervals`) holds two of the
    window test's static intervals whose means differ by more than MOVE_RANGE x the larger of
    the noise ``sig`` and their std on some channel: two poses with a motion between them, not
    one trembling pose (a recording whose 180 deg turns are instant flips but whose other turns
    are smooth motions: the flips make it look like a logger's blocks, a block then spans the
    smooth turns)."""
    a, b = block
    inside = [(max(a, lo), min(b, hi)) for lo, hi in intervals if lo < b and a < hi]
    inside = [iv for iv in inside if iv[1] - iv[0] >= 2]
    if len(inside) < 2:
        return False
    means = np.array([raw[lo:hi].mean(axis=0) for lo, hi in inside])
    yard = np.maximum(sig, np.median([raw[lo:hi].std(axis=0, ddof=1) for lo, hi in inside], axis=0))
    return bool(np.any((means.max(axis=0) - means.min(axis=0)) > MOVE_RANGE * yard))


def sample_where(rec, i: int) -> str:
    return f"sample {int(i)} (t = {float(rec.t[i]):.6g} s)"


def pose_means(rec, intervals: Sequence[Any], device, *, labels: Sequence[Any] | None = None,
               noise: np.ndarray | None = None, check_motion: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, sample count and within-pose std of each static pose.

    ``intervals``: (start, stop) sample index pairs, or index arrays (a labelled pose
    may be split).  With ``check_motion`` (labelled poses: the user says they are
    static) a pose that moves is refused, naming its label, time span and channel:
    one whose mean over an eighth of it differs from another eighth's by more than
    MOVE_RANGE x the channel's noise, or whose std exceeds MOVE_STD x it; the noise
    is the larger of the recording's and the median within-pose std of the poses
    (tremor that every hand-held pose shows is noise, not motion), and for the mean
    test also of the pose's own median std within its eighths (strong tremor in one
    pose swings its eighths' means; a move or a ramp moves them by many times that).  Clipped readings
    are the caller's to set aside (:func:`poses_from_recording`).
    Returns means (P,N), counts (P,), std (P,N).
    """
    raw = np.asarray(rec.raw)
    n, N = raw.shape
    P = len(intervals)
    idx_list = [interval_index(iv) for iv in intervals]
    names = [f"pose {labels[p]}" if labels is not None else f"static interval {p}" for p in range(P)]
    cnt = np.array([len(ix) for ix in idx_list], dtype=np.int64)
    if P == 0:
        return np.zeros((0, N)), cnt, np.zeros((0, N))
    if np.any(cnt == 0):
        raise InputError(rec.source, f"{names[int(np.argmin(cnt))]} has no samples")
    # one gather, then per-pose reductions; integer arithmetic about a reference is exact
    x = raw[np.concatenate(idx_list)]
    offs = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    ref = x[0].copy()
    x = x - ref
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
        ref_sig = np.maximum(np.asarray(noise, float), np.median(std[cnt >= 3], axis=0) if np.any(cnt >= 3) else 0.0)
        ref_sig = np.maximum(ref_sig, 1e-9)
        for p, idx in enumerate(idx_list):
            if idx.size < 2 * MOVE_PARTS:
                continue
            spread, part_sig = part_spread(raw[idx], ref_sig)
            ratio = std[p] / ref_sig
            bad = np.flatnonzero((spread > MOVE_RANGE) | (ratio > MOVE_STD))
            if bad.size:
                c = int(bad[np.argmax(np.maximum(spread[bad] / MOVE_RANGE, ratio[bad] / MOVE_STD))])
                moves = spread[c] > MOVE_RANGE
                what = (f"its mean moves by {spread[c] * part_sig[c]:.4g} counts" if moves
                        else f"it varies by {std[p, c]:.4g} counts rms")
                raise InputError(rec.source, f"{names[p]} (t = {float(rec.t[idx[0]]):.6g} .. {float(rec.t[idx[-1]]):.6g} s, "
                                 f"samples {int(idx[0])}..{int(idx[-1])}) is labelled static but moves: on raw_{c} "
                                 f"{what}, its noise is {(part_sig if moves else ref_sig)[c]:.3g} counts",
                                 column="pose" if labels is not None else f"raw_{c}")
    return mean, cnt, std


def interval_index(iv: Any) -> np.ndarray:
    """The sample indices of an interval: a (start, stop) pair, or an index array as it is (a
    labelled pose may be split)."""
    if isinstance(iv, tuple) and len(iv) == 2 and np.isscalar(iv[0]):
        return np.arange(int(iv[0]), int(iv[1]))
    return np.asarray(iv, dtype=np.int64)


def split_aside(rec, intervals: list, labels: list | None, aside_of) -> tuple[list, list | None, list[dict]]:
    """``intervals`` (and their ``labels``) less those ``aside_of(p, idx)`` sets aside: for each,
    it returns the record's own fields (reason, n_clipped, channels, levels), or None to keep
    the interval.  One record each of what was set aside, with its source, label and span."""
    keep, keep_lab, aside = [], [] if labels is not None else None, []
    for p, iv in enumerate(intervals):
        idx = interval_index(iv)
        why = aside_of(p, idx)
        if why is None:
            keep.append(iv)
            if labels is not None:
                keep_lab.append(labels[p])
            continue
        aside.append({"source": rec.source, "label": labels[p] if labels is not None else None,
                      "t_start": float(rec.t[idx[0]]), "t_stop": float(rec.t[idx[-1]]), "n": int(idx.size), **why})
    return keep, keep_lab, aside


def set_aside_clipped(rec, intervals: list, labels: list | None, clipped: np.ndarray,
                      levels: ClipLevels) -> tuple[list, list | None, list[dict]]:
    """Drop the poses with a clipped reading (their mean would be biased); one record
    each of what was set aside and why."""

    def aside_of(p: int, idx: np.ndarray) -> dict | None:
        cl = clipped[idx]
        if not cl.any():
            return None
        chans = [int(c) for c in np.flatnonzero(cl.any(axis=0))]
        lv = []
        for c in chans:
            v = rec.raw[idx, c][cl[:, c]]
            lv.append(f"raw_{c} at {int(v.max()) if v.max() >= levels.hi[c] else int(v.min())}")
        return {"reason": "clipped", "n_clipped": int(cl.any(axis=1).sum()), "channels": chans,
                "levels": ", ".join(lv)}

    return split_aside(rec, intervals, labels, aside_of)


def gravity_ratio(raw: np.ndarray, device, intervals: Sequence[Any]) -> np.ndarray:
    """(P,) |f| / g of each interval's mean reading with the device file's nominal offsets and
    sensitivities (least squares over the channels)."""
    raw = np.asarray(raw)
    S = device.nominal_sensitivity()
    b = device.nominal_offsets()
    out = np.full(len(intervals), np.nan)
    for p, iv in enumerate(intervals):
        idx = interval_index(iv)
        if idx.size:
            f = np.linalg.lstsq(S, raw[idx].mean(axis=0) - b, rcond=None)[0]
            out[p] = float(np.linalg.norm(f)) / device.gravity_mps2
    return out


def at_gravity(ratio: np.ndarray) -> np.ndarray:
    """Which intervals can be at rest on the Earth by their |f| / g (``ratio``): within
    REST_F_RANGE, or within REST_F_AGREE of the median of three or more that agree (a wrong
    full scale moves every interval alike)."""
    ratio = np.asarray(ratio, float)
    ok = (ratio >= REST_F_RANGE[0]) & (ratio <= REST_F_RANGE[1])
    agreed = scale_agreement(ratio)
    if agreed is not None:
        ok |= agreed[1]
    return ok


def scale_agreement(ratio: np.ndarray) -> tuple[float, np.ndarray] | None:
    """The median of the finite |f| / g ``ratio`` and which of them agree with it within
    REST_F_AGREE, where three or more do (one wrong scale moves every interval alike), else
    None."""
    ratio = np.asarray(ratio, float)
    fin = ratio[np.isfinite(ratio)]
    if fin.size < 3:
        return None
    med = float(np.median(fin))
    agree = np.abs(ratio / med - 1.0) <= REST_F_AGREE
    return (med, agree) if np.count_nonzero(agree) >= 3 else None


def set_aside_off_gravity(rec, device, intervals: list, labels: list | None) -> tuple[list, list | None, list[dict]]:
    """Drop the poses without a reference f whose |f| is far from g (:func:`at_gravity`): a
    jig-free fit takes |f| = g, and a still stretch in free fall or coasting (a rocket's coast
    read 0.03-0.34 g) is no rest.  One record each of what was set aside and why."""
    if not intervals:
        return intervals, labels, []
    ratio = gravity_ratio(rec.raw, device, intervals)
    ok = at_gravity(ratio)

    def aside_of(p: int, idx: np.ndarray) -> dict | None:
        if ok[p] or np.all(np.isfinite(rec.f[idx])):
            return None
        return {"reason": "not at rest", "n_clipped": 0, "channels": [], "ratio": float(ratio[p]),
                "levels": f"|f| = {ratio[p]:.3g} g with the device file's scale"}

    return split_aside(rec, intervals, labels, aside_of)


#: how the calibration's error and its note on a recording without a static pose begin
NO_POSE = "no static pose found"


def no_pose(min_s: float = MIN_POSE_S) -> str:
    """What a recording without a static pose lacks, under a minimum of ``min_s`` seconds (the
    calibration's error and its note; begins with :data:`NO_POSE`)."""
    return (f"{NO_POSE} (no 'pose' labels, and no interval of at least {min_s:g} s in which every channel is "
            f"within {STATIC_THRESHOLD:g} x its noise)")


def poses_from_recording(rec, device, *, use_labels: bool | None = None, required: bool = True,
                         min_s: float = MIN_POSE_S) -> PoseSet:
    """The static poses of one recording: its ``pose`` labels when it has them (and
    ``use_labels`` is not False), else :func:`detect_static` (``min_s``: its shortest interval
    where a motion touches it, seconds).  Poses with clipped
    readings (:func:`accelcal.readings.clipping.clip_levels`: at raw_min/raw_max or piled up at
    a level inside the range) are set aside and listed in ``set_aside``.  The reference
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
        intervals = detect_static(rec, device, noise=noise, min_s=min_s)
        labels = None
    levels = clip_levels(rec.raw, device, noise, w)
    intervals, labels, aside = set_aside_clipped(rec, intervals, labels, levels.mask(rec.raw), levels)
    intervals, labels, off = set_aside_off_gravity(rec, device, intervals, labels)
    aside += off
    empty = PoseSet(np.zeros((0, device.n_channels)), np.zeros(0, dtype=np.int64),
                    np.zeros((0, device.n_channels)), np.zeros((0, 3)), np.zeros(0), [], aside)
    if not intervals and (not required or aside):
        return empty
    if not intervals:
        raise InputError(rec.source, no_pose(min_s) + no_rest_clause(rec.raw, device, noise)
                         + gravity_removed_clause(rec.raw, device))
    means, cnt, std = pose_means(rec, intervals, device, labels=labels, noise=noise, check_motion=labelled)
    P = len(intervals)
    f_ref = np.full((P, 3), np.nan)
    temp = np.full(P, np.nan)
    info = []
    for p, iv in enumerate(intervals):
        idx = interval_index(iv)
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
    return PoseSet(means=means, n=cnt, std=std, f_ref=f_ref, temp=temp, info=info, set_aside=aside,
                   colour_r2=pose_colour(rec.raw, [interval_index(iv) for iv in intervals]),
                   step=np.tile([float(code_step(rec.raw[:, i])) for i in range(rec.raw.shape[1])], (P, 1)))


def one_wrong_scale(aside: list[dict]) -> float | None:
    """The |f| / g at which three or more poses set aside as "not at rest" (each recording
    judged alone: one pose per file) agree within REST_F_AGREE of their median, or None: one
    wrong scale for them all (readings in m/s^2 read as g are 9.81 x), not free fall."""
    agreed = scale_agreement([d["ratio"] for d in aside if d.get("reason") == "not at rest" and "ratio" in d])
    return None if agreed is None else agreed[0]
