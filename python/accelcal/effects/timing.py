"""Timing: time_skew (a channel sampled at t + tau) and bandwidth (first-order low-pass)."""
from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from ..sensor import lowpass_first_order
from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_float_array, as_list, channel_mask, per_channel, strongest
from .fitdata import FitData
from .fitting import SearchCandidate, Shifter
from .settings import DELAY_GRID, SKEW_GRID


def lowpass_runs(t: np.ndarray, x: np.ndarray, w: float, h: float) -> np.ndarray:
    """The registry's first-order low-pass (effects.lowpass_first_order: exact for an input linear
    between samples, steady state at the first sample) with angular cut-off w, computed with
    lfilter over runs of samples at the nominal period h (gaps > 1.5 h get their exact update)."""
    n = t.shape[0]
    y = np.empty_like(x)
    gaps = np.flatnonzero(np.diff(t) > 1.5 * h) + 1
    starts = np.concatenate([[0], gaps])
    ends = np.append(gaps, n)
    a = math.exp(-w * h)
    beta = -math.expm1(-w * h) / (w * h)
    b0, b1 = 1.0 - beta, beta - a
    for a0, e0 in zip(starts, ends):
        if a0 == 0:
            y[0] = x[0]
        else:
            hg = float(t[a0] - t[a0 - 1])
            ag = math.exp(-w * hg)
            bg = -math.expm1(-w * hg) / (w * hg)
            y[a0] = ag * y[a0 - 1] + (bg - ag) * x[a0 - 1] + (1.0 - bg) * x[a0]
        if e0 - a0 > 1:
            zi = (b1 * x[a0] + a * y[a0])[None, :]
            y[a0 + 1:e0] = lfilter([b0, b1], [1.0, -a], x[a0 + 1:e0], axis=0, zi=zi)[0]
    return y


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


class Bandwidth(SearchCandidate, Effect):
    name = "bandwidth"
    tell_apart = "motion at several frequencies (a low-pass damps and lags the faster ones more, a time shift only delays)"
    summary = "the channel responds through a first-order low-pass of cut-off f_c"
    doc = ("y' = 2 pi fc (x - y) on the noise-free readings, exact ramp-invariant discretisation at "
           "the sample times, starting in steady state (fc = inf: no filter).")
    stage = "signal"
    params = (
        Param("fc_hz", 5.0, "Hz", "cut-off frequency", "floats", minimum=0.0, exclusive_min=True),
        CHANNEL_PARAM,
    )
    fit = (FitParam("fc_hz", "channel", "Hz", "cut-off frequency (inf = none)"),)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        return {"fc_hz": per_channel(spec["fc_hz"], 5.0, m, None, self.name, "fc_hz", off_value=math.inf)}

    def identity(self, ctx):
        return {"fc_hz": np.full(ctx.n_channels, math.inf)}

    def apply_signal(self, counts, p, ctx):
        return lowpass_first_order(np.asarray(ctx.truth.t, float), counts, np.asarray(p["fc_hz"], float))

    # -- fit to a residual (the diagnosis) ------------------------------------

    grid = DELAY_GRID

    lower = 0.0

    def prepare(self, D, pcur):
        self.D = D
        self.x = D.pred
        self.recs = [np.flatnonzero(D.rec == k) for k in np.unique(D.rec)]

    def delta(self, u):
        u = np.broadcast_to(np.asarray(u, float), (self.D.N,))
        out = np.zeros_like(self.x)
        if not np.any(u > 0):
            return out
        for v in np.unique(u[u > 0]):
            cols = np.flatnonzero(u == v)
            for idx in self.recs:
                xs = self.x[idx][:, cols]
                out[np.ix_(idx, cols)] = lowpass_runs(self.D.t[idx], xs, 1.0 / (v * self.D.h), self.D.h) - xs
        return out

    def to_params(self, D, u, su):
        d = u * D.h
        fc = np.where(d > 0, 1.0 / (2 * math.pi * np.maximum(d, 1e-300)), math.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            sfc = np.where(d > 0, fc * (su * D.h) / np.maximum(d, 1e-300), math.inf)
        return {"fc_hz": fc}, {"fc_hz": sfc, "delay_s": su * D.h}

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
        return (f"low-pass cut-off down to {fc[i]:.4g} Hz (delay {1e3 * s['delay_s'][i]:.2g} ms 1-sigma) "
                f"on channel {i}")
