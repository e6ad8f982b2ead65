"""What calibrate's summary and warnings say of the fit's residual and scatter (cli_calibrate.py)."""
from __future__ import annotations

from accelcal.calibrate import calibrate_recordings
from accelcal.cli_calibrate import calibration_summary
from test_diagnose_honest import imucal_ferraris


def test_six_poses_with_their_directions_fitted_have_no_residual_to_judge(shared_data):
    """imucal's six-pose session with --jig-accuracy 0.5: the poses' directions are fitted too
    (18 readings against 12 terms and 12 angles), so the readings' residual is ~0 by
    construction; the summary had read "Residual rms 0.000877 counts", a perfect fit.  It now
    says so, and that the dof are the pose priors'."""
    dev, rec = imucal_ferraris(shared_data / "imucal")
    cal = calibrate_recordings(dev, [rec], "full", jig_accuracy_deg=0.5)
    assert cal.extra["fit"]["dof_readings"] == 18 - 24
    text = calibration_summary(cal, 1, "cal.json")
    assert ("near zero by construction, as the pose directions are fitted too (6 poses x 3 readings against 12 "
            "terms and the poses' 12 angles), so it cannot judge the fit here") in text, text
    assert "(6 dof, all of them the pose priors'" in text, text
    # with the references exact the readings keep their dof: said as before
    cal0 = calibrate_recordings(dev, [rec], "full")
    assert "dof_readings" not in cal0.extra["fit"]
    assert "by construction" not in calibration_summary(cal0, 1, "cal.json")
