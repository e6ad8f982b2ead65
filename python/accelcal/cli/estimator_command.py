"""``accelcal attitude``, ``displacement`` and ``rate``: load, estimate, write (in chunks where they
may: :mod:`accelcal.estimators.rate_stream`, :mod:`~accelcal.estimators.attitude_stream`,
:mod:`~accelcal.estimators.displacement_stream`, docs/streaming.md)."""
from __future__ import annotations

import sys

import numpy as np

from ..estimators import attitude_from_recording, displacement_from_recording, rate_from_recording, report_plots
from ..estimators.attitude_stream import attitude_stream
from ..estimators.displacement_stream import displacement_stream
from ..estimators.rate_stream import rate_stream
from ..io.calibration import load_calibration
from ..io.device import default_device, load_device
from ..io.recording import read_recording, write_columns_csv
from ..io.recording_checks import seconds
from ..io.units_cli import scale_from_args
from ..readings.held import held_runs, held_text, readings_rate
from ..resolve_stream import progress_factory
from .paths import check_output, check_output_dir

__all__ = ["ESTIMATORS", "run_estimator", "held_warnings", "estimator_command", "reader_notes", "time_note",
           "load_device_arg", "STREAMED", "STREAM_OPTIONS"]


def reader_notes(rec, command: str) -> list[str]:
    """What the reader did to a recording (a last line cut short, a shifted grid, rounding), one
    stderr line each."""
    return [f"accelcal {command}: note: {rec.source}: {n}" for n in rec.notes]


def time_note(rec, device, command: str) -> None:
    """t in milliseconds (or micro-, nanoseconds) read as such, said once on stderr."""
    note = seconds(rec, device)
    if note is not None:
        print(f"accelcal {command}: note: {rec.source}: {note}", file=sys.stderr)


def load_device_arg(path):
    """The device file, or the seed prototype for "default" (or None)."""
    return default_device() if path in (None, "default") else load_device(path)


ESTIMATORS = {"attitude": attitude_from_recording, "displacement": displacement_from_recording,
              "rate": rate_from_recording}


#: the estimators that read a recording in chunks where they may
STREAMED = {"attitude": attitude_stream, "displacement": displacement_stream, "rate": rate_stream}
#: the options each passes on to its chunked form (any other option given: the whole-file command)
STREAM_OPTIONS = {"attitude": {"omega"}, "displacement": {"omega", "axis", "form"}, "rate": {"omega"}}


def run_estimator(kind: str, device_path, calibration_path, recording_path, output, *, engine: str = "float",
                  report=None, units_args=None, stream: bool = False, quiet: bool = True,
                  **options) -> list[str]:
    """`accelcal attitude|displacement|rate --device D --calibration C REC -o OUT [--engine] [--report DIR]`.

    Load, estimate, write the CSV (atomically) and, with ``report``, the plots.

    Parameters
    ----------
    kind : {"attitude", "displacement", "rate"}
    device_path, calibration_path, recording_path : path
        Inputs (device "default" or None: the seed prototype).
    output : path
        The result CSV.
    engine : {"float", "fixed"}
    report : path, optional
        Directory for the plots.
    stream : bool
        rate, attitude and displacement (options ``form``, ``axis``, ``omega``
        only), without ``report``: read the recording in chunks where it may (:data:`STREAMED`,
        docs/streaming.md), the same output.
    quiet : bool
        No progress bar (the streamed form's; off anyway when stderr is not a terminal).
    units_args : argparse.Namespace, optional
        The parsed ``--units``/``--lsb``/``--full-scale``/``--bits``/``--gravity``
        (units_cli.add_units_options) the recording is read with.
    **options
        To the estimator (attitude: gain, w2_gate, leak_tau_s; displacement: form, axis, keep_turned, resample;
        rate: leak_tau_s).

    Returns
    -------
    list of str
        The warnings, one line each, for the caller to print to stderr.

    Raises
    ------
    AccelcalError
        Bad input (one line), before anything is written.
    """
    fn = ESTIMATORS.get(kind)
    if fn is None:
        raise ValueError(f"unknown estimator {kind!r}")
    check_output(output)
    if report is not None:
        check_output_dir(report, "--report")
    dev = load_device_arg(device_path)
    cal = load_calibration(calibration_path, dev)
    if isinstance(cal.extra, dict) and cal.method != "nominal":
        cal.extra["source"] = str(calibration_path)       # the calibration a message names
    scale = None if units_args is None else scale_from_args(units_args, dev, reader=True)
    streamed = STREAMED.get(kind) if stream and report is None else None
    passed = STREAM_OPTIONS.get(kind, set())
    if streamed is not None and set(options) <= passed | {"omega"} and (
            "omega" in passed or options.get("omega", "alpha") == "alpha"):
        warnings = streamed(dev, cal, recording_path, output, engine=engine, scale=scale,
                            progress=None if quiet else progress_factory(kind),
                            **{k: v for k, v in options.items() if k in passed})
        if warnings is not None:
            return [f"accelcal {kind}: warning: {w}" for w in warnings]
    # displacement leaves out a sample a logger wrote twice (with a note): its integrators need
    # each sample once, and the copy is plainly one
    rec = read_recording(recording_path, dev.n_channels, scale=scale, repeats=kind == "displacement")
    notes = reader_notes(rec, kind)            # the reader's, before t's unit adds its own
    time_note(rec, dev, kind)
    cols = fn(dev, cal, rec, engine, **options)
    warnings = held_warnings(rec) + cols.warnings
    # the notes and warnings in the output's comments too, one line each
    meta = {**cols.meta, **{f"note_{k}": n for k, n in enumerate(rec.notes, 1)},
            **{f"warning_{k}": w for k, w in enumerate(warnings, 1)}}
    write_columns_csv(output, cols, meta)
    if report is not None:
        report_plots(report, cols, rec, kind)
    return notes + [f"accelcal {kind}: warning: {w}" for w in warnings]


def held_warnings(rec) -> list[str]:
    """A per-sample estimator's warning for readings a logger held for several rows
    (:func:`accelcal.readings.held.held_runs`): its output repeats each reading, and the motion between
    two readings is not seen."""
    k, first = held_runs(rec.raw)
    if k == 1:
        return []
    hz = readings_rate(rec, first)
    rows_hz = readings_rate(rec, np.arange(rec.n_samples))         # every row taken as a reading
    rates = f": the readings change at about {hz:.4g} Hz, the rows come at {rows_hz:.4g} Hz" if hz is not None else ""
    return [f"each reading is held for {held_text(k, first, rec.n_samples)} (the logger read the sensor faster "
            f"than it updates){rates}; the motion between two readings is not seen, and a held reading looks "
            "still: a rest found within one is no rest"]


def estimator_command(a, kind):
    """`accelcal attitude|displacement|rate`: run it and print its stderr lines; exit 0."""
    options = {k: v for k, v in (("axis", getattr(a, "axis", None)), ("form", getattr(a, "form", None)),
                                 ("omega", getattr(a, "omega", None))) if v is not None}
    for flag in ("keep_turned", "resample"):
        if getattr(a, flag, False):
            options[flag] = True
    for w in run_estimator(kind, a.device, a.calibration, a.recording, a.output, engine=a.engine,
                           report=a.report, units_args=a, stream=not getattr(a, "whole_file", True),
                           quiet=getattr(a, "quiet", False), **options):
        print(w, file=sys.stderr)
    return 0
