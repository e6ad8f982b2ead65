"""Static poses far off the calibration's terms fitted to them: a mislabelled or knocked pose.

The rule is calibrate's (:func:`accelcal.readings.outliers.far_poses`: a pose's residual over its noise
beyond the poses' median + OUTLIER_K robust sd), applied to what the calibration's own terms
leave of each pose's mean residual: an offset and a free sensitivity vector a channel (its gain
and misalignment), fitted to the pose means as the diagnosis scores them (jig-free, the rows
the pose angles cannot absorb), each weighted by the noise of its mean (the colour within the
poses counted).  A calibration that is merely off leaves nothing there; one pose that is not
where it is stated to be does.

How it weighs on the verdict: the verdict stays what all the poses say (a knocked pose is a
`pose_error`, and the contract's word for it), but the diagnosis of the other poses is given
beside it (``outliers.without``) and a note says when the verdict rests on the named poses
alone; ``outliers="drop"`` sets them aside (as ``calibrate --drop-outliers``).
"""
from __future__ import annotations

import numpy as np

from ..effects.fitdata import FitData
from ..readings.noise import colour_factor
from ..readings.outliers import OUTLIER_RULE, far_poses
from .prepare import kept_recordings
from .where import pose_mean_rows

__all__ = ["OUTLIER_MODES", "pose_chi", "deleted_chi", "find_outliers", "without_poses", "outlier_entry", "outlier_note"]

OUTLIER_MODES = ("name", "drop", "keep")   # name them (and diagnose without them too), set them aside, or neither


def pose_chi(D: FitData, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each static pose's mean residual over its noise against the calibration's terms fitted
    without it.

    Parameters
    ----------
    D : FitData
    e : ndarray, shape (n, N)
        The residual of the given calibration (counts).

    Returns
    -------
    poses : ndarray of int, shape (P',)
        The global pose indices that hold samples.
    chi : ndarray, shape (P',)
        sqrt(sum_j (d_pj / sem_pj)^2) (dimensionless): d_p is what an offset and a sensitivity
        vector per channel (weighted least squares on the pose means r_pj, each over its noise
        sem_pj: white, widened by the colour within the poses or within this pose, whichever is more) leave of pose p's mean residual
        row when p is not among the poses fitted.  The fit is trimmed first: the pose with the
        largest such residual is left out, one at a time, up to a quarter of the poses and while
        the rest keep as many degrees of freedom as parameters; the poses left out are then
        judged by the fit of the others, the rest by the deleted residual (so that one knocked
        pose pulls no fit that the others are judged by: in the fit of all poses, a 3 deg
        knock among 14 had put the others at 5-215 x their noise, and itself at 860 x, within
        the rule's reach of them).
    """
    poses, m, v, r2 = pose_mean_rows(D, e)
    if poses.size == 0:
        return poses, np.zeros(0)
    # the colour pooled over the poses, or a pose's own where its mean wanders further (a rest of
    # 52 s among poses of a few seconds: 3.9 x white noise against the poses' 1.4 x)
    v = v * np.fmax(colour_factor(r2)[None, :] ** 2, r2)
    N = D.N
    F = np.array([D.f[D.pose == p].mean(axis=0) for p in poses])          # (P', 3) m/s^2
    C = np.zeros((poses.size, N, 4 * N))
    for i in range(N):
        C[:, i, 4 * i] = 1.0
        C[:, i, 4 * i + 1:4 * i + 4] = F
    A = C if D.Qp is None else np.einsum("pmn,pnk->pmk", D.Qp[poses], C)
    sw = 1.0 / np.sqrt(v)
    A = A * sw[:, :, None]                                                # (P', R, 4N) over the noise
    y = m * sw                                                            # (P', R)
    keep = np.ones(poses.size, bool)
    while True:
        chi = deleted_chi(A, y, keep)
        rank = np.linalg.matrix_rank(A[keep].reshape(-1, A.shape[2]))
        worst = int(np.argmax(np.where(keep, chi, -np.inf)))
        if (np.count_nonzero(~keep) >= poses.size // 4
                or (np.count_nonzero(keep) - 1) * y.shape[1] - rank < rank):
            return poses, chi
        keep[worst] = False


def deleted_chi(A: np.ndarray, y: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """(P,) each pose's residual against the least-squares fit of the poses ``keep`` other than
    itself, over its own spread (A (P, R, k), y (P, R), both over the noise; studentized, so
    that a pose the fit holds with few others, whose prediction is uncertain, is judged by that
    uncertainty too): for a pose left out, d = y_p - A_p theta against I + A_p M A_p^T
    (M = (A^T A)^+ of the poses fitted); for a pose fitted, its in-sample residual r_p against
    I - H_pp (the hat matrix's block: the same figure as the fit without it), or r_p alone where
    the pose by itself fixes a direction of theta (I - H_pp singular: the others cannot judge it)."""
    P, R, k = A.shape
    Ak = A[keep].reshape(-1, k)
    M = np.linalg.pinv(Ak.T @ Ak)
    theta = M @ (Ak.T @ y[keep].ravel())
    r = y - np.einsum("prk,k->pr", A, theta)
    out = np.sqrt(np.sum(r * r, axis=1))
    for p in range(P):
        AMA = A[p] @ M @ A[p].T
        V = np.eye(R) - AMA if keep[p] else np.eye(R) + AMA
        if np.linalg.eigvalsh(V).min() > 1e-9:
            out[p] = float(np.sqrt(max(r[p] @ np.linalg.solve(V, r[p]), 0.0)))
    return out


def find_outliers(D: FitData, e: np.ndarray) -> dict | None:
    """The poses far off (:func:`pose_chi`, :func:`accelcal.readings.outliers.far_poses`): a dict with
    ``poses`` (global indices, worst first), ``chi`` (theirs) and ``others_worst`` (the largest
    chi of the rest), or None where none is."""
    poses, chi = pose_chi(D, e)
    out = far_poses(chi)
    if out.size == 0:
        return None
    rest = np.setdiff1d(np.arange(chi.size), out)
    return {"poses": poses[out], "chi": chi[out], "others_worst": float(chi[rest].max()) if rest.size else None}


def pose_rows(D: FitData, recs: list, p: int) -> tuple[int, np.ndarray]:
    """Recording index (into ``recs``) and its rows that global pose ``p`` covers: the samples
    the diagnosis used and, where the recording labels its poses, every row of that label."""
    k = int(D.pose_labels[p][0])
    ri = kept_recordings(recs)[k]
    rec = recs[ri]
    rows = np.searchsorted(rec.t, D.t[D.pose == p])
    drop = np.zeros(rec.n_samples, bool)
    drop[rows] = True
    if rec.has_pose():
        labels = np.unique(rec.pose[rows])
        drop |= np.isin(rec.pose, labels[labels >= 0])
    return ri, drop


def without_poses(D: FitData, recs: list, found: dict) -> list:
    """The recordings ``recs`` without the rows of the poses ``found["poses"]`` (:func:`pose_rows`)."""
    drops = {}
    for p in found["poses"]:
        ri, d = pose_rows(D, recs, int(p))
        drops[ri] = drops.get(ri, np.zeros_like(d)) | d
    return [rec.select(~drops[i]) if i in drops else rec for i, rec in enumerate(recs)]


def pose_name(D: FitData, recs: list, p: int) -> str:
    """A pose as its recording names it: its label, else ``static@T0-T1s``; prefixed with the
    recording's source where there are several."""
    ri, drop = pose_rows(D, recs, p)
    rec = recs[ri]
    t = D.t[D.pose == p]
    name = (str(int(rec.pose[np.flatnonzero(drop)[0]])) if rec.has_pose()
            else f"static@{t[0]:.2f}-{t[-1]:.2f}s")
    return f"{rec.source}:{name}" if len(recs) > 1 else name


def outlier_entry(D: FitData, recs: list, found: dict, dropped: bool, without: dict | None = None) -> dict:
    """The JSON's ``outliers``: the rule, each pose named (name, residual over its noise, time
    span in s), the others' worst, whether they were set aside and, when kept, the diagnosis of
    the others (``without``: verdict, model effects, shrink, ambiguous_with)."""
    poses = []
    for p, c in zip(found["poses"], found["chi"]):
        t = D.t[D.pose == p]
        poses.append({"name": pose_name(D, recs, int(p)), "residual_over_noise": float(c),
                      "t_start_s": float(t[0]), "t_stop_s": float(t[-1])})
    out = {"rule": OUTLIER_RULE, "fit": "an offset and a sensitivity vector per channel fitted to the poses' means",
           "poses": poses, "others_worst_residual_over_noise": found["others_worst"], "dropped": bool(dropped),
           "without": None}
    if without is not None:
        out["without"] = {"verdict": without["verdict"], "model_effects": list(without["model"]["effects"]),
                          "shrink": without["model"]["shrink"], "ambiguous_with": list(without["ambiguous_with"])}
    return out


def outlier_note(entry: dict, verdict: str) -> str:
    """One line on the poses named: who, how far, and what the verdict is without them."""
    named = "; ".join(f"pose {p['name']} (t = {p['t_start_s']:.6g}..{p['t_stop_s']:.6g} s), "
                      f"{p['residual_over_noise']:.3g} x its noise" for p in entry["poses"])
    rest = entry["others_worst_residual_over_noise"]
    text = (f"{len(entry['poses'])} static pose(s) lie far off the calibration's terms fitted to the poses "
            f"({entry['rule']}): {named}" + (f"; the others at most {rest:.3g} x" if rest is not None else "")
            + ": a mislabelled or knocked pose, or one not held still")
    if entry["dropped"]:
        return text + "; set aside (--drop-outliers): the diagnosis is of the other poses"
    wo = entry["without"]
    model = " + ".join(wo["model_effects"]) or wo["verdict"]
    if wo["verdict"] != verdict:
        said = (f"the verdict {verdict} rests on them: without them it is {wo['verdict']} (model {model}, "
                f"shrink {wo['shrink']:.3f})")
    else:
        said = f"without them the verdict is the same (model {model}, shrink {wo['shrink']:.3f})"
    return text + f"; {said}; they are kept (--drop-outliers sets them aside)"
