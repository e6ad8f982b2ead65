"""The steps: the step limit (MAX_STEPS) and what it leaves out is said, not silently folded into
'unexplained'; the chosen effects' entries quote the model's (re-linearised) parameters."""
from __future__ import annotations

import numpy as np
import pytest

from accelcal.io.calibration import Calibration
from accelcal.diagnose import MAX_STEPS, diagnose
from accelcal.io.recording import recording_from_arrays
from accelcal.report import summary_text
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


def test_chosen_effects_quote_the_relinearised_parameters():
    """Jig-free, 24 poses of a triad whose gains are 1.2 / -0.8 / 1.8 % and offsets 40 / -25 / 60
    counts off the calibration given: the stepwise fit about that calibration takes part of the
    gain into the poses' forces (+1.04 / -0.67 / +2.19 %, offsets 32 / -18 / 31 counts).  The real
    Xsens recording against its nominal calibration: +0.22 / +0.48 / +0.67 % quoted in the gain's
    entry, its summary and the report, +1.06 / +0.50 / +1.10 % in the model.  The entries quote
    the model's re-linearised values; the stepwise fit is kept as params_stepwise."""
    d = triad()
    k = float(d.counts_per_mps2[0])
    rng = np.random.default_rng(0)
    gain, bias = np.array([0.012, -0.008, 0.018]), np.array([40.0, -25.0, 60.0])
    u = rng.normal(size=(24, 3))
    u /= np.linalg.norm(u, axis=1)[:, None]
    n1 = 300
    t = np.concatenate([p * 5.0 + np.arange(n1) / d.sample_rate_hz for p in range(24)])
    raw = np.vstack([np.round((1 + gain) * k * d.gravity_mps2 * up + bias + rng.normal(0, 2.0, (n1, 3)))
                     for up in u]).astype(np.int64)
    rec = recording_from_arrays(t, raw, pose=np.repeat(np.arange(24), n1))
    res = diagnose(d, Calibration.nominal(d), [rec])
    assert res["mode"] == "jigfree" and set(res["model"]["effects"]) == {"offset", "gain"}
    assert res["model"]["relinearised"] is not None
    entries = {e["name"]: e for e in res["effects"] if e["selected"]}
    scale = np.asarray(entries["gain"]["params"]["scale"])
    assert np.max(np.abs(scale - gain)) < 1e-4                               # 0.01 % of gain
    assert np.max(np.abs(np.asarray(entries["offset"]["params"]["db"]) - bias)) < 0.5    # counts
    for nm, e in entries.items():
        assert e["params"] == res["model"]["params"][nm]
        assert e["params_sigma"] == res["model"]["params_sigma"][nm]
    # the stepwise fit did differ here (the case is one where re-linearising matters)
    assert np.max(np.abs(np.asarray(entries["gain"]["params_stepwise"]["scale"]) - gain)) > 2e-3
    assert "+1.8 " in entries["gain"]["summary"]
    step = [ln for ln in summary_text(res).splitlines() if ln.startswith("- step") and "**gain**" in ln][0]
    assert "+1.8 " in step
