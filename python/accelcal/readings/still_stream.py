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

import math
from typing import Any, Callable

import numpy as np

from ..io.chunks import Fallback
from .clipping import code_step_counts
from .no_rest import REST_NOISE_MAX, force_median, share_of
from .noise import NYQUIST_RATIO, MAD_TO_STD
from .noise_stream import NoisePass, add_counts, median_of_counts
from .static import EDGE_SIGMA, MIN_POSE_S, STATIC_THRESHOLD, STATIC_WINDOW_S, window_len
from .steps import BLOCK_JUMP, BLOCK_SHARE, BLOCK_SPAN, STEP_SIGMA
from .still_pieces import long_enough, refine_pieces, run_pieces, static_runs

__all__ = ["DiffSums", "LoggerBound", "StillPass", "LongRun", "RowsOf", "percentiles_of_counts", "order_stat_of",
           "still_stretches", "MAX_STILL_ROWS"]

#: the most rows of one run of static blocks (and a window either side) the still pass holds (2^18 rows,
#: 6 MiB of counts and about 40 MiB of the step test's floats); a longer run goes as a LongRun (its
#: rows not held; Fallback where it may hold an instant step)
MAX_STILL_ROWS = 1 << 18

#: sums the floats of numpy's means hold exactly
EXACT = 2.0 ** 53
#: rows of a long run whose step test is taken at once (its temporaries: about 200 bytes a row)
SPLIT_SLICE = 1 << 15


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


class RowsOf:
    """The rows of a long run that :func:`accelcal.readings.still_pieces.refine_pieces` takes, sliced as
    it slices the recording: slices within one of ``parts`` ((first sample, rows)), or the subsample
    ``sub`` ((start, stop, stride), rows)."""

    def __init__(self, parts: list, sub: tuple) -> None:
        self.parts, self.sub = parts, sub

    def __getitem__(self, sl: slice) -> np.ndarray:
        if (sl.start, sl.stop, sl.step or 1) == self.sub[0]:
            return self.sub[1]
        for first, rows in self.parts:
            if first <= sl.start and sl.stop <= first + rows.shape[0]:
                return rows[sl.start - first:sl.stop - first]
        raise ValueError(f"rows {sl} not kept")


class LongRun:
    """One run of static blocks [a, b) too long to hold, its span [lo, hi) (the run and a window
    either side) fed in chunks: of it are kept the rows a refinement takes (the span's first rows to
    a + h, its last from b - h, every ``(b - a) // 2000``-th row of the run), the integer sum of the
    rows between, and whether ``step_splits`` finds a candidate step in it (``step``: the means of
    the m rows before and after some split differ by more than STEP_SIGMA x ``sig``; the same floats,
    its cumulative sums being exact integers)."""

    def __init__(self, a: int, b: int, lo: int, hi: int, h: int, m: int, sig: np.ndarray, n_channels: int) -> None:
        self.a, self.b, self.lo, self.hi, self.h, self.m, self.sig = a, b, lo, hi, h, m, sig
        self.head: list[np.ndarray] = []
        self.tail: list[np.ndarray] = []
        self.stride = max(1, (b - a) // 2000)
        self.sub: list[np.ndarray] = []
        self.mid = np.zeros(n_channels, np.int64)
        self.ctx = np.zeros((0, n_channels), np.int64)
        self.ctx_start = a
        self.next_i = a + m                      # the first split not yet tested
        self.step = False

    def add(self, raw: np.ndarray, s: int) -> None:
        """Rows ``raw`` of samples s, s + 1, ..."""
        e = s + raw.shape[0]
        a, b, h, m = self.a, self.b, self.h, self.m
        for keep, lo, hi in ((self.head, self.lo, a + h), (self.tail, b - h, self.hi)):
            if max(lo, s) < min(hi, e):          # copies: a view would keep the whole chunk
                keep.append(raw[max(lo, s) - s:min(hi, e) - s].copy())
        if max(a + h, s) < min(b - h, e):
            self.mid += raw[max(a + h, s) - s:min(b - h, e) - s].sum(axis=0)
        first = a + -(-(max(a, s) - a) // self.stride) * self.stride
        if first < min(b, e):
            self.sub.append(raw[first - s:min(b, e) - s:self.stride].copy())
        seg = raw[max(a, s) - s:max(min(b, e) - s, 0)] if max(a, s) < min(b, e) else raw[:0]
        for k in range(0, seg.shape[0], SPLIT_SLICE):       # the test's temporaries a slice's
            self.test(seg[k:k + SPLIT_SLICE])

    def test(self, rows: np.ndarray) -> None:
        """step_splits' candidate test over the splits whose m rows after are in ``rows`` (the run's
        next rows) and before."""
        b, m = self.b, self.m
        y = np.concatenate([self.ctx, rows])
        y0 = self.ctx_start
        last = min(b - m, y0 + y.shape[0] - m)              # the last split whose m rows after are here
        if last >= self.next_i:
            c = np.concatenate([np.zeros((1, y.shape[1]), np.int64), np.cumsum(y, axis=0)])
            i = np.arange(self.next_i, last + 1) - y0
            left = (c[i] - c[i - m]) / m
            right = (c[i + m] - c[i]) / m
            z = np.max(np.abs(right - left) / self.sig[None, :], axis=1)
            self.step = self.step or bool(np.any(z > STEP_SIGMA))
            self.next_i = last + 1
        self.ctx = y[self.next_i - m - y0:].copy()
        self.ctx_start = self.next_i - m

    def rows(self) -> RowsOf:
        a, b, h = self.a, self.b, self.h
        return RowsOf([(self.lo, np.concatenate(self.head)), (b - h, np.concatenate(self.tail))],
                      ((a, b, self.stride), np.concatenate(self.sub)))

    def mean(self, start: int, stop: int) -> np.ndarray:
        """The mean reading of rows [start, stop) (start at most a + h, stop at least b - h): numpy's
        float of the exact sum."""
        a, b, h = self.a, self.b, self.h
        head, tail = np.concatenate(self.head), np.concatenate(self.tail)
        total = head[start - self.lo:].sum(axis=0) + self.mid + tail[:stop - (b - h)].sum(axis=0)
        return total.astype(float) / (stop - start)


class StillPass:
    """The static detector's intervals within given runs of static blocks, over a recording of
    ``n`` rows fed in chunks: for each run [a, b) (samples, ascending), the rows from a - ``ext``
    to b + ``ext`` are held, then cut at their instant steps and refined as ``detect_static`` does
    (:func:`accelcal.readings.still_pieces.run_pieces`, :func:`~accelcal.readings.still_pieces.refine_pieces`:
    window ``w``, block ``h``, noise ``sig``, edge limit ``lim``, counts); ``out`` the intervals,
    ``means`` the mean reading of each (numpy's mean of its rows: the same floats).  A run whose
    rows would be more than ``hold`` goes as a :class:`LongRun` (its rows not held): ValueError where
    it may hold an instant step, or where its sums ``span`` (the readings' greatest |value| and
    range, counts) could pass the floats' exact integers."""

    def __init__(self, n: int, runs: list[tuple[int, int]], w: int, h: int, ext: int, sig: np.ndarray,
                 lim: np.ndarray, hold: int | None = None, span: int = 0) -> None:
        self.n, self.runs, self.w, self.h, self.ext = n, runs, w, h, ext
        self.sig, self.lim, self.span = sig, lim, span
        self.spans = [(max(0, a - ext), min(n, b + ext)) for a, b in runs]
        self.hold = hold
        self.next = 0
        self.active: dict[int, Any] = {}
        self.seen = 0
        self.out: list[tuple[int, int]] = []
        self.means: list[np.ndarray] = []

    @staticmethod
    def longest(n: int, runs: list[tuple[int, int]], ext: int) -> int:
        """The most rows a StillPass over ``runs`` holds at once (its widest span)."""
        return max((min(n, b + ext) - max(0, a - ext) for a, b in runs), default=0)

    def add(self, raw: np.ndarray) -> None:
        raw = np.asarray(raw, np.int64)
        s, e = self.seen, self.seen + raw.shape[0]
        while self.next < len(self.spans) and self.spans[self.next][0] < e:
            lo, hi = self.spans[self.next]
            a, b = self.runs[self.next]
            if self.hold is not None and hi - lo > self.hold:
                if (b - a) * self.span >= EXACT:
                    raise ValueError("a long still stretch whose sums pass the floats' exact integers")
                self.active[self.next] = LongRun(a, b, lo, hi, self.h, max(2, self.h), self.sig, raw.shape[1])
            else:
                self.active[self.next] = []
            self.next += 1
        for r, parts in self.active.items():
            lo, hi = self.spans[r]
            a, b = max(lo, s), min(hi, e)
            if isinstance(parts, LongRun):
                parts.add(raw, s)
            elif b > a:
                parts.append(raw[a - s:b - s])
        for r in sorted(self.active):
            if self.spans[r][1] > e:
                break
            self.piece(r, self.active.pop(r))
        self.seen = e

    def piece(self, r: int, held: Any) -> None:
        a, b = self.runs[r]
        prev_stop = self.runs[r - 1][1] if r else 0
        next_start = self.runs[r + 1][0] if r + 1 < len(self.runs) else self.n
        first = len(self.out)
        if isinstance(held, LongRun):
            if held.step:
                raise ValueError("a long still stretch that may hold an instant step")
            if b - a < 2 * max(2, self.h) + 1 or self.h >= (b - a) // 2:
                raise ValueError("a long run too short for its kept rows")
            refine_pieces(held.rows(), [(a, b, False, False)], self.out, self.w, self.h, self.ext, self.lim,
                          prev_stop, next_start)
            self.means += [held.mean(lo, hi) for lo, hi in self.out[first:]]
            return
        x = np.concatenate(held)
        off = self.spans[r][0]
        pieces = run_pieces(x, a, b, self.h, self.sig, off)
        refine_pieces(x, pieces, self.out, self.w, self.h, self.ext, self.lim, prev_stop, next_start, off)
        self.means += [x[lo - off:hi - off].mean(axis=0) for lo, hi in self.out[first:]]

    def finish(self) -> None:
        """Every row added (ValueError otherwise)."""
        if self.seen != self.n or self.active or self.next != len(self.spans):
            raise ValueError(f"{self.seen} rows added of {self.n}")


def still_stretches(passes: Callable[..., None], n: int, probe: Any, hists: list, diffs: DiffSums, *,
                    noise: np.ndarray | None = None, min_s: float = MIN_POSE_S, found: list | None = None
                    ) -> tuple[list[tuple[int, int]], list[np.ndarray], np.ndarray]:
    """``detect_static(rec, probe, noise=noise, min_s=min_s)``'s intervals of a recording of ``n``
    rows read by ``passes(*feeds)`` (one pass over its rows in chunks, each chunk's counts to
    every feed), the mean reading of each, and the noise (counts per channel: ``noise`` where given,
    else ``estimate_noise``'s); ``hists`` each channel's histogram (values ascending, counts),
    ``diffs`` the first pass's differences.  ``found``, where given, gets every interval the
    detector finds before its length rule (``detect_static(..., min_s=0)``'s).  Runs of static
    blocks longer than MAX_STILL_ROWS go as a :class:`LongRun`.  :class:`~accelcal.io.chunks.Fallback`
    where the passes cannot give the detector's answer (a tone at half the rate; noise beyond
    REST_NOISE_MAX of |f|: the Welch test; large changes that may be a logger's steps; a long run
    that may hold an instant step; sums beyond exact floats)."""
    w = window_len(probe, STATIC_WINDOW_S, n)
    tone = diffs.tone()
    if tone is None or tone.any():
        raise Fallback("a tone at half the rate (the detector averages it out of the samples)")
    p = NoisePass(n, w, np.array([u[0] for u, _ in hists]), np.array([u[-1] for u, _ in hists]),
                  np.array([code_step_counts(u, cnt) for u, cnt in hists]))
    logger = LoggerBound(n, diffs.change_std(), max(2, w // 4))
    stride, rows, seen = max(1, n // 5000), [], [0]

    def gather(raw: np.ndarray) -> None:
        idx = np.arange(seen[0], seen[0] + raw.shape[0])
        rows.append(raw[idx % stride == 0])
        seen[0] += raw.shape[0]

    try:
        passes(p.add, logger.add, gather)
        try:
            estimated = p.noise()          # also the reference of the window stds
        except ValueError:
            raise Fallback("window sums beyond exact floats") from None
        noise = estimated if noise is None else np.asarray(noise, float)
        if np.any(share_of(force_median(np.concatenate(rows), probe), probe, noise) > REST_NOISE_MAX):
            raise Fallback("noise beyond REST_NOISE_MAX of |f| (the detector's Welch test takes the samples)")
        sig = np.maximum(noise, 1e-9)
        quiet = p.quiet(STATIC_THRESHOLD * sig)
    finally:
        p.close()
    if not quiet.size:
        return [], [], noise
    if logger.maybe_logger():
        raise Fallback("large changes that may be a logger's steps (its blocks take the samples)")
    runs = [(a * p.h, b * p.h) for a, b in static_runs(quiet, p.k)]
    ext = p.k * p.h
    span = max(max(abs(int(u[0])), abs(int(u[-1])), int(u[-1] - u[0])) for u, _ in hists)
    still = StillPass(n, runs, w, p.h, ext, sig, EDGE_SIGMA * sig, hold=MAX_STILL_ROWS, span=span)
    try:
        passes(still.add)
        still.finish()
    except ValueError as e:
        raise Fallback(str(e)) from None
    min_n = max(w, int(math.ceil(min_s * probe.sample_rate_hz)))
    keep = long_enough(still.out, n, min_n)
    if found is not None:
        found += still.out
    return ([iv for iv, k in zip(still.out, keep) if k], [m for m, k in zip(still.means, keep) if k], noise)
