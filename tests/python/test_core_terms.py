"""The C core's correctable terms (ac_temp.h, ac_skew.h, ac_nonlin.h) against their float
reference (accelcal.firmware.terms), within the bounds their headers state, over the whole
input ranges (int16 readings and temperatures, every table field's range) and at the edges."""
import math

import numpy as np
import pytest
from core_settings import core
from hypothesis import example, assume, given, strategies as st

from accelcal.firmware import native
from accelcal._core import ffi, lib
from accelcal.firmware import terms
from accelcal.firmware.terms_fixed import E_MAX, GC_FRAC, OC_FRAC, lag_bound, lag_fixed, nonlin_bound, temp_bound

I16 = st.one_of(st.integers(-32768, 32767), st.sampled_from([-32768, -32767, -1, 0, 1, 32766, 32767]))
TEMP_LSB = 2.0 ** -lib.AC_TEMP_FRAC
O_LSB = 2.0 ** -native.FORMATS.offset_frac


def clip16(v):
    return max(-32768, min(32767, int(v)))


# ---------------------------------------------------------------- the lag filter


@core
@given(st.lists(I16, min_size=1, max_size=40), st.floats(1e-7, 1.0), st.booleans())
def test_lag_within_bound(temps, c, no_lag):
    """ac_temp_lag_step against lag_temperature (the exact weight c) on any run of int16
    temperatures: within lag_bound, unless the step says it clipped (an input 128 degC or more
    from the lagged state)."""
    tau, dt = (None, 1.0) if no_lag else (-1.0 / math.log1p(-c) if c < 1.0 else None, 1.0)
    k, shift = lag_fixed(tau, dt)
    out, sat = native.temp_lag_run(k, shift, temps)
    T = np.asarray(temps, float) * TEMP_LSB
    ref, _ = terms.lag_temperature(T, tau, dt)
    jumps = np.abs(T[1:] - ref[:-1])    # the input against the state it updates
    if not sat.any():
        bound = lag_bound(k, shift, tau, dt, float(np.ptp(T)))
        assert np.all(np.abs(out * TEMP_LSB - ref) <= bound)
    else:
        assert np.any(jumps > 127.99)  # clipping needs a step beyond the state's range (128 degC)
    assert out[0] == temps[0]         # the first step starts the filter at its input


def test_lag_long_time_constant_moves():
    """A lag of an hour at 60 Hz (weight 4.6e-6) still follows a step (no dead band at the
    state's resolution): after one time constant 1 - 1/e of the step, within the bound."""
    dt, tau = 1.0 / 60.0, 3600.0
    k, shift = lag_fixed(tau, dt)
    n = int(tau / dt)
    temps = np.r_[0, np.full(n, 10 * 256)]
    out, sat = native.temp_lag_run(k, shift, temps)
    ref, _ = terms.lag_temperature(temps * TEMP_LSB, tau, dt)
    assert not sat.any()
    assert abs(ref[-1] - 10 * (1 - math.exp(-1))) < 0.01
    assert abs(out[-1] * TEMP_LSB - ref[-1]) <= lag_bound(k, shift, tau, dt, 10.0)
    assert lag_bound(k, shift, tau, dt, 10.0) < 0.01


def test_lag_init_range():
    f = ffi.new("ac_temp_lag *")
    assert lib.ac_temp_lag_init(f, 3, 1) == lib.AC_ERR_RANGE       # weight 1.5 > 1
    assert lib.ac_temp_lag_init(f, 1, 48) == lib.AC_ERR_RANGE
    assert lib.ac_temp_lag_init(ffi.NULL, 1, 0) == lib.AC_ERR_NULL
    assert lib.ac_temp_lag_init(f, 65535, 16) == lib.AC_OK


# ---------------------------------------------------------------- the temperature correction


@st.composite
def temp_tables(draw):
    n = draw(st.integers(1, lib.AC_MAX_CHANNELS))
    oc = draw(st.lists(I16.filter(lambda v: v > -32768), min_size=n, max_size=n))
    gc = draw(st.lists(I16.filter(lambda v: v > -32768), min_size=n, max_size=n))
    o = draw(st.lists(st.integers(-128, 128), min_size=n, max_size=n))
    t_ref = draw(I16)
    return n, t_ref, oc, gc, o


def temp_reference(table, t_off, t_gain, x):
    n, t_ref, oc, gc, o = table
    dto = clip16(t_off - t_ref) * TEMP_LSB
    dtg = clip16(t_gain - t_ref) * TEMP_LSB
    occ, gcc, oo = (np.asarray(oc) * 2.0 ** -OC_FRAC, np.asarray(gc) * 2.0 ** -GC_FRAC, np.asarray(o) * O_LSB)
    e = gcc * dtg
    b = oo    # counts about the trim: the reference's offsets are o
    ref = terms.temperature_correct(np.asarray(x, float)[None, :], b, 0.0, occ, gcc, [dto], [dtg])[0]
    return ref, e, (t_off - t_ref != clip16(t_off - t_ref)) or (t_gain - t_ref != clip16(t_gain - t_ref))


@core
@given(temp_tables(), I16, I16, st.data())
def test_temp_correct_within_bound(table, t_off, t_gain, data):
    """ac_temp_correct against temperature_correct with the table's coefficients: within
    temp_bound wherever it does not flag a clip; and it flags one only where a value leaves
    its range (|e| beyond AC_TEMP_E_MAX, a temperature difference or a reading beyond int16)."""
    n, t_ref, oc, gc, o = table
    x = data.draw(st.lists(I16, min_size=n, max_size=n))
    t = native.new_temp_table(t_ref, oc, gc, o)
    y, sat = native.temp_correct(t, t_off, t_gain, x)
    ref, e, dt_clipped = temp_reference(table, t_off, t_gain, x)
    if not sat:
        assert np.all(np.abs(y - ref) <= temp_bound(np.maximum(np.abs(x), np.abs(ref)), e))
    else:
        w = np.asarray(x) - np.asarray(o) * O_LSB - np.asarray(oc) * 2.0 ** -OC_FRAC * clip16(t_off - t_ref) * TEMP_LSB
        assert (dt_clipped or np.any(np.abs(e) > E_MAX * 2.0 ** -19 - 2.0 ** -20)
                or np.any(np.abs(ref) > 32767 - 1) or np.any(np.abs(w) > 32767 - 1))


@core
@given(temp_tables(), st.integers(-40 * 256, 40 * 256), st.integers(-40 * 256, 40 * 256), st.data())
def test_temp_correct_realistic_no_clip(table, dto, dtg, data):
    """Within +-40 degC of t_ref, gain tempcos up to 1e-3/degC and offset tempcos up to 100
    counts/degC, on readings within +-26000 counts: never a clip, and within 0.6 counts
    (+ |x| 2^-17) of the float reference."""
    n, t_ref, oc, gc, o = table
    oc = data.draw(st.lists(st.integers(-100 * 256, 100 * 256), min_size=n, max_size=n))
    gc = data.draw(st.lists(st.integers(-16777, 16777), min_size=n, max_size=n))   # 1e-3 2^24
    x = data.draw(st.lists(st.integers(-26000, 26000), min_size=n, max_size=n))
    t_ref = 25 * 256
    table = (n, t_ref, oc, gc, o)
    t = native.new_temp_table(t_ref, oc, gc, o)
    y, sat = native.temp_correct(t, t_ref + dto, t_ref + dtg, x)
    ref, e, _ = temp_reference(table, t_ref + dto, t_ref + dtg, x)
    assert not sat
    assert np.all(np.abs(y - ref) <= 0.6 + np.abs(x) * 2.0 ** -17)


def test_temp_table_checks():
    t = native.new_temp_table(0, [0], [0], [129])
    assert lib.ac_temp_check(t) == lib.AC_ERR_FORMAT     # |o| > 128: not a residual offset
    t.o[0], t.n = 0, 0
    assert lib.ac_temp_check(t) == lib.AC_ERR_SIZE
    with pytest.raises(Exception):
        native.temp_correct(t, 0, 0, np.zeros(0, np.int16))   # n = 0: refused per call


# ---------------------------------------------------------------- the skew


@st.composite
def skew_cases(draw):
    n = draw(st.integers(1, lib.AC_MAX_CHANNELS))
    length = draw(st.integers(2, 12))
    whole = draw(st.lists(st.integers(0, length - 2), min_size=n, max_size=n))
    frac = draw(st.lists(st.one_of(st.integers(0, 32767), st.sampled_from([0, 1, 16384, 32767])),
                         min_size=n, max_size=n))
    steps = draw(st.integers(1, 30))
    x = draw(st.lists(st.lists(I16, min_size=n, max_size=n), min_size=steps, max_size=steps))
    return length, whole, frac, np.asarray(x, np.int16)


@core
@given(skew_cases())
def test_skew_within_half_count(case):
    """ac_skew_step against skew_correct with the table's delays: within 0.5 count, and the
    result between the two samples it interpolates (it never clips)."""
    length, whole, frac, x = case
    t = native.new_skew_table(length, whole, frac)
    line = native.SkewLine(t)
    y = np.array([line.step(v) for v in x])
    delays = np.asarray(whole) + np.asarray(frac) / 2.0 ** 15
    ref, _ = terms.skew_correct(x.astype(float), delays, np.repeat(x[:1].astype(float), length, axis=0))
    assert np.all(np.abs(y - ref) <= 0.5)


def test_skew_checks_and_caller_buffer():
    t = native.new_skew_table(3, [1, 2], [0, 0])
    assert lib.ac_skew_check(t) == lib.AC_ERR_FORMAT       # whole 2 needs len >= 4
    t = native.new_skew_table(4, [1, 2], [0, 40000])
    assert lib.ac_skew_check(t) == lib.AC_ERR_FORMAT       # frac beyond 2^15 - 1
    t = native.new_skew_table(4, [1, 2], [0, 1])
    buf = ffi.new("int16_t[]", 7)
    line = ffi.new("ac_skew_line *")
    assert lib.ac_skew_init(line, t, buf, 7) == lib.AC_ERR_SIZE   # 4 x 2 values needed
    assert lib.ac_skew_init(line, t, buf, 8) == lib.AC_OK


# ---------------------------------------------------------------- the nonlinearity


@st.composite
def nonlin_cases(draw):
    n = draw(st.integers(1, lib.AC_MAX_CHANNELS))
    shift = draw(st.integers(0, 30))
    a2, a3 = [], []
    for _ in range(n):
        v2 = draw(st.integers(-32767, 32767))
        room = 32767 - abs(v2)
        a2.append(v2)
        a3.append(draw(st.integers(-room, room)))
    x = draw(st.lists(I16, min_size=n, max_size=n))
    o = draw(st.lists(st.floats(-0.5, 0.5), min_size=n, max_size=n))
    return shift, a2, a3, np.asarray(x), np.asarray(o)


def nonlin_reference(shift, a2, a3, x, o):
    c2, c3 = np.asarray(a2) / 2.0 ** (15 + shift), np.asarray(a3) / 2.0 ** (30 + shift)
    unit = np.tile([1.0, 0.0, 0.0], (len(a2), 1))     # |s| = 1: k2 = c2, k3 = c3
    # readings about the trim: b = trim + o is o there, and the result is the corrected reading
    ref = terms.nonlinearity_invert(x[None, :].astype(float), o, unit, c2, c3)[0]
    return ref, c2, c3


@core
@given(nonlin_cases())
@example((19, [0] * 8 + [29962] + [0] * 3, [0] * 12, np.array([0] * 8 + [-2966] + [0] * 3),
          np.array([0.0] * 8 + [0.5] + [0.0] * 3)))      # 5e-5 counts beyond the bound before the trim's fraction was in it
def test_nonlin_within_bound(case):
    """ac_nonlin_invert against nonlinearity_invert (the same iterations, z_0 = x - o) with
    the table's coefficients: within nonlin_bound unless it flags a clip, and a clip only
    where an iterate leaves int16."""
    shift, a2, a3, x, o = case
    t = native.new_nonlin_table(shift, a2, a3)
    y, sat = native.nonlin_invert(t, x.astype(np.int16))
    ref, c2, c3 = nonlin_reference(shift, a2, a3, x, o)
    z = np.maximum(np.abs(x), np.abs(ref)) + 1.0
    bound = nonlin_bound(z, c2, c3, shift)
    finite = np.isfinite(ref) & np.isfinite(bound)
    if not sat:
        assert np.all(np.abs(y - ref)[finite] <= bound[finite])


@core
@given(st.integers(1, lib.AC_MAX_CHANNELS), st.data())
def test_nonlin_realistic_tight(n, data):
    """Up to 5 % of the reading at full scale (2.5 % square, 2.5 % cube), readings within
    +-28000 counts (the result stays in int16): no clip, and within 1.2 counts of the float
    iteration."""
    c2 = np.asarray(data.draw(st.lists(st.floats(-0.025, 0.025), min_size=n, max_size=n))) / 32768
    c3 = np.asarray(data.draw(st.lists(st.floats(-0.025, 0.025), min_size=n, max_size=n))) / 32768 ** 2
    shift = int(math.floor(math.log2(32766 / max(float(np.max(np.abs(c2) * 2 ** 15 + np.abs(c3) * 2 ** 30)),
                                                 1e-12))))
    shift = min(30, shift)
    a2 = np.floor(c2 * 2.0 ** (15 + shift) + 0.5).astype(int)
    a3 = np.floor(c3 * 2.0 ** (30 + shift) + 0.5).astype(int)
    assume(np.all(np.abs(a2) + np.abs(a3) <= 32767))
    x = np.asarray(data.draw(st.lists(st.integers(-28000, 28000), min_size=n, max_size=n)))
    t = native.new_nonlin_table(shift, a2, a3)
    y, sat = native.nonlin_invert(t, x.astype(np.int16))
    ref, _, _ = nonlin_reference(shift, a2, a3, x, np.zeros(n))
    assert not sat
    assert np.all(np.abs(y - ref) <= 1.2)


def test_nonlin_undoes_the_forward_term():
    """The inversion undoes the nonlinearity effect's forward term to within the iteration's
    L^3 (the float reference) and the core's rounding: readings 0.5 % bent at 1 g on a +-2 g
    16-bit chip (16384 counts/g)."""
    s = np.array([[16384 / 9.80665, 0.0, 0.0]])
    k2, k3 = np.array([0.005 * 16384 / 9.80665 ** 2]), np.array([0.002 * 16384 / 9.80665 ** 3])
    a = np.linspace(-18.6, 18.6, 41)[:, None]     # +-1.9 g: the bent reading stays in int16
    lin = s[0, 0] * a
    raw = lin + k2 * a ** 2 + k3 * a ** 3
    ref = terms.nonlinearity_invert(raw, [0.0], s, k2, k3)
    c2, c3 = terms.nonlinearity_coefficients(s, k2, k3)
    zmax = float(np.max(np.abs(raw)))
    L = 2 * abs(c2[0]) * zmax + 3 * abs(c3[0]) * zmax ** 2        # the contraction: 0.044 here
    # fixed-point iteration from z_0 = raw: |z_K - lin| <= L^K |raw - lin|
    assert np.all(np.abs(ref - lin) <= L ** terms.NONLIN_ITERATIONS * np.abs(raw - lin) + 1e-9)
    assert np.max(np.abs(ref - lin)) < 0.06
    shift = min(30, int(math.floor(math.log2(32766 / (abs(c2[0]) * 2 ** 15 + abs(c3[0]) * 2 ** 30)))))
    t = native.new_nonlin_table(shift, [round(c2[0] * 2 ** (15 + shift))], [round(c3[0] * 2 ** (30 + shift))])
    y = np.array([native.nonlin_invert(t, np.array([round(v)], np.int16))[0][0] for v in raw[:, 0]])
    assert np.max(np.abs(y - lin[:, 0])) <= 1.0
    assert np.max(np.abs(raw[:, 0] - lin[:, 0])) > 300      # the term itself: hundreds of counts


def test_iteration_counts_agree():
    """The float reference iterates as often as the core (AC_NONLIN_ITERATIONS)."""
    assert terms.NONLIN_ITERATIONS == lib.AC_NONLIN_ITERATIONS
