"""A parameter the data do not determine gets no 1-sigma (diagnose/determined.py)."""
from __future__ import annotations

import numpy as np
import pytest

from accelcal.calibration import Calibration
from accelcal.diagnose import diagnose
from test_diagnose_honest import _one_orientation, six_poses, triad


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_gains_of_axes_that_never_see_gravity_have_no_sigma(seed):
    """A foot-worn triad in one orientation (z up within 4 deg), jig-free: the data see |f| alone,
    so the x and y gains are not measured.  Their figures are the smallest change that fits; the
    sigma had been read off the covariance of the combination the data fix (-2.705 +- 0.017 % on
    x and y alike, z's figure).  Now: null sigma, named in not_determined, said in the summary;
    z's gain keeps its sigma."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [_one_orientation(seed)])
    gain = next(e for e in res["effects"] if e["name"] == "gain")
    nd = gain["not_determined"]["scale"]
    assert nd and 2 not in nd
    assert all(gain["params_sigma"]["scale"][i] is None for i in nd)
    assert isinstance(gain["params_sigma"]["scale"][2], float) and gain["params_sigma"]["scale"][2] > 0
    assert "not determined by these data" in gain["summary"] and "+- nan" not in gain["summary"]
    if gain["selected"]:
        assert all(res["model"]["params_sigma"]["gain"]["scale"][i] is None for i in nd)


def test_parameters_the_poses_fix_keep_their_sigma():
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(1, bias_mps2=np.array([0.05, 0.0, -0.03]))])
    assert res["verdict"] == "offset"
    assert all("not_determined" not in e for e in res["effects"])
    assert all(isinstance(s, float) for s in res["model"]["params_sigma"]["offset"]["db"])
