"""The static detector (:func:`accelcal.readings.static.detect_static`) over a recording read in
chunks, its intervals the same, for the nominal scale of ``accelcal convert`` without a stated one
(docs/streaming.md, "convert without a stated scale").

What ``detect_static`` takes from the whole recording comes from passes over the chunks:

* :class:`DiffSums` (first pass): the sums of |lag-1| and |lag-2| differences (the Nyquist-tone
  test, :func:`accelcal.readings.noise.nyquist_tone`: exact integers) and the lag-1 differences'
  histograms (the robust std of the changes, :func:`accelcal.readings.steps.logger_steps`);
* the noise pass (:class:`accelcal.readings.noise_stream.NoisePass`): the noise, each window's std
  (the quiet windows), the rows the noise-share test takes (every ``n // 5000``-th) and
  :class:`LoggerBound`, which counts the large changes and the isolated ones among them: where
  those cannot make the recording a logger's static blocks, ``block_log_intervals`` gives none;
* :class:`StillPass` (a third pass): the samples of one run of static blocks at a time, and a
  window either side, on which the step splits and the end refinement run as on the whole
  recording (:mod:`accelcal.readings.still_pieces`), and the mean of each interval found.

Memory: the histograms, one bool a window (the quiet windows), the runs and intervals found (a few
numbers each) and the samples of the longest run of static blocks (its caller bounds it).
"""
from __future__ import annotations

import numpy as np

from .noise import NYQUIST_RATIO, MAD_TO_STD
from .noise_stream import add_counts, median_of_counts
from .steps import BLOCK_JUMP, BLOCK_SHARE, BLOCK_SPAN
from .still_pieces import refine_pieces, run_pieces

__all__ = ["DiffSums", "LoggerBound", "StillPass", "percentiles_of_counts", "order_stat_of"]

#: sums the floats of numpy's means hold exactly
EXACT = 2.0 ** 53


def order_stat_of(u: np.ndarray, cnt: np.ndarray, i: int) -> np.int64:
    """The ``i``-th smallest (0-based) of the values ``u`` (ascending) counted ``cnt`` times."""
    return u[int(np.searchsorted(np.cumsum(cnt), i, side="right"))]


def percentiles_of_counts(u: np.ndarray, cnt: np.ndarray, qs=(1.0, 99.0)) -> np.ndarray:
    """``np.percentile(x, qs)`` (its default, linear method) of the integers ``x`` counted in a
    histogram (``u`` ascending, ``cnt``): numpy's virtual index, its order statistics and its
    interpolation, the same floats."""
    n = int(np.sum(cnt))
    q = np.true_divide(np.asarray(qs, float), 100)
    vi = (n - 1) * q
    out = np.empty(q.size)
    for j, v in enumerate(vi):
        prev = int(np.floor(v))
        if v >= n - 1:
            prev = nxt = n - 1
            gamma = v - np.float64(-1)
        else:
            nxt = prev + 1
            gamma = v - np.float64(prev)
        a, b = np.int64(order_stat_of(u, cnt, prev)), np.int64(order_stat_of(u, cnt, nxt))
        diff = b - a
        out[j] = b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma
    return out


class DiffSums:
    """Each channel's sums of |x[k+1] - x[k]| and |x[k+2] - x[k]| and the histogram of x[k+1] -
    x[k] over a recording fed in chunks (integer counts)."""

    def __init__(self, n_channels: int = 3) -> None:
        self.tail = np.zeros((0, n_channels), np.int64)
        self.d1 = np.zeros(n_channels, np.int64)
        self.d2 = np.zeros(n_channels, np.int64)
        self.hist: list[dict] = [{} for _ in range(n_channels)]
        self.n = 0

    def add(self, raw: np.ndarray) -> None:
        both = np.concatenate([self.tail, np.asarray(raw, np.int64)])
        if both.shape[0] >= 2:
            d = np.diff(both[max(0, self.tail.shape[0] - 1):], axis=0)
            self.d1 += np.abs(d).sum(axis=0)
            for i in range(d.shape[1]):
                add_counts(self.hist[i], d[:, i])
        if both.shape[0] >= 3:
            self.d2 += np.abs(both[2:] - both[:-2]).sum(axis=0)
        self.tail = both[-2:]
        self.n += raw.shape[0]

    def tone(self) -> np.ndarray | None:
        """``nyquist_tone`` of the rows added; None where the sums pass the floats' exact integers."""
        n = self.n
        if n < 8:
            return np.zeros(self.d1.size, bool)
        if max(int(self.d1.max()), int(self.d2.max())) >= EXACT:
            return None
        d1 = self.d1.astype(float) / (n - 1)
        d2 = self.d2.astype(float) / (n - 2)
        return (d1 > 0) & (d1 >= NYQUIST_RATIO * d2)

    def change_std(self) -> np.ndarray:
        """``logger_steps``' robust std of the sample-to-sample changes, per channel (at least 1)."""
        out = np.zeros(len(self.hist))
        for i, h in enumerate(self.hist):
            med = median_of_counts(h)
            dev: dict = {}
            for v, k in h.items():
                a = abs(v - med)
                dev[a] = dev.get(a, 0) + k
            out[i] = median_of_counts(dev)
        return np.maximum(MAD_TO_STD * out, 1.0)


class LoggerBound:
    """Whether :func:`accelcal.readings.steps.logger_steps` can find a logger's static blocks in a
    recording of ``n`` rows fed in chunks: its large changes (``BLOCK_JUMP`` x ``s_d``, the robust
    std of the changes) grouped as it groups them, and of the groups those that could be steps (at
    most BLOCK_SPAN samples, no other group within ``m`` samples either side, ``m`` samples before
    and after in the recording).  Its steps are among these; where they are fewer than two or
    than BLOCK_SHARE of the groups, it finds none."""

    def __init__(self, n: int, s_d: np.ndarray, m: int) -> None:
        self.n, self.m = n, m
        self.lim = BLOCK_JUMP * np.asarray(s_d, float)
        self.last: np.ndarray | None = None
        self.seen = 0
        self.big = 0
        self.groups = 0
        self.cands = 0
        self.before = -n                 # the last sample of the group before the open one
        self.open: tuple[int, int] | None = None

    def count(self, los: np.ndarray, his: np.ndarray, befores: np.ndarray, afters: np.ndarray) -> None:
        m, n = self.m, self.n
        ok = (his - los <= BLOCK_SPAN) & (los - befores >= m) & (afters - his >= m) & (los - 1 - m >= 0) & \
             (his + m <= n)
        self.groups += los.size
        self.cands += int(np.count_nonzero(ok))

    def add(self, raw: np.ndarray) -> None:
        raw = np.asarray(raw, np.int64)
        if not raw.shape[0]:
            return
        both = raw if self.last is None else np.concatenate([self.last, raw])
        base = self.seen - (0 if self.last is None else 1)
        d = np.diff(both.astype(float), axis=0)
        idx = np.flatnonzero(np.any(np.abs(d) > self.lim, axis=1)) + 1 + base
        self.last, self.seen = raw[-1:], self.seen + raw.shape[0]
        if not idx.size:
            return
        self.big += idx.size
        brk = np.flatnonzero(np.diff(idx) > BLOCK_SPAN) + 1
        los = idx[np.concatenate([[0], brk])].astype(np.int64)
        his = idx[np.concatenate([brk - 1, [idx.size - 1]])].astype(np.int64)
        if self.open is not None:
            if los[0] - self.open[1] <= BLOCK_SPAN:
                los[0] = self.open[0]
            else:
                los, his = np.concatenate([[self.open[0]], los]), np.concatenate([[self.open[1]], his])
        befores = np.concatenate([[self.before], his[:-1]])
        self.count(los[:-1], his[:-1], befores[:-1], los[1:])
        self.before, self.open = int(befores[-1]), (int(los[-1]), int(his[-1]))

    def maybe_logger(self) -> bool:
        """False where ``logger_steps`` gives None for certain (once every row has been added)."""
        if self.open is not None:
            self.count(np.array([self.open[0]]), np.array([self.open[1]]), np.array([self.before]),
                       np.array([2 * self.n]))
            self.open = None
        if self.n < 3 or self.big < 2:
            return False
        return not (self.cands < 2 or self.cands < BLOCK_SHARE * self.groups)


class StillPass:
    """The static detector's intervals within given runs of static blocks, over a recording of
    ``n`` rows fed in chunks: for each run [a, b) (samples, ascending), the rows from a - ``ext``
    to b + ``ext`` are held, then cut at their instant steps and refined as ``detect_static`` does
    (:func:`accelcal.readings.still_pieces.run_pieces`, :func:`~accelcal.readings.still_pieces.refine_pieces`:
    window ``w``, block ``h``, noise ``sig``, edge limit ``lim``, counts); ``out`` the intervals,
    ``means`` the mean reading of each (numpy's mean of its rows: the same floats)."""

    def __init__(self, n: int, runs: list[tuple[int, int]], w: int, h: int, ext: int, sig: np.ndarray,
                 lim: np.ndarray) -> None:
        self.n, self.runs, self.w, self.h, self.ext = n, runs, w, h, ext
        self.sig, self.lim = sig, lim
        self.spans = [(max(0, a - ext), min(n, b + ext)) for a, b in runs]
        self.next = 0
        self.active: dict[int, list[np.ndarray]] = {}
        self.seen = 0
        self.out: list[tuple[int, int]] = []
        self.means: list[np.ndarray] = []

    @staticmethod
    def longest(n: int, runs: list[tuple[int, int]], ext: int) -> int:
        """The most rows a StillPass over ``runs`` holds at once (its widest span)."""
        return max((min(n, b + ext) - max(0, a - ext) for a, b in runs), default=0)

    def add(self, raw: np.ndarray) -> None:
        s, e = self.seen, self.seen + raw.shape[0]
        while self.next < len(self.spans) and self.spans[self.next][0] < e:
            self.active[self.next] = []
            self.next += 1
        for r, parts in self.active.items():
            lo, hi = self.spans[r]
            a, b = max(lo, s), min(hi, e)
            if b > a:
                parts.append(np.asarray(raw[a - s:b - s], np.int64))
        for r in sorted(self.active):
            if self.spans[r][1] > e:
                break
            self.piece(r, np.concatenate(self.active.pop(r)))
        self.seen = e

    def piece(self, r: int, x: np.ndarray) -> None:
        off = self.spans[r][0]
        a, b = self.runs[r]
        pieces = run_pieces(x, a, b, self.h, self.sig, off)
        first = len(self.out)
        refine_pieces(x, pieces, self.out, self.w, self.h, self.ext, self.lim,
                      self.runs[r - 1][1] if r else 0, self.runs[r + 1][0] if r + 1 < len(self.runs) else self.n, off)
        self.means += [x[lo - off:hi - off].mean(axis=0) for lo, hi in self.out[first:]]

    def finish(self) -> None:
        """Every row added (ValueError otherwise)."""
        if self.seen != self.n or self.active or self.next != len(self.spans):
            raise ValueError(f"{self.seen} rows added of {self.n}")
