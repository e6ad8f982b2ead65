"""Pose labels for ``accelcal convert``: regions of sample numbers from a JSON session list
(imucal's), or names per sample (a ``part`` column, a log's blocks); regions named
``x_p, x_a, y_p, y_a, z_p, z_a`` (that axis up, or down) can state the reference specific
force, and regions whose name ends in ``_rot`` are motions, not poses."""
from __future__ import annotations

import re
from typing import Any

import numpy as np

from ..errors import InputError
from ..io.jsonfields import JsonFields, read_json

__all__ = ["POSE_DIRECTIONS", "POSE_COLUMN", "is_motion", "label_poses", "read_regions", "axis_label",
           "pose_column", "text_column", "table_labels", "rows_are_poses", "MEANS_RATE_HZ", "MEANS_TIME", "MEANS_HINT",
           "means_note"]

POSE_DIRECTIONS = {"x_p": (1, 0, 0), "x_a": (-1, 0, 0), "y_p": (0, 1, 0), "y_a": (0, -1, 0),
                   "z_p": (0, 0, 1), "z_a": (0, 0, -1)}
#: the contract's column of pose labels
POSE_COLUMN = "pose"
#: a pose named by an axis and its sign: ``+X UP``, ``-Z``, ``X-``, ``y down``, ``Z_UP``, imucal's ``x_p``
AXIS_LABEL_RE = re.compile(r"(?:(?P<s1>[+-])\s*(?P<a1>[xyz])|(?P<a2>[xyz])\s*(?P<s2>[+-])|(?P<a3>[xyz])(?=[\s_]*(?:up|down)))"
                           r"(?:[\s_]*(?P<ud>up|down))?|(?P<a4>[xyz])_(?P<pa>[pa])", re.I)


def read_regions(path: Any) -> list[tuple[str, int, int]]:
    """Pose regions from a JSON object ``{name: {"start": s, "end": e}, ...}``.

    Returns
    -------
    list of (name, start, end)
        In the file's order; samples ``start <= k < end``.

    Raises
    ------
    InputError
        Naming the field (``x_p.start``) that is missing, not an integer >= 0, or whose
        range is empty or overlaps another.
    """
    doc, source = read_json(path)
    v = JsonFields(source)
    v.no_nonfinite(doc, "")
    doc = v.obj(doc, "")
    if not doc:
        raise v.fail("", "no regions (expected {name: {\"start\": ..., \"end\": ...}, ...})")
    out = []
    for name, reg in doc.items():
        reg = v.obj(reg, name)
        v.known(reg, name, ("start", "end"))
        start = v.integer(v.get(reg, "start", name), f"{name}.start")
        end = v.integer(v.get(reg, "end", name), f"{name}.end")
        if start < 0:
            raise v.fail(f"{name}.start", f"expected a sample number >= 0, got {start}")
        if end <= start:
            raise v.fail(f"{name}.end", f"expected end > start ({start}), got {end}")
        for other, s, e in out:
            if start < e and s < end:
                raise v.fail(name, f"[{start}, {end}) overlaps region {other!r} [{s}, {e})")
        out.append((name, start, end))
    return out


def axis_label(text: str) -> str | None:
    """The POSE_DIRECTIONS name of a pose label that names an axis and its sign (``+X UP`` and
    ``+X``: x up, x_p; ``-X UP``, ``X DOWN``: x_a; ``x_p`` as it is); None for any other text."""
    m = AXIS_LABEL_RE.fullmatch(text.strip())
    if m is None:
        return None
    g = m.groupdict()
    if g["a4"]:
        return f"{g['a4'].lower()}_{g['pa'].lower()}"
    axis = (g["a1"] or g["a2"] or g["a3"]).lower()
    up = (g["s1"] or g["s2"] or "+") == "+"
    up = up if (g["ud"] or "up").lower() == "up" else not up
    return f"{axis}_{'p' if up else 'a'}"


def pose_column(source: str, names: list[str], free: list[str], cells, rows: list[int],
                line) -> tuple[str | None, list[str] | None, np.ndarray | None, str | None]:
    """A table's pose labels from one of its columns not otherwise read (``free``): the one named
    ``pose`` (the contract's: whole numbers kept as written, -1 or empty while moving; other text
    read as names, as a ``part`` column's), else the first whose every non-empty cell names an axis
    and its sign (:func:`axis_label`: ``+X UP`` ... ``-Z UP`` of a pose-means table, read as x_p ...
    z_a, which ``--stated-f`` takes).

    Parameters
    ----------
    names, free : list of str
        The header's columns; those not read as readings, time or index.
    cells : callable
        ``cells(j)``: column j's cells as text, one per table row.
    rows : list of int
        The table rows that are samples, in order.
    line : callable
        A table row's line in the file.

    Returns
    -------
    (column, names per sample, integer labels per sample, note)
        The column used (None: none), and either its names (for :func:`label_poses`) or its
        integer labels (int64, -1 unlabelled), and a note saying how it was read.

    Raises
    ------
    InputError
        A ``pose`` cell that is a whole number below -1, naming its row.
    """
    pose = next((c for c in free if c.strip().lower() == POSE_COLUMN), None)
    if pose is not None:
        text = cells(names.index(pose))
        got = [text[i].strip() for i in rows]
        if all(re.fullmatch(r"[+-]?[0-9]+", v) or not v for v in got):
            labels = np.array([int(v) if v else -1 for v in got], dtype=np.int64)
            low = np.flatnonzero(labels < -1)
            if low.size:
                raise InputError(source, f"pose label {labels[low[0]]}: expected a whole number >= 0 (a pose), or -1 "
                                 "or empty (moving)", row=line(rows[int(low[0])]), column=pose)
            return pose, None, labels, None
        axes = [axis_label(v) if v else "" for v in got]
        named = axes if all(a is not None for a in axes) else got
        return pose, named, None, None
    for c in free:
        text = cells(names.index(c))
        got = [text[i].strip() for i in rows]
        axes = [axis_label(v) if v else "" for v in got]
        if any(axes) and all(a is not None for a in axes):
            shown = dict(zip(axes, got))
            said = ", ".join(f"{shown[a]} = {a}" for a in POSE_DIRECTIONS if a in shown)
            return c, axes, None, f"pose labels from column {c} ({said}: the signed axis that points up)"
    return None, None, None, None


def text_column(names: list[str], free: list[str], cells, rows: list[int]) -> str | None:
    """The first of the columns ``free`` (of ``names``; ``cells(j)``: column j's cells) whose
    first non-empty cell among ``rows`` is no number (a label column, the likely home of a pose's
    name), else None."""
    for c in free:
        text = cells(names.index(c))
        got = next((v.strip() for v in (text[i] for i in rows[:100]) if v.strip()), "")
        try:
            float(got)
        except ValueError:
            if got:
                return c
    return None


def table_labels(source: str, names: list[str], free: list[str], table, rows: list[int], regions_given: bool,
                 stated_f: bool, notes: list[str]):
    """A table's pose labels (:func:`pose_column`) unless ``--regions`` gives them
    (``regions_given``): (the column read or None, names per sample or None, (integer labels,
    None) for :func:`convert_common.finish`'s ``kept`` or None, a text column to name where
    ``stated_f`` finds no poses or None); a note on how a label column was read goes to ``notes``.

    Raises
    ------
    InputError
        ``stated_f`` with integer labels (they state no direction), or a bad ``pose`` cell.
    """
    if regions_given:
        return None, None, None, None
    column, part, labels, note = pose_column(source, names, free, table.strings, rows, table.line)
    notes += [note] if note else []
    if labels is not None and stated_f:
        raise InputError(source, f"--stated-f: the {column} column's labels are numbers, which state no direction: "
                         "give --regions naming the poses x_p ... z_a, or label them so (or +X UP ... -Z UP) in the "
                         "column", column=column)
    hint = text_column(names, free, table.strings, rows) if column is None and stated_f else None
    return column, part, None if labels is None else (labels, None), hint


def rows_are_poses(part: list[str] | None, labels: np.ndarray | None) -> bool:
    """Whether a table's labels (:func:`table_labels`: names per row, or integer labels) make every
    row a pose of its own: each labelled (a name that is no motion's, or a label >= 0) and no two
    alike -- a file of pose means (``+X UP ... -Z UP`` and three means), whose rows carry no time."""
    if part is not None:
        got = [p.strip() for p in part]
        return bool(got) and all(g and not is_motion(g) for g in got) and len(set(got)) == len(got)
    return labels is not None and labels.size > 0 and bool(np.all(labels >= 0)) and \
        np.unique(labels).size == labels.size


#: the rate, Hz, t is written at for a file of pose means without a time column (:func:`rows_are_poses`):
#: t counts its rows
MEANS_RATE_HZ = 1.0
#: what a refusal for want of a rate says of such a file
MEANS_HINT = "a file of pose means, one row a pose, needs none: label each row in a 'pose' column"
#: the metadata ``table.time`` of such a file
MEANS_TIME = f"none: pose means, one row a pose; t is the row's number ({MEANS_RATE_HZ:g} Hz)"


def means_note(column: str | None, n: int) -> str:
    """The note on a file of pose means converted without a time column or ``--rate``: its ``n``
    rows, labelled by ``column``, carry no time, and t counts them."""
    return (f"no time column, and each row is a pose of its own (column {column}: {n} poses, one row each): pose "
            f"means, which carry no time; t counts the rows (0, 1, 2, ... s: a placeholder {MEANS_RATE_HZ:g} Hz; "
            "--rate HZ states a rate where the rows are samples)")


def is_motion(name: str) -> bool:
    return name.lower().endswith("_rot")


def label_poses(index: np.ndarray, names_per_sample: list[str] | None, regions, stated_f: bool,
                gravity: float, source: str, regions_source: str | None, label_hint: str | None = None):
    """(pose (n,), f (n, 3) or None, pose names) from regions of sample numbers or per-sample names;
    ``label_hint``: a column that may hold the poses' names (named in the refusal of
    ``stated_f`` without poses)."""
    n = index.shape[0]
    pose = np.full(n, -1, dtype=np.int64)
    names: list[str] = []
    if regions is not None:
        for name, start, end in regions:
            sel = (index >= start) & (index < end)
            if not sel.any():
                raise InputError(regions_source, f"[{start}, {end}) holds none of the recording's samples "
                                 f"({int(index[0])}..{int(index[-1])})", field=name)
            if not is_motion(name):
                pose[sel] = len(names)
                names.append(name)
    elif names_per_sample is not None:
        code: dict[str, int] = {}
        for i, nm in enumerate(names_per_sample):
            nm = nm.strip()
            if nm and not is_motion(nm):
                if nm not in code:
                    code[nm] = len(names)
                    names.append(nm)
                pose[i] = code[nm]
    f = None
    if stated_f:
        if not names:
            likely = f"; column {label_hint} holds text: if it names the poses, name them x_p ... z_a or +X UP ... " \
                "-Z UP (an axis and its sign), or call it part" if label_hint else ""
            raise InputError(source, f"--stated-f: no pose regions (give --regions JSON or a part column{likely})")
        unknown = [nm for nm in names if nm not in POSE_DIRECTIONS]
        if unknown:
            raise InputError(regions_source or source, f"--stated-f: pose {unknown[0]!r} states no direction "
                             f"(names that do: {', '.join(POSE_DIRECTIONS)})",
                             field=unknown[0] if regions_source else None)
        dirs = np.array([POSE_DIRECTIONS[nm] for nm in names], dtype=float) * gravity
        f = np.where(pose[:, None] >= 0, dirs[np.maximum(pose, 0)], np.nan)
    return pose, f, names
