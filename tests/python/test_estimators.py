"""Motion estimators: the integer C core (ac_trig, ac_rest, ac_attitude, ac_displace)
against its float twins in accelcal.estimators, within the bounds stated in the
headers; the estimators against simulated truth; bad input."""
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import assume, given, strategies as st

from accelcal import estimators as E
from accelcal._core import ffi, lib
from accelcal.calibration import Calibration
from accelcal.device import Device, default_device, default_triad
from accelcal.errors import AccelcalError, InputError, RangeError, SingularError, IllConditionedError
from accelcal.recording import recording_from_arrays
from accelcal.simulate import run_simulation
from core_settings import estimator

U32 = st.integers(0, 2**32 - 1)
I32 = st.one_of(st.integers(-2**31, 2**31 - 1),
                st.sampled_from([-2**31, -2**31 + 1, -1, 0, 1, 2**31 - 1, 2**30, -2**30, 2**16, -2**16]))
G = 9.80665


def rhu(num, den=1):
    """round half up of num / den (exact, Python ints)."""
    return (2 * num + den) // (2 * den)


# ---------------------------------------------------------------------------------
# primitives (exact)
# ---------------------------------------------------------------------------------

def test_flag_constants_match_headers():
    assert (E.REST_QUIET, E.REST_AT_REST, E.REST_ENTER, E.REST_LEAVE, E.REST_CLIP) == \
        (lib.AC_REST_QUIET, lib.AC_REST_AT_REST, lib.AC_REST_ENTER, lib.AC_REST_LEAVE, lib.AC_REST_CLIP)
    assert (E.ATT_GATED, E.ATT_W2_NEG, E.ATT_UNSETTLED, E.ATT_NO_GRAVITY, E.ATT_SAT, E.ATT_SIGN_NEG) == \
        (lib.AC_ATT_GATED, lib.AC_ATT_W2_NEG, lib.AC_ATT_UNSETTLED, lib.AC_ATT_NO_GRAVITY, lib.AC_ATT_SAT,
         lib.AC_ATT_SIGN_NEG)
    assert (E.DISP_NO_REF, E.DISP_REST, E.DISP_MOVING, E.DISP_SEG_END, E.DISP_LONG, E.DISP_SAT, E.DISP_OPEN,
            E.DISP_NO_REST, E.DISP_REF_SET, E.DISP_BAD_REF) == \
        (lib.AC_DISP_NO_REF, lib.AC_DISP_REST, lib.AC_DISP_MOVING, lib.AC_DISP_SEG_END, lib.AC_DISP_LONG,
         lib.AC_DISP_SAT, lib.AC_DISP_OPEN, lib.AC_DISP_NO_REST, lib.AC_DISP_REF_SET, lib.AC_DISP_BAD_REF)
    assert (E.ANGLE_FRAC, E.W_FRAC, E.V_FRAC, E.P_FRAC, E.A_FRAC, E.ROT_FRAC, E.GSUM_MAX) == \
        (lib.AC_ANGLE_FRAC, lib.AC_ATT_W_FRAC, lib.AC_DISP_V_FRAC, lib.AC_DISP_P_FRAC, lib.AC_DISP_A_FRAC,
         lib.AC_DISP_ROT_FRAC, lib.AC_DISP_GSUM_MAX)


@estimator
@given(st.one_of(U32, st.integers(0, 2**20), st.sampled_from([0, 1, 2, 3, 4294901760, 4294901761, 2**32 - 1])))
def test_isqrt32_is_round_sqrt(v):
    out = ffi.new("uint16_t *")
    s = lib.ac_isqrt32(v, out)
    r = math.isqrt(v)
    r = r + 1 if v - r * r > r else r   # round half up (no ties for integers)
    if r <= 65535:
        assert s == lib.AC_OK and out[0] == r
    else:
        assert s == lib.AC_SATURATED and out[0] == 65535


@estimator
@given(U32, U32, st.integers(1, 2**32 - 1))
def test_udiv64_rounds_half_up(hi, lo, den):
    q = ffi.new("uint32_t *")
    s = lib.ac_udiv64(hi, lo, den, q)
    num = hi * 2**32 + lo
    exact = rhu(num, den)
    if hi >= den or exact > 2**32 - 1:
        assert s == lib.AC_SATURATED and q[0] == 2**32 - 1
    else:
        assert s == lib.AC_OK and q[0] == exact


def test_udiv64_zero_divisor():
    q = ffi.new("uint32_t *")
    assert lib.ac_udiv64(0, 5, 0, q) == lib.AC_ERR_RANGE


@estimator
@given(I32, st.integers(0, 65535), st.integers(0, 47))
def test_mul32x16_shift_exact(a, b, n):
    out = ffi.new("int32_t *")
    s = lib.ac_mul32x16_shift(a, b, n, out)
    exact = (a * b + (1 << n) // 2) >> n if n else a * b   # floor(x + 1/2): half up
    clipped = max(-2**31, min(2**31 - 1, exact))
    assert out[0] == clipped
    assert (s == lib.AC_SATURATED) == (exact != clipped)


def check_atan2(y, x):
    ang, mag = E.atan2_fixed([y], [x])
    if x == 0 and y == 0:
        assert ang[0] == 0 and mag[0] == 0
        return
    t = math.atan2(y, x) * 2**13
    err = abs(ang[0] - t)
    err = min(err, 2 * math.pi * 2**13 - err)      # -pi and pi are the same angle
    assert err <= 0.76 <= lib.AC_ATAN2_BOUND_LSB
    h = math.hypot(x, y)
    assert abs(mag[0] - h) <= 2**-14 * h + 1


@estimator
@given(I32, I32)
def test_atan2_within_stated_bound(y, x):
    check_atan2(y, x)


@estimator
@given(st.integers(-40000, 40000), st.integers(-40000, 40000))
def test_atan2_small_operands(y, x):
    check_atan2(y, x)


# ---------------------------------------------------------------------------------
# triad apply
# ---------------------------------------------------------------------------------

@st.composite
def triads(draw):
    k = draw(st.floats(50.0, 2000.0))
    gain = np.array(draw(st.lists(st.floats(-0.05, 0.05), min_size=3, max_size=3)))
    mis = np.array(draw(st.lists(st.floats(-0.03, 0.03), min_size=9, max_size=9))).reshape(3, 3)
    S = k * (np.diag(1.0 + gain) + mis - np.diag(np.diag(mis)))
    b = np.array(draw(st.lists(st.floats(1000.0, 60000.0), min_size=3, max_size=3)))
    return b, S


@estimator
@given(triads(), st.lists(st.integers(0, 65535), min_size=3, max_size=3))
def test_triad_apply_exact_and_float(tri, raw):
    b, S = tri
    tab = E.quantize_triad(b, S)
    raw = np.array([raw])
    f_q, sat = E.triad_apply_fixed(tab, raw)
    exact = E.triad_exact(tab, raw)
    x = raw - tab.trim.astype(np.int64)
    clipped = np.any((x < -32768) | (x > 32767))
    if not sat[0]:
        assert np.all(np.abs(f_q - exact) <= 0.5)
    else:
        assert clipped or np.any(np.abs(exact) > 2**31 - 1)
    if not clipped and not sat[0]:
        # against the float reference: table rounding (half a mantissa LSB per entry) + final rounding
        ref = E.triad_apply_float(b, S, raw) * 1024.0
        half = 0.5 * 2.0 ** (-tab.shift.astype(float))
        bound = (np.abs(x).sum() + 1.0) * half + 0.5 + 1e-6 * np.abs(ref)
        assert np.all(np.abs(f_q - ref) <= bound)


def test_triad_check_rejects_bad_tables():
    tab = E.quantize_triad([32768.0] * 3, np.eye(3) * 1670.7)
    t = tab.cdata()
    assert lib.ac_triad_check(t) == lib.AC_OK
    t.shift[1] = 40
    assert lib.ac_triad_check(t) == lib.AC_ERR_FORMAT
    t.shift[1] = 0
    t.m[0][0], t.m[0][1], t.m[0][2] = 32767, 32767, 2
    assert lib.ac_triad_check(t) == lib.AC_ERR_FORMAT


# ---------------------------------------------------------------------------------
# rest detector
# ---------------------------------------------------------------------------------

@st.composite
def rest_inputs(draw):
    n = draw(st.integers(1, 160))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    noise = draw(st.sampled_from([0.0, 0.002, 0.02, 0.3]))
    up = rng.normal(size=3)
    up /= np.linalg.norm(up)
    f = G * up + rng.normal(0, noise, (n, 3))
    # a few bursts of motion and occasional huge values (clipping)
    for _ in range(draw(st.integers(0, 3))):
        s = int(rng.integers(0, n))
        f[s:s + int(rng.integers(1, 30))] += rng.normal(0, draw(st.sampled_from([0.05, 1.0, 40.0])), 3)
    p = E.RestParams(dev_max=draw(st.floats(0.0, 0.5)), g=draw(st.sampled_from([None, G])),
                     g_tol=draw(st.floats(0.0, 2.0)), hold=draw(st.integers(1, 40)),
                     ema_shift=draw(st.integers(1, 12)),
                     alpha_max=draw(st.sampled_from([math.inf, 0.5])))
    alpha = rng.normal(0, 0.4, (n, 3)) if draw(st.booleans()) else None
    return E._q10(f), p, (None if alpha is None else E._q10(alpha))


@estimator
@given(rest_inputs())
def test_rest_fixed_vs_twin(inp):
    f_q, p, a_q = inp
    fl = E.rest_fixed(f_q, p, a_q)
    tw, dev = E.rest_detect(E._i16(f_q) / 1024.0, p, None if a_q is None else a_q / 1024.0, as_stored=True)
    dev_max = E.rest_params_as_stored(p)[0]
    margin = 2.0 ** (p.ema_shift - 18)          # the floor-rounded mean, stated in ac_rest.h
    q_c, q_t = (fl & E.REST_QUIET) != 0, (tw & E.REST_QUIET) != 0
    differ = q_c != q_t
    assert np.all(np.abs(dev[differ] - dev_max) <= margin)
    # at-rest and the events follow from the quiet bits by the stated run-length rule
    run, at = 0, False
    for i in range(len(fl)):
        run = min(run + 1, 65535) if q_c[i] else 0
        was, at = at, run >= p.hold
        assert bool(fl[i] & E.REST_AT_REST) == at
        assert bool(fl[i] & E.REST_ENTER) == (at and not was)
        assert bool(fl[i] & E.REST_LEAVE) == (was and not at)
    clipped = np.any((f_q < -32768) | (f_q > 32767), axis=1)
    assert np.array_equal((fl & E.REST_CLIP) != 0, clipped)


def test_rest_init_rejects_bad_parameters():
    st_ = ffi.new("ac_rest *")
    for bad in (dict(hold=0), dict(ema_shift=0), dict(ema_shift=13), dict(dev_max=-0.1)):
        c = E.rest_cfg_fixed(dataclasses.replace(E.RestParams(), **{k: v for k, v in bad.items()
                                                                   if k != "dev_max"}))
        if "dev_max" in bad:
            c.dev_max = -1
        assert lib.ac_rest_init(st_, c) == lib.AC_ERR_RANGE


# ---------------------------------------------------------------------------------
# pendulum attitude
# ---------------------------------------------------------------------------------

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
    return E._q10(f1), E._q10(f2), p


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
    from accelcal.native import check
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


def adxl_pendulum_device(r1=0.1, r2=0.3):
    """Two ADXL202E-like triads: 1250 counts per g, zero 5000, 0..10000, 60 Hz, 0.02 m/s^2."""
    pos = np.array([[r1, 0, 0]] * 3 + [[r2, 0, 0]] * 3, float)
    return Device(name="pendulum-adxl", sample_rate_hz=60.0, gravity_mps2=G, raw_min=0, raw_max=10000,
                  positions=pos, axes=np.vstack([np.eye(3), np.eye(3)]),
                  counts_per_mps2=np.full(6, 1250.0 / G), zero_counts=np.full(6, 5000.0), noise_mps2=0.02)


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
    fx = E.attitude_fixed(E._q10(f1), E._q10(f2), p)
    assert fx["flags"][0] & E.ATT_UNSETTLED and not fx["flags"][-1] & E.ATT_UNSETTLED


def test_rate_near_rest_negative_w2_is_handled():
    rng = np.random.default_rng(4)
    n, rate = 500, 60.0
    t = np.arange(n) / rate
    f1, *_ = pendulum_forces(0.1, t, 0.0, 1.0, 0.1, 0.0, 0.02, rng)
    f2, *_ = pendulum_forces(0.3, t, 0.0, 1.0, 0.1, 0.0, 0.02, rng)
    p = E.AttitudeParams(r1=0.1, r2=0.3, dt=1 / rate, noise_mps2=0.02)
    fx = E.attitude_fixed(E._q10(f1), E._q10(f2), p)
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


# ---------------------------------------------------------------------------------
# displacement
# ---------------------------------------------------------------------------------

@estimator
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3), st.floats(0.2, 40.0))
def test_tilt_frame_fixed_vs_float(d, mag):
    v = np.array(d)
    assume(np.linalg.norm(v) > 1e-3)
    g = v / np.linalg.norm(v) * mag
    gq = np.round(g * 2**16).astype(np.int64)
    rot = ffi.new("int16_t[3][3]")
    gc = ffi.new("int32_t[3]", [int(x) for x in gq])
    assert lib.ac_tilt_frame(gc, rot) == lib.AC_OK
    R = np.array([[rot[j][k] for k in range(3)] for j in range(3)]) / 2**14
    Rf = E.tilt_frame(gq / 2**16)
    u = gq / np.linalg.norm(gq)
    near = abs(u[1] ** 2 + u[2] ** 2 - 0.25) < 1e-3    # branch boundary: both frames are valid
    if not near:
        assert np.max(np.abs(R - Rf)) <= 2 * 2**-14
    assert np.max(np.abs(R @ R.T - np.eye(3))) <= 6 * 2**-14
    assert np.max(np.abs(Rf @ (gq / 2**16) / np.linalg.norm(gq / 2**16) - [0, 0, 1])) < 1e-12
    assert np.linalg.det(Rf) > 0.999


def test_tilt_frame_zero():
    rot = ffi.new("int16_t[3][3]")
    assert lib.ac_tilt_frame(ffi.new("int32_t[3]"), rot) == lib.AC_ERR_SINGULAR


def minjerk_acc(n_rest1, n_move, n_rest2, dist, dt):
    a = np.zeros(n_rest1 + n_move + n_rest2)
    T = n_move * dt
    u = np.arange(n_move) * dt / T
    a[n_rest1:n_rest1 + n_move] = dist / T**2 * 60 * (u - 3 * u**2 + 2 * u**3)
    return a


@st.composite
def displacement_runs(draw):
    rate = draw(st.sampled_from([60.0, 100.0]))
    dt = 1 / rate
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    parts = [minjerk_acc(draw(st.integers(0, 60)), draw(st.integers(5, 150)), 0, draw(st.floats(-1, 1)), dt)
             for _ in range(draw(st.integers(1, 3)))]
    a = np.concatenate(parts + [np.zeros(draw(st.integers(0, 60)))])
    n = len(a)
    d = rng.normal(size=3)
    d /= np.linalg.norm(d)
    up = rng.normal(size=3)
    up /= np.linalg.norm(up)
    noise = draw(st.sampled_from([0.0, 0.005, 0.02]))
    f = G * up + a[:, None] * d + rng.normal(0, noise, (n, 3)) + rng.normal(0, 0.05, 3)
    if draw(st.booleans()):
        f[int(rng.integers(0, n))] += 50.0        # a clipped sample
    axis = draw(st.sampled_from([None, None, 0, 1, 2]))
    rp = E.RestParams(dev_max=max(5 * noise, 0.01), hold=draw(st.integers(1, 30)),
                      ema_shift=draw(st.integers(1, 6)), g=draw(st.sampled_from([None, G])))
    return E._q10(f), E.DisplaceParams(dt=dt, axis=axis, rest=rp)


@estimator
@given(displacement_runs())
def test_displacement_fixed_vs_twin(run):
    f_q, p = run
    fx = E.displace_fixed(f_q, p)
    tw = E.displace_twin(f_q, fx, p)
    assert np.array_equal(fx["flags"] & ~E.DISP_SAT, tw["flags"])
    assert np.array_equal(fx["nseg"], tw["nseg"])
    # the working range is |v| < 64 m/s, |p| < 2048 m (AC_DISP_SAT beyond): compare up to there
    over = (np.abs(tw["v"]).max(axis=1) > 63.9) | (np.abs(tw["p"]).max(axis=1) > 2047.0)
    m = int(np.argmax(over)) if over.any() else len(over)
    bv, bp = E.displace_error_bound(fx, tw, p.axis is None)
    assert np.all(np.abs(fx["v"] / 2.0**24 - tw["v"])[:m] <= bv[:m, None])
    assert np.all(np.abs(fx["p"] / 2.0**20 - tw["p"])[:m] <= bp[:m, None])
    for i in np.flatnonzero((fx["flags"] & E.DISP_SEG_END) & ~(fx["flags"] & E.DISP_LONG)):
        if i >= m:
            break
        T = fx["nseg"][i] * fx["dt"]
        zb = bv[i - 1] / T + np.abs(tw["zp"][i]) * 2.0**-17 / T + 2.0**-17 + 2.0**-25 / T
        assert np.all(np.abs(fx["zp"][i] / 2.0**16 - tw["zp"][i]) <= zb)
    # the core's rest decisions against the twin's own: only the floor-rounded mean differs
    th = E._RestThresholds.of(p.rest, True)
    differ = ((fx["rest"] & E.REST_QUIET) != 0) != tw["own_quiet"]
    assert np.all(np.abs(tw["dev"][differ] - th.dev_max) <= 2.0 ** (p.rest.ema_shift - 18))
    if fx["frame"] is not None and fx["frame"][1] is not None:
        g, rot, c = fx["frame"]
        assert np.max(np.abs(rot / 2**14 - E.tilt_frame(g / 2**16))) <= 2 * 2**-14 or \
            abs((g[1] ** 2 + g[2] ** 2) / np.sum(g.astype(float) ** 2) - 0.25) < 1e-3
        # c = round(R g) exactly (Q.16)
        exact = rot.astype(np.int64) @ g.astype(np.int64)          # Q.30
        assert np.array_equal(c, (exact + 2**13) >> 14)


def test_displacement_gravity_mean_is_exact():
    rng = np.random.default_rng(0)
    f = np.vstack([G * np.array([0.1, -0.2, 0.97]) + rng.normal(0, 0.01, (50, 3)),
                   np.tile([3.0, 0, 9.8], (10, 1)), np.tile([0.0, 0, 9.8], (40, 1))])
    fq = E._q10(f)
    p = E.DisplaceParams(dt=0.01, rest=E.RestParams(dev_max=0.06, hold=10, ema_shift=2))
    fx = E.displace_fixed(fq, p)
    g, _, _ = fx["frame"]
    rf = E.rest_fixed(fq, p.rest)
    k = int(np.argmax(~(rf & E.REST_AT_REST).astype(bool)[10:])) + 10   # first motion sample
    quiet = (rf & E.REST_QUIET).astype(bool)
    s = k
    while s > 0 and quiet[s - 1]:
        s -= 1
    mean = fq[s:k].astype(np.int64).sum(axis=0) * 64
    assert np.all(np.abs(g * (k - s) - mean) <= (k - s) / 2)


def test_stop_to_stop_1d_zero_point_correction():
    """The seed's case: 0.5 m in 2 s with a 0.05 m/s^2 zero-point error: <= 0.5 % corrected,
    tens of % uncorrected, for every engine and form."""
    d = default_triad()
    k = float(d.counts_per_mps2[0])
    sim = run_simulation(d, "linear_actuator", seed=21, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                         effects=[f"offset:db={0.05 * k},channel=0"])
    cal = Calibration.nominal(d)
    for engine, form in (("float", "offline"), ("float", "stream"), ("fixed", "stream")):
        c = E.displacement_from_recording(d, cal, sim.recording, engine, form=form, axis="x")
        assert abs(c["p_x"][-1] - 0.5) <= 0.005 * 0.5
        assert abs(c["p_raw_x"][-1] - 0.5) >= 0.1 * 0.5
        assert abs(float(c.meta["zero_point_mps2"].strip("()").split(",")[0]) - 0.05) < 0.005
        assert c["corrected"].any() and not c.warnings


def test_stop_to_stop_tilted_rail_3axis():
    d = default_triad()
    sim = run_simulation(d, "linear_actuator", seed=22, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                         tilt_deg=20.0, strokes=2)
    cal = Calibration.nominal(d)
    R = E.tilt_frame(sim.trajectory.f[0])
    truth = (sim.trajectory.position @ sim.trajectory.attitude[0]) @ R.T   # world -> body -> rest frame
    for engine in ("float", "fixed"):
        c = E.displacement_from_recording(d, cal, sim.recording, engine)
        p = np.column_stack([c["p_x"], c["p_y"], c["p_z"]])
        mid = np.argmin(np.abs(sim.recording.t - 5.0))   # resting after the first stroke
        assert np.linalg.norm(p[mid] - truth[mid]) <= 0.005 * 0.5
        assert np.linalg.norm(p[-1] - truth[-1]) <= 0.005 * 0.5
        assert abs(c["v_x"][mid]) < 1e-9 and c["rest"][mid] == 1


def test_displacement_no_rest_is_an_error():
    d = default_device()
    rec = run_simulation(d, "random_6dof", seed=1, duration_s=5.0).recording
    for engine in ("float", "fixed"):
        with pytest.raises(InputError, match="no rest"):
            E.displacement_from_recording(d, Calibration.nominal(d), rec, engine)


def test_displacement_motion_not_ending_at_rest_is_flagged():
    d = default_triad()
    sim = run_simulation(d, "linear_actuator", seed=2, distance_m=0.5, travel_s=2.0, rest_s=2.0)
    rec = sim.recording.select(sim.recording.t < 3.0)      # cut in the middle of the stroke
    for engine in ("float", "fixed"):
        c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine)
        assert any("does not end at rest" in w for w in c.warnings)
        assert c["corrected"][-1] == 0
    fx = E.displace_fixed(E._q10(E.triad_apply_float(d.zero_counts, d.nominal_sensitivity(), rec.raw)),
                          E.DisplaceParams(dt=0.01, rest=E.default_rest_params(d)))
    assert fx["finish"] & E.DISP_OPEN


def test_displacement_not_starting_at_rest_is_flagged():
    d = default_triad()
    sim = run_simulation(d, "linear_actuator", seed=2, distance_m=0.5, travel_s=2.0, rest_s=2.0, strokes=2)
    rec = sim.recording.select(sim.recording.t > 3.0)      # starts in the middle of the first stroke
    c = E.displacement_from_recording(d, Calibration.nominal(d), rec, "fixed")
    assert any("does not start at rest" in w for w in c.warnings)


def test_displacement_long_motion_not_corrected():
    p = E.DisplaceParams(dt=0.01, axis=0, rest=E.RestParams(g=None, dev_max=0.01, hold=2, ema_shift=1))
    n = 65540 + 40
    f = np.zeros((n, 3))
    f[5:65545, 0] = np.where(np.arange(65540) % 2, 0.5, -0.5)   # never quiet
    fx = E.displace_fixed(E._q10(f), p)
    ends = np.flatnonzero(fx["flags"] & E.DISP_SEG_END)
    assert len(ends) == 1 and fx["flags"][ends[0]] & E.DISP_LONG
    assert np.all(fx["zp"][ends[0]] == 0)


# ---------------------------------------------------------------------------------
# rate with reset on rest
# ---------------------------------------------------------------------------------

@st.composite
def rate_runs(draw):
    n = draw(st.integers(1, 200))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    alpha = rng.normal(0, draw(st.sampled_from([0.01, 0.5, 5.0])), (n, 3))
    f = np.tile([0.0, 0.0, G], (n, 1)) + rng.normal(0, 0.01, (n, 3))
    if draw(st.booleans()):
        s = int(rng.integers(0, n))
        f[s:s + 30] += 1.0
    rest = E.RestParams(dev_max=0.05, hold=draw(st.integers(1, 20)), ema_shift=3,
                        alpha_max=draw(st.sampled_from([math.inf, 1.0])))
    return E._q10(alpha), E._q10(f), 1 / draw(st.sampled_from([60.0, 100.0])), draw(st.integers(0, 2000)), rest


@estimator
@given(rate_runs())
def test_rate_rest_fixed_vs_twin(run):
    a_q, f_q, dt, leak_q, rest = run
    w, fl, sat = E.rate_rest_fixed(a_q, f_q, dt, leak_q, rest)
    dm, dsh = E.dt_fixed(dt)
    tw, _ = E.rate_rest_float(a_q / 1024.0, None, dm * 2.0**-dsh, leak_q / 65536.0, rest, rest_flags=fl)
    # two roundings of at most 2^-27 per step (ac_rate.h) since the last reset, + output rounding
    since = np.zeros(len(fl))
    k = 0
    for i in range(len(fl)):
        k = 0 if fl[i] & E.REST_AT_REST else k + 1
        since[i] = k
    bound = 2.0**-11 + since * 2.0**-26
    ok = ~sat
    assert np.all(np.abs(w / 1024.0 - tw)[ok] <= bound[ok, None])
    assert np.all(w[(fl & E.REST_AT_REST) != 0] == 0)


def test_lane_change_rate_with_rest_reset_beats_plain_integration():
    from accelcal import model
    d = default_device()
    sim = run_simulation(d, "lane_change", seed=3)
    rec = sim.recording
    cal = Calibration.nominal(d)
    for engine in ("float", "fixed"):
        c = E.rate_from_recording(d, cal, rec, engine, leak_tau_s=5.0)
        e = np.sqrt(np.mean((c["w_z"] - rec.w[:, 2]) ** 2))
        assert e < 0.03
        assert 0.1 < c["rest"].mean() < 0.8        # the straights look like rest (omega = 0 there)
    f, a = model.resolve(cal.offsets, cal.sensitivity, d.positions, rec.raw, None)
    plain = model.rate_integrate(a, 1 / d.sample_rate_hz)[:, 2]
    assert np.sqrt(np.mean((plain - rec.w[:, 2]) ** 2)) > e


# ---------------------------------------------------------------------------------
# host plumbing
# ---------------------------------------------------------------------------------

def test_dt_fixed():
    assert E.dt_fixed(1 / 60) == (34953, 21)
    for dt in (1e-4, 0.001, 0.01, 0.3):
        m, sh = E.dt_fixed(dt)
        assert 32768 <= m < 65536 and abs(m * 2.0**-sh / dt - 1) < 2**-15
    with pytest.raises(AccelcalError):
        E.dt_fixed(1.0)


def test_nonuniform_time_is_an_error():
    d = default_triad()
    rec = run_simulation(d, "linear_actuator", seed=2).recording
    t = rec.t.copy()
    t[100:] += 0.5
    bad = recording_from_arrays(t, rec.raw)
    with pytest.raises(InputError, match="not uniform"):
        E.displacement_from_recording(d, Calibration.nominal(d), bad)


def test_report_plots(tmp_path):
    d = adxl_pendulum_device()
    rec = run_simulation(d, "pendulum", seed=1, duration_s=4.0).recording
    cols = E.attitude_from_recording(d, Calibration.nominal(d), rec)
    files = E.report_plots(tmp_path, cols, rec)
    t = default_triad()
    rec2 = run_simulation(t, "linear_actuator", seed=1).recording
    files += E.report_plots(tmp_path, E.displacement_from_recording(t, Calibration.nominal(t), rec2), rec2)
    for f in files:
        assert f.exists() and f.stat().st_size > 1000


def test_displacement_flags_rotation_between_rests():
    """A lane change is no rail: the array's alpha shows the turn and the result is flagged;
    a rail gives no such warning."""
    d = default_device()
    cal = Calibration.nominal(d)
    c = E.displacement_from_recording(d, cal, run_simulation(d, "lane_change", seed=4).recording, "fixed")
    assert any("turned" in w for w in c.warnings)
    c = E.displacement_from_recording(d, cal, run_simulation(d, "linear_actuator", seed=4).recording, "fixed")
    assert not any("turned" in w for w in c.warnings)


def test_run_command_writes_csv_and_plots(tmp_path):
    from accelcal.calibration import save_calibration
    from accelcal.device import save_device
    from accelcal.recording import write_recording
    dev = adxl_pendulum_device()
    save_device(dev, tmp_path / "d.json")
    save_calibration(Calibration.nominal(dev), tmp_path / "c.json")
    write_recording(tmp_path / "r.csv", run_simulation(dev, "pendulum", seed=1, duration_s=3.0).recording)
    warn = E.run_command("attitude", tmp_path / "d.json", tmp_path / "c.json", tmp_path / "r.csv",
                         tmp_path / "o.csv", engine="fixed", report=tmp_path / "rep")
    assert warn == []
    lines = [ln for ln in (tmp_path / "o.csv").read_text().splitlines() if not ln.startswith("#")]
    assert lines[0].split(",")[:4] == ["t", "theta_rad", "w_y", "dw_y"]
    assert (tmp_path / "rep" / "attitude.png").exists()
    # bad input: nothing written
    with pytest.raises(InputError):
        E.run_command("displacement", tmp_path / "d.json", tmp_path / "c.json", tmp_path / "r.csv",
                      tmp_path / "bad.csv")
    assert not (tmp_path / "bad.csv").exists()
