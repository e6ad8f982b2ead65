"""Settings of the effects' fits (grids, thresholds), documented defaults."""
from __future__ import annotations

import numpy as np

BLOCK_S = 2.0              # longest cross-validation block in a moving segment (s)
ROTATING_RADPS = 0.05      # |w| above this counts as rotating (regimes, position_error)
TEMP_MIN_SPAN_C = 1.0      # temperature candidates need this span of temp_c
TEMP_TIME_BINS = 20        # temp_c follows time when the medians of this many stretches of time ...
TEMP_MONOTONE = 0.9        # ... go one way: their net change at least this share of their total variation
T_LAG_GRID_S = (0.0, 10.0, 30.0, 60.0, 120.0, 300.0)   # thermal lags (s) the temperature fits try
T_LAG_MAX_SPANS = 2.0   # ... up to this many times the span of the samples the diagnosis uses
#: the thermal lag is a finding only where the data pin it: the lags whose profile objective, beside each
#: recording's own level of the change, lies within T_LAG_CRIT_CHI2 (the 95 % point of chi2 with one
#: degree of freedom, 3.84; times the residual's excess over the floor and the poses' design effect) of
#: the best form an interval that holds the fitted lag, excludes 0 and ends within T_LAG_INSIDE x the
#: longest recording (one recording with samples; its level is not left free there); else the nested form
#: (no lag) is fitted and reported
T_LAG_CRIT_CHI2 = 3.84
#: a bend's cube and a drift's path through knots are shapes beyond a nested form (the square; the ramp):
#: the chi2 their extra parameters gain must pass this point of chi2 (effects.fitting.shape_pinned)
SHAPE_LEVEL = 0.95
T_LAG_INSIDE = 1.0
#: ... where two recordings or more have samples, the profile leaves each recording's level free and the
#: interval may end within T_LAG_INSIDE_FREE x the longest recording (the lags the search reaches,
#: T_LAG_MAX_SPANS): beside free levels only the shape of the change within the recordings pins the lag,
#: so an interval that closes is a finding even where the lag exceeds the recording (a 100 s lag in a
#: 79 s session: 92-124 s); a shift between recordings leaves the profile flat towards long lags
#: (interval to inf: not determined).  With one recording its level is part of what pins the lag, and a
#: constant offset change can mimic it: the interval must end within the recording
T_LAG_INSIDE_FREE = 2.0
T_LAG_BISECT = 4            # ... its ends refined by this many bisections of a step of 2 (to 2^(1/16))
T_REF_SPANS = 2.0          # a fitted reference temperature stays within this many spans of temp_c
MISALIGN_MAX_RAD = 0.35     # relinearised misalignment fits stay below ~20 deg
POSITION_TOL_M = 1e-3      # position_error reports dr along directions with 1-sigma below this
QUANT_STRONG_FRAC = 0.999  # ... and to take the lattice alone as proof (with QUANT_STRONG_VALUES)
QUANT_STRONG_VALUES = 20   # distinct lattice values needed for the proof (chance <= 2^-19)
QUANT_RELEVANT = 0.25      # a lattice counts when step/sqrt(12) >= this x the channel's noise floor


# noise before the quantiser, as a fraction of the step, tried for each quantised channel
QUANT_DITHER_GRID = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4)
SAT_PROOF_COUNT = 10       # readings at one extreme value, the model >= 5 sigma beyond: proof of a clip
BACKFIT_PASSES = 3
DRIFT_KNOT_FRACTIONS = (1 / 2, 1 / 4, 1 / 8, 1 / 16)  # bias_drift paths: knot spacing / time span
DRIFT_MIN_BLOCKS = 2       # ... each knot interval at least this many CV blocks long
SKEW_GRID = np.array([0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 12.0])
SKEW_GRID = np.concatenate([-SKEW_GRID[:0:-1], SKEW_GRID])          # in samples
DELAY_GRID = np.array([0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0])  # samples
SEARCH_GROW = 1.5          # a minimum at a grid's end: the grid grows by this factor per point ...
SEARCH_MAX_S = 1.0         # ... up to this skew or low-pass delay (s)
PENALTY_PER_PARAM = 2.0    # chi2 units per parameter an effect adds (AIC-like)
REPEAT_DEG = 5.0           # two static poses within this angle are one orientation, repeated ...
REPEAT_MIN_S = 2.0         # ... when their mid-times are at least this far apart (s)
REPEAT_SAME_DEG = 1.0      # a repeat whose readings are compared as those of one orientation: within this
                           # angle (an effect of the orientation, a 3 % cube, changes by < 0.2 % of g there)
AXIS_POSE_DEG = 10.0       # a stated pose within this angle of a channel's axis is a face pose (poses_on_axes)
#: jig-free fits: a combination of parameters of which the poses' projection leaves less than
#: this share of its change of the readings (energy) is not determined by the data; the min-norm
#: solve gives it nothing (the smallest change of the readings that fits)
SEEN_MIN = 1e-3
