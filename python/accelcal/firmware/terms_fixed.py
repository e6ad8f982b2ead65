"""The correctable terms in the C core's integer formats: the quantizer (the one source of
the header's tables and of ``resolve --engine fixed``), the chain run through the core, and
the error bounds that include/accelcal/ac_temp.h, ac_skew.h and ac_nonlin.h state.

The chain's hand-off (``frac`` k, ``<PREFIX>_TERMS_FRAC``): with a temperature table,
ac_temp_correct writes its output in 2^-k counts (Q.k), the skew interpolates it as it is,
the nonlinearity's coefficients are per 2^-k count (c2 2^-k, c3 2^-2k) and the resolver's /
triad's table takes x in 2^-k counts (quantize's ``in_frac``).  k is chosen from the
converter's span about the trims (:func:`terms_frac`); without a temperature table k = 0.

Formats (docs/firmware-terms.md): temperature degC int16 Q.8 (``AC_TEMP_FRAC``); offset
tempco oc[i] Q.8 counts/degC (``AC_TEMP_OC_FRAC``); gain tempco gc[i] Q.24 1/degC
(``AC_TEMP_GC_FRAC``); the lag weight
c = k 2^-shift (k in 32768..65535 unless c = 1); skew delay whole[i] + frac[i] 2^-15 samples;
nonlinearity a2[i] = c2 2^(15 + shift), a3[i] = c3 2^(30 + shift).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import native
from .native import lib
from .quantize import QuantizeError, largest_shift, quantize_calibration, round_half_up, to_fixed
from .terms import (channel_values, has_terms, lag_coefficient, nonlinearity_coefficients, nonlinearity_iterations,
                    nonlinearity_span, skew_delays, skew_latency)
from .triad import quantize_triad

__all__ = ["TEMP_FRAC", "TERMS_FRAC_MAX", "TERMS_FRAC_SPAN", "TermsTables", "terms_frac", "quantize_terms",
           "terms_tables", "lag_fixed", "apply_terms_fixed", "lag_bound", "temp_bound", "nonlin_bound", "temp_to_fixed"]

TEMP_FRAC = lib.AC_TEMP_FRAC
OC_FRAC = lib.AC_TEMP_OC_FRAC
GC_FRAC = lib.AC_TEMP_GC_FRAC
GAIN_FRAC = lib.AC_TEMP_GAIN_FRAC
SKEW_FRAC = lib.AC_SKEW_FRAC
E_MAX = lib.AC_TEMP_E_MAX
ITERATIONS = lib.AC_NONLIN_ITERATIONS
#: the most fraction bits the terms hand on (1/16 count: the hand-off's per-pose bias, uniform in
#: +-2^-(k+1), then stays below a pose mean's standard error on the loop's cases)
TERMS_FRAC_MAX = 4
#: the largest span 2^k (in 2^-k counts) of the readings about their trims: a third of headroom in
#: int16 for what the temperature correction adds (up to 5.47 % of the reading and the offset)
TERMS_FRAC_SPAN = 24576


@dataclass
class TermsTables:
    """The terms' integer tables for one calibration (None where it carries none)."""
    n: int
    dt_s: float
    temp: dict | None = None     # t_ref, oc, gc, o, lag_off/lag_gain (k, shift), tau_off/tau_gain (s)
    skew: dict | None = None     # len, whole, frac, latency
    nonlin: dict | None = None   # shift, a2, a3, iterations
    frac: int = 0                # k: the terms' output (and the resolver's input) in 2^-k counts

    def any(self) -> bool:
        return self.temp is not None or self.skew is not None or self.nonlin is not None

    def latency(self) -> int:
        return 0 if self.skew is None else int(self.skew["latency"])

    # the dequantised coefficients (what the tables hold exactly)
    def temp_coefficients(self) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """(t_ref degC, oc counts/degC, gc 1/degC, o counts) of the temperature table."""
        t = self.temp
        return (t["t_ref"] / 2.0 ** TEMP_FRAC, t["oc"] / 2.0 ** OC_FRAC, t["gc"] / 2.0 ** GC_FRAC,
                t["o"] / 2.0 ** native.FORMATS.offset_frac)

    def nonlin_coefficients(self) -> tuple[np.ndarray, np.ndarray]:
        """(c2, c3) of the nonlinearity table per unit of its input (2^-frac counts): c2 2^-frac,
        c3 2^-2frac for c2 1/counts, c3 1/counts^2."""
        s = self.nonlin["shift"]
        return self.nonlin["a2"] / 2.0 ** (15 + s), self.nonlin["a3"] / 2.0 ** (30 + s)

    def cdata(self) -> dict:
        """The cffi tables: {"temp", "skew", "nonlin"} (absent ones left out)."""
        out = {}
        if self.temp is not None:
            t = self.temp
            out["temp"] = native.new_temp_table(t["t_ref"], t["oc"], t["gc"], t["o"], t["frac"])
        if self.skew is not None:
            out["skew"] = native.new_skew_table(self.skew["len"], self.skew["whole"], self.skew["frac"])
        if self.nonlin is not None:
            out["nonlin"] = native.new_nonlin_table(self.nonlin["shift"], self.nonlin["a2"], self.nonlin["a3"],
                                                    self.nonlin["iterations"])
        return out


def lag_fixed(tau_s: float | None, dt_s: float) -> tuple[int, int]:
    """(k, shift) of the lag weight c = 1 - exp(-dt / tau) (ac_temp_lag_init): (1, 0) for no lag,
    else k in 32768..65535 with the largest shift <= 47."""
    c = lag_coefficient(tau_s, dt_s)
    if c >= 1.0:
        return 1, 0
    s = min(47, largest_shift(c, 65535.0))
    k = int(round_half_up(c * 2.0 ** s))
    while k > 65535:
        s -= 1
        k = int(round_half_up(c * 2.0 ** s))
    if k == 0:
        raise QuantizeError(f"thermal lag tau = {tau_s} s is too long for the sample period {dt_s} s "
                            "(the lag weight rounds to 0)")
    return k, s


def _shift_for(vmax: float, lo: int, hi: int, what: str, limit: float = 32767.0) -> int:
    if vmax == 0.0:
        return hi
    s = min(hi, largest_shift(vmax, limit))
    if s < lo:
        raise QuantizeError(f"{what} = {vmax:.6g} is too large for its fixed-point format")
    return s


def terms_frac(rails, trim) -> int:
    """k, the fraction bits of the terms' hand-off: the largest k <= TERMS_FRAC_MAX with
    span 2^k <= TERMS_FRAC_SPAN, span = max |rail - trim_i| (counts, the largest reading about
    its trim); 0 without rails or trims (a 12-bit converter about mid-scale: 3; the seed's
    0..10000: 2; a 16-bit one: 0)."""
    if rails is None or trim is None:
        return 0
    t = np.asarray(trim, float)
    span = float(np.max(np.maximum(np.abs(float(rails[1]) - t), np.abs(float(rails[0]) - t))))
    k = 0
    while k < TERMS_FRAC_MAX and span * 2.0 ** (k + 1) <= TERMS_FRAC_SPAN:
        k += 1
    return k


def quantize_terms(cal, n: int, dt_s: float, offset_q, rails=None, trim=None) -> TermsTables:
    """The terms of ``cal`` as the core's tables; ``offset_q`` (N,) the residual offsets
    b_i - trim_i in Q.AC_OFFSET_FRAC (the resolver's or the triad's), ``dt_s`` the sample period,
    ``rails`` (raw_min, raw_max) the converter's codes the nonlinearity's iteration count is
    chosen for (firmware.terms.nonlinearity_iterations; None: AC_NONLIN_ITERATIONS) and, with
    ``trim`` (N,) the trims, the hand-off's fraction bits (:func:`terms_frac`; with a temperature
    table only, else 0)."""
    terms = has_terms(cal)
    tt = TermsTables(n=n, dt_s=float(dt_s))
    if terms["temperature"]:
        tt.frac = terms_frac(rails, trim)
        oc, gc = channel_values(cal.offset_tc, n), channel_values(cal.gain_tc, n)
        tt.temp = dict(t_ref=int(to_fixed(cal.temp_ref_c or 0.0, TEMP_FRAC, "temperature_ref_c", -32768, 32767)),
                       oc=to_fixed(oc, OC_FRAC, "offset_tc_counts_per_c", -32767, 32767),
                       gc=to_fixed(gc, GC_FRAC, "gain_tc_per_c", -32767, 32767),
                       o=np.asarray(offset_q, np.int64), frac=tt.frac,
                       lag_off=lag_fixed(cal.temp_offset_tau_s, dt_s), lag_gain=lag_fixed(cal.temp_gain_tau_s, dt_s),
                       tau_off=cal.temp_offset_tau_s, tau_gain=cal.temp_gain_tau_s)
    if terms["skew"]:
        tau = channel_values(cal.time_skew_s, n)
        j = skew_delays(tau, dt_s)
        whole = np.floor(j).astype(np.int64)
        frac = round_half_up((j - whole) * 2.0 ** SKEW_FRAC).astype(np.int64)
        whole, frac = np.where(frac >= 2 ** SKEW_FRAC, whole + 1, whole), np.where(frac >= 2 ** SKEW_FRAC, 0, frac)
        length = int(whole.max()) + 2
        if length > lib.AC_SKEW_MAX_LEN:
            raise QuantizeError(f"time_skew_s: a delay of {float(j.max()):.3g} samples needs a delay line of "
                                f"{length} > AC_SKEW_MAX_LEN = {lib.AC_SKEW_MAX_LEN} samples")
        tt.skew = dict(len=length, whole=whole, frac=frac, latency=skew_latency(tau, dt_s))
    if terms["nonlinearity"]:
        c2, c3 = nonlinearity_coefficients(cal.sensitivity, cal.nonlin_k2, cal.nonlin_k3)
        # per 2^-frac count: C(z) = c2 z^2 + c3 z^3 counts is c2 2^-k zq^2 + c3 2^-2k zq^3 in 2^-k counts
        c2q, c3q = c2 * 2.0 ** -tt.frac, c3 * 2.0 ** (-2 * tt.frac)
        u = np.abs(c2q) * 2.0 ** 15 + np.abs(c3q) * 2.0 ** 30
        shift = _shift_for(float(u.max()), 0, 30, "the nonlinearity at full scale", 32766.0)
        tt.nonlin = dict(shift=shift, a2=to_fixed(c2q, 15 + shift, "nonlin_k2", -32767, 32767),
                         a3=to_fixed(c3q, 30 + shift, "nonlin_k3", -32767, 32767),
                         iterations=nonlinearity_iterations(
                             c2, c3, None if rails is None else nonlinearity_span(cal.offsets, rails)))
    return tt


def terms_tables(device, cal):
    """(table, TermsTables) of a calibration with correctable terms on a device: the resolver's
    (quantize.FixedTables) or, for a 3-axis chip, the triad's (triad.TriadTable) table for input in
    2^-frac counts, and the terms' tables (the header's and ``resolve --engine fixed``'s)."""
    rails = (device.raw_min, device.raw_max)
    signed = device.raw_min < 0
    triad = device.is_triad()
    t = (quantize_triad(cal.offsets, cal.sensitivity, signed, rails) if triad
         else quantize_calibration(device, cal))
    tt = quantize_terms(cal, device.n_channels, 1.0 / float(device.sample_rate_hz), t.offset_q, rails, t.trim)
    if tt.frac:
        t = (quantize_triad(cal.offsets, cal.sensitivity, signed, rails, in_frac=tt.frac) if triad
             else quantize_calibration(device, cal, in_frac=tt.frac))
    return t, tt


def temp_to_fixed(temp_c) -> np.ndarray:
    """degC -> int16 Q.AC_TEMP_FRAC (QuantizeError outside +-128 degC or not finite)."""
    return to_fixed(temp_c, TEMP_FRAC, "temp_c", -32768, 32767).astype(np.int16)


def apply_terms_fixed(tt: TermsTables, x, temp_q=None) -> tuple[np.ndarray, np.ndarray]:
    """The terms through the core, sample by sample, as firmware runs them: x (n, N) int16
    trimmed readings, temp_q (n,) int16 Q.AC_TEMP_FRAC (needed with a temperature table).
    Returns (y (n, N) int16 in 2^-tt.frac counts at the common instant of each step: the skew's
    latency is not taken out here, saturated (n,) bool)."""
    x = np.ascontiguousarray(x, dtype=np.int16)
    n = x.shape[0]
    c = tt.cdata()
    y = np.empty_like(x)
    sat = np.zeros(n, bool)
    if tt.temp is not None:
        if temp_q is None:
            raise ValueError("a temperature table needs the temperature")
        t_off, s_off = native.temp_lag_run(*tt.temp["lag_off"], temp_q)
        t_gain, s_gain = native.temp_lag_run(*tt.temp["lag_gain"], temp_q)
        sat |= s_off | s_gain
    line = native.SkewLine(c["skew"]) if "skew" in c else None
    for k in range(n):
        v = x[k]
        if "temp" in c:
            v, s = native.temp_correct(c["temp"], int(t_off[k]), int(t_gain[k]), v)
            sat[k] |= s
        if line is not None:
            v = line.step(v)
        if "nonlin" in c:
            v, s = native.nonlin_invert(c["nonlin"], v)
            sat[k] |= s
        y[k] = v
    return y, sat


# --------------------------------------------------------------------------
# the error bounds the headers state (against the float references fed the tables' values)
# --------------------------------------------------------------------------


def lag_bound(k: int, shift: int, tau_s: float | None, dt_s: float, span_c: float) -> float:
    """degC: |ac_temp_lag_step - lag_temperature| over a run whose inputs span ``span_c`` degC."""
    c = lag_coefficient(tau_s, dt_s)
    cq = k / 2.0 ** shift
    return 2.0 ** -9 + 2.0 ** -(TEMP_FRAC + lib.AC_TEMP_LAG_EXTRA + 1) / cq + abs(cq - c) / cq * span_c


def temp_bound(x, e, frac: int = 0) -> np.ndarray:
    """counts: |ac_temp_correct 2^-frac - temperature_correct| for readings x (trimmed) and e = gc dTg
    (the table's output in 2^-frac counts)."""
    e = np.abs(np.asarray(e, float))
    return 2.0 ** -(frac + 1) + 2.0 ** -8 + 0.54 * e + (np.abs(np.asarray(x, float)) + 1.0) * (2.0 ** -18 + e ** 4 / (1.0 - e))


def nonlin_bound(z, c2, c3, shift: int, iterations: int = ITERATIONS, frac: int = 0) -> np.ndarray:
    """|ac_nonlin_invert - nonlinearity_invert| in the table's units (2^-frac counts) for readings of
    size up to ``z`` and the table's coefficients c2, c3 (per those units: TermsTables.nonlin_coefficients),
    both running ``iterations`` iterations (the trim's fraction, up to half a count, is 2^(frac-1) units)."""
    z = np.abs(np.asarray(z, float))
    L = 2.0 * np.abs(c2) * z + 3.0 * np.abs(c3) * z * z
    E = 0.5 + (z * z * 2.0 ** -16 + 0.5 * z) * 2.0 ** -shift
    # the C iterates from the reading about its integer trim, the reference from it less the trim's
    # fraction o (|o| <= 0.5) and adds o back: the k-fold map's derivative differs from 1 by at most
    # L + L^2 + ... + L^k (e_{j+1} <= L (1 + e_j)), so the fraction moves the result by up to
    # 0.5 (L + ... + L^k); the C's own arithmetic from the same start adds D (E per iteration, contracted
    # by L).  (Starting D at 0.5 instead, contracted by L^k, had missed 5e-5 counts at shift 19, a2 29962,
    # x -2966, o 0.5: hypothesis found it.)
    D = 0.0 * z
    e = 0.0 * z
    with np.errstate(over="ignore"):      # far outside the contraction the bound is inf: no bound
        for _ in range(int(iterations)):
            D = E + L * D
            e = L * (1.0 + e)
        return D + 2.0 ** (frac - 1) * e
