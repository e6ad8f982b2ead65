"""Ringing after stops: a resonance that the static poses do not show.

A structure that rings when the motion stops (a loose mount, a board on long standoffs)
leaves a damped oscillation in the first part of each rest.  The static detector counts it
as motion, so a diagnosis that models the static poses only (jig-free, or stated f on
labelled poses) never scores those samples, and the spectral-line test of
:mod:`.leftover` sees only what is left of it inside the poses.  This test reads it where
it lies, per recording, in three kinds of windows of SETTLE_WINDOW_S:

* settling: the samples just before each static interval (the end of the motion and the
  ringing that the detector still took for motion);
* onset: the samples just after each static interval ends (the start of the next motion:
  as rough as a stop, but with nothing ringing);
* rest: the last samples of each static interval (the noise);
* early rest: the first samples of each static interval, where a long ringing goes on below
  the detector's threshold.

Per channel every window is detrended (a line) and Hann-windowed, and its periodogram is
averaged over the stops.  A ringing is a bin at or above SETTLE_MIN_HZ (above hand motion
and tremor) whose settling power stands out of the rest spectrum at that frequency and of
the settling spectrum's own running median over SETTLE_BACKGROUND_BINS bins (a line, not
the broadband knock of a hand setting the sensor down), and is no line of the motion
itself: it stands out of the onset spectrum at that frequency, or, where the motions
start far more roughly than they stop (a hand picking the sensor up; imucal's and the
MPU-6050's sessions, where the onset is tens of times the stop's power at 15-50 Hz), it
is still there in the early rest beyond the rest and the onset shows no line there (a
vibration that runs with the motion is a line at its start too, and ends with it).  Each
comparison is passed by chance with probability SETTLE_FALSE_ALARM over every bin and
channel tested (F ratio of two averages of 2 x stops degrees of freedom each; the
running-median test by the chi-square quantile).  At least SETTLE_MIN_STOPS stops are
needed.
"""
from __future__ import annotations

import math

import numpy as np
from scipy import signal, stats
from scipy.ndimage import median_filter

from ..readings.static import detect_static

SETTLE_WINDOW_S = 0.5        # length of the settling, onset and rest windows (s) ...
SETTLE_MIN_SAMPLES = 16      # ... and at least this many samples
SETTLE_MIN_HZ = 15.0         # the lowest frequency a ringing is looked for at (above motion and tremor)
SETTLE_MIN_STOPS = 4         # stops needed (settling windows with an onset and a rest window to compare)
SETTLE_FALSE_ALARM = 1e-3    # chance that noise alone passes all three tests at some bin and channel
SETTLE_BACKGROUND_BINS = 9   # running-median width (bins) of the settling spectrum a line stands out of


def _spectrum(x: np.ndarray) -> np.ndarray:
    """Periodogram (F, N) of one window (L, N): linear trend out, Hann window."""
    return signal.periodogram(x, window="hann", detrend="linear", axis=0, scaling="spectrum")[1]


def settling_ringing(recs, device, sigma: np.ndarray | None = None) -> dict | None:
    """A ringing after the stops of the recordings ``recs`` (see the module doc), or None.

    ``sigma``: per-channel noise (counts) for the static detector (default: from the data).
    Returns ``peak_hz``, ``channels``, ``n_stops``, ``rms_counts`` (the ringing's rms in the
    settling windows beyond the rest's power at the lines' bins, and beyond the onset's where
    that comparison was passed; per channel) and
    ``ratio_to_onset`` / ``ratio_to_rest`` (settling / reference power at the peak)."""
    fs = float(device.sample_rate_hz)
    L = max(SETTLE_MIN_SAMPLES, int(round(SETTLE_WINDOW_S * fs)))
    freqs = np.fft.rfftfreq(L, 1.0 / fs)
    band = freqs >= SETTLE_MIN_HZ
    band[-1] &= L % 2 == 1          # not the Nyquist bin of an even window (a real tone's alias sits there)
    if not band.any():
        return None
    acc = {"settle": None, "onset": None, "rest": None, "early": None}
    n_stops = 0
    for rec in recs:
        raw = np.asarray(rec.raw, float)
        n = raw.shape[0]
        ivs = detect_static(rec, device, noise=sigma) if n >= 4 * L else []
        for k, (a, b) in enumerate(ivs):
            # a settling window after motion (not the recording's start, not overlapping the
            # previous rest), an onset window before the next rest, a rest window past the margin
            prev_end = ivs[k - 1][1] if k > 0 else 0
            if a - L < max(prev_end, 0) or b + L > n or b - a < 2 * L:
                continue
            nxt = ivs[k + 1][0] if k + 1 < len(ivs) else n
            if b + L > nxt:
                continue
            parts = {"settle": raw[a - L:a], "onset": raw[b:b + L], "rest": raw[b - L:b], "early": raw[a:a + L]}
            for key, x in parts.items():
                P = _spectrum(x)
                acc[key] = P if acc[key] is None else acc[key] + P
            n_stops += 1
    if n_stops < SETTLE_MIN_STOPS:
        return None
    Ps, Po, Pr, Pe = (acc[k] / n_stops for k in ("settle", "onset", "rest", "early"))
    tests = int(band.sum()) * Ps.shape[1]
    dof = 2.0 * n_stops
    f_ratio = stats.f.ppf(1.0 - SETTLE_FALSE_ALARM / tests, dof, dof)
    bg = median_filter(Ps, size=(SETTLE_BACKGROUND_BINS, 1), mode="mirror")
    line_ratio = stats.chi2.ppf(1.0 - SETTLE_FALSE_ALARM / tests, dof) / stats.chi2.median(dof)
    tiny = 1e-300

    def above(p, q):
        return p > f_ratio * np.maximum(q, tiny)

    bg_o = median_filter(Po, size=(SETTLE_BACKGROUND_BINS, 1), mode="mirror")
    over_onset = above(Ps, Po)
    # where the motions start rougher than they stop: still there in the rest's first window,
    # and no line at the motion's start (a line of the motion itself starts and ends with it)
    lingers = above(Pe, Pr) & above(Ps / np.maximum(bg, tiny), np.maximum(Po / np.maximum(bg_o, tiny), 1.0))
    hit = band[:, None] & (over_onset | lingers) & above(Ps, Pr) & (Ps > line_ratio * np.maximum(bg, tiny))
    if not hit.any():
        return None
    # the ringing's power: the settling's beyond the rest, and beyond the onset where that was passed
    excess = np.where(hit, Ps - np.where(over_onset, np.maximum(Po, Pr), Pr), 0.0)
    j, ch = np.unravel_index(np.argmax(excess), excess.shape)
    # the periodogram (scaling "spectrum") gives power per bin; a Hann window spreads a line
    # over about 1.5 bins' worth of equivalent noise bandwidth
    enbw = 1.5
    rms_ch = np.sqrt(np.maximum(excess.sum(axis=0), 0.0) / enbw)
    return {"peak_hz": float(freqs[j]), "channels": [int(i) for i in np.flatnonzero(hit.any(axis=0))],
            "n_stops": int(n_stops), "window_s": L / fs, "rms_counts": float(math.sqrt(np.mean(rms_ch ** 2))),
            "rms_per_channel": rms_ch.tolist(),
            "ratio_to_onset": float(Ps[j, ch] / max(Po[j, ch], tiny)),
            "ratio_to_rest": float(Ps[j, ch] / max(Pr[j, ch], tiny))}
