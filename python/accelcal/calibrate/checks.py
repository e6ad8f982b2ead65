"""Checks and small helpers every static fit shares: pose-mean shapes, the design of
one channel, whether a pose set determines a method, the jig accuracy in radians,
the Birge ratio, and the nominal starting forces."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..io.device import NOMINAL_FACTOR
from ..errors import InputError
from ..readings.static import PoseSet
from .settings import (TEMP_UNDETERMINED_G, TEMP_UNDETERMINED_GAIN, CANDIDATES, CHIP_GAIN_TOLERANCE, EXCITATION_MIN_SPAN_G, POORLY_DETERMINED_MG, SCATTER_CHI2,
                       TILTED, TILTED_AFTER_DEG)


def as_means(device, means, what="means") -> np.ndarray:
    m = np.asarray(means, float)
    if m.ndim != 2 or m.shape[1] != device.n_channels:
        raise InputError("<arrays>", f"expected shape (P, {device.n_channels}), got {m.shape}", field=what)
    bad = np.argwhere(~np.isfinite(m))
    if bad.size:
        p, c = bad[0]
        raise InputError("<arrays>", f"not finite: {m[p, c]}", field=f"{what}[{p}][{c}]")
    return m


def design(method: str, device, i: int, F: np.ndarray) -> np.ndarray:
    """Per-channel regressors for pose forces F (P,3): offset [1]; gain [1, u.f]; full [1, f]."""
    one = np.ones((F.shape[0], 1))
    if method == "offset":
        return one
    if method == "gain":
        return np.hstack([one, (F @ device.axes[i])[:, None]])
    return np.hstack([one, F])


def pose_label(info: list[dict] | None, p: int) -> str:
    if info and p < len(info) and info[p].get("label") is not None:
        return f"pose {info[p]['label']}"
    return f"pose {p}"


def check_identifiable(device, method: str, F: np.ndarray, min_rcond: float) -> None:
    """Raise InputError (which pose to add) when the known poses cannot determine
    every free parameter of every channel."""
    g = device.gravity_mps2
    P = F.shape[0]
    if P == 0:
        raise InputError("<poses>", "no static pose to calibrate from")

    def rcond(Fs: np.ndarray, i: int) -> float:
        A = design(method, device, i, Fs / g)
        sv = np.linalg.svd(A, compute_uv=False)
        q = A.shape[1]
        return 0.0 if len(sv) < q else float(sv[-1] / sv[0])

    def best_candidate(i: int) -> str:
        best, name = -1.0, ""
        for nm, d in CANDIDATES:
            r = rcond(np.vstack([F, g * np.asarray(d)]), i)
            if r > best + 1e-9:
                best, name = r, nm
        return name

    channels = range(device.n_channels) if method == "gain" else [0]
    for i in channels:
        if rcond(F, i) >= min_rcond:
            continue
        add = best_candidate(i)
        if method == "gain":
            x = F @ device.axes[i] / g
            raise InputError("<poses>", f"the poses do not determine channel {i}'s gain: every pose gives it "
                             f"u.f = {np.mean(x):+.2f} g along its axis (spread {np.ptp(x):.3f} g); add a pose with "
                             f"f along {add} (body {add} axis up)", field=f"channels[{i}]")
        if P < 4:
            what = f"only {P} pose{'s' if P != 1 else ''}"
        elif np.max(np.linalg.norm(F - F.mean(0), axis=1)) < 0.05 * g:
            fm = F.mean(0) / g
            what = f"all {P} poses have about the same f = [{fm[0]:+.2f}, {fm[1]:+.2f}, {fm[2]:+.2f}] g"
        else:
            A = design("full", device, 0, F / g)
            v = np.linalg.svd(A)[2][-1]
            nrm = v[1:] / np.linalg.norm(v[1:])
            c = -v[0] / np.linalg.norm(v[1:])
            what = (f"all {P} pose forces lie in one plane (n.f = {c:+.2f} g, n = "
                    f"[{nrm[0]:+.2f}, {nrm[1]:+.2f}, {nrm[2]:+.2f}])")
        raise InputError("<poses>", f"the poses do not determine the offset and sensitivity vector of channel {i} "
                         f"(nor of any channel): {what}; 'full' needs f along 4 directions not in one plane: add a "
                         f"pose with f along {add} (body {add} axis up)", field="poses")


#: the largest jig accuracy a known-pose fit takes (its priors are small-angle ones)
MAX_JIG_ACCURACY_DEG = 20.0


def jig_accuracy_rad(jig_accuracy_deg: Any) -> float:
    """Validate a stated jig accuracy (degrees, finite, >= 0) and return it in radians."""
    try:
        v = float(jig_accuracy_deg)
    except (TypeError, ValueError):
        v = float("nan")
    if not (math.isfinite(v) and v >= 0.0):
        raise InputError("<arguments>", f"jig accuracy must be a finite angle >= 0 degrees, got {jig_accuracy_deg!r}",
                         field="jig_accuracy_deg")
    if v > MAX_JIG_ACCURACY_DEG:
        raise InputError("<arguments>", f"jig accuracy {v:g} deg: the poses' priors are small-angle ones (a "
                         f"tangent-plane deviation), good to about {MAX_JIG_ACCURACY_DEG:g} deg; poses that far off "
                         "are not a jig's: calibrate with --method jigfree", field="jig_accuracy_deg")
    return math.radians(v)


def birge_ratio(chi2: float, dof: int) -> float:
    return max(1.0, chi2 / dof) if dof > 0 else 1.0


def bare_poses(m: np.ndarray, F: np.ndarray | None = None) -> PoseSet:
    P, N = m.shape
    return PoseSet(means=m, n=np.ones(P, dtype=np.int64), std=np.zeros((P, N)),
                   f_ref=np.full((P, 3), np.nan) if F is None else F, temp=np.full(P, np.nan),
                   info=[{"label": None} for _ in range(P)])


def min_poses(device, method: str, temp: bool) -> int:
    """Fewest poses a jig-free fit can be determined from.

    The readings m_p = b + S f_p fix (b, S, f_p) only up to f -> A f + c,
    S -> S A^-1, b -> b - S A^-1 c; |f_p| = g must rule out every such map except
    rotations (full) or the identity (gain, offset).  Each pose gives one equation
    on (A, c), so P >= the dimension of the admissible maps: 9 for full (12 affine
    minus 3 rotations, imu_tk's "at least 9"), 3 + dim{A : A^T u_i || u_i} for gain,
    3 for offset.  Also P N readings >= the number of unknowns (temperature terms)."""
    N = device.n_channels
    if method == "full":
        amb = 9
    elif method == "gain":
        # A^T u_i must stay parallel to u_i: (I - u u^T) M u = 0 for M = A^T
        rows = []
        for u in device.axes:
            Pp = np.eye(3) - np.outer(u, u)
            rows.append(np.kron(Pp, u[None, :]))       # vec(M) row-major: (Pp M u)_a = sum Pp_ab M_bc u_c
        K = np.vstack(rows)
        amb = 3 + (9 - int(np.linalg.matrix_rank(K, tol=1e-9)))
    else:
        amb = 3
    q = {"offset": 1, "gain": 2, "full": 4}[method] + (2 if temp else 0)
    gauge = 3 if method == "full" else 0
    count = int(math.ceil((q * N - gauge) / (N - 2))) if N > 2 else 10 ** 9
    return max(amb, count)


def missing_direction(device, F: np.ndarray) -> str:
    """The body axis direction (of +-x, +-y, +-z) farthest from every pose; where every
    axis direction has a pose within TILTED_AFTER_DEG, the farthest tilted one (a cube's
    edge or corner: six faces alone do not determine a jig-free fit)."""
    fh = F / np.linalg.norm(F, axis=1, keepdims=True)

    def farthest(options) -> tuple[float, str]:
        best, name = -2.0, ""
        for nm, d in options:
            score = -float(np.max(fh @ np.asarray(d)))
            if score > best + 1e-9:
                best, name = score, nm
        return best, name

    score, name = farthest(CANDIDATES)
    if -score > math.cos(math.radians(TILTED_AFTER_DEG)):
        name = farthest(TILTED)[1]
    return name


def initial_forces(device, m: np.ndarray) -> np.ndarray:
    """Pose forces from the nominal model, scaled to |f| = g."""
    S = device.nominal_sensitivity()
    F = np.linalg.lstsq(S, (m - device.nominal_offsets()[None, :]).T, rcond=None)[0].T
    n = np.linalg.norm(F, axis=1, keepdims=True)
    n[n == 0] = 1.0
    return device.gravity_mps2 * F / n


def static_force(offsets, sensitivity, means, sigma=None) -> np.ndarray:
    """Specific force (P,3) of each static pose from its mean readings by (weighted)
    least squares f = argmin sum_i ((m_i - b_i - s_i.f)/sigma_i)^2."""
    m = np.atleast_2d(np.asarray(means, float)) - np.asarray(offsets, float)[None, :]
    S = np.asarray(sensitivity, float)
    if sigma is None:
        return np.linalg.lstsq(S, m.T, rcond=None)[0].T
    w = 1.0 / np.atleast_2d(np.asarray(sigma, float))
    out = np.empty((m.shape[0], 3))
    for p in range(m.shape[0]):
        out[p] = np.linalg.lstsq(S * w[p][:, None], m[p] * w[p], rcond=None)[0]
    return out


def far_from_nominal(device, sensitivity, gain_sig=None) -> str | None:
    """A warning when a fitted sensitivity |s_i| (counts per m/s^2) is more than
    NOMINAL_FACTOR above or below the device file's ``counts_per_mps2`` (a wrong device
    file, full scale or LSB); else when a gain |s_i| / k_i - 1 is beyond CHIP_GAIN_TOLERANCE
    by more than 3 of its relative 1-sigma ``gain_sig`` (N,) (none given: 0), beyond any
    chip's datasheet tolerance (a gain 14 % low had passed unsaid); else None."""
    got = np.linalg.norm(np.asarray(sensitivity, float), axis=1)
    nominal = np.asarray(device.counts_per_mps2, float)
    ratio = got / nominal
    off = np.flatnonzero((ratio > NOMINAL_FACTOR) | (ratio < 1.0 / NOMINAL_FACTOR))
    if off.size:
        i = int(off[np.argmax(np.abs(np.log(ratio[off])))])
        return (f"channel {i}'s sensitivity, {got[i]:.4g} counts per m/s^2, is {ratio[i]:.3g} x the device file's "
                f"{nominal[i]:.4g} ({off.size} of {ratio.size} channels beyond {NOMINAL_FACTOR:g} x either way): a "
                "real chip is within a few %; check the device file and the recording's scale (--full-scale, --lsb)")
    sig = np.zeros(ratio.size) if gain_sig is None else np.nan_to_num(np.asarray(gain_sig, float), nan=np.inf)
    gain = ratio - 1.0
    off = np.flatnonzero(np.abs(gain) - 3.0 * sig > CHIP_GAIN_TOLERANCE)
    if not off.size:
        return None
    i = int(off[np.argmax(np.abs(gain[off]))])
    return (f"channel {i}'s gain is {100 * gain[i]:+.3g} % from the device file's {nominal[i]:.4g} counts per m/s^2"
            + (f" (1-sigma {100 * sig[i]:.2g} %)" if gain_sig is not None else "")
            + f" ({off.size} of {ratio.size} channels): beyond a chip's datasheet tolerance "
            f"(+-{100 * CHIP_GAIN_TOLERANCE:g} % for the loosest, +-3 % for an MPU-6050); check the device file's "
            "counts_per_mps2 (the range, --full-scale or --lsb of the conversion; a ratiometric sensor's supply) "
            "or the chip")


def gain_sigma(sensitivity, sensitivity_sigma) -> np.ndarray:
    """(N,) relative 1-sigma of each channel's gain |s_i| (a fraction), from the 1-sigma of
    the components of s_i (counts per m/s^2; their correlations are not kept, and the
    component along s_i dominates)."""
    s = np.asarray(sensitivity, float)
    n = np.linalg.norm(s, axis=1)
    # a component held at 0 (no sigma: NaN) adds nothing to |s_i|
    part = np.where(s != 0.0, np.asarray(sensitivity_sigma, float) * s / n[:, None], 0.0)
    return np.sqrt(np.sum(part ** 2, axis=1)) / n


def poorly_determined(device, F, offset_sigma=None, gain_sig=None, n_samples=None,
                      chi2_dof=None, held_s=None) -> str | None:
    """A warning naming the channels whose fitted offset or gain is poorly determined, with
    the likely causes and what to add, else None.

    A channel is named when its offset's 1-sigma, or its gain's relative 1-sigma times 1 g,
    exceeds POORLY_DETERMINED_MG (mg; settings: why 5 mg), whatever the poses' span (an
    Empatica E4's 26 wrist poses: offsets +-19 and +-24 mg, gains +-2 %, every axis turned
    through 1 g or more).  Without sigmas, a channel the poses turn through less than
    EXCITATION_MIN_SPAN_G of f is named (its offset trades against its gain).  The causes
    given: poses that hardly turn the axis (f along it spans less than EXCITATION_MIN_SPAN_G,
    or no pose within TILTED_AFTER_DEG of +u_i or -u_i: a real LSM303 session kept f along x
    within +-0.29 g, x offset +-114 counts, 28 mg), a coarse LSB (one count beyond
    POORLY_DETERMINED_MG: a pose's mean rests on a few codes), the poses' number and
    length (the sigmas fall as 1/sqrt of both where the noise dithers the codes), and their
    scatter about the fit beyond SCATTER_CHI2 (the sigmas are then scaled up by
    sqrt(chi2/dof): the scatter's, which longer poses do not shrink).

    Parameters
    ----------
    device : Device
    F : array_like (P, 3)
        The poses' specific force, m/s^2 (references or jig-free estimates).
    offset_sigma : array_like (N,), optional
        The fitted offsets' 1-sigma, counts.
    gain_sig : array_like (N,), optional
        The fitted gains' relative 1-sigma (a fraction; :func:`gain_sigma`).
    n_samples : array_like (P,), optional
        Samples a pose, to quote.
    chi2_dof : float, optional
        The fit's chi2/dof, to name as a cause above SCATTER_CHI2.
    held_s : array_like (P,), optional
        How long each pose was held, s, to quote (else n_samples at the device's rate).

    Returns
    -------
    str or None
    """
    F = np.asarray(F, float)
    if F.ndim != 2 or F.shape[0] == 0:
        return None
    g = device.gravity_mps2
    k = np.asarray(device.counts_per_mps2, float)
    N = device.n_channels
    proj = F @ device.axes.T / g                     # (P, N), in g
    span = proj.max(axis=0) - proj.min(axis=0)
    low = span < EXCITATION_MIN_SPAN_G
    off_mg = np.full(N, np.nan) if offset_sigma is None else 1000.0 * np.asarray(offset_sigma, float) / (k * g)
    gain_pc = np.full(N, np.nan) if gain_sig is None else 100.0 * np.asarray(gain_sig, float)
    if offset_sigma is not None or gain_sig is not None:
        # 1 % of gain is 10 mg in a reading of 1 g
        bad = (off_mg > POORLY_DETERMINED_MG) | (10.0 * gain_pc > POORLY_DETERMINED_MG)
    else:
        bad = low
    bad = np.flatnonzero(bad)
    if not bad.size:
        return None
    fh = F / np.linalg.norm(F, axis=1, keepdims=True)
    near = math.cos(math.radians(TILTED_AFTER_DEG))
    parts, turn, add = [], [], []
    for i in bad:
        part = f"channel {i}'s f along its axis spans {proj[:, i].min():+.2f}..{proj[:, i].max():+.2f} g"
        if np.isfinite(off_mg[i]):
            part += f", offset +-{offset_sigma[i]:.3g} counts ({off_mg[i]:.2g} mg)"
        if np.isfinite(gain_pc[i]) and gain_pc[i] > 0:
            part += f", gain +-{gain_pc[i]:.2g} %"
        parts.append(part)
        missing = [axis_name(device.axes[i], sgn) for sgn in (+1, -1)
                   if not np.max(fh @ (sgn * device.axes[i])) >= near]
        if low[i] or missing:
            turn.append(f"channel {i}: " + (f"no pose within {TILTED_AFTER_DEG:g} deg of {' or '.join(missing)}"
                                            if missing else f"f spans {span[i]:.2f} g"))
            add += [d for d in missing if d not in add]
    causes = []
    if turn:
        causes.append(f"poses that hardly turn an axis ({'; '.join(turn)})")
    lsb = 1000.0 / (k[bad] * g)
    if np.any(lsb > POORLY_DETERMINED_MG):
        causes.append(f"a coarse LSB (1 count = {np.max(lsb):.3g} mg: a pose's mean rests on a few codes)")
    one_row = n_samples is not None and len(n_samples) > 0 and bool(np.all(np.asarray(n_samples) == 1))
    if n_samples is not None and len(n_samples):
        n_med = float(np.median(n_samples))
        t_med = n_med / device.sample_rate_hz if held_s is None else float(np.median(held_s))
        if one_row:
            # a file of pose means (its t counts rows): no durations, and each mean's noise unknown
            causes.append(f"few poses ({F.shape[0]} poses, one row each: a table of pose means, whose noise is "
                          "unknown)")
        else:
            causes.append(f"few or short poses ({F.shape[0]} poses, a median {n_med:.0f} samples, "
                          f"{t_med:.3g} s, each)")
    scatter = chi2_dof is not None and chi2_dof > SCATTER_CHI2
    if scatter:
        causes.insert(0, f"the poses' scatter about the fit (chi2/dof {chi2_dof:.3g} scales the sigmas up "
                         f"{math.sqrt(chi2_dof):.3g} x: its cause above)")
    dirs = " and ".join(add) if len(add) < 3 else ", ".join(add[:-1]) + " and " + add[-1]
    want = "add poses" + (f" with f along {dirs}" if add else " in more orientations")
    if not scatter and not one_row and (n_samples is not None or np.any(lsb > POORLY_DETERMINED_MG)):
        want += " and hold each longer (the sigmas fall as 1/sqrt of the poses and of their samples)"
    if offset_sigma is None and gain_sig is None:
        head = f"the poses hardly turn {bad.size} channel(s)"
    else:
        head = (f"the calibration is poorly determined on {bad.size} channel(s): an offset 1-sigma beyond "
                f"{POORLY_DETERMINED_MG:g} mg or a gain 1-sigma beyond {POORLY_DETERMINED_MG / 10:g} % "
                f"({POORLY_DETERMINED_MG:g} mg at 1 g), where a calibration should beat the chip's untrimmed "
                "tolerance (tens of mg, a few %) tenfold")
    return (f"{head} ({'; '.join(parts)}; +-x, +-y, +-z span 2 g); likely causes: "
            f"{'; '.join(causes) if causes else 'the poses'}; {want}")


def axis_name(u, sign: int) -> str:
    """"+x", "-y"... for a unit vector along a body axis, else the vector itself."""
    u = sign * np.asarray(u, float)
    j = int(np.argmax(np.abs(u)))
    if abs(u[j]) > 0.99:
        return f"{'+' if u[j] > 0 else '-'}{'xyz'[j]}"
    return "(" + ", ".join(f"{v + 0.0:.2f}" for v in np.round(u, 2)) + ")"


def undetermined_tempcos(device, fit, temps) -> str | None:
    """The reason the temperature coefficients of ``fit`` (a StaticFit with ``offset_tc_sigma``,
    ``gain_tc_sigma``) are not pinned by the poses, or None.  A channel's offset tempco is
    undetermined when its 1-sigma times the poses' temperature span (degC) exceeds
    TEMP_UNDETERMINED_G of the channel's 1 g (the device file's counts per m/s^2 times g, counts);
    its gain tempco when that product exceeds TEMP_UNDETERMINED_GAIN (a fraction of the gain)."""
    if getattr(fit, "offset_tc", None) is None:
        return None
    span = float(np.ptp(np.asarray(temps, float)))
    one_g = np.abs(np.asarray(device.counts_per_mps2, float)) * float(device.gravity_mps2)
    so = np.nan_to_num(np.asarray(fit.offset_tc_sigma, float), nan=np.inf) * span
    sg = np.nan_to_num(np.asarray(fit.gain_tc_sigma, float), nan=np.inf) * span
    bad = [f"channel {i}'s offset tempco +-{fit.offset_tc_sigma[i]:.3g} counts/degC ({so[i] / one_g[i]:.3g} g "
           f"over the {span:.3g} degC span)" for i in np.flatnonzero(so > TEMP_UNDETERMINED_G * one_g)]
    bad += [f"channel {i}'s gain tempco +-{fit.gain_tc_sigma[i] * 1e6:.3g} ppm/degC ({sg[i] * 100:.3g} % of the "
            f"gain over the {span:.3g} degC span)" for i in np.flatnonzero(sg > TEMP_UNDETERMINED_GAIN)]
    if not bad:
        return None
    return ("temperature coefficients not fitted: the poses do not determine them (1-sigma " + "; ".join(bad)
            + f": beyond {TEMP_UNDETERMINED_G:g} g or {TEMP_UNDETERMINED_GAIN:.0%} of the gain across the span); "
            "the calibration is the fit without them. Vary the temperature more between poses of the same "
            "orientation, or add poses")
