"""Why a recording holds no rest: noise beyond what a still sensor shows against its |f|
(a file of pose means in random order, a motion throughout), or readings with no gravity in
them (a phone app's linear or user acceleration).  The static detector and the refusals of
calibrate and diagnose that found no rest share these rules."""
from __future__ import annotations

import numpy as np

from .device import GRAVITY_REMOVED_G

__all__ = ["REST_NOISE_MAX", "noise_share", "median_force", "no_rest_clause", "gravity_removed_clause"]

REST_NOISE_MAX = 0.05      # a recording whose noise (stated or estimated) on a channel is beyond this x its readings'
                           # median |f| has no rest in it: the static detector finds none, whatever the noise (real
                           # rests: 0.001-0.01 x |f|, a robot arm's quiet windows up to 0.019; 2 x 0.05 is readings
                           # turning by +-10 deg; a file of pose means in random order, whose rows are all its
                           # 'noise': 0.2-0.6, and within twice that rows tens of degrees apart were one pose)


def noise_share(raw: np.ndarray, device, sig: np.ndarray) -> np.ndarray:
    """(N,) each channel's noise ``sig`` (counts) as a share of the readings' median |f| (the
    device file's nominal offsets and sensitivities, least squares over the channels; a wrong
    scale moves |f| and the noise alike); 0 where the median |f| is 0.

    A still sensor's noise is a small share of |f| (REST_NOISE_MAX).  A recording with no rest
    in it (a file of pose means, one orientation a row, in random order) is one regime to
    :func:`accelcal.noise.estimate_noise`, whose noise is then the scatter of its rows: within
    twice that, rows pointing tens of degrees apart had been taken for one pose.
    """
    raw = np.asarray(raw)
    ref = median_force(raw, device)
    if not ref > 0:
        return np.zeros(raw.shape[1])
    return np.asarray(sig, float) / (ref * np.linalg.norm(device.nominal_sensitivity(), axis=1))


def median_force(raw: np.ndarray, device) -> float:
    """The readings' median |f| (m/s^2) through the device file's nominal offsets and
    sensitivities (least squares over the channels; up to 5000 rows, evenly spaced); 0 for no rows."""
    raw = np.asarray(raw)
    x = raw[:: max(1, raw.shape[0] // 5000)] - device.nominal_offsets()
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
            "1 g: gravity looks removed (a phone's linear or user acceleration, such as Sensor Logger's "
            "Accelerometer.csv; its TotalAcceleration.csv or AccelerometerUncalibrated.csv holds gravity)")


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
