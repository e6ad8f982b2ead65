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

from typing import Any, Callable

import numpy as np

from .nominal_device import scale_of_means, scale_said, spread_scale, triad_device, zero_counts
from ..io.chunks import Fallback, Head, csv_chunks
from ..readings.still_stream import percentiles_of_counts, still_stretches

__all__ = ["still_scale"]


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
