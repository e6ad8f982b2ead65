"""The diagnosis report: PNG plots a person reads at a glance and a short summary.md.

    write_report(result, "report/")   # result: accelcal.diagnose.diagnose(...)

Files (each written atomically):

* ``residual_time.png`` -- the residual against time, one panel per channel, with the noise
  floor band (+-1 sigma) and, when the diagnosis chose effects, the residual left after them;
* ``breakdown.png`` -- where the gap lies: RMS by channel, by regime (static / rotating /
  moving), by |w| and |alpha| bin, by frequency band (against white noise of the floor), by
  temperature bin and by time, each against the noise floor;
* ``candidates.png`` -- every candidate's held-out RMS before and after it is added, ranked;
* ``summary.md`` -- the verdict, how far (before / after / shrink), the fitted parameters with
  their uncertainties, the breakdown in words, what was skipped and why.

Only what the JSON holds is needed, except the residual time series, which come from the
result's ``series`` attribute (absent when the result was read back from JSON: the time plot
is then left out).
"""
from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

from .errors import AccelcalError, atomic_write
from .plotting import pyplot, save_figure

__all__ = ["write_report", "summary_text"]

_MAX_POINTS = 20000




MEAN_BINS = 300  # running means per residual trace (long recordings) ...
MEAN_MIN = 10    # ... each of at least this many samples


def _decimate(x: np.ndarray, y: np.ndarray, m: int = _MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Min/max envelope decimation so spikes stay visible."""
    n = x.shape[0]
    if n <= m:
        return x, y
    k = int(math.ceil(n / (m // 2)))
    nb = n // k
    xs = x[: nb * k].reshape(nb, k)
    ys = y[: nb * k].reshape(nb, k)
    lo = ys.argmin(axis=1)
    hi = ys.argmax(axis=1)
    r = np.arange(nb)
    first = np.minimum(lo, hi)
    second = np.maximum(lo, hi)
    xx = np.column_stack([xs[r, first], xs[r, second]]).ravel()
    yy = np.column_stack([ys[r, first], ys[r, second]]).ravel()
    return xx, yy


def _bin_means(x: np.ndarray, y: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Means of consecutive runs of w samples (the last, shorter run included)."""
    if w <= 1:
        return x, y
    edges = np.arange(0, x.shape[0], w)
    counts = np.diff(np.append(edges, x.shape[0]))
    return np.add.reduceat(x, edges) / counts, np.add.reduceat(y, edges) / counts


def _plot_residual_time(res: dict, path: str, dpi: int) -> bool:
    """Per channel: the residual (faint, min/max envelope) and its running mean over w samples
    (bold) before and after the chosen effects, on the noise floor's 1-sigma band and the
    running mean's 2-sigma band: on a long recording the samples fill the axes, and what the
    model misses shows in the mean leaving its band."""
    ser = getattr(res, "series", None)
    if not ser:
        return False
    plt = pyplot()
    tg, e = np.asarray(ser["tg"]), np.asarray(ser["residual"])
    after = np.asarray(ser["residual_after"])
    sig = np.asarray(ser["noise_floor"])
    N = e.shape[1]
    chosen = res.get("model", {}).get("effects", [])
    cols = 1 if N <= 4 else 2
    rows = int(math.ceil(N / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(11 if cols == 2 else 9, 1.7 * rows + 0.8), sharex=True,
                             squeeze=False)
    # break the lines where recordings or time gaps change
    gap = np.flatnonzero(np.diff(tg) > 5 * np.median(np.diff(tg))) + 1 if tg.size > 1 else np.array([], int)
    w = tg.size // MEAN_BINS
    w = w if w >= MEAN_MIN else 1  # a short recording: the samples themselves
    after_label = "after " + " + ".join(chosen)
    for i in range(N):
        ax = axes[i // cols][i % cols]
        for a, b in zip(np.r_[0, gap], np.r_[gap, tg.size]):
            first = a == 0
            for y, color, name in ((e, "C0", "residual"), (after, "C3", after_label)):
                if name != "residual" and not chosen:
                    continue
                x, v = _decimate(tg[a:b], y[a:b, i])
                ax.plot(x, v, lw=0.4 if w > 1 else 0.6, color=color, alpha=0.25 if w > 1 else 0.85,
                        label=name if first and w == 1 else None)
                if w > 1:
                    xm, vm = _bin_means(tg[a:b], y[a:b, i], w)
                    ax.plot(xm, vm, lw=1.3, color=color, label=f"{name}, mean of {w}" if first else None)
        ax.axhspan(-sig[i], sig[i], color="0.88", lw=0, zorder=0, label="noise floor (1 sigma)")
        if w > 1:
            band = 2.0 * sig[i] / math.sqrt(w)
            ax.axhspan(-band, band, color="0.55", alpha=0.5, lw=0, zorder=0.5, label="mean's 2-sigma band")
        ax.set_ylabel(f"ch {i}\ncounts", fontsize=8)
        ax.tick_params(labelsize=7)
    for j in range(N, rows * cols):
        axes[j // cols][j % cols].set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time (s; recordings laid end to end)", fontsize=8)
    fig.suptitle(f"Residual = measured - model ({res.get('device', '')}); verdict: {res.get('verdict')}", fontsize=10)
    # one legend above the panels, where it hides no data
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="upper center", ncol=4, bbox_to_anchor=(0.5, 0.955), frameon=False)
    fig.subplots_adjust(top=1.0 - 0.95 / (1.7 * rows + 0.8))
    save_figure(fig, path, dpi)
    plt.close(fig)
    return True


def _bars(ax, items: list[dict], floor: float, title: str, key: str = "rms_counts", white: bool = False) -> None:
    labels = [str(it.get("label", it.get("channel", ""))) for it in items]
    vals = [float(it.get(key, 0.0) or 0.0) for it in items]
    x = np.arange(len(items))
    ax.bar(x, vals, color="C0", label="residual RMS")
    if white:
        ax.plot(x, [float(it.get("white_noise_rms_counts", 0.0)) for it in items], "k_", ms=18, mew=2,
                label="white noise at the floor")
    else:
        ax.axhline(floor, color="k", ls="--", lw=1, label="noise floor")
    ax.set_xticks(x)
    ax.set_xticklabels(labels, rotation=35 if len(items) > 3 or max(map(len, labels or [""])) > 8 else 0,
                       ha="right" if len(items) > 3 else "center", fontsize=7)
    ax.set_title(title, fontsize=9)
    ax.set_ylabel("counts", fontsize=8)
    ax.tick_params(axis="y", labelsize=7)
    ns = [it.get("n") for it in items]
    if all(isinstance(n, int) for n in ns) and ns:
        for xi, v, n in zip(x, vals, ns):
            ax.text(xi, v, f"{n}", ha="center", va="bottom", fontsize=6, color="0.3")


def _plot_breakdown(res: dict, path: str, dpi: int) -> None:
    plt = pyplot()
    w = res.get("where", {})
    floor = float(res["gap"]["noise_floor_counts"])
    panels = []
    ch = [{"label": f"ch {d['channel']}", "rms_counts": d["rms_counts"]} for d in w.get("by_channel", [])]
    panels.append((ch, "by channel", False))
    for key, title in (("static_vs_rotating", "by regime"), ("omega_bins", "by |w|"), ("alpha_bins", "by |alpha|"),
                       ("temperature_bins", "by temperature"), ("time_bins", "by time")):
        if w.get(key):
            items = w[key]
            if key == "time_bins":
                items = [dict(it, label=it["label"].split(": ", 1)[-1]) if len({i.get("recording") for i in items}) == 1
                         else it for it in items]
            panels.append((items, title, False))
    if w.get("frequency_bands"):
        panels.append((w["frequency_bands"], "by frequency band", True))
    n = len(panels)
    cols = 3 if n > 4 else 2
    rows = int(math.ceil(n / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 2.9 * rows), squeeze=False)
    for k, (items, title, white) in enumerate(panels):
        ax = axes[k // cols][k % cols]
        _bars(ax, items, floor, title, white=white)
        if k == 0:
            ax.legend(fontsize=7)
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].set_visible(False)
    fig.suptitle(f"Where the gap lies: residual RMS {res['gap']['rms_counts']:.3g} counts, noise floor "
                 f"{floor:.3g} counts (numbers on bars: samples)", fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi)
    plt.close(fig)


def _plot_candidates(res: dict, path: str, dpi: int) -> None:
    plt = pyplot()
    eff = res.get("effects", [])
    if not eff:
        return
    names = [e["name"] + (f" (step {e['step']})" if e.get("step") else "") for e in eff]
    before = [e["heldout_rms_before"] for e in eff]
    after = [e["heldout_rms_after"] for e in eff]
    y = np.arange(len(eff))[::-1]
    fig, ax = plt.subplots(figsize=(8, 0.38 * len(eff) + 1.4))
    ax.barh(y + 0.2, before, height=0.38, color="0.7", label="held-out RMS before")
    colors = ["C3" if e.get("selected") else ("C1" if e.get("significant") else "C0") for e in eff]
    ax.barh(y - 0.2, after, height=0.38, color=colors, label="after adding it")
    for yi, e, a in zip(y, eff, after):
        ax.text(a, yi - 0.2, f"  shrink {100 * e['shrink']:.1f} %", va="center", fontsize=7)
    ax.axvline(res["gap"]["noise_floor_counts"], color="k", ls="--", lw=1, label="noise floor")
    ax.set_yticks(y)
    ax.set_yticklabels(names, fontsize=8)
    ax.set_xlabel("counts (RMS over held-out samples)", fontsize=8)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.6 / max(len(eff), 1) - 0.08), ncol=3)
    ax.set_title(f"Candidates (red: chosen, orange: significant); verdict: {res.get('verdict')}", fontsize=10)
    save_figure(fig, path, dpi)
    plt.close(fig)


def _fmt(x: Any) -> str:
    if isinstance(x, str):
        return x
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.4g}"
    return str(x)


def _param_lines(e: dict, limit: int = 16) -> list[str]:
    out = []
    units = e.get("units", {})
    sig = e.get("params_sigma", {})
    for k, v in e.get("params", {}).items():
        if k in ("seed", "rw", "phase", "recording"):
            continue
        u = units.get(k, "")
        s = sig.get(k)
        if isinstance(v, list):
            flat = np.asarray(v, dtype=object).ravel().tolist()
            sflat = np.asarray(s, dtype=object).ravel().tolist() if isinstance(s, list) else None
            items = []
            for j, val in enumerate(flat[:limit]):
                t = _fmt(val)
                if sflat is not None and j < len(sflat) and isinstance(sflat[j], (int, float)) and sflat[j]:
                    t += f" +- {_fmt(float(sflat[j]))}"
                items.append(t)
            more = f", ... ({len(flat)} values)" if len(flat) > limit else ""
            shape = f" (shape {np.shape(v)})" if np.ndim(v) > 1 else ""
            out.append(f"  - `{k}`{shape} [{u}]: " + ", ".join(items) + more)
        else:
            t = _fmt(v)
            if isinstance(s, (int, float)) and s:
                t += f" +- {_fmt(float(s))}"
            out.append(f"  - `{k}` [{u}]: {t}")
    return out


def unexplained_lines(res: dict) -> list[str]:
    """The summary's lines for the JSON's ``unexplained`` (none when it is null): how much the
    model leaves beyond the noise, and where."""
    u = res.get("unexplained")
    if not u:
        return []
    w = u.get("where") or {}
    model = " + ".join(res.get("model", {}).get("effects", [])) or "the calibrated model alone"
    where = [f"in {w['band']}" if w.get("band") else "",
             f"{w['regime']}" if w.get("regime") else "",
             f"channels {', '.join(map(str, w['channels']))}" if w.get("channels") else "",
             f"most in {', '.join(w['poses'][:3])}" if w.get("poses") else ""]
    line = u.get("lines") or {}
    return ["", "## Unexplained", "",
            f"After {model}, **{u['heldout_rms_left']:.3g} counts** held out ({100 * u['fraction']:.1f} % of the gap) "
            f"are left beyond the noise floor of {u['noise_counts']:.3g} counts: "
            + "; ".join(x for x in where if x) + "."
            + (f" A line at {line['peak_hz']:.4g} Hz holds {line['rms_counts']:.3g} counts rms (channels "
               f"{', '.join(map(str, line.get('channels', [])))})." if line.get("peak_hz") else "")]


def summary_text(res: dict, images: list[str] = ()) -> str:
    """The written summary (Markdown) of a diagnosis result."""
    g = res["gap"]
    L = [f"# Diagnosis: {res.get('verdict')}", ""]
    recs = res.get("recordings", [])
    L.append(f"Device `{res.get('device')}`, calibration `{res.get('calibration', {}).get('method')}` "
             f"({res.get('calibration', {}).get('source')}); mode: **{res.get('mode')}**; "
             f"{res.get('n_samples')} samples x {res.get('n_channels')} channels used from {len(recs)} recording(s):")
    L.append("")
    for r in recs:
        L.append(f"- `{r['source']}`: {r['n_used']} of {r['n_samples']} samples ({r['reference']})")
    L += ["", "## The gap", ""]
    ratio = g.get("ratio_to_noise")
    L.append(f"Residual RMS **{g['rms_counts']:.4g} counts** against a noise floor of **{g['noise_floor_counts']:.4g} "
             f"counts** (ratio {ratio:.3g}); noise floor: {g['noise_method']}.")
    if g.get("pose_mean_rms_counts") is not None:
        L.append(f"Static pose means: residual RMS {g['pose_mean_rms_counts']:.3g} counts, "
                 f"{g['pose_mean_ratio']:.3g} x what the noise explains ({g['pose_mean_noise_counts']:.3g}).")
    L += ["", "## Which effect, how far", ""]
    chosen = [e for e in res.get("effects", []) if e.get("selected")]
    if not chosen:
        L.append(f"**{res.get('verdict')}**: no candidate explains a significant part of the gap beyond noise"
                 + ("; what is left is under Unexplained." if res.get("unexplained") else "."))
    else:
        m = res["model"]
        L.append(f"Verdict **{res['verdict']}**. Held-out RMS {m['heldout_rms_before']:.4g} -> "
                 f"{m['heldout_rms_after']:.4g} counts with {' + '.join(m['effects'])} "
                 f"(shrink {100 * m['shrink']:.1f} %).")
        L.append("")
        for e in chosen:
            L.append(f"- step {e['step']}: **{e['name']}** -- {e['summary']}; "
                     f"held-out RMS {e['heldout_rms_before']:.4g} "
                     f"-> {e['heldout_rms_after']:.4g} counts, shrink {100 * e['shrink']:.1f} % "
                     f"(chi2 gain {e['score']['gain_chi2']:.4g}, t {e['score']['t']:.3g}, z {e['score']['z']:.3g}; "
                     f"{e['score']['evidence']})")
            L += _param_lines(e)
            for n in e.get("notes", []):
                L.append(f"  - note: {n}")
    L += unexplained_lines(res)
    L += ["", "All candidates (alone on the calibrated model unless a step is given):", "",
          "| rank | effect | significant | shrink | held-out RMS before | after | params | penalised chi2 gain "
          "| t | z |",
          "| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for k, e in enumerate(res.get("effects", [])):
        s = e["score"]
        L.append(f"| {k + 1} | {e['name']}{' (step ' + str(e['step']) + ')' if e.get('step') else ''} | "
                 f"{'yes' if e['significant'] else 'no'} | {100 * e['shrink']:.2f} % | {e['heldout_rms_before']:.4g} | "
                 f"{e['heldout_rms_after']:.4g} | {e['n_params']} | {s['penalised_gain_chi2']:.4g} | {s['t']:.3g} | "
                 f"{s['z']:.3g} |")
    if res.get("skipped"):
        L += ["", "Skipped:", ""]
        for s in res["skipped"]:
            L.append(f"- {s['name']}: {s['reason']}")
    w = res.get("where", {})
    L += ["", "## Where", ""]
    floor = g["noise_floor_counts"]
    if w.get("by_channel"):
        worst = sorted(w["by_channel"], key=lambda d: -d["ratio_to_noise"])[:3]
        L.append("Worst channels: " + ", ".join(f"ch {d['channel']} {d['rms_counts']:.3g} counts "
                                                  f"({d['ratio_to_noise']:.2g} x its noise, "
                                                  f"mean {d['mean_counts']:+.3g})"
                                                  for d in worst) + ".")
    for key, title in (("static_vs_rotating", "Regimes"), ("omega_bins", "|w| bins"), ("alpha_bins", "|alpha| bins"),
                       ("temperature_bins", "Temperature bins"), ("frequency_bands", "Frequency bands")):
        items = w.get(key)
        if not items:
            continue
        if key == "frequency_bands":
            txt = ", ".join(f"{it['label']}: {it['rms_counts']:.3g} (white noise {it['white_noise_rms_counts']:.3g})"
                            if it.get("rms_counts") is not None else f"{it['label']}: not measurable ({it.get('why', '')})"
                            for it in items)
        else:
            txt = ", ".join(f"{it['label']}: {it['rms_counts']:.3g} ({it['n']} samples)" for it in items)
        L.append(f"{title} (RMS counts; floor {floor:.3g}): {txt}.")
    if w.get("time_bins"):
        tb = w["time_bins"]
        hi = max(tb, key=lambda d: d["rms_counts"])
        lo = min(tb, key=lambda d: d["rms_counts"])
        L.append(f"Time: RMS from {lo['rms_counts']:.3g} ({lo['label']}) to {hi['rms_counts']:.3g} counts "
                 f"({hi['label']}).")
    if res.get("notes"):
        L += ["", "## Notes", ""]
        L += [f"- {n}" for n in res["notes"]]
    if images:
        L += ["", "## Plots", ""]
        L += [f"![{os.path.splitext(im)[0]}]({im})" for im in images]
    cv = res.get("cv", {})
    L += ["", f"Method: blocked {cv.get('folds')}-fold cross-validation over {cv.get('blocks')} blocks; "
          f"{cv.get('rule')} (t_min {cv.get('t_min')}, z_min {cv.get('z_min')}, "
          f"penalty {cv.get('penalty_per_param_chi2')} per parameter, "
          f"min shrink {cv.get('min_shrink')}). See `accelcal.diagnose` for the definitions.", ""]
    return "\n".join(L)


REPORT_FILES = 4  # residual_time.png (when there is a residual), breakdown.png, candidates.png, summary.md


def write_report(result: dict, out_dir: Any, *, dpi: int = 110, progress: Any = None) -> list[str]:
    """Write the plots and summary.md of ``result`` into ``out_dir`` (created if needed).
    ``progress``: optional callable(path) called after each file (at most REPORT_FILES).
    Returns the paths written."""
    if not isinstance(result, dict) or "gap" not in result or "effects" not in result:
        raise AccelcalError("write_report: expected a diagnosis result (the dict diagnose() returns)")
    out_dir = os.fspath(out_dir)
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as e:
        raise AccelcalError(f"{out_dir}: cannot create the report directory: {e.strerror or e}") from None
    written: list[str] = []
    images: list[str] = []

    def done(path: str, image: bool = True) -> None:
        written.append(path)
        if image:
            images.append(os.path.basename(path))
        if progress is not None:
            progress(path)

    p = os.path.join(out_dir, "residual_time.png")
    if _plot_residual_time(result, p, dpi):
        done(p)
    p = os.path.join(out_dir, "breakdown.png")
    _plot_breakdown(result, p, dpi)
    done(p)
    if result.get("effects"):
        p = os.path.join(out_dir, "candidates.png")
        _plot_candidates(result, p, dpi)
        done(p)
    p = os.path.join(out_dir, "summary.md")
    text = summary_text(result, images)
    atomic_write(p, lambda f: f.write(text))
    done(p, image=False)
    return written
