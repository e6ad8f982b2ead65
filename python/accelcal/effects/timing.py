"""Timing: time_skew (a channel sampled at t + tau) and bandwidth (first-order low-pass)."""
from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from ..sensor import BUTTER2_MODE, lowpass_butterworth2, lowpass_first_order
from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_float_array, as_list, channel_mask, per_channel, strongest
from .fitdata import FitData
from .fitting import SearchCandidate, Shifter, block_ss
from .settings import DELAY_GRID, SKEW_GRID, T_LAG_CRIT_CHI2


def lowpass_runs(t: np.ndarray, x: np.ndarray, w: complex, h: float) -> np.ndarray:
    """The registry's first-order low-pass (sensor.lowpass_first_order: exact for an input linear
    between samples, steady state at the first sample) with angular cut-off w, computed with
    lfilter over runs of samples at the nominal period h (gaps > 1.5 h get their exact update).
    A complex w gives one complex mode of a higher-order filter (complex result)."""
    n = t.shape[0]
    a = np.exp(-w * h)
    y = np.empty(x.shape, np.result_type(x, a))
    gaps = np.flatnonzero(np.diff(t) > 1.5 * h) + 1
    starts = np.concatenate([[0], gaps])
    ends = np.append(gaps, n)
    beta = -np.expm1(-w * h) / (w * h)
    b0, b1 = 1.0 - beta, beta - a
    for a0, e0 in zip(starts, ends):
        if a0 == 0:
            y[0] = x[0]
        else:
            hg = float(t[a0] - t[a0 - 1])
            ag = np.exp(-w * hg)
            bg = -np.expm1(-w * hg) / (w * hg)
            y[a0] = ag * y[a0 - 1] + (bg - ag) * x[a0 - 1] + (1.0 - bg) * x[a0]
        if e0 - a0 > 1:
            zi = (b1 * x[a0] + a * y[a0])[None, :]
            y[a0 + 1:e0] = lfilter([b0, b1], [1.0, -a], x[a0 + 1:e0], axis=0, zi=zi)[0]
    return y


def lowpass_order_runs(t: np.ndarray, x: np.ndarray, w: float, h: float, order: int) -> np.ndarray:
    """:func:`lowpass_runs` of the first-order low-pass (order 1) or of the second-order
    Butterworth (order 2, sensor.lowpass_butterworth2) of angular cut-off w."""
    if order == 1:
        return lowpass_runs(t, x, w, h)
    q, c = BUTTER2_MODE
    return 2.0 * np.real(c * lowpass_runs(t, x, w * q, h))


#: a skew of every channel late by the same time, within this share of it, is also a low-pass's
#: group delay: analog filters on each channel from the same parts (cut-offs within +-20 %)
COMMON_LAG = 0.2


class TimeSkew(SearchCandidate, Effect):
    name = "time_skew"
    tell_apart = "fast motion with a sharp start and stop (a time shift moves the edge, a low-pass rounds it)"
    summary = "channel i is sampled at t + tau_i instead of t"
    doc = ("tau_i -> tau_i + tau (s): the motion is evaluated at t + tau_i (exactly from the analytic "
           "trajectory when the truth has one, else by cubic-spline interpolation of the reference).")
    stage = "state"
    params = (
        Param("tau", None, "s", "skew; auto = a quarter of the sample period", "floats"),
        Param("sequential", False, "-", "1: channel i is skewed by i x tau (a multiplexed ADC)", "bool"),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("tau", "channel", "s", "time skew"),)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        default = 0.25 / float(ctx.device.sample_rate_hz)
        tau = per_channel(spec["tau"], default, m, rng if spec["random"] else None, self.name, "tau")
        if spec["sequential"]:
            tau = tau * np.arange(ctx.n_channels)
        return {"tau": tau}

    def identity(self, ctx):
        return {"tau": np.zeros(ctx.n_channels)}

    def modify_state(self, state, p, ctx):
        return state.replace(tau=state.tau + np.asarray(p["tau"], float))

    def alike(self, D, fit):
        # every channel late by about the same time: the group delay of a low-pass on each channel
        # (a second-order one is nearly a pure delay below its cut-off, closer to a skew than the
        # contract's first-order bandwidth), or a common latency
        tau = np.asarray(fit.params.get("tau", ()), float)
        sd = np.asarray(fit.sigma.get("tau", np.zeros_like(tau)), float)
        if tau.size < 2 or not np.all(tau < -3.0 * sd) or not np.all(tau < 0):
            return ()
        lag = float(np.mean(tau))
        return ("bandwidth",) if np.max(np.abs(tau - lag)) <= COMMON_LAG * abs(lag) else ()

    # -- fit to a residual (the diagnosis) ------------------------------------

    grid = SKEW_GRID

    def prepare(self, D, pcur):
        self.D = D
        if getattr(D, "_shifter", None) is None:
            D._shifter = Shifter(D, D.sensed)
        self.sh = D._shifter

    def delta(self, u):
        return self.sh.delta(np.asarray(u, float) * self.D.h)

    def to_params(self, D, u, su):
        return {"tau": u * D.h}, {"tau": su * D.h}

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        c = SearchCandidate.cv(self, D, y, pcur, S0w, S0u, folds)
        shape = skew_interval(D, c.params["tau"], c.sigma["tau"])
        c.shape = {"tau_s": shape}
        loose = [i for i, ok in enumerate(shape["channels_determined"]) if not ok and c.params["tau"][i] != 0.0]
        if loose:
            c.notes = list(c.notes) + [
                "the skew of channel" + ("s " if len(loose) > 1 else " ") + ", ".join(str(i) for i in loose)
                + " is not determined by these data (its 95 % interval holds 0: "
                + "; ".join(f"{1e3 * shape['interval_s'][i][0]:+.3g} to {1e3 * shape['interval_s'][i][1]:+.3g} ms"
                            for i in loose) + "): no finding there"]
        return c

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.001

    def bench_spec(self, m, z, aux):
        return {"tau": as_list(m * z)}

    bench_key = "tau"


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        i = strongest(p["tau"])
        return f"time skew up to {1e3 * p['tau'][i]:+.4g} +- {1e3 * s['tau'][i]:.2g} ms on channel {i}"


def skew_interval(D: FitData, tau: np.ndarray, sd: np.ndarray) -> dict:
    """A time skew's ``shape`` entry: per channel the interval tau +- sqrt(T_LAG_CRIT_CHI2) sigma (s;
    sigma from the profile's curvature and the residual's excess, times the square root of the poses'
    design effect, as the lag's and the bend's rules weigh it) and whether it excludes 0 (the nested
    form: no skew on that channel); ``determined``: some channel's does."""
    tau = np.asarray(tau, float)
    sd = np.asarray(sd, float) * math.sqrt(float(getattr(D, "deff", 1.0) or 1.0))
    half = math.sqrt(T_LAG_CRIT_CHI2) * sd
    lo, hi = tau - half, tau + half
    ok = np.isfinite(half) & ((lo > 0.0) | (hi < 0.0))
    return {"value": tau.tolist(), "interval_s": [[float(a), float(b)] for a, b in zip(lo, hi)],
            "channels_determined": [bool(v) for v in ok], "determined": bool(np.any(ok)),
            "crit_chi2": T_LAG_CRIT_CHI2}


class Bandwidth(SearchCandidate, Effect):
    name = "bandwidth"
    tell_apart = "motion at several frequencies (a low-pass damps and lags the faster ones more, a time shift only delays)"
    summary = "the channel responds through a first-order low-pass of cut-off f_c"
    doc = ("y' = 2 pi fc (x - y) on the noise-free readings (order 2: the second-order Butterworth "
           "y'' + sqrt(2) w y' + w^2 (y - x) = 0, w = 2 pi fc), exact for an input linear between the "
           "sample times, starting in steady state (fc = inf: no filter).")
    stage = "signal"
    params = (
        Param("fc_hz", 5.0, "Hz", "cut-off frequency", "floats", minimum=0.0, exclusive_min=True),
        Param("order", 1, "-", "1: first-order low-pass (the contract's); 2: second-order Butterworth "
              "(a MEMS chip's digital low-pass, an anti-alias filter)", "int", minimum=1, maximum=2),
        CHANNEL_PARAM,
    )
    fit = (FitParam("fc_hz", "channel", "Hz", "cut-off frequency (inf = none)"),
           FitParam("order", "scalar", "-", "1: first-order low-pass, 2: second-order Butterworth", free=False))

    #: the fit's orders: the contract's first-order low-pass, and the second-order Butterworth
    #: whose response is closer to a pure delay below its cut-off (flat to the fourth power of
    #: the frequency); the one with the smaller held-out residual is kept (the same parameters)
    ORDERS = (1, 2)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        return {"fc_hz": per_channel(spec["fc_hz"], 5.0, m, None, self.name, "fc_hz", off_value=math.inf),
                "order": int(spec["order"])}

    def identity(self, ctx):
        return {"fc_hz": np.full(ctx.n_channels, math.inf), "order": 1}

    def apply_signal(self, counts, p, ctx):
        filt = lowpass_butterworth2 if int(p.get("order", 1)) == 2 else lowpass_first_order
        return filt(np.asarray(ctx.truth.t, float), counts, np.asarray(p["fc_hz"], float))

    # -- fit to a residual (the diagnosis) ------------------------------------

    grid = DELAY_GRID

    lower = 0.0

    #: group delay at low frequency per 1/w: first order 1, second-order Butterworth sqrt(2) (u,
    #: the searched delay in samples, maps to one cut-off per order)
    DELAY_PER_W = {1: 1.0, 2: math.sqrt(2.0)}

    order = 1

    def prepare(self, D, pcur):
        self.D = D
        self.x = D.pred
        self.recs = [np.flatnonzero(D.rec == k) for k in np.unique(D.rec)]

    def delta(self, u):
        u = np.broadcast_to(np.asarray(u, float), (self.D.N,))
        out = np.zeros_like(self.x)
        if not np.any(u > 0):
            return out
        k = self.DELAY_PER_W[self.order]
        for v in np.unique(u[u > 0]):
            cols = np.flatnonzero(u == v)
            for idx in self.recs:
                xs = self.x[idx][:, cols]
                out[np.ix_(idx, cols)] = lowpass_order_runs(self.D.t[idx], xs, k / (v * self.D.h), self.D.h,
                                                            self.order) - xs
        return out

    def _search(self, order, D, y, pcur, S0w, S0u, folds):
        """The search of SearchCandidate.cv with the filter of ``order``."""
        self.order = order
        try:
            return SearchCandidate.cv(self, D, y, pcur, S0w, S0u, folds)
        finally:
            self.order = 1

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        # each order searched; kept: the smaller held-out residual (all-data fits: in-sample)
        best = None
        for order in self.ORDERS:
            c = self._search(order, D, y, pcur, S0w, S0u, folds)
            ss = float(np.sum(c.Sw)) if folds else float(np.sum(block_ss(D, D.rows(y - c.delta))[0]))
            if best is None or ss < best[0]:
                best = (ss, c)
        return best[1]

    def refit(self, D, y, pcur, like):
        # the order the fit ``like`` took is kept
        S0w, S0u = block_ss(D, D.rows(y))
        return self._search(int(like.params.get("order", 1)), D, y, pcur, S0w, S0u, folds=False)

    def to_params(self, D, u, su):
        d = u * D.h
        k = self.DELAY_PER_W[self.order]
        fc = np.where(d > 0, k / (2 * math.pi * np.maximum(d, 1e-300)), math.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            sfc = np.where(d > 0, fc * (su * D.h) / np.maximum(d, 1e-300), math.inf)
        return {"fc_hz": fc, "order": self.order}, {"fc_hz": sfc, "delay_s": su * D.h}

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.001

    def bench_spec(self, m, z, aux):
        return {"fc_hz": as_list(1.0 / (2 * math.pi * m * np.asarray(aux["u"], float)))}

    def bench_pair(self, est, truth, sig):
        fe, ft = as_float_array(est["fc_hz"]), np.asarray(truth["fc_hz"], float)
        e = np.where(np.isfinite(fe), 1 / (2 * np.pi * fe), 0.0)     # compared as delays
        t = np.where(np.isfinite(ft), 1 / (2 * np.pi * ft), 0.0)
        return e, t


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        fc = np.asarray(p["fc_hz"], float)
        i = int(np.argmin(fc))
        kind = "second-order Butterworth" if int(p.get("order", 1)) == 2 else "first-order"
        return (f"{kind} low-pass cut-off down to {fc[i]:.4g} Hz (delay {1e3 * s['delay_s'][i]:.2g} ms "
                f"1-sigma) on channel {i}")
