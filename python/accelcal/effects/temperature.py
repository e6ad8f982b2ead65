"""Temperature: offset and gain linear in the sensor's temperature, which may follow the
recorded one through a first-order thermal lag."""
from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.signal import lfilter

from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_list, channel_mask, per_channel, strongest, temperature_of
from .fitdata import FitData, t_ref_known, temp_skip
from .fitting import Cand, Candidate, jig_rows, joint_stats, sep_stats, solve_groups
from .session import per_recording_columns
from .settings import (PENALTY_PER_PARAM, T_LAG_BISECT, T_LAG_CRIT_CHI2, T_LAG_GRID_S, T_LAG_INSIDE, T_LAG_INSIDE_FREE,
                       T_LAG_MAX_SPANS,
                       T_REF_SPANS)


def lagged(T: np.ndarray, t: np.ndarray, tau_s: float, runs: np.ndarray | None = None) -> np.ndarray:
    """The sensor's temperature: the recorded ``T`` (degC) through a first-order lag of time
    constant ``tau_s`` (s), started at the recorded value, per run of samples ``runs``
    (labels; default one run).  ``t`` (s) may have gaps (the samples a diagnosis leaves
    out, such as the motion between static poses): within a stretch of regular spacing
    the filter runs at that spacing; across a gap of length d the state relaxes towards
    the mean of the temperatures on either side by exp(-d / tau_s), so that the lag is
    the same in seconds with or without the samples in between.  ``tau_s`` = 0: T."""
    T = np.asarray(T, float)
    if tau_s <= 0.0 or T.size < 2:
        return T
    t = np.asarray(t, float)
    out = np.empty_like(T)
    runs = np.zeros(T.size, np.int64) if runs is None else np.asarray(runs)
    for r in np.unique(runs):
        idx = np.flatnonzero(runs == r)
        if idx.size < 2:
            out[idx] = T[idx]
            continue
        dt = np.diff(t[idx])
        h = float(np.median(dt))
        # stretches of regular spacing: a step over 1.5 sample spacings is a gap
        cut = np.flatnonzero(dt > 1.5 * h) + 1
        a = math.exp(-h / tau_s)
        y = T[idx[0]]
        for lo, hi in zip(np.r_[0, cut], np.r_[cut, idx.size]):
            piece = idx[lo:hi]
            if lo > 0:  # across the gap from the previous stretch's last sample
                x_gap = 0.5 * (T[idx[lo - 1]] + T[piece[0]])
                y = x_gap + (y - x_gap) * math.exp(-float(dt[lo - 1]) / tau_s)
            out[piece[0]] = y
            if piece.size > 1:
                out[piece[1:]] = lfilter([1.0 - a], [1.0, -a], T[piece[1:]], zi=[a * y])[0]
            y = float(out[piece[-1]])
    return out


class TemperatureFit(Candidate):
    """c_i (T - t_ref) z_i with z = 1 (offset) or the sensed reading (gain); t_ref shared."""

    gain = False
    bench_key = "coeff"  # the benchmark compares the coefficients

    def bench_spec(self, m, z, aux):
        return {"coeff": as_list(m * z)}

    def skip(self, D):
        return temp_skip(D)

    def _z(self, D):
        return D.sensed if self.gain else np.ones((D.n, D.N))

    def _profile(self, D, G2, h2, T, fixed):
        """The all-data fit's objective (-h' theta; lower is better) at the best reference
        temperature of a coarse grid (or the calibration's)."""
        N = D.N
        Tlo, Thi = float(T.min()), float(T.max())
        span = max(Thi - Tlo, 1e-9)
        grid = [fixed] if fixed is not None else np.linspace(Tlo - T_REF_SPANS * span, Thi + T_REF_SPANS * span, 41)
        vals = []
        for tr in grid:
            v = np.array([1.0, -tr])
            if D.Qp is None:
                G = np.einsum("...kl,k,l->...", G2, v, v)[..., None, None]
                hh = np.einsum("...k,k->...", h2, v)[..., None]
            else:
                Vm = np.zeros((2 * N, N))
                for i in range(N):
                    Vm[2 * i:2 * i + 2, i] = v
                G = np.einsum("...ab,ai,bj->...ij", G2, Vm, Vm)
                hh = np.einsum("...a,ai->...i", h2, Vm)
            th = solve_groups(G, hh)[0]
            vals.append(-float(np.einsum("gk,gk->", th, hh)))
        return min(vals)

    def _stats(self, D, y, z, T):
        # columns T z and z: c (T - t_ref) z = c (X2 . [1, -t_ref])
        X2 = np.stack([T[:, None] * z, z], axis=2)
        if D.Qp is None:
            return sep_stats(D, X2, y)
        return joint_stats(D, jig_rows(D, X2), D.rows(y))

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        z = self._z(D)
        fixed = t_ref_known(D)
        N = D.N
        # the thermal lag: the all-data best of T_LAG_GRID_S (a lag must beat none by more than its
        # parameter's penalty); lags up to twice the span of the data used
        span_s = float(np.ptp(D.tg)) if D.n else 0.0
        def lag_fit(tau):
            T = lagged(D.temp, D.tg, tau, D.rec)
            st = self._stats(D, y, z, T)
            return float(self._profile(D, st[0].sum(0), st[1].sum(0), T, fixed)) + (PENALTY_PER_PARAM if tau else 0.0), \
                tau, T, st

        grid = [x for x in T_LAG_GRID_S if x <= T_LAG_MAX_SPANS * span_s]
        fits = [lag_fit(tau) for tau in grid]
        j = int(np.argmin([f[0] for f in fits]))
        best = fits[j]
        if best[1] > 0:
            # refine between the neighbouring grid lags (in log tau)
            lo = grid[j - 1] if grid[j - 1] > 0 else 0.5 * grid[j]
            hi = grid[j + 1] if j + 1 < len(grid) else min(2.0 * grid[j], T_LAG_MAX_SPANS * span_s)
            res = minimize_scalar(lambda u: lag_fit(math.exp(u))[0], bounds=(math.log(lo), math.log(hi)),
                                  method="bounded", options={"xatol": 0.02})
            if res.fun < best[0]:
                best = lag_fit(math.exp(res.x))
        shape = None
        if best[1] > 0:
            if levels_apart(D):
                shape = self._lag_interval(D, self._level_free(D, y, z), best, S0w, T_LAG_INSIDE_FREE)
            else:
                # the fit's own profile: the grid's fits and the best one are already at hand
                known = {f[1]: f[0] - (PENALTY_PER_PARAM if f[1] else 0.0) for f in fits + [best]}
                shape = self._lag_interval(D, lambda tau: lag_fit(tau)[0] - (PENALTY_PER_PARAM if tau else 0.0),
                                           best, S0w, T_LAG_INSIDE, known)
        if shape is not None and not shape["determined"]:
            shaped = self._finish(D, best, S0w, S0u, z, fixed)
            out = self._finish(D, lag_fit(0.0), S0w, S0u, z, fixed)
            shaped.shape = {"tau_s": shape}
            out.shape = {"tau_s": dict(shape, used=0.0)}
            out.shaped = shaped
            out.notes = list(out.notes) + [
                f"the thermal lag is not determined by these data (best {shape['value']:.3g} s, interval "
                f"{_interval(shape)} against the longest recording's {shape['span_s']:.3g} s): fitted without a lag "
                "(the nested form); the lagged form is reported only as an alternative"]
            return out
        out = self._finish(D, best, S0w, S0u, z, fixed)
        if shape is not None:
            out.shape = {"tau_s": shape}
        return out

    def _level_free(self, D, y, z):
        """The profile objective of the lag (lower is better) with each recording's own level of the
        change (``z``: an offset, or a gain, per recording and channel; :func:`per_recording_columns`)
        beside the lagged temperature: what the lag explains *within* the recordings.  A shift between
        recordings reads as a lag far beyond their length (the lagged temperature then stays near its
        first value), so judged on the levels alone a long lag would be pinned by what a shift explains
        as well; beside free levels only the shape of the change within each recording pins it."""
        cols = per_recording_columns(D, z)

        def objective(tau):
            T = lagged(D.temp, D.tg, tau, D.rec)
            X = np.concatenate([(T[:, None] * z)[:, :, None], cols], axis=2)
            st = sep_stats(D, X, y) if D.Qp is None else joint_stats(D, jig_rows(D, X), D.rows(y))
            G, h = st[0].sum(0), st[1].sum(0)
            th = solve_groups(G, h)[0]
            return -float(np.einsum("gk,gk->", th, h))
        return objective

    def _lag_interval(self, D, objective, best, S0w, inside: float, known: dict | None = None) -> dict:
        """The lags whose profile objective (``objective``: beside each recording's own level,
        :meth:`_level_free`, where two recordings or more have samples; else the fit's own) lies within
        T_LAG_CRIT_CHI2 (x the residual's excess over the floor and the poses' design effect) of its
        best: the interval's ends found in steps of 2 from the fitted lag (``best``'s) and refined by
        bisection (0 where no lag fits as well, inf where none up to the first step beyond
        T_LAG_MAX_SPANS x the recording does worse), and whether that pins the lag: the fitted lag lies
        inside the interval, which excludes 0 and ends within ``inside`` x the longest recording
        (:func:`recording_span`).  ``known``: {lag: objective} already computed (not computed again)."""
        tau0 = float(best[1])
        span = recording_span(D)
        probe = [tau0] + [x for x in T_LAG_GRID_S if 0.0 < x <= T_LAG_MAX_SPANS * max(span, 1e-9)]
        vals = dict(known or {})
        vals.update({tau: objective(tau) for tau in probe if tau not in vals})
        obj0 = min(vals[tau] for tau in probe)
        rows = max(D.n * D.R, 1)
        s2 = max(1.0, float(S0w.sum() + obj0) / rows)
        crit = T_LAG_CRIT_CHI2 * s2 * float(getattr(D, "deff", 1.0) or 1.0)

        def worse(tau):
            return (vals[tau] if tau in vals else objective(tau)) - obj0 > crit

        if worse(tau0):
            # beside the recordings' own levels another lag fits clearly better: the fitted one is
            # set by the levels between the recordings, not by the change within them
            return {"value": tau0, "interval_s": [0.0, math.inf], "determined": False, "span_s": span,
                    "crit_chi2": crit, "within": False}

        def crossing(ok, bad):
            # the interval's end between a lag that fits as well (ok) and one that does worse (bad), by
            # bisection in log tau to a ratio of 2^(1/16) (the steps of 2 alone had overstated the interval
            # by up to 2x: a lag of 77 s in a 158 s recording read as "up to 263 s", past the recording)
            for _ in range(T_LAG_BISECT):
                mid = math.sqrt(ok * bad)
                if worse(mid):
                    bad = mid
                else:
                    ok = mid
            return bad

        # upwards in steps of 2 up to the first lag beyond T_LAG_MAX_SPANS x the recording (no crossing
        # there: the interval runs beyond what the recording can pin, reported as inf)
        hi = math.inf
        tau = tau0
        while tau <= T_LAG_MAX_SPANS * span:
            tau *= 2.0
            if worse(tau):
                hi = crossing(tau / 2.0, tau)
                break
        lo = 0.0
        if worse(0.0):
            tau = tau0
            while tau > 0.05 * tau0:
                tau /= 2.0
                lo = tau
                if worse(tau):
                    lo = crossing(2.0 * tau, tau)
                    break
        determined = bool(lo > 0.0 and hi <= inside * span)
        return {"value": tau0, "interval_s": [lo, hi], "determined": determined, "span_s": span,
                "crit_chi2": crit, "within": True}

    def _finish(self, D, best, S0w, S0u, z, fixed):
        """The candidate at the lag of ``best`` (lag_fit's tuple): the reference temperature per
        fold, the held-out scores, the all-data fit."""
        N = D.N
        _, tau, T, (Gw2, hw2, Gu2, hu2) = best
        Tlo, Thi = float(T.min()), float(T.max())
        span = max(Thi - Tlo, 1e-9)

        def reduce(G2, h2, tr):
            v = np.array([1.0, -tr])
            if D.Qp is None:
                return (np.einsum("...kl,k,l->...", G2, v, v)[..., None, None],
                        np.einsum("...k,k->...", h2, v)[..., None])
            P = N
            Vm = np.zeros((2 * P, P))
            for i in range(P):
                Vm[2 * i:2 * i + 2, i] = v
            return (np.einsum("...ab,ai,bj->...ij", G2, Vm, Vm), np.einsum("...a,ai->...i", h2, Vm))

        def objective(G2, h2, tr):
            G, hh = reduce(G2, h2, tr)
            th = solve_groups(G, hh)[0]
            return -float(np.einsum("gk,gk->", th, hh))         # S = q - h' th at the optimum

        def best_tref(G2, h2):
            if fixed is not None:
                return fixed
            # within two spans of the data: further out, c (T - t_ref) is an offset change in disguise
            grid = np.linspace(Tlo - T_REF_SPANS * span, Thi + T_REF_SPANS * span, 41)
            vals = [objective(G2, h2, tr) for tr in grid]
            j = int(np.argmin(vals))
            lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
            res = minimize_scalar(lambda tr: objective(G2, h2, tr), bounds=(lo, hi), method="bounded",
                                  options={"xatol": 1e-3 * span})
            return float(res.x) if res.fun <= vals[j] else float(grid[j])

        K, bf = D.K, D.bfold
        Gt2, ht2 = Gw2.sum(0), hw2.sum(0)
        Sw = np.empty(D.B)
        Su = np.empty(D.B)
        for f in range(K):
            m = bf == f
            Gtr, htr = Gt2 - Gw2[m].sum(0), ht2 - hw2[m].sum(0)
            tr = best_tref(Gtr, htr)
            G, hh = reduce(Gtr, htr, tr)
            th = solve_groups(G, hh)[0]
            Gb, hb = reduce(Gw2[m], hw2[m], tr)
            Gub, hub = reduce(Gu2[m], hu2[m], tr)
            Sw[m] = S0w[m] - 2 * np.einsum("gk,bgk->b", th, hb) + np.einsum("gk,bgkl,gl->b", th, Gb, th)
            Su[m] = S0u[m] - 2 * np.einsum("gk,bgk->b", th, hub) + np.einsum("gk,bgkl,gl->b", th, Gub, th)
        tr = best_tref(Gt2, ht2)
        G, hh = reduce(Gt2, ht2, tr)
        th, Ginv, rank = solve_groups(G, hh)
        Sall = float(S0w.sum() - np.einsum("gk,gk->", th, hh))
        npar = int(rank.sum()) + (0 if fixed is not None else 1) + (1 if tau else 0)
        scale = max(1.0, Sall / max(D.n * D.R - npar, 1))
        if D.Qp is None:
            coeff = th[:, 0]
            sd = np.sqrt(np.maximum(Ginv[:, 0, 0] * scale, 0.0))
        else:
            coeff = th[0]
            sd = np.sqrt(np.maximum(np.diag(Ginv[0]) * scale, 0.0))
        delta = coeff[None, :] * (T - tr)[:, None] * z
        params = {"coeff": coeff, "t_ref": tr, "tau_s": float(tau)}
        sigma = {"coeff": sd, "t_ref": 0.0 if fixed is not None else math.nan, "tau_s": 0.0}
        notes = [] if fixed is None else [f"t_ref = {fixed:.4g} degC from the calibration"]
        if fixed is None:
            # 1-sigma of t_ref from the curvature of the profile objective
            hstep = 0.05 * span + 0.5
            o0, op, om = (objective(Gt2, ht2, tr + d) for d in (0.0, hstep, -hstep))
            curv = (op + om - 2 * o0) / hstep ** 2
            sigma["t_ref"] = float(math.sqrt(2.0 * scale / curv)) if curv > 0 else math.inf
        return Cand(self.name, npar, Sw, Su, delta, params, sigma, notes)


def levels_apart(D) -> bool:
    """Whether two recordings or more have samples: each then has a level of its own (a shift between
    sessions), which the lag's interval leaves free (:meth:`TemperatureFit._level_free`).  With one, its
    level against the calibration's reference temperature is part of what pins the lag, and the rival
    for it is ``offset`` (or ``gain``), judged by the stepwise search."""
    return len(np.unique(D.rec)) >= 2


def recording_span(D) -> float:
    """The longest recording's length (s), first to last sample (``D.rec_info[].duration_s``: the
    temperature is recorded throughout, also where the diagnosis scores no sample), else the span
    of the samples used per recording."""
    spans = [float(ri.get("duration_s", 0.0)) for ri in D.rec_info]
    used = [float(np.ptp(D.tg[D.rec == r])) for r in np.unique(D.rec)]
    return max(spans + used, default=0.0)


def _interval(shape: dict) -> str:
    """A lag interval as prose: "12-48 s", "0-30 s", "of at least 200 s"."""
    lo, hi = shape["interval_s"]
    if not math.isfinite(hi):
        return f"of at least {lo:.3g} s"
    return f"{lo:.3g}-{hi:.3g} s"


class TemperatureOffset(TemperatureFit, Effect):
    name = "temperature_offset"
    time_dependent = True
    covariate = "temp_c"
    tell_apart = "the same pose held at two temperatures, and repeated at one temperature later (temperature apart from time)"
    tells_from = ("bias_drift", "offset", "temperature_gain")
    summary = "b_i changes linearly with temperature"
    doc = ("bias_i(t) += coeff_i (T_s(t) - t_ref) (coeff: counts per degC), T_s the recorded temperature "
           "through a first-order lag tau_s (s; 0: T_s = temp_c).")
    stage = "state"
    params = (
        Param("coeff", None, "counts/degC", "offset tempco; auto = 0.2 % of g per degC in counts", "floats"),
        Param("t_ref", 25.0, "degC", "temperature at which the offset is the calibrated one (the effect shows "
              "only when the motion's temperature moves away from it: temp_profile=ramp or sine)"),
        Param("tau_s", 0.0, "s", "thermal lag: the sensor's temperature follows temp_c through a first-order lag "
              "of this time constant", minimum=0.0),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (
        FitParam("coeff", "channel", "counts/degC", "offset temperature coefficient"),
        FitParam("t_ref", "scalar", "degC", "reference temperature", free=False),
        FitParam("tau_s", "scalar", "s", "thermal lag", free=False),
    )

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        c = per_channel(spec["coeff"], 0.002 * ctx.g_counts(), m, rng if spec["random"] else None, self.name, "coeff")
        return {"coeff": c, "t_ref": float(spec["t_ref"]), "tau_s": float(spec["tau_s"])}

    def identity(self, ctx):
        return {"coeff": np.zeros(ctx.n_channels), "t_ref": 25.0, "tau_s": 0.0}

    def modify_state(self, state, p, ctx):
        T = lagged(temperature_of(ctx, self.name), ctx.truth.t, float(p.get("tau_s", 0.0)))
        add = (T - float(p["t_ref"]))[:, None] * np.asarray(p["coeff"], float)[None, :]
        return state.replace(bias=add if state.bias is None else state.bias + add)

    gain = False  # the fit: coefficient on the sensed reading (True) or on 1

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.1

    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        i = strongest(p["coeff"])
        return (f"offset tempco up to {p['coeff'][i]:+.4g} +- {s['coeff'][i]:.2g} counts/degC on channel {i} "
                f"(t_ref {p['t_ref']:.4g} degC" + (f", lag {p['tau_s']:.3g} s)" if p.get("tau_s") else ")"))


class TemperatureGain(TemperatureFit, Effect):
    name = "temperature_gain"
    time_dependent = True
    covariate = "temp_c"
    tell_apart = "each axis up and down at two temperatures (a gain change scales both readings, an offset change shifts them)"
    tells_from = ("gain", "temperature_offset", "bias_drift")
    summary = "the magnitude of s_i changes linearly with temperature"
    doc = ("gain_i(t) *= 1 + coeff_i (T_s(t) - t_ref) (coeff: fraction per degC), T_s the recorded "
           "temperature through a first-order lag tau_s (s; 0: T_s = temp_c).")
    stage = "state"
    params = (
        Param("coeff", 3e-4, "1/degC", "gain tempco (fraction per degC)", "floats"),
        Param("t_ref", 25.0, "degC", "temperature at which the gain is the calibrated one (the effect shows "
              "only when the motion's temperature moves away from it: temp_profile=ramp or sine)"),
        Param("tau_s", 0.0, "s", "thermal lag: the sensor's temperature follows temp_c through a first-order lag "
              "of this time constant", minimum=0.0),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (
        FitParam("coeff", "channel", "1/degC", "gain temperature coefficient"),
        FitParam("t_ref", "scalar", "degC", "reference temperature", free=False),
        FitParam("tau_s", "scalar", "s", "thermal lag", free=False),
    )

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        c = per_channel(spec["coeff"], 0.0, m, rng if spec["random"] else None, self.name, "coeff")
        return {"coeff": c, "t_ref": float(spec["t_ref"]), "tau_s": float(spec["tau_s"])}

    def identity(self, ctx):
        return {"coeff": np.zeros(ctx.n_channels), "t_ref": 25.0, "tau_s": 0.0}

    def modify_state(self, state, p, ctx):
        T = lagged(temperature_of(ctx, self.name), ctx.truth.t, float(p.get("tau_s", 0.0)))
        fac = 1.0 + (T - float(p["t_ref"]))[:, None] * np.asarray(p["coeff"], float)[None, :]
        return state.replace(gain=fac if state.gain is None else state.gain * fac)

    gain = True  # the fit: coefficient on the sensed reading (True) or on 1

    # -- the benchmark --------------------------------------------------------

    bench_size = 1e-05



    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        i = strongest(p["coeff"])
        return (f"gain tempco up to {1e6 * p['coeff'][i]:+.4g} +- {1e6 * s['coeff'][i]:.2g} ppm/degC "
                f"on channel {i} "
                f"(t_ref {p['t_ref']:.4g} degC" + (f", lag {p['tau_s']:.3g} s)" if p.get("tau_s") else ")"))
