"""Inputs of the diagnosis: devices, calibrations and recordings as objects or paths."""
from __future__ import annotations

import dataclasses
import os
from typing import Any

import numpy as np

from ..io.calibration import Calibration, load_calibration
from ..io.device import Device, load_device
from ..errors import AccelcalError, InputError
from ..firmware.terms import correct_readings, has_terms
from ..firmware.quantize import round_half_up
from ..firmware.terms_fixed import terms_frac
from ..io.recording import Recording, check_for_device, read_recording
from ..io.thinned import read_all_thinned, thin_recordings


def as_device(device: Any):
    if isinstance(device, Device):
        return device
    if isinstance(device, (str, os.PathLike)):
        return load_device(device)
    raise AccelcalError(f"diagnose: expected a Device or a device JSON path, got {type(device).__name__}")


def as_calibration(cal: Any, device) -> tuple[Any, str]:
    if isinstance(cal, (str, os.PathLike)):
        return load_calibration(cal, device), os.fspath(cal)
    if not isinstance(cal, Calibration):
        raise AccelcalError(f"diagnose: expected a Calibration or a calibration JSON path, got {type(cal).__name__}")
    src = str(cal.extra.get("source", "<calibration>")) if isinstance(cal.extra, dict) else "<calibration>"
    if cal.device != device.name:
        raise InputError(src, f"calibration is for {cal.device!r} but the device is {device.name!r}", field="device")
    if cal.n_channels != device.n_channels:
        raise InputError(src, f"calibration has {cal.n_channels} channels but the device {device.name!r} has "
                         f"{device.n_channels}", field="channels")
    if not (np.all(np.isfinite(cal.offsets)) and np.all(np.isfinite(cal.sensitivity))):
        raise InputError(src, "offsets and sensitivities must be finite", field="channels")
    return cal, src


def as_recordings(recordings: Any, device, max_samples: int = 0) -> tuple[list, Any, list[str]]:
    """The recordings (objects, or paths read), cut down where longer than ``max_samples``
    samples (:mod:`accelcal.io.thinned`: paths read so in bounded memory; 0: every sample; a
    Recording's ``thinning`` says what was kept).  Returns (recordings, the device, notes): the
    device at rate / k where every k-th sample is kept (jig-free)."""
    if isinstance(recordings, (Recording, str, os.PathLike)):
        recordings = [recordings]
    items = list(recordings)
    for r in items:
        if not isinstance(r, (Recording, str, os.PathLike)):
            raise AccelcalError(f"diagnose: expected Recordings or CSV paths, got {type(r).__name__}")
    if not items:
        raise InputError("<arguments>", "no recording given")
    rate = float(device.sample_rate_hz)
    if all(isinstance(r, (str, os.PathLike)) for r in items):
        out = read_all_thinned(items, device, max_samples)
    else:
        out = thin_recordings([r if isinstance(r, Recording) else read_recording(r, device.n_channels)
                               for r in items], rate, max_samples)
    for r in out:
        check_for_device(r, device, min_samples=2)
    notes = [r.thinning.note(r.source) for r in out if r.thinning is not None]
    every = [r.thinning for r in out if r.thinning is not None and r.thinning.step > 1]
    if every and abs(rate / every[0].rate_hz - 1.0) < 1e-9:
        # every k-th sample: recordings at rate / k (not yet so where a caller had cut them down and said so)
        device = dataclasses.replace(device, sample_rate_hz=rate / max(th.step for th in every))
    return out, device, notes


def with_terms_applied(cal, recs: list, device) -> tuple[Any, list, list[str]]:
    """A calibration with correctable terms beyond the model's own (a nonlinearity, a time skew,
    a thermal lag: firmware/terms.py, as ``accelcal refine`` writes them): the readings are
    corrected by them first, as the firmware does (float reference, rounded to whole counts; a
    reading at the converter's rails kept there), and the diagnosis is of what they leave
    against the calibration's linear part.  Returns (calibration, recordings, notes); unchanged
    for a calibration without such terms."""
    terms = has_terms(cal)
    lag = bool(cal.temp_offset_tau_s) or bool(cal.temp_gain_tau_s)
    if not (terms["nonlinearity"] or terms["skew"] or (terms["temperature"] and lag)):
        return cal, recs, []
    dt = 1.0 / float(device.sample_rate_hz)
    # the firmware hands the terms' output on in 2^-frac counts (firmware.terms_fixed.terms_frac, the
    # header's <PREFIX>_TERMS_FRAC: with a temperature term only)
    frac = terms_frac((device.raw_min, device.raw_max), round_half_up(cal.offsets)) \
        if terms["temperature"] else 0
    scale = 2.0 ** frac
    out = []
    for r in recs:
        temp = None if r.temp_c is None else np.asarray(r.temp_c, float)
        try:
            y = correct_readings(cal, r.raw, temp, dt, (device.raw_min, device.raw_max))
        except ValueError as e:
            raise InputError(r.source, str(e), column="temp_c") from None
        rails = (r.raw <= device.raw_min) | (r.raw >= device.raw_max)
        y = np.clip(np.floor(y * scale + 0.5) / scale, device.raw_min, device.raw_max)
        y = np.where(rails, r.raw, y)
        rc = dataclasses.replace(r, raw=np.rint(y).astype(np.int64))
        if frac:
            # the hand-off's 2^-frac counts: float readings in counts (a Recording built from arrays holds
            # whole counts; this copy is the diagnosis's own)
            rc.raw = y
        out.append(rc)
    linear = dataclasses.replace(cal, nonlin_k2=None, nonlin_k3=None, time_skew_s=None, offset_tc=None, gain_tc=None,
                                 temp_offset_tau_s=None, temp_gain_tau_s=None,
                                 temp_ref_c=None)
    named = [k for k, v in (("nonlinearity", terms["nonlinearity"]), ("time skew", terms["skew"]),
                            ("temperature offset and gain with their lag", terms["temperature"])) if v]
    return linear, out, [f"the calibration's {', '.join(named)} (firmware/terms.py) applied to the readings first, "
                         "as the firmware does (rounded to whole counts); the diagnosis is of what they leave"]
