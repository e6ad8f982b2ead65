"""What an entry's summary says its figure is (diagnose/text.py)."""
from __future__ import annotations

import numpy as np

from accelcal.io.calibration import Calibration
from accelcal.diagnose import diagnose
from test_diagnose_honest import six_poses, triad


def test_an_effect_left_out_of_the_model_says_its_figure_is_it_alone():
    """An offset the six faces show, with a nominal calibration: the candidates left out had
    quoted their figures as findings (on the real MPU-6050 and Xsens recordings a bend of -12.2
    and -11.7 %: each the bend alone absorbing the calibration's error).  Now the summary of
    every candidate fitted to the gap and not in the model says it is that effect alone, against
    the model before it, and no finding; the model's own effects and the converter's (read from
    the raw values) do not."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(1, bias_mps2=np.array([0.05, 0.0, -0.03]))])
    assert res["verdict"] == "offset"
    left_out = [e for e in res["effects"] if not e["selected"] and e["name"] not in ("saturation", "quantization")]
    assert {"gain", "nonlinearity"} <= {e["name"] for e in left_out}
    for e in left_out:
        assert "not in the model: this effect alone, fitted against the calibrated model" in e["summary"], e
        assert e["summary"].endswith("no finding")
    for e in res["effects"]:
        if e["selected"] or e["name"] in ("saturation", "quantization"):
            assert "not in the model" not in e["summary"], e
