"""Results of the static and lever-arm fits, as objects."""
from __future__ import annotations

import os

from dataclasses import dataclass

import numpy as np

from ..io.calibration import Calibration
from ..readings.static import PoseSet
from .checks import static_force


@dataclass
class StaticFit:
    """Result of a static calibration (known poses or jig-free).

    offsets (N,), sensitivity (N,3) counts per m/s^2, f (P,3) the pose forces used
    (reference or estimated); cov: per channel covariance of its parameters in
    the order [b, s_x, s_y, s_z, beta, gamma] (rows/cols of fixed parameters are
    zero); residual (P,N) counts; chi2, dof; method; poses (PoseSet).
    """

    method: str
    jigfree: bool
    offsets: np.ndarray
    sensitivity: np.ndarray
    f: np.ndarray
    cov: np.ndarray            # (N, 6, 6)
    residual: np.ndarray       # (P, N)
    chi2: float
    dof: int
    poses: PoseSet
    temp_ref_c: float | None = None
    offset_tc: np.ndarray | None = None
    gain_tc: np.ndarray | None = None
    pose_cov: np.ndarray | None = None   # (P, 2, 2) tangent-plane covariance of estimated pose directions (rad^2)
    jig_accuracy_deg: float = 0.0        # stated jig accuracy of the references' priors (0: exact references)
    jig_hint_deg: float | None = None    # jig accuracy 0 but chi2/dof > JIG_HINT_CHI2: the one that gives chi2/dof = 1
    n_prior: int = 0                     # prior rows in chi2 and dof (2 a pose with jig accuracy > 0)
    jig_estimate: dict | None = None     # the jig accuracy estimated from the poses' scatter (jig_estimate.py)

    @property
    def offset_sigma(self) -> np.ndarray:
        return np.sqrt(self.cov[:, 0, 0])

    @property
    def sensitivity_sigma(self) -> np.ndarray:
        return np.sqrt(np.stack([self.cov[:, k, k] for k in (1, 2, 3)], axis=1))

    @property
    def offset_tc_sigma(self) -> np.ndarray:
        return np.sqrt(self.cov[:, 4, 4])

    @property
    def gain_tc_sigma(self) -> np.ndarray:
        return np.sqrt(self.cov[:, 5, 5])

    def rms_per_pose(self) -> np.ndarray:
        return np.sqrt(np.mean(self.residual ** 2, axis=1))

    def rms_per_channel(self) -> np.ndarray:
        return np.sqrt(np.mean(self.residual ** 2, axis=0))


@dataclass
class PositionFit:
    """Lever-arm estimate: delta_r (N,3) m (zero along unobservable directions),
    cov (N,3,3); per channel the principal directions (N,3,3 rows), their 1-sigma
    (N,3) m and whether each is observable (sigma <= tol_m); n_samples used."""

    delta_r: np.ndarray
    cov: np.ndarray
    directions: np.ndarray
    sigma: np.ndarray
    observable: np.ndarray
    n_samples: int
    tol_m: float
    residual_rms: np.ndarray   # (N,) counts after the fit

    def report(self) -> list[dict]:
        out = []
        for i in range(self.delta_r.shape[0]):
            out.append({
                "channel": i,
                "observable_directions": int(self.observable[i].sum()),
                "sigma_m": [float(v) if np.isfinite(v) else None for v in self.sigma[i]],
                "directions": [[float(v) for v in d] for d in self.directions[i]],
                "delta_r_m": [float(v) for v in self.delta_r[i]],
            })
        return out


def pose_names(info: list[dict]) -> list:
    """Labels for poses_used / residual_rms_per_pose: the recording's pose label
    (prefixed with the file name when there are several recordings), or
    ``static@T0-T1s`` for detected intervals."""
    sources = {d.get("source") for d in info}
    out: list = []
    for p, d in enumerate(info):
        if d.get("label") is not None:
            name = d["label"]
        elif "t_start" in d:
            name = f"static@{d['t_start']:.2f}-{d['t_stop']:.2f}s"
        else:
            name = p
        if len(sources) > 1:
            name = f"{os.path.basename(str(d.get('source')))}:{name}"
        out.append(name)
    return out


def set_aside_entry(d: dict) -> dict:
    """A pose left out of the fit, for the calibration's ``extra.set_aside``."""
    name = f"pose {d['label']}" if d.get("label") is not None else f"static@{d['t_start']:.2f}-{d['t_stop']:.2f}s"
    return {"name": name, "source": str(d.get("source")), "reason": d["reason"],
            "t_start_s": d["t_start"], "t_stop_s": d["t_stop"], "n_samples": d["n"],
            "n_clipped": d.get("n_clipped", 0), "levels": d.get("levels", "")}


def to_calibration(device, fit: StaticFit, method: str, positions: PositionFit | None = None):
    """Build the contract's Calibration from a fit: offsets, sensitivity, 1-sigma
    uncertainties, temperature terms, residual RMS per channel and per pose (counts),
    the poses used; ``extra`` holds the details (pose forces, fit statistics,
    temperature-coefficient uncertainties, lever-arm observability)."""

    names = pose_names(fit.poses.info)
    rpp = fit.rms_per_pose()
    pose_detail = []
    for p, d in enumerate(fit.poses.info):
        e = {"name": names[p], "n_samples": int(fit.poses.n[p]),
             "f_mps2": [round(float(v), 6) for v in fit.f[p]],
             "residual_rms_counts": float(rpp[p])}
        if "t_start" in d:
            e["t_start_s"] = d["t_start"]
            e["t_stop_s"] = d["t_stop"]
        if np.isfinite(fit.poses.temp[p]):
            e["temp_c"] = float(fit.poses.temp[p])
        pose_detail.append(e)
    extra: dict = {
        "fit": {
            "model": fit.method,
            "poses": "estimated (jig-free, |f| = g)" if fit.jigfree else (
                f"estimated, the reference f as a prior (rms rotation {fit.jig_accuracy_deg:.3g} deg"
                f"{', estimated from their scatter' if fit.jig_estimate else ''}, |f| = |f_ref|)"
                if fit.jig_accuracy_deg > 0 else "reference f"),
            "gauge": ("sum_i u_i x s_i/|s_i| = 0 (Procrustes: estimated axes rotated as little as possible "
                      "from the nominal ones)") if (fit.jigfree and fit.method == "full") else (
                "none needed (the sensitivities lie along the nominal axes)" if fit.jigfree else
                "fixed by the references' priors (the jig's frame)" if fit.jig_accuracy_deg > 0
                else "fixed by the reference"),
            "chi2": float(fit.chi2), "dof": int(fit.dof),
            "uncertainty": "1-sigma from the Fisher information, inflated by chi2/dof when > 1",
        },
        "poses": pose_detail,
    }
    sens_sigma = fit.sensitivity_sigma
    held = not_fitted(device, fit)
    if held:
        extra["fit"].update(held)
        if fit.method == "offset":
            sens_sigma = np.full_like(sens_sigma, np.nan)      # not fitted: no sigma (null), not 0 (exact)
        elif fit.method == "gain":
            # the components across the nominal axis are held at 0, not fitted: null, not 0 (exact)
            sens_sigma = np.where(np.asarray(device.axes, float) == 0.0, np.nan, sens_sigma)
    if fit.poses.set_aside:
        extra["set_aside"] = [set_aside_entry(d) for d in fit.poses.set_aside]
    if not fit.jigfree:
        extra["fit"]["jig_accuracy_deg"] = float(fit.jig_accuracy_deg)
        if fit.n_prior:
            # the readings' own degrees of freedom: <= 0 where the poses' angles and the channel terms
            # take every reading (six poses: 18 readings, 12 terms + 12 angles), the residual ~0 by construction
            extra["fit"]["dof_readings"] = int(fit.dof - fit.n_prior)
        if fit.jig_hint_deg is not None:
            extra["fit"]["jig_accuracy_consistent_with_scatter_deg"] = float(fit.jig_hint_deg)
        if fit.jig_estimate is not None:
            extra["fit"]["jig_accuracy_estimate"] = dict(fit.jig_estimate)
            note = jig_note(fit.jig_estimate)
            if note:
                extra["fit"]["jig_accuracy_note"] = note
        if fit.jig_accuracy_deg > 0:
            extra["fit"]["uncertainty"] = (
                "1-sigma from the Fisher information of the readings and of the pose priors (each pose "
                f"direction within jig accuracy {fit.jig_accuracy_deg:.3g} deg rms of its reference; chi2 and dof "
                "include the prior terms), inflated by chi2/dof when > 1")
    if fit.jigfree:
        g = device.gravity_mps2
        fh = static_force(fit.offsets, fit.sensitivity, fit.poses.means, fit.poses.sem())
        extra["fit"]["rms_norm_error_mps2"] = float(np.sqrt(np.mean((np.linalg.norm(fh, axis=1) - g) ** 2)))
    offset_tc = gain_tc = None
    if fit.offset_tc is not None:
        offset_tc, gain_tc = fit.offset_tc, fit.gain_tc
        extra["temperature_sigma"] = {"offset_tc_counts_per_c": [float(v) for v in fit.offset_tc_sigma],
                                      "gain_tc_per_c": [float(v) for v in fit.gain_tc_sigma]}
    pos = pos_sig = None
    if positions is not None:
        N = device.n_channels
        any_obs = positions.observable.any(axis=1)
        pos = np.full((N, 3), np.nan)
        pos_sig = np.full((N, 3), np.nan)
        pos[any_obs] = device.positions[any_obs] + positions.delta_r[any_obs]
        pos_sig[any_obs] = np.sqrt(np.einsum("ikk->ik", positions.cov))[any_obs]
        extra["lever_arm"] = {
            "n_samples": positions.n_samples,
            "observable_if_sigma_below_m": positions.tol_m,
            "note": "delta_r is kept only along observable principal directions (nominal along the others); "
                    "position_sigma_m covers the observable part only",
            "channels": positions.report(),
        }
        if not any_obs.any():
            pos = pos_sig = None
    return Calibration(
        device=device.name,
        method=method,
        offsets=fit.offsets,
        sensitivity=fit.sensitivity,
        positions=pos,
        offset_sigma=fit.offset_sigma,
        sensitivity_sigma=sens_sigma,
        position_sigma=pos_sig,
        temp_ref_c=fit.temp_ref_c,
        offset_tc=offset_tc,
        gain_tc=gain_tc,
        residual_rms_per_channel=fit.rms_per_channel(),
        residual_rms_per_pose={str(n): float(r) for n, r in zip(names, rpp)},
        poses_used=names,
        extra=extra,
    )


def interval_text(est: dict) -> str:
    """An estimate's interval in words: "95 % interval 0.19-0.6 deg" ("... 0.19 deg and above" when
    its upper end is beyond the priors' range), or "" when it has none."""
    iv = est.get("interval_deg")
    if not iv:
        return ""
    lo, hi = iv
    level = f"{100 * est.get('interval_level', 0.95):g} % interval"
    return f"{level} {lo:.2g}-{hi:.2g} deg" if hi is not None else f"{level} {lo:.2g} deg and above"


def jig_note(est: dict) -> str | None:
    """The calibration's ``extra["fit"]["jig_accuracy_note"]`` (the header's opening comment carries
    it): the jig accuracy estimated from the poses' scatter and used as their priors; None where the
    estimate is not used (the references exact)."""
    if not est.get("used"):
        return None
    iv = interval_text(est)
    return (f"jig accuracy estimated from the poses' scatter: {est['deg']:.3g} deg rms"
            + (f" ({iv})" if iv else "")
            + "; the pose directions were fitted with their references as priors of that accuracy "
              "(accelcal calibrate --jig-accuracy states one instead)")


def not_fitted(device, fit: StaticFit) -> dict:
    """What the method holds at the device file's nominal instead of fitting, for the
    calibration's ``extra["fit"]``: ``not_fitted`` ({param: [channels]}, as diagnose's
    ``not_determined``) and ``not_fitted_note``; {} for ``full``.

    ``offset``: the sensitivities are the nominal k_i u_i (their sigma is then null, not 0,
    which would read as exact knowledge), and the offsets' sigmas take them as exact: a chip
    whose gain is the nominal's times (1 + e) on channel i has its offset fitted off by
    e k_i <u_i . f> (fitted minus true; <.> the weighted mean over the poses: zero for poses
    balanced about the axis, as +-x, +-y, +-z; k_i g for one pose along it), given for e = 1 %
    in ``offset_counts_per_percent_gain`` (known poses; jig-free the pose
    forces absorb part of it).  ``gain``: the sensitivity's direction stays along the nominal
    axis (the components it holds at 0 get a null sigma, not 0, which would read as exact).

    Parameters
    ----------
    device : Device
    fit : StaticFit

    Returns
    -------
    dict
    """
    N = device.n_channels
    if fit.method == "gain":
        return {"not_fitted": {"sensitivity_direction": list(range(N))},
                "not_fitted_note": "the 'gain' model keeps each sensitivity along the device file's nominal axis: "
                                   "its direction is not fitted (the components the axis holds at 0 have no "
                                   "sigma: null)"}
    if fit.method != "offset":
        return {}
    out: dict = {"not_fitted": {"sensitivity": list(range(N))},
                 "not_fitted_note": "the 'offset' model holds the sensitivities at the device file's nominal "
                                    "(counts_per_mps2 along its axes): not fitted, no sigma; the offsets' sigmas take "
                                    "them as exact"}
    if not fit.jigfree:
        proj = fit.f @ np.asarray(device.axes, float).T                      # (P, N) m/s^2
        sem = fit.poses.sem()
        w = np.where(np.isfinite(sem) & (sem > 0), 1.0 / np.maximum(sem, 1e-300) ** 2, 1.0)
        shift = 0.01 * np.asarray(device.counts_per_mps2, float) * np.sum(w * proj, axis=0) / np.sum(w, axis=0)
        out["offset_counts_per_percent_gain"] = [float(v) + 0.0 for v in shift]
        out["not_fitted_note"] += (" (a chip's gain 1 % above the nominal leaves each offset off by "
                                   "offset_counts_per_percent_gain, fitted minus true: k_i <u_i . f> / 100 over "
                                   "the poses)")
    return out
