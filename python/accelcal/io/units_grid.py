"""How readings in physical units sit on an LSB's grid (:func:`accelcal.io.units_counts.to_counts`): a
column shifted off the grid by a constant fraction of an LSB, and the digits a value was
printed with."""
from __future__ import annotations

from decimal import Decimal

import numpy as np

__all__ = ["grid_shift", "decimal_places", "significant_digits", "SHIFT_MIN_VALUES", "SHIFT_TOL_COUNTS"]


#: distinct readings a column needs before a constant fraction of an LSB is taken for a shifted grid
SHIFT_MIN_VALUES = 20
#: ... each within this much of a count of the grid
SHIFT_TOL_COUNTS = 0.01


def grid_shift(x: np.ndarray) -> float | None:
    """The constant fraction (in (-0.5, 0.5], not ~0) by which every value of ``x`` (counts,
    as floats) is off a whole number, within SHIFT_TOL_COUNTS, or None."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if np.unique(x).size < SHIFT_MIN_VALUES:      # a column of a few values sits on any grid
        return None
    frac = x - np.round(x)
    phase = float(np.angle(np.mean(np.exp(2j * np.pi * frac)))) / (2 * np.pi)
    off = (frac - phase + 0.5) % 1.0 - 0.5
    if abs(phase) <= SHIFT_TOL_COUNTS or float(np.max(np.abs(off))) > SHIFT_TOL_COUNTS:
        return None
    return 0.5 if abs(abs(phase) - 0.5) < 1e-6 else phase     # half a step: +0.5, one convention


def decimal_places(v: float) -> int:
    """Decimal places of ``repr(v)`` past the point (0.007324 -> 6, 0.5 -> 1, 12.0 -> 0)."""
    return max(0, -int(Decimal(repr(v)).normalize().as_tuple().exponent))


def significant_digits(v: float) -> int:
    """Significant digits of ``repr(v)``, the shortest text that reads back as ``v``
    (-0.020752 -> 5, -0.142090 printed by '%g' as -0.14209 -> 5, 1/3 -> 16)."""
    return len(Decimal(repr(v)).normalize().as_tuple().digits)
