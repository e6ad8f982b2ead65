"""``accelcal demo``: the main job end to end on the seed's 6-channel prototype.

simulate (jig poses + a 2 Hz yaw rate table, with a random "true" calibration shaped
like the seed's Table 1) -> calibrate (full, 24 poses) -> emit the C header ->
resolve with the C core (fixed) and the float reference -> diagnose -> summary.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io.calibration import Calibration, save_calibration
from ..calibrate import calibrate_recordings
from ..diagnose import diagnose
from ..firmware.header import render_header
from ..firmware.quantize import FORMATS, quantize_calibration
from ..io.recording import write_recording
from ..resolve import resolve_recording
from ..simulate import seed_prototype_truth, simulate
from ..io.device import default_device, save_device
from ..errors import atomic_write


def _rms(a) -> float:
    a = np.asarray(a, float)
    a = a[np.isfinite(a)]
    return float(np.sqrt(np.mean(a * a))) if a.size else float("nan")


def run_demo(out_dir: Path, seed: int = 1, *, quiet: bool = False) -> int:

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    say = (lambda *a: None) if quiet else print
    dev = default_device()
    save_device(dev, out / "device.json")
    truth = seed_prototype_truth(dev, np.random.default_rng(seed))
    g = dev.gravity_mps2

    # 1. calibration data: 24 jig poses, 60 samples each (the seed's protocol, more poses)
    poses = simulate(dev, "static_poses", seed=seed, calibration=truth, poses="24")
    write_recording(out / "poses.csv", poses)
    cal = calibrate_recordings(dev, [poses], method="full")
    save_calibration(cal, out / "calibration.json")

    # 2. firmware header from the calibration (the one quantizer)
    tables = quantize_calibration(dev, cal)
    header = render_header(tables, calibration_method=cal.method)
    atomic_write(out / "accelcal_calibration.h", lambda f: f.write(header))

    # 3. a motion to resolve: the seed's 2 Hz yaw on a rate table, off-centre
    motion = simulate(dev, "rate_table", seed=seed + 1, calibration=truth,
                      axis="z", freq_hz=2.0, amplitude_deg=30.0)
    write_recording(out / "rate_table.csv", motion)
    f_fix, a_fix, flags = resolve_recording(dev, cal, motion, "fixed")
    f_flt, a_flt, _ = resolve_recording(dev, cal, motion, "float")
    f_nom, a_nom, _ = resolve_recording(dev, Calibration.nominal(dev), motion, "float")
    f_true, a_true = motion.f, motion.dw
    lsb = 2.0 ** -FORMATS.out_frac

    # 4. static check: |f| - g over the calibration poses, before and after
    st_f_cal, _, _ = resolve_recording(dev, cal, poses, "float")
    st_f_nom, _, _ = resolve_recording(dev, Calibration.nominal(dev), poses, "float")
    labels = np.unique(poses.pose[poses.pose >= 0])

    def pose_err(fs):  # |mean f over a pose| - g: noise averaged out, calibration error left
        return np.array([np.linalg.norm(fs[poses.pose == p].mean(axis=0)) - g for p in labels])

    summary = {
        "device": dev.name,
        "true_vs_estimated": {
            "offset_rms_counts": _rms(cal.offsets - truth.offsets),
            "gain_rms_percent": _rms(100 * (np.linalg.norm(cal.sensitivity, axis=1)
                                            / np.linalg.norm(truth.sensitivity, axis=1) - 1)),
        },
        "pose_mean_abs_f_minus_g_rms_mps2": {
            "nominal": _rms(pose_err(st_f_nom)),
            "calibrated": _rms(pose_err(st_f_cal)),
        },
        "rate_table_f_rms_error_mps2": {"nominal": _rms(f_nom - f_true), "calibrated_float": _rms(f_flt - f_true),
                                        "calibrated_fixed_core": _rms(f_fix - f_true)},
        "rate_table_alpha_rms_error_radps2": {"nominal": _rms(a_nom - a_true),
                                              "calibrated_float": _rms(a_flt - a_true),
                                              "calibrated_fixed_core": _rms(a_fix - a_true)},
        "fixed_vs_float_max_lsb": {
            "f": float(np.abs(f_fix - f_flt).max() / lsb), "alpha": float(np.abs(a_fix - a_flt).max() / lsb)},
        "fixed_saturated_samples": int(np.count_nonzero(flags)) if flags is not None else 0,
    }
    try:
        diag = diagnose(dev, cal, [motion])
        summary["diagnosis_verdict"] = diag.get("verdict")
        atomic_write(out / "diagnosis.json", lambda f: json.dump(diag, f, indent=2, default=float))
    except ImportError:
        summary["diagnosis_verdict"] = "(diagnosis not available in this build)"
    atomic_write(out / "summary.json", lambda f: json.dump(summary, f, indent=2))

    s = summary
    say(f"accelcal demo on '{dev.name}' (files in {out}/)")
    say(f"  calibration (24 poses, full): offset error {s['true_vs_estimated']['offset_rms_counts']:.2f} counts rms, "
        f"gain error {s['true_vs_estimated']['gain_rms_percent']:.3f} % rms")
    sf = s["pose_mean_abs_f_minus_g_rms_mps2"]
    say(f"  |pose-mean f| - g rms over the 24 poses: nominal {sf['nominal']:.4f} -> calibrated {sf['calibrated']:.4f} m/s^2")
    rf, ra = s["rate_table_f_rms_error_mps2"], s["rate_table_alpha_rms_error_radps2"]
    say(f"  2 Hz yaw, f error rms: nominal {rf['nominal']:.4f}, float {rf['calibrated_float']:.4f}, "
        f"C core {rf['calibrated_fixed_core']:.4f} m/s^2")
    say(f"  2 Hz yaw, alpha error rms: nominal {ra['nominal']:.3f}, float {ra['calibrated_float']:.3f}, "
        f"C core {ra['calibrated_fixed_core']:.3f} rad/s^2")
    fx = s["fixed_vs_float_max_lsb"]
    say(f"  C core vs float reference: max {fx['f']:.1f} LSB (f), {fx['alpha']:.1f} LSB (alpha); "
        f"1 LSB = {lsb:.2e}; saturated samples: {s['fixed_saturated_samples']}")
    say(f"  header: {out / 'accelcal_calibration.h'}   diagnosis verdict: {s['diagnosis_verdict']}")
    return 0
