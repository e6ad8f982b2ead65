"""Known poses whose readings point far from their stated f: checked before the fit.

A pose labelled with the wrong f (a six-position session whose file named +z holds the -z
pose) is no outlier the fit can name: the outlier rule needs 8 poses or more, and with six the
fit bends to it (a z sensitivity 0.07 x nominal, chi2/dof 6.5e7, and a warning that blamed the
scale).  Each pose's mean reading, taken through the device file's nominal scale and axes,
points somewhere; where it points far beyond what the nominal description can be off by, the
pose is not what its label says.

What the nominal description can be off by, and so the threshold (:func:`allowed_deg`):

* offsets: taken per channel as the poses' median of ``m_pi - k_i u_i . f_p`` (not the device
  file's zero), so a chip's zero-g offset of any size (an ADXL335's z: +-1 g) and a device file
  whose zero is half the range off do not enter, where most poses are right;
* scale: each channel's gain within device.NOMINAL_FACTOR (1.25) of the file's either way
  (beyond it calibrate warns of a wrong scale).  With gain K_i = 1 + e_i, |e_i| <= 0.25, the
  median offset takes (K_i - 1) k_i c_i (c_i the median of u_i . f_q), and the pose reads
  f_p + sum_i e_i (u_i . f_p - c_i) u_i: an error of at most 0.25 |U f_p - c| (times the norm of
  pinv(U) for axes that are not orthonormal), hence an angle of at most asin of that over
  |f_p|: 14.5 deg on the six faces +-x, +-y, +-z (c = 0);
* the axes, the jig and the level of the table: MISLABEL_SLACK_DEG (a chip's cross-axis
  sensitivity of +-2 % is 1.1 deg, its mounting a few degrees, a hand-held face or a table out of
  level up to 10 deg), and 3 x a stated jig accuracy (its rms angle).

The six faces' threshold is so 29.5 deg; a face taken for another is 90 or 180 deg off.  Where
most poses are beyond it (or the ones beyond it all agree once one channel's axis is reversed),
the device file (axis signs, channel order, scale) is the suspect instead.
"""
from __future__ import annotations

import math
import os

import numpy as np

from ..io.device import NOMINAL_FACTOR
from ..errors import InputError
from .checks import axis_name, pose_label, static_force

#: beyond the scale's bound, what the nominal axes, a jig and the table's level may add (deg)
MISLABEL_SLACK_DEG = 15.0

#: poses whose reading through the nominal scale is below this (in g) point nowhere (not checked)
MIN_READ_G = 0.1


def median_offsets(S: np.ndarray, means: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(N,) each channel's offset (counts) as the poses' median of ``m_pi - s_i . f_p`` (``S`` (N,3)
    the nominal sensitivities, counts per m/s^2; ``means`` (P,N) counts; ``F`` (P,3) m/s^2): robust
    to a minority of poses whose f is not the stated one, and to any zero-g offset."""
    return np.median(means - F @ S.T, axis=0)


def allowed_deg(device, F: np.ndarray, jig_accuracy_deg: float = 0.0) -> np.ndarray:
    """(P,) the largest angle (deg) between a pose's stated f and its reading through the nominal
    scale and axes (offsets by :func:`median_offsets`) that a device within its description gives
    (module notes): the scale's bound asin((NOMINAL_FACTOR - 1) |pinv(U)| |U f_p - c| / |f_p|),
    plus MISLABEL_SLACK_DEG, plus 3 x ``jig_accuracy_deg``."""
    U = np.asarray(device.axes, float)
    proj = F @ U.T
    c = np.median(proj, axis=0)
    e = max(NOMINAL_FACTOR - 1.0, 1.0 - 1.0 / NOMINAL_FACTOR) * np.linalg.norm(np.linalg.pinv(U), 2)
    rel = e * np.linalg.norm(proj - c, axis=1) / np.linalg.norm(F, axis=1)
    return np.degrees(np.arcsin(np.minimum(rel, 1.0))) + MISLABEL_SLACK_DEG + 3.0 * float(jig_accuracy_deg)


def reading_angles(device, means: np.ndarray, F: np.ndarray, flip: int | None = None):
    """The poses' readings through the nominal scale and axes (offsets by :func:`median_offsets`)
    in g (P,3) and their angles (deg) from the stated f (NaN where the reading is below
    MIN_READ_G); ``flip``: with that channel's axis reversed."""
    axes = np.array(device.axes, float)
    if flip is not None:
        axes[flip] *= -1.0
    S = np.asarray(device.counts_per_mps2, float)[:, None] * axes
    v = static_force(median_offsets(S, means, F), S, means) / device.gravity_mps2
    n = np.linalg.norm(v, axis=1)
    cos = np.sum(v * F, axis=1) / np.maximum(n * np.linalg.norm(F, axis=1), 1e-300)
    ang = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    ang[n < MIN_READ_G] = np.nan
    return v, ang


def check_stated_poses(device, poses, names: list[str], jig_accuracy_deg: float = 0.0) -> None:
    """Refuse known poses whose readings contradict their stated f (module notes).

    Parameters
    ----------
    device : Device
    poses : PoseSet
        Every pose with its stated f_ref (m/s^2).
    names : list of str
        Each pose's name for the message ("pose 0 (z_p)").
    jig_accuracy_deg : float
        The stated jig accuracy (rms angle, deg).

    Raises
    ------
    InputError
        Where a minority of poses read beyond :func:`allowed_deg` of their stated f: the first
        named with its file, its reading (g) and angle ("mislabelled or recorded in another
        orientation"); where most do, or one channel's reversed axis explains them all: the
        device file.
    """
    F = np.asarray(poses.f_ref, float)
    P = F.shape[0]
    U = np.asarray(device.axes, float)
    if P < 2 or np.linalg.matrix_rank(U) < 3 or not np.all(np.isfinite(F)):
        return
    v, ang = reading_angles(device, poses.means, F)
    lim = allowed_deg(device, F, jig_accuracy_deg)
    bad = np.flatnonzero(ang > lim)
    if not bad.size:
        return
    src = [os.path.basename(str(d.get("source"))) for d in poses.info]

    def one(p: int, file: bool = True) -> str:
        f = F[p] / device.gravity_mps2
        return (f"{names[p]}{f' ({src[p]})' if file else ''} reads f = ({', '.join(f'{x:+.2f}' for x in v[p])}) g, "
                f"{ang[p]:.0f} deg from its stated ({', '.join(f'{x:+.2f}' for x in f)}) g")

    why = (f"beyond the {np.min(lim[bad]):.0f} deg a device within its description allows (the readings through "
           f"the device file's scale and axes, offsets the poses' median; gains within {NOMINAL_FACTOR:g} x, "
           f"axes, jig and table within {MISLABEL_SLACK_DEG:g} deg)")
    flipped = [i for i in range(device.n_channels)
               if bad.size > 1 and np.all(np.nan_to_num(reading_angles(device, poses.means, F, i)[1]) <= lim)]
    if flipped:
        i = flipped[0]
        raise InputError(", ".join(sorted(set(src[p] for p in bad))),
                         f"{len(bad)} of {P} poses read their f reversed along channel {i}'s axis "
                         f"{axis_name(U[i], 1)} ({'; '.join(one(p) for p in bad[:3])}), {why}: with channel {i}'s "
                         f"axis {axis_name(U[i], -1)} every pose agrees: check the device file's axis signs (or "
                         "the poses' labels)")
    if 2 * bad.size > P:
        raise InputError(", ".join(sorted(set(src[p] for p in bad))),
                         f"{len(bad)} of {P} poses read f far from their stated f "
                         f"({'; '.join(one(p) for p in bad[:3])}{'; ...' if bad.size > 3 else ''}), {why}: "
                         "where most poses disagree, the device file is the suspect: check its channels' axis "
                         "signs and order and its scale (--full-scale, --lsb), and the f stated on the poses")
    others = np.setdiff1d(np.arange(P), bad)
    worst = np.nanmax(ang[others]) if np.isfinite(ang[others]).any() else math.nan
    more = (f"; also {'; '.join(one(p) for p in bad[1:3])}{'; ...' if bad.size > 3 else ''}"
            if bad.size > 1 else "")
    raise InputError(src[bad[0]], f"{one(bad[0], False)}, {why}, while the other {others.size} poses agree within "
                     f"{worst:.0f} deg: mislabelled or recorded in another orientation{more}; correct its "
                     "stated f (or leave it out)", column="f_x")


def pose_titles(info: list[dict], recordings) -> list[str]:
    """Each pose's name for a message: "pose 0 (z_p)" where its recording's ``pose_names``
    metadata (written by accelcal convert --regions) names its label, else "pose 0"
    (:func:`accelcal.calibrate.checks.pose_label`), "pose at t = ..s" for a detected one."""
    named: dict = {}
    for rec in recordings:
        pairs = (kv.split("=", 1) for kv in str(rec.metadata.get("pose_names", "")).split())
        named[rec.source] = {k: nm for k, nm in (p for p in pairs if len(p) == 2)}
    out = []
    for p, d in enumerate(info):
        if d.get("label") is None:
            out.append(f"the pose at t = {d.get('t_start', math.nan):.6g}..{d.get('t_stop', math.nan):.6g} s")
            continue
        nm = named.get(d.get("source"), {}).get(str(d["label"]))
        out.append(pose_label(info, p) + (f" ({nm})" if nm else ""))
    return out
