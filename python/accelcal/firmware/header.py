"""C header emission: the quantizer's tables as firmware source.

The header is stb-style: every translation unit sees ``extern`` declarations;
exactly one defines ``<PREFIX>_IMPLEMENTATION`` before including it to get the
definitions.  That keeps it warning-free under -Wall -Wextra (no unused static
tables) on host gcc, h8300-hms-gcc and avr-gcc.
"""
from __future__ import annotations

import re
import textwrap

import numpy as np

from .. import __version__
from .triad import TriadTable, quantize_triad, triad_rounding_bound
from .native import FORMATS
from .omega_table import device_omega_table, insert_omega
from .quantize import FixedTables, quantize_calibration, rail_counts, resolver_rounding_bound, to_fixed
from .terms_fixed import terms_tables
from .terms_header import insert_terms, terms_header_parts


def _c_ident(text: str) -> str:
    s = re.sub(r"[^A-Za-z0-9]+", "_", text).strip("_").upper()
    return s if s and not s[0].isdigit() else f"X_{s}"


def _row(values, width: int = 0) -> str:
    vals = [str(int(v)) for v in values]
    if width:
        vals += ["0"] * (width - len(vals))
    return "{" + ", ".join(vals) + "}"


def warning_lines(warnings, notes=()) -> list[str]:
    """The header comment's lines for a calibration's warnings (its JSON's ``warnings``: what
    ``accelcal calibrate`` warned of), each wrapped at 100 columns under "WARNING", so that a
    poorly determined calibration is not burnt into firmware without a word, then its ``notes``
    under "NOTE" (what the method held at nominal, not fitted); [] for none."""
    lines = []
    for label, texts in (("WARNING", warnings), ("NOTE", notes)):
        for w in texts or ():
            text = str(w).replace("*/", "* /")
            lines += textwrap.wrap(f"{label} (accelcal calibrate): {text}", width=100, initial_indent=" * ",
                                   subsequent_indent=" *   ", break_on_hyphens=False, break_long_words=False)
    return lines + [" *"] if lines else []


def _opening(guard: str, *formats: tuple[str, int]) -> list[str]:
    """The lines that close a header's comment and open its body: the include guard, the
    core's header, and a check that refuses to build against a core with other fractional
    bits (``("OUT", 10)`` checks AC_OUT_FRAC == 10)."""
    cond = " || ".join(f"AC_{name}_FRAC != {bits}" for name, bits in formats)
    return [" */", f"#ifndef {guard}", f"#define {guard}", "", "#include \"accelcal/accelcal.h\"", "",
            f"#if {cond}", "#error \"calibration header made for other fixed-point formats: regenerate it\"", "#endif"]


def resolver_bound_lines(rounding_lsb) -> list[str]:
    """The header comment's statement of the 6-channel error bound, from
    :func:`accelcal.firmware.quantize.resolver_rounding_bound`'s (linear (6,), centripetal (6,)); a
    sentence without figures for None."""
    if rounding_lsb is None:
        return [" *   |out - M (raw - b - C p(omega))| <= 0.5 LSB + the table's rounding (ac_resolve.h:"
                " the exact semantics)"]
    lin, cen = (np.asarray(v, float) for v in rounding_lsb)
    lsb = 2.0 ** -FORMATS.out_frac
    lf, la, cf, ca = lin[:3].max() + 0.5, lin[3:].max() + 0.5, cen[:3].max(), cen[3:].max()
    return [" * Error bound against the float reference M (raw - b - C p(omega)) with this calibration:",
            f" *   linear part: at most {lf:.3g} LSB on f ({lf * lsb:.3g} m/s^2), {la:.3g} LSB on alpha"
            f" ({la * lsb:.3g} rad/s^2)",
            " *     for every reading the trim does not clip (0.5 LSB final rounding + the table's, the",
            " *     largest at a corner of the reading box: both sides are affine in the reading);",
            f" *   centripetal term (quadratic in omega, bounded apart): + {cf:.3g} LSB on f, {ca:.3g} LSB on",
            " *     alpha per (rad/s)^2 of max_a omega_a^2 (its coefficients' rounding), and for any",
            " *     |omega_a| >= 0.125 rad/s the squared rates' rounding E_j of ac_resolve.h."]


MG_MPS2 = 9.80665e-3   # one mg, m/s^2 (standard gravity)


def _c_int(v: int, signed: bool) -> str:
    """An integer literal for a 16-bit argument that means the same with 16-bit int."""
    if not signed:
        return f"{v}u"
    return "(-32767 - 1)" if v == -32768 else (f"({v})" if v < 0 else str(v))


def rail_macros(p: str, rails, signed: bool) -> list[str]:
    """``<p>_RAW_MIN`` / ``<p>_RAW_MAX``: the converter's rails in the chip's counts (the
    arguments ac_trim_rails_s16 takes for a signed chip; the tables hold them as codes)."""
    lo, hi = rail_counts(rails, signed)
    return [f"#define {p}_RAW_MIN {_c_int(lo, signed)}", f"#define {p}_RAW_MAX {_c_int(hi, signed)}"]


def input_lines(rails, signed: bool, counts_per_mps2=None) -> list[str]:
    """The header comment's statement of the input the tables expect: raw counts of the device
    file, their range raw_min..raw_max (justification: a left-justified register is shifted first)
    and, given the device's nominal ``counts_per_mps2`` (N,), the size of one count per channel in
    m/s^2 and mg (a reading in mg is divided by that first)."""
    lo, hi = rail_counts(rails, signed)
    lines = [f" * Input: raw[i] in the device file's counts, {lo}..{hi} (raw_min..raw_max)"]
    span = hi - lo + 1
    bits = span.bit_length() - 1 if span > 1 and span & (span - 1) == 0 else None
    if bits is not None and bits < 16:
        lines += [f" *   ({bits} bits, right-justified{', sign-extended' if signed else ''}): a chip that leaves them at"
                  f" the top of a 16-bit", f" *   register (left-justified, e.g. the LIS3DH) needs its value"
                  f" {'(int16_t)' if signed else '(uint16_t)'} >> {16 - bits} first{' (arithmetic)' if signed else ''}."]
    if counts_per_mps2 is None:
        return lines + [" *   Not mg, not m/s^2: counts as the device file's counts_per_mps2 defines them."]
    k = np.asarray(counts_per_mps2, float)
    groups = []
    for i, v in enumerate(k):
        if groups and groups[-1][2] == v:
            groups[-1][1] = i
        else:
            groups.append([i, i, v])
    lines.append(" *   One count (the device file's counts_per_mps2, the nominal scale the calibration refines):")
    for a, b, v in groups:
        who = f"raw[{a}]" if a == b else f"raw[{a}..{b}]"
        lines.append(f" *     {who}: {v:.6g} counts per m/s^2: one count = {1.0 / v:.6g} m/s^2 = {1.0 / v / MG_MPS2:.6g} mg")
    mg = 1.0 / k / MG_MPS2
    per = f"{mg[0]:.6g} mg" if np.all(mg == mg[0]) else "its channel's mg per count"
    return lines + [f" *   Not mg, not m/s^2: a reading a driver gives in mg is divided by {per} first."]


def signed_recipe(p: str, n: int, resolve_call: str, rails, out: str) -> list[str]:
    """The header comment's per-sample recipe for a chip with signed readings: the pre-trim that
    flags the rails (ac_trim_rails_s16), then ``resolve_call``."""
    lo, hi = rail_counts(rails, True)
    return [f" *     int16_t x[{n}];   (raw: int16_t[{n}], the chip's signed readings)",
            f" *     ac_status s = ac_trim_rails_s16(raw, {p}_TRIM, {n}, {p}_RAW_MIN, {p}_RAW_MAX, x);",
            f" *     ac_status r = {resolve_call};",
            " *   s has the bit AC_AT_RAIL when a reading sits at the converter's rail",
            f" *   ({lo} or {hi}, {p}_RAW_MIN/_RAW_MAX): the chip clipped it, {out} is not a measurement;",
            " *   AC_SATURATED in s or r: a value was clipped to its range."]


def render_header(t: FixedTables, *, prefix: str = "AC_CAL", calibration_method: str = "",
                  temp_ref_c: float | None = None, offset_tc=None, gain_tc=None, warnings=(),
                  rounding_lsb=None, notes=(), counts_per_mps2=None) -> str:
    """The header text for tables t (see quantize.quantize); ``warnings`` (the calibration's,
    one line each) and ``notes`` go into its opening comment; ``rounding_lsb`` (linear (6,) LSB, centripetal
    (6,) LSB per (rad/s)^2: :func:`accelcal.firmware.quantize.resolver_rounding_bound`) the error bound
    it states; ``counts_per_mps2`` (N,) the device's nominal scale, for the size of one count
    (:func:`input_lines`)."""
    f = FORMATS
    p = _c_ident(prefix)
    guard = f"{p}_{_c_ident(t.device or 'DEVICE')}_H"
    n = t.n
    lines = [
        f"/* Generated by accelcal {__version__} -- do not edit.",
        f" * Device: {t.device}   channels: {n}" + (f"   calibration method: {calibration_method}"
                                                   if calibration_method else ""),
        " *",
        *warning_lines(warnings, notes),
        " * Use: in exactly one .c file",
        f" *     #define {p}_IMPLEMENTATION",
        " *     #include \"this header\"",
        " * then per sample:",
    ] + (signed_recipe(p, n, f"ac_resolve(&{p}_RESOLVER, x, omega_or_NULL, out)", t.rails, "out")
          if t.signed else [
        f" *     ac_process(&{p}_RESOLVER, {p}_TRIM, raw, omega_or_NULL, out);   (raw: uint16_t[{n}])",
        " *   its status has the bit AC_AT_RAIL when a reading sits at the converter's rail",
        f" *   ({t.rails[0]} or {t.rails[1]}, {p}_RESOLVER.raw_min/raw_max): the chip clipped it, out is not a measurement",
    ]) + [
        *input_lines(t.rails, t.signed, counts_per_mps2),
        " *",
        " * Fixed-point formats (fractional bits; the core refuses to build with others):",
        f" *   out[0..2] f   [m/s^2]   int32 Q.{f.out_frac}   (1 LSB = {2.0**-f.out_frac:.6g})",
        f" *   out[3..5] alpha [rad/s^2] int32 Q.{f.out_frac}",
        f" *   omega [rad/s] int16 Q.{f.omega_frac}   (1 LSB = {2.0**-f.omega_frac:.6g} rad/s)",
        f" *   {p}_TRIM: counts subtracted from raw readings ({'int16: the chip reads signed counts' if t.signed else 'uint16'})",
        f" *   {p}_RESOLVER.m[j][i] * 2^-(m_shift[j] + {f.out_frac}) = M[j][i] (output units per count)",
        f" *   {p}_RESOLVER.k[j]    * 2^-(m_shift[j] + {f.out_frac}) = (M o)[j] (output units)",
        f" *   {p}_RESOLVER.g[j][q] * 2^-(g_shift[j] + {f.out_frac}) = (M C)[j][q] (units per (rad/s)^2)",
        f" *   {p}_CHANNELS: s_i Q.{f.sens_frac} counts per m/s^2, r_i Q.{f.pos_frac} m,",
        f" *     b_i - trim_i Q.{f.offset_frac} counts (input to ac_resolver_build)",
        f" * 1-norm condition number of the inverted matrix: about 2^{t.cond_log2}.",
        *resolver_bound_lines(rounding_lsb),
        *_opening(guard, ("OUT", f.out_frac), ("OMEGA", f.omega_frac), ("SENS", f.sens_frac), ("POS", f.pos_frac),
                  ("OFFSET", f.offset_frac)),
        f"#if AC_MAX_CHANNELS < {n}",
        f"#error \"this calibration has {n} channels: build accelcal with AC_MAX_CHANNELS >= {n}\"",
        "#endif",
        "",
        f"#define {p}_N_CHANNELS {n}",
        *rail_macros(p, t.rails, t.signed),
        f"extern const {'int16_t' if t.signed else 'uint16_t'} {p}_TRIM[{n}];",
        f"extern const ac_resolver {p}_RESOLVER;",
        f"extern const ac_channel_cal {p}_CHANNELS[{n}];",
    ]
    has_temp = offset_tc is not None or gain_tc is not None
    if has_temp:
        lines += [
            "/* Temperature coefficients about the reference temperature:",
            f" * offset_i(T) = offset_i + {p}_OFFSET_TC[i] * 2^-16 * (T - T_ref)   [counts, T in degC]",
            f" * gain_i(T)   = gain_i * (1 + {p}_GAIN_TC[i] * 2^-30 * (T - T_ref)) */",
            f"#define {p}_TEMP_REF_CENTI_C {int(round((temp_ref_c or 0.0) * 100))}",
            f"extern const int32_t {p}_OFFSET_TC[{n}];",
            f"extern const int32_t {p}_GAIN_TC[{n}];",
        ]
    lines += ["", f"#ifdef {p}_IMPLEMENTATION",
              f"const {'int16_t' if t.signed else 'uint16_t'} {p}_TRIM[{n}] = {_row(t.trim)};",
              f"const ac_resolver {p}_RESOLVER = {{",
              f"    {n}u,",
              f"    {_row(t.m_shift)}, /* m_shift */",
              f"    {_row(t.g_shift)}, /* g_shift */",
              f"    {{{', '.join(f'{int(v)}L' for v in t.k)}}}, /* k */",
              "    { /* m[6][AC_MAX_CHANNELS] */"]
    lines += [f"        {_row(t.m[j])}," for j in range(6)]
    lines += ["    },", "    { /* g[6][6] */"]
    lines += [f"        {_row(t.g[j])}," for j in range(6)]
    lines += ["    },", f"    {int(t.rails[0])}u, {int(t.rails[1])}u /* raw_min, raw_max (codes) */",
              "};", f"const ac_channel_cal {p}_CHANNELS[{n}] = {{"]
    for i in range(n):
        lines.append(f"    {{{{{', '.join(f'{int(v)}L' for v in t.sens_q[i])}}}, "
                     f"{{{', '.join(f'{int(v)}L' for v in t.pos_q[i])}}}, {int(t.offset_q[i])}L}},")
    lines.append("};")
    if has_temp:
        otc = to_fixed(np.zeros(n) if offset_tc is None else offset_tc, 16, "offset_tc")
        gtc = to_fixed(np.zeros(n) if gain_tc is None else gain_tc, 30, "gain_tc")
        lines += [f"const int32_t {p}_OFFSET_TC[{n}] = {{{', '.join(f'{int(v)}L' for v in otc)}}};",
                  f"const int32_t {p}_GAIN_TC[{n}] = {{{', '.join(f'{int(v)}L' for v in gtc)}}};"]
    lines += [f"#endif /* {p}_IMPLEMENTATION */", "", f"#endif /* {guard} */", ""]
    return "\n".join(lines)


def render_triad_header(t: TriadTable, *, device: str, prefix: str = "AC_CAL", calibration_method: str = "",
                        warnings=(), rounding_lsb=None, notes=(), counts_per_mps2=None) -> str:
    """The header text for one 3-axis sensor's table (see estimators.triad.quantize_triad):
    f only, f = S^-1 (raw - b), by ``ac_triad_apply`` (uint16 readings) or ``ac_trim_s16``
    + ``ac_triad_resolve`` (int16 readings); ``warnings`` and ``notes`` (the calibration's) go into its
    opening comment; ``rounding_lsb`` ((3,) output LSB, :func:`accelcal.firmware.triad.triad_rounding_bound`)
    the table's rounding over every reading the trim does not clip, stated with the bound;
    ``counts_per_mps2`` (3,) the device's nominal scale, for the size of one count (:func:`input_lines`)."""
    f = FORMATS
    p = _c_ident(prefix)
    guard = f"{p}_{_c_ident(device or 'DEVICE')}_H"
    tt = "int16_t" if t.signed else "uint16_t"
    bound = (" *   |f - S^-1 (raw - b)| <= 0.5 LSB + the table's rounding, which is at most "
             + ", ".join(f"{v:.3g}" for v in rounding_lsb) + " LSB on f[0..2] for every reading the trim does not "
             f"clip ({float(np.max(rounding_lsb)) + 0.5:.3g} LSB = "
             f"{(float(np.max(rounding_lsb)) + 0.5) * 2.0 ** -f.out_frac:.3g} m/s^2 in all)"
             if rounding_lsb is not None else
             " *   |f - S^-1 (raw - b)| <= 0.5 LSB + the table's rounding (accelcal.firmware.triad.triad_exact: the exact semantics)")
    lines = [
        f"/* Generated by accelcal {__version__} -- do not edit.",
        f" * Device: {device}   a 3-axis sensor" + (f"   calibration method: {calibration_method}"
                                                    if calibration_method else ""),
        " *",
        *warning_lines(warnings, notes),
        " * Use: in exactly one .c file",
        f" *     #define {p}_IMPLEMENTATION",
        " *     #include \"this header\"",
        " * then per sample (f only: a single point sensor gives no alpha):",
    ]
    if t.signed:
        lines += signed_recipe(p, 3, f"ac_triad_resolve(&{p}_TRIAD, x, f)", t.rails, "f")
    else:
        lines += [f" *     ac_triad_apply(&{p}_TRIAD, raw, f);   (raw: uint16_t[3])",
                  " *   its status has the bit AC_AT_RAIL when a reading sits at the converter's rail",
                  f" *   ({t.rails[0]} or {t.rails[1]}, {p}_TRIAD.raw_min/raw_max): the chip clipped it, f is not a measurement"]
    lines += [
        *input_lines(t.rails, t.signed, counts_per_mps2),
        " *",
        " * Fixed-point formats (fractional bits; the core refuses to build with others):",
        f" *   f[0..2] [m/s^2] int32 Q.{f.out_frac}   (1 LSB = {2.0**-f.out_frac:.6g}), rounded half up",
        f" *   {p}_TRIM: counts subtracted from the raw readings ({tt})",
        f" *   {p}_TRIAD.m[j][i] * 2^-(shift[j] + {f.out_frac}) = (S^-1)[j][i] (m/s^2 per count)",
        f" *   {p}_TRIAD.k[j]    * 2^-(shift[j] + {f.out_frac}) = (S^-1 (b - trim))[j] (m/s^2)",
        bound,
    ]
    lines += [f" *   {p}_CHANNELS: s_i Q.{f.sens_frac} counts per m/s^2, b_i - trim_i Q.{f.offset_frac} counts: after a",
              f" *     field recalibration, ac_triad_build({p}_CHANNELS, {p}_TRIAD.trim, &work, &triad) remakes the table"]
    if t.signed:
        lines.append(f" *   {p}_TRIAD.trim holds TRIM + 32768 (offset binary): ac_triad_apply on raw + 32768 is the same")
    lines += [
        *_opening(guard, ("OUT", f.out_frac), ("SENS", f.sens_frac), ("OFFSET", f.offset_frac)),
        "",
        *rail_macros(p, t.rails, t.signed),
        f"extern const {tt} {p}_TRIM[3];",
        f"extern const ac_triad {p}_TRIAD;",
        f"extern const ac_channel_cal {p}_CHANNELS[3];",
        "",
        f"#ifdef {p}_IMPLEMENTATION",
        f"const {tt} {p}_TRIM[3] = {_row(t.trim)};",
        f"const ac_triad {p}_TRIAD = {{",
        f"    {_row(t.trim_code())}, /* trim (uint16 code) */",
        f"    {_row(t.shift)}, /* shift */",
        f"    {{{', '.join(f'{int(v)}L' for v in t.k)}}}, /* k */",
        f"    {{{_row(t.m[0])}, {_row(t.m[1])}, {_row(t.m[2])}}}, /* m */",
        f"    {int(t.rails[0])}u, {int(t.rails[1])}u /* raw_min, raw_max (codes) */",
        "};",
        f"const ac_channel_cal {p}_CHANNELS[3] = {{",
    ] + [f"    {{{{{', '.join(f'{int(v)}L' for v in t.sens_q[i])}}}, {{0L, 0L, 0L}}, {int(t.offset_q[i])}L}},"
         for i in range(3)] + [
        "};",
        f"#endif /* {p}_IMPLEMENTATION */",
        "",
        f"#endif /* {guard} */",
        "",
    ]
    return "\n".join(lines)


def calibration_header(device, cal, *, prefix: str = "AC_CAL") -> str:
    """The firmware header for a device and its calibration: the 6-DOF resolver's tables for
    an array (N >= 6), the triad table for a 3-axis sensor; uint16 or int16 (raw_min < 0)
    readings.  The calibration's warnings (``extra["warnings"]``), what its method did not fit
    (``extra["fit"]["not_fitted_note"]``) and the jig accuracy it estimated and used
    (``extra["fit"]["jig_accuracy_note"]``) go into the opening comment."""
    extra = cal.extra if isinstance(getattr(cal, "extra", None), dict) else {}
    warnings = extra.get("warnings", [])
    fit = extra.get("fit") if isinstance(extra.get("fit"), dict) else {}
    notes = [fit[k] for k in ("not_fitted_note", "jig_accuracy_note") if fit.get(k)]
    signed = device.raw_min < 0
    # the resolver's / triad's table as the terms hand it their output: in 2^-tt.frac counts (the same
    # matrix, each row's shift + frac) where tt.frac > 0, else the whole-count table; the rounding
    # bound stated is the whole-count table's
    t_out, tt = terms_tables(device, cal)
    if device.is_triad():
        t = quantize_triad(cal.offsets, cal.sensitivity, signed=signed, rails=(device.raw_min, device.raw_max)) \
            if tt.frac else t_out
        rounding = triad_rounding_bound(t, cal.offsets, cal.sensitivity, device.raw_min, device.raw_max)
        text = render_triad_header(t_out, device=device.name, prefix=prefix, calibration_method=cal.method,
                                   warnings=warnings, rounding_lsb=rounding, notes=notes,
                                   counts_per_mps2=device.counts_per_mps2)
        call = f"ac_triad_resolve(&{_c_ident(prefix)}_TRIAD, x, f)"
    else:
        t = quantize_calibration(device, cal) if tt.frac else t_out
        pos = cal.positions_or_nominal(device)
        rounding = resolver_rounding_bound(t, cal.offsets, cal.sensitivity, pos, device.raw_min, device.raw_max)
        text = render_header(t_out, prefix=prefix, calibration_method=cal.method,
                             temp_ref_c=getattr(cal, "temp_ref_c", None), offset_tc=getattr(cal, "offset_tc", None),
                             gain_tc=getattr(cal, "gain_tc", None), warnings=warnings, rounding_lsb=rounding,
                             notes=notes, counts_per_mps2=device.counts_per_mps2)
        call = f"ac_resolve(&{_c_ident(prefix)}_RESOLVER, x, omega_or_NULL, out)"
        omega = device_omega_table(device, cal)
        if omega is not None:
            text = insert_omega(text, _c_ident(prefix), omega)
    if not tt.any():
        return text
    trim = np.asarray(t.trim, np.int64)
    span = float(np.max(np.maximum(np.abs(device.raw_max - trim), np.abs(device.raw_min - trim))))
    p = _c_ident(prefix)
    return insert_terms(text, p, terms_header_parts(tt, p, min(span, 32767.0), signed, call))
