"""Device description: the nominal geometry and ADC of a set of single-axis
accelerometer channels, with JSON load/save per the data contract.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import atomic_write
from .jsonfields import JsonFields, check_limits, json_number, read_json, show_json

__all__ = [
    "Device",
    "load_device",
    "device_from_dict",
    "save_device",
    "default_device",
    "default_triad",
    "pendulum_device",
    "tetrahedron_device",
    "axes_device",
    "GRAVITY",
]

GRAVITY = 9.80665  # standard gravity, m/s^2

# Relative tolerance for the rank of [u_i, r_i x u_i]; the angular columns are
# scaled by the array's size first so the test does not depend on units.
_RANK_RTOL = 1e-9
# Positions closer than this (m) count as one point when grouping triads.
_SAME_POINT_M = 1e-9


# --------------------------------------------------------------------------
# JSON reading helpers (shared with calibration.py)
# --------------------------------------------------------------------------


DEVICE_KEYS = ("name", "sample_rate_hz", "gravity_mps2", "raw_min", "raw_max", "noise_mps2", "channels")
CHANNEL_KEYS = ("position_m", "axis", "counts_per_mps2", "zero_counts")


# --------------------------------------------------------------------------
# Device
# --------------------------------------------------------------------------


def _frozen_array(value: Any, dtype: Any, shape: tuple, name: str) -> np.ndarray:
    arr = np.array(value, dtype=dtype)  # copy: the caller's array stays theirs
    if arr.shape != shape:
        raise ValueError(f"Device.{name}: expected shape {shape}, got {arr.shape}")
    arr.setflags(write=False)
    return arr


def _normalise_rows(axes: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length (rows of zeros or non-finite give NaN)."""
    with np.errstate(all="ignore"):
        norms = np.linalg.norm(axes, axis=1)
        # Leave rows that are already unit to the last bits alone, so that
        # loading a saved device gives back exactly the same axes.
        done = np.abs(norms - 1.0) <= 4 * np.finfo(float).eps
        # Divide by the largest component first: |a|^2 of 1e200 or 1e-320
        # would overflow or underflow.
        peak = np.max(np.abs(axes), axis=1, keepdims=True)
        scaled = axes / peak
        unit = scaled / np.linalg.norm(scaled, axis=1, keepdims=True)
    return np.where(done[:, None], axes, unit)


def _geometry_rank(positions: np.ndarray, axes: np.ndarray) -> int:
    """Rank of the rows [u_i, r_i x u_i] (the 6-DOF observability test)."""
    size = float(np.max(np.linalg.norm(positions, axis=1), initial=0.0))
    ang = np.cross(positions, axes) / size if size > 0 else np.zeros_like(axes)
    rows = np.hstack([axes, ang])
    sv = np.linalg.svd(rows, compute_uv=False)
    if sv.size == 0 or sv[0] == 0:
        return 0
    return int(np.sum(sv > _RANK_RTOL * sv[0]))


def _triad_groups(positions: np.ndarray, axes: np.ndarray) -> list[tuple[int, int, int]] | None:
    """Channels as consecutive triads (3k, 3k+1, 3k+2), each at one point with
    independent axes; None when the device is not built that way."""
    n = len(positions)
    if n == 0 or n % 3:
        return None
    groups = []
    for k in range(0, n, 3):
        p = positions[k : k + 3]
        if np.max(np.abs(p - p[0])) > _SAME_POINT_M:
            return None
        if np.linalg.matrix_rank(axes[k : k + 3], tol=1e-6) < 3:
            return None
        groups.append((k, k + 1, k + 2))
    return groups


#: a real chip's sensitivity is within this factor of its nominal, either way (datasheets: a few %,
#: +-10 % for the loosest, an ADXL345's 230-282 LSB/g): beyond it the device file's scale is off
NOMINAL_FACTOR = 1.25
#: a still stretch whose |f| is below this share of g has no gravity in it: a phone's linear or user
#: acceleration (at rest |f| = 1 g; a gain error within NOMINAL_FACTOR or a tilt never takes half of it)
GRAVITY_REMOVED_G = 0.5
#: what readings below GRAVITY_REMOVED_G at rest are, and what to record instead: the one wording of the
#: convert note, the no-rest refusal's clause and displacement's, after each one's evidence ("|f| = 0.02 g ...: ")
GRAVITY_REMOVED_TEXT = ("gravity looks removed (a phone's linear or user acceleration, such as Sensor Logger's "
                        "Accelerometer.csv); calibrate, diagnose and displacement need the accelerometer's own readings, "
                        "gravity in (Sensor Logger's TotalAcceleration.csv or AccelerometerUncalibrated.csv, phyphox's "
                        "'Acceleration with g')")


@dataclass(frozen=True, eq=False)
class Device:
    """Nominal description of N single-axis channels (SI units, body frame).

    Arrays are stored read-only; ``axes`` rows are unit vectors.

    Attributes
    ----------
    name : str
    sample_rate_hz : float
        Hz.
    gravity_mps2 : float
        g at the site, m/s^2.
    raw_min, raw_max : int
        The ADC's rails, counts (signed chips: raw_min < 0).
    positions : ndarray, shape (N, 3)
        r_i, m.
    axes : ndarray, shape (N, 3)
        u_i, unit vectors.
    counts_per_mps2 : ndarray, shape (N,)
        k_i, the nominal scale.
    zero_counts : ndarray, shape (N,)
        z_i, counts at 0 m/s^2.
    noise_mps2 : float
        One channel's rms noise, m/s^2; 0: unknown, estimated from the data.
    """

    name: str
    sample_rate_hz: float
    gravity_mps2: float
    raw_min: int
    raw_max: int
    positions: np.ndarray  # (N, 3) m
    axes: np.ndarray  # (N, 3) unit
    counts_per_mps2: np.ndarray  # (N,)
    zero_counts: np.ndarray  # (N,)
    noise_mps2: float = 0.0  # rms noise of one channel, m/s^2 (project extension); 0: unknown, estimated from the data

    def __post_init__(self) -> None:
        pos = np.asarray(self.positions, dtype=float)
        n = pos.shape[0] if pos.ndim == 2 else -1
        if n < 0:
            raise ValueError(f"Device.positions: expected shape (N, 3), got {pos.shape}")
        set_ = object.__setattr__
        set_(self, "positions", _frozen_array(pos, float, (n, 3), "positions"))
        axes = _normalise_rows(_frozen_array(self.axes, float, (n, 3), "axes"))
        if not np.all(np.isfinite(axes)):
            raise ValueError("Device.axes: every axis must be a finite non-zero vector")
        axes.setflags(write=False)
        set_(self, "axes", axes)
        set_(self, "counts_per_mps2", _frozen_array(self.counts_per_mps2, float, (n,), "counts_per_mps2"))
        set_(self, "zero_counts", _frozen_array(self.zero_counts, float, (n,), "zero_counts"))
        set_(self, "raw_min", int(self.raw_min))
        set_(self, "raw_max", int(self.raw_max))
        set_(self, "sample_rate_hz", float(self.sample_rate_hz))
        set_(self, "gravity_mps2", float(self.gravity_mps2))
        set_(self, "noise_mps2", float(self.noise_mps2))
        set_(self, "name", str(self.name))

    # -- comparison (dataclass eq would compare arrays ambiguously) --
    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Device):
            return NotImplemented
        return (
            self.name == other.name
            and self.sample_rate_hz == other.sample_rate_hz
            and self.gravity_mps2 == other.gravity_mps2
            and self.raw_min == other.raw_min
            and self.raw_max == other.raw_max
            and self.noise_mps2 == other.noise_mps2
            and np.array_equal(self.positions, other.positions)
            and np.array_equal(self.axes, other.axes)
            and np.array_equal(self.counts_per_mps2, other.counts_per_mps2)
            and np.array_equal(self.zero_counts, other.zero_counts)
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def n_channels(self) -> int:
        return int(self.positions.shape[0])

    def nominal_sensitivity(self) -> np.ndarray:
        """(N, 3) nominal s_i = k_i u_i, counts per m/s^2."""
        return self.counts_per_mps2[:, None] * self.axes

    def nominal_offsets(self) -> np.ndarray:
        """(N,) nominal b_i = z_i, counts (float copy)."""
        return np.array(self.zero_counts, dtype=float)

    def noise_counts(self) -> np.ndarray:
        """(N,) rms noise of each channel in counts."""
        return self.noise_mps2 * self.counts_per_mps2

    def geometry_rank(self) -> int:
        """Rank of the rows [u_i, r_i x u_i] (6 for a 6-DOF array)."""
        return _geometry_rank(self.positions, self.axes)

    def is_array(self) -> bool:
        """True for a 6-DOF array: N >= 6 and the rows [u_i, r_i x u_i] have rank 6."""
        return self.n_channels >= 6 and self.geometry_rank() == 6

    def is_triad(self) -> bool:
        """True for a single 3-axis point sensor: N == 3, one position, axes rank 3."""
        return self.n_channels == 3 and _triad_groups(self.positions, self.axes) is not None

    def triads(self) -> list[tuple[int, int, int]] | None:
        """Channel index triples when the device is built of co-located triads
        (channels 3k..3k+2 at one point, independent axes), else None."""
        return _triad_groups(self.positions, self.axes)

    def to_dict(self) -> dict:
        """JSON-ready dict per the data contract, plus ``noise_mps2`` where the device states
        one (> 0).  0 means unknown -- every noise-dependent threshold is then estimated from
        the recording (:func:`noise.noise_for`) -- and is left out, as a written 0.0 read as
        "zero noise" (the reader takes an absent key and 0 alike)."""
        stated = {"noise_mps2": self.noise_mps2} if self.noise_mps2 > 0 else {}
        return {
            "name": self.name,
            "sample_rate_hz": self.sample_rate_hz,
            "gravity_mps2": self.gravity_mps2,
            "raw_min": self.raw_min,
            "raw_max": self.raw_max,
            **stated,
            "channels": [
                {
                    "position_m": [float(x) for x in self.positions[i]],
                    "axis": [float(x) for x in self.axes[i]],
                    "counts_per_mps2": float(self.counts_per_mps2[i]),
                    "zero_counts": json_number(self.zero_counts[i]),
                }
                for i in range(self.n_channels)
            ],
        }


def device_from_dict(d: Any, source: str = "<dict>") -> Device:
    """Validate a parsed device description and build the Device.

    Raises InputError naming ``source`` and the field on any violation.
    """
    v = JsonFields(source)
    v.no_nonfinite(d, "")
    d = v.obj(d, "")
    v.known(d, "", DEVICE_KEYS)
    name = v.string(v.get(d, "name", ""), "name")
    rate = v.number(v.get(d, "sample_rate_hz", ""), "sample_rate_hz")
    if rate <= 0:
        raise v.fail("sample_rate_hz", f"expected a number > 0, got {show_json(d['sample_rate_hz'])}")
    check_limits(v, "sample_rate_hz", rate, "sample_rate_hz")
    grav = v.number(v.get(d, "gravity_mps2", ""), "gravity_mps2")
    if grav <= 0:
        raise v.fail("gravity_mps2", f"expected a number > 0, got {show_json(d['gravity_mps2'])}")
    check_limits(v, "gravity_mps2", grav, "gravity_mps2")
    raw_min = v.integer(v.get(d, "raw_min", ""), "raw_min")
    raw_max = v.integer(v.get(d, "raw_max", ""), "raw_max")
    if raw_min >= raw_max:
        raise v.fail("raw_max", f"expected raw_max > raw_min ({raw_min}), got {raw_max}")
    check_limits(v, "raw_min", raw_min, "raw")
    check_limits(v, "raw_max", raw_max, "raw")
    noise = 0.0
    if "noise_mps2" in d:
        noise = v.number(d["noise_mps2"], "noise_mps2")
        if noise < 0:
            raise v.fail("noise_mps2", f"expected a number >= 0, got {show_json(d['noise_mps2'])}")
        check_limits(v, "noise_mps2", noise, "noise_mps2")
    chans = v.get(d, "channels", "")
    if not isinstance(chans, list):
        raise v.fail("channels", f"expected a list of channel objects, got {show_json(chans)}")
    if len(chans) == 0:
        raise v.fail("channels", "expected at least 3 channels, got an empty list")
    if len(chans) < 3:
        raise v.fail("channels", f"expected at least 3 channels, got {len(chans)}")
    n = len(chans)
    pos = np.zeros((n, 3))
    axes = np.zeros((n, 3))
    k = np.zeros(n)
    z = np.zeros(n)
    for i, ch in enumerate(chans):
        p = f"channels[{i}]"
        ch = v.obj(ch, p)
        v.known(ch, p, CHANNEL_KEYS)
        pos[i] = v.vector(v.get(ch, "position_m", p), f"{p}.position_m")
        check_limits(v, f"{p}.position_m", pos[i], "position_m")
        axes[i] = v.vector(v.get(ch, "axis", p), f"{p}.axis")
        if not np.any(axes[i]):
            raise v.fail(f"{p}.axis", "expected a non-zero vector, got [0, 0, 0]")
        k[i] = v.number(v.get(ch, "counts_per_mps2", p), f"{p}.counts_per_mps2")
        if k[i] <= 0:
            raise v.fail(f"{p}.counts_per_mps2", f"expected a number > 0, got {show_json(ch['counts_per_mps2'])}")
        check_limits(v, f"{p}.counts_per_mps2", k[i], "counts_per_mps2")
        z[i] = v.number(v.get(ch, "zero_counts", p), f"{p}.zero_counts")
        if not raw_min <= z[i] <= raw_max:
            raise v.fail(
                f"{p}.zero_counts",
                f"expected a value in [raw_min, raw_max] = [{raw_min}, {raw_max}], got {show_json(ch['zero_counts'])}",
            )
    unit = _normalise_rows(axes)
    dev = Device(
        name=name,
        sample_rate_hz=rate,
        gravity_mps2=grav,
        raw_min=raw_min,
        raw_max=raw_max,
        positions=pos,
        axes=unit,
        counts_per_mps2=k,
        zero_counts=z,
        noise_mps2=noise,
    )
    why = _geometry_problem(dev)
    if why is not None:
        raise v.fail("channels", why)
    return dev


def _geometry_problem(dev: Device) -> str | None:
    """Why the device is neither a 6-DOF array nor built of triads (None if fine)."""
    if dev.is_array() or dev.triads() is not None:
        return None
    n = dev.n_channels
    if n == 3:
        if np.max(np.abs(dev.positions - dev.positions[0])) > _SAME_POINT_M:
            return (
                "3 channels must share one position to form a triad, "
                "but they are at different positions"
            )
        r = int(np.linalg.matrix_rank(dev.axes, tol=1e-6))
        return f"the 3 axes of the triad have rank {r} < 3 (they must be independent)"
    rank = dev.geometry_rank()
    if n < 6:
        return (
            f"{n} channels are neither a triad (3 channels at one point) nor a "
            f"6-DOF array (needs at least 6 channels; rows [u_i, r_i x u_i] have rank {rank})"
        )
    return (
        f"not a 6-DOF array: rows [u_i, r_i x u_i] have rank {rank} < 6, "
        "and the channels are not co-located triads either"
    )


def load_device(path: Any) -> Device:
    """Read and validate a device description JSON file.

    Parameters
    ----------
    path : str or os.PathLike
        The device file (docs/data-contract.md).

    Returns
    -------
    Device

    Raises
    ------
    AccelcalError
        One line naming the file and the field (a misspelt key with the valid one).
    """
    doc, source = read_json(path)
    return device_from_dict(doc, source)


def save_device(device: Device, path: Any) -> None:
    """Write ``device`` as JSON (indent 2), atomically.

    Parameters
    ----------
    device : Device
    path : str or os.PathLike
        The file to write (written to a temporary file and renamed: no partial file).
    """
    text = json.dumps(device.to_dict(), indent=2, allow_nan=False) + "\n"
    atomic_write(path, lambda f: f.write(text))


# --------------------------------------------------------------------------
# Built-in devices
# --------------------------------------------------------------------------


def default_device() -> Device:
    """The seed prototype: three dual-axis chips (ADXL202E) on an r = 60 mm circle.

    Chip k at phi_k = 120 k deg; channel 2k along the tangent
    (-sin phi, cos phi, 0), channel 2k+1 along +z.

    Returns
    -------
    Device
        ``seed-6ch-r60``: 60 Hz, raw 0..10000, 1250 counts per g about 5000 counts,
        noise 0.02 m/s^2.
    """
    r = 0.06
    pos, axes = [], []
    for k in range(3):
        phi = math.radians(120.0 * k)
        p = [r * math.cos(phi), r * math.sin(phi), 0.0]
        pos += [p, p]
        axes += [[-math.sin(phi), math.cos(phi), 0.0], [0.0, 0.0, 1.0]]
    return Device(
        name="seed-6ch-r60",
        sample_rate_hz=60.0,
        gravity_mps2=GRAVITY,
        raw_min=0,
        raw_max=10000,
        positions=np.array(pos),
        axes=np.array(axes),
        counts_per_mps2=np.full(6, 1250.0 / GRAVITY),
        zero_counts=np.full(6, 5000.0),
        noise_mps2=0.02,
    )


# 16-bit ADC, +-2 g full scale: 16384 counts per g.
_TRIAD_K = 16384.0 / GRAVITY


def default_triad() -> Device:
    """A 3-axis point sensor at the origin (16-bit ADC, +-2 g, 100 Hz)."""
    return Device(
        name="triad-16bit",
        sample_rate_hz=100.0,
        gravity_mps2=GRAVITY,
        raw_min=0,
        raw_max=65535,
        positions=np.zeros((3, 3)),
        axes=np.eye(3),
        counts_per_mps2=np.full(3, _TRIAD_K),
        zero_counts=np.full(3, 32768.0),
        noise_mps2=0.005,
    )


def pendulum_device(r1: float = 0.1, r2: float = 0.3) -> Device:
    """Two triads on the body x axis at r1 and r2 (channels 0-2 and 3-5, along
    x, y, z), same ADC as :func:`default_triad`; body origin is the pivot."""
    if not (math.isfinite(r1) and math.isfinite(r2)) or r1 == r2:
        raise ValueError(f"pendulum_device: need finite r1 != r2, got {r1}, {r2}")
    pos = np.array([[r1, 0.0, 0.0]] * 3 + [[r2, 0.0, 0.0]] * 3)
    return Device(
        name="pendulum-2triad",
        sample_rate_hz=100.0,
        gravity_mps2=GRAVITY,
        raw_min=0,
        raw_max=65535,
        positions=pos,
        axes=np.vstack([np.eye(3), np.eye(3)]),
        counts_per_mps2=np.full(6, _TRIAD_K),
        zero_counts=np.full(6, 32768.0),
        noise_mps2=0.005,
    )


# 16-bit ADC, +-16 g full scale (2048 counts per g): a centripetal 30^2 rad^2/s^2 x 50 mm is 4.6 g.
_ARRAY_K = 2048.0 / GRAVITY


def _triad_array(name: str, points: np.ndarray) -> Device:
    """Triads (x, y, z channels) at ``points`` (K, 3) m: 16-bit, +-16 g, 500 Hz, 0.01 m/s^2 rms."""
    n = 3 * len(points)
    return Device(name=name, sample_rate_hz=500.0, gravity_mps2=GRAVITY, raw_min=0, raw_max=65535,
                  positions=np.repeat(np.asarray(points, float), 3, axis=0), axes=np.tile(np.eye(3), (len(points), 1)),
                  counts_per_mps2=np.full(n, _ARRAY_K), zero_counts=np.full(n, 32768.0), noise_mps2=0.01)


def tetrahedron_device(r: float = 0.05) -> Device:
    """Four triads at the corners of a regular tetrahedron, r (m) from the body origin (12
    channels; 3k..3k+2 along x, y, z): a layout from which the accelerometers observe omega
    (all six rate products).  16-bit ADC, +-16 g, 500 Hz, 0.01 m/s^2 rms noise."""
    if not (math.isfinite(r) and r > 0):
        raise ValueError(f"tetrahedron_device: need a finite r > 0, got {r}")
    return _triad_array(f"tetra-12ch-r{r * 1000:g}", r / math.sqrt(3.0) * np.array([[1, 1, 1], [1, -1, -1],
                                                                                [-1, 1, -1], [-1, -1, 1]], float))


def axes_device(r: float = 0.05, origin: bool = True) -> Device:
    """Triads on the body x, y and z axes at r (m), and with ``origin`` one at the origin (12
    channels, else 9); same ADC as :func:`tetrahedron_device`."""
    if not (math.isfinite(r) and r > 0):
        raise ValueError(f"axes_device: need a finite r > 0, got {r}")
    pts = np.vstack([np.zeros((1, 3)), r * np.eye(3)]) if origin else r * np.eye(3)
    return _triad_array(f"axes-{3 * len(pts)}ch-r{r * 1000:g}", pts)
