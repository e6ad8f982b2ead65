"""The next pose by information: which gravity direction most reduces the worst parameter's
uncertainty, and how to say it to the person holding the sensor.

Model (jig-free, the fit the capture makes): channel i reads ``m_pi = b_i + s_i . f_p`` at
pose p with ``f_p = g u_p`` (|f| = g, the direction u_p unknown: two tangent-plane angles a
pose).  One pose of direction u contributes to the Fisher information of the channel
parameters theta = (b_i, s_i) (4 N of them) its reduced information: with ``Jc`` the
readings' derivatives by theta, ``Jp`` by the pose's two angles and ``W`` the inverse
variances of the pose means,

    I_p = Jc^T W Jc - Jc^T W Jp (Jp^T W Jp)^-1 Jp^T W Jc

(the pose's own angles eliminated: the person's direction is not known, only measured).  The
poses add.  A weak prior (offsets within PRIOR_OFFSET_G, sensitivity components within
PRIOR_GAIN of the nominal) makes the sum invertible before nine poses; it fixes the common
rotation that no reading tells, which the offsets and the gains |s_i| do not depend on.

Criterion, on the normalised target quantities r (every offset's 1-sigma in mg over
``target_mg`` and every gain's 1-sigma, of |s_i|, in % over ``target_pct``): the next direction
is the candidate (a Fibonacci sphere of N_CANDIDATES directions plus the 26 faces, edges and
corners) that meets the target with the smallest largest ratio (minimax) where one pose more can
meet it; else the one with the smallest sum of r^2 (A-optimal on the normalised parameters).  The
greedy minimax from the first pose is myopic: it spends the early poses on the corners that help
the worst channel a little each, and on a triad it needed more poses than the fixed plan of six
faces and six random poses (12.0 against 9.25 on average at 10 mg of noise); the A-optimal
choice with the minimax finish needed 9.0 there, and 10.3 against 15.5 at 20 mg
(docs/capture.md).
"""
from __future__ import annotations

import math

import numpy as np

N_CANDIDATES = 240       # directions of the Fibonacci sphere
PRIOR_OFFSET_G = 0.2     # planning prior: an offset within this (g) of the nominal zero, 1-sigma
PRIOR_GAIN = 0.1         # planning prior: each sensitivity component within this x |s| of nominal, 1-sigma
FACE_DEG = 3.0           # a direction within this (deg) of a face is said as the face alone
AXES = "xyz"


def fibonacci_sphere(n: int) -> np.ndarray:
    """Nearly uniform unit vectors on the sphere (the golden-angle spiral).

    Parameters
    ----------
    n : int
        Number of directions.

    Returns
    -------
    ndarray, shape (n, 3)
        Unit vectors.
    """
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def candidate_directions() -> np.ndarray:
    """The gravity directions the planner chooses from: the 6 faces, 12 edges and 8 corners of
    a cube (easy to hold) and a Fibonacci sphere of N_CANDIDATES.

    Returns
    -------
    ndarray, shape (26 + N_CANDIDATES, 3)
        Unit vectors in the sensor frame.
    """
    cube = np.array([(x, y, z) for x in (-1, 0, 1) for y in (-1, 0, 1) for z in (-1, 0, 1)
                     if (x, y, z) != (0, 0, 0)], float)
    cube /= np.linalg.norm(cube, axis=1)[:, None]
    return np.vstack([cube, fibonacci_sphere(N_CANDIDATES)])


def tangent_pairs(u: np.ndarray) -> np.ndarray:
    """(K, 3, 2) an orthonormal basis across each unit vector of ``u`` (K, 3)."""
    a = np.where((np.abs(u[:, 0]) < 0.9)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    t1 = np.cross(u, a)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return np.stack([t1, np.cross(u, t1)], axis=2)


def pose_information(S: np.ndarray, sigma: np.ndarray, u: np.ndarray, g: float) -> np.ndarray:
    """The reduced Fisher information a pose adds to the channel parameters.

    Parameters
    ----------
    S : ndarray, shape (N, 3)
        Sensitivity vectors, counts per m/s^2 (the current estimate).
    sigma : ndarray, shape (N,)
        1-sigma of each channel's pose mean, counts.
    u : ndarray, shape (3,) or (K, 3)
        Direction of the specific force at the pose (up in the sensor frame; normalised
        here), or K such directions.
    g : float
        Gravity, m/s^2.

    Returns
    -------
    ndarray, shape (4 N, 4 N) or (K, 4 N, 4 N)
        Information on (b_0, s_0, b_1, s_1, ...), the pose's two angles eliminated.
    """
    one = np.ndim(u) == 1
    u = np.atleast_2d(np.asarray(u, float))
    u = u / np.linalg.norm(u, axis=1)[:, None]
    K, N = u.shape[0], S.shape[0]
    w = 1.0 / np.asarray(sigma, float) ** 2
    Jc = np.zeros((K, N, 4 * N))
    for i in range(N):
        Jc[:, i, 4 * i] = 1.0
        Jc[:, i, 4 * i + 1:4 * i + 4] = g * u
    Jp = g * np.einsum("na,kab->knb", S, tangent_pairs(u))
    WJc = w[None, :, None] * Jc
    A = np.einsum("kni,knj->kij", Jc, WJc)
    B = np.einsum("kni,knb->kib", WJc, Jp)
    C = np.einsum("kna,kn,knb->kab", Jp, np.broadcast_to(w, (K, N)), Jp)
    out = A - B @ np.linalg.solve(C, np.swapaxes(B, 1, 2))
    return out[0] if one else out


def prior_information(S: np.ndarray, g: float) -> np.ndarray:
    """The planning prior's information (diagonal): offsets PRIOR_OFFSET_G, sensitivity
    components PRIOR_GAIN x |s_i|.

    Parameters
    ----------
    S : ndarray, shape (N, 3)
        Sensitivity vectors, counts per m/s^2.
    g : float
        Gravity, m/s^2.

    Returns
    -------
    ndarray, shape (4 N, 4 N)
    """
    k = np.linalg.norm(S, axis=1)
    d = np.concatenate([[1.0 / (PRIOR_OFFSET_G * g * ki) ** 2] + [1.0 / (PRIOR_GAIN * ki) ** 2] * 3 for ki in k])
    return np.diag(d)


def target_sigmas(cov: np.ndarray, S: np.ndarray, g: float) -> tuple[np.ndarray, np.ndarray]:
    """Each channel's offset 1-sigma (mg) and gain 1-sigma (% of |s_i|) from a covariance.

    Parameters
    ----------
    cov : ndarray, shape (N, 4, 4) or (4 N, 4 N)
        Covariance of (b_i, s_i): per channel blocks or the whole matrix (counts, counts per m/s^2).
    S : ndarray, shape (N, 3)
        Sensitivity vectors, counts per m/s^2.
    g : float
        Gravity, m/s^2 (1 mg is g / 1000).

    Returns
    -------
    offset_mg : ndarray, shape (N,)
    gain_pct : ndarray, shape (N,)
    """
    N = S.shape[0]
    blocks = cov if cov.ndim == 3 else np.stack([cov[4 * i:4 * i + 4, 4 * i:4 * i + 4] for i in range(N)])
    k = np.linalg.norm(S, axis=1)
    u = S / k[:, None]
    off = np.sqrt(np.maximum(blocks[:, 0, 0], 0.0)) / k / g * 1000.0
    gain = np.sqrt(np.maximum(np.einsum("ia,iab,ib->i", u, blocks[:, 1:4, 1:4], u), 0.0)) / k * 100.0
    return off, gain


def worst_ratio(off_mg: np.ndarray, gain_pct: np.ndarray, target_mg: float, target_pct: float) -> float:
    """The largest of the offsets' sigma over ``target_mg`` and the gains' over ``target_pct``.

    Parameters
    ----------
    off_mg, gain_pct : ndarray
        1-sigma of the offsets (mg) and gains (%).
    target_mg, target_pct : float
        The targets.

    Returns
    -------
    float
        <= 1 where every parameter meets its target.
    """
    return float(max(np.max(off_mg) / target_mg, np.max(gain_pct) / target_pct))


def next_direction(info: np.ndarray, S: np.ndarray, sigma: np.ndarray, g: float, target_mg: float,
                   target_pct: float, candidates: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """The force direction of the next pose: the one that meets the target with the smallest worst
    normalised sigma where one can (minimax), else the one with the smallest sum of the squared
    normalised sigmas (A-optimal).

    Parameters
    ----------
    info : ndarray, shape (4 N, 4 N)
        Information so far (poses captured and the planning prior).
    S : ndarray, shape (N, 3)
        Sensitivity vectors, counts per m/s^2.
    sigma : ndarray, shape (N,)
        Expected 1-sigma of a pose mean, counts.
    g : float
        Gravity, m/s^2.
    target_mg, target_pct : float
        The targets the ratios are taken against.
    candidates : ndarray, shape (K, 3), optional
        Unit directions to choose from (default :func:`candidate_directions`).

    Returns
    -------
    u : ndarray, shape (3,)
        The specific force's direction at the next pose (up in the sensor frame; gravity
        points along -u).
    ratio : float
        The worst normalised sigma expected after that pose.
    """
    cand = candidate_directions() if candidates is None else np.asarray(candidates, float)
    cov = np.linalg.inv(info[None] + pose_information(S, sigma, cand, g))
    N = S.shape[0]
    k = np.linalg.norm(S, axis=1)
    u = S / k[:, None]
    idx = 4 * np.arange(N)
    off = np.sqrt(np.maximum(cov[:, idx, idx], 0.0)) / k / g * 1000.0
    ss = np.stack([cov[:, 4 * i + 1:4 * i + 4, 4 * i + 1:4 * i + 4] for i in range(N)], axis=1)
    gain = np.sqrt(np.maximum(np.einsum("ia,kiab,ib->ki", u, ss, u), 0.0)) / k * 100.0
    r = np.concatenate([off / target_mg, gain / target_pct], axis=1)
    worst = r.max(axis=1)
    j = int(np.argmin(worst)) if worst.min() <= 1.0 else int(np.argmin(np.sum(r * r, axis=1)))
    return cand[j].copy(), float(worst[j])


def words(gravity: np.ndarray) -> str:
    """What to tell the person: the face to turn down and the tilt that remains.

    Parameters
    ----------
    gravity : ndarray, shape (3,)
        Where gravity should point in the sensor frame (unit vector).

    Returns
    -------
    str
        "turn so that +x points down" and, beyond FACE_DEG, "then tilt it A deg so that +y
        dips toward the ground" (the largest remaining component).
    """
    d = np.asarray(gravity, float) / np.linalg.norm(gravity)
    k = int(np.argmax(np.abs(d)))
    face = f"{'+' if d[k] > 0 else '-'}{AXES[k]}"
    text = f"turn so that {face} points down"
    tilt = math.degrees(math.acos(min(1.0, abs(float(d[k])))))
    if tilt > FACE_DEG:
        rest = d.copy()
        rest[k] = 0.0
        j = int(np.argmax(np.abs(rest)))
        other = f"{'+' if rest[j] > 0 else '-'}{AXES[j]}"
        second = [i for i in range(3) if i not in (k, j)][0]
        lean = math.degrees(math.atan2(abs(rest[second]), abs(rest[j])))
        extra = (f" (and {lean:.0f} deg of that toward {'+' if rest[second] > 0 else '-'}{AXES[second]})"
                 if lean > FACE_DEG else "")
        text += f", then tilt it {tilt:.0f} deg so that {other} dips toward the ground{extra}"
    return text
