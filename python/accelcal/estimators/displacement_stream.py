"""``accelcal displacement`` in chunks (docs/streaming.md): memory bounded by the longest motion and
rest, not by the recording's length, and the whole-file output byte for byte.

Three passes over the file (engine ``float``, form ``offline``, the default):

1. :func:`accelcal.estimators.stream_scan.scan` (dt, the noise, bad rows);
2. :class:`RestPass`: f chunk by chunk, the offline form's rest detector with its state carried
   (:class:`RestDetector`, the rest decisions of :func:`~.displacement.displace_core`), its flags
   kept in a temporary file; each rest as it ends: its mean |f| against g
   (:func:`~.rest.rest_on_g`) and its stretches' estimates of the noise's correlation
   (:func:`~.trend.part_correlation`), whose median (:func:`~.trend.median_correlation`) widens the
   trend test and the motions' error bounds as :func:`~.trend.rest_correlation` does over the whole;
3. :class:`MotionPass` (:mod:`.displacement_motions`): f again with the flags read back, one motion
   at a time as its closing rest is declared (:func:`~.rest.motion_window`, the double integration
   and the correction of :func:`~.displacement_host.displace_offline`), each rest tested for a
   trend as it ends, the rows before the next motion's anchor written as they are final
   (:func:`~.displacement_host.at_rest_not_moving`), the motion's checks (turned, rotated, what the
   correction leaves) and the still stretches (:class:`~.displacement_checks.HeldStretches`).

Anything the whole-file command would warn of or refuse, or that needs the whole recording, raises
:class:`~accelcal.io.chunks.Fallback` (nothing written) and the whole-file command runs: see
:func:`displacement_stream`.
"""
from __future__ import annotations

import contextlib
import tempfile
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from .. import model
from ..errors import AccelcalError, InputError
from ..firmware import native
from ..firmware.quantize import quantize_calibration
from ..firmware.triad import triad_forces
from ..io.chunk_source import open_chunks
from ..io.chunks import BLOCK_BYTES, Fallback
from ..io.parquet import BATCH_ROWS
from ..io.result_sink import write_deferred
from .common import CLIP, CLIP_LO, OUT_FRAC, alpha_noise, force_noise_axes, time_span
from .displacement import DISP_REST, GSUM_MAX, DisplaceParams, DispCore, DispFloat, tilt_frame
from .displacement_motions import NAMES, CoreMotionPass, MotionPass
from .omega import omega_observability
from .rest import REST_AT_REST, REST_QUIET, RestState, RestThresholds, default_rest_params
from .stream_scan import on_grid, scan_with_bar
from .trend import TREND_BLOCK_HOLDS, correlation_from_median, nan_median, part_correlation, rest_parts

__all__ = ["RestDetector", "RestPass", "core_rest_flags", "new_core", "open_end_warning", "displacement_stream"]

AXES = {None: None, "x": 0, "y": 1, "z": 2}
#: the most the median of the rests' correlation estimates holds at once (bytes)
MEDIAN_BYTES = 1 << 24


class RestDetector:
    """The offline form's rest decisions (:func:`~.displacement.displace_core` without given flags:
    its ``rest``), chunk by chunk: the float ``RestState`` tested against the first rest's mean f
    (its first GSUM_MAX quiet samples) once the first motion leaves it, state carried."""

    def __init__(self, p: DisplaceParams) -> None:
        self.rs = RestState(RestThresholds.of(p.rest))
        self.axis = p.axis
        self.phase, self.have_ref = 0, False
        self.gsum, self.gcount, self.g = np.zeros(3), 0, None

    def step(self, f: np.ndarray) -> np.ndarray:
        """REST_* flags (n,) uint8 of the chunk's f ((n, 3), m/s^2)."""
        f = np.clip(np.asarray(f, float), CLIP_LO, CLIP)
        out = np.zeros(f.shape[0], np.uint8)
        fl = f.tolist()
        step = self.rs.step
        for i in range(f.shape[0]):
            own = step(fl[i], None, self.g if self.have_ref else None)[0]
            out[i] = own
            quiet, at = bool(own & REST_QUIET), bool(own & REST_AT_REST)
            if self.phase != 2 and not self.have_ref:
                if quiet:
                    if self.gcount < GSUM_MAX:
                        self.gsum = self.gsum + f[i]
                        self.gcount += 1
                elif self.phase == 0:
                    self.gsum, self.gcount = np.zeros(3), 0
            if self.phase == 0:
                if at:
                    self.phase = 1
            elif self.phase == 1:
                if not at:
                    ok = True
                    if not self.have_ref:
                        self.g = self.gsum / self.gcount
                        if self.axis is None:
                            try:
                                tilt_frame(self.g)
                            except AccelcalError:
                                ok = False
                        if ok:
                            self.have_ref = True
                        else:
                            self.phase, self.g = 0, None
                            self.gsum, self.gcount = np.zeros(3), 0
                    if ok:
                        self.phase = 2
            elif at:
                self.phase = 1
        return out


class RestPass:
    """The second pass: the rest flags (into ``flags_file``) and what the rests tell of the whole.

    Attributes
    ----------
    est, K, N : file, int, int
        The rests' stretches' correlation estimates (a temporary file in ``folder``), how many, and
        their samples (:func:`~.trend.rest_parts`).
    rests : int
        Rests (dated back, each from where its quiet run began).
    open_start : int or None
        After :meth:`finish`: the first sample of a last motion that does not end at rest.
    """

    def __init__(self, p: DisplaceParams, n: int, flags_file: Any, folder: Any = None) -> None:
        self.p, self.n, self.file = p, n, flags_file
        self.det = RestDetector(p)
        self.L = max(2, TREND_BLOCK_HOLDS * p.rest.hold)
        self.base, self.F, self.FL = 0, np.zeros((0, 3)), np.zeros(0, np.uint8)   # rows kept from `base`
        self.est = tempfile.TemporaryFile(dir=folder)
        self.K = 0                                # estimates written to self.est
        self.N, self.rests = 0, 0
        self.last_at: int | None = None           # after the last sample at rest
        self.open_start: int | None = None        # the last motion's first sample, when it does not end at rest

    def feed(self, f: np.ndarray, fl: np.ndarray | None = None) -> None:
        """One chunk: f ((n, 3), m/s^2) and the rest flags (REST_AT_REST, REST_QUIET; None: the offline
        form's detector's)."""
        fl = self.det.step(f) if fl is None else fl
        self.file.write(fl.tobytes())
        F, FL = np.concatenate([self.F, f]), np.concatenate([self.FL, fl])
        at, quiet = (FL & REST_AT_REST) != 0, (FL & REST_QUIET) != 0
        idx = np.arange(FL.size)
        run_start = np.maximum.accumulate(np.where(quiet, -1, idx)) + 1
        edges = np.diff(np.concatenate(([0], at.astype(np.int8), [0])))
        keep = FL.size if not quiet[-1] else int(run_start[-1])
        if at.any():
            self.last_at = self.base + int(np.flatnonzero(at)[-1]) + 1
        for d, x in zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()):
            if x == FL.size:                    # a rest still going: kept from where it began
                keep = min(keep, int(run_start[d]))
                continue
            self.rest(F, int(run_start[d]), x)
        self.base += keep
        self.F, self.FL = F[keep:].copy(), FL[keep:].copy()

    def rest(self, F: np.ndarray, r: int, x: int) -> None:
        """The rest [r, x) of the rows kept (from ``base``)."""
        g = self.p.rest
        if self.rests == 0 and self.base + r != 0:
            raise Fallback("the recording does not start at rest")     # its warning, the whole-file way
        self.rests += 1
        if g.g is not None and abs(float(np.linalg.norm(F[r:x].mean(axis=0))) - g.g) > g.g_tol:
            raise Fallback("a rest off g")
        for k in rest_parts(self.base + r, self.base + x, self.n, self.L, g.hold):
            c = part_correlation(F[k - self.base], self.L)
            if c is not None:
                self.est.write(np.ascontiguousarray(c, np.float64).tobytes())
                self.K += 1
                self.N += k.size

    def close(self) -> None:
        """Close the estimates' temporary file (also where a pass ends early: a fallback, an error)."""
        self.est.close()

    def finish(self) -> np.ndarray:
        """The noise's correlation as the rests show it (:func:`~.trend.rest_correlation`)."""
        FL = self.FL
        at = (FL & REST_AT_REST) != 0
        if not FL.size or not at[-1]:
            if self.rests < 2:
                raise Fallback("no rest, or no motion closed by one")
            self.open_start = self.last_at            # the last motion does not end at rest: left out
            return self.correlation()
        quiet = (FL & REST_QUIET) != 0
        run_start = np.maximum.accumulate(np.where(quiet, -1, np.arange(FL.size))) + 1
        d = int(np.flatnonzero(~at)[-1]) + 1 if not at.all() else 0
        self.rest(self.F, int(run_start[d]), FL.size)
        if self.rests < 2:
            raise Fallback("no motion closed by a rest")
        return self.correlation()

    def correlation(self) -> np.ndarray:
        """The median of the stretches' estimates (kept in a temporary file, one (L, 3) block each),
        value by value (:func:`~.trend.nan_median`), in groups of values whose columns take at most
        MEDIAN_BYTES, read back block by block: memory that does not grow with the rests."""
        K, L = self.K, self.L
        if not K:
            return correlation_from_median(None, self.N, L)
        width = 3 * L
        group = max(1, min(width, MEDIAN_BYTES // (8 * K)))
        med = np.zeros(width)
        rows = max(1, MEDIAN_BYTES // (8 * width))
        for g0 in range(0, width, group):
            cols = np.empty((K, min(group, width - g0)))
            self.est.seek(0)
            for r0 in range(0, K, rows):
                blk = np.frombuffer(self.est.read(8 * width * min(rows, K - r0)), np.float64).reshape(-1, width)
                cols[r0:r0 + blk.shape[0]] = blk[:, g0:g0 + cols.shape[1]]
            med[g0:g0 + cols.shape[1]] = nan_median(cols)
        self.est.close()
        return correlation_from_median(med.reshape(L, 3), self.N, L)


def core_rest_flags(core: dict) -> np.ndarray:
    """REST_AT_REST where the C core is at rest (DISP_REST), REST_QUIET where its detector is quiet
    (:meth:`~.displacement.DispCore.step`'s outputs ``core``), for :class:`RestPass`."""
    return (((core["flags"] & DISP_REST) != 0) * REST_AT_REST
            | ((core["rest"] & REST_QUIET) != 0) * REST_QUIET).astype(np.uint8)


def new_core(p: DisplaceParams, fixed: bool):
    """The streaming form's integrator with its state carried over chunks: the C core's ac_disp
    (:class:`~.displacement.DispCore`) or its float reference (:class:`~.displacement.DispFloat`)."""
    return DispCore(p) if fixed else DispFloat(p.dt, p.axis, RestThresholds.of(p.rest))


def _forces(device, cal, channels):
    """f (and alpha of an array) of a chunk's raw readings, as the whole-file command resolves them."""
    if device.is_array():
        args = (cal.offsets, cal.sensitivity, cal.positions_or_nominal(device))

        def array(raw):
            n = raw.shape[0]
            # BLAS multiplies one row (gemv) with other roundings than many (gemm): a lone row goes in twice
            f, a = model.resolve(*args, np.repeat(raw, 2, axis=0) if n == 1 else raw, None)
            return f[:n], a[:n]
        return array
    signed = device.raw_min < 0

    def triad(raw):
        n = raw.shape[0]
        rec = SimpleNamespace(raw=np.repeat(raw, 2, axis=0) if n == 1 else raw)
        return triad_forces(cal, rec, channels, "float", signed)[0][:n], None
    return triad


def _core_forces(device, cal, channels):
    """f of a chunk's raw readings from the C core (int32 Q.AC_OUT_FRAC), as the whole-file command's."""
    if device.is_array():
        t = quantize_calibration(device, cal)
        resolver, trim = t.resolver(), t.trim
        return lambda raw: native.process_batch(resolver, trim, raw, None)[0][:, :3].astype(np.int32)
    signed = device.raw_min < 0
    return lambda raw: triad_forces(cal, SimpleNamespace(raw=raw), channels, "fixed", signed)[0]


def open_end_warning(t0: float, marks: dict, before: int, s: int, last: int) -> str:
    """The whole-file command's line (:func:`~.displacement_host.displacement_from_recording`) for a
    last motion, from sample ``s`` to the last, ``last``, that does not end at rest: left out, the
    output ending at sample ``before`` (``marks``: sample -> (t in s, its row); ``t0`` the first
    stamp, s)."""
    def span(*k):
        t = np.array([t0] + [marks[i][0] for i in k])
        rows = dict(enumerate((marks[i][1] for i in k), 1))
        return time_span(t, 1, None if len(k) == 1 else 2, SimpleNamespace(lines=1, line=rows.get))
    return (f"displacement: the last motion ({span(s, last)}) does not end at rest: without a rest at its end its "
            "zero point cannot be removed (its drift grows with time squared), so it is left out; the output ends "
            f"at {span(before)}, in the rest before it")


def displacement_stream(device, cal, path: Any, output: Any, *, engine: str = "float", form: str | None = None,
                        axis: Any = None, omega: str = "auto", scale: Any = None, block_bytes: int = BLOCK_BYTES,
                        batch_rows: int = BATCH_ROWS, progress: Callable[[Any, str], Any] | None = None
                        ) -> list[str] | None:
    """`accelcal displacement` from ``path`` into ``output`` chunk by chunk.

    Parameters
    ----------
    device, cal : Device, Calibration
        A 6-DOF array or a device with a triad at channels 0-2.
    path, output : str or os.PathLike
        The recording and the result (Parquet by the name .parquet, else CSV).
    engine, form : str
        ``float`` with ``offline`` (the default) or ``stream``, ``fixed`` (``stream``).
    axis : {None, "x", "y", "z"}
    omega : {"auto", "none", "array"}
        An array whose layout observes omega ("auto") or "array": the whole-file command.
    scale : units.Scale, optional
    block_bytes, batch_rows : int
        Chunk size: bytes of CSV text, rows of Parquet.
    progress : callable, optional
        ``progress(total, unit)`` -> a bar (one per pass).

    Returns
    -------
    list of str or None
        The warnings (the whole-file command's: a last motion that does not end at rest, left out;
        anything else that warns goes the whole-file way); None where the whole-file command
        must run (nothing written): ``--resample``, ``--keep-turned``, an array's own omega, a
        recording that does not start at rest, no motion closed by a rest,
        a rest off g, a rest shorter than a trend block (TREND_BLOCK_HOLDS holds) or that holds a
        trend, a motion the body turned in, one longer than the correction holds, a still stretch
        off g or turned, and what :func:`~.stream_scan.scan` leaves to it.

    Raises
    ------
    InputError
        Bad rows, as the whole-file command words them (nothing written).
    """
    form = form or ("offline" if engine == "float" else "stream")
    if (engine, form) not in (("float", "offline"), ("float", "stream"), ("fixed", "stream")) or axis not in AXES:
        return None
    fixed = engine == "fixed"
    streamed = form == "stream"
    if omega not in ("auto", "none", "array") or omega == "array":
        return None
    if device.is_array():
        if omega == "auto" and omega_observability(cal.positions_or_nominal(device), cal.sensitivity).full:
            return None
        channels = None
    elif device.triads():
        channels = device.triads()[0]
    else:
        return None
    try:
        src = open_chunks(path, device.n_channels, scale, block_bytes, batch_rows)
        try:
            sc = scan_with_bar(device, src, fixed=fixed, progress=progress)
        except InputError as e:
            if getattr(e, "column", None) == "t":
                raise Fallback("t not increasing: a row written twice is left out by the whole-file reader")
            raise
        f_axes = force_noise_axes(device, cal, sc.noise, channels)
        f_sigma = float(np.max(f_axes))
        rp = default_rest_params(device, 1.0 / sc.dt, f_sigma=f_sigma)
        p = DisplaceParams(dt=sc.dt, axis=AXES[axis], rest=rp)
        forces = _forces(device, cal, channels)
        core_forces = _core_forces(device, cal, channels) if fixed else None
        folder = Path(output).resolve().parent
        with tempfile.TemporaryFile(dir=folder) as flags_file, \
                contextlib.closing(RestPass(p, sc.n, flags_file, folder)) as first:
            core = new_core(p, fixed) if streamed else None
            bar = progress(src.total, src.unit) if progress is not None else None
            for ch in src.chunks(None if bar is None else bar.update):
                on_grid(sc, ch.start, ch.t)
                if fixed:
                    f_q = core_forces(ch.raw)
                    first.feed(f_q / 2.0**OUT_FRAC, core_rest_flags(core.step(f_q)))
                elif streamed:
                    f = forces(ch.raw)[0]
                    first.feed(f, core_rest_flags(core.step(f)))
                else:
                    first.feed(forces(ch.raw)[0])
            if bar is not None:
                bar.close()
            rho = first.finish()
            flags_file.seek(0)
            note = ("resolved f at the body origin" + (" (C core)" if fixed else "") if device.is_array()
                    else "f of the triad at channels 0-2")
            meta = {"engine": engine, "form": form, "device": device.name, "signal": note,
                    "mode": "3-axis, gravity removed in the frame of the first rest" if p.axis is None else
                    f"1-D along body {'xyz'[p.axis]}"}
            args = (p, sc.n, rho, f_axes, float(device.gravity_mps2),
                    alpha_noise(device, cal, sc.noise) if device.is_array() else None)
            core = new_core(p, fixed) if streamed else None
            second = (CoreMotionPass(*args, step_dt=core.dt if fixed else p.dt, fixed=fixed) if streamed
                      else MotionPass(*args))
            second.open_start = first.open_start
            marks: dict = {}                      # (t, row) of the samples the warning of an open end names
            named = () if first.open_start is None else (first.open_start - 1, first.open_start, sc.n - 1)

            def produce(sink: Any) -> dict:
                bar = progress(src.total, src.unit) if progress is not None else None
                for ch in src.chunks(None if bar is None else bar.update):
                    marks.update({k: (float(ch.t[k - ch.start]), ch.line(k - ch.start)) for k in named
                                  if ch.start <= k < ch.start + ch.n})
                    fl = np.frombuffer(flags_file.read(ch.n), np.uint8)
                    f, alpha = forces(ch.raw)
                    if fixed:
                        f_q = core_forces(ch.raw)
                        second.feed_core(ch.t, f_q / 2.0**OUT_FRAC, alpha, core.step(f_q), sink)
                    elif streamed:
                        second.feed_core(ch.t, f, alpha, core.step(f), sink)
                    else:
                        second.feed(ch.t, f, alpha, fl, sink)
                if bar is not None:
                    bar.close()
                meta.update(second.finish(sink))
                if named:
                    warnings.append(open_end_warning(sc.t0, marks, *named))
                return {**meta, **{f"warning_{k}": w for k, w in enumerate(warnings, 1)}}

            warnings: list[str] = []
            write_deferred(output, NAMES, produce)
    except Fallback:
        return None
    return warnings
