"""The text of a recording file before its rows are read: the bytes (compressed with gzip,
bzip2, xz or zstd, or a zip archive of one file, each told by its magic bytes and never by
the name; :data:`COMPRESSIONS`), checked to be UTF-8, a spreadsheet's byte-order mark and CR
line ends dropped, a spreadsheet's semicolon-separated export with decimal commas rewritten
as CSV; the preamble of ``#`` comments (``# key: value`` metadata, with the line each came
from) up to the header; and text whose cells are separated by runs of blanks or tabs rewritten
as comma-separated cells, line for line, so that the one CSV reader (and its errors naming row
and column) reads them all."""
from __future__ import annotations

import bz2
import gzip
import io
import lzma
import re
import zipfile
import zlib
from dataclasses import dataclass, field
from typing import Any

import zstandard

from .csvtable import META_RE
from ..errors import InputError, read_input

#: a number as a text cell holds it (a header made of such cells is a data row)
NUMBER_RE = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
#: ... or nan and inf, which a log's row may hold where a header's name may not
CELL_NUMBER_RE = re.compile(NUMBER_RE.pattern + r"|[+-]?(?:nan|inf)", re.I)

__all__ = ["NUMBER_RE", "CELL_NUMBER_RE", "GZIP_MAGIC", "COMPRESSIONS", "decompress", "semicolons_to_commas",
           "byte_lines", "Preamble", "read_text_bytes", "read_preamble", "table_preamble", "preamble_notes", "is_whitespace_header",
           "split_whitespace_header",
           "whitespace_to_commas"]

GZIP_MAGIC = b"\x1f\x8b"


class NotOneFile(ValueError):
    """A zip archive that does not hold exactly one file."""


def _unzip(data: bytes) -> bytes:
    """The one file of a zip archive (directories aside)."""
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        files = [i for i in z.infolist() if not i.is_dir()]
        if len(files) != 1:
            names = ", ".join(i.filename for i in files[:4]) + (", ..." if len(files) > 4 else "")
            raise NotOneFile(f"a zip archive of {len(files)} files ({names or 'none'}): give one recording")
        return z.read(files[0])


def _unzstd(data: bytes) -> bytes:
    """A zstd stream of one or more frames (with or without the content size in their headers)."""
    out = []
    rest = data
    try:
        while rest:
            d = zstandard.ZstdDecompressor().decompressobj()
            out.append(d.decompress(rest))
            if not d.eof:
                raise ValueError("the stream ends inside a frame (truncated)")
            rest = d.unused_data
    except zstandard.ZstdError as e:
        raise ValueError(str(e)) from None
    return b"".join(out)


def _is_bzip2(data: bytes) -> bool:
    # "BZh", the block size 1-9, then a block's or the end of stream's magic: plain text does not
    # start so
    return (data[:3] == b"BZh" and data[3:4] in tuple(b"%d" % k for k in range(1, 10))
            and data[4:10] in (b"1AY&SY", b"\x17rE8P\x90"))


#: (name, test on the first bytes, decompress): the forms a recording may come in
COMPRESSIONS = (
    ("gzip", lambda d: d.startswith(GZIP_MAGIC), gzip.decompress),
    ("bzip2", _is_bzip2, bz2.decompress),
    ("xz", lambda d: d.startswith(b"\xfd7zXZ\x00"), lzma.decompress),
    ("zstd", lambda d: d.startswith(b"\x28\xb5\x2f\xfd"), _unzstd),
    ("zip", lambda d: d.startswith(b"PK\x03\x04"), _unzip),
)


def decompress(source: str, data: bytes) -> tuple[bytes, str | None]:
    """``data`` decompressed by the form its first bytes show (:data:`COMPRESSIONS`), and the
    form's name (None: not compressed).  A stream that starts as one but cannot be
    decompressed is an :class:`InputError` naming the form."""
    for name, test, unpack in COMPRESSIONS:
        if test(data):
            try:
                return unpack(data), name
            except NotOneFile as e:
                raise InputError(source, str(e)) from None
            except (OSError, EOFError, ValueError, zlib.error, lzma.LZMAError, zipfile.BadZipFile) as e:
                raise InputError(source, f"starts as {name} but cannot be decompressed: {e}") from None
    return data, None


BLANKS = re.compile(rb"[ \t]+")
EDGE_BLANKS = re.compile(rb"^[ \t]+|[ \t]+$", re.M)


def read_text_bytes(path: Any, semicolons: bool = True) -> tuple[str, bytes]:
    """The bytes of a text file, decompressed when its first bytes show a compression
    (:data:`COMPRESSIONS`: gzip, bzip2, xz, zstd, a zip archive of one file).

    Parameters
    ----------
    path : str or os.PathLike
        The file.  ``.gz``, ``.bz2``, ``.xz``, ``.zst`` or ``.zip`` in the name is neither
        needed nor looked at.
    semicolons : bool
        Rewrite a semicolon-separated export as CSV (:func:`semicolons_to_commas`; False:
        the text as the file holds it, for quoting its lines).

    Returns
    -------
    source : str
        The path as given, for messages.
    data : bytes
        The (decompressed) text as UTF-8 bytes, without a byte-order mark, with ``\\n``
        line ends.

    Raises
    ------
    InputError
        Unreadable file, a damaged or truncated compressed stream, a zip archive of more
        than one file, or text that is not UTF-8
        (naming the line of the first bad byte in the decompressed text).
    """
    source, data = read_input(path)
    data, compressed = decompress(source, data)
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as e:
        line = data.count(b"\n", 0, e.start) + 1
        inside = " of the decompressed text" if compressed else ""
        raise InputError(source, f"not valid UTF-8 text (byte {e.start}{inside})", row=line) from None
    if data.startswith(b"\xef\xbb\xbf"):  # spreadsheet BOM: not data
        data = data[3:]
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n")
    return source, semicolons_to_commas(data) if semicolons else data


def semicolons_to_commas(data: bytes) -> bytes:
    """A spreadsheet's export in a locale whose decimal mark is the comma (cells separated by
    ``;``, numbers written ``0,0167``) rewritten as CSV: when the header (the first line that
    is neither a comment nor blank) has a ``;`` and no ``,``, every later line that is not a
    comment has its commas made points and its semicolons commas.  Every line stays the line
    it was; any other text is returned as it is."""
    pre = read_preamble(data)
    if pre.header is None or ";" not in pre.header or "," in pre.header:
        return data
    lines = data[pre.header_pos:].split(b"\n")
    body = b"\n".join(line if line.startswith(b"#") else line.replace(b",", b".").replace(b";", b",")
                      for line in lines)
    return data[:pre.header_pos] + body


@dataclass
class Preamble:
    """What comes before the data rows.

    ``header`` is the first line that is neither a comment nor blank (None when there is
    none), ``header_line`` its 1-based line number, ``header_pos`` and ``pos`` the byte
    offsets of its start and of the line after it.  ``metadata`` holds the ``# key:
    value`` comments, ``metadata_lines`` the line of each key.  A comment line just before a
    first line of numbers that names as many columns as that line has cells, comma-separated
    (Altus Metrum's ``#version,serial,...,accel_x,...``) or whitespace-separated (``# time tx ty
    tz ...`` over rows of 14 numbers), is the header (``header_from_comment``; ``pos`` then
    the numbers' line, the first data row).  ``title``: (line, text) of a line of free text
    before the header that :func:`table_preamble` passed over, else None.  ``made``: for rows
    without a header, what the header given them (``header``) was made from
    (:func:`accelcal.convert.headerless.timed_rows`), else None."""

    metadata: dict[str, str] = field(default_factory=dict)
    metadata_lines: dict[str, int] = field(default_factory=dict)
    header: str | None = None
    header_line: int = 0
    header_pos: int = 0
    pos: int = 0
    header_from_comment: bool = False
    title: tuple[int, str] | None = None
    made: str | None = None


def byte_lines(data: bytes, pos: int = 0):
    """Each line of ``data`` from byte ``pos`` on: (its text, its first byte, the byte after its
    line end)."""
    while pos < len(data):
        end = data.find(b"\n", pos)
        end = len(data) if end < 0 else end
        yield data[pos:end].decode("utf-8"), pos, end + 1
        pos = end + 1


def read_preamble(data: bytes) -> Preamble:
    """Comments (metadata) and blank lines, then the header line."""
    out = Preamble()
    line_no = 0
    last = None                                  # the comment line just before, (text, line, start)
    for text, start, pos in byte_lines(data):
        line_no += 1
        if text.startswith("#"):
            m = META_RE.fullmatch(text)
            if m:
                out.metadata[m.group(1)] = m.group(2).strip()
                out.metadata_lines[m.group(1)] = line_no
                last = None
            else:
                last = (text[1:].strip(), line_no, start)
            continue
        if not text.strip():
            last = None
            continue
        if last is not None and names_for(last[0], text):
            out.header, out.header_line, out.header_pos, out.pos = last[0], last[1], last[2], start
            out.header_from_comment = True
            break
        out.header, out.header_line, out.header_pos, out.pos = text, line_no, start, pos
        break
    return out


def line_cells(line: str) -> list[str]:
    """A line's cells for telling names from numbers: split at commas where it has any, else at
    runs of blanks or tabs."""
    text = line.rstrip("\r").strip(" \t")
    return [c.strip() for c in text.split(",")] if "," in text else re.split(r"[ \t]+", text)


def numbers_share(cells: list[str]) -> float:
    """The share of ``cells`` that are numbers (CELL_NUMBER_RE)."""
    return sum(bool(CELL_NUMBER_RE.fullmatch(c)) for c in cells) / len(cells) if cells else 0.0


def is_names(cells: list[str]) -> bool:
    """Whether every cell is a name: not empty, not a number."""
    return all(cells) and not any(CELL_NUMBER_RE.fullmatch(c) for c in cells)


def names_for(comment: str, line: str) -> bool:
    """Whether ``comment`` names the columns of ``line``: as many cells (3 or more; comma-separated
    where both have commas, else whitespace-separated), every one a name (not a number, not
    empty), and most cells of ``line`` numbers (a row of a log may hold a call sign or a
    state's name)."""
    if ("," in comment) != ("," in line):
        return False
    names, cells = line_cells(comment), line_cells(line)
    return len(names) >= 3 and len(names) == len(cells) and is_names(names) and numbers_share(cells) > 0.5


def next_line(data: bytes, pos: int) -> tuple[str | None, int, int, int]:
    """The first line at or after byte ``pos`` that is neither blank nor a comment: (its text,
    the lines passed to reach it, its first byte, the byte after its line end); (None, ...) at
    the end."""
    passed = 0
    for text, start, after in byte_lines(data, pos):
        passed += 1
        pos = after
        if text.strip() and not text.startswith("#"):
            return text, passed, start, after
    return None, passed, pos, pos


#: free-text lines before a header passed over, at most
MAX_TITLE_LINES = 3


def table_preamble(data: bytes) -> Preamble:
    """:func:`read_preamble`, passing over lines of free text before the header -- a title such
    as ``Acceleration Data Collected on Level Surface. Z up.`` -- that are neither a header nor
    data: a line with letters, most of its cells not numbers, followed by a header (two or
    more names, another count of cells than the line's) and then a row most of whose cells
    are numbers.  ``title`` keeps the first such line (:func:`preamble_notes` says so)."""
    pre = read_preamble(data)
    for _ in range(MAX_TITLE_LINES):
        if pre.header is None or pre.header_from_comment:
            return pre
        h1 = line_cells(pre.header)
        if not re.search(r"[A-Za-z]", pre.header) or numbers_share(h1) >= 0.5:
            return pre
        h2, passed2, start2, after2 = next_line(data, pre.pos)
        if h2 is None:
            return pre
        h3 = next_line(data, after2)[0]
        cells2 = line_cells(h2)
        if (h3 is None or len(cells2) < 2 or len(cells2) == len(h1) or not is_names(cells2)
                or numbers_share(line_cells(h3)) <= 0.5):
            return pre
        pre.title = pre.title or (pre.header_line, pre.header)
        pre.header, pre.header_line, pre.header_pos, pre.pos = h2, pre.header_line + passed2, start2, after2
    return pre


def preamble_notes(pre: Preamble) -> list[str]:
    """Notes on how the header was found: a title passed over, a comment taken as the header, a
    header made for rows without one."""
    notes = [pre.made] if pre.made is not None else []
    if pre.title is not None:
        notes.append(f"line {pre.title[0]} ({pre.title[1][:60]!r}) is neither a header nor data (a title before "
                     f"the header on line {pre.header_line}): left out")
    if pre.header_from_comment:
        notes.append(f"the column names are read from the comment on line {pre.header_line} (a '#' before the first "
                     "row, naming as many columns as it has)")
    return notes


def is_whitespace_header(header: str) -> bool:
    """Commas in the header: CSV; else runs of blanks or tabs between cells: whitespace text."""
    return "," not in header and re.search(r"[ \t]", header.strip(" \t")) is not None


def split_whitespace_header(header: str) -> list[str]:
    """The names of a whitespace header: at runs of blanks or tabs; a header of quoted names
    between tabs (phyphox's tab-separated export: "Time (s)"\t"Acceleration x (m/s^2)") at
    its tabs, the quotes dropped."""
    h = header.strip(" \t")
    if '"' in h and "\t" in h:
        return [c.strip(" ").strip('"') for c in re.split(r"\t+", h)]
    return re.split(r"[ \t]+", h)


def whitespace_to_commas(data: bytes, pos: int, end: int, names: list[str], first_line: int,
                         source: str) -> bytes:
    """``data[:pos]`` followed by the rows ``data[pos:end]`` of whitespace-separated text
    with each run of blanks or tabs between cells made one comma (blanks at a line's ends
    dropped); every line stays the line it was.

    Raises
    ------
    InputError
        A comma or a double quote in a row (whitespace text has neither separators nor
        quoting of that kind), naming its row and the column it falls in.
    """
    for bad in (b",", b'"'):
        at = data.find(bad, pos, end)
        if at < 0:
            continue
        line_start = data.rfind(b"\n", pos, at) + 1 or pos
        row = first_line + data.count(b"\n", pos, line_start)
        before = data[line_start:at].strip(b" \t")
        j = 0 if not before else len(BLANKS.split(before)) - (0 if data[at - 1:at] in (b" ", b"\t") else 1)
        what = "a comma" if bad == b"," else "a double quote"
        raise InputError(source, f"{what} in whitespace-separated text (the header has no commas, so cells "
                         "are separated by blanks or tabs)", row=row, column=names[j] if j < len(names) else None)
    body = BLANKS.sub(b",", EDGE_BLANKS.sub(b"", data[pos:end]))
    return data[:pos] + body
