"""The third pass of ``accelcal displacement`` in chunks (:mod:`.displacement_stream`): the offline
form one motion at a time, holding the rows from the motion before it on.

Each motion is integrated and corrected when the rest that closes it is declared, as
:func:`~.displacement_host.displace_offline` does it over the whole recording; the rows before its
anchor are then final (no later motion reaches back past an anchor) and are written after
:func:`~.displacement_host.at_rest_not_moving`, the checks of the motion before it
(:func:`~.motion_checks.motion_errors`) and the still blocks in them
(:func:`~.displacement_checks.still_block`).  What would warn raises
:class:`~accelcal.io.chunks.Fallback`.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from ..io.chunks import Fallback
from .displacement import (A_FRAC, DISP_BAD_REF, DISP_LONG, DISP_MOVING, DISP_REST, DISP_SAT, DISP_SEG_END, P_FRAC,
                           V_FRAC, DisplaceParams, tilt_frame)
from .displacement_checks import HeldStretches, still_block, zp_text
from .displacement_host import at_rest_not_moving
from .motion_checks import ERROR_BOUND_COVERS, motion_errors, rotated_motions, turned_motions
from .rest import REST_AT_REST, REST_QUIET, motion_window, rest_run
from .trend import TREND_BLOCK_HOLDS, trend_bound, trend_widening

__all__ = ["NAMES", "MotionPass", "CoreMotionPass"]

NAMES = ["t", "v_x", "v_y", "v_z", "p_x", "p_y", "p_z", "p_raw_x", "p_raw_y", "p_raw_z", "rest", "corrected"]


class MotionPass:
    """The offline form's output, motion by motion (rows from ``B0`` held).

    Parameters
    ----------
    p : DisplaceParams
    n : int
        Samples in the recording.
    rho : ndarray (L, 3)
        The noise's correlation as the rests show it (:func:`~.trend.rest_correlation`).
    f_axes : ndarray (3,)
        The noise of f per body axis, m/s^2.
    g : float
        The device's gravity, m/s^2.
    alpha_sigma : float or None
        An array's alpha noise, rad/s^2 (its turns from the resolved alpha); None for a triad.
    """

    def __init__(self, p: DisplaceParams, n: int, rho: np.ndarray, f_axes: np.ndarray, g: float,
                 alpha_sigma: float | None) -> None:
        self.p, self.n, self.rho, self.g, self.alpha_sigma = p, n, rho, g, alpha_sigma
        self.f_axes = np.asarray(f_axes, float)
        self.f_sigma = float(np.max(self.f_axes))
        self.hold = int(p.rest.hold)
        self.L = max(2, TREND_BLOCK_HOLDS * self.hold)
        self.widen_L = trend_widening(rho, self.L)
        self.hold2 = max(self.hold, 2)
        self.offline = True
        self.extra: tuple = ()                    # a subclass's own per-row buffers
        self.B0 = 0
        self.t = np.zeros(0)
        self.f, self.v, self.pp, self.praw, self.acc = (np.zeros((0, 3)) for _ in range(5))
        self.alpha = np.zeros((0, 3))
        self.fl = np.zeros(0, np.uint8)
        self.atd, self.corr = np.zeros(0, bool), np.zeros(0, bool)
        self.frame = None                        # (g, R) of the first rest, 3-axis
        self.m0 = self.ref = None
        self.first_rest = None                   # global index of the first declaration
        self.s_cur = None                        # the motion going on: its first sample
        self.rest_r = None                       # the rest going on: where it began (dated back)
        self.pos, self.pos_raw = np.zeros(3), np.zeros(3)
        self.last = self.prev_end = 0
        self.written = 0
        self.sink: Any = None
        self.open_start: int | None = None        # the last motion's first sample when it does not end at rest
        self.cut: int | None = None               # the rows written, [0, cut), once that motion began
        self.pending = None                      # (anchor, end, zp, lo) of the motion before
        self.zps: list = []                      # each corrected motion's zp as the comment writes it
        self.errs: list = []                     # each one's error bound as the comment writes it
        self.next_block = 0
        self.keep = 0                             # the rows before are no longer needed (global)
        self.off = HeldStretches(self.hold2, p.rest.dev_max)
        self.turned = HeldStretches(self.hold2, p.rest.dev_max)

    def _acc(self, f: np.ndarray) -> np.ndarray:
        """The integrated acceleration of rows f, as displace_offline's (f - g) @ R.T."""
        if self.p.axis is not None:
            a = np.zeros((f.shape[0], 3))
            a[:, self.p.axis] = f[:, self.p.axis]
            return a
        g, R = self.frame
        # BLAS multiplies one row (gemv) with other roundings than many (gemm): a lone row goes in twice
        if f.shape[0] == 1:
            return ((np.repeat(f, 2, axis=0) - g) @ R.T)[:1]
        return (f - g) @ R.T

    def feed(self, t, f, alpha, fl, sink: Any, rows=None) -> None:
        """One chunk: its stamps (s), f ((n, 3), m/s^2), alpha (array) and rest flags; the final rows
        into ``sink`` (:class:`accelcal.io.result_sink.ColumnSink`)."""
        self.sink = sink
        m0 = self.fl.size
        z3 = np.zeros((f.shape[0], 3))
        self.t = np.concatenate([self.t, t])
        self.f = np.concatenate([self.f, f])
        if alpha is not None:
            self.alpha = np.concatenate([self.alpha, alpha])
        self.fl = np.concatenate([self.fl, fl])
        if rows is None:
            self.v, self.pp, self.praw = (np.concatenate([x, z3]) for x in (self.v, self.pp, self.praw))
        else:                                     # the core's v, p and p_raw (CoreMotionPass)
            self.v, self.pp, self.praw = (np.concatenate([x, y]) for x, y in zip((self.v, self.pp, self.praw),
                                                                                   rows[1:]))
        self.acc = np.concatenate([self.acc, self._acc(f) if self.offline and (
            self.frame is not None or self.p.axis is not None) else z3])
        self.corr = np.concatenate([self.corr, np.zeros(f.shape[0], bool)])
        at = (self.fl & REST_AT_REST) != 0
        self.atd = np.concatenate([self.atd, at[m0:]])
        prev = np.concatenate(([at[m0 - 1] if m0 else False], at[m0:]))
        if self.cut is not None:                  # the motion left out: its still blocks only
            self._blocks(self.B0 + self.fl.size)
            self._drop(self.next_block)
            return
        for gi in (np.flatnonzero(np.diff(prev.astype(np.int8))) + m0 + self.B0).tolist():
            if (self.fl[gi - self.B0] & REST_AT_REST) != 0:
                self._declared(gi)
            else:
                self._moving(gi)
        if self.cut is None:
            self._drop(self.keep)                 # once a chunk: a copy per motion would be chunk x motions

    def _declared(self, gi: int) -> None:
        i = gi - self.B0
        fl = self.fl
        r = i
        if fl[i] & REST_QUIET:                    # each rest from where its quiet run began
            while r > 0 and fl[r - 1] & REST_QUIET:
                r -= 1
            self.atd[r:i] = True
        r += self.B0
        if self.first_rest is None:
            self.first_rest = gi
        elif self.s_cur is not None:
            self._motion(self.s_cur, gi)
        self.rest_r = r
        self.s_cur = None

    def _moving(self, gi: int) -> None:
        i = gi - self.B0
        if self.first_rest is None:
            return
        self._trend(self.rest_r, gi)
        if self.frame is None and self.p.axis is None and self.offline:
            # the first rest: from its first sample (the recording's: the rest pass) to the first motion
            g = self.f[:i].mean(axis=0)
            self.frame = (g, tilt_frame(g))
            self.acc = self._acc(self.f)
        if self.m0 is None:
            self.m0 = self.f[:i].mean(axis=0)
            self.ref = self.f[self.atd][:max(self.p.rest.hold, 1)].mean(axis=0)
        if gi == self.open_start:
            self._open(gi)
        else:
            self.s_cur = gi

    def _open(self, s: int) -> None:
        """The last motion, from s (global), which does not end at rest: left out, the output cut at s
        (displace_offline integrates it from its anchor, whose rows before s are written)."""
        B0, p = self.B0, self.p
        if self.offline:
            pad = (2 ** p.rest.ema_shift) if p.pad is None else int(p.pad)
            W = self.prev_end
            at = (self.fl[W - B0:s - B0 + 1] & REST_AT_REST) != 0
            a_idx = motion_window(self.acc[W - B0:s - B0 + 1], at, s - W, 0, None, p.rest.dev_max / 5.0,
                                  1 if p.axis is not None else 3)[0] + W
            a_idx = max(a_idx - pad, self.prev_end)
            la, ll, ls = a_idx - B0, self.last - B0, s - B0
            self.pp[ll:la + 1] = self.pos
            self.praw[ll:la + 1] = self.pos_raw
            a = self.acc[la:ls]
            vv = np.vstack([np.zeros(3), np.cumsum(0.5 * p.dt * (a[1:] + a[:-1]), axis=0)])[:ls - la]
            pp = np.vstack([np.zeros(3), np.cumsum(0.5 * p.dt * (vv[1:] + vv[:-1]), axis=0)])[:ls - la]
            self.v[la:ls] = vv
            self.pp[la:ls] = self.pos + pp
            self.praw[la:ls] = self.pos_raw + pp
        self.finalize(s)
        self.cut = s

    def _trend(self, r: int, end: int) -> None:
        """The trend test of the rest [r, end) (global), as rest_without_trend: a trend, or a block
        shorter than L (its widening from the whole), goes the whole-file way."""
        hold = self.hold
        e = end - hold if end < self.n and end - r > 2 * hold else end
        starts = list(range(r, e, self.L))
        if len(starts) > 1 and e - starts[-1] < self.L:
            starts[-1] = e - self.L
        sig = np.broadcast_to(self.f_axes, (3,))
        for b in starts:
            c = min(b + self.L, e)
            if c - b < 2:
                continue
            if c - b != self.L:
                raise Fallback("a rest shorter than a trend block")
            slope = np.polyfit(np.arange(c - b, dtype=float), self.f[b - self.B0:c - self.B0], 1)[0]
            change = np.abs(slope) * (c - b - 1)
            bound = trend_bound(c - b, sig, self.widen_L)
            with np.errstate(divide="ignore", invalid="ignore"):
                ratio = np.where(bound > 0, change / bound, np.where(change > 0, np.inf, 0.0))
            if ratio[int(np.argmax(ratio))] > 1.0:
                raise Fallback("a rest holds a trend")

    def _motion(self, s: int, e: int) -> None:
        """The motion [s, e) (global), its closing rest declared at e: displace_offline's step."""
        B0, p = self.B0, self.p
        pad = (2 ** p.rest.ema_shift) if p.pad is None else int(p.pad)
        W = self.prev_end                         # the window [W, e]: what motion_window looks at
        at = (self.fl[W - B0:e - B0 + 1] & REST_AT_REST) != 0
        fq = e - p.rest.hold + 1
        a_idx, b = motion_window(self.acc[W - B0:e - B0 + 1], at, s - W, 0, fq - W, p.rest.dev_max / 5.0,
                                 1 if p.axis is not None else 3)
        a_idx, b = a_idx + W, b + W
        a_idx = max(a_idx - pad, self.prev_end)
        end = min(max(b + pad, s), e)
        la, le, ll = a_idx - B0, end - B0, self.last - B0
        self.pp[ll:la + 1] = self.pos
        self.praw[ll:la + 1] = self.pos_raw
        idx = np.arange(la, le + 1)
        a = self.acc[idx]
        dt = p.dt
        vv = np.vstack([np.zeros(3), np.cumsum(0.5 * dt * (a[1:] + a[:-1]), axis=0)])
        pp = np.vstack([np.zeros(3), np.cumsum(0.5 * dt * (vv[1:] + vv[:-1]), axis=0)])
        self.praw[idx] = self.pos_raw + pp
        T = (end - a_idx) * dt
        zp = vv[-1] / T
        tp = (idx - la) * dt
        self.v[idx] = vv - zp * tp[:, None]
        self.pp[idx] = self.pos + pp - 0.5 * zp * tp[:, None] ** 2
        self.corr[idx] = True
        self.pos = self.pp[le].copy()
        self.pos_raw = self.praw[le].copy()
        self.v[le] = 0.0
        lo = self.prev_end + 1 if self.zps else 0
        self.last, self.prev_end = end + 1, end
        self.zps.append(zp_text(zp))
        self._checked(a_idx, end, zp, lo)

    def _checked(self, a_idx: int, end: int, zp, lo: int) -> None:
        """The motion anchored at a_idx and ending at end (global) checked for a turn; the rows before
        its anchor finalized; the rows before the rest before it dropped."""
        B0, p, dt = self.B0, self.p, self.p.dt
        la, le = a_idx - B0, end - B0
        r = rest_run(self.atd, la, 0, la)[0]      # the rest before it began (dated back)
        w = slice(r, le + 1)                      # what the checks look at: that rest and the motion
        if turned_motions(self.f[w], self.atd[w], [(la - r, le - r, zp)], self.f_sigma, p.rest, p.axis, self.m0):
            raise Fallback("a turned motion")
        if self.alpha_sigma is not None and rotated_motions(self.alpha[w], self.atd[w], [(la - r, le - r, zp)], dt,
                                                            self.alpha_sigma):
            raise Fallback("a rotated motion")
        self.finalize(a_idx)
        self.pending = (a_idx, end, zp, lo)
        self.keep = min(lo, B0 + r, a_idx, self.next_block)     # dropped once the chunk is done

    def finalize(self, upto: int) -> None:
        """Rows [written, upto) are final: at_rest_not_moving, the motion before's error bound, the
        still blocks; written."""
        w, u = self.written - self.B0, upto - self.B0
        at_rest_not_moving(self.atd[w:u], self.corr[w:u], self.v[w:u], self.pp[w:u], self.praw[w:u])
        if self.pending is not None:
            a, e, zp, lo = self.pending
            L0 = lo - self.B0
            err = motion_errors(self.f[L0:u], self.pp[L0:u], self.atd[L0:u], [(a - lo, e - lo, zp)], self.f_axes,
                                self.p.dt, self.p.axis, self.rho)[0]
            if not err[3] <= err[2] - err[3]:
                raise Fallback("a motion longer than the correction holds")   # motion_error_warnings
            self.errs.append(f"{err[2]:.3g}")
        self._blocks(upto)
        v, pp, pr = self.v[w:u], self.pp[w:u], self.praw[w:u]
        self.sink.write([self.t[w:u], v[:, 0], v[:, 1], v[:, 2], pp[:, 0], pp[:, 1], pp[:, 2], pr[:, 0], pr[:, 1],
                         pr[:, 2], self.atd[w:u].astype(float), self.corr[w:u].astype(float)])
        self.written = upto

    def _blocks(self, upto: int) -> None:
        """The still blocks ending by ``upto`` (global), as still_off_g and still_but_turned take them."""
        rp = self.p.rest
        while self.next_block + self.hold2 <= upto:
            j = self.next_block - self.B0
            got = still_block(self.f[j:j + self.hold2], self.atd[j:j + self.hold2], rp)
            if got is not None:
                m, off = got
                if off and rp.g is not None and self.off.feed(self.next_block, m):
                    raise Fallback("a still stretch off g")
                if not off and float(np.linalg.norm(m - self.ref)) > rp.ref_max and \
                        self.turned.feed(self.next_block, m):
                    raise Fallback("a still stretch turned")
            self.next_block += self.hold2

    def _tail(self) -> None:
        """The rows after the last motion: at its end point."""
        ll = self.last - self.B0
        self.pp[ll:] = self.pos
        self.praw[ll:] = self.pos_raw

    def _drop(self, keep: int) -> None:
        k = keep - self.B0
        if k <= 0:
            return
        for name in ("t", "f", "v", "pp", "praw", "acc", "fl", "atd", "corr") + self.extra:
            setattr(self, name, getattr(self, name)[k:].copy())
        if self.alpha.shape[0]:
            self.alpha = self.alpha[k:].copy()
        self.B0 = keep

    def finish(self, sink: Any) -> dict:
        """The last rest and the rows after the last motion's anchor; the metadata."""
        if self.rest_r is None or self.s_cur is not None or not self.zps:
            raise Fallback("no motion closed by a rest")
        self.sink = sink
        if self.cut is None:
            self._trend(self.rest_r, self.n)
            self._tail()
            self.finalize(self.n)
        else:
            self._blocks(self.n)
        if self.off.finish() or self.turned.finish():
            raise Fallback("a still stretch off g or turned")
        return {"segments": str(len(self.zps)),
                "zero_point_mps2": "; ".join(self.zps),
                "error_bound_m": "; ".join(self.errs),
                "error_bound_covers": ERROR_BOUND_COVERS}


class CoreMotionPass(MotionPass):
    """The streaming form motion by motion, the C core's (engine ``fixed``, ``fixed`` True) or its
    float reference's (engine ``float``, form ``stream``): their v and p (:class:`~.displacement.DispCore`,
    :class:`~.displacement.DispFloat`, their state carried by the caller), each closed motion's
    path corrected on the host as :func:`~.displacement_host.retro_correct` does, p_raw with the end
    corrections added back as the whole-file command adds them; the checks and rows of
    :class:`MotionPass`.  ``step_dt``: the core's dt as stored (s)."""

    def __init__(self, *args, step_dt: float, fixed: bool = True) -> None:
        super().__init__(*args)
        self.offline, self.fixed = False, fixed
        self.step_dt = step_dt
        self.extra = ("zq", "dfl")
        self.zq, self.dfl = np.zeros((0, 3)), np.zeros(0, np.int64)
        self.dsum = np.zeros((1, 3))             # the end corrections added back so far

    def feed_core(self, t, f, alpha, core: dict, sink: Any) -> None:
        """One chunk: stamps (s), f ((n, 3), m/s^2), alpha, and the core's outputs (v, p, zp: int arrays
        of the C core, or floats; nseg, flags, rest)."""
        fl = core["flags"]
        if np.any(fl & (DISP_SAT | DISP_BAD_REF)):
            raise Fallback("samples clipped in the core, or no frame")       # warned, the whole-file way
        if self.fixed:
            vq, pq, zq = core["v"] / 2.0**V_FRAC, core["p"] / 2.0**P_FRAC, core["zp"] / 2.0**A_FRAC
        else:
            vq, pq, zq = core["v"], core["p"], core["zp"]
        D = np.zeros((fl.size, 3))
        for e in np.flatnonzero((fl & DISP_SEG_END) != 0).tolist():
            if fl[e] & DISP_LONG:
                raise Fallback("a motion beyond the core's count")
            T = int(core["nseg"][e]) * self.step_dt
            D[e] = 0.5 * np.asarray(zq[e], float) * T * T
        cum = np.cumsum(np.concatenate([self.dsum, D]), axis=0)[1:]
        if fl.size:
            self.dsum = cum[-1:].copy()
        rest = ((fl & DISP_REST) != 0) * REST_AT_REST | ((core["rest"] & REST_QUIET) != 0) * REST_QUIET
        n0 = self.fl.size
        self.zq = np.concatenate([self.zq, zq])
        self.dfl = np.concatenate([self.dfl, fl])
        self.feed(t, f, alpha, rest.astype(np.uint8), sink, rows=(n0, np.array(vq, float), np.array(pq, float),
                                                                   np.array(pq, float) + cum))

    def _tail(self) -> None:
        pass

    def _motion(self, s: int, e: int) -> None:
        """The motion [s, e) (global), closed at e: retro_correct's step."""
        B0, p = self.B0, self.p
        a = s - 1
        if a <= self.prev_end and self.zps:
            raise Fallback("a motion from the sample its rest was declared at")
        la, ls, le = a - B0, s - B0, e - B0
        if not self.dfl[le] & DISP_SEG_END or not self.dfl[ls] & DISP_MOVING:
            raise Fallback("a motion the core did not segment as the detector")
        z = np.asarray(self.zq[le], float)
        tp = self.t[ls:le] - self.t[la]
        self.v[ls:le] -= z * tp[:, None]
        self.pp[ls:le] -= 0.5 * z * tp[:, None] ** 2
        self.corr[ls:le + 1] = True
        lo = self.prev_end + 1 if self.zps else 0
        self.prev_end = e
        self.zps.append(zp_text(self.zq[le]))
        self._checked(a, e, self.zq[le], lo)
