"""nonlinearity: a term in the square of the channel's input."""
from __future__ import annotations


import numpy as np

from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_list, channel_mask, per_channel, strongest
from .fitdata import FitData
from .fitting import LinearCandidate


class Nonlinearity(LinearCandidate, Effect):
    name = "nonlinearity"
    varies_by_pose = True
    tell_apart = "poses at 45 deg between the axes (a nonlinearity bends the reading between -g and +g, a tilt of the table does not)"
    summary = "the reading gains a term in the square of the channel's input"
    doc = ("counts_i += k2_i x_i^2, x_i = (counts_i - b_i - bias_i) / |s_i| the channel's input in m/s^2 "
           "(k2: counts per (m/s^2)^2).  Applied before bandwidth.")
    stage = "signal"
    params = (
        Param("k2", None, "counts/(m/s^2)^2", "quadratic coefficient; auto = 0.5 % of the reading at 1 g", "floats"),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("k2", "channel", "counts/(m/s^2)^2", "quadratic coefficient"),)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        g = float(ctx.device.gravity_mps2)
        k = np.linalg.norm(ctx.state.sensitivity, axis=1)
        k2 = per_channel(spec["k2"], 0.005 * k / g, m, rng if spec["random"] else None, self.name, "k2")
        return {"k2": k2}

    def identity(self, ctx):
        return {"k2": np.zeros(ctx.n_channels)}

    def apply_signal(self, counts, p, ctx):
        k = np.linalg.norm(ctx.state.sensitivity, axis=1)
        x = (counts - ctx.state.total_offset()) / k
        return counts + np.asarray(p["k2"], float) * x * x

    # -- fit to a residual (the diagnosis) ------------------------------------

    pname = 'k2'

    def columns(self, D):
        x = D.sensed / np.linalg.norm(D.s, axis=1)
        return (x * x)[:, :, None]

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.01

    def bench_spec(self, m, z, aux):
        return {"k2": as_list(m * z)}

    bench_key = "k2"


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        ks = np.linalg.norm(D.s, axis=1)
        g = float(D.device.gravity_mps2)
        i = strongest(p["k2"])
        return (f"quadratic term up to {p['k2'][i]:+.4g} counts/(m/s^2)^2 on channel {i} "
                f"({100 * p['k2'][i] * g / ks[i]:+.3g} % of the reading at 1 g)")
