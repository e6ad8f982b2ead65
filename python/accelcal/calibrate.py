"""Calibration estimators: known poses, jig-free (unknown poses), lever arms, temperature.

Model (shared/spec/data-contract.md, seed paper eqs. 16-19): at rest channel i reads

    m_pi = b_i + s_i . f_p (+ noise)                      pose p, specific force f_p

and with temperature ``b_i(T) = b_i + beta_i (T - T0)``,
``s_i(T) = s_i (1 + gamma_i (T - T0))``.  Every estimator works on pose means
(one row per static pose), so a recording of any length costs one vectorised
pass to reduce and a small solve afterwards.

Free parameters per channel (``method``):

``offset``  b_i only; s_i stays nominal (k_i u_i)            -- seed doc 2, 1-pose
``gain``    b_i and k_i with s_i = k_i u_i (nominal axis)      -- seed doc 2, 3-pose
``full``    b_i and the whole vector s_i                       -- seed paper, 6-pose, N-pose

Known poses (f_p given): per-channel weighted least squares, closed form.  A pose
set that cannot determine a parameter raises :class:`InputError` naming the
channel and the pose to add.

Jig accuracy (known poses): a real jig holds pose p not at the stated f_p but
rotated from it by a small error delta_p.  ``jig_accuracy_deg`` = theta states
the rms angle of that rotation (about a random axis; each axis component of
delta_p then has rms theta/sqrt(3)).  With theta > 0 the pose directions are
estimated jointly with every channel's parameters, as in the jig-free model
below, but each with its reference as a prior: per pose, the two tangent-plane
coordinates a_p of the estimated direction about the reference direction
(f_p = |f_ref,p| (d_p + T_p a_p)/|d_p + T_p a_p|, T_p an orthonormal basis
across d_p) enter as two extra residuals

    a_p / (theta / sqrt(3))

(the magnitude |f_ref,p| is kept).  One pose error then moves all of a pose's
channels together, as it does in the sensor, and the channels that see it
determine it: on the six poses +-x, +-y, +-z channel i's offset comes
essentially from the +-i pair (as in Ferraris's method) instead of absorbing
g sin(error) from the four cross poses, and on general pose sets (no pose along
most channel axes) the errors are at the bound for a jig of that accuracy
(tools/bench_calibration.py; on the six-pose set at 2 deg and more the offsets
are somewhat worse than the +-i pair mean: second-order terms from pose tilts
that only the priors set).  The priors fix the common rotation (no gauge
constraint: the result is in the jig's frame, known to about theta/sqrt(3 P)
per axis) and keep the model determined by every pose set the known-pose fit
accepts (the prior rows make the pose coordinates full rank; the channel
parameters need what they need with the poses fixed).  The
covariance is the inverse of J^T J over the reading and prior rows, chi^2 sums
both, and dof = P N - (channel parameters) as for fixed poses (2 rows and 2
parameters a pose).  As theta -> 0 the fit tends to the known-pose fit; theta =
0 (the default) is that fit exactly: ordinary weighted least squares, efficient
(at the Cramer-Rao bound) when the references are exact.  With theta = 0 and
chi^2/dof > JIG_HINT_CHI2 the fit reports the theta at which the prior model's
chi^2/dof is 1 (StaticFit.jig_hint_deg; the CLI warns with it).  Jig-free fits
ignore theta (they use no reference).

Jig-free (f_p unknown, ``|f_p| = g``): one nonlinear least-squares problem over
the channel parameters and two tangent-plane angles per pose (Levenberg-Marquardt
with an analytic Jacobian), started from an offset + gain fit.  It needs at
least 9 poses in general position for ``full`` (the readings fix the parameters
only up to an affine map of f, and |f| = g must rule it out; see _min_poses).
With ``full`` the data cannot tell a common rotation of all s_i and all f_p from
the truth, so the frame is fixed by the nominal geometry:

    GAUGE: the body frame is the one in which the orthogonal-Procrustes rotation
    from the nominal axes u_i to the estimated axis directions s_i/|s_i| is the
    identity, i.e. ``sum_i u_i x (s_i/|s_i|) = 0`` (3 equations).

The same rule holds for triads and arrays (one implementation): the estimated
axes are, as a set, rotated as little as possible from the nominal ones, and the
remaining misalignment is shared among the channels instead of being pinned on
channel 0 (imu_tk's upper-triangular choice is another valid gauge; results
differ from it by one rotation).  With ``gain`` or ``offset`` the axes are
nominal, which fixes the frame, and no gauge is needed.

Uncertainties: the covariance of the estimate is the inverse Fisher information
of the model (weights = 1/variance of each pose mean, the variance from the
pooled within-pose scatter of each channel; with a stated jig accuracy, plus the
prior rows), restricted to the gauge for jig-free ``full``.  When the fit is
worse than the noise (chi^2/dof > 1, e.g. pose errors of a jig), the covariance
is inflated by chi^2/dof (Birge ratio).

Temperature: first order about T0 = the mean pose temperature, fitted jointly with
the channel parameters (and the poses, jig-free) when the pose temperatures span
at least TEMP_MIN_SPAN_C.  Lever arms: from samples that rotate with reference f,
w and dw (rate table), per channel linear least squares for delta_r_i with the
static calibration held, reported per principal direction with its observability.

Static poses come from a recording's ``pose`` labels, or from detect_static
(windowed std against the channel noise).  See calibrate_recordings for the
entry point the command line uses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from .errors import InputError

__all__ = [
    "METHODS",
    "PoseSet",
    "StaticFit",
    "PositionFit",
    "detect_static",
    "estimate_noise",
    "pose_means",
    "poses_from_recording",
    "calibrate_known_poses",
    "calibrate_jigfree",
    "fit_known_poses",
    "fit_static",
    "fit_temperature",
    "calibrate_positions",
    "calibrate_recordings",
    "gauge_rotation",
    "static_force",
    "to_calibration",
]

METHODS = ("offset", "gain", "full")

# --- documented defaults ------------------------------------------------------
STATIC_WINDOW_S = 0.5      # window over which the moving std is taken
STATIC_THRESHOLD = 2.0     # static while every channel's window std <= this x its noise
MIN_POSE_S = 1.0           # shortest static interval kept as a pose
EDGE_SIGMA = 4.0           # static interval ends: the nearest samples this x noise off the median
MOVE_FACTOR = 3.0          # a labelled pose "moves" when a channel's std > this x its noise
MIN_RCOND = 0.02           # known poses: normalised design with a smaller sv ratio cannot determine it
MIN_RCOND_JAC = 1e-4       # nonlinear fits: column-normalised Jacobian with a smaller sv ratio (well-posed
                           # pose sets give 0.03..0.3, degenerate ones 1e-5 and below)
TEMP_MIN_SPAN_C = 1.0      # fit temperature coefficients when pose temperatures span this much
ROTATION_MIN_RADPS = 0.05  # samples with |w| above this count as rotating (lever-arm data)
POSITION_TOL_M = 1e-3      # a lever-arm direction is "observable" when its 1-sigma is below this

JIG_ACCURACY_DEG = 0.0     # stated jig accuracy of known poses (rms rotation angle of a pose error, deg):
                           # 0 = the references are exact (ordinary weighted least squares); > 0: the
                           # references are priors of that accuracy (module notes)
JIG_HINT_CHI2 = 4.0        # known poses with jig accuracy 0: above this chi2/dof, report the jig accuracy
                           # that would explain the scatter (chi2/dof = 1); the CLI prints it as a warning

_QUANT_VAR = 1.0 / 12.0    # variance of rounding to integer counts

# Body directions offered when a pose is missing, in order of preference on ties.
_CANDIDATES = (
    ("-z", (0.0, 0.0, -1.0)), ("+z", (0.0, 0.0, 1.0)),
    ("+x", (1.0, 0.0, 0.0)), ("-x", (-1.0, 0.0, 0.0)),
    ("+y", (0.0, 1.0, 0.0)), ("-y", (0.0, -1.0, 0.0)),
)


# ==============================================================================
# Pose sets
# ==============================================================================


@dataclass
class PoseSet:
    """Static poses reduced to their means.

    means (P,N) counts; n (P,) samples; std (P,N) within-pose sample std (counts);
    f_ref (P,3) reference specific force (NaN = unknown); temp (P,) mean degC (NaN
    = unknown); info: one dict a pose (source, label, first/last sample, t range).
    """

    means: np.ndarray
    n: np.ndarray
    std: np.ndarray
    f_ref: np.ndarray
    temp: np.ndarray
    info: list[dict] = field(default_factory=list)

    @property
    def n_poses(self) -> int:
        return int(self.means.shape[0])

    def channel_noise(self) -> np.ndarray:
        """(N,) pooled within-pose std per channel (counts), floored at rounding noise."""
        dof = np.maximum(self.n - 1, 0).astype(float)
        if dof.sum() <= 0:
            return np.full(self.means.shape[1], math.sqrt(_QUANT_VAR))
        var = (dof[:, None] * self.std ** 2).sum(0) / dof.sum()
        return np.sqrt(np.maximum(var, _QUANT_VAR))

    def sem(self) -> np.ndarray:
        """(P,N) standard error of each pose mean from the pooled channel noise."""
        return self.channel_noise()[None, :] / np.sqrt(np.maximum(self.n, 1))[:, None]

    @staticmethod
    def concat(sets: Sequence["PoseSet"]) -> "PoseSet":
        return PoseSet(
            means=np.concatenate([s.means for s in sets]),
            n=np.concatenate([s.n for s in sets]),
            std=np.concatenate([s.std for s in sets]),
            f_ref=np.concatenate([s.f_ref for s in sets]),
            temp=np.concatenate([s.temp for s in sets]),
            info=[d for s in sets for d in s.info],
        )


def _window_std(raw: np.ndarray, w: int) -> tuple[np.ndarray, int, int]:
    """Std of windows of about w samples at a stride: blocks of h = max(1, w // 4)
    samples, windows of k = ceil(w / h) blocks (L = k h samples, population std).

    Returns (ws (n_windows, N), h, k); window j covers samples [j h, (j + k) h).
    One pass over the data for the block sums, then cumulative sums over blocks."""
    raw = np.asarray(raw)
    n, N = raw.shape
    h = max(1, w // 4)
    k = max(1, -(-w // h))
    nb = n // h
    if nb < k:
        return np.zeros((0, N)), h, k
    ref = np.median(raw[:: max(1, n // 1000)], axis=0)       # keep the sums small
    x = (raw[: nb * h] - ref).reshape(nb, h, N)
    s1 = x.sum(axis=1, dtype=float)
    s2 = np.einsum("bhn,bhn->bn", x, x, dtype=float)
    c1 = np.concatenate([np.zeros((1, N)), np.cumsum(s1, axis=0)])
    c2 = np.concatenate([np.zeros((1, N)), np.cumsum(s2, axis=0)])
    L = k * h
    S1 = c1[k:] - c1[:-k]
    S2 = c2[k:] - c2[:-k]
    return np.sqrt(np.maximum((S2 - S1 * S1 / L) / L, 0.0)), h, k


def _window_len(device, window_s: float, n: int) -> int:
    w = int(round(window_s * device.sample_rate_hz))
    return max(3, min(w, n))


def estimate_noise(raw: np.ndarray, window: int) -> np.ndarray:
    """Per-channel noise (counts) estimated robustly from the data.

    The std of windows of about ``window`` samples is taken (see _window_std); static
    windows form the low cluster.  With s10 the 10th percentile of the window stds,
    the noise is the median of the windows whose std is below 2 x s10, times
    sqrt(L/(L-1)).  This needs at least about 10 % of the recording to be static.
    """
    ws, h, k = _window_std(raw, window)
    if ws.shape[0] == 0:
        return np.full(np.asarray(raw).shape[1], math.sqrt(_QUANT_VAR))
    s10 = np.percentile(ws, 10, axis=0)
    out = np.empty(ws.shape[1])
    for i in range(ws.shape[1]):
        col = ws[:, i]
        out[i] = np.median(col[col <= 2.0 * s10[i]]) if s10[i] > 0 else 0.0
    L = h * k
    out *= math.sqrt(L / max(L - 1, 1))
    return np.maximum(out, math.sqrt(_QUANT_VAR))


def _noise_for(device, raw: np.ndarray, window: int) -> tuple[np.ndarray, str]:
    k = np.asarray(device.noise_counts(), float)
    if np.all(k > 0):
        return np.sqrt(k ** 2 + _QUANT_VAR), "device noise_mps2"
    return estimate_noise(raw, window), "estimated from the data (robust window std)"


def detect_static(rec, device, *, window_s: float = STATIC_WINDOW_S, threshold: float = STATIC_THRESHOLD,
                  min_s: float = MIN_POSE_S, noise: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Static intervals of a continuous recording, as sample index pairs [start, stop).

    1. Windows of about ``window_s`` seconds, taken at a stride of a quarter window
       (_window_std), are quiet when the std of every channel in them is at most
       ``threshold`` times that channel's noise; the blocks a quiet window covers are
       static.
    2. Each run of static blocks is refined to the sample: with med the median of the
       run, its ends move to the nearest samples (searching one window beyond and a
       block inside the run, never into a neighbouring run) at which some channel is
       more than EDGE_SIGMA x noise away from med.  The window test alone would admit
       an edge sample up to about sqrt(3 w) x noise off.
    3. Intervals shorter than ``min_s`` (or one window) are dropped.

    The noise is the device's ``noise_mps2`` (plus rounding) when it is given for
    every channel, else estimated from the data (:func:`estimate_noise`), unless
    ``noise`` (counts, per channel) is passed.
    """
    raw = np.asarray(rec.raw)
    n = raw.shape[0]
    w = _window_len(device, window_s, n)
    if n < w:
        return []
    sig = np.asarray(noise, float) if noise is not None else _noise_for(device, raw, w)[0]
    ws, h, k = _window_std(raw, w)
    nw = ws.shape[0]
    if nw == 0:
        return []
    quiet = np.all(ws <= threshold * sig[None, :], axis=1).astype(np.int64)
    # block b is static if a quiet window j with j <= b <= j + k - 1 covers it
    c = np.concatenate([[0], np.cumsum(quiet)])
    blk = np.arange(nw + k - 1)
    static = (c[np.clip(blk + 1, 0, nw)] - c[np.clip(blk - k + 1, 0, nw)]) > 0
    edges = np.diff(np.concatenate([[0], static.astype(np.int8), [0]]))
    runs = list(zip(np.flatnonzero(edges == 1) * h, np.flatnonzero(edges == -1) * h))
    min_n = max(w, int(math.ceil(min_s * device.sample_rate_hz)))
    ext = k * h
    out: list[tuple[int, int]] = []
    for r, (a, b) in enumerate(runs):
        lo_lim = max(out[-1][1] if out else 0, runs[r - 1][1] if r else 0)
        hi_lim = runs[r + 1][0] if r + 1 < len(runs) else n
        lo, hi = max(lo_lim, a - ext), min(hi_lim, b + ext)
        med = np.median(raw[a:b:max(1, (b - a) // 2000)], axis=0)
        lim = EDGE_SIGMA * sig
        left = np.flatnonzero(np.any(np.abs(raw[lo:a + h] - med) > lim, axis=1))
        start = lo + (int(left[-1]) + 1 if left.size else 0)
        right = np.flatnonzero(np.any(np.abs(raw[b - h:hi] - med) > lim, axis=1))
        stop = b - h + int(right[0]) if right.size else hi
        if stop - start >= min_n:
            out.append((int(start), int(stop)))
    return out


def _where(rec, i: int) -> str:
    return f"sample {int(i)} (t = {float(rec.t[i]):.6g} s)"


def pose_means(rec, intervals: Sequence[Any], device, *, labels: Sequence[Any] | None = None,
               noise: np.ndarray | None = None, check_motion: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, sample count and within-pose std of each static pose.

    ``intervals``: (start, stop) sample index pairs, or index arrays (a labelled pose
    may be split).  Checks (each an InputError naming the recording and where):
    no reading of a pose sits at raw_min/raw_max; with ``check_motion``, no channel's
    std in a pose exceeds MOVE_FACTOR x its noise (the pose would not be static).
    Returns means (P,N), counts (P,), std (P,N).
    """
    raw = np.asarray(rec.raw)
    n, N = raw.shape
    P = len(intervals)
    idx_list = [np.arange(int(iv[0]), int(iv[1])) if _is_pair(iv) else np.asarray(iv, dtype=np.int64)
                for iv in intervals]
    names = [f"pose {labels[p]}" if labels is not None else f"static interval {p}" for p in range(P)]
    cnt = np.array([len(ix) for ix in idx_list], dtype=np.int64)
    if P == 0:
        return np.zeros((0, N)), cnt, np.zeros((0, N))
    if np.any(cnt == 0):
        raise InputError(rec.source, f"{names[int(np.argmin(cnt))]} has no samples")
    # one gather, then per-pose reductions; integer arithmetic about a reference is exact
    x = raw[np.concatenate(idx_list)]
    offs = np.concatenate([[0], np.cumsum(cnt)[:-1]])
    lo, hi = np.minimum.reduceat(x, offs, axis=0), np.maximum.reduceat(x, offs, axis=0)
    bad = np.argwhere((lo <= device.raw_min) | (hi >= device.raw_max))
    if bad.size:
        p, c = (int(v) for v in bad[0])
        seg = raw[idx_list[p], c]
        k = int(np.flatnonzero((seg <= device.raw_min) | (seg >= device.raw_max))[0])
        i = int(idx_list[p][k])
        lim = "raw_max" if raw[i, c] >= device.raw_max else "raw_min"
        raise InputError(rec.source, f"{names[p]}: raw_{c} = {int(raw[i, c])} at {_where(rec, i)} sits at the "
                         f"ADC limit {lim} = {getattr(device, lim)} (clipped readings cannot be calibrated)",
                         column=f"raw_{c}")
    ref = x[0].copy()
    x -= ref
    s1 = np.add.reduceat(x, offs, axis=0).astype(float)
    s2 = np.add.reduceat(x * x, offs, axis=0).astype(float)
    cf = cnt.astype(float)[:, None]
    mean = s1 / cf
    var = np.maximum(s2 - s1 * mean, 0.0) / np.maximum(cf - 1, 1)
    std = np.sqrt(var)
    mean += ref
    if check_motion:
        if noise is None:
            noise = _noise_for(device, raw, _window_len(device, STATIC_WINDOW_S, n))[0]
        ratio = std / np.asarray(noise, float)[None, :]
        ratio[cnt < 3] = 0.0
        if np.any(ratio > MOVE_FACTOR):
            p, c = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
            idx = idx_list[p]
            raise InputError(rec.source, f"{names[p]} ({_where(rec, idx[0])} to {_where(rec, idx[-1])}) is labelled "
                             f"static but moves: raw_{c} varies by {std[p, c]:.3g} counts rms, its noise is "
                             f"{noise[c]:.3g} counts", column="pose" if labels is not None else f"raw_{c}")
    return mean, cnt, std


def _is_pair(iv: Any) -> bool:
    return isinstance(iv, tuple) and len(iv) == 2 and np.isscalar(iv[0])


def poses_from_recording(rec, device, *, use_labels: bool | None = None, required: bool = True) -> PoseSet:
    """The static poses of one recording: its ``pose`` labels when it has them (and
    ``use_labels`` is not False), else :func:`detect_static`.  The reference
    specific force and temperature of a pose are the means of f_* and temp_c over it.
    With ``required`` False a recording without static poses gives an empty set."""
    _check_recording(rec, device)
    labelled = rec.has_pose() if use_labels is None else bool(use_labels)
    n = rec.n_samples
    w = _window_len(device, STATIC_WINDOW_S, n)
    noise = _noise_for(device, rec.raw, w)[0]
    if labelled:
        labs = rec.pose_labels()
        order = np.argsort(rec.pose, kind="stable")
        sorted_lab = rec.pose[order]
        bounds = np.searchsorted(sorted_lab, labs), np.searchsorted(sorted_lab, labs, side="right")
        intervals = [np.sort(order[a:b]) for a, b in zip(*bounds)]
        labels = [int(v) for v in labs]
    else:
        intervals = detect_static(rec, device, noise=noise)
        labels = None
    if not intervals and not required:
        return PoseSet(np.zeros((0, device.n_channels)), np.zeros(0, dtype=np.int64),
                       np.zeros((0, device.n_channels)), np.zeros((0, 3)), np.zeros(0), [])
    if not intervals:
        raise InputError(rec.source, "no static pose found (no 'pose' labels, and no interval of at least "
                         f"{MIN_POSE_S:g} s in which every channel is within {STATIC_THRESHOLD:g} x its noise)")
    means, cnt, std = pose_means(rec, intervals, device, labels=labels, noise=noise, check_motion=True)
    P = len(intervals)
    f_ref = np.full((P, 3), np.nan)
    temp = np.full(P, np.nan)
    info = []
    for p, iv in enumerate(intervals):
        idx = np.arange(iv[0], iv[1]) if _is_pair(iv) else iv
        fr = rec.f[idx]
        ok = np.all(np.isfinite(fr), axis=1)
        if ok.any():
            if not ok.all():
                i = int(idx[int(np.argmin(ok))])
                raise InputError(rec.source, f"pose {labels[p] if labels else p}: f_x, f_y, f_z given on some of "
                                 f"its samples but not at {_where(rec, i)}", column="f_x")
            f_ref[p] = fr.mean(0)
        tc = rec.temp_c[idx]
        if np.isfinite(tc).any():
            temp[p] = float(np.nanmean(tc))
        info.append({
            "source": rec.source,
            "label": labels[p] if labels is not None else None,
            "first": int(idx[0]), "last": int(idx[-1]),
            "t_start": float(rec.t[idx[0]]), "t_stop": float(rec.t[idx[-1]]),
            "n": int(cnt[p]),
        })
    return PoseSet(means=means, n=cnt, std=std, f_ref=f_ref, temp=temp, info=info)


def _check_recording(rec, device) -> None:
    from .recording import check_for_device
    check_for_device(rec, device)


# ==============================================================================
# Results
# ==============================================================================


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


# ==============================================================================
# Known poses: per-channel linear least squares
# ==============================================================================


def _as_means(device, means, what="means") -> np.ndarray:
    m = np.asarray(means, float)
    if m.ndim != 2 or m.shape[1] != device.n_channels:
        raise InputError("<arrays>", f"expected shape (P, {device.n_channels}), got {m.shape}", field=what)
    bad = np.argwhere(~np.isfinite(m))
    if bad.size:
        p, c = bad[0]
        raise InputError("<arrays>", f"not finite: {m[p, c]}", field=f"{what}[{p}][{c}]")
    return m


def _design(method: str, device, i: int, F: np.ndarray) -> np.ndarray:
    """Per-channel regressors for pose forces F (P,3): offset [1]; gain [1, u.f]; full [1, f]."""
    one = np.ones((F.shape[0], 1))
    if method == "offset":
        return one
    if method == "gain":
        return np.hstack([one, (F @ device.axes[i])[:, None]])
    return np.hstack([one, F])


def _pose_label(info: list[dict] | None, p: int) -> str:
    if info and p < len(info) and info[p].get("label") is not None:
        return f"pose {info[p]['label']}"
    return f"pose {p}"


def _identifiability(device, method: str, F: np.ndarray, min_rcond: float) -> None:
    """Raise InputError (which pose to add) when the known poses cannot determine
    every free parameter of every channel."""
    g = device.gravity_mps2
    P = F.shape[0]
    if P == 0:
        raise InputError("<poses>", "no static pose to calibrate from")

    def rcond(Fs: np.ndarray, i: int) -> float:
        A = _design(method, device, i, Fs / g)
        sv = np.linalg.svd(A, compute_uv=False)
        q = A.shape[1]
        return 0.0 if len(sv) < q else float(sv[-1] / sv[0])

    def best_candidate(i: int) -> str:
        best, name = -1.0, ""
        for nm, d in _CANDIDATES:
            r = rcond(np.vstack([F, g * np.asarray(d)]), i)
            if r > best + 1e-9:
                best, name = r, nm
        return name

    channels = range(device.n_channels) if method == "gain" else [0]
    for i in channels:
        if rcond(F, i) >= min_rcond:
            continue
        add = best_candidate(i)
        if method == "gain":
            x = F @ device.axes[i] / g
            raise InputError("<poses>", f"the poses do not determine channel {i}'s gain: every pose gives it "
                             f"u.f = {np.mean(x):+.2f} g along its axis (spread {np.ptp(x):.3f} g); add a pose with "
                             f"f along {add} (body {add} axis up)", field=f"channels[{i}]")
        if P < 4:
            what = f"only {P} pose{'s' if P != 1 else ''}"
        elif np.max(np.linalg.norm(F - F.mean(0), axis=1)) < 0.05 * g:
            fm = F.mean(0) / g
            what = f"all {P} poses have about the same f = [{fm[0]:+.2f}, {fm[1]:+.2f}, {fm[2]:+.2f}] g"
        else:
            A = _design("full", device, 0, F / g)
            v = np.linalg.svd(A)[2][-1]
            nrm = v[1:] / np.linalg.norm(v[1:])
            c = -v[0] / np.linalg.norm(v[1:])
            what = (f"all {P} pose forces lie in one plane (n.f = {c:+.2f} g, n = "
                    f"[{nrm[0]:+.2f}, {nrm[1]:+.2f}, {nrm[2]:+.2f}])")
        raise InputError("<poses>", f"the poses do not determine the offset and sensitivity vector of channel {i} "
                         f"(nor of any channel): {what}; 'full' needs f along 4 directions not in one plane: add a "
                         f"pose with f along {add} (body {add} axis up)", field="poses")


def jig_accuracy_rad(jig_accuracy_deg: Any) -> float:
    """Validate a stated jig accuracy (degrees, finite, >= 0) and return it in radians."""
    try:
        v = float(jig_accuracy_deg)
    except (TypeError, ValueError):
        v = float("nan")
    if not (math.isfinite(v) and v >= 0.0):
        raise InputError("<arguments>", f"jig accuracy must be a finite angle >= 0 degrees, got {jig_accuracy_deg!r}",
                         field="jig_accuracy_deg")
    return math.radians(v)


def _birge(chi2: float, dof: int) -> float:
    return max(1.0, chi2 / dof) if dof > 0 else 1.0


def calibrate_known_poses(device, means, f_ref=None, method: str = "full", sigma=None, *,
                          min_rcond: float = MIN_RCOND, jig_accuracy_deg: float = JIG_ACCURACY_DEG):
    """Known-pose calibration (seed paper eqs. 16-19; seed doc 2's 1- and 3-pose
    methods as ``offset`` and ``gain``) -> Calibration.

    ``means``: a PoseSet (its f_ref is used when ``f_ref`` is None, its within-pose
    scatter for the weights) or a (P,N) array of pose means in counts with ``f_ref``
    (P,3) m/s^2.  ``jig_accuracy_deg``: rms rotation angle of the pose errors (see
    the module notes).  See :func:`fit_known_poses`."""
    poses = means if isinstance(means, PoseSet) else None
    m = poses.means if poses is not None else means
    F = poses.f_ref if (poses is not None and f_ref is None) else f_ref
    if F is None:
        raise ValueError("calibrate_known_poses: f_ref is required with a means array")
    fit = fit_known_poses(device, m, F, method, sigma, poses=poses, min_rcond=min_rcond,
                          jig_accuracy_deg=jig_accuracy_deg)
    return to_calibration(device, fit, method)


def fit_known_poses(device, means, f_ref, method: str = "full", sigma=None, *,
                    poses: PoseSet | None = None, min_rcond: float = MIN_RCOND,
                    jig_accuracy_deg: float = JIG_ACCURACY_DEG) -> StaticFit:
    """Per-channel weighted least squares for b_i (and k_i or s_i) from P known poses.

    means (P,N) counts, f_ref (P,3) m/s^2, sigma (P,N) 1-sigma of each mean (counts;
    default: ``poses.sem()`` when ``poses`` is given, else equal weights and the
    covariance from the residuals).  ``jig_accuracy_deg`` (theta, default
    JIG_ACCURACY_DEG = 0): the references are uncertain by a pose rotation of rms
    angle theta; the pose directions are then estimated jointly with every
    channel's parameters, each with its reference as a prior of that accuracy
    (:func:`fit_static`; module notes), and ``StaticFit.f`` holds the estimated pose
    forces.  Without sigma the noise is then the rounding floor 1/12 count^2 and
    the covariance is inflated by chi2/dof when > 1.  Raises InputError (which pose
    to add) when the poses cannot determine a free parameter.  Returns a
    :class:`StaticFit`.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    jig = jig_accuracy_rad(jig_accuracy_deg)
    m = _as_means(device, means)
    F = np.asarray(f_ref, float)
    if F.shape != (m.shape[0], 3):
        raise InputError("<arrays>", f"expected shape ({m.shape[0]}, 3), got {F.shape}", field="f_ref")
    bad = np.argwhere(~np.isfinite(F))
    if bad.size:
        p = int(bad[0][0])
        raise InputError("<arrays>", f"{_pose_label(poses.info if poses else None, p)} has no reference "
                         "specific force (f_x, f_y, f_z); use the jig-free method", field=f"f_ref[{p}]")
    if sigma is None and poses is not None:
        sigma = poses.sem()
    _identifiability(device, method, F, min_rcond)
    P, N = m.shape
    if jig > 0:
        # the references as priors of the stated accuracy: the nonlinear model with free poses
        # (with a stated jig accuracy the variance model is absolute even without sigma: the
        # rounding floor as the noise, so chi2 counts and the covariance gets the Birge rule)
        sig = np.asarray(sigma, float) if sigma is not None else np.full((P, N), math.sqrt(_QUANT_VAR))
        ps = _bare_poses(m, F) if poses is None else PoseSet(m, poses.n, poses.std, F, poses.temp, poses.info)
        return fit_static(device, ps, method, jigfree=False, temperature=False, sigma=sig, min_rcond=min_rcond,
                          jig_accuracy_deg=jig_accuracy_deg)
    sigma_known = sigma is not None
    sig = np.asarray(sigma, float) if sigma_known else None
    k_nom = device.counts_per_mps2
    offsets = np.empty(N)
    sens = np.empty((N, 3))
    cov = np.zeros((N, 6, 6))
    resid = np.empty((P, N))
    chi2_tot, dof_tot = 0.0, 0
    for i in range(N):
        A = _design(method, device, i, F)
        y = m[:, i].copy()
        if method == "offset":
            y -= F @ (k_nom[i] * device.axes[i])
        w = np.ones(P) if sig is None else 1.0 / sig[:, i]
        Aw = A * w[:, None]
        x, *_ = np.linalg.lstsq(Aw, y * w, rcond=None)
        r = y - A @ x
        q = A.shape[1]
        dof = P - q
        chi2 = float(np.sum((r * w) ** 2))
        C = np.linalg.inv(Aw.T @ Aw)
        if not sigma_known:
            C *= chi2 / dof if dof > 0 else np.nan
        else:
            C *= _birge(chi2, dof)
            chi2_tot += chi2
            dof_tot += dof
        offsets[i] = x[0]
        if method == "offset":
            sens[i] = k_nom[i] * device.axes[i]
            cov[i, 0, 0] = C[0, 0]
        elif method == "gain":
            sens[i] = x[1] * device.axes[i]
            J = np.zeros((4, 2))
            J[0, 0] = 1.0
            J[1:, 1] = device.axes[i]
            cov[i, :4, :4] = J @ C @ J.T
        else:
            sens[i] = x[1:]
            cov[i, :4, :4] = C
        resid[:, i] = r
    ps = poses if poses is not None else _bare_poses(m, F)
    hint = None
    if sigma_known and dof_tot > 0 and chi2_tot / dof_tot > JIG_HINT_CHI2:
        hint = _implied_jig_deg(device, method, m, F, sig, (offsets, sens, None, None))
    return StaticFit(method=method, jigfree=False, offsets=offsets, sensitivity=sens, f=F.copy(), cov=cov,
                     residual=resid, chi2=chi2_tot, dof=dof_tot, poses=ps, jig_accuracy_deg=0.0, jig_hint_deg=hint)


def _implied_jig_deg(device, method, m, F, sig, start) -> float | None:
    """The jig accuracy (deg) at which the known-pose fit with the references as
    priors of that accuracy has chi2/dof = 1: what pose errors alone would explain
    the scatter of the poses about the fit (bisection on a log scale, each fit
    started from the previous one; None when even 30 deg leaves chi2/dof > 1, i.e.
    not a jig error)."""
    P, N = m.shape
    q = {"offset": 1, "gain": 2, "full": 4}[method]
    dof = P * N - q * N
    x_prev = [None]

    def chi2_per_dof(deg: float) -> float:
        prob, x, _ = _prior_solve(device, method, m, sig, None, F, math.radians(deg), start, x_prev[0])
        x_prev[0] = x
        r = prob.residual(x)
        return float(r @ r) / dof

    lo, hi = 1e-4, 30.0
    if chi2_per_dof(hi) > 1.0:
        return None
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        if chi2_per_dof(mid) > 1.0:
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.01:
            break
    return float(math.sqrt(lo * hi))


def _bare_poses(m: np.ndarray, F: np.ndarray | None = None) -> PoseSet:
    P, N = m.shape
    return PoseSet(means=m, n=np.ones(P, dtype=np.int64), std=np.zeros((P, N)),
                   f_ref=np.full((P, 3), np.nan) if F is None else F, temp=np.full(P, np.nan),
                   info=[{"label": None} for _ in range(P)])


# ==============================================================================
# Nonlinear static model: jig-free poses and/or temperature terms
# ==============================================================================


def _tangent_basis(d: np.ndarray) -> np.ndarray:
    """(P,2,3) orthonormal basis of the plane perpendicular to each unit d (P,3)."""
    a = np.where(np.abs(d[:, :1]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    e1 = np.cross(d, a)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(d, e1)
    return np.stack([e1, e2], axis=1)


def gauge_rotation(device, sensitivity: np.ndarray) -> np.ndarray:
    """Rotation R (3,3) that puts ``sensitivity`` into the jig-free gauge: the
    orthogonal-Procrustes rotation mapping the directions s_i/|s_i| onto the nominal
    axes u_i, so that R s_i satisfies sum_i u_i x (R s_i/|s_i|) = 0.  Apply R to the
    s_i and to the pose forces alike (the readings do not change)."""
    s = np.asarray(sensitivity, float)
    sh = s / np.linalg.norm(s, axis=1, keepdims=True)
    H = device.axes.T @ sh                    # sum u_i sh_i^T
    U, _, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))])
    return U @ D @ Vt


class _StaticProblem:
    """Residuals and Jacobian of m_pi = b_i + beta_i dT_p + (1 + gamma_i dT_p) s_i . f_p,
    weighted by 1/sigma_pi, over channel parameters and (optionally) pose tangent coordinates.

    ``prior_rad`` (known poses with a stated jig accuracy theta, radians): the pose
    directions are free about the reference forces F (magnitude |F_p| kept) and
    2 rows a pose are appended, the tangent coordinates a_p / (theta / sqrt(3))
    (the prior: each component of a pose's rotation error has rms theta/sqrt(3))."""

    def __init__(self, device, method, means, sigma, dT, free_poses, F=None, gauge=False, prior_rad=None):
        self.dev = device
        self.method = method
        self.m = means
        self.w = 1.0 / sigma
        self.dT = dT                       # (P,) or None
        self.temp = dT is not None
        self.g = device.gravity_mps2
        self.P, self.N = means.shape
        self.free_poses = free_poses or prior_rad is not None
        self.prior_w = None if prior_rad is None else math.sqrt(3.0) / prior_rad
        self.q = {"offset": 1, "gain": 2, "full": 4}[method] + (2 if self.temp else 0)
        self.n_ch = self.q * self.N
        self.n_pose = 0
        self.F_fixed = None if self.free_poses else np.asarray(F, float)
        self.fmag = np.full(self.P, self.g)
        if self.free_poses and F is not None:
            if prior_rad is not None:
                self.fmag = np.linalg.norm(np.asarray(F, float), axis=1)
            self.set_pose_frame(F, gauge and prior_rad is None)

    @property
    def n_prior(self) -> int:
        return self.n_pose if self.prior_w is not None else 0

    def set_pose_frame(self, F: np.ndarray, gauge: bool) -> None:
        """Linearise the pose directions about F: f_p = |f_p| (d_p + T_p a_p)/|..|, a_p free
        where ``mask``.  With ``gauge``, the common rotation is held fixed during the
        solve: pose 0 entirely, and the pose most perpendicular to it may only move
        in the plane it spans with pose 0 (3 constraints)."""
        d = F / np.linalg.norm(F, axis=1, keepdims=True)
        T = _tangent_basis(d)
        mask = np.ones((self.P, 2), dtype=bool)
        if gauge:
            c = int(np.argmax(np.linalg.norm(np.cross(d[0], d), axis=1)))
            nrm = np.cross(d[0], d[c])
            nrm /= np.linalg.norm(nrm)
            T[c] = np.stack([np.cross(nrm, d[c]), nrm])
            mask[0] = False
            mask[c, 1] = False
        self.d, self.T, self.mask = d, T, mask
        self.n_pose = int(mask.sum())

    def pack(self, b, s, beta=None, gamma=None) -> np.ndarray:
        cols = [b[:, None]]
        if self.method == "gain":
            cols.append(np.sum(s * self.dev.axes, axis=1)[:, None])
        elif self.method == "full":
            cols.append(s)
        if self.temp:
            cols += [np.zeros((self.N, 1)) if beta is None else beta[:, None],
                     np.zeros((self.N, 1)) if gamma is None else gamma[:, None]]
        x = np.hstack(cols).ravel()
        return np.concatenate([x, np.zeros(self.n_pose)])

    def unpack(self, x):
        c = x[: self.n_ch].reshape(self.N, self.q)
        b = c[:, 0]
        if self.method == "offset":
            s = self.dev.nominal_sensitivity()
            j = 1
        elif self.method == "gain":
            s = c[:, 1:2] * self.dev.axes
            j = 2
        else:
            s = c[:, 1:4]
            j = 4
        beta = c[:, j] if self.temp else None
        gamma = c[:, j + 1] if self.temp else None
        return b, s, beta, gamma

    def forces(self, x):
        """(P,3) pose forces and v (P,3) unnormalised directions."""
        if not self.free_poses:
            return self.F_fixed, None
        a = np.zeros((self.P, 2))
        a[self.mask] = x[self.n_ch:]
        v = self.d + np.einsum("pk,pkj->pj", a, self.T)
        return self.fmag[:, None] * v / np.linalg.norm(v, axis=1, keepdims=True), v

    def residual(self, x):
        b, s, beta, gamma = self.unpack(x)
        F, _ = self.forces(x)
        sf = F @ s.T                                   # (P,N)
        pred = b[None, :] + sf
        if self.temp:
            pred = pred + self.dT[:, None] * (beta[None, :] + gamma[None, :] * sf)
        r = ((self.m - pred) * self.w).ravel()
        if self.prior_w is None:
            return r
        return np.concatenate([r, x[self.n_ch:] * self.prior_w])

    def jacobian(self, x):
        P, N, q = self.P, self.N, self.q
        b, s, beta, gamma = self.unpack(x)
        F, v = self.forces(x)
        gain = np.ones((P, N)) if not self.temp else 1.0 + self.dT[:, None] * gamma[None, :]
        J = np.zeros((P, N, self.n_ch + self.n_pose))
        ch = np.arange(N)
        base = ch * q
        J[:, ch, base] = -1.0
        if self.method == "gain":
            J[:, ch, base + 1] = -gain * (F @ self.dev.axes.T)
            j = 2
        elif self.method == "full":
            for k in range(3):
                J[:, ch, base + 1 + k] = -gain * F[:, k:k + 1]
            j = 4
        else:
            j = 1
        if self.temp:
            J[:, ch, base + j] = -self.dT[:, None]
            J[:, ch, base + j + 1] = -self.dT[:, None] * (F @ s.T)
        if self.free_poses and self.n_pose:
            nv = np.linalg.norm(v, axis=1)
            fh = v / nv[:, None]
            # dF/da_k = |f|/|v| (I - fh fh^T) T_k
            dF = (self.fmag / nv)[:, None, None] * (
                self.T - np.einsum("pk,pj->pkj", np.einsum("pkj,pj->pk", self.T, fh), fh))
            ds = np.einsum("pkj,nj->pnk", dF, s) * gain[:, :, None]     # (P,N,2)
            cols = np.cumsum(self.mask.ravel()).reshape(P, 2) - 1 + self.n_ch
            for k in range(2):
                pk = np.flatnonzero(self.mask[:, k])
                J[pk[:, None], ch[None, :], cols[pk, k][:, None]] = -ds[pk, :, k]
        J *= self.w[:, :, None]
        J = J.reshape(P * N, -1)
        if self.prior_w is None:
            return J
        Jp = np.zeros((self.n_pose, J.shape[1]))
        Jp[:, self.n_ch:] = np.eye(self.n_pose) * self.prior_w
        return np.vstack([J, Jp])

    def reading_residual(self, r: np.ndarray) -> np.ndarray:
        """(P,N) reading residuals in counts from a residual vector (prior rows dropped)."""
        return r[: self.P * self.N].reshape(self.P, self.N) / self.w


def _gauge_constraint(device, s: np.ndarray, n_par: int, q: int) -> np.ndarray:
    """(3, n_par) Jacobian of sum_i u_i x (s_i/|s_i|) w.r.t. the parameters (full method;
    channel i's s_i at columns i q + 1 .. i q + 3, nothing else enters)."""
    C = np.zeros((3, n_par))
    for i in range(device.n_channels):
        ns = np.linalg.norm(s[i])
        sh = s[i] / ns
        dsh = (np.eye(3) - np.outer(sh, sh)) / ns
        u = device.axes[i]
        ux = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        C[:, i * q + 1: i * q + 4] = ux @ dsh
    return C


def _min_poses(device, method: str, temp: bool) -> int:
    """Fewest poses a jig-free fit can be determined from.

    The readings m_p = b + S f_p fix (b, S, f_p) only up to f -> A f + c,
    S -> S A^-1, b -> b - S A^-1 c; |f_p| = g must rule out every such map except
    rotations (full) or the identity (gain, offset).  Each pose gives one equation
    on (A, c), so P >= the dimension of the admissible maps: 9 for full (12 affine
    minus 3 rotations, imu_tk's "at least 9"), 3 + dim{A : A^T u_i || u_i} for gain,
    3 for offset.  Also P N readings >= the number of unknowns (temperature terms)."""
    N = device.n_channels
    if method == "full":
        amb = 9
    elif method == "gain":
        # A^T u_i must stay parallel to u_i: (I - u u^T) M u = 0 for M = A^T
        rows = []
        for u in device.axes:
            Pp = np.eye(3) - np.outer(u, u)
            rows.append(np.kron(Pp, u[None, :]))       # vec(M) row-major: (Pp M u)_a = sum Pp_ab M_bc u_c
        K = np.vstack(rows)
        amb = 3 + (9 - int(np.linalg.matrix_rank(K, tol=1e-9)))
    else:
        amb = 3
    q = {"offset": 1, "gain": 2, "full": 4}[method] + (2 if temp else 0)
    gauge = 3 if method == "full" else 0
    count = int(math.ceil((q * N - gauge) / (N - 2))) if N > 2 else 10 ** 9
    return max(amb, count)


def _missing_direction(device, F: np.ndarray) -> str:
    """The body axis direction (of +-x, +-y, +-z) farthest from every pose."""
    fh = F / np.linalg.norm(F, axis=1, keepdims=True)
    best, name = -2.0, ""
    for nm, d in _CANDIDATES:
        score = -float(np.max(fh @ np.asarray(d)))
        if score > best + 1e-9:
            best, name = score, nm
    return name


def fit_static(device, poses: PoseSet, method: str = "full", *, jigfree: bool, temperature: bool = False,
               sigma: np.ndarray | None = None, f_init: np.ndarray | None = None,
               min_rcond: float = MIN_RCOND, jig_accuracy_deg: float = JIG_ACCURACY_DEG) -> StaticFit:
    """Nonlinear static fit: channel parameters (``method``), optionally temperature
    coefficients beta_i (counts/degC) and gamma_i (1/degC) about T0 = mean pose
    temperature, and, with ``jigfree``, the pose directions under |f| = g (gauge:
    see the module notes).  Known poses use ``poses.f_ref``; with ``jig_accuracy_deg``
    theta > 0 the pose directions are estimated too, with the references as priors
    of rms rotation theta (module notes: jig accuracy; ignored jig-free).
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    jig = 0.0 if jigfree else jig_accuracy_rad(jig_accuracy_deg)
    m = _as_means(device, poses.means)
    P, N = m.shape
    # bare means (no within-pose scatter, no sigma): equal weights, covariance from the residuals
    # (with a stated jig accuracy: the rounding floor as the noise, and the Birge rule)
    sigma_known = sigma is not None or bool(np.any(poses.n > 1))
    sig = np.asarray(sigma, float) if sigma is not None else (poses.sem() if sigma_known else np.ones((P, N)))
    if jig > 0 and not sigma_known:
        sig = np.full((P, N), math.sqrt(_QUANT_VAR))
        sigma_known = True
    g = device.gravity_mps2
    dT = None
    T0 = None
    if temperature:
        if not np.all(np.isfinite(poses.temp)):
            p = int(np.flatnonzero(~np.isfinite(poses.temp))[0])
            raise InputError("<poses>", f"{_pose_label(poses.info, p)} has no temp_c; temperature fit needs it on "
                             "every pose", field="temp_c")
        T0 = float(np.mean(poses.temp))
        dT = poses.temp - T0
    need = _min_poses(device, method, temperature) if jigfree else 0
    if jigfree and P < need:
        raise InputError("<poses>", f"jig-free '{method}' calibration of {N} channels needs at least {need} static "
                         f"poses in different orientations, got {P}; add poses (e.g. f along "
                         f"{_missing_direction(device, _initial_forces(device, m))})", field="poses")
    if not jigfree:
        F = np.asarray(poses.f_ref, float)
        if not np.all(np.isfinite(F)):
            p = int(np.flatnonzero(~np.all(np.isfinite(F), axis=1))[0])
            raise InputError("<poses>", f"{_pose_label(poses.info, p)} has no reference f; use the jig-free "
                             "method", field="f_ref")
        _identifiability(device, method, F, min_rcond)
        if jig > 0 and np.any(np.linalg.norm(F, axis=1) <= 0.0):
            p = int(np.flatnonzero(np.linalg.norm(F, axis=1) <= 0.0)[0])
            raise InputError("<poses>", f"{_pose_label(poses.info, p)} has reference f = 0, which has no direction "
                             "for a jig accuracy to rotate; state jig accuracy 0 or give the pose's f", field="f_ref")
    else:
        F = _initial_forces(device, m) if f_init is None else np.asarray(f_init, float)
        fh = F / np.linalg.norm(F, axis=1, keepdims=True)
        spread = float(np.degrees(np.arcsin(min(1.0, np.max(np.linalg.norm(np.cross(fh[0], fh), axis=1))))))
        if spread < 5.0:
            raise InputError("<poses>", f"the {P} static poses all have about the same orientation (within "
                             f"{spread:.1f} deg of each other); jig-free calibration needs poses spread over the "
                             f"sphere (e.g. add f along {_missing_direction(device, F)})", field="poses")
    gauge = jigfree and method == "full"
    b0 = device.nominal_offsets()
    s0 = device.nominal_sensitivity()
    prob = _StaticProblem(device, method, m, sig, dT, jigfree, None if jigfree else F)
    if jigfree:
        if method != "offset":
            # start: offsets and gains along the nominal axes with free poses (no gauge
            # needed), which takes out the large offsets before the full model
            b0, s0, F = _refine_start(device, m, sig, F, b0, s0)
        prob.set_pose_frame(F, gauge)

    def undetermined() -> InputError:
        return InputError("<poses>", f"the {P} poses do not determine every parameter of the "
                          f"{'jig-free ' if jigfree else ''}'{method}'{' + temperature' if temperature else ''} model; "
                          f"add poses in other orientations (e.g. f along {_missing_direction(device, F)})"
                          + ("" if not temperature else " and at other temperatures"), field="poses")

    def not_converged() -> InputError:
        return InputError("<poses>", f"the {'jig-free ' if jigfree else ''}'{method}' fit did not converge in 100 "
                          "iterations: the static poses do not fit the model (moving poses, or another device?)",
                          field="poses")

    x0 = prob.pack(b0, s0)
    if _constrained_inverse(prob.jacobian(x0), None) is None:     # gauge already fixed in prob
        raise undetermined()
    x, converged = _levenberg_marquardt(prob.residual, prob.jacobian, x0)
    if not converged:
        raise not_converged()
    if jig > 0:
        # the references as priors: start from the fit with the poses at their references
        prob, x, converged = _prior_solve(device, method, m, sig, dT, F, jig, prob.unpack(x))
        if not converged:
            raise not_converged()
    b, s, beta, gamma = prob.unpack(x)
    F, _ = prob.forces(x)
    if gauge:
        R = gauge_rotation(device, s)
        s = s @ R.T
        F = F @ R.T
    # covariance in the final gauge: every pose free (2 tangent coordinates), gauge constraint if needed;
    # with the prior, at the solution in the reference's linearisation (prior rows included)
    cov_prob = prob if jig > 0 else _StaticProblem(device, method, m, sig, dT, jigfree, F, gauge=False)
    xf = x if jig > 0 else cov_prob.pack(b, s, beta, gamma)
    r = cov_prob.residual(xf)
    J = cov_prob.jacobian(xf)
    chi2 = float(r @ r)
    n_par = J.shape[1] - (3 if gauge else 0)
    dof = P * N + cov_prob.n_prior - n_par
    # with the prior the rank was checked with the poses fixed (the prior rows make the pose
    # coordinates full rank), and pose directions the readings barely see are normal there:
    # only an exactly singular system is refused
    C = _constrained_inverse(J, _gauge_constraint(device, s, J.shape[1], cov_prob.q) if gauge else None,
                             rtol=1e-13 if jig > 0 else MIN_RCOND_JAC)
    if C is None:
        raise undetermined()
    C *= _birge(chi2, dof) if sigma_known else (chi2 / dof if dof > 0 else np.nan)
    cov = _channel_cov(device, method, temperature, C, cov_prob.q)
    pose_cov = None
    if cov_prob.free_poses:
        idx = cov_prob.n_ch + np.arange(2 * P).reshape(P, 2)
        pose_cov = C[idx[:, :, None], idx[:, None, :]]      # tangent coordinates are radians
    resid = cov_prob.reading_residual(r)
    return StaticFit(method=method, jigfree=jigfree, offsets=b, sensitivity=s, f=F, cov=cov, residual=resid,
                     chi2=chi2, dof=int(dof), poses=poses, temp_ref_c=T0,
                     offset_tc=None if beta is None else np.array(beta),
                     gain_tc=None if gamma is None else np.array(gamma), pose_cov=pose_cov,
                     jig_accuracy_deg=math.degrees(jig))


def _prior_solve(device, method, m, sig, dT, F, jig, start, x_start=None):
    """The known-pose model with the references F as priors of rms rotation ``jig``
    (rad): (problem, x, converged), started from channel parameters ``start`` =
    (b, s, beta, gamma) with the poses at their references, or from ``x_start`` (a
    previous solution of the same parameterisation)."""
    prob = _StaticProblem(device, method, m, sig, dT, True, F, prior_rad=jig)
    x0 = prob.pack(*start) if x_start is None else x_start
    x, converged = _levenberg_marquardt(prob.residual, prob.jacobian, x0)
    return prob, x, converged


def _levenberg_marquardt(fun, jac, x0: np.ndarray, max_iter: int = 100,
                         tol: float = 1e-12) -> tuple[np.ndarray, bool]:
    """Minimise |fun(x)|^2 (Levenberg-Marquardt, Marquardt's diagonal scaling).

    Small dense problems only (a few hundred parameters).  Returns (x, converged):
    converged when the relative decrease of the cost or the scaled step became
    negligible, or no step can lower the cost any more."""
    x = np.array(x0, float)
    r = fun(x)
    cost = float(r @ r)
    lam = 1e-3
    for _ in range(max_iter):
        J = jac(x)
        A = J.T @ J
        grad = J.T @ r
        d = np.maximum(np.diag(A), 1e-300)
        while True:
            try:
                step = -np.linalg.solve(A + lam * np.diag(d), grad)
            except np.linalg.LinAlgError:
                step = None
            if step is not None:
                x_new = x + step
                r_new = fun(x_new)
                cost_new = float(r_new @ r_new)
                if np.isfinite(cost_new) and cost_new <= cost:
                    break
            lam *= 10.0
            if lam > 1e12:
                return x, True        # no step lowers the cost: at the minimum to rounding
        x, r = x_new, r_new
        small_step = np.all(np.abs(step) * np.sqrt(d) <= tol ** 0.5 * (1.0 + np.sqrt(cost)))
        done = cost - cost_new <= tol * cost or small_step
        cost = cost_new
        lam = max(lam / 10.0, 1e-12)
        if done:
            return x, True
    return x, False


def _initial_forces(device, m: np.ndarray) -> np.ndarray:
    """Pose forces from the nominal model, scaled to |f| = g."""
    S = device.nominal_sensitivity()
    F = np.linalg.lstsq(S, (m - device.nominal_offsets()[None, :]).T, rcond=None)[0].T
    n = np.linalg.norm(F, axis=1, keepdims=True)
    n[n == 0] = 1.0
    return device.gravity_mps2 * F / n


def _refine_start(device, m, sig, F, b0, s0):
    """Starting point for a jig-free solve: fit offsets and gains along the nominal
    axes with free poses (no gauge needed), which removes the large offsets."""
    P, N = m.shape
    prob = _StaticProblem(device, "gain", m, sig, None, True, F)
    if P * N < prob.n_ch + prob.n_pose:
        return b0, s0, F
    x, _ = _levenberg_marquardt(prob.residual, prob.jacobian, prob.pack(b0, s0), max_iter=30, tol=1e-8)
    b, s, _, _ = prob.unpack(x)
    F, _ = prob.forces(x)
    return b, s, F


def _constrained_inverse(J: np.ndarray, C: np.ndarray | None, rtol: float = MIN_RCOND_JAC) -> np.ndarray | None:
    """(J^T J)^-1, or Z (Z^T J^T J Z)^-1 Z^T with Z spanning null(C) when a gauge
    constraint C is given; None when rank deficient (a parameter not determined)."""
    if C is None:
        Z = None
        A = J
    else:
        _, _, Vt = np.linalg.svd(C)
        Z = Vt[C.shape[0]:].T
        A = J @ Z
    # scale columns so the rank test does not depend on units
    cn = np.linalg.norm(A, axis=0)
    if np.any(cn == 0):
        return None
    if A.shape[0] < A.shape[1]:
        return None
    _, sv, Vt = np.linalg.svd(A / cn, full_matrices=False)
    if not sv[-1] > rtol * sv[0]:
        return None
    Ci = ((Vt.T / sv ** 2) @ Vt) / np.outer(cn, cn)
    return Ci if Z is None else Z @ Ci @ Z.T


def _channel_cov(device, method, temperature, C, q) -> np.ndarray:
    """Map the per-channel blocks of C to [b, s_x, s_y, s_z, beta, gamma] (N,6,6)."""
    N = device.n_channels
    out = np.zeros((N, 6, 6))
    for i in range(N):
        blk = C[i * q:(i + 1) * q, i * q:(i + 1) * q]
        if method == "offset":
            Jm = np.zeros((6, q))
            Jm[0, 0] = 1
            j = 1
        elif method == "gain":
            Jm = np.zeros((6, q))
            Jm[0, 0] = 1
            Jm[1:4, 1] = device.axes[i]
            j = 2
        else:
            Jm = np.zeros((6, q))
            Jm[:4, :4] = np.eye(4)
            j = 4
        if temperature:
            Jm[4, j] = 1
            Jm[5, j + 1] = 1
        out[i] = Jm @ blk @ Jm.T
    return out


def calibrate_jigfree(device, means, method: str = "full", *, sigma: np.ndarray | None = None,
                      temperature: bool = False):
    """Jig-free calibration -> Calibration: unknown pose directions under |f| = g
    (gauge: see the module notes).  ``means``: a PoseSet (e.g. from
    :func:`poses_from_recording`) or a (P,N) array of pose means in counts (then
    ``sigma`` (P,N), or equal weights with the covariance from the residuals)."""
    poses = means if isinstance(means, PoseSet) else _bare_poses(_as_means(device, means))
    fit = fit_static(device, poses, method, jigfree=True, temperature=temperature, sigma=sigma)
    return to_calibration(device, fit, "jigfree")


def fit_temperature(device, poses: PoseSet, method: str = "full", *, f: np.ndarray | None = None,
                    sigma: np.ndarray | None = None, jig_accuracy_deg: float = JIG_ACCURACY_DEG) -> StaticFit:
    """Offset and gain against temperature (first order about the mean pose
    temperature) jointly with the channel parameters, for known pose forces
    ``f`` (default ``poses.f_ref``; pass a jig-free fit's ``f`` for hand-held data),
    uncertain by ``jig_accuracy_deg`` (see :func:`fit_known_poses`)."""
    ps = poses if f is None else PoseSet(poses.means, poses.n, poses.std, np.asarray(f, float), poses.temp,
                                         poses.info)
    return fit_static(device, ps, method, jigfree=False, temperature=True, sigma=sigma,
                      jig_accuracy_deg=jig_accuracy_deg)


def static_force(offsets, sensitivity, means, sigma=None) -> np.ndarray:
    """Specific force (P,3) of each static pose from its mean readings by (weighted)
    least squares f = argmin sum_i ((m_i - b_i - s_i.f)/sigma_i)^2."""
    m = np.atleast_2d(np.asarray(means, float)) - np.asarray(offsets, float)[None, :]
    S = np.asarray(sensitivity, float)
    if sigma is None:
        return np.linalg.lstsq(S, m.T, rcond=None)[0].T
    w = 1.0 / np.atleast_2d(np.asarray(sigma, float))
    out = np.empty((m.shape[0], 3))
    for p in range(m.shape[0]):
        out[p] = np.linalg.lstsq(S * w[p][:, None], m[p] * w[p], rcond=None)[0]
    return out


# ==============================================================================
# Lever arms from rotation data
# ==============================================================================


def calibrate_positions(device, offsets, sensitivity, raw, f, w, dw, *, segments: np.ndarray | None = None,
                        noise: np.ndarray | None = None, tol_m: float = POSITION_TOL_M,
                        source: str = "<arrays>") -> PositionFit:
    """Lever-arm corrections delta_r_i from samples with reference f, w and dw.

    raw_i - b_i - s_i . f(r_i) = s_i . (dw x dr_i + w x (w x dr_i)) + c_i,k = phi_i . dr_i + c_i,k
    with phi_i = s_i x dw + (s_i . w) w - |w|^2 s_i: linear per channel.  c_i,k is a
    constant per channel and per segment k (``segments``, e.g. one per recording),
    a nuisance that absorbs what the static calibration left in the offsets (else it
    would leak into dr through the mean of w^2).  The normal matrix of each channel
    is split into principal directions; a direction is observable when its 1-sigma
    is at most ``tol_m``; the estimate is kept only along the observable ones (zero,
    i.e. the nominal position, along the others).  ``noise``: per-sample noise of
    each channel (counts); default: from the residuals.
    """
    raw = np.asarray(raw, float)
    f, w, dw = (np.asarray(a, float) for a in (f, w, dw))
    seg = np.zeros(raw.shape[0], dtype=np.int64) if segments is None else np.asarray(segments, np.int64)
    ok = np.all(np.isfinite(f), 1) & np.all(np.isfinite(w), 1) & np.all(np.isfinite(dw), 1)
    if not ok.any():
        raise InputError(source, "no sample has f_*, w_* and dw_* all given: lever arms need rotation with a "
                         "reference", column="w_x")
    raw, f, w, dw, seg = raw[ok], f[ok], w[ok], dw[ok], seg[ok]
    b = np.asarray(offsets, float)
    S = np.asarray(sensitivity, float)
    from .model import predict_counts
    y = raw - predict_counts(b, S, device.positions, f, dw, w)        # (n,N)
    ww = np.sum(w * w, axis=1)
    phi = (np.cross(S[None, :, :], dw[:, None, :])
           + np.einsum("nj,ij->ni", w, S)[:, :, None] * w[:, None, :]
           - ww[:, None, None] * S[None, :, :])                           # (n,N,3)
    # remove the per-segment constant (Frisch-Waugh: demean y and phi within segments)
    _, seg = np.unique(seg, return_inverse=True)
    n_seg = int(seg.max()) + 1
    cnt = np.bincount(seg, minlength=n_seg).astype(float)

    def demean(a):
        flat = a.reshape(a.shape[0], -1)
        means = np.stack([np.bincount(seg, weights=flat[:, j], minlength=n_seg) for j in range(flat.shape[1])], 1)
        return (flat - (means / cnt[:, None])[seg]).reshape(a.shape)

    y = demean(y)
    phi = demean(phi)
    N = S.shape[0]
    A = np.einsum("nik,nil->ikl", phi, phi)                           # (N,3,3)
    rhs = np.einsum("nik,ni->ik", phi, y)
    sig = np.full(N, np.nan) if noise is None else np.asarray(noise, float).copy()
    dr = np.zeros((N, 3))
    cov = np.zeros((N, 3, 3))
    dirs = np.zeros((N, 3, 3))
    sd = np.zeros((N, 3))
    obs = np.zeros((N, 3), dtype=bool)
    rms = np.zeros(N)
    n = raw.shape[0]
    for i in range(N):
        lam, V = np.linalg.eigh(A[i])
        lam = np.maximum(lam, 0.0)
        keep = lam > 1e-12 * max(float(lam.max()), 1e-300)
        coef = np.where(keep, (V.T @ rhs[i]) / np.where(keep, lam, 1.0), 0.0)
        if not np.isfinite(sig[i]):
            res = y[:, i] - phi[:, i, :] @ (V @ coef)
            sig[i] = math.sqrt(float(res @ res) / max(n - n_seg - int(keep.sum()), 1))
        var = np.where(keep, sig[i] ** 2 / np.where(keep, lam, 1.0), np.inf)
        o = np.sqrt(var) <= tol_m
        dirs[i] = V.T
        sd[i] = np.sqrt(var)
        obs[i] = o
        dr[i] = V[:, o] @ coef[o]
        cov[i] = (V[:, o] * var[o]) @ V[:, o].T
        rms[i] = math.sqrt(float(np.mean((y[:, i] - phi[:, i, :] @ dr[i]) ** 2)))
    return PositionFit(delta_r=dr, cov=cov, directions=dirs, sigma=sd, observable=obs, n_samples=int(n),
                       tol_m=tol_m, residual_rms=rms)


# ==============================================================================
# Entry point for the CLI
# ==============================================================================


def calibrate_recordings(device, recordings: Sequence[Any], method: str | None = None, *,
                         jig_accuracy_deg: float = JIG_ACCURACY_DEG):
    """Calibrate ``device`` from recordings and return a Calibration.

    Static poses: a recording's ``pose`` labels when present, else automatic static
    detection.  Method: ``offset``/``gain``/``full`` need reference f_* on the poses
    (known poses); ``jigfree`` ignores any reference.  Default: ``full`` when every
    pose has a reference, ``jigfree`` when none has.  ``jig_accuracy_deg``: rms
    rotation angle by which the jig's poses may differ from their references
    (known poses only; see the module notes; default 0 = exact references).
    Temperature coefficients are fitted when the pose temperatures span at least
    TEMP_MIN_SPAN_C; lever arms when samples rotate (|w| > ROTATION_MIN_RADPS) with
    reference f, w and dw.
    """
    jig_accuracy_rad(jig_accuracy_deg)
    if method is not None and method not in METHODS + ("jigfree",):
        raise InputError("<command line>", f"unknown method {method!r}; expected one of "
                         f"{', '.join(METHODS + ('jigfree',))}", field="method")
    if not recordings:
        raise InputError("<command line>", "no recording given")
    rotating = [_rotating(rec) for rec in recordings]
    sets = [poses_from_recording(rec, device, required=not rot.any()) for rec, rot in zip(recordings, rotating)]
    poses = PoseSet.concat(sets)
    if poses.n_poses == 0:
        raise InputError(recordings[0].source, "no static pose in any recording: the offsets and sensitivities "
                         "need static poses (lever arms alone cannot be estimated without them)")
    has_f = np.all(np.isfinite(poses.f_ref), axis=1)
    if method is None:
        if has_f.all():
            method = "full"
        elif not has_f.any():
            method = "jigfree"
        else:
            p = int(np.flatnonzero(~has_f)[0])
            info = poses.info[p]
            raise InputError(info["source"], f"{_pose_label(poses.info, p)} has no reference f_x, f_y, f_z but "
                             "other poses do: give f on every pose, or choose --method jigfree", column="f_x")
    jigfree = method == "jigfree"
    model_method = "full" if jigfree else method
    if not jigfree and not has_f.all():
        p = int(np.flatnonzero(~has_f)[0])
        info = poses.info[p]
        where = _pose_label(poses.info, p) if info.get("label") is not None else \
            f"the static interval at t = {info['t_start']:.6g}..{info['t_stop']:.6g} s"
        raise InputError(info["source"], f"method '{method}' needs the reference specific force f_x, f_y, f_z on "
                         f"every static pose, but {where} has none (use --method jigfree for unknown poses)",
                         column="f_x")
    temps = poses.temp
    temperature = bool(np.all(np.isfinite(temps)) and np.ptp(temps) >= TEMP_MIN_SPAN_C)
    try:
        if jigfree:
            fit = fit_static(device, poses, model_method, jigfree=True, temperature=temperature)
        elif temperature:
            fit = fit_static(device, poses, model_method, jigfree=False, temperature=True,
                             jig_accuracy_deg=jig_accuracy_deg)
        else:
            fit = fit_known_poses(device, poses.means, poses.f_ref, model_method, poses.sem(), poses=poses,
                                  jig_accuracy_deg=jig_accuracy_deg)
    except InputError as e:
        if e.source != "<poses>":
            raise
        names = sorted({str(d.get("source")) for d in poses.info})
        raise InputError(", ".join(names), e.detail, field=e.field) from None

    pos_fit = None
    rot = [(rec, m) for rec, m in zip(recordings, rotating) if m.any()]
    if rot:
        raw = np.vstack([rec.raw[m] for rec, m in rot])
        f = np.vstack([rec.f[m] for rec, m in rot])
        w = np.vstack([rec.w[m] for rec, m in rot])
        dw = np.vstack([rec.dw[m] for rec, m in rot])
        segs = np.concatenate([np.full(int(m.sum()), k) for k, (_, m) in enumerate(rot)])
        b, S = fit.offsets, fit.sensitivity
        noise = fit.poses.channel_noise()
        pos_fit = calibrate_positions(device, b, S, raw, f, w, dw, segments=segs, noise=noise,
                                      source=rot[0][0].source)
    return to_calibration(device, fit, "jigfree" if jigfree else method, pos_fit)


def _rotating(rec) -> np.ndarray:
    if not (rec.has_omega() and rec.has_alpha() and rec.has_f()):
        return np.zeros(rec.n_samples, dtype=bool)
    ok = np.all(np.isfinite(rec.f), 1) & np.all(np.isfinite(rec.w), 1) & np.all(np.isfinite(rec.dw), 1)
    return ok & (np.linalg.norm(np.nan_to_num(rec.w), axis=1) > ROTATION_MIN_RADPS)


def _pose_names(info: list[dict]) -> list:
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
            import os
            name = f"{os.path.basename(str(d.get('source')))}:{name}"
        out.append(name)
    return out


def to_calibration(device, fit: StaticFit, method: str, positions: PositionFit | None = None):
    """Build the contract's Calibration from a fit: offsets, sensitivity, 1-sigma
    uncertainties, temperature terms, residual RMS per channel and per pose (counts),
    the poses used; ``extra`` holds the details (pose forces, fit statistics,
    temperature-coefficient uncertainties, lever-arm observability)."""
    from .calibration import Calibration

    names = _pose_names(fit.poses.info)
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
                f"estimated, the reference f as a prior (rms rotation {fit.jig_accuracy_deg:g} deg, |f| = |f_ref|)"
                if fit.jig_accuracy_deg > 0 else "reference f"),
            "gauge": ("sum_i u_i x s_i/|s_i| = 0 (Procrustes: estimated axes rotated as little as possible "
                      "from the nominal ones)") if (fit.jigfree and fit.method == "full") else (
                "fixed by the references' priors (the jig's frame)" if fit.jig_accuracy_deg > 0
                else "fixed by the reference"),
            "chi2": float(fit.chi2), "dof": int(fit.dof),
            "uncertainty": "1-sigma from the Fisher information, inflated by chi2/dof when > 1",
        },
        "poses": pose_detail,
    }
    if not fit.jigfree:
        extra["fit"]["jig_accuracy_deg"] = float(fit.jig_accuracy_deg)
        if fit.jig_hint_deg is not None:
            extra["fit"]["jig_accuracy_consistent_with_scatter_deg"] = float(fit.jig_hint_deg)
        if fit.jig_accuracy_deg > 0:
            extra["fit"]["uncertainty"] = (
                "1-sigma from the Fisher information of the readings and of the pose priors (each pose "
                f"direction within jig accuracy {fit.jig_accuracy_deg:g} deg rms of its reference; chi2 and dof "
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
        sensitivity_sigma=fit.sensitivity_sigma,
        position_sigma=pos_sig,
        temp_ref_c=fit.temp_ref_c,
        offset_tc=offset_tc,
        gain_tc=gain_tc,
        residual_rms_per_channel=fit.rms_per_channel(),
        residual_rms_per_pose={str(n): float(r) for n, r in zip(names, rpp)},
        poses_used=names,
        extra=extra,
    )
