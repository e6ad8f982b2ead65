"""The nominal device of a converted file (:func:`nominal_triad`: a triad whose scale is the
stated LSB's, else its readings' at rest) and the ADC's range its readings must fit
(:func:`check_range`)."""
from __future__ import annotations

import numpy as np

from ..io.device import Device
from ..errors import InputError
from ..readings.noise import noise_for
from ..io.recording import Recording
from ..readings.static import STATIC_WINDOW_S, detect_static, scale_agreement, window_len
from ..io.units import Scale

__all__ = ["adc_range", "nominal_triad", "rest_scale", "scale_of_means", "scale_said", "spread_scale",
           "triad_device", "zero_counts", "check_range", "STEP_MIN_VALUES", "code_step_note"]
#: distinct readings a file needs before every count being a multiple of a step is noted (by chance,
#: 16 distinct values are all even with probability 2**-16)
STEP_MIN_VALUES = 16


def adc_range(bits: int, signed: bool) -> tuple[int, int]:
    return (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if signed else (0, 2 ** bits - 1)


def code_step_note(raw: np.ndarray, bits: int) -> list[str]:
    """A note where every count of ``raw`` (n, 3) is a multiple of one step >= 2 (their gcd;
    at least STEP_MIN_VALUES distinct values): a chip whose reading is left-justified in a
    wider register (a LIS3DH's 12 bits in 16: every count a multiple of 16), whose resolution
    is the step, not one count; else none."""
    u = np.unique(np.asarray(raw, dtype=np.int64))
    if u.size < STEP_MIN_VALUES:
        return []
    step = int(np.gcd.reduce(u))
    if step < 2:
        return []
    shift = step.bit_length() - 1
    left = (f" (a {bits - shift}-bit reading left-justified in {bits} bits)"
            if step == 1 << shift and bits > shift else "")
    return [f"every count is a multiple of {step}{left}: the chip's resolution is {step} counts, and the counts "
            "are kept as they are"]


def nominal_triad(name: str, rate: float, gravity: float, raw: np.ndarray, bits: int, signed: bool,
                  scale: Scale | None, notes: list[str], rec: Recording | None = None
                  ) -> tuple[Device, np.ndarray | None]:
    """A triad at the origin along x, y, z: counts per m/s^2 from the LSB when stated, else from
    the readings: the median |reading vector| over the still stretches of ``rec``
    (:func:`rest_scale`: |f| = g at rest, whatever the orientation; each row of a file of pose
    means, every row a pose of its own), and where there is none
    half the spread of each axis between its 1st and 99th percentiles, over g (as load_xsens;
    that assumes every axis turned through +-1 g: a wrist watch whose z never points up read
    74 counts per m/s^2 for 105.8).  A note says which.

    Returns
    -------
    device : Device
    noise : ndarray (3,) or None
        The readings' noise, counts per channel (:func:`noise.noise_for` of the device: it states
        none), where the still stretches were looked for; else None.
    """
    k = scale.counts_per_mps2(gravity) if scale is not None else None
    zero = zero_counts(bits, signed)

    def triad(k: float) -> Device:
        return triad_device(name, rate, gravity, bits, signed, k)

    noise = None
    if k is None:
        spread_lo, spread_hi = np.percentile(raw, [1.0, 99.0], axis=0)
        k = spread_scale(spread_lo, spread_hi, gravity)
        at_rest = None
        means = rec is not None and bool(np.all(rec.pose >= 0)) and np.unique(rec.pose).size == rec.n_samples
        if means:                    # pose means: each row is at rest
            at_rest = rest_scale(rec, triad(k), zero, gravity, intervals=[(i, i + 1) for i in range(rec.n_samples)])
        elif rec is not None and k > 0:
            probe = triad(k)         # (its noise is the final device's: the same rate, neither states one)
            noise = noise_for(probe, rec.raw, window_len(probe, STATIC_WINDOW_S, rec.n_samples))[0]
            at_rest = rest_scale(rec, probe, zero, gravity, noise)
        k = scale_said(k, at_rest, means, bits, gravity, notes)
    return triad(k), noise


def zero_counts(bits: int, signed: bool) -> np.ndarray:
    """The nominal triad's zero: 0 signed, mid-range unsigned (counts)."""
    return np.full(3, 0.0 if signed else 2.0 ** (bits - 1))


def triad_device(name: str, rate: float, gravity: float, bits: int, signed: bool, k: float) -> Device:
    """:func:`nominal_triad`'s device of ``k`` counts per m/s^2."""
    lo, hi = adc_range(bits, signed)
    return Device(name=name, sample_rate_hz=round(rate, 6), gravity_mps2=gravity, raw_min=lo, raw_max=hi,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, k),
                  zero_counts=zero_counts(bits, signed), noise_mps2=0.0)


def spread_scale(spread_lo: np.ndarray, spread_hi: np.ndarray, gravity: float) -> float:
    """Counts per m/s^2 from each axis's 1st and 99th percentiles (half their spread over g, the
    mean over the axes, to 0.1)."""
    return round(float(np.mean((spread_hi - spread_lo) / 2.0)) / gravity, 1)


def scale_said(k: float, at_rest: tuple[float, int] | None, means: bool, bits: int, gravity: float,
               notes: list[str]) -> float:
    """The nominal scale (counts per m/s^2) and its note: the still stretches' ``at_rest``
    (:func:`rest_scale`), else the spread's ``k`` (:func:`spread_scale`), else a guess."""
    if at_rest is not None:
        k = at_rest[0]
        of = f"the {at_rest[1]} pose means" if means else \
            f"{at_rest[1]} still stretch{'es' if at_rest[1] > 1 else ''}"
        notes.append(f"the device's nominal scale, {k:g} counts per m/s^2, is the median |reading| of {of} over g "
                     "(|f| = g at rest; state --full-scale G for the chip's)")
    elif k > 0:
        notes.append(f"the device's nominal scale, {k:g} counts per m/s^2, is taken from the readings' "
                     "spread, 1st to 99th percentile, as if every axis turned through +-1 g (no still stretch "
                     "found; state --full-scale G for the chip's)")
    else:
        k = 2.0 ** (bits - 1) / (2.0 * gravity)
        notes.append(f"the readings span no range: the device's nominal scale is a guess ({k:g} counts per "
                     "m/s^2, +-2 g); state --full-scale G")
    return k


def rest_scale(rec: Recording, device: Device, zero: np.ndarray, gravity: float,
               noise: np.ndarray | None = None, intervals: list[tuple[int, int]] | None = None
               ) -> tuple[float, int] | None:
    """Counts per m/s^2 from the recording's still stretches (``intervals`` of samples [a, b), else
    :func:`static.detect_static`'s with the noise ``noise`` (counts per channel) or else estimated
    from the readings): the median over them of |mean reading - zero|
    over ``gravity`` (|f| = g at rest, the three channels together), of those that agree
    within REST_F_AGREE where three or more do (:func:`static.scale_agreement`: a stretch in
    free fall is no rest), to 4 significant digits; and how many stretches gave it.  None
    where there is no still stretch (or they read no force)."""
    intervals = detect_static(rec, device, noise=noise) if intervals is None else intervals
    return scale_of_means([rec.raw[a:b].mean(axis=0) for a, b in intervals], zero, gravity)


def scale_of_means(means: list, zero: np.ndarray, gravity: float) -> tuple[float, int] | None:
    """:func:`rest_scale` from the still stretches' mean readings ``means`` (counts)."""
    norms = np.array([np.linalg.norm(m - zero) for m in means])
    if norms.size == 0 or not np.any(norms > 0):
        return None
    agreed = scale_agreement(norms)
    if agreed is not None:
        norms = norms[agreed[1]]
    return float(f"{float(np.median(norms)) / gravity:.4g}"), int(norms.size)


def check_range(raw: np.ndarray, bits: int, signed: bool, source: str, locate) -> None:
    lo, hi = adc_range(bits, signed)
    out = np.argwhere((raw < lo) | (raw > hi))
    if out.size:
        i, j = (int(v) for v in out[0])
        row, column = locate(i, j)
        raise InputError(source, f"reading {int(raw[i, j])} counts is outside {'signed' if signed else 'unsigned'} "
                         f"{bits}-bit [{lo}, {hi}] (state --bits N)", row=row, column=column)
