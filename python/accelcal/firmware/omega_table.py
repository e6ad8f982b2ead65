"""The integer core's table of the array's own omega (``ac_omega.h``, issue 36): made from a
calibration, run through the C core, and written into the calibration header.

The table holds the nine readings rows (the six centripetal readings q, whitened counts, and
the three alpha rows, rad/s^2) as int16 with a shift each, exactly as ``ac_resolve`` holds its
rows, and every other constant (m, m^-1, the leak L, the prediction's Qn, P0, dt, the jump
threshold and the ML's ridge) as an ``ac_xf`` (30-bit mantissa and an exponent).
:meth:`OmegaTable.values` gives the exact values of the entries: the float reference
(:func:`accelcal.estimators.omega_fixed.omega_reference`) runs on them, and ``resolve
--engine fixed --omega array`` runs :func:`omega_run` on the same table ``header`` writes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import model
from .native import check, cptr, ffi, lib
from .quantize import COEF_MAX, QuantizeError, FixedTables, quantize_calibration, round_half_up, row_shift

__all__ = ["OmegaTable", "to_xf", "xf_value", "omega_table", "OmegaCore", "omega_run", "omega_header_lines",
           "insert_omega", "device_omega_table",
           "OMEGA_JUMP_CHI2", "OMEGA_RANK_RTOL", "OMEGA_SNAP", "OMEGA_SIGMA0"]

#: the float estimator's constants (estimators.omega / omega_filter), repeated here because
#: firmware does not import the method packages; tests/python/test_omega_fixed.py checks they agree
OMEGA_JUMP_CHI2 = 50.0
OMEGA_RANK_RTOL = 1e-9
OMEGA_SNAP = 3.0e5
OMEGA_SIGMA0 = 0.01
#: the six entries (00 01 02 11 12 22) of a symmetric 3x3 and the upper triangle of a 6x6
_SYM3 = ([0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2])
_SYM6 = np.triu_indices(6)
#: ac_omega.h's AC_OMEGA_LO_BITS
LO_BITS = lib.AC_OMEGA_LO_BITS


def to_xf(v: float) -> tuple[int, int]:
    """A float as an ac_xf (m, e): v ~ m 2^e with 2^29 <= |m| < 2^30 (or 0), rounded to
    nearest with ties away from zero (the core's rule)."""
    v = float(v)
    if v == 0.0:
        return 0, 0
    if not math.isfinite(v):
        raise QuantizeError(f"omega table: non-finite value {v}")
    f, e = math.frexp(abs(v))                 # 0.5 <= f < 1
    m = math.floor(math.ldexp(f, 30) + 0.5)   # ties away from zero on the magnitude
    e -= 30
    if m >= 1 << 30:
        m, e = m >> 1, e + 1
    if not -30000 <= e <= 30000:
        raise QuantizeError(f"omega table: {v} is beyond the ac_xf range")
    return (-m if v < 0 else m), e


def xf_value(me) -> float:
    m, e = me
    return math.ldexp(float(m), int(e))


def _xf_round(a) -> np.ndarray:
    a = np.asarray(a, float)
    return np.array([xf_value(to_xf(v)) for v in a.ravel()]).reshape(a.shape)


@dataclass(frozen=True)
class OmegaTable:
    """The ``ac_omega_table`` of a layout, as exact values.

    Attributes
    ----------
    shift : ndarray (9,) int
    t, tl : ndarray (9, N) int16
        Rows 0..5: q (whitened counts per count); 6..8: alpha (rad/s^2 per count), each
        ``(t + tl 2^-LO_BITS) 2^-shift``.
    k : ndarray (9,)
        The residual offsets through the rows (exact ac_xf values).
    m, minv : ndarray (6, 6)
    leak : ndarray (3, 6)
        rad/s^2 per (rad/s)^2.
    qn, p0 : ndarray (3, 3)
        (rad/s)^2.
    dt, jump, ridge : float
        s, chi^2 units, per (rad/s)^2.
    """

    shift: np.ndarray
    t: np.ndarray
    tl: np.ndarray
    k: np.ndarray
    m: np.ndarray
    minv: np.ndarray
    leak: np.ndarray
    qn: np.ndarray
    p0: np.ndarray
    dt: float
    jump: float
    ridge: float

    @property
    def n(self) -> int:
        return self.t.shape[1]

    def rows(self) -> np.ndarray:
        """(9, N) the rows' exact values."""
        return (self.t + self.tl * 2.0 ** -LO_BITS) * 2.0 ** (-self.shift.astype(float))[:, None]

    def cdata(self):
        """A new ``ac_omega_table *`` with these entries."""
        c = ffi.new("ac_omega_table *")
        c.n = self.n
        for j in range(9):
            c.shift[j] = int(self.shift[j])
            for i in range(self.n):
                c.t[j][i] = int(self.t[j, i])
                c.tl[j][i] = int(self.tl[j, i])
            c.k[j].m, c.k[j].e = to_xf(self.k[j])
        for idx, (i, j) in enumerate(zip(*_SYM6)):
            c.m[idx].m, c.m[idx].e = to_xf(self.m[i, j])
            c.minv[idx].m, c.minv[idx].e = to_xf(self.minv[i, j])
        for i in range(3):
            for j in range(6):
                c.leak[i][j].m, c.leak[i][j].e = to_xf(self.leak[i, j])
        for idx, (i, j) in enumerate(zip(*_SYM3)):
            c.qn[idx].m, c.qn[idx].e = to_xf(self.qn[i, j])
            c.p0[idx].m, c.p0[idx].e = to_xf(self.p0[i, j])
        for name, v in (("dt", self.dt), ("half_dt", self.dt / 2.0), ("jump", self.jump), ("ridge", self.ridge)):
            x = getattr(c, name)
            x.m, x.e = to_xf(v)
        return c


def _rows_int16(rows: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    shifts = np.array([row_shift(rows[j], f"{what} row {j}") for j in range(rows.shape[0])])
    scaled = rows * 2.0 ** shifts[:, None]
    t = round_half_up(scaled)
    tl = round_half_up((scaled - t) * 2.0 ** LO_BITS)      # |tl| <= 2^(LO_BITS-1)
    if np.any(np.abs(t) > COEF_MAX) or np.any(np.abs(tl).sum(axis=1) > 65535):
        raise QuantizeError(f"{what}: a coefficient beyond int16")
    return t.astype(np.int16), tl.astype(np.int16), shifts


def omega_table(tables: FixedTables, noise_counts, dt: float, *, snap: float = OMEGA_SNAP,
                sigma0: float = OMEGA_SIGMA0, jump: float = OMEGA_JUMP_CHI2) -> OmegaTable:
    """The omega table of a quantised calibration (its exact sensitivities, positions and
    offsets: the resolver's), each channel's noise sd (counts, rounding included) and the
    sample interval dt (s).

    Raises
    ------
    QuantizeError
        A layout whose centripetal readings do not fix all six rate products (m singular:
        the core's closed-form start needs m^-1), or a value beyond the formats.
    """
    s, r = tables.sensitivity(), tables.positions()
    o = tables.offsets() - tables.trim.astype(float)
    split = model.centripetal_split(r, s, np.asarray(noise_counts, float))
    lam = np.linalg.eigvalsh(split.m)
    if lam[0] <= 1e-6 * lam[-1]:
        raise QuantizeError("the fixed omega needs a layout whose channels fix all six rate products "
                            "(m invertible: 12 channels as four triads on a tetrahedron, or triads at the "
                            "origin and on the axes); this one fixes fewer")
    t, tl, shifts = _rows_int16(np.vstack([split.qmap, split.lin[3:]]), "omega")
    exact_rows = (t + tl * 2.0 ** -LO_BITS) * 2.0 ** (-shifts.astype(float))[:, None]
    m = _xf_round(split.m)
    m = np.triu(m) + np.triu(m, 1).T
    minv = np.linalg.inv(m)
    minv = _xf_round((minv + minv.T) / 2.0)
    Q = dt * dt * split.cov[3:, 3:] + (snap * dt ** 3 / 12.0) ** 2 * np.eye(3)
    Q = _xf_round((Q + Q.T) / 2.0)
    return OmegaTable(shift=shifts.astype(np.int8), t=t, tl=tl, k=_xf_round(exact_rows @ o), m=m, minv=minv,
                      leak=_xf_round(split.leak[3:]), qn=Q, p0=_xf_round(sigma0 ** 2 * np.eye(3)),
                      dt=xf_value(to_xf(dt)), jump=xf_value(to_xf(jump)),
                      ridge=xf_value(to_xf(OMEGA_RANK_RTOL * float(np.trace(m)))))


class OmegaCore:
    """``ac_omega_step`` with its state kept from one call of :meth:`run` to the next (a recording in
    chunks: the numbers of one run over all of it).

    Parameters
    ----------
    table : OmegaTable
    """

    def __init__(self, table: OmegaTable) -> None:
        self.table = table
        self.c = table.cdata()
        self.st = ffi.new("ac_omega_state *")
        check(lib.ac_omega_init(self.st, self.c), "ac_omega_init")

    def run(self, x) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The next samples (see :func:`omega_run`)."""
        x = np.ascontiguousarray(np.atleast_2d(x), dtype=np.int16)
        n = x.shape[0]
        if x.shape[1] != self.table.n:
            raise ValueError(f"x must be (n, {self.table.n})")
        c, st = self.c, self.st
        w16 = np.zeros((n, 3), np.int32)
        w10 = np.zeros((n, 3), np.int16)
        sig = np.zeros((n, 3), np.int32)
        flags = np.zeros(n, np.uint8)
        sat = np.zeros(n, bool)
        o16, o10, osig, ofl = (ffi.new("int32_t[3]"), ffi.new("int16_t[3]"), ffi.new("int32_t[3]"),
                               ffi.new("uint8_t *"))
        for k in range(n):
            sat[k] = check(lib.ac_omega_step(st, c, cptr("int16_t *", x[k]), o16, o10, ofl), "ac_omega_step")
            sat[k] |= check(lib.ac_omega_sigma(st, osig), "ac_omega_sigma")
            w16[k], w10[k], sig[k], flags[k] = list(o16), list(o10), list(osig), ofl[0]
        return w16, w10, sig, flags, sat


def omega_run(table: OmegaTable, x) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Run ``ac_omega_step`` over every sample of the pre-trimmed readings x (n, N) int16.

    Returns
    -------
    w_q16 : ndarray (n, 3) int32
        rad/s Q15.16.
    w_q10 : ndarray (n, 3) int16
        rad/s Q5.10 (ac_resolve's input).
    sigma_q16 : ndarray (n, 3) int32
        The 1-sigma, rad/s Q15.16.
    flags : ndarray (n,) uint8
        AC_OMEGA_FLAG_*.
    saturated : ndarray (n,) bool
    """
    return OmegaCore(table).run(x)


def _xf_init(v: float) -> str:
    m, e = to_xf(v)
    return f"{{{m}L, {e}}}"


def device_omega_table(device, cal, noise_counts=None) -> OmegaTable | None:
    """The omega table ``accelcal header`` writes for an array: the quantised calibration
    (:func:`quantize_calibration`), each channel's noise (default the device's ``noise_mps2``)
    with the rounding's 1/12 count^2, dt = 1 / the device's sample rate.  None when the
    layout does not fix all six rate products or the noise is unknown (``noise_mps2`` 0 and no
    ``noise_counts``)."""
    if device.is_triad():
        return None
    k = device.noise_counts() if noise_counts is None else np.asarray(noise_counts, float)
    if not np.all(np.asarray(k) > 0):
        return None
    try:
        return omega_table(quantize_calibration(device, cal), np.sqrt(np.asarray(k, float) ** 2 + 1.0 / 12.0),
                           1.0 / float(device.sample_rate_hz))
    except (QuantizeError, np.linalg.LinAlgError):
        return None


def omega_header_lines(table: OmegaTable, prefix: str) -> list[str]:
    """The C definition of the table (``const ac_omega_table {prefix}_OMEGA``), for the
    header's implementation section."""
    p = prefix
    out = [f"const ac_omega_table {p}_OMEGA = {{", f"    {table.n}u,",
           "    {" + ", ".join(str(int(v)) for v in table.shift) + "},"]
    for part in (table.t, table.tl):
        out.append("    {")
        for j in range(9):
            out.append("        {" + ", ".join(str(int(v)) for v in part[j]) + "},")
        out.append("    },")
    xs = lambda vals: "    {" + ", ".join(_xf_init(v) for v in vals) + "},"  # noqa: E731
    out.append(xs(table.k))
    out.append(xs(table.m[_SYM6]))
    out.append(xs(table.minv[_SYM6]))
    out.append("    {" + ", ".join("{" + ", ".join(_xf_init(v) for v in row) + "}" for row in table.leak) + "},")
    out.append(xs(table.qn[_SYM3]))
    out.append(xs(table.p0[_SYM3]))
    out += [f"    {_xf_init(table.dt)},", f"    {_xf_init(table.dt / 2.0)},", f"    {_xf_init(table.jump)},",
            f"    {_xf_init(table.ridge)}", "};"]
    return out


def insert_omega(text: str, prefix: str, table: OmegaTable) -> str:
    """The calibration header with the omega table: its use in the opening comment, its
    declaration after the resolver's, its definition in the implementation section."""
    p = prefix
    use = [" * The array's own omega (ac_omega.h; docs/angular-rate.md), per sample after ac_trim:",
           f" *     ac_omega_init(&st, &{p}_OMEGA);   once, at rest",
           f" *     ac_omega_step(&st, &{p}_OMEGA, x, w_q16, w_q10, &flags);   w_q10: ac_resolve's omega",
           f" *   made for {table.n} channels at dt = {table.dt:.9g} s and the device's noise; its error",
           " *   against the float reference: ac_omega.h.",
           " *"]
    head, sep, rest = text.partition(" * Fixed-point formats")
    text = head + "\n".join(use) + "\n" + sep + rest
    decl = f"extern const ac_resolver {p}_RESOLVER;"
    text = text.replace(decl, decl + f"\nextern const ac_omega_table {p}_OMEGA;", 1)
    end = f"#endif /* {p}_IMPLEMENTATION */"
    return text.replace(end, "\n".join(omega_header_lines(table, p)) + "\n" + end, 1)
