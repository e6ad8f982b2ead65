"""The correctable terms' part of a generated header: the ac_temp / ac_skew / ac_nonlin tables
(firmware.terms_fixed.quantize_terms, the same tables ``resolve --engine fixed`` runs), the
per-sample recipe and the error bounds for this calibration."""
from __future__ import annotations

import numpy as np

from .terms_fixed import TEMP_FRAC, TermsTables, lag_bound, nonlin_bound, temp_bound

#: the temperature span the header's stated bounds assume about t_ref (degC)
BOUND_SPAN_C = 40.0


def _row(values) -> str:
    return "{" + ", ".join(str(int(v)) for v in values) + "}"


def terms_header_parts(tt: TermsTables, prefix: str, reading_span: float, signed: bool,
                       resolve_call: str) -> tuple[list[str], list[str]]:
    """(declarations, definitions) for a header with prefix ``prefix`` (already a C identifier);
    ``reading_span`` the largest |raw - trim| (counts) the bounds are stated for, ``resolve_call``
    what follows the terms (ac_resolve or ac_triad_resolve on x)."""
    p, n = prefix, tt.n
    trim_call = (f"ac_trim_rails_s16(raw, {p}_TRIM, {n}, {p}_RAW_MIN, {p}_RAW_MAX, x)" if signed
                 else f"ac_trim_rails(raw, {p}_TRIM, {n}, {p}_RAW_MIN, {p}_RAW_MAX, x)")
    com = ["/* Correctable terms (docs/firmware-terms.md): made for a sample period of "
           f"{tt.dt_s:.9g} s ({1.0 / tt.dt_s:.6g} Hz).",
           " * Once:"]
    if tt.temp is not None:
        com += [" *     ac_temp_lag lag_off, lag_gain;",
                f" *     ac_temp_lag_init(&lag_off, {p}_TEMP_OFF_LAG_K, {p}_TEMP_OFF_LAG_SHIFT);",
                f" *     ac_temp_lag_init(&lag_gain, {p}_TEMP_GAIN_LAG_K, {p}_TEMP_GAIN_LAG_SHIFT);"]
    if tt.skew is not None:
        com += [f" *     static int16_t line_buf[{p}_SKEW_LEN * {n}];  ac_skew_line line;",
                f" *     ac_skew_init(&line, &{p}_SKEW, line_buf, {p}_SKEW_LEN * {n});"]
    com += [" * Per sample (x: int16_t[%d]; the status bits of each call or-ed together):" % n,
            f" *     {trim_call};"]
    if tt.temp is not None:
        com += [" *     ac_temp_lag_step(&lag_off, temp, &t_off);  ac_temp_lag_step(&lag_gain, temp, &t_gain);",
                f" *     ac_temp_correct(&{p}_TEMP, t_off, t_gain, x, x);",
                f" *   temp: the sensor's temperature in degC * {2 ** TEMP_FRAC} (int16 Q.{TEMP_FRAC}), "
                "t_off, t_gain: int16_t"]
    if tt.skew is not None:
        com += [f" *     ac_skew_step(&{p}_SKEW, &line, x, x);",
                f" *   the outputs are for the instant {p}_SKEW_LATENCY = {tt.latency()} sample(s) before the newest"]
    if tt.nonlin is not None:
        com += [f" *     ac_nonlin_invert(&{p}_NONLIN, x, x);"]
    com += [f" *     {resolve_call};"]
    kf = int(tt.frac)
    if kf:
        table = "TRIAD" if resolve_call.startswith("ac_triad") else "RESOLVER"
        com += [f" * ac_temp_correct writes x in 2^-{kf} counts ({p}_TERMS_FRAC = {kf}: a fraction of a count,",
                " * not rint(raw + c(T)), reaches the resolver); the skew and the nonlinearity keep that unit",
                f" * and {p}_{table} is made for it (each row's shift + {kf}): use it after the terms as above,",
                " * not on whole counts (ac_process / ac_triad_apply); an on-device rebuild (ac_resolver_build /",
                f" * ac_triad_build) makes a whole-count table (add {p}_TERMS_FRAC to its shifts, which must stay <= 31,",
                f" * and multiply its k by 2^{p}_TERMS_FRAC yourself)."]
    com += [" * Error bounds of the terms against their float reference, in counts of x:"]
    z = float(reading_span)
    if tt.temp is not None:
        gc = tt.temp_coefficients()[2]
        e = float(np.max(np.abs(gc))) * BOUND_SPAN_C
        for name, (k, s), tau in (("offset", tt.temp["lag_off"], tt.temp["tau_off"]),
                                  ("gain", tt.temp["lag_gain"], tt.temp["tau_gain"])):
            lb = lag_bound(k, s, tau, tt.dt_s, BOUND_SPAN_C)
            com.append(f" *   lagged temperature ({name}): <= {lb:.3g} degC over a {BOUND_SPAN_C:g} degC span")
        com.append(f" *   ac_temp_correct: <= {float(temp_bound(z, e, kf)):.3g} for |x| <= {z:.0f} and |T_s - t_ref| <= "
                   f"{BOUND_SPAN_C:g} degC (gain change up to {100 * e:.3g} %)")
    if tt.skew is not None:
        com.append(f" *   ac_skew_step: <= {2.0 ** -(kf + 1):g} (+ 2^-16 |x[n-k-1] - x[n-k]| for the delay's rounding)")
    if tt.nonlin is not None:
        c2, c3 = tt.nonlin_coefficients()
        k = int(tt.nonlin["iterations"])
        zq = z * 2.0 ** kf
        nb = float(np.max(nonlin_bound(zq, c2, c3, tt.nonlin["shift"], k, kf))) * 2.0 ** -kf
        L = float(np.max(2 * np.abs(c2) * zq + 3 * np.abs(c3) * zq * zq))
        com.append(f" *   ac_nonlin_invert ({k} iterations): <= {nb:.3g} for |x| <= {z:.0f} (contraction L = {L:.3g}: "
                   f"the float iteration is within L^{k} = {L ** k:.3g} of the term it removes of the exact inverse)")
    com[-1] += " */"
    dec, dfn = list(com), []
    dec += [f"#define {p}_TERMS_FRAC {kf}"]
    if tt.temp is not None:
        t = tt.temp
        dec += [f"#define {p}_TEMP_OFF_LAG_K {int(t['lag_off'][0])}u",
                f"#define {p}_TEMP_OFF_LAG_SHIFT {int(t['lag_off'][1])}u",
                f"#define {p}_TEMP_GAIN_LAG_K {int(t['lag_gain'][0])}u",
                f"#define {p}_TEMP_GAIN_LAG_SHIFT {int(t['lag_gain'][1])}u",
                f"extern const ac_temp_table {p}_TEMP;"]
        dfn += [f"const ac_temp_table {p}_TEMP = {{",
                f"    {n}u, {int(t['t_ref'])}, /* n, t_ref */",
                f"    {_row(t['oc'])}, /* oc */", f"    {_row(t['gc'])}, /* gc */", f"    {_row(t['o'])}, /* o */",
                f"    {int(t['frac'])}u /* frac: x out in 2^-frac counts */", "};"]
    if tt.skew is not None:
        s = tt.skew
        dec += [f"#define {p}_SKEW_LEN {int(s['len'])}", f"#define {p}_SKEW_LATENCY {int(s['latency'])}",
                f"extern const ac_skew_table {p}_SKEW;"]
        dfn += [f"const ac_skew_table {p}_SKEW = {{", f"    {n}u, {int(s['len'])}u, /* n, len */",
                f"    {_row(s['whole'])}, /* whole */", f"    {{{', '.join(f'{int(v)}u' for v in s['frac'])}}} /* frac */",
                "};"]
    if tt.nonlin is not None:
        nl = tt.nonlin
        dec += [f"extern const ac_nonlin_table {p}_NONLIN;"]
        dfn += [f"const ac_nonlin_table {p}_NONLIN = {{", f"    {n}u, {int(nl['shift'])}, /* n, shift */",
                f"    {_row(nl['a2'])}, /* a2 */", f"    {_row(nl['a3'])}, /* a3 */",
                f"    {int(nl['iterations'])}u /* iterations */", "};"]
    return dec, dfn


def insert_terms(text: str, prefix: str, parts: tuple[list[str], list[str]]) -> str:
    """The header ``text`` with the terms' declarations before its implementation block and
    their definitions at the end of it."""
    dec, dfn = parts
    opening = f"#ifdef {prefix}_IMPLEMENTATION"
    closing = f"#endif /* {prefix}_IMPLEMENTATION */"
    text = text.replace(opening, "\n".join(dec) + "\n\n" + opening, 1)
    return text.replace(closing, "\n".join(dfn) + "\n" + closing, 1)
