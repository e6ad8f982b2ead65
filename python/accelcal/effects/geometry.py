"""Geometry under rotation: position_error (lever arm) and the centripetal term."""
from __future__ import annotations


import numpy as np

from ..model import centripetal_matrix, omega_products
from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, as_float_array, as_list, channel_mask, determined, per_channel, unit_rows
from .fitdata import FitData, rotating_mask
from .fitting import Cand, LinearCandidate, linear_fit
from .settings import POSITION_TOL_M, ROTATING_RADPS


class PositionError(LinearCandidate, Effect):
    name = "position_error"
    tell_apart = "rotations about several axes (a position error shows only under rotation)"
    summary = "the true position is r_i + dr_i: shows only under rotation"
    doc = "r_i -> r_i + dr_i (m, body axes)."
    stage = "state"
    params = (
        Param("mm", 1.0, "mm", "size of each selected channel's position error", "floats", minimum=0.0),
        Param("direction", "random", "-", "direction of dr_i: random (per channel) or a body direction",
              "direction_or_random"),
        CHANNEL_PARAM,
    )
    fit = (FitParam("dr", "channel3", "m", "position error"),)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        size = 1e-3 * per_channel(spec["mm"], 0.0, m, None, self.name, "mm")
        N = ctx.n_channels
        if isinstance(spec["direction"], str):
            d = unit_rows(rng.standard_normal((N, 3)))
        else:
            d = np.broadcast_to(spec["direction"], (N, 3))
        return {"dr": d * size[:, None]}

    def identity(self, ctx):
        return {"dr": np.zeros((ctx.n_channels, 3))}

    def modify_state(self, state, p, ctx):
        return state.replace(positions=state.positions + np.asarray(p["dr"], float))

    # -- fit to a residual (the diagnosis) ------------------------------------

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: static poses only, no rotation reference (w, dw)"
        if not rotating_mask(D).any() and not np.any(np.linalg.norm(D.dw, axis=1) > 10 * ROTATING_RADPS):
            return "needs rotation in the reference (w_*, dw_*): none of the samples used rotates"
        return None

    def columns(self, D):
        s = D.s[None, :, :]
        w = D.w[:, None, :]
        X = np.cross(s, D.dw[:, None, :])
        if D.m0:
            sw = np.einsum("nc,tc->tn", D.s, D.w)
            X = X + D.m0 * (sw[:, :, None] * w - np.sum(D.w ** 2, axis=1)[:, None, None] * s)
        if D.gain_t is not None:
            X = X * D.gain_t[:, :, None]
        return X

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        X = self.columns(D)
        Sw, Su, theta, cov, k, delta = linear_fit(D, X, y, S0w, S0u)
        # report dr only along the observable principal directions (1-sigma <= POSITION_TOL_M)
        lam, V = np.linalg.eigh(cov)
        obs = np.sqrt(np.maximum(lam, 0.0)) <= POSITION_TOL_M
        coef = np.einsum("nji,nj->ni", V, theta) * obs
        theta = np.einsum("nij,nj->ni", V, coef)
        cov = np.einsum("nij,nj,nkj->nik", V, np.where(obs, lam, 0.0), V)
        delta = np.einsum("tnk,nk->tn", X, theta)
        sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
        c = Cand(self.name, k, Sw, Su, delta, {"dr": theta}, {"dr": sd})
        nobs = int(obs.sum())
        if nobs < obs.size:
            c.notes.append(f"dr kept along {nobs} of {obs.size} principal directions (the others have 1-sigma "
                           f"> {1e3 * POSITION_TOL_M:g} mm with this motion; reported as 0)")
        c.observable = obs
        return c

    # -- the benchmark --------------------------------------------------------

    bench_size = 1.0

    def bench_spec(self, m, z, aux):
        return {"mm": as_list(m * np.abs(z))}

    def bench_pair(self, est, truth, sig):
        e, t = as_float_array(est["dr"]), np.asarray(truth["dr"], float)
        if sig is not None:      # compare on the directions the motion makes observable
            sd = as_float_array(sig["dr"])
            ok = np.all(sd > 0, axis=1) & np.all(sd <= 1e-3, axis=1)
            e, t = e[ok], t[ok]
        return e, t


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        d = 1e3 * np.linalg.norm(p["dr"], axis=1)
        i = int(np.argmax(d))
        return f"position error up to {d[i]:.3g} mm (+- {1e3 * np.linalg.norm(s['dr'][i]):.2g}) on channel {i}"


class Centripetal(LinearCandidate, Effect):
    name = "centripetal"
    tell_apart = "steady rotations at several rates (the centripetal term grows with the rate squared)"
    summary = "the model leaves out the omega x (omega x r_i) term"
    doc = ("Sets the multiplier of s_i . (omega x (omega x r_i)) in the readings to scale_i.  The physical "
           "truth always has the term (multiplier 1), so in the simulator the default scale=1 changes "
           "nothing and scale<1 withholds (part of) the term from the data.  The diagnosis's base model "
           "is the contract's, with the term (multiplier 1), and the fit recovers the data's scale; "
           "diagnose(model_centripetal=False) starts from the paper's model without it (multiplier 0).")
    stage = "state"
    params = (
        Param("scale", 1.0, "-", "multiplier of the centripetal term (1 = physics, 0 = withheld)", "floats"),
        CHANNEL_PARAM,
    )
    fit = (FitParam("scale", "channel", "-", "multiplier of the centripetal term (set, not added)"),)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        v = per_channel(spec["scale"], 1.0, m, None, self.name, "scale")
        return {"scale": np.where(m, v, ctx.state.centripetal)}

    def identity(self, ctx):
        return {"scale": np.array(ctx.state.centripetal, float)}

    def modify_state(self, state, p, ctx):
        return state.replace(centripetal=np.broadcast_to(np.asarray(p["scale"], float), state.centripetal.shape).copy())

    # -- fit to a residual (the diagnosis) ------------------------------------

    pname = 'scale'

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: static poses only, no rotation reference (w)"
        if np.all(D.r == 0):
            return "every channel is at the origin: there is no centripetal term"
        if not rotating_mask(D).any():
            return "needs rotation in the reference (w_*): none of the samples used rotates"
        return None

    def columns(self, D):
        c = omega_products(D.w) @ centripetal_matrix(D.r, D.s).T
        if D.gain_t is not None:
            c = c * D.gain_t
        return c[:, :, None]

    def to_params(self, D, theta, cov):
        sd = np.sqrt(np.maximum(cov[:, 0, 0], 0.0))
        return {"scale": D.m0 + theta[:, 0]}, {"scale": sd}

    # -- the benchmark --------------------------------------------------------

    bench_size = 1.0

    def bench_spec(self, m, z, aux):
        return {"scale": float(1.0 - min(m, 1.0))}

    def bench_pair(self, est, truth, sig):
        e, t = 1.0 - as_float_array(est["scale"]), 1.0 - np.asarray(truth["scale"], float)
        return determined(e, t, sig["scale"]) if sig is not None and "scale" in sig else (e, t)


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        return (f"centripetal term multiplier {np.mean(p['scale']):.3g} (model {D.m0:g}; per channel "
                f"{np.min(p['scale']):.3g}..{np.max(p['scale']):.3g})")
