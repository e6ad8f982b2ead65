"""Exceptions, and the file helpers that word their errors, shared by every accelcal module.

Every error the user can cause is an :class:`AccelcalError` whose ``str()`` is
one complete line: the command line prints exactly that, with no traceback.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import os
import tempfile
from contextlib import contextmanager
from typing import IO, Any, Callable, Iterable, Iterator

__all__ = [
    "AccelcalError",
    "InputError",
    "OptionError",
    "unknown_option",
    "options_checked",
    "CoreError",
    "NullError",
    "SizeError",
    "SingularError",
    "IllConditionedError",
    "RangeError",
    "FormatError",
    "core_error",
    "atomic_write",
    "read_input",
    "notes_on_refusal",
]


class AccelcalError(Exception):
    """Base of all accelcal errors; ``str(e)`` is the full one-line message.

    ``notes``: what was noted on the input before it was refused (``accelcal convert``'s
    notes: a title line passed over, the unit its time column was read in), for the user
    ahead of the message; empty unless set.
    """

    notes: tuple[str, ...] = ()


@contextmanager
def notes_on_refusal(notes: Callable[[], list[str]]) -> Iterator[None]:
    """A context in which a refusal (an :class:`AccelcalError`) is given the notes made before
    it, ``notes()`` (called then), unless it already holds some (an inner context's, which made
    more): ``accelcal convert`` prints them ahead of the error line.  The one mechanism by which
    every reader and conversion path keeps its notes on a refusal."""
    try:
        yield
    except AccelcalError as e:
        if not e.notes:
            e.notes = tuple(notes())
        raise


def _one_line(text: str) -> str:
    # A message must stay on one line even if a cell or a path held a newline.
    return " ".join(str(text).split("\n")).replace("\r", " ")


class InputError(AccelcalError):
    """Bad input file or value.

    The message reads ``"<source>: row <row>, column <column>: <message>"`` or
    ``"<source>: field <field>: <message>"``; parts that are ``None`` are left
    out.  ``row`` is the 1-based line number in the file (comments and header
    counted); ``field`` is a JSON path such as ``channels[2].axis``.
    """

    def __init__(
        self,
        source: Any,
        message: str,
        *,
        row: int | None = None,
        field: str | None = None,
        column: str | None = None,
    ) -> None:
        self.source = str(source)
        self.row = row
        self.field = field
        self.column = column
        self.detail = message
        where = []
        if row is not None:
            where.append(f"row {row}")
        if column is not None:
            where.append(f"column {column}")
        if field is not None:
            where.append(f"field {field}")
        prefix = self.source + ": " + (", ".join(where) + ": " if where else "")
        super().__init__(_one_line(prefix + message))

    def __reduce__(self):  # keep pickling (multiprocessing) working with kw-only args
        return (
            _rebuild_input_error,
            (self.source, self.detail, self.row, self.field, self.column),
        )


def _rebuild_input_error(source, detail, row, field, column):
    return InputError(source, detail, row=row, field=field, column=column)


class OptionError(AccelcalError, TypeError):
    """An unknown keyword option to a public API function (``ac.calibrate(dev, rec,
    jig_acuracy_deg=1)``).  A ``TypeError``, as Python raises for any unexpected keyword
    argument (``except TypeError`` catches it), and an :class:`AccelcalError` whose one line
    names the public function, the option and the closest valid one (:func:`unknown_option`),
    where Python's own names the internal function the option was forwarded to
    (``attitude_from_recording()``) and suggests nothing."""


def unknown_option(function: str, name: str, valid: Iterable[str], options: Iterable[str]) -> OptionError:
    """The :class:`OptionError` of option ``name`` given to the public ``function``: the closest
    of ``valid`` (every keyword it takes) where one is close (:func:`difflib.get_close_matches`),
    then the list of its ``options``."""
    close = difflib.get_close_matches(name, list(valid), n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    return OptionError(_one_line(f"accelcal.{function}(): unknown option {name!r}{hint}; its options: "
                                 f"{', '.join(options) or 'none'}"))


class CoreError(AccelcalError):
    """A negative status returned by the C core (see ``ac_status.h``)."""

    status: int = 0
    description: str = "C core error"

    def __init__(self, status: int, context: str) -> None:
        self.status = int(status)
        self.context = context
        super().__init__(_one_line(f"{context}: {self.description} (status {self.status})"))

    def __reduce__(self):
        return (type(self), (self.status, self.context))


class NullError(CoreError):
    """AC_ERR_NULL: a required pointer was NULL."""

    description = "a required pointer was NULL"


class SizeError(CoreError):
    """AC_ERR_SIZE: channel or sample count out of range."""

    description = "channel or sample count out of range"


class SingularError(CoreError):
    """AC_ERR_SINGULAR: the geometry does not determine f and alpha."""

    description = "the geometry does not determine f and alpha (singular)"


class IllConditionedError(CoreError):
    """AC_ERR_ILL_COND: the geometry is too ill-conditioned to invert."""

    description = "the geometry is too ill-conditioned for a trustworthy inverse"


class RangeError(CoreError):
    """AC_ERR_RANGE: a parameter is out of its representable range."""

    description = "a parameter is out of its representable range"


class FormatError(CoreError):
    """AC_ERR_FORMAT: a table is inconsistent."""

    description = "a table is inconsistent (e.g. a shift out of range)"


_STATUS_CLASSES: dict[int, type[CoreError]] = {
    -1: NullError,
    -2: SizeError,
    -3: SingularError,
    -4: IllConditionedError,
    -5: RangeError,
    -6: FormatError,
}


def core_error(status: int, context: str) -> CoreError:
    """Return (not raise) the CoreError subclass for a negative C status.

    Unknown negative codes give a plain :class:`CoreError`.  0 (ok) and +1
    (saturated: outputs valid but clipped) are not errors: passing them is a
    programming mistake and raises ``ValueError``.
    """
    status = int(status)
    if status >= 0:
        raise ValueError(f"status {status} is not an error")
    cls = _STATUS_CLASSES.get(status, CoreError)
    return cls(status, context)


def read_input(path: Any) -> tuple[str, bytes]:
    """The bytes of an input file and its name for messages; an unreadable file is an
    :class:`InputError` naming it (the read counterpart of :func:`atomic_write`)."""
    source = os.fspath(path) if not isinstance(path, str) else path
    try:
        with open(path, "rb") as fh:
            return source, fh.read()
    except OSError as e:
        raise InputError(source, f"cannot read the file: {e.strerror or e}") from None


def atomic_write(path: Any, write_fn: Callable[[IO[Any]], Any], mode: str = "w") -> None:
    """Write ``path`` all-or-nothing.

    ``write_fn(f)`` writes to a temporary file in the same directory (so the
    final ``os.replace`` is atomic on one filesystem); on any exception the
    temporary file is removed and the exception re-raised, leaving an existing
    ``path`` untouched.  Text modes use UTF-8 and ``\\n`` line ends.  A directory that
    does not exist, or a path that is a directory, is :class:`AccelcalError` (one line).
    """
    if mode not in ("w", "wb", "wt"):
        raise ValueError(f"atomic_write mode must be 'w', 'wt' or 'wb', not {mode!r}")
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    base = os.path.basename(path)
    if not os.path.isdir(directory):
        raise AccelcalError(f"{path}: directory {os.path.dirname(path) or directory!r} does not exist")
    if os.path.isdir(path):
        raise AccelcalError(f"{path}: is a directory, expected a file name")
    fd, tmp = tempfile.mkstemp(prefix=f".{base}.", suffix=".tmp", dir=directory)
    try:
        if "b" in mode:
            f = os.fdopen(fd, "wb")
        else:
            f = os.fdopen(fd, "w", encoding="utf-8", newline="\n")
        with f:
            write_fn(f)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp makes the file 0600; give it the permissions a plain open() would.
        try:
            mode_bits = os.stat(path).st_mode & 0o777
        except FileNotFoundError:
            umask = os.umask(0)
            os.umask(umask)
            mode_bits = 0o666 & ~umask
        os.chmod(tmp, mode_bits)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise


def options_checked(*targets: Callable[..., Any], extra: Callable[..., Any] | None = None) -> Callable:
    """Decorator of the public functions: a keyword argument that is none of the function's
    parameters -- nor, for one that forwards ``**options``, a keyword-only parameter of one of
    ``targets`` or a name ``extra(*args, **kwargs)`` lists (a motion's parameters; None: not
    known here, the callee decides) -- raises :class:`~accelcal.errors.OptionError` before
    anything runs, naming the public function, the option and the closest valid one."""
    def wrap(fn: Callable[..., Any]) -> Callable[..., Any]:
        params = [p for p in inspect.signature(fn).parameters.values() if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)]
        named = [p.name for p in params]
        options = [p.name for p in params if p.default is not p.empty]
        forwarded = list(dict.fromkeys(p.name for t in targets for p in inspect.signature(t).parameters.values()
                                       if p.kind is p.KEYWORD_ONLY and p.name not in named))

        @functools.wraps(fn)
        def checked(*args: Any, **kwargs: Any) -> Any:
            more = extra(*args, **kwargs) if extra is not None else []
            if more is not None:
                unknown = next((k for k in kwargs if k not in named and k not in forwarded and k not in more), None)
                if unknown is not None:
                    raise unknown_option(fn.__name__, unknown, named + forwarded + more, options + forwarded + more)
            return fn(*args, **kwargs)
        return checked
    return wrap
