"""Sim-to-real diagnosis: how far the data are from the calibrated model, where the gap
lies, which unmodelled effect explains it, and how much of it that effect removes.

    result = diagnose(device, calibration, [recording, ...])      # the JSON object (a dict)
    write_report(result, "report/")                                # PNGs + summary.md

Definitions (what every number in the output means)
---------------------------------------------------
**Model prediction.**  The calibrated model of the data contract driven by the reference:
``pred_i = b_i(T) + g_i(T) s_i . f(r_i)`` with ``f(r) = f + alpha x r + m0 omega x (omega x r)``
(b, s, r and the temperature terms from the calibration; ``m0`` = 1, the contract's model,
or 0 with ``model_centripetal=False``), clipped to [raw_min, raw_max].  It is evaluated with
the effect registry's own ``effects.evaluate``.

* Reference mode (a recording with ``f_*``): every sample whose f (and, for a device with
  channels off the origin, w and dw; static poses count as w = dw = 0) is known.
* Jig-free mode (no recording has ``f_*``; e.g. the real Xsens recording): the static poses
  (``pose`` labels, else ``static.detect_static``) are the reference.  Each pose's specific
  force ``f_p`` is estimated from the pose mean with the calibration under ``|f_p| = g``.  The
  two pose angles are nuisance parameters, so the residual of every sample is projected on
  the N - 2 directions of channel space they cannot explain (per pose, the orthogonal
  complement of ``span(S e1, S e2)`` with e1, e2 across f_p; for a triad that is the one
  direction that changes |f|).  Fits and held-out scores use these projected rows; the
  breakdown ("where") uses the per-channel residual.

**Residual (the gap)**: ``e = raw - pred`` (counts).

**Noise floor** (from the data itself): per channel, from the static segments (pose labels /
detected static intervals) when they give at least MIN_NOISE_DOF degrees of freedom: the
dof-weighted median of the segments' residual variances (each segment's mean removed, so a
constant model error does not count; the median so that a few segments that drift or flip
between quantisation levels do not), corrected by the median of chi2_nu / nu; otherwise
``1.4826 MAD(d) / sqrt(70)`` of the fourth differences
``d = e[t-2] - 4 e[t-1] + 6 e[t] - 4 e[t+1] + e[t+2]`` inside contiguous segments (blind to any
smooth model error).  Floored at 1/sqrt(12) count (rounding).  The pooled floor is the RMS
over channels.  Both assume the noise is white at the sample rate; ``where.frequency_bands``
shows how far it is.

**Blocked cross-validation.**  Usable samples are cut into contiguous segments (a recording,
no time gap, one pose label).  Each segment is split into max(folds, ceil(length / 2 s))
contiguous blocks (a segment shorter than ``folds`` samples is one block); block j of a segment
goes to fold (j + o) mod folds with o a random offset per segment (``seed``).  So every static
pose has samples in every fold (per-pose parameters such as ``pose_error`` can be validated)
while neighbouring, correlated samples stay together.  A candidate's parameters are fitted on
the other folds and the residual is scored on the held-out fold.

**Scores.**  Weighted squares ``chi2 = sum w (residual)^2`` with w = 1 / noise_floor^2 of the
channel (row).  For a candidate, ``gain_b = chi2_b(before) - chi2_b(after)`` per held-out block;
``gain`` = its sum; ``t`` = mean(gain_b) / standard error over blocks (the blocks are the
independent units: residuals are correlated in time); ``penalty`` = PENALTY_PER_PARAM x the
number of parameters it adds; ``z = gain / (2 s2 sqrt(k K/(K-1)))`` compares the gain with its
spread under the null (noise only: mean ~ -k K/(K-1), standard deviation ~ 2 sqrt(k K/(K-1)) in
chi2 units), inflated by ``s2 = max(1, held-out chi2 after / rows)`` when the residual left is
larger than the noise floor says.  A candidate is **significant** when gain - penalty > 0,
(t >= T_MIN or z >= Z_MIN) and its shrink >= MIN_SHRINK -- or on proof from the raw values
(``quantization``: a lattice beyond doubt; ``saturation``: a pile of readings at one extreme
value while the model goes well beyond it).  The t route needs the gain in many blocks; the z
route also finds effects that show in a few blocks only (a short rotation among many static
poses).  Candidates are ranked by gain - penalty.

**Stepwise.**  The best significant candidate is added to the model (its in-sample fit is
subtracted from the residual) and every other candidate is scored again on what is left,
until none is significant or MAX_STEPS effects are in.  The verdict is the first one, or
``none``.  At the end the chosen effects are refitted jointly (backfitting) for the reported
model parameters.

**How far.**  ``heldout_rms_before`` / ``heldout_rms_after``: RMS (counts, over all held-out
rows) of the residual without / with the effect, each sample scored with parameters fitted
without its fold; ``shrink = 1 - after / before`` (0..1, clipped at 0): the fraction of the
held-out gap that adding the effect removes.  The benchmark's true shrink is the same ratio
with the true effect and its true parameters (tools/bench_diagnose.py).

Candidates (the registry's effects; parameters in the registry's concrete form, so that
``EFFECTS[name].apply(ctx, params)`` reproduces the fit):

* linear in their parameters given the reference, per-channel least squares: ``offset``,
  ``gain``, ``misalignment`` (first order in the rotation, 2 per channel), ``position_error``
  (3 per channel, kept along the principal directions with 1-sigma <= POSITION_TOL_M, 0 along
  the others), ``centripetal`` (the multiplier), ``nonlinearity``, ``bias_drift`` (a ramp in
  the recordings' own time from the earliest first sample: recordings that share a time base
  share it; with a reference f also a random walk's path, piecewise linear between knots, when
  it beats the ramp also with the orientation-dependent effects fitted alongside: _BiasDrift), ``temperature_offset`` / ``temperature_gain``
  (per-channel coefficients and one shared reference temperature: the calibration's
  ``temperature_ref_c`` when it has one, else fitted by a 1-D search within T_REF_SPANS spans of
  the recorded temperatures -- further out ``c (T - t_ref)`` would be an offset change in
  disguise);
* ``pose_error``: two angles per static pose (across the stated f), shared by the channels;
* 1-D nonlinear searches per channel: ``time_skew`` (the model's sensed signal shifted by tau
  along a cubic spline per run of samples contiguous in time, clamped at its ends) and
  ``bandwidth`` (the registry's first-order low-pass of the model prediction, run with lfilter,
  parameterised by the delay 1 / (2 pi f_c) >= 0): a grid, then two parabolic steps, per fold;
* from the raw values' distribution: ``saturation`` (a pile of readings at the extreme value
  of a channel, inside [raw_min, raw_max], where the model predicts beyond it; the levels are
  read from all the data and every block is scored with them, since the clipped samples
  often sit in one block that no training fold would see) and ``quantization`` (the raw
  values on a lattice of step q >= 2, likewise from all the data: a fold can miss the lattice
  on a channel with few distinct values); their predictions are the registry's clip of the
  model prediction, and the quantiser's expected error at it
  (``EFFECTS["quantization"].expected_error``) with the noise before the quantiser (``dither``,
  per channel, on the grid QUANT_DITHER_GRID of step fractions, chosen on all the data): with a
  step of a few noise floors the readings are dithered and the error averages into small
  per-pose biases, which the noise-free rounding (dither 0) would overstate.

Also reported: the static poses' mean residual against what noise explains
(``gap.pose_mean_*``), and the use of the raw values' low bits (``raw_values``; a note when
codes are missing or doubled without forming a lattice).

Candidates whose reference is missing are skipped with the reason (``skipped``).

The JSON object (``FORMAT``; arrays as lists, infinities as the strings "inf" / "-inf")
--------------------------------------------------------------------------------------
``verdict`` (an effect name or "none"); ``effects``: every candidate tried, the chosen ones
first in the order they were added, then the others by penalised gain, each with ``name``,
``shrink``, ``heldout_rms_before``, ``heldout_rms_after`` (counts), ``params`` (the registry's
concrete parameters), ``params_sigma`` (1-sigma, same shapes), ``units``, ``n_params``,
``significant``, ``selected``, ``step`` (1, 2, ... or null), ``baseline`` (what it was added to),
``alone`` (its figures when added alone to the calibrated model), ``score`` (``gain_chi2``,
``penalty_chi2``, ``penalised_gain_chi2``, ``t``, ``z``, ``evidence``), ``summary`` (one line in
physical units), ``notes``; the verdict's entry also ``ambiguous_with``.  ``model``: the chosen
effects refitted jointly (``params``, ``params_sigma``) with the held-out RMS before the first
and after the last and the total ``shrink``.  ``gap``: ``rms_counts``, ``noise_floor_counts``,
``ratio_to_noise``, per-channel figures, ``noise_method``, and for static poses
``pose_mean_rms_counts`` / ``pose_mean_noise_counts`` / ``pose_mean_ratio``.  ``where``:
``by_channel``, ``static_vs_rotating``, ``omega_bins``, ``alpha_bins`` (reference mode),
``frequency_bands`` (with the white-noise share of each band), ``temperature_bins`` (when
temp_c varies), ``time_bins``, ``poses``; each bin with ``n``, ``rms_counts``,
``ratio_to_noise``, ``rms_per_channel``, ``mean_per_channel``.  Also ``mode``, ``recordings``,
``skipped``, ``raw_values``, ``cv``, ``notes``, ``elapsed_s``.
"""
from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import lfilter

from .calibration import Calibration, load_calibration
from .device import Device, load_device
from .effects import EFFECT_NAMES, EFFECTS
from .errors import AccelcalError, InputError
from .model import centripetal_matrix, omega_products
from .motions import Trajectory
from .recording import Recording, check_for_device, read_recording
from .report import write_report as _wr
from .sensor import evaluate, rotation_matrix, true_state
from .static import detect_static

__all__ = [
    "diagnose",
    "write_report",
    "DiagnosisResult",
    "FORMAT",
    "T_MIN",
    "Z_MIN",
    "PENALTY_PER_PARAM",
    "MIN_SHRINK",
    "MAX_STEPS",
]

FORMAT = "accelcal-diagnosis/1"

# --- documented defaults ------------------------------------------------------
T_MIN = 4.0                # block t statistic a candidate's held-out gain must reach, or
Z_MIN = 6.0                # ... its held-out chi2 gain in units of its null spread
PENALTY_PER_PARAM = 2.0    # chi2 units per parameter an effect adds (AIC-like)
MIN_SHRINK = 0.005         # a significant effect removes at least this fraction of the gap
MAX_STEPS = 3              # effects found stepwise at most
BLOCK_S = 2.0              # longest cross-validation block in a moving segment (s)
MIN_NOISE_DOF = 30         # static samples needed for the static noise-floor estimate
ROTATING_RADPS = 0.05      # |w| above this counts as rotating (regimes, position_error)
TEMP_MIN_SPAN_C = 1.0      # temperature candidates need this span of temp_c
T_REF_SPANS = 2.0          # a fitted reference temperature stays within this many spans of temp_c
MISALIGN_MAX_RAD = 0.35     # relinearised misalignment fits stay below ~20 deg
POSITION_TOL_M = 1e-3      # position_error reports dr along directions with 1-sigma below this
QUANT_MIN_FRAC = 0.99      # share of readings on the lattice to call a channel quantised
QUANT_STRONG_FRAC = 0.999  # ... and to take the lattice alone as proof (with QUANT_STRONG_VALUES)
QUANT_STRONG_VALUES = 20   # distinct lattice values needed for the proof (chance <= 2^-19)
QUANT_MAX_STEP = 256
# noise before the quantiser, as a fraction of the step, tried for each quantised channel
QUANT_DITHER_GRID = (0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4)
SAT_PROOF_COUNT = 10       # readings at one extreme value, the model >= 5 sigma beyond: proof of a clip
BACKFIT_PASSES = 3
DRIFT_KNOT_FRACTIONS = (1 / 2, 1 / 4, 1 / 8, 1 / 16)  # bias_drift paths: knot spacing / time span
DRIFT_MIN_BLOCKS = 2       # ... each knot interval at least this many CV blocks long

_ROUND_SIGMA = math.sqrt(1.0 / 12.0)
_SKEW_GRID = np.array([0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 12.0])
_SKEW_GRID = np.concatenate([-_SKEW_GRID[:0:-1], _SKEW_GRID])          # in samples
_DELAY_GRID = np.array([0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0])  # samples


class DiagnosisResult(dict):
    """The diagnosis JSON object (a plain dict for ``json.dump``); ``series`` holds the
    per-sample arrays (time, residual before/after, noise floor) that :func:`write_report`
    plots.  It is not part of the JSON."""

    series: dict | None = None


# ==============================================================================
# Inputs
# ==============================================================================


def _as_device(device: Any):
    if isinstance(device, Device):
        return device
    if isinstance(device, (str, os.PathLike)):
        return load_device(device)
    raise AccelcalError(f"diagnose: expected a Device or a device JSON path, got {type(device).__name__}")


def _as_calibration(cal: Any, device) -> tuple[Any, str]:
    if isinstance(cal, (str, os.PathLike)):
        return load_calibration(cal, device), os.fspath(cal)
    if not isinstance(cal, Calibration):
        raise AccelcalError(f"diagnose: expected a Calibration or a calibration JSON path, got {type(cal).__name__}")
    src = str(cal.extra.get("source", "<calibration>")) if isinstance(cal.extra, dict) else "<calibration>"
    if cal.device != device.name:
        raise InputError(src, f"calibration is for {cal.device!r} but the device is {device.name!r}", field="device")
    if cal.n_channels != device.n_channels:
        raise InputError(src, f"calibration has {cal.n_channels} channels but the device {device.name!r} has "
                         f"{device.n_channels}", field="channels")
    if not (np.all(np.isfinite(cal.offsets)) and np.all(np.isfinite(cal.sensitivity))):
        raise InputError(src, "offsets and sensitivities must be finite", field="channels")
    return cal, src


def _as_recordings(recordings: Any, device) -> list:
    if isinstance(recordings, (Recording, str, os.PathLike)):
        recordings = [recordings]
    out = []
    for r in recordings:
        if isinstance(r, (str, os.PathLike)):
            r = read_recording(r, device.n_channels)
        if not isinstance(r, Recording):
            raise AccelcalError(f"diagnose: expected Recordings or CSV paths, got {type(r).__name__}")
        check_for_device(r, device, min_samples=2)
        out.append(r)
    if not out:
        raise InputError("<command line>", "no recording given")
    return out


# ==============================================================================
# The data the candidates work on
# ==============================================================================


@dataclass
class _Data:
    device: Any
    cal: Any
    mode: str                     # "reference" | "jigfree"
    m0: float                     # centripetal multiplier of the model
    K: int                        # folds
    t: np.ndarray                 # (n,) recording time
    tg: np.ndarray                # (n,) strictly increasing global time (recordings laid end to end)
    rec: np.ndarray               # (n,) recording index
    seg: np.ndarray               # (n,) segment index
    seg_lo: np.ndarray            # (S,) first sample of each segment
    seg_hi: np.ndarray            # (S,) one past the last
    bstart: np.ndarray            # (B,) first sample of each block (blocks are contiguous)
    bfold: np.ndarray             # (B,) fold of each block
    bseg: np.ndarray              # (B,)
    block: np.ndarray             # (n,)
    raw: np.ndarray               # (n, N) float
    pred: np.ndarray              # (n, N) model prediction, unclipped
    p0: np.ndarray                # (n, N) clipped to the ADC range
    offset_t: np.ndarray          # (n, N) b + bias(T)
    gain_t: np.ndarray | None     # (n, N) temperature gain factor or None
    sensed: np.ndarray            # (n, N) pred - offset_t
    f: np.ndarray                 # (n, 3) reference (or estimated) specific force
    w: np.ndarray                 # (n, 3)
    dw: np.ndarray                # (n, 3)
    temp: np.ndarray              # (n,) NaN unknown
    pose: np.ndarray              # (n,) global pose index, -1 none
    pose_labels: list             # [(recording index, label)] per global pose
    pose_stated: np.ndarray       # (n,) pose with a stated (reference) f, for pose_error
    static: np.ndarray            # (n,) bool
    s: np.ndarray                 # (N, 3)
    r: np.ndarray                 # (N, 3)
    b: np.ndarray                 # (N,)
    rec_t0: np.ndarray            # (n_rec,) first sample time of each recording
    rec_info: list
    notes: list
    Qp: np.ndarray | None = None  # (P, M, N) jig-free projections per pose
    sigma: np.ndarray | None = None   # (N,) noise floor
    noise_method: str = ""
    W: np.ndarray | None = None   # (n, R) row weights
    h: float = 0.0                # sample period (s)

    @property
    def n(self) -> int:
        return int(self.t.shape[0])

    @property
    def N(self) -> int:
        return int(self.raw.shape[1])

    @property
    def B(self) -> int:
        return int(self.bstart.shape[0])

    def rows(self, A: np.ndarray) -> np.ndarray:
        """Channel-space array (n, N) -> the rows that are fitted and scored (n, R)."""
        if self.Qp is None:
            return A
        return np.einsum("tmn,tn->tm", self.Qp[self.pose], A)

    @property
    def R(self) -> int:
        return self.N if self.Qp is None else int(self.Qp.shape[1])

    def bsum(self, a: np.ndarray) -> np.ndarray:
        """Per-block sums along axis 0."""
        return np.add.reduceat(a, self.bstart, axis=0)


def _tangent_basis(d: np.ndarray) -> np.ndarray:
    """(..., 2, 3) two unit vectors across each unit row of d (..., 3)."""
    d = np.asarray(d, float)
    helper = np.where(np.abs(d[..., :1]) < 0.9, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
    e2 = np.cross(d, e1)
    return np.stack([e1, e2], axis=-2)


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def _segments(t: np.ndarray, usable: np.ndarray, key: np.ndarray, h: float) -> list[tuple[int, int]]:
    """Contiguous runs of usable samples with one key and no time gap (index pairs)."""
    n = t.shape[0]
    brk = np.zeros(n, bool)
    brk[0] = True
    brk[1:] = (np.diff(t) > 1.5 * h) | (key[1:] != key[:-1]) | (usable[1:] != usable[:-1])
    starts = np.flatnonzero(brk)
    ends = np.append(starts[1:], n)
    return [(int(a), int(b)) for a, b in zip(starts, ends) if usable[a]]


def _jigfree_poses(rec, device) -> list[np.ndarray]:
    """Static poses of a recording without reference f: its pose labels, else detected."""
    if rec.has_pose():
        out = []
        for lab in rec.pose_labels():
            out.append(np.flatnonzero(rec.pose == lab))
        return out
    return [np.arange(a, b) for a, b in detect_static(rec, device)]


def _pose_force(S: np.ndarray, ybar: np.ndarray, g: float, wch: np.ndarray) -> np.ndarray:
    """f with |f| = g minimising sum_i w_i (ybar_i - s_i . f)^2 (Gauss-Newton on the sphere)."""
    sw = np.sqrt(wch)
    f = np.linalg.lstsq(S * sw[:, None], ybar * sw, rcond=None)[0]
    nf = np.linalg.norm(f)
    f = g * (f / nf if nf > 0 else np.array([0.0, 0.0, 1.0]))
    for _ in range(8):
        E = _tangent_basis(f / g)                        # (2,3)
        J = (S @ E.T) * sw[:, None]                      # (N,2)
        d = np.linalg.lstsq(J, (ybar - S @ f) * sw, rcond=None)[0]
        f = f + E.T @ d
        f = g * f / np.linalg.norm(f)
        if np.max(np.abs(d)) < 1e-12 * g:
            break
    return f


def _prepare(device, cal, recs: list, K: int, seed: int, m0: float) -> _Data:

    N = device.n_channels
    g = float(device.gravity_mps2)
    b = np.asarray(cal.offsets, float)
    S = np.asarray(cal.sensitivity, float)
    r = cal.positions_or_nominal(device)
    at_origin = bool(np.all(np.abs(r) < 1e-12))
    h = 1.0 / float(device.sample_rate_hz)
    has_f = [rec.has_f() for rec in recs]
    notes: list[str] = []
    if any(has_f):
        mode = "reference"
        keep = [i for i, hf in enumerate(has_f) if hf]
        for i, hf in enumerate(has_f):
            if not hf:
                notes.append(f"{recs[i].source}: skipped: no reference f while other recordings have one "
                             "(diagnose it on its own for a jig-free diagnosis)")
    else:
        mode = "jigfree"
        keep = list(range(len(recs)))

    parts = []
    rec_info = []
    for ri in keep:
        rec = recs[ri]
        n = rec.n_samples
        T = np.asarray(rec.temp_c, float)
        has_tc = cal.temp_ref_c is not None and (cal.offset_tc is not None or cal.gain_tc is not None)
        state = true_state(device, cal, T if has_tc else None)
        state = state.replace(centripetal=np.full(N, float(m0)))
        pose_lab = np.asarray(rec.pose, np.int64)
        if mode == "reference":
            traj = Trajectory.from_recording(rec, g)
            if at_origin:      # no rotation terms: w and dw are not needed
                traj.omega = np.nan_to_num(traj.omega)
                traj.alpha = np.nan_to_num(traj.alpha)
            with np.errstate(invalid="ignore"):
                pred = evaluate(traj, state)
            usable = np.all(np.isfinite(pred), axis=1)
            f, w, dw = traj.f, traj.omega, traj.alpha
            stated = pose_lab >= 0
            key = pose_lab.copy()
            how = "reference f" + (", w, dw" if rec.has_omega() else "") + (", temp_c" if rec.has_temp() else "")
        else:
            poses = _jigfree_poses(rec, device)
            off = state.total_offset()
            off = np.broadcast_to(off, (n, N))
            gain = np.ones((n, N)) if state.gain is None else state.gain
            y = (np.asarray(rec.raw, float) - off) / gain
            f = np.full((n, 3), np.nan)
            key = np.full(n, -1, np.int64)
            wch = 1.0 / np.maximum(np.asarray(device.noise_counts(), float), 1.0) ** 2 \
                if np.all(device.noise_counts() > 0) else np.ones(N)
            for p, idx in enumerate(poses):
                f[idx] = _pose_force(S, y[idx].mean(axis=0), g, wch)
                key[idx] = p
            w = np.where(np.isfinite(f), 0.0, np.nan)
            dw = w.copy()
            usable = np.all(np.isfinite(f), axis=1)
            pred = np.full((n, N), np.nan)
            fu = np.nan_to_num(f)
            pred[:] = off + gain * (fu @ S.T)
            pred[~usable] = np.nan
            stated = np.zeros(n, bool)
            pose_lab = key
            how = f"jig-free: {len(poses)} static poses, |f| = g"
        # readings at the ADC limits carry no information about the model (they would answer no effect)
        at_limit = np.any((rec.raw <= device.raw_min) | (rec.raw >= device.raw_max), axis=1)
        if np.any(at_limit & usable):
            notes.append(f"{rec.source}: {int(np.count_nonzero(at_limit & usable))} samples with a reading at the "
                         f"ADC limits ({device.raw_min} / {device.raw_max}) are left out")
            usable = usable & ~at_limit
        if not usable.any():
            if mode == "jigfree":
                raise InputError(rec.source, "no reference to diagnose against: no f_x, f_y, f_z columns and no "
                                 "static interval (at least 1 s at rest) whose |f| = g could serve instead")
            raise InputError(rec.source, "no sample has a complete reference (f_x, f_y, f_z, and w_*, dw_* while "
                             "moving) to predict the readings from", column="f_x")
        if mode == "reference" and usable.sum() < 0.5 * n:
            notes.append(f"{rec.source}: {int((~usable).sum())} of {n} samples lack part of the reference "
                         "(f, or w/dw while moving) and are left out")
        off = np.broadcast_to(state.total_offset(), (n, N))
        gain_t = None if state.gain is None else np.asarray(state.gain, float)
        parts.append(dict(ri=ri, rec=rec, usable=usable, pred=pred, off=off, gain=gain_t, f=f, w=w, dw=dw,
                          T=T, key=key, stated=stated, pose_lab=pose_lab))
        rec_info.append({"source": rec.source, "n_samples": int(n), "n_used": int(usable.sum()), "reference": how})

    # --- concatenate the usable samples, segments, global pose indices -----------------
    cols: dict[str, list] = {k: [] for k in ("t", "tg", "rec", "raw", "pred", "off", "gain", "f", "w", "dw", "T",
                                             "pose", "stated")}
    seg_lo, seg_hi = [], []
    tg_off = 0.0
    n_tot = 0
    pose_map: dict = {}
    rec_t0 = []
    for k, pt in enumerate(parts):
        rec, u = pt["rec"], pt["usable"]
        t = np.asarray(rec.t, float)
        rec_t0.append(float(t[0]))
        segs = _segments(t, u, pt["key"], h)
        idx = np.concatenate([np.arange(a, bb) for a, bb in segs])
        # local positions of the segments in the concatenated arrays
        pos = n_tot
        for a, bb in segs:
            seg_lo.append(pos)
            seg_hi.append(pos + bb - a)
            pos += bb - a
        tt = t[idx]
        cols["t"].append(tt)
        cols["tg"].append(tt - t[0] + tg_off)
        tg_off += float(t[-1] - t[0]) + 1000.0 * h + 1.0
        cols["rec"].append(np.full(idx.size, k))
        cols["raw"].append(np.asarray(rec.raw, float)[idx])
        cols["pred"].append(pt["pred"][idx])
        cols["off"].append(np.asarray(pt["off"], float)[idx])
        cols["gain"].append(np.ones((idx.size, N)) if pt["gain"] is None else pt["gain"][idx])
        for nm in ("f", "w", "dw"):
            cols[nm].append(np.asarray(pt[nm], float)[idx])
        cols["T"].append(pt["T"][idx])
        lab = pt["pose_lab"][idx]
        gp = np.full(idx.size, -1, np.int64)
        for L in np.unique(lab[lab >= 0]):
            keyp = (k, int(L))
            if keyp not in pose_map:
                pose_map[keyp] = len(pose_map)
            gp[lab == L] = pose_map[keyp]
        cols["pose"].append(gp)
        cols["stated"].append(pt["stated"][idx])
        n_tot += idx.size
    cat = {k: np.concatenate(v) for k, v in cols.items()}
    seg_lo = np.array(seg_lo, np.int64)
    seg_hi = np.array(seg_hi, np.int64)
    n = n_tot
    seg = np.repeat(np.arange(seg_lo.size), seg_hi - seg_lo)

    # --- blocks and folds -----------------------------------------------------------------
    rng = np.random.default_rng(seed)
    blen = max(1, int(round(BLOCK_S / h)))
    bstart, bfold, bseg = [], [], []
    for s_i, (a, bb) in enumerate(zip(seg_lo, seg_hi)):
        L = int(bb - a)
        nb = max(K, -(-L // blen)) if L >= K else 1
        edges = a + (np.arange(nb) * L) // nb
        o = int(rng.integers(K))
        for j, e0 in enumerate(edges):
            bstart.append(int(e0))
            bfold.append((j + o) % K)
            bseg.append(s_i)
    bstart = np.array(bstart, np.int64)
    bfold = np.array(bfold, np.int64)
    if len(np.unique(bfold)) < K:
        raise InputError(rec_info[0]["source"], f"too little data for {K}-fold cross-validation "
                         f"({n} usable samples in {len(bstart)} blocks)")
    block = np.repeat(np.arange(bstart.size), np.diff(np.append(bstart, n)))

    pred = cat["pred"]
    p0 = np.clip(pred, device.raw_min, device.raw_max)
    gain_t = cat["gain"] if np.any(cat["gain"] != 1.0) else None
    static = cat["pose"] >= 0
    D = _Data(device=device, cal=cal, mode=mode, m0=float(m0), K=K, t=cat["t"], tg=cat["tg"], rec=cat["rec"],
              seg=seg, seg_lo=seg_lo, seg_hi=seg_hi, bstart=bstart, bfold=bfold, bseg=np.array(bseg, np.int64),
              block=block, raw=cat["raw"], pred=pred, p0=p0, offset_t=cat["off"], gain_t=gain_t,
              sensed=pred - cat["off"], f=cat["f"], w=cat["w"], dw=cat["dw"], temp=cat["T"], pose=cat["pose"],
              pose_labels=[kk for kk, _ in sorted(pose_map.items(), key=lambda kv: kv[1])],
              pose_stated=np.where(cat["stated"], cat["pose"], -1), static=static, s=S, r=r, b=b,
              rec_t0=np.array(rec_t0), rec_info=rec_info, notes=notes, h=h)
    for i, pt in enumerate(parts):
        D.rec_info[i]["t0"] = rec_t0[i]
    return D


# ==============================================================================
# Noise floor and weights
# ==============================================================================


def _noise_floor(D: _Data, e: np.ndarray) -> tuple[np.ndarray, str]:
    N = D.N
    st = [(a, b) for a, b in zip(D.seg_lo, D.seg_hi) if D.static[a] and b - a >= 3]
    if st:
        var = np.array([np.var(e[a:b], axis=0, ddof=1) for a, b in st])      # (S, N)
        nu = np.array([b - a - 1 for a, b in st], float)
        dof = int(nu.sum())
        if dof >= MIN_NOISE_DOF:
            # the dof-weighted median of the segment variances (robust to a few segments that drift
            # or flip between quantisation levels), corrected by the median of chi2_nu / nu
            corr = (1.0 - 2.0 / (9.0 * nu)) ** 3
            v = var / corr[:, None]
            sig = np.empty(N)
            for i in range(N):
                o = np.argsort(v[:, i])
                cw = np.cumsum(nu[o])
                sig[i] = math.sqrt(v[o[np.searchsorted(cw, 0.5 * cw[-1])], i])
            return (np.maximum(sig, _ROUND_SIGMA),
                    f"median within-segment std of the residual over {len(st)} static segments ({dof} dof)")
    # fourth differences inside segments
    ok = np.zeros(D.n, bool)
    for a, b in zip(D.seg_lo, D.seg_hi):
        if b - a >= 5:
            ok[a + 2:b - 2] = True
    idx = np.flatnonzero(ok)
    if idx.size < 10:
        return np.full(N, max(_ROUND_SIGMA, float(np.std(e)) if e.size else 1.0)), "residual std (too few samples)"
    d = e[idx - 2] - 4 * e[idx - 1] + 6 * e[idx] - 4 * e[idx + 1] + e[idx + 2]
    mad = np.median(np.abs(d - np.median(d, axis=0)), axis=0)
    sig = 1.4826 * mad / math.sqrt(70.0)
    return np.maximum(sig, _ROUND_SIGMA), f"robust (MAD) fourth differences of the residual ({idx.size} samples)"


def _setup_rows(D: _Data, e: np.ndarray) -> None:
    sig, how = _noise_floor(D, e)
    D.sigma, D.noise_method = sig, how
    if D.mode == "jigfree":
        P = len(D.pose_labels)
        M = D.N - 2
        Qp = np.zeros((P, M, D.N))
        Wp = np.zeros((P, M))
        for p in range(P):
            sel = np.flatnonzero(D.pose == p)
            fp = _unit(D.f[sel[0]])
            E = _tangent_basis(fp)                       # (2,3)
            J = D.s @ E.T                                # (N,2)
            U, _, _ = np.linalg.svd(J, full_matrices=True)
            Q = U[:, 2:].T                               # (M,N)
            Qp[p] = Q
            Wp[p] = 1.0 / np.maximum(Q ** 2 @ sig ** 2, 1e-300)
        D.Qp = Qp
        D.W = Wp[D.pose]
    else:
        D.W = np.broadcast_to(1.0 / sig ** 2, (D.n, D.N))


# ==============================================================================
# Scoring
# ==============================================================================


@dataclass
class _Cand:
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
    # filled by _score
    gain: float = 0.0
    penalty: float = 0.0
    t: float = 0.0
    z: float = 0.0
    before: float = 0.0
    after: float = 0.0
    shrink: float = 0.0
    significant: bool = False


def _block_ss(D: _Data, Rr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    sq = Rr * Rr
    return D.bsum(np.sum(sq * D.W, axis=1)), D.bsum(sq.sum(axis=1))


def _score(D: _Data, c: _Cand, S0w: np.ndarray, S0u: np.ndarray) -> _Cand:
    gb = S0w - c.Sw
    c.gain = float(gb.sum())
    c.penalty = PENALTY_PER_PARAM * c.k
    nb = gb.size
    sd = float(np.std(gb, ddof=1)) if nb > 1 else 0.0
    c.t = float(np.mean(gb) / (sd / math.sqrt(nb))) if sd > 0 else (math.inf if c.gain > 0 else 0.0)
    rows = D.n * D.R
    c.before = float(math.sqrt(max(S0u.sum(), 0.0) / rows))
    c.after = float(math.sqrt(max(c.Su.sum(), 0.0) / rows))
    c.shrink = float(max(0.0, 1.0 - c.after / c.before)) if c.before > 0 else 0.0
    # chi2 route: under the null (noise only) the held-out gain has mean ~ -k K/(K-1) and spread
    # ~ 2 sqrt(k K/(K-1)) in chi2 units; s2 >= 1 scales it up when the residual left is larger than
    # the noise floor says (a low floor, correlated noise, other unmodelled effects).
    s2 = max(1.0, float(c.Sw.sum()) / rows)
    kk = max(c.k, 1) * D.K / (D.K - 1)
    c.z = float(c.gain / (2.0 * s2 * math.sqrt(kk)))
    c.significant = bool(c.proof or (c.gain - c.penalty > 0 and (c.t >= T_MIN or c.z >= Z_MIN)
                                     and c.shrink >= MIN_SHRINK))
    return c


# ==============================================================================
# Linear least squares by blocks
# ==============================================================================


def _solve_groups(G: np.ndarray, h: np.ndarray, rtol: float = 1e-10):
    """Batched min-norm solve of G theta = h (G (g,k,k) symmetric PSD), with Jacobi scaling.
    Returns theta (g,k), G^+ (g,k,k), rank (g,)."""
    d = np.sqrt(np.maximum(np.einsum("gii->gi", G), 0.0))
    d = np.where(d > 0, d, 1.0)
    Gs = G / d[:, :, None] / d[:, None, :]
    lam, V = np.linalg.eigh(Gs)
    lmax = np.max(lam, axis=-1, keepdims=True)
    keep = lam > rtol * np.maximum(lmax, 1e-300)
    inv = np.where(keep, 1.0 / np.where(keep, lam, 1.0), 0.0)
    Ginv = np.einsum("gij,gj,gkj->gik", V, inv, V) / d[:, :, None] / d[:, None, :]
    theta = np.einsum("gij,gj->gi", Ginv, h)
    return theta, Ginv, keep.sum(axis=-1)


def _lin_cv(D: _Data, Gw, hw, Gu, hu, S0w, S0u):
    """Fold fits and held-out block scores from block statistics (B, g, k, k) / (B, g, k)."""
    K, bf = D.K, D.bfold
    Gt, ht = Gw.sum(axis=0), hw.sum(axis=0)
    theta = np.zeros((K,) + ht.shape)
    for f in range(K):
        m = bf == f
        theta[f] = _solve_groups(Gt - Gw[m].sum(axis=0), ht - hw[m].sum(axis=0))[0]
    tb = theta[bf]
    Sw = S0w - 2 * np.einsum("bgk,bgk->b", tb, hw) + np.einsum("bgk,bgkl,bgl->b", tb, Gw, tb)
    Su = S0u - 2 * np.einsum("bgk,bgk->b", tb, hu) + np.einsum("bgk,bgkl,bgl->b", tb, Gu, tb)
    th_all, Ginv, rank = _solve_groups(Gt, ht)
    Sall = float(S0w.sum() - 2 * np.einsum("gk,gk->", th_all, ht) + np.einsum("gk,gkl,gl->", th_all, Gt, th_all))
    return Sw, Su, th_all, Ginv, rank, Sall


def _sep_stats(D: _Data, X: np.ndarray, y: np.ndarray):
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


def _joint_stats(D: _Data, Xr: np.ndarray, yr: np.ndarray):
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


def _jig_rows(D: _Data, X: np.ndarray) -> np.ndarray:
    """Per-channel columns X (n,N,k) -> projected joint rows (n, M, N k)."""
    Q = D.Qp[D.pose]                                     # (n,M,N)
    n, N, k = X.shape
    return np.einsum("tmi,tij->tmij", Q, X).reshape(n, Q.shape[1], N * k)


def _linear_fit(D: _Data, X: np.ndarray, y: np.ndarray, S0w, S0u):
    """CV of the per-channel linear columns X (n,N,k) on the target y (n,N).
    Returns Sw, Su, theta (N,k), cov (N,k,k), n_params, delta (n,N)."""
    n, N, k = X.shape
    if D.Qp is None:
        Gw, hw, Gu, hu = _sep_stats(D, X, y)
        Sw, Su, th, Ginv, rank, Sall = _lin_cv(D, Gw, hw, Gu, hu, S0w, S0u)
        theta, cov = th, Ginv
        npar = int(rank.sum())
    else:
        Xr = _jig_rows(D, X)
        yr = D.rows(y)
        Gw, hw, Gu, hu = _joint_stats(D, Xr, yr)
        Sw, Su, th, Ginv, rank, Sall = _lin_cv(D, Gw, hw, Gu, hu, S0w, S0u)
        theta = th[0].reshape(N, k)
        full = Ginv[0]
        cov = np.stack([full[i * k:(i + 1) * k, i * k:(i + 1) * k] for i in range(N)])
        npar = int(rank.sum())
    dof = max(D.n * D.R - npar, 1)
    cov = cov * max(1.0, Sall / dof)
    delta = np.einsum("tnk,nk->tn", X, theta)
    return Sw, Su, theta, cov, npar, delta


# ==============================================================================
# Candidates
# ==============================================================================


def _moving(D: _Data) -> bool:
    mv = ~D.static
    if not mv.any():
        return False
    x = D.sensed[mv]
    return bool(np.any(np.ptp(x, axis=0) > 5 * D.sigma))


def _rotating(D: _Data) -> np.ndarray:
    return np.linalg.norm(D.w, axis=1) > ROTATING_RADPS


def _f_at(D: _Data) -> np.ndarray:
    """(n,N,3) specific force at each channel's position (model terms)."""
    f = D.f[:, None, :]
    if np.all(D.r == 0):
        return np.broadcast_to(f, (D.n, D.N, 3))
    r = D.r[None, :, :]
    a = np.cross(D.dw[:, None, :], r)
    w = D.w[:, None, :]
    c = np.cross(w, np.cross(w, r)) * D.m0
    return f + a + c


def _temp_skip(D: _Data) -> str | None:
    T = D.temp
    if not np.all(np.isfinite(T)):
        return "needs temp_c (the recordings have no temperature)" if not np.isfinite(T).any() else \
            "needs temp_c on every sample used"
    span = float(np.ptp(T))
    if span < TEMP_MIN_SPAN_C:
        return f"temp_c varies by only {span:.3g} degC (needs {TEMP_MIN_SPAN_C:g})"
    return None


def _t_ref_known(D: _Data) -> float | None:
    cal = D.cal
    if cal.temp_ref_c is not None:
        return float(cal.temp_ref_c)
    poses = cal.extra.get("poses") if isinstance(cal.extra, dict) else None
    if isinstance(poses, list):
        ts = [p.get("temp_c") for p in poses if isinstance(p, dict) and isinstance(p.get("temp_c"), (int, float))]
        if ts:
            return float(np.mean(ts))
    return None


class _Candidate:
    name = ""

    def skip(self, D: _Data) -> str | None:
        return None

    def cv(self, D: _Data, y: np.ndarray, pcur: np.ndarray, S0w, S0u) -> _Cand:
        raise NotImplementedError


class _LinearCandidate(_Candidate):
    pname = ""

    def columns(self, D: _Data) -> np.ndarray:
        raise NotImplementedError

    def to_params(self, D: _Data, theta: np.ndarray, cov: np.ndarray) -> tuple[dict, dict]:
        sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
        return {self.pname: theta[:, 0]}, {self.pname: sd[:, 0]}

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        X = self.columns(D)
        Sw, Su, theta, cov, k, delta = _linear_fit(D, X, y, S0w, S0u)
        p, s = self.to_params(D, theta, cov)
        return _Cand(self.name, k, Sw, Su, delta, p, s)


class _Offset(_LinearCandidate):
    name, pname = "offset", "db"

    def columns(self, D):
        return np.ones((D.n, D.N, 1))


class _Gain(_LinearCandidate):
    name, pname = "gain", "scale"

    def columns(self, D):
        return D.sensed[:, :, None]


class _Nonlinearity(_LinearCandidate):
    name, pname = "nonlinearity", "k2"

    def columns(self, D):
        x = D.sensed / np.linalg.norm(D.s, axis=1)
        return (x * x)[:, :, None]


def _hat_basis(t: np.ndarray, t0: float, spacing: float, K: int) -> np.ndarray:
    """(n, K) piecewise-linear interpolation weights of the knots t0 + k spacing, k = 1..K (the
    knot at t0 is pinned at 0, as the ramp is, so that a path is no offset in disguise); beyond
    the last knot a path holds its last value."""
    u = np.clip((t - t0) / spacing, 0.0, float(K))
    k = np.minimum(np.floor(u).astype(np.int64), K - 1)
    fr = u - k
    X = np.zeros((t.size, K + 1))
    rows = np.arange(t.size)
    X[rows, k] = 1.0 - fr
    X[rows, k + 1] = fr
    return X[:, 1:]


class _BiasDrift(_LinearCandidate):
    """A ramp (one rate per channel) or, with a reference f, a bias path: piecewise linear in
    time through knots every ``spacing`` seconds (a random walk's path, estimated at the knots),
    for the spacings DRIFT_KNOT_FRACTIONS of the time span whose intervals hold DRIFT_MIN_BLOCKS
    CV blocks.  A path is the fit only if its penalised held-out gain beats the ramp's both
    alone and with the other linear effects that a path could pass for fitted alongside in
    either (offset, gain, misalignment, nonlinearity, and the temperature terms: a constant, a
    pose-wise pattern of poses visited in turn, a temperature that changes with time).  Jig-free, where every pose's orientation is fitted too, only the ramp is tried (on
    the real Xsens recording a path there took over a 0.5 % gain error).  Both are in recording
    time from the earliest first sample (recordings that share a time base share the drift)."""

    name, pname = "bias_drift", "rate"

    def columns(self, D):
        dt = D.t - float(np.min(D.rec_t0))
        return np.broadcast_to(dt[:, None, None], (D.n, D.N, 1)).copy()

    def to_params(self, D, theta, cov):
        p, s = super().to_params(D, theta, cov)
        p.update(rw=np.zeros(D.N), seed=0, t0=float(np.min(D.rec_t0)), path_t=np.zeros(0),
                 path=np.zeros((D.N, 0)))
        s.update(path=np.zeros((D.N, 0)))
        return p, s

    def _spacings(self, D) -> list[tuple[float, int]]:
        span = float(np.max(D.t)) - float(np.min(D.rec_t0))
        return [(span * frac, int(round(1.0 / frac))) for frac in DRIFT_KNOT_FRACTIONS
                if span * frac >= DRIFT_MIN_BLOCKS * BLOCK_S]

    @staticmethod
    def _nuisance(D) -> np.ndarray:
        """(n, N, 5 or 7): the columns of offset, gain, misalignment (2), nonlinearity and, with
        a usable temperature, temperature offset and gain (T and T times the reading)."""
        Xm, _ = _Misalignment()._cols(D, _f_at(D), D.s)
        x = D.sensed / np.linalg.norm(D.s, axis=1)
        cols = [np.ones((D.n, D.N, 1)), D.sensed[:, :, None], Xm, (x * x)[:, :, None]]
        if _temp_skip(D) is None:
            cols += [np.broadcast_to(D.temp[:, None, None], (D.n, D.N, 1)), (D.temp[:, None] * D.sensed)[:, :, None]]
        return np.concatenate(cols, axis=2)

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        ramp = super().cv(D, y, pcur, S0w, S0u, folds)
        spacings = self._spacings(D) if D.mode == "reference" else []

        def pgain(Sw, k):
            return float((S0w - Sw).sum()) - PENALTY_PER_PARAM * k

        def pgain_of(X):
            fit = _linear_fit(D, X, y, S0w, S0u)
            return pgain(fit[0], fit[4])

        best, best_pg, best_X = ramp, pgain(ramp.Sw, ramp.k), None
        t0 = float(np.min(D.rec_t0))
        for spacing, K in spacings:
            X = np.broadcast_to(_hat_basis(D.t, t0, spacing, K)[:, None, :], (D.n, D.N, K))
            Sw, Su, theta, cov, k, delta = _linear_fit(D, X, y, S0w, S0u)
            if pgain(Sw, k) <= best_pg:
                continue
            sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
            zero = np.zeros(D.N)
            p = {"rate": zero, "rw": zero, "seed": 0, "t0": t0, "path_t": t0 + spacing * np.arange(K + 1),
                 "path": np.concatenate([np.zeros((D.N, 1)), theta], axis=1)}
            s = {"rate": zero, "rw": zero, "path": np.concatenate([np.zeros((D.N, 1)), sd], axis=1)}
            best, best_pg, best_X = _Cand(self.name, k, Sw, Su, delta, p, s), pgain(Sw, k), X
        if best_X is not None:
            # the path must also win with every other smooth or pose-wise linear effect alongside
            Z = self._nuisance(D)
            if pgain_of(np.concatenate([best_X, Z], axis=2)) <= pgain_of(np.concatenate([self.columns(D), Z], axis=2)):
                return ramp
        return best


class _Misalignment(_LinearCandidate):
    """s_i -> Exp(rot_i) s_i.  Linear to first order; for tilts of more than a few tenths of a
    degree the fit is relinearised (Gauss-Newton) about the all-data estimate rot0, and every
    fold fits the increment about it: delta = exact(rot0) + X(rot0) d."""

    name = "misalignment"

    def _cols(self, D, fa, S):
        E = _tangent_basis(_unit(S))                        # (N,2,3)
        X = np.einsum("nkc,tnc->tnk", E, np.cross(S[None, :, :], fa))    # rot . (s x f_at)
        if D.gain_t is not None:
            X = X * D.gain_t[:, :, None]
        return X, E

    def _exact(self, D, fa, rot):
        S1 = np.einsum("nij,nj->ni", rotation_matrix(rot), D.s)
        d = np.einsum("tnc,nc->tn", fa, S1 - D.s)
        return d * D.gain_t if D.gain_t is not None else d, S1

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        fa = _f_at(D)
        X, E = self._cols(D, fa, D.s)
        Sw, Su, theta, cov, k, delta = _linear_fit(D, X, y, S0w, S0u)
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
                s0w, s0u = _block_ss(D, yr)
                Sw1, Su1, th1, cov1, k1, dlin = _linear_fit(D, X1, yr, s0w, s0u)
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
        return _Cand(self.name, k, Sw, Su, delta, {"rot": rot}, {"rot": sd})


class _PositionError(_LinearCandidate):
    name = "position_error"

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: static poses only, no rotation reference (w, dw)"
        if not _rotating(D).any() and not np.any(np.linalg.norm(D.dw, axis=1) > 10 * ROTATING_RADPS):
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
        Sw, Su, theta, cov, k, delta = _linear_fit(D, X, y, S0w, S0u)
        # report dr only along the observable principal directions (1-sigma <= POSITION_TOL_M)
        lam, V = np.linalg.eigh(cov)
        obs = np.sqrt(np.maximum(lam, 0.0)) <= POSITION_TOL_M
        coef = np.einsum("nji,nj->ni", V, theta) * obs
        theta = np.einsum("nij,nj->ni", V, coef)
        cov = np.einsum("nij,nj,nkj->nik", V, np.where(obs, lam, 0.0), V)
        delta = np.einsum("tnk,nk->tn", X, theta)
        sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
        c = _Cand(self.name, k, Sw, Su, delta, {"dr": theta}, {"dr": sd})
        nobs = int(obs.sum())
        if nobs < obs.size:
            c.notes.append(f"dr kept along {nobs} of {obs.size} principal directions (the others have 1-sigma "
                           f"> {1e3 * POSITION_TOL_M:g} mm with this motion; reported as 0)")
        c.observable = obs
        return c


class _Centripetal(_LinearCandidate):
    name, pname = "centripetal", "scale"

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: static poses only, no rotation reference (w)"
        if np.all(D.r == 0):
            return "every channel is at the origin: there is no centripetal term"
        if not _rotating(D).any():
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


class _Temperature(_Candidate):
    """c_i (T - t_ref) z_i with z = 1 (offset) or the sensed reading (gain); t_ref shared."""

    def __init__(self, name: str, gain: bool):
        self.name = name
        self.gain = gain

    def skip(self, D):
        return _temp_skip(D)

    def _z(self, D):
        return D.sensed if self.gain else np.ones((D.n, D.N))

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        z = self._z(D)
        T = D.temp
        # columns T z and z: c (T - t_ref) z = c (X2 . [1, -t_ref])
        X2 = np.stack([T[:, None] * z, z], axis=2)
        fixed = _t_ref_known(D)
        if D.Qp is None:
            Gw2, hw2, Gu2, hu2 = _sep_stats(D, X2, y)
        else:
            Gw2, hw2, Gu2, hu2 = _joint_stats(D, _jig_rows(D, X2), D.rows(y))
        N = D.N
        Tlo, Thi = float(T.min()), float(T.max())
        span = max(Thi - Tlo, 1e-9)

        def reduce(G2, h2, tr):
            v = np.array([1.0, -tr])
            if D.Qp is None:
                return (np.einsum("...kl,k,l->...", G2, v, v)[..., None, None],
                        np.einsum("...k,k->...", h2, v)[..., None])
            P = N
            Vm = np.zeros((2 * P, P))
            for i in range(P):
                Vm[2 * i:2 * i + 2, i] = v
            return (np.einsum("...ab,ai,bj->...ij", G2, Vm, Vm), np.einsum("...a,ai->...i", h2, Vm))

        def objective(G2, h2, tr):
            G, hh = reduce(G2, h2, tr)
            th = _solve_groups(G, hh)[0]
            return -float(np.einsum("gk,gk->", th, hh))         # S = q - h' th at the optimum

        def best_tref(G2, h2):
            if fixed is not None:
                return fixed
            # within two spans of the data: further out, c (T - t_ref) is an offset change in disguise
            grid = np.linspace(Tlo - T_REF_SPANS * span, Thi + T_REF_SPANS * span, 41)
            vals = [objective(G2, h2, tr) for tr in grid]
            j = int(np.argmin(vals))
            from scipy.optimize import minimize_scalar
            lo, hi = grid[max(j - 1, 0)], grid[min(j + 1, grid.size - 1)]
            res = minimize_scalar(lambda tr: objective(G2, h2, tr), bounds=(lo, hi), method="bounded",
                                  options={"xatol": 1e-3 * span})
            return float(res.x) if res.fun <= vals[j] else float(grid[j])

        K, bf = D.K, D.bfold
        Gt2, ht2 = Gw2.sum(0), hw2.sum(0)
        Sw = np.empty(D.B)
        Su = np.empty(D.B)
        for f in range(K):
            m = bf == f
            Gtr, htr = Gt2 - Gw2[m].sum(0), ht2 - hw2[m].sum(0)
            tr = best_tref(Gtr, htr)
            G, hh = reduce(Gtr, htr, tr)
            th = _solve_groups(G, hh)[0]
            Gb, hb = reduce(Gw2[m], hw2[m], tr)
            Gub, hub = reduce(Gu2[m], hu2[m], tr)
            Sw[m] = S0w[m] - 2 * np.einsum("gk,bgk->b", th, hb) + np.einsum("gk,bgkl,gl->b", th, Gb, th)
            Su[m] = S0u[m] - 2 * np.einsum("gk,bgk->b", th, hub) + np.einsum("gk,bgkl,gl->b", th, Gub, th)
        tr = best_tref(Gt2, ht2)
        G, hh = reduce(Gt2, ht2, tr)
        th, Ginv, rank = _solve_groups(G, hh)
        Sall = float(S0w.sum() - np.einsum("gk,gk->", th, hh))
        npar = int(rank.sum()) + (0 if fixed is not None else 1)
        scale = max(1.0, Sall / max(D.n * D.R - npar, 1))
        if D.Qp is None:
            coeff = th[:, 0]
            sd = np.sqrt(np.maximum(Ginv[:, 0, 0] * scale, 0.0))
        else:
            coeff = th[0]
            sd = np.sqrt(np.maximum(np.diag(Ginv[0]) * scale, 0.0))
        delta = coeff[None, :] * (T - tr)[:, None] * z
        params = {"coeff": coeff, "t_ref": tr}
        sigma = {"coeff": sd, "t_ref": 0.0 if fixed is not None else math.nan}
        notes = [] if fixed is None else [f"t_ref = {fixed:.4g} degC from the calibration"]
        if fixed is None:
            # 1-sigma of t_ref from the curvature of the profile objective
            hstep = 0.05 * span + 0.5
            o0, op, om = (objective(Gt2, ht2, tr + d) for d in (0.0, hstep, -hstep))
            curv = (op + om - 2 * o0) / hstep ** 2
            sigma["t_ref"] = float(math.sqrt(2.0 * scale / curv)) if curv > 0 else math.inf
        return _Cand(self.name, npar, Sw, Su, delta, params, sigma, notes)


class _PoseError(_Candidate):
    name = "pose_error"

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
                E[p] = _tangent_basis(_unit(D.f[sel].mean(axis=0)))
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
        Sw, Su, th, Ginv, rank, Sall = _lin_cv(D, Gw, hw, Gu, hu, S0w, S0u)
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
        return _Cand(self.name, npar, Sw, Su, delta, params, {"rot": sd[keep]})


# --- 1-D searches -----------------------------------------------------------------


class _Shifter:
    """x(t + tau) per channel along a cubic spline per run of samples contiguous in time
    (clamped at the run's ends)."""

    def __init__(self, D: _Data, x: np.ndarray):
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


class _SearchCandidate(_Candidate):
    """One scalar parameter u per channel (in samples); delta(D, u (N,)) -> (n, N)."""

    grid = _SKEW_GRID
    lower = -math.inf

    def skip(self, D):
        if D.mode == "jigfree":
            return "jig-free: static poses only, no reference of the motion"
        if not _moving(D):
            return "needs motion in the reference (time effects show only while the readings change)"
        return None

    def prepare(self, D: _Data, pcur: np.ndarray):
        raise NotImplementedError

    def delta(self, u: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def to_params(self, D, u, su) -> tuple[dict, dict]:
        raise NotImplementedError

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        self.prepare(D, pcur)
        N, K, bf = D.N, D.K, D.bfold
        wch = D.W[0]
        grid = self.grid
        Sg = np.empty((grid.size, D.B, N))                  # unweighted block SS per channel
        for gi, u in enumerate(grid):
            R = y - self.delta(np.full(N, u))
            Sg[gi] = D.bsum(R * R)
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
        return _Cand(self.name, npar, Sw, Su, d_all, p, s)


class _TimeSkew(_SearchCandidate):
    name = "time_skew"
    grid = _SKEW_GRID

    def prepare(self, D, pcur):
        self.D = D
        if getattr(D, "_shifter", None) is None:
            D._shifter = _Shifter(D, D.sensed)
        self.sh = D._shifter

    def delta(self, u):
        return self.sh.delta(np.asarray(u, float) * self.D.h)

    def to_params(self, D, u, su):
        return {"tau": u * D.h}, {"tau": su * D.h}


def _lowpass_runs(t: np.ndarray, x: np.ndarray, w: float, h: float) -> np.ndarray:
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


class _Bandwidth(_SearchCandidate):
    name = "bandwidth"
    grid = _DELAY_GRID
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
                out[np.ix_(idx, cols)] = _lowpass_runs(self.D.t[idx], xs, 1.0 / (v * self.D.h), self.D.h) - xs
        return out

    def to_params(self, D, u, su):
        d = u * D.h
        fc = np.where(d > 0, 1.0 / (2 * math.pi * np.maximum(d, 1e-300)), math.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            sfc = np.where(d > 0, fc * (su * D.h) / np.maximum(d, 1e-300), math.inf)
        return {"fc_hz": fc}, {"fc_hz": sfc, "delay_s": su * D.h}


# --- from the raw values ---------------------------------------------------------


def _lattice(v: np.ndarray) -> tuple[int, float, float, int]:
    """Best lattice of integer readings v: (step, phase, share of readings on it, distinct values on it).
    Step 1 when none is found (share >= QUANT_MIN_FRAC with >= 6 distinct values)."""
    u, cnt = np.unique(v.astype(np.int64), return_counts=True)
    tot = float(cnt.sum())
    best = (1, 0.0, 1.0, int(u.size))
    if u.size < 6:
        return best
    span = int(u[-1] - u[0])
    # exact lattice: the gcd of the differences of the values
    gq = int(np.gcd.reduce(np.diff(u)))
    if gq >= 2:
        return (gq, float(u[0] % gq), 1.0, int(u.size))
    # robust: a lattice that holds for QUANT_MIN_FRAC of the readings (a few strays allowed); dense
    # readings (most neighbouring values one count apart) are on none
    if np.mean(np.diff(u) == 1) > 0.3:
        return best
    for q in range(2, min(QUANT_MAX_STEP, max(span // 3, 2)) + 1):
        res = u % q
        bc = np.bincount(res, weights=cnt, minlength=q)
        ph = int(np.argmax(bc))
        frac = bc[ph] / tot
        if frac >= QUANT_MIN_FRAC:
            nd = int(np.count_nonzero(res == ph))
            if nd >= 6:
                best = (q, float(ph), float(frac), nd)
    return best


class _Quantization(_Candidate):
    name = "quantization"

    def _fit(self, D, mask):
        N = D.N
        step = np.zeros(N)
        phase = np.zeros(N)
        frac = np.ones(N)
        nd = np.zeros(N, np.int64)
        for i in range(N):
            q, ph, fr, n_d = _lattice(D.raw[mask, i])
            if q >= 2:
                step[i], phase[i], frac[i], nd[i] = q, ph, fr, n_d
        # one converter, one lattice: the gcd of the steps found is tried on every channel (a channel
        # that sits on a few levels shows no lattice, or a multiple of the step, on its own)
        found = step[step >= 2].astype(np.int64)
        if found.size:
            qc = int(np.gcd.reduce(found))
            if qc >= 2:
                for i in range(N):
                    v = D.raw[mask, i].astype(np.int64)
                    u, cnt = np.unique(v, return_counts=True)
                    bc = np.bincount(u % qc, weights=cnt, minlength=qc)
                    ph = int(np.argmax(bc))
                    share = float(bc[ph] / cnt.sum())
                    if u.size >= 2 and share >= QUANT_MIN_FRAC:
                        step[i], phase[i], frac[i], nd[i] = qc, ph, share, int(np.count_nonzero(u % qc == ph))
        return step, phase, frac, nd

    @staticmethod
    def _delta(pcur, step, phase, dither):
        return EFFECTS["quantization"].expected_error(pcur, step, phase, dither)

    def _dither(self, y, pcur, step, phase):
        """Per channel, the dither s (as a fraction of the step, on a grid) whose expected error
        best matches the residual: a step of a few noise floors is neither a sawtooth nor noise."""
        best = np.zeros(step.size)
        sse = np.full(step.size, np.inf)
        for r in QUANT_DITHER_GRID:
            d = self._delta(pcur, step, phase, r * step)
            e = np.sum((y - d) ** 2, axis=0)
            better = e < sse
            best[better], sse[better] = r * step[better], e[better]
        return best

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        # The lattice is read off the raw values, not fitted to the residual; a training fold can
        # miss it on a channel with few distinct values (static poses): the lattice comes from all
        # the data and every block is scored with it.
        step, phase, frac, nd = self._fit(D, np.ones(D.n, bool))
        dither = self._dither(y, pcur, step, phase)
        delta = self._delta(pcur, step, phase, dither)
        Sw, Su = _block_ss(D, D.rows(y - delta))
        c = _Cand(self.name, int(np.count_nonzero(step)), Sw, Su, delta, {"step": step}, {"step": np.zeros(D.N)})
        strong = (step > 0) & (frac >= QUANT_STRONG_FRAC) & (nd >= QUANT_STRONG_VALUES)
        if np.any(strong):
            c.proof = True
            c.evidence = "lattice of the raw values (read from all the data)"
            c.notes.append("raw values on a lattice: " + ", ".join(
                f"channel {i}: step {int(step[i])} ({100 * frac[i]:.2f} % of readings, {nd[i]} values)"
                for i in np.flatnonzero(strong)))
        c.params["phase"] = phase
        c.params["dither"] = dither
        return c


class _Saturation(_Candidate):
    name = "saturation"

    def _fit(self, D, mask, pcur, with_proof=False):
        N = D.N
        lo = np.full(N, -math.inf)
        hi = np.full(N, math.inf)
        proof = []
        for i in range(N):
            v = D.raw[mask, i]
            pc = pcur[mask, i]
            sig = float(D.sigma[i])
            band = max(4.0 * sig, 4.0)
            for side in (1, -1):
                ext = v.max() if side > 0 else v.min()
                if (side > 0 and ext >= D.device.raw_max) or (side < 0 and ext <= D.device.raw_min):
                    continue
                at = v == ext
                c = int(at.sum())
                if c < 5:
                    continue
                near = (side * (ext - v) > 0) & (side * (ext - v) <= band)
                dens = near.sum() / band
                if c < 4.0 * dens + 5:
                    continue
                beyond = side * float(np.median(pc[at] - ext))
                if beyond <= max(sig, 0.5):
                    continue
                if side > 0:
                    hi[i] = ext
                else:
                    lo[i] = ext
                if c >= SAT_PROOF_COUNT and beyond >= 5.0 * max(sig, 0.5):
                    proof.append(f"channel {i}: {c} readings at {ext:g} while the model goes {beyond:.3g} counts "
                                 "beyond (median)")
        return (lo, hi, proof) if with_proof else (lo, hi)

    @staticmethod
    def _delta(pcur, lo, hi):
        return np.clip(pcur, lo, hi) - pcur

    def cv(self, D, y, pcur, S0w, S0u, folds=True):
        # The clip levels are read off the raw values (the pile), not fitted to the residual, and the
        # clipped samples usually sit in one or two blocks, which no training fold would see: the
        # levels come from all the data and every block is scored with them.
        lo, hi, proof = self._fit(D, np.ones(D.n, bool), pcur, with_proof=True)
        delta = self._delta(pcur, lo, hi)
        Sw, Su = _block_ss(D, D.rows(y - delta))
        k = int(np.count_nonzero(np.isfinite(lo)) + np.count_nonzero(np.isfinite(hi)))
        sd = {"lo": np.where(np.isfinite(lo), 0.5, 0.0), "hi": np.where(np.isfinite(hi), 0.5, 0.0)}
        c = _Cand(self.name, k, Sw, Su, delta, {"lo": lo, "hi": hi}, sd)
        c.evidence = "pile of readings at the clip level (levels read from all the data)"
        if proof:
            c.proof = True
            c.notes.append("readings pile up at " + "; ".join(proof))
        return c


def _candidates() -> dict[str, _Candidate]:
    c = [_Offset(), _Gain(), _Misalignment(), _PositionError(), _Centripetal(), _TimeSkew(), _Bandwidth(),
         _Nonlinearity(), _Temperature("temperature_offset", False), _Temperature("temperature_gain", True),
         _BiasDrift(), _Saturation(), _Quantization(), _PoseError()]
    out = {x.name: x for x in c}
    assert tuple(out) == EFFECT_NAMES, "diagnose: candidates out of step with the effect registry"
    return out


# ==============================================================================
# Where: the gap broken down
# ==============================================================================


def _bin(label: str, mask: np.ndarray, e: np.ndarray, sigma: np.ndarray, **extra) -> dict:
    n = int(mask.sum())
    x = e[mask]
    rms_ch = np.sqrt(np.mean(x * x, axis=0)) if n else np.zeros(e.shape[1])
    rms = float(np.sqrt(np.mean(rms_ch ** 2))) if n else 0.0
    floor = float(np.sqrt(np.mean(sigma ** 2)))
    out = {"label": label, **extra, "n": n, "rms_counts": rms, "ratio_to_noise": rms / floor if floor > 0 else None,
           "rms_per_channel": rms_ch.tolist(), "mean_per_channel": (x.mean(axis=0) if n else rms_ch * 0).tolist()}
    return out


def _bins_by(values: np.ndarray, edges: Sequence[float], unit: str, e, sigma) -> list[dict]:
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (values >= lo) & (values < hi)
        if m.any():
            lab = f"{lo:g}-{hi:g} {unit}" if math.isfinite(hi) else f">= {lo:g} {unit}"
            out.append(_bin(lab, m, e, sigma, lo=float(lo), hi=float(hi) if math.isfinite(hi) else None))
    return out


def _where(D: _Data, e: np.ndarray) -> dict:
    sig = D.sigma
    N = D.N
    rms_ch = np.sqrt(np.mean(e * e, axis=0))
    by_channel = [{"channel": i, "rms_counts": float(rms_ch[i]), "noise_floor_counts": float(sig[i]),
                   "ratio_to_noise": float(rms_ch[i] / sig[i]), "mean_counts": float(e[:, i].mean()),
                   "rms_mps2": float(rms_ch[i] / np.linalg.norm(D.s[i]))} for i in range(N)]
    wn = np.linalg.norm(D.w, axis=1)
    an = np.linalg.norm(D.dw, axis=1)
    rot = wn > ROTATING_RADPS
    regimes = []
    for lab, m in (("static", D.static), ("rotating", rot & ~D.static), ("moving, not rotating", ~rot & ~D.static)):
        if m.any():
            regimes.append(_bin(lab, m, e, sig))
    out: dict = {"by_channel": by_channel, "static_vs_rotating": regimes}
    if D.mode == "reference":
        out["omega_bins"] = _bins_by(wn, [0, ROTATING_RADPS, 0.5, 2.0, 5.0, math.inf], "rad/s", e, sig)
        out["alpha_bins"] = _bins_by(an, [0, 0.5, 5.0, 20.0, 100.0, math.inf], "rad/s^2", e, sig)
    # frequency bands (energy of the residual by FFT of each contiguous segment)
    fs = 1.0 / D.h
    edges = [0.0, 0.1, 1.0, 3.0, 10.0, 30.0, math.inf]
    edges = [x for x in edges if x < fs / 2] + [math.inf]
    E = np.zeros((len(edges) - 1, N))
    for a, b in zip(D.seg_lo, D.seg_hi):
        x = e[a:b]
        L = b - a
        if L < 8:
            E[0] += np.sum(x * x, axis=0)
            continue
        X = np.fft.rfft(x, axis=0)
        p = np.abs(X) ** 2 / L
        p[1:] *= 2.0
        if L % 2 == 0:
            p[-1] /= 2.0
        fr = np.fft.rfftfreq(L, d=D.h)
        k = np.searchsorted(edges, fr, side="right") - 1
        for j in range(len(edges) - 1):
            E[j] += p[k == j].sum(axis=0)
    floor = float(np.sqrt(np.mean(sig ** 2)))
    bands = []
    for j in range(len(edges) - 1):
        rc = np.sqrt(E[j] / D.n)
        rms = float(np.sqrt(np.mean(rc ** 2)))
        hi = edges[j + 1]
        lab = f"{edges[j]:g}-{hi:g} Hz" if math.isfinite(hi) else f">= {edges[j]:g} Hz"
        # white noise spreads evenly up to fs/2: its share of the band
        top = min(hi, fs / 2)
        share = max(top - edges[j], 0.0) / (fs / 2)
        wn = floor * math.sqrt(share)
        bands.append({"label": lab, "lo_hz": edges[j], "hi_hz": top, "rms_counts": rms,
                      "white_noise_rms_counts": wn, "ratio_to_white_noise": rms / wn if wn > 0 else None,
                      "rms_per_channel": rc.tolist()})
    out["frequency_bands"] = bands
    T = D.temp
    if np.all(np.isfinite(T)) and np.ptp(T) >= TEMP_MIN_SPAN_C:
        q = np.quantile(T, np.linspace(0, 1, 6))
        q[-1] = np.nextafter(q[-1], math.inf)
        out["temperature_bins"] = _bins_by(T, list(q), "degC", e, sig)
    tb = []
    for k in np.unique(D.rec):
        sel = D.rec == k
        tt = D.t[sel]
        ed = np.linspace(tt.min(), tt.max(), 11)
        ed[-1] = np.nextafter(ed[-1], math.inf)
        idx = np.flatnonzero(sel)
        for lo, hi in zip(ed[:-1], ed[1:]):
            m = np.zeros(D.n, bool)
            m[idx[(tt >= lo) & (tt < hi)]] = True
            if m.any():
                tb.append(_bin(f"rec {int(k)}: {lo:.4g}-{hi:.4g} s", m, e, sig, recording=int(k),
                               t0=float(lo), t1=float(hi)))
    out["time_bins"] = tb
    if len(D.pose_labels):
        pl = []
        for p, (rr, L) in enumerate(D.pose_labels):
            m = D.pose == p
            if m.any():
                pl.append(_bin(f"rec {rr}: pose {L}", m, e, sig, recording=int(rr), pose=int(L)))
        pl.sort(key=lambda d: -d["rms_counts"])
        out["poses"] = pl[:200]
    return out


# ==============================================================================
# JSON helpers and descriptions
# ==============================================================================


def _pose_mean_gap(D: _Data, e: np.ndarray) -> dict:
    """RMS of the static poses' mean residual rows against what the noise alone gives them."""
    P = len(D.pose_labels)
    if P < 2:
        return {}
    Rr = D.rows(e)
    cnt = np.bincount(D.pose[D.pose >= 0], minlength=P).astype(float)
    on = D.pose >= 0
    ms, vs = [], []
    for j in range(Rr.shape[1]):
        s1 = np.bincount(D.pose[on], weights=Rr[on, j], minlength=P)
        iv = np.bincount(D.pose[on], weights=1.0 / D.W[on, j], minlength=P)
        ok = cnt > 0
        ms.append((s1[ok] / cnt[ok]) ** 2)
        vs.append(iv[ok] / cnt[ok] ** 2)
    rms = float(np.sqrt(np.mean(np.concatenate(ms))))
    noise = float(np.sqrt(np.mean(np.concatenate(vs))))
    return {"pose_mean_rms_counts": rms, "pose_mean_noise_counts": noise,
            "pose_mean_ratio": rms / noise if noise > 0 else None, "n_poses": int(np.count_nonzero(cnt))}


def _json(v: Any) -> Any:
    if isinstance(v, dict):
        return {str(k): _json(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_json(x) for x in v]
    if isinstance(v, np.ndarray):
        return _json(v.tolist())
    if isinstance(v, (np.integer,)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        x = float(v)
        if math.isfinite(x):
            return x
        return "inf" if x > 0 else "-inf" if x < 0 else None
    if isinstance(v, np.bool_):
        return bool(v)
    return v


def _units(name: str) -> dict:
    return {fp.name: fp.unit for fp in EFFECTS[name].fit}


def _strongest(v: np.ndarray) -> int:
    v = np.asarray(v, float)
    a = np.where(np.isfinite(v), np.abs(v), -1.0)
    return int(np.argmax(a))


def _describe(name: str, p: dict, s: dict, D: _Data) -> str:
    """One line in physical units for the summary."""
    ks = np.linalg.norm(D.s, axis=1)
    g = float(D.device.gravity_mps2)
    try:
        if name == "offset":
            i = _strongest(p["db"])
            return (f"offset change up to {p['db'][i]:+.4g} +- {s['db'][i]:.2g} counts "
                    f"({p['db'][i] / ks[i]:+.4g} m/s^2) on channel {i}")
        if name == "gain":
            i = _strongest(p["scale"])
            return f"gain error up to {100 * p['scale'][i]:+.4g} +- {100 * s['scale'][i]:.2g} % on channel {i}"
        if name == "misalignment":
            a = np.degrees(np.linalg.norm(p["rot"], axis=1))
            i = int(np.argmax(a))
            return f"axis tilt up to {a[i]:.3g} deg (+- {np.degrees(np.linalg.norm(s['rot'][i])):.2g}) on channel {i}"
        if name == "position_error":
            d = 1e3 * np.linalg.norm(p["dr"], axis=1)
            i = int(np.argmax(d))
            return f"position error up to {d[i]:.3g} mm (+- {1e3 * np.linalg.norm(s['dr'][i]):.2g}) on channel {i}"
        if name == "centripetal":
            return (f"centripetal term multiplier {np.mean(p['scale']):.3g} (model {D.m0:g}; per channel "
                    f"{np.min(p['scale']):.3g}..{np.max(p['scale']):.3g})")
        if name == "time_skew":
            i = _strongest(p["tau"])
            return f"time skew up to {1e3 * p['tau'][i]:+.4g} +- {1e3 * s['tau'][i]:.2g} ms on channel {i}"
        if name == "bandwidth":
            fc = np.asarray(p["fc_hz"], float)
            i = int(np.argmin(fc))
            return (f"low-pass cut-off down to {fc[i]:.4g} Hz (delay {1e3 * s['delay_s'][i]:.2g} ms 1-sigma) "
                    f"on channel {i}")
        if name == "nonlinearity":
            i = _strongest(p["k2"])
            return (f"quadratic term up to {p['k2'][i]:+.4g} counts/(m/s^2)^2 on channel {i} "
                    f"({100 * p['k2'][i] * g / ks[i]:+.3g} % of the reading at 1 g)")
        if name == "temperature_offset":
            i = _strongest(p["coeff"])
            return (f"offset tempco up to {p['coeff'][i]:+.4g} +- {s['coeff'][i]:.2g} counts/degC on channel {i} "
                    f"(t_ref {p['t_ref']:.4g} degC)")
        if name == "temperature_gain":
            i = _strongest(p["coeff"])
            return (f"gain tempco up to {1e6 * p['coeff'][i]:+.4g} +- {1e6 * s['coeff'][i]:.2g} ppm/degC "
                    f"on channel {i} "
                    f"(t_ref {p['t_ref']:.4g} degC)")
        if name == "bias_drift" and np.size(p.get("path_t", ())):
            path = np.asarray(p["path"], float)
            i, j = np.unravel_index(int(np.argmax(np.abs(path))), path.shape)
            kt = np.asarray(p["path_t"], float)
            return (f"offset wanders (random-walk path, knots every {kt[1] - kt[0]:.3g} s) up to "
                    f"{path[i, j]:+.4g} +- {s['path'][i, j]:.2g} counts ({path[i, j] / ks[i]:+.4g} m/s^2) "
                    f"on channel {i}")
        if name == "bias_drift":
            i = _strongest(p["rate"])
            return (f"offset ramp up to {p['rate'][i]:+.4g} +- {s['rate'][i]:.2g} counts/s "
                    f"({3600 * p['rate'][i] / ks[i]:+.3g} m/s^2 per hour) on channel {i}")
        if name == "saturation":
            parts = [f"ch {i}: " + "..".join(f"{x:g}" for x in (p["lo"][i], p["hi"][i]))
                     for i in range(D.N) if np.isfinite(p["lo"][i]) or np.isfinite(p["hi"][i])]
            return "readings clip at " + ("; ".join(parts) if parts else "(no limit found)")
        if name == "quantization":
            st = [f"ch {i}: {int(q)}" for i, q in enumerate(p["step"]) if q > 0]
            return "quantisation steps (counts) " + (", ".join(st) if st else "(none found)")
        if name == "pose_error":
            a = np.degrees(np.linalg.norm(p["rot"], axis=1))
            if not a.size:
                return "no stated pose"
            return f"stated pose orientations off by up to {a.max():.3g} deg (median {np.median(a):.3g} deg)"
    except (KeyError, ValueError, IndexError):
        pass
    return name


def _entry(D: _Data, c: _Cand, *, step: int | None, selected: bool, baseline: str, alone: _Cand | None = None) -> dict:
    e = {
        "name": c.name,
        "shrink": c.shrink,
        "heldout_rms_before": c.before,
        "heldout_rms_after": c.after,
        "params": _json(c.params),
        "params_sigma": _json(c.sigma),
        "units": _units(c.name),
        "n_params": int(c.k),
        "significant": bool(c.significant),
        "selected": bool(selected),
        "step": step,
        "baseline": baseline,
        "score": {"gain_chi2": c.gain, "penalty_chi2": c.penalty, "penalised_gain_chi2": c.gain - c.penalty,
                  "t": c.t if math.isfinite(c.t) else 1e9, "z": c.z, "evidence": c.evidence},
        "summary": _describe(c.name, c.params, c.sigma, D),
    }
    if c.notes:
        e["notes"] = list(c.notes)
    a = alone if alone is not None else c
    e["alone"] = {"shrink": a.shrink, "heldout_rms_before": a.before, "heldout_rms_after": a.after}
    return e


# ==============================================================================
# The diagnosis
# ==============================================================================


def _run_candidates(D, cands, names, y, pcur, progress):
    Rr = D.rows(y)
    S0w, S0u = _block_ss(D, Rr)
    out = {}
    for nm in names:
        c = cands[nm].cv(D, y, pcur, S0w, S0u)
        out[nm] = _score(D, c, S0w, S0u)
        if progress is not None:
            progress(nm)
    return out, S0w, S0u


def _rank_key(c: _Cand):
    return (-(c.gain - c.penalty), c.k)


def diagnose(device: Any, calibration: Any, recordings: Any, *, folds: int = 5, seed: int = 0,
             candidates: Sequence[str] | None = None, max_steps: int = MAX_STEPS, model_centripetal: bool = True,
             progress: Any = None) -> DiagnosisResult:
    """Diagnose the gap between recordings and a calibrated model (see the module doc).

    ``device``, ``calibration``: objects or JSON paths; ``recordings``: Recordings or CSV
    paths (one or several).  ``folds``: cross-validation folds; ``seed``: fold assignment.
    ``candidates``: effect names to try (default: every effect of the registry).
    ``model_centripetal``: False diagnoses a model without the omega x (omega x r) term.
    ``progress``: optional callable(name) called after each candidate is scored.
    Returns the JSON object of the data contract (a dict; see :class:`DiagnosisResult`).
    Bad input raises :class:`~accelcal.errors.InputError` / AccelcalError (one line).
    """
    t_start = time.perf_counter()
    if isinstance(folds, bool) or not isinstance(folds, (int, np.integer)) or folds < 2:
        raise AccelcalError(f"diagnose: folds must be an integer >= 2, got {folds!r}")
    dev = _as_device(device)
    cal, cal_src = _as_calibration(calibration, dev)
    recs = _as_recordings(recordings, dev)
    cands = _candidates()
    if candidates is None:
        names = list(EFFECT_NAMES)
    else:
        names = []
        for nm in candidates:
            if nm not in cands:
                raise AccelcalError(f"diagnose: unknown candidate effect {nm!r}; effects: {', '.join(EFFECT_NAMES)}")
            names.append(nm)
    D = _prepare(dev, cal, recs, int(folds), int(seed), 1.0 if model_centripetal else 0.0)
    e = D.raw - D.p0
    _setup_rows(D, e)

    skipped = []
    active = []
    for nm in names:
        why = cands[nm].skip(D)
        if why is None:
            active.append(nm)
        else:
            skipped.append({"name": nm, "reason": why})

    # --- step 1: every candidate alone, then stepwise --------------------------------------------
    y = e.copy()
    pcur = D.p0.copy()
    first, _, S0u = _run_candidates(D, cands, active, y, pcur, progress)
    base_rms = float(math.sqrt(S0u.sum() / (D.n * D.R)))
    steps: list[tuple[_Cand, str]] = []
    results = first
    remaining = list(active)
    chosen: list[str] = []
    while True:
        sig = [c for c in results.values() if c.significant]
        if not sig:
            break
        best = sorted(sig, key=_rank_key)[0]
        baseline = "the calibrated model" + ("" if not chosen else " + " + " + ".join(chosen))
        steps.append((best, baseline))
        chosen.append(best.name)
        remaining.remove(best.name)
        if best.gain > 0:
            y = y - best.delta
            pcur = pcur + best.delta
        if len(chosen) >= max_steps or not remaining:
            break
        results, _, _ = _run_candidates(D, cands, remaining, y, pcur, progress)

    # --- joint refit of the chosen effects (backfitting) -----------------------------------------
    joint: dict[str, _Cand] = {c.name: c for c, _ in steps}
    if len(steps) > 1:
        deltas = {c.name: (c.delta if c.gain > 0 else np.zeros_like(c.delta)) for c, _ in steps}
        for _ in range(BACKFIT_PASSES):
            for c, _ in steps:
                if c.gain <= 0:
                    continue
                others = sum((deltas[o] for o in deltas if o != c.name), np.zeros_like(e))
                yt = e - others
                R0 = D.rows(yt)
                s0w, s0u = _block_ss(D, R0)
                cc = cands[c.name].cv(D, yt, D.p0 + others, s0w, s0u, folds=False)
                deltas[c.name] = cc.delta
                joint[c.name] = cc
    total_delta = np.zeros_like(e)
    for c, _ in steps:
        if c.gain > 0:
            total_delta += joint[c.name].delta

    # --- output ------------------------------------------------------------------------------------
    effects = []
    for k, (c, baseline) in enumerate(steps):
        effects.append(_entry(D, c, step=k + 1, selected=True, baseline=baseline, alone=first.get(c.name)))
    rest = sorted((c for nm, c in first.items() if nm not in chosen), key=_rank_key)
    for c in rest:
        effects.append(_entry(D, c, step=None, selected=False, baseline="the calibrated model"))
    verdict = steps[0][0].name if steps else "none"
    model_after = steps[-1][0].after if steps else base_rms
    floor = float(np.sqrt(np.mean(D.sigma ** 2)))
    rms_ch = np.sqrt(np.mean(e * e, axis=0))
    gap_rms = float(np.sqrt(np.mean(rms_ch ** 2)))
    notes = list(D.notes)
    if D.mode == "jigfree":
        notes.append("jig-free: the static poses with |f| = g are the reference; fitted and scored on the "
                     f"{D.R} direction(s) per sample the pose angles cannot absorb")
    if steps and len(steps) > 1:
        notes.append("effects after the first were scored on the residual left by the ones before (their in-sample "
                     "fits subtracted); 'model' gives the joint refit")
    # near-ties for the verdict: candidates whose held-out gain is within a few null spreads of it
    ties = []
    if steps:
        b0 = steps[0][0]
        for c in first.values():
            if c.name != b0.name and c.significant and (b0.gain - c.gain) < 3.0 * math.sqrt(max(b0.gain, 1.0)) \
                    and abs(c.shrink - b0.shrink) < 0.02:
                ties.append(c.name)
        effects[0]["ambiguous_with"] = ties
    if ties:
        notes.append(f"{verdict} is barely ahead of {', '.join(ties)}: the data hardly tell them apart")
    if D.mode == "jigfree" and len(D.pose_labels) < 6:
        notes.append(f"only {len(D.pose_labels)} static pose(s) found: effects that are constant within a pose "
                     "(offset, gain, misalignment, nonlinearity) can hardly be told apart")
    lattice = []
    for i in range(D.N):
        q, ph, fr, nd = _lattice(D.raw[:, i])
        ent = {"channel": i, "step": int(q), "share_on_lattice": fr, "distinct_values": int(nd)}
        if q == 1 and D.n >= 500:
            # uneven use of the low bits (missing or doubled codes): the most used residue class mod m
            v = D.raw[:, i].astype(np.int64)
            best = None
            for m in (2, 3, 4):
                share = float(np.max(np.bincount(v % m, minlength=m))) / D.n
                if best is None or share - 1.0 / m > best[1] - 1.0 / best[0]:
                    best = (m, share)
            ent["low_bits"] = {"modulus": best[0], "share_of_top_residue": best[1], "uniform_share": 1.0 / best[0]}
            if best[1] - 1.0 / best[0] > 0.1:
                notes.append(f"raw_{i}: {100 * best[1]:.0f} % of the readings fall in one residue class mod {best[0]} "
                             f"({100 / best[0]:.0f} % for evenly used codes): the lowest bits are unevenly used "
                             "(missing or doubled codes: a rescaled or differentially nonlinear ADC); not a lattice")
        lattice.append(ent)
    gap_extra = _pose_mean_gap(D, e)
    result = DiagnosisResult({
        "format": FORMAT,
        "verdict": verdict,
        "device": dev.name,
        "calibration": {"source": cal_src, "method": cal.method},
        "mode": D.mode,
        "recordings": D.rec_info,
        "n_samples": D.n,
        "n_channels": D.N,
        "gap": {
            "rms_counts": gap_rms,
            "noise_floor_counts": floor,
            "ratio_to_noise": gap_rms / floor if floor > 0 else None,
            "heldout_rms_counts": base_rms,
            "noise_floor_per_channel": D.sigma.tolist(),
            "rms_per_channel": rms_ch.tolist(),
            "noise_method": D.noise_method,
            **gap_extra,
        },
        "effects": effects,
        "model": {
            "effects": chosen,
            "heldout_rms_before": base_rms,
            "heldout_rms_after": model_after,
            "shrink": float(max(0.0, 1.0 - model_after / base_rms)) if base_rms > 0 else 0.0,
            "params": {nm: _json(joint[nm].params) for nm in chosen},
            "params_sigma": {nm: _json(joint[nm].sigma) for nm in chosen},
        },
        "skipped": skipped,
        "where": _json(_where(D, e)),
        "raw_values": lattice,
        "cv": {"folds": D.K, "blocks": D.B, "seed": int(seed), "block_s": BLOCK_S,
               "t_min": T_MIN, "z_min": Z_MIN, "penalty_per_param_chi2": PENALTY_PER_PARAM, "min_shrink": MIN_SHRINK,
               "rule": "significant: held-out chi2 gain > penalty, (block t >= t_min or chi2 z >= z_min), "
                       "shrink >= min_shrink"},
        "notes": notes,
        "model_centripetal": bool(model_centripetal),
        "elapsed_s": time.perf_counter() - t_start,
    })
    result["where"] = _json(result["where"])
    result.series = {
        "tg": D.tg, "t": D.t, "rec": D.rec, "residual": e, "residual_after": e - total_delta,
        "noise_floor": D.sigma, "sources": [ri["source"] for ri in D.rec_info], "static": D.static,
    }
    return result


def write_report(result: dict, out_dir: Any, **kw: Any) -> list[str]:
    """Plots and a short written summary of a diagnosis into ``out_dir`` (see :mod:`accelcal.report`)."""
    return _wr(result, out_dir, **kw)
