"""The readings' noise of :func:`accelcal.readings.noise.estimate_noise` (integer readings) from
a recording read in chunks, the same floats (docs/streaming.md, "convert in bounded memory").

``estimate_noise`` takes, per channel, the rest level of the window stds (:func:`noise.window_std`:
blocks of h samples, windows of k blocks, their sums about one reference reading, the median of
every ``n // 1000``-th row) and, with one regime only, the white noise of the fourth differences.
:class:`NoisePass` computes the block sums chunk by chunk with the whole-file reference (the rows
it takes are known once the first pass has counted them), carries the cumulative sums across
chunk boundaries (numpy's cumsum adds in order: the same floats), and keeps of each window its
std (one float a window, spilled to a temporary file, held windows left out as the whole-file
function leaves them out), and of the fourth differences their histogram (integers: the medians
are exact).  :func:`rest_level_sorted` is :func:`noise.rest_level` over a sorted array in slices
(its Otsu split the same floats, its temporaries a slice).  Memory: one channel's window stds at
the end (8 bytes a window: 1.1 bytes a sample at 60 Hz, 0.06 at 1 kHz) and the histograms.
"""
from __future__ import annotations

import math
import tempfile
from typing import Any

import numpy as np

from .noise import MAD_TO_STD, NOISE_SPLIT_RATIO, ONE_REGIME_RATIO

__all__ = ["NoisePass", "add_counts", "median_of_counts", "rest_level_sorted", "white_noise_counts", "SLICE"]

#: values a slice of the Otsu split holds
SLICE = 1 << 16


def add_counts(counts: dict, values: np.ndarray) -> None:
    """Add the distinct ``values`` and their counts to ``counts`` (value -> count; the values as
    Python numbers).  The one home of this tally: convert.bounded, estimators.stream_scan, readings.held."""
    u, c = np.unique(values, return_counts=True)
    for v, k in zip(u.tolist(), c.tolist()):
        counts[v] = counts.get(v, 0) + k


def median_of_counts(counts: dict) -> float:
    """``np.median`` of the values counted in ``counts`` (value -> count), from the counts: the
    middle value, or the mean of the two middle ones (the one home of this rule: convert.bounded,
    estimators.stream_scan)."""
    u = np.array(sorted(counts))
    c = np.array([counts[v] for v in u.tolist()], dtype=np.int64)
    n = int(c.sum())
    cum = np.cumsum(c)
    a = u[int(np.searchsorted(cum, (n - 1) // 2, side="right"))]
    if n % 2:
        return float(a)
    b = u[int(np.searchsorted(cum, n // 2, side="right"))]
    return float(np.mean(np.array([a, b], dtype=float)))


def white_noise_counts(d4: dict, n: int) -> float:
    """:func:`accelcal.readings.noise.white_noise` of a channel of ``n`` readings from the counts
    of its fourth differences ``d4`` (exact integers)."""
    if n < 10:
        return 0.0
    med = median_of_counts(d4)
    dev: dict = {}
    for v, k in d4.items():
        a = abs(v - med)
        dev[a] = dev.get(a, 0) + k
    return float(MAD_TO_STD * median_of_counts(dev) / math.sqrt(70.0))


def rest_level_sorted(v: np.ndarray) -> tuple[float, bool]:
    """:func:`accelcal.readings.noise.rest_level` of window stds ``v`` already sorted ascending and
    finite (>= 0), with its arrays of the size of ``v`` taken in slices of SLICE values."""
    if v.size == 0 or v[-1] <= 0.0:
        return 0.0, False
    n = v.size
    if n < 4:
        return median_sorted(v), False
    first_pos = v[int(np.searchsorted(v, 0.0, side="right"))]
    floor = 0.1 * first_pos
    total = 0.0
    c_end = None
    # np.cumsum adds in order: the running sum carried from slice to slice gives its floats
    for a in range(0, n, SLICE):
        x = np.log(np.maximum(v[a:a + SLICE], floor))
        c = np.cumsum(np.concatenate([[total], x]))[1:] if a else np.cumsum(x)
        total = float(c[-1])
    c_end = total
    best, best_j, total = -np.inf, 1, 0.0
    prev_x = None
    for a in range(0, n - 1, SLICE):
        b = min(a + SLICE, n - 1)             # split k = a+1 .. b: lo v[:k]
        x = np.log(np.maximum(v[a:b + 1], floor))
        c = np.cumsum(np.concatenate([[total], x[:-1]]))[1:] if a else np.cumsum(x[:-1])
        total = float(c[-1])
        k = np.arange(a + 1, b + 1)
        m0 = c / k
        m1 = (c_end - c) / (n - k)
        between = k * (n - k) * (m1 - m0) ** 2
        between[x[1:] == x[:-1]] = -1.0
        j = int(np.argmax(between))
        if between[j] > best:                  # the first of equals, as np.argmax over the whole
            best, best_j = float(between[j]), a + 1 + j
        prev_x = x
    del prev_x
    j = best_j
    if best <= 0 or median_sorted(v[j:]) < NOISE_SPLIT_RATIO * max(median_sorted(v[:j]), 1e-300):
        return median_sorted(v), False
    return median_sorted(v[:j]), True


def median_sorted(v: np.ndarray) -> float:
    """``np.median`` of ``v`` sorted ascending, without its copy: the middle value, or numpy's mean
    of the two middle ones."""
    n = v.size
    return float(np.mean(v[(n - 1) // 2:n // 2 + 1]))


class NoisePass:
    """``estimate_noise(raw, window, integer=True)`` of a recording of ``n`` rows fed in chunks.

    Each window's integer sums of its readings and of their squares (and its first reading) go to a
    temporary file as the chunks go by; the reference reading (the median of every ``n // 1000``-th
    row) is known at the end, and each window's std is then the whole-file function's float of
    the same exact sums about it.  Exact where the whole-file cumulative sums are (every partial
    sum below 2**50: :meth:`noise` raises ValueError otherwise).

    Parameters
    ----------
    n : int
        Rows of the recording (from a first pass).
    window : int
        The window length, samples.
    lo, hi : ndarray (N,) int
        Each channel's least and greatest reading (a held window at them is left out).
    q : ndarray (N,)
        Each channel's code step (:func:`accelcal.readings.noise.code_step`).
    """

    def __init__(self, n: int, window: int, lo: np.ndarray, hi: np.ndarray, q: np.ndarray) -> None:
        self.n, self.N = n, len(q)
        self.h = max(1, window // 4)
        self.k = max(1, -(-window // self.h))
        self.nb = n // self.h
        self.lo, self.hi, self.q = np.asarray(lo), np.asarray(hi), np.asarray(q, float)
        self.stride = max(1, n // 1000)
        self.ref_rows: list[np.ndarray] = []
        self.seen = 0
        self.rest = np.zeros((0, self.N), np.int64)     # rows after the last whole block
        self.blocks = 0
        self.keep = np.zeros((0, 3, self.N), np.int64)  # the last k - 1 blocks' sums, squares, first rows
        self.tail = np.zeros((0, self.N), np.int64)     # the last 4 rows (fourth differences)
        self.d4: list[dict] = [{} for _ in range(self.N)]
        self.file: Any = tempfile.TemporaryFile()
        self.windows = 0

    def add(self, raw: np.ndarray) -> None:
        """The next rows (m, N) of counts."""
        raw = np.asarray(raw, dtype=np.int64)
        m = raw.shape[0]
        if not m:
            return
        idx = np.arange(self.seen, self.seen + m)
        self.ref_rows.append(raw[idx % self.stride == 0])
        self.seen += m
        both = np.concatenate([self.tail, raw])
        if both.shape[0] >= 5:
            v = both.astype(float)
            d = v[:-4] - 4 * v[1:-3] + 6 * v[2:-2] - 4 * v[3:-1] + v[4:]
            for i in range(self.N):
                add_counts(self.d4[i], d[:, i])
        self.tail = both[-4:]
        x = np.concatenate([self.rest, raw])
        h, N, k = self.h, self.N, self.k
        take = min(x.shape[0] // h, self.nb - self.blocks)
        self.rest = x[take * h:] if take > 0 else x
        if take <= 0:
            return
        xb = x[:take * h].reshape(take, h, N)
        blk = np.stack([xb.sum(axis=1), (xb * xb).sum(axis=1), xb[:, 0]], axis=1)
        self.blocks += take
        allb = np.concatenate([self.keep, blk])
        if allb.shape[0] >= k:
            cs = np.concatenate([np.zeros((1, 2, N), np.int64), np.cumsum(allb[:, :2], axis=0)])
            win = np.concatenate([cs[k:] - cs[:-k], allb[:allb.shape[0] - k + 1, 2:]], axis=1)
            self.file.write(np.ascontiguousarray(win).tobytes())
            self.windows += win.shape[0]
        self.keep = allb[max(allb.shape[0] - (k - 1), 0):] if k > 1 else allb[:0]

    def noise(self, slice_windows: int = SLICE) -> np.ndarray:
        """(N,) counts: ``estimate_noise``'s, once every row has been added.

        Raises
        ------
        ValueError
            Rows missing, or sums the whole-file floats do not hold exactly."""
        if self.seen != self.n:
            raise ValueError(f"{self.seen} rows added of {self.n}")
        ref = np.median(np.concatenate(self.ref_rows), axis=0)
        dev = np.maximum(np.abs(self.hi - ref), np.abs(self.lo - ref)) + 1
        big = float(np.max(2 * dev)) ** 2
        if self.n * big >= 2.0 ** 50 or big * self.h * self.k >= 2.0 ** 50:
            raise ValueError("sums beyond the floats' exact integers")
        h, k, N = self.h, self.k, self.N
        L = k * h
        self.r2 = np.round(2 * ref).astype(np.int64)            # the median of integers: whole or half
        cols = [tempfile.TemporaryFile() for _ in range(N)]
        for ws, first in self.window_stds(slice_windows):
            for i in range(N):
                held = (ws[:, i] == 0) & ((first[:, i] == self.hi[i]) | (first[:, i] == self.lo[i]))
                cols[i].write(np.ascontiguousarray(ws[~held, i]).tobytes())
        out = np.zeros(N)
        for i in range(N if self.windows else 0):
            cols[i].seek(0)
            col = np.fromfile(cols[i], dtype=np.float64)
            if not np.isfinite(col).all():
                col = col[np.isfinite(col)]
            col.sort()
            out[i], split = rest_level_sorted(col)
            del col
            out[i] *= math.sqrt(L / max(L - 1, 1))
            if not split:
                out[i] = min(out[i], ONE_REGIME_RATIO * white_noise_counts(self.d4[i], self.n))
        for fh in cols:
            fh.close()
        return np.sqrt(out ** 2 + self.q ** 2 / 12.0)

    def window_stds(self, slice_windows: int = SLICE):
        """Each window's std per channel (:func:`noise.window_std`'s floats) and its first reading,
        ``slice_windows`` windows at a time, once :meth:`noise` has been taken (it knows the
        reference reading)."""
        h, k, N = self.h, self.k, self.N
        L = k * h
        r2 = self.r2
        self.file.seek(0)
        per = 3 * N * 8
        while True:
            buf = self.file.read(per * slice_windows)
            if not buf:
                break
            win = np.frombuffer(buf, dtype=np.int64).reshape(-1, 3, N)
            w1, w2, first = win[:, 0], win[:, 1], win[:, 2]
            # the whole-file window sums about ref, exact: S1 = sum(x - ref), S2 = sum((x - ref)^2)
            S1 = (2 * w1 - L * r2).astype(float) / 2.0
            S2 = (4 * w2 - 4 * r2 * w1 + L * r2 * r2).astype(float) / 4.0
            yield np.sqrt(np.maximum((S2 - S1 * S1 / L) / L, 0.0)), first

    def quiet(self, limit: np.ndarray, slice_windows: int = SLICE) -> np.ndarray:
        """(windows,) bool: every channel's window std <= ``limit`` (counts, per channel; the
        static detector's quiet windows), once :meth:`noise` has been taken."""
        return np.concatenate([np.all(ws <= limit[None, :], axis=1) for ws, _ in self.window_stds(slice_windows)]
                              or [np.zeros(0, bool)])

    def close(self) -> None:
        """The windows' temporary file removed."""
        self.file.close()
