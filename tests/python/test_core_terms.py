"""The C core's correctable terms (ac_temp.h, ac_skew.h, ac_nonlin.h) against their float
reference (accelcal.firmware.terms), within the bounds their headers state, over the whole
input ranges (int16 readings and temperatures, every table field's range) and at the edges.

Each example checks a batch of input vectors (core_batch.py): the first drawn by the hypothesis
strategy below, the rest by numpy over the same ranges and edges; core_settings.py has the counts."""
import math

import numpy as np
import pytest
from core_batch import generator, floats, i16, ints, rows_hold, seeds, stack
from core_settings import batched
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


def lag_runs(rng, count):
    """``count`` (temps, c, no_lag) as the strategy below draws them: runs of 1-40 I16, the
    weight c in [1e-7, 1] (half of them log-uniform, so small weights come as often as large)."""
    size = ints(rng, 1, 40, count)
    c = np.where(rng.random(count) < 0.5, floats(rng, 1e-7, 1.0, count), 10.0 ** rng.uniform(-7.0, 0.0, count))
    no_lag = rng.random(count) < 0.5
    temps = i16(rng, (count, 40))
    return [(temps[r, :size[r]].tolist(), float(c[r]), bool(no_lag[r])) for r in range(count)]


@batched("lag")
@given(st.lists(I16, min_size=1, max_size=40), st.floats(1e-7, 1.0), st.booleans(), seeds)
def test_lag_within_bound(temps, c, no_lag, seed):
    """ac_temp_lag_step against lag_temperature (the exact weight c) on any run of int16
    temperatures: within lag_bound, unless the step says it clipped (an input 128 degC or more
    from the lagged state)."""
    for run in [(temps, c, no_lag)] + lag_runs(generator(seed), batched.size("lag") - 1):
        check_lag(*run)


def check_lag(temps, c, no_lag):
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


def temp_batch(t_ref, oc, gc, o, t_off, t_gain, x):
    """ac_temp_correct on each row (t_ref, t_off, t_gain (B,); oc, gc, o, x (B, N)), and the
    reference: temperature_correct fed the tables' values, row by row the arithmetic of one call.
    Returns (y (B, N), sat (B,), ref (B, N), e (B, N), dt_clipped (B,))."""
    y, sat = np.zeros(x.shape, np.int16), np.zeros(len(x), bool)
    for i in range(len(x)):
        t = native.new_temp_table(t_ref[i], oc[i], gc[i], o[i])
        y[i], sat[i] = native.temp_correct(t, t_off[i], t_gain[i], x[i])
    d_off, d_gain = t_off - t_ref, t_gain - t_ref
    dto, dtg = np.clip(d_off, -32768, 32767) * TEMP_LSB, np.clip(d_gain, -32768, 32767) * TEMP_LSB
    occ, gcc, oo = oc * 2.0 ** -OC_FRAC, gc * 2.0 ** -GC_FRAC, o * O_LSB
    e = gcc * dtg[:, None]
    b = oo    # counts about the trim: the reference's offsets are o
    ref = terms.temperature_correct(x.astype(float), b, 0.0, occ, gcc, dto, dtg)
    dt_clipped = (d_off != np.clip(d_off, -32768, 32767)) | (d_gain != np.clip(d_gain, -32768, 32767))
    return y, sat, ref, e, dt_clipped


def temp_rows(rng, n, count):
    """``count`` rows (t_ref, oc, gc, o, t_off, t_gain, x) of n channels as the strategies above
    draw them."""
    t = i16(rng, (3, count))
    return (t[0], i16(rng, (count, n), lo=-32767), i16(rng, (count, n), lo=-32767), ints(rng, -128, 128, (count, n)),
            t[1], t[2], i16(rng, (count, n)))


@batched("temp")
@given(temp_tables(), I16, I16, st.data(), seeds)
def test_temp_correct_within_bound(table, t_off, t_gain, data, seed):
    """ac_temp_correct against temperature_correct with the table's coefficients: within
    temp_bound wherever it does not flag a clip; and it flags one only where a value leaves
    its range (|e| beyond AC_TEMP_E_MAX, a temperature difference or a reading beyond int16)."""
    n, t_ref, oc, gc, o = table
    x = data.draw(st.lists(I16, min_size=n, max_size=n))
    rows = temp_rows(generator(seed), n, batched.size("temp") - 1)
    t_ref, oc, gc, o, t_off, t_gain, x = (stack(a, r) for a, r in zip((t_ref, oc, gc, o, t_off, t_gain, x), rows))
    y, sat, ref, e, dt_clipped = temp_batch(t_ref, oc, gc, o, t_off, t_gain, x)
    within = np.all(np.abs(y - ref) <= temp_bound(np.maximum(np.abs(x), np.abs(ref)), e), axis=1)
    w = x - o * O_LSB - oc * 2.0 ** -OC_FRAC * np.clip(t_off - t_ref, -32768, 32767)[:, None] * TEMP_LSB
    leaves = (dt_clipped | np.any(np.abs(e) > E_MAX * 2.0 ** -19 - 2.0 ** -20, axis=1)
              | np.any(np.abs(ref) > 32767 - 1, axis=1) | np.any(np.abs(w) > 32767 - 1, axis=1))
    rows_hold(np.where(sat, leaves, within), t_ref=t_ref, oc=oc, gc=gc, o=o, t_off=t_off, t_gain=t_gain, x=x,
              y=y, sat=sat)


@batched("temp")
@given(temp_tables(), st.integers(-40 * 256, 40 * 256), st.integers(-40 * 256, 40 * 256), st.data(), seeds)
def test_temp_correct_realistic_no_clip(table, dto, dtg, data, seed):
    """Within +-40 degC of t_ref, gain tempcos up to 1e-3/degC and offset tempcos up to 100
    counts/degC, on readings within +-26000 counts: never a clip, and within 0.6 counts
    (+ |x| 2^-17) of the float reference."""
    n, t_ref, oc, gc, o = table
    oc = data.draw(st.lists(st.integers(-100 * 256, 100 * 256), min_size=n, max_size=n))
    gc = data.draw(st.lists(st.integers(-16777, 16777), min_size=n, max_size=n))   # 1e-3 2^24
    x = data.draw(st.lists(st.integers(-26000, 26000), min_size=n, max_size=n))
    rng, k = generator(seed), batched.size("temp") - 1
    rows = (ints(rng, -40 * 256, 40 * 256, k), ints(rng, -40 * 256, 40 * 256, k), ints(rng, -100 * 256, 100 * 256, (k, n)),
            ints(rng, -16777, 16777, (k, n)), ints(rng, -128, 128, (k, n)), ints(rng, -26000, 26000, (k, n)))
    dto, dtg, oc, gc, o, x = (stack(a, r) for a, r in zip((dto, dtg, oc, gc, o, x), rows))
    t_ref = np.full(len(x), 25 * 256)
    y, sat, ref, _, _ = temp_batch(t_ref, oc, gc, o, t_ref + dto, t_ref + dtg, x)
    rows_hold(~sat & np.all(np.abs(y - ref) <= 0.6 + np.abs(x) * 2.0 ** -17, axis=1),
              dto=dto, dtg=dtg, oc=oc, gc=gc, o=o, x=x, y=y, sat=sat)


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


def skew_runs(rng, count):
    """``count`` cases as skew_cases draws them."""
    m = lib.AC_MAX_CHANNELS
    n, length, steps = ints(rng, 1, m, count), ints(rng, 2, 12, count), ints(rng, 1, 30, count)
    whole = ints(rng, 0, np.repeat(length[:, None] - 2, m, axis=1))
    frac = ints(rng, 0, 32767, (count, m), edges=(0, 1, 16384, 32767))
    x = i16(rng, (count, 30, m)).astype(np.int16)
    return [(int(length[r]), whole[r, :n[r]], frac[r, :n[r]], x[r, :steps[r], :n[r]]) for r in range(count)]


@batched("skew")
@given(skew_cases(), seeds)
def test_skew_within_half_count(case, seed):
    """ac_skew_step against skew_correct with the table's delays: within 0.5 count, and the
    result between the two samples it interpolates (it never clips)."""
    for c in [case] + skew_runs(generator(seed), batched.size("skew") - 1):
        check_skew(*c)


def check_skew(length, whole, frac, x):
    t = native.new_skew_table(length, whole, frac)
    line = native.SkewLine(t)
    x = np.ascontiguousarray(x, np.int16)
    y = np.zeros_like(x)
    xp, yp, n = native.cptr("int16_t *", x), native.cptr("int16_t *", y), x.shape[1]
    for i in range(x.shape[0]):          # ac_skew_step per sample (SkewLine.step without its copies)
        assert lib.ac_skew_step(t, line.line, xp + i * n, yp + i * n) == lib.AC_OK
    delays = np.asarray(whole) + np.asarray(frac) / 2.0 ** 15
    ref, _ = terms.skew_correct(x.astype(float), delays, np.repeat(x[:1].astype(float), length, axis=0))
    assert np.all(np.abs(y - ref) <= 0.5), (length, whole, frac, x, y)


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
    """nonlinearity_invert fed the tables' values: rows a2, a3, x, o (B, N), shift (B, 1)."""
    c2, c3 = np.asarray(a2) / 2.0 ** (15 + shift), np.asarray(a3) / 2.0 ** (30 + shift)
    unit = np.tile([1.0, 0.0, 0.0], (np.shape(a2)[-1], 1))     # |s| = 1: k2 = c2, k3 = c3
    # readings about the trim: b = trim + o is o there, and the result is the corrected reading
    ref = terms.nonlinearity_invert(np.asarray(x).astype(float), o, unit, c2, c3)
    return ref, c2, c3


def nonlin_rows(rng, n, count):
    """``count`` rows (shift (B,), a2, a3, x, o (B, N)) of n channels as nonlin_cases draws them."""
    a2 = ints(rng, -32767, 32767, (count, n))
    room = 32767 - np.abs(a2)
    return ints(rng, 0, 30, count), a2, ints(rng, -room, room), i16(rng, (count, n)), floats(rng, -0.5, 0.5, (count, n))


def nonlin_batch(shift, a2, a3, x, o):
    """ac_nonlin_invert on each row, and nonlin_reference on all rows at once (row by row the
    arithmetic of one call). Returns (y, sat, ref, c2, c3)."""
    y, sat = np.zeros(x.shape, np.int16), np.zeros(len(x), bool)
    for i in range(len(x)):
        y[i], sat[i] = native.nonlin_invert(native.new_nonlin_table(shift[i], a2[i], a3[i]), x[i].astype(np.int16))
    ref, c2, c3 = nonlin_reference(shift[:, None], a2, a3, x, o)
    return y, sat, ref, c2, c3


@batched("nonlin")
@given(nonlin_cases(), seeds)
@example((19, [0] * 8 + [29962] + [0] * 3, [0] * 12, np.array([0] * 8 + [-2966] + [0] * 3),
          np.array([0.0] * 8 + [0.5] + [0.0] * 3)), 0)   # 5e-5 counts beyond the bound before the trim's fraction was in it
def test_nonlin_within_bound(case, seed):
    """ac_nonlin_invert against nonlinearity_invert (the same iterations, z_0 = x - o) with
    the table's coefficients: within nonlin_bound unless it flags a clip, and a clip only
    where an iterate leaves int16."""
    rows = nonlin_rows(generator(seed), len(case[1]), batched.size("nonlin") - 1)
    shift, a2, a3, x, o = (stack(c, r) for c, r in zip(case, rows))
    y, sat, ref, c2, c3 = nonlin_batch(shift, a2, a3, x, o)
    z = np.maximum(np.abs(x), np.abs(ref)) + 1.0
    bound = nonlin_bound(z, c2, c3, shift[:, None])
    finite = np.isfinite(ref) & np.isfinite(bound)
    rows_hold(sat | np.all((np.abs(y - ref) <= bound) | ~finite, axis=1), shift=shift, a2=a2, a3=a3, x=x, o=o, y=y)


def nonlin_realistic_table(c2, c3):
    """(shift, a2, a3) of rows of coefficients c2, c3 (B, N) in 1/counts, 1/counts^2 as the
    property quantizes them, and whether the row fits the table (|a2| + |a3| <= 32767)."""
    peak = np.max(np.abs(c2) * 2 ** 15 + np.abs(c3) * 2 ** 30, axis=1)
    shift = np.minimum(30, np.floor(np.log2(32766 / np.maximum(peak, 1e-12)))).astype(np.int64)
    a2 = np.floor(c2 * 2.0 ** (15 + shift[:, None]) + 0.5).astype(np.int64)
    a3 = np.floor(c3 * 2.0 ** (30 + shift[:, None]) + 0.5).astype(np.int64)
    return shift, a2, a3, np.all(np.abs(a2) + np.abs(a3) <= 32767, axis=1)


@batched("nonlin")
@given(st.integers(1, lib.AC_MAX_CHANNELS), st.data(), seeds)
def test_nonlin_realistic_tight(n, data, seed):
    """Up to 5 % of the reading at full scale (2.5 % square, 2.5 % cube), readings within
    +-28000 counts (the result stays in int16): no clip, and within 1.2 counts of the float
    iteration."""
    c2 = data.draw(st.lists(st.floats(-0.025, 0.025), min_size=n, max_size=n))
    c3 = data.draw(st.lists(st.floats(-0.025, 0.025), min_size=n, max_size=n))
    x = data.draw(st.lists(st.integers(-28000, 28000), min_size=n, max_size=n))
    rng, k = generator(seed), batched.size("nonlin") - 1
    c2 = stack(c2, floats(rng, -0.025, 0.025, (k, n))) / 32768
    c3 = stack(c3, floats(rng, -0.025, 0.025, (k, n))) / 32768 ** 2
    x = stack(x, ints(rng, -28000, 28000, (k, n)))
    shift, a2, a3, fits = nonlin_realistic_table(c2, c3)
    assume(fits.any())       # a row that does not fit the table is not checked (as assume() did per example)
    shift, a2, a3, x = shift[fits], a2[fits], a3[fits], x[fits]
    y, sat, ref, _, _ = nonlin_batch(shift, a2, a3, x, np.zeros(x.shape))
    rows_hold(~sat & np.all(np.abs(y - ref) <= 1.2, axis=1), shift=shift, a2=a2, a3=a3, x=x, y=y, sat=sat)


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
