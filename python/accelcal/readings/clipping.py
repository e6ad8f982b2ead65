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
looks the same as a clip.  On such a channel a pile is a clip only where the device
moves throughout its hold and the channel comes to it from far (:func:`pile_moves`: in
a pose every channel rests, and so it does in the rest before a push across the axis of a
channel held steady through both; a clip that the motion reaches holds while the others
swing by hundreds of their noise).  A channel that reads one value throughout has no level:
nothing came to it from elsewhere.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .noise import code_lattice_counts, code_step, noise_for


CLIP_MIN_COUNT = 10        # readings at one extreme value before it can be a clip level


CLIP_PILE_RATIO = 4.0      # ... and this many times an average code just below it


CLIP_BAND_SIGMA = 4.0      # "just below": within this many noise sigmas


CLIP_MOVING_SIGMA = 20.0   # a channel quieter than a code: its pile is a clip where another channel
                           # spans this many of its noise sigmas throughout the pile's runs ...


CLIP_MOVING_SHARE = 0.5    # ... for at least this share of the pile's readings


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
    return pile_verdict(ext, c, near, band, step)


def pile_level_counts(u: np.ndarray, cnt: np.ndarray, side: int, sigma: float, step: int) -> float | None:
    """:func:`pile_level` from the distinct readings ``u`` (int64, ascending) and their counts."""
    ext = u[-1] if side > 0 else u[0]
    c = int(cnt[-1] if side > 0 else cnt[0])
    if c < CLIP_MIN_COUNT:
        return None
    band = max(CLIP_BAND_SIGMA * sigma, 2.0 * step)
    away = side * (ext - u)
    near = int(cnt[(away > 0) & (away <= band)].sum())
    return pile_verdict(ext, c, near, band, step)


def pile_verdict(ext, c: int, near: int, band: float, step: int) -> float | None:
    """Whether ``c`` readings at the extreme ``ext`` pile up over the ``near`` readings within
    ``band`` of it: ext, else None."""
    per_code = near / max(band / step, 1.0)
    if c < CLIP_PILE_RATIO * per_code + CLIP_MIN_COUNT:
        return None
    return float(ext)


def pile_moves(raw: np.ndarray, i: int, level: float, noise: np.ndarray, window: int) -> bool:
    """Whether channel ``i``'s readings at ``level`` are a clip reached while the device moves.

    For CLIP_MOVING_SHARE of them, their run must be in motion throughout (in each stretch of
    ``window`` readings of it, at a stride of half that, with a sample either side, some other
    channel spans CLIP_MOVING_SIGMA of its noise sigmas, at least its rounding noise
    q / sqrt(12)), and channel ``i`` must come from, or leave for, that many of its own sigmas
    away within ``window`` readings of the run.  A pose that sits on one code holds the level
    with every channel at rest; so does a channel held steady from a rest on into a push
    across its axis, through the rest.  False with no other channel."""
    n, N = raw.shape
    if N < 2:
        return False
    window = max(int(window), 3)
    v = raw[:, i].astype(np.int64)
    at = v == level
    edge = np.diff(np.concatenate(([0], at.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edge == 1), np.flatnonzero(edge == -1)
    floor = np.array([max(float(noise[j]), code_step(raw[:, j]) / np.sqrt(12.0)) for j in range(N)])
    others = [j for j in range(N) if j != i]
    big = CLIP_MOVING_SIGMA * floor[others]

    def moves(lo, hi):
        seg = raw[max(lo, 0):min(hi, n)][:, others].astype(np.int64)
        return bool(np.any(np.ptp(seg, axis=0) >= big))

    moving = 0
    for a, b in zip(starts, ends):
        heads = range(a, max(b - window, a) + 1, max(window // 2, 1))
        near = np.concatenate((v[max(a - window, 0):a], v[b:min(b + window, n)]))
        if (all(moves(h - 1, min(h + window, b) + 1) for h in heads) and near.size
                and np.max(np.abs(near - level)) >= CLIP_MOVING_SIGMA * floor[i]):
            moving += int(b - a)
    return moving >= CLIP_MOVING_SHARE * int(np.count_nonzero(at))


def clip_levels(raw: np.ndarray, device, noise: np.ndarray, window: int) -> ClipLevels:
    """The clip levels of each channel of integer readings.

    Parameters
    ----------
    raw : array_like (n, N) int
        Readings (counts).
    device : Device
        For raw_min / raw_max.
    noise : array_like (N,)
        Noise std per channel (counts), e.g. from :func:`accelcal.readings.noise.noise_for`.
    window : int
        Readings in a static-detection window (``static.window_len``): on a channel quieter
        than a code, the stretch over which a pile must show motion (:func:`pile_moves`).

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
        if v.min() == v.max():
            continue    # one value throughout (a noiseless simulation): nothing reached a level from elsewhere
        q = code_step(v)
        sig = float(noise[i])
        # coarse steps: a pose on one code looks like a pile, which is a clip only while moving
        coarse = sig < q
        top = pile_level(v, 1, sig, q)
        if top is not None and top < device.raw_max and (not coarse or pile_moves(raw, i, top, noise, window)):
            hi[i], in_hi[i] = top, True
        bot = pile_level(v, -1, sig, q)
        if bot is not None and bot > device.raw_min and (not coarse or pile_moves(raw, i, bot, noise, window)):
            lo[i], in_lo[i] = bot, True
    return ClipLevels(lo=lo, hi=hi, inside_lo=in_lo, inside_hi=in_hi)


def code_step_counts(u: np.ndarray, cnt: np.ndarray) -> int:
    """:func:`accelcal.readings.noise.code_step` from the distinct readings ``u`` (int64,
    ascending) and their counts."""
    if u.size < 2:
        return 1
    g = int(np.gcd.reduce(np.diff(u)))
    return g if g >= 2 else code_lattice_counts(u, cnt)[0]


def clip_levels_counts(hists: list[tuple[np.ndarray, np.ndarray]], device, noise: np.ndarray) -> ClipLevels | None:
    """:func:`clip_levels` from each channel's distinct readings and their counts, or None where
    a channel quieter than a code has a pile (:func:`pile_moves` needs the readings in order)."""
    N = len(hists)
    lo, hi = np.full(N, float(device.raw_min)), np.full(N, float(device.raw_max))
    in_lo, in_hi = np.zeros(N, bool), np.zeros(N, bool)
    for i, (u, cnt) in enumerate(hists):
        if u[0] == u[-1]:
            continue
        q = code_step_counts(u, cnt)
        sig = float(noise[i])
        top, bot = pile_level_counts(u, cnt, 1, sig, q), pile_level_counts(u, cnt, -1, sig, q)
        top = top if top is not None and top < device.raw_max else None
        bot = bot if bot is not None and bot > device.raw_min else None
        if sig < q and (top is not None or bot is not None):
            return None
        if top is not None:
            hi[i], in_hi[i] = top, True
        if bot is not None:
            lo[i], in_lo[i] = bot, True
    return ClipLevels(lo=lo, hi=hi, inside_lo=in_lo, inside_hi=in_hi)


def clip_note(raw: np.ndarray, device, window: int, name=lambda i: f"raw_{i}",
              noise: np.ndarray | None = None) -> str | None:
    """A note counting the clipped readings (:func:`clip_levels`, the noise ``noise``, counts per
    channel, else from :func:`noise.noise_for`) per channel and end: how many at each level, which
    is the converter's limit (raw_min / raw_max) or a pile inside the range; None where there are
    none.  ``name(i)``: channel i's name for the note (a file's column)."""
    raw = np.asarray(raw)
    if raw.shape[0] < 2:
        return None
    noise = noise_for(device, raw, window)[0] if noise is None else noise
    levels = clip_levels(raw, device, noise, window)
    counts = [(int(np.count_nonzero(raw[:, i] <= levels.lo[i])), int(np.count_nonzero(raw[:, i] >= levels.hi[i])))
              for i in range(raw.shape[1])]
    return clip_counts_text(counts, levels.lo, levels.hi, levels.inside_lo, levels.inside_hi, name)


def clip_counts_text(counts, lo, hi, inside_lo, inside_hi, name=lambda i: f"raw_{i}") -> str | None:
    """:func:`clip_note`'s text from each channel's (readings <= lo, readings >= hi) ``counts`` and
    its levels (``inside_*``: a pile inside the range, else the converter's limit); None for none."""
    parts, total = [], 0
    for i, (k_lo, k_hi) in enumerate(counts):
        ends = []
        for k, level, inside, limit in ((k_lo, lo[i], inside_lo[i], "raw_min"), (k_hi, hi[i], inside_hi[i], "raw_max")):
            if k:
                total += k
                ends.append(f"{k} at {int(level)}" + (" (a pile inside the range)" if inside else f" ({limit})"))
        if ends:
            parts.append(f"{name(i)} " + " and ".join(ends))
    if not total:
        return None
    return (f"{total} reading(s) sit at the ends of the range, clipped (in counts: {'; '.join(parts)}): the sensor "
            "went beyond its full scale there (shocks, vibration); calibrate and diagnose set aside the poses they "
            "touch")


def at_rails(rec, device) -> np.ndarray:
    """(n,) bool: samples with a channel at the ADC's rail (``raw_min`` or ``raw_max`` of the
    device): the chip clipped there, and f read from it is short of the truth, whatever the
    engine.  The C core's saturation flag reports its own arithmetic (a pre-trim that leaves 16
    bits), which a rail reading sets or not by the sign of its trim; this is the sensor's."""
    raw = np.asarray(rec.raw)
    return np.any((raw <= device.raw_min) | (raw >= device.raw_max), axis=1)


def rails_warning(rec, device) -> str | None:
    """The warning for samples at the ADC's rails (:func:`at_rails`), per channel, or None."""
    raw = np.asarray(rec.raw)
    low, high = raw <= device.raw_min, raw >= device.raw_max
    clipped = np.any(low | high, axis=1)
    if not clipped.any():
        return None
    return rails_text(low.sum(axis=0), high.sum(axis=0), int(np.count_nonzero(clipped)),
                      rec.line(int(np.argmax(clipped))), device)


def rails_text(low, high, count: int, first_line: int, device) -> str:
    """:func:`rails_warning`'s text from its counts: per channel the readings at raw_min (``low``)
    and raw_max (``high``), the samples with any (``count``) and the first one's line (a reader
    that goes through a recording in chunks adds them up)."""
    per = [f"raw_{j}: {int(low[j])} at {device.raw_min}, {int(high[j])} at {device.raw_max}"
           for j in range(len(low)) if low[j] or high[j]]
    return (f"{count} samples read a channel at the ADC's rail ({'; '.join(per)}; the first "
            f"at row {first_line}): the chip clipped there and their f is short of the truth (see column "
            "clipped)")



def pile_warning(rec, levels: ClipLevels) -> str | None:
    """The warning for samples at a clip level inside the range (``levels``' piles, the ones
    :func:`clip_note` names for convert and diagnose), per channel and level, or None: the
    rails' own samples are :func:`rails_warning`'s."""
    raw = np.asarray(rec.raw)
    at = np.zeros(raw.shape[0], bool)
    hits = np.zeros((raw.shape[1], 2), np.int64)
    for j in range(raw.shape[1]):
        for side, (inside, hit) in enumerate(((levels.inside_lo[j], raw[:, j] <= levels.lo[j]),
                                              (levels.inside_hi[j], raw[:, j] >= levels.hi[j]))):
            if inside:
                at |= hit
                hits[j, side] = int(hit.sum())
    if not at.any():
        return None
    return pile_text(levels, hits, int(np.count_nonzero(at)), rec.line(int(np.argmax(at))))


def pile_text(levels: ClipLevels, hits: np.ndarray, count: int, first_line: int) -> str:
    """:func:`pile_warning`'s text from its counts: ``hits`` (N, 2) the readings at or beyond each
    channel's low and high level inside the range, ``count`` the samples with any, the first
    one's line."""
    per = []
    for j in range(hits.shape[0]):
        ends = [f"{int(hits[j, side])} at {int(level)}"
                for side, (inside, level) in enumerate(((levels.inside_lo[j], levels.lo[j]),
                                                        (levels.inside_hi[j], levels.hi[j])))
                if inside and hits[j, side]]
        if ends:
            per.append(f"raw_{j}: " + ", ".join(ends))
    return (f"{count} samples read a channel at a clip level inside the range, where its "
            f"readings pile up ({'; '.join(per)}; the first at row {first_line}; convert and diagnose name the "
            "same levels): the sensor clipped there and their f is short of the truth (see column clipped)")
