"""The array's own omega in the integer C core (ac_omega.h, issue 36): the core against its
float twin (estimators.omega_fixed.omega_reference) within the bound ac_omega.h states, over
whole input ranges; the fixed engine against the truth of the independent generator; the
table's constants against the float estimator's."""
from __future__ import annotations

import inspect

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import indep_model as im
from accelcal import model
from accelcal.errors import CoreError, InputError
from accelcal.estimators import omega as omega_mod, omega_filter
from accelcal.estimators.omega_fixed import omega_fixed_from_recording, omega_reference, pretrim, table_for_recording
from accelcal.firmware.native import ffi, lib
from accelcal.firmware.omega_table import (OMEGA_JUMP_CHI2, OMEGA_RANK_RTOL, OMEGA_SIGMA0, OMEGA_SNAP, omega_run,
                                           omega_table, to_xf, xf_value)
from accelcal.firmware.quantize import QuantizeError, quantize
from accelcal.io.device import axes_device, tetrahedron_device
from core_settings import CORE_EXAMPLES

#: each example runs the Python twin of the fixed arithmetic over a recording (~0.1-0.2 s): a tenth of
#: the core's 10,000 took 5 min of the CI's suite (budget 15 min); a fortieth, with the limits drawn
#: explicitly by the strategies, keeps it near 1 min
OMEGA_EXAMPLES = max(20, CORE_EXAMPLES // 40)

#: ac_omega.h's bound: |w_fixed - w_float| <= 2^-17 + 2^-20 |w| plus the output's rounding 2^-17 (rad/s)
Q16 = 2.0 ** -16


def _bound(w_ref):
    return 2.0 ** -17 + 2.0 ** -20 * np.abs(w_ref) + 2.0 ** -17


def _layout(r, jitter, seed, origin):
    dev = tetrahedron_device(r) if origin is None else axes_device(r, origin=True)
    rng = np.random.default_rng(seed)
    pos = dev.positions + rng.normal(scale=jitter * r, size=(dev.n_channels, 3))
    ax = dev.axes + rng.normal(scale=jitter, size=(dev.n_channels, 3))
    ax /= np.linalg.norm(ax, axis=1, keepdims=True)
    gain = dev.counts_per_mps2 * (1 + rng.uniform(-0.03, 0.03, dev.n_channels))
    return dev, pos, ax * gain[:, None], 32768 + rng.uniform(-500, 500, dev.n_channels)


def _readings(sens, pos, offs, w, dw, f, noise, rng):
    """Counts of the model's channels (uint16 codes, rounded, clipped)."""
    acc = f[:, None, :] + np.cross(dw[:, None, :], pos[None]) + np.cross(w[:, None, :], np.cross(w[:, None, :], pos[None]))
    raw = offs + np.einsum("nij,ij->ni", acc, sens) + rng.normal(scale=noise, size=(len(w), len(offs)))
    return np.clip(np.round(raw), 0, 65535)


def _compare(table, x):
    """The core and the twin agree within the bound on every sample before the first one where
    the jump test's decision differs, and there the twin's margin is within rounding of 0."""
    w16, w10, sig, flags, sat = omega_run(table, x)
    margins = []
    w_ref, cov, _ = omega_reference(table, x, margins)
    margins = np.asarray(margins)
    jumped = (flags & lib.AC_OMEGA_FLAG_JUMP) != 0
    differ = np.flatnonzero(jumped != (margins < 0))
    end = len(x) if differ.size == 0 else int(differ[0])
    if end < len(x):
        # a tie: cost(ML) and cost(prediction) - jump are equal to within the arithmetic's rounding
        # (ac_xf's 2^-30 on terms of the whitened readings' size squared, and the jump's 1e-6)
        scale = np.max(np.abs(x[end]).astype(float)) ** 2 * 1e-9 + 1e-6 * table.jump
        assert abs(margins[end]) <= scale, (end, margins[end])
    wc = w16[:end] * Q16
    clipped = np.abs(w_ref[:end]) >= 32768 - Q16
    err = np.abs(wc - w_ref[:end])
    ok = (err <= _bound(w_ref[:end])) | clipped
    assert ok.all(), (np.argwhere(~ok)[:3], err[~ok][:3], w_ref[:end][~ok][:3])
    # the Q5.10 output is the same value, clipped to int16 with the flag
    q10 = np.clip(np.floor(w_ref[:end] * 1024 + 0.5), -32768, 32767)
    assert np.all(np.abs(w10[:end] - q10) <= 1 + 2 ** -10 * np.abs(q10))
    at_rail16 = np.any(np.abs(w_ref[:end]) * 1024 >= 32767.5 - 1, axis=1)
    sat16 = (flags[:end] & lib.AC_OMEGA_FLAG_SAT16) != 0
    assert not np.any(sat16[~at_rail16])
    beyond = np.any(np.abs(w_ref[:end]) * 1024 > 32768 + 1, axis=1)
    assert np.all(sat16[beyond])
    sig_ref = np.sqrt(np.diagonal(cov[:end], axis1=1, axis2=2))
    assert np.all(np.abs(sig[:end] * Q16 - sig_ref) <= _bound(sig_ref))
    return end


@settings(max_examples=OMEGA_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(r=st.floats(0.02, 0.2), jitter=st.floats(0.0, 0.05), seed=st.integers(0, 2 ** 16),
       origin=st.sampled_from([None, True]), w0=st.lists(st.floats(-40, 40), min_size=3, max_size=3),
       dw=st.lists(st.floats(-300, 300), min_size=3, max_size=3), noise=st.floats(0.0, 30.0),
       rate=st.sampled_from([100.0, 500.0, 2000.0]))
def test_core_matches_twin_on_turns(r, jitter, seed, origin, w0, dw, noise, rate):
    """Turning layouts (rates up to 40 rad/s, any start: at rest or mid-turn, the jump test):
    core and twin agree within ac_omega.h's bound."""
    dev, pos, sens, offs = _layout(r, jitter, seed, origin)
    rng = np.random.default_rng(seed + 1)
    n = 24
    t = np.arange(n) / rate
    w = np.asarray(w0)[None] + np.asarray(dw)[None] * t[:, None]
    f = np.array([0.0, 0.0, 9.81])[None] + rng.normal(scale=2.0, size=3)[None]
    raw = _readings(sens, pos, offs, w, np.repeat(np.asarray(dw)[None], n, 0), np.repeat(f, n, 0), noise, rng)
    try:
        tables = quantize(offs, sens / 1.0, pos)
        table = omega_table(tables, np.full(len(offs), max(noise, 0.3)), 1.0 / rate)
    except QuantizeError:
        return   # a layout beyond the formats is refused, not run
    x, _ = pretrim(tables, raw)
    _compare(table, x)


@settings(max_examples=OMEGA_EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), seed=st.integers(0, 2 ** 16))
def test_core_matches_twin_over_int16(data, seed):
    """Any int16 readings, the limits included (the state then far from anything a layout
    reads): the core agrees with its twin within the bound, or both fail (AC_ERR_RANGE)."""
    dev, pos, sens, offs = _layout(0.05, 0.01, seed, None)
    tables = quantize(offs, sens, pos)
    table = omega_table(tables, np.full(12, 1.0), 0.002)
    edge = st.sampled_from([-32768, -32767, -1, 0, 1, 32766, 32767])
    x = np.array(data.draw(st.lists(st.lists(st.one_of(edge, st.integers(-32768, 32767)), min_size=12, max_size=12),
                                    min_size=1, max_size=6)), dtype=np.int16)
    try:
        _compare(table, x)
    except CoreError:
        with np.errstate(all="ignore"):
            w_ref, _, _ = omega_reference(table, x)
        assert not np.all(np.isfinite(w_ref)) or np.max(np.abs(w_ref)) > 1e6


def test_fixed_engine_at_the_float_estimators_accuracy():
    """resolve --engine fixed --omega array on the independent generator's turns: the C core's
    omega within 0.001 rad/s of the float estimator and as close to the truth (RMS within 2 %)."""
    d = im.make_spin_array(tetrahedron_device(), 3, n_turns=4)
    est_c = omega_fixed_from_recording(d["device"], d["cal"], d["recording"])
    est_f = omega_mod.omega_from_recording(d["device"], d["cal"], d["recording"])
    assert np.max(np.abs(est_c.w - est_f.w)) < 1e-3
    rms_c = np.sqrt(np.mean((est_c.w - d["w"]) ** 2))
    rms_f = np.sqrt(np.mean((est_f.w - d["w"]) ** 2))
    assert rms_c < 1.02 * rms_f
    assert np.all(est_c.sigma > 0)


def test_fixed_engine_is_the_core_bit_for_bit():
    """The fixed engine's omega is the core's Q15.16 output on the header's table."""
    d = im.make_spin_array(tetrahedron_device(), 5, n_turns=2)
    tables, table = table_for_recording(d["device"], d["cal"], d["recording"])
    x, _ = pretrim(tables, d["recording"].raw)
    w16 = omega_run(table, x)[0]
    est = omega_fixed_from_recording(d["device"], d["cal"], d["recording"])
    assert np.array_equal(est.w, w16 * Q16)


def test_table_refuses_layouts_without_all_six_products():
    dev = axes_device(0.05, origin=False)           # 9 channels: 3 of the 6 products
    tables = quantize(np.full(9, 32768.0), dev.nominal_sensitivity(), dev.positions)
    with pytest.raises(QuantizeError, match="six rate products"):
        omega_table(tables, np.ones(9), 0.002)
    d = im.make_spin_array(dev, 0, n_turns=1)
    with pytest.raises(InputError):
        omega_fixed_from_recording(d["device"], d["cal"], d["recording"])


def test_constants_are_the_float_estimators():
    assert OMEGA_JUMP_CHI2 == omega_filter.JUMP_CHI2
    assert OMEGA_RANK_RTOL == omega_mod.RANK_RTOL
    assert OMEGA_SNAP == omega_mod.SNAP
    assert inspect.signature(omega_mod.array_omega).parameters["sigma0"].default == OMEGA_SIGMA0


@given(st.floats(-1e300, 1e300, allow_nan=False), st.integers(-2 ** 31, 2 ** 31 - 1), st.integers(-40, 40))
def test_xf_conversion(v, i, frac):
    """to_xf normalises and rounds as the core does (ac_xf_from_fixed on integers)."""
    m, e = to_xf(v)
    assert m == 0 or 2 ** 29 <= abs(m) < 2 ** 30
    assert abs(xf_value((m, e)) - v) <= abs(v) * 2.0 ** -30
    out = ffi.new("ac_xf *")
    assert lib.ac_xf_from_fixed(i, frac, out) == 0
    assert (out.m, out.e) == to_xf(i * 2.0 ** -frac)


def test_model_split_is_what_the_table_holds():
    """The table's rows reproduce the float split's q and uncorrected alpha to 2^-24 relative."""
    dev = tetrahedron_device()
    tables = quantize(np.full(12, 32768.0), dev.nominal_sensitivity(), dev.positions)
    noise = np.full(12, 1.0)
    table = omega_table(tables, noise, 0.002)
    split = model.centripetal_split(tables.positions(), tables.sensitivity(), noise)
    want = np.vstack([split.qmap, split.lin[3:]])
    assert np.max(np.abs(table.rows() - want)) <= 2.0 ** -24 * np.max(np.abs(want))
