"""The calibration's settings: methods, rank thresholds, jig accuracy default, spans."""
from __future__ import annotations




METHODS = ("offset", "gain", "full")


MIN_RCOND = 0.02           # known poses: normalised design with a smaller sv ratio cannot determine it


MIN_RCOND_JAC = 1e-4       # nonlinear fits: column-normalised Jacobian with a smaller sv ratio (well-posed
                           # pose sets give 0.03..0.3, degenerate ones 1e-5 and below)


TEMP_MIN_SPAN_C = 1.0      # fit temperature coefficients when pose temperatures span this much


ROTATION_MIN_RADPS = 0.05  # samples with |w| above this count as rotating (lever-arm data)


POSITION_TOL_M = 1e-3      # a lever-arm direction is "observable" when its 1-sigma is below this


JIG_ACCURACY_DEG = 0.0     # stated jig accuracy of known poses (rms rotation angle of a pose error, deg):
                           # 0 = the references are exact (ordinary weighted least squares); > 0: the
                           # references are priors of that accuracy (module notes)


JIG_HINT_CHI2 = 4.0        # known poses with jig accuracy 0: above this chi2/dof, report the jig accuracy
                           # that would explain the scatter (chi2/dof = 1); the CLI prints it as a warning


CANDIDATES = (
    ("-z", (0.0, 0.0, -1.0)), ("+z", (0.0, 0.0, 1.0)),
    ("+x", (1.0, 0.0, 0.0)), ("-x", (-1.0, 0.0, 0.0)),
    ("+y", (0.0, 1.0, 0.0)), ("-y", (0.0, -1.0, 0.0)),
)
