"""What calibrate's summary and warnings say of the fit's residual and scatter (cli_calibrate.py)."""
from __future__ import annotations

import numpy as np

from accelcal.calibrate import calibrate_recordings
from accelcal.cli.calibrate_command import calibrate_warnings, calibration_summary
from accelcal.io.recording import recording_from_arrays
from test_diagnose_honest import G, K, imucal_ferraris, triad


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
    cal0 = calibrate_recordings(dev, [rec], "full", jig_accuracy_deg=0.0)
    assert "dof_readings" not in cal0.extra["fit"]
    assert "by construction" not in calibration_summary(cal0, 1, "cal.json")


def test_a_table_of_pose_means_is_not_judged_against_a_noise_it_does_not_give():
    """Six pose means, one row each (t counts rows at 1 Hz), scattered by 15 mg about the fit:
    calibrate had warned that the poses scatter "far beyond their noise" (chi2/dof ~1e7) and of
    "few or short poses (... 1 samples, 1 s, each)".  With one row a pose the noise is unknown:
    the warning says that, and the poses' number without durations."""
    rng = np.random.default_rng(1)
    u = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    m = u * G * np.array([1.002, 0.997, 1.004]) + np.array([0.03, -0.07, 0.02]) + 0.15 * rng.standard_normal((6, 3))
    rec = recording_from_arrays(np.arange(6.0), np.round(m * K).astype(np.int64), f=u * G, pose=np.arange(6))
    dev = triad()
    cal = calibrate_recordings(dev, [rec], "full")
    said = " | ".join(calibrate_warnings(dev, cal))
    assert "far beyond their noise" not in said, said
    assert "each pose is one row (a file of pose means): the poses' noise is unknown" in said, said
    assert "few poses (6 poses, one row each" in said and " s, each)" not in said, said
    assert "hold each longer" not in said, said
