"""``accelcal attitude`` in chunks (docs/streaming.md): memory that does not grow with the
recording, the whole-file output byte for byte.

The first pass is :func:`accelcal.estimators.stream_scan.scan` (dt, the noise); the second takes
each chunk through the triads' f (float reference or the C core) and the estimator with its state
carried over (:func:`~accelcal.estimators.attitude.attitude_core`'s ``state``, the C core's
``ac_att``), counting what the warnings say (samples unsettled, |g| off, saturated).  The warnings
are comments above the rows, so the rows go to a temporary file first
(:func:`accelcal.io.result_sink.write_deferred`).

With the array's own omega (``--omega array``, or ``auto`` on a layout that observes it and a file
without w columns) the second pass runs the fused omega filter (float: :class:`FusedOmega`; fixed:
the C core's ``ac_omega`` through :class:`~accelcal.firmware.omega_table.OmegaCore`) with its state
carried, and :func:`~accelcal.estimators.attitude.array_block` on each chunk.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from ..errors import AccelcalError, InputError
from ..firmware.native import FORMATS
from ..firmware.omega_table import OmegaCore, device_omega_table
from ..firmware.quantize import quantize_calibration
from ..firmware.triad import triad_forces
from ..io.chunk_source import open_chunks
from ..io.chunks import BLOCK_BYTES, Fallback
from ..io.parquet import BATCH_ROWS
from ..io.result_sink import write_deferred
from .attitude import (AttitudeConsts, AttitudeParams, array_block, array_warnings, att_init_fixed, attitude_core,
                       fixed_block, float_outputs, triad_geometry)
from .common import force_noise, time_span
from .omega import FusedOmega, omega_observability
from .omega_fixed import ESTIMATOR_OMEGA, pretrim
from .stream_scan import on_grid, scan_with_bar

__all__ = ["attitude_stream"]

NAMES = ["t", "theta_rad", "w_y", "dw_y", "g_mps2", "gated", "unsettled", "saturated"]
#: with the array's own omega
ARRAY_NAMES = ["t", "theta_rad", "w_y", "dw_y", "g_mps2", "w_y_sigma", "gated", "unsettled", "saturated"]


def attitude_stream(device, cal, path: Any, output: Any, *, engine: str = "float", gain: float = 2.0,
                    w2_gate: float | None = None, leak_tau_s: float = 2.0, omega: str = "auto", scale: Any = None,
                    block_bytes: int = BLOCK_BYTES, batch_rows: int = BATCH_ROWS,
                    progress: Callable[[Any, str], Any] | None = None) -> list[str] | None:
    """`accelcal attitude` from ``path`` into ``output`` chunk by chunk.

    Parameters
    ----------
    device, cal : Device, Calibration
        Two triads on body x (:func:`~accelcal.estimators.attitude.attitude_from_recording`).
    path, output : str or os.PathLike
        The recording and the result (Parquet by the name .parquet, else CSV).
    engine : {"float", "fixed"}
    gain, w2_gate, leak_tau_s : float
        As :func:`~accelcal.estimators.attitude.attitude_from_recording` (1/rad, (rad/s)^2, s).
    omega : {"auto", "array", "none"}
        As :func:`~accelcal.estimators.attitude.attitude_from_recording`.
    scale : units.Scale, optional
    block_bytes, batch_rows : int
        Chunk size: bytes of CSV text, rows of Parquet.
    progress : callable, optional
        ``progress(total, unit)`` -> a bar (one per pass).

    Returns
    -------
    list of str or None
        The warnings (the whole-file command's); None where the whole-file command must run
        (nothing written).

    Raises
    ------
    InputError
        Bad rows, as the whole-file command words them (nothing written).
    """
    if engine not in ("float", "fixed") or omega not in ESTIMATOR_OMEGA:
        return None
    observed = not device.is_triad() and omega_observability(cal.positions_or_nominal(device), cal.sensitivity).full
    if omega == "array" or (omega == "auto" and observed):
        if not observed:
            return None                     # the whole-file command's refusal, after its checks
        try:
            src = open_chunks(path, device.n_channels, scale, block_bytes, batch_rows)
        except Fallback:
            return None
        return _array_stream(device, cal, src, output, engine=engine, auto=omega == "auto", progress=progress)
    try:
        r1, r2 = triad_geometry(device, cal)
    except InputError:
        return None                         # the whole-file command checks the recording first
    try:
        src = open_chunks(path, device.n_channels, scale, block_bytes, batch_rows)
        sc = scan_with_bar(device, src, fixed=engine == "fixed", progress=progress)
    except Fallback:
        return None
    try:
        p = AttitudeParams(r1=r1, r2=r2, dt=sc.dt, gain=gain, w2_gate=w2_gate,
                           noise_mps2=max(force_noise(device, cal, sc.noise, (0, 1, 2)), 1e-4), leak_tau_s=leak_tau_s)
        p.check()
    except AccelcalError:
        return None                         # the whole-file command words it, in its order
    signed = device.raw_min < 0
    g0 = float(device.gravity_mps2)
    fixed = att_init_fixed(p) if engine == "fixed" else None
    consts = AttitudeConsts.exact(p) if engine == "float" else None
    state: dict = {}
    tally = SimpleNamespace(unsettled=0, off=0, sat=0, t0=sc.t0, at=None)

    def produce(sink: Any) -> dict:
        bar = progress(src.total, src.unit) if progress is not None else None
        for ch in src.chunks(None if bar is None else bar.update):
            on_grid(sc, ch.start, ch.t)
            rec = SimpleNamespace(raw=ch.raw)
            if engine == "float":
                r = attitude_core(*(triad_forces(cal, rec, c, "float")[0] for c in ((0, 1, 2), (3, 4, 5))), consts,
                                  state=state)
                theta, w, dw, gmag, gated, unsettled, sat = float_outputs(r, ch.n)
            else:
                theta, w, dw, gmag, gated, unsettled, sat = fixed_block(cal, rec, p, signed, state=fixed)
            k = tally.unsettled + int(np.count_nonzero(unsettled))
            if (k > tally.unsettled and tally.unsettled < ch.start) or np.any(unsettled[1:] & ~unsettled[:-1]):
                raise Fallback("unsettled samples that are not the first")   # the warning names sample k
            # the warning names sample min(k, n - 1): k once the first k are unsettled
            if tally.at is None and ch.start <= k < ch.start + ch.n:
                tally.at = (float(ch.t[k - ch.start]), ch.line(k - ch.start))
            tally.unsettled = k
            tally.off += int(np.count_nonzero(np.abs(gmag - g0) > 0.2 * g0))
            tally.sat += int(np.count_nonzero(sat))
            if ch.n and ch.start + ch.n == sc.n and tally.at is None:
                tally.at = (float(ch.t[-1]), ch.line(ch.n - 1))
            sink.write([ch.t, theta, w, dw, gmag, gated.astype(float), unsettled.astype(float), sat.astype(float)])
        if bar is not None:
            bar.close()
        warnings = warnings_of(tally)
        meta = {"engine": engine, "device": device.name, "r1_m": f"{r1:.6g}", "r2_m": f"{r2:.6g}",
                "w2_gate": f"{p.gate():.6g}", "gain": f"{gain:g}", "leak_tau_s": f"{leak_tau_s:g}"}
        return {**meta, **{f"warning_{k}": w for k, w in enumerate(warnings, 1)}}

    return _write(output, NAMES, produce)


def _array_stream(device, cal, src: Any, output: Any, *, engine: str, auto: bool,
                  progress: Callable[[Any, str], Any] | None) -> list[str] | None:
    """attitude with the array's own omega, chunk by chunk (see the module doc)."""
    try:
        sc = scan_with_bar(device, src, fixed=engine == "fixed", progress=progress)
    except Fallback:
        return None
    if engine == "float":
        fo = FusedOmega(cal.offsets, cal.sensitivity, cal.positions_or_nominal(device), sc.dt,
                        np.sqrt(np.asarray(sc.noise, float) ** 2 + 1.0 / 12.0))
    else:       # omega_fixed.table_for_recording's table, its refusals the whole-file command's
        table = device_omega_table(device, cal) if device.noise_mps2 > 0 else None
        if table is None or abs(sc.dt * float(device.sample_rate_hz) - 1.0) > 0.01:
            return None
        tables, core = quantize_calibration(device, cal), OmegaCore(table)
    g0 = float(device.gravity_mps2)
    tally = SimpleNamespace(off=0, sat=0)

    def produce(sink: Any) -> dict:
        bar = progress(src.total, src.unit) if progress is not None else None
        for ch in src.chunks(None if bar is None else bar.update):
            on_grid(sc, ch.start, ch.t)
            if auto and ch.vecs.get("w") is not None:
                raise Fallback("w columns: auto takes them where complete")
            if engine == "float":
                w, cov = fo.step(*fo.readings(ch.raw))
                sigma, w_core = np.sqrt(np.diagonal(cov, axis1=1, axis2=2)), None
            else:
                w16, w10, sig, _, _ = core.run(pretrim(tables, ch.raw)[0])
                w, sigma, w_core = w16 * 2.0 ** -16, sig * 2.0 ** -16, w10 * 2.0 ** -FORMATS.omega_frac
            rec = SimpleNamespace(raw=ch.raw, source=src.head.source, line=ch.line)
            theta, dw, gmag, sat = array_block(device, cal, rec, engine, w, w_core)
            tally.off += int(np.count_nonzero(np.abs(gmag - g0) > 0.2 * g0))
            tally.sat += int(np.count_nonzero(sat))
            zero = np.zeros(ch.n)
            sink.write([ch.t, np.asarray(theta, float), np.asarray(w[:, 1], float), np.asarray(dw, float),
                        np.asarray(gmag, float), sigma[:, 1], zero, zero, sat.astype(float)])
        if bar is not None:
            bar.close()
        meta = {"engine": engine, "device": device.name, "omega": "array"}
        return {**meta, **{f"warning_{k}": w for k, w in enumerate(array_warnings(tally.off, tally.sat), 1)}}

    return _write(output, ARRAY_NAMES, produce)


def _write(output: Any, names: list[str], produce: Callable[[Any], dict]) -> list[str] | None:
    """``write_deferred(output, names, produce)``; the warnings among the comments ``produce``
    returns, or None where it falls back (nothing written)."""
    result: list[str] = []

    def keep(sink: Any) -> dict:
        meta = produce(sink)
        result.extend(v for k, v in meta.items() if k.startswith("warning_"))
        return meta

    try:
        write_deferred(output, names, keep)
    except Fallback:
        return None
    return result


def warnings_of(tally: Any) -> list[str]:
    """attitude's warnings from the counts (the whole-file command's words)."""
    out = []
    if tally.unsettled:
        k = tally.unsettled
        t_at, row = tally.at
        until = time_span(np.array([tally.t0, t_at]), 1, rec=SimpleNamespace(lines=1, line=lambda i: row))
        out.append(f"attitude: the sign of w_y is not yet established for the first {k} samples "
                   f"(until {until}: no pass through low rate yet); column unsettled = 1")
    if tally.off:
        out.append(f"attitude: on {tally.off} samples the two triads see |g| more than 20 % "
                   "off gravity (pivot moving, wrong r1/r2, or clipping): theta there is doubtful; "
                   "column g_mps2")
    if tally.sat:
        out.append(f"attitude: {tally.sat} samples clipped in the fixed-point core (column saturated)")
    return out
