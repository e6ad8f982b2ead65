"""accelcal: calibration, 6-DOF resolution and sim-to-real diagnosis for
accelerometer-only motion sensors.

The C core (integer-only firmware library) is reached through
``accelcal.native``; everything else here is float64 host code.
"""

__version__ = "0.1.0"
