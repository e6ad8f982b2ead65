"""What every format of ``accelcal convert`` shares: the result (:class:`Converted`), the
options the command line states, reading a table's named columns, and :func:`finish` --
range check, sample order, time, poses, metadata and the nominal device
(:mod:`accelcal.convert.nominal_device`)."""
from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..readings.clipping import clip_note
from .nominal_device import check_range, code_step_note, nominal_triad
from .regions import label_poses
from .rows import placeholder_lead
from .time import FLOAT_EXACT, burst_fit, exact_stamps, rate_from_t, time_in_seconds
from ..io.csvtable import convert_columns, cut_short_end, make_table, split_header
from ..io.device import GRAVITY_REMOVED_G, GRAVITY_REMOVED_TEXT, Device
from ..errors import InputError, notes_on_refusal
from ..readings.held import held_runs, held_share, held_text, inner_runs, uneven
from ..io.recording import Recording, write_recording
from ..io.recording_checks import GAP_STEPS, RATE_TOL
from ..readings.noise import window_std
from ..readings.static import STATIC_WINDOW_S, window_len
from ..io.textinput import NUMBER_RE, is_whitespace_header, split_whitespace_header, whitespace_to_commas
from ..io.units import STANDARD_GRAVITY, Scale

__all__ = ["Converted", "Options", "INDEX_COLUMNS", "GYRO_RE", "NUMBER_RE", "header_cells", "read_columns",
           "find_column", "exact_time", "in_sample_order", "finish", "recording_metadata",
           "stated_rate_off", "drop_note", "whole_counts", "is_gyro", "stillest_force",
           "gravity_removed_note", "held_note", "held_note_text"]

INDEX_COLUMNS = ("n_samples", "samples")
#: a gyroscope's column: gx, gyro_x, wx, w_x, EuRoC's frame-subscripted w_RS_S_x (a unit in () or [] after any)
GYRO_RE = re.compile(r"(?:(?:gyr|gyro|g)[_ ]?[xyz]|w_?[xyz]|w_(?:[a-z0-9]+_)*[xyz])(?:\s*[(\[][^)\]]*[)\]])?", re.I)
#: a unit of angular rate in a column's name: rad/s, rad s^-1, deg/s, dps, degrees per second
ANGULAR_RATE_RE = re.compile(r"[(\[]\s*(?:rad|deg|\u00b0)\s*(?:/\s*s|s\s*\^?\s*-1)\s*[)\]]|[(\[]\s*dps\s*[)\]]", re.I)


@dataclass
class Converted:
    """A converted file: the contract recording, a nominal device for it, and what was done.

    Attributes
    ----------
    recording : Recording
        Counts in raw_0..raw_2, t in s, pose labels (and f in m/s^2 when stated).
    device : Device or None
        A nominal triad for the recording: counts per m/s^2 from the LSB when known, else
        from the data's spread; zero 0 (signed) or 2**(bits-1) (unsigned); the ADC's range.
    format, pose_names, notes, scale, sorted_rows
        The format read; the region name of pose label 0, 1, ...; lines for stderr;
        what one count of the file's readings was; whether the rows were put in sample order.
    device_notes : list of str
        How the nominal device was made (its rate, its scale): lines for stderr when it is written.
    writer : callable or None
        ``writer(path)`` writes the recording where it is not held whole (:mod:`accelcal.convert.stream`:
        read again in chunks); None: :func:`accelcal.io.recording.write_recording` of ``recording``.
    """

    recording: Recording
    device: Device | None
    format: str
    pose_names: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    scale: Scale | None = None
    sorted_rows: bool = False
    device_notes: list[str] = field(default_factory=list)
    writer: Callable[[Any], None] | None = None

    def write(self, path: Any) -> None:
        """Write the recording to ``path`` (CSV, or Parquet by the name), atomically."""
        if self.writer is not None:
            self.writer(path)
        else:
            write_recording(path, self.recording)

    def summary(self, output: Any) -> str:
        """One line: rows, channels, rate, poses, where it went."""
        rec = self.recording
        if self.device is not None:
            rate = self.device.sample_rate_hz
        else:
            rate = 1.0 / float(np.median(np.diff(rec.t))) if rec.n_samples > 1 else float("nan")
        what = f"{self.format}: {rec.n_samples} rows, {rec.n_channels} channels"
        if self.scale is not None and self.scale.converts:
            what += f" ({self.scale.describe()})"
        what += f", {rate:.6g} Hz"
        if self.pose_names:
            what += f", {len(self.pose_names)} poses ({', '.join(self.pose_names)})"
            what += ", reference f stated" if rec.has_f() else ""
        else:
            what += ", no pose labels"
        if self.sorted_rows:
            what += ", rows put in sample order"
        return f"{what}; written to {output}"


@dataclass
class Options:
    """What the command line states (see :func:`convert_file`)."""

    scale: Scale | None = None
    rate_hz: float | None = None
    regions: list[tuple[str, int, int]] | None = None
    regions_source: str | None = None
    stated_f: bool = False
    gravity_mps2: float | None = None
    bits: int = 16
    time_unit: str = "auto"
    time_column: str | None = None
    repeated_stamps: str = "refuse"
    columns: str | None = None


def header_cells(header: str) -> list[str]:
    if is_whitespace_header(header):
        return split_whitespace_header(header)
    try:
        return split_header(header)
    except csv.Error:
        return [header]


def read_columns(source: str, data: bytes, pre, want: dict[str, str]) -> tuple[list[str], dict, Any]:
    """The header's columns and the cells of the wanted ones (kinds: raw, t, text) with the
    reader's strict errors; returns (names, {name: values}, table)."""
    header = pre.header
    spaced = is_whitespace_header(header)
    names = [c.strip() for c in header_cells(header)]
    pos = pre.pos
    end = pos + len(data[pos:].rstrip(b"\n \t"))  # trailing blank lines are not rows
    if end <= pos:
        raise InputError(source, "no data rows after the header", row=pre.header_line)
    first = pre.header_line + 1
    end, cut_note = cut_short_end(data, pos, end, len(names), first)
    if spaced:
        data = whitespace_to_commas(data, pos, end, names, first, source)
        end = len(data)
    table = make_table(data, pos, end, len(names), first, source)
    table.cut_note = cut_note             # a last line cut short, left out (csvtable.cut_short_end)
    values = {name: table.strings(names.index(name)) for name, kind in want.items() if kind == "text"}
    numbers, err = convert_columns(table, {name: (names.index(name), kind) for name, kind in want.items()
                                           if kind != "text"})
    values.update(numbers)
    if err is not None:
        i, j, msg = err
        if want[names[j]] == "raw" and names[j] not in INDEX_COLUMNS and NUMBER_RE.fullmatch(table.cell(i, j).strip()):
            msg += " (readings in m/s^2, mm/s^2, g or mg: state --units mps2|mmps2|g|mg with --lsb VALUE or --full-scale G)"
        raise InputError(source, msg, row=table.line(i), column=names[j])
    return names, values, table


def find_column(names: list[str], wanted: str) -> str | None:
    return next((n for n in names if n.strip().lower() == wanted), None)


def exact_time(stamps: np.ndarray, cells, rows: np.ndarray | None = None) -> np.ndarray:
    """A time column read exactly where float64 rounds it: ``stamps`` (as read, float64, in
    the column's unit) beyond FLOAT_EXACT in magnitude (an epoch in ns) whose cells are all
    whole numbers (:func:`convert_time.exact_stamps`) are returned as int64; else ``stamps``.

    Parameters
    ----------
    stamps : ndarray (n,) float64
        The time column as read (NaN where empty).
    cells : callable
        Returns the column's n cells as text (called only when needed: a table's ``strings``).
    rows : ndarray of int, optional
        The rows that count (a table's rows with readings); the others are 0 in the int64
        result.  Default: all.
    """
    rows = np.arange(stamps.size) if rows is None else rows
    t = stamps[rows]
    if not np.any(np.abs(t[np.isfinite(t)]) >= FLOAT_EXACT):
        return stamps
    text = cells()
    exact = exact_stamps([text[i] for i in rows.tolist()])
    if exact is None:
        return stamps
    out = np.zeros(stamps.size, dtype=np.int64)
    out[rows] = exact
    return out


def in_sample_order(index: np.ndarray, source: str, column: str | None, line) -> np.ndarray | None:
    """The permutation putting the rows in order of their sample numbers (None when they are)."""
    if np.all(np.diff(index) > 0):
        return None
    order = np.argsort(index, kind="stable")
    dup = np.flatnonzero(np.diff(index[order]) == 0)
    if dup.size:
        a, b = sorted(int(v) for v in order[dup[0]:dup[0] + 2])
        raise InputError(source, f"sample number {int(index[b])} is also that of row {line(a)}", row=line(b),
                         column=column)
    return order


def finish(source: str, fmt: str, raw: np.ndarray, index: np.ndarray, t: np.ndarray | None, part: list[str] | None,
           opts: Options, scale: Scale | None, signed: bool, rate: float | None, metadata: dict[str, str],
           notes: list[str], locate, index_column: str | None, device: Device | None = None,
           kept: tuple[np.ndarray, np.ndarray | None] | None = None, time_column: str | None = None,
           t0: float = 0.0, label_hint: str | None = None) -> Converted:
    """Range check, a leading placeholder left out (:func:`convert_rows.placeholder_lead`), sample
    order, time, poses, metadata and the nominal device, shared by the formats (without time
    stamps ``t``, t is ``t0`` (s) + the sample index over ``rate``: a row left out before keeps
    its place).  ``kept``: the recording's own pose labels and f (f None: none); ``label_hint``: a
    column that may name the poses (:func:`convert_regions.label_poses`).  A refusal carries
    ``notes``, those made before it (:func:`errors.notes_on_refusal`)."""
    with notes_on_refusal(lambda: notes):    # a refusal after notes were made: they go with it
        check_range(raw, opts.bits, signed, source, locate)
        gravity = opts.gravity_mps2 or (device.gravity_mps2 if device is not None else STANDARD_GRAVITY)
        lead = placeholder_lead(raw, scale, gravity, lambda i: locate(i, 0)[0], notes)
        if lead:
            raw, index = raw[lead:], index[lead:]
            t = None if t is None else t[lead:]
            part = None if part is None else part[lead:]
            kept = None if kept is None else (kept[0][lead:], None if kept[1] is None else kept[1][lead:])
            shown = locate

            def locate(i: int, j: int) -> tuple[int, str]:
                return shown(i + lead, j)
        extra_columns: dict[str, list[str]] = {}
        order = in_sample_order(index, source, index_column, lambda i: locate(i, 0)[0]) if t is None else None
        if order is not None:
            raw, index = raw[order], index[order]
            part = None if part is None else [part[i] for i in order.tolist()]
            kept = None if kept is None else (kept[0][order], None if kept[1] is None else kept[1][order])
        if t is None:
            t = t0 + index / rate
        else:
            t = np.asarray(t)           # int64 from exact_time: an epoch in ns
            t, rel = time_in_seconds(t if t.dtype.kind in "iu" else t.astype(float), opts.time_unit, time_column,
                                     source, notes)
            fit = burst_fit(rel)
            burst = fit is not None
            rate = opts.rate_hz if opts.rate_hz is not None else rate_from_t(rel, notes, fit)
            off = None if burst else stated_rate_off(rel, opts.rate_hz)
            if burst or off is not None:
                # the samples are the sensor's, evenly spaced; the host's stamps are kept beside them
                extra_columns["t_host"] = [repr(float(v)) for v in t]
                t = t[0] + np.arange(t.size) / rate
                notes.append(f"t is written on the {rate:.6g} Hz grid from the first stamp (the integrators need the "
                             "sensor's even spacing); the host's stamps are kept as column t_host" if burst else
                             f"the time column's steps give {off:.6g} Hz (median step), more than "
                             f"{100 * RATE_TOL:.0f} % from --rate {rate:g} Hz: its clock is not the sensor's; t is "
                             f"written on the {rate:g} Hz grid from the first stamp and the time column's stamps are "
                             "kept as column t_host")
                notes += [] if burst else grid_gaps_note(rel)
        if kept is not None:  # a contract recording without --regions keeps its labels and references
            (pose, f), names = kept, [str(k) for k in np.unique(kept[0][kept[0] >= 0])]
        else:
            pose, f, names = label_poses(index, part, opts.regions, opts.stated_f, gravity, source, opts.regions_source,
                                         label_hint)
        metadata = recording_metadata(source, fmt, metadata, scale, opts, names, kept is not None)
        rec = Recording(t=t, raw=raw, f=f, pose=pose, metadata=metadata, extra=extra_columns, source=source)
        device_notes: list[str] = []
        noise = None
        k, first = held_runs(raw)
        distinct_hz = None
        if k > 1 and rate:
            inner = inner_runs(first, raw.shape[0])
            distinct_hz = rate / (float(np.mean(inner)) if uneven(k, inner) else k)   # rows per reading
        if k > 1:
            notes.append(held_note(k, first, raw.shape[0], distinct_hz))
        notes += code_step_note(raw, opts.bits)
        if device is None:
            # rows that hold each reading for k rows: the device states the sensor's rate, that of the distinct
            # readings (calibrate, diagnose take it as such: held.distinct_recordings), unless --rate states one
            own = distinct_hz if distinct_hz is not None and opts.rate_hz is None else None
            device, noise = nominal_triad(f"{fmt}-triad", own or rate, gravity, raw, opts.bits, signed, scale,
                                          device_notes, rec)
            if own is not None:
                device_notes.append(f"the device's rate is {device.sample_rate_hz:.6g} Hz, the distinct readings'; "
                                    f"the recording keeps every row (at {rate:.6g} Hz)")
        notes += gravity_removed_note(raw, scale, rate, lambda i: locate(i, 0)[0], pose)
        clipped = clip_note(raw, device, window_len(device, STATIC_WINDOW_S, raw.shape[0]), lambda j: locate(0, j)[1],
                            noise)
        notes += [clipped] if clipped else []
        return Converted(rec, device, fmt, names, notes, scale, order is not None, device_notes)


def recording_metadata(source: str, fmt: str, metadata: dict[str, str], scale: Scale | None, opts: Options,
                       names: list[str], kept: bool) -> dict[str, str]:
    """The converted recording's metadata comments: the file, its format, the file's own comments,
    the scale, the regions file and (poses labelled from regions, not ``kept`` from the file) the
    pose names."""
    metadata = {"source_file": " ".join(source.splitlines()), "source_format": fmt, **metadata}
    if scale is not None and (scale.converts or scale.lsb_g):
        metadata["source_scale"] = scale.describe()
    if opts.regions_source:
        metadata["source_regions"] = " ".join(opts.regions_source.splitlines())
    if names and not kept:
        metadata["pose_names"] = " ".join(f"{k}={nm}" for k, nm in enumerate(names))
    return metadata


def grid_gaps_note(rel: np.ndarray) -> list[str]:
    """A note for the stamps' long steps (``rel``: s from the first; longer than GAP_STEPS x the
    median step: a pause or samples lost) that t on --rate's grid does not keep, or none."""
    steps = np.diff(rel)
    long = np.flatnonzero(steps > GAP_STEPS * float(np.median(steps)))
    if not long.size:
        return []
    k = steps[long] / float(np.median(steps))
    return [f"the time column has {long.size} step{'s' if long.size > 1 else ''} longer than {GAP_STEPS:g} x its "
            f"median step (after sample {int(long[0])}{' and others' if long.size > 1 else ''}; the longest "
            f"{float(k.max()):.4g} median steps): a pause or samples lost, which the grid does not keep (each is one "
            "step; t_host keeps them); where the time column is the sensor's clock in another unit, --time-unit "
            "states it (a tick: 25us) and t keeps them"]


def stated_rate_off(rel: np.ndarray, stated: float | None) -> float | None:
    """The rate t's median step gives, Hz, where ``stated`` (``--rate``) is more than RATE_TOL
    from it either way (the test :func:`recording_checks.rate_for` makes, and its converse),
    else None (also without ``stated``, or with fewer than 3 stamps).

    Parameters
    ----------
    rel : ndarray (n,)
        Every time stamp less the first, s.
    stated : float or None
        The rate stated, Hz.
    """
    if stated is None or rel.size < 3:
        return None
    step = float(np.median(np.diff(rel)))
    if step <= 0:
        return None
    rate = 1.0 / step
    return rate if max(abs(stated / rate - 1.0), abs(rate / stated - 1.0)) > RATE_TOL else None


def is_gyro(name: str) -> bool:
    """Whether a column is a gyroscope's: named so (GYRO_RE, or ``gyr`` in it) or in a unit of
    angular rate (``[rad s^-1]``, ``(deg/s)``, ``(dps)``)."""
    return bool(GYRO_RE.fullmatch(name.strip()) or re.search(r"gyr", name, re.I) or ANGULAR_RATE_RE.search(name))


def drop_note(dropped: list[str], ignored: list[str]) -> list[str]:
    parts = []
    if dropped:
        parts.append(f"dropped gyroscope column{'s' if len(dropped) > 1 else ''} {', '.join(dropped)} (accelcal "
                     "calibrates the accelerometer)")
    if ignored:
        parts.append(f"ignored column{'s' if len(ignored) > 1 else ''} {', '.join(ignored)}")
    return ["; ".join(parts)] if parts else []


def whole_counts(values: np.ndarray, source: str, locate) -> np.ndarray:
    """Readings in counts (no unit stated) as int64.

    Raises
    ------
    InputError
        The first reading that is not a whole number, or beyond 2**62, naming its row and
        column.
    """
    with np.errstate(invalid="ignore"):
        big = np.argwhere(~(np.abs(values) < 2.0 ** 62))
    if big.size:
        i, j = (int(v) for v in big[0])
        row, column = locate(i, j)
        raise InputError(source, f"reading {float(values[i, j]):.10g} does not fit a count of 64 bits", row=row,
                         column=column)
    frac = np.argwhere(values != np.round(values))
    if frac.size:
        i, j = (int(v) for v in frac[0])
        row, column = locate(i, j)
        raise InputError(source, f"reading {values[i, j]:.10g} is not a whole count (readings in m/s^2 or g: "
                         "state --units mps2|g with --lsb VALUE or --full-scale G)", row=row, column=column)
    return values.astype(np.int64)


def stillest_force(raw: np.ndarray, rate_hz: float, pose: np.ndarray | None = None) -> tuple[int, int, float] | None:
    """The stillest window of about STATIC_WINDOW_S (:func:`noise.window_std`: the one whose
    largest channel std is least, the first of equals): its first sample, the sample after its
    last and the mean over its rows of |reading| (counts; each row's own magnitude, so that a
    window over samples in different orientations -- a slow logger's, a file of pose means --
    still reads |f|); None where the recording is shorter than a window.  With pose labels
    (``pose``, -1 where none) a window lies within one labelled pose (a pose shorter than a
    window is a window of its own)."""
    raw = np.asarray(raw)
    w = max(3, int(round(STATIC_WINDOW_S * rate_hz))) if np.isfinite(rate_hz) and rate_hz > 0 else 3
    spans = [(0, raw.shape[0])]
    if pose is not None and np.any(pose >= 0):
        cut = np.concatenate([[0], np.flatnonzero(np.diff(pose) != 0) + 1, [pose.size]])
        spans = [(int(a), int(b)) for a, b in zip(cut[:-1], cut[1:]) if pose[a] >= 0]
    best: tuple[float, int, int] | None = None
    for s, e in spans:
        ws, h, k = window_std(raw[s:e], w)
        if ws.shape[0]:
            j = int(np.argmin(ws.max(axis=1)))
            cand = (float(ws[j].max()), s + j * h, s + (j + k) * h)
        elif pose is not None and e > s:
            cand = (float(raw[s:e].std(axis=0).max()), s, e)
        else:
            continue
        if best is None or cand[0] < best[0]:
            best = cand
    if best is None:
        return None
    _, a, b = best
    return a, b, float(np.mean(np.linalg.norm(raw[a:b].astype(float), axis=1)))


#: a unit read as another: |f| at rest, in g, that it gives (gravity_removed_note)
MISREAD_UNITS = (("readings in mm/s^2 read as m/s^2", "mps2", 1000.0),
                 ("readings in m/s^2 read as g", "g", STANDARD_GRAVITY),
                 ("readings in mm/s^2 read as g", "g", 1000.0 * STANDARD_GRAVITY),
                 ("readings in mg read as g", "g", 1000.0),
                 ("readings in g read as mg", "mg", 0.001))


def gravity_removed_note(raw: np.ndarray, scale: Scale | None, rate_hz: float, line,
                         pose: np.ndarray | None = None) -> list[str]:
    """A note where readings converted from m/s^2 or g (``scale``) read |f| below
    GRAVITY_REMOVED_G g at their stillest (:func:`stillest_force`, within a pose where ``pose``
    labels them): gravity has been taken out (a phone's linear or user acceleration), which no
    later command can use; or |f| at rest about a unit's factor off (MISREAD_UNITS: 1000 g for
    mm/s^2 read as m/s^2); ``line(i)`` is sample i's row in the file.  Empty otherwise (readings
    in counts: their zero and scale are the device's to say)."""
    if scale is None or not scale.converts or not scale.lsb_g:
        return []
    still = stillest_force(raw, rate_hz, pose)
    if still is None:
        return []
    a, b, norm = still
    f_g = norm * scale.lsb_g
    misread = [what for what, unit, factor in MISREAD_UNITS if unit == scale.units and abs(f_g / factor - 1) < 0.1]
    if misread:
        return [f"the readings' stillest {(b - a) / rate_hz:.2g} s (rows {line(a)}-{line(b - 1)}) read |f| = "
                f"{f_g:.4g} g, where anything at rest reads 1 g: {misread[0]}? (Klipper's ACCELEROMETER_MEASURE "
                "writes mm/s^2: --units mmps2; readings in mg: --units mg); state the readings' own unit with --units and --lsb"]
    if f_g >= GRAVITY_REMOVED_G:
        return []
    return [f"the readings' stillest {(b - a) / rate_hz:.2g} s (rows {line(a)}-{line(b - 1)}) read |f| = {f_g:.3g} g, "
            f"where anything at rest reads 1 g: {GRAVITY_REMOVED_TEXT}"]


def held_note(k: int, first: np.ndarray, n: int, distinct_hz: float | None) -> str:
    """The note on readings held for ``k`` rows (:func:`held.held_runs`'s k and ``first`` over
    ``n`` rows; ``distinct_hz``: the distinct readings' rate, Hz, when known)."""
    return held_note_text(held_share(first, n), held_text(k, first, n), first.size, distinct_hz)


def held_note_text(share: float, held_for: str, distinct: int, distinct_hz: float | None) -> str:
    """:func:`held_note` from the share of rows repeated, how long (``held.held_text``), the distinct
    readings' count and their rate (a reader in chunks gives these from the runs' counts)."""
    at = f" at about {distinct_hz:.4g} Hz" if distinct_hz is not None else ""
    return (f"{100 * share:.0f} % of the rows repeat the row before in all three readings (each reading held for "
            f"{held_for}): the logger read the sensor faster than it updates; the {distinct} distinct "
            f"readings come{at}, and successive rows are not independent samples (calibrate and diagnose count each "
            "reading once)")
