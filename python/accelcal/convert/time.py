"""Time columns in the files other tools write: their unit (seconds, or a logger's millis(),
micros(), an epoch in nanoseconds) and the sample rate their steps give (a host that stamps
the samples in bursts).  Used by :mod:`accelcal.convert.formats` for every format with a time column."""
from __future__ import annotations

import datetime
import re

import numpy as np

from ..errors import InputError
from ..io.recording_checks import GAP_STEPS, even_steps, regular_step

__all__ = ["TIME_FACTORS", "TIME_COLUMN_RE", "is_time_name", "is_broad_time_name", "EPOCH_MIN_S", "epoch_like", "MIN_PLAUSIBLE_HZ", "BURST_SHARE", "FLOAT_EXACT", "unit_in_name",
           "exact_stamps", "time_factor", "DATETIME_RE", "is_datetime", "datetime_stamps", "time_in_seconds", "burst_fit",
           "burst_starts", "burst_rate", "rate_from_t"]

#: the unit of a time column: its factor to seconds
TIME_FACTORS = {"s": 1.0, "ms": 1e3, "us": 1e6, "ns": 1e9}
TIME_WORDS = {"ms": ("ms", "msec", "millis", "millisecond", "milliseconds"),
              "us": ("us", "\u00b5s", "usec", "micros", "microsecond", "microseconds"),
              "ns": ("ns", "nsec", "nanos", "nanosecond", "nanoseconds"),
              "s": ("s", "sec", "secs", "second", "seconds")}
#: below this rate t read as seconds is taken for a finer unit (auto)
MIN_PLAUSIBLE_HZ = 2.0
#: t's median step and its mean step disagreeing by more than this share: bursty time stamps
BURST_SHARE = 0.25
#: ... and a straight line through the bursts' first stamps misses them by at most this share
#: of its sample period, rms: the host reads in bursts as the sensor fills them
BURST_FIT_STEPS = 0.5
#: ... or t's median step is below this share of its mean step
BURST_TINY_STEP = 0.05
#: float64 holds every whole number below this exactly (a time stamp beyond it, an epoch in
#: ns, is read as an integer: :func:`exact_stamps`)
FLOAT_EXACT = 2.0 ** 53
#: a column of whole numbers (a sign, digits, blanks about them), one a line
INTEGER_CELLS_RE = re.compile(r"(?:[ \t]*[+-]?[0-9]+[ \t]*\n)*[ \t]*[+-]?[0-9]+[ \t]*")
#: a table's time column: t, time, timestamp, with a unit in () or [] or after _ (``time_ms``)
TIME_COLUMN_RE = re.compile(r"(?:t|ts|tstamp|time|timestamp|time[ _]stamp)(?:\s*[(\[][^)\]]*[)\]]|_[a-z\u00b5]+)?"
                            r"|%time|(?:field\.)?header\.stamp", re.I)     # rostopic echo -p: ns

#: a word of a column's name that makes it a time column beyond TIME_COLUMN_RE's forms (unix_timestamp,
#: epoch, unix_time, sensorTimestamp, time_since_boot_ms), and words that make it no time stamp (a step
#: between samples, a zone, a duration)
TIME_NAME_WORDS = ("time", "times", "timestamp", "timestamps", "stamp", "epoch", "ts", "datetime", "utime")
NOT_TIME_WORDS = ("delta", "dt", "diff", "zone", "tz", "offset", "step", "interval", "period", "duration",
                  "exposure", "sync", "zero")
#: a stamp at least this far past 1970 in seconds (1973) whatever its unit: an epoch
EPOCH_MIN_S = 1e8


def name_words(name: str) -> list[str]:
    """A column name's words, lower case: split at anything not a letter and at camelCase
    (``unixTimestamp_US``: unix, timestamp, us)."""
    return [w.lower() for w in re.findall(r"[A-Z]?[a-z\u00b5]+|[A-Z]+(?![a-z])", name)]


def is_broad_time_name(name: str) -> bool:
    """Whether a name not of TIME_COLUMN_RE's forms holds a time word (``unix_timestamp``,
    ``epoch``, ``unix_time``, ``SensorTimestamp``) and none that makes it a step, zone or
    duration (``delta_time``, ``time_zone``).  Such a column is a time column where its name
    states a unit or its stamps are an epoch's (:func:`epoch_like`; the caller's rule)."""
    words = name_words(name)
    return any(w in TIME_NAME_WORDS for w in words) and not any(w in NOT_TIME_WORDS for w in words)


def is_time_name(name: str) -> bool:
    """Whether a column's name makes it a candidate time column: TIME_COLUMN_RE's forms, or a
    time word among others (:func:`is_broad_time_name`)."""
    name = name.strip()
    return bool(TIME_COLUMN_RE.fullmatch(name)) or is_broad_time_name(name)


def epoch_like(text: str) -> bool:
    """Whether a time cell is a number of an epoch's magnitude in any unit (at least
    EPOCH_MIN_S, s since 1970: 1973 in s, and any later epoch in ms, us or ns)."""
    try:
        return float(text) >= EPOCH_MIN_S
    except ValueError:
        return False


#: an ISO-8601 date and time of day: ``2019-10-16T12:09:01.702+02:00``, ``2019-12-23 21:04:06.690``,
#: ``2021-05-07T10:29:56``, ``...Z``; seconds optional, a fraction of any length, a zone or none
DATETIME_RE = re.compile(r"(?P<y>\d{4})-(?P<mo>\d{2})-(?P<d>\d{2})[T ](?P<h>\d{2}):(?P<mi>\d{2})"
                         r"(?::(?P<s>\d{2})(?:[.,](?P<frac>\d+))?)?"
                         r"(?P<zone>Z|[+-]\d{2}(?::?\d{2})?)?", re.I)
#: the Unix epoch as a proleptic Gregorian ordinal (days)
EPOCH_DAY = datetime.date(1970, 1, 1).toordinal()


def is_datetime(text: str) -> bool:
    """Whether a time column's cell is a full ISO-8601 date-time (a date and a time of day,
    :data:`DATETIME_RE`); a time of day alone or a date alone is not."""
    return DATETIME_RE.fullmatch(text.strip()) is not None


def datetime_ns(m: re.Match) -> tuple[int, int | None]:
    """A matched date-time as whole nanoseconds since 1970-01-01 of its own clock (the zone not
    applied; digits of the fraction beyond the ns dropped), and its zone's offset east of UTC
    in ns (None when it states no zone).  Raises ValueError for a day or time that does not
    exist (2019-02-30, 25:00)."""
    g = m.groupdict()
    day = datetime.date(int(g["y"]), int(g["mo"]), int(g["d"])).toordinal() - EPOCH_DAY
    h, mi, s = int(g["h"]), int(g["mi"]), int(g["s"] or 0)
    if h > 23 or mi > 59 or s > 60:             # 60: a leap second
        raise ValueError("no such time of day")
    ns = ((day * 24 + h) * 60 + mi) * 60 + s
    ns = ns * 1_000_000_000 + int(((g["frac"] or "") + "000000000")[:9])
    zone = g["zone"]
    if zone is None:
        return ns, None
    if zone.upper() == "Z":
        return ns, 0
    digits = zone[1:].replace(":", "")
    offset = (int(digits[:2]) * 60 + int(digits[2:4] or 0)) * 60_000_000_000
    return ns, offset if zone[0] == "+" else -offset


def datetime_stamps(cells: list[str], source: str, lines: list[int], column: str,
                    notes: list[str]) -> np.ndarray:
    """A time column of ISO-8601 date-times (:func:`is_datetime`) as int64 nanoseconds since
    1970-01-01 UTC, exact to the ns (float64 seconds since the epoch keep ~0.2 us).

    Date-times with a zone (``+02:00``, ``Z``) are converted to UTC, also where the zone
    changes within the file (a clock put forward: a note names the row); date-times without
    one are read as the clock wrote them (taken for UTC, with a note).

    Parameters
    ----------
    cells : list of str
        The column's cells of the rows read, in order.
    source : str
        The file, for the error.
    lines : list of int
        Each cell's line in the file, for the error and the note.
    column : str
        The column's name, for the error.
    notes : list of str
        Appended to.

    Returns
    -------
    ndarray (n,) int64
        ns since 1970-01-01 00:00 UTC (of the clock's own zone where none is stated).

    Raises
    ------
    InputError
        A cell that is no date-time, a day or time that does not exist, or a date-time
        without a zone among ones with a zone (or the reverse), naming its row.
    """
    out = np.empty(len(cells), dtype=np.int64)
    first_zone: int | None = None
    changed: tuple[int, int, int] | None = None
    for i, cell in enumerate(cells):
        m = DATETIME_RE.fullmatch(cell.strip())
        try:
            if m is None:
                raise ValueError
            ns, zone = datetime_ns(m)
        except ValueError:
            raise InputError(source, f"expected a date-time as in the column's first row ({cells[0].strip()!r}), "
                             f"got {cell.strip()!r}", row=lines[i], column=column) from None
        if i == 0:
            first_zone = zone
        elif (zone is None) != (first_zone is None):
            said = ("states no zone", "does") if zone is None else ("states a zone", "does not")
            raise InputError(source, f"date-time {cell.strip()!r} {said[0]} where the first row's "
                             f"({cells[0].strip()!r}) {said[1]}: "
                             "the two cannot be put on one clock", row=lines[i], column=column)
        elif zone != first_zone and changed is None:
            changed = (i, first_zone, zone)
        out[i] = ns - (zone or 0)
    said = f"{column!r} holds ISO-8601 date-times: t is seconds since 1970-01-01 "
    if first_zone is None:
        notes.append(said + "on their clock (they state no zone; taken for UTC)")
    elif changed is None:
        notes.append(said + f"UTC (their zone, UTC{first_zone / 3.6e12:+g} h, taken off)")
    else:
        i, was, now = changed
        notes.append(said + f"UTC; their zone changes at row {lines[i]} (UTC{was / 3.6e12:+g} h to "
                     f"UTC{now / 3.6e12:+g} h, a clock put forward or back), each taken off")
    return out


def unit_in_name(name: str | None) -> str | None:
    """The time unit a column's name states (``Time (ms)``, ``timestamp_us``, ``t[ns]``,
    ``Time (s)``), or None."""
    if not name:
        return None
    words = [w for w in re.findall(r"[a-z\u00b5]+", name.lower())
             if w not in ("t", "time", "times", "timestamp", "timestamps", "stamp", "elapsed", "sample", "in")]
    for unit, spelled in TIME_WORDS.items():
        if any(w in spelled for w in words):
            return unit
    return None


def exact_stamps(cells: list[str]) -> np.ndarray | None:
    """A time column's cells as int64 when every one is a whole number (digits with an optional
    sign; no point, no exponent) below 2**62 in magnitude, else None.

    float64 keeps whole numbers exactly only below FLOAT_EXACT (2**53, 104 days in ns): an
    epoch in nanoseconds (1.7e18) would keep each stamp to 256 ns, 2.6e-4 of a 1 kHz step.
    Read as integers, the steps are exact (:func:`time_in_seconds` subtracts the first stamp
    before dividing).
    """
    joined = "\n".join(cells)
    if not cells or joined.count("\n") != len(cells) - 1 or not INTEGER_CELLS_RE.fullmatch(joined):
        return None
    values = [int(c) for c in cells]
    if max(abs(min(values)), abs(max(values))) >= 2 ** 62:      # steps must fit int64 too
        return None
    return np.array(values, dtype=np.int64)


#: a --time-unit: one of TIME_FACTORS's units, or a tick: a number of one (``25us``, ``0.5 ms``, ``1e-4s``)
TIME_UNIT_RE = re.compile(r"\s*((?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:e[+-]?[0-9]+)?)?\s*(s|ms|us|\u00b5s|ns)\s*", re.I)


def time_factor(unit: str) -> float | None:
    """The factor that makes stamps in ``unit`` seconds' (stamps / factor = s): s, ms, us, ns
    (TIME_FACTORS), or a tick of a number of one (``25us``: a chip's clock in 25 us ticks, factor
    4e4); None for anything else (a tick of zero)."""
    m = TIME_UNIT_RE.fullmatch(unit)
    if m is None:
        return None
    k = TIME_FACTORS[m.group(2).lower().replace("\u00b5", "u")]
    tick = float(m.group(1)) if m.group(1) else 1.0
    return k / tick if tick > 0 else None


def time_in_seconds(t: np.ndarray, unit: str, column: str | None, source: str,
                    notes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """``t`` in seconds: divided by the factor of ``unit`` (s, ms, us, ns), or with ``auto`` of
    the unit the column's name states, else, for time stamps whose steps read as seconds
    would give under MIN_PLAUSIBLE_HZ, of the smallest unit that gives more (a logger's
    millis(), micros() or an epoch in nanoseconds), with a note.

    Parameters
    ----------
    t : ndarray (n,)
        The time stamps as written, in their unit: float64, or int64 when written as whole
        numbers (:func:`exact_stamps`; the differences are then taken exactly).
    unit : str
        "auto", "s", "ms", "us", "ns", or a tick: a number of one of those (``25us``: a chip's
        clock in 25 us ticks; :func:`time_factor`).
    column : str or None
        The time column's name (its unit, ``Time (ms)``).
    source : str
        The file, for the error.
    notes : list of str
        Appended to: the unit guessed or read from the name.

    Returns
    -------
    t, rel : ndarray (n,) float64
        The time stamps in s, and every stamp less the first in s (an epoch in seconds keeps
        ~0.2 us, too coarse for the steps of a fast logger, so the rate is taken from these).
    """
    exact = t.dtype.kind in "iu"
    t0 = int(t[0]) if exact and t.size else float(t[0]) if t.size else 0.0
    steps_from_t0 = (t - t[0]).astype(np.float64) if exact and t.size else np.asarray(t, float) - t0

    def divided(k: float) -> tuple[np.ndarray, np.ndarray]:
        # each stamp divided by k, correctly rounded (25 ms: 0.025, where t0 / k + rel gave
        # 0.024999999999999998), but for whole numbers past FLOAT_EXACT (an epoch in ns)
        rel = steps_from_t0 / k
        if not exact or not t.size or max(abs(int(t.min())), abs(int(t.max()))) < FLOAT_EXACT:
            return np.asarray(t, float) / k if k != 1.0 else np.asarray(t, float), rel
        return float(t0) / k + rel, rel

    if unit != "auto":
        k = time_factor(unit)
        if k is None:
            raise InputError(source, f"--time-unit {unit!r}: expected auto, one of {', '.join(TIME_FACTORS)}, or a "
                             "tick: a number of one (25us)")
        return divided(k)
    named = unit_in_name(column)
    if named == "s":
        return divided(1.0)
    if named is not None:
        k = TIME_FACTORS[named]
        if k != 1.0:
            notes.append(f"t read in {named}, as its column's name {column!r} says; the recording's t is in seconds")
        return divided(k)
    if t.size < 3:
        return divided(1.0)
    steps = np.diff(t).astype(np.float64)       # exact for int64 stamps
    step = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 0.0
    if step <= 0 or 1.0 / step >= MIN_PLAUSIBLE_HZ:
        return divided(1.0)
    for unit_name, k in list(TIME_FACTORS.items())[1:]:
        if k / step >= MIN_PLAUSIBLE_HZ:
            notes.append(f"t read in {unit_name}: its steps (median {step:.6g}) would give "
                         f"{1.0 / step:.4g} Hz in seconds, {k / step:.6g} Hz in {unit_name} (state --time-unit s, "
                         "ms, us or ns when that is not its unit)")
            return divided(k)
    return divided(1.0)


def burst_fit(t: np.ndarray) -> tuple[float, str] | None:
    """The sensor's rate and the burst's sample each stamp is tied to (:func:`burst_rate`)
    where the time stamps ``t`` (s) were taken by a host that reads the sensor in bursts, else
    None.  Bursts: t's median step and its mean step (duration over samples) disagree by more
    than BURST_SHARE, and the bursts' first stamps keep time with their samples' numbers -- a
    straight line through them misses them by at most BURST_FIT_STEPS of its sample period,
    rms.  A recording paused and resumed (a phone app's pause: steady 9.58 ms steps, one of
    163 s) has the same disagreement, but its runs' starts do not keep time with their
    samples; it had been taken for 5 bursts, and its t rewritten at 46 Hz instead of 104 Hz.
    A median step below BURST_TINY_STEP x the mean is bursts whatever the fit (a host's stamps
    microseconds apart, its jitter between bursts beyond the fit's bound)."""
    if t.size < 3 or even_steps(t, BURST_SHARE):
        return None
    median, mean = float(np.median(np.diff(t))), float(t[-1] - t[0]) / (t.size - 1)
    rate, which, misfit = burst_rate(t)
    if median < BURST_TINY_STEP * mean or (misfit is not None and misfit <= BURST_FIT_STEPS / rate):
        return rate, which
    return None


def burst_starts(t: np.ndarray) -> np.ndarray:
    """The first sample of each burst of bursty time stamps (``t`` in s, n >= 2): sample 0 and
    every sample after a step longer than half the mean step (within a burst the host's stamps
    are microseconds apart, between bursts several sample periods)."""
    mean = float(t[-1] - t[0]) / (t.size - 1)
    return np.concatenate([[0], np.flatnonzero(np.diff(t) > 0.5 * mean) + 1])


def burst_rate(t: np.ndarray) -> tuple[float, str, float | None]:
    """The sensor's rate, Hz, from time stamps a host took in bursts (``t`` in s, increasing).

    A burst's stamp is tied to one of its samples: the first (a host that stamps when a burst
    begins) or the last (one that stamps when it reads what the sensor has buffered).  Each
    is fitted by least squares -- every burst's first stamp against that sample's number,
    leaving out the burst the file may have cut (the first one's start, the last one's end)
    -- and the fit whose residual is smaller gives the rate: samples between stamps over
    their time.  (n - 1) / duration counted the last burst's other samples over no time:
    biased by (burst - 1) / n, +2.08 % for 50 rows of 100 Hz in bursts of 2.

    Returns
    -------
    rate : float
        Hz.  With two bursts, the samples between their first stamps over that time; with
        one, (n - 1) / duration.
    which : str
        The burst's sample its stamp was found tied to: "first", "last" ("" without a fit).
    misfit : float or None
        The rms distance of the bursts' stamps from the fitted line, s (None without a fit:
        fewer than three bursts, or a line that does not rise).
    """
    starts = burst_starts(t)
    if starts.size < 3:
        span = (starts[-1], float(t[starts[-1]] - t[0])) if starts.size == 2 else (t.size - 1, float(t[-1] - t[0]))
        return span[0] / span[1], "", None
    ends = np.append(starts[1:] - 1, t.size - 1)
    fits = []
    for which, anchor, keep in (("first", starts, slice(1, None)), ("last", ends, slice(None, -1))):
        x, y = anchor[keep].astype(float), t[starts[keep]] - t[0]
        slope, icpt = np.polyfit(x, y, 1)
        fits.append((float(np.sqrt(np.mean((y - (icpt + slope * x)) ** 2))), which, float(slope)))
    misfit, which, slope = min(fits, key=lambda f: f[0])      # a tie (bursts of one size): the first's
    return (1.0 / slope, which, misfit) if slope > 0 else ((t.size - 1) / float(t[-1] - t[0]), "", None)


def rate_from_t(t: np.ndarray, notes: list[str], fit: tuple[float, str] | None) -> float:
    """The sample rate t's steps give, Hz (``t`` in s): the steps up to GAP_STEPS x the median
    step, counted over their time (a clock that steps 10.079 ms with a 7.56 ms correction
    every few samples runs at 100.00 Hz, where its median step gave 99.21; a pause or a
    dropout is no sample period), unless the stamps come in bursts (``fit``, t's
    :func:`burst_fit`), when the bursts' rate is given, with a note."""
    if t.size < 2:
        notes.append("a single sample: t gives no rate, and the device's 1 Hz is a placeholder (--rate HZ states it)")
        return 1.0
    step, gaps, median = regular_step(t)
    mean = float(t[-1] - t[0]) / (t.size - 1)
    if fit is None or mean <= 0:
        if median <= 0:
            return 1.0
        if gaps:
            notes.append(f"t has {gaps} step{'s' if gaps > 1 else ''} longer than {GAP_STEPS:g} x its median step "
                         f"({median:.6g} s; the longest {float(np.diff(t).max()):.6g} s): a pause or samples lost; the "
                         "rate is that of the other steps")
        return 1.0 / step
    rate, which = fit
    bursts = burst_starts(t).size
    notes.append(f"t's median step gives {1.0 / median if median > 0 else float('inf'):.6g} Hz but its {t.size} samples "
                 f"come in {bursts} bursts over {float(t[-1] - t[0]):.6g} s: the time stamps are a host's clock, not the "
                 f"sensor's; the device's rate is that of the samples between the bursts' stamps, {rate:.6g} Hz"
                 + (f" (each burst stamped at its {which} sample)" if which else "") + " (--rate HZ states it)")
    return rate
