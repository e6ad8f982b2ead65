"""``accelcal convert`` of a recording CSV in memory that does not grow with the recording
(docs/streaming.md, "convert in bounded memory").

The first pass reads the rows in chunks and keeps, in place of t, the counts and the labels,
what :func:`accelcal.convert.common.finish` infers from them reduced to bounded summaries
(:class:`Sums`): each channel's histogram of readings (the ADC range and signedness, the code
step, the clip levels and their counts), the runs of identical rows
(:class:`accelcal.readings.held.RunCounts`), the counts of the distinct time steps (the time unit,
the median step, the gaps, the rate), the first and last stamps, the pose labels seen and
whether f is given.  :func:`bounded_convert` then gives the notes, the nominal device and the
recording's layout exactly as ``finish`` gives them on the whole arrays, and the second pass
writes the rows as they are read again.

Where an inference takes more than these summaries give, :class:`~accelcal.io.chunks.Fallback`
is raised before anything is written and the caller runs the first-pass-arrays path
(:func:`accelcal.convert.stream.convert_csv_chunked`'s, the same output):

* no stated scale (``--full-scale``/``--lsb``) and no ``still_of`` (the nominal scale then comes
  from the static detector, :func:`accelcal.readings.static.detect_static`: with ``still_of``,
  :func:`accelcal.convert.bounded_scale.still_scale` finds its still stretches in two more
  passes, or raises Fallback where it cannot);
* a leading ``0, 0, 0`` row, readings held for several rows, stamps in bursts, t in another
  unit than s, ``--rate`` off the stamps, ``--regions``: the notes name rows or take the samples;
* an extreme reading held by CLIP_MIN_COUNT samples or more inside the ADC's range whose pile
  verdict depends on the noise (:func:`pile_free`), the noise being estimated from the samples;
* a mean step whose rounding could change the device's rate (:func:`certified_rate`), more than
  MAX_STEP_VALUES distinct time steps, fewer than 3 rows.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, Callable

import numpy as np

from .common import Converted, Options, held_note_text, recording_metadata
from .nominal_device import adc_range, code_step_note, nominal_triad, triad_device
from .time import BURST_SHARE, FLOAT_EXACT, MIN_PLAUSIBLE_HZ, TIME_FACTORS, time_factor, unit_in_name
from ..errors import InputError, atomic_write
from ..io.chunks import Fallback, Head, csv_chunks, reader_checks
from ..io.csvformat import csv_rows
from ..io.parquet import is_parquet
from ..io.recording import Recording, recording_layout
from ..io.recording_checks import GAP_STEPS, RATE_TOL
from ..io.units import STANDARD_GRAVITY, Scale
from ..readings.clipping import (CLIP_BAND_SIGMA, CLIP_MIN_COUNT, CLIP_PILE_RATIO, ClipLevels, clip_counts_text,
                                 clip_levels_counts, code_step_counts)
from ..readings.noise_stream import NoisePass, add_counts, median_of_counts
from ..readings.static import STATIC_WINDOW_S, window_len
from ..readings.still_stream import DiffSums
from ..readings.held import (HELD_CHANGED_SHARE, HELD_MAX, HELD_MIN_RUNS, HELD_MIN_RUNS_UNEVEN, HELD_MODAL_SHARE,
                             HELD_SINGLE_SHARE, RunCounts, order_stat)

__all__ = ["Sums", "MAX_STEP_VALUES", "first_pass_sums", "bounded_convert", "rate_bounds", "held_counts", "pile_free"]

#: distinct time steps kept (more: Fallback)
MAX_STEP_VALUES = 1 << 16
#: the time units other than s that t may be read in (time.TIME_FACTORS' factors)
TICKS = (1e3, 1e6, 1e9)
#: relative margin of the certified comparisons (the float arithmetic of the whole-file functions)
MARGIN = 1e-9


@dataclass
class Sums:
    """What the first pass keeps of a recording CSV (bounded: histograms of the readings, of the
    time steps and of the runs of identical rows)."""

    n: int = 0
    t0: float = math.nan
    t_last: float = math.nan
    hist: list = field(default_factory=lambda: [{}, {}, {}])     # per channel: reading -> count
    factors: tuple = (1.0,) + TICKS                              # the time units t may be read in (s, ms, us, ns)
    t_steps: dict = field(default_factory=dict)                  # np.diff(t): step -> count
    rel_steps: dict = field(default_factory=dict)                # per factor k: np.diff((t - t0) / k): step -> count
    runs: RunCounts = field(default_factory=RunCounts)
    labels: set = field(default_factory=set)                     # pose labels >= 0
    has_pose: bool = False
    f_given: bool = False
    rel_last: dict = field(default_factory=dict)
    factor: float = 1.0                                          # the unit t is read in (in_seconds)
    diffs: DiffSums | None = None                                # without a stated scale: the detector's sums

    def add(self, t: np.ndarray, raw: np.ndarray, pose: np.ndarray | None, f: np.ndarray | None) -> None:
        """One chunk's rows (t as read, counts, labels or None, f or None)."""
        m = t.size
        if m == 0:
            return
        if self.n == 0:
            if np.all(raw[0] == 0):
                raise Fallback("a leading 0, 0, 0 row (the placeholder test takes the samples)")
            self.t0 = float(t[0])
        if np.any(np.abs(t) >= FLOAT_EXACT):
            raise Fallback("an epoch in ns (read exactly from its text)")
        steps = np.asarray(t, float) - self.t0
        add_counts(self.t_steps, np.diff(np.concatenate([[self.t_last], t]) if self.n else t))
        for k in self.factors:
            rel = steps / k if k != 1.0 else steps             # time_in_seconds' rel in s
            counts = self.rel_steps.setdefault(k, {})
            add_counts(counts, np.diff(np.concatenate([[self.rel_last[k]], rel]) if self.n else rel))
            self.rel_last[k] = float(rel[-1])
        if max([len(self.t_steps)] + [len(c) for c in self.rel_steps.values()]) > MAX_STEP_VALUES:
            raise Fallback(f"more than {MAX_STEP_VALUES} distinct time steps")
        for j in range(3):
            add_counts(self.hist[j], raw[:, j])
        self.runs.add(raw)
        if self.diffs is not None:
            self.diffs.add(raw)
        if pose is not None:
            self.has_pose = True
            self.labels.update(int(v) for v in np.unique(pose[pose >= 0]))
        self.f_given = self.f_given or (f is not None and bool(np.isfinite(f).any()))
        self.n += m
        self.t_last = float(t[-1])


def sorted_counts(counts: dict) -> tuple[np.ndarray, np.ndarray]:
    """(values ascending, their counts) of a histogram."""
    u = np.array(sorted(counts))
    return u, np.array([counts[v] for v in u.tolist()], dtype=np.int64)


def first_pass_sums(path: Any, head: Head, block_bytes: int, bar: Any, time_unit: str = "auto",
                    diffs: bool = False) -> Sums:
    """The first pass (Fallback at any bad row or a row off its line: the whole-file reader words
    it); t's steps counted in s and, ``time_unit`` auto, in ms, us and ns, else in that unit;
    with ``diffs`` the readings' differences too (:class:`accelcal.readings.still_stream.DiffSums`)."""
    k = time_factor(time_unit) if time_unit != "auto" else None
    if time_unit != "auto" and k is None:
        raise Fallback("--time-unit refused by the whole-file command")
    sums, prev = Sums(factors=(1.0,) + TICKS if k is None else (k,), diffs=DiffSums() if diffs else None), None
    for ch in csv_chunks(path, head, block_bytes, None if bar is None else bar.update):
        if reader_checks(head, ch, prev) or not np.all(np.isfinite(ch.t)):
            raise Fallback("a bad row")
        first = head.first_line + ch.start
        if ch.n and (ch.line(0) != first or ch.line(ch.n - 1) != first + ch.n - 1):
            raise Fallback("rows not on consecutive lines")
        sums.add(ch.t, ch.raw, ch.other.get("pose"), ch.vecs.get("f"))
        prev = ch
    if bar is not None:
        bar.close()
    if sums.n < 3:
        raise Fallback("fewer than 3 rows")
    return sums


def in_seconds(sums: Sums, opts: Options, column: str, notes: list[str]) -> float:
    """The factor :func:`accelcal.convert.time.time_in_seconds` divides t by (its note made), from
    the counts of t's steps (Fallback for a unit not counted)."""
    k = 1.0
    if opts.time_unit != "auto":
        k = time_factor(opts.time_unit)
    else:
        named = unit_in_name(column)
        if named is not None:
            k = TIME_FACTORS[named]
            if k != 1.0:
                notes.append(f"t read in {named}, as its column's name {column!r} says; the recording's t is in seconds")
        else:
            pos = {v: c for v, c in sums.t_steps.items() if v > 0}
            step = median_of_counts(pos) if pos else 0.0
            if step > 0 and 1.0 / step < MIN_PLAUSIBLE_HZ:
                for unit_name, f in list(TIME_FACTORS.items())[1:]:
                    if f / step >= MIN_PLAUSIBLE_HZ:
                        notes.append(f"t read in {unit_name}: its steps (median {step:.6g}) would give "
                                     f"{1.0 / step:.4g} Hz in seconds, {f / step:.6g} Hz in {unit_name} (state "
                                     "--time-unit s, ms, us or ns when that is not its unit)")
                        k = f
                        break
    if k is None or k not in sums.rel_steps:
        raise Fallback("t in a unit whose steps were not counted")
    return k


def rate_bounds(steps: dict, notes: list[str]) -> tuple[float, float]:
    """:func:`accelcal.convert.time.rate_from_t` of even stamps whose steps are counted in
    ``steps`` (its gap note made): the rate's least and greatest value.  The mean of the regular
    steps (``regular_step``) is numpy's pairwise sum, which the counts give to within its rounding
    bound only; the caller takes what the rate decides at both ends (equal: certified)."""
    median = median_of_counts(steps)
    if median <= 0:
        return 1.0, 1.0
    regular = {v: k for v, k in steps.items() if 0 < v <= GAP_STEPS * median}
    gaps = sum(k for v, k in steps.items() if v > GAP_STEPS * median)
    if gaps:
        notes.append(f"t has {gaps} step{'s' if gaps > 1 else ''} longer than {GAP_STEPS:g} x its median step "
                     f"({median:.6g} s; the longest {max(steps):.6g} s): a pause or samples lost; the "
                     "rate is that of the other steps")
    size = sum(regular.values())
    if not size:
        return 1.0 / median, 1.0 / median
    exact = sum((Fraction(v) * k for v, k in regular.items()), Fraction(0))
    # numpy's pairwise summation: error below (log2 n + 2 x 128 leaf adds) ulps of the sum of |x|
    bound = exact * Fraction(2 * (math.ceil(math.log2(size + 1)) + 256), 2 ** 53)
    lo = float(np.nextafter(float(exact - bound), -np.inf))
    hi = float(np.nextafter(float(exact + bound), np.inf))
    return 1.0 / (hi / size), 1.0 / (lo / size)


def held_counts(runs: RunCounts, n: int, n_channels: int) -> tuple[int, dict, int]:
    """:func:`accelcal.readings.held.held_runs`' k from the runs' counts, with the inner runs'
    histogram (length -> runs, the first and the last left out) and the number of runs (Fallback
    where the 90th percentile of the run lengths falls between two lengths about HELD_MAX)."""
    hist = dict(runs.hist)
    hist[runs.open_len] = hist.get(runs.open_len, 0) + 1
    total = sum(hist.values())
    inner = dict(hist)
    if total >= 2:
        for length in (runs.first_len, runs.open_len):
            inner[length] -= 1
    else:
        inner = {}
    inner = {v: c for v, c in inner.items() if c}
    top = max(hist.values())
    k = min(length for length, c in hist.items() if c == top)      # np.argmax of the bincount: the first
    if 2 <= k <= HELD_MAX and total >= HELD_MIN_RUNS and top >= HELD_MODAL_SHARE * total:
        return k, inner, total
    m = sum(inner.values())
    if m >= HELD_MIN_RUNS_UNEVEN and inner.get(1, 0) / m <= HELD_SINGLE_SHARE:
        idx = 0.9 * (m - 1)
        lo, hi = order_stat(inner, math.floor(idx)), order_stat(inner, math.ceil(idx))
        if lo <= HELD_MAX < hi:
            raise Fallback("the runs' 90th percentile between two lengths about HELD_MAX")
        if hi <= HELD_MAX and runs.changed / ((total - 1) * n_channels) >= HELD_CHANGED_SHARE:
            return max(2, int(round(sum(v * c for v, c in inner.items()) / m))), inner, total
    return 1, inner, total


def held_note_counts(k: int, inner: dict, total: int, n: int, distinct_hz: float | None) -> str:
    """:func:`accelcal.convert.common.held_note` from the runs' counts."""
    m = sum(inner.values())
    lo, hi = (min(inner), max(inner)) if m else (k, k)
    if lo == hi or not uneven_counts(k, inner):
        held_for = f"{k} rows"
    else:
        held_for = f"{lo}-{hi} rows ({sum(v * c for v, c in inner.items()) / m:.1f} on average)"
    return held_note_text((n - total) / (n - 1) if n > 1 else 0.0, held_for, total, distinct_hz)


def uneven_counts(k: int, inner: dict) -> bool:
    """:func:`accelcal.readings.held.uneven` of the inner runs' histogram."""
    m = sum(inner.values())
    return bool(m) and inner.get(k, 0) / m < HELD_MODAL_SHARE


def pile_free(u: np.ndarray, cnt: np.ndarray, side: int, q: int, sigma_lo: float, sigma_hi: float) -> bool:
    """Whether :func:`accelcal.readings.clipping.pile_level_counts` finds no pile on ``side`` for
    every noise in [sigma_lo, sigma_hi] (counts): its band max(CLIP_BAND_SIGMA sigma, 2 q) then runs
    over an interval, and the readings within the band per code are least just below each
    distance at which the band takes in a new reading, or at its top (a margin of MARGIN)."""
    ext = u[-1] if side > 0 else u[0]
    c = int(cnt[-1] if side > 0 else cnt[0])
    if c < CLIP_MIN_COUNT:
        return True
    b0 = max(CLIP_BAND_SIGMA * sigma_lo * (1 - MARGIN), 2.0 * q)       # 2 q: the band's floor, exact
    b1 = max(CLIP_BAND_SIGMA * sigma_hi * (1 + MARGIN), 2.0 * q)
    away = (side * (ext - u)).astype(float)
    order = np.argsort(away)
    away, k = away[order], cnt[order]
    within = np.cumsum(k) - c                       # readings with 0 < away <= away[i] (ext itself is away 0)
    cands = [(float(within[np.searchsorted(away, b1, side="right") - 1]), b1)]
    for d in np.unique(away[(away > b0) & (away <= b1)]).tolist():
        below = int(k[away < d].sum()) - c          # readings with 0 < away < d: the band just below d
        cands.append((float(below), d))
    for near, band in cands:
        per_code = near / max(band / q, 1.0)
        if not c < CLIP_PILE_RATIO * per_code * (1 - MARGIN) + CLIP_MIN_COUNT:
            return False
    return True


def clip_note_counts(hists: list[tuple[np.ndarray, np.ndarray]], device: Any,
                     noise_of: Callable[[Any, list], np.ndarray] | None) -> str | None:
    """:func:`accelcal.readings.clipping.clip_note` from each channel's histogram: where no pile
    inside the range can be found whatever the noise (:func:`pile_free`), from the counts alone;
    else with the noise ``noise_of(device, hists)`` (:class:`accelcal.readings.noise_stream.NoisePass`,
    a pass over the file: ``estimate_noise``'s floats) and :func:`clip_levels_counts` (Fallback
    where that needs the readings in order, or without ``noise_of``)."""
    free = True
    for u, cnt in hists:
        if u[0] != u[-1]:
            q = code_step_counts(u, cnt)
            # the noise estimate_noise can give: its rounding floor, to the widest window std and rounding
            lo = q / math.sqrt(12.0)
            hi = math.sqrt((0.5 * float(u[-1] - u[0])) ** 2 * 1.5 + q * q / 12.0)
            for side, inside in ((1, u[-1] < device.raw_max), (-1, u[0] > device.raw_min)):
                free = free and not (inside and not pile_free(u, cnt, side, q, lo, hi))
    if free:
        n_ch = len(hists)
        levels = ClipLevels(lo=np.full(n_ch, float(device.raw_min)), hi=np.full(n_ch, float(device.raw_max)),
                            inside_lo=np.zeros(n_ch, bool), inside_hi=np.zeros(n_ch, bool))
    else:
        if noise_of is None:
            raise Fallback("an extreme reading held often inside the range (the pile test takes the noise)")
        levels = clip_levels_counts(hists, device, noise_of(device, hists))
        if levels is None:
            raise Fallback("a pile on a channel quieter than a code (the test takes the readings in order)")
    counts = [(int(cnt[u <= levels.lo[i]].sum()), int(cnt[u >= levels.hi[i]].sum())) for i, (u, cnt) in enumerate(hists)]
    return clip_counts_text(counts, levels.lo, levels.hi, levels.inside_lo, levels.inside_hi, lambda j: f"raw_{j}")


def bounded_convert(head: Head, sums: Sums, opts: Options, scale: Scale | None,
                    noise_of: Callable[[Any, list], np.ndarray] | None = None,
                    still_of: Callable[..., tuple[float, np.ndarray | None]] | None = None) -> Converted:
    """``finish``'s result from the first pass's sums (module doc; Fallback where they do not
    give it).  Its recording is a stand-in of n rows (broadcast views, no memory): the layout
    decisions (f, pose given) and the counts; the rows are written by the second pass.  Without a
    stated scale, ``still_of(hists, rate_hz, gravity, signed, notes)`` gives the nominal scale and
    the noise (:func:`accelcal.convert.bounded_scale.still_scale` bound to the file)."""
    if opts.regions is not None:
        raise Fallback("--regions (the poses are labelled from the samples)")
    gravity = opts.gravity_mps2 or STANDARD_GRAVITY
    k = scale.counts_per_mps2(gravity) if scale is not None else None
    if k is None and (still_of is None or sums.diffs is None):
        raise Fallback("no stated scale: the nominal scale takes the static detector over the samples")
    if scale is not None and scale.converts:
        raise Fallback("readings in a unit: converted in the whole-file reader")
    hists = [sorted_counts(h) for h in sums.hist]
    signed = any(u[0] < 0 for u, _ in hists)
    lo, hi = adc_range(opts.bits, signed)
    if any(u[0] < lo or u[-1] > hi for u, _ in hists):
        raise Fallback("a reading outside the ADC's range (the refusal names its row)")
    notes: list[str] = []
    sums.factor = in_seconds(sums, opts, "t", notes)
    steps = sums.rel_steps[sums.factor]
    median = median_of_counts(steps)
    mean = float(sums.rel_last[sums.factor] - 0.0) / (sums.n - 1)
    if not (median > 0 and mean > 0 and abs(mean / median - 1.0) <= BURST_SHARE):
        raise Fallback("stamps not even (bursts, pauses: the burst fit takes the stamps)")
    if opts.rate_hz is not None:
        rates = (opts.rate_hz, opts.rate_hz)
        own = 1.0 / median
        if max(abs(opts.rate_hz / own - 1.0), abs(own / opts.rate_hz - 1.0)) > RATE_TOL:
            raise Fallback("--rate off the stamps (t is written on the grid)")
    else:
        rates = rate_bounds(steps, notes)
    k_held, inner, total = held_counts(sums.runs, sums.n, 3)
    values = np.unique(np.concatenate([u for u, _ in hists]))
    names = [str(v) for v in sorted(sums.labels)]
    metadata = recording_metadata(head.source, "csv", dict(head.metadata), scale, opts, names, True)

    def rate_decides(rate: float) -> tuple:
        """What finish makes of the rate: the held note, the device and its notes."""
        said, device_notes = [], []
        distinct_hz = None
        if k_held > 1 and rate:
            distinct_hz = rate / (sum(v * c for v, c in inner.items()) / sum(inner.values())
                                  if uneven_counts(k_held, inner) else k_held)
            said.append(held_note_counts(k_held, inner, total, sums.n, distinct_hz))
        own = distinct_hz if distinct_hz is not None and opts.rate_hz is None else None
        device = (nominal_triad("csv-triad", own or rate, gravity, None, opts.bits, signed, scale, device_notes, None)[0]
                  if k is not None else triad_device("csv-triad", own or rate, gravity, opts.bits, signed, 1.0))
        if own is not None:
            device_notes.append(f"the device's rate is {device.sample_rate_hz:.6g} Hz, the distinct readings'; "
                                f"the recording keeps every row (at {rate:.6g} Hz)")
        return said, device, device_notes

    ends = [rate_decides(r) for r in rates]
    if ends[0][0] != ends[1][0] or ends[0][2] != ends[1][2] or \
            ends[0][1].sample_rate_hz != ends[1][1].sample_rate_hz:
        raise Fallback("the rate's rounding within the sum's bound changes the device or a note")
    said, device, device_notes = ends[0]
    if k is None:               # the scale of the still stretches, its note before the rate's
        scale_notes: list[str] = []
        k_rest, noise = still_of(hists, device.sample_rate_hz, gravity, signed, scale_notes)
        device = triad_device("csv-triad", device.sample_rate_hz, gravity, opts.bits, signed, k_rest)
        device_notes = scale_notes + device_notes
        if noise is not None:
            noise_of = (lambda known: lambda device, hists: known)(noise)
    notes += said
    notes += code_step_note(values.reshape(-1, 1), opts.bits)
    clipped = clip_note_counts(hists, device, noise_of)
    notes += [clipped] if clipped else []
    n = sums.n
    nan = np.float64(np.nan)
    rec = Recording(t=np.broadcast_to(np.float64(0.0), (n,)), raw=np.broadcast_to(np.int64(0), (n, 3)),
                    f=np.broadcast_to(np.float64(0.0) if sums.f_given else nan, (n, 3)),
                    w=np.broadcast_to(nan, (n, 3)), dw=np.broadcast_to(nan, (n, 3)),
                    temp_c=np.broadcast_to(nan, (n,)),
                    pose=np.broadcast_to(np.int64(0 if sums.labels else -1), (n,)), metadata=metadata,
                    source=head.source)
    return Converted(rec, device, "csv", names, notes, scale, False, device_notes)


def second_pass(path: Any, head: Head, block_bytes: int, bar: Any, like: Recording, output: Any,
                factor: float = 1.0) -> None:
    """Write the rows chunk by chunk as they are read again (t as read, in s; the counts; the
    file's labels and f), atomically, in the whole-file writer's layout (``like``: the stand-in);
    t divided by ``factor`` (its unit's, :func:`in_seconds`)."""
    if is_parquet(output):
        raise ValueError("the chunked writer writes CSV: a .parquet output is written whole")
    lines, _, formats = recording_layout(like)
    n = like.n_samples

    def write(fh: Any) -> None:
        fh.write("\n".join(lines))
        fh.write("\n")
        done = 0
        for ch in csv_chunks(path, head, block_bytes, None if bar is None else bar.update):
            if not ch.n:
                continue
            part = Recording(t=ch.t / factor if factor != 1.0 else ch.t, raw=ch.raw,
                             f=ch.vecs.get("f") if like.has_f() else None, pose=ch.other.get("pose"),
                             metadata=like.metadata, source=like.source)
            _, columns, _ = recording_layout(part, like=like)
            for text in csv_rows(columns, formats, [""] * len(columns)):
                fh.write(text)
            done += ch.n
        if done != n:
            raise InputError(head.source, f"the file changed while it was read ({done} rows, then {n})")

    try:
        atomic_write(output, write)
    finally:
        if bar is not None:
            bar.close()


def noise_pass(path: Any, head: Head, block_bytes: int, bar_for: Callable[[], Any], n: int
               ) -> Callable[[Any, list], np.ndarray]:
    """``noise_of(device, hists)`` for :func:`clip_note_counts`: the file read again into a
    :class:`NoisePass` (the clip note's window, ``static.window_len`` of the device), its noise."""
    def noise_of(device: Any, hists: list) -> np.ndarray:
        q = np.array([code_step_counts(u, cnt) for u, cnt in hists])
        p = NoisePass(n, window_len(device, STATIC_WINDOW_S, n), np.array([u[0] for u, _ in hists]),
                      np.array([u[-1] for u, _ in hists]), q)
        bar = bar_for()
        for ch in csv_chunks(path, head, block_bytes, None if bar is None else bar.update):
            p.add(ch.raw)
        if bar is not None:
            bar.close()
        try:
            return p.noise()
        except ValueError:
            raise Fallback("window sums beyond exact floats") from None
        finally:
            p.close()
    return noise_of


def bounded_writer(path: Any, head: Head, block_bytes: int, bar_for: Callable[[], Any], conv: Converted,
                   factor: float = 1.0) -> Callable[[Any], None]:
    """``Converted.writer`` of the bounded path (the second pass, with its own bar)."""
    def write(output: Any) -> None:
        second_pass(path, head, block_bytes, bar_for(), conv.recording, output, factor)
    return write
