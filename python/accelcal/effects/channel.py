"""Channel parameters: offset, gain, misalignment."""
from __future__ import annotations


import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import AccelcalError
from ..sensor import rotation_matrix
from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_list, channel_mask, owner, per_channel, random_perpendicular, strongest, unit_rows
from .fitdata import FitData, force_at, poses_on_axes, tangent_basis, unit_rows3
from .fitting import Cand, LinearCandidate, block_ss, linear_fit
from .settings import MISALIGN_MAX_RAD


class Offset(LinearCandidate, Effect):
    name = "offset"
    tell_apart = "each axis both up and down (an offset shifts the +g and -g readings the same way, a gain scales them apart)"
    tells_from = ("gain", "temperature_gain")
    summary = "b_i differs from the calibrated value (a constant shift)"
    doc = "b_i -> b_i + db_i (counts)."
    stage = "state"
    params = (
        Param("db", None, "counts", "offset change; auto = 1 % of g in counts (per channel, from |s_i|)", "floats"),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("db", "channel", "counts", "offset change"),)
    absorbs = True
    exact_with_reference = True

    def absorb(self, cal, p):
        return dataclasses.replace(cal, offsets=cal.offsets + np.asarray(p["db"], float))

    def params_between(self, cal0, cal1):
        return {"db": np.asarray(cal1.offsets, float) - np.asarray(cal0.offsets, float)}

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        db = per_channel(spec["db"], 0.01 * ctx.g_counts(), m, rng if spec["random"] else None, self.name, "db")
        return {"db": db}

    def identity(self, ctx):
        return {"db": np.zeros(ctx.n_channels)}

    def modify_state(self, state, p, ctx):
        return state.replace(offsets=state.offsets + np.asarray(p["db"], float))

    # -- fit to a residual (the diagnosis) ------------------------------------

    pname = 'db'

    def columns(self, D):
        return np.ones((D.n, D.N, 1))

    # -- the benchmark --------------------------------------------------------

    bench_size = 1.0

    def bench_spec(self, m, z, aux):
        return {"db": as_list(m * z)}

    bench_key = "db"


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        ks = np.linalg.norm(D.s, axis=1)
        i = strongest(p["db"])
        return (f"offset change up to {p['db'][i]:+.4g} +- {s['db'][i]:.2g} counts "
                f"({p['db'][i] / ks[i]:+.4g} m/s^2) on channel {i}")


class Gain(LinearCandidate, Effect):
    name = "gain"
    varies_by_pose = True
    tell_apart = "each axis both up and down (a gain error scales the +g and -g readings apart, an offset shifts both)"
    tells_from = ("offset", "temperature_offset")
    summary = "the magnitude of s_i differs (scale error along the axis)"
    doc = "s_i -> (1 + scale_i) s_i (scale: fraction)."
    stage = "state"
    params = (
        Param("scale", 0.01, "fraction", "relative gain change delta k_i / k_i", "floats", minimum=-0.99),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("scale", "channel", "fraction", "relative gain change"),)
    absorbs = True
    exact_with_reference = True

    def absorb(self, cal, p):
        return dataclasses.replace(cal, sensitivity=cal.sensitivity * (1.0 + np.asarray(p["scale"], float))[:, None])

    def params_between(self, cal0, cal1):
        return {"scale": np.linalg.norm(cal1.sensitivity, axis=1) / np.linalg.norm(cal0.sensitivity, axis=1) - 1.0}

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        return {"scale": per_channel(spec["scale"], 0.0, m, rng if spec["random"] else None, self.name, "scale")}

    def identity(self, ctx):
        return {"scale": np.zeros(ctx.n_channels)}

    def modify_state(self, state, p, ctx):
        return state.replace(sensitivity=state.sensitivity * (1.0 + np.asarray(p["scale"], float))[:, None])

    # -- fit to a residual (the diagnosis) ------------------------------------

    pname = 'scale'

    def columns(self, D):
        return D.sensed[:, :, None]

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.001

    def bench_spec(self, m, z, aux):
        return {"scale": as_list(m * z)}

    bench_key = "scale"


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        i = strongest(p["scale"])
        return f"gain error up to {100 * p['scale'][i]:+.4g} +- {100 * s['scale'][i]:.2g} % on channel {i}"


class Misalignment(LinearCandidate, Effect):
    name = "misalignment"
    varies_by_pose = True
    tell_apart = "poses with gravity between the axes, at 45 deg (a misalignment mixes the other axes' g into a channel)"
    tells_from = ("pose_error", "nonlinearity", "gain")
    summary = "the direction of s_i differs (cross-axis sensitivity)"
    doc = ("s_i -> Exp(rot_i) s_i: s_i rotated by the small rotation vector rot_i (rad, body axes); "
           "only the part of rot_i perpendicular to s_i matters (2 free values per channel).")
    stage = "state"
    params = (
        Param("angle_deg", 0.5, "deg", "tilt of each selected channel's sensitive axis", "floats", minimum=0.0),
        Param("toward", "random", "-", "direction the axis tilts toward: random (per channel) or a body direction",
              "direction_or_random"),
        CHANNEL_PARAM,
    )
    fit = (FitParam("rot", "channel3", "rad", "rotation vector applied to s_i"),)
    absorbs = True

    def absorb(self, cal, p):
        R = rotation_matrix(np.asarray(p["rot"], float))
        return dataclasses.replace(cal, sensitivity=np.einsum("nij,nj->ni", R, cal.sensitivity))

    def params_between(self, cal0, cal1):
        """The smallest rotation (perpendicular to s_i) that turns s_i's direction in ``cal0``
        into its direction in ``cal1``."""
        u0, u1 = unit_rows(cal0.sensitivity), unit_rows(cal1.sensitivity)
        rot = np.zeros_like(u0)
        for i in range(u0.shape[0]):
            rot[i] = Rotation.align_vectors(u1[i][None, :], u0[i][None, :])[0].as_rotvec()
        return {"rot": rot}

    def looks_like(self, D):
        # on the six faces of a box a tilt of each pose is a misalignment to first order
        return ("pose_error",) if poses_on_axes(D) else ()

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        ang = np.radians(per_channel(spec["angle_deg"], 0.0, m, None, self.name, "angle_deg"))
        u = unit_rows(ctx.state.sensitivity)
        if isinstance(spec["toward"], str):
            d = random_perpendicular(u, rng)
        else:
            d = np.broadcast_to(spec["toward"], u.shape)
            d = d - np.sum(d * u, axis=1, keepdims=True) * u
            small = np.linalg.norm(d, axis=1) < 1e-9
            if np.any(small & m):
                i = int(np.flatnonzero(small & m)[0])
                raise AccelcalError(
                    f"{owner(self.name)} parameter 'toward': channel {i}'s axis already points that way"
                )
            d = unit_rows(d)
        axis = unit_rows(np.cross(u, d))  # rotating u about u x d tilts it toward d
        return {"rot": axis * ang[:, None]}

    def identity(self, ctx):
        return {"rot": np.zeros((ctx.n_channels, 3))}

    def modify_state(self, state, p, ctx):
        R = rotation_matrix(np.asarray(p["rot"], float))
        return state.replace(sensitivity=np.einsum("nij,nj->ni", R, state.sensitivity))

    # -- fit to a residual (the diagnosis) ------------------------------------

    # fit: s_i -> Exp(rot_i) s_i.  Linear to first order; for tilts of more than a few tenths of a
    #     degree the fit is relinearised (Gauss-Newton) about the all-data estimate rot0, and every
    #     fold fits the increment about it: delta = exact(rot0) + X(rot0) d.

    def _cols(self, D, fa, S):
        E = tangent_basis(unit_rows3(S))                        # (N,2,3)
        X = np.einsum("nkc,tnc->tnk", E, np.cross(S[None, :, :], fa))    # rot . (s x f_at)
        if D.gain_t is not None:
            X = X * D.gain_t[:, :, None]
        return X, E

    def _exact(self, D, fa, rot):
        S1 = np.einsum("nij,nj->ni", rotation_matrix(rot), D.s)
        d = np.einsum("tnc,nc->tn", fa, S1 - D.s)
        return d * D.gain_t if D.gain_t is not None else d, S1

    def param_columns(self, D, params):
        # rot_i = E_i^T theta_i: the two tilts across s_i (its part along s_i is no parameter)
        X, E = self._cols(D, force_at(D), D.s)
        return X, {"rot": E}

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        fa = force_at(D)
        X, E = self._cols(D, fa, D.s)
        Sw, Su, theta, cov, k, delta = linear_fit(D, X, y, S0w, S0u)
        rot = np.einsum("nk,nkc->nc", theta, E)
        # Gauss-Newton when second order matters (> ~0.1 deg), in reference mode only (jig-free, a
        # common rotation is absorbed by the poses and the steps could wander along it); a step is
        # kept only when it lowers the all-data chi2, and tilts stay below MISALIGN_MAX_RAD
        if D.Qp is None and 2e-3 < np.max(np.linalg.norm(rot, axis=1)) < MISALIGN_MAX_RAD:
            best = float(np.sum(D.W * (y - delta) ** 2))
            for _ in range(3):
                d0, S1 = self._exact(D, fa, rot)
                X1, E1 = self._cols(D, fa, S1)
                yr = y - d0
                s0w, s0u = block_ss(D, yr)
                Sw1, Su1, th1, cov1, k1, dlin = linear_fit(D, X1, yr, s0w, s0u)
                step = np.einsum("nk,nkc->nc", th1, E1)
                new_rot = rot + step             # Exp(step) Exp(rot) ~ Exp(rot + step) for small steps
                if np.max(np.linalg.norm(new_rot, axis=1)) > MISALIGN_MAX_RAD:
                    break
                d_new, _ = self._exact(D, fa, new_rot)
                obj = float(np.sum(D.W * (y - d_new) ** 2))
                if obj >= best:
                    break
                best, rot, delta = obj, new_rot, d_new
                Sw, Su, cov, k, E = Sw1, Su1, cov1, k1, E1
                if np.max(np.linalg.norm(step, axis=1)) < 1e-6:
                    break
        sd = np.sqrt(np.maximum(np.einsum("nkc,nkl,nlc->nc", E, cov, E), 0.0))
        return Cand(self.name, k, Sw, Su, delta, {"rot": rot}, {"rot": sd})

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.1

    def bench_spec(self, m, z, aux):
        return {"angle_deg": as_list(m * np.abs(z))}

    bench_key = "rot"


    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        rot = np.asarray(p["rot"], float)
        a = np.degrees(np.linalg.norm(rot, axis=1))
        i = int(np.argmax(a))
        text = f"axis tilt up to {a[i]:.3g} deg (+- {np.degrees(np.linalg.norm(s['rot'][i])):.2g}) on channel {i}"
        # the tilt's direction: an electrical crosstalk of channel j into channel i adds c s_j to s_i,
        # which no reading tells from a tilt toward s_j
        u = unit_rows3(D.s)
        tilt = np.cross(rot[i], u[i])
        if np.linalg.norm(tilt) > 0 and D.N > 1:
            tilt = tilt / np.linalg.norm(tilt)
            perp = u - np.outer(u @ u[i], u[i])             # each axis across channel i's
            nrm = np.linalg.norm(perp, axis=1)
            cos = np.where(nrm > 0.1, np.abs(perp @ tilt) / np.maximum(nrm, 1e-300), -1.0)
            cos[i] = -1.0
            j = int(np.argmax(cos))
            if cos[j] >= 0.9:
                text += (f", toward channel {j}'s axis (an electrical crosstalk of channel {j} into {i} reads the "
                         "same)")
        return text
