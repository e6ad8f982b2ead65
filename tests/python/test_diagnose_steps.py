"""The step limit (MAX_STEPS): what it leaves out is said, not silently folded into 'unexplained'."""
from __future__ import annotations

import numpy as np
import pytest

from accelcal.calibration import Calibration
from accelcal.diagnose import MAX_STEPS, diagnose
from test_diagnose_honest import six_poses, triad


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_hand_placed_tilt_after_the_calibration_terms_is_named_as_the_next_step(seed):
    """shehab299/AVRLabs's MPU-6050 on six faces (its shape: 30 s a face, 0.013 m/s^2 of noise) against
    its nominal calibration: an offset of 0.42 m/s^2 on z, z's gain +1.7 %, z tilted 3 deg toward x,
    and each face placed by hand within 0.2 deg.  Offset, misalignment and gain are the three steps;
    the tilts are left, and had been reported only as 16 counts unexplained.  A fourth step is not
    taken (on the independent benchmark the fourth member was no effect of the data in 87 of the 91
    models it lengthened); the pose_error it would add is named, in unexplained.beyond_step_limit
    and a note."""
    assert MAX_STEPS == 3
    S = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.052, 0.0, 1.017]])
    rec = six_poses(seed, tilt_deg=0.2, sensor=S, bias_mps2=np.array([0.0, 0.0, 0.42]), hold_s=30.0, noise=0.013)
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [rec])
    assert res["model"]["effects"] == ["offset", "misalignment", "gain"]
    nxt = res["unexplained"]["beyond_step_limit"]
    assert nxt["name"] == "pose_error" and nxt["shrink"] > 0.05 and "deg" in nxt["summary"]
    assert any(n.startswith("pose_error would be step 4") for n in res["notes"])


def test_no_word_where_the_search_ends_before_the_limit():
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(1, bias_mps2=np.array([0.05, 0.0, -0.03]))])
    assert res["model"]["effects"] == ["offset"]
    assert not any("would be step" in n for n in res["notes"])
