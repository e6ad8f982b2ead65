"""Whether a calibration's lever arms are good enough for the array's own omega
(docs/angular-rate.md): a position error delta_r_i adds s_i . (omega x (omega x delta_r_i)) to
channel i, which the omega estimator reads as a bias of omega proportional to |omega|."""
from __future__ import annotations

import numpy as np

from .. import model
from .settings import POSITION_TOL_M

__all__ = ["OMEGA_CHECK_RADPS", "lever_arm_omega_warning", "lever_arm_omega_bias"]

#: the |omega| (rad/s) at which the lever arms' effect is stated
OMEGA_CHECK_RADPS = 10.0


def _rates() -> np.ndarray:
    d = np.random.default_rng(36).normal(size=(24, 3))
    return OMEGA_CHECK_RADPS * d / np.linalg.norm(d, axis=1, keepdims=True)


def lever_arm_omega_bias(device, cal) -> tuple[float, float, np.ndarray] | None:
    """The array omega's error at |omega| = OMEGA_CHECK_RADPS from the positions' uncertainty.

    Returns
    -------
    (bias, noise, sigma) or None
        ``bias``: rms over 24 rate directions of the 1-sigma omega error (rad/s) that the
        position uncertainty gives (a bias: the same on every sample at that rate);
        ``noise``: the per-sample Cramer-Rao bound there (rad/s, sqrt of the trace);
        ``sigma`` (N, 3) the position sigma used (m): the calibration's, or POSITION_TOL_M where a
        channel's position was not calibrated.  None when the layout does not observe omega.
    """
    S = np.asarray(cal.sensitivity, float)
    pos = cal.positions_or_nominal(device)
    noise = np.sqrt(np.asarray(device.noise_counts(), float) ** 2 + 1.0 / 12.0)
    try:
        split = model.centripetal_split(pos, S, noise)
    except np.linalg.LinAlgError:
        return None
    w = _rates()
    info = model.omega_information(split.m, w)
    # zero information beside the centripetal readings' own size: six channels, or a layout
    # that leaves an axis of omega to the integration (nothing of the array's omega to warn of)
    scale = float(np.sum((model.centripetal_matrix(pos, S) / noise[:, None]) ** 2)) * OMEGA_CHECK_RADPS ** 2
    if np.any(np.linalg.eigvalsh(info)[:, 0] <= 1e-9 * scale):
        return None
    sig = np.full(pos.shape, POSITION_TOL_M)
    if cal.position_sigma is not None:
        known = np.all(np.isfinite(cal.position_sigma), axis=1)
        sig[known] = np.asarray(cal.position_sigma, float)[known]
    cov_inv = np.linalg.inv(info)
    K = cov_inv @ np.swapaxes(model.product_jacobian(w), -1, -2) @ split.qmap        # (k, 3, N)
    phi = (w @ S.T)[:, :, None] * w[:, None, :] - np.sum(w * w, axis=1)[:, None, None] * S[None]   # (k, N, 3)
    var = np.sum(phi ** 2 * sig[None] ** 2, axis=2)                                   # (k, N)
    bias = float(np.sqrt(np.mean(np.einsum("kin,kn,kin->k", K, var, K))))
    crb = float(np.sqrt(np.mean(np.trace(cov_inv, axis1=1, axis2=2))))
    return bias, crb, sig


def lever_arm_omega_warning(device, cal) -> str | None:
    """One line when the lever arms limit the array's omega more than the noise does at
    |omega| = OMEGA_CHECK_RADPS (None otherwise, and for layouts that do not observe omega)."""
    got = lever_arm_omega_bias(device, cal)
    if got is None:
        return None
    bias, crb, sig = got
    if bias <= crb:
        return None
    unknown = cal.position_sigma is None or not np.all(np.isfinite(cal.position_sigma))
    what = (f"the channel positions are not all calibrated (taking {POSITION_TOL_M * 1e3:g} mm for their mounting "
            "error)" if unknown else f"the lever arms are known to {1e3 * float(np.max(sig)):.3g} mm (largest "
            "position_sigma)")
    return (f"{what}: the array's own omega (resolve --omega array) is off by {bias:.3g} rad/s "
            f"({100 * bias / OMEGA_CHECK_RADPS:.2g} %) at |omega| = {OMEGA_CHECK_RADPS:g} rad/s from them, more than "
            f"the noise's bound there ({crb:.3g} rad/s per sample); record turns with a reference rate (turntable or "
            "gyro columns w_*, dw_*, f_*) about all three axes, longer or faster (docs/angular-rate.md)")
