"""The accelerometer's axis columns of a table with named columns (``accelcal convert``'s
``table`` format): ``accX``, ``'Acceleration y (m/s^2)'``, ``scaledAccelZ``, ROS's
``linear_acceleration.x``, PX4's ``accelerometer_m_s2[0]`` and its sensor_accel topic's bare
``x, y, z``, bare axes with a unit of acceleration (``x (g)``), bare ``x, y, z`` beside a time
column and nothing else, the three columns ``--columns`` names, and the unit their names
state."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .time import is_time_name
from ..errors import InputError

__all__ = ["AXIS_RE", "BARE_AXES", "PX4_ACCEL_FILE_RE", "NAMED_UNITS", "AxisColumn", "axis_column", "table_axes",
           "px4_export", "names_unit", "find_named", "stated_axes", "axis_triples", "mirrored_note"]

#: a unit after a column's name, in () or []
UNIT_PART = r"\s*[(\[](?P<unit>[^)\]]*)[)\]]"
#: a table's accelerometer axis column: a prefix, the word, the axis, a unit in () or [] or after _
AXIS_RE = re.compile(r"(?P<pre>.*?)(?:accelerometer|acceleration|accel|acc|(?<![a-z])a)[\s_.-]*(?P<axis>[xyz])"
                     r"(?:" + UNIT_PART + r"|_(?P<tail>g|mps2|ms2|counts|lsb|raw))?", re.I)
#: an axis named by its letter alone with a unit: ``x (g)``, ``Z [m/s^2]`` (an accelerometer's where the unit
#: is one of acceleration, ACCELERATION_UNITS)
BARE_UNIT_RE = re.compile(r"(?P<axis>[xyz])" + UNIT_PART, re.I)
#: EuRoC's and Kalibr's frame-subscripted acceleration, ``a_RS_S_x [m s^-2]`` (the acceleration of S
#: against R, in S's axes): an accelerometer's where the unit is one of acceleration (``w_RS_S_x`` is the gyro)
FRAMED_AXIS_RE = re.compile(r"a_(?:[a-z0-9]+_)*(?P<axis>[xyz])" + UNIT_PART, re.I)
#: a unit in a column's name, at its end
NAME_UNIT_RE = re.compile(r".*?" + UNIT_PART)
#: a file name that says its bare x, y, z are another sensor's (PX4's sensor_gyro, sensor_mag topics)
OTHER_SENSOR_FILE_RE = re.compile(r"gyr|mag|compass|angular|rotation", re.I)
#: a robotics message's accelerometer field: ROS's (field.)linear_acceleration.x, PX4's
#: accelerometer_m_s2[0] (ulog2csv)
MESSAGE_AXIS_RE = re.compile(r"(?:(?:field\.)?(?P<ros>linear_acceleration)\.(?P<axis>[xyz])"
                             r"|(?:accelerometer|accel|acc)(?P<mps2>_m_s2)?\[(?P<index>[012])\])", re.I)
#: a file pyulog's ulog2csv wrote for PX4's sensor_accel topic (<log>_sensor_accel_<instance>.csv):
#: its bare x, y, z columns are the accelerometer's, in m/s^2 (sensor_gyro and sensor_mag have the same)
PX4_ACCEL_FILE_RE = re.compile(r"(?:^|_)sensor_accel(?:_\d+)?\.csv$", re.I)
#: a file name that says its bare x, y, z are an accelerometer's (a phone app's Accelerometer.csv,
#: AccelerometerUncalibrated.csv, TotalAcceleration.csv), unless it names another sensor too
ACCEL_FILE_RE = re.compile(r"accel", re.I)
#: a file name that says its readings are a phone's virtual sensor (linear acceleration, gravity)
VIRTUAL_FILE_RE = re.compile(r"linear|gravity", re.I)
#: the axes' columns named by the axis alone
BARE_AXES = ("x", "y", "z")
#: the prefixes of an accelerometer's own axis columns (LORD's scaledAccelX)
AXIS_PREFIXES = ("", "scaled", "raw")
#: prefixes of a phone's virtual sensors: not an accelerometer's specific force
VIRTUAL_WORDS = ("linear", "gravity")
#: a unit in an axis column's name (lower case, blanks dropped) -> units.UNITS
NAMED_UNITS = {"g": "g", "m/s^2": "mps2", "m/s\u00b2": "mps2", "m/s/s": "mps2", "mps2": "mps2", "m/s2": "mps2",
               "ms^-2": "mps2", "ms-2": "mps2", "m*s^-2": "mps2", "m.s^-2": "mps2", "m/s**2": "mps2",  # Kalibr, EuRoC
               "ms2": "mps2", "counts": "counts", "count": "counts", "lsb": "counts", "raw": "counts"}
#: the units of NAMED_UNITS that only an accelerometer's readings have (a gyroscope's or a magnetometer's
#: counts are counts too)
ACCELERATION_UNITS = ("g", "mps2")


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
    ``AccX [g]``, ``acc_x_g``; ``x (g)`` and EuRoC's ``a_RS_S_x [m s^-2]`` where the unit is one of
    acceleration), or None: another column (a prefix other than scaled, raw,
    or one naming linear acceleration or gravity, is not an accelerometer's axis)."""
    m = MESSAGE_AXIS_RE.fullmatch(name.strip())
    if m is not None:
        # a robotics message's field: ROS sensor_msgs/Imu's linear_acceleration is the specific force
        # (gravity in), PX4's accelerometer_m_s2[i] likewise
        axis = m.group("axis").lower() if m.group("axis") else "xyz"[int(m.group("index"))]
        return AxisColumn(name, axis, "mps2" if m.group("mps2") or m.group("ros") else None, False)
    m = BARE_UNIT_RE.fullmatch(name.strip()) or FRAMED_AXIS_RE.fullmatch(name.strip())
    if m is not None:
        unit = re.sub(r"\s+", "", m.group("unit")).lower()
        named = NAMED_UNITS.get(unit)
        return AxisColumn(name, m.group("axis").lower(), unit, False) if named in ACCELERATION_UNITS else None
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


def table_axes(source: str, names: list[str], row: int, notes: list[str] | None = None) -> list[AxisColumn]:
    """The x, y, z columns of a table's header (``row``: its line).  Bare ``x, y, z`` are the
    accelerometer's in PX4's sensor_accel export (m/s^2), and beside nothing but time columns
    or in a file whose name says accelerometer (ACCEL_FILE_RE: a phone app's
    ``AccelerometerUncalibrated.csv``), where that name names no other sensor and no virtual
    one (a note appended to ``notes`` says so).  A refusal's ``--columns`` hint lists them in
    X, Y, Z order, whatever the header's (Sensor Logger writes ``z,y,x``).

    Raises
    ------
    InputError
        No column for an axis, more than one, or only a phone's virtual sensor
        (linear acceleration, gravity), naming the candidates and listing the header's
        columns (``--columns`` names the three).
    """
    found = [c for c in (axis_column(n) for n in names) if c is not None]
    bare = [n for n in names if n.lower() in BARE_AXES]
    if not found and len(bare) == len(BARE_AXES):
        others = [n for n in names if n and n not in bare]
        file = Path(source).name
        ordered = sorted(bare, key=str.lower)           # X, Y, Z: --columns's order, not the header's
        other_sensor = OTHER_SENSOR_FILE_RE.search(file) or VIRTUAL_FILE_RE.search(file)
        if PX4_ACCEL_FILE_RE.search(file):
            found = [AxisColumn(n, n.lower(), "mps2", False) for n in bare]
        elif others and all(is_time_name(n) for n in others) and not other_sensor:
            found = [AxisColumn(n, n.lower(), None, False) for n in bare]
            if notes is not None:
                notes.append(f"the columns {', '.join(ordered)} beside {', '.join(others)} and no other sensor's are "
                             "taken as the accelerometer's (--columns names others)")
        elif ACCEL_FILE_RE.search(file) and not other_sensor:
            found = [AxisColumn(n, n.lower(), None, False) for n in bare]
            if notes is not None:
                notes.append(f"the columns {', '.join(ordered)} are taken as the accelerometer's, as the file's name "
                             f"{file!r} says (--columns names others)")
        else:
            raise InputError(source, "the columns x, y, z do not say they are an accelerometer's (a gyroscope's or a "
                             f"magnetometer's are written alike; the header's columns: {listed(names)}): if they are, "
                             f"give --columns {','.join(ordered)} (a PX4 sensor_accel topic exported by ulog2csv: keep "
                             "its file name <log>_sensor_accel_0.csv)", row=row)
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
            among = (f"among the accelerometer columns {', '.join(repr(c.name) for c in real)}" if real else
                     "among the header's columns")
            raise InputError(source, f"{what} {among} (the header's columns: {listed(names)}; names such as accX, "
                             f"'Acceleration y (m/s^2)', 'x (g)', or name the three with {columns_hint(names)})",
                             row=row)
        axes.append(on[0])
    return axes


def listed(names: list[str], most: int = 20) -> str:
    """The header's column names for a message (at most ``most``)."""
    shown = [repr(n) for n in names[:most]]
    return ", ".join(shown) + (f" and {len(names) - most} more" if len(names) > most else "") or "(none)"


def axis_triples(names: list[str]) -> list[list[str]]:
    """The names that come in threes differing only in their last letter x, y, z (``tx, ty, tz``;
    ``gyro_x (dps)``, ...), in the header's order: what ``--columns`` may name."""
    groups: dict[str, dict[str, str]] = {}
    for n in names:
        m = re.fullmatch(r"(.*)([xyz])((?:\s*[(\[][^)\]]*[)\]])?[^a-z]*)", n, re.I)
        if m is not None:
            groups.setdefault((m.group(1) + "#" + m.group(3)).lower(), {}).setdefault(m.group(2).lower(), n)
    return [[g[a] for a in "xyz"] for g in groups.values() if len(g) == 3]


def columns_hint(names: list[str]) -> str:
    """``--columns X,Y,Z``, with the header's x/y/z triples (:func:`axis_triples`) as examples."""
    triples = axis_triples(names)
    if not triples:
        return "--columns X,Y,Z"
    return f"--columns {','.join(triples[0])}" + (
        f" (the header's triples: {'; '.join(','.join(t) for t in triples)})" if len(triples) > 1 else "")


def find_named(source: str, names: list[str], stated: str, option: str, row: int) -> str:
    """The header's column an option names: the name equal to ``stated`` (blanks about it
    dropped), else the only one equal to it ignoring case, else the only one whose name without
    the unit in () or [] at its end is.

    Raises
    ------
    InputError
        No such column, or several, naming ``option`` and listing the header's columns.
    """
    want = stated.strip()
    found = [n for n in names if n == want] or [n for n in names if n.lower() == want.lower()]
    if not found:
        # the name without the unit at its end (EuRoC's 'a_RS_S_x [m s^-2]' named as a_RS_S_x)
        bare = [re.sub(UNIT_PART + r"\s*$", "", n).strip() for n in names]
        found = [n for n, b in zip(names, bare) if b.lower() == want.lower()]
    if len(found) != 1:
        raise InputError(source, f"{option} {stated!r}: "
                         f"{'no such column' if not found else 'more than one column of that name'}; the columns are "
                         f"{listed([n for n in names if n])}", row=row)
    return found[0]


def stated_axes(source: str, names: list[str], stated: str, row: int) -> list[AxisColumn]:
    """The accelerometer's x, y, z columns ``--columns X,Y,Z`` names (:func:`find_named`), each
    with the unit its name states (``x (g)``: in () or [] at its end; an accelerometer name's
    ``acc_x_g``), else none.

    Raises
    ------
    InputError
        Not three names, a name not in the header, or one named twice.
    """
    wanted = [w for w in stated.split(",")]
    if len(wanted) != 3 or not all(w.strip() for w in wanted):
        raise InputError(source, f"--columns {stated!r}: expected the accelerometer's three columns X,Y,Z, "
                         f"comma-separated; the header's columns: {listed([n for n in names if n])}", row=row)
    cols = [find_named(source, names, w, "--columns", row) for w in wanted]
    if len(set(cols)) != 3:
        raise InputError(source, f"--columns {stated!r}: a column named twice", row=row)
    out = []
    for axis, n in zip("xyz", cols):
        known = axis_column(n)
        m = NAME_UNIT_RE.fullmatch(n.strip())
        unit = known.unit if known is not None else (re.sub(r"\s+", "", m.group("unit")).lower() if m else None)
        out.append(AxisColumn(n, axis, unit, False))
    return out


def mirrored_note(axes: list[AxisColumn]) -> list[str]:
    """A note where ``--columns`` puts the columns whose names state the axes x, y, z (``accX``,
    ``x (g)``, a bare ``x``) as an odd permutation of them: a swap of two mirrors the frame
    (left-handed), which no mounting of a sensor gives; a cyclic order (y,z,x) is a rotation, no note.
    (``--columns`` takes names only, no sign: it flips no axis.)"""
    said = []
    for c in axes:
        known = axis_column(c.name)
        said.append(known.axis if known is not None else c.name.strip().lower())
    if sorted(said) != list(BARE_AXES) or said == list(BARE_AXES):
        return []
    order = [BARE_AXES.index(a) for a in said]
    swaps = sum(order[i] > order[j] for i in range(3) for j in range(i + 1, 3))
    if swaps % 2 == 0:
        return []
    moved = ", ".join(f"column {c.name!r} as the {c.axis} axis" for c, a in zip(axes, said) if a != c.axis)
    xyz = [axes[said.index(a)].name for a in BARE_AXES]
    cyclic = " or ".join(",".join(xyz[k:] + xyz[:k]) for k in range(3))
    return [f"--columns puts {moved}: the frame is mirrored (left-handed), unless that is meant; a sensor mounted "
            f"rotated is one of {cyclic}"]


def px4_export(source: str, axes: list[AxisColumn]) -> bool:
    """Whether the table is PX4's, as pyulog's ulog2csv writes it: a sensor_accel file, or
    sensor_combined's accelerometer_m_s2[i] columns (its time stamps are in us)."""
    return bool(PX4_ACCEL_FILE_RE.search(Path(source).name)) or \
        all(c.name.lower().startswith("accelerometer_m_s2[") for c in axes)


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
