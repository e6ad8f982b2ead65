"""The one quantizer: calibration (float) -> the C core's fixed-point tables.

The generated C header, ``resolve --engine fixed`` and the tests all take their
constants from :func:`quantize`, so "the fixed engine uses exactly the header's
constants" holds by construction.  The same rules are implemented on the device
by ``ac_resolver_build`` (csrc/ac_resolver_build.c); tests compare the two.

Rules (see include/accelcal/ac_resolve.h for the arithmetic they feed):
  trim_i   = round(b_i)                       uint16 counts (int16 for a chip with signed output)
  o_i      = b_i - trim_i                     residual offset, Q.AC_OFFSET_FRAC
  s_i, r_i                                    Q.AC_SENS_FRAC, Q.AC_POS_FRAC (int32)
  M        = pinv(R(s~, r~)) in output LSB per count, from the *quantised* s~, r~
  m_shift_j = largest s <= 31 with max_i|M_ji| 2^s <= 32767 and sum_i|M_ji| 2^s <= 65535 - N
  m_ji     = round(M_ji 2^m_shift_j),  k_j = round((M o~)_j 2^m_shift_j)
  G        = M C (LSB per (rad/s)^2), g / g_shift by the same rule with 6 terms
Rounding is half up (floor(x + 1/2)), as in the core.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import model
from ..errors import AccelcalError, IllConditionedError, SingularError
from .native import FORMATS, new_resolver

COEF_MAX = 32767
ROW_L1_MAX = 65535


class QuantizeError(AccelcalError):
    """A calibration value does not fit its fixed-point format."""


def round_half_up(x):
    return np.floor(np.asarray(x, float) + 0.5)


def largest_shift(v: float, limit: float) -> int:
    """Largest integer s with v * 2^s <= limit (v > 0), exactly."""
    s = math.floor(math.log2(limit / v))
    while math.ldexp(v, s) > limit:
        s -= 1
    while math.ldexp(v, s + 1) <= limit:
        s += 1
    return s


def row_shift(row: np.ndarray, what: str) -> int:
    a = np.abs(np.asarray(row, float))
    vmax, vsum = float(a.max()), float(a.sum())
    if vmax == 0.0:
        return 31
    s = min(31, largest_shift(vmax, COEF_MAX), largest_shift(vsum, ROW_L1_MAX - len(a)))
    if s < -31:
        raise QuantizeError(f"{what}: coefficients too large for the resolver's Q format")
    return s


def to_fixed(x, frac: int, what: str, lo: int = -2**31, hi: int = 2**31 - 1) -> np.ndarray:
    """x in Q.frac, rounded half up, as int64; QuantizeError naming ``what`` and the index of
    the first value outside [lo, hi] (or not finite)."""
    q = round_half_up(np.asarray(x, float) * 2.0**frac)
    bad = np.argwhere((q < lo) | (q > hi) | ~np.isfinite(q))
    if bad.size:
        idx = tuple(int(v) for v in bad[0])
        val = np.asarray(x, float)[idx]
        raise QuantizeError(f"{what}{list(idx)} = {val:.9g} does not fit its fixed-point format "
                            f"(Q.{frac} in [{lo}, {hi}])")
    return q.astype(np.int64)


@dataclass
class FixedTables:
    """Everything the firmware needs, in the core's integer formats."""
    device: str
    trim: np.ndarray      # (N,) uint16 counts (int16 when ``signed``)
    sens_q: np.ndarray    # (N,3) int32 Q.sens_frac
    pos_q: np.ndarray     # (N,3) int32 Q.pos_frac
    offset_q: np.ndarray  # (N,) int32 Q.offset_frac (b_i - trim_i)
    m: np.ndarray         # (6,N) int16
    m_shift: np.ndarray   # (6,) int8
    k: np.ndarray         # (6,) int32
    g: np.ndarray         # (6,6) int16
    g_shift: np.ndarray   # (6,) int8
    cond_log2: int
    extra: dict = field(default_factory=dict)
    signed: bool = False  # the chip's readings are int16 (pre-trim with ac_trim_s16)
    rails: tuple = (0, 0)  # the converter's (raw_min, raw_max) as uint16 codes (rail_codes); (0, 0) unknown

    @property
    def n(self) -> int:
        return len(self.trim)

    # dequantised views (exact values of the table entries)
    def sensitivity(self) -> np.ndarray:
        return self.sens_q / 2.0**FORMATS.sens_frac

    def positions(self) -> np.ndarray:
        return self.pos_q / 2.0**FORMATS.pos_frac

    def offsets(self) -> np.ndarray:
        return self.trim + self.offset_q / 2.0**FORMATS.offset_frac

    def resolver(self):
        return new_resolver(self.m, self.m_shift, self.k, self.g, self.g_shift, self.rails)


def cond_log2_equilibrated(R: np.ndarray) -> int:
    """ceil(log2 cond_1) of the matrix ac_resolver_build inverts (R~ or R~^T R~)."""
    colmax = np.abs(R).max(axis=0)
    colexp = np.array([math.frexp(v)[1] for v in colmax])  # colmax * 2^-colexp in [0.5, 1)
    Rt = R * 2.0 ** (-colexp)
    A = Rt if R.shape[0] == 6 else Rt.T @ Rt
    c = np.linalg.norm(A, 1) * np.linalg.norm(np.linalg.inv(A), 1)
    return int(math.ceil(math.log2(c)))


def trim_range(signed: bool) -> tuple[int, int]:
    """The pre-trim's input range: int16 for a chip with signed output, else uint16."""
    return (-32768, 32767) if signed else (0, 65535)


def rail_codes(raw_min: int | None, raw_max: int | None, signed: bool) -> tuple[int, int]:
    """The converter's rails (counts) as the uint16 codes the core's tables hold (offset binary,
    count + 32768, for a chip with signed output, as the trim codes); (0, 0), "unknown: flag
    nothing", for None.  QuantizeError naming the rail outside the code range."""
    if raw_min is None or raw_max is None:
        return (0, 0)
    lo, hi = trim_range(signed)
    for name, v in (("raw_min", raw_min), ("raw_max", raw_max)):
        if not lo <= v <= hi:
            raise QuantizeError(f"{name} = {v} is outside the core's reading range [{lo}, {hi}]")
    off = 32768 if signed else 0
    return (int(raw_min) + off, int(raw_max) + off)


def rail_counts(codes, signed: bool) -> tuple[int, int]:
    """The converter's (raw_min, raw_max) in the chip's own counts from the tables' uint16 codes
    (:func:`rail_codes`' inverse: what ac_trim_rails_s16 takes for a signed chip); (0, 0) codes,
    "unknown", stay an empty pair (raw_min >= raw_max)."""
    off = 32768 if signed else 0
    return int(codes[0]) - off, int(codes[1]) - off


def quantize(offsets, sensitivity, positions, device: str = "", signed: bool = False,
             rails: tuple[int, int] | None = None, in_frac: int = 0) -> FixedTables:
    """Quantise a calibration (b (N,), s (N,3), r (N,3)) into the core's tables
    (``signed``: the chip's readings are int16, and so is the trim; ``rails``: the converter's
    (raw_min, raw_max) in counts, flagged by the core as AC_AT_RAIL, or None: unknown).

    ``in_frac`` k > 0: the table takes x in 2^-k counts (the correctable terms' output,
    ac_temp.h's frac): each row's shift m_shift_j + k (at most 31) with the same m_ji
    (M 2^(m_shift_j + k) 2^-k), k_j = round((M o~)_j 2^(m_shift_j + k)); the matrix keeps its
    precision, the offset term gains k bits.  0: today's table bit for bit."""
    f = FORMATS
    b = np.asarray(offsets, float)
    n = len(b)
    if not 6 <= n <= f.max_channels:
        raise QuantizeError(f"{n} channels: the resolver takes 6..{f.max_channels}"
                            + ("; a 3-axis sensor gets the triad table (quantize_triad)" if n == 3 else ""))
    trim = to_fixed(b, 0, "offset_counts", *trim_range(signed))
    sens_q = to_fixed(sensitivity, f.sens_frac, "sensitivity")
    pos_q = to_fixed(positions, f.pos_frac, "position_m")
    offset_q = to_fixed(b - trim, f.offset_frac, "residual offset")
    s_t = sens_q / 2.0**f.sens_frac
    r_t = pos_q / 2.0**f.pos_frac
    o_t = offset_q / 2.0**f.offset_frac
    R = model.sensor_matrix(r_t, s_t)
    rank = int(np.linalg.matrix_rank(R))
    if rank < 6:
        raise SingularError(-3, f"device {device or '(unnamed)'}: the sensor matrix of its {n} channels has rank "
                                f"{rank} < 6, so the 6-DOF resolver's table cannot be built (two triads on one line, "
                                "a pendulum's, leave the turn about that line open: 'accelcal attitude' resolves them)")
    cl2 = cond_log2_equilibrated(R)
    if cl2 > f.cond_log2_max:
        raise IllConditionedError(-4, f"geometry too ill-conditioned: cond ~ 2^{cl2} > 2^{f.cond_log2_max}")
    M = np.linalg.pinv(R) * 2.0**f.out_frac            # LSB per count
    G = M @ model.centripetal_matrix(r_t, s_t)          # LSB per (rad/s)^2
    kv = M @ o_t                                        # LSB
    m_shift = np.array([row_shift(M[j], f"resolve matrix row {j}") for j in range(6)])
    g_shift = np.array([row_shift(G[j], f"centripetal table row {j}") for j in range(6)])
    m = round_half_up(M * 2.0 ** (np.minimum(m_shift + in_frac, 31) - in_frac)[:, None]).astype(np.int16)
    m_shift = np.minimum(m_shift + in_frac, 31)
    g = round_half_up(G * 2.0 ** g_shift[:, None]).astype(np.int16)
    k = to_fixed(kv * 2.0 ** m_shift, 0, "offset term k")
    return FixedTables(device=device, trim=trim.astype(np.int16 if signed else np.uint16),
                       sens_q=sens_q.astype(np.int32),
                       pos_q=pos_q.astype(np.int32), offset_q=offset_q.astype(np.int32),
                       m=m, m_shift=m_shift.astype(np.int8), k=k.astype(np.int32), g=g,
                       g_shift=g_shift.astype(np.int8), cond_log2=cl2, signed=signed,
                       rails=rail_codes(*(rails or (None, None)), signed))


def quantize_calibration(device, cal, in_frac: int = 0) -> FixedTables:
    """quantize() for a Device and a Calibration (positions default to the device's)."""
    pos = cal.positions_or_nominal(device)
    return quantize(cal.offsets, cal.sensitivity, pos, device.name, signed=device.raw_min < 0,
                    rails=(device.raw_min, device.raw_max), in_frac=in_frac)


def omega_to_fixed(omega) -> np.ndarray:
    """rad/s -> int16 Q.AC_OMEGA_FRAC, refusing values outside the range (no silent clipping)."""
    return to_fixed(omega, FORMATS.omega_frac, "omega", -32768, 32767).astype(np.int16)


def exact_fixed_semantics(t: FixedTables, raw: np.ndarray, omega_q: np.ndarray | None = None):
    """The core's arithmetic without its intermediate roundings, in float64.

    Returns (exact (n,6) in output LSB, bound (n,6) in LSB, trim_saturated (n,)):
    the core's output must satisfy |out - exact| <= 0.5 + bound unless it saturated."""
    f = FORMATS
    raw = np.atleast_2d(np.asarray(raw, np.int64))
    d = raw - t.trim.astype(np.int64)
    x = np.clip(d, -32768, 32767)
    trim_sat = np.any(x != d, axis=1)
    ms = t.m_shift.astype(float)
    exact = (x @ t.m.T.astype(float) - t.k) * 2.0 ** (-ms)
    bound = np.zeros_like(exact)
    if omega_q is not None:
        w = np.atleast_2d(np.asarray(omega_q, np.int64))
        p = model.omega_products(w.astype(float))                 # units 2^-2W (rad/s)^2, exact
        gs = t.g_shift.astype(float)
        exact = exact - (p @ t.g.T.astype(float)) * 2.0 ** (-2 * f.omega_frac - gs)
        maxsq = np.max(w * w, axis=1)
        s = np.maximum(0, np.array([int(v).bit_length() for v in maxsq]) - 14)
        gl1 = np.abs(t.g.astype(float)).sum(axis=1)
        bound = np.where(s[:, None] > 0, gl1 * 2.0 ** (s[:, None] - 1 - 2 * f.omega_frac - gs), 0.0)
        dsh = s[:, None] - 2 * f.omega_frac - gs + ms
        bound = bound + np.where(dsh < 0, 2.0 ** (-1 - ms), 0.0)
    return exact, bound, trim_sat


def table_error_bound(t: FixedTables, raw: np.ndarray, omega_q: np.ndarray | None = None) -> np.ndarray:
    """Bound (n,6) in output LSB on |exact fixed semantics - float reference| that comes from
    rounding the table entries (m, k, g each by at most half a mantissa LSB); the float
    reference here uses the calibration as the tables store it (s, r, o in their Q formats)."""
    raw = np.atleast_2d(np.asarray(raw, np.int64))
    x = np.clip(raw - t.trim.astype(np.int64), -32768, 32767)
    half_m = 0.5 * 2.0 ** (-t.m_shift.astype(float))
    bound = (np.abs(x).sum(axis=1, keepdims=True) + 1.0) * half_m
    if omega_q is not None:
        p = np.abs(model.omega_products(np.atleast_2d(omega_q) / 2.0 ** FORMATS.omega_frac))
        bound = bound + p.sum(axis=1, keepdims=True) * 0.5 * 2.0 ** (-t.g_shift.astype(float))
    return bound


def resolver_rounding_bound(t: FixedTables, offsets, sensitivity, positions, raw_min: int,
                            raw_max: int) -> tuple[np.ndarray, np.ndarray]:
    """What the table's rounding (of s~, r~, o~, m, k and g) can add to the core's error against
    the float reference ``model.resolve`` with the unquantised calibration: the 6-channel
    analogue of :func:`accelcal.firmware.triad.triad_rounding_bound`.

    The result is not affine in the reading alone (the centripetal term is quadratic in
    omega), so the two parts are bounded separately:

    * linear part, (6,) output LSB: the largest |(m x - k) 2^-m_shift - M (raw - b) 2^AC_OUT_FRAC|
      over every reading in [raw_min, raw_max]^N that the trim does not clip.  Both sides are
      affine in the reading on that box, so the largest difference is |d(mid)| + sum_i |A_i| h_i
      (A the difference's slope, mid and h the box's centre and half-widths): reached at a corner.
    * centripetal part, (6,) output LSB per (rad/s)^2: sum_q |g_jq 2^-g_shift_j - (M C)_jq
      2^AC_OUT_FRAC|; times max_a omega_a^2 it bounds the table's centripetal error at any omega
      (every |p_q| <= max_a omega_a^2), the float fed the same (quantised) omega.

    The core adds its final rounding (0.5 LSB) and, for |omega_a| >= 0.125 rad/s, the rounding
    of the squared rates E_j of ac_resolve.h (:func:`exact_fixed_semantics`'s bound).
    """
    f = FORMATS
    raw_min, raw_max = int(raw_min), int(raw_max)
    trim = t.trim.astype(np.int64)
    lo = np.maximum(raw_min, trim - 32768).astype(float)
    hi = np.minimum(raw_max, trim + 32767).astype(float)
    M = model.resolve_matrix(np.asarray(positions, float), np.asarray(sensitivity, float)) * 2.0 ** f.out_frac
    scale = 2.0 ** (-t.m_shift.astype(float))[:, None]
    A = t.m.astype(float) * scale - M                                   # LSB per count
    c = -(t.k.astype(float) + t.m.astype(float) @ trim.astype(float)) * scale[:, 0] + M @ np.asarray(offsets, float)
    mid, half = (lo + hi) / 2.0, (hi - lo) / 2.0
    linear = np.abs(A @ mid + c) + np.abs(A) @ half
    G = M @ model.centripetal_matrix(np.asarray(positions, float), np.asarray(sensitivity, float))
    centripetal = np.abs(t.g.astype(float) * 2.0 ** (-t.g_shift.astype(float))[:, None] - G).sum(axis=1)
    return linear, centripetal
