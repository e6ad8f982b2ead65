"""PNG plots of the estimators' results, drawn through the one plotting home
(:mod:`accelcal.plotting`: Agg backend, every file written atomically)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import pyplot, save_figure
from .common import Columns

__all__ = ["report_plots"]


def report_plots(out_dir, columns: Columns, rec=None, kind: str | None = None) -> list[Path]:
    """PNG plots of an attitude / displacement / rate result.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Directory (created if missing) for attitude.png, displacement.png or rate.png.
    columns : Columns
        The estimator's result.
    rec : Recording, optional
        With reference columns (f, w, dw: a simulated truth), they are overlaid and the
        errors shown.
    kind : {"attitude", "displacement", "rate"}, optional
        Default: from the columns.

    Returns
    -------
    list of Path
        The files written (each atomically).
    """
    plt = pyplot()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t = columns["t"]
    kind = kind or ("attitude" if "theta_rad" in columns else "displacement" if "p_x" in columns else "rate")
    files = []
    if kind == "attitude":
        ref_theta = ref_w = None
        if rec is not None and np.isfinite(rec.f).all():
            ref_theta = np.arctan2(-rec.f[:, 0], rec.f[:, 2])
        if rec is not None and np.isfinite(rec.w[:, 1]).all():
            ref_w = rec.w[:, 1]
        has_ref = ref_theta is not None or ref_w is not None
        fig, axs = plt.subplots(4 if has_ref else 3, 1, figsize=(9, 10 if has_ref else 8), sharex=True)
        axs[0].plot(t, np.degrees(columns["theta_rad"]), label="theta (estimate)")
        if ref_theta is not None:
            axs[0].plot(t, np.degrees(ref_theta), "--", label="reference (from f)")
        axs[0].set_ylabel("theta [deg]")
        axs[1].plot(t, columns["w_y"], label="w_y (estimate)")
        if ref_w is not None:
            axs[1].plot(t, ref_w, "--", label="w_y reference")
        g = columns.get("gated")
        if g is not None and np.any(g > 0):
            axs[1].fill_between(t, 0, 1, where=g > 0, transform=axs[1].get_xaxis_transform(), alpha=0.15,
                                color="grey", label="gated (integrated)")
        axs[1].set_ylabel("w_y [rad/s]")
        axs[2].plot(t, columns["dw_y"], label="dw_y (estimate)")
        if rec is not None and np.isfinite(rec.dw[:, 1]).all():
            axs[2].plot(t, rec.dw[:, 1], "--", label="dw_y reference")
        axs[2].set_ylabel("dw_y [rad/s^2]")
        if has_ref:
            # the estimate and its reference overlap on the panels above: their difference shows
            # how good the estimate is at a glance
            ax = axs[3]
            if ref_theta is not None:
                d = np.degrees(np.angle(np.exp(1j * (columns["theta_rad"] - ref_theta))))
                ax.plot(t, d, color="C0", lw=0.8, label=f"theta error (rms {np.sqrt(np.mean(d * d)):.3g} deg)")
            ax.set_ylabel("theta error [deg]")
            if ref_w is not None:
                ax2 = ax.twinx()
                d = columns["w_y"] - ref_w
                ax2.plot(t, d, color="C3", lw=0.8, label=f"w_y error (rms {np.sqrt(np.mean(d * d)):.3g} rad/s)")
                ax2.set_ylabel("w_y error [rad/s]", color="C3")
                ax2.tick_params(axis="y", colors="C3")
                ax2.legend(loc="lower right", fontsize=8)
            ax.axhline(0.0, color="k", lw=0.5)
        axs[-1].set_xlabel("t [s]")
        for a in axs:
            a.legend(loc="upper right", fontsize=8)
            a.grid(alpha=0.3)
        fig.suptitle("pendulum attitude from two triads")
        path = out / "attitude.png"
    elif kind == "displacement":
        fig, axs = plt.subplots(2, 1, figsize=(9, 7), sharex=True)
        for c, col in zip("xyz", ("C0", "C1", "C2")):
            axs[0].plot(t, columns[f"p_{c}"], col, label=f"p_{c} corrected")
            if f"p_raw_{c}" in columns:
                axs[0].plot(t, columns[f"p_raw_{c}"], col, ls=":", label=f"p_{c} uncorrected")
            axs[1].plot(t, columns[f"v_{c}"], col, label=f"v_{c}")
        r = columns.get("rest")
        if r is not None:
            for a in axs:
                a.fill_between(t, 0, 1, where=r > 0, transform=a.get_xaxis_transform(), alpha=0.12,
                               color="green", label="rest")
        axs[0].set_ylabel("p [m]")
        axs[1].set_ylabel("v [m/s]")
        axs[1].set_xlabel("t [s]")
        for a in axs:
            a.legend(loc="upper left", fontsize=8)
            a.grid(alpha=0.3)
        fig.suptitle("stop-to-stop displacement (frame of the first rest)")
        path = out / "displacement.png"
    else:
        fig, ax = plt.subplots(1, 1, figsize=(9, 4))
        for c in "xyz":
            ax.plot(t, columns[f"w_{c}"], label=f"w_{c}")
        ref = rec is not None and np.isfinite(rec.w).all()
        if ref:
            for i, c in enumerate("xyz"):
                ax.plot(t, rec.w[:, i], "--", label=f"w_{c} reference")
            err = np.column_stack([columns[f"w_{c}"] for c in "xyz"]) - rec.w
            rms = np.sqrt(np.mean(err * err, axis=0))
            ax.set_title("error rms " + ", ".join(f"w_{c} {v:.3g}" for c, v in zip("xyz", rms)) + " rad/s",
                         fontsize=9)
        ax.set_ylabel("rad/s")
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        path = out / "rate.png"
    fig.tight_layout()
    save_figure(fig, path, dpi=110)
    files.append(path)
    return files
