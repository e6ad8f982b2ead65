"""Changes between recordings (issue 33, item 1): an offset or a gain that moved between the
calibration's session and the diagnosed one is named as such (``session_offset``,
``session_gain``), not as a temperature effect through a lag longer than the recording; a
temperature effect is still named where the temperature explains change within a recording.

The data come from the independent generator (tests/python/indep_model.py: make_sessions),
the calibration from ``accelcal.api.calibrate`` on the calibration's session, as a user does.
"""
from __future__ import annotations

import numpy as np
import pytest

import indep_model as im
from accelcal.api import calibrate
from accelcal.diagnose import diagnose
from accelcal.effects import EFFECTS
from accelcal.simulate import run_simulation
from accelcal.io.device import default_triad


def _run(kind, seed, temperature="varying", own_cal=True, **kw):
    ds = im.make_sessions(kind, seed, temperature=temperature, **kw)
    cal = calibrate(ds["device"], ds["recordings"][:1]) if own_cal else ds["cal"]
    return ds, diagnose(ds["device"], cal, ds["recordings"], seed=seed)


def test_offset_shift_between_sessions_is_named_not_a_temperature_lag():
    """The issue's case: poses at a constant 25 degC calibrated; a recording of motion at 18-42 degC
    with every channel's offset higher, constant in time.  Old code: temperature_offset with a lag
    of 237 s (4.6 x the recording), ambiguous_with empty."""
    ds, res = _run("session_offset", 2, device="adxl12", rate=50.0)
    assert res["verdict"] == "session_offset"
    assert "temperature_offset" in res["ambiguous_with"]
    assert "calibration's temperature" in res["separate_by"]
    db = np.asarray(res["model"]["params"]["session_offset"]["db"], float)
    sd = np.asarray(res["model"]["params_sigma"]["session_offset"]["db"], float)
    assert db.shape == (2, ds["device"].n_channels)
    true = ds["effects"]["offset"]["delta"]
    # the calibration's session read ~0, the diagnosed one its shift (within 5 sigma + a count of rounding)
    assert np.all(np.abs(db[0]) <= 5 * sd[0] + 1.0)
    assert np.all(np.abs(db[1] - true) <= 5 * sd[1] + 1.0 + 0.05 * np.abs(true))
    ent = res["effects"][0]
    assert ent["name"] == "session_offset" and "changed between recordings by" in ent["summary"]
    assert "temperature_offset" not in res["model"]["effects"] and "offset" not in res["model"]["effects"]


def test_gain_shift_between_sessions_is_named():
    """Old code: temperature_gain (lag 304 s on seed 1's 50 s session)."""
    ds, res = _run("session_gain", 1, device="adxl12", rate=50.0)
    assert res["verdict"] == "session_gain"
    assert "temperature_gain" in res["ambiguous_with"]
    sc = np.asarray(res["model"]["params"]["session_gain"]["scale"], float)
    true = ds["effects"]["gain"]["delta"]
    assert np.allclose(sc[1], true, rtol=0.1, atol=2e-4)
    assert np.all(np.abs(sc[0]) < 2e-4)


def test_shift_at_a_constant_other_temperature_is_named_with_the_temperature_stated():
    """At a constant temperature other than the calibration's, a tempco and a shift are the same
    change: the shift is named and the temperature effect stated beside it (old code: the
    temperature effect alone, with fewer parameters)."""
    ds, res = _run("session_offset", 1, temperature="constant", own_cal=False, device="adxl12", rate=50.0)
    assert res["verdict"] == "session_offset"
    assert "temperature_offset" in res["ambiguous_with"]


def test_shift_beside_a_time_skew():
    """time skew + offset: old code named temperature_offset + time_skew."""
    ds, res = _run("time_skew+session_offset", 1, own_cal=False, device="adxl12", rate=100.0)
    assert {"time_skew", "session_offset"} <= set(res["model"]["effects"])
    assert not any(e.startswith("temperature") for e in res["model"]["effects"])


def test_true_temperature_effect_with_a_varying_temperature_is_still_named():
    """A true thermal offset (lag 61 s in a 67 s session) is never hidden behind a shift: where its
    lag is pinned it is the verdict and stays significant after the shift; where the lag's interval
    runs past the recording (diagnose/shapes.py) it is stated in ambiguous_with, with what
    recording would pin it, and no lag is quoted as a finding."""
    ds, res = _run("temperature_offset", 3, own_cal=False)
    if res["verdict"] == "temperature_offset":
        # the temperature explains change within the session beyond one shift per recording
        after = res["effects"][0]["contest"]["rivals"]["session_offset"]["verdict_after_rival"]
        assert after["significant"]
        assert "session_offset" not in res["ambiguous_with"]
    else:
        assert "temperature_offset" in res["ambiguous_with"]
        assert "temperature changes slowly" in res["separate_by"]
        assert res["verdict"] != "session_offset"
    for e in res["effects"]:
        shape = e.get("shape") or {}
        if e["name"].startswith("temperature") and "tau_s" in shape and e["name"] in res["model"]["effects"]:
            assert shape["tau_s"].get("determined"), "a lag the data do not pin quoted as a finding"


@pytest.mark.parametrize("seed", [233440, 233441])
def test_a_thermal_lag_longer_than_the_session_is_pinned_beside_the_shift(seed):
    """A true thermal offset through a lag of 100-105 s in a session of 75-79 s.  The old code
    judged the lag's interval on the levels too and required it to end inside the recording: the
    lag was "not determined", the lag-free form explained nothing, ``session_offset`` took the
    level and a temperature term refitted on what it left quoted 28 s (interval 27-29 s) as a
    finding.  Judged beside each recording's own level, the change within the session pins the
    lag: the verdict is the temperature offset, with an interval that holds the true lag."""
    ds, res = _run("temperature_offset", seed, own_cal=False)
    true_tau = float(ds["effects"]["temperature_offset"]["tau_s"])
    span = max(float(r["duration_s"]) for r in res["recordings"])
    assert true_tau > span                      # the case: a lag longer than the session
    assert res["verdict"] == "temperature_offset"
    sh = res["effects"][0]["shape"]["tau_s"]
    assert sh["determined"]
    lo, hi = sh["interval_s"]
    assert lo <= true_tau <= hi, (lo, hi, true_tau)
    assert lo <= float(res["model"]["params"]["temperature_offset"]["tau_s"]) <= hi


@pytest.mark.parametrize("seed", [412681, 412682, 412683])
def test_a_drift_while_the_temperature_only_rises_is_stated_beside_the_temperature(seed):
    """A gain shift and a random-walk drift in a session whose temperature rises from 18 to 42 degC
    (the calibration's session at a constant 25 degC beside it): the temperature through its lag
    follows the drift's trend, and the data cannot say which it is.  The old code judged "the
    temperature follows time" over both recordings together, where the calibration's constant
    25 degC broke the rise, and named temperature_offset with the drift in neither the verdict nor
    ambiguous_with (seeds 412681 and 412683 had it only as the model's second member, 412682 nowhere).
    Now the drift is the verdict, in ambiguous_with, or the temperature effect is not named."""
    ds, res = _run("session_gain+bias_drift", seed, own_cal=False)
    named_temp = res["verdict"].startswith("temperature")
    assert not named_temp or "bias_drift" in res["ambiguous_with"], (res["verdict"], res["ambiguous_with"])


def test_an_offset_of_every_recording_stays_an_offset():
    """One shift for all recordings (a jig recording given in two parts): the plain offset, fewer
    parameters, is the verdict; session_offset adds nothing after it."""
    ds = im.make_jig(["offset"], 5, device="adxl12", rate=50.0, temperature=False, motion=False)
    rec = ds["recording"]
    half = rec.n_samples // 2
    recs = [rec.select(np.arange(half)), rec.select(np.arange(half, rec.n_samples))]
    res = diagnose(ds["device"], ds["cal"], recs, seed=5)
    assert res["verdict"] == "offset"
    assert "session_offset" not in res["model"]["effects"]


def test_one_recording_skips_the_shift():
    ds = im.make_jig(["offset"], 6, device="adxl12", rate=50.0, temperature=False, motion=False)
    res = diagnose(ds["device"], ds["cal"], ds["recordings"], seed=6)
    skipped = {s["name"]: s["reason"] for s in res["skipped"]}
    assert "two recordings" in skipped["session_offset"] and "session_gain" in skipped
    assert res["verdict"] == "offset"


@pytest.mark.parametrize("name, spec, key", [("session_offset", "session_offset:db=[5,-3,2]", "db"),
                                              ("session_gain", "session_gain:scale=0.01", "scale")])
def test_simulate_accepts_the_shift(name, spec, key):
    """The simulator takes the effect as the simulated recording's change against the calibration."""
    dev = default_triad()
    base = run_simulation(dev, "static_poses", seed=3)
    sim = run_simulation(dev, "static_poses", seed=3, effects=[spec])
    d = sim.clean_counts - base.clean_counts
    v = np.asarray(sim.effects[name][key], float)
    assert v.shape == (1, dev.n_channels)
    if name == "session_offset":
        assert np.allclose(d, [5.0, -3.0, 2.0])
    else:
        assert np.allclose(d, 0.01 * (base.clean_counts - base.base_state.offsets[None, :]), atol=1e-6)
    assert EFFECTS[name].summary
