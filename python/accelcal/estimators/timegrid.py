"""The uniform time grid the integrators run on: each sample's place on it, from time stamps
that jitter, drift slowly against the sensor's clock, come late on delivery, or skip the
samples a logger dropped (those filled by interpolation)."""
from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import InputError
from ..io.recording import Recording
from ..io.recording_checks import CHANCE_REPEAT_P, GAP_STEPS, chance_repeats, regular_step
from .common import time_span

__all__ = ["REGRID_HINT", "RESAMPLE_BRIDGE_SAMPLES", "resampled", "MAX_FILL_SAMPLES", "MAX_FILL_SHARE", "MAX_JITTER_STEPS",
           "JITTER_NOTE_STEPS", "MAX_LATE_STEPS",
           "MAX_WANDER_STEPS", "WANDER_BLOCK", "COHERENT_SHARE", "COHERENT_BLOCK", "block_phases", "stamp_trend",
           "grid_places", "places_from", "on_uniform_grid", "long_gaps", "beyond_filling"]

#: the remedy a refusal of stamps off the grid names (a sensor sampled at a constant rate whose stamps stray)
REGRID_HINT = ("; if the sensor sampled at a constant rate and only its time stamps stray (a logger that polls it, a "
               "host that stamps on arrival), accelcal convert --rate HZ (the sensor's rate) writes the recording on "
               "that rate's grid, the stamps kept as column t_host")

#: dropped samples are filled (linear interpolation) up to this many in one gap ...
MAX_FILL_SAMPLES = 10
#: ... and this share of the recording; longer or more gaps are refused
MAX_FILL_SHARE = 0.05
#: time stamps may stray this far (in steps) from their place: jitter of the stamps, not the samples
#: (within a quarter step each, every step rounds to its whole number of steps)
MAX_JITTER_STEPS = 0.25
#: ... and below this they are not worth a word (nor a new grid)
JITTER_NOTE_STEPS = 0.05
#: a sample stamped late by up to this (steps), the next one on time at the next place, was delivered
#: late: its place is on the grid (a phone's log: 0.66 of a step late, the next 0.34 of a step after
#: it; two in a row 0.65 and 0.66 late, the next on time) -- a run of them too
MAX_LATE_STEPS = 0.75
#: the stamps' local mean may drift this far (steps) from one uniform grid: a host's clock against the
#: sensor's (a flight controller's log: -0.38..+0.2 over 68 s; a phone's: -0.23..+0.22 over 300 s).
#: Further, the sample rate itself changes, and no one grid holds the samples
MAX_WANDER_STEPS = 0.5
#: ... that local mean: a trimmed circular mean of the stamps' phases over blocks of this many samples
WANDER_BLOCK = 256

#: at least this share of every COHERENT_BLOCK samples must be stamped within ON_TIME of their places
#: (samples stamped late or early now and then; a rate that changes spreads the stamps over the step)
COHERENT_SHARE = 0.75
COHERENT_BLOCK = 64

# a stamp on time lies within this of its place (steps): the jitter, and the local mean's own error
ON_TIME = 1.25 * MAX_JITTER_STEPS
# the latest a late sample may be (steps), with the same room
LATE_ROOM = MAX_LATE_STEPS + 0.25 * MAX_JITTER_STEPS


def wrapped(x: np.ndarray) -> np.ndarray:
    """x less its nearest whole number: in [-1/2, 1/2]."""
    return x - np.round(x)


def block_phases(w: np.ndarray, block: int) -> tuple[np.ndarray, np.ndarray]:
    """The mean phase (steps) of time stamps at ``w`` steps along a uniform grid over blocks of
    ``block`` samples: each stamp's phase (w less its nearest whole step: a dropped sample shifts a
    place, not a phase) averaged as an angle, trimmed to the phases within ON_TIME of the mean (three
    times over: samples stamped late do not pull it), unwrapped from block to block.

    Returns
    -------
    phase : ndarray, shape (nb,)
        Each block's mean phase.
    edges : ndarray of int, shape (nb + 1,)
        The blocks' bounds (block b is samples edges[b] .. edges[b + 1] - 1).
    """
    nb = max(w.size // block, 1)
    edges = np.linspace(0, w.size, nb + 1).astype(np.int64)
    phase = np.empty(nb)
    for b in range(nb):
        x = w[edges[b]:edges[b + 1]]
        m = float(np.angle(np.sum(np.exp(2j * np.pi * x)))) / (2 * np.pi)
        for _ in range(3):
            dev = wrapped(x - m)
            dev = dev[np.abs(dev) <= ON_TIME]
            if dev.size:
                m += float(np.mean(dev))
        phase[b] = m
    return np.unwrap(2 * np.pi * phase) / (2 * np.pi), edges


def stamp_trend(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The slow drift (steps) of time stamps at ``w`` steps along a uniform grid: their mean phase
    over blocks of WANDER_BLOCK samples (:func:`block_phases`), linearly interpolated between the
    blocks' centres; and the blocks' bounds."""
    phase, edges = block_phases(w, WANDER_BLOCK)
    centre = (edges[:-1] + edges[1:] - 1) / 2.0
    return np.interp(np.arange(w.size), centre, phase), edges


def grid_places(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each sample's place on a uniform grid, counted in steps.

    The step starts from the median step and from the regular steps' period
    (:func:`~accelcal.io.recording_checks.regular_step`), and the grid that puts more stamps on time
    is kept (the median first where they tie): a host clock that catches up with a short step now
    and then does not keep the median (10.24 ms for a 10.00 ms sensor, 2.4 % off: every sample had
    been pushed off its place within 40 samples), and where the rate changes part way the period is
    neither half's.  Each start is corrected (twice, over blocks of 16 then 64 samples) by the slope
    of the stamps' mean phase on it (:func:`block_phases`: jitter, late stamps and dropped samples do
    not move it), then (three times) by the slope of the stamps on time against the places found;
    the stamps' slow drift from that grid is :func:`stamp_trend`.  A sample's place is the nearest
    to its stamp (less the drift; k + 1/2 taken as k), or the one before where the next sample
    takes that place: a sample stamped late is pushed back by those after it.

    Returns
    -------
    q : ndarray of int64, shape (n,)
        The places, strictly increasing, q[0] = 0.
    late : ndarray, shape (n,)
        How late (steps) each stamp is about the stamps' local mean (>= -1/2).
    pushed : ndarray of bool, shape (n,)
        The samples pushed back from their nearest place by the ones after them.
    edges : ndarray of int
        The blocks of :func:`stamp_trend`.
    """
    best = None
    regular, _, median = regular_step(t)
    # the period a second start only where it differs (stamps on an even grid give one)
    for step in (median,) + (() if abs(regular - median) <= 1e-12 * abs(median) else (regular,)):
        got = places_from(t, step)
        on = int(np.count_nonzero(np.abs(got[1]) <= ON_TIME))
        if best is None or on > best[0]:
            best = (on, got)
    return best[1]


def places_from(t: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`grid_places` from one starting step (s)."""
    for block in (16, 64):
        w = (t - t[0]) / step
        phase, edges = block_phases(w, block)
        if phase.size > 2:
            centre = np.array([np.mean(w[a:b]) for a, b in zip(edges[:-1], edges[1:])])
            step *= 1.0 + float(np.polyfit(centre, phase, 1)[0])
    i = np.arange(t.size)
    for _ in range(3):          # then the slope of the stamps on time against their places
        w = (t - t[0]) / step
        trend, edges = stamp_trend(w)
        u = w - trend
        f = np.ceil(u - 0.5 - 1e-9)     # the nearest place, k + 1/2 taken as k
        q = (np.minimum.accumulate((f - i)[::-1])[::-1] + i).astype(np.int64)
        on = np.abs(u - q) <= ON_TIME
        if np.count_nonzero(on) > 2:
            step = float(np.polyfit(q[on].astype(float), t[on], 1)[0])
    q0 = int(q[0])
    return q - q0, u - q, q < f, edges


def crowded(rec, t: np.ndarray, late: np.ndarray, pushed: np.ndarray, dt: float, hint: str = REGRID_HINT
            ) -> InputError | None:
    """The refusal of more samples than the grid has places for (one pushed back further than
    LATE_ROOM by those after it), or None.

    Rows b..e are named: e the first not pushed back after the first sample pushed too far, b the
    last one pushed too far before it; a row among them that repeats the readings of the row before
    exactly (a sample delivered twice) is named as such, and the refusal's row is the last of those,
    else e -- where the repeat is evidence of a copy: stamped within half a step of the row before,
    or rows that repeat the row before far more often than chance gives
    (:func:`~accelcal.io.recording_checks.chance_repeats`); a coarse grid's chance repeat is not."""
    bad = np.flatnonzero(pushed & (late > LATE_ROOM))
    if not bad.size:
        return None
    j = int(bad[0])
    e = j + int(np.flatnonzero(~pushed[j:])[0])
    b = int(bad[bad < e][-1])
    raw = np.asarray(rec.raw)
    # a repeat is a copy only off the grid (within half a step of the row before: two samples on
    # one place) or where repeats in the recording are beyond chance (a coarse grid repeats rows)
    copies = chance_repeats(raw)[2] < CHANCE_REPEAT_P
    same = [m for m in range(b + 1, e + 1) if np.array_equal(raw[m], raw[m - 1])
            and (copies or t[m] - t[m - 1] < 0.5 * dt)]
    head = (f"sample times are not uniform: the step to {time_span(t, e)} is {t[e] - t[e - 1]:.6g} s, "
            f"{(t[e] - t[e - 1]) / dt:.2f} of the median step {dt:.6g} s: rows {rec.line(b)}-{rec.line(e)} are "
            f"{e - b + 1} samples within {(t[e] - t[b]) / dt:.2f} steps, one more than the uniform grid has places "
            "for" + (f" (every place before them back to row {rec.line(j)} taken)" if j < b else ""))
    if same:
        a = same[0] - 1
        while a > 0 and np.array_equal(raw[a - 1], raw[a]):
            a -= 1
        rows = (f"row {rec.line(same[0])} repeats" if len(same) == 1 else
                f"rows {', '.join(str(rec.line(m)) for m in same)} repeat")
        return InputError(rec.source, f"{head}; {rows} the readings of the row before exactly (rows "
                          f"{rec.line(a)}-{rec.line(same[-1])} alike): a sample delivered twice, with no place of its "
                          "own on the grid -- not left out here (a copy is left out by accelcal convert where such "
                          "copies stand out in the file); leave one copy out of the recording to go on: the "
                          "integrators need a constant rate", row=rec.line(same[-1]), column="t")
    return InputError(rec.source, f"{head}; row {rec.line(b)} would be {late[b]:.2f} of a step late (up to "
                      f"{MAX_LATE_STEPS:g} is taken as a sample delivered late, {MAX_JITTER_STEPS:g} as jitter of the "
                      "stamps): the integrators need a constant rate" + hint, row=rec.line(e), column="t")


def long_gaps(rec, t: np.ndarray) -> InputError | None:
    """The refusal of a step that no filling bridges -- at least MAX_FILL_SAMPLES + 2 regular steps
    (:func:`~accelcal.io.recording_checks.regular_step`), more than MAX_FILL_SAMPLES places empty
    whatever the stamps' jitter or lateness -- named at the row after the first such step, with the
    samples missing in the steps beyond GAP_STEPS x the median, the longest gap, and the share of the
    span without samples (a
    recording of captures joined, such as Klipper's: 10 gaps of 1.6 s, 61 %), or None.  It comes
    before the grid's finer refusals, which such gaps would otherwise precede with a lesser defect."""
    step, gaps, median = regular_step(t)
    d = np.diff(t)
    beyond = np.flatnonzero(d >= (MAX_FILL_SAMPLES + 2) * step)
    if not beyond.size or step <= 0:
        return None
    i, j = int(beyond[0]), int(np.argmax(d))
    long = d > GAP_STEPS * median
    lost = np.rint(d[long] / step) - 1
    span = float(t[-1] - t[0])
    empty = 100 * float(np.sum(d[long] - step)) / span
    return InputError(rec.source, f"sample times are not uniform: {int(lost.sum())} sample(s) missing in {gaps} gap(s), "
                      f"the longest {int(lost.max())} ({d[j]:.6g} s against {step:.6g} s; a gap: a step beyond "
                      f"{GAP_STEPS:g} x the median), {empty:.2g} % of the span of {span:.6g} s without samples; the first beyond "
                      f"filling is the step to {time_span(t, i + 1)} ({d[i]:.6g} s): pauses between captures, or samples "
                      f"lost, where at most {MAX_FILL_SAMPLES} in one gap and {100 * MAX_FILL_SHARE:g} % of the recording "
                      "are filled by interpolation; cut the recording at the gaps (each part on its own): the integrators "
                      "need a constant rate", row=rec.line(i + 1), column="t")


def incoherent(rec, t: np.ndarray, late: np.ndarray, dt: float, hint: str = REGRID_HINT) -> InputError | None:
    """The refusal of stamps that keep no uniform grid over COHERENT_BLOCK samples (fewer than
    COHERENT_SHARE of them within ON_TIME of their places: the rate changes), or None -- named at the
    first stamp off the jitter in the first such block."""
    off = np.abs(late) > ON_TIME
    n = t.size
    if n < COHERENT_BLOCK:
        return None
    c = np.concatenate([[0], np.cumsum(off)])
    share = (c[COHERENT_BLOCK:] - c[:-COHERENT_BLOCK]) / COHERENT_BLOCK
    bad = np.flatnonzero(share > 1.0 - COHERENT_SHARE)
    if not bad.size:
        return None
    a = int(bad[0])
    b = a + COHERENT_BLOCK - 1
    i = a + int(np.flatnonzero(off[a:b + 1])[0])
    return InputError(rec.source, f"sample times are not uniform: rows {rec.line(a)}-{rec.line(b)} keep no uniform "
                      f"grid: {int(c[b + 1] - c[a])} of their {COHERENT_BLOCK} stamps lie more than {ON_TIME:g} of a step "
                      f"off it ({time_span(t, i)} is {late[i]:+.2f} steps off a uniform grid of about {dt:.6g} s; "
                      f"their steps {(t[b] - t[a]) / (b - a):.6g} s on average): the rate changes, and up to "
                      f"{MAX_JITTER_STEPS:g} of a step off is taken as jitter of the stamps, a sample up to "
                      f"{MAX_LATE_STEPS:g} late now and then as delivered late: the integrators need a constant rate"
                      + hint, row=rec.line(i), column="t")


def beyond_filling(lost: np.ndarray, limit: int) -> bool:
    """Whether the samples ``lost`` after each sample (a recording's steps, whole samples) are more than
    interpolation fills: more than ``limit`` in one gap, or more than MAX_FILL_SHARE of the grid (the
    samples kept and lost) in all.  The rule of the filling of dropped samples
    (:func:`on_uniform_grid`, MAX_FILL_SAMPLES) and of --resample's bridge (:func:`resampled`,
    RESAMPLE_BRIDGE_SAMPLES); each caller words its own refusal."""
    lost = np.asarray(lost, np.int64)
    total = int(lost.sum())
    return bool(lost.size) and (int(lost.max()) > limit or total > MAX_FILL_SHARE * (lost.size + 1 + total))


def wander(off: np.ndarray, on: np.ndarray, edges: np.ndarray) -> float:
    """How far (steps) the stamps ``off`` a grid drift from it: the largest |median| over the
    blocks ``edges`` of the stamps on time (``on``); blocks without one left out."""
    return max((abs(float(np.median(off[a:b][on[a:b]]))) for a, b in zip(edges[:-1], edges[1:]) if on[a:b].any()),
               default=0.0)


def wander_error(rec, t: np.ndarray, q: np.ndarray, on: np.ndarray, edges: np.ndarray, hint: str = REGRID_HINT
                 ) -> InputError:
    """The refusal of stamps whose local mean leaves one uniform grid by more than MAX_WANDER_STEPS,
    named where it leaves the grid of the rows before it (the line through the blocks before the
    first block that no line through those before it and itself holds within MAX_WANDER_STEPS)."""
    nb = edges.size - 1
    blk = np.searchsorted(edges, np.arange(t.size), side="right") - 1
    s, c = np.polyfit(q[on].astype(float), t[on], 1)
    for b in range(1, nb):
        sel = on & (blk <= b)
        s2, c2 = np.polyfit(q[sel].astype(float), t[sel], 1)
        off = (t - c2 - s2 * q) / s2
        if wander(off, sel, edges[:b + 2]) > MAX_WANDER_STEPS:
            break
        s, c = s2, c2
    else:
        b = 0
    off = (t - c - s * q) / s
    beyond = np.flatnonzero(on & (np.abs(off) > MAX_WANDER_STEPS) & (blk >= b))
    j = int(beyond[0]) if beyond.size else int(edges[b])
    lo, hi = int(edges[b]), int(edges[min(b + 1, nb)]) - 1
    local = (t[hi] - t[lo]) / max(int(q[hi] - q[lo]), 1)
    return InputError(rec.source, f"sample times are not uniform: {time_span(t, j)} is {off[j]:+.2f} steps off the "
                      f"uniform grid of the rows before it ({s:.6g} s a step), the steps about it {local:.6g} s on "
                      f"average: the stamps' local mean may drift up to {MAX_WANDER_STEPS:g} of a step from one "
                      "uniform grid (a host's clock against the sensor's), the sample rate may not change: the "
                      "integrators need a constant rate" + hint, row=rec.line(j), column="t")


def on_uniform_grid(rec, hint: str = REGRID_HINT) -> tuple[Any, np.ndarray, str | None]:
    """A recording whose time stamps jitter, drift, come late on delivery, or whose logger dropped
    samples, on its uniform time grid.

    Each sample's place is found by :func:`grid_places`.  About the stamps' local mean
    (:func:`stamp_trend`), a stamp is on time within ON_TIME (1.25 MAX_JITTER_STEPS: the jitter of
    the stamps, not of the samples) or late by up to MAX_LATE_STEPS (delivered late: alone or in a
    run, the run followed by a sample on time at the next place); that local mean may drift up to
    MAX_WANDER_STEPS from the straight grid fitted to the samples on time (the grid's step their
    mean interval).  Places left empty are dropped samples: up to MAX_FILL_SAMPLES in one gap and
    MAX_FILL_SHARE of the whole are filled by linear interpolation of the counts (rounded to whole
    counts), so that the integrators run at their constant rate.

    ``hint`` ends a refusal of stamps that keep no uniform grid: the remedy the caller offers.

    Returns
    -------
    rec : Recording
        The recording itself when its stamps are uniform to JITTER_NOTE_STEPS and nothing was
        dropped, else a new one (t and raw only, t on the grid: the time base the integrators use).
    filled : ndarray of bool, shape (n,)
        True on the interpolated samples.
    note : str or None
        What was done, for the user.

    Raises
    ------
    InputError
        A step no filling bridges (:func:`long_gaps`, first), a sample with no place of its own
        (two on one place: a sample delivered twice, or stamped too late; naming the second), a sample late with a gap after it, stamps that drift further
        (naming where they leave the grid of the rows before), or gaps beyond the limits (naming
        the row after the longest).
    """
    t = np.asarray(rec.t, float)
    if t.size < 2:
        raise InputError(rec.source, "the recording needs at least 2 samples")
    d = np.diff(t)
    dt = float(np.median(d))
    err = long_gaps(rec, t)
    if err is not None:
        raise err
    q, late, pushed, edges = grid_places(t)
    for err in (crowded(rec, t, late, pushed, dt, hint), incoherent(rec, t, late, dt, hint)):
        if err is not None:
            raise err
    lt = late > ON_TIME
    early = late < -ON_TIME
    on = ~(lt | early)
    slope, icpt = (float(v) for v in np.polyfit(q[on].astype(float), t[on], 1)) if np.count_nonzero(on) > 2 \
        else (dt, float(t[0]))
    off = (t - icpt - slope * q) / slope
    drift = wander(off, on, edges)
    if drift > MAX_WANDER_STEPS:
        raise wander_error(rec, t, q, on, edges, hint)
    missing = np.diff(q) - 1
    total = int(missing.sum())
    jitter = float(np.max(np.abs(off[on])))
    if total == 0 and jitter <= JITTER_NOTE_STEPS and not (lt | early).any():
        return rec, np.zeros(t.size, bool), None
    notes = []
    if lt.any():
        starts = np.flatnonzero(lt & ~np.concatenate([[False], lt[:-1]]))
        ends = np.flatnonzero(lt & ~np.concatenate([lt[1:], [False]]))
        notes.append(f"{int(lt.sum())} sample(s) stamped late by up to {float(np.max(late[lt])):.2f} of a step "
                     f"({starts.size} run(s), the longest {int(np.max(ends - starts)) + 1} in a row: a host that stamps "
                     "on delivery) are taken at their place on the grid")
    if early.any():
        notes.append(f"{int(early.sum())} sample(s) stamped early by up to {-float(np.min(late)):.2f} of a step "
                     "(beyond the jitter, within half a step) are taken at their nearest place on the grid")
    if jitter > JITTER_NOTE_STEPS:
        drifts = (f" (their local mean drifts by up to {drift:.2f} of a step from it: a host's clock against the "
                  "sensor's)" if drift > MAX_JITTER_STEPS / 2 else "")
        notes.append(f"the time stamps stray by up to {jitter:.2f} of a step from a uniform {1.0 / slope:.6g} Hz "
                     f"grid{drifts}: taken as jitter of the stamps, the samples as uniform (t is written on that grid)")
    if total:
        i = int(np.argmax(missing))
        if beyond_filling(missing, MAX_FILL_SAMPLES):
            raise InputError(rec.source, f"sample times are not uniform: {total} sample(s) missing in "
                             f"{int(np.count_nonzero(missing))} gap(s), "
                             f"the longest {int(missing[i])} ({d[i]:.6g} s against {dt:.6g} s): the integrators "
                             f"need a constant rate, and at most {MAX_FILL_SAMPLES} in one gap and "
                             f"{100 * MAX_FILL_SHARE:g} % of the recording are filled by interpolation",
                             row=rec.line(i + 1), column="t")
        notes.append(f"{total} dropped sample(s) in {int(np.count_nonzero(missing))} gap(s) (the longest "
                     f"{int(missing[i])}, after {time_span(t, i, rec=rec)}) filled by linear interpolation of the "
                     "counts; column filled = 1 there")
    grid = icpt + slope * np.arange(q[-1] + 1)
    kept = np.zeros(grid.size, bool)
    kept[q] = True
    raw = np.asarray(rec.raw, float)
    full = np.rint(np.column_stack([np.interp(grid, grid[q], raw[:, j]) for j in range(raw.shape[1])]))
    full = full.astype(np.int64)
    full[kept] = np.asarray(rec.raw, np.int64)
    out = Recording(t=grid, raw=full, metadata=dict(rec.metadata), source=rec.source)
    return out, ~kept, "; ".join(notes)


#: --resample bridges a gap of up to this many samples lost in a row (a step of up to 2.5 regular steps):
#: a straight line across one sample moves a 0.2 m stroke at 100 Hz by 3e-7 m (median over places) to
#: 1.9e-4 m (its fastest part: about the noise's spread, within the output's error bound; figures in
#: tests/python/test_timegrid.py), where cutting the recording at the gap loses the rests that anchor
#: the path; longer gaps are refused, and at most MAX_FILL_SHARE of the grid is bridged.  A gap: a step beyond GAP_STEPS x the
#: median step (the rule convert's note uses), its samples lost the whole regular steps less one
RESAMPLE_BRIDGE_SAMPLES = 1


def resampled(rec) -> tuple[Any, str, np.ndarray]:
    """A recording whose samples were taken at their (uneven) time stamps -- a sensor read on a loop
    whose period varies, a driver that stamps each sample as it reads it -- interpolated onto a
    uniform grid over the same span (linear interpolation of the counts, rounded to whole counts).
    Steps up to GAP_STEPS x the median step are taken as the loop's; a longer step is a gap, of
    round(step / regular step) - 1 samples lost (:func:`~accelcal.io.recording_checks.regular_step`):
    gaps of up to RESAMPLE_BRIDGE_SAMPLES are bridged, with a note, the grid holding one place for
    each sample kept or lost (its step the span over them).

    Returns
    -------
    rec : Recording
        t on the uniform grid, raw interpolated.
    note : str
        What was done, for the user.
    bridged : ndarray of bool, shape (n_grid,)
        True on the grid's samples inside a bridged gap.

    Raises
    ------
    InputError
        A gap of more than RESAMPLE_BRIDGE_SAMPLES lost, or more bridged than MAX_FILL_SHARE of
        the grid, naming the row after the longest gap.
    """
    t = np.asarray(rec.t, float)
    if t.size < 2:
        raise InputError(rec.source, "the recording needs at least 2 samples")
    d = np.diff(t)
    step, gaps, median = regular_step(t)
    gap = d > GAP_STEPS * median
    lost = np.where(gap, np.maximum(np.rint(d / step) - 1, 1), 0).astype(np.int64)
    total = int(lost.sum())
    i = int(np.argmax(d))
    if beyond_filling(lost, RESAMPLE_BRIDGE_SAMPLES):
        raise InputError(rec.source, f"--resample: the step to {time_span(t, i + 1)} is {d[i]:.6g} s, "
                         f"{d[i] / step:.3g} of the regular step {step:.6g} s (the longest of {gaps} steps beyond "
                         f"{GAP_STEPS:g} x the median step, {total} sample(s) lost in all): about {int(lost[i])} "
                         f"sample(s) lost there, where a gap of up to {RESAMPLE_BRIDGE_SAMPLES} sample(s) lost (and "
                         f"{100 * MAX_FILL_SHARE:g} % of the recording in all) is bridged with a straight line; cut the "
                         "recording at the gap (each part on its own)", row=rec.line(i + 1), column="t")
    m = t.size + total
    dt = (t[-1] - t[0]) / (m - 1)
    grid = t[0] + dt * np.arange(m)
    raw = np.asarray(rec.raw, float)
    out = np.rint(np.column_stack([np.interp(grid, t, raw[:, j]) for j in range(raw.shape[1])])).astype(np.int64)
    k = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, d.size - 1)
    bridged = gap[k] & (grid > t[k]) & (grid < t[k + 1])
    regular = d[~gap]
    places = np.arange(t.size) + np.concatenate([[0], np.cumsum(lost)])
    off = float(np.max(np.abs(t - grid[places]))) / dt
    note = (f"--resample: {t.size} samples interpolated (linearly) from their stamps onto a uniform "
            f"{1.0 / dt:.6g} Hz grid (steps {regular.min() / dt:.2f}-{regular.max() / dt:.2f} of the grid's, the "
            f"stamps up to {off:.2f} of a step off it)")
    if total:
        note += (f"; {int(gap.sum())} gap(s), {total} lost sample(s) (steps beyond {GAP_STEPS:g} x the median, the longest "
                 f"{d[i]:.6g} s = {d[i] / dt:.2f} steps, after {time_span(t, i, rec=rec)}; {float(d[gap].sum()):.4g} s "
                 "in all) bridged with a straight line; column filled = 1 there")
    return Recording(t=grid, raw=out, metadata=dict(rec.metadata), source=rec.source), note, bridged
