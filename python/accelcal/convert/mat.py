"""``accelcal convert``'s ``mat`` format: a MATLAB file holding the readings as a numeric
array of three columns (x, y, z) or four (t, x, y, z), in either layout MATLAB writes --
version 5 (read by :func:`scipy.io.loadmat`) or 7.3 (HDF5, read by h5py; MATLAB's column-major
arrays come out transposed there).  Told by the file's first bytes (``MATLAB 5.0 MAT-file``,
``MATLAB 7.3 MAT-file``), never by its name."""
from __future__ import annotations

import io
import os
import re
import struct
import warnings
import zlib
from typing import Any

import h5py
import numpy as np
import scipy.io

from .common import Converted, Options, finish, whole_counts
from .rows import LOST_SAMPLES, lost_rows
from ..errors import InputError, notes_on_refusal
from ..io.units import file_scale
from ..io.units_counts import to_counts

__all__ = ["MAT_MAGIC", "is_mat", "mat_arrays", "pick_array", "convert_mat"]

#: the text every MAT-file begins with (its 128-byte header), before the version
MAT_MAGIC = b"MATLAB "
#: an array of readings has this many columns (x, y, z; or t, x, y, z) and more rows than that
READING_COLUMNS = (3, 4)
#: a version-5 MAT-file's element type of a zlib-compressed element (its data: another element)
MI_COMPRESSED = 15
#: arrays named in a refusal, at most
SHAPES_LISTED = 8


def is_mat(path: Any) -> bool:
    """Whether the file at ``path`` begins with a MAT-file's header."""
    try:
        with open(os.fspath(path), "rb") as f:
            head = f.read(128)
    except (OSError, TypeError):
        return False
    return head.startswith(MAT_MAGIC) and b"MAT-file" in head[:32]


def unchecked_v5(data: bytes) -> bytes:
    """A version-5 MAT-file with each compressed element inflated without its zlib checksum
    (raw deflate): the same file, uncompressed.  MATLAB reads a file whose adler32 checks
    fail (some acquisition programs write them wrong); zlib, and so scipy, refuses it.

    Raises
    ------
    ValueError
        An element that runs past the end of the file, or data that do not inflate.
    """
    order = "<" if data[126:128] == b"IM" else ">"
    out, pos = [data[:128]], 128
    while pos + 8 <= len(data):
        kind, size = struct.unpack(order + "II", data[pos:pos + 8])
        if kind >> 16:                      # a small element: its data in the tag's 8 bytes
            out.append(data[pos:pos + 8])
            pos += 8
            continue
        if pos + 8 + size > len(data):
            raise ValueError(f"an element of {size} bytes at byte {pos} runs past the end of the file")
        if kind == MI_COMPRESSED:
            try:
                out.append(zlib.decompressobj(-zlib.MAX_WBITS).decompress(data[pos + 10:pos + 8 + size]))
            except zlib.error as e:
                raise ValueError(f"the compressed element at byte {pos} does not inflate ({e})") from None
            pos += 8 + size
        else:
            end = pos + 8 + size + (-size) % 8
            out.append(data[pos:end])
            pos = end
    return b"".join(out)


def mat_arrays(path: Any, source: str, notes: list[str] | None = None) -> dict[str, np.ndarray]:
    """Every real numeric 2-D array of a MAT-file by its name (nested HDF5 groups as
    ``group/name``), oriented as MATLAB shows it.  A version-5 file whose compressed
    elements fail their zlib checksum is read as MATLAB reads it (:func:`unchecked_v5`),
    with a note appended to ``notes``.  The readers' warnings (scipy's MatReadWarning: a
    variable name repeated in the file) are caught and each said once as a note
    (:func:`reader_notes`), never printed.

    Raises
    ------
    InputError
        A damaged file, or one neither reader takes (naming the reason).
    """
    with open(os.fspath(path), "rb") as f:
        head = f.read(128)
    out: dict[str, np.ndarray] = {}

    def take_v5(arrays: dict) -> None:
        for name, v in arrays.items():
            if not name.startswith("__") and isinstance(v, np.ndarray) and v.ndim == 2 and v.dtype.kind in "iuf":
                out[name] = v.astype(float)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_arrays(path, source, head, take_v5, out, notes)
    if notes is not None:
        notes.extend(reader_notes(caught, out))
    return out


def reader_notes(caught: list[warnings.WarningMessage], arrays: dict[str, np.ndarray]) -> list[str]:
    """A note for each distinct warning the MATLAB readers gave (its first line; scipy's
    second line advises splitting the file, which accelcal need not): a name repeated in the
    file only where it is one of the numeric ``arrays`` (the readings may be either; scipy
    names MATLAB's unnamed objects 'None', which is nothing accelcal reads)."""
    seen: list[str] = []
    for w in caught:
        first = str(w.message).strip().splitlines()[0] if str(w.message).strip() else w.category.__name__
        if first not in seen:
            seen.append(first)
    out = []
    for first in seen:
        dup = re.fullmatch(r'Duplicate variable name "(.*)" in stream.*', first)
        if dup is None:
            out.append(f"the MATLAB reader warns: {first}")
        elif dup.group(1) in arrays:
            out.append(f"the file holds more than one variable named {dup.group(1)!r}: the last of them is read")
    return out


def read_arrays(path: Any, source: str, head: bytes, take_v5, out: dict[str, np.ndarray],
                notes: list[str] | None) -> None:
    """Read the file's arrays into ``out`` (:func:`mat_arrays`, which catches the warnings)."""
    try:
        if b"MATLAB 7.3" in head[:20]:
            with h5py.File(os.fspath(path), "r") as h5:
                def take(name: str, obj: Any) -> None:
                    if isinstance(obj, h5py.Dataset) and obj.ndim == 2 and obj.dtype.kind in "iuf":
                        out[name] = np.asarray(obj[()], dtype=float).T     # HDF5 holds MATLAB's transpose
                h5.visititems(take)
        else:
            try:
                take_v5(scipy.io.loadmat(os.fspath(path)))
            except zlib.error as e:
                with open(os.fspath(path), "rb") as f:
                    take_v5(scipy.io.loadmat(io.BytesIO(unchecked_v5(f.read()))))
                if notes is not None:
                    notes.append(f"the file's compressed data fail their zlib checksum ({e}); read without it, "
                                 "as MATLAB reads them")
    except (OSError, ValueError, TypeError, NotImplementedError, zlib.error) as e:
        raise InputError(source, f"cannot read the MATLAB file: {e}") from None


def pick_array(arrays: dict[str, np.ndarray], variable: str | None, source: str) -> tuple[str, np.ndarray]:
    """The array of readings, as (name, an (n, 3 or 4) array): the one named ``variable``, or
    the only array with 3 or 4 columns (or rows: taken transposed) and more samples than that,
    4 only where the first increases (:func:`increases`: time stamps).

    Raises
    ------
    InputError
        No such array, the named one missing or not of that shape, or several (naming them:
        ``--variable NAME`` picks one).
    """
    def oriented(a: np.ndarray) -> np.ndarray | None:
        if a.shape[1] in READING_COLUMNS and a.shape[0] > a.shape[1]:
            return a
        if a.shape[0] in READING_COLUMNS and a.shape[1] > a.shape[0]:
            return a.T
        return None

    listed = [f"{k} {v.shape[0]}x{v.shape[1]}" for k, v in arrays.items()]
    shapes = ", ".join(listed[:SHAPES_LISTED]) + (f" and {len(listed) - SHAPES_LISTED} more" if
                                                   len(listed) > SHAPES_LISTED else "") or "none"
    vectors = sum(min(v.shape) == 1 for v in arrays.values())
    if variable is not None and "," in variable:
        return variable, vectors_array(arrays, [v.strip() for v in variable.split(",")], source, shapes)
    if variable is not None:
        if variable not in arrays:
            raise InputError(source, f"--variable {variable}: no such numeric 2-D array (the file has: {shapes})")
        a = oriented(arrays[variable])
        if a is None:
            raise InputError(source, f"--variable {variable}: {arrays[variable].shape[0]}x{arrays[variable].shape[1]}; "
                             "expected 3 columns (x, y, z) or 4 (t, x, y, z) of samples")
        return variable, a
    # a first column that is no time (not increasing: ABB's 4xN quaternion) makes no t, x, y, z candidate
    found = {k: a for k, v in arrays.items()
             if (a := oriented(v)) is not None and (a.shape[1] == 3 or increases(a[:, 0]))}
    if len(found) != 1:
        what = "no array" if not found else f"{len(found)} arrays ({', '.join(found)})"
        raise InputError(source, f"{what} of 3 columns (x, y, z) or 4 (t, x, y, z) among the file's numeric arrays "
                         f"({shapes}): give --variable NAME" + (", or --variable X,Y,Z (T,X,Y,Z) for readings held "
                                                                 "one vector per channel" if vectors >= 3 else ""))
    return next(iter(found.items()))


def increases(t: np.ndarray) -> bool:
    """Whether ``t``'s finite values never decrease and end above where they start: time stamps
    (a repeated one is refused later, naming its row; a lost sample's NaN aside), not a
    quaternion's w, which turns back."""
    v = t[np.isfinite(t)]
    return v.size > 1 and bool(np.all(np.diff(v) >= 0)) and v[-1] > v[0]


def vectors_array(arrays: dict[str, np.ndarray], names: list[str], source: str, shapes: str) -> np.ndarray:
    """The readings held one vector per channel (a data-acquisition program's export): the
    vectors ``names`` (x, y, z, or t, x, y, z) side by side, as an (n, 3 or 4) array.

    Raises
    ------
    InputError
        Not 3 or 4 names, a name not in the file, an array that is no vector, or vectors of
        different lengths.
    """
    if len(names) not in READING_COLUMNS:
        raise InputError(source, f"--variable {','.join(names)}: {len(names)} names; expected 3 vectors (x, y, z) or "
                         "4 (t, x, y, z)")
    cols = []
    for n in names:
        if n not in arrays:
            raise InputError(source, f"--variable: no numeric array {n!r} (the file has: {shapes})")
        if min(arrays[n].shape) != 1:
            raise InputError(source, f"--variable: {n} is {arrays[n].shape[0]}x{arrays[n].shape[1]}; expected a vector "
                             "(one channel)")
        cols.append(arrays[n].ravel())
    if len({c.size for c in cols}) != 1:
        raise InputError(source, "--variable: the vectors differ in length (" +
                         ", ".join(f"{n} {c.size}" for n, c in zip(names, cols)) + ")")
    return np.column_stack(cols)


def convert_mat(source: str, path: Any, opts: Options, variable: str | None = None) -> Converted:
    """A MAT-file's readings (:func:`pick_array`): three columns x, y, z (``--rate`` gives the
    rate) or four t, x, y, z (t as a time column: ``--time-unit``, or read in ms/us/ns where
    seconds would give under 2 Hz), in counts or in the unit ``opts.scale`` states.  A row whose
    readings are all NaN is a sample the logger lost: left out with a note, the rows after
    keeping their places (:func:`convert_rows.lost_rows`); one with some NaN is refused."""
    notes: list[str] = []
    with notes_on_refusal(lambda: notes):       # a refusal after a note: it goes with it
        name, a = pick_array(mat_arrays(path, source, notes), variable, source)
        timed = a.shape[1] == 4
        first = 1 if timed else 0
        readings = a[:, first:]
        vectors = name.split(",") if "," in name else None

        def col(j: int) -> str:
            return vectors[j] if vectors else f"{name}(:,{j + 1})"        # as MATLAB names them (1-based)

        column = [col(j + first) for j in range(3)]

        keep = lost_rows(source, readings, lambda i: i + 1, lambda j: column[j],
                         lambda i, j: repr(float(readings[i, j])), notes, LOST_SAMPLES)
        bad = np.argwhere(~np.isfinite(a[keep]))
        if bad.size:
            i, j = int(keep[bad[0][0]]), int(bad[0][1])
            raise InputError(source, f"{float(a[i, j])} is not a finite number", row=i + 1, column=col(j))
        a, readings = a[keep], readings[keep]

        def locate(i: int, j: int) -> tuple[int, str]:
            return int(keep[i]) + 1, column[j]

        t = None
        if timed:
            t = a[:, 0]
            back = np.flatnonzero(np.diff(t) <= 0)
            if back.size:
                i = int(back[0]) + 1
                raise InputError(source, f"t = {float(t[i]):.10g} is not after {float(t[i - 1]):.10g}: the first column "
                                 "is taken as time stamps, which must increase (--variable names another array)",
                                 row=int(keep[i]) + 1, column=col(0))
        elif opts.rate_hz is None:
            raise InputError(source, f"array {name} has no time column (3 columns): give the sample rate with --rate HZ")
        elif opts.time_unit != "auto":
            raise InputError(source, f"--time-unit: array {name} has no time column (3 columns; --rate states its rate)")
        scale = file_scale(opts.scale, {}, {}, source)
        converts = scale is not None and scale.converts
        raw = to_counts(readings, scale, source, locate, notes=notes) if converts else \
            whole_counts(readings, source, locate)
        return finish(source, "mat", raw, keep, t, None, opts, scale, converts or bool(np.any(raw < 0)),
                      opts.rate_hz, {"mat.variable": name}, notes, locate, None)
