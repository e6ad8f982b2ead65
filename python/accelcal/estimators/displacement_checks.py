"""The displacement's checks of a recording, for its warnings and errors: why no rest was
found (:func:`no_rest_reason`), a still stretch that is no rest because its |f| strays from g
(:func:`still_off_g`: the calibration's scale) or because the body turned
(:func:`still_but_turned`), rests that hold a trend (:func:`trend_warnings`).  The checks of the
corrected motions (a turn, what the correction leaves) are in :mod:`.motion_checks`."""
from __future__ import annotations

import math

import numpy as np

from ..io.device import GRAVITY_REMOVED_G, GRAVITY_REMOVED_TEXT
from ..errors import InputError
from .common import time_span
from .rest import RestParams, rest_dated_back, rest_on_g
from .trend import TREND_BLOCK_HOLDS, trend_bound

__all__ = ["REST_DEV_WARN_MPS2", "REST_NOISE_MAX_MPS2", "rest_noise_max", "wide_rest_warning", "no_rest_reason",
           "scale_off", "scale_cause", "still_off_g", "still_off_g_text", "off_g_text", "still_but_turned",
           "still_block", "HeldStretches", "zp_text",
           "streamed_off_g", "trend_warnings", "final_trend_note"]


#: the noisiest sensor at rest of issue 13's range, m/s^2 per axis (its 5 sigma: 0.25)
REST_NOISE_MAX_MPS2 = 0.05
#: a rest test (5 sigma of a noise estimated from the data) wider than this many sigma of the
#: noisiest sensor at rest is warned of (a rocket's vibration: 0.67 m/s^2)
REST_WARN_SIGMAS = 8.0


def rest_noise_max(q_f: float = 0.0) -> float:
    """The largest noise (m/s^2 per axis) :func:`accelcal.readings.noise.estimate_noise` gives for a sensor
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


def scale_off(norm: float, rp: RestParams) -> bool:
    """Whether a still stretch whose mean |f| is ``norm`` (m/s^2) is kept from being a rest by its
    |f|: the mean lies beyond g +- g_tol (:func:`.rest.rest_on_g`'s test of a rest; False when the
    |f| test is off).  A mean within it is no cause, whatever the noise does to single samples."""
    return rp.g is not None and abs(norm - rp.g) > rp.g_tol


def still_off_g_text(t, off, rp: RestParams, rec=None, cal=None) -> str:
    """The words for :func:`still_off_g`'s stretch ``off`` (``t`` in s; ``rec`` names its rows;
    ``cal`` the calibration used, :func:`scale_cause`)."""
    a, b, norm = off
    return (f"the body is still at {time_span(t, a, b, rec)} but that is no rest: it "
            f"{off_g_text(norm, rp, cal)}")


def scale_cause(cal, norm: float, g: float) -> str:
    """Why a still stretch's mean |f| (``norm``, m/s^2) is off ``g`` (m/s^2), after the calibration
    ``cal`` used (None or the device's nominal values: calibrate first).  A calibration given is named
    (``cal.extra['source']``, its file, else 'the calibration given'), with its method and model and
    how far |f| is off: a model that estimates no scale (jig-free 'offset') keeps the device file's
    nominal scale; one that does was made for another device, range or temperature.  Below
    ``GRAVITY_REMOVED_G`` of g no scale is to blame: the readings hold no gravity (the one wording,
    ``device.GRAVITY_REMOVED_TEXT``)."""
    if norm < GRAVITY_REMOVED_G * g:
        return f"|f| is {norm / g:.2g} g where the body is still, and any sensor at rest reads 1 g: {GRAVITY_REMOVED_TEXT}"
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


def off_g_text(norm: float, rp: RestParams, cal=None) -> str:
    """Why a still stretch is no rest when its |f| strays from g: its mean |f| (``norm``, m/s^2)
    beyond the rest test's g +- g_tol, and the cause (:func:`scale_cause` of the calibration ``cal``
    used)."""
    return (f"read |f| = {norm:.4g} m/s^2 on average, beyond the rest test's {rp.g:g} +- {rp.g_tol:g} m/s^2: "
            f"{scale_cause(cal, norm, rp.g)}")


def no_rest_reason(f, t, rp: RestParams, cal=None) -> str:
    """Why no rest was found, for the error: the stillest block of ``rp.hold`` samples (blocks
    at a stride of half a block), how far its f strays from its mean, and, when it is still
    enough but its mean |f| lies beyond the rest test's g +- g_tol, that |f| (a calibration whose
    scale is off: an uncalibrated chip 7.7 % high read with its nominal scale; ``cal``, the
    calibration used, named by
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
    if not scale_off(norm, rp):
        return (f"the stillest {hold} samples ({where}) stray only {dev:.3g} m/s^2 from their own mean and read "
                f"|f| = {norm:.4g} m/s^2, but the rest detector's running mean never settles on a still stretch "
                "that long: the body creeps or turns slowly throughout")
    return f"the stillest {hold} samples ({where}) are still (within {dev:.3g} m/s^2) but {off_g_text(norm, rp, cal)}"


def zp_text(z) -> str:
    """A motion's zero point (m/s^2) as the comment ``zero_point_mps2`` writes it."""
    return "(" + ", ".join(f"{c:.4g}" for c in np.atleast_1d(z)) + ")"


def still_block(blk, at_blk, rp: RestParams):
    """One block of ``rp.hold`` samples (f ``blk``, m/s^2; at rest ``at_blk``) as
    :func:`_still_blocks` takes it: (its mean f in m/s^2, whether its mean |f| keeps it from being a
    rest (:func:`scale_off`)) when it is not at rest and its f stays within ``rp.dev_max`` of that
    mean, else None."""
    if at_blk.any():
        return None
    m = blk.mean(axis=0)
    if float(np.max(np.abs(blk - m))) <= rp.dev_max:
        return m, scale_off(float(np.linalg.norm(m)), rp)
    return None


def _still_blocks(f, at_rest, rp: RestParams):
    """Each block of ``rp.hold`` samples (at a stride of a block) not at rest whose f stays within
    ``rp.dev_max`` of its mean: (its first sample, its mean f in m/s^2, whether its mean |f| keeps
    it from being a rest (:func:`scale_off`))."""
    hold = max(int(rp.hold), 2)
    for i in range(0, f.shape[0] - hold + 1, hold):
        got = still_block(f[i:i + hold], at_rest[i:i + hold], rp)
        if got is not None:
            yield i, got[0], got[1]


class HeldStretches:
    """:func:`_held_stretches` fed one block at a time (a recording read in chunks:
    accelcal.estimators.displacement_stream): :meth:`feed` and :meth:`finish` return the stretches
    that end there (first sample, last sample, the blocks' means)."""

    def __init__(self, hold: int, dev_max: float) -> None:
        self.hold, self.dev_max = hold, dev_max
        self.run: list | None = None

    def feed(self, i: int, m) -> list[tuple]:
        """The block at sample ``i`` with mean f ``m`` (m/s^2)."""
        run, hold = self.run, self.hold
        if (run is not None and _grow(tuple(run[:2]), i, hold) != tuple(run[:2])
                and float(np.max(np.abs(m - run[2][0]))) <= self.dev_max):
            run[1] = i + hold - 1
            run[2].append(m)
            return []
        self.run = [i, i + hold - 1, [m]]
        return [tuple(run)] if run is not None and len(run[2]) >= TREND_BLOCK_HOLDS else []

    def finish(self) -> list[tuple]:
        run = self.run
        return [tuple(run)] if run is not None and len(run[2]) >= TREND_BLOCK_HOLDS else []


def _grow(first, i: int, hold: int):
    """The first stretch (first and last sample) grown by the block at sample ``i`` when it
    begins within 1.5 blocks of its end (else kept)."""
    if first is None:
        return i, i + hold - 1
    return (first[0], i + hold - 1) if first[1] >= i - 1.5 * (hold - 1) else first


def _held_stretches(blocks, hold: int, dev_max: float):
    """The stretches of ``blocks`` ((first sample, mean f (3,) in m/s^2) of still blocks of ``hold``
    samples, in order) in which the body holds one f: each grown block by block (:func:`_grow`) while
    the block's mean stays within ``dev_max`` (m/s^2, each axis) of the stretch's first, that hold
    TREND_BLOCK_HOLDS blocks or more (1 s at the default hold: a hand that pauses while it
    accelerates, or the flat peaks of a smooth stroke's acceleration, hold that acceleration for a
    moment; a body set down off g or turned stays so): (first sample, last sample, the blocks' means),
    lazily in order (:class:`HeldStretches`)."""
    held = HeldStretches(hold, dev_max)
    for i, m in blocks:
        yield from held.feed(i, m)
    yield from held.finish()


def still_off_g(f, at_rest, rp: RestParams) -> tuple[int, int, float] | None:
    """The first stretch where the body is still (blocks of ``rp.hold`` samples within
    ``rp.dev_max`` of their mean) and not at rest because its mean |f| lies beyond the rest test's
    g +- g_tol (:func:`scale_off`), for TREND_BLOCK_HOLDS
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
    (int, int, float) or None
        The stretch's first and last sample and its mean |f| (m/s^2); None when there is none (or
        the |f| test is off).
    """
    f = np.asarray(f, float)
    at_rest = np.asarray(at_rest, bool)
    if rp.g is None:
        return None
    blocks = ((i, m) for i, m, off in _still_blocks(f, at_rest, rp) if off)
    for a, b, means in _held_stretches(blocks, max(int(rp.hold), 2), rp.dev_max):
        return a, b, float(np.mean(np.linalg.norm(means, axis=1)))
    return None


def still_but_turned(f, at_rest, rp: RestParams) -> tuple[float, int, int] | None:
    """A stretch where the body is still but not at rest: blocks of ``rp.hold`` samples whose
    f stays within ``rp.dev_max`` of its mean with its mean |f| within ``rp.g_tol`` of g (not one
    kept from a rest by the scale, :func:`still_off_g`'s: no turn is told there), away from the
    rest's direction by more than ``rp.ref_max``, for TREND_BLOCK_HOLDS blocks or more
    (:func:`_held_stretches`: the flat peak of a smooth stroke's acceleration, one sine period of
    0.785 m/s^2 over 2 s, holds still for a block or two at each of its peaks, and had been called
    a turn of 4.5 deg).
    For a body that only translates (a rail) every still stretch is a rest; such a stretch is a
    turn, which no accelerometer alone tells from an acceleration held as long (a constant
    acceleration of a second or more is taken for a turn).  Returns (its largest angle from the
    first rest's f, deg, over such stretches; the first such stretch's first and last sample) or
    None.  ``f`` in m/s^2, (n, 3)."""
    f = np.asarray(f, float)
    at_rest = np.asarray(at_rest, bool)
    if not at_rest.any():
        return None
    ref = f[at_rest][: max(rp.hold, 1)].mean(axis=0)
    blocks = ((i, m) for i, m, off in _still_blocks(f, at_rest, rp)
              if not off and float(np.linalg.norm(m - ref)) > rp.ref_max)
    worst, first = 0.0, None
    for a, b, means in _held_stretches(blocks, max(int(rp.hold), 2), rp.dev_max):
        first = first or (a, b)
        for m in means:
            cosang = float(np.dot(m, ref) / (np.linalg.norm(m) * np.linalg.norm(ref)))
            worst = max(worst, math.degrees(math.acos(min(1.0, max(-1.0, cosang)))))
    return None if first is None else (worst, first[0], first[1])


def streamed_off_g(t, at, quiet, f, rp: RestParams, rec=None, cal=None) -> list[str]:
    """The streaming detector's rests whose mean |f| is off g (:func:`.rest.rest_on_g`): it tests
    each sample (the firmware cannot look back) and takes them as rests.  The warning (one line, or
    none) names the first; none kept: the refusal, as the offline form's (it leaves them out).

    Parameters
    ----------
    t : ndarray (n,)
        s.
    at, quiet : ndarray (n,) bool
        The detector's rests (as declared) and quiet samples.
    f : ndarray (n, 3)
        Specific force, m/s^2.
    rp : RestParams
    rec, cal : optional
        Name the rows and the calibration used (:func:`.displacement_checks.still_off_g_text`).

    Raises
    ------
    InputError
        Every rest is off g.
    """
    kept, off = rest_on_g(rest_dated_back(at, quiet, f, rp), f, rp)
    if not off:
        return []
    words = still_off_g_text(t, (off[0][0], off[0][1] - 1, off[0][2]), rp, rec, cal)
    if not kept.any():
        raise InputError(rec.source if rec is not None else "recording",
                         f"displacement: no rest was detected anywhere in the recording: {words}; the stop-to-stop "
                         "method needs a rest at both ends of each motion")
    return [f"displacement: {words}; the streaming detector took {len(off)} such stretch(es) as rests (it tests "
            f"each sample, whose |f| may stray by the noise's {rp.g_noise:.3g} m/s^2 more): the motions about them "
            "are doubtful; the offline form (--form offline) leaves them out"]


def trend_warnings(t, trends, rp: RestParams, streamed: bool, rec=None) -> list[str]:
    """The warning (one line, or none) of the stretches the detector declared at rest in which f
    changes steadily (``trends`` of :func:`.trend.rest_without_trend`: (first, end, change, its bound,
    its axis's noise sigma, all m/s^2)); ``streamed``: the streaming forms, which took them as rests
    (the firmware's detector cannot look back), else the offline form, which left them out.  ``t``
    in s; ``rec`` names the rows (:func:`.common.time_span`)."""
    if not trends:
        return []
    b, e, ch, bound, sk = max(trends, key=lambda x: x[2])
    n = e - b
    what = ("were taken as rests by the streaming detector (it cannot look back): the motions about them "
            "are cut there and doubtful; the offline form (--form offline) leaves them out" if streamed else
            "are not taken as rests")
    return [f"displacement: f changes steadily where the rest detector found a rest ({len(trends)} block(s) of up "
            f"to {TREND_BLOCK_HOLDS * rp.hold} samples; the largest change {ch:.3g} m/s^2 over "
            f"{time_span(t, b, e - 1, rec)}, beyond the {bound:.2g} m/s^2 that noise of {sk:.2g} m/s^2 on that axis "
            f"gives (5 sigma of the change of a line fitted to {n} samples of it, {_correlated(bound, n, sk)})): a "
            f"slow motion, not a rest; they {what}"]


def _correlated(bound: float, n: int, sigma: float) -> str:
    """How a trend bound reads its noise: as white, or widened by the noise's correlation at rest."""
    w = bound / trend_bound(n, sigma) if sigma > 0 else 1.0
    return ("white: its samples not correlated at rest" if w < 1.005 else
            f"x {w:.2g} for its samples' correlation at rest")


def final_trend_note(t, trends, kept, rec=None) -> str:
    """Why the recording's end is no rest when the trend test rejected it (``trends`` of
    :func:`.trend.rest_without_trend`, those with no rest in ``kept`` after them), for the line of a
    last motion that does not end at rest: the stretch, its change against its bound (as a ratio: a
    rejection by a few per cent decides between a corrected path and none), and that a longer final
    rest decides more surely (the bound falls as n^-1/2).  Empty when no such stretch.  ``t`` in s."""
    kept = np.asarray(kept, bool)
    last = [x for x in trends if not kept[x[0]:].any()]
    if not last:
        return ""
    b, e, ch, bound, sk = max(last, key=lambda x: x[0])
    return (f"; the still stretch before its end ({time_span(t, b, e - 1, rec)}, {e - b} samples) is no rest by the "
            f"trend test: a line fitted to f changes by {ch:.3g} m/s^2 over it, {ch / bound:.3g} x the {bound:.2g} "
            f"m/s^2 that noise of {sk:.2g} m/s^2 on that axis gives (5 sigma, {_correlated(bound, e - b, sk)}; a "
            f"slow motion, or a rest rejected by {100 * (ch / bound - 1):.2g} %: end the recording with a longer rest, "
            "over which noise changes a fitted line less, as n^-1/2)")
