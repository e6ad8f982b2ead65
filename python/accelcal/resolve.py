"""Per-sample f and alpha from a recording: the float reference or the C core.

``engine="fixed"`` runs the integer core with exactly the tables the header
generator emits (both come from quantize.quantize_calibration).
"""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from . import model
from .firmware import native
from .readings.clipping import at_rails, clip_levels, pile_warning, rails_warning
from .errors import AccelcalError, InputError
from .readings.noise import noise_for
from .readings.static import STATIC_WINDOW_S, window_len
from .firmware.triad import quantize_triad, triad_apply_float, triad_forces
from .firmware.native import FORMATS
from .firmware.quantize import QuantizeError, omega_to_fixed, quantize_calibration
from .firmware.terms import correct_readings, has_terms
from .firmware.terms_fixed import apply_terms_fixed, temp_to_fixed, terms_tables
from .io.recording import check_core_input, check_for_device


def omega_for(rec, source: str) -> np.ndarray | None:
    """The omega used for the centripetal correction: 'reference' (the recording's
    w_* columns), 'none', or 'auto' (reference when every sample has it)."""
    if source == "none":
        return None
    have = np.all(np.isfinite(rec.w), axis=1)
    if source == "reference":
        if not have.all():
            row = int(np.argmin(have))
            raise InputError(rec.source, "omega source 'reference' needs w_x, w_y, w_z on every sample",
                             row=rec.line(row), column="w_x")
        return rec.w
    if source == "auto":
        return rec.w if have.all() else None
    raise ValueError(f"unknown omega source {source!r}")


@dataclass
class Resolver:
    """What resolving needs of a device and a calibration, computed once per recording and
    used on every chunk of its readings (:func:`resolve_chunk`): the whole-file
    :func:`resolve_recording` and the streaming command (:mod:`accelcal.resolve_stream`) share it.

    Attributes
    ----------
    device, cal : Device, Calibration
    engine : {"float", "fixed"}
    signed : bool
        int16 readings (the device's raw_min < 0).
    tables : quantize.FixedTables or None
        The header's tables (engine "fixed", 6-channel array).
    positions : ndarray (N, 3) or None
        m (engine "float", 6-channel array).
    """

    device: Any
    cal: Any
    engine: str
    signed: bool
    tables: Any = None
    positions: Any = None


def resolver_for(device, cal, engine: str) -> Resolver:
    """The :class:`Resolver` of a device, calibration and engine (the engine is checked)."""
    if engine not in ("float", "fixed"):
        raise AccelcalError(f"unknown engine {engine!r}: expected float or fixed")
    r = Resolver(device, cal, engine, device.raw_min < 0)
    if device.is_triad():
        return r
    if engine == "float":
        r.positions = cal.positions_or_nominal(device)
    else:
        r.tables = quantize_calibration(device, cal)
    return r


def resolve_chunk(r: Resolver, raw: np.ndarray, omega: np.ndarray | None):
    """Resolve a chunk of readings: the per-sample part of :func:`resolve_recording`, the
    same numbers whether the recording comes whole or in chunks (no state between samples).

    Parameters
    ----------
    r : Resolver
    raw : ndarray (n, N) int
        Counts, checked against the device (and the core's input range for "fixed").
    omega : ndarray (n, 3) or None
        rad/s for the centripetal correction.

    Returns
    -------
    f : ndarray (n, 3) m/s^2
    alpha : ndarray (n, 3) rad/s^2 (NaN for a 3-axis sensor)
    flags : ndarray (n,) uint8 or None
    """
    if r.device.is_triad():
        holder = SimpleNamespace(raw=raw)
        try:
            f, sat = triad_forces(r.cal, holder, (0, 1, 2), r.engine, r.signed)
        except AccelcalError as e:
            raise InputError(getattr(r.cal, "source", "calibration"), str(e), field="channels") from None
        if r.engine == "fixed":
            f = f / 2.0 ** FORMATS.out_frac
        return f, np.full_like(f, np.nan, dtype=float), None if sat is None else sat.astype(np.uint8)
    if r.engine == "float":
        try:
            f, a = model.resolve(r.cal.offsets, r.cal.sensitivity, r.positions, raw, omega)
        except np.linalg.LinAlgError as e:
            raise InputError(getattr(r.cal, "source", "calibration"),
                             f"the calibrated sensor matrix cannot be inverted ({e})",
                             field="channels") from None
        return f, a, None
    w_q = None if omega is None else omega_to_fixed(omega)
    out, flags = native.process_batch(r.tables.resolver(), r.tables.trim, raw, w_q)
    y = out / 2.0 ** FORMATS.out_frac
    # the flags of the core's own arithmetic; its rail bit is the recording's `clipped` (at_rails)
    return y[:, :3], y[:, 3:], flags & ~np.uint8(native.lib.AC_FLAG_AT_RAIL)


def resolve_recording(device, cal, rec, engine: str = "float", omega_source: str = "auto", omega=None):
    """Returns (f (n,3) m/s^2, alpha (n,3) rad/s^2, flags (n,) uint8 or None).

    ``omega`` (n, 3) rad/s, when given, is the centripetal term's rate (the array's own
    estimate, ``accelcal.estimators.omega``) in place of ``omega_source``.

    A 3-axis sensor (``device.is_triad()``) gives f = S^-1 (raw - b) at its point and no
    alpha (NaN): the float reference, or the C core's ``ac_triad_apply`` (``ac_trim_s16`` +
    ``ac_triad_resolve`` for signed readings) with the header's triad table."""
    if engine not in ("float", "fixed"):
        raise AccelcalError(f"unknown engine {engine!r}: expected float or fixed")
    check_for_device(rec, device)
    if any(has_terms(cal).values()):
        return _resolve_with_terms(device, cal, rec, engine, omega_source)
    if device.is_triad():
        if engine == "fixed":
            check_core_input(rec, device.raw_min < 0)
        return resolve_chunk(resolver_for(device, cal, engine), rec.raw, None)
    omega = omega_for(rec, omega_source) if omega is None else np.asarray(omega, float)
    if engine == "fixed":
        check_core_input(rec, device.raw_min < 0)
    return resolve_chunk(resolver_for(device, cal, engine), rec.raw, omega)


def _terms_input(device, cal, rec):
    """The temperature column the terms need (None when the calibration has no tempcos)."""
    if not has_terms(cal)["temperature"]:
        return None
    temp = np.asarray(rec.temp_c, float)
    if not np.all(np.isfinite(temp)):
        row = int(np.argmin(np.isfinite(temp)))
        raise InputError(rec.source, "the calibration has temperature coefficients: temp_c is needed on every "
                         "sample", row=rec.line(row), column="temp_c")
    return temp


def _resolve_with_terms(device, cal, rec, engine, omega_source):
    """resolve_recording for a calibration with correctable terms (firmware.terms): the readings
    corrected (float reference, or the C core's ac_temp / ac_skew / ac_nonlin as a generated
    header's firmware runs them), then resolved as without them."""
    temp = _terms_input(device, cal, rec)
    dt = 1.0 / float(device.sample_rate_hz)
    triad = device.is_triad()
    if engine == "float":
        y = correct_readings(cal, rec.raw, temp, dt, (device.raw_min, device.raw_max))
        if triad:
            f = triad_apply_float(cal.offsets, cal.sensitivity, y)
            return f, np.full_like(f, np.nan), None
        omega = omega_for(rec, omega_source)
        try:
            f, a = model.resolve(cal.offsets, cal.sensitivity, cal.positions_or_nominal(device), y, omega)
        except np.linalg.LinAlgError as e:
            raise InputError(getattr(cal, "source", "calibration"),
                             f"the calibrated sensor matrix cannot be inverted ({e})", field="channels") from None
        return f, a, None
    signed = device.raw_min < 0
    check_core_input(rec, signed)
    try:
        t, tt = terms_tables(device, cal)     # the resolver's / triad's table takes x in 2^-tt.frac counts
        temp_q = None if temp is None else temp_to_fixed(temp)
    except QuantizeError as e:
        raise InputError(getattr(cal, "source", "calibration"), str(e), field="channels") from None
    m = tt.latency()
    raw = np.asarray(rec.raw, np.int64)
    raw = np.concatenate([raw, np.repeat(raw[-1:], m, axis=0)])
    if temp_q is not None:
        temp_q = np.concatenate([temp_q, np.repeat(temp_q[-1:], m)])
    d = raw - np.asarray(t.trim, np.int64)
    x = np.clip(d, -32768, 32767).astype(np.int16)
    sat = np.any(x != d, axis=1)
    y, tsat = apply_terms_fixed(tt, x, temp_q)
    y, sat = y[m:], (sat | tsat)[m:]
    if triad:
        f, fsat = native.triad_resolve_batch(t.cdata(), y)
        return f / 2.0 ** FORMATS.out_frac, np.full(f.shape, np.nan), (sat | fsat).astype(np.uint8)
    omega = omega_for(rec, omega_source)
    w_q = None if omega is None else omega_to_fixed(omega)
    r = native.new_resolver(t.m, t.m_shift, t.k, t.g, t.g_shift)     # no rails: x is corrected already
    out, flags = native.process_batch(r, np.zeros(t.n, np.int16), y, w_q)
    flags = flags | np.where(sat, np.uint8(native.lib.AC_FLAG_TRIM_SAT), np.uint8(0))
    yq = out / 2.0 ** FORMATS.out_frac
    return yq[:, :3], yq[:, 3:], flags


def clipped_samples(rec, device) -> tuple[np.ndarray, list[str]]:
    """The samples whose f is not a measurement, and the warnings naming them.

    Returns
    -------
    clipped : ndarray (n,) bool
        A channel at the converter's rails (:func:`accelcal.readings.clipping.at_rails`) or at a clip
        level inside the range where its readings pile up (:func:`accelcal.readings.clipping.clip_levels`,
        with the window and noise convert and diagnose use: a micro:bit's +-2040 mg).
    warnings : list of str
        :func:`accelcal.readings.clipping.rails_warning` and :func:`accelcal.readings.clipping.pile_warning`, each
        where it has samples."""
    raw = np.asarray(rec.raw)
    clipped = at_rails(rec, device)
    warnings = [w for w in (rails_warning(rec, device),) if w]
    if raw.shape[0] < 2:
        return clipped, warnings
    window = window_len(device, STATIC_WINDOW_S, raw.shape[0])
    levels = clip_levels(raw, device, noise_for(device, raw, window)[0], window)
    piles = pile_warning(rec, levels)
    if piles:
        clipped = clipped | np.any(levels.mask(raw), axis=1)
        warnings.append(piles)
    return clipped, warnings


@dataclass
class ResolveResult:
    """Per-sample specific force and angular acceleration.

    Attributes
    ----------
    t : ndarray, shape (n,)
        Time (s).
    f : ndarray, shape (n, 3)
        Specific force at the body origin (m/s^2).
    alpha : ndarray, shape (n, 3)
        Angular acceleration (rad/s^2).
    saturated : ndarray of uint8, shape (n,), or None
        The C core's saturation flags (``engine="fixed"`` only): its own arithmetic saturated
        (a pre-trim beyond 16 bits), which a reading at the chip's rail sets or not by the sign
        of its trim; see ``clipped``.
    clipped : ndarray of bool, shape (n,), or None
        Samples with a channel at the ADC's rail (the device's ``raw_min`` or ``raw_max``) or at a
        clip level inside the range where its readings pile up (:func:`clipped_samples`,
        as ``accelcal resolve``'s column), either engine: the chip clipped, and f there is short of
        the truth.
    w, w_sigma : ndarray, shape (n, 3), or None
        The array's own angular rate and its 1-sigma (rad/s) with ``omega="array"`` (or "auto" where
        it applies: docs/angular-rate.md), the centripetal term's rate.
    """

    t: np.ndarray
    f: np.ndarray
    alpha: np.ndarray
    saturated: np.ndarray | None = None
    clipped: np.ndarray | None = None
    w: np.ndarray | None = None
    w_sigma: np.ndarray | None = None
