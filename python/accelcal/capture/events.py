"""The capture's events: JSON lines on standard output with ``--json`` (one event a line), the
human text on standard error (always).  The events are documented in docs/capture.md."""
from __future__ import annotations

import json
import math
import sys
from typing import Any, Callable, TextIO


def clean(value: Any) -> Any:
    """``value`` with numpy numbers and arrays as plain JSON (NaN and infinities as null).

    Parameters
    ----------
    value : Any
        A number, array, list or dict.

    Returns
    -------
    Any
        The same in JSON's types.
    """
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, dict):
        return {k: clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


class Events:
    """Where the capture says what happens.

    Parameters
    ----------
    json_out : bool
        Write each event as a JSON line to ``out``.
    out, err : file, optional
        Standard output and error (defaults: sys.stdout, sys.stderr).
    listener : callable, optional
        Called with every event dict (the in-process simulations react to ``next_pose``).
    quiet : bool
        No human text.
    """

    def __init__(self, json_out: bool = False, out: TextIO | None = None, err: TextIO | None = None,
                 listener: Callable[[dict], None] | None = None, quiet: bool = False):
        self.json_out = json_out
        self.out = out
        self.err = err
        self.listener = listener
        self.quiet = quiet
        self.log: list[dict] = []

    def emit(self, event: str, **fields: Any) -> dict:
        """Send one event.

        Parameters
        ----------
        event : str
            ``next_pose``, ``pose_captured``, ``progress``, ``done``.
        **fields : Any
            Its fields (numpy values are converted).

        Returns
        -------
        dict
            The event as sent.
        """
        ev = {"event": event, **clean(fields)}
        self.log.append(ev)
        if self.json_out:
            out = self.out or sys.stdout
            out.write(json.dumps(ev) + "\n")
            out.flush()
        if self.listener is not None:
            self.listener(ev)
        return ev

    def say(self, text: str) -> None:
        """One line of human text on standard error.

        Parameters
        ----------
        text : str
            The line.
        """
        if self.quiet:
            return
        err = self.err or sys.stderr
        err.write(text + "\n")
        err.flush()
