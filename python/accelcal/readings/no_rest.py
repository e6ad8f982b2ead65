"""Why a recording holds no rest: noise beyond what a still sensor shows against its |f|
(a file of pose means in random order, a motion throughout), or readings with no gravity in
them (a phone app's linear or user acceleration).  The static detector and the refusals of
calibrate and diagnose that found no rest share these rules."""
from __future__ import annotations

import numpy as np
from scipy.signal import welch

from ..io.device import GRAVITY_REMOVED_G, GRAVITY_REMOVED_TEXT

__all__ = ["REST_NOISE_MAX", "noise_share", "share_of", "median_force", "force_median", "no_rest_clause", "gravity_removed_clause", "tonal",
           "TONE_SHARE", "TONE_MIN_BINS"]

REST_NOISE_MAX = 0.05      # a recording whose noise (stated or estimated) on a channel is beyond this x its readings'
                           # median |f| has no rest in it: the static detector finds none, whatever the noise (real
                           # rests: 0.001-0.01 x |f|, a robot arm's quiet windows up to 0.019; 2 x 0.05 is readings
                           # turning by +-10 deg; a file of pose means in random order, whose rows are all its
                           # 'noise': 0.2-0.6, and within twice that rows tens of degrees apart were one pose)

TONE_SHARE = 0.5           # a channel whose fluctuation within the static windows holds more than this share of
                           # its power in TONE_BINS bins around one frequency is a line (mains pickup) ...
TONE_BINS = 5
TONE_MIN_BINS = 50         # ... judged where the band has at least this many bins (white noise: 5/50 = 0.1)


def tonal(raw: np.ndarray, rate_hz: float, window: int) -> np.ndarray:
    """(N,) bool: channels whose fluctuation within a static window (frequencies from 2 / the
    window's length up) is a line: more than TONE_SHARE of its power (Welch's periodogram) in
    TONE_BINS bins around one frequency.  Such noise is stationary and averages out within a
    window: a rest still holds its mean under it (50 Hz mains picked up at 200 Hz, 6 % of |f|:
    its 29 poses had been no rest by REST_NOISE_MAX), where the scatter of rows in unrelated
    directions (a file of pose means shuffled) is white."""
    x = np.asarray(raw, float)
    n, N = x.shape
    out = np.zeros(N, bool)
    if n < 8 or window < 2:
        return out
    f, p = welch(x - x.mean(axis=0), fs=rate_hz, nperseg=min(1024, n), axis=0, detrend="linear")
    band = f >= 2.0 * rate_hz / window
    p = p[band]
    if p.shape[0] < TONE_MIN_BINS:
        return out
    for j in range(N):
        k = int(np.argmax(p[:, j]))
        total = float(p[:, j].sum())
        out[j] = total > 0 and p[max(0, k - TONE_BINS // 2):k + TONE_BINS // 2 + 1, j].sum() > TONE_SHARE * total
    return out


def noise_share(raw: np.ndarray, device, sig: np.ndarray) -> np.ndarray:
    """(N,) each channel's noise ``sig`` (counts) as a share of the readings' median |f| (the
    device file's nominal offsets and sensitivities, least squares over the channels; a wrong
    scale moves |f| and the noise alike); 0 where the median |f| is 0.

    A still sensor's noise is a small share of |f| (REST_NOISE_MAX).  A recording with no rest
    in it (a file of pose means, one orientation a row, in random order) is one regime to
    :func:`accelcal.readings.noise.estimate_noise`, whose noise is then the scatter of its rows: within
    twice that, rows pointing tens of degrees apart had been taken for one pose.
    """
    raw = np.asarray(raw)
    return share_of(median_force(raw, device), device, sig)


def share_of(ref: float, device, sig: np.ndarray) -> np.ndarray:
    """:func:`noise_share` from the readings' median |f| ``ref`` (m/s^2, :func:`median_force`)."""
    sig = np.asarray(sig, float)
    if not ref > 0:
        return np.zeros(sig.shape[0])
    return sig / (ref * np.linalg.norm(device.nominal_sensitivity(), axis=1))


def median_force(raw: np.ndarray, device) -> float:
    """The readings' median |f| (m/s^2) through the device file's nominal offsets and
    sensitivities (least squares over the channels; up to 5000 rows, evenly spaced); 0 for no rows."""
    raw = np.asarray(raw)
    return force_median(raw[:: max(1, raw.shape[0] // 5000)], device)


def force_median(rows: np.ndarray, device) -> float:
    """:func:`median_force` of the rows it takes (every ``max(1, n // 5000)``-th of n: a reader in
    chunks gathers them)."""
    x = np.asarray(rows) - device.nominal_offsets()
    if not x.size:
        return 0.0
    return float(np.median(np.linalg.norm(np.linalg.lstsq(device.nominal_sensitivity(), x.T, rcond=None)[0], axis=0)))


def gravity_removed_clause(raw: np.ndarray, device) -> str:
    """"; ... gravity looks removed ..." where the readings' median |f| (:func:`median_force`) is
    below ``GRAVITY_REMOVED_G`` of the device's g (a phone app's linear or user acceleration, no
    sensor's reading: at rest any reads 1 g), to append to a refusal that found no rest; else ""."""
    g = float(device.gravity_mps2)
    ref = median_force(raw, device)
    if not 0 < ref < GRAVITY_REMOVED_G * g:
        return ""
    return (f"; the readings' median |f| is {ref / g:.2g} g with the device file's scale, where a sensor at rest reads "
            f"1 g: {GRAVITY_REMOVED_TEXT}")


def no_rest_clause(raw: np.ndarray, device, sig: np.ndarray) -> str:
    """Why a recording has no rest, where its noise ``sig`` (counts) is beyond REST_NOISE_MAX of
    its |f| (:func:`noise_share`): ": the noise ... " to append to :func:`no_pose`; else ""."""
    share = noise_share(raw, device, sig)
    c = int(np.argmax(share))
    if not share[c] > REST_NOISE_MAX:
        return ""
    return (f": its noise on raw_{c} ({sig[c]:.4g} counts) is {100 * share[c]:.3g} % of its readings' median |f|, "
            f"beyond a still sensor's {100 * REST_NOISE_MAX:g} %: its readings scatter throughout, as a motion's or "
            "as rows pointing in unrelated directions")
