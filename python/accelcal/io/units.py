"""Readings in physical units: what one count of a recording's m/s^2 or g values is.

A logger that writes floats (imucal's sessions, phone logs) has still read an integer
register: every value is a whole number of LSBs.  The LSB is stated by an option
(``--lsb VALUE`` with ``--units mps2|g``, or ``--full-scale G`` and ``--bits N``) or by
the file's metadata comments (``# units: mps2``, ``# lsb: 0.0047900390625``); this module
turns those statements into a :class:`Scale`, and :func:`accelcal.io.units_counts.to_counts`
divides the readings by it (whole numbers within :data:`REL_TOL`, or refused naming row and
column).  Used by the recording reader and by ``accelcal convert``.

An option and a comment may both state the scale (:func:`file_scale`): where they agree
the option's is used, and where they contradict each other (another unit, another
count size) the file is refused naming the comment's line -- neither silently wins.
"""
from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass
from typing import Any, Callable

from ..errors import AccelcalError, InputError

__all__ = ["UNITS", "REL_TOL", "Scale", "scale_from_options", "scale_from_metadata",
           "METADATA_KEYS", "STANDARD_GRAVITY", "OPTION_NAMES",
           "converted_metadata", "stated_scale", "file_scale", "in_file_unit", "unstated_lsb", "COUNTS_STATED", "parse_bits", "split_lsb", "LSB_SUFFIXES"]

UNITS = ("counts", "mps2", "mmps2", "g", "mg")
REL_TOL = 1e-6
"""How far value / lsb may be from an integer n: ``REL_TOL * max(|n|, 1)``.  A float
written by ``n * lsb`` and read back is within ~1e-15 of n; a wrong LSB is off by far more."""
STANDARD_GRAVITY = 9.80665
METADATA_KEYS = ("units", "lsb", "full_scale_g", "bits", "gravity_mps2")
UNIT_TEXT = {"counts": "counts", "mps2": "m/s^2", "mmps2": "mm/s^2", "g": "g", "mg": "mg"}
OPTION_NAMES = {"units": "--units", "lsb": "--lsb", "full_scale_g": "--full-scale", "bits": "--bits",
                "gravity_mps2": "--gravity", "round": "--round"}
METADATA_NAMES = {k: f"'# {k}:'" for k in METADATA_KEYS}


@dataclass(frozen=True)
class Scale:
    """What one count of a recording's readings is.

    Attributes
    ----------
    units : {"counts", "mps2", "g"}
        The unit of the readings as written in the file.
    lsb : float or None
        One count in ``units`` (m/s^2 per count for ``mps2``, g per count for ``g``);
        None for ``counts`` when the count's size is not stated.
    lsb_g : float or None
        One count in g, when known (for a device's nominal scale).
    how : str
        Where the LSB came from, for messages (e.g. ``"--lsb"``, ``"# lsb: (row 3)"``).
    rounds : bool
        Readings are rounded to the nearest LSB (``--round``: a logger that writes calibrated
        floats, on no grid), with a note of how far, instead of refused when not whole.
    unit_stated : bool
        Whether ``units`` was stated (``--units``, a comment); False for ``--full-scale`` or
        ``--lsb`` alone, which take the unit the file states (:func:`in_file_unit`): until then
        ``units`` is ``"counts"``, with ``lsb`` the bare ``--lsb`` value (in the file's unit) or None.
    gravity_mps2 : float
        g in m/s^2, to size one count in m/s^2 from ``lsb_g`` once the file's unit is known.
    """

    units: str
    lsb: float | None
    lsb_g: float | None = None
    how: str = ""
    rounds: bool = False
    unit_stated: bool = True
    gravity_mps2: float = STANDARD_GRAVITY

    @property
    def converts(self) -> bool:
        """Whether the readings must be divided by the LSB (physical units)."""
        return self.units != "counts"

    def counts_per_mps2(self, gravity_mps2: float) -> float | None:
        """The nominal sensitivity, counts per m/s^2, or None when the LSB is unknown.

        Parameters
        ----------
        gravity_mps2 : float
            g in m/s^2, used only when the LSB is in g.
        """
        if self.units == "mps2" and self.lsb:
            return 1.0 / self.lsb
        return 1.0 / (self.lsb_g * gravity_mps2) if self.lsb_g else None

    def describe(self) -> str:
        if not self.converts:
            return "counts" + (f" (1 count = {self.lsb_g:.9g} g)" if self.lsb_g else "")
        return f"{UNIT_TEXT[self.units]} / {self.lsb:.12g} {UNIT_TEXT[self.units]} per count"


def _positive(text: Any, what: str, fail: Callable[[str], Exception]) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise fail(f"{what} {text!r}: expected a finite number > 0")
    return v


LSB_SUFFIXES = ("mmps2", "mps2", "mg", "g")  # units an LSB may carry ("1mg"; size: g_per), longest first as tried


def g_per(unit: str, gravity_mps2: float) -> float:
    """One ``unit`` (LSB_SUFFIXES; mmps2: Klipper's files) in g, with g = ``gravity_mps2`` m/s^2."""
    return {"g": 1.0, "mg": 1e-3, "mps2": 1.0 / gravity_mps2, "mmps2": 1e-3 / gravity_mps2}[unit]


def split_lsb(text: Any) -> tuple[str, str | None]:
    """An LSB's number and its unit suffix (one of LSB_SUFFIXES, else None): "1mg" -> ("1", "mg"),
    "0.0048 mps2" -> ("0.0048", "mps2"), "0.001" -> ("0.001", None)."""
    m = re.fullmatch(rf"\s*([0-9.eE+-]+?)\s*({'|'.join(LSB_SUFFIXES)})?\s*", str(text), flags=re.IGNORECASE)
    if m is None:
        return str(text), None
    return m.group(1), None if m.group(2) is None else m.group(2).lower()


def parse_bits(text: Any, fail: Callable[[str], Exception], what: str) -> int:
    """An ADC's bits (2..32) from ``text``; else ``fail`` (an exception class taking the
    message) naming ``what`` (the option or comment)."""
    try:
        b = int(str(text).strip())
    except ValueError:
        b = 0
    if not 2 <= b <= 32:
        raise fail(f"{what} {text!r}: expected an integer 2..32 (the ADC's bits)")
    return b


def scale_from_options(units: str | None = None, lsb: Any = None, full_scale_g: Any = None, bits: Any = 16,
                       gravity_mps2: Any = None, *, names: dict[str, str] | None = None) -> Scale | None:
    """The Scale stated on the command line (or by keyword), or None when nothing is stated.

    Parameters
    ----------
    units : {"counts", "mps2", "g"}, optional
        Unit of the readings in the file.  Default: ``counts`` unless an ``lsb`` is given
        (then it must be stated).
    lsb : float or str, optional
        One count in ``units``, or with a unit suffix (LSB_SUFFIXES: "1mg", "0.001g",
        "0.0048mps2"): needed with ``units`` "counts" (integer readings already in counts whose
        count's size is known: it sets the nominal scale and converts nothing), converted to
        ``units`` otherwise.
    full_scale_g : float, optional
        The range's full scale in g (``16`` for +-16 g): one count is
        ``2 * full_scale_g / 2**bits`` g.  Exclusive with ``lsb``.
    bits : int
        The ADC's bits for ``full_scale_g`` (default 16).
    gravity_mps2 : float, optional
        g in m/s^2 to turn a full scale in g into an LSB in m/s^2 (default 9.80665).
    names : dict, optional
        How the parameters are spelt in messages (default: the command line's options,
        :data:`OPTION_NAMES`).

    Raises
    ------
    AccelcalError
        A value that is not a positive number, or options that contradict each other.
    """
    spelt = OPTION_NAMES if names is None else names
    opt = spelt.__getitem__

    def fail(msg: str) -> AccelcalError:
        return AccelcalError(msg)

    if units is not None and units not in UNITS:
        raise fail(f"{opt('units')} {units!r}: expected one of {', '.join(UNITS)}")
    if lsb is None and full_scale_g is None:
        if units in (None, "counts"):
            return None
        raise fail(f"{opt('units')} {units}: state the size of one count with {opt('lsb')} VALUE "
                   f"(in {UNIT_TEXT[units]}) or {opt('full_scale_g')} G")
    if lsb is not None and full_scale_g is not None:
        raise fail(f"{opt('lsb')} and {opt('full_scale_g')} both given: state the count's size once")
    g = STANDARD_GRAVITY if gravity_mps2 is None else _positive(gravity_mps2, opt("gravity_mps2"), fail)
    if lsb is not None:
        num, unit = split_lsb(lsb)
        v = _positive(num, opt("lsb"), fail)
        if units is None:       # in the unit the file states (in_file_unit), else refused there
            in_g = None if unit is None else v * g_per(unit, g)
            return Scale("counts", v if unit is None else None, in_g, opt("lsb"), unit_stated=False,
                         gravity_mps2=g)
        if units == "counts" and unit is None:
            raise fail(f"{opt('lsb')} {lsb} with {opt('units')} counts: give one count's size with its unit "
                       f"({opt('lsb')} {num}g, or in mg or mps2); the readings stay the integers they are")
        if unit is not None and unit != units:
            in_g = v * g_per(unit, g)
            if units == "counts":
                return Scale("counts", None, in_g, opt("lsb"))
            v = in_g / g_per(units, g)
        return Scale(units, v, v * g_per(units, g), opt("lsb"))
    fs = _positive(full_scale_g, opt("full_scale_g"), fail)
    lsb_g = 2.0 * fs / 2.0 ** parse_bits(bits, fail, opt("bits"))
    stated, units = units is not None, units or "counts"
    return Scale(units, None if units == "counts" else lsb_g / g_per(units, g), lsb_g,
                 opt("full_scale_g"), unit_stated=stated, gravity_mps2=g)


def stated_scale(units: str | None = None, lsb: Any = None, full_scale_g: Any = None, bits: Any = 16,
                 gravity_mps2: Any = None, rounds: bool = False) -> Scale | None:
    """The Scale the unit options state, the command line's and the API's alike
    (:func:`scale_from_options`), with ``rounds`` (``--round``: readings in m/s^2 or g rounded
    to the nearest LSB); an explicit ``units="counts"`` alone is :data:`COUNTS_STATED`
    (converts nothing, but contradicts a file whose comments say m/s^2 or g); None when
    nothing is stated.

    Raises
    ------
    AccelcalError
        A bad value, options that contradict each other, or ``rounds`` without an LSB or with
        counts (one line naming the option).
    """
    scale = scale_from_options(units, lsb, full_scale_g, bits, gravity_mps2)
    if rounds:
        # --full-scale without --units: the unit is the file's (a table's names, a '# units:' comment),
        # weighed by file_scale, which refuses --round where it stays counts
        r, u = OPTION_NAMES["round"], OPTION_NAMES["units"]
        if scale is None:
            raise AccelcalError(f"{r}: it rounds readings in m/s^2 or g to their LSB; state the LSB with "
                                f"{OPTION_NAMES['lsb']} VALUE (and {u} mps2|g) or {OPTION_NAMES['full_scale_g']} G")
        if units == "counts":
            raise AccelcalError(f"{r} with {u} counts: readings in counts are integers, nothing to round "
                                f"(readings in m/s^2 or g: {u} mps2|g)")
        scale = dataclasses.replace(scale, rounds=True)
    if scale is None and units == "counts":
        return COUNTS_STATED
    return scale


def unstated_lsb(option: Scale) -> str:
    """The refusal of ``--lsb`` without ``--units`` over a file that states no unit."""
    num = f"{option.lsb:.12g}" if option.lsb else f"{option.lsb_g:.12g}g"
    return (f"{option.how} {num}: state the unit of the readings it divides with {OPTION_NAMES['units']} mps2|g "
            "(or by the file: a '# units:' comment, the columns' names); for integer readings already in counts, "
            f"{OPTION_NAMES['units']} counts with one count's size and its unit ({option.how} {num.rstrip('g')}g, "
            f"or in mg or mps2) or {OPTION_NAMES['full_scale_g']}")


def in_file_unit(option: Scale | None, unit: str | None, source: str) -> Scale | None:
    """``option`` in the unit the file states where the options stated none (``--full-scale``
    or ``--lsb`` without ``--units``: ``option.unit_stated`` False): one count is then its
    ``lsb_g`` (or the bare ``--lsb`` value) in ``unit``, the file's ``# units:`` comment or its
    columns' names.  Else ``option`` unchanged.

    Raises
    ------
    InputError
        ``--lsb`` without ``--units`` over a file whose unit is not m/s^2 or g
        (:func:`unstated_lsb`).
    """
    if option is None or option.unit_stated:
        return option
    if unit in ("mps2", "mmps2", "g", "mg"):
        per = g_per(unit, option.gravity_mps2)
        if option.lsb:                      # a bare --lsb: in the file's unit
            lsb, lsb_g = option.lsb, option.lsb * per
        else:
            lsb, lsb_g = option.lsb_g / per, option.lsb_g
        how = f"{option.how} in the file's {UNIT_TEXT[unit]}"
        return dataclasses.replace(option, units=unit, lsb=lsb, lsb_g=lsb_g, how=how)
    if option.how == OPTION_NAMES["lsb"]:
        raise InputError(source, unstated_lsb(option))
    return option


def scale_from_metadata(metadata: dict[str, str], lines: dict[str, int], source: str) -> Scale | None:
    """The Scale a recording's ``# units:``, ``# lsb:`` (or ``# full_scale_g:``, ``# bits:``,
    ``# gravity_mps2:``) comments state, or None when they state none.

    Raises
    ------
    InputError
        A bad or contradictory value, naming the comment's line.
    """
    given = {k: metadata[k] for k in METADATA_KEYS if k in metadata}
    if not given or set(given) == {"gravity_mps2"}:
        return None
    if "lsb" in given and "units" not in given:     # a comment's lsb has no file unit to take (in_file_unit)
        n, (lsb, units, fs) = split_lsb(given["lsb"])[0], (METADATA_NAMES[k] for k in ("lsb", "units", "full_scale_g"))
        raise InputError(source, f"{lsb} {given['lsb']}: state the unit of the readings it divides with {units} "
                         f"mps2|g; for integer readings already in counts, {units} counts with one count's size and its "
                         f"unit ({lsb} {n}g, or in mg or mps2) or {fs}", row=lines.get("lsb"))
    try:
        scale = scale_from_options(given.get("units"), given.get("lsb"), given.get("full_scale_g"),
                                   given.get("bits", 16), given.get("gravity_mps2"), names=METADATA_NAMES)
    except AccelcalError as e:
        key = next((k for k in METADATA_KEYS if str(e).startswith(METADATA_NAMES[k])), next(iter(given)))
        raise InputError(source, str(e), row=lines.get(key)) from None
    if scale is None:
        return None
    key = "lsb" if "lsb" in given else "full_scale_g"
    return Scale(scale.units, scale.lsb, scale.lsb_g, f"{METADATA_NAMES[key]} (row {lines.get(key)})")


COUNTS_STATED = Scale("counts", None, None, "--units counts")
"""An explicit ``--units counts`` without a count size: converts nothing, but a file whose
comments say m/s^2 or g contradicts it (:func:`file_scale`)."""


def _same_size(a: float | None, b: float | None) -> bool:
    return a is None or b is None or abs(a - b) <= REL_TOL * max(abs(a), abs(b))


def _size(scale: Scale) -> str:
    if scale.converts:
        return f"one count = {scale.lsb:.12g} {UNIT_TEXT[scale.units]}"
    return f"one count = {scale.lsb_g:.12g} g" if scale.lsb_g else "counts of unstated size"


def file_scale(option: Scale | None, metadata: dict[str, str], lines: dict[str, int],
               source: str, unit_source: str | None = None) -> Scale | None:
    """The Scale of a file's readings from what the caller states and the file's comments.

    The one rule for every reader (``read_recording``, so every command, and
    ``accelcal convert``): without ``option`` the comments decide
    (:func:`scale_from_metadata`); with it, a comment that states something else -- a
    ``# units:`` other than the option's unit, a ``# lsb:`` or ``# full_scale_g:`` (with
    ``# bits:``, ``# gravity_mps2:``) giving another count size (beyond :data:`REL_TOL`)
    -- is an error naming the comment's line, and comments that agree (or state nothing)
    leave the option's Scale.  A size comment without ``# units:`` is read in the option's
    unit.

    Parameters
    ----------
    option : Scale or None
        Stated by options (:func:`scale_from_options`, or :data:`COUNTS_STATED`).
    metadata, lines : dict
        The file's ``# key: value`` comments and the line of each.
    source : str
        The file, for messages.
    unit_source : str, optional
        What states ``metadata["units"]`` when it is not a comment (``accelcal convert``'s
        table: the axis columns' names), for the message of a contradiction.

    Returns
    -------
    Scale or None
        None: the readings are counts, and nothing states their size.

    Raises
    ------
    InputError
        A bad comment, or one that contradicts the option (naming its line); ``--round``
        (``option.rounds``) where the readings stay counts (:data:`ROUNDS_COUNTS`).
    """
    scale = _weighed(option, metadata, lines, source, unit_source)
    if option is not None and option.rounds and not (scale is not None and scale.converts):
        raise InputError(source, ROUNDS_COUNTS)
    return scale


ROUNDS_COUNTS = ("--round: the readings are counts (no unit of m/s^2 or g is stated: not by --units, a '# units:' "
                 "comment nor a table's column names), integers with nothing to round; for readings in m/s^2 or g "
                 "state the unit with --units mps2|g")
"""The refusal of ``--round`` (with ``--full-scale`` alone) over a file whose readings stay counts."""


def _weighed(option: Scale | None, metadata: dict[str, str], lines: dict[str, int], source: str,
             unit_source: str | None) -> Scale | None:
    """:func:`file_scale` before its check of ``--round``."""
    if option is None:
        return scale_from_metadata(metadata, lines, source)
    unit = metadata.get("units")
    option = in_file_unit(option, unit, source)
    by = option.how or "the option"
    if unit is not None and unit in UNITS and unit != option.units:
        with_ = "" if by.startswith(OPTION_NAMES["units"]) else f", with {by}"
        what = unit_source or f"the comment '# units: {unit}'"
        raise InputError(source, f"{what} contradicts the options' unit, "
                         f"{UNIT_TEXT[option.units]} ({OPTION_NAMES['units']} {option.units}{with_}): state the "
                         f"unit once, by the options or by the {'file' if unit_source else 'comments'}",
                         row=lines.get("units"))
    if not any(k in metadata for k in ("lsb", "full_scale_g")):
        if unit is not None and unit not in UNITS:
            scale_from_metadata(metadata, lines, source)  # the comment's own error
        return option
    stated = scale_from_metadata({"units": option.units, **metadata}, lines, source)
    if stated is None:
        return option
    key = "lsb" if "lsb" in metadata else "full_scale_g"
    same = _same_size(stated.lsb, option.lsb) if option.converts else _same_size(stated.lsb_g, option.lsb_g)
    if not same:
        raise InputError(source, f"the comment '# {key}: {metadata[key]}' ({_size(stated)}) contradicts "
                         f"{by} ({_size(option)}): state the count's size once, by the options or by the "
                         "comments", row=lines.get(key))
    return option


def converted_metadata(metadata: dict[str, str], scale: Scale) -> dict[str, str]:
    """The metadata of readings now in counts: each ``units``/``lsb``/... key renamed
    ``source_<key>`` (so the file written from them is not converted twice), and
    ``source_scale`` saying what the readings were."""
    out = {(f"source_{k}" if k in METADATA_KEYS else k): v for k, v in metadata.items()}
    out["source_scale"] = scale.describe()
    return out
