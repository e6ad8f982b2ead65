"""The C core's resolve path, on-device inversion and rate integrator against
the float reference, over random geometries, calibrations and inputs."""
import math

import numpy as np
import pytest
from core_settings import core
from hypothesis import assume, given, strategies as st

from accelcal import model
from accelcal.firmware import native
from accelcal.estimators import dt_fixed
from accelcal._core import ffi, lib
from accelcal.errors import IllConditionedError, SingularError
from accelcal.firmware.quantize import (FORMATS, QuantizeError, exact_fixed_semantics, quantize,
                               table_error_bound)

OUT = 2.0 ** FORMATS.out_frac
BIG = 2**31


def random_geometry(rng, n):
    """A random array: seed-like circle layouts, or random positions and axes."""
    if rng.random() < 0.5:
        radius = rng.uniform(0.02, 0.2)
        phi = np.repeat(np.arange(math.ceil(n / 2)) * 2 * np.pi / math.ceil(n / 2), 2)[:n]
        phi = phi + rng.normal(0, 0.05, n)
        pos = radius * np.stack([np.cos(phi), np.sin(phi), rng.normal(0, 0.01, n)], axis=1)
        ax = np.stack([-np.sin(phi), np.cos(phi), np.zeros(n)], axis=1)
        ax[1::2] = [0, 0, 1]
    else:
        pos = rng.uniform(-0.2, 0.2, (n, 3))
        ax = rng.normal(size=(n, 3))
    ax = ax + rng.normal(0, 0.02, ax.shape)
    ax /= np.linalg.norm(ax, axis=1, keepdims=True)
    return pos, ax


@st.composite
def calibrated_arrays(draw):
    seed = draw(st.integers(0, 2**32 - 1))
    n = draw(st.integers(6, 12))
    rng = np.random.default_rng(seed)
    pos, ax = random_geometry(rng, n)
    k = 10 ** rng.uniform(0, 3.4)  # 1 .. 2500 counts per m/s^2
    sens = k * ax * (1 + rng.uniform(-0.01, 0.04, (n, 1))) + k * rng.normal(0, 0.0175, (n, 3))
    offsets = rng.uniform(200, 65300, n)
    try:
        t = quantize(offsets, sens, pos, "prop")
    except (IllConditionedError, SingularError):
        assume(False)
    return t, offsets, sens, pos, rng


RAW_EDGE = np.array([0, 1, 32767, 32768, 65534, 65535])
W_EDGE = np.array([-32768, -32767, -129, -128, -1, 0, 1, 127, 128, 32767])


def inputs(rng, t, count=6):
    n = t.n
    raw = rng.integers(0, 65536, (count, n))
    near = t.trim.astype(np.int64) + rng.integers(-3000, 3000, (count, n))
    raw[: count // 2] = np.clip(near[: count // 2], 0, 65535)
    raw[-1] = rng.choice(RAW_EDGE, n)
    w = rng.integers(-32768, 32768, (count, 3))
    w[0] = rng.integers(-200, 200, 3)  # slow rotation: p exact
    w[1] = rng.choice(W_EDGE, 3)
    return raw, w


def intermediates_overflow(t, raw, w):
    """Python big-int check: does any int32 intermediate of the core overflow?"""
    x = np.clip(raw.astype(object) - t.trim.astype(object), -32768, 32767)
    acc = np.array([[int(sum(int(t.m[j, i]) * int(x[r, i]) for i in range(t.n))) for j in range(6)]
                    for r in range(len(raw))], dtype=object) - t.k.astype(object)
    p = model.omega_products(w.astype(float))
    tacc = (p @ t.g.T.astype(float)) * 2.0 ** (-2 * FORMATS.omega_frac - t.g_shift + t.m_shift)
    lim = BIG * (1 - 2**-12)
    out = (acc.astype(float) - tacc) * 2.0 ** (-t.m_shift.astype(float))
    return (np.abs(acc.astype(float)) >= lim) | (np.abs(tacc) >= lim) | \
        (np.abs(acc.astype(float) - tacc) >= lim) | (np.abs(out) >= lim)


@core
@given(calibrated_arrays())
def test_resolve_within_bound_of_exact(case):
    t, _, _, _, rng = case
    raw, w = inputs(rng, t)
    out, flags = native.process_batch(t.resolver(), t.trim, raw, w)
    exact, bound, trim_sat = exact_fixed_semantics(t, raw, w)
    assert np.array_equal(flags & lib.AC_FLAG_TRIM_SAT > 0, trim_sat)
    ok = np.abs(out - exact) <= 0.5 + bound + 1e-9
    out_sat = (flags & lib.AC_FLAG_OUT_SAT) > 0
    # an unflagged sample is within the bound; a flagged one really overflowed
    assert np.all(ok[~out_sat])
    if out_sat.any():
        assert np.all(intermediates_overflow(t, raw[out_sat], w[out_sat]).any(axis=1))


@core
@given(calibrated_arrays())
def test_resolve_without_rotation_is_correctly_rounded(case):
    """No omega: the linear path is exact before one rounding (half up)."""
    t, _, _, _, rng = case
    raw, _ = inputs(rng, t)
    out, flags = native.process_batch(t.resolver(), t.trim, raw, None)
    exact, _, _ = exact_fixed_semantics(t, raw, None)
    clean = flags == 0
    assert np.array_equal(out[clean], np.floor(exact[clean] + 0.5))


@core
@given(calibrated_arrays())
def test_device_build_matches_host_quantizer(case):
    t, *_ = case
    r, cond_log2 = native.build_resolver(t.sens_q, t.pos_q, t.offset_q)
    assert cond_log2 == t.cond_log2 or abs(cond_log2 - t.cond_log2) <= 1
    dev = native.resolver_arrays(r)
    # compare dequantised coefficients: 29-bit xf arithmetic vs float64, so the
    # two may round differently by one mantissa LSB, more when cond is large
    tol_rel = 2.0 ** (t.cond_log2 - 24)
    for name, shift in (("m", "m_shift"), ("g", "g_shift")):
        a = dev[name] * 2.0 ** -dev[shift].astype(float)[:, None]
        b = getattr(t, name) * 2.0 ** -getattr(t, shift).astype(float)[:, None]
        lsb = 2.0 ** -np.minimum(dev[shift], getattr(t, shift)).astype(float)[:, None]
        assert np.all(np.abs(a - b) <= lsb * (1 + 32767 * tol_rel))
    ka = dev["k"] * 2.0 ** -dev["m_shift"].astype(float)
    kb = t.k * 2.0 ** -t.m_shift.astype(float)
    assert np.all(np.abs(ka - kb) <= 2.0 ** -np.minimum(dev["m_shift"], t.m_shift) * (1 + 1e-6 * 0)
                  + np.abs(kb) * 2.0**-26 * 2.0 ** t.cond_log2)


@core
@given(calibrated_arrays())
def test_fixed_path_tracks_float_reference(case):
    """Against the float reference: the core's arithmetic bound plus the rounding
    of the table entries, nothing else."""
    t, offsets, sens, pos, rng = case
    raw, w = inputs(rng, t)
    out, flags = native.process_batch(t.resolver(), t.trim, raw, w)
    clean = flags == 0
    assume(clean.any())
    f, a = model.resolve(t.offsets(), t.sensitivity(), t.positions(), raw,
                         w / 2.0 ** FORMATS.omega_frac)
    ref = np.hstack([f, a]) * OUT
    _, bound, _ = exact_fixed_semantics(t, raw, w)
    total = 0.5 + bound + table_error_bound(t, raw, w) + 1e-9 * (1 + np.abs(ref))
    assert np.all((np.abs(out - ref) <= total)[clean])


# ---- inversion --------------------------------------------------------------

def to_xf_matrix(A):
    a = ffi.new("ac_xf[6][6]")
    exact = np.zeros((6, 6))
    for i in range(6):
        for j in range(6):
            fr, ex = math.frexp(float(A[i, j]))
            m = int(round(fr * 2**30))
            e = ex - 30
            if abs(m) == 2**30:
                m //= 2
                e += 1
            a[i][j].m, a[i][j].e = m, e
            exact[i, j] = math.ldexp(m, e)
    return a, exact


@core
@given(st.integers(0, 2**32 - 1), st.floats(0, 15))
def test_invert6_accuracy_scales_with_condition(seed, log2cond):
    rng = np.random.default_rng(seed)
    U, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    V, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    sv = 2.0 ** np.linspace(0, -log2cond, 6)
    A = (U * sv) @ V.T * 10 ** rng.uniform(-3, 3)
    a, exact = to_xf_matrix(A)
    perm = ffi.new("int8_t[6]")
    cl2 = ffi.new("int16_t *")
    st_ = lib.ac_invert6(a, perm, cl2)
    kappa = np.linalg.norm(exact, 1) * np.linalg.norm(np.linalg.inv(exact), 1)
    assert abs(cl2[0] - math.ceil(math.log2(kappa))) <= 1
    if cl2[0] > FORMATS.cond_log2_max:
        assert st_ == lib.AC_ERR_ILL_COND
        return
    assert st_ == lib.AC_OK
    inv = np.array([[math.ldexp(a[i][j].m, a[i][j].e) for j in range(6)] for i in range(6)])
    ref = np.linalg.inv(exact)
    # Gauss-Jordan with partial pivoting: forward error <~ n^2 kappa u, u = 2^-29
    err = np.abs(inv - ref).max() / np.abs(ref).max()
    assert err <= 36 * kappa * 2.0**-29


def test_invert6_singular():
    A = np.arange(36, dtype=float).reshape(6, 6) + 1  # rank 2
    a, _ = to_xf_matrix(A)
    assert lib.ac_invert6(a, ffi.new("int8_t[6]"), ffi.NULL) == lib.AC_ERR_SINGULAR


@pytest.mark.parametrize("layout", ["all_x", "one_point", "coplanar_axes"])
def test_singular_geometries_are_reported(layout):
    n = 6
    pos = np.random.default_rng(1).uniform(-0.1, 0.1, (n, 3))
    ax = np.random.default_rng(2).normal(size=(n, 3))
    if layout == "all_x":
        ax[:] = [1, 0, 0]
    elif layout == "one_point":
        pos[:] = [0.05, 0, 0]  # same point: alpha about x is invisible
    else:
        ax[:, 2] = 0  # nothing senses f_z
    ax /= np.linalg.norm(ax, axis=1, keepdims=True)
    sens = 100 * ax
    sq = np.round(sens * 2**FORMATS.sens_frac)
    pq = np.round(pos * 2**FORMATS.pos_frac)
    with pytest.raises((SingularError, IllConditionedError)):
        native.build_resolver(sq, pq, np.zeros(n))
    with pytest.raises((SingularError, IllConditionedError, QuantizeError)):
        quantize(np.full(n, 1000.0), sens, pos)


def test_build_rejects_bad_sizes():
    with pytest.raises(Exception) as e:
        native.build_resolver(np.zeros((5, 3)), np.zeros((5, 3)), np.zeros(5))
    assert "ac_resolver_build" in str(e.value)


# ---- rate integrator --------------------------------------------------------

@core
@given(st.integers(0, 2**32 - 1), st.sampled_from([0, 1, 109, 1000, 65535]),
       st.sampled_from([2.5, 60.0, 100.0, 1000.0]))
def test_rate_integrator_within_bound(seed, leak, rate_hz):
    rng = np.random.default_rng(seed)
    n = 200
    dt_m, dt_shift = dt_fixed(1.0 / rate_hz)
    alpha_q = rng.integers(-2**20, 2**20, (n, 3)) // rng.choice([1, 64, 4096])
    w_q, sat = native.rate_integrate(alpha_q, dt_m, dt_shift, leak)
    dtq = dt_m * 2.0**-dt_shift
    ref = model.rate_integrate(alpha_q / OUT, dtq, leak / 65536) * 2.0**FORMATS.omega_frac
    steps = np.minimum(np.arange(1, n + 1), 65536 / max(leak, 1e-9))
    bound = (0.5 + steps * 2.0 ** (FORMATS.omega_frac - FORMATS.rate_state_frac))[:, None]
    # up to the first saturated step the integrator is within its bound; the
    # first flagged step is one where the reference itself leaves the range
    first = int(np.argmax(sat)) if sat.any() else n
    assert np.all(np.abs(w_q - ref)[:first] <= bound[:first] + 1e-9)
    if first < n:
        assert np.any(np.abs(ref[first]) >= 32767.5 - bound[first, 0])
    else:
        assert np.all(np.abs(ref) < 32767.5 + bound)


def test_rate_bad_init():
    stt = ffi.new("ac_rate *")
    assert lib.ac_rate_init(stt, 0, 20, 0) == lib.AC_ERR_RANGE
    assert lib.ac_rate_init(stt, 100, 15, 0) == lib.AC_ERR_RANGE
    assert lib.ac_rate_init(ffi.NULL, 100, 20, 0) == lib.AC_ERR_NULL
    # 1 s steps: dt = 32768 * 2^-15 needs dt_shift 15, below the core's 16
    assert lib.ac_rate_init(stt, 32768, 15, 0) == lib.AC_ERR_RANGE
