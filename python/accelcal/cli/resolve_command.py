"""``accelcal resolve`` in chunks where it may (:mod:`accelcal.resolve_stream`, docs/streaming.md); the
``--omega`` of ``attitude`` and ``displacement`` (the array's own omega, as ``resolve`` chooses it)."""
from __future__ import annotations

import sys

from ..estimators.omega import omega_observability
from ..estimators.omega_fixed import ESTIMATOR_OMEGA
from ..firmware.terms import has_terms
from ..io.units_cli import add_units_options, scale_from_args
from ..resolve_stream import progress_factory, resolve_stream, resolve_warnings


def stream_resolve(a, dev, cal) -> bool:
    """Resolve ``a.recording`` into ``a.output`` chunk by chunk and print the command's stderr lines;
    False (nothing written) where the whole-file command must run: a calibration with correctable
    terms, omega from the array (``--omega array``, or ``auto`` without w columns on a layout that
    observes omega), or what :func:`accelcal.resolve_stream.resolve_stream` leaves to it."""
    if any(has_terms(cal).values()) or a.omega not in ("none", "reference", "auto"):
        return False
    if a.omega == "auto" and not dev.is_triad() and omega_observability(cal.positions_or_nominal(dev),
                                                                       cal.sensitivity).full:
        return False
    res = resolve_stream(dev, cal, a.recording, a.output, engine=a.engine, omega_source=a.omega,
                         scale=scale_from_args(a, dev, reader=True),
                         progress=None if a.quiet else progress_factory("resolve"))
    if res is None:
        return False
    for w in resolve_warnings(res.saturated, res.clip_warnings, res.extra):
        print(w, file=sys.stderr)
    return True


def add_estimator_options(s, name: str) -> None:
    """The options of ``accelcal attitude|displacement|rate`` after their own: ``--omega`` for attitude
    and displacement (not passed unless given: the estimator's default "auto"), the units' options."""
    if name in ("attitude", "displacement"):
        s.add_argument("--omega", choices=ESTIMATOR_OMEGA,
                       help="auto (default): the array's own omega where the layout observes it and the recording "
                       "has no complete w columns, else none; array: always (refused, with the layout that would, "
                       "where omega is not observable); none: no array omega (docs/angular-rate.md)")
    add_units_options(s)
