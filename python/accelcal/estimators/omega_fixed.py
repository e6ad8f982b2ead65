"""The array's own omega in the integer C core (``ac_omega.h``), and its float twin.

* :func:`omega_reference` -- the core's algorithm in float64 on the exact values of an
  :class:`accelcal.firmware.omega_table.OmegaTable` (the twin the property tests hold the
  core to, within the bound stated in ``ac_omega.h``): the readings through the table's rows,
  the per-sample ML from the core's closed form (the column of ``m^-1 q`` with the largest
  diagonal entry over its root) and :func:`accelcal.estimators.omega_filter.fuse`.
* :func:`omega_fixed_from_recording` -- ``resolve --engine fixed --omega array``: the table
  ``accelcal header`` writes, run through the C core.
"""
from __future__ import annotations

import numpy as np

from ..errors import AccelcalError, InputError
from ..firmware.native import FORMATS
from ..firmware.omega_table import OmegaTable, device_omega_table, omega_run
from ..firmware.quantize import quantize_calibration
from ..io.recording import check_for_device
from .common import channel_noise, uniform_dt
from .omega import ArrayOmega, omega_from_recording, omega_ml, omega_observability, wants_array_omega
from .omega_filter import fuse

__all__ = ["ML_ITERATIONS", "FUSE_ITERATIONS", "column_start", "omega_reference", "pretrim",
           "table_for_recording", "omega_fixed_from_recording", "choose_omega_engine"]

#: ac_omega.h's AC_OMEGA_ML_ITER and AC_OMEGA_ITER
ML_ITERATIONS = 4
FUSE_ITERATIONS = 2
#: the six products' places in the symmetric matrix omega omega^T, column by column
_COLUMN = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2]])


def column_start(q, minv) -> np.ndarray:
    """The core's closed-form start (n, 3) rad/s: with phat = m^-1 q, the column k of the
    symmetric matrix of products whose diagonal entry phat_k is the largest (the first of
    equals), over its root; 0 where that entry is not positive."""
    phat = np.atleast_2d(np.asarray(q, float)) @ np.asarray(minv, float).T
    k = np.argmax(phat[:, :3], axis=1)
    d = phat[np.arange(len(k)), k]
    col = phat[np.arange(len(k))[:, None], _COLUMN[k]]
    with np.errstate(invalid="ignore", divide="ignore"):
        w = col / np.sqrt(d)[:, None]
    return np.where((d > 0)[:, None], w, 0.0)


def omega_reference(table: OmegaTable, x, margins: list | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The core's ``ac_omega_step`` in float64 on the table's exact values.

    Parameters
    ----------
    table : OmegaTable
    x : array_like (n, N)
        The pre-trimmed readings (int16 values), counts.
    margins : list, optional
        Appended per sample: the jump test's margin (:func:`omega_filter.fuse`).

    Returns
    -------
    w : ndarray (n, 3)
        rad/s.
    cov : ndarray (n, 3, 3)
        (rad/s)^2.
    w_ml : ndarray (n, 3)
        The per-sample ML estimate the jump test uses, rad/s (either sign).
    """
    y = np.atleast_2d(np.asarray(x, float)) @ table.rows().T - table.k
    q, lin = y[:, :6], y[:, 6:]
    w_ml, _ = omega_ml(q, table.m, column_start(q, table.minv), ML_ITERATIONS, table.ridge)
    w, cov = fuse(q, lin, table.leak, table.qn, table.m, w_ml, table.dt, np.zeros(3), table.p0,
                  FUSE_ITERATIONS, table.jump, margins)
    return w, cov, w_ml


def pretrim(tables, raw) -> tuple[np.ndarray, np.ndarray]:
    """The core's int16 inputs raw - trim (clipped) and which samples clipped."""
    d = np.atleast_2d(np.asarray(raw, np.int64)) - tables.trim.astype(np.int64)
    x = np.clip(d, -32768, 32767)
    return x.astype(np.int16), np.any(x != d, axis=1)


def table_for_recording(device, cal, rec) -> tuple[object, OmegaTable]:
    """The quantised calibration and the omega table for a recording: the table ``accelcal
    header`` writes (:func:`device_omega_table`: the device's noise and sample rate); on a
    device that states no ``noise_mps2``, the recording's own noise (the header then has no
    omega table).

    Raises
    ------
    InputError
        A layout that does not fix all six rate products, or a recording whose sample
        interval is off the device's rate by more than 1 % (the table's dt is the device's).
    """
    dt = uniform_dt(rec)
    if abs(dt * float(device.sample_rate_hz) - 1.0) > 0.01:
        raise InputError(getattr(rec, "source", "recording"), f"its sample interval {dt:.6g} s is not the device's 1/{device.sample_rate_hz:g} s: "
                         "the fixed omega's table is made for the device's rate", field="t")
    noise = None if device.noise_mps2 > 0 else channel_noise(device, rec)
    table = device_omega_table(device, cal, noise)
    if table is None:
        raise InputError(device.name, "the fixed omega needs a layout whose channels fix all six rate products "
                         "(12 channels as four triads on a tetrahedron, or triads at the origin and on the axes)")
    return quantize_calibration(device, cal), table


def omega_fixed_from_recording(device, cal, rec) -> ArrayOmega:
    """The array's own omega from the C core (``resolve --engine fixed --omega array``).

    f, alpha are left to the resolver (NaN here), w_ml and info_ml are NaN (the core keeps the
    ML estimate only for its jump test).

    Raises
    ------
    InputError
        A layout that does not observe omega on every axis or does not fix all six rate
        products (the core's table needs m^-1).
    """
    check_for_device(rec, device, min_samples=2)
    pos = cal.positions_or_nominal(device)
    obs = omega_observability(pos, cal.sensitivity)
    if not obs.full:
        raise InputError(device.name, obs.line)
    tables, table = table_for_recording(device, cal, rec)
    x, _ = pretrim(tables, rec.raw)
    w16, w10, sig, _, _ = omega_run(table, x)
    n = x.shape[0]
    nan = np.full((n, 3), np.nan)
    scale = 2.0 ** -16
    return ArrayOmega(w16 * scale, sig * scale, nan, nan.copy(), nan.copy(), np.full((n, 3, 3), np.nan), obs,
                      w10 * 2.0 ** -FORMATS.omega_frac)



def choose_omega_engine(device, cal, rec, source: str, engine: str = "float") -> ArrayOmega | None:
    """``resolve --omega SOURCE --engine ENGINE``: the array's own omega where
    :func:`accelcal.estimators.omega.wants_array_omega`, from the float estimator or (engine
    "fixed") the C core on the header's table; else None."""
    if engine not in ("float", "fixed"):
        raise AccelcalError(f"unknown engine {engine!r}: expected float or fixed")
    if not wants_array_omega(device, cal, rec, source):
        return None
    return omega_fixed_from_recording(device, cal, rec) if engine == "fixed" else omega_from_recording(device, cal, rec)


#: ``attitude --omega`` / ``displacement --omega``: "auto" (the array's omega where the layout
#: observes it and the recording has no complete w columns, else none), "array", "none"
ESTIMATOR_OMEGA = ("auto", "array", "none")


def estimator_omega(device, cal, rec, source: str, engine: str = "float") -> ArrayOmega | None:
    """The array's own omega for ``attitude`` and ``displacement`` (``omega`` ``source``, one of
    :data:`ESTIMATOR_OMEGA`), as ``resolve --omega`` chooses it, or None ("none"; "auto" where the
    layout does not observe omega or the recording has complete w columns).

    Raises
    ------
    InputError
        "array" on a layout that does not observe omega (the observability line, naming what layout
        would), or (engine "fixed") one whose channels do not fix all six rate products.
    ValueError
        An unknown source.
    """
    if source not in ESTIMATOR_OMEGA:
        raise ValueError(f"unknown omega {source!r}: expected one of {', '.join(ESTIMATOR_OMEGA)}")
    return None if source == "none" else choose_omega_engine(device, cal, rec, source, engine)
