"""``accelcal resolve`` in chunks: memory that does not grow with the recording.

The recording is read chunk by chunk (:mod:`accelcal.io.chunks` for CSV,
:mod:`accelcal.io.parquet` for Parquet), each chunk resolved by
:func:`accelcal.resolve.resolve_chunk` (the per-sample part of the whole-file
:func:`accelcal.resolve.resolve_recording`) and written as it is done into a temporary file
that replaces the output at the end (:func:`accelcal.errors.atomic_write`): bad input
anywhere leaves no output.  The output is the whole-file command's byte for byte, and so are
its errors: each check of a chunk has the rank of its place in the whole-file command
(reader, device, omega, core input), and the first error of the lowest rank is raised after
the rest of the file has been read for errors of a lower rank.

What needs the whole recording is decided at the end, from sums kept along the way:

* the ``clipped`` column is written when a channel reads the ADC's rail: found at the end, the
  file is resolved once more with the column (:func:`accelcal.readings.clipping.rails_text` words the
  warning from the counts);
* a channel whose readings pile up at a level inside the range: the levels from each channel's
  histogram of readings (:func:`accelcal.readings.clipping.clip_levels_counts`, with the device's stated
  noise), then the file once more with the column; where the noise must be estimated from the
  data, or a pile lies on a channel quieter than a code (its motion is told from the readings
  in order), the whole-file command decides;
* t in milliseconds, microseconds or nanoseconds (its median step from counts of the steps in
  each unit's band): the whole-file command;
* omega "auto" with a sample whose w_* are missing: the file is resolved again without omega.

``resolve_stream`` returns None where the whole-file command must run (then nothing was written).
"""
from __future__ import annotations

import os
import sys
from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np
from tqdm import tqdm

from .readings.clipping import CLIP_MIN_COUNT, clip_levels_counts, pile_text, rails_text
from .io.csvformat import REPR, csv_rows
from .errors import InputError, atomic_write
from .io.chunks import BLOCK_BYTES, Fallback, csv_chunks, csv_head, reader_checks
from .io.parquet import BATCH_ROWS, ParquetSink, is_parquet, parquet_chunks, parquet_head
from .io.pipeline import WriteBehind, read_ahead
from .readings.noise import noise_for, states_noise
from .io.recording_checks import TIME_UNIT_TOL, TIME_UNITS, check_core_input, check_raw_range
from .resolve import omega_for, resolve_chunk, resolver_for

__all__ = ["StreamResult", "resolve_stream", "result_names", "CsvSink", "PROGRESS_DELAY_S", "progress_factory",
           "resolve_warnings"]

#: a progress bar shows once a command has run this long (s)
PROGRESS_DELAY_S = 2.0

#: ranks of the whole-file command's checks after the reader's (1-4: io.chunks.reader_checks)
RANK_RANGE, RANK_OMEGA, RANK_CORE = 10, 11, 12
#: the readings' histograms (for the pile levels) are kept for ranges of up to this many codes
HIST_MAX_CODES = 1 << 20


#: Parquet rows a chunk: half of BATCH_ROWS, as the chunks are read ahead and written behind in threads
#: (io.pipeline): 263 MB peak at 3x10^6 rows against 299 MB with BATCH_ROWS
RESOLVE_BATCH_ROWS = BATCH_ROWS // 2
#: CSV bytes a chunk: half of BLOCK_BYTES, for the same reason: at 3x10^6 samples CSV->CSV peaks at
#: 258 MB against 294 MB (7.83 s against 7.46 s), CSV->Parquet at 267 against 286 MB
RESOLVE_BLOCK_BYTES = BLOCK_BYTES // 2


class _Again(Exception):
    """Resolve the file once more with other settings (the clipped column, or no omega)."""

    def __init__(self, **settings: Any) -> None:
        super().__init__("again")
        self.settings = settings


@dataclass
class StreamResult:
    """What the command says after writing: the ignored columns, the samples the core
    saturated, the clipping warnings (the rails', the piles')."""

    extra: list[str] = field(default_factory=list)
    saturated: int = 0
    clip_warnings: list[str] = field(default_factory=list)


class CsvSink:
    """Result columns written as CSV chunk by chunk, as
    :func:`accelcal.io.recording.write_columns_csv` writes them whole."""

    def __init__(self, f: Any, names: list[str], meta: dict | None) -> None:
        self.f = f
        for k, v in (meta or {}).items():
            f.write(f"# {k}: {v}\n")
        f.write(",".join(names) + "\n")
        self.formats = [REPR if k == "t" else "%.9g" for k in names]

    def write(self, columns: list[np.ndarray]) -> None:
        for text in csv_rows([np.asarray(c, float) for c in columns], self.formats):
            self.f.write(text)

    def close(self) -> None:
        pass


def result_names(saturated: bool, clipped: bool) -> list[str]:
    """resolve's output columns (``saturated``: the fixed engine's; ``clipped``: with a rail)."""
    names = ["t", "f_x", "f_y", "f_z", "dw_x", "dw_y", "dw_z"]
    return names + (["saturated"] if saturated else []) + (["clipped"] if clipped else [])


class _Tally:
    """Sums over the chunks for what the whole recording decides."""

    def __init__(self, n_raw: int, device) -> None:
        self.n = 0
        self.low = np.zeros(n_raw, np.int64)
        self.high = np.zeros(n_raw, np.int64)
        self.clipped = 0                          # samples at a rail or a pile
        self.rails = 0                            # samples at a rail
        self.first_rail: int | None = None
        self.vmin = np.full(n_raw, np.iinfo(np.int64).max)
        self.vmax = np.full(n_raw, np.iinfo(np.int64).min)
        self.cmin = np.zeros(n_raw, np.int64)
        self.cmax = np.zeros(n_raw, np.int64)
        self.below = np.zeros(len(TIME_UNITS), np.int64)
        self.inband = np.zeros(len(TIME_UNITS), np.int64)
        self.saturated = 0
        self.device = device
        self.last_t: float | None = None
        span = int(device.raw_max) - int(device.raw_min) + 1
        self.hist = np.zeros((n_raw, span), np.int64) if span <= HIST_MAX_CODES else None
        self.levels: Any = None                  # the pile levels inside the range, once known
        self.pile_hits = np.zeros((n_raw, 2), np.int64)
        self.piled = 0
        self.first_pile: int | None = None

    def add(self, ch, flags, ext: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """Add a chunk (``ext``: its columns' minima and maxima, where known); returns its samples
        at a rail."""
        dev = self.device
        raw = ch.raw
        if ext is not None and ch.n and (ext[0] > dev.raw_min).all() and (ext[1] < dev.raw_max).all():
            at, k = np.zeros(ch.n, bool), 0        # no reading at a rail
        else:
            low, high = raw <= dev.raw_min, raw >= dev.raw_max
            at = np.any(low | high, axis=1)
            k = int(np.count_nonzero(at))
        if k:
            self.low += low.sum(axis=0)
            self.high += high.sum(axis=0)
            if self.first_rail is None:
                self.first_rail = ch.line(int(np.argmax(at)))
            self.rails += k
        if self.hist is not None:
            for j in range(raw.shape[1]):
                self.hist[j] += np.bincount(raw[:, j] - dev.raw_min, minlength=self.hist.shape[1])
        if self.levels is not None:
            lv = self.levels
            pile = np.zeros(raw.shape[0], bool)
            for j in range(raw.shape[1]):
                for side, (inside, hit) in enumerate(((lv.inside_lo[j], raw[:, j] <= lv.lo[j]),
                                                      (lv.inside_hi[j], raw[:, j] >= lv.hi[j]))):
                    if inside:
                        pile |= hit
                        self.pile_hits[j, side] += int(hit.sum())
            if pile.any():
                if self.first_pile is None:
                    self.first_pile = ch.line(int(np.argmax(pile)))
                self.piled += int(np.count_nonzero(pile))
            at = at | np.any(lv.mask(raw), axis=1)
        k = int(np.count_nonzero(at))
        self.clipped += k
        if ch.n and self.hist is None:            # else from the histograms (extremes)
            mn, mx = ext if ext is not None else (raw.min(axis=0), raw.max(axis=0))
            for best, cnt, v, side in ((self.vmin, self.cmin, mn, -1), (self.vmax, self.cmax, mx, 1)):
                c = (raw == v).sum(axis=0)
                new = v < best if side < 0 else v > best
                same = v == best
                cnt[same] += c[same]
                cnt[new] = c[new]
                best[new] = v[new]
        if ch.n:
            steps = np.diff(ch.t) if self.last_t is None else np.diff(np.concatenate(([self.last_t], ch.t)))
            rate = float(dev.sample_rate_hz)
            for u, (unit, _) in enumerate(TIME_UNITS):
                x = steps * rate / unit - 1.0
                self.below[u] += int(np.count_nonzero(x < -TIME_UNIT_TOL))
                self.inband[u] += int(np.count_nonzero(np.abs(x) <= TIME_UNIT_TOL))
            self.last_t = float(ch.t[-1])
        self.n += ch.n
        if flags is not None:
            self.saturated += int(np.count_nonzero(flags))
        return at

    def pile_levels(self) -> Any:
        """The clip levels where a channel's readings may pile up inside the range
        (:func:`accelcal.readings.clipping.clip_levels_counts` from the histograms), None where none can.

        Raises
        ------
        Fallback
            Where the whole-file command must tell (the noise estimated from the data, a pile
            on a channel quieter than a code, a range too wide for the histograms)."""
        dev = self.device
        if self.n < 2:
            return None
        if self.hist is not None:                 # the extremes and their counts from the histograms
            for j, h in enumerate(self.hist):
                nz = np.flatnonzero(h)
                self.vmin[j], self.vmax[j] = nz[0] + dev.raw_min, nz[-1] + dev.raw_min
                self.cmin[j], self.cmax[j] = h[nz[0]], h[nz[-1]]
        maybe = [j for j in range(len(self.vmin)) if self.vmin[j] != self.vmax[j] and (
            (self.vmax[j] < dev.raw_max and self.cmax[j] >= CLIP_MIN_COUNT)
            or (self.vmin[j] > dev.raw_min and self.cmin[j] >= CLIP_MIN_COUNT))]
        if not maybe:
            return None
        if self.hist is None or not states_noise(dev):
            raise Fallback("a possible pile inside the range")
        hists = []
        for h in self.hist:
            u = np.flatnonzero(h)
            hists.append((u.astype(np.int64) + int(dev.raw_min), h[u]))
        levels = clip_levels_counts(hists, dev, noise_for(dev, np.zeros((0, len(hists)), np.int64), 1)[0])
        if levels is None:
            raise Fallback("a pile on a channel quieter than a code")
        return levels if levels.any_inside() else None

    def whole_file_decides(self) -> str | None:
        """Why the whole-file command must decide (t in another unit), or None."""
        if self.n >= 3:
            m = self.n - 1
            for below, inband in zip(self.below, self.inband):
                mids = {(m - 1) // 2, m // 2}
                if any(below <= i < below + inband for i in mids):
                    return "t in another unit"
        return None


def resolve_stream(device, cal, path: Any, output: Any, *, engine: str = "float", omega_source: str = "auto",
                   scale: Any = None, block_bytes: int = RESOLVE_BLOCK_BYTES, batch_rows: int = RESOLVE_BATCH_ROWS,
                   progress: Callable[..., Any] | None = None) -> StreamResult | None:
    """Resolve a recording file into ``output`` chunk by chunk (see the module doc).

    Parameters
    ----------
    device, cal : Device, Calibration
    path : str or os.PathLike
        The recording: CSV, or Parquet by its name (.parquet).
    output : str or os.PathLike
        The result: Parquet when its name ends in .parquet, else CSV.
    engine, omega_source : str
        As :func:`accelcal.resolve.resolve_recording`.
    scale : units.Scale, optional
        Stated units (readings in physical units go the whole-file way).
    block_bytes, batch_rows : int
        Chunk size: bytes of CSV text, rows of Parquet.
    progress : callable, optional
        ``progress(total, unit)`` -> a bar with ``update(k)`` and ``close()`` (tqdm's).

    Returns
    -------
    StreamResult or None
        None: the whole-file command must run (nothing written).

    Raises
    ------
    InputError
        As the whole-file command raises it, with no output written.
    """
    settings: dict[str, Any] = {"clipped": False, "omega_source": omega_source, "levels": None}
    for _ in range(4):
        try:
            return _stream(device, cal, path, output, engine, scale, block_bytes, batch_rows, progress, **settings)
        except Fallback:
            return None
        except _Again as again:
            settings.update(again.settings)
    raise RuntimeError("resolve_stream: no settings converged")  # pragma: no cover


def _stream(device, cal, path, output, engine, scale, block_bytes, batch_rows, progress, *, clipped: bool,
            omega_source: str, levels: Any) -> StreamResult:
    if is_parquet(path):
        if scale is not None and scale.converts:
            raise Fallback("units stated for a Parquet recording")   # refused by the whole-file reader
        head, pf = parquet_head(path, device.n_channels)
        total, unit = pf.metadata.num_rows, " rows"
        total_rows = total
        chunks = lambda tick: parquet_chunks(pf, head, batch_rows, tick)  # noqa: E731
    else:
        head = csv_head(path, device.n_channels, scale)
        total, unit, total_rows = None, "B", None       # a CSV block holds two rows unless the file has one
        chunks = lambda tick: csv_chunks(path, head, block_bytes, tick)  # noqa: E731
    try:
        resolver = resolver_for(device, cal, engine)
    except Exception:   # noqa: BLE001 - the whole-file command raises it in its own order
        raise Fallback("calibration") from None
    triad = device.is_triad()
    names = result_names(engine == "fixed", clipped)
    signed = device.raw_min < 0
    # where the core's input range (int16 or uint16) holds the device's (always, where the fixed engine's
    # tables are made), a reading outside it is outside the device's range too and refused first
    # (RANK_RANGE < RANK_CORE): the core's check then runs only on a chunk with such a reading
    core_lo, core_hi = (-32768, 32767) if signed else (0, 65535)
    core_always = not (core_lo <= device.raw_min and device.raw_max <= core_hi)
    tally = _Tally(head.n_raw, device)
    tally.levels = levels
    result = StreamResult(extra=list(head.extra))
    meta = {"engine": engine, "device": device.name}
    if total is None:
        total = max(os.path.getsize(path) - head.pos, 0)

    def write(f: Any) -> None:
        sink = ParquetSink(f, names, meta) if is_parquet(output) else CsvSink(f, names, meta)
        bar = progress(total, unit) if progress is not None else None
        pending: tuple[int, InputError] | None = None
        prev = None
        # the chunks read one ahead and written one behind, each in a thread (io.pipeline); leaving
        # the block closes the sink, an exception drops what is queued (nothing written after it)
        with WriteBehind(sink) as out:
            for ch in read_ahead(chunks(bar.update if bar is not None else None)):
                # each chunk's extremes first: the checks of every reading run only where one is outside
                ext = (ch.raw.min(axis=0), ch.raw.max(axis=0)) if ch.n else None
                out_range = ext is not None and bool((ext[0] < device.raw_min).any() or (ext[1] > device.raw_max).any())
                w_missing = ch.vecs["w"] is None
                rec = SimpleNamespace(raw=ch.raw, source=head.source, line=ch.line, w=ch.vecs["w"])
                if w_missing and omega_source == "reference" and not triad:   # refused at its first row
                    rec.w = np.full((ch.n, 3), np.nan)
                errs = reader_checks(head, ch, prev)
                for rank, check in ((RANK_RANGE, lambda: check_raw_range(rec, device) if out_range else None),
                                    (RANK_OMEGA, lambda: None if triad or (w_missing and omega_source != "reference")
                                     else omega_for(rec, omega_source)),
                                    (RANK_CORE, lambda: check_core_input(rec, signed)
                                     if engine == "fixed" and (core_always or out_range) else None)):
                    try:
                        check()
                    except InputError as e:
                        errs.append((rank, e))
                for rank, e in errs:
                    if pending is None or rank < pending[0]:
                        pending = (rank, e)
                prev = ch
                if pending is not None:
                    continue
                omega = None
                if not triad and omega_source != "none" and ch.vecs["w"] is not None:
                    have = np.all(np.isfinite(ch.vecs["w"]), axis=1)
                    if not have.all():
                        raise _Again(omega_source="none")     # "auto": no omega for any sample
                    omega = ch.vecs["w"]
                if ch.n == 1 and (ch.start > 0 or (total_rows or 1) > 1):
                    # BLAS multiplies one row (gemv) with other roundings than a row of many (gemm): the
                    # last chunk's one row goes in twice, as the whole file's rows went
                    f_, a_, flags = resolve_chunk(resolver, np.repeat(ch.raw, 2, axis=0),
                                                  None if omega is None else np.repeat(omega, 2, axis=0))
                    f_, a_, flags = f_[:1], a_[:1], None if flags is None else flags[:1]
                else:
                    f_, a_, flags = resolve_chunk(resolver, ch.raw, omega)
                at = tally.add(ch, flags, ext)
                cols = [ch.t, f_[:, 0], f_[:, 1], f_[:, 2], a_[:, 0], a_[:, 1], a_[:, 2]]
                if flags is not None:
                    cols.append(flags)
                if clipped:
                    cols.append(at)
                out.write(cols)
            if bar is not None:
                bar.close()
            if pending is not None:
                raise pending[1]
            why = tally.whole_file_decides()
            if why is not None:
                raise Fallback(why)
            if levels is None:
                found = tally.pile_levels()
                if found is not None:
                    raise _Again(clipped=True, levels=found)
            if tally.clipped and not clipped:
                raise _Again(clipped=True)

    atomic_write(output, write, mode="wb" if is_parquet(output) else "w")
    result.saturated = tally.saturated
    if tally.rails:
        result.clip_warnings.append(rails_text(tally.low, tally.high, tally.rails, tally.first_rail, device))
    if tally.piled:
        result.clip_warnings.append(pile_text(levels, tally.pile_hits, tally.piled, tally.first_pile))
    return result


def progress_factory(command: str, delay: float = PROGRESS_DELAY_S) -> Callable[[Any, str], Any]:
    """A progress bar factory for :func:`resolve_stream`: (total, unit) -> tqdm on stderr, shown
    once the command has run ``delay`` s and only when stderr is a terminal (tqdm's disable=None)."""
    def make(total: Any, unit: str) -> Any:
        return tqdm(desc=command, total=total, unit=unit, unit_scale=True, unit_divisor=1024 if unit == "B" else 1000,
                    file=sys.stderr, disable=None, leave=False, dynamic_ncols=True, delay=delay)
    return make


def resolve_warnings(saturated: int, clip_warnings: list[str], ignored: list[str] = ()) -> list[str]:
    """resolve's stderr lines: the columns ignored (a note), the samples the core saturated, then the
    clipping's warnings."""
    ignored = sorted(ignored)
    out = [f"accelcal resolve: note: ignored column{'s' if len(ignored) > 1 else ''} {', '.join(ignored)} "
           "(not part of the accelerometer model)"] if ignored else []
    if saturated:
        out.append(f"accelcal resolve: warning: {saturated} samples saturated in the "
                   "fixed-point core's arithmetic (see column saturated)")
    return out + [f"accelcal resolve: warning: {w}" for w in clip_warnings]
