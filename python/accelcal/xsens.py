"""The real Xsens accelerometer recording from imu_tk (shared/data/imu_tk_xsens).

File: whitespace-separated ASCII (optionally gzip), one sample a row: t [s], then
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

import gzip
import os
from typing import Any

import numpy as np

from .device import Device
from .errors import InputError
from .recording import Recording

__all__ = ["load_xsens", "XSENS_GRAVITY", "XSENS_ZERO"]

XSENS_GRAVITY = 9.81744
XSENS_ZERO = 32768.0


def load_xsens(path: Any) -> tuple[Device, Recording]:
    """Read the imu_tk accelerometer file; returns (Device, Recording)."""
    source = os.fspath(path)
    opener = gzip.open if source.endswith(".gz") else open
    try:
        with opener(source, "rt") as fh:
            data = np.loadtxt(fh, ndmin=2)
    except OSError as e:
        raise InputError(source, f"cannot read the file: {e.strerror or e}") from None
    except ValueError as e:
        raise InputError(source, f"not a whitespace-separated table of numbers: {e}") from None
    if data.shape[1] != 4:
        raise InputError(source, f"expected 4 columns (t, x, y, z), got {data.shape[1]}", row=1)
    bad = np.argwhere(~np.isfinite(data))
    if bad.size:
        raise InputError(source, "not a finite number", row=int(bad[0][0]) + 1)
    t = data[:, 0]
    raw = data[:, 1:]
    if np.any(raw != np.round(raw)):
        r = int(np.argwhere(raw != np.round(raw))[0][0])
        raise InputError(source, "raw readings must be integer counts", row=r + 1)
    dt_bad = np.flatnonzero(~(np.diff(t) > 0))
    if dt_bad.size:
        raise InputError(source, "t must be strictly increasing", row=int(dt_bad[0]) + 2)
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
    rec = Recording(t=t, raw=raw.astype(np.int64), source=source)
    return device, rec
