"""Pendulum attitude from two triads (seed 3): theta, w_y and dw_y of a body swinging
about its y axis, the triads on body x at r1 and r2 (include/accelcal/ac_attitude.h
derives the equations and signs from f(r) = f + alpha x r + omega x (omega x r)).

Float core (:func:`attitude_core`, the algorithm of ``ac_att_step`` in float64): fed the
exact geometry it is the reference (:func:`attitude_float`); fed the constants as the C
struct stores them, the same clipped inputs and the C decisions it is the twin
(:func:`attitude_twin`) the property tests hold the C core (:func:`attitude_fixed`) to,
within :func:`attitude_rate_bound`.  Recording form: :func:`attitude_from_recording`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import AccelcalError, InputError
from ..firmware.native import FORMATS, check, cptr, ffi, lib
from ..firmware.quantize import round_half_up
from ..io.recording import check_core_input, check_for_device
from .common import (CLIP, CLIP_LO, OMEGA_FRAC, OUT_FRAC, Columns, channel_noise, clip_i16, dt_fixed, force_noise,
                     resolve_array, time_span, uniform_dt)
from .omega import resolve_rows, wants_array_omega
from .omega_fixed import ESTIMATOR_OMEGA, estimator_omega
from .timegrid import on_uniform_grid
from ..firmware.triad import triad_forces

__all__ = ["ATT_GATED", "ATT_W2_NEG", "ATT_UNSETTLED", "ATT_NO_GRAVITY", "ATT_SAT", "ATT_SIGN_NEG",
           "ANGLE_FRAC", "W_FRAC", "W2_FRAC", "atan2_fixed", "AttitudeParams", "AttitudeConsts",
           "attitude_core", "attitude_float", "att_init_fixed", "attitude_fixed", "attitude_twin",
           "attitude_rate_bound", "triad_geometry", "attitude_from_recording", "array_block", "array_warnings"]

# flag bits, from the compiled core
ATT_GATED, ATT_W2_NEG, ATT_UNSETTLED, ATT_NO_GRAVITY, ATT_SAT, ATT_SIGN_NEG = (
    lib.AC_ATT_GATED, lib.AC_ATT_W2_NEG, lib.AC_ATT_UNSETTLED, lib.AC_ATT_NO_GRAVITY, lib.AC_ATT_SAT,
    lib.AC_ATT_SIGN_NEG)
ANGLE_FRAC = FORMATS.angle_frac   # AC_ANGLE_FRAC: theta, rad
W_FRAC = FORMATS.att_w_frac       # AC_ATT_W_FRAC: the rate state, rad/s
W2_FRAC = FORMATS.att_w2_frac     # AC_ATT_W2_FRAC: w^2 and its gate, (rad/s)^2
# formats of ac_att_init's arguments and of ac_att_cfg, stated in ac_attitude.h (no #define there)
GAIN_FRAC = 8    # gain_q8
LEAK_FRAC = 16   # leak per gated step
C_FRAC = 14      # c1, c2
K_FRAC = 16      # the gain K per step


def atan2_fixed(y, x) -> tuple[np.ndarray, np.ndarray]:
    """ac_atan2 elementwise on integers: (angle int Q.AC_ANGLE_FRAC rad, magnitude, the operands' unit)."""
    y = np.atleast_1d(np.asarray(y, np.int64))
    x = np.atleast_1d(np.asarray(x, np.int64))
    a = ffi.new("int16_t *")
    m = ffi.new("uint32_t *")
    ang = np.empty(y.shape, np.int64)
    mag = np.empty(y.shape, np.int64)
    for i, (yy, xx) in enumerate(zip(y.tolist(), x.tolist())):
        check(lib.ac_atan2(yy, xx, a, m), "ac_atan2")
        ang[i], mag[i] = a[0], m[0]
    return ang, mag


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


def attitude_core(f1, f2, C: AttitudeConsts, gated=None, sign_neg=None, state: dict | None = None):
    """The algorithm of ac_att_step in float64 (see include/accelcal/ac_attitude.h).

    f1, f2 (n,3) m/s^2 (clipped to +-32 like the core).  ``gated``/``sign_neg`` (n,) bool
    override the decisions (twin mode).  Returns a dict of (n,) arrays: theta, w, dw, w2,
    gmag, gated, sign_neg, settled, and the internals wp, wm, K, m (for the bounds).  ``state``
    (a dict, empty at the recording's first sample) carries the loop's state from one chunk of a
    recording to the next (accelcal.estimators.attitude_stream)."""
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
    st = {} if state is None else state
    w, a_prev, settled, first = st.get("w", 0.0), st.get("a_prev", 0.0), st.get("settled", 0), not st
    reacq = np.zeros(n, bool)
    dwl, w2l = dw.tolist(), w2.tolist()
    half_dt = 0.5 * C.dt
    for i in range(n):
        start = first and i == 0
        wp = 0.0 if start else w + half_dt * (a_prev + dwl[i])
        g = (w2l[i] < C.gate) if gated is None else bool(gated[i])
        wp_a[i] = wp
        if g:
            w = wp * (1.0 - C.leak)
            settled = 2 if (start or settled == 2) else 1
        else:
            m = math.sqrt(max(w2l[i], 0.0))
            neg = (wp < 0.0) if sign_neg is None else bool(sign_neg[i])
            wm = -m if neg else m
            if start or settled == 1:
                K = 1.0
                reacq[i] = True
                if not start:
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
    if state is not None and n:
        state.update(w=w, a_prev=a_prev, settled=settled)
    return dict(theta=theta, w=out_w, dw=dw, w2=w2, gmag=gmag, gated=g_out, sign_neg=s_out,
                settled=settled_out, wp=wp_a, wm=wm_a, K=K_a, m=m_a, y=y, x=x, reacq=reacq)


def attitude_float(f1, f2, p: AttitudeParams) -> dict:
    """Float reference with the exact geometry (engine="float")."""
    return attitude_core(f1, f2, AttitudeConsts.exact(p))


def att_init_fixed(p: AttitudeParams):
    """An initialised ac_att (C) and its constants as floats (the twin's AttitudeConsts)."""
    p.check()
    st = ffi.new("ac_att *")
    pos = 2.0 ** FORMATS.pos_frac
    r1q, r2q = int(round_half_up(p.r1 * pos)), int(round_half_up(p.r2 * pos))
    if r1q == r2q:
        raise AccelcalError(f"attitude: r1 = {p.r1:g} m and r2 = {p.r2:g} m are equal in Q.20")
    dt_m, dt_sh = dt_fixed(p.dt)
    gain_q8 = int(min(65535, round_half_up(p.gain * 2.0**GAIN_FRAC)))
    gate_q = int(min(2**31 - 1, round_half_up(p.gate() * 2.0**W2_FRAC)))
    leak_q = int(min(65535, round_half_up(p.leak() * 2.0**LEAK_FRAC)))
    check(lib.ac_att_init(st, r1q, r2q, dt_m, dt_sh, gain_q8, gate_q, leak_q), "ac_att_init")
    c = st.cfg
    # K (Q.K_FRAC) = m (|w|, Q.W2_FRAC/2) kdt_m 2^-kdt_shift
    C = AttitudeConsts(c1=c.c1 / 2.0**C_FRAC, c2=c.c2 / 2.0**C_FRAC, k=c.k_m * 2.0 ** -c.k_shift,
                       gs=c.gs_m * 2.0 ** -c.gs_shift, dt=c.dt_m * 2.0 ** -c.dt_shift,
                       kdt=c.kdt_m * 2.0 ** (W2_FRAC // 2 - K_FRAC - c.kdt_shift), leak=c.leak / 2.0**LEAK_FRAC,
                       gate=c.w2_gate / 2.0**W2_FRAC)
    return st, C


def attitude_fixed(f1_q, f2_q, p: AttitudeParams, state=None) -> dict:
    """ac_att_batch on int32 Q.AC_OUT_FRAC inputs (m/s^2).  Returns int arrays theta
    (Q.AC_ANGLE_FRAC rad), w (Q.AC_OMEGA_FRAC rad/s), dw (Q.AC_OUT_FRAC rad/s^2), w2
    (Q.AC_ATT_W2_FRAC (rad/s)^2), gmag (Q.AC_OUT_FRAC m/s^2), flags (ATT_*), plus 'consts'
    (AttitudeConsts as stored) and 'cfg' (an owned copy of the C ac_att_cfg).  ``state``: an
    :func:`att_init_fixed` pair (ac_att, constants) carried from one chunk of a recording to the next."""
    st, C = att_init_fixed(p) if state is None else state
    f = np.ascontiguousarray(np.hstack([np.asarray(f1_q, np.int32), np.asarray(f2_q, np.int32)]), dtype=np.int32)
    n = f.shape[0]
    out = ffi.new("ac_att_out[]", max(n, 1))
    check(lib.ac_att_batch(st, cptr("int32_t *", f), n, out), "ac_att_batch")
    buf = ffi.buffer(out, ffi.sizeof("ac_att_out") * n)
    dt = np.dtype([("theta", "<i2"), ("w", "<i2"), ("dw", "<i4"), ("w2", "<i4"), ("gmag", "<i4"), ("flags", "u1")],
                  align=True)
    assert dt.itemsize == ffi.sizeof("ac_att_out")
    rec = np.frombuffer(buf, dtype=dt, count=n).copy() if n else np.zeros(0, dt)
    res = {k: rec[k].astype(np.int64) for k in ("theta", "w", "dw", "w2", "gmag", "flags")}
    res["consts"] = C
    # an owned copy: st.cfg is a view into st's memory that does not keep st alive (cffi), so
    # once this function returns it would read freed memory (the rate bound's kdt_m and
    # kdt_shift came out as garbage now and then: a flaky property test)
    cfg = ffi.new("struct ac_att_cfg *")
    cfg[0] = st.cfg
    res["cfg"] = cfg
    return res


def attitude_twin(f1_q, f2_q, fixed: dict) -> dict:
    """The float twin of a fixed run: same clipped inputs, constants as stored, the C decisions."""
    fl = fixed["flags"]
    return attitude_core(clip_i16(f1_q) / 2.0**OUT_FRAC, clip_i16(f2_q) / 2.0**OUT_FRAC, fixed["consts"],
                          gated=(fl & ATT_GATED) != 0, sign_neg=(fl & ATT_SIGN_NEG) != 0)


def _isqrt_round(v: int) -> int:
    r = math.isqrt(v)
    return r + 1 if v - r * r > r else r


def attitude_rate_bound(fixed: dict, twin: dict) -> np.ndarray:
    """E_n + 0.5 LSB: the bound (rad/s) on |w_out 2^-10 - w_twin| stated in ac_attitude.h."""
    c = fixed["cfg"]
    C: AttitudeConsts = fixed["consts"]
    n = len(fixed["w"])
    h21 = 0.5 * 2.0 ** -W_FRAC            # half an LSB of the rate state
    h_dw = 0.5 * 2.0 ** -OUT_FRAC         # of dw
    h_m = 0.5 * 2.0 ** -(W2_FRAC // 2)    # of the measured |w| (isqrt of w^2)
    h_w = 0.5 * 2.0 ** -OMEGA_FRAC        # of the output w
    h_k = 0.5 * 2.0 ** -K_FRAC            # of K
    step_in = h21 + C.dt * h_dw   # inc rounding + dw rounding (both alphas) in wp
    out = np.zeros(n)
    E = 0.0
    for i in range(n):
        w2q = int(fixed["w2"][i])
        if twin["gated"][i]:
            E = (1.0 - C.leak) * ((E if i else 0.0) + step_in) + h21
        else:
            mt = twin["m"][i]
            em = h_m + (min(math.sqrt(h21), h21 / mt) if mt > 0 else math.sqrt(h21))
            if twin["reacq"][i]:
                E = em
            else:
                mq = _isqrt_round(max(w2q, 0))
                if c.kdt_shift > 32:
                    Kq = 0
                elif c.kdt_shift == 0:
                    Kq = 2**K_FRAC if c.kdt_m else 0
                else:
                    q = (mq * c.kdt_m) >> (c.kdt_shift - 1)
                    Kq = min(2**K_FRAC, (q >> 1) + (q & 1))
                K = Kq / 2.0**K_FRAC
                eK = h_k + C.kdt * em
                E = (1.0 - K) * (E + step_in) + K * em + eK * abs(twin["wm"][i] - twin["wp"][i]) + h21
        out[i] = E + h_w
    return out


def float_outputs(r: dict, n: int):
    """(theta, w, dw, gmag, gated, unsettled, saturated) of :func:`attitude_core`'s result ``r``
    over ``n`` samples (the float engine clips nothing)."""
    return r["theta"], r["w"], r["dw"], r["gmag"], r["gated"], ~r["settled"], np.zeros(n, bool)


def fixed_block(cal, rec, p: AttitudeParams, signed: bool, state=None):
    """The C core's attitude of the readings ``rec.raw`` (both triads through ``ac_triad_apply``,
    then ``ac_att``; ``state`` carries the estimator across blocks): (theta rad, w rad/s,
    dw rad/s^2, gmag m/s^2, gated, unsettled, saturated), the core's fixed-point outputs scaled to
    physical units, saturated also where a triad's force clipped."""
    f1, s1 = triad_forces(cal, rec, (0, 1, 2), "fixed", signed)
    f2, s2 = triad_forces(cal, rec, (3, 4, 5), "fixed", signed)
    r = attitude_fixed(f1, f2, p, state=state)
    fl = r["flags"]
    return (r["theta"] / 2.0**ANGLE_FRAC, r["w"] / 2.0**OMEGA_FRAC, r["dw"] / 2.0**OUT_FRAC,
            r["gmag"] / 2.0**OUT_FRAC, (fl & ATT_GATED) != 0, (fl & ATT_UNSETTLED) != 0,
            ((fl & ATT_SAT) != 0) | s1 | s2)


def triad_geometry(device, cal) -> tuple[float, float]:
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


def attitude_from_recording(device, cal, rec, engine: str = "float", *, gain: float = 2.0,
                            w2_gate: float | None = None, leak_tau_s: float = 2.0, omega: str = "auto") -> Columns:
    """`accelcal attitude`: the pendulum's angle, rate and angular acceleration.

    Parameters
    ----------
    device : Device
        Two triads (channels 0-2 and 3-5) on body x, the pivot at the origin.
    cal : Calibration
    rec : Recording
        Uniformly sampled.
    engine : {"float", "fixed"}
        Float reference or the C core (triads and estimator).
    gain : float
        K = gain dt |w| (1/rad).
    w2_gate : float, optional
        (rad/s)^2 below which |w| is not measured (default: 3 sigma of w^2 from the noise).
    leak_tau_s : float
        Time constant (s) of the pull to 0 while gated.
    omega : {"auto", "array", "none"}
        "array": a device whose layout observes omega (12 channels: four triads on a tetrahedron,
        triads at the origin and on the axes; docs/angular-rate.md) swinging about body y, the
        pivot at its origin: theta from the resolved f at the origin, w_y the array's own omega
        (fused with the integrated alpha; engine "fixed": ``ac_omega``), dw_y its alpha (gain,
        w2_gate, leak_tau_s unused).  "auto": "array" where the layout observes omega and the
        recording has no complete w columns, else the two-triad estimator.  "none": the
        two-triad estimator.

    Returns
    -------
    Columns
        t (s), theta_rad (rad), w_y (rad/s), dw_y (rad/s^2) (the contract's), g_mps2 (|g| the
        pair sees, m/s^2), gated (|w| not measured: integrated), unsettled (sign of w not yet
        established), saturated; with the array's omega also w_y_sigma (rad/s); warnings for
        unsettled samples, |g| more than 20 % off gravity, saturation.

    Raises
    ------
    InputError
        Not two triads on x, r1 = r2, non-uniform time, counts outside uint16 (fixed); omega
        "array" on a layout that does not observe it (the observability line).
    """
    if engine not in ("float", "fixed"):
        raise ValueError(f"unknown engine {engine!r}")
    if omega not in ESTIMATOR_OMEGA:
        raise ValueError(f"unknown omega {omega!r}: expected one of {', '.join(ESTIMATOR_OMEGA)}")
    check_for_device(rec, device, min_samples=2)
    if omega == "array" or (omega == "auto" and wants_array_omega(device, cal, rec, "auto")):
        return _array_attitude(device, cal, rec, engine, omega)
    r1, r2 = triad_geometry(device, cal)
    if engine == "fixed":
        check_core_input(rec, device.raw_min < 0)
    rec, filled, fill_note = on_uniform_grid(rec)
    dt = uniform_dt(rec)
    p = AttitudeParams(r1=r1, r2=r2, dt=dt, gain=gain, w2_gate=w2_gate,
                       noise_mps2=max(force_noise(device, cal, channel_noise(device, rec), (0, 1, 2)), 1e-4),
                       leak_tau_s=leak_tau_s)
    try:
        p.check()
    except AccelcalError as e:
        raise InputError(device.name, str(e)) from None
    warnings = [f"attitude: {fill_note}"] if fill_note else []
    if engine == "float":
        r = attitude_float(*(triad_forces(cal, rec, ch, "float")[0] for ch in ((0, 1, 2), (3, 4, 5))), p)
        theta, w, dw, gmag, gated, unsettled, sat = float_outputs(r, rec.n_samples)
    else:
        theta, w, dw, gmag, gated, unsettled, sat = fixed_block(cal, rec, p, device.raw_min < 0)
    g0 = float(device.gravity_mps2)
    off = np.abs(gmag - g0) > 0.2 * g0
    if unsettled.any():
        k = int(np.count_nonzero(unsettled))
        until = time_span(rec.t, min(k, rec.n_samples - 1), rec=rec)
        warnings.append(f"attitude: the sign of w_y is not yet established for the first {k} samples "
                        f"(until {until}: no pass through low rate yet); column unsettled = 1")
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
                   **({"filled": filled.astype(float)} if filled.any() else {}),
                   warnings=warnings,
                   meta={"engine": engine, "device": device.name, "r1_m": f"{r1:.6g}", "r2_m": f"{r2:.6g}",
                         "w2_gate": f"{p.gate():.6g}", "gain": f"{gain:g}", "leak_tau_s": f"{leak_tau_s:g}"})
    return cols


def array_block(device, cal, rec, engine: str, w, w_core) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The pendulum's angle from the array's omega on a block of samples (the recording whole, or a
    chunk: ``rec`` has raw, and source and line for the fixed engine's messages): f at the pivot
    (the origin), f(0) = (-g sin theta, ., g cos theta) as ac_attitude.h's pair sees it.

    Parameters
    ----------
    w : ndarray (n, 3)
        rad/s: the float estimate (engine "float").
    w_core : ndarray (n, 3)
        rad/s: the C core's Q5.10 rate (engine "fixed").

    Returns
    -------
    theta_rad, dw_y, g_mps2 : ndarray (n,)
        rad, rad/s^2, |f| in the swing's plane m/s^2.
    saturated : ndarray (n,) bool
    """
    if engine == "float":     # each row's sums in one order: the same numbers in chunks
        f, a = resolve_rows(cal.offsets, cal.sensitivity, cal.positions_or_nominal(device), rec.raw, w)
        return np.arctan2(-f[:, 0], f[:, 2]), a[:, 1], np.hypot(f[:, 0], f[:, 2]), np.zeros(len(f), bool)
    f, a, sat = resolve_array(device, cal, rec, engine, w_core, with_flags=True)
    ang, mag = atan2_fixed(-np.asarray(f[:, 0], np.int64), f[:, 2])    # the core's atan2 on Q.AC_OUT_FRAC f
    return ang / 2.0**ANGLE_FRAC, a[:, 1] / 2.0**OUT_FRAC, np.hypot(f[:, 0], f[:, 2]) / 2.0**OUT_FRAC, sat


def array_warnings(off: int, sat: int) -> list[str]:
    """attitude's warnings with the array's omega: samples whose f at the pivot is off g, clipped."""
    out = []
    if off:
        out.append(f"attitude: on {off} samples f at the pivot is more than 20 % off "
                   "gravity in the swing's plane (pivot moving, turning about another axis, or clipping): "
                   "theta there is doubtful; column g_mps2")
    if sat:
        out.append(f"attitude: {sat} samples clipped in the fixed-point core (column saturated)")
    return out


def _array_attitude(device, cal, rec, engine: str, omega: str) -> Columns:
    """attitude_from_recording with the array's own omega: theta from f at the pivot
    (:func:`array_block`), w_y and dw_y from the array (docs/angular-rate.md)."""
    if engine == "fixed":
        check_core_input(rec, device.raw_min < 0)
    rec, filled, fill_note = on_uniform_grid(rec)
    est = estimator_omega(device, cal, rec, "array", engine)
    theta, dw, gmag, sat = array_block(device, cal, rec, engine, est.w, est.w_core)
    g0 = float(device.gravity_mps2)
    warnings = ([f"attitude: {fill_note}"] if fill_note else []) + array_warnings(
        int(np.count_nonzero(np.abs(gmag - g0) > 0.2 * g0)), int(np.count_nonzero(sat)))
    n = rec.n_samples
    return Columns(t=np.asarray(rec.t, float), theta_rad=np.asarray(theta, float), w_y=np.asarray(est.w[:, 1], float),
                   dw_y=np.asarray(dw, float), g_mps2=np.asarray(gmag, float), w_y_sigma=est.sigma[:, 1],
                   gated=np.zeros(n), unsettled=np.zeros(n), saturated=sat.astype(float),
                   **({"filled": filled.astype(float)} if filled.any() else {}),
                   warnings=warnings, meta={"engine": engine, "device": device.name, "omega": "array"})
