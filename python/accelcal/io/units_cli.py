"""The command line's ``--units``, ``--lsb``, ``--full-scale`` (with ``--bits`` and
``--gravity``): one argument group for ``convert`` and for every command that reads
recordings, and the one function that turns them into the :class:`~accelcal.io.units.Scale`
the readers take (:func:`accelcal.io.units.file_scale` then weighs it against the file's
``# units:``/``# lsb:`` comments: where both state the scale they must agree).
"""
from __future__ import annotations

import argparse
import math
from typing import Any

from ..errors import AccelcalError
from .units import UNITS, Scale, stated_scale

__all__ = ["add_units_options", "scale_from_args", "device_bits"]

UNITS_HELP = ("the unit of the recording's readings: counts (default), mps2 (m/s^2), mmps2 (mm/s^2: Klipper's "
              "ACCELEROMETER_MEASURE files), g or mg; all but counts need "
              "--lsb or --full-scale, and every reading must then be a whole number of LSBs (within 1e-6, "
              "or within the rounding of the digits it is printed with, up to a quarter of a count), "
              "else the first that is not is named by row and column.  The file's '# units:'/'# lsb:' "
              "comments state the same; given both, they must agree (a contradiction is refused, naming the "
              "comment)")
LSB_HELP = ("one count, in --units (m/s^2 or g per count; without --units, in the unit the file states by a "
            "'# units:' comment or its columns' names), e.g. 0.0047900390625 for 9.81/2048; or with its unit "
            "(mg, g, mps2, mmps2): '--units counts --lsb 1mg' states integer readings already in counts of 1 mg each "
            "(the nominal scale; nothing is converted, and readings that are not integers are refused)")
FULL_SCALE_HELP = ("the range's full scale in g (16 for +-16 g): one count is 2*G/2**bits g (--bits), in the unit "
                   "--units or else the file states; with counts it {counts}")
READER_BITS_HELP = ("the ADC's bits for --full-scale's LSB (default: from the device's raw range when "
                    "raw_max - raw_min + 1 is a power of two, else 16)")
READER_GRAVITY_HELP = ("g in m/s^2 for --full-scale with --units mps2 (default: the device's gravity_mps2, as "
                       "convert --device-out wrote it from convert --gravity)")


def add_units_options(parser: argparse.ArgumentParser, *, bits_help: str | None = None,
                      gravity_help: str | None = None, bits_default: str | None = None,
                      full_scale_counts: str = "converts nothing (it need only agree with the file's comments)") -> None:
    """Add the group "readings in physical units" to a subcommand's parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subcommand's parser.
    bits_help, gravity_help : str, optional
        Help of ``--bits`` and ``--gravity`` where the command gives them more meaning
        (``convert``: the device's range and g); default: the reading commands' (the
        LSB of ``--full-scale`` only, defaults from the device).
    bits_default : str, optional
        ``--bits``'s default (``convert``: "16"); None: from the device (:func:`device_bits`).
    full_scale_counts : str
        What ``--full-scale`` does with readings in counts, for its help.
    """
    g = parser.add_argument_group("readings in physical units",
                                  "for recordings whose readings are m/s^2 or g (floats that are whole "
                                  "multiples of the sensor's LSB); --units, --lsb and --full-scale mean the same in "
                                  "every command that reads recordings")
    g.add_argument("--units", choices=UNITS, help=UNITS_HELP)
    g.add_argument("--lsb", metavar="VALUE", help=LSB_HELP)
    g.add_argument("--full-scale", metavar="G", help=FULL_SCALE_HELP.format(counts=full_scale_counts))
    g.add_argument("--bits", default=bits_default, metavar="N", help=bits_help or READER_BITS_HELP)
    g.add_argument("--gravity", metavar="MPS2", help=gravity_help or READER_GRAVITY_HELP)
    g.add_argument("--round", action="store_true", help="round readings in m/s^2 or g to the nearest LSB (a "
                   "logger that writes calibrated floats, on no grid: choose an LSB well below the noise); a note "
                   "says how far they were off")


def device_bits(device: Any) -> int:
    """The ADC's bits a device's raw range implies (raw_max - raw_min + 1 = 2**bits), else 16."""
    if device is None:
        return 16
    span = int(device.raw_max) - int(device.raw_min) + 1
    bits = int(round(math.log2(span))) if span > 0 else 0
    return bits if 2 <= bits <= 32 and 2 ** bits == span else 16


def scale_from_args(a: argparse.Namespace, device: Any = None, *, reader: bool = False) -> Scale | None:
    """The Scale the options of :func:`add_units_options` state (None: nothing stated).

    Parameters
    ----------
    a : argparse.Namespace
        The parsed arguments.
    device : Device, optional
        The reading commands' device: the defaults of ``--bits`` (its raw range) and
        ``--gravity`` (its ``gravity_mps2``).
    reader : bool
        A command that only reads recordings: ``--bits`` and ``--gravity`` size nothing
        but ``--full-scale``'s LSB, so either without it is refused.

    Returns
    -------
    Scale or None
        An explicit ``--units counts`` alone is :data:`~accelcal.io.units.COUNTS_STATED`
        (converts nothing, but contradicts a file whose comments say m/s^2 or g).

    Raises
    ------
    AccelcalError
        A bad value or options that contradict each other (one line naming the option).
    """
    if reader and a.full_scale is None:
        for opt, value in (("--bits", a.bits), ("--gravity", a.gravity)):
            if value is not None:
                raise AccelcalError(f"{opt} {value}: it sizes only --full-scale's LSB; give --full-scale G "
                                    "(or the LSB itself with --units mps2|g --lsb VALUE)")
    bits = a.bits if a.bits is not None else device_bits(device)
    gravity = a.gravity if a.gravity is not None or device is None else device.gravity_mps2
    return stated_scale(a.units, a.lsb, a.full_scale, bits, gravity, getattr(a, "round", False))
