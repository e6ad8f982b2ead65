"""Long recordings cut down to a bounded number of their own samples, read in bounded memory,
for the commands that fit the whole recording (``accelcal diagnose``; docs/streaming.md,
"diagnose on a long recording").

Recordings of more than ``max_samples`` samples are cut down two ways (:func:`plan`):

* **with a reference** (f columns: the diagnosis scores every sample, the motion too, against
  its own reference): each such recording is cut into windows of :func:`window_len`
  consecutive samples (2 to 10 s at the device's rate) and about ``max_samples`` samples' worth
  of them are kept, spread evenly from the first window to the last.  A window is a stretch of
  full-rate samples: the timing within a motion, the rests after it, the code lattice and the
  noise are the recording's;
* **jig-free** (no reference: the static poses are the reference, and each one's orientation
  counts): every k-th sample of every recording, k the smallest integer that brings the longest
  recording to ``max_samples``; the recordings are then recordings at the device's rate / k
  (the diagnosis takes the device at that rate), and every pose keeps 1/k of its samples.

Every row of a file is still read and checked (the bad cells, t increasing, a vector given in
part, a reading outside the device's range), with the whole-file reader's message naming the
file's row, so a recording refused whole is refused thinned, with the same line.  What is lost is
precision: an effect is judged against the noise of the samples kept, not the whole recording's.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from ..errors import InputError
from .chunk_source import open_chunks
from .chunks import BLOCK_BYTES, Fallback, gather_rows, recording_of
from .parquet import BATCH_ROWS
from .recording import read_recording
from .recording_checks import check_raw_range
from .recording_type import Recording
from .units import Scale

__all__ = ["MAX_SAMPLES", "WINDOWS", "MIN_WINDOWS", "WINDOW_S", "MIN_RATE_HZ", "Thinning", "thinning", "plan", "window_len",
           "check_max_samples", "thin_recordings", "read_thinned", "read_all_thinned"]

#: samples of a recording kept by default (``accelcal diagnose --max-samples``); 0 or None keeps all
MAX_SAMPLES = 100_000
#: the windows kept number about this many when the window length allows
WINDOWS = 256
#: and at least this many (windows shorter than WINDOW_S[0] for a small budget)
MIN_WINDOWS = 16
#: a window's length, s: at least WINDOW_S[0], at most WINDOW_S[1]
WINDOW_S = (2.0, 10.0)
#: jig-free, every k-th sample is kept down to this rate (Hz; a 2 s pose keeps 10 samples), windows of those beyond
MIN_RATE_HZ = 5.0


@dataclass(frozen=True)
class Thinning:
    """Which samples of a recording are kept: one sample in every ``step`` (a recording at the
    rate / ``step``: its ``m = ceil(n_read / step)`` samples), and of those, ``kept`` of their
    ``windows`` windows of ``window`` consecutive samples (window ``j``: samples ``j * window`` to
    ``(j + 1) * window - 1`` of the m), spread evenly from the first (window ``j`` is kept where
    ``floor(j * kept / windows)`` steps; every window where ``kept == windows``).

    Attributes
    ----------
    n_read : int
        Samples in the recording (every row read and checked).
    step : int
        1, or k: every k-th sample (jig-free).
    window : int
        Samples (of the m) per window.
    windows : int
        Windows of the m (the last may be short).
    kept : int
        Windows kept.
    rate_hz : float
        The device's rate the plan was made for (Hz).
    """

    n_read: int
    step: int
    window: int
    windows: int
    kept: int
    rate_hz: float

    def kept_windows(self, j: np.ndarray) -> np.ndarray:
        """Whether each window ``j`` is kept (bool)."""
        j = np.asarray(j, np.int64)
        if self.kept >= self.windows:
            return np.ones(j.shape, bool)
        return (j * self.kept) // self.windows != ((j - 1) * self.kept) // self.windows

    def keep(self, start: int, n: int) -> np.ndarray:
        """Whether each of the samples ``start .. start + n - 1`` is kept (bool (n,))."""
        i = np.arange(start, start + n, dtype=np.int64)
        q, r = np.divmod(i, self.step)
        return (r == 0) & self.kept_windows(q // self.window)

    @property
    def windowed(self) -> bool:
        """Whether only some windows are kept."""
        return self.kept < self.windows

    @property
    def n_kept(self) -> int:
        """Samples kept."""
        m = -(-self.n_read // self.step)
        if not self.windowed:
            return m
        j = np.flatnonzero(self.kept_windows(np.arange(self.windows)))
        return int(np.minimum(self.window, m - j * self.window).sum())

    def describe(self) -> dict:
        """The JSON entry (docs/diagnosis-json.md: ``recordings[].thinned``)."""
        rate = self.rate_hz / self.step
        out = {"n_read": int(self.n_read), "n_kept": self.n_kept, "every": int(self.step), "rate_hz": rate}
        if self.windowed:
            out.update({"windows": int(self.kept), "window_samples": int(self.window), "window_s": self.window / rate,
                        "spacing_s": self.window * self.windows / self.kept / rate})
        return out

    def note(self, source: str) -> str:
        """One sentence for the diagnosis's notes."""
        rate = self.rate_hz / self.step
        what = []
        if self.step > 1:
            what.append(f"one sample in every {self.step:,} (a recording at {rate:.6g} Hz)")
        if self.windowed:
            what.append(f"{self.kept:,} windows of {self.window:,} samples ({self.window / rate:.3g} s), one every "
                        f"{self.window * self.windows / self.kept / rate:.4g} s over the whole recording")
        return (f"{source}: {self.n_read:,} samples, diagnosed on {self.n_kept:,} of them: {'; of those, '.join(what)} "
                "(--max-samples; 0 keeps every sample); an effect is judged against the noise of the samples kept")


def window_len(rate_hz: float, max_samples: int) -> int:
    """Samples per window: ``max_samples / WINDOWS`` within ``WINDOW_S`` at ``rate_hz``, and
    short enough for ``MIN_WINDOWS`` windows."""
    lo, hi = (max(1, int(round(s * float(rate_hz)))) for s in WINDOW_S)
    return int(max(1, min(max(lo, min(hi, max_samples // WINDOWS)), max_samples // MIN_WINDOWS)))


def thinning(n: int, rate_hz: float, max_samples: int | None, step: int = 1) -> Thinning | None:
    """What is kept of an ``n``-sample recording at ``rate_hz`` for ``max_samples``: one sample
    in every ``step``, then windows of those where they are more than ``max_samples`` (None:
    every sample, when ``max_samples`` is 0 or None or ``n`` <= ``max_samples``)."""
    step = max(1, int(step))
    if not max_samples or (step == 1 and n <= max_samples):
        return None
    m = -(-int(n) // step)
    w = window_len(rate_hz / step, int(max_samples))
    windows = -(-m // w)
    kept = windows if m <= max_samples else max(1, int(max_samples) // w)
    return Thinning(int(n), step, w, windows, kept, float(rate_hz))


def plan(sizes: list[tuple[int, bool]], rate_hz: float, max_samples: int | None) -> list[Thinning | None]:
    """What is kept of each recording, from (samples, has a reference f) of each (see the module
    doc): windows of each longer recording where any has a reference, else every k-th sample of
    every recording (one k, so that they share one rate; at most ``rate_hz / MIN_RATE_HZ``, and
    windows of those samples beyond)."""
    if not max_samples:
        return [None] * len(sizes)
    if any(has_f for _, has_f in sizes):
        return [thinning(n, rate_hz, max_samples) for n, _ in sizes]
    k = max([-(-n // max_samples) for n, _ in sizes] or [1])
    k = max(1, min(k, int(rate_hz / MIN_RATE_HZ)))
    return [thinning(n, rate_hz, max_samples, k) for n, _ in sizes]


def check_max_samples(max_samples: Any) -> int:
    """``max_samples`` as an int >= 0 (0: every sample), else ValueError."""
    if max_samples is None:
        return 0
    if isinstance(max_samples, bool) or not isinstance(max_samples, (int, np.integer)) or max_samples < 0:
        raise ValueError(f"max_samples must be an integer >= 0 (0: every sample), got {max_samples!r}")
    if 0 < max_samples < 100:
        raise ValueError(f"max_samples must be 0 (every sample) or at least 100, got {max_samples}")
    return int(max_samples)


def thin_recordings(recs: list[Recording], rate_hz: float, max_samples: int | None) -> list[Recording]:
    """Recordings held in memory cut down as :func:`read_thinned` cuts their files (:func:`plan`;
    a recording kept whole is itself)."""
    return [_take(r, th) for r, th in zip(recs, plan([(r.n_samples, r.has_f()) for r in recs], rate_hz,
                                                     max_samples))]


def _take(rec: Recording, th: Thinning | None) -> Recording:
    if th is None:
        return rec
    out = rec.select(th.keep(0, rec.n_samples))
    out.thinning = th
    return out


def _count_rows(src: Any, path: Any) -> int:
    """Rows of a recording: a Parquet file's metadata, a CSV's lines after its header (an
    estimate only where the file has blank lines at its end: the plan, not the result, takes it)."""
    if src.unit != "B":
        return int(src.total)
    n, last = 0, b"\n"
    with open(path, "rb") as fh:
        fh.seek(src.head.pos)
        while True:
            buf = fh.read(1 << 24)
            if not buf:
                break
            n += buf.count(b"\n")
            last = buf[-1:]
    return n + (last != b"\n")


def read_thinned(path: Any, device: Any, max_samples: int | None, scale: Scale | None = None,
                 block_bytes: int = BLOCK_BYTES, batch_rows: int = BATCH_ROWS) -> Recording:
    """One recording file read as :func:`read_all_thinned` reads several."""
    return read_all_thinned([path], device, max_samples, scale, block_bytes, batch_rows)[0]


def read_all_thinned(paths: list, device: Any, max_samples: int | None, scale: Scale | None = None,
                     block_bytes: int = BLOCK_BYTES, batch_rows: int = BATCH_ROWS) -> list[Recording]:
    """Recording files (CSV, or Parquet by the name) cut down by :func:`plan`: every row read and
    checked, only the kept rows' arrays held (a plain CSV or a Parquet file: in chunks, after a
    count of its rows; anything the chunked reader leaves to the whole-file reader, such as a
    compressed file: read whole, then cut down).

    Returns
    -------
    list of Recording
        The kept samples of each (each with its file line, for messages; ``thinning`` says
        which), or the whole-file reader's Recording where it is kept whole.

    Raises
    ------
    InputError
        The whole-file reader's error for a bad row anywhere in a file, or a reading outside the
        device's range.
    """
    rate = float(device.sample_rate_hz)
    if not max_samples:
        return [read_recording(p, device.n_channels, scale=scale) for p in paths]
    found: list[Any] = []          # per file: a ChunkSource, or the Recording read whole
    sizes: list[tuple[int, bool]] = []
    for p in paths:
        try:
            src = open_chunks(p, device.n_channels, scale, block_bytes=block_bytes, batch_rows=batch_rows)
            if src.head.extra:
                raise Fallback("extra columns")
            found.append(src)
            sizes.append((_count_rows(src, p), "f_x" in src.head.cols))
        except Fallback:
            rec = read_recording(p, device.n_channels, scale=scale)
            found.append(rec)
            sizes.append((rec.n_samples, rec.has_f()))
    out = []
    for p, got, th, (n_est, _) in zip(paths, found, plan(sizes, rate, max_samples), sizes):
        if isinstance(got, Recording):
            out.append(_take(got, th))
        elif th is None:
            out.append(read_recording(p, device.n_channels, scale=scale))
        else:
            try:
                out.append(_read_kept(got, device, th))
            except Fallback:       # later text the chunked reader leaves to the whole-file reader
                out.append(_take(read_recording(p, device.n_channels, scale=scale), th))
    return out


def _read_kept(src: Any, device: Any, th: Thinning) -> Recording:
    """The rows ``th`` keeps of a recording read in chunks, every row checked.

    Raises
    ------
    Fallback
        Text the chunked reader leaves to the whole-file reader, or fewer rows than counted.
    """
    head = src.head
    first_range: list[InputError] = []

    def range_check(ch: Any, clean: bool) -> None:
        if clean and not first_range:
            try:
                check_raw_range(SimpleNamespace(raw=ch.raw, source=head.source, line=ch.line), device)
            except InputError as e:
                first_range.append(e)

    cols, lines, n = gather_rows(head, src.chunks(), th.keep, range_check)
    if first_range:     # check_for_device's range check, over every row
        raise first_range[0]
    if n != th.n_read:
        raise Fallback("fewer rows than lines counted")
    rec = recording_of(head, cols, lines)
    rec.thinning = th
    return rec
