"""The diagnosis's documented defaults (significance, penalty, steps)."""
from __future__ import annotations

from ..effects.settings import PENALTY_PER_PARAM  # one home: the effects\' fits use it too
FORMAT = "accelcal-diagnosis/1"
T_MIN = 4.0                # block t statistic a candidate's held-out gain must reach, or
Z_MIN = 6.0                # ... its held-out chi2 gain in units of its null spread
MIN_SHRINK = 0.005         # a significant effect removes at least this fraction of the gap
MAX_STEPS = 3              # effects found stepwise at most
MIN_NOISE_DOF = 30         # static samples needed for the static noise-floor estimate
TERMS_PASSES = 20          # backfitting passes of the calibration's terms that a bend must beat (they are correlated)

POSE_MEAN_NOTE_RATIO = 2.0  # verdict none: a note when the poses' means scatter beyond this x their noise

__all__ = ["FORMAT", "T_MIN", "Z_MIN", "PENALTY_PER_PARAM", "MIN_SHRINK", "MAX_STEPS", "MIN_NOISE_DOF", "TERMS_PASSES",
           "POSE_MEAN_NOTE_RATIO"]
