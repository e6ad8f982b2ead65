"""The static detector's still stretches, piece by piece (:func:`accelcal.readings.static.detect_static`
and its reader in chunks, :class:`accelcal.readings.still_stream.StillPass`, share these).

* :func:`static_runs`: the runs of static blocks the quiet windows cover;
* :func:`run_pieces`: a run cut where its readings step (:func:`accelcal.readings.steps.step_splits`);
* :func:`refine_pieces`: each piece's ends refined to the sample, against its median;
* :func:`long_enough`: the intervals kept (MIN_POSE_S, or one window between instant steps).

Every function takes sample indices into ``raw`` less ``off`` (``raw`` may hold only the samples
of one still stretch and the window either side: the same floats as on the whole recording,
since every quantity here is taken over the piece's own samples).
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from .steps import step_splits

__all__ = ["static_runs", "run_pieces", "refine_pieces", "long_enough"]


def static_runs(quiet: np.ndarray, k: int) -> list[tuple[int, int]]:
    """The runs [a, b) of static blocks (block indices): block j is static when a quiet window i
    (``quiet``: one bool a window, window i covering blocks i .. i + k - 1) covers it."""
    e = np.diff(np.concatenate([[0], np.asarray(quiet, np.int8), [0]]))
    out: list[tuple[int, int]] = []
    for a, b in zip(np.flatnonzero(e == 1).tolist(), (np.flatnonzero(e == -1) + k - 1).tolist()):
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def run_pieces(raw: np.ndarray, a: int, b: int, h: int, sig: np.ndarray, off: int = 0
               ) -> list[tuple[int, int, bool, bool]]:
    """The pieces of the static run [a, b) between its instant steps, (start, stop, start is a
    step, stop is a step)."""
    cuts = [a] + [c + off for c in step_splits(raw, a - off, b - off, max(2, h), sig)] + [b]
    return [(cuts[j], cuts[j + 1], j > 0, j + 2 < len(cuts)) for j in range(len(cuts) - 1)]


def refine_pieces(raw: np.ndarray, pieces: Sequence[tuple[int, int, bool, bool]], out: list, w: int, h: int,
                  ext: int, lim: np.ndarray, prev_stop: int, next_start: int, off: int = 0) -> list[int]:
    """Append to ``out`` each piece refined to the sample, where it keeps ``w`` samples: its ends
    move to the nearest samples (one window ``ext`` beyond, a block ``h`` inside, never into a
    neighbouring piece, the previous interval of ``out``, ``prev_stop`` or ``next_start``) at which
    some channel is more than ``lim`` away from the piece's median (of a subsample: its length /
    2,000).  Returns which pieces were appended (their indices)."""
    kept = []
    for r, (a, b, cut_a, cut_b) in enumerate(pieces):
        lo_lim = max(out[-1][1] if out else 0, pieces[r - 1][1] if r else prev_stop)
        hi_lim = pieces[r + 1][0] if r + 1 < len(pieces) else next_start
        lo = a if cut_a else max(lo_lim, a - ext)
        hi = b if cut_b else min(hi_lim, b + ext)
        if b - a < 1:
            continue
        med = np.median(raw[a - off:b - off:max(1, (b - a) // 2000)], axis=0)
        left = np.flatnonzero(np.any(np.abs(raw[lo - off:min(a + h, b) - off] - med) > lim, axis=1))
        start = lo + (int(left[-1]) + 1 if left.size else 0)
        r0 = max(b - h, a)
        right = np.flatnonzero(np.any(np.abs(raw[r0 - off:hi - off] - med) > lim, axis=1))
        stop = r0 + int(right[0]) if right.size else hi
        if stop - start >= w:
            out.append((int(start), int(stop)))
            kept.append(r)
    return kept


def long_enough(out: Sequence[tuple[int, int]], n: int, min_n: int) -> list[bool]:
    """Which intervals of ``out`` (of a recording of ``n`` samples) are kept: at least ``min_n``
    samples, or joined to its neighbours (or the recording's ends) with no sample between them
    (recorded as a static block: no motion touches it)."""
    stops = {0} | {iv[1] for iv in out}
    starts = {n} | {iv[0] for iv in out}
    return [iv[1] - iv[0] >= min_n or (iv[0] in stops and iv[1] in starts) for iv in out]
