"""pose_error: the stated reference orientation of static poses is off by a small rotation."""
from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ..sensor import Context, evaluate, rotation_matrix
from ..spec import Param
from .base import Effect, FitParam, as_float_array, random_perpendicular, unit_rows
from .fitdata import FitData, poses_on_axes, tangent_basis, unit_rows3
from .fitting import Cand, Candidate, lin_cv


class PoseError(Candidate, Effect):
    name = "pose_error"
    varies_by_pose = True
    tell_apart = "a pose repeated after re-placing the sensor (a placement error changes, an error of the sensor does not)"
    tells_from = ("misalignment", "gain", "offset", "nonlinearity", "bias_drift")
    summary = "the stated reference orientation of static poses is off by a small rotation"
    doc = ("For each static pose label p, f_true = Exp(rot_p) f_stated (rot_p in rad, body axes): "
           "the simulator writes f_stated = Exp(rot_p)^T f_true in the reference f columns of the "
           "pose's samples and leaves the readings alone; by default rot_p tilts the pose's gravity "
           "direction by angle_deg in a random direction.  apply() (the diagnosis) predicts the "
           "readings from the recorded reference rotated back, Exp(rot_p) f_recorded.")
    stage = "reference"
    params = (
        Param("angle_deg", 1.0, "deg", "tilt of each static pose's stated orientation", "float", minimum=0.0),
    )
    fit = (
        FitParam("labels", "pose", "-", "pose labels the rotations belong to", free=False),
        FitParam("rot", "pose3", "rad", "rotation from the stated to the true orientation"),
    )

    free_per_pose = True

    def mimics_calibration(self, fit):
        # a tilt of each pose moves the other channels' readings of that pose: it takes their
        # offsets and the axes' misalignment at once (six poses held once against a nominal
        # calibration: 5.6 deg "tilts" that were 40 mg offsets and a 2.9 deg turn of the axes)
        return True

    def looks_like(self, D):
        # on the six faces of a box a misalignment of the axes is a tilt of each pose to first order
        return ("misalignment",) if poses_on_axes(D) else ()

    def _resolve(self, spec, ctx, rng):
        pose = np.asarray(ctx.truth.pose)
        labels = np.unique(pose[pose >= 0])
        f = np.asarray(ctx.truth.f, float)
        rot = np.zeros((labels.size, 3))
        ang = math.radians(spec["angle_deg"])
        for j, lab in enumerate(labels):
            fm = f[pose == lab].mean(axis=0)
            if np.linalg.norm(fm) > 1e-9:
                ax = random_perpendicular(unit_rows(fm[None, :]), rng)[0]
            else:
                ax = unit_rows(rng.standard_normal((1, 3)))[0]
            rot[j] = ax * ang
        return {"labels": labels.astype(np.int64), "rot": rot}

    def identity(self, ctx):
        pose = np.asarray(ctx.truth.pose)
        labels = np.unique(pose[pose >= 0])
        return {"labels": labels.astype(np.int64), "rot": np.zeros((labels.size, 3))}

    def _rotate(self, f: np.ndarray, p: Mapping[str, Any], ctx: Context, inverse: bool) -> np.ndarray:
        pose = np.asarray(ctx.truth.pose)
        out = np.array(f, float, copy=True)
        labels = np.asarray(p["labels"]).astype(np.int64)
        R = rotation_matrix(np.asarray(p["rot"], float).reshape(-1, 3))
        for j, lab in enumerate(labels.tolist()):
            sel = pose == lab
            if np.any(sel):
                # rows: f_true_row = f_stated_row @ R^T; f_stated_row = f_true_row @ R
                out[sel] = out[sel] @ (R[j] if inverse else R[j].T)
        return out

    def apply_reference(self, f_ref, p, ctx):
        return self._rotate(f_ref, p, ctx, inverse=True)

    def apply(self, ctx, p):
        f_corr = self._rotate(np.asarray(ctx.truth.f, float), p, ctx, inverse=False)
        return evaluate(ctx.truth, ctx.state, f=f_corr)

    # -- fit to a residual (the diagnosis) ------------------------------------

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: the poses have no stated orientation"
        if not np.any(D.pose_stated >= 0):
            return "needs static poses with a stated reference f (pose labels and f_*)"
        return None

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        ps = D.pose_stated
        P = len(D.pose_labels)
        E = np.zeros((P, 2, 3))
        for p in range(P):
            sel = ps == p
            if sel.any():
                E[p] = tangent_basis(unit_rows3(D.f[sel].mean(axis=0)))
        on = ps >= 0
        X = np.zeros((D.n, D.N, 2))
        fs = np.cross(D.f[on][:, None, :], D.s[None, :, :])       # f x s (m,N,3)
        X[on] = np.einsum("tkc,tnc->tnk", E[ps[on]], fs)
        if D.gain_t is not None:
            X *= D.gain_t[:, :, None]
        wch = D.W[0]
        bp = ps[D.bstart]                                           # each block lies in one pose (or none)
        Gw = np.zeros((D.B, P, 2, 2))
        Gu = np.zeros((D.B, P, 2, 2))
        hw = np.zeros((D.B, P, 2))
        hu = np.zeros((D.B, P, 2))
        XXw = np.einsum("tnk,tnl,n->tkl", X, X, wch)
        XXu = np.einsum("tnk,tnl->tkl", X, X)
        Xyw = np.einsum("tnk,tn,n->tk", X, y, wch)
        Xyu = np.einsum("tnk,tn->tk", X, y)
        has = bp >= 0
        bi = np.flatnonzero(has)
        Gw[bi, bp[bi]] = D.bsum(XXw)[bi]
        Gu[bi, bp[bi]] = D.bsum(XXu)[bi]
        hw[bi, bp[bi]] = D.bsum(Xyw)[bi]
        hu[bi, bp[bi]] = D.bsum(Xyu)[bi]
        Sw, Su, th, Ginv, rank, Sall = lin_cv(D, Gw, hw, Gu, hu, S0w, S0u)
        npar = int(rank.sum())
        scale = max(1.0, Sall / max(D.n * D.R - npar, 1))
        rot = np.einsum("pk,pkc->pc", th, E)
        sd = np.sqrt(np.maximum(np.einsum("pkc,pkl,plc->pc", E, Ginv * scale, E), 0.0))
        delta = np.zeros((D.n, D.N))
        delta[on] = np.einsum("tnk,tk->tn", X[on], th[ps[on]])
        labels = [int(L) for _, L in D.pose_labels]
        recs = [int(rr) for rr, _ in D.pose_labels]
        keep = [p for p in range(P) if np.any(ps == p)]
        params = {"labels": np.array([labels[p] for p in keep], np.int64), "rot": rot[keep],
                  "recording": np.array([recs[p] for p in keep], np.int64)}
        return Cand(self.name, npar, Sw, Su, delta, params, {"rot": sd[keep]})

    # -- the benchmark --------------------------------------------------------

    bench_size = 0.1

    def bench_spec(self, m, z, aux):
        return {"angle_deg": float(m)}

    def bench_pair(self, est, truth, sig):
        lab_e = list(as_float_array(est["labels"]).astype(int))
        lab_t = list(np.asarray(truth["labels"]).astype(int))
        re_ = as_float_array(est["rot"]).reshape(-1, 3)
        e = np.array([re_[lab_e.index(L)] if L in lab_e else np.zeros(3) for L in lab_t])
        return e, np.asarray(truth["rot"], float)

    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        a = np.degrees(np.linalg.norm(p["rot"], axis=1))
        if not a.size:
            return "no stated pose"
        return f"stated pose orientations off by up to {a.max():.3g} deg (median {np.median(a):.3g} deg)"
