"""Calibration: the estimated offset, sensitivity vector (and optionally
position, uncertainties, temperature terms, residuals) of every channel, with
JSON load/save per the data contract.  The estimators live in ``calibrate``.
"""

from __future__ import annotations

import difflib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .device import Device
from .jsonfields import KEY_CUTOFF, JsonFields, check_limits, json_number, read_json, show_json
from ..errors import InputError, atomic_write

__all__ = ["Calibration", "KNOWN_KEYS", "NOMINAL", "load_calibration", "save_calibration", "calibration_from_dict",
           "calibration_to_dict"]

#: the calibration argument that names the device's datasheet values (load_calibration)
NOMINAL = "nominal"

# Per-channel optional JSON keys: (Calibration attribute, JSON key, width).
# Width 1 is a number per channel, 3 a 3-vector.  A channel may leave one out
# (e.g. position_m: "absent means nominal"); the array then holds NaN there.
_OPTIONAL_CHANNEL_FIELDS = (
    ("positions", "position_m", 3),
    ("offset_sigma", "offset_sigma_counts", 1),
    ("sensitivity_sigma", "sensitivity_sigma", 3),
    ("position_sigma", "position_sigma_m", 3),
    ("offset_tc", "offset_tc_counts_per_c", 1),
    ("gain_tc", "gain_tc_per_c", 1),
    ("nonlin_k2", "nonlin_k2_counts_per_mps2_2", 1),
    ("nonlin_k3", "nonlin_k3_counts_per_mps2_3", 1),
    ("time_skew_s", "time_skew_s", 1),
)
# Top-level optional numbers >= 0: (Calibration attribute, JSON key): the thermal lags (s)
_OPTIONAL_TOP_LAGS = (("temp_offset_tau_s", "temperature_offset_tau_s"),
                      ("temp_gain_tau_s", "temperature_gain_tau_s"))
_NONNEGATIVE = {"offset_sigma", "sensitivity_sigma", "position_sigma"}
_KNOWN_TOP = {"device", "method", "channels", "temperature_ref_c", "residual_rms_counts", "poses_used"} | {
    key for _, key in _OPTIONAL_TOP_LAGS}
#: every top-level key a calibration file's reader knows ("fit", "poses" and "warnings" are kept in
#: ``extra``; "warnings": what ``accelcal calibrate`` warned of, one line each, which ``header`` carries as a
#: comment); an unknown key close to one of these is refused as a misspelling (jsonfields.KEY_CUTOFF)
KNOWN_KEYS = tuple(sorted(_KNOWN_TOP | {"fit", "poses", "warnings"}))


def _opt_array(value: Any, shape: tuple[int, ...], name: str) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.array(value, dtype=np.float64)
    if arr.shape != shape:
        raise ValueError(f"Calibration.{name}: expected shape {shape}, got {arr.shape}")
    return arr


@dataclass(eq=False)
class Calibration:
    """Per-channel calibration of a device (counts, m, SI units).

    The reading model is ``raw_i = b_i + s_i . f(r_i)``: apply it to a 3-axis
    reading as ``f = np.linalg.solve(sensitivity, raw - offsets)`` (or
    :func:`accelcal.resolve`, either engine).  ``positions`` None means every
    channel is at its nominal position; a NaN row means that channel's position
    was not estimated (nominal).  Optional per-channel arrays use NaN the same
    way; a sigma that is None (or NaN) is unknown or not fitted (a 3-vector sigma may be NaN in
    some components: those the method held instead of fitting, null in the JSON).

    Attributes
    ----------
    device : str
        The device's name.
    method : str
        ``full``, ``gain``, ``offset``, ``jigfree`` or ``nominal``.
    offsets : ndarray, shape (N,)
        b_i, counts at f = 0.
    sensitivity : ndarray, shape (N, 3)
        Row i is s_i, counts per m/s^2 (its norm the gain, its direction the axis).
    positions : ndarray, shape (N, 3), or None
        r_i, m.
    offset_sigma, sensitivity_sigma, position_sigma : ndarray or None
        1-sigma of each (counts; counts per m/s^2; m).
    temp_ref_c, offset_tc, gain_tc : float, ndarray (N,) or None
        Temperature terms: reference degC, counts per degC, fraction per degC.
    temp_offset_tau_s, temp_gain_tau_s : float or None
        The first-order thermal lag (s) of the temperature the offset and the gain tempcos act
        on (effects/temperature.py's ``tau_s``); None or 0: the recorded temperature itself.
    nonlin_k2, nonlin_k3 : ndarray (N,) or None
        The reading gains ``k2 a^2 + k3 a^3`` counts, ``a = (linear reading - b_i) / |s_i|`` in m/s^2
        (effects/nonlinearity.py): counts per (m/s^2)^2 and per (m/s^2)^3.
    time_skew_s : ndarray (N,) or None
        Channel i's sample is taken tau_i seconds late: it reads the motion at t + tau_i
        (effects/timing.py's ``time_skew``).
    The correction of these terms (firmware.terms) runs before the resolve.
    residual_rms_per_channel : ndarray, shape (N,), or None
        Counts.
    residual_rms_per_pose : dict of str to float, or None
        Counts, by pose name.
    poses_used : list of str or None
    extra : dict
        The fit's details: ``fit`` (model, chi2, dof, not_fitted ...), ``poses``
        (each pose's f and samples), ``set_aside``, ``outliers``, ``warnings``.
    """

    device: str
    method: str
    offsets: np.ndarray  # (N,) counts
    sensitivity: np.ndarray  # (N, 3) counts per m/s^2
    positions: np.ndarray | None = None  # (N, 3) m
    offset_sigma: np.ndarray | None = None  # (N,) counts
    sensitivity_sigma: np.ndarray | None = None  # (N, 3)
    position_sigma: np.ndarray | None = None  # (N, 3) m
    temp_ref_c: float | None = None
    offset_tc: np.ndarray | None = None  # (N,) counts per degC
    gain_tc: np.ndarray | None = None  # (N,) fraction per degC
    nonlin_k2: np.ndarray | None = None  # (N,) counts per (m/s^2)^2
    nonlin_k3: np.ndarray | None = None  # (N,) counts per (m/s^2)^3
    time_skew_s: np.ndarray | None = None  # (N,) s
    temp_offset_tau_s: float | None = None  # s
    temp_gain_tau_s: float | None = None  # s
    residual_rms_per_channel: np.ndarray | None = None  # (N,) counts
    residual_rms_per_pose: dict[str, float] | None = None
    poses_used: list | None = None
    extra: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.offsets = np.array(self.offsets, dtype=np.float64)
        if self.offsets.ndim != 1:
            raise ValueError(f"Calibration.offsets: expected shape (N,), got {self.offsets.shape}")
        n = self.offsets.shape[0]
        self.sensitivity = np.array(self.sensitivity, dtype=np.float64)
        if self.sensitivity.shape != (n, 3):
            raise ValueError(f"Calibration.sensitivity: expected shape ({n}, 3), got {self.sensitivity.shape}")
        for attr, _, width in _OPTIONAL_CHANNEL_FIELDS:
            shape = (n, 3) if width == 3 else (n,)
            setattr(self, attr, _opt_array(getattr(self, attr), shape, attr))
        self.residual_rms_per_channel = _opt_array(self.residual_rms_per_channel, (n,), "residual_rms_per_channel")
        if self.temp_ref_c is not None:
            self.temp_ref_c = float(self.temp_ref_c)
        for attr, _ in _OPTIONAL_TOP_LAGS:
            val = getattr(self, attr)
            if val is not None:
                val = float(val)
                if not (np.isfinite(val) and val >= 0.0):
                    raise ValueError(f"Calibration.{attr}: expected a finite number >= 0, got {val}")
                setattr(self, attr, val)
        if self.residual_rms_per_pose is not None:
            self.residual_rms_per_pose = {str(k): float(v) for k, v in self.residual_rms_per_pose.items()}
        if self.poses_used is not None:
            self.poses_used = list(self.poses_used)
        self.extra = dict(self.extra)

    @property
    def n_channels(self) -> int:
        return int(self.offsets.shape[0])

    @classmethod
    def nominal(cls, device: Device) -> "Calibration":
        """The device's datasheet values: offsets = zero_counts, s_i = k_i u_i."""
        return cls(
            device=device.name,
            method="nominal",
            offsets=device.nominal_offsets(),
            sensitivity=device.nominal_sensitivity(),
        )

    def positions_or_nominal(self, device: Device) -> np.ndarray:
        """(N, 3) positions: estimated ones where known, nominal elsewhere."""
        if device.n_channels != self.n_channels:
            raise ValueError(
                f"calibration has {self.n_channels} channels but device {device.name!r} has {device.n_channels}"
            )
        nominal = np.array(device.positions, dtype=np.float64)
        if self.positions is None:
            return nominal
        known = np.all(np.isfinite(self.positions), axis=1)
        return np.where(known[:, None], self.positions, nominal)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Calibration):
            return NotImplemented

        def same(a: Any, b: Any) -> bool:
            if a is None or b is None:
                return a is None and b is None
            return np.array_equal(a, b, equal_nan=True)

        arrays = ["offsets", "sensitivity", "residual_rms_per_channel"] + [a for a, _, _ in _OPTIONAL_CHANNEL_FIELDS]
        return (
            self.device == other.device
            and self.method == other.method
            and all(same(getattr(self, a), getattr(other, a)) for a in arrays)
            and self.temp_ref_c == other.temp_ref_c
            and all(getattr(self, a) == getattr(other, a) for a, _ in _OPTIONAL_TOP_LAGS)
            and self.residual_rms_per_pose == other.residual_rms_per_pose
            and self.poses_used == other.poses_used
            and self.extra == other.extra
        )

    __hash__ = None  # type: ignore[assignment]


# --------------------------------------------------------------------------
# JSON
# --------------------------------------------------------------------------


def _row_or_none(arr: np.ndarray | None, i: int, name: str) -> list | float | None:
    """Channel i's value of an optional array for JSON (None when unknown)."""
    if arr is None:
        return None
    row = np.atleast_1d(arr[i])
    fin = np.isfinite(row)
    if not fin.any():
        return None
    if not fin.all():
        if name in _NONNEGATIVE:
            # a sigma a method leaves out for some components (held, not fitted): null there
            return [float(x) if f else None for x, f in zip(row, fin)]
        raise ValueError(f"Calibration.{name}: channel {i} is partly NaN (give all 3 values or none)")
    return float(row[0]) if arr.ndim == 1 else [float(x) for x in row]


def calibration_to_dict(cal: Calibration) -> dict:
    """JSON-ready dict per the data contract; optional parts only when present."""
    if not np.all(np.isfinite(cal.offsets)) or not np.all(np.isfinite(cal.sensitivity)):
        raise ValueError("Calibration: offsets and sensitivity must be finite")
    channels = []
    for i in range(cal.n_channels):
        ch: dict[str, Any] = {
            "offset_counts": float(cal.offsets[i]),
            "sensitivity": [float(x) for x in cal.sensitivity[i]],
        }
        for attr, key, _ in _OPTIONAL_CHANNEL_FIELDS:
            value = _row_or_none(getattr(cal, attr), i, attr)
            if value is not None:
                ch[key] = value
        channels.append(ch)
    out: dict[str, Any] = {"device": cal.device, "method": cal.method, "channels": channels}
    if cal.temp_ref_c is not None:
        out["temperature_ref_c"] = float(cal.temp_ref_c)
    for attr, key in _OPTIONAL_TOP_LAGS:
        if getattr(cal, attr) is not None:
            out[key] = float(getattr(cal, attr))
    resid: dict[str, Any] = {}
    if cal.residual_rms_per_channel is not None:
        if not np.all(np.isfinite(cal.residual_rms_per_channel)):
            raise ValueError("Calibration.residual_rms_per_channel: must be finite")
        resid["per_channel"] = [float(x) for x in cal.residual_rms_per_channel]
    if cal.residual_rms_per_pose is not None:
        resid["per_pose"] = {str(k): float(v) for k, v in cal.residual_rms_per_pose.items()}
    if resid:
        out["residual_rms_counts"] = resid
    if cal.poses_used is not None:
        out["poses_used"] = [p if isinstance(p, str) else json_number(p) for p in cal.poses_used]
    for k, v in cal.extra.items():
        if k in _KNOWN_TOP:
            raise ValueError(f"Calibration.extra: key {k!r} is reserved")
        out[k] = v
    return out


def save_calibration(cal: Calibration, path: Any) -> None:
    """Write ``cal`` as JSON (indent 2), atomically.

    Parameters
    ----------
    cal : Calibration
    path : str or os.PathLike
        The file to write (written to a temporary file and renamed: no partial file).
    """
    text = json.dumps(calibration_to_dict(cal), indent=2, allow_nan=False) + "\n"
    atomic_write(path, lambda f: f.write(text))


def calibration_from_dict(d: Any, source: str = "<dict>", device: Device | None = None) -> Calibration:
    """Validate a parsed calibration and build it; with ``device``, also check
    it belongs to that device and fill unestimated positions with nominal."""
    v = JsonFields(source)
    v.no_nonfinite(d, "")
    d = v.obj(d, "")
    v.known(d, "", KNOWN_KEYS)
    dev_name = v.string(v.get(d, "device", ""), "device")
    method = v.string(v.get(d, "method", ""), "method")
    chans = v.get(d, "channels", "")
    if not isinstance(chans, list):
        raise v.fail("channels", f"expected a list of channel objects, got {show_json(chans)}")
    if not chans:
        raise v.fail("channels", "expected at least one channel, got an empty list")
    if device is not None:
        if dev_name != device.name:
            raise v.fail("device", f"calibration is for {dev_name!r} but the device is {device.name!r}")
        if len(chans) != device.n_channels:
            raise v.fail(
                "channels",
                f"calibration has {len(chans)} channels but the device {device.name!r} has {device.n_channels}",
            )
    n = len(chans)
    offsets = np.zeros(n)
    sens = np.zeros((n, 3))
    opt: dict[str, np.ndarray] = {}
    for i, ch in enumerate(chans):
        p = f"channels[{i}]"
        ch = v.obj(ch, p)
        v.known(ch, p, ["offset_counts", "sensitivity"] + [key for _, key, _ in _OPTIONAL_CHANNEL_FIELDS])
        offsets[i] = v.number(v.get(ch, "offset_counts", p), f"{p}.offset_counts")
        check_limits(v, f"{p}.offset_counts", offsets[i], "offset_counts")
        sens[i] = v.vector(v.get(ch, "sensitivity", p), f"{p}.sensitivity")
        check_limits(v, f"{p}.sensitivity", sens[i], "sensitivity")
        if not np.any(sens[i]):
            raise v.fail(f"{p}.sensitivity", "expected a non-zero vector, got [0, 0, 0]")
        for attr, key, width in _OPTIONAL_CHANNEL_FIELDS:
            if key not in ch:
                continue
            fp = f"{p}.{key}"
            if width == 3:
                raw = ch[key]
                # a sigma may be null for components the method held instead of fitting (not all three)
                held = (attr in _NONNEGATIVE and isinstance(raw, list) and None in raw
                        and any(x is not None for x in raw))
                value = v.vector([0.0 if x is None else x for x in raw] if held else raw, fp)
                if held:
                    value[[x is None for x in raw]] = np.nan
            else:
                value = np.array([v.number(ch[key], fp)])
            if key == "position_m":
                check_limits(v, fp, value, "position_m")
            if attr in _NONNEGATIVE and np.any(value < 0):
                raise v.fail(fp, f"expected values >= 0 (an uncertainty), got {show_json(ch[key])}")
            if attr not in opt:
                opt[attr] = np.full((n, 3) if width == 3 else (n,), np.nan)
            opt[attr][i] = value if width == 3 else value[0]

    if "warnings" in d and not (isinstance(d["warnings"], list) and all(isinstance(x, str) for x in d["warnings"])):
        raise v.fail("warnings", f"expected a list of one-line texts, got {show_json(d['warnings'])}")
    temp_ref = None
    if "temperature_ref_c" in d:
        temp_ref = v.number(d["temperature_ref_c"], "temperature_ref_c")
    elif "offset_tc" in opt or "gain_tc" in opt:
        which = "offset_tc_counts_per_c" if "offset_tc" in opt else "gain_tc_per_c"
        raise v.fail("temperature_ref_c", f"missing (required when channels give {which})")
    lags = {}
    for attr, key in _OPTIONAL_TOP_LAGS:
        if key in d:
            lags[attr] = v.number(d[key], key)
            if lags[attr] < 0:
                raise v.fail(key, f"expected a time constant >= 0 s, got {show_json(d[key])}")

    per_channel = per_pose = None
    if "residual_rms_counts" in d:
        res = v.obj(d["residual_rms_counts"], "residual_rms_counts")
        if "per_channel" in res:
            pc = res["per_channel"]
            fp = "residual_rms_counts.per_channel"
            if not isinstance(pc, list) or len(pc) != n:
                got = len(pc) if isinstance(pc, list) else show_json(pc)
                raise v.fail(fp, f"expected {n} numbers (one per channel), got {got}")
            per_channel = np.array([v.number(x, f"{fp}[{k}]") for k, x in enumerate(pc)])
            if np.any(per_channel < 0):
                k = int(np.flatnonzero(per_channel < 0)[0])
                raise v.fail(f"{fp}[{k}]", f"expected a number >= 0, got {show_json(pc[k])}")
        if "per_pose" in res:
            pp = v.obj(res["per_pose"], "residual_rms_counts.per_pose")
            per_pose = {}
            for k, x in pp.items():
                val = v.number(x, f"residual_rms_counts.per_pose.{k}")
                if val < 0:
                    raise v.fail(f"residual_rms_counts.per_pose.{k}", f"expected a number >= 0, got {show_json(x)}")
                per_pose[k] = val

    poses = None
    if "poses_used" in d:
        pu = d["poses_used"]
        if not isinstance(pu, list):
            raise v.fail("poses_used", f"expected a list of pose labels, got {show_json(pu)}")
        poses = []
        for k, x in enumerate(pu):
            if isinstance(x, str):
                poses.append(x)
            else:
                poses.append(v.integer(x, f"poses_used[{k}]"))

    positions = opt.get("positions")
    if device is not None and positions is not None:
        # Absent position_m means nominal: with the device at hand, say so explicitly.
        known = np.all(np.isfinite(positions), axis=1)
        positions = np.where(known[:, None], positions, device.positions)
    return Calibration(
        device=dev_name,
        method=method,
        offsets=offsets,
        sensitivity=sens,
        positions=positions,
        offset_sigma=opt.get("offset_sigma"),
        sensitivity_sigma=opt.get("sensitivity_sigma"),
        position_sigma=opt.get("position_sigma"),
        temp_ref_c=temp_ref,
        offset_tc=opt.get("offset_tc"),
        gain_tc=opt.get("gain_tc"),
        nonlin_k2=opt.get("nonlin_k2"),
        nonlin_k3=opt.get("nonlin_k3"),
        time_skew_s=opt.get("time_skew_s"),
        temp_offset_tau_s=lags.get("temp_offset_tau_s"),
        temp_gain_tau_s=lags.get("temp_gain_tau_s"),
        residual_rms_per_channel=per_channel,
        residual_rms_per_pose=per_pose,
        poses_used=poses,
        extra={k: val for k, val in d.items() if k not in _KNOWN_TOP},
    )


def load_calibration(path: Any, device: Device | None = None) -> Calibration:
    """Read and validate a calibration JSON file (see calibration_from_dict).  ``"nominal"``
    (when no file has that name) is the device's datasheet values (:meth:`Calibration.nominal`):
    a calibration to diagnose or estimate with before any exists.

    Parameters
    ----------
    path : str or os.PathLike
        The calibration file (docs/data-contract.md), or ``"nominal"``.
    device : Device, optional
        The device it is for: the calibration must name it and have its channels (positions
        not estimated are filled with its nominal ones); ``"nominal"`` needs it.

    Returns
    -------
    Calibration
    """
    if isinstance(path, str) and path == NOMINAL and device is not None and not Path(path).is_file():
        return Calibration.nominal(device)
    if isinstance(path, str) and not Path(path).exists() and difflib.get_close_matches(path, [NOMINAL], 1, KEY_CUTOFF):
        raise InputError(path, f"no such calibration file; did you mean {NOMINAL!r} (the device's datasheet values)?")
    doc, source = read_json(path)
    return calibration_from_dict(doc, source, device)
