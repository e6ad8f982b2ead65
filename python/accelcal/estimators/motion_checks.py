"""The displacement's checks of its corrected motions, for its warnings and what it leaves out:
motions whose zero point only a turn explains (:func:`turned_motions`), and what the zero-point
correction leaves of a motion's position (:func:`motion_errors`).  The checks of the rests are in
:mod:`.displacement_checks`."""
from __future__ import annotations

import math

import numpy as np

from .common import time_span
from .rest import RestParams, rest_run
from .trend import trend_widening

__all__ = ["ZP_TURN_MPS2", "ZP_TURN_LINES", "zp_limit", "turned_motions", "turned_text", "turned_warnings",
           "ROTATION_MAX_DEG", "rotated_motions", "rotated_text", "ERROR_BOUND_MISS", "ERROR_BOUND_COVERS",
           "motion_errors", "motion_error_warnings"]


#: a motion's zero point held beyond what the rests show, past which the motion is warned of
#: (m/s^2): g sin 2.9 deg, a tilt of 2.9 deg held through the whole motion and undone by its end.
#: For a body that only translates, every calibration error is constant and enters the rest's
#: mean f, which is removed (offset, gain, misalignment alike); a gain error acts on the motion's
#: mean acceleration, zero from stop to stop; what is left is the zero point's drift over a
#: motion (0.05 m/s^2 at most, the room the rest's reference test leaves): ten times that is a
#: turn, not an error of the sensor
ZP_TURN_MPS2 = 0.5
#: motions named one line each up to this many (then one line for the rest)
ZP_TURN_LINES = 5


def zp_limit(n: int, f_sigma: float, rp: RestParams) -> float:
    """The largest |zp| (m/s^2) a motion of ``n`` samples gets without turning:
    ZP_TURN_MPS2, plus 5 sigma of zp's own noise (zp = v(T) / T sums n samples of f whose noise is
    ``f_sigma``, m/s^2: sigma / sqrt(n)), plus the detector's lag (up to ``rp.hold`` samples at
    each end within ``rp.dev_max`` of the rest's level, not integrated: a velocity of up to
    2 dev_max hold dt, over T = n dt)."""
    n = max(int(n), 1)
    return ZP_TURN_MPS2 + 5.0 * float(f_sigma) / math.sqrt(n) + 2.0 * rp.dev_max * rp.hold / n


def turned_motions(f, at, motions, f_sigma: float, rp: RestParams, axis: int | None, m0=None
                   ) -> list[tuple[int, int, float, float]]:
    """The corrected motions whose zero point is more than a calibration or tilt error gives
    (:func:`zp_limit`): an accelerometer alone cannot tell a turn from an acceleration, and a body
    that turned and turned back during a motion leaves a large zp (the mean gravity that leaked
    in), which the correction spreads over the path.

    Parameters
    ----------
    f : ndarray (n, 3)
        Specific force in body axes, m/s^2.
    at : ndarray (n,) bool
        At rest (each rest from where it began).
    motions : list of (int, int, array_like)
        Each corrected motion: its anchor (the rest sample before it), its end sample, and zp
        (m/s^2, the integrator's frame: the first rest's, or 1-D along ``axis``).
    f_sigma : float
        The noise of f, m/s^2.
    rp : RestParams
    axis : int or None
        1-D along that body axis (nothing removed: the rest's level is part of zp), or None.
    m0 : array_like (3,), optional
        The first rest's mean f (m/s^2); None: from ``at`` and ``f`` (given: ``f`` and ``at`` may be
        a stretch of the recording that holds each motion's rest before it, as read in chunks).

    Returns
    -------
    list of (int, int, float, float)
        Each such motion's anchor and end sample, its |zp| and the limit it passed (m/s^2).

    Notes
    -----
    What the rest before the motion shows is not held against it: its mean f less the first
    rest's (3-axis: by the triangle inequality, |zp| less the norm of that difference), or its
    mean f along ``axis`` (1-D: a tilted rail's g sin tilt, a calibration's offset).
    """
    at = np.asarray(at, bool)
    if not at.any():
        return []
    if m0 is None:
        first = int(np.argmax(at))
        first_end = first + int(np.argmin(at[first:])) if not at[first:].all() else at.size
        m0 = f[first:first_end].mean(axis=0)
    out = []
    for a, e, zp in motions:
        s = rest_run(at, a, 0, a)[0]
        level = f[s:a + 1].mean(axis=0) if at[a] else m0
        z = np.asarray(zp, float)
        held = (abs(z[axis] - level[axis]) if axis is not None else
                float(np.linalg.norm(z)) - float(np.linalg.norm(level - m0)))
        lim = zp_limit(e - a, f_sigma, rp)
        if held > lim:
            out.append((int(a), int(e), float(np.linalg.norm(z)), float(lim)))
    return out


def turned_text(t, turn: tuple[int, int, float, float], g: float, rec=None) -> str:
    """The words for a motion of :func:`turned_motions` (``t`` in s; ``g``, m/s^2, for the tilt
    its zp equals; ``rec`` names its rows, :func:`.common.time_span`)."""
    a, e, mag, lim = turn
    return (f"the motion at {time_span(t, a, e, rec)} was corrected by a zero point of |zp| = {mag:.3g} m/s^2, as "
            f"much as a tilt of {math.degrees(math.asin(min(1.0, mag / g))):.1f} deg held through the whole motion, "
            f"beyond what a calibration or tilt error gives ({lim:.2g} m/s^2 here): the body likely turned during the "
            "motion, which an accelerometer-only estimate cannot follow (gravity leaks into the path), or was not at a "
            "standstill at its end (a steady speed reads as a rest)")


#: a 6-DOF array's turn within a motion (from its resolved alpha) beyond which the motion is not
#: reported (deg): gravity leaks into the path by g sin(angle), 0.51 m/s^2 at 3 deg -- ZP_TURN_MPS2
ROTATION_MAX_DEG = 3.0


def rotated_motions(alpha, at, motions, dt: float, alpha_sigma: float) -> list[tuple[int, int, float]]:
    """The corrected motions in which a 6-DOF array turned by more than ROTATION_MAX_DEG: the largest
    angle (deg) from the motion's anchor, integrating the resolved ``alpha`` ((n, 3), rad/s^2) twice
    from rest (omega = 0 at the anchor, at rest) over anchor .. end; angles within 5 sigma of what
    the alpha noise alone (``alpha_sigma``, rad/s^2 per axis) integrates to are not counted (a
    double random walk: sigma_alpha dt^2 sqrt(k^3 / 3) after k steps).  ``at``: at rest (n,) bool;
    ``motions``: (anchor, end, zp) each; ``dt`` in s.  Returns (anchor, end, angle) of each."""
    alpha = np.asarray(alpha, float)
    out = []
    for a, e, _ in motions:
        w = np.cumsum(alpha[a + 1:e + 1] * dt, axis=0)
        ang = np.linalg.norm(np.cumsum(w * dt, axis=0), axis=1)
        k = np.arange(1, ang.size + 1, dtype=float)
        sig = float(alpha_sigma) * dt * dt * np.sqrt(k ** 3 / 3.0)
        worst = math.degrees(float(np.max(np.where(ang > 5.0 * sig, ang, 0.0), initial=0.0)))
        if worst > ROTATION_MAX_DEG:
            out.append((int(a), int(e), worst))
    return out


def rotated_text(t, rot: tuple[int, int, float], rec=None) -> str:
    """The words for a motion of :func:`rotated_motions` (``t`` in s; ``rec`` names its rows)."""
    a, e, ang = rot
    return (f"the body turned by up to {ang:.1f} deg during the motion at {time_span(t, a, e, rec)} (from the "
            f"resolved alpha), beyond the {ROTATION_MAX_DEG:g} deg the stop-to-stop method takes (gravity removal "
            "assumes no rotation between rests, a rail: gravity leaks into the path)")


def turned_warnings(turns) -> list[str]:
    """The warnings of the turned motions ``turns`` ((anchor, words) each: :func:`turned_text`,
    :func:`rotated_text`) kept in the output (``--keep-turned``): one line per motion, the first
    ZP_TURN_LINES, then one line for the others."""
    out = [f"displacement: {words}; its path and the positions after it are not valid (kept: --keep-turned)"
           for _, words in turns]
    if len(out) > ZP_TURN_LINES:
        out = out[:ZP_TURN_LINES] + [f"displacement: {len(out) - ZP_TURN_LINES} more motion(s) like these"]
    return out


def motion_errors(f, p, at, motions, f_sigma, dt: float, axis: int | None, rho=None
                  ) -> list[tuple[int, int, float, float, float, float, float]]:
    """What the zero-point correction leaves of each corrected motion's position, from what its
    rests can tell.

    The correction removes a zero point that stays constant through the motion (a calibration
    error, a tilt held from rest to rest).  A change of it at an unknown time (a tilt change, a
    drift) is not removed: a step of D at time tau of a motion of T leaves D tau (T - tau) / 2 at
    its end, up to D T^2 / 8 at the middle.  D is the change between the rests' levels (their mean
    f) or, where that is below what they can tell, the smallest change they tell: 5 sigma of the
    difference of two means of n1 and n2 samples of noise sigma, 5 sigma sqrt(1/n1 + 1/n2).  The
    noise itself leaves 5 sigma sqrt(dt T^3 / 12) (white noise integrated twice, the end pinned to
    zero velocity: p(T) - v(T) T / 2 = sum_i a_i dt (T/2 - t_i), the weights of a fitted line's slope,
    so noise whose samples are correlated widens its variance by :func:`.trend.trend_widening` over
    the motion's samples, from the correlation ``rho`` the rests show; the largest axis's
    sigma^2 x widening).  The change grows with T^2, the noise with T^1.5: beyond
    T_max = (40 sigma / D)^2 dt / 12 the change dominates (with D = what the rests tell,
    T_max = 16/3 dt / (1/n1 + 1/n2): 8/3 of rests of equal length).

    Parameters
    ----------
    f : ndarray (n, 3)
        Specific force in body axes, m/s^2.
    p : ndarray (n, 3)
        The corrected position, m.
    at : ndarray (n,) bool
        At rest (each rest from where it began).
    motions : list of (int, int, array_like)
        Each corrected motion: anchor (a rest sample before it), end sample, zp.
    f_sigma : float or array_like (3,)
        The noise of f, m/s^2 per axis (one figure: the same for all).
    dt : float
        s.
    axis : int or None
        1-D along that body axis, or None (3-axis).
    rho : array_like (L, 3), optional
        The noise's autocorrelation per axis at lags 0 .. L-1 (:func:`.trend.rest_correlation`);
        None: white.

    Returns
    -------
    list of (int, int, float, float, float, float, float)
        Per motion: anchor, end, the error bound E (m), its part from the change of level (m), the
        change D used (m/s^2), the change the rests tell (5 sigma, m/s^2), and the path's largest
        distance from its start (m).
    """
    at = np.asarray(at, bool)
    f = np.asarray(f, float)
    n = at.size
    sig = np.broadcast_to(np.asarray(f_sigma, float), (3,))
    f_sigma = float(np.max(sig))
    out = []
    for k, (a, e, _) in enumerate(motions):
        lo = motions[k - 1][1] + 1 if k else 0
        hi = motions[k + 1][0] if k + 1 < len(motions) else n
        b0, b1 = rest_run(at, a, lo, a + 1) if at[a] else (a, a + 1)
        j = e if at[e] else min(e + 1 + int(np.argmax(at[e + 1:])) if e + 1 < n and at[e + 1:].any() else e, n - 1)
        c0, c1 = rest_run(at, j, max(a + 1, lo), hi) if at[j] else (j, j + 1)
        d = f[c0:c1].mean(axis=0) - f[b0:b1].mean(axis=0)
        seen = abs(float(d[axis])) if axis is not None else float(np.linalg.norm(d))
        tell = 5.0 * float(f_sigma) * math.sqrt(1.0 / (b1 - b0) + 1.0 / (c1 - c0))
        D = max(seen, tell)
        T = (e - a) * dt
        tilt = D * T * T / 8.0
        widen = np.ones(3) if rho is None else trend_widening(rho, e - a + 1)
        noise = 5.0 * math.sqrt(float(np.max(sig ** 2 * widen)) * dt * T ** 3 / 12.0)
        seg = np.asarray(p[a:e + 1], float) - np.asarray(p[a], float)
        path = float(np.max(np.abs(seg[:, axis]))) if axis is not None else float(np.max(np.linalg.norm(seg, axis=1)))
        out.append((int(a), int(e), tilt + noise, tilt, D, tell, path))
    return out


#: what the figures of ``error_bound_m`` (:func:`motion_errors`, one per motion) cover, for the output's meta
#: the chance per motion that its noise alone leaves more than the noise part of error_bound_m, which
#: the bound is held to: 5 sigma of Gaussian noise, 5.7e-7; more where the rests' estimate of the
#: noise's correlation falls short of the truth (AR(1) noise with phi = 0.9: ~0.9 x its sigma, 2e-5)
#: -- tests/python/test_displacement_limits.py
ERROR_BOUND_MISS = 1e-4
#: what the metadata's error_bound_m is, and what it is not
ERROR_BOUND_COVERS = (
    "per motion, m, at its end: 5 sigma of the noise of f integrated twice over the motion with its end "
    "velocity pinned to 0 (sigma sqrt(dt T^3 / 12) for white noise, the largest axis's; noise whose samples "
    "are correlated widened by that correlation as the rests show it), plus D T^2 / 8 for a change D of the "
    "zero point between its rests (or the smallest change they tell, 5 sigma); the noise alone exceeds it "
    f"in fewer than {ERROR_BOUND_MISS:g} of motions; not covered: a turn within the motion undone by its end (a "
    "triad's up to the turned-motion limit on its zero point), noise in the motion unlike the rests' (a motor's "
    "vibration), noise correlated over more than the noise estimate's window sees (AR(1) phi = 0.97 at 100 Hz "
    "without the device's noise_mps2: 3 motions in 89 beyond), and the calibration's scale and cross-axis errors "
    "(a share of the path)")


def motion_error_warnings(t, errs, f_sigma: float, dt: float, g: float, rec=None) -> list[str]:
    """The warnings of :func:`motion_errors`: a motion whose error from a change of its zero point
    (D T^2 / 8) exceeds what its noise leaves -- longer than the stop-to-stop correction holds with
    the rests about it (said to be not determined when that error reaches its path; a motion the
    detector found in the noise has a path below its noise, which is no warning).  One line per motion, the first
    ZP_TURN_LINES, then one line for the others.  ``t`` in s, ``f_sigma`` in m/s^2, ``dt`` in s,
    ``g`` in m/s^2 (the tilt a change equals)."""
    out = []
    for a, e, err, tilt, D, tell, path in errs:
        noise = err - tilt
        if tilt <= noise:
            continue
        T = (e - a) * dt
        if D > tell:
            what = "the change of level between its rests"
            hint = ("; the correction cannot remove a change of the zero point within a motion: keep the attitude "
                    "from rest to rest (a rail, a fixture) and the motions short")
        else:
            what = "a change of level as small as its rests can tell (5 sigma)"
            hint = (f"; with these rests the correction holds motions up to {(40.0 * f_sigma / D) ** 2 * dt / 12.0:.2g} "
                    "s (longer rests tell a smaller change)")
        out.append(
            f"displacement: the motion at {time_span(t, a, e, rec)} lasts {T:.3g} s, longer than the stop-to-stop "
            f"correction holds: it leaves up to {err:.3g} m of its position, against a path of {path:.3g} m from "
            f"its start ({what}, {D:.2g} m/s^2 = {math.degrees(math.asin(min(1.0, D / g))):.2g} deg of tilt, at "
            f"its middle: {tilt:.3g} m, growing with T^2; the noise: {noise:.2g} m)"
            + ("; its path is no larger than that error: it is not determined" if err >= path else "") + hint)
    if len(out) > ZP_TURN_LINES:
        out = out[:ZP_TURN_LINES] + [f"displacement: {len(out) - ZP_TURN_LINES} more motion(s) like these"]
    return out
