"""calibrate leaves out temperature coefficients its poses do not determine (issue 35's loop:
the nonlinearity + temperature offset case of tests/python/loop_cases.py, a 3-axis chip whose
calibration session had left channel z's offset tempco at +-1.4e5 counts/degC, which refine then
carried into a gain tempco the header refused)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import accelcal as ac
import loop_cases as lc
from accelcal.calibrate.checks import undetermined_tempcos


def _case(name):
    return next(c for c in lc.CASES if c.name == name)


@pytest.fixture(scope="module")
def nonlin_temp():
    return lc.build(_case("nonlinearity + temperature offset"), 11)


def test_undetermined_tempco_is_left_out_with_its_reason(nonlin_temp):
    b = nonlin_temp
    cal = ac.calibrate(b["device"], b["rec0"])
    why = cal.extra["fit"].get("temperature_dropped")
    assert why is not None and "channel 2's offset tempco" in why
    assert cal.offset_tc is None and cal.gain_tc is None
    assert any(w.startswith("temperature coefficients not fitted") for w in cal.extra["warnings"])
    # the fit without them is a calibration: offsets within the converter, gains within 10 % of the truth
    assert np.all((cal.offsets > 0) & (cal.offsets < 4095))
    s_true = np.linalg.norm(b["params"]["S"], axis=1)
    np.testing.assert_allclose(np.linalg.norm(cal.sensitivity, axis=1), s_true, rtol=0.1)
    ac.header(b["device"], cal)


def test_determined_tempcos_are_kept():
    b = lc.build(lc.Case("t", ("temperature_offset",), "adxl12", noise_mps2=0.01), 11)
    cal = ac.calibrate(b["device"], b["rec0"])
    assert "temperature_dropped" not in cal.extra["fit"]
    assert cal.offset_tc is not None and cal.gain_tc is not None


def _fit(oc_sigma, gc_sigma):
    n = len(oc_sigma)
    return SimpleNamespace(offset_tc=np.zeros(n), gain_tc=np.zeros(n), offset_tc_sigma=np.asarray(oc_sigma, float),
                           gain_tc_sigma=np.asarray(gc_sigma, float))


def test_threshold_is_one_g_and_all_the_gain_across_the_span():
    dev = ac.default_device()
    one_g = float(np.abs(dev.counts_per_mps2[0]) * dev.gravity_mps2)
    temps = np.array([20.0, 30.0])          # a 10 degC span
    N = dev.n_channels
    assert undetermined_tempcos(dev, _fit([0.99 * one_g / 10] * N, [0.099] * N), temps) is None
    why = undetermined_tempcos(dev, _fit([0.0] * (N - 1) + [1.01 * one_g / 10], [0.0] * N), temps)
    assert why is not None and f"channel {N - 1}'s offset tempco" in why
    why = undetermined_tempcos(dev, _fit([0.0] * N, [0.101] + [0.0] * (N - 1)), temps)
    assert why is not None and "channel 0's gain tempco" in why
    assert undetermined_tempcos(dev, SimpleNamespace(offset_tc=None), temps) is None
