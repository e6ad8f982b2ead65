"""The C core's fixed-point primitives against Python's exact integers."""
import math
from fractions import Fraction

import numpy as np
from core_settings import core
from hypothesis import given, strategies as st

from accelcal._core import ffi, lib

I32 = st.one_of(st.integers(-2**31, 2**31 - 1),
                st.sampled_from([-2**31, -2**31 + 1, -1, 0, 1, 2**31 - 1, 2**30, -2**30, 2**16, -2**16]))
INT32_MIN, INT32_MAX = -2**31, 2**31 - 1


def clip32(v):
    return max(INT32_MIN, min(INT32_MAX, v))


def round_half_up(fr: Fraction) -> int:
    return math.floor(fr + Fraction(1, 2))


@core
@given(I32, I32, st.integers(-40, 40), st.integers(0, 62))
def test_int32_primitives_exact(a, b, shift, n):
    """ac_scale_round32, ac_mul32x32, ac_mul32_shift, ac_add32_sat, ac_asr32 and
    ac_bitlen32 against Python's exact integers (one draw feeds all six, so each
    property gets every example)."""
    out = ffi.new("int32_t *")
    st_ = lib.ac_scale_round32(a, shift, out)
    exact = round_half_up(Fraction(a) / Fraction(2) ** shift)
    assert out[0] == clip32(exact)
    assert (st_ == lib.AC_SATURATED) == (exact != clip32(exact))

    o64 = ffi.new("ac_i64 *")
    assert lib.ac_mul32x32(a, b, o64) == lib.AC_OK
    assert o64.hi * 2**32 + o64.lo == a * b

    st_ = lib.ac_mul32_shift(a, b, n, out)
    exact = round_half_up(Fraction(a * b, 2**n))
    assert out[0] == clip32(exact)
    assert (st_ == lib.AC_SATURATED) == (exact != clip32(exact))

    st_ = lib.ac_add32_sat(a, b, out)
    assert out[0] == clip32(a + b)
    assert (st_ == lib.AC_SATURATED) == (a + b != clip32(a + b))

    assert lib.ac_asr32(a, n % 32, out) == lib.AC_OK
    assert out[0] == a >> (n % 32)  # Python's >> is floor division by 2^n

    o8 = ffi.new("uint8_t *")
    lib.ac_bitlen32(b, o8)
    assert o8[0] == abs(b).bit_length()


def test_sat16_exhaustive_band():
    out = ffi.new("int16_t *")
    for v in list(range(-33000, -32000)) + list(range(32000, 33000)) + [INT32_MIN, INT32_MAX, 0]:
        st_ = lib.ac_sat16(v, out)
        c = max(-32768, min(32767, v))
        assert out[0] == c and (st_ == lib.AC_SATURATED) == (c != v)


def test_null_pointers_give_status():
    assert lib.ac_sat16(1, ffi.NULL) == lib.AC_ERR_NULL
    assert lib.ac_mul32_shift(1, 1, 1, ffi.NULL) == lib.AC_ERR_NULL
    assert lib.ac_mul32_shift(1, 1, 63, ffi.new("int32_t *")) == lib.AC_ERR_RANGE
    assert lib.ac_asr32(1, 32, ffi.new("int32_t *")) == lib.AC_ERR_RANGE


# ---- extended-range numbers -------------------------------------------------

def xf_value(x) -> Fraction:
    return Fraction(x.m) * Fraction(2) ** x.e


def xf_of(v: int, frac: int):
    x = ffi.new("ac_xf *")
    assert lib.ac_xf_from_fixed(v, frac, x) == lib.AC_OK
    return x[0]


XF_IN = st.tuples(st.integers(-2**31, 2**31 - 1).filter(lambda v: v != 0), st.integers(-200, 200))
REL = Fraction(1, 2**29)  # one ulp of the 30-bit mantissa, relative


def check_normalised(x):
    assert x.m == 0 or 2**29 <= abs(x.m) < 2**30


@core
@given(XF_IN, XF_IN, st.sampled_from(["add", "sub", "mul", "div"]))
def test_xf_arithmetic_correctly_rounded(a, b, op):
    xa, xb = xf_of(*a), xf_of(*b)
    out = ffi.new("ac_xf *")
    assert getattr(lib, f"ac_xf_{op}")(xa, xb, out) == lib.AC_OK
    va, vb = xf_value(xa), xf_value(xb)
    exact = {"add": va + vb, "sub": va - vb, "mul": va * vb, "div": va / vb}[op]
    check_normalised(out[0])
    # one rounding to a 30-bit mantissa: half an ulp of the result
    assert abs(xf_value(out[0]) - exact) <= abs(exact) * REL / 2 * (1 + REL) or exact == 0


def test_xf_div_by_zero():
    out = ffi.new("ac_xf *")
    assert lib.ac_xf_div(xf_of(1, 0), xf_of(0, 0), out) == lib.AC_ERR_SINGULAR


@core
@given(XF_IN, st.integers(-60, 60))
def test_xf_from_and_to_fixed(v, frac):
    """ac_xf_from_fixed (exact, or rounded to the 30-bit mantissa) and ac_xf_to_fixed
    (correctly rounded, saturating) on the same draw."""
    x = xf_of(*v)
    check_normalised(x)
    exact = Fraction(v[0]) / Fraction(2) ** v[1]
    assert abs(xf_value(x) - exact) <= abs(exact) * REL / 2
    out = ffi.new("int32_t *")
    st_ = lib.ac_xf_to_fixed(x, frac, out)
    exact = round_half_up(xf_value(x) * Fraction(2) ** frac)
    assert out[0] == clip32(exact)
    assert (st_ == lib.AC_SATURATED) == (exact != clip32(exact))


def test_trim_exhaustive_over_raw():
    """Every raw value 0..65535 against a sweep of trims, boundaries included."""
    raw = np.arange(65536, dtype=np.uint16)
    x = np.zeros(65535, dtype=np.int16)
    for trim_v in [0, 1, 5000, 32767, 32768, 32769, 65534, 65535]:
        for lo in (0, 1):  # n is uint16: cover all 65536 raw values in two calls
            r = np.ascontiguousarray(raw[lo:lo + 65535])
            t = np.full(65535, trim_v, dtype=np.uint16)
            st_ = lib.ac_trim(ffi.cast("uint16_t *", ffi.from_buffer(r)),
                              ffi.cast("uint16_t *", ffi.from_buffer(t)), 65535,
                              ffi.cast("int16_t *", ffi.from_buffer(x)))
            d = r.astype(np.int64) - trim_v
            expect = np.clip(d, -32768, 32767)
            assert np.array_equal(x, expect)
            assert (st_ == lib.AC_SATURATED) == bool(np.any(d != expect))
