"""The displacement's checks of a recording, for its warnings and errors: why no rest was
found (:func:`no_rest_reason`), a still stretch that is no rest because its |f| strays from g
(:func:`still_off_g`: the calibration's scale) or because the body turned
(:func:`still_but_turned`), and corrected motions whose zero point only a turn explains
(:func:`turned_motions`), rests that hold a trend (:func:`trend_warnings`)."""
from __future__ import annotations

import math

import numpy as np

from ..device import GRAVITY_REMOVED_G
from .common import time_span
from .rest import TREND_BLOCK_HOLDS, RestParams, rest_run, trend_bound

__all__ = ["REST_DEV_WARN_MPS2", "REST_NOISE_MAX_MPS2", "rest_noise_max", "wide_rest_warning", "ZP_TURN_MPS2",
           "no_rest_reason", "scale_off", "scale_cause", "still_off_g", "still_off_g_text", "off_g_text", "still_but_turned",
           "zp_limit", "turned_motions", "turned_text", "turned_warnings", "trend_warnings", "motion_errors",
           "motion_error_warnings", "final_trend_note"]


#: the noisiest sensor at rest of issue 13's range, m/s^2 per axis (its 5 sigma: 0.25)
REST_NOISE_MAX_MPS2 = 0.05
#: a rest test (5 sigma of a noise estimated from the data) wider than this many sigma of the
#: noisiest sensor at rest is warned of (a rocket's vibration: 0.67 m/s^2)
REST_WARN_SIGMAS = 8.0


def rest_noise_max(q_f: float = 0.0) -> float:
    """The largest noise (m/s^2 per axis) :func:`accelcal.noise.estimate_noise` gives for a sensor
    at rest whose own noise is at most REST_NOISE_MAX_MPS2, read on codes a step ``q_f`` apart
    (m/s^2 per axis: the code step through the calibration).

    A still channel's rounding error never exceeds half a step, so its window std s is at most
    sigma + q/2 (a reading that flips between two codes: q/2 with no noise at all); the estimate
    adds the rounding noise q^2/12: sqrt((sigma + q/2)^2 + q^2/12).  With q = 0 this is sigma.
    An 8-bit Empatica E4 at +-2 g (q = 0.153 m/s^2) at rest reads up to 0.13 m/s^2."""
    q = float(q_f)
    return math.hypot(REST_NOISE_MAX_MPS2 + 0.5 * q, q / math.sqrt(12.0))


#: the widest rest test not warned of with fine codes (m/s^2): 8 sigma of 0.05 m/s^2
REST_DEV_WARN_MPS2 = REST_WARN_SIGMAS * rest_noise_max()


def wide_rest_warning(dev_max: float, q_f: float) -> list[str]:
    """The warning (one line, or none) of a rest test whose width ``dev_max`` (m/s^2, 5 sigma of
    the noise estimated from the data) is more than REST_WARN_SIGMAS sigma of what a sensor at rest
    gives on codes ``q_f`` apart (:func:`rest_noise_max`): vibration throughout.  A test wide only
    because the codes are coarse (an 8-bit sensor dwelling on 2-4 codes) is the sensor at rest."""
    top = rest_noise_max(q_f)
    if dev_max <= REST_WARN_SIGMAS * top:
        return []
    coarse = (f"; {5 * top:.2g} with this sensor's code step of {q_f:.3g} m/s^2" if 5 * top > 0.26 else "")
    return [f"displacement: the noise estimated from the recording gives a rest test of |f - mean| <= {dev_max:.3g} "
            f"m/s^2 (5 sigma), beyond what most sensors at rest show (0.01-0.25 m/s^2{coarse}): no still stretch "
            "is that quiet (vibration throughout, a flight -- or a noisy sensor: an x-IMU reads 0.11 m/s^2 per axis "
            "standing still), so a slow motion may pass for a rest; state the sensor's own noise_mps2 in the device "
            "file"]


def _band_share(blk, rp: RestParams) -> float:
    """The share of the samples ``blk`` (m, 3), m/s^2, whose |f| falls outside the rest test's band
    g +- g_tol (0 when the |f| test is off): one such sample breaks the quiet run a rest needs."""
    if rp.g is None:
        return 0.0
    lo, hi = rp.g2_bounds()
    g2 = np.sum(np.asarray(blk, float) ** 2, axis=1)
    return float(np.mean((g2 < lo) | (g2 > hi)))


def scale_off(norm: float, share: float, rp: RestParams) -> bool:
    """Whether a still stretch whose mean |f| is ``norm`` (m/s^2) and whose samples fall outside
    the rest test's band in the ``share`` given is kept from being a rest by the scale: its mean
    sits within half the test's width (dev_max / 2, 2.5 sigma) of the band's edge or beyond it.
    Nearer g, the samples that leave the band are the noise's (a test nearly as wide as the band:
    an 8-bit sensor's 0.47 m/s^2 against 0.5), not the scale's."""
    return rp.g is not None and share > 0.0 and abs(norm - rp.g) >= rp.g_tol - 0.5 * rp.dev_max


def still_off_g_text(t, off, rp: RestParams, rec=None, cal=None) -> str:
    """The words for :func:`still_off_g`'s stretch ``off`` (``t`` in s; ``rec`` names its rows;
    ``cal`` the calibration used, :func:`scale_cause`)."""
    a, b, norm, share = off
    return (f"the body is still at {time_span(t, a, b, rec)} but that is no rest: it "
            f"{off_g_text(norm, share, rp, cal)}")


def scale_cause(cal, norm: float, g: float) -> str:
    """Why a still stretch's mean |f| (``norm``, m/s^2) is off ``g`` (m/s^2), after the calibration
    ``cal`` used (None or the device's nominal values: calibrate first).  A calibration given is named
    (``cal.extra['source']``, its file, else 'the calibration given'), with its method and model and
    how far |f| is off: a model that estimates no scale (jig-free 'offset') keeps the device file's
    nominal scale; one that does was made for another device, range or temperature.  Below
    ``GRAVITY_REMOVED_G`` of g no scale is to blame: the readings hold no gravity."""
    if norm < GRAVITY_REMOVED_G * g:
        return (f"|f| is {norm / g:.2g} g where the body is still, and any sensor at rest reads 1 g: gravity has been "
                "removed from these readings (a phone's linear or user acceleration, such as Sensor Logger's "
                "Accelerometer.csv); record the accelerometer's own readings (TotalAcceleration.csv or "
                "AccelerometerUncalibrated.csv, phyphox's 'Acceleration with g')")
    if cal is None or getattr(cal, "method", "nominal") == "nominal":
        return "the calibration's scale is off (a chip's nominal scale?); calibrate it first (accelcal calibrate) and use that calibration"
    extra = cal.extra if isinstance(cal.extra, dict) else {}
    name = extra.get("source", "the calibration given")
    model = (extra.get("fit") or {}).get("model") if isinstance(extra.get("fit"), dict) else None
    poses = f" from {len(cal.poses_used)} poses" if cal.poses_used else ""
    what = f"{cal.method}" + (f" '{model}' model" if model else "") + poses
    off = f"|f| {100.0 * (norm / g - 1.0):+.2g} % off g"
    if model == "offset":
        return (f"the calibration given ({name}: {what}) estimates the offsets only and keeps the device file's "
                f"nominal scale, which reads {off} here: calibrate with a model that estimates the scale (jig-free "
                "'gain' or 'full', from poses in more orientations, or poses on a jig) and use that calibration")
    return (f"the calibration given ({name}: {what}) reads {off} here: its scale does not hold for this recording "
            "(made for another device, range setting or temperature?); calibrate from a recording of this device "
            "as it is now")


def off_g_text(norm: float, share: float, rp: RestParams, cal=None) -> str:
    """Why a still stretch is no rest when its |f| strays from g: its mean |f| (``norm``, m/s^2),
    the ``share`` of its samples outside the rest test's band g +- g_tol, and the cause
    (:func:`scale_cause` of the calibration ``cal`` used)."""
    return (f"read |f| = {norm:.4g} m/s^2, {100 * share:.0f} % of the samples outside the rest test's "
            f"{rp.g:g} +- {rp.g_tol:g} m/s^2: {scale_cause(cal, norm, rp.g)}")


def no_rest_reason(f, t, rp: RestParams, cal=None) -> str:
    """Why no rest was found, for the error: the stillest block of ``rp.hold`` samples (blocks
    at a stride of half a block), how far its f strays from its mean, and, when it is still
    enough but some of its samples' |f| fall outside the rest test's band, that |f| (a
    calibration whose scale is off: an uncalibrated chip 7.7 % high read with its nominal scale;
    a chip 5 % low whose mean |f| sits at the band's edge; ``cal``, the calibration used, named by
    :func:`scale_cause`).  ``f`` in m/s^2, (n, 3); ``t`` in s."""
    f = np.asarray(f, float)
    hold = max(int(rp.hold), 2)
    if f.shape[0] < hold:
        return f"the recording has {f.shape[0]} samples, fewer than a rest's {hold}"
    starts = np.arange(0, f.shape[0] - hold + 1, max(1, hold // 2))
    best = (math.inf, 0, 0.0)
    for chunk in np.array_split(starts, max(1, starts.size // 4096)):
        w = f[chunk[:, None] + np.arange(hold)[None, :]]             # (c, hold, 3)
        m = w.mean(axis=1)
        dev = np.max(np.abs(w - m[:, None, :]), axis=(1, 2))
        j = int(np.argmin(dev))
        if dev[j] < best[0]:
            best = (float(dev[j]), int(chunk[j]), float(np.linalg.norm(m[j])))
    dev, i, norm = best
    if rp.g is None:
        return f"the stillest {hold} samples stray {dev:.3g} m/s^2 from their mean"
    where = time_span(t, i, i + hold - 1)
    if dev > rp.dev_max:
        return (f"the stillest {hold} samples ({where}) stray {dev:.3g} m/s^2 from their mean, beyond the rest's "
                f"{rp.dev_max:.3g}: the body never stops")
    share = _band_share(f[i:i + hold], rp)
    if not scale_off(norm, share, rp):
        return (f"the stillest {hold} samples ({where}) stray only {dev:.3g} m/s^2 from their own mean and read "
                f"|f| = {norm:.4g} m/s^2, but the rest detector's running mean never settles on a still stretch "
                "that long: the body creeps or turns slowly throughout")
    return f"the stillest {hold} samples ({where}) are still (within {dev:.3g} m/s^2) but {off_g_text(norm, share, rp, cal)}"


def _still_blocks(f, at_rest, rp: RestParams):
    """Each block of ``rp.hold`` samples (at a stride of a block) not at rest whose f stays within
    ``rp.dev_max`` of its mean: (its first sample, its mean f in m/s^2, the share of its samples
    outside the |f| band when that is the scale's doing (:func:`scale_off`), else 0)."""
    hold = max(int(rp.hold), 2)
    for i in range(0, f.shape[0] - hold + 1, hold):
        blk = f[i:i + hold]
        if at_rest[i:i + hold].any():
            continue
        m = blk.mean(axis=0)
        if float(np.max(np.abs(blk - m))) <= rp.dev_max:
            share = _band_share(blk, rp)
            yield i, m, share if scale_off(float(np.linalg.norm(m)), share, rp) else 0.0


def _grow(first, i: int, hold: int):
    """The first stretch (first and last sample) grown by the block at sample ``i`` when it
    begins within 1.5 blocks of its end (else kept)."""
    if first is None:
        return i, i + hold - 1
    return (first[0], i + hold - 1) if first[1] >= i - 1.5 * (hold - 1) else first


def still_off_g(f, at_rest, rp: RestParams) -> tuple[int, int, float, float] | None:
    """The first stretch where the body is still (blocks of ``rp.hold`` samples within
    ``rp.dev_max`` of their mean) and not at rest because some of its samples' |f| fall outside
    the rest test's band g +- g_tol with a mean |f| off g (:func:`scale_off`), for TREND_BLOCK_HOLDS
    blocks or more (1 s at the default hold: a hand that pauses while it accelerates holds that
    acceleration for a moment, a chip read with the wrong scale for as long as it is still): a
    calibration whose scale is off (a chip's gain error read with its nominal scale), not a turn
    or a motion.

    Parameters
    ----------
    f : array_like (n, 3)
        Specific force, m/s^2.
    at_rest : array_like (n,) bool
    rp : RestParams

    Returns
    -------
    (int, int, float, float) or None
        The stretch's first and last sample, its mean |f| (m/s^2) and the share of its samples
        outside the band; None when there is none (or the |f| test is off).
    """
    f = np.asarray(f, float)
    at_rest = np.asarray(at_rest, bool)
    if rp.g is None:
        return None
    hold = max(int(rp.hold), 2)
    runs = []                   # each stretch: [first sample, last sample, the blocks' |mean f|, shares]
    for i, m, share in _still_blocks(f, at_rest, rp):
        if share == 0.0:
            continue
        if runs and _grow(tuple(runs[-1][:2]), i, hold) != tuple(runs[-1][:2]):
            runs[-1][1] = i + hold - 1
        elif runs and len(runs[-1][2]) >= TREND_BLOCK_HOLDS:
            break
        else:
            runs.append([i, i + hold - 1, [], []])
        runs[-1][2].append(float(np.linalg.norm(m)))
        runs[-1][3].append(share)
    for a, b, norms, shares in runs:
        if len(norms) >= TREND_BLOCK_HOLDS:
            return a, b, float(np.mean(norms)), float(np.mean(shares))
    return None


def still_but_turned(f, at_rest, rp: RestParams) -> tuple[float, int, int] | None:
    """A stretch where the body is still but not at rest: blocks of ``rp.hold`` samples whose
    f stays within ``rp.dev_max`` of its mean with |f| within ``rp.g_tol`` of g (not one kept
    from a rest by the scale, :func:`still_off_g`'s: no turn is told there), away from the
    rest's direction by more than ``rp.ref_max``.  For a body that only translates (a rail)
    every still stretch is a rest; such a stretch is a turn, which no accelerometer alone
    tells from an acceleration.  Returns (its largest angle from the first rest's f, deg;
    the first such stretch's first and last sample) or None.  ``f`` in m/s^2, (n, 3)."""
    f = np.asarray(f, float)
    at_rest = np.asarray(at_rest, bool)
    if not at_rest.any():
        return None
    ref = f[at_rest][: max(rp.hold, 1)].mean(axis=0)
    hold = max(int(rp.hold), 2)
    worst, first = 0.0, None
    for i, m, share in _still_blocks(f, at_rest, rp):
        if share > 0.0 or float(np.linalg.norm(m - ref)) <= rp.ref_max:
            continue
        if rp.g is not None and abs(float(np.linalg.norm(m)) - rp.g) > rp.g_tol:
            continue
        cosang = float(np.dot(m, ref) / (np.linalg.norm(m) * np.linalg.norm(ref)))
        ang = math.degrees(math.acos(min(1.0, max(-1.0, cosang))))
        worst = max(worst, ang)
        first = _grow(first, i, hold)
    return None if first is None else (worst, first[0], first[1])


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


def turned_motions(f, at, motions, f_sigma: float, rp: RestParams, axis: int | None
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


def turned_warnings(t, turns, g: float, rec=None) -> list[str]:
    """The warnings of the turned motions ``turns`` (:func:`turned_motions`) kept in the output
    (``--keep-turned``): one line per motion, the first ZP_TURN_LINES, then one line for the others."""
    out = [f"displacement: {turned_text(t, x, g, rec)}; its path and the positions after it are not valid "
           "(kept: --keep-turned)" for x in turns]
    if len(out) > ZP_TURN_LINES:
        out = out[:ZP_TURN_LINES] + [f"displacement: {len(out) - ZP_TURN_LINES} more motion(s) like these"]
    return out


def trend_warnings(t, trends, rp: RestParams, sigma: float, streamed: bool, rec=None) -> list[str]:
    """The warning (one line, or none) of the stretches the detector declared at rest in which f
    changes steadily (``trends`` of :func:`.rest.rest_without_trend`: (first, end, change in
    m/s^2)); ``streamed``: the streaming forms, which took them as rests (the firmware's detector
    cannot look back), else the offline form, which left them out.  ``t`` in s, ``sigma`` the
    noise of f in m/s^2; ``rec`` names the rows (:func:`.common.time_span`)."""
    if not trends:
        return []
    b, e, ch = max(trends, key=lambda x: x[2])
    n = e - b
    what = ("were taken as rests by the streaming detector (it cannot look back): the motions about them "
            "are cut there and doubtful; the offline form (--form offline) leaves them out" if streamed else
            "are not taken as rests")
    return [f"displacement: f changes steadily where the rest detector found a rest ({len(trends)} block(s) of up "
            f"to {TREND_BLOCK_HOLDS * rp.hold} samples; the largest change {ch:.3g} m/s^2 over "
            f"{time_span(t, b, e - 1, rec)}, beyond the {trend_bound(n, sigma):.2g} m/s^2 that noise of {sigma:.2g} "
            f"m/s^2 gives (5 sigma of the change of a line fitted to {n} samples of it)): a slow motion, not a rest; "
            f"they {what}"]


def final_trend_note(t, trends, kept, rp: RestParams, sigma: float, rec=None) -> str:
    """Why the recording's end is no rest when the trend test rejected it (``trends`` of
    :func:`.rest.rest_without_trend`, those with no rest in ``kept`` after them), for the line of a
    last motion that does not end at rest: the stretch, its change against its bound (as a ratio: a
    rejection by a few per cent decides between a corrected path and none), and that a longer final
    rest decides more surely (the bound falls as n^-1/2).  Empty when no such stretch.  ``t`` in s,
    ``sigma`` the noise of f in m/s^2."""
    kept = np.asarray(kept, bool)
    last = [x for x in trends if not kept[x[0]:].any()]
    if not last:
        return ""
    b, e, ch = max(last, key=lambda x: x[0])
    bound = trend_bound(e - b, sigma)
    return (f"; the still stretch before its end ({time_span(t, b, e - 1, rec)}, {e - b} samples) is no rest by the "
            f"trend test: a line fitted to f changes by {ch:.3g} m/s^2 over it, {ch / bound:.3g} x the {bound:.2g} "
            f"m/s^2 that noise of {sigma:.2g} m/s^2 gives (5 sigma; a slow motion, or a rest rejected by "
            f"{100 * (ch / bound - 1):.2g} %: end the recording with a longer rest, over which noise changes a fitted "
            "line less, as n^-1/2)")


def motion_errors(f, p, at, motions, f_sigma: float, dt: float, axis: int | None
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
    zero velocity).  The change grows with T^2, the noise with T^1.5: beyond
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
    f_sigma : float
        The noise of f, m/s^2 per axis.
    dt : float
        s.
    axis : int or None
        1-D along that body axis, or None (3-axis).

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
        noise = 5.0 * float(f_sigma) * math.sqrt(dt * T ** 3 / 12.0)
        seg = np.asarray(p[a:e + 1], float) - np.asarray(p[a], float)
        path = float(np.max(np.abs(seg[:, axis]))) if axis is not None else float(np.max(np.linalg.norm(seg, axis=1)))
        out.append((int(a), int(e), tilt + noise, tilt, D, tell, path))
    return out


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
