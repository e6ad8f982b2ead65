"""Motion estimators: pendulum attitude from two triads (seed 3), stop-to-stop
displacement (seed 4) and angular rate from alpha with reset on rest (seed 1).

Three layers, as everywhere in accelcal:

* **float reference** (float64, the truth the C core is held to): the same
  algorithms as ``csrc/ac_attitude.c``, ``ac_displace.c``, ``ac_rest.c``, written
  once as "core" functions that take their constants as floats.  Fed the exact
  geometry they are the reference (``engine="float"``); fed the constants as the
  C structs store them, the same clipped integer inputs and the C decisions
  (gate, sign, rest) they are the **twins** the property tests compare the C
  code with, sample by sample, within the bounds stated in the headers
  (``attitude_rate_bound``, ``displace_error_bound``).
* **fixed-point wrappers** through cffi (``*_fixed``): the C core on arrays.
* **host forms** on recordings: ``attitude_from_recording``,
  ``displacement_from_recording`` (streaming and offline), ``rate_from_recording``
  returning :class:`Columns`, and ``report_plots``.

Conventions follow shared/spec/data-contract.md (see include/accelcal/ac_attitude.h
for the derivation of the signs from f(r) = f + alpha x r + omega x (omega x r)).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import AccelcalError, InputError
from .native import FORMATS, cptr
from .quantize import round_half_up
from .recording import check_for_device
from .resolve import check_core_input

__all__ = [
    "Columns", "RestParams", "AttitudeParams", "DisplaceParams",
    "dt_fixed", "quantize_triad", "triad_apply_fixed", "triad_apply_float",
    "rest_detect", "rest_fixed", "rest_cfg_fixed",
    "attitude_float", "attitude_fixed", "attitude_twin", "attitude_rate_bound",
    "tilt_frame", "displace_stream", "displace_fixed", "displace_twin", "displace_offline",
    "displace_error_bound", "rate_rest_float", "rate_rest_fixed",
    "attitude_from_recording", "displacement_from_recording", "rate_from_recording",
    "report_plots",
]

OUT_FRAC = FORMATS.out_frac        # AC_OUT_FRAC: f, alpha (from the compiled core)
OMEGA_FRAC = FORMATS.omega_frac    # AC_OMEGA_FRAC
ANGLE_FRAC = 13     # AC_ANGLE_FRAC
W_FRAC = 20         # AC_ATT_W_FRAC, AC_ATT_W2_FRAC
A_FRAC, V_FRAC, P_FRAC, ROT_FRAC, G_FRAC = 16, 24, 20, 14, 16
GSUM_MAX = 4096     # AC_DISP_GSUM_MAX
CLIP = 32767 / 1024.0  # inputs are clipped to int16 Q.10 for the tests and sums
CLIP_LO = -32768 / 1024.0

# flag bits (mirrors of the C headers; checked against the compiled core in the tests)
REST_QUIET, REST_AT_REST, REST_ENTER, REST_LEAVE, REST_CLIP = 0x01, 0x02, 0x04, 0x08, 0x10
ATT_GATED, ATT_W2_NEG, ATT_UNSETTLED, ATT_NO_GRAVITY, ATT_SAT, ATT_SIGN_NEG = 0x01, 0x02, 0x04, 0x08, 0x10, 0x20
(DISP_NO_REF, DISP_REST, DISP_MOVING, DISP_SEG_END, DISP_LONG, DISP_SAT, DISP_OPEN, DISP_NO_REST,
 DISP_REF_SET, DISP_BAD_REF) = (1 << i for i in range(10))


def _lib():
    from ._core import ffi, lib
    return ffi, lib


def _check(status: int, context: str) -> bool:
    from .native import check
    return check(status, context)


class Columns(dict):
    """Output columns (name -> (n,) float array) in CSV order, with ``warnings``
    (one-line strings for the user: flagged, not fatal) and ``meta`` (comments)."""

    def __init__(self, *args: Any, warnings: list[str] | None = None, meta: dict | None = None, **kw: Any):
        super().__init__(*args, **kw)
        self.warnings: list[str] = list(warnings or [])
        self.meta: dict = dict(meta or {})


# =============================================================================
# small fixed-point helpers
# =============================================================================

def dt_fixed(dt: float) -> tuple[int, int]:
    """dt -> (dt_m, dt_shift) with dt_m in [2^15, 2^16) and dt = dt_m 2^-dt_shift
    (the ac_rate convention; 1/60 s -> 34953, 21).  dt_shift must be 16..46."""
    if not (math.isfinite(dt) and dt > 0):
        raise AccelcalError(f"sample interval {dt!r} s is not a positive number")
    sh = 15 - math.floor(math.log2(dt))
    m = int(round_half_up(dt * 2.0 ** sh))
    if m >= 65536:
        sh -= 1
        m = int(round_half_up(dt * 2.0 ** sh))
    if m < 32768:
        sh += 1
        m = int(round_half_up(dt * 2.0 ** sh))
    if not 16 <= sh <= 46:
        raise AccelcalError(f"sample interval {dt:.6g} s is outside the fixed-point integrators' range "
                            "(about 15 us .. 0.5 s)")
    return m, sh


def _i16(x):
    return np.clip(np.asarray(x, np.int64), -32768, 32767)


def _q10(f) -> np.ndarray:
    """m/s^2 -> int32 Q.10 (half up), saturating (used only to feed the fixed engine)."""
    return np.clip(round_half_up(np.asarray(f, float) * 1024.0), -2**31, 2**31 - 1).astype(np.int32)


def atan2_fixed(y, x) -> tuple[np.ndarray, np.ndarray]:
    """ac_atan2 elementwise: (angle int Q.13 rad, magnitude)."""
    ffi, lib = _lib()
    y = np.atleast_1d(np.asarray(y, np.int64))
    x = np.atleast_1d(np.asarray(x, np.int64))
    a = ffi.new("int16_t *")
    m = ffi.new("uint32_t *")
    ang = np.empty(y.shape, np.int64)
    mag = np.empty(y.shape, np.int64)
    for i, (yy, xx) in enumerate(zip(y.tolist(), x.tolist())):
        _check(lib.ac_atan2(yy, xx, a, m), "ac_atan2")
        ang[i], mag[i] = a[0], m[0]
    return ang, mag


# =============================================================================
# triad: raw -> calibrated specific force at its point
# =============================================================================

@dataclass
class TriadTable:
    """One triad's fixed-point table (ac_triad): f = round((m x - k) 2^-shift), x = raw - trim."""
    trim: np.ndarray   # (3,) uint16
    m: np.ndarray      # (3,3) int16
    shift: np.ndarray  # (3,) int8
    k: np.ndarray      # (3,) int32

    def cdata(self):
        ffi, _ = _lib()
        t = ffi.new("ac_triad *")
        for j in range(3):
            t.trim[j] = int(self.trim[j])
            t.shift[j] = int(self.shift[j])
            t.k[j] = int(self.k[j])
            for i in range(3):
                t.m[j][i] = int(self.m[j, i])
        return t


def triad_matrix(sens3: np.ndarray) -> np.ndarray:
    """M = S^-1 (3x3, m/s^2 per count) of a triad whose rows are s_i (counts per m/s^2)."""
    S = np.asarray(sens3, float)
    if S.shape != (3, 3) or not np.all(np.isfinite(S)) or abs(np.linalg.det(S)) <= 1e-12 * np.abs(S).max() ** 3:
        raise AccelcalError("a triad's sensitivity matrix is singular: its three axes do not span 3-D")
    return np.linalg.inv(S)


def quantize_triad(offsets3, sens3) -> TriadTable:
    """The triad's table by the rules of quantize.quantize (trim = round(b), residual folded into k,
    row shift: max |m| <= 32767 and sum |m| <= 65535 - 3)."""
    from .quantize import _fixed, row_shift
    b = np.asarray(offsets3, float)
    trim = _fixed(b, 0, "offset_counts", 0, 65535)
    M = triad_matrix(sens3) * 2.0 ** OUT_FRAC       # output LSB per count
    o = b - trim
    shift = np.array([row_shift(M[j], f"triad matrix row {j}") for j in range(3)])
    m = round_half_up(M * 2.0 ** shift[:, None]).astype(np.int16)
    k = _fixed((M @ o) * 2.0 ** shift, 0, "triad offset term k")
    return TriadTable(trim=trim.astype(np.uint16), m=m, shift=shift.astype(np.int8), k=k.astype(np.int32))


def triad_apply_fixed(table: TriadTable, raw) -> tuple[np.ndarray, np.ndarray]:
    """ac_triad_apply on (n,3) raw -> (f (n,3) int32 Q.10, saturated (n,) bool)."""
    ffi, lib = _lib()
    raw = np.ascontiguousarray(raw, dtype=np.uint16)
    t = table.cdata()
    _check(lib.ac_triad_check(t), "ac_triad_check")
    out = np.zeros((raw.shape[0], 3), np.int32)
    sat = np.zeros(raw.shape[0], bool)
    fo = ffi.new("int32_t[3]")
    for n in range(raw.shape[0]):
        sat[n] = _check(lib.ac_triad_apply(t, cptr("uint16_t *", raw[n]), fo), "ac_triad_apply")
        out[n] = (fo[0], fo[1], fo[2])
    return out, sat


def triad_exact(table: TriadTable, raw) -> np.ndarray:
    """The triad table's exact result in output LSB (before the final rounding)."""
    x = np.clip(np.asarray(raw, np.int64) - table.trim.astype(np.int64), -32768, 32767)
    return (x @ table.m.T.astype(float) - table.k) * 2.0 ** (-table.shift.astype(float))


def triad_apply_float(offsets3, sens3, raw) -> np.ndarray:
    """Float reference: f = S^-1 (raw - b), (n,3) m/s^2."""
    return (np.asarray(raw, float) - np.asarray(offsets3, float)) @ triad_matrix(sens3).T


# =============================================================================
# rest detector (ac_rest)
# =============================================================================

@dataclass
class RestParams:
    """Rest test (see include/accelcal/ac_rest.h).  ``g`` None switches the |f| test off;
    ``ref_max`` bounds |f - (the first rest's mean f)| once the displacement knows it."""
    dev_max: float = 0.1            # m/s^2, max_k |f_k - mean_k|
    g: float | None = 9.80665       # m/s^2
    g_tol: float = 0.5              # |f| within g +- g_tol
    alpha_max: float = math.inf     # rad/s^2 (only when alpha is given)
    hold: int = 25                  # samples
    ema_shift: int = 3              # mean weight 2^-ema_shift
    ref_max: float = 0.15           # m/s^2 (only when a reference is given)

    def g2_bounds(self) -> tuple[float, float]:
        if self.g is None:
            return 0.0, math.inf
        return max(self.g - self.g_tol, 0.0) ** 2, (self.g + self.g_tol) ** 2


def default_rest_params(device, rate_hz: float | None = None, alpha_sigma: float | None = None) -> RestParams:
    """dev_max = 5 sigma (device noise; at least 0.01 m/s^2), ref_max = dev_max + 0.05 m/s^2
    (room for a zero-point drift between rests), hold = 0.25 s, mean over ~0.1 s, |f| within
    0.5 m/s^2 of g, |alpha| <= 5 sigma_alpha when given."""
    rate = float(rate_hz or device.sample_rate_hz)
    noise = float(getattr(device, "noise_mps2", 0.0) or 0.0)
    k = int(min(12, max(1, round(math.log2(max(2.0, 0.1 * rate))))))
    dev = max(5.0 * noise, 0.01)
    return RestParams(dev_max=dev, g=float(device.gravity_mps2), g_tol=0.5,
                      alpha_max=math.inf if alpha_sigma is None else max(5.0 * alpha_sigma, 0.05),
                      hold=max(4, int(round(0.25 * rate))), ema_shift=k, ref_max=dev + 0.05)


def _q_thr(x: float) -> int:
    return int(min(round_half_up(x * 1024.0), 2**31 - 1)) if math.isfinite(x) else 2**31 - 1


def rest_cfg_fixed(p: RestParams):
    """The ac_rest_cfg for p (thresholds rounded half up to their Q formats)."""
    ffi, _ = _lib()
    c = ffi.new("ac_rest_cfg *")
    c.dev_max = _q_thr(p.dev_max)
    lo, hi = p.g2_bounds()
    c.g2_lo = int(min(round_half_up(lo * 2.0**20), 2**32 - 1))
    c.g2_hi = int(min(round_half_up(hi * 2.0**20), 2**32 - 1)) if math.isfinite(hi) else 2**32 - 1
    c.alpha_max = _q_thr(p.alpha_max)
    c.ref_max = _q_thr(p.ref_max)
    c.hold = int(p.hold)
    c.ema_shift = int(p.ema_shift)
    return c


@dataclass
class _RestThresholds:
    dev_max: float
    g2_lo: float
    g2_hi: float
    alpha_max: float
    ref_max: float
    hold: int
    ema_shift: int

    @classmethod
    def of(cls, p: RestParams, as_stored: bool = False) -> "_RestThresholds":
        if as_stored:
            c = rest_cfg_fixed(p)
            return cls(c.dev_max / 1024.0, c.g2_lo / 2.0**20, c.g2_hi / 2.0**20, c.alpha_max / 1024.0,
                       c.ref_max / 1024.0, p.hold, p.ema_shift)
        lo, hi = p.g2_bounds()
        return cls(p.dev_max, lo, hi, p.alpha_max, p.ref_max, p.hold, p.ema_shift)


def rest_params_as_stored(p: RestParams) -> tuple[float, float, float, float]:
    """(dev_max, g2_lo, g2_hi, alpha_max) exactly as the fixed cfg holds them."""
    t = _RestThresholds.of(p, True)
    return t.dev_max, t.g2_lo, t.g2_hi, t.alpha_max


class _RestState:
    """The float twin of ac_rest (one sample at a time, on clipped inputs)."""

    def __init__(self, th: _RestThresholds):
        self.th = th
        self.w = 2.0 ** -th.ema_shift
        self.m = None
        self.run = 0
        self.at = False

    def step(self, x, alpha=None, ref=None) -> tuple[int, float, float]:
        """flags (REST_*), the deviation from the mean, the deviation from ref (0 without)."""
        th = self.th
        if self.m is None:
            self.m = [x[0], x[1], x[2]]
        m = self.m
        d0, d1, d2 = x[0] - m[0], x[1] - m[1], x[2] - m[2]
        dev = max(abs(d0), abs(d1), abs(d2))
        m[0] += d0 * self.w
        m[1] += d1 * self.w
        m[2] += d2 * self.w
        g2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
        quiet = dev <= th.dev_max and th.g2_lo <= g2 <= th.g2_hi
        if alpha is not None and max(abs(alpha[0]), abs(alpha[1]), abs(alpha[2])) > th.alpha_max:
            quiet = False
        dref = 0.0
        if ref is not None:
            dref = max(abs(x[0] - ref[0]), abs(x[1] - ref[1]), abs(x[2] - ref[2]))
            if dref > th.ref_max:
                quiet = False
        self.run = min(self.run + 1, 65535) if quiet else 0
        was, self.at = self.at, self.run >= th.hold
        fl = REST_QUIET if quiet else 0
        if self.at:
            fl |= REST_AT_REST | (0 if was else REST_ENTER)
        elif was:
            fl |= REST_LEAVE
        return fl, dev, dref


def _rest_core(f, th: _RestThresholds, alpha=None):
    """Float rest detector on (n,3) f (clipped like the core): (flags (n,), dev (n,))."""
    f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
    n = f.shape[0]
    flags = np.zeros(n, np.uint8)
    dev = np.zeros(n)
    rs = _RestState(th)
    fl = f.tolist()
    al = None if alpha is None else np.asarray(alpha, float).tolist()
    for i in range(n):
        flags[i], dev[i], _ = rs.step(fl[i], None if al is None else al[i])
    return flags, dev


def rest_detect(f, p: RestParams, alpha=None, *, as_stored: bool = False):
    """Float rest detector (flags, deviation).  ``as_stored`` uses the thresholds as the
    fixed cfg stores them (the twin of ac_rest; f should then be the Q.10 inputs / 1024)."""
    return _rest_core(f, _RestThresholds.of(p, as_stored), alpha)


def rest_fixed(f_q, p: RestParams, alpha_q=None) -> np.ndarray:
    """ac_rest_batch on (n,3) int32 Q.10 -> flags (n,) uint8."""
    ffi, lib = _lib()
    f_q = np.ascontiguousarray(f_q, dtype=np.int32)
    st = ffi.new("ac_rest *")
    _check(lib.ac_rest_init(st, rest_cfg_fixed(p)), "ac_rest_init")
    flags = np.zeros(f_q.shape[0], np.uint8)
    ap = ffi.NULL if alpha_q is None else cptr("int32_t *", np.ascontiguousarray(alpha_q, dtype=np.int32))
    _check(lib.ac_rest_batch(st, cptr("int32_t *", f_q), ap, f_q.shape[0], cptr("uint8_t *", flags)),
           "ac_rest_batch")
    return flags


# =============================================================================
# pendulum attitude (ac_att)
# =============================================================================

@dataclass
class AttitudeParams:
    """r1, r2: triad radii on body x (m); dt (s); gain: K = gain dt |w|; w2_gate
    ((rad/s)^2): below it |w| is not measured (None: 3 sigma of w^2 from noise_mps2);
    leak_tau_s: time constant of the pull to 0 while gated."""
    r1: float
    r2: float
    dt: float
    gain: float = 2.0
    w2_gate: float | None = None
    noise_mps2: float = 0.02
    leak_tau_s: float = 2.0

    def gate(self) -> float:
        if self.w2_gate is not None:
            return float(self.w2_gate)
        return 3.0 * math.sqrt(2.0) * self.noise_mps2 / abs(self.r1 - self.r2)

    def leak(self) -> float:
        return min(1.0, self.dt / self.leak_tau_s) if self.leak_tau_s > 0 else 0.0

    def check(self) -> None:
        if not (math.isfinite(self.r1) and math.isfinite(self.r2)):
            raise AccelcalError(f"attitude: triad radii must be finite, got r1={self.r1}, r2={self.r2}")
        if self.r1 == self.r2:
            raise AccelcalError(f"attitude: r1 = r2 = {self.r1:g} m: the two triads must sit at different "
                                "radii (eqs. 1-3 divide by r1 - r2)")
        rmax = max(abs(self.r1), abs(self.r2))
        if rmax > 1024.0 * abs(self.r1 - self.r2):
            raise AccelcalError(f"attitude: |r1 - r2| = {abs(self.r1 - self.r2):.3g} m is too small against "
                                f"max|r| = {rmax:.3g} m (noise gain above 1024)")


@dataclass
class AttitudeConsts:
    """Constants of the estimator as floats: exact (reference) or as the C struct stores them (twin)."""
    c1: float
    c2: float
    k: float       # 1/(r1 - r2), 1/m
    gs: float      # max|r| / |r1 - r2|
    dt: float
    kdt: float     # K = min(1, kdt m)
    leak: float
    gate: float
    q_y: float = 1.0  # scale of (y, x) for the magnitude: gmag = hypot * gs * q_y

    @classmethod
    def exact(cls, p: AttitudeParams) -> "AttitudeConsts":
        p.check()
        s = 1.0 if p.r2 > p.r1 else -1.0
        rmax = max(abs(p.r1), abs(p.r2))
        return cls(c1=s * p.r1 / rmax, c2=s * p.r2 / rmax, k=1.0 / (p.r1 - p.r2),
                   gs=rmax / abs(p.r1 - p.r2), dt=p.dt, kdt=p.gain * p.dt, leak=p.leak(), gate=p.gate())


def _attitude_core(f1, f2, C: AttitudeConsts, gated=None, sign_neg=None):
    """The algorithm of ac_att_step in float64 (see include/accelcal/ac_attitude.h).

    f1, f2 (n,3) m/s^2 (clipped to +-32 like the core).  ``gated``/``sign_neg`` (n,) bool
    override the decisions (twin mode).  Returns a dict of (n,) arrays: theta, w, dw, w2,
    gmag, gated, sign_neg, settled, and the internals wp, wm, K, m (for the bounds)."""
    f1 = np.clip(np.asarray(f1, float), CLIP_LO, CLIP)
    f2 = np.clip(np.asarray(f2, float), CLIP_LO, CLIP)
    n = f1.shape[0]
    y = C.c1 * f2[:, 0] - C.c2 * f1[:, 0]
    x = C.c2 * f1[:, 2] - C.c1 * f2[:, 2]
    theta = np.arctan2(y, x)
    gmag = np.hypot(x, y) * C.gs
    dw = (f2[:, 2] - f1[:, 2]) * C.k
    w2 = (f2[:, 0] - f1[:, 0]) * C.k
    out_w = np.zeros(n)
    g_out = np.zeros(n, bool)
    s_out = np.zeros(n, bool)
    settled_out = np.zeros(n, bool)
    wp_a, wm_a, K_a, m_a = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    w, a_prev, settled = 0.0, 0.0, 0
    reacq = np.zeros(n, bool)
    dwl, w2l = dw.tolist(), w2.tolist()
    half_dt = 0.5 * C.dt
    for i in range(n):
        wp = 0.0 if i == 0 else w + half_dt * (a_prev + dwl[i])
        g = (w2l[i] < C.gate) if gated is None else bool(gated[i])
        wp_a[i] = wp
        if g:
            w = wp * (1.0 - C.leak)
            settled = 2 if (i == 0 or settled == 2) else 1
        else:
            m = math.sqrt(max(w2l[i], 0.0))
            neg = (wp < 0.0) if sign_neg is None else bool(sign_neg[i])
            wm = -m if neg else m
            if i == 0 or settled == 1:
                K = 1.0
                reacq[i] = True
                if i > 0:
                    settled = 2
            else:
                K = min(1.0, C.kdt * m)
            w = wp + K * (wm - wp)
            s_out[i] = neg
            wm_a[i], K_a[i], m_a[i] = wm, K, m
        g_out[i] = g
        settled_out[i] = settled == 2
        out_w[i] = w
        a_prev = dwl[i]
    return dict(theta=theta, w=out_w, dw=dw, w2=w2, gmag=gmag, gated=g_out, sign_neg=s_out,
                settled=settled_out, wp=wp_a, wm=wm_a, K=K_a, m=m_a, y=y, x=x, reacq=reacq)


def attitude_float(f1, f2, p: AttitudeParams) -> dict:
    """Float reference with the exact geometry (engine="float")."""
    return _attitude_core(f1, f2, AttitudeConsts.exact(p))


def att_init_fixed(p: AttitudeParams):
    """An initialised ac_att (C) and its constants as floats (the twin's AttitudeConsts)."""
    ffi, lib = _lib()
    p.check()
    st = ffi.new("ac_att *")
    pos = 2.0 ** 20  # AC_POS_FRAC
    r1q, r2q = int(round_half_up(p.r1 * pos)), int(round_half_up(p.r2 * pos))
    if r1q == r2q:
        raise AccelcalError(f"attitude: r1 = {p.r1:g} m and r2 = {p.r2:g} m are equal in Q.20")
    dt_m, dt_sh = dt_fixed(p.dt)
    gain_q8 = int(min(65535, round_half_up(p.gain * 256.0)))
    gate_q = int(min(2**31 - 1, round_half_up(p.gate() * 2.0**20)))
    leak_q = int(min(65535, round_half_up(p.leak() * 65536.0)))
    _check(lib.ac_att_init(st, r1q, r2q, dt_m, dt_sh, gain_q8, gate_q, leak_q), "ac_att_init")
    c = st.cfg
    C = AttitudeConsts(c1=c.c1 / 2.0**14, c2=c.c2 / 2.0**14, k=c.k_m * 2.0 ** -c.k_shift,
                       gs=c.gs_m * 2.0 ** -c.gs_shift, dt=c.dt_m * 2.0 ** -c.dt_shift,
                       kdt=c.kdt_m * 2.0 ** (-6 - c.kdt_shift), leak=c.leak / 65536.0,
                       gate=c.w2_gate / 2.0**20)
    return st, C


def attitude_fixed(f1_q, f2_q, p: AttitudeParams) -> dict:
    """ac_att_batch on Q.10 inputs.  Returns int arrays theta (Q.13), w (Q.10), dw (Q.10),
    w2 (Q.20), gmag (Q.10), flags, plus 'consts' (AttitudeConsts as stored) and 'cfg'."""
    ffi, lib = _lib()
    st, C = att_init_fixed(p)
    f = np.ascontiguousarray(np.hstack([np.asarray(f1_q, np.int32), np.asarray(f2_q, np.int32)]), dtype=np.int32)
    n = f.shape[0]
    out = ffi.new("ac_att_out[]", max(n, 1))
    _check(lib.ac_att_batch(st, cptr("int32_t *", f), n, out), "ac_att_batch")
    buf = ffi.buffer(out, ffi.sizeof("ac_att_out") * n)
    dt = np.dtype([("theta", "<i2"), ("w", "<i2"), ("dw", "<i4"), ("w2", "<i4"), ("gmag", "<i4"), ("flags", "u1")],
                  align=True)
    assert dt.itemsize == ffi.sizeof("ac_att_out")
    rec = np.frombuffer(buf, dtype=dt, count=n).copy() if n else np.zeros(0, dt)
    res = {k: rec[k].astype(np.int64) for k in ("theta", "w", "dw", "w2", "gmag", "flags")}
    res["consts"] = C
    res["cfg"] = st.cfg
    return res


def attitude_twin(f1_q, f2_q, fixed: dict) -> dict:
    """The float twin of a fixed run: same clipped inputs, constants as stored, the C decisions."""
    fl = fixed["flags"]
    return _attitude_core(_i16(f1_q) / 1024.0, _i16(f2_q) / 1024.0, fixed["consts"],
                          gated=(fl & ATT_GATED) != 0, sign_neg=(fl & ATT_SIGN_NEG) != 0)


def _isqrt_round(v: int) -> int:
    r = math.isqrt(v)
    return r + 1 if v - r * r > r else r


def attitude_rate_bound(fixed: dict, twin: dict) -> np.ndarray:
    """E_n + 0.5 LSB: the bound (rad/s) on |w_out 2^-10 - w_twin| stated in ac_attitude.h."""
    c = fixed["cfg"]
    C: AttitudeConsts = fixed["consts"]
    n = len(fixed["w"])
    h21 = 2.0 ** -21
    step_in = h21 + C.dt * 2.0 ** -11   # inc rounding + dw rounding (both alphas) in wp
    out = np.zeros(n)
    E = 0.0
    for i in range(n):
        w2q = int(fixed["w2"][i])
        if twin["gated"][i]:
            E = (1.0 - C.leak) * ((E if i else 0.0) + step_in) + h21
        else:
            mt = twin["m"][i]
            em = 2.0 ** -11 + (min(math.sqrt(h21), h21 / mt) if mt > 0 else math.sqrt(h21))
            if twin["reacq"][i]:
                E = em
            else:
                mq = _isqrt_round(max(w2q, 0))
                if c.kdt_shift > 32:
                    Kq = 0
                elif c.kdt_shift == 0:
                    Kq = 65536 if c.kdt_m else 0
                else:
                    q = (mq * c.kdt_m) >> (c.kdt_shift - 1)
                    Kq = min(65536, (q >> 1) + (q & 1))
                K = Kq / 65536.0
                eK = 2.0 ** -17 + C.kdt * em
                E = (1.0 - K) * (E + step_in) + K * em + eK * abs(twin["wm"][i] - twin["wp"][i]) + h21
        out[i] = E + 2.0 ** -11
    return out


# =============================================================================
# displacement (ac_disp)
# =============================================================================

@dataclass
class DisplaceParams:
    """dt (s); axis None: 3-axis with gravity removed in the frame of the first rest;
    0/1/2: 1-D along that body axis (the seed's case, nothing removed); rest: RestParams;
    pad (offline only): samples added before each detected start and after each end."""
    dt: float
    axis: int | None = None
    rest: RestParams = field(default_factory=RestParams)
    pad: int | None = 2


def tilt_frame(g) -> np.ndarray:
    """Float twin of ac_tilt_frame: rows = x, y, z of the rest frame in body axes."""
    g = np.asarray(g, float)
    n = np.linalg.norm(g)
    if n == 0 or not np.isfinite(n):
        raise AccelcalError("the rest's mean specific force is zero: no 'up' to define a frame")
    u = g / n
    R = np.zeros((3, 3))
    R[2] = u
    if u[1] ** 2 + u[2] ** 2 >= 0.25:
        rho = math.hypot(u[1], u[2])
        R[0] = (rho, -u[0] * u[1] / rho, -u[0] * u[2] / rho)
        R[1] = (0.0, u[2] / rho, -u[1] / rho)
    else:
        sig = math.hypot(u[0], u[2])
        R[0] = (u[2] / sig, 0.0, -u[0] / sig)
        R[1] = (-u[1] * u[0] / sig, sig, -u[1] * u[2] / sig)
    return R


def _displace_core(f, dt, axis, th: _RestThresholds, rest_flags=None, frame=None):
    """The algorithm of ac_disp_step in float64 on (n,3) f (clipped like the core).

    The rest test runs inline (its reference, the first rest's mean, is known only once
    that rest ends).  Twin mode: ``rest_flags`` (the core's AC_REST_* per sample) are
    used instead of the own decisions, which are still computed (``own_quiet``, ``dev``,
    ``dref``) for the margin checks; ``frame`` (g, R, c) replaces the gravity reference
    (R, c None for 1-D).  Returns v, p (n,3), flags (n,), zp (n,3), nseg (n,), rest (n,),
    segments [(anchor, end, zp (3,) or None)], frame (g, R, c) or None, phase."""
    f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
    n = f.shape[0]
    V, P, ZP = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
    FL = np.zeros(n, np.int64)
    NS = np.zeros(n, np.int64)
    RF = np.zeros(n, np.int64)
    own_q, DEV, DREF = np.zeros(n, bool), np.zeros(n), np.zeros(n)
    segments = []
    phase, have_ref = 0, False
    gsum, gcount = np.zeros(3), 0
    g = R = c = None
    v, p, a_prev = np.zeros(3), np.zeros(3), np.zeros(3)
    f_prev = np.zeros(3)
    nseg, long_seg, anchor = 0, False, -1
    half_dt = 0.5 * dt
    rs = _RestState(th)
    fl_list = f.tolist()

    def accel(x):
        if axis is not None:
            a = np.zeros(3)
            a[axis] = x[axis]
            return a
        return R @ x - c

    for i in range(n):
        own, DEV[i], DREF[i] = rs.step(fl_list[i], None, g if have_ref else None)
        own_q[i] = bool(own & REST_QUIET)
        rf = own if rest_flags is None else int(rest_flags[i])
        RF[i] = rf
        quiet, at = bool(rf & REST_QUIET), bool(rf & REST_AT_REST)
        fc = f[i]
        flags = 0
        zp = None
        if phase != 2 and not have_ref:
            if quiet:
                if gcount < GSUM_MAX:
                    gsum = gsum + fc
                    gcount += 1
            elif phase == 0:
                gsum, gcount = np.zeros(3), 0
        moving_now = False
        if phase == 0:
            if at:
                phase = 1
                flags |= DISP_REST
            else:
                flags |= DISP_NO_REF
        elif phase == 1:
            if at:
                flags |= DISP_REST
            else:
                ok = True
                if not have_ref:
                    if frame is not None:
                        g = np.asarray(frame[0], float)
                        R = None if frame[1] is None else np.asarray(frame[1], float)
                        c = None if frame[2] is None else np.asarray(frame[2], float)
                    else:
                        g = gsum / gcount
                        if axis is None:
                            try:
                                R = tilt_frame(g)
                            except AccelcalError:
                                ok = False
                            else:
                                c = R @ g
                    if ok:
                        have_ref = True
                        flags |= DISP_REF_SET
                    else:
                        phase = 0
                        g = None
                        gsum, gcount = np.zeros(3), 0
                        flags |= DISP_NO_REF | DISP_BAD_REF
                if ok:
                    a_prev = accel(f_prev)
                    v = np.zeros(3)
                    nseg, long_seg, anchor = 0, False, i - 1
                    phase = 2
                    moving_now = True
        else:
            moving_now = True
        if moving_now:
            a = accel(fc)
            v_new = v + half_dt * (a_prev + a)
            p = p + half_dt * (v + v_new)
            v = v_new
            a_prev = a
            if nseg == 65535:
                long_seg = True
            else:
                nseg += 1
            if at:
                flags |= DISP_SEG_END | DISP_REST
                T = nseg * dt
                if long_seg or T <= 0:
                    flags |= DISP_LONG
                    zp = None
                else:
                    p = p - v * T / 2.0
                    zp = v / T
                    ZP[i] = zp
                segments.append((anchor, i, zp))
                v = np.zeros(3)
                phase = 1
            else:
                flags |= DISP_MOVING
        f_prev = fc
        V[i], P[i], FL[i], NS[i] = v, p, flags, nseg
    return dict(v=V, p=P, flags=FL, zp=ZP, nseg=NS, rest=RF, own_quiet=own_q, dev=DEV, dref=DREF,
                segments=segments, phase=phase, frame=None if g is None else (g, R, c))


def displace_stream(f, p: DisplaceParams) -> dict:
    """Float reference of the streaming form (engine="float", form="stream")."""
    return _displace_core(f, p.dt, p.axis, _RestThresholds.of(p.rest))


def disp_cfg_fixed(p: DisplaceParams):
    ffi, _ = _lib()
    c = ffi.new("ac_disp_cfg *")
    rc = rest_cfg_fixed(p.rest)
    c.rest = rc[0]
    c.dt_m, c.dt_shift = dt_fixed(p.dt)
    c.axis = -1 if p.axis is None else int(p.axis)
    return c


def displace_fixed(f_q, p: DisplaceParams) -> dict:
    """ac_disp_batch + ac_disp_finish on (n,3) int32 Q.10.  Returns int arrays v (Q.24), p (Q.20),
    zp (Q.16), nseg, flags, rest (the AC_REST_* flags); 'finish' (the ac_disp_finish flags);
    'frame' (g Q.16, rot Q.14 or None, c Q.16 or None) and 'dt' (as stored)."""
    ffi, lib = _lib()
    f_q = np.ascontiguousarray(f_q, dtype=np.int32)
    n = f_q.shape[0]
    st = ffi.new("ac_disp *")
    cfg = disp_cfg_fixed(p)
    _check(lib.ac_disp_init(st, cfg), "ac_disp_init")
    out = ffi.new("ac_disp_out[]", max(n, 1))
    _check(lib.ac_disp_batch(st, cptr("int32_t *", f_q), n, out), "ac_disp_batch")
    fin = ffi.new("ac_disp_out *")
    _check(lib.ac_disp_finish(st, fin), "ac_disp_finish")
    dt = np.dtype([("v", "<i4", 3), ("p", "<i4", 3), ("zp", "<i4", 3), ("nseg", "<u2"), ("flags", "<u2"),
                   ("rest", "u1")], align=True)
    assert dt.itemsize == ffi.sizeof("ac_disp_out")
    rec = np.frombuffer(ffi.buffer(out, ffi.sizeof("ac_disp_out") * n), dtype=dt, count=n).copy() if n \
        else np.zeros(0, dt)
    frame = None
    if st.have_ref:
        g = np.array([st.g[k] for k in range(3)], np.int64)
        if p.axis is None:
            frame = (g, np.array([[st.rot[j][k] for k in range(3)] for j in range(3)], np.int64),
                     np.array([st.c[k] for k in range(3)], np.int64))
        else:
            frame = (g, None, None)
    return dict(v=rec["v"].astype(np.int64), p=rec["p"].astype(np.int64), zp=rec["zp"].astype(np.int64),
                nseg=rec["nseg"].astype(np.int64), flags=rec["flags"].astype(np.int64),
                rest=rec["rest"].astype(np.int64), finish=int(fin.flags),
                frame=frame, dt=cfg.dt_m * 2.0 ** -cfg.dt_shift)


def displace_twin(f_q, fixed: dict, p: DisplaceParams) -> dict:
    """The float twin of a fixed run: same clipped inputs, the core's rest decisions, g/R/c as stored."""
    frame = None
    if fixed["frame"] is not None:
        g, rot, c = fixed["frame"]
        frame = (g / 2.0**G_FRAC, None if rot is None else rot / 2.0**ROT_FRAC,
                 None if c is None else c / 2.0**A_FRAC)
    return _displace_core(_i16(f_q) / 1024.0, fixed["dt"], p.axis, _RestThresholds.of(p.rest, True),
                          rest_flags=fixed["rest"], frame=frame)


def displace_error_bound(fixed: dict, twin: dict, three_axis: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample bounds (m/s, m) on |v - v'| and |p - p'| (each component) stated in
    ac_displace.h, carried through segment ends."""
    dt = fixed["dt"]
    ea = 2.0 ** -17 if three_axis else 0.0
    n = len(fixed["flags"])
    bv, bp = np.zeros(n), np.zeros(n)
    Ev, Ep = 0.0, 0.0
    vmag = np.abs(twin["v"]).max(axis=1) if n else np.zeros(0)
    for i in range(n):
        fl = int(fixed["flags"][i])
        if fl & (DISP_MOVING | DISP_SEG_END):
            Ev_new = Ev + dt * ea + 2.0 ** -25
            Ep = Ep + dt * (Ev + Ev_new) / 2.0 + 2.0 ** -21
            Ev = Ev_new
            if fl & DISP_SEG_END:
                T = int(fixed["nseg"][i]) * dt
                if not fl & DISP_LONG:
                    # |v| before the reset: recover from the twin's zp
                    vT = float(np.max(np.abs(twin["zp"][i]))) * T
                    Ep = Ep + Ev * T / 2.0 + vT * 2.0 ** -17 + 2.0 ** -21
                Ev = 0.0
        else:
            Ev = 0.0
        bv[i], bp[i] = Ev, Ep
    return bv, bp


def _motion_runs(at_rest, start: int = 0) -> list[tuple[int, int]]:
    """Maximal runs [s, e) of not-at-rest samples from index start on (e = n when the
    recording ends in motion)."""
    moving = ~np.asarray(at_rest, bool)[start:]
    edges = np.diff(np.concatenate(([0], moving.astype(np.int8), [0])))
    return [(int(s) + start, int(e) + start)
            for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1))]


def _segments_from_flags(flags) -> list[tuple[int, int]]:
    """(first moving sample, end sample (rest declared) or -1 if open) from displacement flags."""
    segs, start = [], None
    for i, fl in enumerate(np.asarray(flags).tolist()):
        if fl & DISP_MOVING and start is None:
            start = i
        if fl & DISP_SEG_END:
            segs.append((start if start is not None else i, i))
            start = None
    if start is not None:
        segs.append((start, -1))
    return segs


def retro_correct(t, v, p, flags, zp) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The seed's correction applied to the whole path of each closed motion (host side):
    v(t) - zp t', p(t) - zp t'^2 / 2 with t' from the anchor (the sample before the motion).
    Returns (v, p, corrected (n,) bool).  End points already carry the core's correction."""
    t = np.asarray(t, float)
    v, p = np.array(v, float), np.array(p, float)
    corrected = np.zeros(len(t), bool)
    for s, e in _segments_from_flags(flags):
        if e < 0:
            continue
        corrected[s:e + 1] = True
        if flags[e] & DISP_LONG:
            corrected[s:e + 1] = False
            continue
        a = s - 1
        z = np.asarray(zp[e], float)
        tp = t[s:e] - t[a]
        v[s:e] -= z * tp[:, None]
        p[s:e] -= 0.5 * z * tp[:, None] ** 2
    return v, p, corrected


def displace_offline(f, p: DisplaceParams, rest_flags=None) -> dict:
    """Host offline form (float): the rest detector's segments, each widened by ``pad``
    samples at the start (the detector lags a smooth start) and ending ``pad`` samples
    after the first quiet sample of the final rest (not at the declaration); gravity and
    the frame from the mean of the whole first rest; the correction over the whole path.
    Returns v, p (corrected), v_raw, p_raw (uncorrected: same segments, no zero-point
    correction), rest (n,) bool, corrected (n,) bool, segments [(anchor, end, zp)], frame,
    open (a motion still going at the end), no_rest."""
    f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
    n = f.shape[0]
    dt = p.dt
    if rest_flags is None:
        # the streaming detector (with its reference test once the first rest is known)
        rest_flags = displace_stream(f, p)["rest"]
    at = (np.asarray(rest_flags) & REST_AT_REST) != 0
    quiet = (np.asarray(rest_flags) & REST_QUIET) != 0
    pad = (2 ** p.rest.ema_shift) if p.pad is None else int(p.pad)
    res = dict(v=np.zeros((n, 3)), p=np.zeros((n, 3)), v_raw=np.zeros((n, 3)), p_raw=np.zeros((n, 3)),
               rest=at.copy(), corrected=np.zeros(n, bool), segments=[], frame=None, open=False,
               no_rest=not at.any())
    if not at.any():
        return res
    first_rest = int(np.argmax(at))
    # motions: maximal runs of not-at-rest samples after the first rest
    runs = [(s, e if e < n else -1) for s, e in _motion_runs(at, first_rest)]
    # the first rest: from the start of its quiet run to the first motion
    rs = first_rest
    while rs > 0 and quiet[rs - 1]:
        rs -= 1
    re_ = runs[0][0] if runs else n
    if p.axis is None:
        g = f[rs:re_].mean(axis=0)
        R = tilt_frame(g)
        acc = (f - g) @ R.T
        res["frame"] = (g, R, R @ g)
    else:
        acc = np.zeros((n, 3))
        acc[:, p.axis] = f[:, p.axis]
    pos, pos_raw = np.zeros(3), np.zeros(3)
    prev_end = re_ - 1
    last = first_rest
    for s, e in runs:
        a_idx = max(s - 1 - pad, prev_end)          # anchor: at rest, before the motion
        if e < 0:
            end, closed = n - 1, False
        else:
            fq = e - p.rest.hold + 1                # first quiet sample of the final rest
            end, closed = min(max(fq + pad, s), e), True
        res["p"][last:a_idx + 1] = pos
        res["p_raw"][last:a_idx + 1] = pos_raw
        idx = np.arange(a_idx, end + 1)
        a = acc[idx]
        vv = np.vstack([np.zeros(3), np.cumsum(0.5 * dt * (a[1:] + a[:-1]), axis=0)])
        pp = np.vstack([np.zeros(3), np.cumsum(0.5 * dt * (vv[1:] + vv[:-1]), axis=0)])
        res["v_raw"][idx] = vv
        res["p_raw"][idx] = pos_raw + pp
        if closed:
            T = (end - a_idx) * dt
            zp = vv[-1] / T
            tp = (idx - a_idx) * dt
            res["v"][idx] = vv - zp * tp[:, None]
            res["p"][idx] = pos + pp - 0.5 * zp * tp[:, None] ** 2
            res["corrected"][idx] = True
            res["segments"].append((int(a_idx), int(end), zp))
            pos = res["p"][end].copy()
            pos_raw = res["p_raw"][end].copy()
            res["v"][end] = 0.0
            last = end + 1
            prev_end = end
        else:
            res["v"][idx] = vv
            res["p"][idx] = pos + pp
            res["segments"].append((int(a_idx), int(end), None))
            res["open"] = True
            last = n
            break
    if last < n:
        res["p"][last:] = pos
        res["p_raw"][last:] = pos_raw
    return res


# =============================================================================
# rate from alpha with reset on rest (ac_rest_rate_step)
# =============================================================================

def rate_rest_float(alpha, f, dt: float, leak: float, rest: RestParams, rest_flags=None, *, as_stored=False):
    """w[n] = w[n-1] (1 - leak) + dt alpha[n]; w = 0 (and state reset) at rest.  Returns (omega, flags)."""
    alpha = np.asarray(alpha, float)
    if rest_flags is None:
        rest_flags, _ = rest_detect(f, rest, alpha=alpha, as_stored=as_stored)
    at = (np.asarray(rest_flags) & REST_AT_REST) != 0
    out = np.zeros_like(alpha)
    w = np.zeros(3)
    lam = 1.0 - leak
    for i in range(alpha.shape[0]):
        w = w * lam + dt * alpha[i]
        if at[i]:
            w = np.zeros(3)
        out[i] = w
    return out, rest_flags


def rate_rest_fixed(alpha_q, f_q, dt: float, leak_q16: int, rest: RestParams):
    """ac_rest_rate_step per sample: omega (n,3) int16 Q.10, rest flags (n,), saturated (n,)."""
    ffi, lib = _lib()
    alpha_q = np.ascontiguousarray(alpha_q, dtype=np.int32)
    f_q = np.ascontiguousarray(f_q, dtype=np.int32)
    n = alpha_q.shape[0]
    rs = ffi.new("ac_rest *")
    _check(lib.ac_rest_init(rs, rest_cfg_fixed(rest)), "ac_rest_init")
    rt = ffi.new("ac_rate *")
    dm, dsh = dt_fixed(dt)
    _check(lib.ac_rate_init(rt, dm, dsh, int(leak_q16)), "ac_rate_init")
    w = ffi.new("int16_t[3]")
    fl = ffi.new("uint8_t *")
    om = np.zeros((n, 3), np.int64)
    flags = np.zeros(n, np.int64)
    sat = np.zeros(n, bool)
    for i in range(n):
        sat[i] = _check(lib.ac_rest_rate_step(rs, rt, cptr("int32_t *", f_q[i]), cptr("int32_t *", alpha_q[i]),
                                              w, fl), "ac_rest_rate_step")
        om[i] = (w[0], w[1], w[2])
        flags[i] = fl[0]
    return om, flags, sat


# =============================================================================
# recordings (the CLI's `attitude` and `displacement`)
# =============================================================================

def _uniform_dt(rec) -> float:
    t = np.asarray(rec.t, float)
    if t.size < 2:
        raise InputError(rec.source, "the recording needs at least 2 samples")
    d = np.diff(t)
    dt = float(np.median(d))
    bad = np.flatnonzero(np.abs(d - dt) > 0.25 * dt)
    if bad.size:
        i = int(bad[0])
        raise InputError(rec.source, f"sample times are not uniform (step {d[i]:.6g} s against {dt:.6g} s): "
                         "the integrators need a constant rate", row=rec.line(i + 1), column="t")
    return dt


def _triad_geometry(device, cal) -> tuple[float, float]:
    """r1, r2 of a two-triad pendulum device (channels 0-2 and 3-5 on body x)."""
    tri = device.triads()
    if device.n_channels != 6 or tri is None or len(tri) != 2:
        raise InputError(device.name, "attitude needs a device of two triads: channels 0-2 and 3-5, each at "
                         "one point (device.pendulum_device)")
    pos = cal.positions_or_nominal(device) if hasattr(cal, "positions_or_nominal") else np.asarray(device.positions)
    p1, p2 = pos[0:3].mean(axis=0), pos[3:6].mean(axis=0)
    r1, r2 = float(p1[0]), float(p2[0])
    scale = max(abs(r1), abs(r2), 1e-3)
    for name, pp in (("0-2", p1), ("3-5", p2)):
        if abs(pp[1]) > 1e-3 * scale or abs(pp[2]) > 1e-3 * scale:
            raise InputError(device.name, f"attitude: triad {name} at {pp.tolist()} m is off the body x axis "
                             "(the pendulum equations need both triads on x, the pivot at the origin)")
    if r1 == r2:
        raise InputError(device.name, f"attitude: r1 = r2 = {r1:g} m: the two triads must be at different "
                         "radii (eqs. 1-3 divide by r1 - r2)")
    return r1, r2


def _triad_forces(cal, rec, chans, engine):
    b = np.asarray(cal.offsets, float)[list(chans)]
    s = np.asarray(cal.sensitivity, float)[list(chans)]
    raw = np.asarray(rec.raw)[:, list(chans)]
    if engine == "float":
        return triad_apply_float(b, s, raw), None
    tab = quantize_triad(b, s)
    f_q, sat = triad_apply_fixed(tab, raw)
    return f_q, sat


def attitude_from_recording(device, cal, rec, engine: str = "float", *, gain: float = 2.0,
                            w2_gate: float | None = None, leak_tau_s: float = 2.0) -> Columns:
    """`accelcal attitude`: columns t, theta_rad, w_y, dw_y (contract) plus g_mps2 (|g| the pair
    sees), gated (|w| not measured: integrated), unsettled (sign of w not yet established),
    saturated.  Warnings for: unsettled samples, |g| far from gravity, saturation."""
    if engine not in ("float", "fixed"):
        raise ValueError(f"unknown engine {engine!r}")
    check_for_device(rec, device, min_samples=2)
    r1, r2 = _triad_geometry(device, cal)
    dt = _uniform_dt(rec)
    p = AttitudeParams(r1=r1, r2=r2, dt=dt, gain=gain, w2_gate=w2_gate,
                       noise_mps2=max(float(device.noise_mps2), 1e-4), leak_tau_s=leak_tau_s)
    try:
        p.check()
    except AccelcalError as e:
        raise InputError(device.name, str(e)) from None
    warnings = []
    if engine == "float":
        f1, _ = _triad_forces(cal, rec, (0, 1, 2), "float")
        f2, _ = _triad_forces(cal, rec, (3, 4, 5), "float")
        r = attitude_float(f1, f2, p)
        theta, w, dw, gmag = r["theta"], r["w"], r["dw"], r["gmag"]
        gated, unsettled = r["gated"], ~r["settled"]
        sat = np.zeros(rec.n_samples, bool)
    else:
        check_core_input(rec)
        f1, s1 = _triad_forces(cal, rec, (0, 1, 2), "fixed")
        f2, s2 = _triad_forces(cal, rec, (3, 4, 5), "fixed")
        r = attitude_fixed(f1, f2, p)
        theta = r["theta"] / 2.0**ANGLE_FRAC
        w = r["w"] / 2.0**OMEGA_FRAC
        dw = r["dw"] / 2.0**OUT_FRAC
        gmag = r["gmag"] / 2.0**OUT_FRAC
        fl = r["flags"]
        gated, unsettled = (fl & ATT_GATED) != 0, (fl & ATT_UNSETTLED) != 0
        sat = ((fl & ATT_SAT) != 0) | s1 | s2
    g0 = float(device.gravity_mps2)
    off = np.abs(gmag - g0) > 0.2 * g0
    if unsettled.any():
        k = int(np.count_nonzero(unsettled))
        warnings.append(f"attitude: the sign of w_y is not yet established for the first {k} samples "
                        f"(until t = {rec.t[min(k, rec.n_samples - 1)]:.3f} s: no pass through low rate yet); "
                        "column unsettled = 1")
    if off.any():
        warnings.append(f"attitude: on {int(np.count_nonzero(off))} samples the two triads see |g| more than 20 % "
                        "off gravity (pivot moving, wrong r1/r2, or clipping): theta there is doubtful; "
                        "column g_mps2")
    if sat.any():
        warnings.append(f"attitude: {int(np.count_nonzero(sat))} samples clipped in the fixed-point core "
                        "(column saturated)")
    cols = Columns(t=np.asarray(rec.t, float), theta_rad=np.asarray(theta, float), w_y=np.asarray(w, float),
                   dw_y=np.asarray(dw, float), g_mps2=np.asarray(gmag, float), gated=gated.astype(float),
                   unsettled=unsettled.astype(float), saturated=sat.astype(float),
                   warnings=warnings,
                   meta={"engine": engine, "device": device.name, "r1_m": f"{r1:.6g}", "r2_m": f"{r2:.6g}",
                         "w2_gate": f"{p.gate():.6g}", "gain": f"{gain:g}", "leak_tau_s": f"{leak_tau_s:g}"})
    return cols


def _body_forces(device, cal, rec, engine):
    """f at the origin (6-DOF array, no rotation assumed) or at the first triad: (n,3) float
    m/s^2 (float) or int32 Q.10 (fixed), and a note for the metadata."""
    if device.is_array():
        from . import model
        if engine == "float":
            pos = cal.positions_or_nominal(device)
            f, _ = model.resolve(cal.offsets, cal.sensitivity, pos, rec.raw, None)
            return f, "resolved f at the body origin"
        from . import native
        from .quantize import quantize_calibration
        t = quantize_calibration(device, cal)
        out, _ = native.process_batch(t.resolver(), t.trim, rec.raw, None)
        return out[:, :3].astype(np.int32), "resolved f at the body origin (C core)"
    tri = device.triads()
    if tri:
        f, _ = _triad_forces(cal, rec, tri[0], engine)
        return f, "f of the triad at channels 0-2"
    raise InputError(device.name, "displacement needs a 6-DOF array or a device with a 3-axis sensor "
                     "(a triad at channels 0-2)")


def _max_rotation_deg(device, cal, rec, at_rest, dt) -> float:
    """Largest angle (deg) turned within any run of not-at-rest samples, integrating the
    resolved alpha twice from rest (omega = 0 at rest); angles within 5 sigma of what the
    alpha noise alone integrates to are not counted."""
    from . import model
    pos = cal.positions_or_nominal(device)
    _, a = model.resolve(cal.offsets, cal.sensitivity, pos, rec.raw, None)
    M = model.resolve_matrix(pos, cal.sensitivity)
    sig_a = float(np.max(np.sqrt(np.sum((M[3:] * device.noise_counts()[None, :]) ** 2, axis=1))))
    worst = 0.0
    for i, j in _motion_runs(at_rest):
        w = np.cumsum(a[i:j] * dt, axis=0)
        ang = np.linalg.norm(np.cumsum(w * dt, axis=0), axis=1)
        # noise alone: a double random walk, sigma = sigma_alpha dt^2 sqrt(k^3 / 3) after k steps
        k = np.arange(1, j - i + 1, dtype=float)
        sig = sig_a * dt * dt * np.sqrt(k**3 / 3.0)
        worst = max(worst, float(np.max(np.where(ang > 5.0 * sig, ang, 0.0))))
    return math.degrees(worst)


def _axis_arg(axis) -> int | None:
    if axis is None or axis in ("3d", "xyz", "all"):
        return None
    m = {"x": 0, "y": 1, "z": 2, 0: 0, 1: 1, 2: 2}
    if axis not in m:
        raise AccelcalError(f"displacement axis {axis!r}: expected x, y, z or none (3-axis)")
    return m[axis]


def displacement_from_recording(device, cal, rec, engine: str = "float", *, form: str | None = None,
                                axis=None, rest: RestParams | None = None) -> Columns:
    """`accelcal displacement`: columns t, v_x, v_y, v_z, p_x, p_y, p_z (frame of the first rest,
    z up, gravity removed; corrected between rests) plus p_raw_* (the same without the zero-point
    correction), rest (1 at rest) and corrected (1 on the samples of a motion closed by a rest,
    whose correction was applied; 0 at rest and on a motion that never stopped).

    engine "float": form "offline" (default) or "stream" (the float twin of the firmware form);
    engine "fixed": the C streaming form (ac_disp), with the path between rests corrected on the
    host from the core's per-motion zero-point estimate.  ``axis`` x/y/z: 1-D along that body
    axis (the seed's case: nothing removed).  Errors: no rest at all (nothing can be anchored).
    Flagged (warnings, column corrected = 0): a recording that does not start at rest (the part
    before the first rest is not estimated), a motion that does not end at rest (uncorrected)."""
    if engine not in ("float", "fixed"):
        raise ValueError(f"unknown engine {engine!r}")
    form = form or ("offline" if engine == "float" else "stream")
    if form not in ("offline", "stream") or (engine == "fixed" and form != "stream"):
        raise ValueError(f"form {form!r} with engine {engine!r}: fixed has only 'stream'")
    check_for_device(rec, device, min_samples=2)
    ax = _axis_arg(axis)
    dt = _uniform_dt(rec)
    rp = rest or default_rest_params(device, 1.0 / dt)
    p = DisplaceParams(dt=dt, axis=ax, rest=rp)
    if engine == "fixed":
        check_core_input(rec)
    f, note = _body_forces(device, cal, rec, engine)
    t = np.asarray(rec.t, float)
    n = len(t)
    warnings = []
    if engine == "float" and form == "offline":
        r = displace_offline(f, p)
        if r["no_rest"]:
            raise InputError(rec.source, "displacement: no rest was detected anywhere in the recording "
                             f"(rest = |f - mean| <= {rp.dev_max:.3g} m/s^2 for {rp.hold} samples"
                             + (f" with |f| within {rp.g_tol:g} of {rp.g:g} m/s^2" if rp.g is not None else "")
                             + "): the stop-to-stop method needs a rest at both ends of each motion")
        v, pp, p_raw = r["v"], r["p"], r["p_raw"]
        at, corrected = r["rest"], r["corrected"]
        is_open = r["open"]
        zps = [s[2] for s in r["segments"] if s[2] is not None]
    else:
        if engine == "float":
            r = displace_stream(f, p)
            vq, pq, zq, fl = r["v"], r["p"], r["zp"], r["flags"]
            fin_open = r["phase"] == 2
            no_rest = not (fl & DISP_REST).any()
        else:
            r = displace_fixed(f, p)
            vq, pq = r["v"] / 2.0**V_FRAC, r["p"] / 2.0**P_FRAC
            zq, fl = r["zp"] / 2.0**A_FRAC, r["flags"]
            fin_open = bool(r["finish"] & DISP_OPEN)
            no_rest = bool(r["finish"] & DISP_NO_REST)
            if (fl & DISP_SAT).any():
                warnings.append(f"displacement: {int(np.count_nonzero(fl & DISP_SAT))} samples clipped in the "
                                "fixed-point core")
        if no_rest:
            raise InputError(rec.source, "displacement: no rest was detected anywhere in the recording: the "
                             "stop-to-stop method needs a rest at both ends of each motion")
        v, pp, corrected = retro_correct(t, vq, pq, fl, zq)
        # uncorrected path: add back each end correction zp T^2 / 2 from its sample on
        D = np.zeros((n, 3))
        step_dt = r["dt"] if engine == "fixed" else dt
        for s_, e in _segments_from_flags(fl):
            if e >= 0 and not fl[e] & DISP_LONG:
                T = int(r["nseg"][e]) * step_dt
                D[e] = 0.5 * np.asarray(zq[e], float) * T * T
        p_raw = np.array(pq, float) + np.cumsum(D, axis=0)
        at = (fl & DISP_REST) != 0
        is_open = fin_open
        zps = [zq[e] for s, e in _segments_from_flags(fl) if e >= 0 and not fl[e] & DISP_LONG]
        if (fl & DISP_LONG).any():
            warnings.append("displacement: a motion longer than 65535 samples was not corrected")
    first_at = int(np.argmax(at)) if np.any(at) else n
    if first_at > rp.hold - 1:
        # the first rest's quiet run did not begin with the recording
        warnings.append(f"displacement: the recording does not start at rest: nothing is estimated before the "
                        f"first rest (declared at t = {t[min(first_at, n - 1)]:.3f} s; rows before are 0)")
    if is_open:
        warnings.append("displacement: the last motion does not end at rest: it is NOT corrected "
                        "(column corrected = 0 there) and its drift grows with time squared")
    if device.is_array():
        # the rail assumption: no rotation between rests (checked from the resolved alpha)
        rot = _max_rotation_deg(device, cal, rec, np.asarray(at, bool), dt)
        if rot > 3.0:
            warnings.append(f"displacement: the body turned by up to {rot:.1f} deg during a motion (from the "
                            "resolved alpha): gravity removal assumes no rotation between rests (a rail), so "
                            "the result is doubtful")
    meta = {"engine": engine, "form": form, "device": device.name, "signal": note,
            "mode": "3-axis, gravity removed in the frame of the first rest" if ax is None else
            f"1-D along body {'xyz'[ax]}", "segments": str(len(zps))}
    if zps:
        meta["zero_point_mps2"] = "; ".join("(" + ", ".join(f"{c:.4g}" for c in np.atleast_1d(z)) + ")" for z in zps)
    cols = Columns(t=t, v_x=v[:, 0], v_y=v[:, 1], v_z=v[:, 2], p_x=pp[:, 0], p_y=pp[:, 1], p_z=pp[:, 2],
                   p_raw_x=p_raw[:, 0], p_raw_y=p_raw[:, 1], p_raw_z=p_raw[:, 2],
                   rest=np.asarray(at, float), corrected=np.asarray(corrected, float),
                   warnings=warnings, meta=meta)
    return cols


def rate_from_recording(device, cal, rec, engine: str = "float", *, leak_tau_s: float = 5.0,
                        rest: RestParams | None = None) -> Columns:
    """Angular rate from the resolved alpha of a 6-DOF array: leaky integration (high-pass,
    time constant leak_tau_s), reset to 0 on detected rest (f quiet, |f| ~ g, |alpha| small).
    Columns t, w_x, w_y, w_z, rest."""
    from . import model
    if not device.is_array():
        raise InputError(device.name, "rate needs a 6-DOF array (alpha from the resolver)")
    check_for_device(rec, device, min_samples=2)
    dt = _uniform_dt(rec)
    pos = cal.positions_or_nominal(device)
    M = model.resolve_matrix(pos, cal.sensitivity)
    sig_alpha = float(np.max(np.sqrt(np.sum((M[3:] * device.noise_counts()[None, :]) ** 2, axis=1))))
    rp = rest or default_rest_params(device, 1.0 / dt, alpha_sigma=sig_alpha)
    leak = min(1.0, dt / leak_tau_s) if leak_tau_s > 0 else 0.0
    if engine == "float":
        f, a = model.resolve(cal.offsets, cal.sensitivity, pos, rec.raw, None)
        w, fl = rate_rest_float(a, f, dt, leak, rp)
    elif engine == "fixed":
        from . import native
        from .quantize import quantize_calibration
        check_core_input(rec)
        t = quantize_calibration(device, cal)
        out, _ = native.process_batch(t.resolver(), t.trim, rec.raw, None)
        wq, fl, _ = rate_rest_fixed(out[:, 3:], out[:, :3], dt, int(round_half_up(leak * 65536)), rp)
        w = wq / 2.0**OMEGA_FRAC
    else:
        raise ValueError(f"unknown engine {engine!r}")
    return Columns(t=np.asarray(rec.t, float), w_x=w[:, 0], w_y=w[:, 1], w_z=w[:, 2],
                   rest=((np.asarray(fl) & REST_AT_REST) != 0).astype(float),
                   meta={"engine": engine, "leak_tau_s": f"{leak_tau_s:g}"})


# =============================================================================
# plots
# =============================================================================

def report_plots(out_dir, columns: Columns, rec=None, kind: str | None = None) -> list[Path]:
    """PNG plots of an attitude / displacement / rate result (matplotlib, Agg) into out_dir;
    with a recording that has reference columns (w, dw, or a simulated truth) they are overlaid.
    Returns the files written."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t = columns["t"]
    kind = kind or ("attitude" if "theta_rad" in columns else "displacement" if "p_x" in columns else "rate")
    files = []
    if kind == "attitude":
        ref_theta = ref_w = None
        if rec is not None and np.isfinite(rec.f).all():
            ref_theta = np.arctan2(-rec.f[:, 0], rec.f[:, 2])
        if rec is not None and np.isfinite(rec.w[:, 1]).all():
            ref_w = rec.w[:, 1]
        has_ref = ref_theta is not None or ref_w is not None
        fig, axs = plt.subplots(4 if has_ref else 3, 1, figsize=(9, 10 if has_ref else 8), sharex=True)
        axs[0].plot(t, np.degrees(columns["theta_rad"]), label="theta (estimate)")
        if ref_theta is not None:
            axs[0].plot(t, np.degrees(ref_theta), "--", label="reference (from f)")
        axs[0].set_ylabel("theta [deg]")
        axs[1].plot(t, columns["w_y"], label="w_y (estimate)")
        if ref_w is not None:
            axs[1].plot(t, ref_w, "--", label="w_y reference")
        g = columns.get("gated")
        if g is not None and np.any(g > 0):
            axs[1].fill_between(t, 0, 1, where=g > 0, transform=axs[1].get_xaxis_transform(), alpha=0.15,
                                color="grey", label="gated (integrated)")
        axs[1].set_ylabel("w_y [rad/s]")
        axs[2].plot(t, columns["dw_y"], label="dw_y (estimate)")
        if rec is not None and np.isfinite(rec.dw[:, 1]).all():
            axs[2].plot(t, rec.dw[:, 1], "--", label="dw_y reference")
        axs[2].set_ylabel("dw_y [rad/s^2]")
        if has_ref:
            # the estimate and its reference overlap on the panels above: their difference shows
            # how good the estimate is at a glance
            ax = axs[3]
            if ref_theta is not None:
                d = np.degrees(np.angle(np.exp(1j * (columns["theta_rad"] - ref_theta))))
                ax.plot(t, d, color="C0", lw=0.8, label=f"theta error (rms {np.sqrt(np.mean(d * d)):.3g} deg)")
            ax.set_ylabel("theta error [deg]")
            if ref_w is not None:
                ax2 = ax.twinx()
                d = columns["w_y"] - ref_w
                ax2.plot(t, d, color="C3", lw=0.8, label=f"w_y error (rms {np.sqrt(np.mean(d * d)):.3g} rad/s)")
                ax2.set_ylabel("w_y error [rad/s]", color="C3")
                ax2.tick_params(axis="y", colors="C3")
                ax2.legend(loc="lower right", fontsize=8)
            ax.axhline(0.0, color="k", lw=0.5)
        axs[-1].set_xlabel("t [s]")
        for a in axs:
            a.legend(loc="upper right", fontsize=8)
            a.grid(alpha=0.3)
        fig.suptitle("pendulum attitude from two triads")
        path = out / "attitude.png"
    elif kind == "displacement":
        fig, axs = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
        for c, col in zip("xyz", ("C0", "C1", "C2")):
            axs[0].plot(t, columns[f"p_{c}"], col, label=f"p_{c} corrected")
            if f"p_raw_{c}" in columns:
                axs[0].plot(t, columns[f"p_raw_{c}"], col, ls=":", label=f"p_{c} uncorrected")
            axs[1].plot(t, columns[f"v_{c}"], col, label=f"v_{c}")
        r = columns.get("rest")
        if r is not None:
            for a in axs:
                a.fill_between(t, 0, 1, where=r > 0, transform=a.get_xaxis_transform(), alpha=0.12,
                               color="green", label="rest")
        axs[0].set_ylabel("p [m]")
        axs[1].set_ylabel("v [m/s]")
        axs[1].set_xlabel("t [s]")
        for a in axs:
            a.legend(loc="upper left", fontsize=8)
            a.grid(alpha=0.3)
        fig.suptitle("stop-to-stop displacement (frame of the first rest)")
        path = out / "displacement.png"
    else:
        fig, ax = plt.subplots(1, 1, figsize=(9, 4))
        for c in "xyz":
            ax.plot(t, columns[f"w_{c}"], label=f"w_{c}")
        ref = rec is not None and np.isfinite(rec.w).all()
        if ref:
            for i, c in enumerate("xyz"):
                ax.plot(t, rec.w[:, i], "--", label=f"w_{c} reference")
            err = np.column_stack([columns[f"w_{c}"] for c in "xyz"]) - rec.w
            rms = np.sqrt(np.mean(err * err, axis=0))
            ax.set_title("error rms " + ", ".join(f"w_{c} {v:.3g}" for c, v in zip("xyz", rms)) + " rad/s",
                         fontsize=9)
        ax.set_ylabel("rad/s")
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        path = out / "rate.png"
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    files.append(path)
    return files


# =============================================================================
# command line (the lead wires these into cli.py)
# =============================================================================

def write_columns_csv(path, cols: Columns) -> None:
    """CSV with '# key: value' comments from cols.meta, the header, then the rows (atomic)."""
    from .errors import atomic_write
    from .recording import CSV_G_NAN, csv_rows
    names = list(cols)

    def write(f):
        for k, v in cols.meta.items():
            f.write(f"# {k}: {v}\n")
        f.write(",".join(names) + "\n")
        if names:  # '%.9g' % x per cell, as numpy.savetxt(fmt="%.9g") writes it
            for chunk in csv_rows([np.asarray(cols[k], float) for k in names], [CSV_G_NAN] * len(names), 9):
                f.write(chunk)
    atomic_write(path, write)


def run_command(kind: str, device_path, calibration_path, recording_path, output, *, engine: str = "float",
                report=None, **options) -> list[str]:
    """`accelcal attitude|displacement|rate --device D --calibration C REC -o OUT [--engine] [--report DIR]`:
    load, estimate, write the CSV (atomically) and, with ``report``, the plots.  Returns the
    warnings (one line each) for the caller to print to stderr; raises AccelcalError (one
    line) on bad input, before anything is written.  ``options`` go to the estimator
    (attitude: gain, w2_gate, leak_tau_s; displacement: form, axis; rate: leak_tau_s)."""
    from .calibration import load_calibration
    from .device import default_device, load_device
    from .recording import read_recording
    dev = default_device() if device_path in (None, "default") else load_device(device_path)
    cal = load_calibration(calibration_path, dev)
    rec = read_recording(recording_path, dev.n_channels)
    fn = {"attitude": attitude_from_recording, "displacement": displacement_from_recording,
          "rate": rate_from_recording}.get(kind)
    if fn is None:
        raise ValueError(f"unknown estimator {kind!r}")
    cols = fn(dev, cal, rec, engine, **options)
    write_columns_csv(output, cols)
    if report is not None:
        report_plots(report, cols, rec, kind)
    return [f"accelcal {kind}: warning: {w}" for w in cols.warnings]
