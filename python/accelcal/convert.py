"""``accelcal convert``: the data contract's recording (and a nominal device) from the
files other tools write.

Formats (``detect_format`` tells them from the first line that is not a comment):

- ``imu_tk``: imu_tk's text, no header, whitespace-separated ``t ax ay az`` (s, counts),
  read by :func:`accelcal.xsens.load_xsens`.
- ``imucal``: imucal's CSV, columns ``acc_x, acc_y, acc_z`` (m/s^2 or g with a stated
  LSB, or counts), no time column (``--rate``; an index column ``n_samples`` or
  ``samples`` gives each row's sample number), poses from a JSON of ``{name: {start,
  end}}`` sample ranges (end excluded) or from a ``part`` column.
- ``mpu6050``: the MPU-6050 logger's CSV: ``key,value`` lines (``Fs,100`` the rate), then
  ``ax,ay,az,gx,gy,gz`` in signed counts, no time column.
- ``csv``: a recording per the contract (or any form ``read_recording`` takes: compressed,
  whitespace, physical units), rewritten as plain CSV in counts.
- ``log``: a serial monitor's capture: lines of three numbers among the logger's text
  (prompts, banners), no header, no time column (``--rate``); with ``blocks`` each run of
  readings between text lines is a pose (:mod:`accelcal.convert_log`).
- ``table``: a CSV or whitespace table with named columns (phyphox, x-io's NGIMU, a
  LORD/MicroStrain log, a logger's ``time_ms,accX,accY,accZ``): one column per axis named
  acc/accel/accelerometer/acceleration (optionally scaled/raw) and x, y or z, with an
  optional unit (``Accelerometer X (g)``, ``AccX [g]``, ``acc_x_mps2``) that states the
  readings' unit; an optional time column (``t``, ``Time (s)``, ``timestamp_us``), else
  ``--rate``.  Rows whose three readings are all empty (another packet's) are skipped.
  Told last, after the formats above.

Gyroscope columns are dropped (one note).  Pose regions named ``x_p, x_a, y_p, y_a, z_p,
z_a`` (imucal's: that axis pointing up, or down) can state the reference specific force
(``stated_f``): +-g along that axis, making a known-pose (``full``) calibration possible.
Regions whose name ends in ``_rot`` are motions, not poses.
"""
from __future__ import annotations

import csv
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .convert_log import is_log, read_log
from .convert_regions import POSE_DIRECTIONS, label_poses, read_regions
from .csvtable import convert_columns, cut_short_end, got_text, make_table, split_header
from .device import Device
from .errors import InputError
from .held import held_runs
from .recording import Recording, read_recording
from .textinput import is_whitespace_header, read_preamble, read_text_bytes, split_whitespace_header, whitespace_to_commas
from .units import STANDARD_GRAVITY, UNIT_TEXT, Scale, file_scale, to_counts
from .xsens import load_xsens

__all__ = ["FORMATS", "POSE_DIRECTIONS", "Converted", "detect_format", "convert_file", "read_regions"]

FORMATS = ("auto", "imu_tk", "imucal", "mpu6050", "csv", "log", "table")
ACC = {"imucal": ("acc_x", "acc_y", "acc_z"), "mpu6050": ("ax", "ay", "az")}
INDEX_COLUMNS = ("n_samples", "samples")
GYRO_RE = re.compile(r"(gyr|gyro|g)[_ ]?[xyz]|w_?[xyz]", re.I)
NUMBER_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
#: a table's accelerometer axis column: a prefix, the word, the axis, a unit in () or [] or after _
AXIS_RE = re.compile(r"(?P<pre>.*?)(?:accelerometer|acceleration|accel|acc|(?<![a-z])a)[\s_.-]*(?P<axis>[xyz])"
                     r"(?:\s*[(\[](?P<unit>[^)\]]*)[)\]]|_(?P<tail>g|mps2|ms2|counts|lsb|raw))?", re.I)
#: the prefixes of an accelerometer's own axis columns (LORD's scaledAccelX)
AXIS_PREFIXES = ("", "scaled", "raw")
#: prefixes of a phone's virtual sensors: not an accelerometer's specific force
VIRTUAL_WORDS = ("linear", "gravity")
#: a unit in an axis column's name (lower case, blanks dropped) -> units.UNITS
NAMED_UNITS = {"g": "g", "m/s^2": "mps2", "m/s\u00b2": "mps2", "m/s/s": "mps2", "mps2": "mps2", "m/s2": "mps2",
               "ms2": "mps2", "counts": "counts", "count": "counts", "lsb": "counts", "raw": "counts"}
#: a table's time column: t, time, timestamp, with a unit in () or [] or after _ (``time_ms``)
TIME_COLUMN_RE = re.compile(r"(?:t|time|timestamp|time[ _]stamp)(?:\s*[(\[][^)\]]*[)\]]|_[a-z\u00b5]+)?", re.I)


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
    """

    recording: Recording
    device: Device | None
    format: str
    pose_names: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    scale: Scale | None = None
    sorted_rows: bool = False
    device_notes: list[str] = field(default_factory=list)  # how the nominal device was made

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


# ---- detection ---------------------------------------------------------------------

def header_cells(header: str) -> list[str]:
    if is_whitespace_header(header):
        return split_whitespace_header(header)
    try:
        return split_header(header)
    except csv.Error:
        return [header]


def detect_format(path: Any, data: bytes | None = None) -> str:
    """The format of a file (its text ``data`` when already read), from its first line that
    is not a comment.

    Raises
    ------
    InputError
        Unreadable, empty, or none of the formats (naming the line).
    """
    source, data = read_text_bytes(path) if data is None else (str(path), data)
    pre = read_preamble(data)
    if pre.header is None:
        raise InputError(source, "the file is empty (nothing but comments and blank lines)")
    cells = header_cells(pre.header)
    low = {c.strip().lower() for c in cells}
    if "t" in cells and "raw_0" in cells:
        return "csv"
    if any(TIME_COLUMN_RE.fullmatch(c.strip()) for c in cells) and any(axis_column(c) for c in cells):
        # a time column beside the axes: neither imucal's nor the MPU-6050 logger's (they have none)
        return "table"
    if set(ACC["imucal"]) <= low:
        return "imucal"
    if set(ACC["mpu6050"]) <= low or cells[0].strip().lower() == "fs":
        return "mpu6050"
    if is_whitespace_header(pre.header) and all(NUMBER_RE.fullmatch(c) for c in cells):
        return "imu_tk"
    if is_log(data):
        return "log"
    if any(axis_column(c) for c in cells):
        return "table"
    raise InputError(source, f"cannot tell the format from this line ({pre.header[:60]!r}): expected a "
                     "recording CSV (t, raw_0, ...), imucal's acc_x/acc_y/acc_z, the MPU-6050 log (Fs,... "
                     "then ax,ay,az,...), imu_tk's 't ax ay az' text, a monitor's log (lines of three "
                     "numbers among text) or a table with accelerometer columns (accX, 'Acceleration y "
                     "(m/s^2)', ...); give --format", row=pre.header_line)


# ---- tables --------------------------------------------------------------------------

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
            msg += " (readings in m/s^2 or g: state --units mps2|g with --lsb VALUE or --full-scale G)"
        raise InputError(source, msg, row=table.line(i), column=names[j])
    return names, values, table


def find_column(names: list[str], wanted: str) -> str | None:
    return next((n for n in names if n.strip().lower() == wanted), None)


# ---- the formats -----------------------------------------------------------------------

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


def adc_range(bits: int, signed: bool) -> tuple[int, int]:
    return (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if signed else (0, 2 ** bits - 1)


def nominal_triad(name: str, rate: float, gravity: float, raw: np.ndarray, bits: int, signed: bool,
                  scale: Scale | None, notes: list[str]) -> Device:
    """A triad at the origin along x, y, z: counts per m/s^2 from the LSB when stated, else half
    the spread of each axis between its 1st and 99th percentiles, over g (as load_xsens)."""
    k = scale.counts_per_mps2(gravity) if scale is not None else None
    if k is None:
        lo, hi = np.percentile(raw, [1.0, 99.0], axis=0)
        k = round(float(np.mean((hi - lo) / 2.0)) / gravity, 1)
        if k > 0:
            notes.append(f"the device's nominal scale, {k:g} counts per m/s^2, is taken from the readings' "
                         "spread (state --full-scale G for the chip's)")
        else:
            k = 2.0 ** (bits - 1) / (2.0 * gravity)
            notes.append(f"the readings span no range: the device's nominal scale is a guess ({k:g} counts per "
                         "m/s^2, +-2 g); state --full-scale G")
    lo, hi = adc_range(bits, signed)
    return Device(name=name, sample_rate_hz=round(rate, 6), gravity_mps2=gravity, raw_min=lo, raw_max=hi,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, k),
                  zero_counts=np.full(3, 0.0 if signed else 2.0 ** (bits - 1)), noise_mps2=0.0)


def check_range(raw: np.ndarray, bits: int, signed: bool, source: str, locate) -> None:
    lo, hi = adc_range(bits, signed)
    out = np.argwhere((raw < lo) | (raw > hi))
    if out.size:
        i, j = (int(v) for v in out[0])
        row, column = locate(i, j)
        raise InputError(source, f"reading {int(raw[i, j])} counts is outside {'signed' if signed else 'unsigned'} "
                         f"{bits}-bit [{lo}, {hi}] (state --bits N)", row=row, column=column)


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


def time_in_seconds(t: np.ndarray, unit: str, column: str | None, source: str,
                    notes: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """``t`` in seconds: divided by the factor of ``unit`` (s, ms, us, ns), or with ``auto`` of
    the unit the column's name states, else, for time stamps whose steps read as seconds
    would give under MIN_PLAUSIBLE_HZ, of the smallest unit that gives more (a logger's
    millis(), micros() or an epoch in nanoseconds), with a note.  Returns (t, every time stamp
    less the first), in seconds: an epoch in seconds keeps ~0.2 us, too coarse for the steps
    of a fast logger, so the rate is taken from the differences."""
    t0 = float(t[0]) if t.size else 0.0

    def divided(k: float) -> tuple[np.ndarray, np.ndarray]:
        return (t, t - t0) if k == 1.0 else (t0 / k + (t - t0) / k, (t - t0) / k)

    if unit != "auto":
        if unit not in TIME_FACTORS:
            raise InputError(source, f"--time-unit {unit!r}: expected one of auto, {', '.join(TIME_FACTORS)}")
        k = TIME_FACTORS[unit]
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
    steps = np.diff(t)
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


def rate_from_t(t: np.ndarray, notes: list[str]) -> float:
    """The sample rate t's steps give: from the median step, unless it and the mean step
    (duration over samples) disagree by more than BURST_SHARE -- time stamps taken by a host
    that reads the sensor in bursts -- when the mean is taken, with a note."""
    if t.size < 2:
        return 1.0
    steps = np.diff(t)
    median = float(np.median(steps))
    mean = float(t[-1] - t[0]) / (t.size - 1)
    if median > 0 and mean > 0 and abs(mean / median - 1.0) <= BURST_SHARE:
        return 1.0 / median
    if mean <= 0:
        return 1.0 / median if median > 0 else 1.0
    notes.append(f"t's median step gives {1.0 / median if median > 0 else float('inf'):.6g} Hz but its {t.size} samples "
                 f"over {float(t[-1] - t[0]):.6g} s give {1.0 / mean:.6g} Hz: the time stamps come in bursts (a host's "
                 "clock, not the sensor's); the device's rate is the latter (--rate HZ states it)")
    return 1.0 / mean


def finish(source: str, fmt: str, raw: np.ndarray, index: np.ndarray, t: np.ndarray | None, part: list[str] | None,
           opts: Options, scale: Scale | None, signed: bool, rate: float | None, metadata: dict[str, str],
           notes: list[str], locate, index_column: str | None, device: Device | None = None,
           kept: tuple[np.ndarray, np.ndarray] | None = None, time_column: str | None = None) -> Converted:
    """Range check, sample order, time, poses, metadata and the nominal device, shared by the formats."""
    check_range(raw, opts.bits, signed, source, locate)
    order = in_sample_order(index, source, index_column, lambda i: locate(i, 0)[0]) if t is None else None
    if order is not None:
        raw, index = raw[order], index[order]
        part = None if part is None else [part[i] for i in order.tolist()]
    if t is None:
        t = index / rate
    else:
        t, rel = time_in_seconds(np.asarray(t, dtype=float), opts.time_unit, time_column, source, notes)
        rate = opts.rate_hz if opts.rate_hz is not None else rate_from_t(rel, notes)
    gravity = opts.gravity_mps2 or (device.gravity_mps2 if device is not None else STANDARD_GRAVITY)
    if kept is not None:  # a contract recording without --regions keeps its labels and references
        (pose, f), names = kept, [str(k) for k in np.unique(kept[0][kept[0] >= 0])]
    else:
        pose, f, names = label_poses(index, part, opts.regions, opts.stated_f, gravity, source, opts.regions_source)
    metadata = {"source_file": " ".join(source.splitlines()), "source_format": fmt, **metadata}
    if scale is not None and (scale.converts or scale.lsb_g):
        metadata["source_scale"] = scale.describe()
    if opts.regions_source:
        metadata["source_regions"] = " ".join(opts.regions_source.splitlines())
    if names and kept is None:
        metadata["pose_names"] = " ".join(f"{k}={nm}" for k, nm in enumerate(names))
    rec = Recording(t=t, raw=raw, f=f, pose=pose, metadata=metadata, source=source)
    device_notes: list[str] = []
    if device is None:
        device = nominal_triad(f"{fmt}-triad", rate, gravity, raw, opts.bits, signed, scale, device_notes)
    return Converted(rec, device, fmt, names, notes, scale, order is not None, device_notes)


def drop_note(dropped: list[str], ignored: list[str]) -> list[str]:
    parts = []
    if dropped:
        parts.append(f"dropped gyroscope column{'s' if len(dropped) > 1 else ''} {', '.join(dropped)} (accelcal "
                     "calibrates the accelerometer)")
    if ignored:
        parts.append(f"ignored column{'s' if len(ignored) > 1 else ''} {', '.join(ignored)}")
    return ["; ".join(parts)] if parts else []


def convert_table(source: str, data: bytes, pre, fmt: str, opts: Options, metadata: dict[str, str]) -> Converted:
    """imucal's CSV or the MPU-6050 log's rows (after its key,value lines)."""
    names = [c.strip() for c in header_cells(pre.header)]
    acc = [find_column(names, a) for a in ACC[fmt]]
    if None in acc:
        missing = ACC[fmt][acc.index(None)]
        raise InputError(source, f"the header has no {missing} column (expected {', '.join(ACC[fmt])})",
                         row=pre.header_line)
    scale = file_scale(opts.scale, pre.metadata, pre.metadata_lines, source)
    converts = scale is not None and scale.converts
    want = {a: ("t" if converts else "raw") for a in acc}
    index_column = next((n for n in names if n.lower() in INDEX_COLUMNS), None)
    if index_column:
        want[index_column] = "raw"
    part_column = find_column(names, "part") if opts.regions is None else None
    if part_column:
        want[part_column] = "text"
    names, values, table = read_columns(source, data, pre, want)
    matrix = np.column_stack([values[a] for a in acc])

    def locate(i: int, j: int) -> tuple[int, str]:
        return table.line(i), acc[j]

    shifted: list[str] = []
    raw = to_counts(matrix, scale, source, locate, notes=shifted) if converts else matrix.astype(np.int64)
    n = raw.shape[0]
    index = values[index_column] if index_column else np.arange(n)
    rate = opts.rate_hz
    if rate is None:
        timed = next((n for n in names if TIME_COLUMN_RE.fullmatch(n)), None)
        hint = f" (--format table reads the time column {timed!r})" if timed else ""
        raise InputError(source, f"{fmt} files have no time column: give the sample rate with --rate HZ{hint}")
    used = set(want)
    dropped = [c for c in names if c and c not in used and GYRO_RE.fullmatch(c)]
    ignored = [c for c in names if c and c not in used and c not in dropped]
    return finish(source, fmt, raw, index, None, values.get(part_column), opts, scale, True, rate, metadata,
                  drop_note(dropped, ignored) + shifted + ([table.cut_note] if table.cut_note else []), locate,
                  index_column)


def mpu6050_preamble(source: str, data: bytes, pre) -> tuple[Any, dict[str, str], float | None]:
    """The logger's ``key,value`` lines before the header ``ax,ay,az,...``: (the header's
    preamble, metadata ``mpu6050.<key>``, the rate from ``Fs``)."""
    meta, rate = {}, None
    while pre.header is not None and find_column(header_cells(pre.header), "ax") is None:
        cells = [c.strip() for c in pre.header.split(",")]
        if len(cells) != 2 or not cells[0]:
            raise InputError(source, f"expected a 'key,value' line (such as 'Fs,100') or the header 'ax,ay,az,...', "
                             f"got {pre.header[:60]!r}", row=pre.header_line)
        key = re.sub(r"[^A-Za-z0-9_.-]+", "_", cells[0].lower()).strip("_") or "key"
        meta[f"mpu6050.{key}"] = cells[1]
        if key == "fs":
            try:
                rate = float(cells[1])
            except ValueError:
                rate = float("nan")
            if not (np.isfinite(rate) and rate > 0):
                raise InputError(source, f"Fs {cells[1]!r}: expected a sample rate in Hz > 0", row=pre.header_line)
        rest = read_preamble(data[pre.pos:])
        rest.header_line += pre.header_line
        rest.header_pos += pre.pos
        rest.pos += pre.pos
        rest.metadata, rest.metadata_lines = pre.metadata, pre.metadata_lines
        pre = rest
    if pre.header is None:
        raise InputError(source, "no header 'ax,ay,az,...' after the logger's key,value lines")
    return pre, meta, rate


# ---- named-column tables ---------------------------------------------------------------

@dataclass
class AxisColumn:
    """An accelerometer axis column of a table: its name, axis (x, y, z), the unit its name
    states (a key of NAMED_UNITS, lower case, blanks dropped; None when none) and whether
    it is a phone's virtual sensor (linear acceleration, gravity)."""

    name: str
    axis: str
    unit: str | None
    virtual: bool


def axis_column(name: str) -> AxisColumn | None:
    """The accelerometer axis ``name`` is (``Acceleration x (m/s^2)``, ``scaledAccelX``,
    ``AccX [g]``, ``acc_x_g``), or None: another column (a prefix other than scaled, raw,
    or one naming linear acceleration or gravity, is not an accelerometer's axis)."""
    m = AXIS_RE.fullmatch(name.strip())
    if m is None:
        return None
    pre = re.sub(r"[\s_.-]+", "", m.group("pre")).lower()
    virtual = any(w in pre for w in VIRTUAL_WORDS)
    if pre not in AXIS_PREFIXES and not virtual:
        return None
    unit = m.group("unit") if m.group("unit") is not None else m.group("tail")
    unit = None if unit is None else re.sub(r"\s+", "", unit).lower()
    return AxisColumn(name, m.group("axis").lower(), unit, virtual)


def table_axes(source: str, names: list[str], row: int) -> list[AxisColumn]:
    """The x, y, z columns of a table's header (``row``: its line).

    Raises
    ------
    InputError
        No column for an axis, more than one, or only a phone's virtual sensor
        (linear acceleration, gravity), naming the candidates.
    """
    found = [c for c in (axis_column(n) for n in names) if c is not None]
    real = [c for c in found if not c.virtual]
    if not real and found:
        raise InputError(source, f"the accelerometer columns {', '.join(repr(c.name) for c in found)} are a phone's "
                         "virtual sensor (linear acceleration or gravity), not an accelerometer's specific force: "
                         "export the accelerometer's own readings (phyphox 'Acceleration with g')", row=row)
    axes = []
    for axis in "xyz":
        on = [c for c in real if c.axis == axis]
        if len(on) != 1:
            what = (f"{len(on)} columns for axis {axis} ({', '.join(repr(c.name) for c in on)}): expected one"
                    if on else f"no column for axis {axis}")
            raise InputError(source, f"{what} among the accelerometer columns "
                             f"{', '.join(repr(c.name) for c in real) or '(none)'} (names such as accX, "
                             "'Acceleration y (m/s^2)', scaledAccelZ)", row=row)
        axes.append(on[0])
    return axes


def names_unit(source: str, axes: list[AxisColumn], row: int) -> str | None:
    """The unit (a key of units.UNITS) all three axis columns' names state, or None when none
    does.

    Raises
    ------
    InputError
        A unit not read (``mg``), or one stated by some of the names and not the others.
    """
    for c in axes:
        if c.unit is not None and c.unit not in NAMED_UNITS:
            raise InputError(source, f"column {c.name!r}: unit {c.unit!r} is not one accelcal reads (g, m/s^2, "
                             "counts)", row=row)
    units = {NAMED_UNITS[c.unit] if c.unit is not None else None for c in axes}
    if len(units) > 1:
        raise InputError(source, f"the columns {', '.join(repr(c.name) for c in axes)} state different units: "
                         "expected the same unit in all three names, or in none", row=row)
    return units.pop()


def table_scale(source: str, pre, option: Scale | None, unit: str | None, units_stated: bool,
                gravity: float, axes: list[AxisColumn]) -> Scale | None:
    """The Scale of a table's readings: the unit its axis names state weighed against the
    options and the ``# units:``/``# lsb:`` comments by :func:`units.file_scale` (the names'
    unit taken as the file's ``units``); ``--full-scale`` without ``--units``
    (``units_stated`` False) is read in the names' unit.

    Raises
    ------
    InputError
        A contradiction (options or comment against the names), or readings in m/s^2 or g
        with no LSB stated anywhere.
    """
    meta, lines = dict(pre.metadata), dict(pre.metadata_lines)
    if unit is None:
        return file_scale(option, meta, lines, source)
    cols = ", ".join(c.name for c in axes)
    said = meta.get("units")
    if said is not None and said != unit:
        raise InputError(source, f"the comment '# units: {said}' contradicts the unit the header's columns state, "
                         f"{UNIT_TEXT[unit]} ({cols}): state the unit once", row=lines.get("units"))
    if option is not None and not units_stated and not option.converts and option.lsb_g and unit != "counts":
        option = Scale(unit, option.lsb_g * (gravity if unit == "mps2" else 1.0), option.lsb_g, option.how)
    sized = any(k in meta for k in ("lsb", "full_scale_g")) or (option is not None and bool(option.lsb or option.lsb_g))
    if unit != "counts" and not sized and (option is None or option.units == unit):
        raise InputError(source, f"the readings are in {UNIT_TEXT[unit]} (the header's {cols}) and no LSB is "
                         "stated: give --full-scale G (or --units {0} --lsb VALUE, or a '# lsb:' comment) to "
                         "make them counts".format(unit), row=pre.header_line)
    meta["units"], lines["units"] = unit, pre.header_line
    return file_scale(option, meta, lines, source,
                      unit_source=f"the unit the header's columns state, {UNIT_TEXT[unit]} ({cols}),")


def present_rows(source: str, matrix: np.ndarray, table, axes: list[AxisColumn], js: list[int],
                 notes: list[str]) -> np.ndarray:
    """The indices of the rows with readings (``matrix``: the three axis columns, NaN where
    empty; ``js``: their indices in the table); rows whose three readings are all empty (a
    LORD log's other packets) are skipped with a note.

    Raises
    ------
    InputError
        A row with one or two of its readings empty, naming its line and the column.
    """
    empty = np.isnan(matrix)
    gone = empty.all(axis=1)
    partly = np.flatnonzero(empty.any(axis=1) & ~gone)
    if partly.size:
        i = int(partly[0])
        j = int(np.flatnonzero(empty[i])[0])
        others = [axes[k].name for k in range(3) if not empty[i, k]]
        raise InputError(source, f"expected a reading, got {got_text(table.cell(i, js[j]))} where "
                         f"{' and '.join(others)} {'has' if len(others) == 1 else 'have'} one (a row's three readings "
                         "are all given, or all empty for another packet)", row=table.line(i), column=axes[j].name)
    if gone.any():
        notes.append(f"skipped {int(gone.sum())} row(s) whose readings ({', '.join(c.name for c in axes)}) are all "
                     "empty (other packets)")
    return np.flatnonzero(~gone)


def table_time(source: str, stamps: np.ndarray, table, rows: np.ndarray, column: str, j: int) -> np.ndarray:
    """The time stamps of the rows read (``rows``), as written: finite and increasing.

    Raises
    ------
    InputError
        An empty or unknown stamp, or one not after the stamp before, naming its line.
    """
    t = stamps[rows]
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        i = int(rows[bad[0]])
        raise InputError(source, f"expected a time stamp, got {got_text(table.cell(i, j))}", row=table.line(i),
                         column=column)
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        h, i = int(rows[back[0]]), int(rows[back[0] + 1])
        raise InputError(source, f"time stamp {table.cell(i, j).strip()!r} is not after {table.cell(h, j).strip()!r} "
                         f"(row {table.line(h)}): time stamps must increase", row=table.line(i), column=column)
    return t


def whole_counts(values: np.ndarray, source: str, locate) -> np.ndarray:
    """Readings in counts (no unit stated) as int64.

    Raises
    ------
    InputError
        The first reading that is not a whole number, naming its row and column.
    """
    frac = np.argwhere(values != np.round(values))
    if frac.size:
        i, j = (int(v) for v in frac[0])
        row, column = locate(i, j)
        raise InputError(source, f"reading {values[i, j]:.10g} is not a whole count (readings in m/s^2 or g: "
                         "state --units mps2|g with --lsb VALUE or --full-scale G)", row=row, column=column)
    return values.astype(np.int64)


def convert_named(source: str, data: bytes, pre, opts: Options, units_stated: bool) -> Converted:
    """A table with named columns: the three accelerometer axes (:func:`table_axes`), their
    unit (:func:`table_scale`), an optional time column (else ``--rate``); rows without
    readings skipped (:func:`present_rows`)."""
    names = [c.strip() for c in header_cells(pre.header)]
    axes = table_axes(source, names, pre.header_line)
    acc = [c.name for c in axes]
    scale = table_scale(source, pre, opts.scale, names_unit(source, axes, pre.header_line), units_stated,
                        opts.gravity_mps2 or STANDARD_GRAVITY, axes)
    time_column = next((n for n in names if n not in acc and TIME_COLUMN_RE.fullmatch(n)), None)
    if time_column is None and opts.rate_hz is None:
        raise InputError(source, "the table has no time column (t, time, timestamp, 'Time (s)', time_ms, ...): give "
                         "the sample rate with --rate HZ", row=pre.header_line)
    if time_column is None and opts.time_unit != "auto":
        raise InputError(source, "--time-unit: the table has no time column (--rate states its rate)")
    want = {a: "ref" for a in acc}
    if time_column is not None:
        want[time_column] = "ref"
    names, values, table = read_columns(source, data, pre, want)
    js = [names.index(a) for a in acc]
    notes: list[str] = []
    rows = present_rows(source, np.column_stack([values[a] for a in acc]), table, axes, js, notes)
    if rows.size == 0:
        raise InputError(source, f"no row has readings in {', '.join(acc)}", row=pre.header_line)
    matrix = np.column_stack([values[a][rows] for a in acc])

    def locate(i: int, j: int) -> tuple[int, str]:
        return table.line(int(rows[i])), acc[j]

    converts = scale is not None and scale.converts
    raw = to_counts(matrix, scale, source, locate, notes=notes) if converts else whole_counts(matrix, source, locate)
    t = None if time_column is None else table_time(source, values[time_column], table, rows, time_column,
                                                    names.index(time_column))
    used = set(want)
    dropped = [c for c in names if c and c not in used and re.search(r"gyr", c, re.I)]
    ignored = [c for c in names if c and c not in used and c not in dropped]
    meta = {"table.columns": ", ".join(acc + ([time_column] if time_column else []))}
    return finish(source, "table", raw, np.arange(rows.size), t, None, opts, scale, converts or bool(np.any(raw < 0)),
                  opts.rate_hz, meta, drop_note(dropped, ignored) + notes + ([table.cut_note] if table.cut_note else []),
                  locate, None, time_column=time_column)


def convert_log(source: str, data: bytes, opts: Options, blocks: bool) -> Converted:
    """A serial monitor's capture (:mod:`accelcal.convert_log`)."""
    values, lines, block, info = read_log(source, data)

    def locate(i: int, j: int) -> tuple[int, str]:
        return lines[i], f"field {j + 1}"

    scale = opts.scale
    shifted: list[str] = []
    raw = to_counts(values, scale, source, locate, notes=shifted) if scale is not None and scale.converts else \
        whole_counts(values, source, locate)
    if opts.rate_hz is None:
        raise InputError(source, "log files have no time column: give the sample rate with --rate HZ")
    if blocks and opts.regions is not None:
        raise InputError(source, "--blocks and --regions both label the poses: give one")
    notes = [f"{info['text_lines']} line(s) of text (the first: {info['first_text']!r}) split the readings into "
             f"{info['blocks']} block(s)" + ("; each block is a pose" if blocks else
                                            "; --blocks labels each as a pose")] if info["text_lines"] else []
    notes += shifted
    k, first = held_runs(raw)
    n = raw.shape[0]
    share = (n - first.size) / (n - 1) if n > 1 else 0.0      # rows that repeat the row before
    if k > 1:
        notes.append(f"{100 * share:.0f} % of the rows repeat the row before in all three readings (each reading "
                     f"held for {k} rows): the logger read the sensor faster than it updates; the distinct readings "
                     f"come at about {opts.rate_hz / k:.4g} Hz, and successive rows are not independent samples")
    meta = {"log.text_lines": str(info["text_lines"]), "log.blocks": str(info["blocks"]),
            "log.held_share": f"{share:.4f}"}
    return finish(source, "log", raw, np.arange(raw.shape[0]), None, block if blocks else None, opts, scale,
                  bool(np.any(raw < 0)), opts.rate_hz, meta, notes, locate, None)


def convert_file(path: Any, fmt: str = "auto", *, scale: Scale | None = None, rate_hz: float | None = None,
                 regions: Any = None, stated_f: bool = False, gravity_mps2: float | None = None,
                 bits: int = 16, blocks: bool = False, time_unit: str = "auto",
                 units_stated: bool = True) -> Converted:
    """Read another tool's file as a contract recording of a triad.

    Parameters
    ----------
    path : str or os.PathLike
        The file (compressed or not: gzip, bzip2, xz, zstd, a zip of one file).
    fmt : {"auto", "imu_tk", "imucal", "mpu6050", "csv", "log", "table"}
        ``auto`` tells it from the first line (:func:`detect_format`; a log from its lines).
    scale : units.Scale, optional
        The readings' unit and LSB (``--units``/``--lsb``/``--full-scale``), or the
        file's ``# units:``/``# lsb:`` comments, else counts; stated by both, they must
        agree (:func:`units.file_scale`).  A table's axis names may state the unit
        (``Accelerometer X (g)``): the same rule, the names taken as the file's unit.
    rate_hz : float, optional
        Sample rate, Hz, for files without a time column (imucal, log, a table without one;
        the MPU-6050 log's ``Fs`` otherwise); with a time column (csv, table), the device's
        rate where t's steps do not give it (a host's time stamps).
    regions : path, optional
        JSON ``{name: {"start": s, "end": e}}`` of sample numbers (end excluded): pose labels.
    stated_f : bool
        Give each pose named ``x_p ... z_a`` the reference f = +-g (m/s^2) along its axis.
    gravity_mps2 : float, optional
        g for the stated f and the device (default 9.80665; imu_tk: 9.81744).
    bits : int
        The ADC's bits: the device's range, and the readings must fit it.
    blocks : bool
        log: each block of readings between text lines is a pose (``block_1``, ...).
    time_unit : {"auto", "s", "ms", "us", "ns"}
        The time column's unit (csv, imu_tk, table).  ``auto``: the unit its name states, else
        seconds, except time stamps whose steps in seconds would give under
        MIN_PLAUSIBLE_HZ (then the smallest of ms, us, ns that gives more; a note says so).
        The recording's t is written in seconds; the device's rate is from t's median
        step, or from its mean step where the two disagree (bursts; a note).
    units_stated : bool
        Whether ``scale``'s unit was stated (``--units``); when not, a ``--full-scale``
        alone (a Scale in counts) is read in the unit a table's axis names state.

    Returns
    -------
    Converted

    Raises
    ------
    InputError
        One line naming the file and the row and column (or JSON field) at fault.
    """
    source, data = read_text_bytes(path)
    if fmt == "auto":
        fmt = detect_format(source, data)
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}")
    opts = Options(scale, rate_hz, None, None, stated_f, gravity_mps2, bits, time_unit)
    if regions is not None:
        opts.regions, opts.regions_source = read_regions(regions), str(regions)
    if blocks and fmt != "log":
        raise InputError(source, f"--blocks: {fmt} files have no blocks (it labels a log's poses)")
    if fmt == "log":
        return convert_log(source, data, opts, blocks)
    if time_unit != "auto" and fmt not in ("imu_tk", "csv", "table"):
        raise InputError(source, f"--time-unit: {fmt} files have no time column (--rate states their rate)")
    if fmt in ("imu_tk", "csv"):
        if rate_hz is not None and fmt == "imu_tk":
            raise InputError(source, "--rate: imu_tk files have a time column and their own rate")
        if fmt == "imu_tk" and scale is not None and scale.converts:
            raise InputError(source, "imu_tk's readings are counts: --units mps2|g and --lsb do not apply")
        if fmt == "imu_tk":
            device, rec = load_xsens(path)
            device = device if scale is None or scale.lsb_g is None else None  # a stated full scale: the nominal device from it
        else:
            device, rec = None, read_recording(path, scale=scale)
            if rec.n_channels != 3:
                raise InputError(source, f"{rec.n_channels} raw channels: convert makes a triad's recording (3)")
        signed = fmt == "csv" and bool(np.any(rec.raw < 0))
        kept = (rec.pose, rec.f) if fmt == "csv" and opts.regions is None else None
        if kept is not None and stated_f:
            raise InputError(source, "--stated-f: a recording's poses are its own; give --regions to name them")
        return finish(source, fmt, rec.raw, np.arange(rec.n_samples), rec.t, None, opts, scale, signed, None,
                      dict(rec.metadata), list(rec.notes), lambda i, j: (rec.line(i), f"raw_{j}"), None, device, kept,
                      time_column="t" if fmt == "csv" else None)
    pre = read_preamble(data)
    if pre.header is None:
        raise InputError(source, "the file is empty (nothing but comments and blank lines)")
    if fmt == "table":
        return convert_named(source, data, pre, opts, units_stated)
    meta: dict[str, str] = {}
    if fmt == "mpu6050":
        pre, meta, fs = mpu6050_preamble(source, data, pre)
        opts.rate_hz = rate_hz if rate_hz is not None else fs
    return convert_table(source, data, pre, fmt, opts, meta)
