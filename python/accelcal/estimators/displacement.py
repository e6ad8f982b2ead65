"""Stop-to-stop displacement (seed 4), the streaming form of the firmware's ac_disp
(include/accelcal/ac_displace.h): integrate twice from a rest, and when the next rest is
declared remove the zero point zp = v(T) / T from the end point.

Float core (:func:`displace_core`, the algorithm of ``ac_disp_step`` in float64 with the
rest test inline): the reference of the streaming form (:func:`displace_stream`) and,
fed the core's rest decisions and its stored frame, the twin (:func:`displace_twin`) the
property tests hold the C core (:func:`displace_fixed`) to within
:func:`displace_error_bound`.  The host forms (offline estimator, path correction,
recordings) are in :mod:`.displacement_host`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import AccelcalError
from ..firmware.native import FORMATS, check, cptr, ffi, lib
from .common import CLIP, CLIP_LO, OUT_FRAC, clip_i16, dt_fixed
from .rest import REST_AT_REST, REST_QUIET, RestParams, RestState, RestThresholds, rest_cfg_fixed

__all__ = ["DISP_NO_REF", "DISP_REST", "DISP_MOVING", "DISP_SEG_END", "DISP_LONG", "DISP_SAT", "DISP_OPEN",
           "DISP_NO_REST", "DISP_REF_SET", "DISP_BAD_REF", "A_FRAC", "V_FRAC", "P_FRAC", "ROT_FRAC", "G_FRAC",
           "GSUM_MAX", "DisplaceParams", "tilt_frame", "DispFloat", "displace_core", "displace_stream",
           "disp_cfg_fixed", "DispCore", "displace_fixed", "displace_twin", "displace_error_bound"]

# flag bits, from the compiled core
(DISP_NO_REF, DISP_REST, DISP_MOVING, DISP_SEG_END, DISP_LONG, DISP_SAT, DISP_OPEN, DISP_NO_REST,
 DISP_REF_SET, DISP_BAD_REF) = (lib.AC_DISP_NO_REF, lib.AC_DISP_REST, lib.AC_DISP_MOVING, lib.AC_DISP_SEG_END,
                                lib.AC_DISP_LONG, lib.AC_DISP_SAT, lib.AC_DISP_OPEN, lib.AC_DISP_NO_REST,
                                lib.AC_DISP_REF_SET, lib.AC_DISP_BAD_REF)
A_FRAC = FORMATS.disp_a_frac        # AC_DISP_A_FRAC: acceleration and zp, m/s^2
V_FRAC = FORMATS.disp_v_frac        # AC_DISP_V_FRAC: velocity, m/s
P_FRAC = FORMATS.disp_p_frac        # AC_DISP_P_FRAC: position, m
ROT_FRAC = FORMATS.disp_rot_frac    # AC_DISP_ROT_FRAC: the rest frame's rotation
G_FRAC = FORMATS.disp_g_frac        # AC_DISP_G_FRAC: the first rest's mean f, m/s^2
GSUM_MAX = FORMATS.disp_gsum_max    # AC_DISP_GSUM_MAX: samples of the first rest averaged for g
T_FRAC = 16                         # the motion's duration T, s (stated in ac_displace.h, no #define)


@dataclass
class DisplaceParams:
    """dt (s); axis None: 3-axis with gravity removed in the frame of the first rest;
    0/1/2: 1-D along that body axis (the seed's case, nothing removed); rest: RestParams;
    pad (offline only): samples added before each motion's start and after its end, as dated
    from the rests' levels (rest.motion_window); None: 2**ema_shift.  One: the last sample of a
    smooth start or end within the noise still belongs to the motion (left out, it is missed in
    v(T) -- up to thr dt T / 4 in p, 0.09 % of a 0.5 m stroke in 2 s at 0.02 m/s^2 and 60 Hz),
    where a sample of rest more adds only a share 1.5 dt / T to the noise of p."""
    dt: float
    axis: int | None = None
    rest: RestParams = field(default_factory=RestParams)
    pad: int | None = 1


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


class DispFloat:
    """The algorithm of ac_disp_step in float64 (:func:`displace_core`), its state carried from one
    batch of samples to the next (the whole recording in one: :func:`displace_core`; in chunks:
    accelcal.estimators.displacement_stream).  ``frame``: as :func:`displace_core`'s."""

    def __init__(self, dt, axis, th: RestThresholds, frame=None) -> None:
        self.dt, self.axis, self.frame_given = dt, axis, frame
        self.rs = RestState(th)
        self.segments: list = []
        self.phase, self.have_ref = 0, False
        self.gsum, self.gcount = np.zeros(3), 0
        self.g = self.R = self.c = None
        self.v, self.p, self.a_prev, self.f_prev = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
        self.nseg, self.long_seg, self.anchor = 0, False, -1
        self.i0 = 0                               # the first sample of the next batch

    def step(self, f, rest_flags=None) -> dict:
        """One batch (n,3) f (clipped like the core): v, p (n,3), flags (n,), zp (n,3), nseg (n,),
        rest (n,), own_quiet, dev, dref (n,)."""
        f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
        n = f.shape[0]
        V, P, ZP = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 3))
        FL = np.zeros(n, np.int64)
        NS = np.zeros(n, np.int64)
        RF = np.zeros(n, np.int64)
        own_q, DEV, DREF = np.zeros(n, bool), np.zeros(n), np.zeros(n)
        segments = self.segments
        phase, have_ref = self.phase, self.have_ref
        gsum, gcount = self.gsum, self.gcount
        g, R, c = self.g, self.R, self.c
        v, p, a_prev = self.v, self.p, self.a_prev
        f_prev = self.f_prev
        nseg, long_seg, anchor = self.nseg, self.long_seg, self.anchor
        dt, axis, frame, i0 = self.dt, self.axis, self.frame_given, self.i0
        half_dt = 0.5 * dt
        rs = self.rs
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
                        nseg, long_seg, anchor = 0, False, i0 + i - 1
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
                    segments.append((anchor, i0 + i, zp))
                    v = np.zeros(3)
                    phase = 1
                else:
                    flags |= DISP_MOVING
            f_prev = fc
            V[i], P[i], FL[i], NS[i] = v, p, flags, nseg
        self.phase, self.have_ref = phase, have_ref
        self.gsum, self.gcount = gsum, gcount
        self.g, self.R, self.c = g, R, c
        self.v, self.p, self.a_prev, self.f_prev = v, p, a_prev, f_prev
        self.nseg, self.long_seg, self.anchor = nseg, long_seg, anchor
        self.i0 = i0 + n
        return dict(v=V, p=P, flags=FL, zp=ZP, nseg=NS, rest=RF, own_quiet=own_q, dev=DEV, dref=DREF)


def displace_core(f, dt, axis, th: RestThresholds, rest_flags=None, frame=None):
    """The algorithm of ac_disp_step in float64 on (n,3) f (clipped like the core).

    The rest test runs inline (its reference, the first rest's mean, is known only once
    that rest ends).  Twin mode: ``rest_flags`` (the core's AC_REST_* per sample) are
    used instead of the own decisions, which are still computed (``own_quiet``, ``dev``,
    ``dref``) for the margin checks; ``frame`` (g, R, c) replaces the gravity reference
    (R, c None for 1-D).  Returns v, p (n,3), flags (n,), zp (n,3), nseg (n,), rest (n,),
    segments [(anchor, end, zp (3,) or None)], frame (g, R, c) or None, phase
    (:class:`DispFloat` over the whole recording)."""
    core = DispFloat(dt, axis, th, frame)
    out = core.step(f, rest_flags)
    return dict(**out, segments=core.segments, phase=core.phase,
                frame=None if core.g is None else (core.g, core.R, core.c))


def displace_stream(f, p: DisplaceParams) -> dict:
    """Float reference of the streaming form (engine="float", form="stream")."""
    return displace_core(f, p.dt, p.axis, RestThresholds.of(p.rest))


def disp_cfg_fixed(p: DisplaceParams):
    """The ac_disp_cfg for p (rest thresholds as rest_cfg_fixed, dt as dt_fixed)."""
    c = ffi.new("ac_disp_cfg *")
    rc = rest_cfg_fixed(p.rest)
    c.rest = rc[0]
    c.dt_m, c.dt_shift = dt_fixed(p.dt)
    c.axis = -1 if p.axis is None else int(p.axis)
    return c


class DispCore:
    """The C core's ac_disp with its state carried from one batch of samples to the next (the whole
    recording in one: :func:`displace_fixed`; in chunks: accelcal.estimators.displacement_stream)."""

    #: one ac_disp_out as numpy reads it
    OUT = np.dtype([("v", "<i4", 3), ("p", "<i4", 3), ("zp", "<i4", 3), ("nseg", "<u2"), ("flags", "<u2"),
                    ("rest", "u1")], align=True)

    def __init__(self, p: DisplaceParams) -> None:
        self.p = p
        self.st = ffi.new("ac_disp *")
        self.cfg = disp_cfg_fixed(p)
        check(lib.ac_disp_init(self.st, self.cfg), "ac_disp_init")
        self.dt = self.cfg.dt_m * 2.0 ** -self.cfg.dt_shift          # dt as stored, s

    def step(self, f_q) -> dict:
        """ac_disp_batch on (n,3) int32 Q.10: int64 arrays v (Q.24), p (Q.20), zp (Q.16), nseg, flags,
        rest (the AC_REST_* flags)."""
        f_q = np.ascontiguousarray(f_q, dtype=np.int32)
        n = f_q.shape[0]
        out = ffi.new("ac_disp_out[]", max(n, 1))
        check(lib.ac_disp_batch(self.st, cptr("int32_t *", f_q), n, out), "ac_disp_batch")
        assert self.OUT.itemsize == ffi.sizeof("ac_disp_out")
        rec = np.frombuffer(ffi.buffer(out, ffi.sizeof("ac_disp_out") * n), dtype=self.OUT, count=n).copy() if n \
            else np.zeros(0, self.OUT)
        return {k: rec[k].astype(np.int64) for k in ("v", "p", "zp", "nseg", "flags", "rest")}

    def finish(self) -> int:
        """ac_disp_finish's flags."""
        fin = ffi.new("ac_disp_out *")
        check(lib.ac_disp_finish(self.st, fin), "ac_disp_finish")
        return int(fin.flags)

    def frame(self):
        """(g Q.16, rot Q.14 or None, c Q.16 or None) as stored, or None before the first motion."""
        st = self.st
        if not st.have_ref:
            return None
        g = np.array([st.g[k] for k in range(3)], np.int64)
        if self.p.axis is not None:
            return (g, None, None)
        return (g, np.array([[st.rot[j][k] for k in range(3)] for j in range(3)], np.int64),
                np.array([st.c[k] for k in range(3)], np.int64))


def displace_fixed(f_q, p: DisplaceParams) -> dict:
    """ac_disp_batch + ac_disp_finish on (n,3) int32 Q.10.  Returns int arrays v (Q.24), p (Q.20),
    zp (Q.16), nseg, flags, rest (the AC_REST_* flags); 'finish' (the ac_disp_finish flags);
    'frame' (g Q.16, rot Q.14 or None, c Q.16 or None) and 'dt' (as stored)."""
    core = DispCore(p)
    out = core.step(f_q)
    return dict(**out, finish=core.finish(), frame=core.frame(), dt=core.dt)


def displace_twin(f_q, fixed: dict, p: DisplaceParams) -> dict:
    """The float twin of a fixed run: same clipped inputs, the core's rest decisions, g/R/c as stored."""
    frame = None
    if fixed["frame"] is not None:
        g, rot, c = fixed["frame"]
        frame = (g / 2.0**G_FRAC, None if rot is None else rot / 2.0**ROT_FRAC,
                 None if c is None else c / 2.0**A_FRAC)
    return displace_core(clip_i16(f_q) / 2.0**OUT_FRAC, fixed["dt"], p.axis, RestThresholds.of(p.rest, True),
                          rest_flags=fixed["rest"], frame=frame)


def displace_error_bound(fixed: dict, twin: dict, three_axis: bool) -> tuple[np.ndarray, np.ndarray]:
    """Per-sample bounds (m/s, m) on |v - v'| and |p - p'| (each component) stated in
    ac_displace.h, carried through segment ends."""
    dt = fixed["dt"]
    h_v, h_p, h_t = 0.5 * 2.0**-V_FRAC, 0.5 * 2.0**-P_FRAC, 0.5 * 2.0**-T_FRAC   # half LSBs of v, p, T
    ea = 0.5 * 2.0**-A_FRAC if three_axis else 0.0
    n = len(fixed["flags"])
    bv, bp = np.zeros(n), np.zeros(n)
    Ev, Ep = 0.0, 0.0
    for i in range(n):
        fl = int(fixed["flags"][i])
        if fl & (DISP_MOVING | DISP_SEG_END):
            Ev_new = Ev + dt * ea + h_v
            Ep = Ep + dt * (Ev + Ev_new) / 2.0 + h_p
            Ev = Ev_new
            if fl & DISP_SEG_END:
                T = int(fixed["nseg"][i]) * dt
                if not fl & DISP_LONG:
                    # |v| before the reset: recover from the twin's zp
                    vT = float(np.max(np.abs(twin["zp"][i]))) * T
                    Ep = Ep + Ev * T / 2.0 + vT * h_t + h_p
                Ev = 0.0
        else:
            Ev = 0.0
        bv[i], bp[i] = Ev, Ep
    return bv, bp
