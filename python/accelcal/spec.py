"""Spec strings: the small language of ``--effect`` and ``--motion`` arguments.

``NAME[:k=v,k=v,...]``; values are numbers, words (``x``, ``-z``, ``random``, ``all``)
or bracketed lists (``db=[10,20,0,0,0,0]``, ``toward=[0,1,1]``; commas inside
brackets do not split parameters); ``;`` or ``|`` also separate list items
(``channel=0;2``).  :class:`Param` declares one parameter (default, unit, doc, kind)
and coerces a user's value; :func:`check_params` checks a whole set.  Errors are
:class:`~accelcal.errors.AccelcalError` with one line naming the owner and parameter.
"""
from __future__ import annotations

import difflib
import math
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from .errors import AccelcalError

__all__ = ["Param", "parse_spec", "format_spec", "check_params", "with_defaults", "show_value", "BadValue"]


def _split_top(text: str, seps: str = ",") -> list[str]:
    """Split at separators that are not inside [...]; raises on unbalanced brackets."""
    parts, depth, cur = [], 0, []
    for ch in text:
        if ch == "[":
            depth += 1
        elif ch == "]":
            depth -= 1
            if depth < 0:
                raise ValueError("unbalanced ']'")
        if ch in seps and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    if depth != 0:
        raise ValueError("unbalanced '['")
    parts.append("".join(cur))
    return parts


def _parse_value(text: str) -> Any:
    """A spec value: a string, or a (nested) list of strings from [a,b] or a;b / a|b."""
    s = text.strip()
    if s.startswith("[") and s.endswith("]"):
        inner = s[1:-1].strip()
        if not inner:
            return []
        return [_parse_value(p) for p in _split_top(inner, ",;|")]
    if ("[" in s) or ("]" in s):
        raise ValueError(f"misplaced bracket in {s!r}")
    if ";" in s or "|" in s:
        return [p.strip() for p in s.replace("|", ";").split(";")]
    return s


def parse_spec(text: str, what: str = "effect") -> tuple[str, dict[str, Any]]:
    """Split ``NAME[:k=v,...]`` into (name, {k: raw value}); values stay strings
    or lists of strings (coercion is the registry's job).  Raises AccelcalError."""
    if not isinstance(text, str):
        raise AccelcalError(f"{what} spec: expected a string like NAME[:k=v,...], got {text!r}")
    s = text.strip()
    if not s:
        raise AccelcalError(f"{what} spec is empty (expected NAME[:k=v,...])")
    name, sep, rest = s.partition(":")
    name = name.strip()
    if not name:
        raise AccelcalError(f"{what} spec {s!r}: the name before ':' is missing")
    params: dict[str, Any] = {}
    if sep and not rest.strip():
        raise AccelcalError(f"{what} spec {s!r}: nothing after ':' (expected k=v,...)")
    if rest.strip():
        try:
            items = _split_top(rest, ",")
        except ValueError as e:
            raise AccelcalError(f"{what} spec {s!r}: {e}") from None
        for item in items:
            if not item.strip():
                raise AccelcalError(f"{what} spec {s!r}: empty parameter (stray ',')")
            k, eq, v = item.partition("=")
            k = k.strip()
            if not eq or not k:
                raise AccelcalError(f"{what} spec {s!r}: expected k=v, got {item.strip()!r}")
            if k in params:
                raise AccelcalError(f"{what} spec {s!r}: parameter {k!r} given more than once")
            if not v.strip():
                raise AccelcalError(f"{what} spec {s!r}: parameter {k!r} has no value")
            try:
                params[k] = _parse_value(v)
            except ValueError as e:
                raise AccelcalError(f"{what} spec {s!r}: parameter {k!r}: {e}") from None
    return name, params


_AXIS_WORDS = {
    "x": (1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
}


def _axis_word(s: str) -> np.ndarray | None:
    w = s.strip().lower()
    sign = 1.0
    if w and w[0] in "+-":
        sign = -1.0 if w[0] == "-" else 1.0
        w = w[1:]
    if w in _AXIS_WORDS:
        return sign * np.array(_AXIS_WORDS[w])
    return None


def show_value(v: Any) -> str:
    if isinstance(v, np.ndarray):
        v = v.tolist()
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."


@dataclass(frozen=True)
class Param:
    """One user-facing parameter of an effect or a motion.

    ``kind`` says what values it takes:

    - ``float`` / ``int`` / ``bool`` / ``str``: one value;
    - ``floats``: one number or a per-channel list;
    - ``choice``: one of ``choices``;
    - ``direction``: a unit vector: an axis word (``x``, ``-z``) or 3 numbers
      (normalised); ``direction_or_random`` also takes ``random``;
    - ``vector``: 3 numbers (not normalised);
    - ``channels``: ``all``, one index or a list of indices;
    - ``poses``: a preset name/count (``4``, ``6``, ``18``, ``24``, ``26``)
      or a list of directions (each an axis word or 3 numbers).

    ``default`` None means "derived" (the doc says from what).
    """

    name: str
    default: Any
    unit: str
    doc: str
    kind: str = "float"
    choices: tuple = ()
    minimum: float | None = None
    maximum: float | None = None
    exclusive_min: bool = False

    def help(self) -> str:
        d = self.default
        if d is None:
            dtext = "auto"
        elif isinstance(d, bool):
            dtext = "1" if d else "0"
        elif isinstance(d, (list, tuple, np.ndarray)):
            dtext = "[" + ",".join(str(x) for x in np.asarray(d).tolist()) + "]"
        else:
            dtext = str(d)
        unit = f" {self.unit}" if self.unit and self.unit != "-" else ""
        return f"{self.name}={dtext}{unit}: {self.doc}"

    # -- coercion ---------------------------------------------------------

    def coerce(self, value: Any, owner: str) -> Any:
        """Check and convert ``value`` (a Python value or a spec string);
        raises AccelcalError naming ``owner`` and the parameter."""
        if value is None:
            return None
        try:
            out = getattr(self, "_as_" + self.kind)(value)
        except BadValue as e:
            raise AccelcalError(f"{owner} parameter {self.name!r}: expected {e}, got {show_value(value)}") from None
        return out

    def _range(self, x: float) -> float:
        lo, hi = self.minimum, self.maximum
        if lo is not None and (x < lo or (self.exclusive_min and x == lo)):
            rel = ">" if self.exclusive_min else ">="
            raise BadValue(f"a number {rel} {lo:g}")
        if hi is not None and x > hi:
            raise BadValue(f"a number <= {hi:g}")
        return x

    @staticmethod
    def _num(v: Any, what: str = "a finite number") -> float:
        if isinstance(v, (bool, np.bool_)):
            raise BadValue(what)
        if isinstance(v, str):
            try:
                x = float(v.strip())
            except ValueError:
                raise BadValue(what) from None
        elif isinstance(v, (int, float, np.integer, np.floating)):
            x = float(v)
        else:
            raise BadValue(what)
        if not math.isfinite(x):
            raise BadValue(what)
        return x

    def _as_float(self, v: Any) -> float:
        return self._range(self._num(v))

    def _as_floats(self, v: Any) -> float | np.ndarray:
        if isinstance(v, (list, tuple, np.ndarray)):
            arr = np.asarray(v, dtype=object).ravel()
            if arr.size == 0:
                raise BadValue("a number or a per-channel list of numbers")
            try:
                return np.array([self._range(self._num(x)) for x in arr], dtype=float)
            except BadValue:
                raise BadValue("a number or a per-channel list of numbers") from None
        return self._range(self._num(v, "a number or a per-channel list of numbers"))

    def _as_int(self, v: Any) -> int:
        x = self._num(v, "an integer")
        if x != math.floor(x):
            raise BadValue("an integer")
        return int(self._range(x))

    def _as_bool(self, v: Any) -> bool:
        if isinstance(v, (bool, np.bool_)):
            return bool(v)
        if isinstance(v, (int, np.integer)) and v in (0, 1):
            return bool(v)
        if isinstance(v, str) and v.strip().lower() in ("1", "true", "yes", "on"):
            return True
        if isinstance(v, str) and v.strip().lower() in ("0", "false", "no", "off"):
            return False
        raise BadValue("0/1 (or true/false)")

    def _as_str(self, v: Any) -> str:
        if not isinstance(v, str):
            raise BadValue("a string")
        return v.strip()

    def _as_choice(self, v: Any) -> str:
        if not isinstance(v, str) or v.strip().lower() not in self.choices:
            raise BadValue("one of " + ", ".join(self.choices))
        return v.strip().lower()

    def _as_vector(self, v: Any) -> np.ndarray:
        if isinstance(v, str):
            w = _axis_word(v)
            if w is not None:
                return w
            raise BadValue("3 numbers like [0,0.1,0]")
        arr = np.asarray(v, dtype=object).ravel()
        if arr.size != 3:
            raise BadValue("3 numbers like [0,0.1,0]")
        return np.array([self._num(x, "3 numbers like [0,0.1,0]") for x in arr])

    def _as_direction(self, v: Any) -> np.ndarray:
        what = "an axis (x, y, z, -x, ...) or 3 numbers like [0,1,1]"
        if isinstance(v, str):
            w = _axis_word(v)
            if w is None:
                raise BadValue(what)
            return w
        try:
            vec = self._as_vector(v)
        except BadValue:
            raise BadValue(what) from None
        n = float(np.linalg.norm(vec))
        if not n > 1e-12 or not math.isfinite(n):
            raise BadValue("a non-zero direction")
        return vec / n

    def _as_direction_or_random(self, v: Any) -> Any:
        if isinstance(v, str) and v.strip().lower() == "random":
            return "random"
        try:
            return self._as_direction(v)
        except BadValue:
            raise BadValue("'random', an axis (x, y, z, -x, ...) or 3 numbers") from None

    def _as_channels(self, v: Any) -> tuple[int, ...] | None:
        what = "'all', a channel index or a list of indices"
        if isinstance(v, str) and v.strip().lower() == "all":
            return None
        items = list(np.asarray(v, dtype=object).ravel()) if isinstance(v, (list, tuple, np.ndarray)) else [v]
        if not items:
            raise BadValue(what)
        out = []
        for x in items:
            try:
                xf = self._num(x, what)
            except BadValue:
                raise BadValue(what) from None
            if xf != math.floor(xf) or xf < 0:
                raise BadValue(what)
            out.append(int(xf))
        return tuple(sorted(set(out)))

    def _as_poses(self, v: Any) -> Any:
        what = "a preset (4, 6, 18, 24, 26) or a list of directions like [x,y,z,-z]"
        if isinstance(v, (int, np.integer)) and not isinstance(v, bool):
            v = str(int(v))
        if isinstance(v, str):
            s = v.strip().lower()
            if s in ("4", "6", "18", "24", "26"):
                return s
            w = _axis_word(s)
            if w is not None:
                return np.array([w])
            raise BadValue(what)
        if isinstance(v, np.ndarray) and v.ndim == 2 and v.shape[1] == 3:
            items = list(v)
        elif isinstance(v, (list, tuple)):
            items = list(v)
        else:
            raise BadValue(what)
        if not items:
            raise BadValue(what)
        # A flat list of 3 numbers is one direction.
        if len(items) == 3 and all(not isinstance(x, (list, tuple, np.ndarray)) and _axis_word(str(x)) is None
                                   for x in items):
            items = [items]
        dirs = []
        for x in items:
            try:
                dirs.append(self._as_direction(x))
            except BadValue:
                raise BadValue(what) from None
        return np.array(dirs)


class BadValue(Exception):
    """Internal: a value did not fit a Param's kind (message = what was expected)."""


def check_params(params: Sequence[Param], given: Mapping[str, Any], owner: str) -> dict[str, Any]:
    """Coerce the given values, reject unknown names; returns only the given ones."""
    by_name = {p.name: p for p in params}
    out = {}
    for k, v in given.items():
        if k not in by_name:
            names = list(by_name)
            close = difflib.get_close_matches(k, names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            known = ", ".join(names) if names else "none"
            raise AccelcalError(f"{owner}: unknown parameter {k!r}{hint}; parameters: {known}")
        out[k] = by_name[k].coerce(v, owner)
    return out


def with_defaults(params: Sequence[Param], given: Mapping[str, Any]) -> dict[str, Any]:
    """Checked values plus every other parameter's (coerced) default."""
    out = {p.name: p.coerce(p.default, "default") for p in params}
    out.update(given)
    return out


def _format_value(v: Any) -> str:
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, (float, np.floating)):
        x = float(v)
        return str(int(x)) if x.is_integer() and abs(x) < 1e15 else repr(x)
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    if isinstance(v, np.ndarray) or isinstance(v, (list, tuple)):
        arr = np.asarray(v, dtype=object)
        if arr.ndim == 0:
            return _format_value(arr.item())
        return "[" + ",".join(_format_value(x) for x in arr.tolist()) + "]"
    return str(v)


def format_spec(name: str, params: Mapping[str, Any]) -> str:
    """Canonical ``NAME:k=v,...`` text (parses back to the same values)."""
    if not params:
        return name
    return name + ":" + ",".join(f"{k}={_format_value(v)}" for k, v in params.items())
