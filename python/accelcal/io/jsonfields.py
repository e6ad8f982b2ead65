"""JSON documents of the data contract (device, calibration): strict parsing (no NaN or
Infinity, duplicate keys and non-finite numbers found), and :class:`JsonFields`, the
validator whose every failure is an :class:`~accelcal.errors.InputError` naming the file
and the field (misspelt keys named with the closest valid one)."""
from __future__ import annotations

import difflib
import json
import math
from typing import Any, Iterable

import numpy as np

from ..errors import InputError, read_input

__all__ = ["JsonFields", "NonFinite", "read_json", "parse_json_text", "show_json", "json_number", "LIMITS",
           "check_limits", "KEY_CUTOFF", "MISSING_KEY_CUTOFF"]


class NonFinite:
    """Stand-in for a JSON NaN/Infinity token, so validation can name its field."""

    def __init__(self, token: str) -> None:
        self.token = token

    def __repr__(self) -> str:
        return self.token


class JsonObject(dict):
    """A JSON object that remembers keys given more than once."""

    duplicates: tuple[str, ...] = ()


def object_pairs(pairs: list[tuple[str, Any]]) -> JsonObject:
    obj = JsonObject()
    dups = []
    for k, v in pairs:
        if k in obj:
            dups.append(k)
        obj[k] = v
    if dups:
        obj.duplicates = tuple(dups)
    return obj


def parse_json_float(text: str) -> Any:
    value = float(text)
    # 1e400 parses to inf: keep the literal so the message can show it.
    return value if math.isfinite(value) else NonFinite(text)


def read_json(path: Any) -> tuple[Any, str]:
    """Read and parse a JSON file; returns (document, source name)."""
    source, data = read_input(path)
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        raise InputError(source, f"line {line}: not valid UTF-8 (byte {e.start})") from None
    return parse_json_text(text, source), source


def parse_json_text(text: str, source: str) -> Any:
    if not text.strip():
        raise InputError(source, "the file is empty (expected a JSON object)")
    try:
        return json.loads(
            text,
            parse_constant=NonFinite,
            parse_float=parse_json_float,
            object_pairs_hook=object_pairs,
        )
    except json.JSONDecodeError as e:
        raise InputError(
            source, f"not valid JSON at line {e.lineno}, column {e.colno}: {e.msg}"
        ) from None
    except (ValueError, RecursionError) as e:  # e.g. integer too long to convert
        raise InputError(source, f"not valid JSON: {e}") from None


def show_json(value: Any) -> str:
    """Short JSON-like rendering of a value for an error message."""
    if isinstance(value, NonFinite):
        return value.token
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    try:
        text = json.dumps(value)
    except (TypeError, ValueError):
        text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


KEY_CUTOFF = 0.8  # difflib similarity above which an unknown JSON key is taken for a misspelling


MISSING_KEY_CUTOFF = 0.6  # ... and, when a required key is missing, above which a key present is named


class JsonFields:
    """Validator for one JSON document: every failure is an InputError with
    the document's source and the field path."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.known_keys: dict[int, list[str]] = {}  # id(object) -> its valid keys (see known())

    def fail(self, path: str, message: str) -> InputError:
        if not path:
            return InputError(self.source, message)
        return InputError(self.source, message, field=path)

    def obj(self, value: Any, path: str) -> dict:
        if not isinstance(value, dict):
            where = "" if path else " at the top level"
            raise self.fail(path, f"expected a JSON object{where}, got {show_json(value)}")
        dups = getattr(value, "duplicates", ())
        if dups:
            where = f"{path}.{dups[0]}" if path else dups[0]
            raise self.fail(where, "given more than once")
        return value

    def get(self, obj: dict, key: str, path: str, *, required: bool = True) -> Any:
        sub = f"{path}.{key}" if path else key
        if key not in obj:
            if required:
                valid = self.known_keys.get(id(obj), ())
                near = difflib.get_close_matches(key, [k for k in obj if isinstance(k, str) and k not in valid],
                                                 n=1, cutoff=MISSING_KEY_CUTOFF)
                hint = f"; the object has {near[0]!r}: did you mean {key!r}?" if near else ""
                raise self.fail(sub, f"missing (required){hint}")
            return None
        return obj[key]

    def known(self, obj: dict, path: str, keys: Iterable[str]) -> None:
        """Refuse a key that is not one of ``keys`` but close to one (a misspelling).

        Keys far from every known one are extensions and pass (the contract lets a
        file carry fields of its own); a near miss such as ``noise_mps`` for
        ``noise_mps2`` would otherwise be silently ignored.
        """
        keys = list(keys)
        self.known_keys[id(obj)] = keys
        for k in obj:
            if not isinstance(k, str) or k in keys:
                continue
            near = difflib.get_close_matches(k, keys, n=1, cutoff=KEY_CUTOFF)
            if near and near[0] not in obj:
                sub = f"{path}.{k}" if path else k
                raise self.fail(sub, f"unknown key: did you mean {near[0]!r}?")

    def number(self, value: Any, path: str, *, what: str = "a number") -> float:
        if isinstance(value, NonFinite):
            raise self.fail(path, f"expected a finite number, got {value.token}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(path, f"expected {what}, got {show_json(value)}")
        try:
            out = float(value)
        except OverflowError:
            raise self.fail(path, f"expected a finite number, got {show_json(value)}") from None
        if not math.isfinite(out):
            raise self.fail(path, f"expected a finite number, got {show_json(value)}")
        return out

    def integer(self, value: Any, path: str) -> int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        x = self.number(value, path, what="an integer")
        if x != math.floor(x):
            raise self.fail(path, f"expected an integer, got {show_json(value)}")
        return int(x)

    def string(self, value: Any, path: str) -> str:
        if not isinstance(value, str):
            raise self.fail(path, f"expected a string, got {show_json(value)}")
        return value

    def vector(self, value: Any, path: str, n: int = 3) -> np.ndarray:
        if not isinstance(value, list) or len(value) != n:
            got = f"{len(value)}" if isinstance(value, list) else show_json(value)
            raise self.fail(path, f"expected {n} numbers, got {got}")
        return np.array([self.number(v, f"{path}[{i}]") for i, v in enumerate(value)])

    def no_nonfinite(self, value: Any, path: str) -> None:
        """Reject NaN/Infinity anywhere below ``value`` (also in unknown fields)."""
        if isinstance(value, NonFinite):
            raise self.fail(path, f"expected a finite number, got {value.token}")
        if isinstance(value, dict):
            self.obj(value, path)  # duplicate keys
            for k, v in value.items():
                self.no_nonfinite(v, f"{path}.{k}" if path else k)
        elif isinstance(value, list):
            for i, v in enumerate(value):
                self.no_nonfinite(v, f"{path}[{i}]")


def json_number(x: float) -> int | float:
    """Integral values as JSON integers (readable files), others as floats."""
    x = float(x)
    if x.is_integer() and abs(x) < 2**53:
        return int(x)
    return x


# The ranges a file may use.  Far wider than any real sensor, they keep absurd values
# (1e300 m, 1e30 Hz) out of the numerics, where they would overflow or underflow and
# surface as a numerical failure instead of a message that names the field.
LIMITS = {
    "sample_rate_hz": (1e-3, 1e6, "Hz"),
    "gravity_mps2": (1e-2, 1e3, "m/s^2"),
    "noise_mps2": (0.0, 1e3, "m/s^2"),
    "position_m": (-1e3, 1e3, "m"),
    "counts_per_mps2": (1e-6, 1e9, "counts per m/s^2"),
    "raw": (-(2.0**53), 2.0**53, "counts"),
    "sensitivity": (-1e9, 1e9, "counts per m/s^2"),
    "offset_counts": (-(2.0**53), 2.0**53, "counts"),
}


def check_limits(fields: Any, field: str, value: Any, kind: str) -> None:
    """Raise the field's InputError when value (scalar or vector) leaves LIMITS[kind]."""
    lo, hi, unit = LIMITS[kind]
    a = np.atleast_1d(np.asarray(value, float))
    if np.any(a < lo) or np.any(a > hi):
        raise fields.fail(field, f"expected values in [{lo:g}, {hi:g}] {unit}, got {show_json(value)}")
