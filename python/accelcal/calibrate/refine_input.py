"""What ``refine`` takes from a diagnosis (docs/diagnosis-json.md) and from the recordings.

A diagnosis's ``model.effects`` names the effects its model holds; each is either a term the
firmware can correct (a calibration term: refitted, or added to the calibration) or one it
cannot, with the reason (:data:`NOT_CORRECTABLE`).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError

#: model effects that are the calibration's existing terms: refitted jointly
EXISTING = {"offset": "offsets", "gain": "sensitivity", "misalignment": "sensitivity",
            "position_error": "lever arms", "centripetal": "lever arms"}
#: model effects the firmware corrects with a term added to the calibration (firmware/terms.py)
ADDED = ("nonlinearity", "temperature_offset", "temperature_gain", "time_skew")
#: model effects no calibration term takes out, and why
NOT_CORRECTABLE = {
    "bias_drift": "a drift of the offset with time: re-zero at rest instead",
    "bandwidth": "a low-pass: not invertible without amplifying the noise",
    "saturation": "in the converter (clipped readings carry no value to correct)",
    "quantization": "in the converter (the code step is lost before the firmware)",
    "pose_error": "the jig's poses, not the sensor: no calibration term",
    "session_offset": "a change of the offset between recordings: re-zero at rest, or recalibrate, in each session",
    "session_gain": "a change of the gain between recordings: recalibrate in the new session",
}


@dataclass
class Diagnosed:
    """The parts of a diagnosis refine uses: the model's effects and their parameters."""

    source: str
    device: str | None
    effects: list[str]
    params: dict[str, dict]
    unexplained: bool


def read_diagnosis(diagnosis: Any, device) -> Diagnosed:
    """A diagnosis (a path to its JSON or the dict ``diagnose`` returns) checked against ``device``.

    Raises InputError naming the file and the field on a missing or misspelt field, or a
    diagnosis made for another device."""
    if isinstance(diagnosis, (str, Path)):
        source = str(diagnosis)
        try:
            with open(diagnosis, encoding="utf-8") as fh:
                d = json.load(fh)
        except OSError as e:
            raise InputError(source, f"cannot read the diagnosis ({e.strerror or e})") from None
        except (json.JSONDecodeError, UnicodeDecodeError) as e:
            raise InputError(source, f"not a diagnosis JSON ({e})") from None
    else:
        source, d = "<diagnosis>", diagnosis
    if not isinstance(d, dict):
        raise InputError(source, "not a diagnosis JSON object")
    for key in ("model", "verdict"):
        if key not in d:
            raise InputError(source, "missing (docs/diagnosis-json.md)", field=key)
    model = d["model"]
    if model is None:
        model = {"effects": [], "params": {}}
    if not isinstance(model, dict):
        raise InputError(source, "expected an object", field="model")
    for key in ("effects", "params"):
        if key not in model:
            raise InputError(source, "missing (docs/diagnosis-json.md)", field=f"model.{key}")
    effects = model["effects"]
    if not isinstance(effects, list) or not all(isinstance(e, str) for e in effects):
        raise InputError(source, "expected a list of effect names", field="model.effects")
    known = set(EXISTING) | set(ADDED) | set(NOT_CORRECTABLE)
    for name in effects:
        if name not in known:
            raise InputError(source, f"unknown effect {name!r}", field="model.effects")
    params = model["params"]
    if not isinstance(params, dict):
        raise InputError(source, "expected an object", field="model.params")
    for name in effects:
        if name in ADDED and not isinstance(params.get(name), dict):
            raise InputError(source, f"no parameters for {name!r}", field=f"model.params.{name}")
    dev_name = d.get("device")
    if dev_name is not None and dev_name != device.name:
        raise InputError(source, f"a diagnosis of device {dev_name!r}, not of {device.name!r}", field="device")
    n_ch = d.get("n_channels")
    if n_ch is not None and n_ch != device.n_channels:
        raise InputError(source, f"a diagnosis of {n_ch} channels; device {device.name!r} has "
                         f"{device.n_channels}", field="n_channels")
    return Diagnosed(source, dev_name, list(effects), params,
                     d.get("verdict") == "unexplained" or bool(d.get("unexplained")))


def start_value(params: dict, name: str, key: str, n: int, default: float = 0.0) -> np.ndarray:
    """(n,) a model effect's per-channel parameter as a start value (``default`` where absent)."""
    v = params.get(name, {}).get(key)
    if v is None:
        return np.full(n, default)
    a = np.asarray([np.nan if x is None or isinstance(x, str) else x for x in np.ravel(v)], float)
    if a.size == 1:
        a = np.full(n, a[0])
    return np.nan_to_num(a[:n], nan=default) if a.size >= n else np.full(n, default)


@dataclass
class Rows:
    """The reference samples of the recordings, joined: what the fit compares."""

    t: np.ndarray        # (n,) s, each recording after the last with a gap of 1000 s
    raw: np.ndarray      # (n, N) counts
    f: np.ndarray        # (n, 3) m/s^2 (NaN where no reference)
    w: np.ndarray        # (n, 3) rad/s (0 where unknown at a pose)
    dw: np.ndarray       # (n, 3) rad/s^2
    temp: np.ndarray | None   # (n,) degC
    use: np.ndarray      # (n,) bool: the samples the fit scores
    block: np.ndarray    # (n,) int: 2 s blocks within contiguous runs (the held-out split)
    rec: np.ndarray      # (n,) int: which recording


def reference_rows(recordings, device, need_temp: bool) -> Rows:
    """The recordings' samples with their reference (f, and w, dw where the device has channels
    off the origin), checked: a recording without any reference sample, or without the
    temperature the terms need, is refused naming it."""
    off_origin = bool(np.any(np.abs(np.asarray(device.positions, float)) > 0))
    parts = []
    t_shift = 0.0
    for k, rec in enumerate(recordings):
        n = rec.raw.shape[0]
        f = np.full((n, 3), np.nan) if rec.f is None else np.asarray(rec.f, float)
        w = np.full((n, 3), np.nan) if rec.w is None else np.asarray(rec.w, float)
        dw = np.full((n, 3), np.nan) if rec.dw is None else np.asarray(rec.dw, float)
        have = np.all(np.isfinite(f), axis=1)
        if off_origin:
            have &= np.all(np.isfinite(w), axis=1) & np.all(np.isfinite(dw), axis=1)
        if not np.any(have):
            raise InputError(rec.source, "no sample has a reference (f_x..f_z" + (", w_*, dw_*" if off_origin else "")
                             + "): refine needs the jig's stated f or a reference motion", column="f_x")
        temp = None if rec.temp_c is None else np.asarray(rec.temp_c, float)
        if need_temp and (temp is None or not np.all(np.isfinite(temp))):
            row = 0 if temp is None else int(np.argmin(np.isfinite(temp)))
            raise InputError(rec.source, "the model's temperature terms need temp_c on every sample",
                             row=rec.line(row), column="temp_c")
        t = np.asarray(rec.t, float) - float(rec.t[0]) + t_shift
        t_shift = float(t[-1]) + 1000.0
        # the samples scored: a reference, not at the rails, and not at the edge of a run of them
        # (a channel's skew reads the motion a fraction of a sample beyond the run)
        inside = have & np.all((rec.raw > device.raw_min) & (rec.raw < device.raw_max), axis=1)
        edge = np.zeros(n, bool)
        edge[:-1] |= ~have[1:]
        edge[1:] |= ~have[:-1]
        edge[[0, -1]] = True
        run = np.cumsum(np.r_[True, have[1:] != have[:-1]])
        h = 1.0 / float(device.sample_rate_hz)
        block = run * 100000 + np.floor((t - t[0]) / 2.0).astype(int)
        parts.append((t, np.asarray(rec.raw, float), f, np.nan_to_num(w), np.nan_to_num(dw), temp,
                      inside & ~edge, block + k * 10 ** 9, np.full(n, k)))
        del h
    cat = [np.concatenate([p[j] for p in parts]) for j in (0, 1, 2, 3, 4, 6, 7, 8)]
    temps = None if any(p[5] is None for p in parts) else np.concatenate([p[5] for p in parts])
    return Rows(t=cat[0], raw=cat[1], f=cat[2], w=cat[3], dw=cat[4], temp=temps, use=cat[5], block=cat[6],
                rec=cat[7])
