"""Angular rate from the accelerometers themselves (issue 36; docs/angular-rate.md).

Recordings from the independent generator (indep_model.make_spin_array: quintic turns up to
40 rad/s, true channel parameters off the nominal, noise, rounding); the estimator is held to
the truth, to its own stated information, and to the integration it falls back on.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import accelcal as ac
import indep_model as im
from accelcal import model
from accelcal.calibrate import calibrate_recordings
from accelcal.calibrate.omega_check import lever_arm_omega_bias
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.cli.main import main
from accelcal.cli.calibrate_command import calibrate_warnings
from accelcal.io.device import (Device, axes_device, default_device, default_triad, save_device,
                             tetrahedron_device)
from accelcal.estimators import array_omega, omega_from_recording, omega_ml, omega_observability
from accelcal.io.recording import recording_from_arrays, write_recording


@pytest.fixture(scope="module")
def spin():
    d = im.make_spin_array(tetrahedron_device(), 5, n_turns=12)
    d["est"] = omega_from_recording(d["device"], d["cal"], d["recording"])
    return d


def _noise(dev, cal):
    return np.sqrt((dev.noise_mps2 * np.linalg.norm(cal.sensitivity, axis=1)) ** 2 + 1.0 / 12.0)


def test_observability_lines():
    tet = tetrahedron_device()
    o = omega_observability(tet.positions, tet.axes)
    assert o.full and o.products == 6
    assert o.line.startswith("omega is observable on all three axes from this layout's 12 channels (up to its sign")
    six = default_device()
    o = omega_observability(six.positions, six.axes)
    assert o.axes == (False, False, False) and o.products == 0
    assert "not observable" in o.line and "six channels fix f and alpha exactly" in o.line
    assert "tetrahedron_device" in o.line                     # what layout would
    # the seed's circle plus a triad at the origin: rotation about z moves no channel along its axis
    o = omega_observability(np.vstack([six.positions, np.zeros((3, 3))]), np.vstack([six.axes, np.eye(3)]))
    assert o.axes == (True, True, False)
    assert "only on w_x, w_y" in o.line and "w_z from the integrated alpha alone" in o.line
    nine = axes_device(origin=False)
    o = omega_observability(nine.positions, nine.axes)
    assert o.full and o.products == 3 and "mirror solutions" in o.line
    tri = default_triad()
    assert "do not resolve alpha" in omega_observability(tri.positions, tri.axes).line


def test_ml_error_matches_its_fisher_information(spin):
    """Per sample, (w_ml - w)^T I (w_ml - w) is chi2(3) at the Cramer-Rao bound: its mean is 3."""
    w, est = spin["w"], spin["est"]
    s = np.linalg.norm(w, axis=1) >= 3.0
    d = est.w_ml[s] - w[s]
    chi2 = np.einsum("ni,nij,nj->n", d, est.info_ml[s], d)
    assert s.sum() > 1000
    assert 2.7 < chi2.mean() < 3.3, chi2.mean()
    # the information is the model's at the truth (not only the estimator's own)
    m = model.centripetal_split(spin["cal"].positions, spin["cal"].sensitivity, _noise(spin["device"], spin["cal"])).m
    crb = np.linalg.inv(model.omega_information(m, w[s]))
    ratio = np.sqrt(np.mean(np.sum(d * d, axis=1)) / np.mean(np.trace(crb, axis1=1, axis2=2)))
    assert 0.9 < ratio < 1.1, ratio


def test_fused_error_within_its_sigma(spin):
    w, est = spin["w"], spin["est"]
    s = np.linalg.norm(w, axis=1) >= 1.0
    z = (est.w[s] - w[s]) / est.sigma[s]
    assert 0.7 < np.sqrt(np.mean(z * z)) < 1.3
    # the fused estimate beats the accelerometers alone (it has the integration too)
    assert np.mean(np.sum((est.w[s] - w[s]) ** 2, 1)) < np.mean(np.sum((est.w_ml[s] - w[s]) ** 2, 1))


def test_sign_by_continuity(spin):
    w, est = spin["w"], spin["est"]
    s = np.linalg.norm(w, axis=1) >= 1.0
    assert np.mean(np.sum(est.w[s] * w[s], axis=1) < 0) < 0.001
    # one sample's readings do not have it: the closed-form ML alone is right half the time
    split = model.centripetal_split(spin["cal"].positions, spin["cal"].sensitivity, _noise(spin["device"], spin["cal"]))
    y = spin["recording"].raw - spin["cal"].offsets
    w1, _ = omega_ml(y @ split.qmap.T, split.m)
    assert 0.3 < np.mean(np.sum(w1[s] * w[s], axis=1) < 0) < 0.7


def test_small_rates_fall_back_to_the_integration(spin):
    """Below 0.5 rad/s the accelerometers' ML is noise; the fused estimate stays with the integration
    (no worse than integrating alpha resolved with the true omega's centripetal term)."""
    dev, cal, rec, w, est = spin["device"], spin["cal"], spin["recording"], spin["w"], spin["est"]
    s = np.linalg.norm(w, axis=1) < 0.5
    alpha = model.resolve(cal.offsets, cal.sensitivity, cal.positions, rec.raw, w)[1]
    dt = 1.0 / dev.sample_rate_hz
    integ = np.vstack([np.zeros(3), np.cumsum((alpha[1:] + alpha[:-1]) * (dt / 2.0), axis=0)])
    rms = lambda e: float(np.sqrt(np.mean(np.sum(e[s] ** 2, axis=1))))  # noqa: E731
    assert rms(est.w - w) <= rms(integ - w)
    assert rms(est.w_ml - w) > 10 * rms(est.w - w)


def test_at_rest_from_the_start_it_stays_near_zero():
    dev = tetrahedron_device()
    d = im.make_spin_array(dev, 9, n_turns=0)
    est = omega_from_recording(dev, d["cal"], d["recording"])
    assert np.max(np.abs(est.w)) < 0.05


def _files(tmp_path, d):
    save_device(d["device"], tmp_path / "dev.json")
    save_calibration(d["cal"], tmp_path / "cal.json")
    write_recording(tmp_path / "rec.csv", d["recording"])
    return [str(tmp_path / n) for n in ("dev.json", "cal.json", "rec.csv")]


def _read(path):
    lines = [ln for ln in open(path, encoding="utf-8") if not ln.startswith("#")]
    return np.genfromtxt(lines, delimiter=",", names=True)


def test_cli_resolve_omega_array_columns(tmp_path, spin):
    dev, cal, rec = _files(tmp_path, spin)
    for how in ("array", "auto"):
        assert main(["resolve", "--device", dev, "--calibration", cal, rec, "--omega", how,
                     "-o", str(tmp_path / f"{how}.csv")]) == 0
    out = _read(tmp_path / "array.csv")
    assert out.dtype.names == ("t", "f_x", "f_y", "f_z", "dw_x", "dw_y", "dw_z", "w_x", "w_y", "w_z",
                               "w_x_sigma", "w_y_sigma", "w_z_sigma")
    w = np.stack([out["w_x"], out["w_y"], out["w_z"]], axis=1)
    np.testing.assert_allclose(w, spin["est"].w, atol=1e-6)
    np.testing.assert_array_equal(_read(tmp_path / "auto.csv"), out)
    # f resolved with that omega's centripetal term: within a few noise sd of the truth
    f = np.stack([out["f_x"], out["f_y"], out["f_z"]], axis=1)
    assert np.sqrt(np.mean((f - spin["f"]) ** 2)) < 0.02
    assert main(["resolve", "--device", dev, "--calibration", cal, rec, "--omega", "none",
                 "-o", str(tmp_path / "none.csv")]) == 0
    assert "w_x" not in _read(tmp_path / "none.csv").dtype.names
    assert main(["rate", "--device", dev, "--calibration", cal, rec, "--omega", "array",
                 "-o", str(tmp_path / "rate.csv")]) == 0
    r = _read(tmp_path / "rate.csv")
    np.testing.assert_allclose(r["w_z"], out["w_z"], atol=1e-6)
    assert "w_z_sigma" in r.dtype.names


def test_auto_keeps_the_w_columns(tmp_path):
    d = im.make_spin_array(tetrahedron_device(), 2, n_turns=2, with_w=True)
    r = ac.resolve(d["device"], d["cal"], d["recording"])
    assert r.w is None                                             # the gyro's columns are the omega
    r = ac.resolve(d["device"], d["cal"], d["recording"], omega="array")
    assert r.w.shape == d["w"].shape and r.w_sigma.shape == d["w"].shape
    s = np.linalg.norm(d["w"], axis=1) >= 3.0
    assert np.all(np.abs(r.w[s] - d["w"][s]) < 6 * r.w_sigma[s])


def test_six_channel_device_refused(tmp_path, capsys):
    dev = default_device()
    save_device(dev, tmp_path / "dev.json")
    rec = recording_from_arrays(np.arange(50) / 60.0, np.full((50, 6), 5000, dtype=np.int64))
    write_recording(tmp_path / "rec.csv", rec)
    out = tmp_path / "out.csv"
    assert main(["resolve", "--device", str(tmp_path / "dev.json"), "--calibration", "nominal",
                 str(tmp_path / "rec.csv"), "--omega", "array", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "omega is not observable from this layout's 6 channels" in err[0]
    assert not out.exists()
    # auto on the same: no array omega, no w columns, as before
    assert main(["resolve", "--device", str(tmp_path / "dev.json"), "--calibration", "nominal",
                 str(tmp_path / "rec.csv"), "-o", str(out)]) == 0
    assert "w_x" not in _read(out).dtype.names


def test_partial_layout_refused_with_its_axes():
    six = default_device()
    dev = Device(name="circle+origin", sample_rate_hz=100.0, gravity_mps2=9.80665, raw_min=0, raw_max=65535,
                 positions=np.vstack([six.positions, np.zeros((3, 3))]), axes=np.vstack([six.axes, np.eye(3)]),
                 counts_per_mps2=np.full(9, 200.0), zero_counts=np.full(9, 32768.0), noise_mps2=0.01)
    rec = recording_from_arrays(np.arange(20) / 100.0, np.full((20, 9), 32768, dtype=np.int64))
    with pytest.raises(ac.AccelcalError, match="only on w_x, w_y"):
        ac.resolve(dev, ac.Calibration.nominal(dev), rec, omega="array")


def test_nine_channels_mirror_solutions_by_continuity():
    """Three triads on the axes fix only 3 of the 6 rate products; continuity picks the branch."""
    dev = axes_device(origin=False)
    d = im.make_spin_array(dev, 4, n_turns=8)
    est = array_omega(d["cal"].offsets, d["cal"].sensitivity, d["cal"].positions, d["recording"].raw,
                      1.0 / dev.sample_rate_hz, _noise(dev, d["cal"]))
    w = d["w"]
    s = np.linalg.norm(w, axis=1) >= 3.0
    err = np.linalg.norm(est.w[s] - w[s], axis=1)
    assert np.quantile(err, 0.999) < 0.2 * np.min(np.linalg.norm(w[s], axis=1))


def test_calibrate_says_when_the_lever_arms_limit_omega():
    dev = tetrahedron_device()
    poses_only = im.make_array_calibration(dev, 1, rotations=False)
    cal = calibrate_recordings(dev, [poses_only["recording"]])
    warn = [w for w in calibrate_warnings(dev, cal) if "omega" in w]
    assert len(warn) == 1 and "not all calibrated" in warn[0] and "at |omega| = 10 rad/s" in warn[0]
    turned = im.make_array_calibration(dev, 1, rotations=True)
    cal = calibrate_recordings(dev, [turned["recording"]])
    assert np.nanmax(np.abs(cal.positions - turned["cal"].positions)) < 1e-4       # 0.1 mm
    assert not [w for w in calibrate_warnings(dev, cal) if "omega" in w]
    # a six-channel array has no array omega to warn of
    six = default_device()
    assert not [w for w in calibrate_warnings(six, ac.Calibration.nominal(six)) if "omega" in w]


def test_lever_arm_figure_is_the_error_it_causes(spin):
    """The stated omega error from position_sigma matches the error positions off by that much give."""
    dev, truth, rec, w = spin["device"], spin["cal"], spin["recording"], spin["w"]
    rng = np.random.default_rng(7)
    s = (np.linalg.norm(w, axis=1) > 8.0) & (np.linalg.norm(w, axis=1) < 12.0)
    err2, stated = [], []
    for _ in range(4):
        off = Calibration(device=dev.name, method="truth", offsets=truth.offsets, sensitivity=truth.sensitivity,
                          positions=truth.positions + rng.normal(0.0, 1e-3, truth.positions.shape),
                          position_sigma=np.full(truth.positions.shape, 1e-3))
        stated.append(lever_arm_omega_bias(dev, off)[0])
        est = omega_from_recording(dev, off, rec)
        err2.append(np.mean(np.sum((est.w[s] - w[s]) ** 2, axis=1) * (10.0 / np.linalg.norm(w[s], axis=1)) ** 2))
    ratio = np.sqrt(np.mean(err2)) / np.mean(stated)
    assert 0.5 < ratio < 2.0, ratio


def _short_case(seed: int):
    """200 samples of a smooth turn (model.predict_counts: exact readings plus noise, unrounded)."""
    rng = np.random.default_rng(seed)
    dev = tetrahedron_device()
    S = dev.nominal_sensitivity() * (1.0 + 0.02 * rng.normal(size=(12, 1)))
    b = dev.zero_counts + rng.normal(0.0, 50.0, 12)
    t = np.arange(200) / dev.sample_rate_hz
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    rate = rng.uniform(2.0, 30.0) * np.sin(np.pi * t / t[-1]) ** 2
    w = rate[:, None] * axis
    dw = np.gradient(rate, t)[:, None] * axis
    f = np.tile([0.0, 0.0, 9.80665], (200, 1))
    raw = model.predict_counts(b, S, dev.positions, f, dw, w) + rng.normal(0.0, 2.0, (200, 12))
    return dev, b, S, raw, np.full(12, 2.0)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000), st.permutations(list(range(12))))
def test_estimate_does_not_depend_on_channel_order(seed, order):
    dev, b, S, raw, k = _short_case(seed)
    o = np.asarray(order)
    a = array_omega(b, S, dev.positions, raw, 1.0 / dev.sample_rate_hz, k)
    p = array_omega(b[o], S[o], dev.positions[o], raw[:, o], 1.0 / dev.sample_rate_hz, k[o])
    np.testing.assert_allclose(p.w, a.w, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(p.sigma, a.sigma, rtol=1e-7)


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 10_000), st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4).filter(
    lambda v: np.linalg.norm(v) > 0.1))
def test_estimate_turns_with_the_layout(seed, quat):
    """The same readings from a layout turned by R (every position and axis) give R omega."""
    dev, b, S, raw, k = _short_case(seed)
    x, y, z, s = np.asarray(quat) / np.linalg.norm(quat)
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * s), 2 * (x * z + y * s)],
                  [2 * (x * y + z * s), 1 - 2 * (x * x + z * z), 2 * (y * z - x * s)],
                  [2 * (x * z - y * s), 2 * (y * z + x * s), 1 - 2 * (x * x + y * y)]])
    a = array_omega(b, S, dev.positions, raw, 1.0 / dev.sample_rate_hz, k)
    r = array_omega(b, S @ R.T, dev.positions @ R.T, raw, 1.0 / dev.sample_rate_hz, k)
    np.testing.assert_allclose(r.w, a.w @ R.T, rtol=1e-6, atol=1e-8)
    # the ML alone where it has information (at |omega| ~ 0 it fits noise, ill-conditioned)
    s = np.linalg.norm(a.w, axis=1) > 1.0
    np.testing.assert_allclose(r.w_ml[s], a.w_ml[s] @ R.T, rtol=1e-6, atol=1e-8)


def test_a_recording_that_starts_mid_turn_is_caught(spin):
    """The prior says rest; the ML start catches a recording cut where the array turns fast."""
    w, rec = spin["w"], spin["recording"]
    k = int(np.argmax(np.linalg.norm(w, axis=1) > 20.0))
    cut = recording_from_arrays(rec.t[k:] - rec.t[k], rec.raw[k:])
    est = omega_from_recording(spin["device"], spin["cal"], cut)
    err = np.linalg.norm(est.w - w[k:], axis=1)
    assert err[0] < 0.05                       # at 20 rad/s, on the first sample
    assert np.max(err[:200]) < 0.02
