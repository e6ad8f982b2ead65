"""Inputs of the diagnosis: devices, calibrations and recordings as objects or paths."""
from __future__ import annotations

import os
from typing import Any

import numpy as np

from ..io.calibration import Calibration, load_calibration
from ..io.device import Device, load_device
from ..errors import AccelcalError, InputError
from ..io.recording import Recording, check_for_device, read_recording


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


def as_recordings(recordings: Any, device) -> list:
    if isinstance(recordings, (Recording, str, os.PathLike)):
        recordings = [recordings]
    out = []
    for r in recordings:
        if isinstance(r, (str, os.PathLike)):
            r = read_recording(r, device.n_channels)
        if not isinstance(r, Recording):
            raise AccelcalError(f"diagnose: expected Recordings or CSV paths, got {type(r).__name__}")
        check_for_device(r, device, min_samples=2)
        out.append(r)
    if not out:
        raise InputError("<arguments>", "no recording given")
    return out
