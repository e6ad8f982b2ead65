"""The C core flags a reading at the converter's rails (raw_min / raw_max) as the host does.

ac_trim_rails, ac_trim_rails_s16 (a signed chip's pre-trim, in its own counts), ac_process, ac_process_batch and ac_triad_apply against the host's
:func:`accelcal.readings.clipping.at_rails` over whole reading ranges, the boundary values raw_min,
raw_min + 1, raw_max - 1 and raw_max drawn often; the rail test changes no number (x, the
outputs and the saturation bits equal those of a table without rails).

Each example checks a batch (core_batch.py): the first vector drawn by the hypothesis strategies
below, the rest by numpy over the same ranges and edges (rails_rng, readings_rng); core_settings.py
has the counts."""
from types import SimpleNamespace

import numpy as np
from core_batch import EDGE_SHARE, generator, ints, seeds
from core_settings import batched
from hypothesis import assume, given, strategies as st

from accelcal.readings.clipping import at_rails
from accelcal.errors import IllConditionedError, SingularError
from accelcal.firmware.native import at_rail, check, cptr, ffi, lib, offset_binary, process_batch
from accelcal.firmware.quantize import QuantizeError, quantize, rail_codes, rail_counts
from accelcal.firmware.triad import quantize_triad, triad_apply_fixed
from test_core_resolve import random_geometry

SAT, RAIL = lib.AC_SATURATED, lib.AC_AT_RAIL


@st.composite
def rails(draw, signed=None):
    """(raw_min, raw_max, signed): a full 16-bit converter, a 12-bit one, or any pair."""
    signed = draw(st.booleans()) if signed is None else signed
    lo, hi = (-32768, 32767) if signed else (0, 65535)
    kind = draw(st.sampled_from(["full", "12bit", "any"]))
    if kind == "full":
        return lo, hi, signed
    if kind == "12bit":
        return (-2048, 2047, signed) if signed else (0, 4095, signed)
    a = draw(st.integers(lo, hi - 1))
    return a, draw(st.integers(a + 1, hi)), signed


def rails_rows(rng, count, signed=None):
    """``count`` rails (raw_min, raw_max, signed) (count,) as rails() draws them."""
    sgn = rng.random(count) < 0.5 if signed is None else np.full(count, bool(signed))
    lo, hi = np.where(sgn, -32768, 0), np.where(sgn, 32767, 65535)
    kind = rng.integers(0, 3, count)           # full, 12 bit, any pair
    a = ints(rng, lo, hi - 1)
    b = ints(rng, a + 1, hi)
    raw_min = np.choose(kind, [lo, np.where(sgn, -2048, 0), a])
    raw_max = np.choose(kind, [hi, np.where(sgn, 2047, 4095), b])
    return raw_min, raw_max, sgn


def readings_rows(rng, raw_min, raw_max, shape):
    """Readings (count, ...) in row r's [raw_min[r], raw_max[r]] as readings() draws them: half of
    them raw_min, raw_min + 1, raw_max - 1 or raw_max."""
    lo = np.asarray(raw_min).reshape((-1,) + (1,) * (len(shape) - 1))
    hi = np.asarray(raw_max).reshape(lo.shape)
    edges = [np.clip(v, lo, hi) for v in (lo, lo + 1, hi - 1, hi)]
    v = rng.integers(lo, hi, size=shape, endpoint=True)
    e = np.choose(rng.integers(0, 4, shape), [np.broadcast_to(x, shape) for x in edges])
    return np.where(rng.random(shape) < EDGE_SHARE, e, v).astype(np.int64)


def rails_rng(rng, signed=None):
    """One (raw_min, raw_max, signed) as rails() draws them."""
    lo, hi, sgn = rails_rows(rng, 1, signed)
    return int(lo[0]), int(hi[0]), bool(sgn[0])


def readings_rng(rng, raw_min, raw_max, shape):
    """Readings of shape ``shape`` in [raw_min, raw_max] as readings() draws them."""
    return readings_rows(rng, [raw_min], [raw_max], (1,) + tuple(shape))[0]


def readings(draw, raw_min, raw_max, shape):
    """Readings in [raw_min, raw_max], a third of them on or next to a rail."""
    edge = st.sampled_from([raw_min, raw_min + 1, raw_max - 1, raw_max]).map(lambda v: min(max(v, raw_min), raw_max))
    vals = draw(st.lists(st.one_of(edge, st.integers(raw_min, raw_max)), min_size=int(np.prod(shape)),
                         max_size=int(np.prod(shape))))
    return np.array(vals, np.int64).reshape(shape)


def host_rails(raw, raw_min, raw_max):
    return at_rails(SimpleNamespace(raw=raw), SimpleNamespace(raw_min=raw_min, raw_max=raw_max))


def codes(a, signed):
    return offset_binary(a) if signed else np.asarray(a).astype(np.uint16)


def call_trim(fn, ctype, raw, trim, *rails):
    """One sample through a pre-trim of the core (``fn``: ac_trim, ac_trim_rails, ac_trim_s16 or
    ac_trim_rails_s16, readings and trims as ``ctype``, then the rails where it takes them) ->
    (status, x)."""
    n = len(raw)
    x = np.zeros(n, np.int16)
    dt = np.uint16 if ctype == "uint16_t" else np.int16
    raw, trim = np.ascontiguousarray(raw, dt), np.ascontiguousarray(trim, dt)  # alive for the call
    s = fn(cptr(f"{ctype} *", raw), cptr(f"{ctype} *", trim), n, *(int(r) for r in rails), cptr("int16_t *", x))
    return int(s), x


def trim_rails(raw_c, trim_c, lo_c, hi_c):
    """ac_trim_rails on one sample of uint16 codes -> (status, x)."""
    return call_trim(lib.ac_trim_rails, "uint16_t", raw_c, trim_c, lo_c, hi_c)


def trim_plain(raw_c, trim_c):
    return call_trim(lib.ac_trim, "uint16_t", raw_c, trim_c)


def trim_rows(rng, n, count, signed=None):
    """``count`` (raw_min, raw_max, signed, raw (n,), trim (n,)) as the properties below draw them."""
    raw_min, raw_max, sgn = rails_rows(rng, count, signed)
    raw = readings_rows(rng, raw_min, raw_max, (count, n))
    trim = ints(rng, np.where(sgn, -32768, 0)[:, None], np.where(sgn, 32767, 65535)[:, None], (count, n))
    return [(int(raw_min[r]), int(raw_max[r]), bool(sgn[r]), raw[r], trim[r]) for r in range(count)]


@batched("trim")
@given(st.data(), seeds)
def test_trim_rails_flags_what_at_rails_flags(data, seed):
    raw_min, raw_max, signed = data.draw(rails())
    n = data.draw(st.integers(1, 14))
    raw = readings(data.draw, raw_min, raw_max, (n,))
    trim = np.array(data.draw(st.lists(st.integers(*((-32768, 32767) if signed else (0, 65535))),
                                       min_size=n, max_size=n)), np.int64)
    for row in [(raw_min, raw_max, signed, raw, trim)] + trim_rows(generator(seed), n, batched.size("trim") - 1):
        check_trim_rails(*row)


def check_trim_rails(raw_min, raw_max, signed, raw, trim):
    lo_c, hi_c = rail_codes(raw_min, raw_max, signed)
    s, x = trim_rails(codes(raw, signed), codes(trim, signed), lo_c, hi_c)
    s0, x0 = trim_plain(codes(raw, signed), codes(trim, signed))
    assert bool(s & RAIL) == bool(host_rails(raw[None, :], raw_min, raw_max)[0])
    assert (s & SAT) == s0 and np.array_equal(x, x0)


def trim_rails_s16(raw, trim, lo, hi):
    """ac_trim_rails_s16 on one sample of int16 counts -> (status, x)."""
    return call_trim(lib.ac_trim_rails_s16, "int16_t", raw, trim, lo, hi)


def trim_s16(raw, trim):
    return call_trim(lib.ac_trim_s16, "int16_t", raw, trim)


@batched("trim")
@given(st.data(), seeds)
def test_trim_rails_s16_flags_what_at_rails_flags(data, seed):
    """A signed chip's pre-trim with its rails in its own counts (the header's recipe for signed
    chips, -2048 and 2047 for a 12-bit one): AC_AT_RAIL exactly where the host's at_rails is,
    x and the saturation bit those of ac_trim_s16, the status that of ac_trim_rails on the codes."""
    raw_min, raw_max, _ = data.draw(rails(signed=True))
    n = data.draw(st.integers(1, 14))
    raw = readings(data.draw, raw_min, raw_max, (n,))
    trim = np.array(data.draw(st.lists(st.integers(-32768, 32767), min_size=n, max_size=n)), np.int64)
    rows = [(raw_min, raw_max, True, raw, trim)] + trim_rows(generator(seed), n, batched.size("trim") - 1, signed=True)
    for raw_min, raw_max, _, raw, trim in rows:
        check_trim_rails_s16(raw_min, raw_max, raw, trim)


def check_trim_rails_s16(raw_min, raw_max, raw, trim):
    s, x = trim_rails_s16(raw, trim, raw_min, raw_max)
    s0, x0 = trim_s16(raw, trim)
    assert bool(s & RAIL) == bool(host_rails(raw[None, :], raw_min, raw_max)[0])
    assert (s & SAT) == s0 and np.array_equal(x, x0)
    lo_c, hi_c = rail_codes(raw_min, raw_max, True)
    assert rail_counts((lo_c, hi_c), True) == (raw_min, raw_max)
    s_c, x_c = trim_rails(codes(raw, True), codes(trim, True), lo_c, hi_c)
    assert s == s_c and np.array_equal(x, x_c)


def unknown_rows(rng, lo, hi, count):
    """``count`` (a, b, raw) as the strategies below draw them: raw 1-14 values in [lo, hi]."""
    ab, size, raw = ints(rng, lo, hi, (count, 2)), ints(rng, 1, 14, count), ints(rng, lo, hi, (count, 14))
    return [(int(ab[r, 0]), int(ab[r, 1]), raw[r, :size[r]].tolist()) for r in range(count)]


@batched("trim")
@given(st.integers(-32768, 32767), st.integers(-32768, 32767), st.lists(st.integers(-32768, 32767), min_size=1,
                                                                        max_size=14), seeds)
def test_unknown_rails_s16_flag_nothing(a, b, raw, seed):
    """raw_min >= raw_max (the (0, 0) codes of a table without rails are -32768, -32768 in counts):
    nothing flagged, -32768 and 32767 included."""
    for row in [(a, b, raw)] + unknown_rows(generator(seed), -32768, 32767, batched.size("trim") - 1):
        check_unknown_s16(*row)


def check_unknown_s16(a, b, raw):
    lo, hi = max(a, b), min(a, b)
    raw = np.array(raw + [-32768, 32767, lo, hi], np.int16)
    for pair in ((lo, hi), rail_counts((0, 0), True)):
        s, x = trim_rails_s16(raw, raw[::-1].copy(), *pair)
        s0, x0 = trim_s16(raw, raw[::-1].copy())
        assert s == s0 and np.array_equal(x, x0)


@batched("trim")
@given(st.integers(0, 65535), st.integers(0, 65535), st.lists(st.integers(0, 65535), min_size=1, max_size=14), seeds)
def test_unknown_rails_flag_nothing(a, b, raw, seed):
    """raw_min >= raw_max (0, 0 in a zeroed table): no reading is flagged, 0 and 65535 included."""
    for row in [(a, b, raw)] + unknown_rows(generator(seed), 0, 65535, batched.size("trim") - 1):
        check_unknown(*row)


def check_unknown(a, b, raw):
    lo, hi = max(a, b), min(a, b)
    raw = np.array(raw + [0, 65535, lo, hi], np.uint16)
    s, x = trim_rails(raw, raw[::-1].copy(), lo, hi)
    s0, x0 = trim_plain(raw, raw[::-1].copy())
    assert s == s0 and np.array_equal(x, x0)


@batched("process")
@given(st.data())
def test_process_and_batch_flag_the_rails(data):
    raw_min, raw_max, signed = data.draw(rails())
    seed = data.draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    count = batched.size("process")
    n = int(rng.integers(6, 13))
    pos, ax = random_geometry(rng, n)
    k = 10 ** rng.uniform(0, 3.4)
    sens = k * ax * (1 + rng.uniform(-0.01, 0.04, (n, 1))) + k * rng.normal(0, 0.0175, (n, 3))
    offsets = rng.uniform(raw_min, raw_max, n)
    try:
        t = quantize(offsets, sens, pos, "rails", signed=signed, rails=(raw_min, raw_max))
    except (IllConditionedError, SingularError, QuantizeError):
        assume(False)
    raw = np.concatenate([readings(data.draw, raw_min, raw_max, (1, n)),      # one drawn by hypothesis
                          readings_rng(rng, raw_min, raw_max, (count - 1, n))])
    w = rng.integers(-3000, 3000, (count, 3)) if rng.random() < 0.5 else None
    expect = host_rails(raw, raw_min, raw_max)
    out, flags = process_batch(t.resolver(), t.trim, raw, w)
    t0 = quantize(offsets, sens, pos, "rails", signed=signed)            # the same table, no rails
    out0, flags0 = process_batch(t0.resolver(), t0.trim, raw, w)
    assert np.array_equal(flags & lib.AC_FLAG_AT_RAIL != 0, expect)
    assert np.array_equal(flags & ~np.uint8(lib.AC_FLAG_AT_RAIL), flags0) and np.array_equal(out, out0)
    r = t.resolver()
    trim_c = np.ascontiguousarray(codes(t.trim, signed), np.uint16)
    o = np.zeros(6, np.int32)
    for i in range(count):
        wp = ffi.NULL if w is None else cptr("int16_t *", np.ascontiguousarray(w[i], np.int16))
        s = int(lib.ac_process(r, cptr("uint16_t *", trim_c),
                               cptr("uint16_t *", np.ascontiguousarray(codes(raw[i], signed), np.uint16)), wp,
                               cptr("int32_t *", o)))
        assert at_rail(s) == expect[i] and np.array_equal(o, out[i])
        assert check(s, "ac_process") == bool(flags0[i])


@batched("triad")
@given(st.data())
def test_triad_apply_flags_the_rails(data):
    raw_min, raw_max, _ = data.draw(rails(signed=False))
    seed = data.draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    check_triad(rng, raw_min, raw_max, readings(data.draw, raw_min, raw_max, (1, 3)))    # one drawn by hypothesis
    for _ in range(batched.size("triad") - 1):
        raw_min, raw_max, _ = rails_rng(rng, signed=False)
        check_triad(rng, raw_min, raw_max, np.zeros((0, 3), np.int64))


#: readings per table of test_triad_apply_flags_the_rails (5 before batching)
TRIAD_READINGS = 20


def check_triad(rng, raw_min, raw_max, raw):
    """One table of ``rng`` on rails (raw_min, raw_max) and TRIAD_READINGS readings: ``raw``, then
    readings drawn by rng."""
    S = np.diag(10 ** rng.uniform(0, 3.4, 3)) @ (np.eye(3) + rng.normal(0, 0.02, (3, 3)))
    b = rng.uniform(raw_min, raw_max, 3)
    try:
        t = quantize_triad(b, S, rails=(raw_min, raw_max))
    except QuantizeError:
        return      # not a table: not checked (as assume() did per example)
    raw = np.concatenate([raw, readings_rng(rng, raw_min, raw_max, (TRIAD_READINGS - len(raw), 3))])
    f, sat = triad_apply_fixed(t, raw)
    f0, sat0 = triad_apply_fixed(quantize_triad(b, S), raw)
    assert np.array_equal(f, f0) and np.array_equal(sat, sat0)
    c = t.cdata()
    fo = ffi.new("int32_t[3]")
    got = [at_rail(lib.ac_triad_apply(c, cptr("uint16_t *", np.ascontiguousarray(r, np.uint16)), fo)) for r in raw]
    assert got == list(host_rails(raw, raw_min, raw_max))


def test_rail_codes_of_a_signed_chip_are_offset_binary():
    assert rail_codes(-2048, 2047, True) == (30720, 34815)
    assert rail_codes(0, 4095, False) == (0, 4095)
    assert rail_codes(None, None, False) == (0, 0)
