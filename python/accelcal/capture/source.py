"""Where the samples come from: a serial port (pyserial; a pseudo-terminal's path works),
standard input (``-``) or a file replayed; one sample a line, the raw readings as integers,
comma-separated (a time stamp first with ``--time-column``).  Lines that do not parse are
counted, never fatal.
"""
from __future__ import annotations

import os
import stat
import sys
from typing import Iterator

import serial

from ..errors import InputError


class PortLost(Exception):
    """The port went away while reading (unplugged, the other end closed)."""


class LineSource:
    """Lines of one stream, parsed into samples.

    Parameters
    ----------
    port : str
        A serial port or pseudo-terminal path, ``-`` for standard input, or a regular file
        (replayed).
    baud : int
        Baud rate (serial ports only).
    n_channels : int
        Raw readings a line.
    time_column : bool
        Whether each line begins with a time stamp (seconds).
    """

    def __init__(self, port: str, baud: int, n_channels: int, time_column: bool = False):
        self.port = port
        self.n_channels = n_channels
        self.time_column = time_column
        self.bad_lines = 0
        self.first_bad: str | None = None
        self.lines = 0
        self.kind = "stdin" if port == "-" else "file" if os.path.isfile(port) else "port"
        self.stream = None
        if self.kind == "stdin":
            self.stream = sys.stdin.buffer
        elif self.kind == "file":
            self.stream = open(port, "rb")
        else:
            try:
                mode = os.stat(port).st_mode
            except OSError as e:
                raise InputError(port, f"cannot open the port: {e.strerror}", field="--port") from None
            if not stat.S_ISCHR(mode):
                raise InputError(port, "not a serial port, a file or '-'", field="--port")
            try:
                self.stream = serial.Serial(port, baud, timeout=0.5)
            except (serial.SerialException, ValueError) as e:
                raise InputError(port, f"cannot open the port: {e}", field="--port") from None

    def raw_lines(self) -> Iterator[bytes]:
        """The stream's lines as bytes, until its end.

        Yields
        ------
        bytes
            One line (without its end).

        Raises
        ------
        PortLost
            A serial port that fails while reading.
        """
        if self.kind != "port":
            for line in self.stream:
                yield line
            return
        pending = b""
        while True:
            try:
                chunk = self.stream.read(max(1, self.stream.in_waiting))
            except (serial.SerialException, OSError) as e:
                raise PortLost(str(e)) from None
            if not chunk:
                continue
            pending += chunk
            *done, pending = pending.split(b"\n")
            yield from done

    def samples(self) -> Iterator[tuple[float | None, list[int]]]:
        """The stream's samples: (time stamp or None, raw readings).

        Yields
        ------
        tuple
            (t in seconds or None, list of ``n_channels`` ints); a line that does not parse is
            counted in ``bad_lines`` and skipped.
        """
        for line in self.raw_lines():
            self.lines += 1
            got = parse_line(line, self.n_channels, self.time_column)
            if got is None:
                text = line.strip()
                if text:
                    self.bad_lines += 1
                    if self.first_bad is None:
                        self.first_bad = text[:60].decode("utf-8", "replace")
                continue
            yield got

    def close(self) -> None:
        """Close the port or file (standard input is left open)."""
        if self.kind != "stdin" and self.stream is not None:
            try:
                self.stream.close()
            except (OSError, serial.SerialException):
                pass


def parse_line(line: bytes, n_channels: int, time_column: bool = False) -> tuple[float | None, list[int]] | None:
    """One line as a sample, or None where it does not parse.

    Parameters
    ----------
    line : bytes
        ``r0,r1,...`` (integers), or ``t,r0,r1,...`` with ``time_column``.
    n_channels : int
        Readings expected.
    time_column : bool
        Whether a time stamp (seconds, a finite number) comes first.

    Returns
    -------
    tuple or None
        (t or None, readings) or None for a line of another form.
    """
    try:
        parts = line.decode("ascii").strip().split(",")
    except UnicodeDecodeError:
        return None
    if len(parts) != n_channels + (1 if time_column else 0):
        return None
    t = None
    try:
        if time_column:
            t = float(parts[0])
            if t != t or t in (float("inf"), float("-inf")):
                return None
            parts = parts[1:]
        return t, [int(p) for p in parts]
    except ValueError:
        return None
