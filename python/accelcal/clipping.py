"""Clipped readings: where a channel's readings stop at a limit, and which samples sit there.

A reading is clipped when it sits at the converter's limits (the device's ``raw_min`` /
``raw_max``) or at a level inside the range at which the readings pile up: the chip's
own full scale, a saturating amplifier or filter.  Clipped readings are evidence (the
diagnosis can name ``saturation`` from them), not a reason to stop: the calibration
sets aside the poses they touch and counts them, and the rest is used.

The pile test (:func:`clip_levels`), per channel and side: the extreme value holds at
least CLIP_MIN_COUNT readings, and more than CLIP_PILE_RATIO times as many as an
average code within CLIP_BAND_SIGMA noise sigmas below it (a Gaussian tail puts only
a few readings on its extreme code).  It needs the noise to span a few codes (sigma >=
the channel's code step); a coarsely quantised channel whose pose sits on one code
looks the same as a clip, so no level inside the range is claimed there.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .noise import code_step


CLIP_MIN_COUNT = 10        # readings at one extreme value before it can be a clip level


CLIP_PILE_RATIO = 4.0      # ... and this many times an average code just below it


CLIP_BAND_SIGMA = 4.0      # "just below": within this many noise sigmas


@dataclass
class ClipLevels:
    """Per channel, the levels at and beyond which readings are clipped.

    Attributes
    ----------
    lo, hi : ndarray (N,)
        Counts: readings <= lo or >= hi are clipped (raw_min / raw_max when no level
        inside the range was found).
    inside_lo, inside_hi : ndarray (N,) bool
        The level lies inside [raw_min, raw_max] (a pile), not at the converter's limit.
    """

    lo: np.ndarray
    hi: np.ndarray
    inside_lo: np.ndarray
    inside_hi: np.ndarray

    def mask(self, raw: np.ndarray) -> np.ndarray:
        """(n, N) bool: the readings that are clipped."""
        raw = np.asarray(raw)
        return (raw <= self.lo[None, :]) | (raw >= self.hi[None, :])

    def any_inside(self) -> bool:
        return bool(self.inside_lo.any() or self.inside_hi.any())

    def describe(self) -> str:
        """Short text: the levels inside the range, channel by channel."""
        parts = []
        for i in range(self.lo.size):
            side = [f"{'<=' if s == 'lo' else '>='} {int(v)}" for s, v, on in
                    (("lo", self.lo[i], self.inside_lo[i]), ("hi", self.hi[i], self.inside_hi[i])) if on]
            if side:
                parts.append(f"raw_{i} " + " and ".join(side))
        return "; ".join(parts)


def pile_level(v: np.ndarray, side: int, sigma: float, step: int) -> float | None:
    """The extreme value of readings ``v`` on ``side`` (+1 top, -1 bottom) when readings
    pile up there (see the module doc), else None."""
    ext = v.max() if side > 0 else v.min()
    c = int(np.count_nonzero(v == ext))
    if c < CLIP_MIN_COUNT:
        return None
    band = max(CLIP_BAND_SIGMA * sigma, 2.0 * step)
    away = side * (ext - v)
    near = int(np.count_nonzero((away > 0) & (away <= band)))
    per_code = near / max(band / step, 1.0)
    if c < CLIP_PILE_RATIO * per_code + CLIP_MIN_COUNT:
        return None
    return float(ext)


def clip_levels(raw: np.ndarray, device, noise: np.ndarray) -> ClipLevels:
    """The clip levels of each channel of integer readings.

    Parameters
    ----------
    raw : array_like (n, N) int
        Readings (counts).
    device : Device
        For raw_min / raw_max.
    noise : array_like (N,)
        Noise std per channel (counts), e.g. from :func:`accelcal.noise.noise_for`.

    Returns
    -------
    ClipLevels
    """
    raw = np.asarray(raw)
    N = raw.shape[1]
    lo = np.full(N, float(device.raw_min))
    hi = np.full(N, float(device.raw_max))
    in_lo = np.zeros(N, bool)
    in_hi = np.zeros(N, bool)
    for i in range(N):
        v = raw[:, i]
        q = code_step(v)
        sig = float(noise[i])
        if sig < q:          # coarse steps: a pose on one code looks like a clip
            continue
        top = pile_level(v, 1, sig, q)
        if top is not None and top < device.raw_max:
            hi[i], in_hi[i] = top, True
        bot = pile_level(v, -1, sig, q)
        if bot is not None and bot > device.raw_min:
            lo[i], in_lo[i] = bot, True
    return ClipLevels(lo=lo, hi=hi, inside_lo=in_lo, inside_hi=in_hi)
