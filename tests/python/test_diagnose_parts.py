"""Unit tests of the diagnosis's parts on data whose answer is known in closed form:
the noise floor, the scoring of a candidate's held-out gain, and the breakdown of the gap."""
import math

import numpy as np
import pytest

from accelcal.io.calibration import Calibration
from accelcal.io.device import Device, default_device
from accelcal.diagnose import diagnose
from accelcal.diagnose.text import separate_by
from accelcal.diagnose.floor import noise_floor, setup_rows
from accelcal.diagnose.prepare import prepare
from accelcal.diagnose.scoring import score
from accelcal.diagnose.settings import PENALTY_PER_PARAM, T_MIN, Z_MIN
from accelcal.diagnose.where import where_breakdown
from accelcal.effects import EFFECTS
from accelcal.effects.fitting import Cand
from accelcal.io.recording import recording_from_arrays
from accelcal.simulate import simulate

DEV = default_device()


def _truth_cal(dev):
    return Calibration(device=dev.name, method="truth", offsets=dev.nominal_offsets(),
                       sensitivity=dev.nominal_sensitivity())


def _data(rec, dev=DEV):
    D = prepare(dev, _truth_cal(dev), [rec], 5, 0, 1.0)
    e = D.raw - D.p0
    return D, e


@pytest.fixture(scope="module")
def static_data():
    rec = simulate(DEV, "static_poses", poses="24", seed=11)
    return _data(rec)


def test_noise_floor_from_static_poses_matches_the_simulated_noise(static_data):
    D, e = static_data
    sig, how = noise_floor(D, e)
    assert "static segments" in how
    true = np.sqrt(DEV.noise_counts() ** 2 + 1.0 / 12.0)      # Gaussian noise, then rounding
    dof = sum(b - a - 1 for a, b in zip(D.seg_lo, D.seg_hi) if D.static[a])
    # a std from dof samples has relative spread 1 / sqrt(2 dof); the median of the segments'
    # variances is less efficient than their mean (about 1.25x the spread): allow 4 such sigmas
    tol = 4 * 1.25 / math.sqrt(2.0 * dof)
    np.testing.assert_allclose(sig, true, rtol=tol)


def test_noise_floor_ignores_a_constant_model_error(static_data):
    D, e = static_data
    shifted = e + np.array([40.0, 0, 0, 0, 0, -25.0])[None, :]    # an offset the model lacks
    np.testing.assert_allclose(noise_floor(D, shifted)[0], noise_floor(D, e)[0], rtol=1e-12)


def test_noise_floor_without_static_stretches_uses_fourth_differences():
    rec = simulate(DEV, "random_6dof", seed=3, duration_s=20.0)
    D, e = _data(rec)
    assert not D.static.any()
    smooth = e + 30.0 * np.sin(2 * np.pi * 0.05 * D.t)[:, None]   # a slow model error
    sig, how = noise_floor(D, smooth)
    assert "fourth differences" in how
    true = np.sqrt(DEV.noise_counts() ** 2 + 1.0 / 12.0)
    np.testing.assert_allclose(sig, true, rtol=0.15)


def _cand(D, Sw, Su, k=1):
    return Cand(name="test", k=k, Sw=Sw, Su=Su, delta=np.zeros((D.n, D.N)), params={}, sigma={})


def test_score_of_no_gain_is_not_significant(static_data):
    D, e = static_data
    setup_rows(D, e)
    rng = np.random.default_rng(0)
    S0w = rng.uniform(50, 60, D.B)
    c = score(D, _cand(D, S0w.copy(), S0w.copy()), S0w, S0w.copy())
    assert c.gain == 0 and c.shrink == 0 and not c.significant
    assert c.penalty == PENALTY_PER_PARAM * 1


def test_score_of_a_consistent_large_gain_is_significant(static_data):
    D, e = static_data
    setup_rows(D, e)
    rng = np.random.default_rng(1)
    S0w = rng.uniform(50, 60, D.B)
    Sw = 0.25 * S0w                      # every block loses three quarters of its chi2
    c = score(D, _cand(D, Sw, Sw.copy()), S0w, S0w.copy())
    assert c.significant and (c.t >= T_MIN or c.z >= Z_MIN)
    assert c.shrink == pytest.approx(1 - math.sqrt(0.25), rel=1e-12)
    assert c.before > c.after > 0


def test_score_of_a_gain_in_one_block_only_is_not_trusted(static_data):
    D, e = static_data
    setup_rows(D, e)
    S0w = np.full(D.B, 55.0)
    Sw = S0w.copy()
    Sw[0] = 54.0                         # a small gain in one block, none elsewhere
    c = score(D, _cand(D, Sw, Sw.copy(), k=6), S0w, S0w.copy())
    assert not c.significant             # below the penalty of 6 parameters


def test_where_puts_the_gap_on_the_channel_that_has_it(static_data):
    D, e = static_data
    setup_rows(D, e)
    bad = e.copy()
    bad[:, 3] += 20.0 * np.sign(np.sin(np.arange(D.n)))   # a large error on channel 3 only
    w = where_breakdown(D, bad)
    ratios = [c["ratio_to_noise"] for c in w["by_channel"]]
    assert int(np.argmax(ratios)) == 3
    sig3 = w["by_channel"][3]["noise_floor_counts"]
    assert ratios[3] == pytest.approx(math.sqrt(20.0 ** 2 + sig3 ** 2) / sig3, rel=0.05)
    assert max(r for i, r in enumerate(ratios) if i != 3) < 1.2   # the others: noise only
    assert [r["label"] for r in w["static_vs_rotating"]] == ["static"]


def test_one_pose_jig_free_gives_the_smallest_change_of_the_readings():
    """One level pose (a flight controller on the ground, PX4's sample log): only the reading
    along gravity is fixed, and the offset that fits is the smallest change of the readings -- the
    z channel's 184 counts -- where the fit had put 3.4e4 counts on x (its column nearly emptied
    by the projection) and the re-linearisation ran off to 6-7 g."""
    from accelcal.io.device import default_triad
    from accelcal.io.recording import recording_from_arrays
    from accelcal import diagnose
    d = default_triad()
    rng = np.random.default_rng(2)
    n = int(6.5 * d.sample_rate_hz)
    b = d.nominal_offsets() + np.array([0.0, 0.0, 184.0])
    tilt = np.radians(0.7)
    f = d.gravity_mps2 * np.array([np.sin(tilt), 0.0, np.cos(tilt)])
    raw = np.round(b + d.nominal_sensitivity() @ f + 3.0 * rng.standard_normal((n, 3))).astype(np.int64)
    res = diagnose(d, Calibration.nominal(d), [recording_from_arrays(np.arange(n) / d.sample_rate_hz, raw)])
    assert res["verdict"] == "offset"
    db = np.asarray(res["model"]["params"]["offset"]["db"])
    assert abs(db[2] - 184.0) < 10.0 and np.all(np.abs(db[:2]) < 10.0), db


def _coarse_triad_poses(seed, *, sigma_codes, dnl=False, n_poses=12, hold_s=20.0, rate=32.0):
    """An 8-bit triad (64 counts per g, as an Empatica E4) written from the sensor equation
    alone: offsets of up to 2 codes, gains within 3 %, ``n_poses`` still poses in random
    orientations, noise of ``sigma_codes``; ``dnl``: an ADC whose odd codes are half as wide
    (half the readings that round to an odd code read the even code below)."""
    g = 9.80665
    k = 64.0 / g
    dev = Device(name="e4-like", sample_rate_hz=rate, gravity_mps2=g, raw_min=-128, raw_max=127,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, k), zero_counts=np.zeros(3))
    rng = np.random.default_rng(seed)
    off, gain = rng.uniform(-2, 2, 3), 1 + rng.uniform(-0.03, 0.03, 3)
    t, raw, f, pose = [], [], [], []
    n = int(hold_s * rate)
    for p in range(n_poses):
        u = rng.normal(size=3)
        fp = g * u / np.linalg.norm(u)
        r = np.round(off + k * gain * fp + rng.normal(0, sigma_codes, (n, 3))).astype(np.int64)
        if dnl:
            r[(r % 2 == 1) & (rng.random(r.shape) < 0.5)] -= 1
        t.append(p * (hold_s + 2) + np.arange(n) / rate)
        raw.append(r)
        f.append(np.tile(fp, (n, 1)))
        pose.append(np.full(n, p))
    return dev, recording_from_arrays(np.concatenate(t), np.vstack(raw), f=np.vstack(f), pose=np.concatenate(pose))


@pytest.mark.parametrize("seed", [0, 2, 4])
def test_a_signal_dwelling_on_few_codes_is_no_adc_defect(seed):
    """An 8-bit sensor holding still sits on 2-4 codes a pose, so some residue class mod 2-4
    holds far more than its share (up to 55 % for 33 % here); the Empatica E4 had been told its
    ADC has "missing or doubled codes".  The class differs from pose to pose: no note."""
    dev, rec = _coarse_triad_poses(seed, sigma_codes=0.35)
    res = diagnose(dev, Calibration.nominal(dev), [rec])
    assert not any("residue class" in n for n in res["notes"]), res["notes"]
    low = [e["low_bits"] for e in res["raw_values"] if "low_bits" in e]
    assert low and max(b["share_of_top_residue"] - b["uniform_share"] for b in low) > 0.1   # the excess is there
    assert all(b["parts_agreeing"] < 0.9 for b in low)


@pytest.mark.parametrize("seed", [0, 1])
def test_an_adc_with_narrow_odd_codes_is_named(seed):
    dev, rec = _coarse_triad_poses(seed, sigma_codes=2.0, dnl=True)
    res = diagnose(dev, Calibration.nominal(dev), [rec])
    said = [n for n in res["notes"] if "residue class mod 2" in n and "unevenly used" in n]
    assert len(said) == 3, res["notes"]


def test_separate_by_asks_for_each_pose_or_motion_once():
    """An offset's and a gain's hints both ask for each axis up and down, each with its own why:
    a real robot-arm session's separate_by said it twice in one sentence."""
    text = separate_by(dict(EFFECTS), "offset", ["gain"])
    assert text.count("each axis both up and down") == 1, text
