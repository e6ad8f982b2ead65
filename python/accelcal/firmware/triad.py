"""One triad: raw counts -> calibrated specific force at its point, f = S^-1 (raw - b).

The firmware path of a 3-axis sensor (the calibration header, ``resolve --engine fixed``)
and the estimators' triads share it.

Float reference (:func:`triad_apply_float`), the fixed-point table by the quantizer's
rules (:func:`quantize_triad`), the C core's ``ac_triad_apply`` on arrays
(:func:`triad_apply_fixed`) with its exact semantics (:func:`triad_exact`), and the
recording form (:func:`triad_forces`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import AccelcalError
from .native import FORMATS, check, cptr, ffi, lib
from .quantize import rail_codes, rail_counts, round_half_up, row_shift, to_fixed, trim_range

OUT_FRAC = FORMATS.out_frac
I16_MIN, I16_MAX = -32768, 32767

__all__ = ["TriadTable", "triad_matrix", "quantize_triad", "build_triad_on_device", "triad_apply_fixed", "triad_exact",
           "triad_apply_float", "triad_forces", "triad_rounding_bound"]


@dataclass
class TriadTable:
    """One triad's fixed-point table (ac_triad): f = round((m x - k) 2^-shift), x = raw - trim."""
    trim: np.ndarray   # (3,) uint16 counts (int16 when ``signed``)
    m: np.ndarray      # (3,3) int16
    shift: np.ndarray  # (3,) int8
    k: np.ndarray      # (3,) int32
    signed: bool = False   # int16 readings: pre-trim with ac_trim_s16, then ac_triad_resolve
    sens_q: np.ndarray | None = None    # (3,3) int32 Q.AC_SENS_FRAC: s~ (the header's channel entries)
    offset_q: np.ndarray | None = None  # (3,) int32 Q.AC_OFFSET_FRAC: b - trim
    rails: tuple = (0, 0)   # the converter's (raw_min, raw_max), uint16 codes (quantize.rail_codes)

    def trim_code(self) -> np.ndarray:
        """The trim as the uint16 code ac_triad's ``trim`` field holds: offset binary
        (trim + 32768) for a signed chip, so ac_triad_apply on offset-binary readings gives
        what ac_trim_s16 + ac_triad_resolve give on the signed ones."""
        t = self.trim.astype(np.int64)
        return (t + 32768 if self.signed else t).astype(np.uint16)

    def cdata(self):
        """The table as a C ``ac_triad``."""
        t = ffi.new("ac_triad *")
        for j in range(3):
            t.trim[j] = int(self.trim_code()[j])
            t.shift[j] = int(self.shift[j])
            t.k[j] = int(self.k[j])
            for i in range(3):
                t.m[j][i] = int(self.m[j, i])
        t.raw_min, t.raw_max = (int(v) for v in self.rails)
        return t


def triad_matrix(sens3: np.ndarray) -> np.ndarray:
    """M = S^-1 (3x3, m/s^2 per count) of a triad whose rows are s_i (counts per m/s^2).

    Raises
    ------
    AccelcalError
        S singular (its three axes do not span 3-D) or not finite.
    """
    S = np.asarray(sens3, float)
    if S.shape != (3, 3) or not np.all(np.isfinite(S)) or abs(np.linalg.det(S)) <= 1e-12 * np.abs(S).max() ** 3:
        raise AccelcalError("a triad's sensitivity matrix is singular: its three axes do not span 3-D")
    return np.linalg.inv(S)


def quantize_triad(offsets3, sens3, signed: bool = False, rails: tuple[int, int] | None = None,
                   in_frac: int = 0) -> TriadTable:
    """The triad's table by the rules of quantize.quantize.

    Parameters
    ----------
    offsets3 : array_like (3,)
        Offsets b, counts.
    sens3 : array_like (3, 3)
        Sensitivity rows s_i, counts per m/s^2.
    signed : bool
        The chip's readings are int16 (trim in -32768..32767), else uint16.
    rails : (int, int) or None
        The converter's (raw_min, raw_max), counts: ``ac_triad_apply`` flags a reading there
        (AC_AT_RAIL); None: unknown, nothing flagged.
    in_frac : int
        k > 0: the table takes x in 2^-k counts (the correctable terms' output, ac_temp.h's frac,
        for ``ac_triad_resolve``): each row's shift + k (at most 31) with the same m, k = M o~
        2^(shift + k).  0: today's table.

    Returns
    -------
    TriadTable
        trim = round(b); s~ = s in Q.AC_SENS_FRAC and o~ = b - trim in Q.AC_OFFSET_FRAC (the
        values the header's ac_channel_cal entries hold, from which ``ac_triad_build``
        makes the same table on the device); M = S~^-1 in output LSB per count; each row's
        shift the largest with max |m| <= 32767 and sum |m| <= 65535 - 3; k = M o~.
    """
    b = np.asarray(offsets3, float)
    trim = to_fixed(b, 0, "offset_counts", *trim_range(signed))
    sens_q = to_fixed(sens3, FORMATS.sens_frac, "sensitivity")
    offset_q = to_fixed(b - trim, FORMATS.offset_frac, "residual offset")
    M = triad_matrix(sens_q / 2.0 ** FORMATS.sens_frac) * 2.0 ** OUT_FRAC       # output LSB per count
    o = offset_q / 2.0 ** FORMATS.offset_frac
    shift = np.array([row_shift(M[j], f"triad matrix row {j}") for j in range(3)])
    m = round_half_up(M * 2.0 ** (np.minimum(shift + in_frac, 31) - in_frac)[:, None]).astype(np.int16)
    shift = np.minimum(shift + in_frac, 31)
    k = to_fixed((M @ o) * 2.0 ** shift, 0, "triad offset term k")
    return TriadTable(trim=trim.astype(np.int16 if signed else np.uint16), m=m, shift=shift.astype(np.int8),
                      k=k.astype(np.int32), signed=signed, sens_q=sens_q.astype(np.int32),
                      offset_q=offset_q.astype(np.int32), rails=rail_codes(*(rails or (None, None)), signed))


def build_triad_on_device(table: TriadTable) -> TriadTable:
    """The C core's ``ac_triad_build`` from the table's fixed-point channel parameters
    (``sens_q``, ``offset_q``, the trim codes): what firmware rebuilds after a field
    recalibration.  Raises AccelcalError with the core's status on failure."""
    cal = ffi.new("ac_channel_cal[3]")
    for i in range(3):
        for a in range(3):
            cal[i].sens[a] = int(table.sens_q[i][a])
        cal[i].offset = int(table.offset_q[i])
    trim = np.ascontiguousarray(table.trim_code(), dtype=np.uint16)
    work = ffi.new("ac_build_work *")
    out = ffi.new("ac_triad *")
    check(lib.ac_triad_build(cal, cptr("uint16_t *", trim), work, out), "ac_triad_build")
    return TriadTable(trim=table.trim.copy(), m=np.array([[out.m[j][i] for i in range(3)] for j in range(3)], np.int16),
                      shift=np.array([out.shift[j] for j in range(3)], np.int8),
                      k=np.array([out.k[j] for j in range(3)], np.int32), signed=table.signed,
                      sens_q=table.sens_q, offset_q=table.offset_q, rails=table.rails)


def triad_apply_fixed(table: TriadTable, raw) -> tuple[np.ndarray, np.ndarray]:
    """ac_triad_apply on every sample.

    Parameters
    ----------
    table : TriadTable
    raw : array_like (n, 3)
        Counts: uint16, or int16 for a ``signed`` table (then pre-trimmed with
        ``ac_trim_rails_s16`` and resolved with ``ac_triad_resolve``, as the header tells signed
        firmware to).

    Returns
    -------
    f : ndarray (n, 3) int32
        Q.AC_OUT_FRAC m/s^2.
    saturated : ndarray (n,) bool
    """
    t = table.cdata()
    check(lib.ac_triad_check(t), "ac_triad_check")
    raw = np.ascontiguousarray(raw, dtype=np.int16 if table.signed else np.uint16)
    out = np.zeros((raw.shape[0], 3), np.int32)
    sat = np.zeros(raw.shape[0], bool)
    fo = ffi.new("int32_t[3]")
    if table.signed:
        trim = np.ascontiguousarray(table.trim, dtype=np.int16)
        x = np.zeros(3, np.int16)
        lo, hi = rail_counts(table.rails, True)
        for n in range(raw.shape[0]):
            s1 = check(lib.ac_trim_rails_s16(cptr("int16_t *", raw[n]), cptr("int16_t *", trim), 3, lo, hi,
                                             cptr("int16_t *", x)), "ac_trim_rails_s16")
            s2 = check(lib.ac_triad_resolve(t, cptr("int16_t *", x), fo), "ac_triad_resolve")
            sat[n] = s1 or s2
            out[n] = (fo[0], fo[1], fo[2])
        return out, sat
    for n in range(raw.shape[0]):
        sat[n] = check(lib.ac_triad_apply(t, cptr("uint16_t *", raw[n]), fo), "ac_triad_apply")
        out[n] = (fo[0], fo[1], fo[2])
    return out, sat


def triad_exact(table: TriadTable, raw) -> np.ndarray:
    """The triad table's exact result in output LSB (before the final rounding), (n, 3)."""
    x = np.clip(np.asarray(raw, np.int64) - table.trim.astype(np.int64), I16_MIN, I16_MAX)
    return (x @ table.m.T.astype(float) - table.k) * 2.0 ** (-table.shift.astype(float))


def triad_rounding_bound(table: TriadTable, offsets3, sens3, raw_min: int, raw_max: int) -> np.ndarray:
    """(3,) the largest |triad_exact - f_float| (output LSB) over every reading in
    [raw_min, raw_max]^3 that the trim does not clip: the table's rounding (of S~, o~, m and k).
    Both sides are affine in the reading on that box, so the largest difference is at one of its
    8 corners; the core's final rounding adds 0.5 LSB on top."""
    trim = table.trim.astype(np.int64)
    lo = np.maximum(raw_min, trim + I16_MIN)
    hi = np.minimum(raw_max, trim + I16_MAX)
    corners = np.array([[(lo, hi)[(c >> j) & 1][j] for j in range(3)] for c in range(8)], np.int64)
    exact = triad_exact(table, corners)
    ref = triad_apply_float(offsets3, sens3, corners) * 2.0 ** OUT_FRAC
    return np.max(np.abs(exact - ref), axis=0)


def triad_apply_float(offsets3, sens3, raw) -> np.ndarray:
    """Float reference: f = S^-1 (raw - b), (n, 3) m/s^2 from (n, 3) counts."""
    return (np.asarray(raw, float) - np.asarray(offsets3, float)) @ triad_matrix(sens3).T


def triad_forces(cal, rec, chans, engine: str, signed: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """f of the triad at channels ``chans`` of a recording (``signed``: int16 readings).

    Returns
    -------
    f : ndarray (n, 3)
        engine "float": m/s^2; "fixed": int32 Q.AC_OUT_FRAC from the C core.
    saturated : ndarray (n,) bool or None
        The core's saturation per sample (None for "float").
    """
    b = np.asarray(cal.offsets, float)[list(chans)]
    s = np.asarray(cal.sensitivity, float)[list(chans)]
    raw = np.asarray(rec.raw)[:, list(chans)]
    if engine == "float":
        return triad_apply_float(b, s, raw), None
    return triad_apply_fixed(quantize_triad(b, s, signed), raw)
