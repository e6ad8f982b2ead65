"""The ADC's own rounding in the diagnosis's base model (diagnose/prepare.rounding_bias):
under noise well below a count every rest sits on one or two codes, and the prediction
must hold the bias that rounding leaves per pose, or a clean recording is given an effect."""
from __future__ import annotations

import importlib

import numpy as np
import pytest

import indep_model as im
from accelcal.calibrate import calibrate_recordings
from accelcal.io.device import Device
from accelcal.diagnose import diagnose
from accelcal.io.recording import recording_from_arrays

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


def _ten_bit_session(seed: int, labelled: bool, *, counts_per_g: float = 256, noise_counts: float = 0.05,
                     step: int = 1, bits: int = 10):
    """A 10-bit triad (256 counts/g, offsets 4.6 / -3.1 / 7.7 counts, gains and axes off by a few
    0.1 %) through 26 face, edge and corner poses of 3 s at 50 Hz with 1.5 s turns between
    them, 0.002 m/s^2 of noise (0.05 counts: each pose sits on one code); the jig states f,
    the hand-held session does not.  Other chips: ``counts_per_g``, ``bits``, ``noise_counts``
    and the readings' code ``step``."""
    g, rate = 9.80665, 50.0
    k = counts_per_g / g
    lo, hi = -2 ** (bits - 1), 2 ** (bits - 1) - 1
    dev = Device(name="triad", sample_rate_hz=rate, gravity_mps2=g, raw_min=lo, raw_max=hi,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, k), zero_counts=np.zeros(3))
    rng = np.random.default_rng(seed)
    # the 6 faces, the 12 edges, the 8 corners
    ups = [sgn * np.eye(3)[a] for a in range(3) for sgn in (1, -1)]
    ups += [(si * np.eye(3)[i] + sj * np.eye(3)[j]) / np.sqrt(2) for i in range(3) for j in range(i + 1, 3)
            for si in (1, -1) for sj in (1, -1)]
    ups += [np.array([sx, sy, sz]) / np.sqrt(3) for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)]
    ups = np.array(ups)
    S = k * (np.diag([1.01, 0.995, 1.02]) + np.array([[0, 0.002, -0.001], [0.001, 0, 0.003], [-0.002, 0.001, 0]]))
    fs, pose = [], []
    for p, u in enumerate(ups):
        if p:
            s = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, 77)[1:-1])
            v = ups[p - 1][None, :] * (1 - s)[:, None] + u[None, :] * s[:, None]
            fs.append(g * v / np.linalg.norm(v, axis=1)[:, None] + rng.normal(0, 0.3, v.shape))
            pose.append(np.full(75, -1))
        fs.append(np.tile(g * u, (150, 1)))
        pose.append(np.full(150, p))
    f, pose = np.concatenate(fs), np.concatenate(pose)
    x = f @ S.T + np.array([4.6, -3.1, 7.7])
    raw = np.clip(step * np.round((x + rng.normal(0, noise_counts, x.shape)) / step), lo, hi).astype(np.int64)
    t = np.arange(len(f)) / rate
    if labelled:
        return dev, recording_from_arrays(t, raw, f=np.where(pose[:, None] >= 0, f, np.nan), pose=pose)
    return dev, recording_from_arrays(t, raw)


@pytest.mark.parametrize("labelled", [True, False])
@pytest.mark.parametrize("seed", [3, 4])
def test_a_ten_bit_chip_whose_poses_sit_on_one_code_is_none(seed, labelled):
    """Each pose's mean is off by its rounding (up to half a code), the same in all its samples
    and so in every fold: fitted on the training folds, kept on the held-out ones.  Had been
    gain + pose_error + nonlinearity (shrink 0.074) on the jig and bias_drift + nonlinearity
    (0.03) hand-held, each with its own calibration; the poses' design effect
    (diagnose.floor.pose_design_effect) and the rounding's part of the noise left say none."""
    dev, rec = _ten_bit_session(seed, labelled)
    cal = calibrate_recordings(dev, [rec], "full" if labelled else "jigfree")
    res = diagnose(dev, cal, [rec])
    assert res["verdict"] == "none", [(e["name"], round(e["shrink"], 3)) for e in res["effects"][:3]]
    assert res["unexplained"] is None


@pytest.mark.parametrize("seed", [0, 1])
def test_coarse_steps_that_do_not_dither_are_named_over_a_tilt_of_each_pose(seed):
    """A 16-bit triad read in steps of 64 counts with 0.3 counts of noise (each pose on one code),
    its jig's f stated exactly and its own calibration: pose_error had been the verdict (shrink
    0.73) ahead of quantization, which was not even listed as ambiguous; each pose's rounding to
    the steps is what a tilt of each pose took."""
    dev, rec = _ten_bit_session(seed, True, counts_per_g=16384, noise_counts=0.3, step=64, bits=16)
    res = diagnose(dev, calibrate_recordings(dev, [rec], "full"), [rec])
    assert res["verdict"] == "quantization", (res["verdict"], res["model"]["effects"], res["ambiguous_with"])
    assert "pose_error" not in res["model"]["effects"]
