"""The real Xsens accelerometer recording from imu_tk (shared/data/imu_tk_xsens).

File: whitespace-separated ASCII (optionally compressed), no header, one sample a row: t [s], then
raw x, y, z in 16-bit ADC counts, 100 Hz.  No reference orientation: a jig-free
calibration problem (about 50 s at rest, then about 40 hand-held static poses).

Device built for it (a triad at the origin, axes x, y, z):

- zero 32768 counts (imu_tk's example initialises the accelerometer bias there);
- raw range 0..65535 (16-bit ADC);
- gravity 9.81744 m/s^2 (the local value imu_tk's example uses);
- nominal scale from the data itself (the vendor's is not in the file): half the
  spread of each axis' readings between their 1st and 99th percentiles over the
  whole recording -- the ~40 hand-held poses take every axis to about +-1 g --
  averaged over the three axes, divided by g and rounded to 0.1 count (about 410
  counts per m/s^2; the jig-free calibration finds 412..415).  The norm at rest
  would not do: the offsets are several hundred counts and bias it by ~9 %.
  The calibration estimates each axis' sensitivity; the nominal only starts the
  solve and defines the axes;
- noise_mps2 = 0 (unknown): static detection then estimates it from the data.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..io.device import Device
from ..io.recording import Recording, read_recording

__all__ = ["load_xsens", "XSENS_GRAVITY", "XSENS_ZERO"]

XSENS_GRAVITY = 9.81744
XSENS_ZERO = 32768.0
COLUMNS = ("t", "raw_0", "raw_1", "raw_2")  # the file has no header: imu_tk's t, x, y, z


def load_xsens(path: Any) -> tuple[Device, Recording]:
    """Read the imu_tk accelerometer file; returns (Device, Recording).

    Parameters
    ----------
    path : str or os.PathLike
        imu_tk's text: no header, whitespace-separated ``t ax ay az`` (s, then counts;
        integral values may be written as ``3.3108000e+04``), compressed or not (told by
        the first bytes: textinput.COMPRESSIONS).

    Raises
    ------
    InputError
        Naming the file, the line and the column (t, raw_0, raw_1, raw_2) of the first bad
        cell, a row that has not 4 cells, or a time that does not increase.
    """
    rec = read_recording(path, 3, columns=list(COLUMNS))
    t, raw = rec.t, rec.raw
    lo, hi = np.percentile(raw, [1.0, 99.0], axis=0)
    scale = round(float(np.mean((hi - lo) / 2.0)) / XSENS_GRAVITY, 1)
    rate = 1.0 / float(np.median(np.diff(t)))
    device = Device(
        name="xsens-imu_tk",
        sample_rate_hz=round(rate, 3),
        gravity_mps2=XSENS_GRAVITY,
        raw_min=0,
        raw_max=65535,
        positions=np.zeros((3, 3)),
        axes=np.eye(3),
        counts_per_mps2=np.full(3, scale),
        zero_counts=np.full(3, XSENS_ZERO),
        noise_mps2=0.0,
    )
    return device, rec
