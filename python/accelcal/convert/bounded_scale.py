"""The nominal scale of ``accelcal convert`` without a stated one (no ``--full-scale``, no
``--lsb``), for a recording CSV read in chunks (docs/streaming.md, "convert without a stated
scale"): what :func:`accelcal.convert.nominal_device.nominal_triad` takes from the whole arrays,
from the first pass's histograms and two more passes over the file.

* the readings' spread: each channel's 1st and 99th percentiles, from its histogram
  (:func:`accelcal.readings.still_stream.percentiles_of_counts`, numpy's floats);
* the still stretches (:func:`accelcal.readings.static.detect_static` on the probe triad of that
  spread): the noise pass (:class:`accelcal.readings.noise_stream.NoisePass`: the noise, the quiet
  windows; the rows of the noise-share test; :class:`accelcal.readings.still_stream.LoggerBound`)
  and the still pass (:class:`accelcal.readings.still_stream.StillPass`: one run of static blocks
  at a time, its intervals and their means);
* the scale, its note: :func:`accelcal.convert.nominal_device.scale_of_means`,
  :func:`~accelcal.convert.nominal_device.scale_said`.

Where the detector takes more than this (a tone at half the rate, noise beyond REST_NOISE_MAX of
|f|: the Welch test; a recording whose large changes may be a logger's steps; a run of static
blocks longer than MAX_STILL_ROWS rows that may hold an instant step; a file of pose means; sums beyond exact
floats) :class:`~accelcal.io.chunks.Fallback` is raised and the arrays path runs (the same output).
"""
from __future__ import annotations

import math
from typing import Any, Callable

import numpy as np

from .nominal_device import scale_of_means, scale_said, spread_scale, triad_device, zero_counts
from ..io.chunks import Fallback, Head, csv_chunks
from ..readings.clipping import code_step_counts
from ..readings.no_rest import REST_NOISE_MAX, force_median, share_of
from ..readings.noise_stream import NoisePass
from ..readings.static import EDGE_SIGMA, MIN_POSE_S, STATIC_THRESHOLD, STATIC_WINDOW_S, window_len
from ..readings.still_pieces import long_enough, static_runs
from ..readings.still_stream import DiffSums, LoggerBound, StillPass, percentiles_of_counts

__all__ = ["MAX_STILL_ROWS", "still_scale", "still_stretches"]

#: the most rows of one run of static blocks (and a window either side) the still pass holds (2^18 rows,
#: 6 MiB of counts and about 40 MiB of the step test's floats); a longer run goes as a LongRun (its
#: rows not held; Fallback where it may hold an instant step)
MAX_STILL_ROWS = 1 << 18


def read(path: Any, head: Head, block_bytes: int, bar: Any, *feeds: Callable[[np.ndarray], None]) -> None:
    """One pass over the file's rows, each chunk's counts to every ``feeds``."""
    for ch in csv_chunks(path, head, block_bytes, None if bar is None else bar.update):
        for feed in feeds:
            feed(ch.raw)
    if bar is not None:
        bar.close()


def still_scale(path: Any, head: Head, block_bytes: int, bar_for: Callable[[], Any], sums: Any, hists: list,
                rate_hz: float, gravity: float, bits: int, signed: bool, notes: list[str]
                ) -> tuple[float, np.ndarray | None]:
    """``nominal_triad``'s scale (counts per m/s^2, its note appended to ``notes``) and noise
    (counts per channel, or None where the spread gives no probe) for the recording whose first
    pass gave ``sums`` (:class:`accelcal.convert.bounded.Sums`, with its differences) and the
    channels' histograms ``hists``; ``rate_hz`` the device's rate."""
    n = sums.n
    if sums.labels and len(sums.labels) == n:
        raise Fallback("every row a pose of its own (a file of pose means)")
    pct = np.array([percentiles_of_counts(u, cnt) for u, cnt in hists])
    k = spread_scale(pct[:, 0], pct[:, 1], gravity)
    at_rest, noise = None, None
    if k > 0:
        probe = triad_device("csv-triad", rate_hz, gravity, bits, signed, k)

        def passes(*feeds: Callable[[np.ndarray], None]) -> None:
            read(path, head, block_bytes, bar_for(), *feeds)

        out, means, noise = still_stretches(passes, n, probe, hists, sums.diffs)
        at_rest = scale_of_means(means, zero_counts(bits, signed), gravity)
    return scale_said(k, at_rest, False, bits, gravity, notes), noise


def still_stretches(passes: Callable[..., None], n: int, probe: Any, hists: list, diffs: DiffSums
                    ) -> tuple[list[tuple[int, int]], list[np.ndarray], np.ndarray]:
    """``detect_static(rec, probe, noise=noise)``'s intervals of a recording of ``n`` rows read
    by ``passes(*feeds)`` (one pass over its rows in chunks, each chunk's counts to every feed),
    the mean reading of each, and the noise (``estimate_noise``'s); ``hists`` each channel's
    histogram (values ascending, counts), ``diffs`` the first pass's differences (module doc for
    the Fallbacks)."""
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
            noise = p.noise()
        except ValueError:
            raise Fallback("window sums beyond exact floats") from None
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
    min_n = max(w, int(math.ceil(MIN_POSE_S * probe.sample_rate_hz)))
    keep = long_enough(still.out, n, min_n)
    return ([iv for iv, k in zip(still.out, keep) if k], [m for m, k in zip(still.means, keep) if k], noise)
