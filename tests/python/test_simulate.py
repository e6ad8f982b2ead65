"""Simulator: exact kinematics of every motion, every effect doing what the
registry says, reproducibility, the CSV round trip and spec errors."""

import math
import time

import numpy as np
import pytest
from hypothesis import given, strategies as st
from scipy.signal import lsim, tf2ss

from accelcal.io.device import GRAVITY, Device, default_device, default_triad, pendulum_device
from accelcal.effects import EFFECT_NAMES, EFFECTS, parse_effect_spec, parse_effect_specs
from accelcal.sensor import lowpass_butterworth2, lowpass_first_order, make_context, rotation_matrix, true_state
from accelcal.errors import AccelcalError
from accelcal.model import predict_counts, specific_force_at
from accelcal.motions import MOTION_NAMES, MOTIONS, Trajectory, parse_motion_spec, pose_directions
from accelcal.io.recording import read_recording, write_recording
from accelcal.simulate import SEED_TABLE1, run_simulation, seed_prototype_truth, simulate

DEV = default_device()
G = DEV.gravity_mps2
EZ = np.array([0.0, 0.0, 1.0])


def _skew_inv(M):
    return 0.5 * np.stack([M[..., 2, 1] - M[..., 1, 2], M[..., 0, 2] - M[..., 2, 0], M[..., 1, 0] - M[..., 0, 1]], -1)


def _quiet(dev=DEV):
    """The same device without noise (exact comparisons of readings)."""
    return Device(name=dev.name, sample_rate_hz=dev.sample_rate_hz, gravity_mps2=dev.gravity_mps2,
                  raw_min=dev.raw_min, raw_max=dev.raw_max, positions=dev.positions, axes=dev.axes,
                  counts_per_mps2=dev.counts_per_mps2, zero_counts=dev.zero_counts, noise_mps2=0.0)


# ---------------------------------------------------------------------------
# kinematics
# ---------------------------------------------------------------------------


@pytest.mark.parametrize("name", MOTION_NAMES)
def test_motion_kinematics_exactly_consistent(name):
    """omega from dC/dt, alpha = d omega/dt, f = C^T (d2p/dt2 + g z), C orthonormal,
    and the sampled arrays equal the evaluator's values."""
    tr = MOTIONS[name](DEV, np.random.default_rng(7))
    ev = tr.evaluator
    ts = np.random.default_rng(1).uniform(tr.t[0], tr.t[-1], 300)
    h = 1e-5
    km, k0, kp = ev(ts - h), ev(ts), ev(ts + h)
    w_num = _skew_inv(np.einsum("nji,njk->nik", k0.attitude, (kp.attitude - km.attitude) / (2 * h)))
    a_num = (kp.omega - km.omega) / (2 * h)
    wscale = 1.0 + np.abs(k0.omega).max()
    ascale = 1.0 + np.abs(k0.alpha).max()
    assert np.abs(w_num - k0.omega).max() < 1e-7 * wscale
    assert np.abs(a_num - k0.alpha).max() < 1e-6 * ascale
    H = 1e-3
    kP, kM = ev(ts + H), ev(ts - H)
    acc = (kP.position - 2 * k0.position + kM.position) / H**2
    f_num = np.einsum("nji,nj->ni", k0.attitude, acc + G * EZ)
    assert np.abs(f_num - k0.f).max() < 2e-3  # O(H^2) and a jerk step at segment ends
    C = tr.attitude
    assert np.abs(np.einsum("nji,njk->nik", C, C) - np.eye(3)).max() < 1e-12
    assert np.allclose(np.linalg.det(C), 1.0, atol=1e-12)
    k = ev(tr.t)
    for a, b in ((k.f, tr.f), (k.omega, tr.omega), (k.alpha, tr.alpha), (k.attitude, tr.attitude)):
        assert np.array_equal(a, b)
    assert not np.any(np.signbit(tr.alpha) & (tr.alpha == 0))  # no "-0" in the CSV
    # gravity part of f: at rest (pose >= 0) f is exactly C^T g z
    rest = tr.pose >= 0
    if rest.any():
        assert np.allclose(tr.f[rest], np.einsum("nji,j->ni", C[rest], G * EZ), atol=1e-12)
        assert np.all(tr.omega[rest] == 0) and np.all(tr.alpha[rest] == 0)
    assert np.all(np.diff(tr.t) > 0) and tr.t[0] == 0.0
    assert np.all(tr.temp_c == 25.0)


@pytest.mark.parametrize("preset,count", [("4", 4), ("6", 6), ("18", 18), ("24", 24), ("26", 26)])
def test_static_pose_sets(preset, count):
    tr = MOTIONS["static_poses"](DEV, None, poses=preset, samples_per_pose=10)
    assert tr.n_samples == 10 * count
    assert np.allclose(np.linalg.norm(tr.f, axis=1), G, rtol=1e-14)
    assert np.all(tr.omega == 0) and np.all(tr.alpha == 0)
    labels, counts = np.unique(tr.pose, return_counts=True)
    assert labels.tolist() == list(range(count)) and np.all(counts == 10)
    d, _ = pose_directions(preset)
    f_pose = np.array([tr.f[tr.pose == k][0] for k in range(count)])
    assert np.allclose(f_pose, G * d, atol=1e-12)
    # the jig moves unrecorded between poses: one pose per dwell period
    assert np.allclose(tr.t[10] - tr.t[0], 10 / DEV.sample_rate_hz + 1.0)


def test_seed_four_poses_and_listed_directions():
    tr = MOTIONS["static_poses"](DEV, None, poses="4", samples_per_pose=3)
    f = tr.f[::3]
    assert np.allclose(f, G * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]]), atol=1e-12)
    m, given = parse_motion_spec("static_poses:poses=[x,-y,[1,0,1]],samples_per_pose=2,dwell_s=5")
    tr = m(DEV, None, **given)
    assert np.allclose(tr.f[::2], G * np.array([[1, 0, 0], [0, -1, 0], [2**-0.5, 0, 2**-0.5]]), atol=1e-12)
    assert np.allclose(tr.t[::2], [0, 5, 10])


def test_random_and_handheld_poses_are_static_and_varied():
    tr = MOTIONS["handheld"](DEV, np.random.default_rng(3), n_poses=12)
    rest = tr.pose >= 0
    assert set(np.unique(tr.pose[rest])) == set(range(13))
    assert np.allclose(np.linalg.norm(tr.f[rest], axis=1), G, rtol=1e-13)
    assert np.all(tr.f[tr.pose == 0] @ EZ > G * (1 - 1e-12))  # the first rest: z up
    moving = ~rest
    assert np.abs(tr.omega[moving]).max() > 0.3  # real motion between poses
    ups = np.array([tr.f[tr.pose == k].mean(0) / G for k in range(13)])
    assert np.linalg.matrix_rank(ups, tol=1e-3) == 3
    tr2 = MOTIONS["random_poses"](DEV, np.random.default_rng(3), n_poses=8, samples_per_pose=5)
    assert np.allclose(np.linalg.norm(tr2.f, axis=1), G)
    assert len(np.unique(np.round(tr2.f, 6), axis=0)) == 8


def test_pendulum_theta_convention():
    """Contract: body z up at theta = 0, gravity in body axes g(-sin, 0, cos),
    omega and alpha about +y right-handed; theta = center + A cos(2 pi f t)."""
    tr = MOTIONS["pendulum"](pendulum_device(), None, amplitude_deg=40, freq_hz=0.5, center_deg=10)
    th = math.radians(10) + math.radians(40) * np.cos(math.pi * tr.t)
    assert np.allclose(tr.f, G * np.column_stack([-np.sin(th), 0 * th, np.cos(th)]), atol=1e-12)
    c, s = np.cos(th), np.sin(th)
    Ry = np.stack([np.stack([c, 0 * c, s], -1), np.stack([0 * c, 1 + 0 * c, 0 * c], -1),
                   np.stack([-s, 0 * c, c], -1)], -2)
    assert np.allclose(tr.attitude, Ry, atol=1e-12)
    thd = -math.radians(40) * math.pi * np.sin(math.pi * tr.t)
    thdd = -math.radians(40) * math.pi**2 * np.cos(math.pi * tr.t)
    assert np.allclose(tr.omega, np.column_stack([0 * th, thd, 0 * th]), atol=1e-12)
    assert np.allclose(tr.alpha, np.column_stack([0 * th, thdd, 0 * th]), atol=1e-12)
    # the seed's two-triad relations, in the contract's right-handed convention:
    # f_x(r) = -r thd^2 - g sin(th); f_z(r) = g cos(th) - r thdd
    r1 = 0.1
    fa = specific_force_at(tr.f, tr.alpha, tr.omega, np.array([r1, 0, 0]))
    assert np.allclose(fa[:, 0], -r1 * thd**2 - G * s, atol=1e-12)
    assert np.allclose(fa[:, 2], G * c - r1 * thdd, atol=1e-12)
    # damping: amplitude decays by e over decay_s
    tr = MOTIONS["pendulum"](pendulum_device(), None, decay_s=4.0, duration_s=10)
    i = np.flatnonzero(np.isclose(tr.t, 4.0))[0]
    assert math.isclose(math.atan2(-tr.f[i, 0], tr.f[i, 2]), math.radians(40) * math.exp(-1) * math.cos(2 * math.pi),
                        rel_tol=1e-9)


def test_rate_table_amplitude_and_off_axis_origin():
    tr = MOTIONS["rate_table"](DEV, None, axis="z", freq_hz=2, amplitude_deg=10, duration_s=3)
    w = 2 * math.pi * 2
    assert math.isclose(np.abs(tr.omega[:, 2]).max(), math.radians(10) * w, rel_tol=1e-3)
    assert np.all(tr.omega[:, :2] == 0)
    assert np.allclose(tr.f, G * EZ, atol=1e-12)  # vertical axis, origin on it: gravity only
    # off-axis origin: the body point on the axis feels gravity only
    c = np.array([0.03, -0.02, 0.01])
    tr = MOTIONS["rate_table"](DEV, None, axis="x", mount="z", center_m=c, duration_s=2, rest_s=0.5, ramp_s=0.5)
    fc = specific_force_at(tr.f, tr.alpha, tr.omega, c)
    assert np.allclose(fc, np.einsum("nji,j->ni", tr.attitude, G * EZ), atol=1e-12)
    assert np.all(tr.pose[tr.t < 0.5] == 0) and np.all(tr.pose[tr.t >= 0.5] == -1)
    assert np.all(tr.omega[tr.t <= 0.5] == 0)


def test_lane_change_returns_to_the_lane():
    dev = default_triad()
    tr = MOTIONS["lane_change"](dev, None)
    ev = tr.evaluator
    end = ev(tr.t[-1:])
    assert abs(end.position[0, 1]) < 1e-12 and abs(end.omega[0, 2]) < 1e-12
    assert np.allclose(end.attitude[0], np.eye(3), atol=1e-12)
    mid = tr.position[:, 1].max()
    assert math.isclose(mid, 3.5, rel_tol=1e-9)
    # integrate the world acceleration from the recorded f: no lateral drift end to end
    t = np.linspace(0, tr.t[-1], 200001)
    k = ev(t)
    a = np.einsum("nij,nj->ni", k.attitude, k.f) - G * EZ
    dt = t[1] - t[0]
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:, 1] + a[:-1, 1]) * dt)])
    y = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])
    assert abs(v[-1]) < 1e-6 and abs(y[-1]) < 1e-5
    heading = np.sum(0.5 * (k.omega[1:, 2] + k.omega[:-1, 2]) * dt)
    assert abs(heading) < 1e-9
    assert np.all(np.abs(a[:, 2]) < 1e-12) and np.all(tr.omega[:, :2] == 0)
    assert 2.0 < np.abs(a[:, 1]).max() < 12.0  # a real manoeuvre, under 1.2 g


def test_linear_actuator_stop_to_stop():
    tr = MOTIONS["linear_actuator"](DEV, None, axis="y", distance_m=0.3, travel_s=1.5, rest_s=1.0, strokes=2,
                                    tilt_deg=5, tilt_axis="x", profile="cycloid")
    C0 = rotation_matrix(np.array([math.radians(5), 0, 0]))
    assert np.allclose(tr.attitude, C0, atol=1e-15)
    assert np.all(tr.omega == 0) and np.all(tr.alpha == 0)
    # labels: rest 0, move, rest 1, move, rest 2
    assert [k for k in np.unique(tr.pose)] == [-1, 0, 1, 2]
    p1 = tr.position[tr.pose == 1]
    assert np.allclose(p1, C0 @ np.array([0, 0.3, 0]), atol=1e-12)
    assert np.allclose(tr.position[tr.pose == 2], 0, atol=1e-12)
    # integrating the body-axis acceleration (f minus the rail's gravity) gives the travel
    a = tr.f - C0.T @ (G * EZ)
    assert np.allclose(a[:, [0, 2]], 0, atol=1e-12)
    ev = tr.evaluator
    t = np.linspace(0, 2.5, 100001)
    ay = ev(t).f[:, 1] - (C0.T @ (G * EZ))[1]
    dt = t[1] - t[0]
    v = np.concatenate([[0.0], np.cumsum(0.5 * (ay[1:] + ay[:-1]) * dt)])
    x = np.sum(0.5 * (v[1:] + v[:-1]) * dt)
    assert abs(v[-1]) < 1e-8 and abs(x - 0.3) < 1e-7


def test_temperature_profiles():
    tr = MOTIONS["pendulum"](DEV, None, duration_s=10, temp_profile="ramp", temp_c=20, temp_end_c=40)
    assert tr.temp_c[0] == 20 and math.isclose(tr.temp_c[-1], 40) and np.all(np.diff(tr.temp_c) > 0)
    tr = MOTIONS["static_poses"](DEV, None, temp_profile="sine", temp_c=30, temp_amplitude_c=2, temp_period_s=4)
    assert np.allclose(tr.temp_c, 30 + 2 * np.sin(2 * math.pi * tr.t / 4))


# ---------------------------------------------------------------------------
# the reading model
# ---------------------------------------------------------------------------


def test_clean_readings_follow_the_contract_model():
    cal = seed_prototype_truth(DEV, 5)
    sim = run_simulation(DEV, "random_6dof", seed=2, calibration=cal, duration_s=5)
    tr = sim.trajectory
    expect = predict_counts(cal.offsets, cal.sensitivity, DEV.positions, tr.f, tr.alpha, tr.omega)
    assert np.allclose(sim.clean_counts, expect, rtol=0, atol=1e-9)
    raw = sim.recording.raw
    resid = raw - expect
    noise = DEV.noise_counts()
    assert np.all(np.abs(resid.std(axis=0) / np.sqrt(noise**2 + 1 / 12) - 1) < 0.1)
    assert np.all(raw >= DEV.raw_min) and np.all(raw <= DEV.raw_max)


def test_reference_columns_exact_and_clipping():
    sim = run_simulation(DEV, "rate_table", seed=0, duration_s=2)
    rec, tr = sim.recording, sim.trajectory
    assert np.array_equal(rec.f, tr.f) and np.array_equal(rec.w, tr.omega) and np.array_equal(rec.dw, tr.alpha)
    assert np.array_equal(rec.temp_c, tr.temp_c) and np.array_equal(rec.pose, tr.pose)
    # a hard manoeuvre on a narrow ADC clips at [raw_min, raw_max]
    dev = Device(name="narrow", sample_rate_hz=60, gravity_mps2=G, raw_min=4000, raw_max=6000,
                 positions=DEV.positions, axes=DEV.axes, counts_per_mps2=DEV.counts_per_mps2,
                 zero_counts=DEV.zero_counts, noise_mps2=0.02)
    rec = simulate(dev, "random_6dof", seed=1, duration_s=5)
    assert rec.raw.min() == 4000 and rec.raw.max() == 6000
    rec = simulate(DEV, "static_poses", reference=False)
    assert not rec.has_f() and not rec.has_pose() and not rec.has_temp()


# ---------------------------------------------------------------------------
# effects: each changes the readings as documented
# ---------------------------------------------------------------------------


def _pair(motion, effect, dev=DEV, seed=4, **kw):
    a = run_simulation(dev, motion, seed=seed, **kw)
    b = run_simulation(dev, motion, effects=[effect], seed=seed, **kw)
    return a, b


def test_offset_shifts_by_exactly_db():
    a, b = _pair("static_poses", "offset:db=[10,-20,0,3,0,7]")
    d = b.recording.raw - a.recording.raw
    assert np.all(d == np.array([10, -20, 0, 3, 0, 7]))
    a, b = _pair("handheld", "offset:db=25,channel=2", n_poses=3)
    d = b.recording.raw - a.recording.raw
    assert np.all(d[:, 2] == 25) and np.all(d[:, [0, 1, 3, 4, 5]] == 0)
    # default: 1 % of g in counts
    a, b = _pair("static_poses", "offset")
    assert np.allclose(b.clean_counts - a.clean_counts, 0.01 * 1250.0)


def test_gain_scales_the_sensed_part():
    a, b = _pair("random_6dof", "gain:scale=0.02,channel=[1,4]", duration_s=3)
    sensed = a.clean_counts - DEV.nominal_offsets()
    expect = np.zeros_like(sensed)
    expect[:, [1, 4]] = 0.02 * sensed[:, [1, 4]]
    assert np.allclose(b.clean_counts - a.clean_counts, expect, atol=1e-9)
    assert np.allclose(np.linalg.norm(b.state.sensitivity[1]), 1.02 * DEV.counts_per_mps2[1])


def test_misalignment_tilts_the_axis():
    a, b = _pair("static_poses", "misalignment:angle_deg=0.8")
    s0, s1 = a.state.sensitivity, b.state.sensitivity
    assert np.allclose(np.linalg.norm(s1, axis=1), np.linalg.norm(s0, axis=1))
    ang = np.degrees(np.arccos(np.sum(s0 * s1, 1) / np.linalg.norm(s0, axis=1) / np.linalg.norm(s1, axis=1)))
    assert np.allclose(ang, 0.8, atol=1e-9)
    tr = a.trajectory
    assert np.allclose(b.clean_counts, DEV.nominal_offsets() + tr.f @ s1.T, atol=1e-9)
    # toward a direction: channel 1 (along z) tilts toward +x
    _, c = _pair("static_poses", "misalignment:angle_deg=1,toward=x,channel=1")
    s = c.state.sensitivity[1] / np.linalg.norm(c.state.sensitivity[1])
    assert np.allclose(s, [math.sin(math.radians(1)), 0, math.cos(math.radians(1))], atol=1e-12)


def test_position_error_shows_only_under_rotation():
    a, b = _pair("static_poses", "position_error:mm=2")
    assert np.array_equal(a.recording.raw, b.recording.raw)
    a, b = _pair("rate_table", "position_error:mm=2,direction=x", duration_s=2)
    dr = b.effects["position_error"]["dr"]
    assert np.allclose(dr, [[0.002, 0, 0]] * 6)
    tr = a.trajectory
    s = DEV.nominal_sensitivity()
    expect = np.stack([s[i] @ (np.cross(tr.alpha, dr[i]) + np.cross(tr.omega, np.cross(tr.omega, dr[i]))).T
                       for i in range(6)], axis=1)
    assert np.allclose(b.clean_counts - a.clean_counts, expect, atol=1e-9)
    assert np.abs(expect).max() > 5  # visible on the seed's 2 Hz yaw


def test_centripetal_scale_withholds_the_term():
    # about body x: the seed layout's channels see the centripetal term (not under yaw)
    a, b = _pair("rate_table", "centripetal:scale=0", duration_s=2, axis="x", mount="z")
    tr = a.trajectory
    no_c = predict_counts(DEV.nominal_offsets(), DEV.nominal_sensitivity(), DEV.positions, tr.f, tr.alpha, None)
    assert np.allclose(b.clean_counts, no_c, atol=1e-9)
    assert np.abs(a.clean_counts - no_c).max() > 10
    # default scale 1: the physical truth, nothing changes
    a, b = _pair("rate_table", "centripetal", duration_s=1)
    assert np.array_equal(a.recording.raw, b.recording.raw)


def test_time_skew_samples_the_motion_at_t_plus_tau():
    a, b = _pair("random_6dof", "time_skew:tau=0.004,sequential=1", duration_s=4)
    tr = a.trajectory
    S, r = DEV.nominal_sensitivity(), DEV.positions
    for i in range(6):
        k = tr.evaluator(tr.t + 0.004 * i)
        fi = specific_force_at(k.f, k.alpha, k.omega, r[i])
        assert np.allclose(b.clean_counts[:, i], DEV.zero_counts[i] + fi @ S[i], atol=1e-9)
    assert np.array_equal(b.clean_counts[:, 0], a.clean_counts[:, 0])
    # without an evaluator (a recording's references) the truth is interpolated
    traj = Trajectory.from_recording(a.recording, G)
    traj.f, traj.omega, traj.alpha = tr.f, tr.omega, tr.alpha  # exact references
    ctx = make_context(DEV, traj)
    p = EFFECTS["time_skew"].identity(ctx)
    p["tau"] = np.full(6, 0.004)
    interp = EFFECTS["time_skew"].apply(ctx, p)
    exact = EFFECTS["time_skew"].apply(make_context(DEV, tr), p)
    assert np.abs(interp - exact)[5:-5].max() < 0.5  # counts, cubic spline at 60 Hz


def test_lowpass_is_the_exact_first_order_response():
    w = 2 * math.pi * 3.0
    # ramp input, uneven spacing: exact for inputs linear between samples
    t = np.cumsum(np.random.default_rng(0).uniform(0.005, 0.05, 400))
    t -= t[0]
    x = 7.0 * t
    y = lowpass_first_order(t, x[:, None], [3.0])[:, 0]
    assert np.allclose(y, 7.0 * (t - (1 - np.exp(-w * t)) / w), rtol=1e-12, atol=1e-15)
    # sinusoid steady state: gain 1/sqrt(1 + (f/fc)^2), phase -atan(f/fc)
    t = np.arange(20000) / 2000.0
    f = 2.0
    y = lowpass_first_order(t, np.sin(2 * math.pi * f * t)[:, None], [3.0])[:, 0]
    g = 1 / math.sqrt(1 + (f / 3.0) ** 2)
    ph = -math.atan(f / 3.0)
    tail = t > 5
    assert np.allclose(y[tail], g * np.sin(2 * math.pi * f * t[tail] + ph), atol=1e-6)
    # long records and big gaps (blockwise closed form) agree with the recursion
    t = np.concatenate([np.arange(3000) / 60.0, 100 + np.arange(3000) / 60.0])
    x = np.random.default_rng(1).standard_normal((t.size, 2)) + 5000
    y = lowpass_first_order(t, x, [20.0, math.inf])
    ref = np.empty(t.size)
    ref[0] = x[0, 0]
    wc = 2 * math.pi * 20.0
    for k in range(1, t.size):
        h = t[k] - t[k - 1]
        a = math.exp(-wc * h)
        beta = (1 - a) / (wc * h)
        ref[k] = a * ref[k - 1] + (beta - a) * x[k - 1, 0] + (1 - beta) * x[k, 0]
    assert np.allclose(y[:, 0], ref, rtol=1e-12)
    assert np.array_equal(y[:, 1], x[:, 1])


@pytest.mark.parametrize("order", [1, 2])
def test_bandwidth_attenuates_the_rate_table_signal(order):
    """The rate table's 2 Hz tone through a 4 Hz low-pass: 1 / sqrt(1 + (f / fc)^(2 order))."""
    a, b = _pair("rate_table", f"bandwidth:fc_hz=4,order={order},channel=0", duration_s=6)
    ac = a.clean_counts[:, 0] - a.clean_counts[:, 0].mean()
    bc = b.clean_counts[:, 0] - b.clean_counts[:, 0].mean()
    tail = a.trajectory.t > 2
    ratio = bc[tail].std() / ac[tail].std()
    assert abs(ratio - 1 / math.sqrt(1 + (2 / 4) ** (2 * order))) < 0.03
    assert np.array_equal(a.clean_counts[:, 1:], b.clean_counts[:, 1:])


def test_second_order_bandwidth_is_the_analog_butterworth():
    """lowpass_butterworth2 against scipy.signal.lsim of the analog Butterworth from steady
    state: uniform sampling (the input linear between samples is exact) and random spacing
    (against lsim on a fine grid of the same piecewise-linear input)."""
    w = 2 * math.pi * 5.0
    A, B, C, D = tf2ss([w * w], [1.0, math.sqrt(2) * w, w * w])
    rng = np.random.default_rng(3)
    for t in (np.arange(0.0, 3.0, 0.01), np.sort(rng.uniform(0.0, 3.0, 400))):
        x = np.sin(2 * math.pi * 1.3 * t) + 0.3 * t + 1.0
        y = lowpass_butterworth2(t, np.stack([x, x], axis=1), [5.0, math.inf])
        tf = np.linspace(t[0], t[-1], 200_001)
        xf = np.interp(tf, t, x)
        _, yf, _ = lsim((A, B, C, D), xf, tf - tf[0], X0=np.linalg.solve(A, -B[:, 0] * xf[0]), interp=True)
        assert np.max(np.abs(y[:, 0] - np.interp(t, tf, yf))) < 1e-6
        assert np.array_equal(y[:, 1], x)


def test_nonlinearity_adds_k2_input_squared():
    a, b = _pair("static_poses", "nonlinearity:k2=0.1")
    x = (a.clean_counts - DEV.nominal_offsets()) / DEV.counts_per_mps2
    assert np.allclose(b.clean_counts - a.clean_counts, 0.1 * x * x, atol=1e-9)
    a, b = _pair("static_poses", "nonlinearity")  # default: 0.5 % of the reading at 1 g
    d = b.clean_counts - a.clean_counts
    assert math.isclose(d.max(), 0.005 * 1250, rel_tol=1e-9)
    a, b = _pair("static_poses", "nonlinearity:k2=0,k3=0.01")       # the optional cube
    assert np.allclose(b.clean_counts - a.clean_counts, 0.01 * x ** 3, atol=1e-9)


def test_temperature_effects():
    kw = dict(temp_profile="ramp", temp_c=15, temp_end_c=45)
    a, b = _pair("static_poses", "temperature_offset:coeff=2,t_ref=25", **kw)
    T = a.trajectory.temp_c
    assert np.allclose(b.clean_counts - a.clean_counts, 2 * (T - 25)[:, None], atol=1e-9)
    a, b = _pair("static_poses", "temperature_gain:coeff=1e-3", **kw)
    sensed = a.clean_counts - DEV.nominal_offsets()
    assert np.allclose(b.clean_counts - a.clean_counts, 1e-3 * (T - 25)[:, None] * sensed, atol=1e-9)
    # constant 25 degC: the effect cannot show
    a, b = _pair("static_poses", "temperature_offset")
    assert np.array_equal(a.recording.raw, b.recording.raw)


def test_bias_drift_ramp_and_random_walk():
    a, b = _pair("handheld", "bias_drift:rate=0.5", n_poses=4)
    t = a.trajectory.t
    assert np.allclose(b.clean_counts - a.clean_counts, 0.5 * (t - t[0])[:, None], atol=1e-9)
    a, b = _pair("handheld", "bias_drift:rate=0,rw=3", n_poses=20)
    d = b.clean_counts - a.clean_counts
    assert np.all(d[0] == 0)
    inc = np.diff(d, axis=0) / np.sqrt(np.diff(a.trajectory.t))[:, None]
    assert abs(inc.std() / 3.0 - 1) < 0.05
    assert not np.allclose(d[:, 0], d[:, 1])  # independent per channel


def test_saturation_clips_inside_the_adc_range():
    a, b = _pair("random_6dof", "saturation:lo=4000,hi=6000,channel=[0,1]", duration_s=10)
    raw_a, raw_b = a.recording.raw, b.recording.raw
    assert raw_b[:, :2].min() == 4000 and raw_b[:, :2].max() == 6000
    assert np.array_equal(raw_b[:, :2], np.clip(raw_a[:, :2], 4000, 6000))
    assert np.array_equal(raw_b[:, 2:], raw_a[:, 2:])
    # default: +-1.5 g around the offset
    p = b.effects["saturation"]
    assert np.all(np.isinf(p["lo"][2:]))
    _, c = _pair("random_6dof", "saturation", duration_s=10)
    lo, hi = c.effects["saturation"]["lo"], c.effects["saturation"]["hi"]
    assert np.allclose(hi - DEV.zero_counts, 1.5 * 1250)
    assert np.all(c.recording.raw >= np.floor(lo)) and np.all(c.recording.raw <= np.ceil(hi))


def test_quantization_steps():
    a, b = _pair("random_6dof", "quantization:step=16", duration_s=5)
    assert np.all(b.recording.raw % 16 == 0)
    assert np.abs(b.recording.raw - a.recording.raw).max() <= 8 + 1
    _, c = _pair("static_poses", "quantization:step=4,channel=3")
    assert np.all(c.recording.raw[:, 3] % 4 == 0) and np.any(c.recording.raw[:, 0] % 4 != 0)


def test_pose_error_changes_only_the_stated_reference():
    a, b = _pair("static_poses", "pose_error:angle_deg=1.5", seed=9)
    assert np.array_equal(a.recording.raw, b.recording.raw)
    fa, fb = a.recording.f, b.recording.f
    cos = np.sum(fa * fb, 1) / np.linalg.norm(fa, axis=1) / np.linalg.norm(fb, axis=1)
    assert np.allclose(np.degrees(np.arccos(np.clip(cos, -1, 1))), 1.5, atol=1e-6)
    assert np.allclose(np.linalg.norm(fb, axis=1), G)
    assert np.array_equal(a.recording.w, b.recording.w)
    # the diagnosis side: the recorded (stated) reference, rotated back by the
    # true pose rotations, predicts the readings again
    traj = Trajectory.from_recording(b.recording, G)
    ctx = make_context(DEV, traj)
    p = b.effects["pose_error"]
    assert np.allclose(EFFECTS["pose_error"].apply(ctx, p), a.clean_counts, atol=1e-9)
    assert np.abs(ctx.counts - a.clean_counts).max() > 5
    # a jig file with f and pose only: static samples have omega = alpha = 0
    rec = b.recording
    jig = type(rec)(t=rec.t, raw=rec.raw, f=rec.f, pose=rec.pose)
    traj = Trajectory.from_recording(jig, G)
    assert np.all(traj.omega == 0) and np.all(traj.alpha == 0)
    assert np.allclose(make_context(DEV, traj).counts, ctx.counts)


@pytest.mark.parametrize("name", EFFECT_NAMES)
def test_registry_apply_matches_the_simulator(name):
    """Effect.apply on the nominal context equals the simulator's readings with
    that effect alone (so the diagnosis fits what the simulator does), and the
    identity parameters change nothing."""
    motion = "static_poses" if name == "pose_error" else "random_6dof"
    kw = {} if name == "pose_error" else dict(duration_s=3, temp_profile="ramp")
    dev = _quiet()
    spec = {"saturation": "saturation:limit_g=0.8", "quantization": "quantization:step=5"}.get(name, name)
    a, b = _pair(motion, spec, dev=dev, **kw)
    eff = EFFECTS[name]
    # pose_error: the diagnosis sees the stated reference, i.e. the recording's
    truth = Trajectory.from_recording(b.recording, G) if name == "pose_error" else a.trajectory
    ctx = make_context(dev, truth)
    assert np.allclose(eff.apply(ctx, eff.identity(ctx)), ctx.counts, atol=1e-9)
    p = b.effects[name]
    got = eff.apply(ctx, p)
    if name == "pose_error":
        assert np.allclose(got, a.clean_counts, atol=1e-9)
        assert np.abs(ctx.counts - a.clean_counts).max() > 1
    else:
        assert np.allclose(got, b.clean_counts if eff.stage != "adc" else eff.apply_signal(a.clean_counts, p, ctx),
                           atol=1e-8)
        changed = np.abs(np.rint(got) - np.rint(ctx.counts)).max()
        if name != "centripetal":
            assert changed > 0, f"{name} changed nothing"
    # every spec parameter is documented with a unit
    for prm in eff.params:
        assert prm.doc and prm.unit
    assert {f.name for f in eff.fit} >= set(p)


# ---------------------------------------------------------------------------
# reproducibility, files, truth, errors, speed
# ---------------------------------------------------------------------------


def test_reproducible_from_seed():
    effects = ["misalignment", "bias_drift:rw=2", "pose_error"]
    r1 = simulate(DEV, "random_poses", effects=effects, seed=11)
    r2 = simulate(DEV, "random_poses", effects=effects, seed=11)
    r3 = simulate(DEV, "random_poses", effects=effects, seed=12)
    assert r1 == r2
    assert not np.array_equal(r1.raw, r3.raw) and not np.allclose(r1.f, r3.f)
    # adding an effect leaves the motion, the noise and the other effects' draws alone
    a = run_simulation(DEV, "random_poses", effects=["misalignment"], seed=11)
    b = run_simulation(DEV, "random_poses", effects=["misalignment", "offset:db=3"], seed=11)
    assert np.array_equal(a.trajectory.f, b.trajectory.f)
    assert np.array_equal(a.effects["misalignment"]["rot"], b.effects["misalignment"]["rot"])
    assert np.array_equal(b.recording.raw - a.recording.raw, np.full_like(a.recording.raw, 3))
    assert r1.metadata["seed"] == "11" and r1.metadata["motion"] == "random_poses"
    assert r1.metadata["effects"] == "misalignment; bias_drift:rw=2; pose_error"


def test_csv_round_trip(tmp_path):
    sim = run_simulation(DEV, "handheld", effects=["gain:scale=0.01,channel=2", "quantization:step=2"], seed=3,
                         n_poses=3, temp_profile="ramp")
    rec = sim.recording
    p = tmp_path / "rec.csv"
    write_recording(p, rec)
    back = read_recording(p, DEV.n_channels)
    assert np.array_equal(back.t, rec.t) and np.array_equal(back.raw, rec.raw)
    assert np.array_equal(back.pose, rec.pose)
    for k in ("f", "w", "dw", "temp_c"):
        assert np.allclose(getattr(back, k), getattr(rec, k), rtol=1e-8, atol=1e-12)
    assert back.metadata == rec.metadata
    text = p.read_text().splitlines()
    assert "# motion: handheld:n_poses=3,temp_profile=ramp" in text
    assert "# effects: gain:scale=0.01,channel=[2]; quantization:step=2" in text
    assert "# seed: 3" in text


def test_given_calibration_is_the_truth():
    rng = np.random.default_rng(2)
    cal = seed_prototype_truth(DEV, rng, position_error_mm=0.1)
    gain = np.linalg.norm(cal.sensitivity, axis=1) / DEV.counts_per_mps2 - 1
    assert np.all((gain >= SEED_TABLE1["gain"][0]) & (gain <= SEED_TABLE1["gain"][1]))
    cross = np.linalg.norm(np.cross(cal.sensitivity / np.linalg.norm(cal.sensitivity, axis=1, keepdims=True),
                                    DEV.axes), axis=1)
    assert np.all(cross <= math.sqrt(2) * 0.0175 + 1e-12) and np.all(cross > 0)
    off = (cal.offsets - DEV.zero_counts) / (G * DEV.counts_per_mps2)
    assert np.all((off >= -0.283) & (off <= 0.254))
    assert np.abs(cal.positions - DEV.positions).max() <= 1e-4
    sim = run_simulation(DEV, "static_poses", calibration=cal, seed=1)
    assert np.array_equal(sim.state.sensitivity, cal.sensitivity)
    assert np.array_equal(sim.state.positions, cal.positions)
    # temperature coefficients of a given calibration are part of the truth
    cal.temp_ref_c = 20.0
    cal.offset_tc = np.full(6, 3.0)
    st = true_state(DEV, cal, np.array([20.0, 30.0]))
    assert np.allclose(st.total_offset()[1] - st.total_offset()[0], 30.0)
    with pytest.raises(AccelcalError, match="calibration has 6 channels but device 'triad-16bit' has 3"):
        run_simulation(default_triad(), "static_poses", calibration=cal)


@pytest.mark.parametrize("spec,fragments", [
    ("gian:scale=0.01", ["unknown effect 'gian'", "did you mean 'gain'", "offset, gain"]),
    ("none", ["verdict"]),
    ("gain:scal=0.01", ["effect 'gain'", "unknown parameter 'scal'", "did you mean 'scale'", "scale, channel"]),
    ("gain:scale=abc", ["effect 'gain' parameter 'scale'", "expected a number", "'abc'"]),
    ("gain:scale", ["expected k=v", "'scale'"]),
    ("gain:", ["nothing after ':'"]),
    (":scale=1", ["name before ':' is missing"]),
    ("gain:scale=0.1,,channel=1", ["empty parameter"]),
    ("gain:scale=1,scale=2", ["given more than once"]),
    ("offset:db=[1,2", ["unbalanced"]),
    ("offset:channel=-1", ["'channel'", "channel index"]),
    ("misalignment:toward=sideways", ["'toward'", "'random'"]),
    ("quantization:step=0.5", ["'step'", ">= 1"]),
    ("bandwidth:fc_hz=0", ["'fc_hz'", "> 0"]),
    ("random:x=1", ["unknown effect"]),
    ("misalignment:toward=[x,,y]", ["'toward'"]),
    ("misalignment:toward=-", ["'toward'"]),
    ("", ["empty"]),
])
def test_bad_effect_specs(spec, fragments):
    with pytest.raises(AccelcalError) as ei:
        parse_effect_spec(spec)
    msg = str(ei.value)
    assert "\n" not in msg
    for frag in fragments:
        assert frag in msg, (frag, msg)


_SPEC_ALPHABET = st.sampled_from(list("gainoffset_:=,;|[]-+.0123456789exyz ") + ["scale", "channel", "toward",
                                                                                  "random", "nan", "inf"])


@given(st.lists(_SPEC_ALPHABET, max_size=30).map("".join))
def test_any_spec_text_parses_or_raises_accelcal_error(text):
    for candidate in (text, "gain:" + text, "misalignment:toward=" + text, "offset:channel=" + text):
        try:
            spec = parse_effect_spec(candidate)
        except AccelcalError as e:
            assert "\n" not in str(e)
        else:
            assert spec.effect in EFFECTS.values()


def test_bad_values_found_at_resolve_time_and_motion_errors():
    with pytest.raises(AccelcalError, match=r"channel 7 is out of range \(the device has 6 channels: 0..5\)"):
        simulate(DEV, "static_poses", effects=["offset:channel=7"])
    with pytest.raises(AccelcalError, match="expected 1 value or 6"):
        simulate(DEV, "static_poses", effects=["offset:db=[1,2,3]"])
    with pytest.raises(AccelcalError, match="given more than once"):
        parse_effect_specs(["gain", "gain:scale=0.1"])
    with pytest.raises(AccelcalError, match="unknown motion 'pendulm'.*did you mean 'pendulum'"):
        simulate(DEV, "pendulm")
    with pytest.raises(AccelcalError, match="motion 'rate_table': unknown parameter 'freq'.*freq_hz"):
        simulate(DEV, "rate_table", freq=2)
    with pytest.raises(AccelcalError, match="'amplitude_deg'.*expected a finite number"):
        simulate(DEV, "rate_table:amplitude_deg=nan")
    with pytest.raises(AccelcalError, match="'poses'"):
        simulate(DEV, "static_poses", poses="7")
    with pytest.raises(AccelcalError, match="'poses'"):
        simulate(DEV, "static_poses:poses=[x,,y]")
    with pytest.raises(AccelcalError, match="dwell_s"):
        simulate(DEV, "static_poses", dwell_s=0.1)
    with pytest.raises(AccelcalError, match="seed"):
        simulate(DEV, "static_poses", seed=1.5)
    # the spec and keyword forms of motion parameters agree
    r1 = simulate(DEV, "rate_table:freq_hz=1,axis=[0,1,1]", duration_s=1)
    r2 = simulate(DEV, "rate_table:duration_s=1", freq_hz=1, axis=[0, 1, 1])
    assert np.array_equal(r1.raw, r2.raw) and np.array_equal(r1.w, r2.w)
    assert r1.metadata["motion"] == "rate_table:freq_hz=1,axis=[0,0.7071067811865475,0.7071067811865475],duration_s=1"


def test_parse_effect_spec_values():
    s = parse_effect_spec("misalignment:angle_deg=[0.1,0.2,0.3,0.4,0.5,0.6],toward=[0,1,1],channel=0;2")
    assert np.allclose(s.params["toward"], [0, 2**-0.5, 2**-0.5])
    assert s.params["channel"] == (0, 2)
    assert np.allclose(s.params["angle_deg"], [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    assert parse_effect_spec(("gain", {"scale": 0.02})).params == {"scale": 0.02}
    assert str(parse_effect_spec("bias_drift:rw=2,random=1")) == "bias_drift:rw=2,random=1"
    assert set(EFFECTS) == {"offset", "gain", "misalignment", "position_error", "centripetal", "time_skew",
                            "bandwidth", "nonlinearity", "temperature_offset", "temperature_gain", "session_offset",
                            "session_gain", "bias_drift",
                            "saturation", "quantization", "pose_error"}


def test_vectorised_speed():
    pos = np.repeat(np.array([[0.05, 0, 0], [-0.05, 0, 0], [0, 0.05, 0], [0, 0, 0.05]]), 3, axis=0)
    dev = Device(name="12ch", sample_rate_hz=100.0, gravity_mps2=GRAVITY, raw_min=0, raw_max=65535,
                 positions=pos, axes=np.tile(np.eye(3), (4, 1)), counts_per_mps2=np.full(12, 1670.0),
                 zero_counts=np.full(12, 32768.0), noise_mps2=0.005)
    c0 = time.process_time()
    rec = simulate(dev, "random_6dof", seed=1, duration_s=2000, effects=["gain", "bandwidth"])
    cpu = time.process_time() - c0
    assert rec.raw.shape == (200000, 12)
    assert cpu < 4.0  # ~0.5 s on one core: 1e6 x 12 takes a few seconds


@given(x0=st.floats(-50.0, 50.0), q=st.integers(2, 40),
       r=st.one_of(st.just(0.0), st.floats(1e-3, 0.6)), phase=st.integers(0, 39))
def test_quantization_expected_error_matches_monte_carlo(x0, q, r, phase):
    """EFFECTS['quantization'].expected_error is E[Q(x + n) - (x + n)] for n ~ N(0, (r q)^2):
    checked against 20,000 draws of the simulator's own quantiser (apply_signal) per point."""
    eff = EFFECTS["quantization"]
    rng = np.random.default_rng(abs(hash((x0, q, r, phase))) % 2**32)
    x = x0 + np.linspace(0.0, q, 7)[:, None] + phase % q
    sigma = r * q
    n = rng.standard_normal((x.shape[0], 20000)) * sigma
    y = x + n                                    # the readings before the quantiser
    shifted = y - (phase % q)                    # a phase: quantise on the lattice phase + k q
    qy = eff.apply_signal(shifted.reshape(-1, 1), {"step": np.array([float(q)])}, None).reshape(y.shape)
    mc = np.mean(qy - shifted, axis=1)
    se = np.std(qy - shifted, axis=1) / math.sqrt(y.shape[1])
    got = eff.expected_error(x, np.full(1, float(q)), np.full(1, float(phase % q)), np.full(1, sigma))[:, 0]
    assert np.all(np.abs(got - mc) <= 6.0 * se + 1e-3 * q), (got, mc, se)  # 6 sigma: no false alarms


@pytest.mark.parametrize("motion, param", [("rate_table", "duration_s=1e7"), ("static_poses", "samples_per_pose=2000000")])
def test_a_simulation_too_large_for_memory_is_refused_before_it_starts(motion, param, capfd):
    """10^9 samples took 24 GB and were killed; now one line names the size, exit 2."""
    from cli_run import run
    rc, _, err, _ = run(["simulate", "--device", "default", "--motion", motion, "--param", param, "-o", "/dev/null"],
                        capfd)
    assert rc == 2 and err.count("\n") == 1 and "more than the 10,000,000 a simulation makes" in err


def test_an_effect_that_changes_no_reading_is_noted(capfd, tmp_path):
    """A clip at 1.5 g (the default) that a hand-held session never reaches changed nothing,
    without a word; a clip it reaches gives no note."""
    from cli_run import run
    rc, _, err, _ = run(["simulate", "--device", "default", "--motion", "static_poses", "--effect", "saturation",
                         "-o", tmp_path / "a.csv"], capfd)
    assert rc == 0 and "note: effect saturation changed no reading" in err
    rc, _, err, _ = run(["simulate", "--device", "default", "--motion", "static_poses", "--effect",
                         "saturation:limit_g=0.5", "-o", tmp_path / "b.csv"], capfd)
    assert rc == 0 and "changed no reading" not in err
