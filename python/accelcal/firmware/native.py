"""Bindings to the integer C core (``accelcal._core``, cffi API mode).

Wrappers take and return numpy arrays; a negative status becomes the matching
``CoreError`` subclass, and saturation comes back as flags, never silently.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._core import ffi, lib
from ..errors import core_error


@dataclass(frozen=True)
class Formats:
    """Fixed-point formats of the compiled core, read from its constants (the headers are
    the single source: ac_config.h for the resolver, ac_rate.h, and the estimators' ac_trig.h,
    ac_rest.h, ac_attitude.h, ac_displace.h).  ``*_frac`` are fraction bits of Q formats."""
    out_frac: int          # AC_OUT_FRAC: f (m/s^2), alpha (rad/s^2)
    omega_frac: int        # AC_OMEGA_FRAC: omega (rad/s)
    sens_frac: int         # AC_SENS_FRAC
    pos_frac: int          # AC_POS_FRAC: positions (m), also the attitude's r1, r2
    offset_frac: int       # AC_OFFSET_FRAC
    max_channels: int      # AC_MAX_CHANNELS
    cond_log2_max: int     # AC_COND_LOG2_MAX
    rate_state_frac: int   # AC_RATE_STATE_FRAC
    angle_frac: int        # AC_ANGLE_FRAC: ac_atan2's angle (rad)
    rest_extra_frac: int   # AC_REST_EXTRA_FRAC: the rest mean is Q.(out_frac + this)
    att_w_frac: int        # AC_ATT_W_FRAC: the attitude's rate state (rad/s)
    att_w2_frac: int       # AC_ATT_W2_FRAC: w^2 and its gate ((rad/s)^2)
    disp_a_frac: int       # AC_DISP_A_FRAC: acceleration, zero point (m/s^2)
    disp_v_frac: int       # AC_DISP_V_FRAC: velocity (m/s)
    disp_p_frac: int       # AC_DISP_P_FRAC: position (m)
    disp_rot_frac: int     # AC_DISP_ROT_FRAC: the rest frame's rotation
    disp_g_frac: int       # AC_DISP_G_FRAC: the first rest's mean f (m/s^2)
    disp_gsum_max: int     # AC_DISP_GSUM_MAX: samples of the first rest averaged for g


FORMATS = Formats(out_frac=lib.AC_OUT_FRAC, omega_frac=lib.AC_OMEGA_FRAC,
                  sens_frac=lib.AC_SENS_FRAC, pos_frac=lib.AC_POS_FRAC,
                  offset_frac=lib.AC_OFFSET_FRAC, max_channels=lib.AC_MAX_CHANNELS,
                  cond_log2_max=lib.AC_COND_LOG2_MAX, rate_state_frac=lib.AC_RATE_STATE_FRAC,
                  angle_frac=lib.AC_ANGLE_FRAC, rest_extra_frac=lib.AC_REST_EXTRA_FRAC,
                  att_w_frac=lib.AC_ATT_W_FRAC, att_w2_frac=lib.AC_ATT_W2_FRAC,
                  disp_a_frac=lib.AC_DISP_A_FRAC, disp_v_frac=lib.AC_DISP_V_FRAC,
                  disp_p_frac=lib.AC_DISP_P_FRAC, disp_rot_frac=lib.AC_DISP_ROT_FRAC,
                  disp_g_frac=lib.AC_DISP_G_FRAC, disp_gsum_max=lib.AC_DISP_GSUM_MAX)


def check(status: int, context: str) -> bool:
    """Raise for an error status; return True when the core reports saturation (the status
    bit AC_SATURATED; the other warning bit, AC_AT_RAIL, is :func:`at_rail`'s)."""
    if status < 0:
        raise core_error(int(status), context)
    return bool(status & lib.AC_SATURATED)


def at_rail(status: int) -> bool:
    """The status bit AC_AT_RAIL: a raw reading sat at a rail of the table (its raw_min /
    raw_max), so the outputs are not a measurement (ac_trim_rails, ac_process, ac_triad_apply)."""
    return status >= 0 and bool(status & lib.AC_AT_RAIL)


def cptr(ctype: str, arr: np.ndarray):
    """A C pointer of type ctype into a contiguous numpy array (no copy)."""
    return ffi.cast(ctype, ffi.from_buffer(arr))


def new_resolver(m, m_shift, k, g, g_shift, rails=(0, 0)):
    """An ``ac_resolver`` filled from table arrays (m is 6 x N); ``rails`` the converter's
    (raw_min, raw_max) as uint16 codes ((0, 0): unknown, nothing flagged)."""
    m = np.asarray(m)
    n = m.shape[1]
    r = ffi.new("ac_resolver *")
    r.n = n
    r.raw_min, r.raw_max = (int(v) for v in rails)
    for j in range(6):
        r.m_shift[j] = int(m_shift[j])
        r.g_shift[j] = int(g_shift[j])
        r.k[j] = int(k[j])
        for i in range(n):
            r.m[j][i] = int(m[j, i])
        for q in range(6):
            r.g[j][q] = int(g[j][q])
    return r


def resolver_arrays(r) -> dict:
    """The table arrays of an ``ac_resolver`` (inverse of new_resolver)."""
    n = int(r.n)
    return dict(
        m=np.array([[r.m[j][i] for i in range(n)] for j in range(6)], dtype=np.int16),
        m_shift=np.array([r.m_shift[j] for j in range(6)], dtype=np.int8),
        k=np.array([r.k[j] for j in range(6)], dtype=np.int32),
        g=np.array([[r.g[j][q] for q in range(6)] for j in range(6)], dtype=np.int16),
        g_shift=np.array([r.g_shift[j] for j in range(6)], dtype=np.int8),
        rails=(int(r.raw_min), int(r.raw_max)),
    )


def offset_binary(a: np.ndarray) -> np.ndarray:
    """int16 counts as the uint16 codes a + 32768 (order and differences kept): what
    ``ac_trim_s16`` pre-trims, so ac_process_batch on these equals ac_trim_s16 + ac_resolve."""
    return (np.asarray(a, np.int64) + 32768).astype(np.uint16)


def process_batch(resolver, trim: np.ndarray, raw: np.ndarray,
                  omega_q: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Pre-trim and resolve every sample: raw (n,N) -> out (n,6) int32 Q.AC_OUT_FRAC, flags (n,).
    A signed (int16) ``trim`` means signed readings: both are passed as offset-binary codes
    (bit for bit what ``ac_trim_s16`` does; tests/python/test_signed_triad.py checks it)."""
    if np.asarray(trim).dtype == np.int16:
        raw, trim = offset_binary(raw), offset_binary(trim)
    raw = np.ascontiguousarray(raw, dtype=np.uint16)
    trim = np.ascontiguousarray(trim, dtype=np.uint16)
    n = raw.shape[0]
    if raw.ndim != 2 or raw.shape[1] != resolver.n or trim.shape != (resolver.n,):
        raise ValueError(f"raw must be (n, {resolver.n}) and trim ({resolver.n},)")
    out = np.zeros((n, 6), dtype=np.int32)
    flags = np.zeros(n, dtype=np.uint8)
    if omega_q is not None:
        omega_q = np.ascontiguousarray(omega_q, dtype=np.int16)
        if omega_q.shape != (n, 3):
            raise ValueError("omega must be (n, 3)")
        wp = cptr("int16_t *", omega_q)
    else:
        wp = ffi.NULL
    st = lib.ac_process_batch(resolver, cptr("uint16_t *", trim), cptr("uint16_t *", raw), n, wp,
                              cptr("int32_t *", out), cptr("uint8_t *", flags))
    check(st, "ac_process_batch")
    return out, flags


def resolve_one(resolver, x: np.ndarray, omega_q: np.ndarray | None = None) -> tuple[np.ndarray, bool]:
    """ac_resolve on one sample of trimmed readings; returns (out (6,), saturated)."""
    x = np.ascontiguousarray(x, dtype=np.int16)
    out = np.zeros(6, dtype=np.int32)
    wp = ffi.NULL if omega_q is None else cptr("int16_t *", np.ascontiguousarray(omega_q, dtype=np.int16))
    sat = check(lib.ac_resolve(resolver, cptr("int16_t *", x), wp, cptr("int32_t *", out)), "ac_resolve")
    return out, sat


def build_resolver(sens_q: np.ndarray, pos_q: np.ndarray, offset_q: np.ndarray):
    """On-device inversion (ac_resolver_build) from fixed-point channel parameters.

    Returns (resolver, cond_log2)."""
    n = len(offset_q)
    cal = ffi.new("ac_channel_cal[]", max(n, 1))
    for i in range(n):
        for a in range(3):
            cal[i].sens[a] = int(sens_q[i][a])
            cal[i].pos[a] = int(pos_q[i][a])
        cal[i].offset = int(offset_q[i])
    work = ffi.new("ac_build_work *")
    out = ffi.new("ac_resolver *")
    info = ffi.new("ac_build_info *")
    check(lib.ac_resolver_build(cal, n, work, out, info), "ac_resolver_build")
    return out, int(info.cond_log2)


def rate_integrate(alpha_q: np.ndarray, dt_m: int, dt_shift: int,
                   leak: int) -> tuple[np.ndarray, np.ndarray]:
    """ac_rate_step over alpha (n,3) int32 Q.AC_OUT_FRAC -> omega (n,3) int16 Q.AC_OMEGA_FRAC,
    and the per-step saturation flags (n,)."""
    alpha_q = np.ascontiguousarray(alpha_q, dtype=np.int32)
    st = ffi.new("ac_rate *")
    check(lib.ac_rate_init(st, dt_m, dt_shift, leak), "ac_rate_init")
    out = np.zeros(alpha_q.shape, dtype=np.int16)
    a = ffi.new("int32_t[3]")
    w = ffi.new("int16_t[3]")
    sat = np.zeros(alpha_q.shape[0], dtype=bool)
    for n in range(alpha_q.shape[0]):
        a[0], a[1], a[2] = (int(v) for v in alpha_q[n])
        sat[n] = check(lib.ac_rate_step(st, a, w), "ac_rate_step")
        out[n] = (w[0], w[1], w[2])
    return out, sat


# --------------------------------------------------------------------------
# the correctable terms (ac_temp.h, ac_skew.h, ac_nonlin.h)
# --------------------------------------------------------------------------


def new_temp_table(t_ref: int, oc, gc, o, frac: int = 0):
    """An ``ac_temp_table`` (ac_temp.h) from its integer fields (oc Q.AC_TEMP_OC_FRAC, gc
    Q.AC_TEMP_GC_FRAC, o Q.AC_OFFSET_FRAC: (N,); ``frac`` the output's fraction bits k, y in
    2^-k counts)."""
    t = ffi.new("ac_temp_table *")
    t.n, t.t_ref, t.frac = len(oc), int(t_ref), int(frac)
    for i in range(len(oc)):
        t.oc[i], t.gc[i], t.o[i] = int(oc[i]), int(gc[i]), int(o[i])
    return t


def new_skew_table(length: int, whole, frac):
    """An ``ac_skew_table`` (ac_skew.h): delay line length, whole (N,) and frac (N,) Q.15 delays."""
    t = ffi.new("ac_skew_table *")
    t.n, t.len = len(whole), int(length)
    for i in range(len(whole)):
        t.whole[i], t.frac[i] = int(whole[i]), int(frac[i])
    return t


def new_nonlin_table(shift: int, a2, a3, iterations: int = 0):
    """An ``ac_nonlin_table`` (ac_nonlin.h): a2, a3 (N,), their shared shift and the iteration
    count (0: AC_NONLIN_ITERATIONS)."""
    t = ffi.new("ac_nonlin_table *")
    t.n, t.shift, t.iterations = len(a2), int(shift), int(iterations)
    for i in range(len(a2)):
        t.a2[i], t.a3[i] = int(a2[i]), int(a3[i])
    return t


def temp_lag_run(k: int, shift: int, temp_q) -> tuple[np.ndarray, np.ndarray]:
    """ac_temp_lag_step over temp_q (n,) int16 Q.AC_TEMP_FRAC from a fresh filter: the lagged
    temperatures (n,) int16 and the per-step saturation (n,) bool."""
    f = ffi.new("ac_temp_lag *")
    check(lib.ac_temp_lag_init(f, int(k), int(shift)), "ac_temp_lag_init")
    temp_q = np.asarray(temp_q, np.int64)
    out = np.zeros(temp_q.shape[0], np.int16)
    sat = np.zeros(temp_q.shape[0], bool)
    y = ffi.new("int16_t *")
    for n, v in enumerate(temp_q):
        sat[n] = check(lib.ac_temp_lag_step(f, int(v), y), "ac_temp_lag_step")
        out[n] = y[0]
    return out, sat


def temp_correct(table, t_off: int, t_gain: int, x) -> tuple[np.ndarray, bool]:
    """ac_temp_correct on one sample x (N,) int16: (y (N,) int16, saturated)."""
    x = np.ascontiguousarray(x, dtype=np.int16)
    y = np.zeros_like(x)
    sat = check(lib.ac_temp_correct(table, int(t_off), int(t_gain), cptr("int16_t *", x), cptr("int16_t *", y)),
                "ac_temp_correct")
    return y, sat


def nonlin_invert(table, x) -> tuple[np.ndarray, bool]:
    """ac_nonlin_invert on one sample x (N,) int16: (y (N,) int16, saturated)."""
    x = np.ascontiguousarray(x, dtype=np.int16)
    y = np.zeros_like(x)
    sat = check(lib.ac_nonlin_invert(table, cptr("int16_t *", x), cptr("int16_t *", y)), "ac_nonlin_invert")
    return y, sat


class SkewLine:
    """An ``ac_skew_line`` on a buffer this object owns (the caller's, as firmware's)."""

    def __init__(self, table):
        self.table = table
        self.buf = np.zeros(int(table.len) * int(table.n), np.int16)
        self.line = ffi.new("ac_skew_line *")
        check(lib.ac_skew_init(self.line, table, cptr("int16_t *", self.buf), self.buf.size), "ac_skew_init")

    def step(self, x) -> np.ndarray:
        """ac_skew_step on one sample x (N,) int16 -> y (N,) int16."""
        x = np.ascontiguousarray(x, dtype=np.int16)
        y = np.zeros_like(x)
        check(lib.ac_skew_step(self.table, self.line, cptr("int16_t *", x), cptr("int16_t *", y)), "ac_skew_step")
        return y


def triad_resolve_batch(table, x) -> tuple[np.ndarray, np.ndarray]:
    """ac_triad_resolve on every sample of trimmed readings x (n, 3) int16: f (n, 3) int32
    Q.AC_OUT_FRAC and the saturation (n,) bool."""
    check(lib.ac_triad_check(table), "ac_triad_check")
    x = np.ascontiguousarray(x, dtype=np.int16)
    out = np.zeros((x.shape[0], 3), np.int32)
    sat = np.zeros(x.shape[0], bool)
    for n in range(x.shape[0]):
        sat[n] = check(lib.ac_triad_resolve(table, cptr("int16_t *", x[n]), cptr("int32_t *", out[n])),
                       "ac_triad_resolve")
    return out, sat
