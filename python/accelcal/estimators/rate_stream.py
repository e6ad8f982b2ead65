"""``accelcal rate`` in chunks (``--omega alpha`` and ``array``; docs/streaming.md): memory that does
not grow with the recording, the whole-file output byte for byte.

Two passes over the file: :func:`accelcal.estimators.stream_scan.scan` (dt, the noise, and that
nothing else needs the whole recording), then chunk by chunk f and alpha (the float reference or
the C core's batch resolver), the rest detector and the leaky integrator with their state
carried from one chunk to the next (the float :class:`~accelcal.estimators.rest.RestState` and
scipy's ``lfilter`` state; the C core's ``ac_rest`` and ``ac_rate``), or (``--omega array``) the
array's fused omega filter with its state carried (:class:`~accelcal.estimators.omega.FusedOmega`),
each chunk written as it is done into a temporary file that replaces the output at the end.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any, Callable

import numpy as np
from scipy.signal import lfilter

from .. import model
from ..errors import atomic_write
from ..firmware import native
from ..firmware.native import check, cptr, ffi, lib
from ..firmware.quantize import quantize_calibration, round_half_up
from ..io.chunk_source import open_chunks
from ..io.chunks import BLOCK_BYTES, Fallback
from ..io.parquet import BATCH_ROWS, is_parquet
from ..io.result_sink import ColumnSink
from .common import CLIP, CLIP_LO, OMEGA_FRAC, alpha_noise, dt_fixed, force_noise
from .omega import FusedOmega, omega_columns, omega_observability
from .rate import LEAK_FRAC
from .rest import REST_AT_REST, RestState, RestThresholds, default_rest_params, rest_cfg_fixed
from .stream_scan import RANK_RANGE, Deferred, on_grid, raise_deferred, scan_with_bar

__all__ = ["rate_stream"]


class _FloatRate:
    """The float reference's rest detector and integrator, state carried across chunks."""

    def __init__(self, device, cal, rest, dt: float, leak: float) -> None:
        self.args = (cal.offsets, cal.sensitivity, cal.positions_or_nominal(device))
        self.rest = RestState(RestThresholds.of(rest, False))
        self.b, self.a = [dt], [1.0, -(1.0 - leak)]
        self.zi: np.ndarray | None = None          # the integrator's state where a motion runs on

    def step(self, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n = raw.shape[0]
        # BLAS multiplies one row (gemv) with other roundings than many (gemm): a lone row goes in twice
        f, alpha = model.resolve(*self.args, np.repeat(raw, 2, axis=0) if n == 1 else raw, None)
        f, alpha = f[:n], alpha[:n]
        fl = np.clip(f, CLIP_LO, CLIP).tolist()
        al = alpha.tolist()
        flags = np.zeros(n, np.uint8)
        for i in range(n):
            flags[i] = self.rest.step(fl[i], al[i])[0]
        at = (flags & REST_AT_REST) != 0
        w = np.zeros_like(alpha)
        edges = np.diff(np.concatenate(([0], (~at).astype(np.int8), [0])))
        carry = None
        for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            zi = self.zi if s == 0 and self.zi is not None else np.zeros((1, 3))
            w[s:e], zf = lfilter(self.b, self.a, alpha[s:e], axis=0, zi=zi)
            if e == n:
                carry = zf
        self.zi = carry
        return w, flags


class _FixedRate:
    """The C core: the batch resolver, then ac_rest_rate_step per sample with its state carried."""

    def __init__(self, device, cal, rest, dt: float, leak: float) -> None:
        t = quantize_calibration(device, cal)
        self.resolver, self.trim = t.resolver(), t.trim
        self.rs = ffi.new("ac_rest *")
        check(lib.ac_rest_init(self.rs, rest_cfg_fixed(rest)), "ac_rest_init")
        self.rt = ffi.new("ac_rate *")
        dm, dsh = dt_fixed(dt)
        check(lib.ac_rate_init(self.rt, dm, dsh, int(round_half_up(leak * 2.0**LEAK_FRAC))), "ac_rate_init")

    def step(self, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        out, _ = native.process_batch(self.resolver, self.trim, raw, None)
        f_q = np.ascontiguousarray(out[:, :3], dtype=np.int32)
        a_q = np.ascontiguousarray(out[:, 3:], dtype=np.int32)
        n = raw.shape[0]
        om = np.zeros((n, 3), np.int16)
        flags = np.zeros(n, np.uint8)
        # pointers into the chunk's arrays, stepped per sample (cffi's arithmetic: no array per call)
        fp, ap = cptr("int32_t *", f_q), cptr("int32_t *", a_q)
        wp, flp = cptr("int16_t *", om), cptr("uint8_t *", flags)
        step, rs, rt = lib.ac_rest_rate_step, self.rs, self.rt
        for i in range(n):
            k = 3 * i
            status = step(rs, rt, fp + k, ap + k, wp + k, flp + i)
            if status < 0:
                check(status, "ac_rest_rate_step")
        return om.astype(np.int64) / 2.0**OMEGA_FRAC, flags.astype(np.int64)


class _ArrayRate:
    """The array's own omega (``--omega array``): the fused filter, its state carried across chunks."""

    def __init__(self, device, cal, noise: np.ndarray, dt: float) -> None:
        self.fo = FusedOmega(cal.offsets, cal.sensitivity, cal.positions_or_nominal(device), dt,
                             np.sqrt(np.asarray(noise, float) ** 2 + 1.0 / 12.0))

    def step(self, raw: np.ndarray) -> list[np.ndarray]:
        w, cov = self.fo.step(*self.fo.readings(raw))
        sigma = np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
        return list(omega_columns(SimpleNamespace(w=w, sigma=sigma)).values())


def rate_stream(device, cal, path: Any, output: Any, *, engine: str = "float", leak_tau_s: float = 5.0,
                omega: str = "alpha", scale: Any = None, block_bytes: int = BLOCK_BYTES,
                batch_rows: int = BATCH_ROWS, progress: Callable[[Any, str], Any] | None = None) -> list[str] | None:
    """`accelcal rate` from ``path`` into ``output`` chunk by chunk.

    Parameters
    ----------
    device, cal : Device, Calibration
        A 6-DOF array.
    path, output : str or os.PathLike
        The recording and the result (Parquet by the name .parquet, else CSV).
    engine : {"float", "fixed"}
    leak_tau_s : float
        The integrator's leak time constant, s (0: none; ``omega`` "alpha").
    omega : {"alpha", "array"}
        "array": the array's own omega (:func:`accelcal.estimators.omega.array_omega`; engine
        "float", a layout that observes omega on every axis, else the whole-file command).
    scale : units.Scale, optional
        Stated units (readings in physical units go the whole-file way).
    block_bytes, batch_rows : int
        Chunk size: bytes of CSV text, rows of Parquet.
    progress : callable, optional
        ``progress(total, unit)`` -> a bar with ``update(k)`` and ``close()`` (one per pass).

    Returns
    -------
    list of str or None
        The warnings (none: what warns goes the whole-file way); None where the whole-file
        command must run (nothing written).

    Raises
    ------
    InputError
        Bad rows, as the whole-file command words them (nothing written).
    """
    if not device.is_array() or engine not in ("float", "fixed") or omega not in ("alpha", "array"):
        return None
    if omega == "array" and (engine != "float" or
                             not omega_observability(cal.positions_or_nominal(device), cal.sensitivity).full):
        return None                 # the whole-file command's refusal, after its reader's checks
    try:
        src = open_chunks(path, device.n_channels, scale, block_bytes, batch_rows)
        # the whole-file --omega array puts t on its grid before it checks the device's range
        try:
            sc = scan_with_bar(device, src, fixed=engine == "fixed", progress=progress,
                               defer_from=RANK_RANGE if omega == "array" else None)
        except Deferred as d:
            raise_deferred(src, d)
        if omega == "array":
            core: Any = _ArrayRate(device, cal, sc.noise, sc.dt)
            meta = {"engine": engine, "omega": "array"}
            names = ["t", "w_x", "w_y", "w_z", "w_x_sigma", "w_y_sigma", "w_z_sigma"]
        else:
            k = sc.noise
            rest = default_rest_params(device, 1.0 / sc.dt, alpha_sigma=alpha_noise(device, cal, k),
                                       f_sigma=force_noise(device, cal, k))
            leak = min(1.0, sc.dt / leak_tau_s) if leak_tau_s > 0 else 0.0
            core = (_FloatRate if engine == "float" else _FixedRate)(device, cal, rest, sc.dt, leak)
            meta = {"engine": engine, "leak_tau_s": f"{leak_tau_s:g}"}
            names = ["t", "w_x", "w_y", "w_z", "rest"]

        def write(f: Any) -> None:
            sink = ColumnSink(f, names, meta, is_parquet(output))
            bar = progress(src.total, src.unit) if progress is not None else None
            for ch in src.chunks(None if bar is None else bar.update):
                on_grid(sc, ch.start, ch.t)
                if omega == "array":
                    sink.write([ch.t, *core.step(ch.raw)])
                    continue
                w, flags = core.step(ch.raw)
                sink.write([ch.t, w[:, 0], w[:, 1], w[:, 2], ((flags & REST_AT_REST) != 0).astype(float)])
            if bar is not None:
                bar.close()
            sink.close()

        atomic_write(output, write, mode="wb" if is_parquet(output) else "w")
    except Fallback:
        return None
    return []
