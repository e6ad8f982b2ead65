"""The displacement's host forms: the offline estimator (:func:`displace_offline`), the
seed's correction applied to the streamed path between rests (:func:`retro_correct`), and
the recording form behind ``accelcal displacement`` (:func:`displacement_from_recording`;
its checks for the warnings in :mod:`.displacement_checks` and :mod:`.motion_checks`).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import AccelcalError, InputError
from ..readings.noise import code_step, states_noise
from ..io.recording import check_core_input, check_for_device
from .common import (CLIP, CLIP_LO, OUT_FRAC, Columns, alpha_noise, channel_noise, force_noise,
                     force_noise_axes, resolve_array, time_span, uniform_dt)
from .omega_fixed import estimator_omega
from .timegrid import RESAMPLE_BRIDGE_SAMPLES, on_uniform_grid, resampled
from .displacement import (A_FRAC, DISP_LONG, DISP_MOVING, DISP_NO_REST, DISP_OPEN, DISP_REST, DISP_SAT,
                           DISP_SEG_END, P_FRAC, V_FRAC, DisplaceParams, displace_fixed, displace_stream,
                           tilt_frame)
from .displacement_checks import (REST_DEV_WARN_MPS2, final_trend_note, no_rest_reason, still_but_turned, still_off_g,
                                  still_off_g_text, streamed_off_g, trend_warnings, wide_rest_warning, zp_text)
from .motion_checks import (ERROR_BOUND_COVERS, motion_error_warnings, motion_errors, rotated_motions, rotated_text,
                            turned_motions, turned_text, turned_warnings)
from .rest import (REST_AT_REST, REST_QUIET, RestParams, default_rest_params, motion_window, rest_dated_back,
                   rest_detect, rest_on_g)
from .trend import TREND_BLOCK_HOLDS, rest_correlation, rest_without_trend
from ..firmware.triad import triad_forces

__all__ = ["RESAMPLE_HINT", "retro_correct", "displace_offline", "displacement_from_recording"]

#: the remedy a refusal of stamps off the grid names here
RESAMPLE_HINT = ("; if the samples were taken at their stamps (a sensor read on a loop whose period varies, a driver "
                 "that stamps each one as it reads it) or the stamps stray by less than a step, and no more than "
                 f"{RESAMPLE_BRIDGE_SAMPLES} sample in a row was lost, accelcal displacement --resample interpolates "
                 "them onto a uniform grid")


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
    """Host offline form (float): the rest detector's segments, each dated from the rests' own
    levels (:func:`motion_window`: the first samples of a smooth start, which the detector lags,
    are integrated; the final rest's samples before its detector settled are not) and widened by
    ``pad`` samples at each end; gravity and the frame from the mean of the whole first rest; the
    correction over the whole path.
    Returns v, p (corrected), v_raw, p_raw (uncorrected: same segments, no zero-point
    correction), rest (n,) bool (as declared), quiet (n,) bool (the detector's quiet samples),
    corrected (n,) bool, segments [(anchor, end, zp)], frame, open (a motion still going at the
    end), no_rest."""
    f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
    n = f.shape[0]
    dt = p.dt
    if rest_flags is None:
        # the streaming detector (with its reference test once the first rest is known)
        rest_flags = displace_stream(f, p)["rest"]
    at = (np.asarray(rest_flags) & REST_AT_REST) != 0
    quiet = (np.asarray(rest_flags) & REST_QUIET) != 0
    pad = (2 ** p.rest.ema_shift) if p.pad is None else int(p.pad)
    sigma = p.rest.dev_max / 5.0                # the rest test is 5 sigma of f's noise (default_rest_params)
    res = dict(v=np.zeros((n, 3)), p=np.zeros((n, 3)), v_raw=np.zeros((n, 3)), p_raw=np.zeros((n, 3)),
               rest=at.copy(), quiet=quiet, corrected=np.zeros(n, bool), segments=[], frame=None, open=False,
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
    prev_end = rs                               # the earliest a motion's window may start
    last = first_rest
    for s, e in runs:
        fq = None if e < 0 else e - p.rest.hold + 1     # first quiet sample of the final rest
        a_idx, b = motion_window(acc, at, s, prev_end, fq, sigma, 1 if p.axis is not None else 3)
        a_idx = max(a_idx - pad, prev_end)          # anchor: at rest, before the motion
        if e < 0:
            end, closed = n - 1, False
        else:
            end, closed = min(max(b + pad, s), e), True
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


def _offline_rests(f, p: DisplaceParams):
    """The offline form's rest decisions: the detector's flags (n,), its rests (each from where it
    began) whose mean |f| lies within g_tol of g, and those that do not (:func:`.rest.rest_on_g`).
    The detector takes the first rest's mean f for its reference, which every later rest must match:
    when that first rest is off g (left out), the detector runs again from the first still stretch
    on g (as the detector finds them without a reference), so that this one sets the reference."""
    flags = displace_stream(f, p)["rest"]

    def decided(fl):
        return rest_on_g(rest_dated_back((fl & REST_AT_REST) != 0, (fl & REST_QUIET) != 0, f, p.rest), f, p.rest)

    kept, off = decided(flags)
    if off and (not kept.any() or off[0][0] < int(np.argmax(kept))):
        free = rest_detect(f, p.rest)[0]
        on_g = decided(free)[0]
        if on_g.any():
            s = int(np.argmax(on_g))
            flags = np.concatenate([flags[:s], displace_stream(f[s:], p)["rest"]])
            kept, off = decided(flags)
    return flags, kept, off


def at_rest_not_moving(at, corrected, v, p, p_raw) -> None:
    """A sample is either part of a motion or of a rest: where a motion's integration runs over
    rest samples (the closing rest's first samples, up to its declaration hold samples after it
    began, and offline the pad; offline the anchor and pad before the motion too) those are
    reported at rest, in place: corrected 0, v = 0, and p, p_raw held at the motion's end point
    (a closing rest: its value at the declaration, where the correction ends) or at its start (an
    opening rest).  The motion's corrected span ends where its rest began.

    Parameters
    ----------
    at, corrected : ndarray (n,) bool
        At rest (dated back); corrected (changed in place).
    v, p, p_raw : ndarray (n, 3)
        m/s, m, m (changed in place).
    """
    both = np.asarray(at, bool) & corrected
    moving = corrected & ~both
    for a, b in _motion_runs(~both):
        k = b - 1 if a > 0 and moving[a - 1] else a          # after a motion: its end; else its start
        p[a:b] = p[k]
        p_raw[a:b] = p_raw[k]
        v[a:b] = 0.0
        corrected[a:b] = False


def _body_forces(device, cal, rec, engine, est=None):
    """f at the origin (6-DOF array: no rotation assumed, or the centripetal term of ``est``, the
    array's own omega) or at the first triad: (n,3) float m/s^2 (float) or int32 Q.10 (fixed), and
    a note for the metadata."""
    if device.is_array():
        f, _ = resolve_array(device, cal, rec, engine, None if est is None else est.for_resolver())
        return f, ("resolved f at the body origin" + (" (C core)" if engine == "fixed" else "")
                   + ("" if est is None else ", the centripetal term of the array's own omega"))
    tri = device.triads()
    if tri:
        f, _ = triad_forces(cal, rec, tri[0], engine, device.raw_min < 0)
        return f, "f of the triad at channels 0-2"
    raise InputError(device.name, "displacement needs a 6-DOF array or a device with a 3-axis sensor "
                     "(a triad at channels 0-2)")


def _axis_arg(axis) -> int | None:
    if axis is None or axis in ("3d", "xyz", "all"):
        return None
    m = {"x": 0, "y": 1, "z": 2, 0: 0, 1: 1, 2: 2}
    if axis not in m:
        raise AccelcalError(f"displacement axis {axis!r}: expected x, y, z or none (3-axis)")
    return m[axis]


def _left_out(t, at, closed, long_anchors, is_open, turns, rec, open_note=""):
    """Where the output ends: at the first motion that cannot be reported (one that does not end at
    rest, one longer than the fixed core counts, or, in ``turns``, one the body turned in), which is
    left out with everything after it (their positions would carry its unknown displacement).

    Parameters
    ----------
    t : ndarray (n,)
        s.
    at : ndarray (n,) bool
        At rest (dated back).
    closed : list of (int, int, array_like)
        The corrected motions: anchor (a rest sample before it), end sample, zp.
    long_anchors : list of int
        The anchors of the motions too long to be corrected.
    is_open : bool
        The last motion does not end at rest.
    turns : list of (int, str)
        The turned motions to leave out: anchor, and why (:func:`.motion_checks.turned_text`,
        :func:`.motion_checks.rotated_text`).
    open_note : str
        Added to the line of a last motion that does not end at rest (why its end is no rest).

    Returns
    -------
    cut : int
        The rows kept, [0, cut) (n: all).
    line : str or None
        What was left out and why, for the user.
    kept : list of (int, int, array_like)
        The motions of ``closed`` reported.
    """
    n = len(t)
    at = np.asarray(at, bool)

    def start(a: int) -> int:             # the motion's first sample not at rest after its anchor a
        return a + 1 + int(np.argmin(at[a + 1:])) if a + 1 < n and not at[a + 1:].all() else min(a + 1, n)

    cands = [(start(a), words + "; the stop-to-stop method assumes the same attitude at both rests: it is left "
              "out (--keep-turned writes it, with a warning)") for a, words in turns]
    cands += [(start(a), f"the motion from {time_span(t, start(a), rec=rec)} is longer than 65535 samples, the fixed "
               "core's count, and has no zero-point correction: it is left out (the float engine's offline form has "
               "no such limit)") for a in long_anchors]
    starts = [start(m[0]) for m in closed] + [start(a) for a in long_anchors]
    if is_open:
        rest_idx = np.flatnonzero(at)
        s = int(rest_idx[-1]) + 1 if rest_idx.size else 0
        starts.append(s)
        cands.append((s, f"the last motion ({time_span(t, s, n - 1, rec)}) does not end at rest: without a rest at its "
                      "end its zero point cannot be removed (its drift grows with time squared), so it is left out"
                      + open_note))
    if not cands:
        return n, None, list(closed)
    cut, line = min(cands, key=lambda c: c[0])
    kept = [m for m in closed if start(m[0]) < cut]
    after = sum(1 for s in starts if s > cut)
    if after:
        line += (f"; the {after} motion(s) after it are not reported either (their positions would carry its "
                 "displacement)")
    if kept:
        line += f"; the output ends at {time_span(t, cut - 1, rec=rec)}, in the rest before it"
    return cut, line, kept


def displacement_from_recording(device, cal, rec, engine: str = "float", *, form: str | None = None,
                                axis=None, rest: RestParams | None = None, keep_turned: bool = False,
                                resample: bool = False, omega: str = "auto") -> Columns:
    """`accelcal displacement`: columns t, v_x, v_y, v_z, p_x, p_y, p_z (frame of the first rest,
    z up, gravity removed; corrected between rests) plus p_raw_* (the same without the zero-point
    correction), rest (1 at rest: each rest from where it began, :func:`.rest.rest_dated_back`, not
    from where the detector declared it hold samples later) and corrected (1 on the samples of a
    motion closed by a rest, whose correction was applied: its integration runs to the rest's
    declaration, over the rest's first samples in the stream forms, pad samples past its first quiet
    sample offline; 0 at rest otherwise).

    engine "float": form "offline" (default) or "stream" (the float twin of the firmware form);
    engine "fixed": the C streaming form (ac_disp), with the path between rests corrected on the
    host from the core's per-motion zero-point estimate.  ``axis`` x/y/z: 1-D along that body
    axis (the seed's case: nothing removed).  A motion is reported only with a rest at both ends
    (its zero point removed) and no turn between them (:func:`.motion_checks.turned_motions`;
    ``keep_turned``: reported with a warning): the first that is not (the last motion that never
    stops, one the body turned in, one beyond the fixed core's count) ends the output, at the rest
    before it, with a warning naming it.  Errors: no rest at all (nothing can be anchored), or
    motions none of which can be reported.  Flagged (warning, rows 0): a recording that does not
    start at rest (the part before the first rest is not estimated).
    Samples a logger dropped are filled first (:func:`~.timegrid.on_uniform_grid`: warning and
    column ``filled``); ``resample``: the samples are first interpolated from their stamps onto a
    uniform grid (:func:`~.timegrid.resampled`: stamps that keep no grid; a gap of one lost sample
    bridged, with a warning and column ``filled``).  ``omega`` (an array's f): "array" resolves f with the
    centripetal term of the array's own omega (:func:`~.omega_fixed.estimator_omega`; engine "fixed": the
    C core's), refused with the observability line on a layout that does not observe it; "auto" does so
    where the layout observes omega and the recording has no complete w columns; "none": no centripetal
    term (the default before)."""
    if engine not in ("float", "fixed"):
        raise ValueError(f"unknown engine {engine!r}")
    form = form or ("offline" if engine == "float" else "stream")
    if form not in ("offline", "stream") or (engine == "fixed" and form != "stream"):
        raise ValueError(f"form {form!r} with engine {engine!r}: fixed has only 'stream'")
    check_for_device(rec, device, min_samples=2)
    ax = _axis_arg(axis)
    if engine == "fixed":
        check_core_input(rec, device.raw_min < 0)
    re_note, bridged = None, None
    if resample:
        rec, re_note, bridged = resampled(rec)
    rec, filled, fill_note = on_uniform_grid(rec, RESAMPLE_HINT)
    if bridged is not None and bridged.size == filled.size:
        filled = filled | bridged
    dt = uniform_dt(rec)
    est = estimator_omega(device, cal, rec, omega, engine)
    f, note = _body_forces(device, cal, rec, engine, est)
    noise = channel_noise(device, rec)
    channels = None if device.is_array() else device.triads()[0]
    f_axes = force_noise_axes(device, cal, noise, channels)       # per body axis, m/s^2
    f_sigma = float(np.max(f_axes))
    rp = rest or default_rest_params(device, 1.0 / dt, f_sigma=f_sigma)
    p = DisplaceParams(dt=dt, axis=ax, rest=rp)
    t = np.asarray(rec.t, float)
    n = len(t)
    warnings = [f"displacement: {w}" for w in (re_note, fill_note) if w]
    if rest is None and rp.dev_max > REST_DEV_WARN_MPS2 and not states_noise(device):
        # the code step through the calibration: coarse codes widen the test of a sensor at rest
        q_f = force_noise(device, cal, [code_step(c) for c in np.asarray(rec.raw).T], channels)
        warnings += wide_rest_warning(rp.dev_max, q_f)
    checked = len(warnings)             # the warnings from here on are the recording's, said in a refusal too
    if engine == "float" and form == "offline":
        flags, kept, off_rests = _offline_rests(f, p)
        declared = (flags & REST_AT_REST) != 0
        # each rest tested for a trend from where it began (the detector declares it hold samples
        # later: a rocket's 0.36 s "rest" mid-flight held 12 declared samples and 36 in all)
        kept, trends = rest_without_trend(kept, f, rp, f_axes)
        gone = declared & ~kept
        r = displace_offline(f, p, np.where(gone, flags & ~(REST_AT_REST | REST_QUIET), flags))
        tw = trend_warnings(t, trends, rp, False, rec)
        warnings += tw
        open_note = final_trend_note(t, trends, kept, rec)
        if r["no_rest"]:
            off = still_off_g(f, np.zeros(n, bool), rp) if trends or off_rests else None
            raise InputError(rec.source, "displacement: no rest was detected anywhere in the recording "
                             f"(rest = |f - mean| <= {rp.dev_max:.3g} m/s^2 for {rp.hold} samples"
                             + (f" with a mean |f| within {rp.g_tol:g} of {rp.g:g} m/s^2" if rp.g is not None else "")
                             + "): " + ("; ".join([w.removeprefix("displacement: ") for w in tw]
                                                  + ([still_off_g_text(t, off, rp, rec, cal)] if off else []))
                                        or no_rest_reason(f, t, rp, cal))
                             + "; the stop-to-stop method needs a rest at both ends of each motion")
        v, pp, p_raw = r["v"], r["p"], r["p_raw"]
        at, quiet, corrected = r["rest"], r["quiet"], r["corrected"]
        is_open = r["open"]
        closed = [s for s in r["segments"] if s[2] is not None]
        long_anchors = []
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
            raise InputError(rec.source, "displacement: no rest was detected anywhere in the recording: "
                             f"{no_rest_reason(f / 2.0**OUT_FRAC if engine == 'fixed' else f, t, rp, cal)}"
                             "; the stop-to-stop method needs a rest at both ends of "
                             "each motion")
        v, pp, corrected = retro_correct(t, vq, pq, fl, zq)
        # uncorrected path: add back each end correction zp T^2 / 2 from its sample on
        D = np.zeros((n, 3))
        step_dt = r["dt"] if engine == "fixed" else dt
        for s_, e in _segments_from_flags(fl):
            if e >= 0 and not fl[e] & DISP_LONG:
                T = int(r["nseg"][e]) * step_dt
                D[e] = 0.5 * np.asarray(zq[e], float) * T * T
        p_raw = np.array(pq, float) + np.cumsum(D, axis=0)
        at, quiet = (fl & DISP_REST) != 0, (r["rest"] & REST_QUIET) != 0
        f_rest = f if engine == "float" else np.asarray(f, float) / 2.0**OUT_FRAC
        warnings += streamed_off_g(t, at, quiet, f_rest, rp, rec, cal)
        warnings += trend_warnings(t, rest_without_trend(rest_dated_back(at, quiet, f_rest, rp), f_rest, rp,
                                                         f_axes)[1], rp, True, rec)
        is_open = fin_open
        segs = [(s - 1, e) for s, e in _segments_from_flags(fl) if e >= 0]
        closed = [(a, e, zq[e]) for a, e in segs if not fl[e] & DISP_LONG]
        long_anchors = [a for a, e in segs if fl[e] & DISP_LONG]
        open_note = ""
    f_host = f if engine == "float" else np.asarray(f, float) / 2.0**OUT_FRAC
    declared = int(np.argmax(at)) if np.any(at) else n
    # each rest from where it began, not from the detector's declaration hold samples later
    at = rest_dated_back(at, quiet, f_host, rp)
    at_rest_not_moving(at, corrected, v, pp, p_raw)
    first_at = int(np.argmax(at)) if np.any(at) else n
    # a still stretch kept from being a rest by its |f| (the scale), said once: where the recording
    # does not start at rest when it lies before the first rest, else on its own
    off = still_off_g(f_host, at, rp)
    off_words = [] if off is None else [still_off_g_text(t, off, rp, rec, cal)]
    if first_at > 0:
        before = off_words if off is not None and off[0] < first_at else []
        warnings.append(f"displacement: the recording does not start at rest: nothing is estimated before the "
                        f"first rest (from {time_span(t, min(first_at, n - 1), rec=rec)}, declared at "
                        f"{time_span(t, min(declared, n - 1))}; rows before are 0)" + "".join("; " + w for w in before))
        off_words = [w for w in off_words if w not in before]
    warnings += ["displacement: " + w for w in off_words]
    g = float(device.gravity_mps2)
    # a motion is reported only with a rest at both ends and no turn between them (the stop-to-stop
    # method's assumptions); the first that is not ends the output.  A 6-DOF array measures its turn
    # (from the resolved alpha); a triad's shows in the motion's zero point
    turns = [(x[0], turned_text(t, x, g, rec)) for x in turned_motions(f_host, at, closed, f_sigma, rp, ax)]
    if device.is_array():
        turns += [(x[0], rotated_text(t, x, rec)) for x in rotated_motions(
            resolve_array(device, cal, rec, "float", None if est is None else est.w)[1], np.asarray(at, bool), closed,
            dt, alpha_noise(device, cal, noise))]
    if keep_turned:
        warnings += turned_warnings(sorted(turns))
    cut, left_out, kept = _left_out(t, at, closed, long_anchors, is_open, [] if keep_turned else turns, rec,
                                    open_note)
    zps = [z for _, _, z in kept]
    # the noise's correlation as the rests show it widens what the noise leaves of each motion
    rho = rest_correlation(at, f_host, max(2, TREND_BLOCK_HOLDS * rp.hold), rp.hold)
    errs = motion_errors(f_host, pp, at, kept, f_axes, dt, ax, rho)
    warnings += motion_error_warnings(t, errs, f_sigma, dt, g, rec)
    turned = still_but_turned(f_host, at, rp)
    still_turned = None
    if turned is not None:
        ang, a0, a1 = turned
        still_turned = (f"the body is still at {time_span(t, a0, a1, rec)} (the first such stretch) but turned from the "
                        f"first rest (by up to {ang:.1f} deg over the recording): an accelerometer alone cannot tell a "
                        "turn from an acceleration, so gravity leaks into the path from there on (up to "
                        f"{2 * math.sin(math.radians(ang) / 2) * g:.3g} m/s^2) and such a stretch is not taken as a "
                        "rest; the result after it is not valid")
    if left_out is not None:
        warnings.append("displacement: " + left_out)
    if still_turned is not None:
        warnings.append("displacement: " + still_turned)
    if left_out is not None and not kept:
        raise InputError(rec.source, "displacement: no motion can be reported: " + "; ".join(
            [left_out] + [w.removeprefix("displacement: ") for w in warnings[checked:] if w != "displacement: " + left_out])
            + "; the stop-to-stop method needs a rest at both ends of each motion, at the same attitude")
    meta = {"engine": engine, "form": form, "device": device.name, "signal": note,
            "mode": "3-axis, gravity removed in the frame of the first rest" if ax is None else
            f"1-D along body {'xyz'[ax]}", "segments": str(len(zps))}
    if zps:
        meta["zero_point_mps2"] = "; ".join(zp_text(z) for z in zps)
        meta["error_bound_m"] = "; ".join(f"{x[2]:.3g}" for x in errs)
        meta["error_bound_covers"] = ERROR_BOUND_COVERS
    k = slice(0, cut)
    cols = Columns(t=t[k], v_x=v[k, 0], v_y=v[k, 1], v_z=v[k, 2], p_x=pp[k, 0], p_y=pp[k, 1], p_z=pp[k, 2],
                   p_raw_x=p_raw[k, 0], p_raw_y=p_raw[k, 1], p_raw_z=p_raw[k, 2],
                   rest=np.asarray(at[k], float), corrected=np.asarray(corrected[k], float),
                   **({"filled": filled[k].astype(float)} if filled[k].any() else {}),
                   warnings=warnings, meta=meta)
    return cols
