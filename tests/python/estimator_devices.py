"""Devices of the estimators' tests and benchmark (tools/bench_estimators.py imports them
from here): ADXL202E-like triads, 1250 counts per g, zero 5000, range 0..10000, 60 Hz,
0.02 m/s^2 rms noise."""
import numpy as np

from accelcal.io.device import Device

G = 9.80665


def adxl_pendulum_device(r1=0.1, r2=0.3):
    """Two ADXL202E-like triads on body x at r1 and r2 (m) from the pivot."""
    pos = np.array([[r1, 0, 0]] * 3 + [[r2, 0, 0]] * 3, float)
    return Device(name="pendulum-adxl202e", sample_rate_hz=60.0, gravity_mps2=G, raw_min=0, raw_max=10000,
                  positions=pos, axes=np.vstack([np.eye(3), np.eye(3)]),
                  counts_per_mps2=np.full(6, 1250.0 / G), zero_counts=np.full(6, 5000.0), noise_mps2=0.02)


def adxl_triad():
    """One ADXL202E-like triad at the origin."""
    return Device(name="triad-adxl202e", sample_rate_hz=60.0, gravity_mps2=G, raw_min=0, raw_max=10000,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1250.0 / G),
                  zero_counts=np.full(3, 5000.0), noise_mps2=0.02)
