"""The rest detector: the float twin of the firmware's ac_rest (include/accelcal/ac_rest.h).

It stays here as the C core's reference: :func:`rest_detect` decides as ``ac_rest``
does, sample by sample (with ``as_stored`` on the thresholds as the C config holds
them), and the property tests hold :func:`rest_fixed` (the C core) to it.  The
displacement (its reference test) and the rate's reset use the same state machine
(:class:`RestState`).  An offline static detector for calibration and diagnosis is
``accelcal.readings.static``, not this one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from ..firmware.native import check, cptr, ffi, lib
from ..firmware.quantize import round_half_up
from .common import CLIP, CLIP_LO, OUT_FRAC

__all__ = ["REST_QUIET", "REST_AT_REST", "REST_ENTER", "REST_LEAVE", "REST_CLIP", "RestParams",
           "default_rest_params", "rest_cfg_fixed", "RestThresholds", "rest_params_as_stored", "RestState",
           "rest_detect", "rest_fixed", "rest_dated_back", "REST_LEVEL_P", "motion_window", "rest_run", "rest_runs", "rest_on_g"]

# flag bits, from the compiled core (include/accelcal/ac_rest.h)
REST_QUIET, REST_AT_REST, REST_ENTER, REST_LEAVE, REST_CLIP = (
    lib.AC_REST_QUIET, lib.AC_REST_AT_REST, lib.AC_REST_ENTER, lib.AC_REST_LEAVE, lib.AC_REST_CLIP)
THR_SCALE = 2.0 ** OUT_FRAC          # dev_max, alpha_max, ref_max: Q.AC_OUT_FRAC
G2_SCALE = 2.0 ** (2 * OUT_FRAC)     # g2_lo, g2_hi: Q.(2 AC_OUT_FRAC) (m/s^2)^2


@dataclass
class RestParams:
    """Rest test (see include/accelcal/ac_rest.h).  ``g`` None switches the |f| test off;
    ``ref_max`` bounds |f - (the first rest's mean f)| once the displacement knows it.

    ``g_tol`` bounds a rest's mean |f| about g (the body's: a calibration's scale error, a tilt
    within the rest), ``g_noise`` what the noise adds to one sample's |f|: the detector tests each
    sample against g +- (g_tol + g_noise) (:meth:`g2_bounds`), and the host tests each rest's mean
    against g +- g_tol (:func:`rest_on_g`).  With ``g_noise`` 0 a body whose mean |f| lies within
    the noise of the band's edge has some of its samples outside it, each breaking the quiet run a
    rest needs: its rests come and go (a still LSM303 at 0.965 g with 0.11 m/s^2 of noise: 10 %
    of its samples out, motions of 55 s and 3.8 m)."""
    dev_max: float = 0.1            # m/s^2, max_k |f_k - mean_k|
    g: float | None = 9.80665       # m/s^2
    g_tol: float = 0.5              # a rest's mean |f| within g +- g_tol
    g_noise: float = 0.0            # m/s^2, a sample's |f| within g +- (g_tol + g_noise)
    alpha_max: float = math.inf     # rad/s^2 (only when alpha is given)
    hold: int = 25                  # samples
    ema_shift: int = 3              # mean weight 2^-ema_shift
    ref_max: float = 0.15           # m/s^2 (only when a reference is given)

    def g2_bounds(self) -> tuple[float, float]:
        """The per-sample band of |f|^2, (m/s^2)^2: (g -+ (g_tol + g_noise))^2."""
        if self.g is None:
            return 0.0, math.inf
        w = self.g_tol + self.g_noise
        return max(self.g - w, 0.0) ** 2, (self.g + w) ** 2


def default_rest_params(device, rate_hz: float | None = None, alpha_sigma: float | None = None,
                        f_sigma: float | None = None) -> RestParams:
    """dev_max = 5 sigma (sigma: ``f_sigma``, the noise of f in m/s^2 -- see
    :func:`~accelcal.estimators.common.force_noise` -- else the device's ``noise_mps2``; at least
    0.01 m/s^2), ref_max = dev_max + 0.05 m/s^2 (room for a zero-point drift between rests),
    hold = 0.25 s, mean over ~0.1 s, a rest's mean |f| within 0.5 m/s^2 of g and each sample's
    within that plus dev_max (g_noise: the noise's 5 sigma, as the deviation's test allows it),
    |alpha| <= 5 sigma_alpha when given."""
    rate = float(rate_hz or device.sample_rate_hz)
    noise = float(f_sigma) if f_sigma is not None else float(getattr(device, "noise_mps2", 0.0) or 0.0)
    k = int(min(12, max(1, round(math.log2(max(2.0, 0.1 * rate))))))
    dev = max(5.0 * noise, 0.01)
    return RestParams(dev_max=dev, g=float(device.gravity_mps2), g_tol=0.5, g_noise=dev,
                      alpha_max=math.inf if alpha_sigma is None else max(5.0 * alpha_sigma, 0.05),
                      hold=max(4, int(round(0.25 * rate))), ema_shift=k, ref_max=dev + 0.05)


def _q_thr(x: float) -> int:
    return int(min(round_half_up(x * THR_SCALE), 2**31 - 1)) if math.isfinite(x) else 2**31 - 1


def rest_cfg_fixed(p: RestParams):
    """The ac_rest_cfg for p (thresholds rounded half up to their Q formats)."""
    c = ffi.new("ac_rest_cfg *")
    c.dev_max = _q_thr(p.dev_max)
    lo, hi = p.g2_bounds()
    c.g2_lo = int(min(round_half_up(lo * G2_SCALE), 2**32 - 1))
    c.g2_hi = int(min(round_half_up(hi * G2_SCALE), 2**32 - 1)) if math.isfinite(hi) else 2**32 - 1
    c.alpha_max = _q_thr(p.alpha_max)
    c.ref_max = _q_thr(p.ref_max)
    c.hold = int(p.hold)
    c.ema_shift = int(p.ema_shift)
    return c


@dataclass
class RestThresholds:
    """The rest test's thresholds as floats (m/s^2, (m/s^2)^2, rad/s^2): exact, or as the C
    config stores them (``of(p, as_stored=True)``, the twin's)."""
    dev_max: float
    g2_lo: float
    g2_hi: float
    alpha_max: float
    ref_max: float
    hold: int
    ema_shift: int

    @classmethod
    def of(cls, p: RestParams, as_stored: bool = False) -> "RestThresholds":
        if as_stored:
            c = rest_cfg_fixed(p)
            return cls(c.dev_max / THR_SCALE, c.g2_lo / G2_SCALE, c.g2_hi / G2_SCALE, c.alpha_max / THR_SCALE,
                       c.ref_max / THR_SCALE, p.hold, p.ema_shift)
        lo, hi = p.g2_bounds()
        return cls(p.dev_max, lo, hi, p.alpha_max, p.ref_max, p.hold, p.ema_shift)


def rest_params_as_stored(p: RestParams) -> tuple[float, float, float, float]:
    """(dev_max, g2_lo, g2_hi, alpha_max) exactly as the fixed cfg holds them."""
    t = RestThresholds.of(p, True)
    return t.dev_max, t.g2_lo, t.g2_hi, t.alpha_max


class RestState:
    """The float twin of ac_rest (one sample at a time, on clipped inputs)."""

    def __init__(self, th: RestThresholds):
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


def rest_detect(f, p: RestParams, alpha=None, *, as_stored: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Float rest detector, sample by sample.

    Parameters
    ----------
    f : array_like (n, 3)
        Specific force, m/s^2 (clipped to the core's +-32 m/s^2).
    p : RestParams
    alpha : array_like (n, 3), optional
        Angular acceleration, rad/s^2 (the |alpha| test only when given).
    as_stored : bool
        Use the thresholds as the fixed cfg stores them: the twin of ac_rest (f should
        then be the Q.AC_OUT_FRAC inputs / 2^AC_OUT_FRAC).

    Returns
    -------
    flags : ndarray (n,) uint8
        REST_* bits.
    dev : ndarray (n,)
        max_k |f_k - mean_k| before the mean's update, m/s^2.
    """
    f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
    n = f.shape[0]
    flags = np.zeros(n, np.uint8)
    dev = np.zeros(n)
    rs = RestState(RestThresholds.of(p, as_stored))
    fl = f.tolist()
    al = None if alpha is None else np.asarray(alpha, float).tolist()
    for i in range(n):
        flags[i], dev[i], _ = rs.step(fl[i], None if al is None else al[i])
    return flags, dev


def rest_fixed(f_q, p: RestParams, alpha_q=None) -> np.ndarray:
    """ac_rest_batch: f (n, 3) and alpha (n, 3) int32 Q.AC_OUT_FRAC -> REST_* flags (n,) uint8."""
    f_q = np.ascontiguousarray(f_q, dtype=np.int32)
    st = ffi.new("ac_rest *")
    check(lib.ac_rest_init(st, rest_cfg_fixed(p)), "ac_rest_init")
    flags = np.zeros(f_q.shape[0], np.uint8)
    ap = ffi.NULL if alpha_q is None else cptr("int32_t *", np.ascontiguousarray(alpha_q, dtype=np.int32))
    check(lib.ac_rest_batch(st, cptr("int32_t *", f_q), ap, f_q.shape[0], cptr("uint8_t *", flags)),
          "ac_rest_batch")
    return flags


def rest_dated_back(at, quiet, f, p: RestParams) -> np.ndarray:
    """The rest intervals from when each rest began, not from when it was declared.

    The detector (float and C alike, sample by sample: firmware cannot look back) declares
    a rest at the p.hold-th quiet sample in a row, 0.24 s after it began at 100 Hz; and its
    running mean starts at the first sample's f, so a sample of the noise can fail the test
    against it before it settles (~2**ema_shift samples).  For reporting, each rest is dated
    back to the first sample of the quiet run that declared it, and the first rest to the
    recording's first sample when every sample before that run is still against that rest's
    own level: max_k |f_k - m_k| <= dev_max about m, the mean f of the run, with |f| about g
    (the test of :class:`RestState`, against a mean that has settled).

    Parameters
    ----------
    at, quiet : array_like (n,) bool
        The detector's at-rest and quiet decisions (REST_AT_REST, REST_QUIET), per sample.
    f : array_like (n, 3)
        Specific force, m/s^2 (clipped to the core's +-32 m/s^2 as the detector's input).
    p : RestParams
        The detector's parameters (dev_max, m/s^2; the |f| bounds; hold, samples).

    Returns
    -------
    ndarray (n,) bool
        At rest: ``at`` with each rest's start moved back.
    """
    at = np.asarray(at, bool)
    quiet = np.asarray(quiet, bool)
    out = at.copy()
    n = at.size
    if not at.any():
        return out
    run_start = np.maximum.accumulate(np.where(quiet, -1, np.arange(n))) + 1   # each sample's quiet run began
    declared = np.flatnonzero(at & ~np.concatenate([[False], at[:-1]]))
    for i in declared.tolist():
        if quiet[i]:
            out[run_start[i]:i] = True
    s, i = int(run_start[declared[0]]), int(declared[0])
    if 0 < s <= i and quiet[i]:
        f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
        m = f[s:i + 1].mean(axis=0)
        lo, hi = p.g2_bounds()
        g2 = np.sum(f[:s] ** 2, axis=1)
        if np.all(np.max(np.abs(f[:s] - m), axis=1) <= p.dev_max) and np.all((g2 >= lo) & (g2 <= hi)):
            out[:s] = True
    return out


def rest_runs(at) -> list[tuple[int, int]]:
    """The runs [s, e) of at-rest samples (``at``, (n,) bool)."""
    edges = np.diff(np.concatenate(([0], np.asarray(at, bool).astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def rest_on_g(at, f, p: RestParams) -> tuple[np.ndarray, list[tuple[int, int, float]]]:
    """The rests whose mean |f| lies within ``p.g_tol`` of ``p.g``, and those that do not.

    The detector tests each sample's |f| against a band widened by the noise (``p.g_noise``): a
    decision on one sample would flicker where a still body's mean |f| sits within the noise of
    the band's edge.  Each rest's mean over all its samples decides instead, once for the rest (its
    noise is the samples' over sqrt(n)): a body whose mean is off g by more than ``g_tol`` (a
    calibration's scale, a constant vertical acceleration) is at no rest, whatever its samples.

    Parameters
    ----------
    at : array_like (n,) bool
        At rest (each rest from where it began).
    f : array_like (n, 3)
        Specific force, m/s^2.
    p : RestParams
        g, g_tol (m/s^2); g None: every rest kept.

    Returns
    -------
    kept : ndarray (n,) bool
        ``at`` less the rests off g.
    off : list of (int, int, float)
        Each rest left out: first sample, end (exclusive), its mean |f| (m/s^2).
    """
    kept = np.array(at, bool)
    off = []
    if p.g is None:
        return kept, off
    f = np.asarray(f, float)
    for s, e in rest_runs(kept):
        norm = float(np.linalg.norm(f[s:e].mean(axis=0)))
        if abs(norm - p.g) > p.g_tol:
            kept[s:e] = False
            off.append((s, e, norm))
    return kept, off


#: a sample within this share of the noise's spread of its rest's level (chi-square, per component
#: integrated) is taken as at rest where a motion's window is dated (:func:`motion_window`)
REST_LEVEL_P = 0.95


def rest_run(at, i: int, lo: int, hi: int) -> tuple[int, int]:
    """The run [s, e) of at-rest samples (``at``, bool) through sample ``i``, kept within [lo, hi)."""
    s = e = i
    while s > lo and at[s - 1]:
        s -= 1
    while e < hi and at[e]:
        e += 1
    return s, e


def motion_window(acc, at, s: int, lo: int, fq: int | None, sigma: float, k: int) -> tuple[int, int | None]:
    """The samples a motion's integration runs over, from the rest before it to the rest after it.

    The detector declares a motion where f leaves its running mean by more than its test (5 sigma)
    -- late on a smooth start, whose first samples are then not integrated: a velocity missed, which
    the zero point spreads over the path (-0.24 % of a 0.5 m stroke at 0.02 m/s^2 noise and 60 Hz) --
    and a rest only once its running mean has settled, past the motion's end (rest samples that
    add only noise).  Dated from the rests' own levels: the start is the last sample before the
    declared one that is within the noise of the rest before it (its whole mean), the end the first
    sample of the run before the final rest's quiet run that lies within the noise of that rest's
    level.  Within the noise: |acc - level| below sigma sqrt(chi2(REST_LEVEL_P, k)).

    Parameters
    ----------
    acc : ndarray (n, 3)
        The integrated acceleration, m/s^2 (k components nonzero).
    at : ndarray (n,) bool
        At rest (as declared).
    s : int
        The first sample declared moving.
    lo : int
        The earliest sample the start may take (the previous motion's end).
    fq : int or None
        The first quiet sample of the final rest (its quiet run up to the declaration), or None:
        the motion does not end at rest.
    sigma : float
        The noise of acc, m/s^2 per component.
    k : int
        The components integrated (1 or 3).

    Returns
    -------
    (int, int or None)
        The anchor (at rest, v = 0) and the end (the first sample at rest; None when ``fq`` is None).
    """
    thr = float(sigma) * math.sqrt(float(chi2.ppf(REST_LEVEL_P, k)))
    r0 = rest_run(at, s - 1, lo, s - 1)[0]
    level = acc[r0:s].mean(axis=0)
    a = s - 1
    while a > max(lo, r0) and float(np.linalg.norm(acc[a] - level)) > thr:
        a -= 1
    if fq is None:
        return a, None
    level = acc[fq:].mean(axis=0) if not at[fq:].any() else acc[fq:fq + max(1, int(np.argmax(at[fq:])) + 1)].mean(axis=0)
    b = fq
    while b - 1 > s and float(np.linalg.norm(acc[b - 1] - level)) <= thr:
        b -= 1
    return a, b
