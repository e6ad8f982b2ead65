"""A recording without ``pose`` labels reduced to its still stretches while it is read in chunks
(``calibrate`` on long recordings; docs/streaming.md, "calibrate reduced while read", issue 37).

:func:`accelcal.readings.static.poses_from_recording` holds the whole recording, finds its still
stretches (:func:`~accelcal.readings.static.detect_static`) and gathers each one's readings;
:func:`reduce_unlabelled` reads the file four times in chunks (:mod:`accelcal.io.chunk_source`):

1. :func:`accelcal.calibrate.pose_stream.checked_pass`: the reader's checks, the device's range,
   the time steps, held rows, each channel's histogram; the differences of
   :class:`accelcal.readings.still_stream.DiffSums`;
2. and 3. :func:`accelcal.readings.still_stream.still_stretches`: the noise (the device's
   ``noise_mps2`` where it states one, else ``estimate_noise``'s from the window sums), the quiet
   windows, then the detector's intervals (the same as ``detect_static``'s, with and without
   its minimum length);
4. per interval the integer sums of its readings and of their squares about its first reading
   (exact: ``pose_means`` sums the same integers), the sum of f (added row after row, as numpy's
   mean over the rows adds them), the rows where f is given, its first and last samples; an
   interval of at most MAX_STILL_ROWS rows is held while read (one at a time) and its colour
   ratios (``pose_colour``) and mean temperature are the whole-file functions' own; of a longer
   one the COLOUR_BATCHES batch sums are kept and a fifth pass adds its squared deviations row
   after row (:class:`IntervalSums`).

Then as ``poses_from_recording``: the stretches with a clipped reading are set aside ("clipped",
with their clipped rows, channels and levels), then of the others those whose |f| is far from g
and that have no f on every row ("not at rest"), the others' means, counts and std are the whole-file
ones bit for bit (the sums moved to the first kept reading exactly in integers), f_ref, the
colour ratios and temp too, but for the temperature of an interval longer than MAX_STILL_ROWS
(summed in chunks; numpy's nanmean adds the column pairwise: one ulp measured).  Where this
path cannot tell what the whole-file path would do it returns None and the caller reads the file
whole: ``pose`` labels (:func:`accelcal.calibrate.pose_stream.reduce_labelled`'s), what
:func:`~accelcal.calibrate.pose_stream.checked_pass` refuses, the Fallbacks of ``still_stretches``
(a tone at half the rate, noise beyond REST_NOISE_MAX of |f|, a logger's static blocks, a long
still stretch that may hold an instant step, sums beyond exact floats), clip levels the
histograms cannot give (``clip_levels_counts``), f given on part of a stretch
kept, no stretch kept, any reader fallback or input error (the whole-file reader words it).
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ..io.chunk_source import open_chunks
from ..io.chunks import BLOCK_BYTES, Fallback
from ..readings.clipping import clip_levels_counts, code_step_counts
from ..readings.noise import COLOUR_BATCHES, noise_for, pose_colour, states_noise
from ..readings.static import MIN_POSE_S, PoseSet, at_gravity
from ..readings.still_stream import EXACT, MAX_STILL_ROWS, DiffSums, still_stretches
from .pose_stream import Reduced, checked_pass, mean_var

__all__ = ["reduce_unlabelled"]


def reduce_unlabelled(path: Any, device, scale=None, block_bytes: int = BLOCK_BYTES,
                      min_s: float = MIN_POSE_S) -> Reduced | None:
    """The recording at ``path`` (no ``pose`` column) reduced to the still stretches the static
    detector finds in it (``min_s``: its shortest stretch where a motion touches it, seconds), or
    None where the whole file must be read (see the module doc)."""
    try:
        return _reduce(path, device, scale, block_bytes, min_s)
    except (Fallback, InputError):
        return None


class IntervalSums:
    """Pass 4: the sums of each interval [a, b) of ``kept`` over the chunks fed in order, with the
    clip levels ``levels`` (each interval's clipped rows, channels and levels: :meth:`clipped`), the
    file's name ``source``.  An interval of at most ``hold`` rows is held while it is read (one at
    a time: they do not overlap) and its colour ratios and mean temperature are then the
    whole-file functions' own; of a longer one its batch sums are kept and :meth:`spread` (a
    fifth pass) adds its squared deviations from the mean row after row as numpy's variance
    does, and its temperature is summed in chunks (rounding: numpy adds a column pairwise)."""

    def __init__(self, kept: list[tuple[int, int]], N: int, levels, hold: int, source: str) -> None:
        P, B = len(kept), COLOUR_BATCHES
        self.kept, self.levels, self.hold, self.source = kept, levels, hold, source
        self.a = np.array([a for a, _ in kept], np.int64)
        self.b = np.array([b for _, b in kept], np.int64)
        self.L = (self.b - self.a) // B
        self.r0 = np.zeros((P, N), np.int64)
        self.s1 = np.zeros((P, N), np.int64)
        self.s2 = np.zeros((P, N), np.int64)
        self.b1 = np.zeros((P, B, N), np.int64)
        self.fsum = np.zeros((P, 3))
        self.fin = np.zeros(P, np.int64)
        self.tsum = np.zeros(P)
        self.tcnt = np.zeros(P, np.int64)
        self.t_start = np.zeros(P)
        self.t_stop = np.zeros(P)
        self.colour = np.full((P, N), np.nan)
        self.temp = np.full(P, np.nan)
        self.dev2 = np.zeros((P, N))             # long intervals: sum of (x - mean)^2 (pass 5)
        self.held: dict[int, tuple[list, list]] = {}
        self.n_clipped = np.zeros(P, np.int64)           # rows with a clipped reading
        self.clip_hi = np.full((P, N), np.iinfo(np.int64).min)   # each channel's greatest and least
        self.clip_lo = np.full((P, N), np.iinfo(np.int64).max)   # clipped reading
        self.next = 0          # the first interval not yet past

    def add(self, ch) -> None:
        s, e = ch.start, ch.start + ch.n
        p = self.next
        while p < len(self.kept) and self.a[p] < e:
            a, b = int(self.a[p]), int(self.b[p])
            lo, hi = max(a, s), min(b, e)
            if lo < hi:
                self.interval(p, ch, lo - s, hi - s, lo - a)
            if b <= e:
                self.next = p + 1
                self.done(p)
            p += 1

    def interval(self, p: int, ch, i: int, j: int, rank0: int) -> None:
        """Rows i..j-1 of chunk ``ch``, ranks rank0.. in interval p."""
        x = np.asarray(ch.raw[i:j], np.int64)
        tc = ch.other.get("temp_c")
        tv = None if tc is None else np.asarray(tc[i:j], float)
        if rank0 == 0:
            self.r0[p] = x[0]
            self.t_start[p] = float(ch.t[i])
            if self.b[p] - self.a[p] <= self.hold:
                self.held[p] = ([], [])
        self.t_stop[p] = float(ch.t[j - 1])
        cl = self.levels.mask(x)
        if cl.any():
            self.n_clipped[p] += int(np.count_nonzero(cl.any(axis=1)))
            big, small = np.where(cl, x, np.iinfo(np.int64).min), np.where(cl, x, np.iinfo(np.int64).max)
            self.clip_hi[p] = np.maximum(self.clip_hi[p], big.max(axis=0))
            self.clip_lo[p] = np.minimum(self.clip_lo[p], small.min(axis=0))
        d = x - self.r0[p]
        self.s1[p] += d.sum(axis=0)
        self.s2[p] += (d * d).sum(axis=0)
        if p in self.held:
            self.held[p][0].append(x)
            if tv is not None:
                self.held[p][1].append(tv)
        elif int(self.L[p]) >= 1:
            L = int(self.L[p])
            rank = np.arange(rank0, rank0 + x.shape[0])
            inb = rank < COLOUR_BATCHES * L
            np.add.at(self.b1[p], rank[inb] // L, d[inb])
            if tv is not None:
                ok = np.isfinite(tv)
                self.tsum[p] += float(np.sum(tv[ok]))
                self.tcnt[p] += int(np.count_nonzero(ok))
        f = ch.vecs.get("f")
        if f is not None:
            fr = f[i:j]
            ok = np.all(np.isfinite(fr), axis=1)
            self.fin[p] += int(np.count_nonzero(ok))
            # row after row, in order: numpy's mean over the rows adds them so
            np.add.at(self.fsum, np.full(int(ok.sum()), p), fr[ok])

    def done(self, p: int) -> None:
        """Interval p read: a held one's colour and temperature from its rows."""
        if p not in self.held:
            if self.tcnt[p]:
                self.temp[p] = self.tsum[p] / self.tcnt[p]
            return
        rows, temps = self.held.pop(p)
        x = np.concatenate(rows)
        self.colour[p] = pose_colour(x, [np.arange(x.shape[0])])[0]
        if temps:
            tc = np.concatenate(temps)
            if np.isfinite(tc).any():
                self.temp[p] = float(np.nanmean(tc))

    def clipped(self, p: int) -> dict | None:
        """``set_aside_clipped``'s record of interval p where it has a clipped reading, else None."""
        if not self.n_clipped[p]:
            return None
        chans = [int(c) for c in np.flatnonzero(self.clip_hi[p] > np.iinfo(np.int64).min)]
        lv = [f"raw_{c} at {int(self.clip_hi[p, c]) if self.clip_hi[p, c] >= self.levels.hi[c] else int(self.clip_lo[p, c])}"
              for c in chans]
        return {"source": self.source, "label": None, "t_start": float(self.t_start[p]),
                "t_stop": float(self.t_stop[p]), "n": int(self.b[p] - self.a[p]), "reason": "clipped",
                "n_clipped": int(self.n_clipped[p]), "channels": chans, "levels": ", ".join(lv)}

    def long(self) -> list[int]:
        """The intervals not held whose colour a fifth pass (:meth:`spread`) gives."""
        return [p for p in range(len(self.kept)) if self.b[p] - self.a[p] > self.hold and self.L[p] >= 2]

    def spread(self, ch) -> None:
        """Pass 5: each long interval's (x - m)^2 added row after row (m the mean of its first
        B L rows, numpy's float of their exact sum): numpy's var over the rows adds them so."""
        s, e = ch.start, ch.start + ch.n
        B = COLOUR_BATCHES
        for p in self.long():
            a = int(self.a[p])
            stop = a + B * int(self.L[p])
            lo, hi = max(a, s), min(stop, e)
            if lo >= hi:
                continue
            m = (self.b1[p].sum(axis=0) + B * int(self.L[p]) * self.r0[p]).astype(float) / (B * int(self.L[p]))
            dv = np.asarray(ch.raw[lo - s:hi - s], float) - m
            self.dev2[p] = np.sum(np.concatenate([self.dev2[p][None], dv * dv]), axis=0)

    def long_colour(self) -> None:
        """``pose_colour``'s ratios of the long intervals, from the batch sums and pass 5."""
        B = COLOUR_BATCHES
        for p in self.long():
            L = int(self.L[p])
            bm = (self.b1[p] + L * self.r0[p]).astype(float) / L
            v = self.dev2[p] / (B * L - 1)
            ok = v > 0
            self.colour[p] = np.where(ok, bm.var(axis=0, ddof=1) * L / np.where(ok, v, 1.0), 1.0)


def _reduce(path: Any, device, scale, block_bytes: int, min_s: float) -> Reduced | None:
    src = open_chunks(path, device.n_channels, scale, block_bytes=block_bytes, batch_rows=max(block_bytes // 64, 1))
    head = src.head
    if "pose" in head.cols or head.n_raw != device.n_channels:
        return None
    N = device.n_channels
    diffs = DiffSums(N)
    first = checked_pass(src, device, lambda ch: diffs.add(ch.raw))
    if first is None:
        return None
    n, hists = first

    def passes(*feeds) -> None:
        for ch in src.chunks():
            for feed in feeds:
                feed(ch.raw)

    stated = noise_for(device, np.zeros((0, N), np.int64), 1)[0] if states_noise(device) else None
    found: list = []
    kept, _, noise = still_stretches(passes, n, device, hists, diffs, noise=stated, min_s=min_s, found=found)
    if not kept:
        return None
    levels = clip_levels_counts(hists, device, noise)
    if levels is None:
        return None
    sums = IntervalSums(kept, N, levels, MAX_STILL_ROWS, head.source)
    for ch in src.chunks():
        sums.add(ch)
    if sums.long():
        for ch in src.chunks():
            sums.spread(ch)
        sums.long_colour()
    cnt = sums.b - sums.a
    total = sums.s1 + cnt[:, None] * sums.r0              # each interval's exact sum of readings
    if np.any(np.abs(total) >= EXACT):                    # numpy's float sums of them would round
        return None
    # set_aside_clipped, then set_aside_off_gravity on the others: |f| / g of each interval's mean
    # through the nominal scale
    aside = [d for d in (sums.clipped(p) for p in range(len(kept))) if d is not None]
    rest = np.flatnonzero(sums.n_clipped == 0)
    S, b0 = device.nominal_sensitivity(), device.nominal_offsets()
    ratio = np.array([float(np.linalg.norm(np.linalg.lstsq(S, m - b0, rcond=None)[0])) / device.gravity_mps2
                      for m in total[rest].astype(float) / cnt[rest, None]])
    ok = at_gravity(ratio) | (sums.fin[rest] == cnt[rest])
    aside += [{"source": head.source, "label": None, "t_start": float(sums.t_start[p]),
               "t_stop": float(sums.t_stop[p]), "n": int(cnt[p]), "reason": "not at rest", "n_clipped": 0,
               "channels": [], "ratio": float(r), "levels": f"|f| = {r:.3g} g with the device file's scale"}
              for p, r in zip(rest[~ok].tolist(), ratio[~ok].tolist())]
    use = rest[ok]
    if not use.size or np.any((sums.fin[use] > 0) & (sums.fin[use] < cnt[use])):
        return None
    # pose_means about the first reading of the first interval kept: the sums moved there exactly
    ref = sums.r0[use[0]].copy()
    dlt = sums.r0[use] - ref
    c = cnt[use]
    s1 = sums.s1[use] + c[:, None] * dlt
    s2 = sums.s2[use] + 2 * dlt * sums.s1[use] + c[:, None] * dlt * dlt
    means, var = mean_var(s1, s2, c, ref)
    has_f = sums.fin[use] == c
    f_ref = np.where(has_f[:, None], sums.fsum[use] / c[:, None], np.nan)
    temp = sums.temp[use]
    info = [{"source": head.source, "label": None, "first": int(sums.a[p]), "last": int(sums.b[p]) - 1,
             "t_start": float(sums.t_start[p]), "t_stop": float(sums.t_stop[p]), "n": int(cnt[p])} for p in use.tolist()]
    step = np.array([float(code_step_counts(u, k)) for u, k in hists])
    poses = PoseSet(means=means, n=c, std=np.sqrt(var), f_ref=f_ref, temp=temp, info=info, set_aside=aside,
                    colour_r2=sums.colour[use], step=np.tile(step, (use.size, 1)))
    taken = set(kept)
    short = [(b - a) / device.sample_rate_hz for a, b in found if (a, b) not in taken]
    return Reduced(source=head.source, n_samples=n, poses=poses, extra=list(head.extra),
                   metadata=dict(head.metadata), labelled=False, short=short)
