"""Instant steps: where a recording's readings jump from one level to another with no samples
of motion in between, and the static blocks a logger records that way.

* :func:`step_splits` cuts a static run where the means either side differ (two poses
  joined by an instant change).
* :func:`logger_steps` tells a recording made of static blocks alone (a logger that
  records each pose after a prompt, and nothing while the device is turned) from one with
  motions between its poses: nearly all of its large sample-to-sample changes are isolated
  steps, where a motion makes runs of them.
* :func:`block_log_intervals` gives such a recording's blocks as static intervals when
  their means hold still (:func:`part_spread`) however much the hand trembles in them: the
  window test of :func:`accelcal.readings.static.detect_static` measures tremor against the
  recording's noise, and a hand-held logger's tremor can be twice that in every window of
  a pose (CK-Explorer's acc_log.csv: 64 of its 160 blocks found at 100 Hz, 160 with this).
"""
from __future__ import annotations

import numpy as np

from .noise import MAD_TO_STD

__all__ = ["STEP_SIGMA", "MOVE_PARTS", "MOVE_RANGE", "MOVE_STD", "BLOCK_JUMP", "BLOCK_SPAN", "BLOCK_LEVELS",
           "BLOCK_SHARE", "BLOCK_EDGE", "step_splits", "part_spread", "logger_steps", "block_log_intervals"]


STEP_SIGMA = 4.0           # an instant step inside a static run: means of the h samples either side
                           # differ by this x noise (the same size EDGE_SIGMA calls an edge)


MOVE_PARTS = 8             # the parts a pose is cut into for the mean test


BLOCK_JUMP = 12.0          # a large change: between two samples, this x the robust std of such changes


BLOCK_SPAN = 2             # a logger's step: large changes over at most this many samples, none other
                           # within a quarter window either side


BLOCK_LEVELS = 10.0        # ... between two levels: the means of the quarter windows either side differ by
                           # this x their std (a quick motion's peak: 2.6-8.6; CK-Explorer's steps: 95 % > 15)


BLOCK_SHARE = 0.5          # a recording of static blocks: at least this share of its large changes are steps


BLOCK_EDGE = 8.0           # a block's end samples this x its yardstick off its median belong to the step


MOVE_RANGE = 8.0           # a pose "moves" when a channel's mean over a part of it strays this x its
                           # noise from another part's ...


MOVE_STD = 6.0             # ... or its std exceeds this x its noise (noise: the larger of the recording's
                           # and the median within-pose std of the poses: hand-held tremor is noise)


def step_splits(raw: np.ndarray, a: int, b: int, m: int, sig: np.ndarray) -> list[int]:
    """Sample indices in (a, b) at which the readings step: the means of the m samples
    before and after differ by more than STEP_SIGMA x noise on some channel (the local
    maximum of each run of such indices), and so do the medians of the pieces between
    neighbouring splits (the least distinct split is dropped until all are)."""
    L = b - a
    if L < 2 * m + 1:
        return []
    x = np.asarray(raw[a:b], float)
    c = np.concatenate([np.zeros((1, x.shape[1])), np.cumsum(x - x[0], axis=0)])
    i = np.arange(m, L - m + 1)                       # split before local sample i
    left = (c[i] - c[i - m]) / m
    right = (c[i + m] - c[i]) / m
    z = np.max(np.abs(right - left) / sig[None, :], axis=1)
    over = z > STEP_SIGMA
    if not over.any():
        return []
    edges = np.diff(np.concatenate([[0], over.astype(np.int8), [0]]))
    out = []
    for s0, e0 in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        out.append(a + int(i[s0 + int(np.argmax(z[s0:e0]))]))
    # a step joins two levels: a split whose pieces' medians do not differ by that much
    # was a swing of coloured (tremor) noise inside one pose (the least distinct goes first;
    # only the merged piece's median and its two splits' distinctness change)
    cuts = [a] + out + [b]
    med = [np.median(raw[cuts[j]:cuts[j + 1]], axis=0) for j in range(len(cuts) - 1)]

    def apart(j):
        return float(np.max(np.abs(med[j + 1] - med[j]) / sig))

    z = [apart(j) for j in range(len(out))]
    while z:
        j = int(np.argmin(z))
        if z[j] > STEP_SIGMA:
            break
        del cuts[j + 1], med[j + 1], z[j]
        med[j] = np.median(raw[cuts[j]:cuts[j + 1]], axis=0)
        if j > 0:
            z[j - 1] = apart(j - 1)
        if j < len(z):
            z[j] = apart(j)
    return cuts[1:-1]


def part_spread(x: np.ndarray, ref_sig: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far the means of MOVE_PARTS consecutive parts of the readings ``x`` (n, N) stray:
    (their range per channel over ``part_sig``, ``part_sig``), with ``part_sig`` the larger of
    ``ref_sig`` and the parts' median std (strong tremor swings the parts' means; a move or
    a ramp moves them by many times what each part varies within).  Readings too few to give
    every part two samples (fewer than 2 MOVE_PARTS: a part's std would be 0/0) cannot tell
    that they hold still: their range is inf (the mean test fails) and ``part_sig`` is ``ref_sig``."""
    x = np.asarray(x, float)
    if x.shape[0] < 2 * MOVE_PARTS:
        return np.full(x.shape[1], np.inf), np.asarray(ref_sig, float) * np.ones(x.shape[1])
    parts = np.array_split(x, MOVE_PARTS)
    pm = np.array([q.mean(axis=0) for q in parts])
    part_sig = np.maximum(ref_sig, np.median([q.std(axis=0, ddof=1) for q in parts], axis=0))
    return (pm.max(axis=0) - pm.min(axis=0)) / part_sig, part_sig


def logger_steps(raw: np.ndarray, sig: np.ndarray, w: int) -> list[tuple[int, int]] | None:
    """The instant steps of a recording made of static blocks, as (first, stop) sample
    ranges of the change (``first`` the first sample after the block before; ``stop`` the
    first of the block after: one transition sample at most between), or None when the
    recording is not one.

    A large change is one between two samples of BLOCK_JUMP x the robust std of all such
    changes on some channel; large changes within BLOCK_SPAN samples of each other are one.
    It is a step where no other large change lies within a quarter window ``w`` either side
    and the means of the quarter windows either side differ by STEP_SIGMA x noise ``sig``
    and by BLOCK_LEVELS x the larger of their std (two levels, not a quick motion's peak).
    The recording is made of blocks when at least two of its large changes, and BLOCK_SHARE
    of them, are steps (a motion between poses makes runs of large changes: no more than 4
    and 20 of 707 and 8,486 are isolated at all on the real MPU-6050 and Xsens recordings;
    CK-Explorer's blocks: 81-85 % steps)."""
    raw = np.asarray(raw)
    n = raw.shape[0]
    if n < 3:
        return None
    d = np.diff(raw.astype(float), axis=0)
    s_d = np.maximum(MAD_TO_STD * np.median(np.abs(d - np.median(d, axis=0)), axis=0), 1.0)
    big = np.flatnonzero(np.any(np.abs(d) > BLOCK_JUMP * s_d, axis=1)) + 1   # first sample after the change
    if big.size < 2:
        return None
    groups = np.split(big, np.flatnonzero(np.diff(big) > BLOCK_SPAN) + 1)
    m = max(2, w // 4)
    steps = []
    for k, g in enumerate(groups):
        lo, hi = int(g[0]), int(g[-1])
        before = int(groups[k - 1][-1]) if k else -n
        after = int(groups[k + 1][0]) if k + 1 < len(groups) else 2 * n
        if hi - lo > BLOCK_SPAN or lo - before < m or after - hi < m or lo - 1 - m < 0 or hi + m > n:
            continue
        left = raw[lo - 1 - m:lo - 1].astype(float)
        right = raw[hi:hi + m].astype(float)
        jump = np.abs(right.mean(axis=0) - left.mean(axis=0))
        spread = np.maximum(np.maximum(left.std(axis=0), right.std(axis=0)), 1.0)
        if np.any(jump > STEP_SIGMA * sig) and np.max(jump / spread) >= BLOCK_LEVELS:
            steps.append((lo, hi))
    if len(steps) < 2 or len(steps) < BLOCK_SHARE * len(groups):
        return None
    return steps


def block_log_intervals(raw: np.ndarray, sig: np.ndarray, w: int, h: int) -> list[tuple[int, int]]:
    """The static blocks of a recording made of them (:func:`logger_steps`; [] for any
    other), as [start, stop) pairs: the pieces between its steps and the splits where the
    readings step (:func:`step_splits` against the yardstick below: steps too small for a
    large change), at least ``w`` samples long, trimmed of end samples BLOCK_EDGE x the yardstick
    off the median (a transition sample), whose parts' means hold still (:func:`part_spread`
    within MOVE_RANGE) and whose std is within MOVE_STD x the yardstick: the larger of the
    noise ``sig`` and the pieces' median std (the tremor every hand-held pose shows)."""
    raw = np.asarray(raw)
    n = raw.shape[0]
    steps = logger_steps(raw, sig, w)
    if steps is None:
        return []

    def pieces_between(cuts):
        return [(a, b) for a, b in zip(cuts[:-1], cuts[1:]) if b - a >= w]

    cuts = sorted({0, n, *(c for s in steps for c in s)})
    first = pieces_between(cuts)
    if not first:
        return []
    ref = np.maximum(sig, np.median([raw[a:b].std(axis=0, ddof=1) for a, b in first], axis=0))
    # steps too small for a large change, measured against the tremor, not the noise alone
    pieces = pieces_between(sorted({*cuts, *step_splits(raw, 0, n, max(2, h), ref)}))
    out = []
    for a, b in pieces:
        med = np.median(raw[a:b], axis=0)
        off = np.any(np.abs(raw[a:b] - med) > BLOCK_EDGE * ref, axis=1)
        while a < b and off[0]:
            a, off = a + 1, off[1:]
        while b > a and off[-1]:
            b, off = b - 1, off[:-1]
        if b - a < w:
            continue
        spread, _ = part_spread(raw[a:b], ref)
        if np.all(spread <= MOVE_RANGE) and np.all(raw[a:b].std(axis=0, ddof=1) <= MOVE_STD * ref):
            out.append((int(a), int(b)))
    return out
