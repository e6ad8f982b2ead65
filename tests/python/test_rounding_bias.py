"""The ADC's own rounding in the diagnosis's base model (diagnose/prepare.rounding_bias):
under noise well below a count every rest sits on one or two codes, and the prediction
must hold the bias that rounding leaves per pose, or a clean recording is given an effect."""
from __future__ import annotations

import importlib

import numpy as np
import pytest

import indep_model as im
from accelcal.diagnose import diagnose

prepare = importlib.import_module("accelcal.diagnose.prepare")


def _rest_errors(rng, sigma: float, m: int) -> tuple[float, float]:
    """40 rests of m samples at random fractional levels x, read as round(x + n) with
    n ~ N(0, sigma^2), predicted as x: the rms over rests and channels of each rest's mean
    error without and with the rounding bias."""
    rests, raw, pred = [], [], []
    for k in range(40):
        x = rng.uniform(-50, 50, size=3)
        raw.append(np.round(x + rng.normal(scale=sigma, size=(m, 3))))
        pred.append(np.broadcast_to(x, (m, 3)))
        rests.append((m * k, m * (k + 1)))
    raw, pred = np.concatenate(raw), np.concatenate(pred)
    bias = prepare.rounding_bias(raw, pred, rests)
    before = np.array([np.mean(raw[a:b] - pred[a:b], axis=0) for a, b in rests])
    after = np.array([np.mean(raw[a:b] - pred[a:b] - bias[a:b], axis=0) for a, b in rests])
    return float(np.sqrt(np.mean(before ** 2))), float(np.sqrt(np.mean(after ** 2)))


@pytest.mark.parametrize("sigma", [0.0, 0.05, 0.15])
def test_the_bias_of_each_rest_is_predicted(sigma):
    """Rests at random fractional levels, read through round(x + n): the rounding bias
    takes out most of each rest's mean error (the sawtooth of a noise-free reading, its
    smoothed form under a dither).  At 0.3 counts of noise the bias (0.05 rms) is the size
    of a 200-sample mean's own scatter: test_a_larger_dither_is_not_made_worse."""
    before, after = _rest_errors(np.random.default_rng(4), sigma, 200)
    assert after < 0.35 * before


def test_a_larger_dither_is_not_made_worse():
    before, after = _rest_errors(np.random.default_rng(6), 0.3, 2000)
    assert after < before


def test_noisy_channels_are_left_alone():
    rng = np.random.default_rng(5)
    x = rng.uniform(-50, 50, size=(1, 3))
    raw = np.round(x + rng.normal(scale=2.0, size=(500, 3)))
    pred = np.broadcast_to(x, raw.shape).copy()
    assert not np.any(prepare.rounding_bias(raw, pred, [(0, 500)]))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_clean_sub_count_noise_jig_recordings_are_none(seed):
    """The independent model's 12-bit device at 0.004 m/s^2 of noise (about 0.1 count) on
    its jig: without the rounding bias all of these were named pose_error.  (Jig-free, the
    pose forces are fitted to the rounded means, and clean hand-held sessions of this device
    can still get an effect with a shrink below 0.01: README, not done.)"""
    ds = im.make_jig([], seed, device="adxl12", noise=0.004)
    res = diagnose(ds["device"], ds["cal"], ds["recordings"], seed=seed)
    assert res["verdict"] == "none", [(e["name"], round(e["shrink"], 3)) for e in res["effects"][:3]]
