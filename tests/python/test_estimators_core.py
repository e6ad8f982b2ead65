"""Motion estimators' primitives against the C core: ac_trig (isqrt, division, multiply,
atan2), the triad table (ac_triad), the rest detector (ac_rest) against its float twin,
the sample interval, and the compiled core's formats and flags against the headers."""
import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

from accelcal import estimators as E
from accelcal.errors import AccelcalError
from accelcal.firmware.native import FORMATS, ffi, lib
from core_settings import estimator
from estimator_devices import G

U32 = st.integers(0, 2**32 - 1)
I32 = st.one_of(st.integers(-2**31, 2**31 - 1),
                st.sampled_from([-2**31, -2**31 + 1, -1, 0, 1, 2**31 - 1, 2**30, -2**30, 2**16, -2**16]))
INCLUDE = Path(__file__).resolve().parents[2] / "include" / "accelcal"


def rhu(num, den=1):
    """round half up of num / den (exact, Python ints)."""
    return (2 * num + den) // (2 * den)


def header_defines():
    """Every integer #define of the public headers, as written there."""
    out = {}
    for h in INCLUDE.glob("*.h"):
        for m in re.finditer(r"^#define\s+(AC_[A-Z0-9_]+)\s+\(?(0x[0-9A-Fa-f]+|\d+)u?\)?[ \t]*(?:/\*.*)?$",
                             h.read_text(), re.M):
            out.setdefault(m.group(1), int(m.group(2), 0))
    return out


def test_formats_and_flags_are_the_headers():
    """The Q formats (native.FORMATS) and flag bits the estimators use are those the headers
    define: a stale extension or a changed header fails here."""
    h = header_defines()
    fm = {"out_frac": "AC_OUT_FRAC", "omega_frac": "AC_OMEGA_FRAC", "pos_frac": "AC_POS_FRAC",
          "angle_frac": "AC_ANGLE_FRAC", "rest_extra_frac": "AC_REST_EXTRA_FRAC", "att_w_frac": "AC_ATT_W_FRAC",
          "att_w2_frac": "AC_ATT_W2_FRAC", "disp_a_frac": "AC_DISP_A_FRAC", "disp_v_frac": "AC_DISP_V_FRAC",
          "disp_p_frac": "AC_DISP_P_FRAC", "disp_rot_frac": "AC_DISP_ROT_FRAC", "disp_g_frac": "AC_DISP_G_FRAC",
          "disp_gsum_max": "AC_DISP_GSUM_MAX"}
    for field, name in fm.items():
        assert getattr(FORMATS, field) == h[name], name
    flags = {"REST_QUIET": "AC_REST_QUIET", "REST_AT_REST": "AC_REST_AT_REST", "REST_ENTER": "AC_REST_ENTER",
             "REST_LEAVE": "AC_REST_LEAVE", "REST_CLIP": "AC_REST_CLIP"}
    flags.update({f"ATT_{k}": f"AC_ATT_{k}" for k in ("GATED", "W2_NEG", "UNSETTLED", "NO_GRAVITY", "SAT",
                                                     "SIGN_NEG")})
    flags.update({f"DISP_{k}": f"AC_DISP_{k}" for k in ("NO_REF", "REST", "MOVING", "SEG_END", "LONG", "SAT",
                                                       "OPEN", "NO_REST", "REF_SET", "BAD_REF")})
    for py, c in flags.items():
        assert getattr(E, py) == h[c], c
    assert (E.ANGLE_FRAC, E.W_FRAC, E.W2_FRAC, E.A_FRAC, E.V_FRAC, E.P_FRAC, E.ROT_FRAC, E.G_FRAC, E.GSUM_MAX) == \
        (h["AC_ANGLE_FRAC"], h["AC_ATT_W_FRAC"], h["AC_ATT_W2_FRAC"], h["AC_DISP_A_FRAC"], h["AC_DISP_V_FRAC"],
         h["AC_DISP_P_FRAC"], h["AC_DISP_ROT_FRAC"], h["AC_DISP_G_FRAC"], h["AC_DISP_GSUM_MAX"])
    # the clip of the core's tests and sums: int16 in Q.AC_OUT_FRAC
    assert (E.CLIP, E.CLIP_LO) == (32767 / 2.0 ** h["AC_OUT_FRAC"], -32768 / 2.0 ** h["AC_OUT_FRAC"])


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


# ---- triad apply ----

def test_triad_check_rejects_bad_tables():
    tab = E.quantize_triad([32768.0] * 3, np.eye(3) * 1670.7)
    t = tab.cdata()
    assert lib.ac_triad_check(t) == lib.AC_OK
    t.shift[1] = 40
    assert lib.ac_triad_check(t) == lib.AC_ERR_FORMAT
    t.shift[1] = 0
    t.m[0][0], t.m[0][1], t.m[0][2] = 32767, 32767, 2
    assert lib.ac_triad_check(t) == lib.AC_ERR_FORMAT


# ---- rest detector ----

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
    return E.q_out(f), p, (None if alpha is None else E.q_out(alpha))


@estimator
@given(rest_inputs())
def test_rest_fixed_vs_twin(inp):
    f_q, p, a_q = inp
    fl = E.rest_fixed(f_q, p, a_q)
    tw, dev = E.rest_detect(E.clip_i16(f_q) / 1024.0, p, None if a_q is None else a_q / 1024.0, as_stored=True)
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


def test_dt_fixed():
    assert E.dt_fixed(1 / 60) == (34953, 21)
    for dt in (1e-4, 0.001, 0.01, 0.3):
        m, sh = E.dt_fixed(dt)
        assert 32768 <= m < 65536 and abs(m * 2.0**-sh / dt - 1) < 2**-15
    with pytest.raises(AccelcalError):
        E.dt_fixed(1.0)
