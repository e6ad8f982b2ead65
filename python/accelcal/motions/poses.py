"""Pose direction sets (faces, edges, corners of a cube; random) and the static stretches of a pose sequence."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import AccelcalError
from .trajectory import EZ, MAX_SAMPLES, Segments


#: poses closer than this (deg) are one orientation (for the count a jig-free fit needs)
SAME_ORIENTATION_DEG = 3.0


def faces() -> np.ndarray:
    return np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)


def edges() -> np.ndarray:
    out = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        for si in (1, -1):
            for sj in (1, -1):
                v = np.zeros(3)
                v[i], v[j] = si, sj
                out.append(v / math.sqrt(2.0))
    return np.array(out)


def corners() -> np.ndarray:
    return np.array([[sx, sy, sz] for sx in (1, -1) for sy in (1, -1) for sz in (1, -1)], float) / math.sqrt(3.0)


#: Preset pose sets: the body direction that points up in each pose (f = g d).
POSE_SETS: dict[str, str] = {
    "4": "the seed's four poses (eq. 19): f along +x, +y, +z, -z",
    "6": "the six faces: f along +-x, +-y, +-z",
    "18": "six faces and twelve edges (45 deg tilts)",
    "24": "the 24 rotations of a cube: each face up, turned 0/90/180/270 deg about the vertical",
    "26": "faces, edges and corners",
}


def pose_directions(poses: Any) -> tuple[np.ndarray, np.ndarray]:
    """(up directions (P, 3) unit, headings (P,) rad) for a preset name or a list."""
    if isinstance(poses, str):
        if poses == "4":
            d = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, -1]], float)
        elif poses == "6":
            d = faces()
        elif poses == "18":
            d = np.vstack([faces(), edges()])
        elif poses == "24":
            d = np.repeat(faces(), 4, axis=0)
            return d, np.tile(np.radians([0.0, 90.0, 180.0, 270.0]), 6)
        elif poses == "26":
            d = np.vstack([faces(), edges(), corners()])
        else:
            raise AccelcalError(f"unknown pose set {poses!r}; sets: {', '.join(POSE_SETS)}")
        return d, np.zeros(d.shape[0])
    d = np.atleast_2d(np.asarray(poses, float))
    return d / np.linalg.norm(d, axis=1, keepdims=True), np.zeros(d.shape[0])


def random_directions(rng: np.random.Generator, n: int) -> np.ndarray:
    v = rng.standard_normal((n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def static_segments(C: np.ndarray, period: float, g: float) -> Segments:
    P = C.shape[0]
    t0 = np.arange(P) * period
    z3 = np.zeros((P, 3))
    return Segments(t0, np.full(P, period), C, np.tile(EZ, (P, 1)), np.zeros(P), z3, z3, np.arange(P), g)


def static_times(P: int, spp: int, rate: float, dwell: float | None) -> tuple[np.ndarray, float]:
    rec = spp / rate
    period = rec + 1.0 if dwell is None else dwell
    if period < rec - 1e-12:
        raise AccelcalError(
            f"motion parameter 'dwell_s': expected at least samples_per_pose / rate = {rec:g} s, got {period:g}"
        )
    if P * spp > MAX_SAMPLES:
        raise AccelcalError(f"{P} poses of {spp} samples: {P * spp:,} samples, more than the {MAX_SAMPLES:,} a "
                            "simulation makes; simulate them in parts")
    t = (np.arange(P)[:, None] * period + np.arange(spp)[None, :] / rate).ravel()
    return t, period


def distinct_orientations(F: np.ndarray, same_deg: float = SAME_ORIENTATION_DEG) -> int:
    """How many of the poses' directions ``F`` (P, 3) differ by more than ``same_deg``: a pose
    held twice gives the jig-free fit the same equation twice."""
    fh = F / np.linalg.norm(F, axis=1, keepdims=True)
    kept: list[np.ndarray] = []
    c = math.cos(math.radians(same_deg))
    for u in fh:
        if all(float(np.dot(u, v)) < c for v in kept):
            kept.append(u)
    return len(kept)
