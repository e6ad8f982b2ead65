"""The pendulum attitude estimator: the C core (ac_attitude) against its float twin within
the bounds of ac_attitude.h, its constants, its errors, and the estimator against the
simulator's truth."""
import dataclasses
import gc
import math

import numpy as np
import pytest
from hypothesis import assume, given, strategies as st

from accelcal import estimators as E
from accelcal.io.calibration import Calibration
from accelcal.io.device import default_device
from accelcal.errors import AccelcalError, IllConditionedError, InputError, RangeError, SingularError
from accelcal.firmware.native import check, ffi, lib
from accelcal.simulate import run_simulation
from core_settings import estimator
from estimator_devices import G, adxl_pendulum_device


def pendulum_forces(r, t, A, om, c0, ph, noise, rng, decay=0.0):
    E_ = np.exp(-decay * t)
    th = c0 + A * E_ * np.cos(om * t + ph)
    w = A * E_ * (-decay * np.cos(om * t + ph) - om * np.sin(om * t + ph))
    a = A * E_ * ((decay**2 - om**2) * np.cos(om * t + ph) + 2 * decay * om * np.sin(om * t + ph))
    f = np.column_stack([-G * np.sin(th) - w * w * r, np.zeros_like(t), G * np.cos(th) - a * r])
    return f + rng.normal(0, noise, f.shape), th, w, a


@st.composite
def pendulum_runs(draw):
    r1 = draw(st.floats(-0.6, 0.6))
    r2 = draw(st.floats(-0.6, 0.6))
    assume(abs(r1 - r2) > 0.01 and max(abs(r1), abs(r2)) < 1024 * abs(r1 - r2))
    rate = draw(st.sampled_from([50.0, 60.0, 100.0, 200.0]))
    n = draw(st.integers(1, 150))
    t = np.arange(n) / rate
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    A = draw(st.floats(0.0, 1.6))
    om = 2 * math.pi * draw(st.floats(0.1, 3.0))
    c0 = draw(st.floats(-math.pi, math.pi))
    ph = draw(st.floats(0, 2 * math.pi))
    noise = draw(st.sampled_from([0.0, 0.005, 0.02, 0.2, 2.0]))
    f1, *_ = pendulum_forces(r1, t, A, om, c0, ph, noise, rng)
    f2, *_ = pendulum_forces(r2, t, A, om, c0, ph, noise, rng)
    if draw(st.booleans()):   # clipping and garbage
        k = int(rng.integers(0, n))
        f1[k] = rng.normal(0, 50, 3)
    p = E.AttitudeParams(r1=r1, r2=r2, dt=1 / rate, gain=draw(st.floats(0.0, 8.0)),
                         noise_mps2=max(noise, 1e-3), leak_tau_s=draw(st.sampled_from([0.0, 0.5, 2.0])),
                         w2_gate=draw(st.sampled_from([None, 0.0, 0.5])))
    return E.q_out(f1), E.q_out(f2), p


@estimator
@given(pendulum_runs())
def test_attitude_fixed_vs_twin(run):
    f1, f2, p = run
    fx = E.attitude_fixed(f1, f2, p)
    tw = E.attitude_twin(f1, f2, fx)
    sat = (fx["flags"] & E.ATT_SAT) != 0
    ok = ~sat
    # theta: ac_atan2 bound
    dth = np.abs(fx["theta"] - tw["theta"] * 2**13)
    dth = np.minimum(dth, 2 * math.pi * 2**13 - dth)
    assert np.all(dth[(tw["x"] != 0) | (tw["y"] != 0)] <= 0.76)
    assert np.array_equal((fx["flags"] & E.ATT_NO_GRAVITY) != 0, (tw["x"] == 0) & (tw["y"] == 0))
    # dw and w2: one rounding each
    assert np.all(np.abs(fx["dw"] - tw["dw"] * 1024)[ok] <= 0.5)
    assert np.all(np.abs(fx["w2"] - tw["w2"] * 2**20)[ok] <= 0.5)
    if sat.any():
        return
    # w: the recursion bound of ac_attitude.h
    bound = E.attitude_rate_bound(fx, tw)
    assert np.all(np.abs(fx["w"] / 1024.0 - tw["w"]) <= bound)
    # decisions: the twin's own choice differs only inside the stated margins
    C = fx["consts"]
    own_gate = tw["w2"] < C.gate
    dg = own_gate != tw["gated"]
    assert np.all(np.abs(tw["w2"][dg] - C.gate) <= 2.0**-21)
    own_neg = tw["wp"] < 0
    ds = (own_neg != tw["sign_neg"]) & ~tw["gated"]
    prev = np.concatenate([[0.0], bound[:-1] - 2.0**-11])
    assert np.all(np.abs(tw["wp"][ds]) <= prev[ds] + 2.0**-21 + C.dt * 2.0**-11)
    assert np.array_equal((fx["flags"] & E.ATT_UNSETTLED) != 0, ~tw["settled"])
    assert np.array_equal((fx["flags"] & E.ATT_W2_NEG) != 0, fx["w2"] < 0)


def test_attitude_constants_close_to_geometry():
    for r1, r2 in ((0.1, 0.3), (0.3, 0.1), (-0.2, 0.25), (0.0, 0.5), (1.0, 1.001), (2.0, -7.5)):
        p = E.AttitudeParams(r1=r1, r2=r2, dt=0.01)
        _, C = E.att_init_fixed(p)
        # against the geometry as the core holds it (r in Q.20: 1 um steps)
        X = E.AttitudeConsts.exact(dataclasses.replace(p, r1=round(r1 * 2**20) / 2**20,
                                                       r2=round(r2 * 2**20) / 2**20))
        for a in ("c1", "c2"):
            assert abs(getattr(C, a) - getattr(X, a)) <= 2.0**-15
        for a in ("k", "gs"):
            assert abs(getattr(C, a) / getattr(X, a) - 1.0) <= 2.0**-14
        assert abs(C.kdt / X.kdt - 1.0) <= 2.0**-15


def test_attitude_init_errors():
    st_ = ffi.new("ac_att *")
    assert lib.ac_att_init(st_, 104858, 104858, 40000, 22, 512, 0, 0) == lib.AC_ERR_SINGULAR
    assert lib.ac_att_init(st_, 2**28, 2**28 + 100, 40000, 22, 512, 0, 0) == lib.AC_ERR_ILL_COND
    assert lib.ac_att_init(st_, 104858, 314573, 0, 22, 512, 0, 0) == lib.AC_ERR_RANGE
    assert lib.ac_att_init(st_, 104858, 314573, 40000, 15, 512, 0, 0) == lib.AC_ERR_RANGE
    assert lib.ac_att_init(st_, 104858, 314573, 40000, 22, 512, -1, 0) == lib.AC_ERR_RANGE
    assert lib.ac_att_init(st_, 2**31 - 1, 0, 40000, 22, 512, 0, 0) == lib.AC_ERR_RANGE
    with pytest.raises(AccelcalError, match="r1 = r2"):
        E.attitude_float(np.zeros((2, 3)), np.zeros((2, 3)), E.AttitudeParams(r1=0.2, r2=0.2, dt=0.01))
    with pytest.raises(SingularError):
        check(lib.ac_att_init(st_, 5, 5, 40000, 22, 512, 0, 0), "ac_att_init")
    with pytest.raises(IllConditionedError):
        check(lib.ac_att_init(st_, 2**28, 2**28 + 100, 40000, 22, 512, 0, 0), "ac_att_init")
    with pytest.raises(RangeError):
        check(lib.ac_att_init(st_, 5, 6, 0, 22, 512, 0, 0), "ac_att_init")


def test_attitude_step_rejects_uninitialised_state():
    st_ = ffi.new("ac_att *")
    out = ffi.new("ac_att_out *")
    f = ffi.new("int32_t[3]")
    assert lib.ac_att_step(st_, f, f, out) == lib.AC_ERR_RANGE


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_pendulum_attitude_against_simulator(engine):
    d = adxl_pendulum_device()
    sim = run_simulation(d, "pendulum", seed=11, duration_s=20.0, amplitude_deg=40.0, freq_hz=0.5)
    rec = sim.recording
    cols = E.attitude_from_recording(d, Calibration.nominal(d), rec, engine)
    assert list(cols)[:4] == ["t", "theta_rad", "w_y", "dw_y"]
    th_ref = np.arctan2(-rec.f[:, 0], rec.f[:, 2])   # contract: f = g(-sin th, 0, cos th) at the pivot
    e_th = np.degrees(np.angle(np.exp(1j * (cols["theta_rad"] - th_ref))))
    assert np.sqrt(np.mean(e_th**2)) <= 0.3
    # rate and its sign: the contract's right-handed w_y, dw_y (the simulator's reference columns)
    assert np.sqrt(np.mean((cols["w_y"] - rec.w[:, 1]) ** 2)) <= 0.03
    assert np.corrcoef(cols["w_y"], rec.w[:, 1])[0, 1] > 0.999
    assert np.corrcoef(cols["dw_y"], rec.dw[:, 1])[0, 1] > 0.99
    assert not cols.warnings


def test_pendulum_fixed_close_to_float():
    d = adxl_pendulum_device()
    rec = run_simulation(d, "pendulum", seed=5, duration_s=10.0).recording
    a = E.attitude_from_recording(d, Calibration.nominal(d), rec, "float")
    b = E.attitude_from_recording(d, Calibration.nominal(d), rec, "fixed")
    assert np.max(np.abs(a["theta_rad"] - b["theta_rad"])) < 2e-3     # triad quantisation + LSB
    assert np.max(np.abs(a["w_y"] - b["w_y"])) < 0.02
    assert np.max(np.abs(a["dw_y"] - b["dw_y"])) < 0.05


def test_rate_sign_from_a_wrong_start_settles():
    """Starting mid-swing (|w| large, alpha ~ 0) the sign is a guess: flagged until the first
    pass through the gated low-rate band, right afterwards."""
    rng = np.random.default_rng(3)
    rate, n = 100.0, 600
    t = np.arange(n) / rate
    om = 2 * math.pi * 0.5
    ph = math.pi / 2 + 0.02       # just past the bottom: w < 0, alpha slightly > 0 (sign guess wrong)
    f1, th, w, a = pendulum_forces(0.1, t, 0.7, om, 0.0, ph, 0.005, rng)
    f2, *_ = pendulum_forces(0.3, t, 0.7, om, 0.0, ph, 0.005, rng)
    p = E.AttitudeParams(r1=0.1, r2=0.3, dt=1 / rate, noise_mps2=0.005)
    for out in (E.attitude_float(f1, f2, p),):
        uns = ~out["settled"]
        assert uns[0] and not uns[-1]
        k = int(np.argmin(uns))
        assert k < rate * 1.1                     # within about half a period
        assert np.sqrt(np.mean((out["w"][k + 50:] - w[k + 50:]) ** 2)) < 0.05
    fx = E.attitude_fixed(E.q_out(f1), E.q_out(f2), p)
    assert fx["flags"][0] & E.ATT_UNSETTLED and not fx["flags"][-1] & E.ATT_UNSETTLED


def test_rate_near_rest_negative_w2_is_handled():
    rng = np.random.default_rng(4)
    n, rate = 500, 60.0
    t = np.arange(n) / rate
    f1, *_ = pendulum_forces(0.1, t, 0.0, 1.0, 0.1, 0.0, 0.02, rng)
    f2, *_ = pendulum_forces(0.3, t, 0.0, 1.0, 0.1, 0.0, 0.02, rng)
    p = E.AttitudeParams(r1=0.1, r2=0.3, dt=1 / rate, noise_mps2=0.02)
    fx = E.attitude_fixed(E.q_out(f1), E.q_out(f2), p)
    assert np.any(fx["flags"] & E.ATT_W2_NEG)             # noise makes w^2 < 0 ...
    assert np.all(fx["flags"][fx["w2"] < 0] & E.ATT_GATED)  # ... and it is never square-rooted
    assert np.max(np.abs(fx["w"][60:])) / 1024.0 < 0.1   # the leak keeps the integral near 0
    assert abs(np.mean(fx["theta"]) / 8192.0 - 0.1) < 0.005


def test_attitude_from_recording_bad_devices():
    d = adxl_pendulum_device()
    rec = run_simulation(d, "pendulum", seed=1, duration_s=1.0).recording
    same = dataclasses.replace(d, positions=np.array([[0.2, 0, 0]] * 6))
    with pytest.raises(InputError, match="r1 = r2"):
        E.attitude_from_recording(same, Calibration.nominal(same), rec)
    off = dataclasses.replace(d, positions=np.array([[0.1, 0, 0]] * 3 + [[0.3, 0.05, 0]] * 3))
    with pytest.raises(InputError, match="off the body x axis"):
        E.attitude_from_recording(off, Calibration.nominal(off), rec)
    with pytest.raises(InputError, match="two triads"):
        dd = default_device()
        E.attitude_from_recording(dd, Calibration.nominal(dd), run_simulation(dd, "pendulum", duration_s=1).recording)


def test_attitude_flags_pivot_that_moves():
    """A body spinning about z (not the pendulum's y axis) breaks the model: the pair's |g|
    is far from gravity and the result is flagged, not silently wrong."""
    d = adxl_pendulum_device()
    sim = run_simulation(d, "rate_table", seed=2, axis="z", freq_hz=2.0, amplitude_deg=90.0, duration_s=3.0)
    cols = E.attitude_from_recording(d, Calibration.nominal(d), sim.recording)
    assert any("|g|" in w for w in cols.warnings)


def test_the_fixed_run_keeps_its_configuration_after_the_state_is_gone():
    """attitude_fixed's 'cfg' is an owned copy: the C state it came from is freed when the
    call returns, and a view into it read garbage once the memory was reused (the rate
    bound then came out wrong now and then)."""
    f = np.zeros((5, 3), np.int32)
    f[:, 2] = -10000
    p = E.AttitudeParams(r1=0.03, r2=0.05, dt=1 / 60, gain=7.5, w2_gate=None, noise_mps2=0.005, leak_tau_s=2.0)
    fx = E.attitude_fixed(f, f.copy(), p)
    before = (fx["cfg"].kdt_shift, fx["cfg"].kdt_m, fx["cfg"].w2_gate)
    gc.collect()
    size = ffi.sizeof("ac_att")
    reuse = [ffi.new("ac_att *") for _ in range(2000)]
    for r in reuse:
        ffi.memmove(r, b"\xff" * size, size)
    assert (fx["cfg"].kdt_shift, fx["cfg"].kdt_m, fx["cfg"].w2_gate) == before
