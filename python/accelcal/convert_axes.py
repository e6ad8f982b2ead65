"""The accelerometer's axis columns of a table with named columns (``accelcal convert``'s
``table`` format): ``accX``, ``'Acceleration y (m/s^2)'``, ``scaledAccelZ``, ROS's
``linear_acceleration.x``, PX4's ``accelerometer_m_s2[0]`` and its sensor_accel topic's bare
``x, y, z``, and the unit their names state."""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from .errors import InputError

__all__ = ["AXIS_RE", "BARE_AXES", "PX4_ACCEL_FILE_RE", "NAMED_UNITS", "AxisColumn", "axis_column", "table_axes",
           "px4_export", "names_unit"]

#: a table's accelerometer axis column: a prefix, the word, the axis, a unit in () or [] or after _
AXIS_RE = re.compile(r"(?P<pre>.*?)(?:accelerometer|acceleration|accel|acc|(?<![a-z])a)[\s_.-]*(?P<axis>[xyz])"
                     r"(?:\s*[(\[](?P<unit>[^)\]]*)[)\]]|_(?P<tail>g|mps2|ms2|counts|lsb|raw))?", re.I)
#: a robotics message's accelerometer field: ROS's (field.)linear_acceleration.x, PX4's
#: accelerometer_m_s2[0] (ulog2csv)
MESSAGE_AXIS_RE = re.compile(r"(?:(?:field\.)?(?P<ros>linear_acceleration)\.(?P<axis>[xyz])"
                             r"|(?:accelerometer|accel|acc)(?P<mps2>_m_s2)?\[(?P<index>[012])\])", re.I)
#: a file pyulog's ulog2csv wrote for PX4's sensor_accel topic (<log>_sensor_accel_<instance>.csv):
#: its bare x, y, z columns are the accelerometer's, in m/s^2 (sensor_gyro and sensor_mag have the same)
PX4_ACCEL_FILE_RE = re.compile(r"(?:^|_)sensor_accel(?:_\d+)?\.csv$", re.I)
#: the axes' columns named by the axis alone
BARE_AXES = ("x", "y", "z")
#: the prefixes of an accelerometer's own axis columns (LORD's scaledAccelX)
AXIS_PREFIXES = ("", "scaled", "raw")
#: prefixes of a phone's virtual sensors: not an accelerometer's specific force
VIRTUAL_WORDS = ("linear", "gravity")
#: a unit in an axis column's name (lower case, blanks dropped) -> units.UNITS
NAMED_UNITS = {"g": "g", "m/s^2": "mps2", "m/s\u00b2": "mps2", "m/s/s": "mps2", "mps2": "mps2", "m/s2": "mps2",
               "ms2": "mps2", "counts": "counts", "count": "counts", "lsb": "counts", "raw": "counts"}


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
    m = MESSAGE_AXIS_RE.fullmatch(name.strip())
    if m is not None:
        # a robotics message's field: ROS sensor_msgs/Imu's linear_acceleration is the specific force
        # (gravity in), PX4's accelerometer_m_s2[i] likewise
        axis = m.group("axis").lower() if m.group("axis") else "xyz"[int(m.group("index"))]
        return AxisColumn(name, axis, "mps2" if m.group("mps2") or m.group("ros") else None, False)
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
    bare = [n for n in names if n.lower() in BARE_AXES]
    if not found and len(bare) == len(BARE_AXES):
        if not PX4_ACCEL_FILE_RE.search(Path(source).name):
            raise InputError(source, "the columns x, y, z do not say they are an accelerometer's (a gyroscope's or a "
                             "magnetometer's are written alike): if they are, name them acc_x, acc_y, acc_z (a PX4 "
                             "sensor_accel topic exported by ulog2csv: keep its file name <log>_sensor_accel_0.csv)",
                             row=row)
        found = [AxisColumn(n, n.lower(), "mps2", False) for n in bare]
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
