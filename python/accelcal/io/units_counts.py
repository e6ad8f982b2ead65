"""Readings in physical units as the integer counts the data contract asks for
(:func:`to_counts`), once their Scale is known (:mod:`accelcal.io.units`: what states it).

A logger that writes floats has still read an integer register: every value is a whole
number of LSBs, taken only when each is (within :data:`~accelcal.io.units.REL_TOL` of one, or
of the digits it was printed with); else the first value that is not is named by row and
column.  Used by the recording reader and by ``accelcal convert``.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

from ..errors import InputError
from .units import REL_TOL, UNIT_TEXT, Scale
from .units_grid import decimal_places, grid_shift, significant_digits

__all__ = ["to_counts", "counts_stated_as_units", "PRINT_TOL_COUNTS", "WHOLE_MIN_VALUES"]

PRINT_TOL_COUNTS = 0.25
"""A value printed with few digits ('%g') may be off its count by half a unit in its last
significant place, where that half unit is at most this many counts (the count is then
unambiguous)."""

def to_counts(values: np.ndarray, scale: Scale, source: str,
              locate: Callable[[int, int], tuple[int, str]], notes: list | None = None) -> np.ndarray:
    """Readings in physical units as integer counts, exactly.

    Parameters
    ----------
    values : ndarray, shape (n, k)
        The readings, in ``scale.units`` (m/s^2 or g), finite.
    scale : Scale
        Its ``lsb`` is one count in the same unit.
    source : str
        The file, for messages.
    locate : callable
        ``locate(i, j)`` -> (row, column name) of reading ``values[i, j]`` in the file.
    notes : list, optional
        Where a column whose every reading is a whole number of LSBs plus one constant
        fraction (a grid shifted by an OS's offset: 0.5 LSB on a phone's axis) is said to be
        read as counts less that fraction (with at least SHIFT_MIN_VALUES readings);
        without it, such a column is refused like any other.

    Returns
    -------
    ndarray of int64, shape (n, k)
        ``round(values / lsb)`` (less the column's constant fraction where ``notes`` allows).

    Raises
    ------
    InputError
        At the first reading (earliest row, then leftmost column) that is not a whole
        number of LSBs within ``REL_TOL``, nor within the rounding of the last significant
        digit the values are printed with (the most any value of that column shows, as significant
        digits or as decimal places; a column of zeros and one such value does not show it) where
        that is at most
        PRINT_TOL_COUNTS of a count (a value printed by '%g' as -0.020752 g is -340 counts of
        1/16384 g: -340.0008), or whose count does not fit 64 bits; readings that are counts
        (:func:`counts_stated_as_units`).
    """
    counts_stated_as_units(np.asarray(values, dtype=np.float64), scale, source, locate)
    with np.errstate(invalid="ignore", over="ignore"):
        v = np.asarray(values, dtype=np.float64)
        x = v / scale.lsb
        n = np.round(x)
        big = ~(np.abs(n) < 2.0 ** 62)
        bad = ~(np.abs(x - n) <= REL_TOL * np.maximum(np.abs(n), 1.0)) | big
    sel = bad & ~big
    if scale.rounds:
        off = np.abs(x - n)[~big]
        if notes is not None and off.size:
            notes.append(f"readings rounded to whole LSBs of {scale.lsb:.6g} {UNIT_TEXT[scale.units]} (--round): up to "
                         f"{float(off.max()):.3g} of an LSB off, rms {float(np.sqrt(np.mean(off ** 2))):.3g}")
        bad = big
    elif sel.any():
        # a logger that prints its values with few digits ('%g': six significant, trailing zeros
        # dropped) leaves each off its count by up to half a unit in its last significant place, at the
        # most digits any of them shows: such a value is the count it rounds to, where that half unit
        # is at most PRINT_TOL_COUNTS of a count (the count is then unambiguous)
        u, inv = np.unique(v[sel], return_inverse=True)
        # the printing precision shows in every value of the columns at fault, the whole ones too
        shown = np.unique(v[:, np.flatnonzero(sel.any(axis=0))])
        digits = max(significant_digits(float(w)) for w in shown[np.isfinite(shown)])
        places = max(decimal_places(float(w)) for w in shown[np.isfinite(shown)])
        mag = np.floor(np.log10(np.maximum(np.abs(u), np.finfo(float).tiny)))
        # printed with that many significant digits ('%g'), or with that many decimal places ('%.6f':
        # an Axivity export's 0.007324 g is 15 counts of 1/2048 g, 14.99955)
        tol = (np.maximum(0.5 * 10.0 ** (mag - (digits - 1)), 0.5 * 10.0 ** -places) / scale.lsb)[inv.ravel()]
        fine = tol <= PRINT_TOL_COUNTS
        ok = fine & (np.abs(x[sel] - n[sel]) <= tol * (1.0 + 1e-9) + REL_TOL * np.maximum(np.abs(n[sel]), 1.0))
        bad[sel] = ~ok
    if bad.any() and notes is not None:
        for j in np.flatnonzero(bad.any(axis=0) & ~big.any(axis=0)):
            shift = grid_shift(x[:, j])
            if shift is not None:
                n[:, j] = np.round(x[:, j] - shift)
                bad[:, j] = False
                notes.append(f"column {locate(0, int(j))[1]}: every reading is a whole number of LSBs plus {shift:+.3f} "
                             "(a grid shifted by a constant, as an offset applied before writing leaves): read as "
                             "counts less that fraction, which the calibration's offset takes")
    if bad.any():
        i, j = (int(v) for v in np.argwhere(bad)[0])
        row, column = locate(i, j)
        unit = UNIT_TEXT[scale.units]
        raise InputError(source, f"{float(values[i, j])!r} {unit} is {float(x[i, j]):.9g} counts of "
                         f"{scale.lsb:.12g} {unit} (the LSB stated by {scale.how}), not a whole number: "
                         "wrong LSB or units, or the values were rounded when written (a calibrated logger's "
                         f"floats on no grid: --round rounds them to the LSB that {scale.how or 'is stated'} "
                         "states)", row=row,
                         column=column)
    return n.astype(np.int64)


#: distinct readings, all whole numbers, that show counts where a unit was stated with an LSB of at most half a unit
WHOLE_MIN_VALUES = 10


def counts_stated_as_units(v: np.ndarray, scale: Scale, source: str, locate: Callable[[int, int], tuple[int, str]]
                           ) -> None:
    """Refuse readings that are counts stated as m/s^2 or g (``--units g --lsb 0.001`` over
    whole numbers: 1000 read as 1000 g): every one a whole number, at least WHOLE_MIN_VALUES
    distinct, where the LSB is at most half a unit (whole numbers then lie 2 or more counts
    apart: a sensor whose every reading falls on such a coarse grid is not read in that LSB).

    Raises
    ------
    InputError
        Naming the largest reading's row and column and the options meant: ``--units counts``
        with the LSB's size, or ``--lsb 1`` for readings truly in whole units.
    """
    fin = v[np.isfinite(v)]
    if not scale.converts or not scale.lsb or scale.lsb > 0.5 or np.unique(fin).size < WHOLE_MIN_VALUES or \
            np.any(fin != np.round(fin)):
        return
    i, j = (int(k) for k in np.unravel_index(np.nanargmax(np.abs(v)), v.shape))
    row, column = locate(i, j)
    unit, suffix = UNIT_TEXT[scale.units], {"g": "g", "mps2": "mps2"}.get(scale.units, "")
    raise InputError(source, f"every reading is a whole number ({np.unique(fin).size} distinct; this one, "
                     f"{v[i, j]:g}, would be {v[i, j]:g} {unit}) where one count is {scale.lsb:.6g} {unit} (the LSB "
                     f"stated by {scale.how or 'the options'}): they are counts -- give --units counts --lsb "
                     f"{scale.lsb:.6g}{suffix} (or --full-scale G) for their size; were they whole {unit}, --lsb 1",
                     row=row, column=column)
