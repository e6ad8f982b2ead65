"""The command line's output paths: refused before any work when they cannot be written, or
when they name one of the command's own input files."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..errors import AccelcalError

__all__ = ["check_output", "check_output_dir", "check_not_an_input", "INPUT_OPTIONS", "OUTPUT_OPTIONS"]


def check_output(path, option: str = "-o") -> None:
    """Refuse, before any work, an output path that cannot be written (one line).

    Parameters
    ----------
    path : str or os.PathLike
        The output file.
    option : str
        The option that named it, for the message.

    Raises
    ------
    AccelcalError
        The directory does not exist or is not a directory, or the path is a directory.
    """
    out = Path(path)
    parent = out.parent if str(out.parent) else Path(".")
    if out.is_dir():
        raise AccelcalError(f"{option} {path}: is a directory, expected a file name")
    if not parent.exists():
        raise AccelcalError(f"{option} {path}: directory {str(parent)!r} does not exist")
    if not parent.is_dir():
        raise AccelcalError(f"{option} {path}: {str(parent)!r} is not a directory")


def check_output_dir(path, option: str) -> None:
    """Refuse a report directory that is a file, or whose parent does not exist."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise AccelcalError(f"{option} {path}: exists and is not a directory")
    parent = out.parent if str(out.parent) else Path(".")
    if not out.exists() and not parent.is_dir():
        raise AccelcalError(f"{option} {path}: directory {str(parent)!r} does not exist")


#: the options that name files a command reads, and those it writes
INPUT_OPTIONS = ("device", "calibration", "recordings", "recording", "input", "regions", "diagnosis")
OUTPUT_OPTIONS = (("output", "-o"), ("json", "--json"), ("device_out", "--device-out"))


def check_not_an_input(a: argparse.Namespace) -> None:
    """Refuse an output path that is one of the command's input files (``-o rec.csv`` on
    ``rec.csv`` would replace the recording by the result)."""
    inputs = []
    for name in INPUT_OPTIONS:
        v = getattr(a, name, None)
        inputs += [str(p) for p in (v if isinstance(v, list) else [v]) if p is not None]
    for name, option in OUTPUT_OPTIONS:
        out = getattr(a, name, None)
        if out is None or not Path(out).exists():
            continue
        for p in inputs:
            if Path(p).exists() and Path(p).resolve() == Path(out).resolve():
                raise AccelcalError(f"{option} {out}: is also an input of this command ({p}); write the "
                                    "result to another file")
