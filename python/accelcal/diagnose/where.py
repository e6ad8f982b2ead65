"""Where the gap lies: the residual broken down by channel, regime, rate, band, temperature, time."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np

from ..effects.fitdata import FitData
from ..effects.settings import ROTATING_RADPS, TEMP_MIN_SPAN_C
from ..readings.noise import colour_factor, pose_colour


def bin_index(label: str, mask: np.ndarray, e: np.ndarray, sigma: np.ndarray, **extra) -> dict:
    n = int(mask.sum())
    x = e[mask]
    rms_ch = np.sqrt(np.mean(x * x, axis=0)) if n else np.zeros(e.shape[1])
    rms = float(np.sqrt(np.mean(rms_ch ** 2))) if n else 0.0
    floor = float(np.sqrt(np.mean(sigma ** 2)))
    out = {"label": label, **extra, "n": n, "rms_counts": rms, "ratio_to_noise": rms / floor if floor > 0 else None,
           "rms_per_channel": rms_ch.tolist(), "mean_per_channel": (x.mean(axis=0) if n else rms_ch * 0).tolist()}
    return out


def bins_by(values: np.ndarray, edges: Sequence[float], unit: str, e, sigma) -> list[dict]:
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (values >= lo) & (values < hi)
        if m.any():
            lab = f"{lo:g}-{hi:g} {unit}" if math.isfinite(hi) else f">= {lo:g} {unit}"
            out.append(bin_index(lab, m, e, sigma, lo=float(lo), hi=float(hi) if math.isfinite(hi) else None))
    return out


def where_breakdown(D: FitData, e: np.ndarray) -> dict:
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
            regimes.append(bin_index(lab, m, e, sig))
    out: dict = {"by_channel": by_channel, "static_vs_rotating": regimes}
    if D.mode == "reference":
        out["omega_bins"] = bins_by(wn, [0, ROTATING_RADPS, 0.5, 2.0, 5.0, math.inf], "rad/s", e, sig)
        out["alpha_bins"] = bins_by(an, [0, 0.5, 5.0, 20.0, 100.0, math.inf], "rad/s^2", e, sig)
    # frequency bands (energy of the residual by FFT of each contiguous segment)
    fs = 1.0 / D.h
    edges = [0.0, 0.1, 1.0, 3.0, 10.0, 30.0, math.inf]
    edges = [x for x in edges if x < fs / 2] + [math.inf]
    E = np.zeros((len(edges) - 1, N))
    nbins = np.zeros(len(edges) - 1, np.int64)     # spectral bins that fall in each band, over all runs
    for a, b in zip(D.seg_lo, D.seg_hi):
        x = e[a:b]
        L = b - a
        if L < 8:
            E[0] += np.sum(x * x, axis=0)
            nbins[0] += 1
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
            nbins[j] += int(np.count_nonzero(k == j))
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
        if nbins[j] == 0:
            # no run is long enough to resolve this band (short static stretches, time stamps that
            # break the recording into pieces): not measurable, not zero
            bands.append({"label": lab, "lo_hz": edges[j], "hi_hz": top, "measurable": False, "rms_counts": None,
                          "white_noise_rms_counts": wn, "ratio_to_white_noise": None, "rms_per_channel": None,
                          "why": f"no contiguous run longer than {1.0 / max(edges[j + 1] if math.isfinite(edges[j + 1]) else fs / 2, 1e-300):.3g} s"})
            continue
        bands.append({"label": lab, "lo_hz": edges[j], "hi_hz": top, "measurable": True, "rms_counts": rms,
                      "white_noise_rms_counts": wn, "ratio_to_white_noise": rms / wn if wn > 0 else None,
                      "rms_per_channel": rc.tolist()})
    out["frequency_bands"] = bands
    T = D.temp
    if np.all(np.isfinite(T)) and np.ptp(T) >= TEMP_MIN_SPAN_C:
        q = np.quantile(T, np.linspace(0, 1, 6))
        q[-1] = np.nextafter(q[-1], math.inf)
        out["temperature_bins"] = bins_by(T, list(q), "degC", e, sig)
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
                # said from the recording's start (t since a boot or an epoch: 6.727e+05-6.727e+05 s)
                tb.append(bin_index(f"rec {int(k)}: {lo - tt.min():.3f}-{min(hi, tt.max()) - tt.min():.3f} s from "
                                    "its start", m, e, sig, recording=int(k),
                               t0=float(lo), t1=float(hi)))
    out["time_bins"] = tb
    if len(D.pose_labels):
        pl = []
        for p, (rr, L) in enumerate(D.pose_labels):
            m = D.pose == p
            if m.any():
                pl.append(bin_index(f"rec {rr}: pose {L}", m, e, sig, recording=int(rr), pose=int(L)))
        pl.sort(key=lambda d: -d["rms_counts"])
        out["poses"] = pl[:200]
    return out


def pose_mean_rows(D: FitData, e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The static poses' mean residual rows and the variance the noise alone gives them.

    Parameters
    ----------
    D : FitData
    e : ndarray, shape (n, N)
        Residual in counts (channel space; projected here with ``D.rows``).

    Returns
    -------
    poses : ndarray of int, shape (P',)
        The global pose indices that hold samples.
    means : ndarray, shape (P', R)
        Each pose's mean residual row (counts).
    var : ndarray, shape (P', R)
        Its white-noise variance (counts^2, from the rows' weights).
    r2 : ndarray, shape (P', R)
        Each pose's own squared widening of its mean's spread beyond white noise's by the
        noise's colour within it (:func:`accelcal.readings.noise.pose_colour`; NaN for a short pose);
        :func:`accelcal.readings.noise.colour_factor` pools them as the calibration's pose sems are.
    """
    P = len(D.pose_labels)
    Rr = D.rows(e)
    cnt = np.bincount(D.pose[D.pose >= 0], minlength=P).astype(float)
    on = D.pose >= 0
    ok = cnt > 0
    ms, vs = [], []
    for j in range(Rr.shape[1]):
        s1 = np.bincount(D.pose[on], weights=Rr[on, j], minlength=P)
        iv = np.bincount(D.pose[on], weights=1.0 / D.W[on, j], minlength=P)
        ms.append(s1[ok] / cnt[ok])
        vs.append(iv[ok] / cnt[ok] ** 2)
    r2 = pose_colour(Rr, [np.flatnonzero(D.pose == p) for p in range(P) if cnt[p] > 0])
    return np.flatnonzero(ok), np.array(ms).T, np.array(vs).T, r2


def pose_mean_gap(D: FitData, e: np.ndarray) -> dict:
    """RMS of the static poses' mean residual rows against what the noise alone gives them:
    the white noise's, widened by the colour of the noise within the poses
    (:func:`pose_mean_rows`)."""
    if len(D.pose_labels) < 2:
        return {}
    poses, m, v, r2 = pose_mean_rows(D, e)
    colour = colour_factor(r2)
    rms = float(np.sqrt(np.mean(m ** 2)))
    white = float(np.sqrt(np.mean(v)))
    # noise coloured within the poses (a hand's slow tremor) moves their means more than white noise
    noise = white * float(np.sqrt(np.mean(colour ** 2)))
    return {"pose_mean_rms_counts": rms, "pose_mean_noise_counts": noise, "pose_mean_white_noise_counts": white,
            "pose_mean_ratio": rms / noise if noise > 0 else None, "n_poses": int(poses.size)}
