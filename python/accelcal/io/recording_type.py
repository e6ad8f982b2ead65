"""The Recording: n samples of N raw channels plus reference columns, in memory, and the
data contract's rules on one built from arrays (:func:`recording_from_arrays`).  Reading and
writing it as CSV: :mod:`accelcal.io.recording`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .csvtable import RAW_RE, REFERENCE_NAMES

__all__ = ["Recording", "recording_from_arrays", "check_content"]


def _nan_array(value: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    if value is None:
        return np.full(shape, np.nan)
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != shape:
        raise ValueError(f"Recording.{name}: expected shape {shape}, got {arr.shape}")
    return arr


def _int_array(value: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    arr = np.asarray(value)
    if arr.shape != shape:
        raise ValueError(f"Recording.{name}: expected shape {shape}, got {arr.shape}")
    if arr.dtype.kind == "f":
        if not np.all(np.isfinite(arr)) or np.any(arr != np.round(arr)):
            raise ValueError(f"Recording.{name}: expected integers, got non-integral values")
    elif arr.dtype.kind not in "iub":
        raise ValueError(f"Recording.{name}: expected integers, got dtype {arr.dtype}")
    return arr.astype(np.int64, copy=False)


@dataclass(eq=False)
class Recording:
    """One recording: n samples of N raw channels plus reference columns.

    Unknown reference values are NaN (``pose`` -1); absent columns are
    all-NaN.  Vectors are in the body frame B (the data contract).

    Attributes
    ----------
    t : ndarray, shape (n,)
        Sample times, s (strictly increasing in a file).
    raw : ndarray of int64, shape (n, N)
        Channel readings, counts.
    f : ndarray, shape (n, 3)
        Reference specific force at the origin O, m/s^2 (NaN: unknown).
    w : ndarray, shape (n, 3)
        Reference angular velocity, rad/s (NaN: unknown).
    dw : ndarray, shape (n, 3)
        Reference angular acceleration, rad/s^2 (NaN: unknown).
    temp_c : ndarray, shape (n,)
        Temperature, degC (NaN: unknown).
    pose : ndarray of int64, shape (n,)
        Static-pose label (>= 0) shared by one pose's samples; -1 while moving or unknown.
    metadata : dict of str to str
        The file's ``# key: value`` comments.
    extra : dict of str to list of str
        Unknown columns, as text, n values each.
    source : str
        The file read from, for messages (``"<memory>"`` when built in memory).
    lines : int, ndarray of int64 (n,) or None
        Each sample's line in the CSV file it was read from (an int: the first sample's, the
        others following); None when built in memory (see :meth:`line`).
    notes : list of str
        What a check changed in reading the file (e.g. t read as milliseconds).
    thinning : accelcal.io.thinned.Thinning or None
        Where the samples are evenly spaced windows of a longer recording
        (:mod:`accelcal.io.thinned`): which; None for every sample.
    """

    t: np.ndarray  # (n,) s
    raw: np.ndarray  # (n, N) int64
    f: np.ndarray | None = None  # (n, 3) m/s^2, specific force at O
    w: np.ndarray | None = None  # (n, 3) rad/s
    dw: np.ndarray | None = None  # (n, 3) rad/s^2
    temp_c: np.ndarray | None = None  # (n,) degC
    pose: np.ndarray | None = None  # (n,) int64, -1 = moving/unknown
    metadata: dict[str, str] = field(default_factory=dict)
    extra: dict[str, list[str]] = field(default_factory=dict)
    source: str = "<memory>"
    # file line of each sample when read from CSV (see line())
    lines: Any = field(default=None, repr=False)
    # what a check changed in reading the file (recording_checks.seconds: t in milliseconds)
    notes: list = field(default_factory=list, repr=False, compare=False)
    # the windows of a longer recording these samples are (io.thinned), None: every sample
    thinning: Any = field(default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        self.t = np.asarray(self.t, dtype=np.float64)
        if self.t.ndim != 1:
            raise ValueError(f"Recording.t: expected shape (n,), got {self.t.shape}")
        n = self.t.shape[0]
        raw = np.asarray(self.raw)
        if raw.ndim != 2 or raw.shape[0] != n:
            raise ValueError(f"Recording.raw: expected shape ({n}, N), got {raw.shape}")
        self.raw = _int_array(raw, raw.shape, "raw")
        self.f = _nan_array(self.f, (n, 3), "f")
        self.w = _nan_array(self.w, (n, 3), "w")
        self.dw = _nan_array(self.dw, (n, 3), "dw")
        self.temp_c = _nan_array(self.temp_c, (n,), "temp_c")
        self.pose = np.full(n, -1, dtype=np.int64) if self.pose is None else _int_array(self.pose, (n,), "pose")
        self.metadata = {str(k): str(v) for k, v in dict(self.metadata).items()}
        extra = {}
        for k, v in dict(self.extra).items():
            vals = [str(x) for x in v]
            if len(vals) != n:
                raise ValueError(f"Recording.extra[{k!r}]: expected {n} values, got {len(vals)}")
            extra[str(k)] = vals
        self.extra = extra
        self.source = str(self.source)

    @property
    def n_samples(self) -> int:
        return int(self.t.shape[0])

    @property
    def n_channels(self) -> int:
        return int(self.raw.shape[1])

    def line(self, i: int) -> int:
        """Where sample i is, as InputError's ``row``: its line in the CSV file
        (comments and header counted) when read from one, else i + 1."""
        if self.lines is None:
            return int(i) + 1
        if isinstance(self.lines, int):
            return self.lines + int(i)
        return int(self.lines[int(i)])

    def has_f(self) -> bool:
        """Any finite reference specific force."""
        return bool(np.isfinite(self.f).any())

    def has_omega(self) -> bool:
        return bool(np.isfinite(self.w).any())

    def has_alpha(self) -> bool:
        return bool(np.isfinite(self.dw).any())

    def has_temp(self) -> bool:
        return bool(np.isfinite(self.temp_c).any())

    def has_pose(self) -> bool:
        return bool(np.any(self.pose >= 0))

    def pose_labels(self) -> np.ndarray:
        """Sorted unique static-pose labels (>= 0)."""
        return np.unique(self.pose[self.pose >= 0])

    def select(self, mask: Any) -> "Recording":
        """New Recording with the samples picked by a boolean mask (n,) or by
        strictly increasing indices (so t stays increasing)."""
        m = np.asarray(mask)
        if m.dtype == bool:
            if m.shape != (self.n_samples,):
                raise ValueError(f"select: mask must have shape ({self.n_samples},), got {m.shape}")
            idx = np.flatnonzero(m)
        elif m.dtype.kind in "iu" and m.ndim == 1:
            idx = m.astype(np.int64)
            if idx.size and (np.any(np.diff(idx) <= 0) or idx[0] < 0 or idx[-1] >= self.n_samples):
                raise ValueError("select: indices must be strictly increasing and in range")
        else:
            raise ValueError("select: expected a boolean mask or an index array")
        ilist = idx.tolist()
        return Recording(
            t=self.t[idx],
            raw=self.raw[idx],
            f=self.f[idx],
            w=self.w[idx],
            dw=self.dw[idx],
            temp_c=self.temp_c[idx],
            pose=self.pose[idx],
            metadata=dict(self.metadata),
            extra={k: [v[i] for i in ilist] for k, v in self.extra.items()},
            source=self.source,
            lines=None if self.lines is None else np.array([self.line(i) for i in ilist], dtype=np.int64),
            thinning=self.thinning,
        )

    def __eq__(self, other: object) -> bool:
        """Same samples, references (NaN equal to NaN), metadata and extras."""
        if not isinstance(other, Recording):
            return NotImplemented
        return (
            np.array_equal(self.t, other.t)
            and self.raw.shape == other.raw.shape
            and np.array_equal(self.raw, other.raw)
            and all(
                np.array_equal(getattr(self, k), getattr(other, k), equal_nan=True)
                for k in ("f", "w", "dw", "temp_c")
            )
            and np.array_equal(self.pose, other.pose)
            and self.metadata == other.metadata
            and self.extra == other.extra
        )

    __hash__ = None  # type: ignore[assignment]


def check_content(rec: Recording) -> None:
    """Contract rules on a Recording built in memory (ValueError: a bug, not input)."""
    if rec.n_samples == 0:
        raise ValueError("Recording: no samples")
    if rec.n_channels == 0:
        raise ValueError("Recording: no raw channels")
    if not np.all(np.isfinite(rec.t)):
        raise ValueError(f"Recording.t: not finite at sample {int(np.flatnonzero(~np.isfinite(rec.t))[0])}")
    bad = np.flatnonzero(~(np.diff(rec.t) > 0))
    if bad.size:
        raise ValueError(f"Recording.t: not strictly increasing at sample {int(bad[0]) + 1}")
    for name in ("f", "w", "dw"):
        arr = getattr(rec, name)
        if np.isinf(arr).any():
            raise ValueError(f"Recording.{name}: infinite value (use NaN for unknown)")
        fin = np.isfinite(arr)
        part = np.flatnonzero(fin.any(axis=1) & ~fin.all(axis=1))
        if part.size:
            raise ValueError(f"Recording.{name}: partly given vector at sample {int(part[0])}")
    if np.isinf(rec.temp_c).any():
        raise ValueError("Recording.temp_c: infinite value (use NaN for unknown)")
    if np.any(rec.pose < -1):
        raise ValueError("Recording.pose: labels must be >= 0, or -1 for moving/unknown")
    for k in rec.extra:
        if k in ("t",) or k in REFERENCE_NAMES or RAW_RE.fullmatch(k):
            raise ValueError(f"Recording.extra: column name {k!r} is reserved")


def recording_from_arrays(
    t: Any,
    raw: Any,
    *,
    f: Any = None,
    w: Any = None,
    dw: Any = None,
    temp_c: Any = None,
    pose: Any = None,
    metadata: dict[str, str] | None = None,
) -> Recording:
    """Build a Recording from arrays, checking shapes and the contract rules
    (finite, strictly increasing t; integral raw; whole vectors; pose >= -1).
    Raises ValueError on a violation."""
    raw = np.asarray(raw)
    if raw.ndim == 1:
        raise ValueError("recording_from_arrays: raw must be 2-D (n, N)")
    rec = Recording(t=t, raw=raw, f=f, w=w, dw=dw, temp_c=temp_c, pose=pose, metadata=dict(metadata or {}))
    check_content(rec)
    return rec
