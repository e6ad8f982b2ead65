"""The model's prediction for the recordings (through :mod:`accelcal.sensor`) and the
data the candidates fit: reference or jig-free poses, segments, blocks and folds."""
from __future__ import annotations


import numpy as np

from ..readings.clipping import at_rails, clip_levels
from ..effects.adc import Quantization
from ..effects.fitdata import FitData, tangent_basis
from ..effects.settings import BLOCK_S, QUANT_DITHER_GRID
from ..errors import InputError
from ..motions import Trajectory
from ..readings.no_rest import gravity_removed_clause
from ..readings.noise import noise_for
from ..sensor import evaluate, true_state
from ..readings.static import STATIC_WINDOW_S, detect_static, set_aside_off_gravity, window_len


def segments(t: np.ndarray, usable: np.ndarray, key: np.ndarray, h: float) -> list[tuple[int, int]]:
    """Contiguous runs of usable samples with one key and no time gap (index pairs)."""
    n = t.shape[0]
    brk = np.zeros(n, bool)
    brk[0] = True
    brk[1:] = (np.diff(t) > 1.5 * h) | (key[1:] != key[:-1]) | (usable[1:] != usable[:-1])
    starts = np.flatnonzero(brk)
    ends = np.append(starts[1:], n)
    return [(int(a), int(b)) for a, b in zip(starts, ends) if usable[a]]


def jigfree_poses(rec, device) -> tuple[list[np.ndarray], list[str]]:
    """Static poses of a recording without reference f: its pose labels, else detected; those
    whose |f| is far from g (:func:`accelcal.readings.static.set_aside_off_gravity`: a rocket's coast)
    left out, each named in the list returned beside them."""
    if rec.has_pose():
        poses = [np.flatnonzero(rec.pose == lab) for lab in rec.pose_labels()]
    else:
        poses = [np.arange(a, b) for a, b in detect_static(rec, device)]
    poses, _, aside = set_aside_off_gravity(rec, device, poses, None)
    return poses, [f"the still stretch at t = {d['t_start']:.6g}..{d['t_stop']:.6g} s reads {d['levels']}: no rest "
                   "on the Earth (free fall, coasting, a turntable) unless the scale is wrong; not a reference"
                   for d in aside]


CLIPPED_WEIGHT = 1e-6       # relative weight of a clipped channel in a jig-free pose's force
ROUNDING_STD_MAX = 0.6      # channels whose readings scatter less than this (counts) within the rests ...
ROUNDING_MODEL_MAX = 0.5    # ... and whose rests' means the model predicts to this (rms, counts) ...
ROUNDING_DITHER = QUANT_DITHER_GRID + (0.5,)   # ... get the rounding bias, at the best of these dithers


def rounding_bias(raw: np.ndarray, pred: np.ndarray, rests: list[tuple[int, int]]) -> np.ndarray:
    """E[round(x + n)] - x for the ADC's own rounding to whole counts, per sample and channel.

    A channel whose noise before the rounding is well below a count sits on one or two codes
    in each rest, and the rounding leaves each pose with a bias of up to half a count that
    the unrounded prediction ``pred`` does not hold (a 12-bit chip under 0.1 counts of noise:
    clean recordings were named pose_error, gain or bias_drift from it).  For the channels
    whose readings scatter by less than ROUNDING_STD_MAX counts within the rests ``rests``
    (index pairs), the noise reaching the rounding is the dither of ROUNDING_DITHER that
    best fits the rests' readings (:meth:`Quantization.expected_error`, step 1, phase 0);
    elsewhere the bias is below 0.003 counts and left at 0.  The bias is a function of the
    true reading: evaluated at a prediction that misses the rests' means by more than the
    rounding can (rms over the rests above ROUNDING_MODEL_MAX counts: an effect is there)
    it would be a sawtooth of the wrong phase, so such a channel is left at 0 too."""
    out = np.zeros_like(pred)
    rests = [(a, b) for a, b in rests if b - a >= 3]
    if not rests:
        return out
    idx = np.concatenate([np.arange(a, b) for a, b in rests])
    var = np.array([np.var(raw[a:b], axis=0, ddof=1) * (b - a - 1) for a, b in rests]).sum(axis=0)
    std = np.sqrt(var / sum(b - a - 1 for a, b in rests))
    miss = np.sqrt(np.mean([np.mean(raw[a:b] - pred[a:b], axis=0) ** 2 for a, b in rests], axis=0))
    one = np.ones(1)
    for i in np.flatnonzero((std < ROUNDING_STD_MAX) & (miss <= ROUNDING_MODEL_MAX)):
        x, y = pred[idx, i:i + 1], raw[idx, i] - pred[idx, i]
        sse = [float(np.sum((y - Quantization.expected_error(x, one, 0 * one, r * one)[:, 0]) ** 2))
               for r in ROUNDING_DITHER]
        r = ROUNDING_DITHER[int(np.argmin(sse))]
        out[:, i] = Quantization.expected_error(pred[:, i:i + 1], one, 0 * one, r * one)[:, 0]
    return out


def pose_force(S: np.ndarray, ybar: np.ndarray, g: float, wch: np.ndarray, f0: np.ndarray | None = None) -> np.ndarray:
    """f with |f| = g minimising sum_i w_i (ybar_i - s_i . f)^2 (Gauss-Newton on the sphere),
    from ``f0`` (default: the weighted linear solution)."""
    sw = np.sqrt(wch)
    f = np.linalg.lstsq(S * sw[:, None], ybar * sw, rcond=None)[0] if f0 is None else np.asarray(f0, float)
    nf = np.linalg.norm(f)
    f = g * (f / nf if nf > 0 else np.array([0.0, 0.0, 1.0]))
    for _ in range(8):
        E = tangent_basis(f / g)                        # (2,3)
        J = (S @ E.T) * sw[:, None]                      # (N,2)
        d = np.linalg.lstsq(J, (ybar - S @ f) * sw, rcond=None)[0]
        f = f + E.T @ d
        f = g * f / np.linalg.norm(f)
        if np.max(np.abs(d)) < 1e-12 * g:
            break
    return f


def kept_recordings(recs: list) -> list[int]:
    """The recordings a diagnosis uses (indices into ``recs``): those with a reference f where any
    has one (the others are skipped with a note), else all of them (jig-free)."""
    has_f = [rec.has_f() for rec in recs]
    return [i for i, hf in enumerate(has_f) if hf] if any(has_f) else list(range(len(recs)))


def prepare(device, cal, recs: list, K: int, seed: int, m0: float) -> FitData:

    N = device.n_channels
    g = float(device.gravity_mps2)
    b = np.asarray(cal.offsets, float)
    S = np.asarray(cal.sensitivity, float)
    r = cal.positions_or_nominal(device)
    at_origin = bool(np.all(np.abs(r) < 1e-12))
    h = 1.0 / float(device.sample_rate_hz)
    has_f = [rec.has_f() for rec in recs]
    notes: list[str] = []
    keep = kept_recordings(recs)
    mode = "reference" if any(has_f) else "jigfree"
    if any(has_f):
        for i, hf in enumerate(has_f):
            if not hf:
                notes.append(f"{recs[i].source}: skipped: no reference f while other recordings have one "
                             "(diagnose it on its own for a jig-free diagnosis)")

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
        raw_i = np.asarray(rec.raw)
        wl = window_len(device, STATIC_WINDOW_S, n)
        levels = clip_levels(raw_i, device, noise_for(device, raw_i, wl)[0], wl)
        clipped = levels.mask(raw_i)
        not_rest: list[str] = []
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
            poses, not_rest = jigfree_poses(rec, device)
            notes += [f"{rec.source}: {o}" for o in not_rest]
            off = state.total_offset()
            off = np.broadcast_to(off, (n, N))
            gain = np.ones((n, N)) if state.gain is None else state.gain
            y = (np.asarray(rec.raw, float) - off) / gain
            f = np.full((n, 3), np.nan)
            key = np.full(n, -1, np.int64)
            wch = 1.0 / np.maximum(np.asarray(device.noise_counts(), float), 1.0) ** 2 \
                if np.all(device.noise_counts() > 0) else np.ones(N)
            for p, idx in enumerate(poses):
                ybar = y[idx].mean(axis=0)
                f[idx] = pose_force(S, ybar, g, wch)
                hit = clipped[idx].any(axis=0)
                if hit.any() and np.count_nonzero(~hit) >= 2:
                    # a clipped channel's mean is not the model's: the pose's force from the others
                    # (from the all-channel solution), so the clipped reading stays in the residual
                    # where `saturation` can explain it
                    f[idx] = pose_force(S, ybar, g, np.where(hit, CLIPPED_WEIGHT, 1.0) * wch, f[idx[0]])
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
        at_limit = at_rails(rec, device)
        usable0 = usable
        if np.any(at_limit & usable):
            notes.append(f"{rec.source}: {int(np.count_nonzero(at_limit & usable))} samples with a reading at the "
                         f"ADC limits ({device.raw_min} / {device.raw_max}) are left out")
            usable = usable & ~at_limit
        if not usable.any():
            if mode == "jigfree":
                raise InputError(rec.source, "no reference to diagnose against: no f_x, f_y, f_z columns and no "
                                 "static interval (at least 1 s at rest) whose |f| = g could serve instead"
                                 + (f" ({'; '.join(not_rest[:2])})" if not_rest else "")
                                 + gravity_removed_clause(rec.raw, device))
            raise InputError(rec.source, "no sample has a complete reference (f_x, f_y, f_z, and w_*, dw_* while "
                             "moving) to predict the readings from", column="f_x")
        if mode == "reference" and usable.sum() < 0.5 * n:
            notes.append(f"{rec.source}: {int((~usable).sum())} of {n} samples lack part of the reference "
                         "(f, or w/dw while moving) and are left out")
        off = np.asarray(state.total_offset(), float)     # (N,), or (n, N) with a bias in time
        gain_t = None if state.gain is None else np.asarray(state.gain, float)
        parts.append(dict(ri=ri, rec=rec, usable=usable, pred=pred, off=off, gain=gain_t, f=f, w=w, dw=dw,
                          T=T, key=key, stated=stated, pose_lab=pose_lab))
        rec_info.append({"source": rec.source, "n_samples": int(n), "n_used": int(usable.sum()),
                         "duration_s": float(np.ptp(np.asarray(rec.t, float))) if n else 0.0, "reference": how,
                         "clipping": {"levels_lo": levels.lo.tolist(), "levels_hi": levels.hi.tolist(),
                                      "inside_range": (levels.inside_lo | levels.inside_hi).tolist(),
                                      "clipped_per_channel": clipped.sum(axis=0).astype(int).tolist(),
                                      "left_out_at_adc_limits": int(np.count_nonzero(at_limit & usable0))},
                         # the share of a longer recording these samples are (io.thinned)
                         **({} if rec.thinning is None else {"thinned": rec.thinning.describe()})})
        if levels.any_inside():
            hit = clipped.any(axis=1)
            out = int(np.count_nonzero(hit & ~usable))
            notes.append(f"{rec.source}: readings pile up at levels inside the range ({levels.describe()}): "
                         f"{int(hit.sum())} samples clipped; "
                         + ("kept, so that `saturation` can explain them" if not out else
                            "none of them among the samples scored" if out == int(hit.sum()) else
                            f"{int(hit.sum()) - out} of them among the samples scored (kept, so that `saturation` "
                            f"can explain them), {out} outside them")
                         + (" (jig-free the static poses alone are scored: a clip that only the motion reaches "
                            "is seen in the readings, but no model reading is there to measure it against)"
                            if out and mode == "jigfree" else ""))

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
        segs = segments(t, u, pt["key"], h)
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
        cols["off"].append(pt["off"] if pt["off"].ndim == 1 else np.asarray(pt["off"], float)[idx])
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
    offs = cols.pop("off")
    cat = {k: np.concatenate(v) for k, v in cols.items()}
    # one offset for every sample (no bias in time): a read-only view, not n copies of it
    cat["off"] = np.broadcast_to(offs[0], (n_tot, N)) if all(o.ndim == 1 and np.array_equal(o, offs[0])
                                                             for o in offs) \
        else np.concatenate([np.broadcast_to(o, (sz, N)) if o.ndim == 1 else o
                             for o, sz in zip(offs, (c.shape[0] for c in cols["t"]))])
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
    static = cat["pose"] >= 0
    rests = [(int(a), int(bb)) for a, bb in zip(seg_lo, seg_hi) if static[a]]
    p0 = np.clip(pred + rounding_bias(cat["raw"], pred, rests), device.raw_min, device.raw_max)
    gain_t = cat["gain"] if np.any(cat["gain"] != 1.0) else None
    D = FitData(device=device, cal=cal, mode=mode, m0=float(m0), K=K, t=cat["t"], tg=cat["tg"], rec=cat["rec"],
              seg=seg, seg_lo=seg_lo, seg_hi=seg_hi, bstart=bstart, bfold=bfold, bseg=np.array(bseg, np.int64),
              block=block, raw=cat["raw"], pred=pred, p0=p0, offset_t=cat["off"], gain_t=gain_t,
              sensed=pred - cat["off"], f=cat["f"], w=cat["w"], dw=cat["dw"], temp=cat["T"], pose=cat["pose"],
              pose_labels=[kk for kk, _ in sorted(pose_map.items(), key=lambda kv: kv[1])],
              pose_stated=np.where(cat["stated"], cat["pose"], -1), static=static, s=S, r=r, b=b,
              rec_t0=np.array(rec_t0), rec_info=rec_info, notes=notes, h=h)
    for i, pt in enumerate(parts):
        D.rec_info[i]["t0"] = rec_t0[i]
    return D
