"""nonlinearity: a term in the square of the channel's input, and optionally in its cube.

The contract's nonlinearity is the square term.  Real sensors also bend symmetrically (an
odd, cubic term); on poses at +-1 g alone a cube is a gain change (x^3 = g^2 x there), so
it is told from gain only by readings between the axes (poses at 45 deg, motion).  The
fit carries both terms, so a bend of either parity is named ``nonlinearity`` and not the
gain that the cube resembles at the faces; on data that hold only face poses the two are
the same, and the cube is not fitted there (:data:`CUBE_APART`)."""
from __future__ import annotations


import numpy as np

from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_list, channel_mask, per_channel, strongest
from .fitdata import FitData
from .fitting import Cand, LinearCandidate, linear_fit, shape_pinned
from .settings import PENALTY_PER_PARAM

#: the cube is fitted on a channel only where the data can tell it from a gain: the part of
#: x^3 that no multiple of x reproduces, relative to x^3 over the fitted samples, is at least
#: this.  Poses on the axes alone give ~0 (x^3 = g^2 x at 0 and +-g; six hand-placed face poses
#: 0.011-0.016 on imucal's sessions), poses between the axes 0.17-0.45 (the Xsens and MPU-6050
#: hand-held sessions, a jig with edge and corner poses).
CUBE_APART = 0.05


class Nonlinearity(LinearCandidate, Effect):
    name = "nonlinearity"
    varies_by_pose = True
    tell_apart = "poses at 45 deg between the axes (a nonlinearity bends the reading between -g and +g, a tilt of the table does not)"
    tells_from = ("gain", "misalignment", "pose_error", "saturation", "offset")
    summary = "the reading gains a term in the square of the channel's input"
    doc = ("counts_i += k2_i x_i^2 + k3_i x_i^3, x_i = (counts_i - b_i - bias_i) / |s_i| the channel's input "
           "in m/s^2 (k2: counts per (m/s^2)^2, k3: counts per (m/s^2)^3; k3 = 0 unless given).  "
           "Applied before bandwidth.")
    stage = "signal"
    params = (
        Param("k2", None, "counts/(m/s^2)^2", "quadratic coefficient; auto = 0.5 % of the reading at 1 g", "floats"),
        Param("k3", 0.0, "counts/(m/s^2)^3", "cubic coefficient", "floats"),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("k2", "channel", "counts/(m/s^2)^2", "quadratic coefficient"),
           FitParam("k3", "channel", "counts/(m/s^2)^3", "cubic coefficient"))

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        g = float(ctx.device.gravity_mps2)
        k = np.linalg.norm(ctx.state.sensitivity, axis=1)
        rnd = rng if spec["random"] else None
        k2 = per_channel(spec["k2"], 0.005 * k / g, m, rnd, self.name, "k2")
        k3 = per_channel(spec.get("k3", 0.0), 0.0, m, rnd, self.name, "k3")
        return {"k2": k2, "k3": k3}

    def identity(self, ctx):
        return {"k2": np.zeros(ctx.n_channels), "k3": np.zeros(ctx.n_channels)}

    def apply_signal(self, counts, p, ctx):
        k = np.linalg.norm(ctx.state.sensitivity, axis=1)
        x = (counts - ctx.state.total_offset()) / k
        k3 = np.asarray(p.get("k3", np.zeros_like(p["k2"])), float)
        return counts + (np.asarray(p["k2"], float) + k3 * x) * x * x

    # -- fit to a residual (the diagnosis) ------------------------------------

    @staticmethod
    def _input(D) -> np.ndarray:
        """(n, N) the channels' input x (m/s^2) as the model predicts it."""
        return D.sensed / np.linalg.norm(D.s, axis=1)

    def columns(self, D):
        x = self._input(D)
        x2 = x * x
        return np.stack([x2, np.where(self.cube_told(x), x2 * x, 0.0)], axis=2)

    @staticmethod
    def cube_told(x: np.ndarray) -> np.ndarray:
        """(N,) bool: channels whose input ``x`` (n, N) tells a cube from a gain (:data:`CUBE_APART`)."""
        x3 = x ** 3
        xx = np.sum(x * x, axis=0)
        proj = np.sum(x * x3, axis=0) / np.where(xx > 0, xx, 1.0)
        apart = np.sum((x3 - proj * x) ** 2, axis=0)
        whole = np.sum(x3 * x3, axis=0)
        return apart >= CUBE_APART ** 2 * np.where(whole > 0, whole, np.inf)

    def mimics_calibration(self, fit):
        # the cube (x^3 = g^2 x on the axes) takes a part of a gain; the square alone does not
        return bool(np.any(np.asarray(fit.params.get("k3", ()), float) != 0))

    def looks_like(self, D):
        # on poses along the axes alone a cube is a gain change: a gain verdict there could be a bend
        return ("gain",) if not np.any(self.cube_told(self._input(D))) else ()

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        # the square alone, or the square and the cube: the one with the larger penalised held-out
        # gain (a bend of one parity does not pay for the other's parameters); the cube only where the
        # data determine it beyond the square (shape_pinned), else the square is fitted and the cube's
        # test is the candidate's ``shape``
        X = self.columns(D)
        fits = []
        for cols in (X[:, :, :1], X):
            Sw, Su, theta, cov, k, delta = linear_fit(D, cols, y, S0w, S0u)
            th = np.zeros((theta.shape[0], 2))
            cv2 = np.zeros((theta.shape[0], 2, 2))
            m = cols.shape[2]
            th[:, :m] = theta
            cv2[:, :m, :m] = cov
            p, s = self.to_params(D, th, cv2)
            fits.append((Cand(self.name, k, Sw, Su, delta, p, s), float((S0w - Sw).sum()) - PENALTY_PER_PARAM * k))
            if not np.any(X[:, :, 1]):
                break                                   # no channel tells a cube from a gain
        (square, pg_sq), full = fits[0], (fits[1] if len(fits) > 1 else None)
        if full is None or full[1] <= pg_sq:
            return square
        cube = full[0]
        test = shape_pinned(D, square.Sw, cube.Sw, cube.k - square.k)
        if test["determined"]:
            cube.shape = {"k3": test}
            return cube
        square.shape = {"k3": dict(test, used=0.0)}
        square.notes = list(square.notes) + [
            f"the cube is not determined by these data beyond the square (its chi2 gain {test['chi2_gain']:.3g} "
            f"against {test['crit_chi2']:.3g} for {test['extra_params']} more parameter(s)): the square alone is fitted"]
        return square

    def to_params(self, D, theta, cov):
        sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
        return {"k2": theta[:, 0], "k3": theta[:, 1]}, {"k2": sd[:, 0], "k3": sd[:, 1]}

    def param_columns(self, D, params):
        # the cube's column is zero on a channel whose input does not tell it from a gain
        return self.columns(D), {"k2": np.tile([1.0, 0.0], (D.N, 1)), "k3": np.tile([0.0, 1.0], (D.N, 1))}

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
        k2 = np.asarray(p["k2"], float)
        k3 = np.asarray(p.get("k3", np.zeros_like(k2)), float)
        q = 100 * k2 * g / ks            # % of the reading at 1 g
        c = 100 * k3 * g * g / ks
        i = strongest(np.abs(q) + np.abs(c))
        return (f"reading bends by up to {q[i]:+.3g} % (square term, {k2[i]:+.4g} counts/(m/s^2)^2) and "
                f"{c[i]:+.3g} % (cube term, {k3[i]:+.4g} counts/(m/s^2)^3) of the reading at 1 g on channel {i}")
