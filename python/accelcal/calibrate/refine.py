"""``refine``: a calibration refitted with the terms a diagnosis's model says the firmware can
correct (docs/refine.md).

The model of a reading is the effect registry's own (accelcal.effects): the calibration's
channel state (offsets b, sensitivity vectors s, positions r; sensor.evaluate), each channel
read at t + tau_i (``time_skew``), the offset and the gain changing with the lagged temperature
(``temperature_offset``, ``temperature_gain``), the reading bending by k2 a^2 + k3 a^3
(``nonlinearity``).  Every parameter of the calibration and of the terms is fitted jointly by
``scipy.optimize.least_squares`` on the recordings' reference samples (the jig's stated f at
the poses, the reference motion), weighted by each channel's noise; 1-sigma from the Jacobian
at the solution (scaled by the reduced chi2 where it exceeds 1).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares
from scipy.sparse import coo_matrix

from ..effects.nonlinearity import Nonlinearity
from ..effects.temperature import TemperatureGain, TemperatureOffset
from ..effects.timing import TimeSkew
from ..errors import AccelcalError
from ..firmware.header import calibration_header
from ..firmware.terms import has_terms
from ..io.calibration import Calibration, load_calibration, save_calibration
from ..io.device import Device, default_device, load_device
from ..io.recording import Recording, read_recording
from ..sensor import ChannelState, Context, calibration_arrays, evaluate
from .refine_pinned import TERM_GROUPS, covariance, describe, drop, unpinned
from .refine_input import ADDED, EXISTING, NOT_CORRECTABLE, Rows, read_diagnosis, reference_rows, start_value

#: longest thermal lag fitted, in spans of the recordings' duration
MAX_LAG_SPANS = 4.0
#: the thermal lag's start where neither the calibration nor the diagnosis gives one (s; at most a
#: quarter of the recordings' span): from 0 the fit stays at the bound, the lag's slope there being ~0
LAG_START_S = 60.0


class Truth:
    """The reference as sensor.evaluate reads it: t, f, omega, alpha, temp_c, and ``sample``
    (the reference at other times, by a cubic spline within each run of reference samples)."""

    def __init__(self, rows: Rows):
        self.t, self.f, self.omega, self.alpha, self.temp_c = rows.t, rows.f, rows.w, rows.dw, rows.temp
        have = np.all(np.isfinite(rows.f), axis=1)
        edges = np.flatnonzero(np.diff(np.r_[0, have.astype(int), 0]))
        self.runs = []
        y = np.concatenate([rows.f, rows.w, rows.dw], axis=1)
        for lo, hi in zip(edges[::2], edges[1::2]):
            sp = CubicSpline(rows.t[lo:hi], y[lo:hi], axis=0) if hi - lo >= 4 else None
            self.runs.append((lo, hi, sp))

    def sample(self, times):
        out = np.full((times.size, 9), np.nan)
        for lo, hi, sp in self.runs:
            tt = np.clip(times[lo:hi], self.t[lo], self.t[hi - 1])
            out[lo:hi] = sp(tt) if sp is not None else np.column_stack(
                [np.interp(tt, self.t[lo:hi], self.f[lo:hi, k]) for k in range(3)]
                + [self.omega[lo:hi], self.alpha[lo:hi]])
        return out[:, :3], out[:, 3:6], out[:, 6:]


@dataclass
class Layout:
    """Where each parameter sits in the least-squares vector."""

    N: int
    groups: dict = field(default_factory=dict)   # name -> (slice, shape)
    per_channel: dict = field(default_factory=dict)   # name -> channels the group's values belong to
    size: int = 0

    def add(self, name, shape, channels=None):
        k = int(np.prod(shape))
        self.groups[name] = (slice(self.size, self.size + k), shape)
        self.per_channel[name] = channels
        self.size += k

    def get(self, x, name, default=None):
        if name not in self.groups:
            return default
        sl, shape = self.groups[name]
        return x[sl].reshape(shape)


class Model:
    """The recordings' readings as a function of the parameter vector (the effects' forward models)."""

    def __init__(self, device, rows: Rows, terms: set, cube: np.ndarray, fit_r: bool, t_ref: float | None,
                 lags: dict):
        self.device, self.rows, self.terms, self.cube, self.fit_r, self.t_ref = device, rows, terms, cube, fit_r, t_ref
        self.lags = lags   # tau_off / tau_gain -> None (fitted) or the fixed value (s)
        self.truth = Truth(rows)
        N = rows.raw.shape[1]
        L = Layout(N)
        L.add("b", (N,))
        L.add("s", (N, 3))
        if fit_r:
            L.add("r", (N, 3))
        if "nonlinearity" in terms:
            L.add("k2", (N,))
            if np.any(cube):
                L.add("k3", (int(cube.sum()),), np.flatnonzero(cube))
        if "temperature_offset" in terms:
            L.add("oc", (N,))
            if lags.get("tau_off") is None:
                L.add("tau_off", (1,), "all")
        if "temperature_gain" in terms:
            L.add("gc", (N,))
            if lags.get("tau_gain") is None:
                L.add("tau_gain", (1,), "all")
        if "time_skew" in terms:
            L.add("skew", (N,))
        self.L = L
        self.r0 = None

    def params(self, x):
        L, N = self.L, self.L.N
        k3 = np.zeros(N)
        if "k3" in L.groups:
            k3[self.cube] = L.get(x, "k3")
        return {"b": L.get(x, "b"), "s": L.get(x, "s"), "r": L.get(x, "r", self.r0),
                "k2": L.get(x, "k2", np.zeros(N)), "k3": k3, "oc": L.get(x, "oc"), "gc": L.get(x, "gc"),
                "tau_off": float(L.get(x, "tau_off", [self.lags.get("tau_off") or 0.0])[0]),
                "tau_gain": float(L.get(x, "tau_gain", [self.lags.get("tau_gain") or 0.0])[0]),
                "skew": L.get(x, "skew", np.zeros(N))}

    def predict(self, x) -> np.ndarray:
        """(n, N) the noise-free readings (counts) of the parameters ``x``."""
        p = self.params(x)
        state = ChannelState.from_parameters(p["b"], p["s"], p["r"])
        ctx = Context(device=self.device, truth=self.truth, state=state, counts=None)
        if "time_skew" in self.terms:
            state = TimeSkew().modify_state(state, {"tau": p["skew"]}, ctx)
        if p["oc"] is not None:
            state = TemperatureOffset().modify_state(state, {"coeff": p["oc"], "t_ref": self.t_ref,
                                                             "tau_s": p["tau_off"]}, ctx)
        if p["gc"] is not None:
            state = TemperatureGain().modify_state(state, {"coeff": p["gc"], "t_ref": self.t_ref,
                                                           "tau_s": p["tau_gain"]}, ctx)
        counts = evaluate(self.truth, state)
        if "nonlinearity" in self.terms:
            counts = Nonlinearity().apply_signal(counts, {"k2": p["k2"], "k3": p["k3"]}, ctx.replace(state=state))
        return counts

    def sparsity(self, n_rows: int):
        """Which residuals each parameter moves: a channel's parameters its own channel's only."""
        L, N = self.L, self.L.N
        ri, ci = [], []
        base = np.arange(n_rows) * N
        for name, (sl, shape) in L.groups.items():
            chans = L.per_channel[name]
            cols = np.arange(sl.start, sl.stop)
            if isinstance(chans, str):
                ri.append(np.arange(n_rows * N))
                ci.append(np.full(n_rows * N, cols[0]))
                continue
            chans = np.arange(N) if chans is None else np.asarray(chans)
            per = cols.size // chans.size
            for j, i in enumerate(chans):
                for c in cols[j * per:(j + 1) * per]:
                    ri.append(base + i)
                    ci.append(np.full(n_rows, c))
        ri, ci = np.concatenate(ri), np.concatenate(ci)
        return coo_matrix((np.ones(ri.size, np.int8), (ri, ci)), shape=(n_rows * N, L.size)).tocsr()


def channel_noise(rows: Rows) -> np.ndarray:
    """(N,) counts: each channel's white noise from the fourth differences of its readings inside
    runs of scored samples (1.4826 MAD / sqrt(70)), at least the rounding's 1/sqrt(12)."""
    u = rows.use
    ok = u[:-4] & u[1:-3] & u[2:-2] & u[3:-1] & u[4:]
    r = rows.raw
    d = r[:-4] - 4 * r[1:-3] + 6 * r[2:-2] - 4 * r[3:-1] + r[4:]
    d = d[ok]
    if d.shape[0] < 10:
        return np.full(r.shape[1], 1.0)
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    return np.maximum(1.4826 * mad / np.sqrt(70.0), 1.0 / np.sqrt(12.0))


@dataclass
class Fit:
    x: np.ndarray
    sigma: np.ndarray
    chi2: float
    dof: int


def fit(model: Model, x0, lo, hi, mask, noise, free=None) -> Fit:
    """least_squares of the weighted residual on the samples ``mask`` over the parameters ``free``
    (all by default; the others stay at ``x0``); 1-sigma from the Jacobian (infinite where it does
    not determine a parameter: refine_pinned.covariance; 0 for a fixed one)."""
    raw = model.rows.raw[mask]
    free = np.ones(x0.size, bool) if free is None else free

    def resid(xf):
        x = x0.copy()
        x[free] = xf
        return ((model.predict(x)[mask] - raw) / noise).ravel()

    res = least_squares(resid, x0[free], bounds=(lo[free], hi[free]),
                        jac_sparsity=model.sparsity(int(mask.sum()))[:, free], x_scale="jac", method="trf",
                        max_nfev=60)
    chi2 = float(2.0 * res.cost)
    dof = max(res.fun.size - int(free.sum()), 1)
    x, sigma = x0.copy(), np.zeros(x0.size)
    x[free] = res.x
    sigma[free] = np.sqrt(np.maximum(np.diag(covariance(res.jac, max(1.0, chi2 / dof))), 0.0))
    return Fit(x, sigma, chi2, dof)


@dataclass
class RefineResult:
    """What :func:`refine_calibration` found.

    Attributes
    ----------
    calibration : Calibration
        The refined calibration (the given one's fields refitted, the added terms set).
    added : dict
        Each added term's name -> {parameter: (N,) values}, and ``sigma`` -> their 1-sigma.
    not_added : dict
        Each model effect not added -> the reason.
    heldout_rms_before, heldout_rms_after : float
        RMS (counts) of the readings minus the prediction on the held-out half (alternate 2 s
        blocks of the reference samples): the given calibration, and the refined model fitted on
        the other half.
    noise_counts : float
        The channels' RMS white noise (counts), for scale.
    paragraph : str
        The summary ``accelcal refine`` prints.
    """

    calibration: Calibration
    added: dict
    not_added: dict
    heldout_rms_before: float
    heldout_rms_after: float
    noise_counts: float
    paragraph: str = ""


class NothingToCorrect(AccelcalError):
    """The diagnosis's model holds no effect a calibration term takes out."""


def _start(model: Model, cal: Calibration, device, diag):
    """Start values and bounds of the parameter vector."""
    L, N = model.L, model.L.N
    b, s, r = calibration_arrays(device, cal)
    x0, lo, hi = np.zeros(L.size), np.full(L.size, -np.inf), np.full(L.size, np.inf)
    span = float(np.ptp(model.rows.t[model.rows.use])) if model.rows.use.any() else 1.0
    lags = {"tau_off": ("temperature_offset", cal.temp_offset_tau_s), "tau_gain": ("temperature_gain", cal.temp_gain_tau_s)}
    vals = {"b": b, "s": s, "r": r,
            "k2": cal.nonlin_k2 if cal.nonlin_k2 is not None else start_value(diag.params, "nonlinearity", "k2", N),
            "k3": (cal.nonlin_k3 if cal.nonlin_k3 is not None else start_value(diag.params, "nonlinearity", "k3", N)),
            "oc": cal.offset_tc if cal.offset_tc is not None else start_value(diag.params, "temperature_offset", "coeff", N),
            "gc": cal.gain_tc if cal.gain_tc is not None else start_value(diag.params, "temperature_gain", "coeff", N),
            "skew": cal.time_skew_s if cal.time_skew_s is not None else start_value(diag.params, "time_skew", "tau", N)}
    for name, (sl, shape) in L.groups.items():
        if name in lags:
            eff, given = lags[name]
            v = given or float(diag.params.get(eff, {}).get("tau_s") or 0.0) or min(LAG_START_S, 0.25 * span)
            x0[sl] = min(max(v, 0.0), MAX_LAG_SPANS * span)
            lo[sl], hi[sl] = 0.0, MAX_LAG_SPANS * span
            continue
        v = np.nan_to_num(np.asarray(vals[name], float))
        if name == "k3":
            v = v[model.cube]
        x0[sl] = v.reshape(-1)
    if "skew" in L.groups:
        h = 1.0 / float(device.sample_rate_hz)
        lo[L.groups["skew"][0]], hi[L.groups["skew"][0]] = -4.0 * h, 4.0 * h
        x0[L.groups["skew"][0]] = np.clip(x0[L.groups["skew"][0]], -3.9 * h, 3.9 * h)
    return x0, lo, hi


def _gap(model: Model, x, mask) -> float:
    return float(np.sqrt(np.mean((model.rows.raw[mask] - model.predict(x)[mask]) ** 2)))


def _given_x(model: Model, cal, device, diag):
    """The parameter vector of the given calibration (its terms where it has them, else none)."""
    x0, _, _ = _start(model, cal, device, diag)
    L = model.L
    for name in ("k2", "k3", "oc", "gc", "skew", "tau_off", "tau_gain"):
        if name in L.groups:
            src = {"k2": cal.nonlin_k2, "k3": cal.nonlin_k3, "oc": cal.offset_tc, "gc": cal.gain_tc,
                   "skew": cal.time_skew_s, "tau_off": cal.temp_offset_tau_s, "tau_gain": cal.temp_gain_tau_s}[name]
            sl = L.groups[name][0]
            if src is None:
                x0[sl] = 0.0
            else:
                v = np.nan_to_num(np.atleast_1d(np.asarray(src, float)))
                x0[sl] = v[model.cube] if name == "k3" else v
    return x0


def refine_calibration(device, calibration: Calibration, diagnosis, recordings) -> RefineResult:
    """The calibration refitted on ``recordings`` with the terms of ``diagnosis``'s model that the
    firmware can correct (module doc).  Raises NothingToCorrect (nothing correctable) or
    InputError (bad input: the file and the field)."""
    diag = read_diagnosis(diagnosis, device)
    cal = calibration
    not_added = {e: NOT_CORRECTABLE[e] for e in diag.effects if e in NOT_CORRECTABLE}
    if diag.unexplained:
        not_added["unexplained"] = "no effect of the table explains it: no term to add"
    added = [e for e in ADDED if e in diag.effects]
    existing = [e for e in diag.effects if e in EXISTING]
    if not added and not existing:
        raise NothingToCorrect("nothing to correct: the diagnosis's model holds no effect a calibration term takes out"
                               + ("" if not not_added else " (" + "; ".join(f"{k}: {v}" for k, v in not_added.items())
                                  + ")"))
    carried = has_terms(cal)
    held = {"temperature_offset" if carried["temperature"] and cal.offset_tc is not None else None,
            "temperature_gain" if carried["temperature"] and cal.gain_tc is not None else None,
            "nonlinearity" if carried["nonlinearity"] else None,
            "time_skew" if carried["skew"] else None} - {None}
    terms = set(added) | held
    # the thermal lag of each temperature term in the model is fitted (a calibration's tempcos from
    # calibrate have none: the lag the diagnosis then sees as a gain or an offset is fitted here)
    lags = {"tau_off": None, "tau_gain": None}
    rows = reference_rows(recordings, device, bool(terms & {"temperature_offset", "temperature_gain"}))
    off_origin = bool(np.any(np.abs(np.asarray(device.positions, float)) > 0))
    moving = rows.use & ((np.linalg.norm(rows.w, axis=1) > 0.2) | (np.linalg.norm(rows.dw, axis=1) > 2.0))
    fit_r = off_origin and int(moving.sum()) >= 20
    s_norm = np.linalg.norm(np.asarray(cal.sensitivity, float), axis=1)
    _, _, r_cal = calibration_arrays(device, cal)
    x_in = np.einsum("nk,ik->ni", rows.f[rows.use], np.asarray(cal.sensitivity, float)) / s_norm
    cube = Nonlinearity.cube_told(x_in) if "nonlinearity" in terms else np.zeros(device.n_channels, bool)
    t_ref = cal.temp_ref_c if cal.temp_ref_c is not None else (
        float(np.mean(rows.temp[rows.use])) if rows.temp is not None else None)
    model = Model(device, rows, terms, cube, fit_r, t_ref, lags)
    model.r0 = r_cal
    noise = channel_noise(rows)
    x0, lo, hi = _start(model, cal, device, diag)
    ids = np.unique(rows.block, return_inverse=True)[1]
    train, test = rows.use & (ids % 2 == 0), rows.use & (ids % 2 == 1)
    given = _given_x(model, cal, device, diag)
    before = _gap(model, given, test)
    free, dropped = np.ones(x0.size, bool), {}
    whole = fit(model, x0, lo, hi, rows.use, noise)
    for _ in range(3):      # what the recordings do not pin is fixed, and the rest refitted
        unpin = unpinned(model, whole.x, whole.sigma, free)
        if not unpin:
            break
        for name, (bad, reasons) in unpin.items():
            old = dropped.get(name, (np.zeros(bad.size, bool), reasons))
            dropped[name] = (old[0] | bad, [r if b else o for r, o, b in zip(reasons, old[1], bad)])
        free, x0 = drop(model, unpin, free, x0, given)
        whole = fit(model, x0, lo, hi, rows.use, noise, free)
    half = fit(model, x0, lo, hi, train, noise, free)
    after = _gap(model, half.x, test)
    out, values = _calibration(model, whole, cal, device, free)
    added = [e for e in added if e in values]
    for e in ADDED:
        if e in diag.effects and e not in values:
            not_added[e] = "the recordings do not determine it, below"
    text = paragraph({k: v for k, v in values.items() if k in added}, {k: v for k, v in values.items() if k not in added},
                     not_added, existing, before, after, float(np.sqrt(np.mean(noise ** 2))), model.fit_r)
    text += describe(model, dropped)
    if dropped:
        out.extra["fit"]["refine_not_determined"] = {TERM_GROUPS[k][1]: [int(c) for c in np.flatnonzero(b)]
                                                     for k, (b, _) in dropped.items()}
    try:
        calibration_header(device, out)
    except AccelcalError as e:    # a term beyond the firmware's fixed formats: said, the file still written
        text += f" Warning: the firmware header cannot hold this calibration ({e})."
    return RefineResult(out, values, not_added, before, after, float(np.sqrt(np.mean(noise ** 2))), text)


def _calibration(model: Model, res: Fit, cal: Calibration, device, free=None):
    """The refined Calibration and the added terms' values with 1-sigma: an entry not fitted
    (``free`` False: not determined, refine_pinned) shows as NaN and keeps the calibration's own
    value, else none; a term none of whose entries was fitted is left as the calibration had it."""
    p = model.params(res.x)
    sd = model.params(res.sigma)
    L = model.L
    free = np.ones(res.x.size, bool) if free is None else free
    fitted = model.params(free.astype(float))

    def shown(name, v):
        f = fitted[name]
        return np.where(np.asarray(f, float) > 0, v, np.nan) if f is not None else v

    def any_fitted(*names):
        return any(n in L.groups and free[L.groups[n][0]].any() for n in names)

    kw = dict(offsets=p["b"], sensitivity=p["s"], offset_sigma=sd["b"], sensitivity_sigma=sd["s"],
              method=cal.method if cal.method.endswith("+refine") else f"{cal.method}+refine")
    if model.fit_r:
        kw.update(positions=p["r"], position_sigma=sd["r"])
    vals = {}
    if "nonlinearity" in model.terms and any_fitted("k2", "k3"):
        cube = model.cube & (fitted["k3"] > 0)
        kw.update(nonlin_k2=p["k2"], nonlin_k3=p["k3"])
        vals["nonlinearity"] = {"k2": shown("k2", p["k2"]), "k3": np.where(cube, p["k3"], np.nan),
                                "sigma": {"k2": sd["k2"], "k3": np.where(cube, sd["k3"], np.nan)}}
    if "temperature_offset" in model.terms and any_fitted("oc"):
        kw.update(offset_tc=p["oc"], temp_offset_tau_s=p["tau_off"], temp_ref_c=model.t_ref)
        vals["temperature_offset"] = {"coeff": shown("oc", p["oc"]), "tau_s": p["tau_off"],
                                      "sigma": {"coeff": sd["oc"], "tau_s": sd["tau_off"]}}
    if "temperature_gain" in model.terms and any_fitted("gc"):
        kw.update(gain_tc=p["gc"], temp_gain_tau_s=p["tau_gain"], temp_ref_c=model.t_ref)
        vals["temperature_gain"] = {"coeff": shown("gc", p["gc"]), "tau_s": p["tau_gain"],
                                    "sigma": {"coeff": sd["gc"], "tau_s": sd["tau_gain"]}}
    if "time_skew" in model.terms and any_fitted("skew"):
        kw.update(time_skew_s=p["skew"])
        vals["time_skew"] = {"tau": shown("skew", p["skew"]), "sigma": {"tau": sd["skew"]}}
    extra = dict(cal.extra or {})
    fitx = dict(extra.get("fit") or {})
    fitx.update(refine_chi2=res.chi2, refine_dof=res.dof, refine_terms=sorted(vals))
    extra["fit"] = fitx
    kw["extra"] = extra
    return dataclasses.replace(cal, **kw), vals


UNITS = {"k2": ("counts/(m/s^2)^2", 1.0), "k3": ("counts/(m/s^2)^3", 1.0), "coeff_off": ("counts/degC", 1.0),
         "coeff_gain": ("ppm/degC", 1e6), "tau_s": ("s", 1.0), "tau": ("ms", 1e3)}


def _fmt(v, s, scale):
    return ", ".join("-" if not np.isfinite(a) else f"{a * scale:+.4g} +- {b * scale:.2g}" for a, b in zip(v, s))


def paragraph(values, kept, not_added, existing, before, after, noise, lever_arms=False) -> str:
    """The one paragraph ``accelcal refine`` prints on success."""
    parts = []
    for name, v in values.items():
        sg = v["sigma"]
        if name == "nonlinearity":
            parts.append(f"nonlinearity k2 [{_fmt(v['k2'], sg['k2'], 1)}] counts/(m/s^2)^2, "
                         f"k3 [{_fmt(v['k3'], sg['k3'], 1)}] counts/(m/s^2)^3")
        elif name == "time_skew":
            parts.append(f"time skew [{_fmt(v['tau'], sg['tau'], 1e3)}] ms")
        else:
            unit, scale = ("counts/degC", 1.0) if name == "temperature_offset" else ("ppm/degC", 1e6)
            parts.append(f"{name.replace('_', ' ')} [{_fmt(v['coeff'], sg['coeff'], scale)}] {unit} with lag "
                         f"{v['tau_s']:.4g} +- {sg['tau_s']:.2g} s")
    text = ("Refined: " + ("; ".join(parts) if parts else "no term added") + ", fitted jointly with the offsets, "
            "sensitivity vectors" + (" and lever arms" if existing and "position_error" in existing else "")
            + (f" (the model's {', '.join(existing)} refitted)" if existing else "")
            + (f" and the calibration's own {', '.join(k.replace('_', ' ') for k in kept)}" if kept else "")
            + f". Held-out gap (alternate 2 s blocks of the reference samples; fitted on the others): "
            f"{before:.3g} counts RMS with the given calibration, {after:.3g} after (noise {noise:.3g}).")
    if not_added:
        text += " Not added: " + "; ".join(f"{k} ({v})" for k, v in not_added.items()) + "."
    return text


def refine(device, calibration, diagnosis, recordings, *, output=None) -> RefineResult:
    """Refit a calibration with the diagnosed effects the firmware can correct (as ``accelcal refine``).

    Parameters
    ----------
    device : Device, path or "default"
        The device (its JSON, or "default": the seed prototype).
    calibration : Calibration or path
        The calibration to refine.
    diagnosis : dict or path
        What :func:`accelcal.diagnose` returned, or its JSON file: its ``model.effects`` and
        ``model.params`` (docs/diagnosis-json.md) must be for ``device``.
    recordings : Recording, path or a sequence of them
        Recordings with a reference: the jig's stated f at the poses, a reference motion (f, w,
        dw); ``temp_c`` on every sample for the temperature terms.
    output : path, optional
        Also write the refined calibration there (atomically; nothing on an error).

    Returns
    -------
    RefineResult
        ``calibration`` (offsets, sensitivity vectors and lever arms refitted; the added terms'
        fields ``nonlin_k2``, ``nonlin_k3`` in counts per (m/s^2)^2 and ^3, ``offset_tc`` in
        counts per degC, ``gain_tc`` per degC, ``temp_offset_tau_s``, ``temp_gain_tau_s`` and
        ``time_skew_s`` in s), ``added`` (values and 1-sigma), ``not_added`` (effect -> reason),
        ``heldout_rms_before`` / ``heldout_rms_after`` (counts), ``paragraph``.

    Raises
    ------
    AccelcalError
        Bad input (one line naming the file and field); ``NothingToCorrect`` (an AccelcalError)
        when the diagnosis's model holds nothing a calibration term takes out.
    """
    dev = default_device() if device is None or (isinstance(device, str) and device == "default") else (
        device if isinstance(device, Device) else load_device(device))
    cal = calibration if isinstance(calibration, Calibration) else load_calibration(calibration, dev)
    recs = recordings if isinstance(recordings, (list, tuple)) else [recordings]
    recs = [r if isinstance(r, Recording) else read_recording(r, dev.n_channels) for r in recs]
    res = refine_calibration(dev, cal, diagnosis, recs)
    if output is not None:
        save_calibration(res.calibration, output)
    return res
