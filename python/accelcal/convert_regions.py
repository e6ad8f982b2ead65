"""Pose labels for ``accelcal convert``: regions of sample numbers from a JSON session list
(imucal's), or names per sample (a ``part`` column, a log's blocks); regions named
``x_p, x_a, y_p, y_a, z_p, z_a`` (that axis up, or down) can state the reference specific
force, and regions whose name ends in ``_rot`` are motions, not poses."""
from __future__ import annotations

from typing import Any

import numpy as np

from .errors import InputError
from .jsonfields import JsonFields, read_json

__all__ = ["POSE_DIRECTIONS", "is_motion", "label_poses", "read_regions"]

POSE_DIRECTIONS = {"x_p": (1, 0, 0), "x_a": (-1, 0, 0), "y_p": (0, 1, 0), "y_a": (0, -1, 0),
                   "z_p": (0, 0, 1), "z_a": (0, 0, -1)}


def read_regions(path: Any) -> list[tuple[str, int, int]]:
    """Pose regions from a JSON object ``{name: {"start": s, "end": e}, ...}``.

    Returns
    -------
    list of (name, start, end)
        In the file's order; samples ``start <= k < end``.

    Raises
    ------
    InputError
        Naming the field (``x_p.start``) that is missing, not an integer >= 0, or whose
        range is empty or overlaps another.
    """
    doc, source = read_json(path)
    v = JsonFields(source)
    v.no_nonfinite(doc, "")
    doc = v.obj(doc, "")
    if not doc:
        raise v.fail("", "no regions (expected {name: {\"start\": ..., \"end\": ...}, ...})")
    out = []
    for name, reg in doc.items():
        reg = v.obj(reg, name)
        v.known(reg, name, ("start", "end"))
        start = v.integer(v.get(reg, "start", name), f"{name}.start")
        end = v.integer(v.get(reg, "end", name), f"{name}.end")
        if start < 0:
            raise v.fail(f"{name}.start", f"expected a sample number >= 0, got {start}")
        if end <= start:
            raise v.fail(f"{name}.end", f"expected end > start ({start}), got {end}")
        for other, s, e in out:
            if start < e and s < end:
                raise v.fail(name, f"[{start}, {end}) overlaps region {other!r} [{s}, {e})")
        out.append((name, start, end))
    return out


def is_motion(name: str) -> bool:
    return name.lower().endswith("_rot")


def label_poses(index: np.ndarray, names_per_sample: list[str] | None, regions, stated_f: bool,
                gravity: float, source: str, regions_source: str | None):
    """(pose (n,), f (n, 3) or None, pose names) from regions of sample numbers or per-sample names."""
    n = index.shape[0]
    pose = np.full(n, -1, dtype=np.int64)
    names: list[str] = []
    if regions is not None:
        for name, start, end in regions:
            sel = (index >= start) & (index < end)
            if not sel.any():
                raise InputError(regions_source, f"[{start}, {end}) holds none of the recording's samples "
                                 f"({int(index[0])}..{int(index[-1])})", field=name)
            if not is_motion(name):
                pose[sel] = len(names)
                names.append(name)
    elif names_per_sample is not None:
        code: dict[str, int] = {}
        for i, nm in enumerate(names_per_sample):
            nm = nm.strip()
            if nm and not is_motion(nm):
                if nm not in code:
                    code[nm] = len(names)
                    names.append(nm)
                pose[i] = code[nm]
    f = None
    if stated_f:
        if not names:
            raise InputError(source, "--stated-f: no pose regions (give --regions JSON or a part column)")
        unknown = [nm for nm in names if nm not in POSE_DIRECTIONS]
        if unknown:
            raise InputError(regions_source or source, f"--stated-f: pose {unknown[0]!r} states no direction "
                             f"(names that do: {', '.join(POSE_DIRECTIONS)})",
                             field=unknown[0] if regions_source else None)
        dirs = np.array([POSE_DIRECTIONS[nm] for nm in names], dtype=float) * gravity
        f = np.where(pose[:, None] >= 0, dirs[np.maximum(pose, 0)], np.nan)
    return pose, f, names
