"""Angular rate from the resolved alpha of a 6-DOF array (seed 1): leaky integration
w[n] = (1 - leak) w[n-1] + dt alpha[n], reset to 0 on rest (the firmware's
``ac_rest_rate_step``: ac_rate_step behind ac_rest).

Float core (:func:`rate_rest_float`): the reference and, with the core's rest flags and
its dt and leak as stored, the twin the property tests hold :func:`rate_rest_fixed` to.
Recording form: :func:`rate_from_recording`.
"""
from __future__ import annotations

import numpy as np
from scipy.signal import lfilter

from ..errors import InputError
from ..firmware.native import check, cptr, ffi, lib
from ..firmware.quantize import round_half_up
from ..io.recording import check_core_input, check_for_device
from .omega import omega_columns, omega_from_recording
from .common import (OMEGA_FRAC, Columns, alpha_noise, channel_noise, dt_fixed, force_noise, resolve_array,
                     uniform_dt)
from .timegrid import on_uniform_grid
from .rest import REST_AT_REST, RestParams, default_rest_params, rest_cfg_fixed, rest_detect

__all__ = ["LEAK_FRAC", "rate_rest_float", "rate_rest_fixed", "rate_from_recording"]

LEAK_FRAC = 16   # ac_rate_init's leak per step (stated in ac_rate.h, no #define)


def rate_rest_float(alpha, f, dt: float, leak: float, rest: RestParams, rest_flags=None, *,
                    as_stored: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Leaky integration of alpha, reset on rest, in float64.

    Parameters
    ----------
    alpha : array_like (n, 3)
        Angular acceleration, rad/s^2.
    f : array_like (n, 3)
        Specific force, m/s^2 (for the rest test; unused when ``rest_flags`` is given).
    dt : float
        Sample interval, s.
    leak : float
        Fraction of w lost per step (0: plain integration).
    rest : RestParams
    rest_flags : array_like (n,), optional
        REST_* flags to use instead of the float detector's (the twin takes the core's).
    as_stored : bool
        The float detector with the thresholds as the C config stores them.

    Returns
    -------
    omega : ndarray (n, 3)
        rad/s; w[n] = (1 - leak) w[n-1] + dt alpha[n], and 0 (state reset) at rest.
    rest_flags : ndarray (n,)
    """
    alpha = np.asarray(alpha, float)
    if rest_flags is None:
        rest_flags, _ = rest_detect(f, rest, alpha=alpha, as_stored=as_stored)
    at = (np.asarray(rest_flags) & REST_AT_REST) != 0
    out = np.zeros_like(alpha)
    # between rests, from w = 0: scipy's direct form gives the recursion's numbers bit for bit
    edges = np.diff(np.concatenate(([0], (~at).astype(np.int8), [0])))
    for s, e in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
        out[s:e] = lfilter([dt], [1.0, -(1.0 - leak)], alpha[s:e], axis=0)
    return out, rest_flags


def rate_rest_fixed(alpha_q, f_q, dt: float, leak_q16: int, rest: RestParams
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ac_rest_rate_step per sample.

    Parameters
    ----------
    alpha_q, f_q : array_like (n, 3)
        int32 Q.AC_OUT_FRAC rad/s^2 and m/s^2.
    dt : float
        Sample interval, s (as dt_fixed stores it).
    leak_q16 : int
        Leak per step, Q.16.
    rest : RestParams

    Returns
    -------
    omega : ndarray (n, 3) int64
        Q.AC_OMEGA_FRAC rad/s.
    flags : ndarray (n,)
        REST_* per sample.
    saturated : ndarray (n,) bool
    """
    alpha_q = np.ascontiguousarray(alpha_q, dtype=np.int32)
    f_q = np.ascontiguousarray(f_q, dtype=np.int32)
    n = alpha_q.shape[0]
    rs = ffi.new("ac_rest *")
    check(lib.ac_rest_init(rs, rest_cfg_fixed(rest)), "ac_rest_init")
    rt = ffi.new("ac_rate *")
    dm, dsh = dt_fixed(dt)
    check(lib.ac_rate_init(rt, dm, dsh, int(leak_q16)), "ac_rate_init")
    w = ffi.new("int16_t[3]")
    fl = ffi.new("uint8_t *")
    om = np.zeros((n, 3), np.int64)
    flags = np.zeros(n, np.int64)
    sat = np.zeros(n, bool)
    for i in range(n):
        sat[i] = check(lib.ac_rest_rate_step(rs, rt, cptr("int32_t *", f_q[i]), cptr("int32_t *", alpha_q[i]),
                                             w, fl), "ac_rest_rate_step")
        om[i] = (w[0], w[1], w[2])
        flags[i] = fl[0]
    return om, flags, sat


def rate_from_recording(device, cal, rec, engine: str = "float", *, leak_tau_s: float = 5.0,
                        rest: RestParams | None = None, omega: str = "alpha") -> Columns:
    """`accelcal rate`: angular rate from the resolved alpha of a 6-DOF array.

    ``omega="alpha"``: leaky integration (a high-pass of time constant ``leak_tau_s``, s;
    0 = none), reset to 0 on detected rest (f quiet, |f| ~ g, |alpha| within 5 sigma of its
    noise).  ``omega="array"``: the accelerometers' own omega fused with the integrated alpha
    (:func:`accelcal.estimators.omega.omega_from_recording`; float engine only).

    Returns
    -------
    Columns
        t (s), w_x, w_y, w_z (rad/s), rest (1 at rest); with "array" w_*_sigma (rad/s) for rest.

    Raises
    ------
    InputError
        Not a 6-DOF array, a recording that does not fit the device, non-uniform time,
        raw counts outside uint16 (engine "fixed").
    """
    if not device.is_array():
        raise InputError(device.name, "rate needs a 6-DOF array (alpha from the resolver)")
    if omega not in ("alpha", "array"):
        raise ValueError(f"unknown omega {omega!r}: expected alpha or array")
    if omega == "array":
        if engine != "float":
            raise InputError(device.name, "rate --omega array runs on the float engine only (no C core yet)")
        rec, filled, fill_note = on_uniform_grid(rec)
        est = omega_from_recording(device, cal, rec)
        return Columns(t=np.asarray(rec.t, float), **omega_columns(est),
                       **({"filled": filled.astype(float)} if filled.any() else {}),
                       warnings=[f"rate: {fill_note}"] if fill_note else [], meta={"engine": engine, "omega": "array"})
    check_for_device(rec, device, min_samples=2)
    if engine == "fixed":
        check_core_input(rec, device.raw_min < 0)
    rec, filled, fill_note = on_uniform_grid(rec)
    dt = uniform_dt(rec)
    if rest is None:
        k = channel_noise(device, rec)
        rest = default_rest_params(device, 1.0 / dt, alpha_sigma=alpha_noise(device, cal, k),
                                   f_sigma=force_noise(device, cal, k))
    rp = rest
    leak = min(1.0, dt / leak_tau_s) if leak_tau_s > 0 else 0.0
    if engine == "float":
        f, a = resolve_array(device, cal, rec, "float")
        w, fl = rate_rest_float(a, f, dt, leak, rp)
    elif engine == "fixed":
        f_q, a_q = resolve_array(device, cal, rec, "fixed")
        wq, fl, _ = rate_rest_fixed(a_q, f_q, dt, int(round_half_up(leak * 2.0**LEAK_FRAC)), rp)
        w = wq / 2.0**OMEGA_FRAC
    else:
        raise ValueError(f"unknown engine {engine!r}")
    return Columns(t=np.asarray(rec.t, float), w_x=w[:, 0], w_y=w[:, 1], w_z=w[:, 2],
                   rest=((np.asarray(fl) & REST_AT_REST) != 0).astype(float),
                   **({"filled": filled.astype(float)} if filled.any() else {}),
                   warnings=[f"rate: {fill_note}"] if fill_note else [],
                   meta={"engine": engine, "leak_tau_s": f"{leak_tau_s:g}"})
