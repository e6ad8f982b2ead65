"""The calibration's settings: methods, rank thresholds, jig accuracy default, spans."""
from __future__ import annotations

import numpy as np

METHODS = ("offset", "gain", "full")


#: the jig-free fit's channel model: ``auto`` is ``full``, else the first of ``gain``, ``offset`` the
#: poses determine (and that converges), with the reason in the calibration's ``extra["fit"]["fallback"]``
JIGFREE_MODELS = ("auto", "full", "gain", "offset")


MIN_RCOND = 0.02           # known poses: normalised design with a smaller sv ratio cannot determine it


STRUCTURED_MIN_POSES = 100  # jig-free fits of this many poses or more solve with a sparse Jacobian and take
                            # their covariance by eliminating each pose (O(P), the dense forms O(P^3))


MIN_RCOND_JAC = 1e-4       # nonlinear fits: column-normalised Jacobian with a smaller sv ratio (well-posed
                           # pose sets give 0.03..0.3, degenerate ones 1e-5 and below)


TEMP_MIN_SPAN_C = 1.0      # fit temperature coefficients when pose temperatures span this much


#: a temperature coefficient is undetermined when its 1-sigma, across the poses' temperature span, moves
#: the reading by more than the channel's 1 g (offset tempco) or its gain by more than 100 % (gain
#: tempco): the data do not tell it from a term as large as the signal itself
TEMP_UNDETERMINED_G = 1.0
TEMP_UNDETERMINED_GAIN = 1.0


ROTATION_MIN_RADPS = 0.05  # samples with |w| above this count as rotating (lever-arm data)


POSITION_TOL_M = 1e-3      # a lever-arm direction is "observable" when its 1-sigma is below this


JIG_ACCURACY_DEG = 0.0     # stated jig accuracy of known poses (rms rotation angle of a pose error, deg):
                           # 0 = the references are exact (ordinary weighted least squares); > 0: the
                           # references are priors of that accuracy (module notes).  The default of the
                           # fits that take it stated (fit_known_poses, fit_static)


JIG_ACCURACY_AUTO = "auto"  # the default of calibrate_recordings (and of the command's --jig-accuracy): the jig
                            # accuracy estimated from the poses' scatter about the fit (jig_estimate.py)


JIG_HINT_CHI2 = 4.0        # known poses with jig accuracy 0: above this chi2/dof, report the jig accuracy
                           # that would explain the scatter (chi2/dof = 1); the CLI prints it as a warning


SCATTER_CHI2 = 4.0         # above this chi2/dof the poses scatter beyond their noise (warned of): the
                           # sigmas, scaled up by sqrt(chi2/dof), are then the scatter's, which longer
                           # poses do not shrink


CANDIDATES = (
    ("-z", (0.0, 0.0, -1.0)), ("+z", (0.0, 0.0, 1.0)),
    ("+x", (1.0, 0.0, 0.0)), ("-x", (-1.0, 0.0, 0.0)),
    ("+y", (0.0, 1.0, 0.0)), ("-y", (0.0, -1.0, 0.0)),
)
#: beyond the axes, the tilted directions a pose to add may take (edges of a cube, then corners)
TILTED = tuple((f"{a}{b} (45 deg between {a} and {b})",
                tuple(float(v) for v in (np.asarray(da) + np.asarray(db)) / np.sqrt(2.0)))
               for i, (a, da) in enumerate(CANDIDATES) for (b, db) in CANDIDATES[i + 1:]
               if abs(float(np.dot(da, db))) < 0.5) + \
    tuple((f"{x}{y}{z} (a corner: equally along x, y and z)", tuple(float(v) / np.sqrt(3.0) for v in (sx, sy, sz)))
          for x, sx in (("+x", 1.0), ("-x", -1.0)) for y, sy in (("+y", 1.0), ("-y", -1.0))
          for z, sz in (("+z", 1.0), ("-z", -1.0)))
#: a pose to add is a tilted one when every axis direction has a pose within this (deg)
TILTED_AFTER_DEG = 20.0
#: a channel whose axis the poses turn through less f than this (in g; +-x, +-y, +-z: 2 g) hardly turns
#: (named as the cause where its parameters are poorly determined; without their sigmas, warned of alone)
EXCITATION_MIN_SPAN_G = 1.0
#: a fitted parameter is poorly determined (warned of, whatever the poses' span) when its 1-sigma, as the
#: error it makes in a reading of 1 g, is above this (mg): the offset's sigma itself, the gain's relative
#: sigma times 1 g (5 mg: 0.5 % of gain).  A calibration is burnt into firmware to replace the chip's
#: untrimmed tolerances, a zero-g offset of +-40..80 mg and a sensitivity of +-1..3 % for consumer MEMS
#: (MPU-6050: +-50 mg x/y, +-80 mg z, +-3 %); a tenth of +-50 mg is 5 mg, a level reading's tilt of
#: 0.29 deg (1 mg = 0.057 deg), 25 mm of drift after 1 s of integration.  Beyond it the fit tells the
#: chip's own offset and gain little better than its datasheet does (the real recordings the tests
#: calibrate: offsets within 0.03..2.9 mg, gains 0.003..0.44 %; an Empatica E4's 26 wrist poses: 8..24 mg,
#: 0.7..2 %)
POORLY_DETERMINED_MG = 5.0

#: a chip's sensitivity is within this fraction of its datasheet's nominal (the loosest: an ADXL345's
#: 230-282 LSB/g about 256, an ADXL335's 270-330 mV/g about 300; an MPU-6050's initial tolerance is
#: +-3 %): a fitted gain beyond it by more than 3 of its 1-sigma, yet within the wrong-scale factor
#: (device.NOMINAL_FACTOR), is warned of: the device file's counts_per_mps2 is not this chip's (another
#: range, a ratiometric sensor at another supply), or the chip is out of its specification
CHIP_GAIN_TOLERANCE = 0.10

#: where a "too few poses" error's advice to add poses begins: calibrate_recordings leaves it out
#: where the shortage is the static detector's (a file of pose means, one row a pose)
ADD_POSES = "; add poses"
