"""``accelcal capture``: guided capture from a live sensor (docs/capture.md)."""
from __future__ import annotations

import argparse
import math
from typing import Any, Callable

import numpy as np

from ..calibrate import calibrate_recordings
from ..capture.events import Events
from ..capture.loop import CaptureLoop
from ..capture.source import LineSource, PortLost
from ..errors import AccelcalError, InputError
from ..io.calibration import save_calibration
from ..io.device import default_device, load_device
from ..io.recording import write_recording

#: exit status of a capture that stopped short of its target (the port lost, the input ended)
EXIT_SHORT = 1
#: exit status after Ctrl-C (what was captured is written)
EXIT_INTERRUPTED = 130

DESCRIPTION = ("Read a live sensor (one sample a line: the raw readings as comma-separated integers), find each still "
               "pose, refit the calibration jig-free after each, and tell the person the next orientation: the one "
               "that most reduces the worst parameter's uncertainty. Stops at the target or at --max-poses and writes "
               "the recording with pose labels (-o), which 'accelcal calibrate' reads to the same calibration.")


def positive_number(text: str, option: str) -> float:
    """``text`` as a finite number > 0, else one line naming ``option``.

    Parameters
    ----------
    text : str
        The option's value.
    option : str
        The option's name.

    Returns
    -------
    float
    """
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise InputError("<arguments>", f"{option} {text!r}: expected a number > 0", field=option)
    return v


def positive_int(text: str, option: str) -> int:
    """``text`` as an integer >= 1, else one line naming ``option``.

    Parameters
    ----------
    text : str
        The option's value.
    option : str
        The option's name.

    Returns
    -------
    int
    """
    try:
        v = int(text)
    except ValueError:
        v = 0
    if v < 1:
        raise InputError("<arguments>", f"{option} {text!r}: expected a whole number >= 1", field=option)
    return v


def add_capture_parser(sub: Any, check_output: Callable[..., None]) -> None:
    """Add ``capture`` to the subcommands.

    Parameters
    ----------
    sub : argparse subparsers
        The command's subparsers.
    check_output : callable
        The CLI's output-path check (before any work).
    """
    s = sub.add_parser("capture", help="guided capture from a live sensor: the next pose by information, stop at the "
                       "target", description=DESCRIPTION)
    s.add_argument("--port", required=True, metavar="PORT",
                   help="serial port or pseudo-terminal path (pyserial), '-' for standard input, or a file to replay")
    s.add_argument("--baud", default="115200", metavar="N", help="baud rate (default %(default)s)")
    s.add_argument("--device", required=True, metavar="D.json", help="device description (JSON), or 'default'")
    s.add_argument("-o", "--output", required=True, metavar="poses.csv",
                   help="the recording CSV with pose labels (written at the end, also after Ctrl-C or a lost port)")
    s.add_argument("--target-mg", default="1", metavar="X", help="target 1-sigma of every offset, mg (default 1)")
    s.add_argument("--target-pct", default="0.1", metavar="Y",
                   help="target 1-sigma of every sensitivity's magnitude, %% (default 0.1)")
    s.add_argument("--max-poses", default="40", metavar="K", help="stop after K poses (default 40)")
    s.add_argument("--json", action="store_true", dest="json_events",
                   help="standard output is JSON lines, one event a line (next_pose, pose_captured, progress, done); "
                   "the human text goes to standard error")
    s.add_argument("--time-column", action="store_true", help="each line begins with a time stamp (s)")
    s.add_argument("--calibration-out", metavar="CAL.json", help="also write the calibration of the poses captured")
    s.set_defaults(func=lambda a: cmd_capture(a, check_output))


def cmd_capture(a: argparse.Namespace, check_output: Callable[..., None]) -> int:
    """Run ``accelcal capture``.

    Parameters
    ----------
    a : argparse.Namespace
        The parsed options.
    check_output : callable
        The CLI's output-path check.

    Returns
    -------
    int
        0 at the target or --max-poses, 1 when the port was lost or the input ended first, 130 after Ctrl-C.
    """
    target_mg = positive_number(a.target_mg, "--target-mg")
    target_pct = positive_number(a.target_pct, "--target-pct")
    max_poses = positive_int(a.max_poses, "--max-poses")
    baud = positive_int(a.baud, "--baud")
    check_output(a.output)
    if a.calibration_out:
        check_output(a.calibration_out, "--calibration-out")
    dev = default_device() if a.device == "default" else load_device(a.device)
    events = Events(json_out=a.json_events)
    src = LineSource(a.port, baud, dev.n_channels, a.time_column)
    loop = CaptureLoop(dev, events, target_mg=target_mg, target_pct=target_pct, max_poses=max_poses,
                       bad_lines=lambda: src.bad_lines)
    events.say(f"capture: reading {a.port} ({dev.n_channels} channels a line{', time stamp first' if a.time_column else ''}); "
               f"target {target_mg:g} mg on every offset, {target_pct:g} % on every gain")
    loop.start()
    try:
        run(loop, src, dev.n_channels)
    except KeyboardInterrupt:
        loop.stop("interrupted")
    except PortLost as e:
        loop.stop("port_lost")
        events.say(f"capture: the port was lost ({e})")
    finally:
        src.close()
    loop.stop("end_of_input")
    return finish(a, loop, src, events)


def run(loop: CaptureLoop, src: LineSource, n_channels: int) -> None:
    """Feed the source's samples to the loop in chunks until it finishes or the source ends.

    Parameters
    ----------
    loop : CaptureLoop
    src : LineSource
    n_channels : int
    """
    ts: list = []
    rows: list = []
    try:
        for t, vals in src.samples():
            ts.append(t)
            rows.append(vals)
            if len(rows) >= loop.check_n:
                loop.feed(None if ts[0] is None else np.array(ts), np.array(rows))
                ts, rows = [], []
                if loop.finished:
                    return
    finally:
        if rows and not loop.finished:
            loop.feed(None if ts[0] is None else np.array(ts), np.array(rows).reshape(-1, n_channels))


def finish(a: argparse.Namespace, loop: CaptureLoop, src: LineSource, events: Events) -> int:
    """Write what was captured, say so, send ``done``, and give the exit status.

    Parameters
    ----------
    a : argparse.Namespace
    loop : CaptureLoop
    src : LineSource
    events : Events

    Returns
    -------
    int
        The exit status.
    """
    reason = loop.done_reason
    reached = reason == "target"
    wrote = []
    if loop.n:
        rec = loop.recording()
        write_recording(a.output, rec)
        wrote.append(f"{a.output} ({loop.n} samples, {loop.n_poses} poses)")
        if a.calibration_out:
            try:
                save_calibration(calibrate_recordings(loop.device, [rec], "jigfree"), a.calibration_out)
                wrote.append(a.calibration_out)
            except AccelcalError as e:
                events.say(f"capture: no calibration written: {e}")
    gain = (f"{np.max(loop.gain_sigma_pct):.3g} %" if np.all(np.isfinite(loop.gain_sigma_pct)) else "not fitted")
    worst = (f"worst offset sigma {np.max(loop.offset_sigma_mg):.3g} mg, worst gain sigma {gain}, model {loop.model}"
             if np.all(np.isfinite(loop.offset_sigma_mg)) else "no fit")
    how = {"target": "target reached", "max_poses": f"stopped at --max-poses {loop.max_poses}, target not reached",
           "interrupted": "interrupted (Ctrl-C), target not reached", "port_lost": "the port was lost, target not reached",
           "end_of_input": "the input ended, target not reached"}[reason]
    bad = (f"; {src.bad_lines} line(s) did not parse (first: {src.first_bad!r})" if src.bad_lines else "")
    files = "wrote " + ", ".join(wrote) if wrote else "nothing captured, nothing written"
    events.say(f"capture: {how} after {loop.n_poses} poses ({worst}); {files}{bad}")
    events.emit("done", poses=loop.n_poses, offset_sigma_mg=loop.offset_sigma_mg, gain_sigma_pct=loop.gain_sigma_pct,
                model=loop.model, target_reached=reached, reason=reason, bad_lines=src.bad_lines, samples=loop.n,
                seconds=float(loop.t[loop.n - 1] - loop.t[0]) if loop.n else 0.0,
                output=a.output if loop.n else None,
                calibration_out=a.calibration_out if a.calibration_out in wrote else None)
    if reason == "interrupted":
        return EXIT_INTERRUPTED
    return 0 if reason in ("target", "max_poses") else EXIT_SHORT

