"""The fitting toolkit the effects share: a candidate's cross-validated result
(:class:`Cand`), block least squares with held-out scoring (linear effects), and the
search over a nonlinear parameter with a linear nuisance (time shifts, low-pass)."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.stats import chi2 as chi2_dist

from .fitdata import FitData, is_moving
from .settings import SEARCH_GROW, SEARCH_MAX_S, SEEN_MIN, SHAPE_LEVEL, SKEW_GRID


@dataclass
class Cand:
    """One candidate's cross-validated result on a target residual."""

    name: str
    k: int                        # parameters it adds
    Sw: np.ndarray                # (B,) held-out weighted chi2 after
    Su: np.ndarray                # (B,) held-out sum of squares after (counts^2)
    delta: np.ndarray             # (n, N) in-sample (all-data fit) change to the prediction
    params: dict
    sigma: dict
    notes: list = field(default_factory=list)
    evidence: str = "held-out gain"
    proof: bool = False           # significant on its own evidence (quantization lattice)
    # filled by score
    gain: float = 0.0
    penalty: float = 0.0
    t: float = 0.0
    z: float = 0.0
    before: float = 0.0
    after: float = 0.0
    shrink: float = 0.0
    significant: bool = False
    #: shape parameters (a thermal lag) and whether the data pin them: {param: {"value", "interval",
    #: "determined", ...}}; None for an effect without one
    shape: dict | None = None
    #: where a shape parameter is not pinned, this candidate is fitted in the nested form (no lag) and
    #: ``shaped`` holds the fit with the shape the data preferred (scored beside it, reported only as
    #: an alternative the data cannot tell from the nested one)
    shaped: "Cand | None" = None


def block_ss(D: FitData, Rr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    sq = Rr * Rr
    return D.bsum(np.sum(sq * D.W, axis=1)), D.bsum(sq.sum(axis=1))


def shape_pinned(D: FitData, Sw_nested: np.ndarray, Sw_shaped: np.ndarray, extra_k: int) -> dict:
    """Whether the data determine a shape beyond its nested form (a bend's cube beyond the square, a
    drift's path through knots beyond the ramp): the all-data chi2 the shape's ``extra_k`` more
    parameters gain must exceed the SHAPE_LEVEL point of chi2 with ``extra_k`` degrees of freedom,
    times the residual's excess over the floor and the poses' design effect (the lag's rule,
    :meth:`accelcal.effects.temperature.TemperatureFit._lag_interval`).  An AIC-like penalty of 2
    per parameter alone had let a shape in on a gain of 2.1 chi2 per parameter.  Returns the
    ``shape`` entry's fields: ``determined``, ``chi2_gain``, ``crit_chi2``, ``extra_params``."""
    rows = max(D.n * D.R, 1)
    s2 = max(1.0, float(np.sum(Sw_shaped)) / rows)
    gain = float(np.sum(Sw_nested) - np.sum(Sw_shaped))
    k = max(int(extra_k), 1)
    crit = float(chi2_dist.ppf(SHAPE_LEVEL, k)) * s2 * float(getattr(D, "deff", 1.0) or 1.0)
    return {"determined": bool(gain > crit), "chi2_gain": gain, "crit_chi2": crit, "extra_params": k}


def kept_space(G: np.ndarray, d: np.ndarray, rtol: float):
    """The eigen-decomposition of G (..., k, k) scaled by ``d`` (..., k; zeros taken as 1) and the
    directions a min-norm solve keeps: (lam, V, keep, d), keep where lam > rtol x the largest."""
    d = np.where(d > 0, d, 1.0)
    lam, V = np.linalg.eigh(G / d[..., :, None] / d[..., None, :])
    keep = lam > rtol * np.maximum(np.max(lam, axis=-1, keepdims=True), 1e-300)
    return lam, V, keep, d


def solve_groups(G: np.ndarray, h: np.ndarray, rtol: float = 1e-10, scale: np.ndarray | None = None):
    """Batched min-norm solve of G theta = h (G (g,k,k) symmetric PSD), with Jacobi scaling:
    the norm minimised is that of theta x ``scale`` (g,k), default sqrt(diag G).
    Returns theta (g,k), G^+ (g,k,k), rank (g,)."""
    d = np.sqrt(np.maximum(np.einsum("gii->gi", G), 0.0)) if scale is None else np.asarray(scale, float)
    lam, V, keep, d = kept_space(G, d, rtol)
    inv = np.where(keep, 1.0 / np.where(keep, lam, 1.0), 0.0)
    Ginv = np.einsum("gij,gj,gkj->gik", V, inv, V) / d[:, :, None] / d[:, None, :]
    theta = np.einsum("gij,gj->gi", Ginv, h)
    return theta, Ginv, keep.sum(axis=-1)


def lin_cv(D: FitData, Gw, hw, Gu, hu, S0w, S0u, scale: np.ndarray | None = None, rtol: float = 1e-10):
    """Fold fits and held-out block scores from block statistics (B, g, k, k) / (B, g, k);
    ``scale`` (g, k): the parameters' sizes the min-norm solve weighs, ``rtol`` its cut
    (:func:`solve_groups`)."""
    K, bf = D.K, D.bfold
    Gt, ht = Gw.sum(axis=0), hw.sum(axis=0)
    theta = np.zeros((K,) + ht.shape)
    for f in range(K):
        m = bf == f
        theta[f] = solve_groups(Gt - Gw[m].sum(axis=0), ht - hw[m].sum(axis=0), rtol=rtol, scale=scale)[0]
    tb = theta[bf]
    Sw = S0w - 2 * np.einsum("bgk,bgk->b", tb, hw) + np.einsum("bgk,bgkl,bgl->b", tb, Gw, tb)
    Su = S0u - 2 * np.einsum("bgk,bgk->b", tb, hu) + np.einsum("bgk,bgkl,bgl->b", tb, Gu, tb)
    th_all, Ginv, rank = solve_groups(Gt, ht, rtol=rtol, scale=scale)
    Sall = float(S0w.sum() - 2 * np.einsum("gk,gk->", th_all, ht) + np.einsum("gk,gkl,gl->", th_all, Gt, th_all))
    return Sw, Su, th_all, Ginv, rank, Sall


def sep_stats(D: FitData, X: np.ndarray, y: np.ndarray):
    """Per-channel (separable) block statistics: X (n,N,k), y (n,N) -> Gw, hw, Gu, hu."""
    k = X.shape[2]
    B, N = D.B, D.N
    Gu = np.empty((B, N, k, k))
    if k <= 3:
        for a in range(k):
            for c in range(a, k):
                v = D.bsum(X[:, :, a] * X[:, :, c])
                Gu[:, :, a, c] = v
                Gu[:, :, c, a] = v
        hu = D.bsum(X * y[:, :, None])
    else:
        # many columns: a batched matrix product per block (the k^2 / 2 column products over
        # all samples would dominate a long recording)
        hu = np.empty((B, N, k))
        ends = np.append(D.bstart[1:], D.n)
        for bi, (a, e) in enumerate(zip(D.bstart, ends)):
            Xb = X[a:e].transpose(1, 2, 0)                      # (N, k, n_b)
            Gu[bi] = Xb @ Xb.transpose(0, 2, 1)
            hu[bi] = (Xb @ y[a:e].T[:, :, None])[:, :, 0]
    wch = D.W[0]
    return Gu * wch[None, :, None, None], hu * wch[None, :, None], Gu, hu


def joint_stats(D: FitData, Xr: np.ndarray, yr: np.ndarray):
    """One group, rows (n, R, P) with weights D.W (n, R)."""
    n, R, P = Xr.shape
    sw = np.sqrt(D.W)
    Xw = Xr * sw[:, :, None]
    yw = yr * sw
    Gw = np.empty((D.B, 1, P, P))
    Gu = np.empty((D.B, 1, P, P))
    hw = D.bsum(np.einsum("trp,tr->tp", Xw, yw))[:, None, :]
    hu = D.bsum(np.einsum("trp,tr->tp", Xr, yr))[:, None, :]
    ends = np.append(D.bstart[1:], n)
    for bi, (a, e) in enumerate(zip(D.bstart, ends)):
        A = Xw[a:e].reshape(-1, P)
        Gw[bi, 0] = A.T @ A
        A = Xr[a:e].reshape(-1, P)
        Gu[bi, 0] = A.T @ A
    return Gw, hw, Gu, hu


def jig_rows(D: FitData, X: np.ndarray) -> np.ndarray:
    """Per-channel columns X (n,N,k) -> projected joint rows (n, M, N k)."""
    Q = D.Qp[D.pose]                                     # (n,M,N)
    n, N, k = X.shape
    return np.einsum("tmi,tij->tmij", Q, X).reshape(n, Q.shape[1], N * k)


def fit_cut(D: FitData, X: np.ndarray) -> tuple[np.ndarray | None, float]:
    """The Jacobi scale (1, N k) -- or None, sqrt(diag G) -- and the cut ``rtol`` with which
    :func:`linear_fit` solves for the per-channel columns X (n, N, k): with a reference each
    channel alone, rank cut 1e-10; jig-free all channels at once, the parameters weighed by their
    unprojected columns' norms (the smallest change of the readings themselves), cut SEEN_MIN."""
    if D.Qp is None:
        return None, 1e-10
    return np.sqrt(np.einsum("tnk,tnk->nk", X, X)).reshape(1, -1), SEEN_MIN


def seen_space(D: FitData, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The directions of the per-channel columns X (n, N, k) that the data see, as
    :func:`linear_fit` scales them: (V (g, P, P) eigenvectors of the scaled normal matrix,
    seen (g, P) bool, d (g, P) the scale), per channel (g = N, P = k) with a reference, one
    group (g = 1, P = N k) jig-free.  Seen: kept by the fit's cut (:func:`kept_space`) and,
    jig-free, keeping at least SEEN_MIN of its change of the readings through the poses'
    projection (energy; the cut is relative to the best-seen direction, and on six face poses
    jig-free every misalignment keeps < 6e-4 of its change, yet the fit kept a 95 deg tilt)."""
    scale, rtol = fit_cut(D, X)
    n, N, k = X.shape
    if D.Qp is None:
        # per channel: its constant weight changes neither the scaled matrix nor its kept space
        G = np.einsum("tnk,tnl->nkl", X, X)
        lam, V, keep, d = kept_space(G, np.sqrt(np.maximum(np.einsum("nkk->nk", G), 0.0)), rtol)
        return V, keep, d
    Xr = jig_rows(D, X)
    Xw = Xr * np.sqrt(D.W)[:, :, None]
    lam, V, keep, d = kept_space(np.einsum("trp,trq->pq", Xw, Xw)[None], scale, rtol)
    Z = V[0] / d[0][:, None]                                   # the eigen-combinations, unscaled
    kept = np.einsum("trp,pj->trj", Xr, Z)
    whole = np.einsum("tnk,nkj->tnj", X, Z.reshape(N, k, -1))
    share = np.einsum("trj,trj->j", kept, kept) / np.maximum(np.einsum("tnj,tnj->j", whole, whole), 1e-300)
    return V, keep & (share >= SEEN_MIN)[None], d


def linear_fit(D: FitData, X: np.ndarray, y: np.ndarray, S0w, S0u):
    """CV of the per-channel linear columns X (n,N,k) on the target y (n,N).
    Returns Sw, Su, theta (N,k), cov (N,k,k), n_params, delta (n,N)."""
    n, N, k = X.shape
    if D.Qp is None:
        Gw, hw, Gu, hu = sep_stats(D, X, y)
        Sw, Su, th, Ginv, rank, Sall = lin_cv(D, Gw, hw, Gu, hu, S0w, S0u)
        theta, cov = th, Ginv
        npar = int(rank.sum())
    else:
        Xr = jig_rows(D, X)
        yr = D.rows(y)
        Gw, hw, Gu, hu = joint_stats(D, Xr, yr)
        # the directions the poses' angles absorb leave parameters the data do not fix: of those
        # that fit, the smallest change of the readings themselves (the unprojected columns' norms;
        # one pose level along z had put 3.4e4 counts on x, whose column the projection nearly emptied)
        # (a combination of which the projection leaves less than SEEN_MIN of the readings' change
        # is not fixed either: a board held in one orientation had put -1.6 m/s^2 of offset on y
        # and +5857 % of gain on x, on directions that kept 1e-6..6e-5 of their change)
        scale, rtol = fit_cut(D, X)
        Sw, Su, th, Ginv, rank, Sall = lin_cv(D, Gw, hw, Gu, hu, S0w, S0u, scale, rtol=rtol)
        theta = th[0].reshape(N, k)
        full = Ginv[0]
        cov = np.stack([full[i * k:(i + 1) * k, i * k:(i + 1) * k] for i in range(N)])
        npar = int(rank.sum())
    dof = max(D.n * D.R - npar, 1)
    cov = cov * max(1.0, Sall / dof)
    delta = np.einsum("tnk,nk->tn", X, theta)
    return Sw, Su, theta, cov, npar, delta


class Candidate:
    name = ""

    def skip(self, D: FitData) -> str | None:
        return None

    def cv(self, D: FitData, y: np.ndarray, pcur: np.ndarray, S0w, S0u) -> Cand:
        raise NotImplementedError

    def refit(self, D: FitData, y: np.ndarray, pcur: np.ndarray, like: Cand) -> Cand:
        """The all-data fit of ``y`` in the form ``like`` (a fit of this effect) took: where the
        effect chooses among forms by the data (a drift's ramp or path), the form is kept, so
        that "can this fit take that change" asks the fitted form, not whichever form the
        new target selects."""
        S0w, S0u = block_ss(D, D.rows(y))
        return self.cv(D, y, pcur, S0w, S0u, folds=False)


class LinearCandidate(Candidate):
    pname = ""

    def columns(self, D: FitData) -> np.ndarray:
        raise NotImplementedError

    def to_params(self, D: FitData, theta: np.ndarray, cov: np.ndarray) -> tuple[dict, dict]:
        sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
        return {self.pname: theta[:, 0]}, {self.pname: sd[:, 0]}

    def param_columns(self, D: FitData, params: dict) -> tuple[np.ndarray, dict] | None:
        """The per-channel columns X (n, N, k) the fit that gave ``params`` solved for, and for
        each fitted parameter the map A from a channel's coefficients theta_i (k,) to its values:
        A (N, k) for one value a channel (value_i = A_i . theta_i), (N, k, m) for m values
        (value_ic = A_i[:, c] . theta_i); None where the effect's fit is of another form.
        Default: one column a channel, the parameter ``pname`` (plus a constant)."""
        X = self.columns(D)
        return (X, {self.pname: np.ones((D.N, 1))}) if X.ndim == 3 and X.shape[2] == 1 else None

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        X = self.columns(D)
        Sw, Su, theta, cov, k, delta = linear_fit(D, X, y, S0w, S0u)
        p, s = self.to_params(D, theta, cov)
        return Cand(self.name, k, Sw, Su, delta, p, s)


class Shifter:
    """x(t + tau) per channel along a cubic spline per run of samples contiguous in time
    (clamped at the run's ends)."""

    def __init__(self, D: FitData, x: np.ndarray):
        n, N = x.shape
        self.x = x
        self.tg = D.tg
        C = np.zeros((4, n, N))
        C[3] = x
        # runs of samples contiguous in time (a pose label change without a time gap is motion
        # going on: the rest -> travel of a linear actuator)
        brk = np.flatnonzero(np.diff(D.tg) > 1.5 * D.h) + 1
        lo = np.r_[0, brk]
        hi = np.r_[brk, n]
        self.ilo = np.repeat(lo, hi - lo)
        self.ihi = np.repeat(hi, hi - lo) - 1                        # last sample of the run
        for a, b in zip(lo, hi):
            L = b - a
            if L < 2:
                continue
            xs = x[a:b]
            if np.all(xs == xs[0]):
                continue
            ts = D.tg[a:b]
            if L >= 4:
                C[:, a:b - 1] = CubicSpline(ts, xs, axis=0).c
            else:
                C[2, a:b - 1] = np.diff(xs, axis=0) / np.diff(ts)[:, None]
        self.C = C
        self.tlo = D.tg[self.ilo]
        self.thi = D.tg[self.ihi]

    def _eval(self, tt: np.ndarray, cols: np.ndarray | None) -> np.ndarray:
        k = np.searchsorted(self.tg, tt, side="right") - 1
        k = np.clip(k, self.ilo, np.maximum(self.ilo, self.ihi - 1))
        dx = tt - self.tg[k]
        if cols is None:
            c = self.C[:, k, :]
            dx = dx[:, None]
        else:
            c = self.C[:, k, cols]
        return ((c[0] * dx + c[1]) * dx + c[2]) * dx + c[3]

    def delta(self, tau: np.ndarray) -> np.ndarray:
        tau = np.asarray(tau, float)
        if tau.ndim == 0 or np.all(tau == tau.flat[0]):
            tv = float(tau.flat[0])
            if tv == 0:
                return np.zeros_like(self.x)
            tt = np.clip(self.tg + tv, self.tlo, self.thi)
            return self._eval(tt, None) - self.x
        n, N = self.x.shape
        tt = np.clip(self.tg[:, None] + tau[None, :], self.tlo[:, None], self.thi[:, None])
        k = np.searchsorted(self.tg, tt.ravel(), side="right").reshape(n, N) - 1
        k = np.clip(k, self.ilo[:, None], np.maximum(self.ilo, self.ihi - 1)[:, None])
        dx = tt - self.tg[k]
        c = self.C[:, k, np.arange(N)[None, :]]
        return ((c[0] * dx + c[1]) * dx + c[2]) * dx + c[3] - self.x


class SearchCandidate(Candidate):
    """One scalar parameter u per channel (in samples); delta(D, u (N,)) -> (n, N)."""

    grid = SKEW_GRID
    lower = -math.inf

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: static poses only, no reference of the motion"
        if not is_moving(D):
            return "needs motion in the reference (time effects show only while the readings change)"
        return None

    def prepare(self, D: FitData, pcur: np.ndarray):
        raise NotImplementedError

    def delta(self, u: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def to_params(self, D, u, su) -> tuple[dict, dict]:
        raise NotImplementedError

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        self.prepare(D, pcur)
        N, K, bf = D.N, D.K, D.bfold
        wch = D.W[0]

        def block_ss_at(points):
            """Unweighted block SS per channel (G, B, N) with every channel at each grid point."""
            out = np.empty((len(points), D.B, N))
            for gi, u in enumerate(points):
                R = y - self.delta(np.full(N, u))
                out[gi] = D.bsum(R * R)
            return out

        grid = np.asarray(self.grid, float)
        Sg = block_ss_at(grid)
        # a minimum at an end of the grid lies beyond it (a logger's skew of 100 ms and more, a
        # low-pass far below the motion's band): the grid grows there by SEARCH_GROW per point, up
        # to SEARCH_MAX_S
        limit = SEARCH_MAX_S / D.h
        while True:
            j = np.argmin(Sg.sum(axis=1), axis=0)
            grow = []
            if np.any(j == grid.size - 1) and grid[-1] > 0 and grid[-1] * SEARCH_GROW <= limit:
                grow.append(grid[-1] * SEARCH_GROW)
            if np.any(j == 0) and grid[0] < 0 and -grid[0] * SEARCH_GROW <= limit:
                grow.append(grid[0] * SEARCH_GROW)
            if not grow:
                break
            grid = np.concatenate([grid, grow])
            Sg = np.concatenate([Sg, block_ss_at(grow)])
            o = np.argsort(grid)
            grid, Sg = grid[o], Sg[o]
        tot = Sg.sum(axis=1)                                # (G,N)
        cols = np.arange(N)

        def parabola(x3, y3):
            A = np.vstack([x3 ** 2, x3, np.ones(3)]).T
            try:
                a2, a1, _ = np.linalg.solve(A, y3)
            except np.linalg.LinAlgError:
                return None, 0.0
            if not a2 > 0:
                return None, 0.0
            return float(np.clip(-a1 / (2 * a2), x3.min(), x3.max())), float(a2)

        def refine(mask_blocks, obj):
            """Grid minimum, then two parabolic steps, per channel, on the blocks in mask_blocks.
            Returns u (N,), block SS at u (B,N), curvature (N,)."""
            j = np.argmin(obj, axis=0)
            u = grid[j].astype(float)
            best_obj = obj[j, cols].copy()
            best_S = Sg[j, :, cols].T.copy()                # (B,N)
            curv = np.zeros(N)
            # three distinct grid points around the minimum (at an end of the grid: the end and its
            # two neighbours)
            c0 = np.clip(j - 1, 0, grid.size - 3)
            pts = [[(float(grid[c]), float(obj[c, i])) for c in range(c0[i], c0[i] + 3)] for i in range(N)]
            for _ in range(2):
                cand = u.copy()
                for i in range(N):
                    near = []
                    for p in sorted(pts[i], key=lambda p: p[1]):
                        if all(abs(p[0] - q[0]) > 1e-12 for q in near):
                            near.append(p)
                        if len(near) == 3:
                            break
                    if len(near) < 3:
                        continue
                    x3 = np.array([p[0] for p in near])
                    v, a2 = parabola(x3, np.array([p[1] for p in near]))
                    if v is not None:
                        cand[i] = max(v, self.lower)
                        curv[i] = a2
                if np.all(cand == u):
                    break
                R = y - self.delta(cand)
                Sr = D.bsum(R * R)
                o = Sr[mask_blocks].sum(axis=0)
                for i in range(N):
                    pts[i].append((float(cand[i]), float(o[i])))
                better = o < best_obj
                u = np.where(better, cand, u)
                best_obj = np.where(better, o, best_obj)
                best_S[:, better] = Sr[:, better]
            return u, best_S, curv

        Sw = np.full(D.B, np.nan)
        Su = np.full(D.B, np.nan)
        if folds:
            for f in range(K):
                trn = bf != f
                _, Sb, _ = refine(trn, Sg[:, trn].sum(axis=1))
                m = bf == f
                Sw[m] = Sb[m] @ wch
                Su[m] = Sb[m].sum(axis=1)
        u, Sb_all, curv = refine(np.ones(D.B, bool), tot)
        d_all = self.delta(u)
        Sall = float(Sb_all.sum(axis=0) @ wch)
        npar = N
        scale = max(1.0, Sall / max(D.n * N - npar, 1))
        with np.errstate(divide="ignore"):
            su = np.where(curv > 0, np.sqrt(scale / np.maximum(curv * wch, 1e-300)), math.inf)
        p, s = self.to_params(D, u, su)
        return Cand(self.name, npar, Sw, Su, d_all, p, s)
