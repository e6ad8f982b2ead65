"""The ``accelcal convert`` subcommand: its options and what it prints (the work is
:func:`accelcal.convert.formats.convert_file`)."""
from __future__ import annotations

import argparse
import math
import sys
from typing import Any, Callable

from ..convert.formats import FORMATS, convert_file
from ..io.device import save_device
from ..errors import AccelcalError
from ..io.parquet import is_parquet
from ..resolve_stream import progress_factory
from ..io.units import parse_bits
from ..io.units_cli import add_units_options, scale_from_args

__all__ = ["add_convert_parser", "cmd_convert"]

DESCRIPTION = """\
Write the data contract's recording CSV (t, raw_0..raw_2 in counts, pose, and f_x..f_z when
the poses state their orientation) from another tool's file, and with --device-out a nominal
device JSON for it.  Formats: imu_tk (whitespace 't ax ay az' in counts, no header), imucal
(CSV with acc_x, acc_y, acc_z; no time column: --rate; poses from --regions JSON or a 'part'
column), mpu6050 (the logger's 'Fs,100'... lines, then ax,ay,az,gx,gy,gz in signed counts),
csv (a recording: compressed, whitespace and physical units rewritten as plain counts), log (a serial
monitor's capture: lines of three numbers among the logger's prompts, no header: --rate; with
--blocks each run of readings between text lines is a pose), table (a CSV or whitespace table
with named columns, told last: one accelerometer column per axis such as accX, acc_y, 'Acceleration
z (m/s^2)', 'Accelerometer X (g)' or scaledAccelX, a unit in all three names being the readings'
unit (with --full-scale or --lsb for the LSB); an optional time column t, time, timestamp,
'Time (s)', time_ms, ..., else --rate; rows whose three readings are all empty are skipped, linear
acceleration and gravity columns are refused).  Any of them may be compressed (gzip, bzip2, xz,
zstd, a zip of one file).  mat: a MATLAB file (version 5 or 7.3, told by its header) holding an
array of 3 columns x, y, z (--rate) or 4 columns t, x, y, z; --variable names it where there are
several.  e4: an Empatica E4's ACC.csv (row 1 the start as unix time, row 2 the rate, each repeated
in three columns; then x,y,z in counts of 1/64 g).  Gyroscope columns are dropped with a note."""


def positive(text: Any, option: str) -> float | None:
    """An option's finite value > 0 (None when not given)."""
    if text is None:
        return None
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise AccelcalError(f"{option} {text!r}: expected a finite number > 0")
    return v


def print_notes(notes: Any) -> None:
    """Each note a line on stderr."""
    for note in notes:
        print(f"accelcal convert: note: {note}", file=sys.stderr)


def cmd_convert(a: argparse.Namespace, check_output: Callable[..., None]) -> int:
    """Convert, write the recording (and the device), print the notes and a one-line summary."""
    check_output(a.output)
    if a.device_out is not None:
        check_output(a.device_out, "--device-out")
        if a.device_out == a.output:
            raise AccelcalError(f"--device-out {a.device_out}: the same file as -o")
    bits = parse_bits(a.bits, AccelcalError, "--bits")
    scale = scale_from_args(a)
    try:
        conv = convert_file(a.input, a.format, scale=scale, rate_hz=positive(a.rate, "--rate"), regions=a.regions,
                            stated_f=a.stated_f, gravity_mps2=positive(a.gravity, "--gravity"), bits=bits,
                            blocks=a.blocks, time_unit=a.time_unit,
                            variable=a.variable, time_column=a.time_column,
                            repeated_stamps=a.repeated_stamps, columns=a.columns,
                            stream=not a.whole_file and not is_parquet(a.output),
                            progress=None if a.quiet else progress_factory("convert"))
    except AccelcalError as e:          # the notes made before a refusal, ahead of its error line
        print_notes(e.notes)
        raise
    conv.write(a.output)
    if a.device_out is not None:
        save_device(conv.device, a.device_out)
    print_notes(conv.notes + (conv.device_notes if a.device_out is not None else []))
    print(conv.summary(a.output) + (f"; device {a.device_out}" if a.device_out else ""))
    return 0


def add_convert_parser(sub: Any, check_output: Callable[..., None]) -> None:
    """Add ``convert`` to the subcommands (``check_output``: the CLI's output-path check)."""
    s = sub.add_parser("convert", help="the contract's recording CSV from imu_tk, imucal, MPU-6050, serial-monitor "
                       "logs, tables with named accelerometer columns or other recording files", description=DESCRIPTION)
    s.add_argument("input", metavar="FILE", help="the file to convert (compressed or not: gzip, bzip2, xz, zstd, a zip of one file)")
    s.add_argument("--format", choices=FORMATS, default="auto",
                   help="the input's format (default auto: told from its first line)")
    add_units_options(s, bits_default="16", full_scale_counts="sets only the device's nominal scale",
                      bits_help="the ADC's bits (default 16): the device's raw range, and the LSB of --full-scale",
                      gravity_help="g in m/s^2 for --full-scale with mps2, the stated f and the device (default "
                      "9.80665; imu_tk 9.81744)")
    s.add_argument("--rate", metavar="HZ", help="sample rate of a file without a time column (imucal, log, a table: "
                   "required; the MPU-6050 log: its Fs line otherwise); with a time column, the device's rate "
                   "(where a host's time stamps do not give it)")
    s.add_argument("--time-unit", metavar="UNIT", default="auto",
                   help="the time column's unit: s, ms, us, ns, or a tick of a chip's clock, a number of one "
                   "(25us) (default auto: the unit its name states, else seconds, but "
                   "time stamps that would be under 2 Hz in seconds are read in the smallest of "
                   "ms, us, ns that gives more, with a note; a chip's clock preferred to a host's packet stamps is "
                   "measured against them); t is written in seconds")
    s.add_argument("--time-column", metavar="NAME", help="table: the time column (default: of the columns named "
                   "t, time, timestamp, 'Time (s)', ..., those holding numbers, not a clock time or a date, the "
                   "first whose name states a unit, else the first; a note names it)")
    s.add_argument("--columns", metavar="X,Y,Z", help="table: the accelerometer's three columns, comma-separated, as "
                   "the header names them (default: the names say: accX, 'Acceleration y (m/s^2)', 'x (g)', ...); a "
                   "unit in () or [] at a name's end states the readings' unit; a file not told otherwise is then "
                   "read as a table")
    s.add_argument("--repeated-stamps", choices=("refuse", "drop", "shift"), default="refuse",
                   help="table: rows whose time stamp repeats the row before's with other readings (a watch that "
                   "stamps two samples with one stamp) are refused (default; the message counts them) or, with drop, "
                   "left out with a note; shift moves stamps that slipped a place late (after a step of two, caught "
                   "up by the repeat) back one step, keeping every sample, and leaves out the other repeats")
    s.add_argument("--variable", metavar="NAME", help="mat: the array of readings (3 columns x, y, z, or 4: t, x, y, "
                   "z) where the MATLAB file holds more than one; or X,Y,Z (T,X,Y,Z): the names of vectors that hold "
                   "one channel each")
    s.add_argument("--regions", metavar="FILE", help="a JSON file of pose regions {name: {\"start\": s, \"end\": e}} in "
                   "sample numbers, end excluded (imucal's session list); names ending in _rot are motions")
    s.add_argument("--blocks", action="store_true", help="log: each run of readings between the logger's text "
                   "lines (a prompt before each pose) is a pose, labelled block_1, block_2, ...")
    s.add_argument("--stated-f", action="store_true", help="poses named x_p, x_a, y_p, y_a, z_p, z_a (that "
                   "axis up, p, or down, a) get the reference f = +-g along it, for a known-pose calibration")
    s.add_argument("--device-out", metavar="D.json", help="also write a nominal device JSON for the "
                   "recording (a triad at the origin; scale from the LSB, else from the readings; no noise_mps2: "
                   "every command estimates the noise from the recording, and a noise_mps2 > 0 added by hand "
                   "overrides that)")
    s.add_argument("--whole-file", action="store_true", help="read the file whole (a recording CSV is otherwise "
                   "read in chunks, twice: docs/streaming.md)")
    s.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    s.add_argument("-o", "--output", required=True, metavar="OUT.csv",
                   help="the recording CSV to write (atomically: no partial file on error)")
    s.set_defaults(func=lambda a: cmd_convert(a, check_output))
