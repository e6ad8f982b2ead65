"""Tests of accelcal.calibrate: known poses, jig-free, static detection, lever arms,
temperature, the real Xsens recording and bad input.

Simulated data come from a small forward generator here (model.predict_counts +
Gaussian noise + rounding), not from accelcal.simulate.
"""
from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from accelcal import model
from accelcal.calibrate import (PoseSet, calibrate_jigfree, calibrate_known_poses, calibrate_recordings,
                                detect_static, estimate_noise, fit_known_poses, fit_static, fit_temperature,
                                gauge_rotation, pose_means, poses_from_recording, static_force)
from accelcal.calibrate.checks import gain_sigma
from accelcal.io.calibration import load_calibration
from accelcal.io.device import default_device, default_triad, save_device
from accelcal.errors import InputError
from accelcal.convert.xsens import load_xsens
from shared_data import XSENS_ACC
from accelcal.io.recording import Recording, read_recording, recording_from_arrays, write_recording
from cli_run import run

G = 9.80665

AXES6 = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])


# ----------------------------------------------------------------------------- generator
def fib_dirs(P):
    i = np.arange(P) + 0.5
    z = 1 - 2 * i / P
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)


def draw_truth(dev, rng, gain=(-0.007, 0.036), cross=0.0175, offset=0.28):
    """Seed-prototype-like channel errors: gain, cross-axis (fraction of k), offset (fraction of g)."""
    N = dev.n_channels
    k = dev.counts_per_mps2
    gn = rng.uniform(*gain, N)
    cr = rng.uniform(-cross, cross, (N, 3))
    cr -= np.sum(cr * dev.axes, axis=1, keepdims=True) * dev.axes
    S = (k * (1 + gn))[:, None] * dev.axes + k[:, None] * cr
    b = dev.zero_counts + rng.uniform(-offset, offset, N) * dev.gravity_mps2 * k
    return b, S


def make_recording(dev, b, S, F, rng, *, hold=60, move=30, labels=True, f_ref=None, temps=None,
                   beta=None, gamma=None, clip=True):
    """Static poses F (P,3) held ``hold`` samples, joined by ``move``-sample swings.
    With ``labels``, pose labels and (f_ref or F) as the reference on static samples."""
    P = len(F)
    sig = dev.noise_mps2 * dev.counts_per_mps2
    fs, pose, tc = [], [], []
    for p in range(P):
        fs.append(np.repeat(F[p][None], hold, 0))
        pose.append(np.full(hold, p))
        tc.append(np.full(hold, np.nan if temps is None else temps[p]))
        if move:
            u = np.linspace(0, 1, move + 2)[1:-1, None]
            q = F[(p + 1) % P]
            fs.append((1 - u) * F[p] + u * q + 4.0 * np.sin(np.pi * u) * np.array([1.0, -0.7, 0.4]))
            pose.append(np.full(move, -1))
            tc.append(np.full(move, np.nan if temps is None else temps[p]))
    f = np.vstack(fs)
    pose = np.concatenate(pose)
    temp = np.concatenate(tc)
    clean = model.predict_counts(b, S, dev.positions, f)
    if temps is not None:
        dT = temp - np.mean(temps)
        clean = clean + dT[:, None] * (beta[None, :] + gamma[None, :] * (f @ S.T))
    raw = np.round(clean + rng.normal(size=clean.shape) * sig)
    if clip:
        raw = np.clip(raw, dev.raw_min, dev.raw_max)
    t = np.arange(len(f)) / dev.sample_rate_hz
    kw = {}
    if labels:
        ref = F if f_ref is None else f_ref
        kw["pose"] = pose
        kw["f"] = np.where((pose >= 0)[:, None], ref[np.maximum(pose, 0)], np.nan)
    if temps is not None:
        kw["temp_c"] = temp
    return recording_from_arrays(t, raw.astype(np.int64), **kw)


def poseset_from(dev, b, S, F, rng, n=60, f_ref=True):
    sig = dev.noise_mps2 * dev.counts_per_mps2
    clean = model.predict_counts(b, S, dev.positions, F)
    raw = np.round(clean[:, None, :] + rng.normal(size=(len(F), n, dev.n_channels)) * sig)
    P = len(F)
    return PoseSet(raw.mean(1), np.full(P, n), raw.std(1, ddof=1), F if f_ref else np.full((P, 3), np.nan),
                   np.full(P, np.nan), [{"label": p} for p in range(P)])


def z_scores(est, truth, sigma):
    return (np.asarray(est) - np.asarray(truth)) / np.asarray(sigma)


# ----------------------------------------------------------------------------- known poses
def test_known_full_recording_recovers_parameters_within_uncertainty():
    rng = np.random.default_rng(1)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    F = G * fib_dirs(12)
    rec = make_recording(dev, b, S, F, rng)
    cal = calibrate_recordings(dev, [rec])
    assert cal.method == "full"
    zb = z_scores(cal.offsets, b, cal.offset_sigma)
    zs = z_scores(cal.sensitivity, S, cal.sensitivity_sigma)
    z = np.concatenate([zb, zs.ravel()])
    assert np.max(np.abs(z)) < 4.5
    assert 0.6 < np.sqrt(np.mean(z ** 2)) < 1.5          # uncertainties are honest
    # post-calibration errors, % of 1 g
    k = dev.counts_per_mps2
    assert np.max(np.abs(cal.offsets - b) / (k * G)) < 1e-3
    assert np.max(np.abs(np.linalg.norm(cal.sensitivity, axis=1) / np.linalg.norm(S, axis=1) - 1)) < 1e-3
    assert cal.poses_used == list(range(12))
    assert set(cal.residual_rms_per_pose) == {str(p) for p in range(12)}
    assert cal.residual_rms_per_channel.shape == (6,)
    assert np.all(cal.residual_rms_per_channel < 1.0)   # counts; noise of a 60-sample mean is 0.33


def test_known_four_poses_of_the_paper_is_exact_fit():
    rng = np.random.default_rng(2)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    F = G * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1.0]])
    ps = poseset_from(dev, b, S, F, rng)
    fit = fit_known_poses(dev, ps.means, F, "full", ps.sem(), poses=ps)
    assert fit.dof == 0
    assert np.max(np.abs(fit.residual)) < 1e-8
    assert np.max(np.abs(z_scores(fit.offsets, b, fit.offset_sigma))) < 4.5
    assert np.max(np.abs(z_scores(fit.sensitivity, S, fit.sensitivity_sigma))) < 4.5


def test_three_pose_gain_method_matches_seed_formula():
    """Seed doc 2: offsets = mean of the two poses where the axis sees 0 g, gain = AccX1 - Xofs."""
    rng = np.random.default_rng(3)
    dev = default_triad()
    b, S = draw_truth(dev, rng, cross=0.0)
    F = G * np.eye(3)
    ps = poseset_from(dev, b, S, F, rng)
    fit = fit_known_poses(dev, ps.means, F, "gain", ps.sem(), poses=ps)
    m = ps.means
    ofs = np.array([(m[1, 0] + m[2, 0]) / 2, (m[0, 1] + m[2, 1]) / 2, (m[0, 2] + m[1, 2]) / 2])
    gain = np.array([m[0, 0], m[1, 1], m[2, 2]]) - ofs
    np.testing.assert_allclose(fit.offsets, ofs, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.diag(fit.sensitivity) * G, gain, rtol=1e-12)
    assert np.all(fit.sensitivity[~np.eye(3, dtype=bool)] == 0)
    assert np.max(np.abs(z_scores(np.diag(fit.sensitivity), np.diag(S), np.diag(fit.sensitivity_sigma)))) < 4.5


def test_one_pose_offset_method():
    rng = np.random.default_rng(4)
    dev = default_triad()
    b, _ = draw_truth(dev, rng)
    S = dev.nominal_sensitivity()
    F = G * np.array([[0, 0, 1.0]])
    ps = poseset_from(dev, b, S, F, rng)
    fit = fit_known_poses(dev, ps.means, F, "offset", ps.sem(), poses=ps)
    assert np.max(np.abs(z_scores(fit.offsets, b, fit.offset_sigma))) < 4.5
    np.testing.assert_array_equal(fit.sensitivity, S)


def test_array_entry_points_return_calibrations():
    """calibrate_known_poses / calibrate_jigfree on bare mean arrays (no scatter known):
    equal weights, uncertainties from the residuals."""
    rng = np.random.default_rng(22)
    dev = default_triad()
    b, S = draw_truth(dev, rng)
    F = G * fib_dirs(16)
    ps = poseset_from(dev, b, S, F, rng)
    cal = calibrate_known_poses(dev, ps.means, F, "full")
    assert cal.method == "full" and cal.device == dev.name
    assert np.max(np.abs(z_scores(cal.offsets, b, cal.offset_sigma))) < 5
    assert cal == calibrate_known_poses(dev, ps.means, F, "full")
    jf = calibrate_jigfree(dev, ps.means)
    assert jf.method == "jigfree"
    R = gauge_rotation(dev, S)
    assert np.max(np.abs(z_scores(jf.sensitivity, S @ R.T, jf.sensitivity_sigma))) < 5
    # with the PoseSet: per-channel weights from the scatter; the same estimate to well within 1 sigma
    jf2 = calibrate_jigfree(dev, ps)
    assert np.all(np.abs(jf2.sensitivity - jf.sensitivity) < 0.5 * jf2.sensitivity_sigma)
    assert len(jf2.extra["poses"]) == 16 and "f_mps2" in jf2.extra["poses"][0]


def test_gain_method_shows_model_error_full_removes_it():
    """With cross-axis sensitivity in the truth, the gain model leaves residuals far
    above the noise (and its uncertainties grow with them); full does not."""
    rng = np.random.default_rng(5)
    dev = default_triad()
    b, S = draw_truth(dev, rng)
    F = G * fib_dirs(12)
    ps = poseset_from(dev, b, S, F, rng)
    gain = fit_known_poses(dev, ps.means, F, "gain", ps.sem(), poses=ps)
    full = fit_known_poses(dev, ps.means, F, "full", ps.sem(), poses=ps)
    assert gain.chi2 / gain.dof > 100
    assert full.chi2 / full.dof < 3


# ----------------------------------------------------------------------------- identifiability
def test_full_with_three_axis_poses_says_which_pose_to_add():
    dev = default_device()
    F = G * np.eye(3)
    m = model.predict_counts(dev.nominal_offsets(), dev.nominal_sensitivity(), dev.positions, F)
    with pytest.raises(InputError) as e:
        calibrate_known_poses(dev, m, F, "full")
    msg = str(e.value)
    assert "only 3 poses" in msg and "add a pose with f along -z" in msg
    assert "\n" not in msg
    # four poses on one circle of the sphere (the plane x + y + z = g): still not enough
    F4 = G * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [2 / 3, 2 / 3, -1 / 3]])
    m4 = model.predict_counts(dev.nominal_offsets(), dev.nominal_sensitivity(), dev.positions, F4)
    with pytest.raises(InputError, match=r"all 4 pose forces lie in one plane .*add a pose with f along -[xyz]"):
        calibrate_known_poses(dev, m4, F4, "full")


def test_full_with_too_few_poses_is_an_error():
    dev = default_triad()
    F = G * np.array([[0, 0, 1.0], [0, 0, -1.0]])
    m = model.predict_counts(dev.nominal_offsets(), dev.nominal_sensitivity(), dev.positions, F)
    with pytest.raises(InputError, match=r"only 2 poses.*add a pose with f along"):
        calibrate_known_poses(dev, m, F, "full")


def test_repeated_pose_is_refused_by_both_methods():
    rng = np.random.default_rng(23)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    F = np.repeat(G * np.array([[0, 0, 1.0]]), 12, 0)
    ps = poseset_from(dev, b, S, F, rng)
    with pytest.raises(InputError, match=r"all 12 poses have about the same f = \[\+0\.00, \+0\.00, \+1\.00\] g.*add a pose"):
        calibrate_known_poses(dev, ps)
    with pytest.raises(InputError, match=r"all have about the same orientation"):
        calibrate_jigfree(dev, ps)


def test_gain_names_the_channel_that_is_not_excited():
    dev = default_triad()
    F = G * np.array([[0, 0, 1.0], [0, 0, -1.0], [0, 1.0, 0]])
    m = model.predict_counts(dev.nominal_offsets(), dev.nominal_sensitivity(), dev.positions, F)
    with pytest.raises(InputError, match=r"channel 0's gain.*add a pose with f along [+-]x"):
        calibrate_known_poses(dev, m, F, "gain")


def test_jigfree_needs_nine_poses():
    rng = np.random.default_rng(6)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    ps = poseset_from(dev, b, S, G * fib_dirs(8), rng, f_ref=False)
    with pytest.raises(InputError, match=r"needs at least 9 static poses in different orientations, got 8"):
        calibrate_jigfree(dev, ps)


@pytest.mark.parametrize("P", [12, 150])
def test_jigfree_degenerate_poses_is_an_error_not_a_solve(P):
    """P poses all tilted about one axis (a cone): the full jig-free model is not determined
    (150: the rank test of the structured solve, each pose eliminated)."""
    rng = np.random.default_rng(7)
    dev = default_triad()
    b, S = draw_truth(dev, rng)
    ang = np.linspace(0, 2 * np.pi, P, endpoint=False)
    F = G * np.stack([0.5 * np.cos(ang), 0.5 * np.sin(ang), np.full(P, math.sqrt(0.75))], 1)
    ps = poseset_from(dev, b, S, F, rng, f_ref=False)
    with pytest.raises(InputError, match=r"do not determine"):
        calibrate_jigfree(dev, ps)


# ----------------------------------------------------------------------------- static detection
def test_detect_static_finds_synthetic_steps():
    rng = np.random.default_rng(8)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    F = G * fib_dirs(10)
    hold, move = 120, 45
    rec = make_recording(dev, b, S, F, rng, hold=hold, move=move, labels=False)
    iv = detect_static(rec, dev)
    assert len(iv) == 10
    w = int(round(0.5 * dev.sample_rate_hz))
    for p, (a, z) in enumerate(iv):
        t0, t1 = p * (hold + move), p * (hold + move) + hold
        assert t0 <= a <= t0 + 2 and t1 - 2 <= z <= t1 + 1, (p, a, z, t0, t1)
    # the same with the noise estimated from the data (device without noise_mps2)
    est = estimate_noise(rec.raw, w)
    np.testing.assert_allclose(est, np.sqrt((0.02 * dev.counts_per_mps2) ** 2 + 1 / 12), rtol=0.15)
    assert len(detect_static(rec, dev, noise=est)) == 10


def test_pose_means_matches_numpy():
    rng = np.random.default_rng(9)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng, labels=False)
    iv = detect_static(rec, dev)
    m, n, sd = pose_means(rec, iv, dev)
    for p, (a, z) in enumerate(iv):
        np.testing.assert_allclose(m[p], rec.raw[a:z].mean(0), rtol=0, atol=1e-9)
        np.testing.assert_allclose(sd[p], rec.raw[a:z].std(0, ddof=1), rtol=1e-9)
        assert n[p] == z - a


# ----------------------------------------------------------------------------- jig-free
@pytest.mark.parametrize("dev_fn,P", [(default_triad, 24), (default_device, 12)])
def test_jigfree_recovers_parameters_up_to_the_gauge(dev_fn, P):
    rng = np.random.default_rng(10 + P)
    dev = dev_fn()
    b, S = draw_truth(dev, rng)
    F = G * fib_dirs(P)
    rec = make_recording(dev, b, S, F, rng, hold=int(1.5 * dev.sample_rate_hz), labels=False)
    cal = calibrate_recordings(dev, [rec])
    assert cal.method == "jigfree"
    assert len(cal.poses_used) == P
    # documented gauge: sum_i u_i x s_i/|s_i| = 0
    sh = cal.sensitivity / np.linalg.norm(cal.sensitivity, axis=1, keepdims=True)
    assert np.linalg.norm(np.sum(np.cross(dev.axes, sh), axis=0)) < 1e-9
    R = gauge_rotation(dev, S)
    z = np.concatenate([z_scores(cal.offsets, b, cal.offset_sigma),
                        z_scores(cal.sensitivity, S @ R.T, cal.sensitivity_sigma).ravel()])
    assert np.max(np.abs(z)) < 4.5
    assert 0.5 < np.sqrt(np.mean(z ** 2)) < 1.6
    f = static_force(cal.offsets, cal.sensitivity, poses_from_recording(rec, dev).means)
    assert np.sqrt(np.mean((np.linalg.norm(f, axis=1) - G) ** 2)) < 2e-3


def test_jigfree_is_immune_to_pose_errors_known_pose_is_not():
    rng = np.random.default_rng(11)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    F_nom = G * fib_dirs(24)
    ax = rng.normal(size=(24, 3))
    ax /= np.linalg.norm(ax, axis=1, keepdims=True)
    th = math.radians(2.0)
    F_true = F_nom * math.cos(th) + np.cross(ax, F_nom) * math.sin(th) + ax * np.sum(ax * F_nom, 1)[:, None] * (1 - math.cos(th))
    ps = poseset_from(dev, b, S, F_true, rng)
    known = fit_known_poses(dev, ps.means, F_nom, "full", ps.sem(), poses=ps)
    jf = fit_static(dev, ps, jigfree=True)
    R = gauge_rotation(dev, S)
    z_known = z_scores(known.sensitivity, S, known.sensitivity_sigma / math.sqrt(known.chi2 / known.dof))
    z_jf = z_scores(jf.sensitivity, S @ R.T, jf.sensitivity_sigma)
    assert np.sqrt(np.mean(z_known ** 2)) > 10       # far outside its noise-only uncertainty
    assert np.sqrt(np.mean(z_jf ** 2)) < 1.6
    # and the known-pose fit reports it: chi2/dof and the inflated uncertainties
    assert known.chi2 / known.dof > 50


# ----------------------------------------------------------------------------- temperature
def test_temperature_coefficients_known_and_jigfree():
    rng = np.random.default_rng(12)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    P = 24
    F = G * fib_dirs(P)
    temps = np.linspace(5, 45, P)
    rng.shuffle(temps)
    beta = rng.uniform(-2, 2, 6)              # counts per degC
    gamma = rng.uniform(-3e-4, 3e-4, 6)       # per degC
    rec = make_recording(dev, b, S, F, rng, temps=temps, beta=beta, gamma=gamma)
    cal = calibrate_recordings(dev, [rec])
    assert cal.temp_ref_c == pytest.approx(np.mean(temps))
    ts = cal.extra["temperature_sigma"]
    assert np.max(np.abs(z_scores(cal.offset_tc, beta, ts["offset_tc_counts_per_c"]))) < 4.5
    assert np.max(np.abs(z_scores(cal.gain_tc, gamma, ts["gain_tc_per_c"]))) < 4.5
    assert np.max(np.abs(z_scores(cal.offsets, b, cal.offset_sigma))) < 4.5
    # jig-free with temperature
    ps = poses_from_recording(rec, dev)
    ps.f_ref[:] = np.nan
    fit = fit_static(dev, ps, jigfree=True, temperature=True)
    assert np.max(np.abs(z_scores(fit.offset_tc, beta, fit.offset_tc_sigma))) < 4.5
    assert np.max(np.abs(z_scores(fit.gain_tc, gamma, fit.gain_tc_sigma))) < 4.5
    # fit_temperature with the jig-free poses' forces agrees
    ft = fit_temperature(dev, ps, f=fit.f)
    np.testing.assert_allclose(ft.offset_tc, fit.offset_tc, atol=3 * np.max(fit.offset_tc_sigma))


# ----------------------------------------------------------------------------- lever arms
def _spin(dev, b, S, r_true, axis, rng, n=1200, W=5.0, fr=1.0):
    t = np.arange(n) / dev.sample_rate_hz
    w = W * np.sin(2 * np.pi * fr * t)[:, None] * axis
    a = W * 2 * np.pi * fr * np.cos(2 * np.pi * fr * t)[:, None] * axis
    f = np.repeat(G * axis[None], n, 0)
    sig = dev.noise_mps2 * dev.counts_per_mps2
    raw = np.round(model.predict_counts(b, S, r_true, f, a, w) + rng.normal(size=(n, dev.n_channels)) * sig)
    return recording_from_arrays(t, raw.astype(np.int64), f=f, w=w, dw=a)


def test_positions_from_rate_table_and_observability():
    rng = np.random.default_rng(13)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    dr = rng.uniform(-1e-3, 1e-3, (6, 3))
    r_true = dev.positions + dr
    static = make_recording(dev, b, S, G * fib_dirs(12), rng)
    yaw = _spin(dev, b, S, r_true, np.array([0, 0, 1.0]), rng)
    # yaw only: z channels see nothing, tangential ones nothing along z
    cal = calibrate_recordings(dev, [static, yaw])
    rep = cal.extra["lever_arm"]["channels"]
    assert [c["observable_directions"] for c in rep] == [2, 0, 2, 0, 2, 0]
    assert np.all(np.isnan(cal.positions[1::2]))
    # three axes: everything observable and recovered within its uncertainty
    spins = [_spin(dev, b, S, r_true, ax, rng) for ax in np.eye(3)]
    cal = calibrate_recordings(dev, [static] + spins)
    rep = cal.extra["lever_arm"]["channels"]
    assert all(c["observable_directions"] == 3 for c in rep)
    z = z_scores(cal.positions, r_true, cal.position_sigma)
    assert np.max(np.abs(z)) < 4.5
    assert np.max(np.abs(cal.positions - r_true)) < 2e-4


# ----------------------------------------------------------------------------- real data
def test_xsens_jigfree_calibration(shared_data):
    dev, rec = load_xsens(shared_data.joinpath(*XSENS_ACC))
    ps = poses_from_recording(rec, dev)
    assert 38 <= ps.n_poses <= 44                 # the README: about 40 poses (+ the initial rest)
    cal = calibrate_recordings(dev, [rec])
    f = static_force(cal.offsets, cal.sensitivity, ps.means)
    rms = float(np.sqrt(np.mean((np.linalg.norm(f, axis=1) - dev.gravity_mps2) ** 2)))
    assert rms <= 0.002                          # the requirement
    assert rms == pytest.approx(0.00108, abs=1.5e-4)   # measured: 0.00108 m/s^2 over 40 poses
    assert cal.extra["fit"]["rms_norm_error_mps2"] == pytest.approx(rms, rel=1e-3)
    # the offset + gain (3-pose) model on the same poses is far worse: cross-axis terms matter
    gain = fit_static(dev, ps, "gain", jigfree=True)
    f3 = static_force(gain.offsets, gain.sensitivity, ps.means)
    assert np.sqrt(np.mean((np.linalg.norm(f3, axis=1) - dev.gravity_mps2) ** 2)) > 10 * rms


# ----------------------------------------------------------------------------- files, CLI, bad input
def test_csv_round_trip_and_calibration_json(tmp_path):
    from accelcal.io.calibration import load_calibration, save_calibration
    rng = np.random.default_rng(14)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng)
    path = tmp_path / "rec.csv"
    write_recording(path, rec)
    cal = calibrate_recordings(dev, [read_recording(path, dev.n_channels)])
    out = tmp_path / "cal.json"
    save_calibration(cal, out)
    back = load_calibration(out, dev)
    np.testing.assert_array_equal(back.offsets, cal.offsets)
    doc = json.loads(out.read_text())
    assert doc["method"] == "full" and "offset_sigma_counts" in doc["channels"][0]
    # a calibration for another device is refused, naming the field
    other = default_triad()
    with pytest.raises(InputError, match=r"cal\.json: field device"):
        load_calibration(out, other)


def test_recording_with_other_channel_count_is_refused():
    rng = np.random.default_rng(15)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng)
    with pytest.raises(InputError, match=r"6 raw channels \(raw_0..raw_5\) but device 'triad-16bit' has 3"):
        calibrate_recordings(default_triad(), [rec])


def test_labelled_pose_that_moves_is_refused():
    rng = np.random.default_rng(16)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng)
    raw = rec.raw.copy()
    idx = np.flatnonzero(rec.pose == 3)
    raw[idx] += (np.linspace(-60, 60, len(idx))[:, None]).astype(np.int64)   # drifts during pose 3
    bad = Recording(t=rec.t, raw=raw, f=rec.f, pose=rec.pose, source="moving.csv")
    with pytest.raises(InputError, match=r"^moving\.csv: column pose: pose 3 .* is labelled static but moves"):
        calibrate_recordings(dev, [bad])


def test_pose_with_a_reading_at_the_adc_limit_is_set_aside_and_counted():
    rng = np.random.default_rng(17)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    P = np.vstack([AXES6, AXES6[:2] * 0.6 + AXES6[2:4] * 0.8])
    rec = make_recording(dev, b, S, G * P, rng)
    raw = rec.raw.copy()
    i = int(np.flatnonzero(rec.pose == 2)[5])
    raw[i, 4] = dev.raw_max
    clipped = Recording(t=rec.t, raw=raw, f=rec.f, pose=rec.pose, source="clip.csv")
    cal = calibrate_recordings(dev, [clipped])
    aside = cal.extra["set_aside"]
    assert [d["name"] for d in aside] == ["pose 2"] and aside[0]["n_clipped"] == 1
    assert aside[0]["reason"] == "clipped" and f"raw_4 at {dev.raw_max}" in aside[0]["levels"]
    assert "2" not in [str(p) for p in cal.poses_used] and len(cal.poses_used) == P.shape[0] - 1
    # what is left is calibrated as without the clipped pose
    keep = rec.pose != 2
    ref = calibrate_recordings(dev, [Recording(t=rec.t[keep], raw=rec.raw[keep], f=rec.f[keep], pose=rec.pose[keep])])
    np.testing.assert_allclose(cal.offsets, ref.offsets, rtol=0, atol=1e-9)
    # with a stated jig accuracy (the references as priors) and with temperature the set-aside
    # pose is still named in the calibration
    assert [d["name"] for d in calibrate_recordings(dev, [clipped], jig_accuracy_deg=1.0).extra["set_aside"]] \
        == ["pose 2"]
    temp = np.where(rec.pose >= 0, 20.0 + 2.0 * rec.pose, np.nan)
    warm = Recording(t=rec.t, raw=raw, f=rec.f, pose=rec.pose, temp_c=temp, source="clip.csv")
    assert [d["name"] for d in calibrate_recordings(dev, [warm]).extra["set_aside"]] == ["pose 2"]


def test_every_pose_clipped_is_one_line_naming_them():
    rng = np.random.default_rng(17)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng)
    raw = rec.raw.copy()
    for p in range(6):
        raw[np.flatnonzero(rec.pose == p)[3], 0] = dev.raw_min
    with pytest.raises(InputError, match=r"^c\.csv: no usable static pose in any recording \(6 set aside because "
                                         r"their readings clip: pose 0 \(raw_0 at 0\)"):
        calibrate_recordings(dev, [Recording(t=rec.t, raw=raw, f=rec.f, pose=rec.pose, source="c.csv")])


def test_non_increasing_time_is_refused():
    rng = np.random.default_rng(18)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng)
    t = rec.t.copy()
    t[100] = t[99]
    bad = Recording(t=t, raw=rec.raw, f=rec.f, pose=rec.pose, source="time.csv")
    with pytest.raises(InputError, match=r"time\.csv: row 101, column t: t must be strictly increasing: t = 1.65 s follows"):
        calibrate_recordings(dev, [bad])


def test_nan_and_inf_in_arrays_are_refused():
    dev = default_device()
    F = G * AXES6
    m = model.predict_counts(dev.nominal_offsets(), dev.nominal_sensitivity(), dev.positions, F)
    m[2, 3] = np.nan
    with pytest.raises(InputError, match=r"field means\[2\]\[3\]: not finite"):
        calibrate_known_poses(dev, m, F)
    m[2, 3] = 5000
    F2 = F.copy()
    F2[4, 0] = np.inf
    with pytest.raises(InputError, match=r"field f_ref\[4\]"):
        calibrate_known_poses(dev, m, F2)


def test_too_few_known_poses_names_the_recording():
    rng = np.random.default_rng(21)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * np.eye(3), rng)
    rec.source = "three.csv"
    with pytest.raises(InputError, match=r"^three\.csv: field poses: .*only 3 poses.*add a pose with f along -z"):
        calibrate_recordings(dev, [rec])


def test_known_method_without_reference_is_refused():
    rng = np.random.default_rng(19)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * fib_dirs(12), rng, labels=False)
    with pytest.raises(InputError, match=r"method 'full' needs the reference specific force.*jigfree"):
        calibrate_recordings(dev, [rec], method="full")


def test_bad_csv_cells_name_file_row_and_column(tmp_path):
    """NaN/inf raw cells and missing columns are refused by the reader before calibration."""
    rng = np.random.default_rng(20)
    dev = default_device()
    b, S = draw_truth(dev, rng)
    rec = make_recording(dev, b, S, G * AXES6, rng)
    path = tmp_path / "r.csv"
    write_recording(path, rec)
    lines = path.read_text().splitlines()
    cells = lines[5].split(",")
    cells[2] = "nan"
    bad = tmp_path / "nan.csv"
    bad.write_text("\n".join(lines[:5] + [",".join(cells)] + lines[6:]) + "\n")
    with pytest.raises(InputError, match=r"nan\.csv: row 6, column raw_1"):
        read_recording(bad, dev.n_channels)
    hdr = lines[0].split(",")
    keep = [j for j, h in enumerate(hdr) if h != "f_y"]
    missing = tmp_path / "missing.csv"
    missing.write_text("\n".join(",".join(l.split(",")[j] for j in keep) for l in lines) + "\n")
    with pytest.raises(InputError, match=r"missing\.csv: row 1: .*f_y"):
        read_recording(missing, dev.n_channels)


def test_a_recording_without_a_pose_among_several_is_named_and_adds_none():
    """Several recordings, one of them a motion with no static pose (a sweep recorded beside
    the poses): the calibration is that of the others, and a note names the one that added
    none; alone, it is refused as before; with no pose in any, refused."""
    d = default_triad()
    rng = np.random.default_rng(5)
    b, S = draw_truth(d, rng)
    poses = make_recording(d, b, S, d.gravity_mps2 * fib_dirs(16), rng, labels=False,
                           hold=int(2 * d.sample_rate_hz), move=int(0.5 * d.sample_rate_hz))
    tt = np.arange(600) / d.sample_rate_hz
    f = np.column_stack([3 * np.sin(7 * tt), 2 * np.cos(5 * tt), d.gravity_mps2 + 3 * np.sin(3 * tt)])
    raw = np.round(model.predict_counts(b, S, d.positions, f) + rng.normal(size=f.shape))
    sweep = recording_from_arrays(tt, raw.astype(np.int64))
    sweep.source = "sweep.csv"
    alone = calibrate_recordings(d, [poses], "jigfree")
    both = calibrate_recordings(d, [poses, sweep], "jigfree")
    np.testing.assert_allclose(both.offsets, alone.offsets)
    np.testing.assert_allclose(both.sensitivity, alone.sensitivity)
    assert any(n.startswith("sweep.csv: no static pose found") for n in both.extra["notes"])
    with pytest.raises(InputError, match="no static pose found"):
        calibrate_recordings(d, [sweep], "jigfree")
    with pytest.raises(InputError, match="no usable static pose in any recording"):
        calibrate_recordings(d, [sweep, sweep], "jigfree")


def test_too_few_orientations_are_counted_as_such_and_a_tilted_pose_is_asked_for():
    """imucal's session converted without its regions: 13 static runs in only its six face
    orientations.  The jig-free full fit needs 9 orientations; a pose held twice gives the same
    equation twice, so the count is of orientations (it had gone on and failed to converge,
    blaming "moving poses, or another device?"), and with every face already there the pose
    to add is a tilted one (it asked for f along -z, which the file had).  The full model,
    asked for, is refused so; by default the gain model, which six faces determine, is fitted
    instead, with full's reason kept, and its offsets and gains are the truth's."""
    d = default_triad()
    rng = np.random.default_rng(7)
    b, S = draw_truth(d, rng, cross=0.0)
    faces = d.gravity_mps2 * np.vstack([np.eye(3), -np.eye(3)])
    F = np.vstack([faces, faces[[0, 2, 4, 1, 3, 5, 0]]])
    rec = make_recording(d, b, S, F, rng, labels=False, hold=int(2 * d.sample_rate_hz),
                         move=int(0.5 * d.sample_rate_hz))
    with pytest.raises(InputError) as ei:
        calibrate_recordings(d, [rec], "jigfree", jigfree_model="full")
    msg = str(ei.value)
    assert "needs at least 9 static poses in different orientations, got 6 (13 poses, 6 orientations" in msg
    assert "a corner: equally along x, y and z" in msg
    cal = calibrate_recordings(d, [rec], "jigfree")
    fb = cal.extra["fit"]["fallback"]
    assert fb["from"] == "full" and fb["to"] == "gain" and list(fb["reasons"]) == ["full"]
    assert "got 6 (13 poses, 6 orientations" in fb["reasons"]["full"]
    assert cal.extra["fit"]["model"] == "gain" and cal.method == "jigfree"
    # the truth within 4 of the fit's own 1-sigma (offsets in counts, gains along the axes)
    assert np.all(np.abs(cal.offsets - b) < 4 * cal.offset_sigma), (cal.offsets - b, cal.offset_sigma)
    gain = np.sum(cal.sensitivity * d.axes, axis=1)
    g_sig = gain_sigma(cal.sensitivity, cal.sensitivity_sigma) * np.linalg.norm(cal.sensitivity, axis=1)
    assert np.all(np.abs(gain - np.linalg.norm(S, axis=1)) < 4 * g_sig), (gain - np.linalg.norm(S, axis=1), g_sig)


def calibrate_cli(tmp_path, capfd, F, seed):
    """Poses F (P,3) of a seed-like triad held 2 s each, written to r.csv beside d.json, and
    ``accelcal calibrate`` run on them: (b, S, rec, rc, stdout, stderr)."""
    from cli_run import run
    from accelcal.io.device import save_device
    d = default_triad()
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(seed)
    b, S = draw_truth(d, rng)
    rec = make_recording(d, b, S, F, rng, labels=False, hold=int(2 * d.sample_rate_hz),
                         move=int(0.5 * d.sample_rate_hz))
    write_recording(tmp_path / "r.csv", rec)
    rc, out, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "r.csv", "-o",
                           tmp_path / "c.json"], capfd)
    return b, S, rec, rc, out, err


def test_jig_free_auto_falls_back_to_what_the_poses_determine_and_the_cli_says_why(tmp_path, capfd):
    """Poses in 5 orientations (+-z, +-y, +x; a real hand-held session, sunsided/sensor-fusion's
    tilt-around-x, had 7 poses in 6 orientations, none along x): neither full (9
    orientations) nor gain (6) is determined, the offsets are.  The CLI writes the
    offset model and warns, naming both reasons and --jigfree-model; --jigfree-model full keeps
    the one-line refusal.  Poses that all face one way determine nothing: full's error."""
    from cli_run import run
    d = default_triad()
    F = d.gravity_mps2 * np.array([[0, 0, 1.0], [0, 1.0, 0], [0, 0, -1.0], [1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0]])
    b, S, rec, rc, out, err = calibrate_cli(tmp_path, capfd, F, 3)
    rng = np.random.default_rng(30)
    assert rc == 0, err
    assert "warning: fitted the jig-free 'offset' model (offsets only, no cross-axis terms), as the poses do " \
           "not determine 'full' or 'gain'." in err, err
    assert "'gain': jig-free 'gain' calibration of 3 channels needs at least 6 static poses in different " \
           "orientations, got 5 (6 poses, 5 orientations" in err, err
    assert "--jigfree-model" in err and "jigfree ('offset' model) calibration of 3 channels" in out
    cal = json.loads((tmp_path / "c.json").read_text())
    assert cal["fit"]["model"] == "offset" and cal["fit"]["gauge"].startswith("none needed")
    # the offsets within 4 sigma of the truth (the cross-axis terms, absent from the model, are small)
    got = np.array([c["offset_counts"] for c in cal["channels"]])
    sig = np.array([c["offset_sigma_counts"] for c in cal["channels"]])
    assert np.all(np.abs(got - b) < 4 * sig), (got - b, sig)
    rc, _, err, files = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "r.csv", "-o",
                             tmp_path / "c2.json", "--jigfree-model", "full"], capfd)
    assert rc == 2 and "needs at least 9 static poses in different orientations" in err
    assert not (tmp_path / "c2.json").exists()
    same = make_recording(d, b, S, np.repeat(F[:1], 3, 0) + np.array([[0, 0.01, 0]]) * np.arange(3)[:, None],
                          rng, labels=False, hold=int(2 * d.sample_rate_hz), move=int(0.5 * d.sample_rate_hz))
    with pytest.raises(InputError, match="jig-free 'full'") as e:
        calibrate_recordings(d, [same], "jigfree")
    # the default model falls back: the refusal says what fewer orientations determine (it had quoted
    # full's 9 alone, where 3 faces of a box already give the offsets)
    assert "the 'gain' model needs 6 orientations, the 'offset' model 3" in str(e.value)
    assert "the 'offset' model" not in err      # --jigfree-model full asked for that model alone
    with pytest.raises(InputError, match="unknown jig-free model 'affine'"):
        calibrate_recordings(d, [rec], "jigfree", jigfree_model="affine")


def test_a_sensitivity_far_from_the_device_file_s_is_warned_of():
    """A calibration 8 x or 0.5 x the device file's counts per m/s^2 (the device file of
    another chip, or --full-scale 4 for a +-2 g log) is warned of; within a few % it is not."""
    from accelcal.calibrate.checks import far_from_nominal
    d = default_triad()
    S = d.nominal_sensitivity()
    assert far_from_nominal(d, S * 1.03) is None
    for k in (8.17, 0.5):
        w = far_from_nominal(d, S * k)
        assert w is not None and f"{k:.3g} x the device file's" in w


def test_a_jig_free_fit_that_leaves_the_poses_beyond_their_noise_says_so(tmp_path, capfd):
    """chi2/dof far above 1 after a jig-free fit (a phone's 30 orientations: 44.9; the Xsens
    hand-held poses: 16.4) was printed without a word; it is warned of, naming what causes it.
    Here a cube the model lacks; the same poses without it give no warning."""
    from cli_run import run
    from accelcal.io.device import save_device
    d = default_triad()
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(12)
    b, S = draw_truth(d, rng)
    F = d.gravity_mps2 * fib_dirs(16)
    U = np.linalg.norm(S, axis=1) * d.gravity_mps2          # counts at 1 g along each axis
    for bend, warned in ((0.0, False), (0.002, True)):     # 0.2 % of the reading at 1 g
        rec = make_recording(d, b, S, F, rng, labels=False, hold=int(2 * d.sample_rate_hz),
                             move=int(0.5 * d.sample_rate_hz))
        u = rec.raw - b
        rec.raw = np.round(rec.raw + bend * u ** 3 / U ** 2).astype(np.int64)
        write_recording(tmp_path / "r.csv", rec)
        rc, _, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "r.csv", "-o",
                             tmp_path / "c.json"], capfd)
        assert rc == 0, err
        assert ("the poses scatter about the fit beyond their noise" in err) == warned, err


def test_a_channel_the_poses_hardly_turn_is_warned_of_with_the_poses_to_add():
    """A real LSM303 session (JustinPringle/TWLogger) whose 39 poses kept f along x within
    +-0.29 g was calibrated jig-free with an x offset of -195 +- 114 counts and nothing said;
    the warning names the channel, the span, the offset's sigma and the poses to add.  Six
    faces, or poses that turn the axis through 1.3 g, give none."""
    from accelcal.calibrate.checks import poorly_determined
    d = default_triad()
    g = d.gravity_mps2
    faces = g * np.vstack([np.eye(3), -np.eye(3)])
    assert poorly_determined(d, faces) is None
    a = np.radians(np.linspace(-17, 17, 7))
    F = g * np.vstack([np.stack([np.sin(a), np.zeros_like(a), -np.cos(a)], 1),
                       np.stack([np.sin(a), -np.cos(a), np.zeros_like(a)], 1)])
    w = poorly_determined(d, F, np.array([114.0, 25.0, 33.0]))
    assert w is not None and "channel 0's f along its axis spans -0.29..+0.29 g, offset +-114 counts" in w, w
    assert "add poses with f along +x and -x" in w and "channel 1" not in w and "channel 2" not in w
    # the same span with the offset known to 1 mg: nothing to warn of
    one_mg = 0.001 * d.gravity_mps2 * d.counts_per_mps2
    assert poorly_determined(d, F, np.array([1.0, 1.0, 1.0]) * one_mg) is None
    b = np.radians(40.0)
    wide = np.vstack([F, g * np.array([[np.sin(b), 0, -np.cos(b)], [-np.sin(b), 0, -np.cos(b)]])])
    assert poorly_determined(d, wide) is None                      # +-0.64 g along x: 1.29 g


def test_noise_coloured_within_the_poses_widens_their_sem_not_their_chi2():
    """A pose mean's noise is that of its own batches' means: white noise keeps the white sem
    (factor 1), noise with a slow component (an AR(1) of 40-sample memory, as a hand's tremor)
    widens it, and the jig-free chi2/dof of such poses, 5-10 x with the white sem, is near 1
    (real sessions: an LSM303's 8.8 -> 4.1, the Xsens hand-held poses' 16.4 -> 7.4)."""
    from accelcal.readings.noise import colour_factor, pose_colour
    d = default_triad()
    rng = np.random.default_rng(21)
    white = np.round(1000 + 3 * rng.standard_normal((4000, 3))).astype(np.int64)
    ivs = [np.arange(i, i + 400) for i in range(0, 4000, 400)]
    np.testing.assert_array_equal(colour_factor(pose_colour(white, ivs)), np.ones(3))
    b, S = draw_truth(d, rng)
    F = d.gravity_mps2 * fib_dirs(16)
    rec = make_recording(d, b, S, F, rng, labels=False, hold=int(4 * d.sample_rate_hz),
                         move=int(0.5 * d.sample_rate_hz))
    e = np.zeros((rec.n_samples, 3))
    a = np.exp(-1 / 40.0)
    z = rng.standard_normal((rec.n_samples, 3)) * 6.0 * np.sqrt(1 - a * a)
    for i in range(1, rec.n_samples):
        e[i] = a * e[i - 1] + z[i]
    rec.raw = np.round(rec.raw + e).astype(np.int64)
    ps = poses_from_recording(rec, d)
    assert np.all(ps.sem_scale() > 2.0), ps.sem_scale()
    fit = fit_static(d, ps, "full", jigfree=True)
    plain = fit_static(d, dataclasses.replace(ps, colour_r2=None), "full", jigfree=True)
    assert plain.chi2 / plain.dof > 5 and 0.4 < fit.chi2 / fit.dof < 2.5, (plain.chi2 / plain.dof, fit.chi2 / fit.dof)
    # the same poses one recording each (one file per jig pose): the colour is pooled over them alike
    one_each = PoseSet.concat([poses_from_recording(rec.select(np.arange(i["first"], i["last"] + 1)), d,
                                                    required=False) for i in ps.info])
    assert one_each.n_poses == ps.n_poses
    np.testing.assert_allclose(one_each.sem_scale(), ps.sem_scale(), rtol=0.05)


@pytest.mark.parametrize("device_name,method", [("triad", "full"), ("triad", "gain"), ("six", "full")])
def test_many_poses_solve_by_their_structure_with_the_dense_solution_and_covariance(monkeypatch, device_name,
                                                                                     method):
    """Jig-free fits of many poses take a sparse Jacobian and eliminate each pose for the
    covariance (O(P); the dense QR and SVD are O(P^3): 805 poses took 24 s and 651 MB).  At
    120 poses both ways give the same parameters, chi2, channel covariance and pose
    covariances; and 2,000 poses are fitted."""
    import importlib
    problem = importlib.import_module("accelcal.calibrate.problem")
    rng = np.random.default_rng(8)
    dev = default_triad() if device_name == "triad" else default_device()
    b, S = draw_truth(dev, rng)
    ps = poseset_from(dev, b, S, dev.gravity_mps2 * fib_dirs(120), rng, f_ref=False)
    fast = fit_static(dev, ps, method, jigfree=True)
    monkeypatch.setattr(problem, "STRUCTURED_MIN_POSES", 10 ** 9)
    slow = fit_static(dev, ps, method, jigfree=True)
    # the two solvers stop at their own tolerances: the same solution to a thousandth of its sigma
    sig_b = np.sqrt(slow.cov[:, 0, 0])
    sig_s = np.sqrt(np.maximum(np.diagonal(slow.cov[:, 1:4, 1:4], axis1=1, axis2=2), 1e-30))
    assert np.all(np.abs(fast.offsets - slow.offsets) < 1e-3 * sig_b), (fast.offsets - slow.offsets, sig_b)
    live = sig_s > 1e-12                      # gain: the cross-axis terms are not free
    assert np.all(np.abs(fast.sensitivity - slow.sensitivity)[live] < 1e-3 * sig_s[live])
    assert fast.chi2 == pytest.approx(slow.chi2, rel=1e-6) and fast.dof == slow.dof
    for a, c in ((fast.cov, slow.cov), (fast.pose_cov, slow.pose_cov)):   # in correlation units
        d = np.sqrt(np.maximum(np.diagonal(c, axis1=1, axis2=2), 1e-300))
        np.testing.assert_allclose(a / (d[:, :, None] * d[:, None, :]), c / (d[:, :, None] * d[:, None, :]),
                                   rtol=0, atol=1e-5)
    monkeypatch.undo()
    if device_name == "triad" and method == "full":
        big = poseset_from(dev, b, S, dev.gravity_mps2 * fib_dirs(2000), rng, f_ref=False)
        fit = fit_static(dev, big, "full", jigfree=True)
        sig = np.sqrt(fit.cov[:, 0, 0])
        assert np.all(np.abs(fit.offsets - b) < 5 * sig) and 0.8 < fit.chi2 / fit.dof < 1.2


def test_a_still_stretch_far_from_g_is_no_rest_unless_every_pose_agrees(tmp_path, capfd):
    """A rocket's coast (RocketPy's CATS log: 16.7 s still at 0.03-0.34 g) had been a static pose
    for calibrate and the |f| = g reference of a confident `bias_drift` diagnosis.  A still
    stretch whose |f| is beyond 0.5-2 g with the device file's scale is set aside (named, with
    its |f|) and is no reference for diagnose; poses that all read 4 g alike (a +-8 g log with a
    +-2 g device file) stay, for the sensitivity warning to name the scale."""
    from accelcal import diagnose
    d = default_triad()
    F = np.vstack([d.gravity_mps2 * fib_dirs(12), [[0.0, 0.3, 1.0]]])       # the last: 1.04 m/s^2, coasting
    b, S, rec, rc, out, err = calibrate_cli(tmp_path, capfd, F, 4)
    rng = np.random.default_rng(40)
    assert rc == 0, err
    assert "from 12 static poses" in out and "1 pose set aside (not at rest)" in out, out
    import re
    ratio = float(re.search(r"\|f\| = ([0-9.]+) g with the device file's scale", out).group(1))
    assert ratio < 0.5                          # the nominal offsets (up to 0.28 g) move it from 0.106
    coast = make_recording(d, b, S, F[-1:], rng, labels=False, hold=int(3 * d.sample_rate_hz), move=0)
    cal = calibrate_recordings(d, [rec], "jigfree")
    with pytest.raises(InputError, match=r"no reference to diagnose against.*reads \|f\| = 0\.[0-4][0-9]* g"):
        diagnose(d, cal, [coast])
    ps = poses_from_recording(rec, d)
    assert ps.n_poses == 12 and ps.set_aside[0]["reason"] == "not at rest"
    four = make_recording(d, b, S * 4.0, d.gravity_mps2 * fib_dirs(12), rng, labels=False,
                          hold=int(2 * d.sample_rate_hz), move=int(0.5 * d.sample_rate_hz), clip=False)
    big = dataclasses.replace(d, raw_min=-10 ** 7, raw_max=10 ** 7)
    assert poses_from_recording(four, big).n_poses == 12


def test_poses_one_per_file_that_agree_far_from_g_name_the_scale():
    """Six faces, one per file, read 9.81 g each (a header said g over readings in m/s^2): each
    file alone has one pose far from g, so every pose is set aside; the refusal says they agree,
    so the scale is off, rather than leaving a user to read "not at rest" six times."""
    rng = np.random.default_rng(44)
    d = default_triad()
    big = dataclasses.replace(d, raw_min=-10 ** 7, raw_max=10 ** 7)
    b, S = draw_truth(big, rng)
    recs = [make_recording(big, b, S * 9.80665, G * AXES6[k:k + 1], rng, labels=False,
                           hold=int(3 * d.sample_rate_hz), move=0, clip=False) for k in range(6)]
    with pytest.raises(InputError, match=r"6 set aside because their \|f\| is far from g.*they agree at \|f\| = "
                                         r"9\.[6-9][0-9]* g: the readings' scale is off by that factor"):
        calibrate_recordings(big, recs, "jigfree")


def test_parameters_a_method_holds_at_nominal_are_reported_as_not_fitted(tmp_path, capfd):
    """--method offset had written each sensitivity with a 1-sigma of 0 (read as exact
    knowledge) and offsets whose sigma takes the nominal gain as exact.  Now the sensitivities'
    sigma is null (left out), extra fit.not_fitted names them (as diagnose's not_determined),
    and offset_counts_per_percent_gain says how far a gain 1 % off moves each offset: from one
    pose along -z a chip 1 % above nominal on z leaves its offset off by exactly that (here
    -164 counts, 170 times its sigma); the summary says so.  'gain' names the direction it holds."""
    d = dataclasses.replace(default_triad(), noise_mps2=0.02)
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(8)
    b = d.zero_counts + np.array([300.0, -200.0, 500.0])
    S = d.nominal_sensitivity() * np.array([1.0, 1.0, 1.01])[:, None]          # z 1 % above nominal
    write_recording(tmp_path / "one.csv", make_recording(d, b, S, np.array([[0.0, 0.0, -G]]), rng, hold=2000,
                                                         move=0))
    rc, said, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "one.csv", "--method", "offset",
                            "-o", tmp_path / "c.json"], capfd)
    assert rc == 0, err
    js = json.loads((tmp_path / "c.json").read_text())
    assert all("sensitivity_sigma" not in ch for ch in js["channels"]), js["channels"]
    assert js["fit"]["not_fitted"] == {"sensitivity": [0, 1, 2]}, js["fit"]
    moves = np.array(js["fit"]["offset_counts_per_percent_gain"])
    assert np.allclose(moves, [0.0, 0.0, -0.01 * d.counts_per_mps2[2] * G]), moves
    got = np.array([ch["offset_counts"] for ch in js["channels"]])
    sig = np.array([ch["offset_sigma_counts"] for ch in js["channels"]])
    assert abs(got[2] - b[2]) > 50 * sig[2] and abs(got[2] - b[2] - moves[2]) < 4 * sig[2], (got - b, moves, sig)
    assert "Sensitivities held at the device file's nominal (not fitted, no sigma" in said, said
    assert "1 % above the nominal would leave the offsets off by +0, +0, -164 counts" in said, said
    cal = load_calibration(tmp_path / "c.json")
    assert cal.sensitivity_sigma is None
    F = G * AXES6
    write_recording(tmp_path / "six.csv", make_recording(d, b, S, F, rng, hold=200))
    rc, said, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "six.csv", "--method", "gain",
                            "-o", tmp_path / "g.json"], capfd)
    js = json.loads((tmp_path / "g.json").read_text())
    assert rc == 0 and js["fit"]["not_fitted"] == {"sensitivity_direction": [0, 1, 2]}, (err, js["fit"])
    assert "offset_counts_per_percent_gain" not in js["fit"] and "Sensitivities held" not in said
    # the components across each axis are held at 0: null sigma (they had been 0, read as exact); the
    # component along the axis keeps its sigma
    for i, ch in enumerate(js["channels"]):
        assert [s is None for s in ch["sensitivity_sigma"]] == [c != i for c in range(3)], ch
        assert ch["sensitivity_sigma"][i] > 0
    assert "Sensitivity directions held along the device file's nominal axes (not fitted" in said, said
    gcal = load_calibration(tmp_path / "g.json")
    assert np.array_equal(np.isnan(gcal.sensitivity_sigma), ~np.eye(3, dtype=bool))
    assert np.all(np.isfinite(gain_sigma(gcal.sensitivity, gcal.sensitivity_sigma)))
