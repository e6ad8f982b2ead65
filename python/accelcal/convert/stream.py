"""``accelcal convert`` of a recording CSV (``--format csv``, or told so: a header with ``t`` and
``raw_0``) in two passes over the file in chunks (docs/streaming.md, "convert in chunks").

The first pass reads the rows in chunks (:func:`accelcal.io.chunks.csv_chunks`, the whole-file
reader's own functions on each block, with a progress bar) and keeps of them only what the
inference of :func:`accelcal.convert.common.finish` takes: t (float64), the counts (int64) and
the pose labels where the file has them; not the file's text, the parser's table, f or the other
columns.  ``finish`` then runs on those arrays as on the whole-file reader's (the range check,
the leading placeholder, the time unit and rate, held readings, the nominal device, the clip
levels), f standing in as a read-only view of one value that says only whether the file gives any.
The second pass reads the chunks again and writes each as it is done (the recording's t, counts
and labels, the file's f) into a temporary file that replaces the output at the end
(:func:`accelcal.errors.atomic_write`), through :func:`accelcal.io.recording.recording_layout`,
the whole-file writer's layout: the output is the whole-file command's, byte for byte.

Where this path cannot tell what the whole-file command does, it raises
:class:`~accelcal.io.chunks.Fallback` before writing anything and the whole-file command runs
(the same output or refusal, the whole file's memory): what the chunked reader leaves to the
whole-file reader (compressed, units, quoted cells, a last line cut short, ...), any bad row (the
whole-file reader words it), a file not read as a contract recording, an epoch in nanoseconds
(read exactly from its text), ``--stated-f`` without ``--regions``, not three channels.
"""
from __future__ import annotations

from typing import Any, Callable

import numpy as np

from .bounded import bounded_convert, bounded_writer, first_pass_sums, noise_pass
from .bounded_scale import still_scale
from .common import Converted, Options, finish
from .time import FLOAT_EXACT
from ..errors import InputError, atomic_write
from ..io.chunks import BLOCK_BYTES, Fallback, Head, csv_chunks, csv_head, reader_checks
from ..io.csvformat import csv_rows
from ..io.parquet import is_parquet
from ..io.recording import Recording, recording_layout
from ..io.textinput import table_preamble
from ..io.units import STANDARD_GRAVITY, Scale, in_file_unit

__all__ = ["convert_csv_chunked", "contract_head"]


def contract_head(path: Any, scale: Scale | None) -> Head:
    """The head of a file :func:`accelcal.convert.formats.told_format` tells as ``csv`` from its
    header (``t`` and ``raw_0`` among its cells, not a comment), read by the chunked reader.

    Raises
    ------
    Fallback
        Anything else (the whole-file command tells it and words any refusal).
    """
    try:
        head = csv_head(path, None, scale)
    except InputError:
        raise Fallback("a header the whole-file reader refuses") from None
    with open(path, "rb") as fh:
        text = fh.read(head.pos)
    pre = table_preamble(text + b"\n")
    if pre.header_from_comment or pre.header_line != head.first_line - 1 or \
            "t" not in head.names or "raw_0" not in head.names:
        raise Fallback("not told as a contract recording from its header")
    return head


def convert_csv_chunked(path: Any, opts: Options, scale: Scale | None, block_bytes: int = BLOCK_BYTES,
                        progress: Callable[[Any, str], Any] | None = None) -> Converted:
    """:func:`accelcal.convert.formats.convert_file`'s ``csv`` format in two passes (module doc).

    Parameters
    ----------
    path : str or os.PathLike
        A recording CSV.
    opts : Options
        As ``convert_file`` made them (regions read).
    scale : units.Scale or None
        ``--units``/``--lsb``/``--full-scale`` (a converting unit: Fallback).
    block_bytes : int
        Bytes of text per chunk (whole lines; at least one row).
    progress : callable, optional
        ``progress(total, unit)`` -> a bar (tqdm's ``update``, ``close``), one per pass.

    Returns
    -------
    Converted
        Its ``writer`` writes the output in the second pass; its recording holds t, the counts
        and the labels, and f as a stand-in (not the file's values).

    Raises
    ------
    Fallback
        Where the whole-file command must run (module doc).
    InputError
        A refusal of :func:`accelcal.convert.common.finish` (a reading outside the ADC's range), as
        the whole-file command words it.
    """
    head = contract_head(path, scale)
    if head.n_raw != 3:
        raise Fallback("not 3 raw channels")
    if opts.regions is None and opts.stated_f:
        raise Fallback("--stated-f without --regions")
    scale = in_file_unit(scale, head.metadata.get("source_units"), head.source)
    if opts.regions is None and (scale is None or not scale.converts):
        try:                # in bounded memory (accelcal.convert.bounded), else the arrays below
            stated = scale is not None and scale.counts_per_mps2(opts.gravity_mps2 or STANDARD_GRAVITY) is not None
            sums = first_pass_sums(path, head, block_bytes, bar_for(path, head, progress), opts.time_unit,
                                   diffs=not stated)

            def bars() -> Any:
                return bar_for(path, head, progress)

            def still_of(hists: list, rate_hz: float, gravity: float, signed: bool, notes: list[str]) -> Any:
                return still_scale(path, head, block_bytes, bars, sums, hists, rate_hz, gravity, opts.bits, signed,
                                   notes)

            conv = bounded_convert(head, sums, opts, scale, noise_pass(path, head, block_bytes, bars, sums.n),
                                   still_of)
            conv.writer = bounded_writer(path, head, block_bytes, bars, conv, sums.factor)
            return conv
        except Fallback:
            pass
    t, raw, pose, f_given = first_pass(path, head, block_bytes, progress)
    n = t.size
    if np.any(np.abs(t) >= FLOAT_EXACT):
        raise Fallback("an epoch in ns (read exactly from its text)")
    # f stands in as one value: finite where the file gives any (the writer's layout), not its values
    f = np.broadcast_to(np.float64(0.0 if f_given else np.nan), (n, 3))
    kept = (pose if pose is not None else np.broadcast_to(np.int64(-1), (n,)), f) if opts.regions is None else None
    first = head.first_line
    conv = finish(head.source, "csv", raw, np.arange(n), t, None, opts, scale, bool(np.any(raw < 0)), None,
                  dict(head.metadata), [], lambda i, j: (first + i, f"raw_{j}"), None, None, kept, time_column="t")
    rec = conv.recording
    lead = n - rec.n_samples                       # leading placeholder rows left out (convert_rows)

    def write(output: Any) -> None:
        second_pass(path, head, block_bytes, progress, rec, lead, kept is not None, output)

    conv.writer = write
    return conv


def first_pass(path: Any, head: Head, block_bytes: int, progress: Callable[[Any, str], Any] | None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, bool]:
    """t, the counts, the pose labels (None: no pose column) and whether any f is given, read in
    chunks into arrays sized from the file's bytes (Fallback at any bad row or a row whose line is
    not the header's + its index: the whole-file reader words it)."""
    cols: dict[str, np.ndarray] = {}              # t, raw, pose, grown in place (not a list of chunks joined)
    n, f_given, prev = 0, False, None
    size, read = file_size(path) - head.pos, [0]
    bar = bar_for(path, head, progress)

    def tick(k: int) -> None:
        read[0] += k
        if bar is not None:
            bar.update(k)

    for ch in csv_chunks(path, head, block_bytes, tick):
        if reader_checks(head, ch, prev) or not np.all(np.isfinite(ch.t)):
            raise Fallback("a bad row")
        if ch.n and (ch.line(0) != head.first_line + ch.start or ch.line(ch.n - 1) != head.first_line + ch.start + ch.n - 1):
            raise Fallback("rows not on consecutive lines")
        parts = {"t": ch.t, "raw": ch.raw, **({"pose": ch.other["pose"]} if "pose" in ch.other else {})}
        if n + ch.n > (len(cols["t"]) if cols else 0):
            # room for the rows the file holds at the mean bytes a row so far, and a tenth more
            # (at least a quarter more than before: an estimate short again and again copies rarely)
            want = max(n + ch.n, int(1.1 * size * (n + ch.n) / max(read[0], 1)),
                       int(1.25 * len(cols["t"])) if cols else 0)
            cols = {k: grown(cols.get(k), v, want) for k, v in parts.items()}
        for k, v in parts.items():
            cols[k][n:n + ch.n] = v
        n += ch.n
        f = ch.vecs.get("f")
        f_given = f_given or (f is not None and bool(np.isfinite(f).any()))
        prev = ch
    if bar is not None:
        bar.close()
    if prev is None:
        raise Fallback("no rows")
    return cols["t"][:n], cols["raw"][:n], cols["pose"][:n] if "pose" in cols else None, f_given


def file_size(path: Any) -> int:
    with open(path, "rb") as fh:
        return fh.seek(0, 2)


def grown(arr: np.ndarray | None, like: np.ndarray, rows: int) -> np.ndarray:
    """``arr`` (or nothing) in an array of ``rows`` rows of ``like``'s dtype and columns."""
    out = np.empty((rows,) + like.shape[1:], dtype=like.dtype)
    if arr is not None:
        out[:len(arr)] = arr
    return out


def bar_for(path: Any, head: Head, progress: Callable[[Any, str], Any] | None) -> Any:
    """A bar over the bytes of the rows (None without ``progress``)."""
    if progress is None:
        return None
    return progress(max(file_size(path) - head.pos, 0), "B")


def second_pass(path: Any, head: Head, block_bytes: int, progress: Callable[[Any, str], Any] | None,
                rec: Recording, lead: int, file_f: bool, output: Any) -> None:
    """Write the recording chunk by chunk (the file read again, the placeholder rows ``lead``
    left out; f the file's where ``file_f``, else ``rec``'s: the stated poses'), atomically."""
    if is_parquet(output):
        raise ValueError("the chunked writer writes CSV: a .parquet output is written whole")
    lines, _, formats = recording_layout(rec)
    bar = bar_for(path, head, progress)

    def write(fh: Any) -> None:
        fh.write("\n".join(lines))
        fh.write("\n")
        done = 0
        for ch in csv_chunks(path, head, block_bytes, None if bar is None else bar.update):
            a = max(ch.start - lead, 0)
            b = ch.start + ch.n - lead
            if b <= a:
                continue
            k = ch.n - (b - a)                      # the chunk's rows before the first written
            part = rec_slice(rec, a, b, ch.vecs.get("f") if file_f else None, k)
            _, columns, _ = recording_layout(part, like=rec)
            for text in csv_rows(columns, formats, [""] * len(columns)):
                fh.write(text)
            done = b
        if done != rec.n_samples:
            raise InputError(head.source, f"the file changed while it was read ({done} rows, then "
                             f"{rec.n_samples})")

    try:
        atomic_write(output, write)
    finally:
        if bar is not None:
            bar.close()


def rec_slice(rec: Recording, a: int, b: int, f: np.ndarray | None, k: int) -> Recording:
    """Samples a..b of ``rec`` (f from the chunk's ``f`` from its row ``k`` where given)."""
    return Recording(t=rec.t[a:b], raw=rec.raw[a:b], f=rec.f[a:b] if f is None else f[k:],
                     pose=rec.pose[a:b], extra={name: v[a:b] for name, v in rec.extra.items()},
                     metadata=rec.metadata, source=rec.source)
