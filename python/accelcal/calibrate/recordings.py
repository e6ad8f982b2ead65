"""The entry point the command line uses: recordings in, a Calibration out."""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ..errors import InputError
from ..readings.held import distinct_recordings
from ..readings.static import (MIN_POSE_S, NO_POSE, STATIC_THRESHOLD, STATIC_WINDOW_S, PoseSet, at_gravity, detect_static,
                      no_pose, one_wrong_scale, poses_from_recording, window_len)
from .checks import jig_accuracy_rad, min_poses, pose_label, static_force, undetermined_tempcos
from .jig_estimate import fit_estimating_jig
from .known_poses import fit_known_poses
from .pose_stream import Reduced
from .outliers import outlier_poses, outlier_report, subset
from .lever_arms import calibrate_positions
from .results import pose_names, set_aside_entry, to_calibration
from .stated_poses import check_stated_poses, pose_titles
from .settings import ADD_POSES, JIG_ACCURACY_AUTO, JIGFREE_MODELS, METHODS, ROTATION_MIN_RADPS, TEMP_MIN_SPAN_C
from .static_model import fit_static


def calibrate_recordings(device, recordings: Sequence[Any], method: str | None = None, *,
                         jig_accuracy_deg: float | str = JIG_ACCURACY_AUTO, jigfree_model: str = "auto",
                         drop_outliers: bool = False, min_static_s: float = MIN_POSE_S):
    """Calibrate ``device`` from recordings and return a Calibration.

    Static poses: a recording's ``pose`` labels when present, else automatic static
    detection.  Method: ``offset``/``gain``/``full`` need reference f_* on the poses
    (known poses); ``jigfree`` ignores any reference.  Default: ``full`` when every
    pose has a reference, ``jigfree`` when none has.  ``jig_accuracy_deg``: rms
    rotation angle by which the jig's poses may differ from their references
    (known poses only; see the module notes; 0 = exact references); the default,
    ``"auto"``, estimates it from the poses' scatter about the fit and uses it where a
    perfect jig is rejected (:mod:`accelcal.calibrate.jig_estimate`; the calibration's
    ``extra["fit"]["jig_accuracy_estimate"]``).
    ``jigfree_model`` (jig-free only): the channel model, ``full``, ``gain`` or ``offset``;
    ``auto`` (the default) is ``full``, or, where the poses do not determine it (too few
    orientations, a degenerate spread, no convergence), the first of ``gain`` and ``offset``
    they do, with the reason in ``extra["fit"]["fallback"]``.
    Temperature coefficients are fitted when the pose temperatures span at least
    TEMP_MIN_SPAN_C and the fit determines them (:func:`accelcal.calibrate.checks.undetermined_tempcos`;
    else the fit without them, the reason in ``extra["fit"]["temperature_dropped"]``); lever arms
    when samples rotate (|w| > ROTATION_MIN_RADPS) with
    reference f, w and dw.  Readings held for several rows by a logger faster than the
    sensor are counted once (:func:`accelcal.readings.held.distinct_recordings`; the calibration's
    ``extra["notes"]`` says so).  Of several recordings, one without a static pose adds none
    and is named in those notes; with no pose in any, InputError.  Poses far off the fit
    (:mod:`accelcal.calibrate.outliers`) are named in ``extra["outliers"]`` with the fit's
    change without them; ``drop_outliers`` leaves them out (set aside, "far off the fit").
    ``min_static_s``: the shortest still stretch the static detector takes for a pose where a
    motion touches it (seconds; default MIN_POSE_S, a pause in a hand's movement being none;
    below the detector's window it acts as the window).  Known poses whose readings, through the
    device file's scale and axes, point beyond what a device within its description allows from
    their stated f are refused before the fit, naming the pose (mislabelled) or, where most do or
    one reversed axis explains them, the device file (:mod:`accelcal.calibrate.stated_poses`).
    """
    auto = isinstance(jig_accuracy_deg, str) and jig_accuracy_deg == JIG_ACCURACY_AUTO
    if not auto:
        jig_accuracy_rad(jig_accuracy_deg)
    if not (np.isfinite(min_static_s) and min_static_s >= 0):
        raise InputError("<arguments>", f"minimum static stretch {min_static_s!r}: expected a finite number of "
                         "seconds >= 0", field="min_static_s")
    if jigfree_model not in JIGFREE_MODELS:
        raise InputError("<arguments>", f"unknown jig-free model {jigfree_model!r}; expected one of "
                         f"{', '.join(JIGFREE_MODELS)}", field="jigfree_model")
    if method is not None and method not in METHODS + ("jigfree",):
        raise InputError("<arguments>", f"unknown method {method!r}; expected one of "
                         f"{', '.join(METHODS + ('jigfree',))}", field="method")
    if not recordings:
        raise InputError("<arguments>", "no recording given")
    recordings = list(recordings)
    if all(isinstance(rec, Reduced) for rec in recordings):   # reduced while read: no held rows, the device's rate
        notes: list[str] = []
    else:
        recordings, device, notes = distinct_recordings(recordings, device)
    rotating = [np.zeros(1, bool) if isinstance(rec, Reduced) else rotating_samples(rec) for rec in recordings]
    # with several recordings, one without a static pose (a motion, a sweep) adds none and is named
    several = len(recordings) > 1
    try:
        sets = [rec.poses if isinstance(rec, Reduced) else
                poses_from_recording(rec, device, required=not (rot.any() or several), min_s=min_static_s)
                for rec, rot in zip(recordings, rotating)]
    except InputError as e:
        if not e.detail.startswith(NO_POSE):
            raise
        raise InputError(e.source, with_detector_hint(e.detail, device, recordings, None, min_static_s),
                         field=e.field) from None
    for rec, rot, ps in zip(recordings, rotating, sets):
        if several and not rot.any() and ps.n_poses == 0:
            clipped = (f" ({len(ps.set_aside)} set aside: "
                       f"{', '.join(sorted({setaside_reason(d) for d in ps.set_aside}))})" if ps.set_aside else "")
            notes.append(f"{rec.source}: {no_pose(min_static_s)}{clipped}: it adds none")
    poses = PoseSet.concat(sets)
    if poses.n_poses == 0:
        why = (f" ({len(poses.set_aside)} set aside because "
               f"{' or '.join(sorted({setaside_reason(d) for d in poses.set_aside}))}: "
               + "; ".join(f"{set_aside_entry(d)['name']} ({d['levels']})" for d in poses.set_aside[:3]) + ")"
               if poses.set_aside else "")
        scale = one_wrong_scale(poses.set_aside)
        hint = (f"; {'they' if len(poses.set_aside) > 1 else 'it'} agree at |f| = {scale:.3g} g: the readings' scale "
                "is off by that factor, not a free fall (readings in m/s^2 read as g give 9.81 g, in mm/s^2 read as m/s^2 "
                "1000 g: Klipper's files, --units mmps2): check --units, "
                "--full-scale or --lsb of the conversion, or the device file" if scale is not None else "")
        levers = " (lever arms alone cannot be estimated without them)" if np.ptp(device.positions, axis=0).any() else ""
        each = "" if poses.set_aside else no_pose_reasons(recordings, device, min_static_s)
        raise InputError(recordings[0].source if len(recordings) == 1 else f"{len(recordings)} recordings",
                         f"no usable static pose in any recording{why}{hint}: the offsets and sensitivities need "
                         f"static poses{levers}{each}")
    has_f = np.all(np.isfinite(poses.f_ref), axis=1)
    if method is None:
        if has_f.all():
            method = "full"
        elif not has_f.any():
            method = "jigfree"
        else:
            p = int(np.flatnonzero(~has_f)[0])
            info = poses.info[p]
            raise InputError(info["source"], f"{pose_label(poses.info, p)} has no reference f_x, f_y, f_z but "
                             "other poses do: give f on every pose, or choose --method jigfree", column="f_x")
    jigfree = method == "jigfree"
    if not jigfree and not has_f.all():
        p = int(np.flatnonzero(~has_f)[0])
        info = poses.info[p]
        where = pose_label(poses.info, p) if info.get("label") is not None else \
            f"the static interval at t = {info['t_start']:.6g}..{info['t_stop']:.6g} s"
        raise InputError(info["source"], f"method '{method}' needs the reference specific force f_x, f_y, f_z on "
                         f"every static pose, but {where} has none (use --method jigfree for unknown poses)",
                         column="f_x")
    if not jigfree:
        check_stated_poses(device, poses, pose_titles(poses.info, recordings), 0.0 if auto else jig_accuracy_deg)
    temps = poses.temp
    temperature = bool(np.all(np.isfinite(temps)) and np.ptp(temps) >= TEMP_MIN_SPAN_C)

    def solve(ps):
        if jigfree:
            return fit_jigfree(device, ps, jigfree_model, temperature)
        if auto:
            return fit_estimating_jig(device, ps, method, temperature=temperature), None
        if temperature:
            return fit_static(device, ps, method, jigfree=False, temperature=True,
                              jig_accuracy_deg=jig_accuracy_deg), None
        return fit_known_poses(device, ps.means, ps.f_ref, method, ps.sem(), poses=ps,
                               jig_accuracy_deg=jig_accuracy_deg), None

    try:
        fit, fallback = solve(poses)
        # temperature coefficients the poses do not pin are not a finding: the fit without them
        dropped = undetermined_tempcos(device, fit, temps) if temperature else None
        if dropped:
            temperature = False
            fit, fallback = solve(poses)
    except InputError as e:
        if e.source != "<poses>":
            raise
        names = sorted({str(d.get("source")) for d in poses.info})
        raise InputError(", ".join(names), with_detector_hint(e.detail, device, recordings, poses, min_static_s),
                         field=e.field) from None
    fit, fallback, outliers = without_outliers(device, fit, fallback, solve, drop_outliers)

    pos_fit = None
    rot = [(rec, m) for rec, m in zip(recordings, rotating) if m.any()]
    if rot:
        raw = np.vstack([rec.raw[m] for rec, m in rot])
        f = np.vstack([rec.f[m] for rec, m in rot])
        w = np.vstack([rec.w[m] for rec, m in rot])
        dw = np.vstack([rec.dw[m] for rec, m in rot])
        segs = np.concatenate([np.full(int(m.sum()), k) for k, (_, m) in enumerate(rot)])
        b, S = fit.offsets, fit.sensitivity
        noise = fit.poses.channel_noise()
        pos_fit = calibrate_positions(device, b, S, raw, f, w, dw, segments=segs, noise=noise,
                                      source=rot[0][0].source)
    cal = to_calibration(device, fit, "jigfree" if jigfree else method, pos_fit)
    if fallback is not None:
        hint = hint_clause(detector_found(device, recordings, poses, min_static_s))
        if hint:
            fallback["detector"] = hint[2:]
        cal.extra["fit"]["fallback"] = fallback
    if dropped:
        cal.extra["fit"]["temperature_dropped"] = dropped
    if outliers is not None:
        cal.extra["outliers"] = outliers
    if notes:
        cal.extra["notes"] = notes
    return cal


def without_outliers(device, fit, fallback, solve, drop: bool):
    """The poses far off ``fit`` (:func:`accelcal.calibrate.outliers.outlier_poses`) and the fit
    without them (``solve(PoseSet) -> (fit, fallback)``): (fit, fallback, report or None).  With
    ``drop`` the fit without them is returned, the poses set aside as "far off the fit"; else
    ``fit`` as it is.  The report is the calibration's ``extra["outliers"]``."""
    out = outlier_poses(fit)
    if not out.size:
        return fit, fallback, None
    poses = fit.poses
    keep = np.setdiff1d(np.arange(poses.n_poses), out)
    try:
        other, other_fb = solve(subset(poses, keep))
    except InputError as e:
        if e.source != "<poses>":
            raise
        other = other_fb = None
    rep = outlier_report(device, fit, out, pose_names(poses.info), other)
    if not (drop and other is not None):
        return fit, fallback, rep
    rep["dropped"] = True
    for p, d in zip(out, rep["poses"]):
        info = poses.info[p]
        other.poses.set_aside.append({**info, "reason": "far off the fit", "n_clipped": 0, "channels": [],
                                      "levels": f"|f| {d['norm_error_mps2']:+.3g} m/s^2 off, "
                                                f"{d['residual_over_noise']:.3g} x its noise"})
    return other, other_fb, rep


#: what a file whose rows are each one pose's mean needs (the static detector takes a pose from
#: several samples)
POSE_MEANS_HINT = ("if each row is already one pose's mean (a file of pose means, as Magneto's input), give every "
                   "row its own label in a 'pose' column (0, 1, 2, ...), which takes each row as a pose")


def detector_found(device, recordings, poses: PoseSet | None, min_s: float = MIN_POSE_S) -> tuple[str, bool] | None:
    """What the static detector needs and found, where the poses were detected (no recording
    has ``pose`` labels; else None): a still stretch of several samples a pose, how many it
    found and the rows they hold, and the still stretches shorter than ``min_s`` that a motion
    touches (:func:`short_stretches`: a robot arm's stops of 0.75-1 s had gone unmentioned); and
    whether they hold less than half of the rows and the rows look like pose means
    (:func:`rows_look_like_pose_means`: Magneto's input, 178 hand-held orientations, one row
    each, had been told "got 2; add poses").

    Parameters
    ----------
    device : Device
    recordings : list of Recording
    poses : PoseSet or None
        The poses found (None: none).
    min_s : float
        The detector's shortest interval where a motion touches it (seconds).

    Returns
    -------
    (str, bool) or None
        "the static detector ..." and whether :data:`POSE_MEANS_HINT` applies.
    """
    if any(rec.has_pose() for rec in recordings):
        return None
    rows = sum(rec.n_samples for rec in recordings)
    held = 0 if poses is None else int(np.sum(poses.n))
    found = 0 if poses is None else poses.n_poses
    w = max(window_len(device, STATIC_WINDOW_S, rec.n_samples) for rec in recordings)
    short = short_stretches(device, recordings, min_s)
    span = "" if not short else (f"{min(short):.2g}" if f"{min(short):.2g}" == f"{max(short):.2g}"
                                 else f"{min(short):.2g}-{max(short):.2g}")
    shorter = (f"; {len(short)} still stretch(es) of {span} s, shorter than {min_s:g} s, were left out as pauses "
               f"in a motion (--min-static {math.floor(100 * min(short)) / 100:g} takes them, if the sensor stood "
               "still there: a robot's stops)" if short else "")
    return (f"the static detector takes a pose from a still stretch of several samples (at least {w} here, "
            f"and {min_s:g} s where a motion touches it, with every channel within {STATIC_THRESHOLD:g} x "
            f"its noise) and found {found}, holding {held} of {rows} rows{shorter}"), \
        held < rows / 2 and rows_look_like_pose_means(device, recordings)


def short_stretches(device, recordings, min_s: float) -> list[float]:
    """The lengths (s) of the still stretches :func:`accelcal.readings.static.detect_static` leaves out as
    shorter than ``min_s`` where a motion touches them: those it finds with no minimum beyond its
    window, less those it finds with ``min_s`` (of a recording reduced while read, its ``short``)."""
    out: list[float] = []
    for rec in recordings:
        if isinstance(rec, Reduced):          # reduced while read: the lengths it kept
            out += rec.short
            continue
        kept = set(detect_static(rec, device, min_s=min_s))
        out += [(b - a) / device.sample_rate_hz for a, b in detect_static(rec, device, min_s=0.0) if (a, b) not in kept]
    return out


#: consecutive rows whose readings point this far apart (median, deg) are separate orientations,
#: each a pose of its own (a file of pose means), not a motion sampled row by row
POSE_ROW_TURN_DEG = 5.0

#: the share of a file's rows that must read an |f| a rest can have (static.at_gravity) for its rows
#: to be taken for pose means: each row of such a file is a rest; 5 % leaves room for a stray row (a
#: vibrating flight's rows: 72 % of them within 0.5-2 g)
POSE_ROWS_AT_REST = 0.95


def nominal_rows(device, rec) -> np.ndarray:
    """(n, 3) each row's reading through the device file's nominal offsets and sensitivities
    (m/s^2; least squares over the channels: :func:`accelcal.calibrate.checks.static_force`)."""
    return static_force(device.nominal_offsets(), device.nominal_sensitivity(), rec.raw)


def rows_turn_deg(rows: list[np.ndarray]) -> float:
    """The median angle (deg) between consecutive rows' readings (each recording's
    :func:`nominal_rows`).  Magneto's 178 hand-held pose means, one a row, turn by tens of degrees
    from row to row; a 200 Hz flight by a fraction of one (it had been told to label its rows as
    pose means), a vibrating one by tens too (75 deg)."""
    angles = []
    for v in rows:
        n = np.linalg.norm(v, axis=1)
        ok = (n[1:] > 0) & (n[:-1] > 0)
        c = np.sum(v[1:] * v[:-1], axis=1)[ok] / (n[1:] * n[:-1])[ok]
        angles.append(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
    a = np.concatenate(angles) if angles else np.zeros(0)
    return float(np.median(a)) if a.size else 0.0


def rows_at_rest(device, rows: list[np.ndarray]) -> float:
    """The share of the rows (each recording's :func:`nominal_rows`) whose |f| a rest can read
    (:func:`accelcal.readings.static.at_gravity`: within REST_F_RANGE x g, or with three or more rows
    agreeing on one wrong scale)."""
    ratio = np.concatenate([np.linalg.norm(v, axis=1) for v in rows]) if rows else np.zeros(0)
    ratio /= device.gravity_mps2
    return float(np.mean(at_gravity(ratio))) if ratio.size else 0.0


def rows_look_like_pose_means(device, recordings) -> bool:
    """Whether the rows of a triad's recordings look like a file of pose means, one orientation a
    row: consecutive rows turn by POSE_ROW_TURN_DEG or more (median), and at least
    POSE_ROWS_AT_REST of them read an |f| a rest can (:func:`rows_at_rest`).  A vibrating flight
    (PX4, 250 Hz) turns by 75 deg from row to row, as pose means do, but its rows read 0.37-3.6 g
    (1-99 %): it had been told to label its rows as pose means."""
    if device.n_channels != 3:
        return False
    rows = [nominal_rows(device, rec) for rec in recordings]
    return rows_turn_deg(rows) >= POSE_ROW_TURN_DEG and rows_at_rest(device, rows) >= POSE_ROWS_AT_REST


def hint_clause(found: tuple[str, bool] | None) -> str:
    """A :func:`detector_found` result as a clause to append ("; the static detector ..."; with
    :data:`POSE_MEANS_HINT` after it where that applies), or "" for None."""
    if found is None:
        return ""
    return "; " + found[0] + (": " + POSE_MEANS_HINT if found[1] else "")


def no_pose_reasons(recordings, device, min_s: float) -> str:
    """Each recording's own reason for holding no static pose, the one-recording refusal's text
    (:func:`with_detector_hint`), as ``"; FILE: reason"`` for each, or "" where none gives one."""
    said = []
    for rec in recordings:
        try:
            poses_from_recording(rec, device, required=True, min_s=min_s)
        except InputError as e:
            said.append(f"{rec.source}: {with_detector_hint(e.detail, device, [rec], None, min_s)}")
    return "".join(f"; {s}" for s in said)


def with_detector_hint(detail: str, device, recordings, poses: PoseSet | None, min_s: float = MIN_POSE_S) -> str:
    """A "too few poses" or "no static pose" error's ``detail`` with :func:`detector_found` (under
    ``min_s``); where the error advises adding poses (ADD_POSES) and the poses found hold less
    than half of the rows (a file of pose means), the hint first and that advice left out: such
    a file needs a 'pose' column, not more poses."""
    found = detector_found(device, recordings, poses, min_s)
    if found is None or not found[1] or ADD_POSES not in detail:
        return detail + hint_clause(found)
    return f"{POSE_MEANS_HINT}: {found[0]}; {detail.split(ADD_POSES)[0]}"


def setaside_reason(d: dict) -> str:
    """Why a pose was set aside, in words: "their readings clip", "their |f| is far from g"."""
    return "their |f| is far from g" if d.get("reason") == "not at rest" else "their readings clip"


def fit_jigfree(device, poses: PoseSet, model: str, temperature: bool):
    """The jig-free fit of ``model``; for ``auto``, of ``full``, else of the first of ``gain``
    and ``offset`` the poses determine.

    Returns
    -------
    fit : StaticFit
    fallback : dict or None
        ``{"from": "full", "to": model, "reasons": {model tried: why it was not determined}}``
        when ``auto`` fell back (:func:`calibrate_recordings` adds ``"detector"``, the
        :func:`detector_found` clause, where the poses were detected); None otherwise.

    Raises
    ------
    InputError
        ``full``'s own error when no model is determined (for ``auto``).
    """
    if model != "auto":
        return fit_static(device, poses, model, jigfree=True, temperature=temperature), None
    failed: dict = {}
    for m in ("full", "gain", "offset"):
        try:
            fit = fit_static(device, poses, m, jigfree=True, temperature=temperature)
        except InputError as e:
            if e.source != "<poses>":
                raise
            failed[m] = e
            continue
        return fit, (None if not failed else {"from": "full", "to": m,
                                              "reasons": {k: v.detail for k, v in failed.items()}})
    e = failed["full"]
    needs = {m: min_poses(device, m, temperature) for m in ("gain", "offset")}
    raise InputError(e.source, e.detail + f"; fewer determine less: the 'gain' model needs {needs['gain']} orientations, "
                     f"the 'offset' model {needs['offset']} (the default, --jigfree-model auto, fits the first of "
                     "full, gain and offset that the poses determine)", field=e.field)


def rotating_samples(rec) -> np.ndarray:
    if not (rec.has_omega() and rec.has_alpha() and rec.has_f()):
        return np.zeros(rec.n_samples, dtype=bool)
    ok = np.all(np.isfinite(rec.f), 1) & np.all(np.isfinite(rec.w), 1) & np.all(np.isfinite(rec.dw), 1)
    return ok & (np.linalg.norm(np.nan_to_num(rec.w), axis=1) > ROTATION_MIN_RADPS)


