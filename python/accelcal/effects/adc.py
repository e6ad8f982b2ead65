"""The converter: saturation (clipping inside the range) and quantization (coarse steps)."""
from __future__ import annotations

import math

import numpy as np

from ..errors import AccelcalError
from ..readings.noise import QUANT_MIN_FRAC, code_lattice
from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, as_float_array, channel_mask, owner, per_channel
from .fitdata import FitData
from .fitting import Cand, Candidate, block_ss
from .settings import QUANT_DITHER_GRID, QUANT_RELEVANT, QUANT_STRONG_FRAC, QUANT_STRONG_VALUES, SAT_PROOF_COUNT


ERFC = np.frompyfunc(math.erfc, 1, 1)


def normal_tail(z: np.ndarray) -> np.ndarray:
    """P(N(0, 1) > z), elementwise."""
    return 0.5 * ERFC(np.asarray(z, float) / math.sqrt(2.0)).astype(float)


def data_lattice(D):
    """The converter's code lattice per channel of the readings D.raw: (step, phase, share,
    distinct), each (N,); step 0 where the channel shows none (noise.code_lattice per channel,
    then the gcd of the steps found tried on every channel).  Read off the raw values once per
    FitData (kept in ``D.lattice``): the noise floor, the clip test and the quantiser's fit
    share it."""
    if D.lattice is None:
        D.lattice = _lattice(D.raw)
    return D.lattice


def _lattice(raw: np.ndarray):
    N = raw.shape[1]
    step = np.zeros(N)
    phase = np.zeros(N)
    frac = np.ones(N)
    nd = np.zeros(N, np.int64)
    for i in range(N):
        q, ph, fr, n_d = code_lattice(raw[:, i])
        if q >= 2:
            step[i], phase[i], frac[i], nd[i] = q, ph, fr, n_d
    # one converter, one lattice: the gcd of the steps found is tried on every channel (a channel
    # that sits on a few levels shows no lattice, or a multiple of the step, on its own)
    found = step[step >= 2].astype(np.int64)
    if found.size:
        qc = int(np.gcd.reduce(found))
        if qc >= 2:
            for i in range(N):
                u, cnt = np.unique(raw[:, i].astype(np.int64), return_counts=True)
                bc = np.bincount(u % qc, weights=cnt, minlength=qc)
                ph = int(np.argmax(bc))
                share = float(bc[ph] / cnt.sum())
                if u.size >= 2 and share >= QUANT_MIN_FRAC:
                    step[i], phase[i], frac[i], nd[i] = qc, ph, share, int(np.count_nonzero(u % qc == ph))
    return step, phase, frac, nd


class Saturation(Candidate, Effect):
    name = "saturation"
    tell_apart = "poses and motions that keep every reading well inside the range (a clip flattens only the readings beyond its level)"
    tells_from = ("gain", "nonlinearity")
    summary = "readings clip at limits inside [raw_min, raw_max]"
    doc = ("counts_i -> clip(counts_i, lo_i, hi_i) (counts).  By default the limits are the "
           "channel's offset -+ limit_g g in counts; lo/hi give them directly.")
    stage = "adc"
    params = (
        Param("limit_g", 1.5, "g", "symmetric limit around each channel's offset", "floats", minimum=0.0,
              exclusive_min=True),
        Param("lo", None, "counts", "lower clip level (overrides limit_g)", "floats"),
        Param("hi", None, "counts", "upper clip level (overrides limit_g)", "floats"),
        CHANNEL_PARAM,
    )
    fit = (
        FitParam("lo", "channel", "counts", "lower clip level (-inf = none)"),
        FitParam("hi", "channel", "counts", "upper clip level (+inf = none)"),
    )

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        lim = per_channel(spec["limit_g"], 1.5, m, None, self.name, "limit_g", off_value=0.0)
        half = lim * ctx.g_counts()
        lo = ctx.state.offsets - half if spec["lo"] is None else per_channel(spec["lo"], 0.0, m, None, self.name, "lo")
        hi = ctx.state.offsets + half if spec["hi"] is None else per_channel(spec["hi"], 0.0, m, None, self.name, "hi")
        lo = np.where(m, lo, -math.inf)
        hi = np.where(m, hi, math.inf)
        dev = ctx.device
        for i in np.flatnonzero(m):
            if not lo[i] < hi[i]:
                raise AccelcalError(f"{owner(self.name)}: channel {i}: expected lo < hi, got lo={lo[i]:g}, hi={hi[i]:g}")
        lo = np.where(m, np.maximum(lo, dev.raw_min), lo)
        hi = np.where(m, np.minimum(hi, dev.raw_max), hi)
        return {"lo": lo, "hi": hi}

    def identity(self, ctx):
        N = ctx.n_channels
        return {"lo": np.full(N, -math.inf), "hi": np.full(N, math.inf)}

    def apply_signal(self, counts, p, ctx):
        return np.clip(counts, np.asarray(p["lo"], float), np.asarray(p["hi"], float))

    # -- fit to a residual (the diagnosis) ------------------------------------

    def _fit(self, D, mask, pcur, with_proof=False):
        N = D.N
        lo = np.full(N, -math.inf)
        hi = np.full(N, math.inf)
        proof = []
        steps = data_lattice(D)[0]
        for i in range(N):
            v = D.raw[mask, i]
            pc = pcur[mask, i]
            sig = float(D.sigma[i])
            # on a lattice of step q (coarse codes) a pose can sit on one code, with the model up to
            # q/2 beyond it: a pile is a clip only against the codes next to it and beyond q/2
            q = float(max(steps[i], 1.0))
            band = max(4.0 * sig, 4.0, 2.0 * q)
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
                if beyond <= max(sig, 0.5, 0.5 * q):
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
        Sw, Su = block_ss(D, D.rows(y - delta))
        k = int(np.count_nonzero(np.isfinite(lo)) + np.count_nonzero(np.isfinite(hi)))
        sd = {"lo": np.where(np.isfinite(lo), 0.5, 0.0), "hi": np.where(np.isfinite(hi), 0.5, 0.0)}
        c = Cand(self.name, k, Sw, Su, delta, {"lo": lo, "hi": hi}, sd)
        c.evidence = "pile of readings at the clip level (levels read from all the data)"
        if proof:
            c.proof = True
            c.notes.append("readings pile up at " + "; ".join(proof))
        return c

    # -- the benchmark --------------------------------------------------------

    def bench_pair(self, est, truth, sig):
        """The median error of the found clip levels (counts)."""
        errs = []
        for k in ("lo", "hi"):
            a, b = as_float_array(est[k]), np.asarray(truth[k], float)
            m = np.isfinite(b) & np.isfinite(a)
            errs += list(np.abs(a[m] - b[m]))
        return float(np.median(errs)) if errs else None

    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        def level(i):
            lo, hi = float(p["lo"][i]), float(p["hi"][i])
            if math.isfinite(lo) and math.isfinite(hi):
                return f"{lo:g} and {hi:g}"
            return f"{hi:g} (above)" if math.isfinite(hi) else f"{lo:g} (below)"

        parts = [f"ch {i}: {level(i)}" for i in range(D.N) if np.isfinite(p["lo"][i]) or np.isfinite(p["hi"][i])]
        return "readings clip at " + ("; ".join(parts) if parts else "(no limit found)")


class Quantization(Candidate, Effect):
    name = "quantization"
    varies_by_pose = True      # the quantiser's error is a function of the reading: fixed per pose
    tell_apart = "a slow, smooth change of the input, such as a ramp between poses (coarse codes show as steps)"
    summary = "readings are quantised in steps coarser than one count"
    doc = ("counts_i -> step_i round(counts_i / step_i) (step in counts, >= 1), instead of rounding to 1 "
           "count; step 0 (unselected channels, identity) leaves the channel alone.")
    stage = "adc"
    params = (
        Param("step", 8.0, "counts", "quantisation step", "floats", minimum=1.0),
        CHANNEL_PARAM,
    )
    fit = (FitParam("step", "channel", "counts", "quantisation step (0 = none, 1 = plain rounding)"),)

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        return {"step": per_channel(spec["step"], 8.0, m, None, self.name, "step", off_value=0.0)}

    def identity(self, ctx):
        return {"step": np.zeros(ctx.n_channels)}

    def apply_signal(self, counts, p, ctx):
        step = np.broadcast_to(np.asarray(p["step"], float), (counts.shape[1],))
        on = step > 0
        if not np.any(on):
            return counts
        out = np.array(counts, float, copy=True)
        out[:, on] = step[on] * np.round(out[:, on] / step[on])
        return out

    @staticmethod
    def expected_error(x, step, phase, dither):
        """E[Q(x + n) - (x + n)] for readings x (n, N) before the noise, quantiser steps and phases
        (N,; step 0 = channel not quantised) and noise n ~ N(0, dither^2) reaching the quantiser:
        q sum_k (-1)^k / (pi k) sin(2 pi k (x - phase) / q) exp(-2 pi^2 k^2 dither^2 / q^2).
        dither 0 gives the sawtooth q round((x - phase)/q) - (x - phase) of a noise-free reading;
        with a dither of a quarter step it is a small smooth bias, which averages over a static
        pose into a per-pose offset that the sawtooth overstates.  This is the part of the effect
        a model of the clean readings can predict (the rest is noise)."""
        x = np.asarray(x, float)
        out = np.zeros_like(x)
        for i in np.flatnonzero(np.asarray(step) > 0):
            q, ph = float(step[i]), float(phase[i])
            u = (x[:, i] - ph) / q
            r = float(dither[i]) / q
            if r == 0.0:  # noise-free: the quantiser itself (apply_signal's rounding)
                out[:, i] = q * (np.round(u) - u)
                continue
            if r < 0.02:
                # the series would need > 40 terms; the noise reaches only the nearest cell
                # boundaries: crossing up (down) with probability Phi(-distance / noise)
                k0 = np.floor(u + 0.5)
                up = normal_tail((k0 + 0.5 - u) / r)
                down = normal_tail((u - k0 + 0.5) / r)
                out[:, i] = q * (k0 - u + up - down)
                continue
            k = np.arange(1, int(math.ceil(0.84 / r)) + 1)  # exp(-2 pi^2 k^2 r^2) < 1e-6 beyond
            coef = (-1.0) ** k / (math.pi * k) * np.exp(-2.0 * math.pi ** 2 * k ** 2 * r * r)
            out[:, i] = q * (np.sin(2.0 * math.pi * np.outer(u, k)) @ coef)
        return out

    # -- fit to a residual (the diagnosis) ------------------------------------

    def _delta(self, pcur, step, phase, dither):
        return self.expected_error(pcur, step, phase, dither)

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
        step, phase, frac, nd = data_lattice(D)
        dither = self._dither(y, pcur, step, phase)
        delta = self._delta(pcur, step, phase, dither)
        Sw, Su = block_ss(D, D.rows(y - delta))
        # (the parameters are copies: the lattice stays as read for the next candidate and step)
        c = Cand(self.name, int(np.count_nonzero(step)), Sw, Su, delta, {"step": step.copy()}, {"step": np.zeros(D.N)})
        strong = (step > 0) & (frac >= QUANT_STRONG_FRAC) & (nd >= QUANT_STRONG_VALUES)
        # a lattice is the cause of a gap only where its rounding noise (step / sqrt(12)) is a real
        # part of the noise: the MPU-6050's 4-count steps under 50-80 counts of noise are not
        relevant = np.asarray(step, float) / np.sqrt(12.0) >= QUANT_RELEVANT * np.asarray(D.sigma, float)
        if np.any(strong & ~relevant):
            c.notes.append("raw values on a lattice too fine to matter: " + ", ".join(
                f"channel {i}: step {int(step[i])} against {D.sigma[i]:.3g} counts of noise"
                for i in np.flatnonzero(strong & ~relevant)))
        strong &= relevant
        if np.any(strong):
            c.proof = True
            c.evidence = "lattice of the raw values (read from all the data)"
            c.notes.append("raw values on a lattice: " + ", ".join(
                f"channel {i}: step {int(step[i])} ({100 * frac[i]:.2f} % of readings, {nd[i]} values)"
                for i in np.flatnonzero(strong)))
        c.params["phase"] = phase.copy()
        c.params["dither"] = dither
        return c

    # -- the benchmark --------------------------------------------------------

    def bench_pair(self, est, truth, sig):
        """The share of channels with the wrong step."""
        e, t = as_float_array(est["step"]), np.asarray(truth["step"], float)
        return float(np.mean(np.abs(e - t) > 0))

    # -- report prose ---------------------------------------------------------

    def describe(self, p: dict, s: dict, D: FitData) -> str:
        """One line in physical units for the report (p: parameters, s: their 1-sigma)."""
        st = [f"ch {i}: {int(q)}" for i, q in enumerate(p["step"]) if q > 0]
        return "quantisation steps (counts) " + (", ".join(st) if st else "(none found)")
