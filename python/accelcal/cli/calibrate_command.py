"""The ``calibrate`` command's words: the --jig-accuracy argument, the warnings a
calibration calls for and the summary paragraph."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from ..calibrate.checks import far_from_nominal, gain_sigma, poorly_determined
from ..calibrate.jig_estimate import p_text
from ..calibrate.omega_check import lever_arm_omega_warning
from ..calibrate.pose_stream import Reduced, reduce_labelled
from ..calibrate.still_reduce import reduce_unlabelled
from ..calibrate.results import interval_text
from ..calibrate.settings import JIG_ACCURACY_AUTO, SCATTER_CHI2
from ..errors import AccelcalError
from ..io.units_cli import scale_from_args


def non_negative(text, option: str, what: str) -> float:
    """A finite number >= 0 from ``text`` (a one-line error naming ``option`` and ``what`` it is
    otherwise)."""
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not (np.isfinite(v) and v >= 0):
        raise AccelcalError(f"{option} {text!r}: expected {what}")
    return v


def jig_accuracy_arg(text) -> float | str:
    """--jig-accuracy DEG: a finite angle >= 0, or "auto" (estimated from the poses' scatter; one-line
    error naming the option otherwise)."""
    if str(text).strip().lower() == JIG_ACCURACY_AUTO:
        return JIG_ACCURACY_AUTO
    return non_negative(text, "--jig-accuracy", "a finite angle in degrees >= 0 (the rms rotation angle of the "
                        "jig's pose errors; 0 = exact references) or 'auto' (estimated from the poses' scatter)")


def min_static_arg(text) -> float:
    """--min-static SECONDS: a finite number >= 0 (one-line error naming the option otherwise)."""
    return non_negative(text, "--min-static", "a finite number of seconds >= 0 (the shortest still stretch taken "
                        "for a pose where a motion touches it)")


def calibrate_warnings(dev, cal) -> list[str]:
    """The warnings a calibration calls for, one line each: a jig-free model reduced from
    ``full``, poses scattered beyond their noise (with what causes it), channels whose offset
    or gain is poorly determined (:func:`accelcal.calibrate.checks.poorly_determined`), a
    sensitivity far from the device file's, temperature coefficients left out as undetermined.

    Parameters
    ----------
    dev : Device
    cal : Calibration
        The result of ``calibrate_recordings``.

    Returns
    -------
    list of str
    """
    fit = cal.extra.get("fit", {}) if isinstance(cal.extra, dict) else {}
    warnings = []
    fb = fit.get("fallback")
    if fb:
        what = {"gain": "offsets and gains along the nominal axes", "offset": "offsets only"}[fb["to"]]
        why = " ".join(f"'{m}': {r.rstrip('.')}." for m, r in fb["reasons"].items())
        warnings.append(f"fitted the jig-free '{fb['to']}' model ({what}, no cross-axis terms), as the poses do not "
                        f"determine {' or '.join(repr(m) for m in fb['reasons'])}. {why} (--jigfree-model chooses "
                        "the model)" + (f"; {fb['detector']}" if fb.get("detector") else ""))
    if fit.get("temperature_dropped"):
        warnings.append(fit["temperature_dropped"])
    poses = cal.extra.get("poses", []) if isinstance(cal.extra, dict) else []
    chi2, dof = fit.get("chi2"), fit.get("dof")
    red = chi2 / dof if chi2 is not None and dof else None
    cross_axis = fit.get("model", cal.method) == "full"
    outl = cal.extra.get("outliers") if isinstance(cal.extra, dict) else None
    far = outlier_warning(dev, outl) if outl else None
    red_wo = (outl.get("without") or {}).get("chi2_dof") if outl and not outl.get("dropped") else None
    if red is not None and red > SCATTER_CHI2 and red_wo is not None and red_wo <= SCATTER_CHI2:
        # the scatter is theirs: no hand's tremor to blame
        warnings.append(f"the poses scatter about the fit beyond their noise (chi2/dof {red:.3g}; the uncertainties "
                        f"are scaled up by it) because of the {len(outl['poses'])} pose(s) far off the fit named "
                        f"below: {red_wo:.3g} without them")
        red = None
    hint = fit.get("jig_accuracy_consistent_with_scatter_deg")
    one_row = bool(poses) and all(p.get("n_samples") == 1 for p in poses)
    if one_row and red is not None and red > SCATTER_CHI2:
        # a file of pose means: no noise to judge the scatter against
        jig = (f"; a jig error of about {hint:.2g} deg would give such a scatter (--jig-accuracy states one)"
               if hint is not None and cross_axis else "")
        warnings.append(f"each pose is one row (a file of pose means): the poses' noise is unknown, so their scatter "
                        f"about the fit (chi2/dof {red:.3g}) is measured against the rounding's (1/sqrt(12) count), "
                        f"not judged against their noise; the uncertainties are scaled up by it{jig}")
    elif hint is not None and cross_axis:
        warnings.append(f"the poses scatter about the fit far beyond their noise (chi2/dof {red:.3g}), as a jig "
                        f"error of about {hint:.2g} deg would; if the jig is that inaccurate, state it with "
                        "--jig-accuracy (else the offsets absorb it)")
    elif red is not None and red > SCATTER_CHI2 and cross_axis:
        known = "" if cal.method == "jigfree" else ", stated f off the poses' real one"
        also = (f", {red_wo:.3g} without the {len(outl['poses'])} pose(s) far off the fit named below"
                if red_wo is not None else "")
        why = (f"poses that move while held (a hand's tremor, a slow turn){known} or an effect the model lacks; "
               "'accelcal diagnose' with this calibration tests the effects it knows")
        warnings.append(f"the poses scatter about the fit beyond their noise (chi2/dof {red:.3g}{also}; the uncertainties "
                        f"are scaled up by it): {why}")
    elif red is not None and red > SCATTER_CHI2 and not cross_axis:
        use = ("poses in other orientations would determine them (above)" if fb else
               f"use {'--jigfree-model full' if cal.method == 'jigfree' else '--method full'} if the poses "
               "determine it")
        warnings.append(f"the poses scatter about the fit far beyond their noise (chi2/dof {red:.3g}): the "
                        f"'{fit.get('model', cal.method)}' model has no cross-axis terms, which a real sensor "
                        f"has, and the poses may move while held; {use}")
    elif not cross_axis and (fit.get("jig_accuracy_estimate") or {}).get("used"):
        # the estimated jig accuracy took up the scatter, and with it what the model lacks
        warnings.append(f"the poses scatter about the fit beyond their noise, taken up by the jig accuracy "
                        f"estimated ({fit['jig_accuracy_estimate']['deg']:.3g} deg); the '{fit.get('model', cal.method)}' "
                        "model has no cross-axis terms, which a real sensor has and which look like pose tilts, so "
                        "part of that may be theirs: use --method full if the poses determine it")
    gs = None if cal.sensitivity_sigma is None else gain_sigma(cal.sensitivity, cal.sensitivity_sigma)
    if poses:
        # first to last sample, and one sample's step more: the time n samples take
        held = [(p["t_stop_s"] - p["t_start_s"]) * p["n_samples"] / max(p["n_samples"] - 1, 1)
                for p in poses if "t_start_s" in p and "n_samples" in p]
        low = poorly_determined(dev, [p["f_mps2"] for p in poses], cal.offset_sigma, gs,
                                [p.get("n_samples", 0) for p in poses], chi2_dof=red,
                                held_s=held if len(held) == len(poses) else None)
        if low:
            warnings.append(low)
    if far:
        warnings.append(far)
    scale = far_from_nominal(dev, cal.sensitivity, gs)
    if scale:
        warnings.append(scale)
    warnings += clipping_warnings(dev, cal)
    levers = lever_arm_omega_warning(dev, cal)
    return warnings + ([levers] if levers else [])


def clipping_warnings(dev, cal) -> list[str]:
    """Poses set aside because their readings clip (the calibration's ``extra["set_aside"]``), and
    channels whose range, through the calibration, does not reach 1 g either way along their own
    axis: (raw_min - b_i) / |s_i| to (raw_max - b_i) / |s_i| m/s^2.  A chip whose offset leaves
    less than g before its rail clips in its ordinary attitudes, and firmware that reads it there
    gets f short of the truth (the C core's saturation flag reports its own arithmetic, not the
    chip's rail)."""
    out = []
    aside = [d for d in (cal.extra.get("set_aside", []) if isinstance(cal.extra, dict) else [])
             if d.get("n_clipped")]
    if aside:
        out.append(f"{len(aside)} pose(s) set aside because their readings clip ("
                   + "; ".join(f"{d['name']}: {d['n_clipped']} samples, {d.get('levels', '')}".rstrip(", ")
                               for d in aside[:3]) + ("; ..." if len(aside) > 3 else "")
                   + "): the calibration is fitted without them, and readings at those levels are clipped")
    g = dev.gravity_mps2
    k = np.linalg.norm(np.asarray(cal.sensitivity, float), axis=1)
    b = np.asarray(cal.offsets, float)
    lo, hi = (dev.raw_min - b) / k, (dev.raw_max - b) / k
    short = [i for i in range(len(k)) if k[i] > 0 and min(-lo[i], hi[i]) < g]
    if short:
        out.append("the range through this calibration does not reach 1 g on "
                   + "; ".join(f"channel {i} ({lo[i] / g:+.3g} to {hi[i] / g:+.3g} g along its axis: its offset "
                               f"{b[i]:.0f} counts leaves {min(-lo[i], hi[i]) / g:.3g} g before the rail)"
                               for i in short)
                   + ": readings beyond clip at the ADC's rail and f there is short of the truth (accelcal resolve "
                     "flags them in its column clipped; firmware should compare raw with the rails)")
    return out


def outlier_warning(dev, outl: dict) -> str:
    """One line on the poses far off the fit (the calibration's ``extra["outliers"]``): each with
    its |f| error, the others' worst, and how the offsets (counts and mg) and gains move and the
    chi2/dof without them (or that they were left out, and how the fit moved)."""
    g = dev.gravity_mps2
    def name(p):
        if str(p["name"]).startswith("static@"):
            return str(p["name"])
        return f"pose {p['name']}" + (f" (t = {p['t_start_s']:.3f} s)" if "t_start_s" in p else "")

    named = "; ".join(f"{name(p)}: |f| {p['norm_error_mps2']:+.3g} m/s^2, {p['residual_over_noise']:.3g} x its noise"
                      for p in outl["poses"])
    n = len(outl["poses"])
    rest = outl.get("others_worst_norm_error_mps2")
    text = (f"{n} pose(s) sit far off the fit ({outl['rule']}): {named}"
            + (f"; the others' worst |f| error is {rest:+.3g} m/s^2" if rest is not None else ""))
    wo = outl.get("without")
    if wo is None:
        return text + ("; without them the poses determine no fit: check them (a knock, a pose not held, a wrong "
                       "row); they are kept")
    off = np.asarray(wo["offset_change_counts"])
    mg = 1000.0 * off / (np.asarray(dev.counts_per_mps2, float) * g)
    moves = (f"the offsets move by {', '.join(f'{v:+.3g}' for v in off)} counts ({', '.join(f'{v:+.2g}' for v in mg)} "
             f"mg), the gains by {', '.join(f'{100 * v:+.2g}' for v in wo['gain_change'])} %")
    chi = (f", chi2/dof {outl['chi2_dof']:.3g} -> {wo['chi2_dof']:.3g}"
           if outl.get("chi2_dof") is not None and wo.get("chi2_dof") is not None else "")
    if outl.get("dropped"):
        return text + f"; left out (--drop-outliers): without them {moves}{chi}"
    return (text + f"; without them {moves}{chi}: check those poses (a knock, a pose not held, a wrong row); "
            "they are kept (--drop-outliers leaves them out)")


def record_warnings(dev, cal) -> list[str]:
    """:func:`calibrate_warnings`, also recorded in the calibration's ``extra["warnings"]`` (the
    JSON's top-level ``warnings``, which ``accelcal header`` carries as a comment) when there are any.

    Parameters
    ----------
    dev : Device
    cal : Calibration
        Changed in place.

    Returns
    -------
    list of str
    """
    warnings = calibrate_warnings(dev, cal)
    if warnings:
        cal.extra["warnings"] = list(warnings)
    return warnings


def calibration_summary(cal, n_recordings: int, output) -> str:
    """One paragraph on what a calibration used and how well it fits.

    Parameters
    ----------
    cal : Calibration
        The result of ``calibrate_recordings``.
    n_recordings : int
        How many recordings went in.
    output : path
        Where it was written.

    Returns
    -------
    str
    """
    fit = cal.extra.get("fit", {}) if isinstance(cal.extra, dict) else {}
    n = cal.offsets.shape[0]
    poses = len(cal.poses_used) if cal.poses_used is not None else None
    model = f" ('{fit['model']}' model)" if cal.method == "jigfree" and fit.get("model", "full") != "full" else ""
    parts = [f"{cal.method}{model} calibration of {n} channel{'s' if n != 1 else ''}"]
    src = f"from {poses} static pose{'s' if poses != 1 else ''}" if poses is not None else "from the recordings"
    how = fit.get("poses")
    parts.append(f"{src} ({how}; {n_recordings} recording{'s' if n_recordings != 1 else ''})" if how
                 else f"{src} ({n_recordings} recording{'s' if n_recordings != 1 else ''})")
    text = " ".join(parts) + "."
    chi2, dof, dof_r = fit.get("chi2"), fit.get("dof"), fit.get("dof_readings")
    if cal.residual_rms_per_channel is not None:
        r = np.asarray(cal.residual_rms_per_channel, dtype=float)
        text += f" Residual rms {np.sqrt(np.mean(r ** 2)):.3g} counts (worst channel {int(np.argmax(r))}: {r.max():.3g})"
        if dof_r is not None and dof_r <= 0 and poses:
            # the pose directions are fitted too: terms + 2 angles a pose take every reading
            par = poses * n - dof_r
            text += (f": near zero by construction, as the pose directions are fitted too ({poses} poses x {n} "
                     f"readings against {par - 2 * poses} terms and the poses' {2 * poses} angles), so it cannot "
                     "judge the fit here")
        text += "."
    if chi2 is not None and dof:
        if dof_r is not None and dof_r <= 0:
            text += (f" chi2/dof {chi2 / dof:.3g} ({dof} dof, all of them the pose priors': the fitted pose "
                     "directions against the jig accuracy).")
        elif dof_r is not None:
            text += f" chi2/dof {chi2 / dof:.3g} ({dof} dof, {dof - dof_r} of them the pose priors')."
        else:
            text += f" chi2/dof {chi2 / dof:.3g} ({dof} dof)."
    aside = cal.extra.get("set_aside", []) if isinstance(cal.extra, dict) else []
    if aside:
        n_cl = sum(int(d.get("n_clipped", 0)) for d in aside)
        why = ", ".join(sorted({d.get("reason", "clipped") for d in aside}))
        count = f"{n_cl} clipped samples" if n_cl else why
        text += (f" {len(aside)} pose{'s' if len(aside) != 1 else ''} set aside ({count}): "
                 + "; ".join(f"{d['name']} ({d['levels']})" for d in aside[:3]) + ("; ..." if len(aside) > 3 else "")
                 + ".")
    held = fit.get("not_fitted", {})
    if "sensitivity" in held:
        text += " Sensitivities held at the device file's nominal (not fitted, no sigma; the offsets' sigmas take them"
        moves = fit.get("offset_counts_per_percent_gain")
        sig = cal.offset_sigma
        if moves is not None and sig is not None and np.any(np.abs(moves) > np.nan_to_num(sig, nan=np.inf)):
            text += (" as exact: a chip's gain 1 % above the nominal would leave the offsets off by "
                     + ", ".join(f"{v:+.3g}" for v in moves) + " counts).")
        else:
            text += " as exact)."
    if "sensitivity_direction" in held:
        text += (" Sensitivity directions held along the device file's nominal axes (not fitted: no sigma for the "
                 "components held at 0).")
    est = fit.get("jig_accuracy_estimate")
    if est and est.get("used"):
        iv = interval_text(est)
        text += (f" Jig accuracy estimated from the poses' scatter: {est['deg']:.3g} deg rms"
                 + (f" ({iv}; likelihood-ratio test of a perfect jig: {p_text(est['p_value'])})" if iv else "")
                 + ", used as the poses' priors (--jig-accuracy states one instead).")
    elif est and "p_value" in est:
        text += (f" Jig accuracy estimated: the poses' scatter is within their noise ({p_text(est['p_value'])}), "
                 "so the references are taken as exact (ordinary least squares).")
    elif est:
        text += " Jig accuracy not estimated: one row a pose, the noise unknown; the references are taken as exact."
    elif fit.get("jig_accuracy_deg"):
        text += f" Jig accuracy stated: {fit['jig_accuracy_deg']:g} deg."
    if cal.positions is not None:
        text += " Lever arms estimated."
    if cal.offset_tc is not None or cal.gain_tc is not None:
        text += " Temperature coefficients fitted."
    return text + f" Written to {output}."



def reduced_recordings(paths, dev, a) -> list[Reduced] | None:
    """Each recording reduced to its poses while read in chunks
    (:func:`accelcal.calibrate.pose_stream.reduce_labelled` with ``pose`` labels, else
    :func:`accelcal.calibrate.still_reduce.reduce_unlabelled`), or None where one of them is not
    (the caller then reads them whole; the same paths given twice: None, the whole-file reader
    refuses them).  None too where no recording is labelled, the device a triad and the poses hold
    less than half of the rows: the whole-file messages then ask whether the rows are pose means
    (:func:`accelcal.calibrate.recordings.rows_look_like_pose_means`), which takes every row.  The
    note on ignored columns as the whole-file reader gives it, on stderr."""
    if len({Path(p).resolve() for p in paths}) != len(paths):
        return None
    scale = scale_from_args(a, dev, reader=True)
    min_s = min_static_arg(a.min_static)
    out = []
    for p in paths:
        r = reduce_labelled(p, dev, scale) or reduce_unlabelled(p, dev, scale, min_s=min_s)
        if r is None:
            return None
        out.append(r)
    held = sum(int(np.sum(r.poses.n)) for r in out)
    if not any(r.labelled for r in out) and dev.n_channels == 3 and held < sum(r.n_samples for r in out) / 2:
        return None
    ignored = sorted({k for r in out for k in r.extra})
    if ignored:
        print(f"accelcal calibrate: note: ignored column{'s' if len(ignored) > 1 else ''} "
              f"{', '.join(ignored)} (not part of the accelerometer model)", file=sys.stderr)
    return out
