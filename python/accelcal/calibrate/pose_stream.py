"""A labelled recording reduced to its pose statistics while it is read in chunks (``calibrate``
on long recordings; docs/streaming.md, issue 37).

:func:`accelcal.readings.static.poses_from_recording` holds the whole recording and gathers each
pose's readings; :func:`reduce_labelled` reads the file twice in chunks
(:mod:`accelcal.io.chunk_source`) and keeps per pose only sums:

1. per chunk the reader's checks and the device's range; more than half the time steps within
   RATE_TOL / 2 of the device's (t in seconds, the device's rate stands) and the runs of
   identical rows (:class:`accelcal.readings.held.RunCounts`: no readings held for several
   rows); per label its sample count, each channel's histogram of readings (the clip levels,
   :func:`accelcal.readings.clipping.clip_levels_counts`, and the code step) and where f is given;
2. per pose the integer sums of its readings and of their squares about one reference reading
   (exact: the whole-file :func:`~accelcal.readings.static.pose_means` sums the same integers),
   the same sums over each of its MOVE_PARTS parts (the motion test) and COLOUR_BATCHES batches
   (:func:`~accelcal.readings.noise.pose_colour`), the sums of f and temp_c, its first and last
   samples.

The means, counts and std equal the whole-file ones bit for bit; the parts' and batches' figures
and f_ref, temp differ by rounding only (float sums in another order).  Where this path cannot
tell what the whole-file path would do it returns None and the caller reads the file whole:
no ``pose`` labels (:func:`accelcal.calibrate.still_reduce.reduce_unlabelled` reduces those), the
noise estimate's sums beyond exact floats (a device without ``noise_mps2``: :func:`data_noise`, a
third pass), a pose with a clipped reading or that moves, rotating samples (the
lever arms need them), f given on part of a pose, a pose off gravity without f, a pose before the lowest label's first
sample, half the steps or more off the device's by more than RATE_TOL / 2, readings held for
several rows, any reader fallback or input error (the whole-file reader words it).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np

from ..errors import InputError
from ..io.chunk_source import open_chunks
from ..io.chunks import BLOCK_BYTES, Fallback, reader_checks
from ..io.recording_checks import RATE_TOL, check_raw_range
from ..readings.held import RunCounts
from ..readings.clipping import clip_levels_counts, code_step_counts
from ..readings.noise import COLOUR_BATCHES, noise_for, states_noise
from ..readings.noise_stream import NoisePass
from ..readings.static import STATIC_WINDOW_S, PoseSet, at_gravity, window_len
from ..readings.steps import MOVE_PARTS, MOVE_RANGE, MOVE_STD
from .settings import ROTATION_MIN_RADPS

__all__ = ["Reduced", "reduce_labelled", "checked_pass", "data_noise", "mean_var"]

@dataclass
class Reduced:
    """A recording reduced to its static poses (what :func:`accelcal.calibrate.calibrate_recordings`
    takes from a labelled recording without rotation).

    Attributes
    ----------
    source : str
        The path as given.
    n_samples : int
        Rows.
    poses : PoseSet
        As :func:`accelcal.readings.static.poses_from_recording` gives it.
    extra : list of str
        The columns that are not the contract's.
    metadata : dict of str to str
        The file's comments (``pose_names`` names the poses in messages).
    labelled : bool
        Whether the poses are the file's ``pose`` labels (else the static detector's still
        stretches: :func:`accelcal.calibrate.still_reduce.reduce_unlabelled`).
    short : list of float
        The lengths (s) of the still stretches the detector left out as shorter than its minimum
        where a motion touches them (:func:`accelcal.calibrate.recordings.short_stretches`).
    """

    source: str
    n_samples: int
    poses: PoseSet
    extra: list
    metadata: dict
    labelled: bool = True
    short: list = field(default_factory=list)

    def has_pose(self) -> bool:
        return self.labelled


def _group_sums(x: np.ndarray, key: np.ndarray, groups: int) -> tuple[np.ndarray, np.ndarray]:
    """Integer sums of ``x`` (n, N) and of its squares by ``key`` (n,) in 0..groups-1."""
    N = x.shape[1]
    s1 = np.zeros((groups, N), np.int64)
    s2 = np.zeros((groups, N), np.int64)
    np.add.at(s1, key, x)
    np.add.at(s2, key, x * x)
    return s1, s2


def mean_var(s1: np.ndarray, s2: np.ndarray, cnt: np.ndarray, ref: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """pose_means' arithmetic: mean and ddof-1 variance from integer sums about ``ref``."""
    a, b = s1.astype(float), s2.astype(float)
    cf = cnt.astype(float)[..., None]
    mean = a / np.maximum(cf, 1)
    var = np.maximum(b - a * mean, 0.0) / np.maximum(cf - 1, 1)
    return mean + ref, var


def reduce_labelled(path: Any, device, scale=None, block_bytes: int = BLOCK_BYTES) -> Reduced | None:
    """The recording at ``path`` reduced to its poses, or None where the whole file must be read
    (see the module doc)."""
    try:
        return _reduce(path, device, scale, block_bytes)
    except (Fallback, InputError):
        return None


def checked_pass(src, device, each: Callable[[Any], None] | None = None) -> tuple[int, list] | None:
    """The first pass over ``src`` (:func:`accelcal.io.chunk_source.open_chunks`): per chunk the
    reader's checks and the device's range, the time steps, the runs of identical rows, each
    channel's histogram and no rotating sample (f, w, dw given, |w| > ROTATION_MIN_RADPS), then
    ``each(chunk)``.  Returns (rows, each channel's histogram as (values ascending, counts)), or
    None where the whole-file path must read the file: a reader's error or fallback, t not
    finite, a rotating sample, half the steps or more off the device's by more than RATE_TOL / 2,
    readings held for several rows, a range of more than 2^20 codes."""
    head = src.head
    N = device.n_channels
    span = int(device.raw_max) - int(device.raw_min) + 1
    if span > (1 << 20):
        return None
    hist = np.zeros((N, span), np.int64)
    prev = None
    n_rows = 0
    runs = RunCounts()
    near = 0
    for ch in src.chunks():
        # the reader's checks and the range: any error is the whole-file path's to word
        if reader_checks(head, ch, prev):
            return None
        check_raw_range(SimpleNamespace(raw=ch.raw, source=head.source, line=ch.line), device)
        # most steps within RATE_TOL / 2 of the device's: the median is, so t is in seconds and the
        # device's rate stands (io.recording_checks.rate_for)
        t = ch.t if prev is None else np.concatenate(([prev.t[-1]], ch.t))
        if not np.all(np.isfinite(t)):
            return None
        near += int(np.count_nonzero(np.abs(np.diff(t) * device.sample_rate_hz - 1.0) <= RATE_TOL / 2))
        runs.add(ch.raw)
        prev = ch
        n_rows += ch.n
        for j in range(N):
            hist[j] += np.bincount(ch.raw[:, j] - int(device.raw_min), minlength=span)
        w, dw, f = ch.vecs.get("w"), ch.vecs.get("dw"), ch.vecs.get("f")
        if w is not None and dw is not None and f is not None:
            ok = np.all(np.isfinite(f), 1) & np.all(np.isfinite(w), 1) & np.all(np.isfinite(dw), 1)
            if np.any(ok & (np.linalg.norm(np.nan_to_num(w), axis=1) > ROTATION_MIN_RADPS)):
                return None
        if each is not None:
            each(ch)
    if 2 * near <= n_rows - 1 or runs.held(N) != 1:
        return None
    hists = []
    for h in hist:
        u = np.flatnonzero(h)
        hists.append((u.astype(np.int64) + int(device.raw_min), h[u]))
    return n_rows, hists


def data_noise(src, device, n: int, hists: list) -> np.ndarray | None:
    """:func:`accelcal.readings.noise.noise_for`'s noise of the recording read by ``src`` (``n``
    rows, each channel's histogram ``hists``): the device's ``noise_mps2`` where it states one,
    else ``estimate_noise``'s from a pass over the chunks (:class:`accelcal.readings.noise_stream.NoisePass`:
    the same floats), or None where its sums pass the floats' exact integers."""
    N = device.n_channels
    if states_noise(device):
        return noise_for(device, np.zeros((0, N), np.int64), 1)[0]
    p = NoisePass(n, window_len(device, STATIC_WINDOW_S, n), np.array([u[0] for u, _ in hists]),
                  np.array([u[-1] for u, _ in hists]), np.array([code_step_counts(u, c) for u, c in hists]))
    try:
        for ch in src.chunks():
            p.add(ch.raw)
        return p.noise()
    except ValueError:
        return None
    finally:
        p.close()


def _reduce(path: Any, device, scale, block_bytes: int) -> Reduced | None:
    src = open_chunks(path, device.n_channels, scale, block_bytes=block_bytes, batch_rows=max(block_bytes // 64, 1))
    head = src.head
    if "pose" not in head.cols:
        return None
    if head.n_raw != device.n_channels:
        return None
    N = device.n_channels
    counts: dict[int, int] = {}
    f_seen: dict[int, list] = {}          # label -> [any f given, any f missing]

    def each(ch) -> None:
        pose = ch.other["pose"]
        labs, cnt = np.unique(pose[pose >= 0], return_counts=True)
        for v, c in zip(labs.tolist(), cnt.tolist()):
            counts[v] = counts.get(v, 0) + c
        f = ch.vecs.get("f")
        if f is not None:
            fin = np.all(np.isfinite(f), axis=1)
            for v in labs.tolist():
                m = pose == v
                seen = f_seen.setdefault(v, [False, False])
                seen[0] |= bool(fin[m].any())
                seen[1] |= bool((~fin[m]).any())

    first = checked_pass(src, device, each)
    if first is None or not counts or any(a and b for a, b in f_seen.values()):
        return None
    n_rows, hists = first
    labels = sorted(counts)
    P = len(labels)
    cnt = np.array([counts[v] for v in labels], np.int64)
    noise = data_noise(src, device, n_rows, hists)
    if noise is None:
        return None
    levels = clip_levels_counts(hists, device, noise)
    if levels is None:
        return None
    step = np.array([float(code_step_counts(u, c)) for u, c in hists])
    # pass 3: the sums; parts as np.array_split cuts them, batches of L = n // B (the rest left out)
    B = COLOUR_BATCHES
    part_len = [np.array([len(q) for q in np.array_split(np.arange(n), MOVE_PARTS)]) for n in cnt.tolist()]
    part_end = np.array([np.cumsum(q) for q in part_len], np.int64)
    labels_arr = np.array(labels, np.int64)
    L = cnt // B
    seen = np.zeros(P, np.int64)
    ref = None
    s1 = np.zeros((P, N), np.int64)
    s2 = np.zeros((P, N), np.int64)
    p1 = np.zeros((P * MOVE_PARTS, N), np.int64)
    p2 = np.zeros((P * MOVE_PARTS, N), np.int64)
    b1 = np.zeros((P * B, N), np.int64)
    b2 = np.zeros((P * B, N), np.int64)
    fsum = np.zeros((P, 3))
    tsum = np.zeros(P)
    tcnt = np.zeros(P, np.int64)
    first = np.full(P, -1, np.int64)
    last = np.zeros(P, np.int64)
    t_start = np.zeros(P)
    t_stop = np.zeros(P)
    clipped = False
    for ch in src.chunks():
        pose = ch.other["pose"]
        rows = np.flatnonzero(pose >= 0)
        if not rows.size:
            continue
        pidx = np.searchsorted(labels_arr, pose[rows])
        x = ch.raw[rows]
        clipped |= bool(levels.mask(x).any())
        if ref is None:       # pose_means' reference: the first sample of the lowest label
            lo = np.flatnonzero(pidx == 0)
            if lo.size:
                ref = x[lo[0]].copy()
        # rank of each row within its pose
        order = np.argsort(pidx, kind="stable")
        sp = pidx[order]
        starts = np.searchsorted(sp, np.arange(P))
        rank = np.empty(rows.size, np.int64)
        rank[order] = np.arange(rows.size) - starts[sp] + seen[sp]
        if ref is None:        # a pose before the lowest label's first sample: the whole file
            return None
        xr = x - ref
        a, b = _group_sums(xr, pidx, P)
        s1 += a
        s2 += b
        part = (rank[:, None] >= part_end[pidx]).sum(axis=1)
        a, b = _group_sums(xr, pidx * MOVE_PARTS + part, P * MOVE_PARTS)
        p1 += a
        p2 += b
        inb = rank < B * L[pidx]
        bat = np.where(inb, rank // np.maximum(L[pidx], 1), 0)
        a, b = _group_sums(xr[inb], (pidx * B + bat)[inb], P * B)
        b1 += a
        b2 += b
        f = ch.vecs.get("f")
        if f is not None:
            fin = np.all(np.isfinite(f[rows]), axis=1)
            np.add.at(fsum, pidx[fin], f[rows][fin])
        tc = ch.other.get("temp_c")
        if tc is not None:
            tv = tc[rows]
            ok = np.isfinite(tv)
            np.add.at(tsum, pidx[ok], tv[ok])
            np.add.at(tcnt, pidx[ok], 1)
        gidx = rows + ch.start
        for p in np.unique(pidx).tolist():
            m = pidx == p
            if first[p] < 0:
                first[p] = int(gidx[m][0])
                t_start[p] = float(ch.t[rows[m][0]])
            last[p] = int(gidx[m][-1])
            t_stop[p] = float(ch.t[rows[m][-1]])
        np.add.at(seen, pidx, 1)
    if clipped:
        return None
    means, var = mean_var(s1, s2, cnt, ref)
    std = np.sqrt(var)
    # the motion test of labelled poses (pose_means' check_motion) on the parts' sums
    ref_sig = np.maximum(np.asarray(noise, float), np.median(std[cnt >= 3], axis=0) if np.any(cnt >= 3) else 0.0)
    ref_sig = np.maximum(ref_sig, 1e-9)
    pc = np.concatenate(part_len)
    pm, pv = mean_var(p1, p2, pc, ref)
    for p in range(P):
        if cnt[p] < 2 * MOVE_PARTS:
            continue
        q = slice(p * MOVE_PARTS, (p + 1) * MOVE_PARTS)
        part_sig = np.maximum(ref_sig, np.median(np.sqrt(pv[q]), axis=0))
        spread = (pm[q].max(axis=0) - pm[q].min(axis=0)) / part_sig
        if np.any((spread > MOVE_RANGE) | (std[p] / ref_sig > MOVE_STD)):
            return None          # refused by the whole-file path, which words it
    # the colour ratios (pose_colour): var of the batch means x L / var of the first B L samples
    colour = np.full((P, N), np.nan)
    for p in range(P):
        if L[p] < 2:
            continue
        bm = b1[p * B:(p + 1) * B] / float(L[p])
        tot = b1[p * B:(p + 1) * B].sum(axis=0).astype(float)
        sq = b2[p * B:(p + 1) * B].sum(axis=0).astype(float)
        v = np.maximum(sq - tot * (tot / (B * L[p])), 0.0) / (B * L[p] - 1)
        ok = v > 0
        colour[p] = np.where(ok, bm.var(axis=0, ddof=1) * L[p] / np.where(ok, v, 1.0), 1.0)
    ratio = np.array([float(np.linalg.norm(np.linalg.lstsq(device.nominal_sensitivity(), m - device.nominal_offsets(),
                                                            rcond=None)[0])) / device.gravity_mps2 for m in means])
    has_f = np.array([f_seen.get(v, [False, False])[0] for v in labels])
    if not np.all(at_gravity(ratio) | has_f):
        return None
    f_ref = np.where(has_f[:, None], fsum / cnt[:, None], np.nan)
    temp = np.where(tcnt > 0, tsum / np.maximum(tcnt, 1), np.nan)
    info = [{"source": head.source, "label": v, "first": int(first[p]), "last": int(last[p]),
             "t_start": float(t_start[p]), "t_stop": float(t_stop[p]), "n": int(cnt[p])} for p, v in enumerate(labels)]
    poses = PoseSet(means=means, n=cnt, std=std, f_ref=f_ref, temp=temp, info=info, set_aside=[],
                    colour_r2=colour, step=np.tile(step, (P, 1)))
    return Reduced(source=head.source, n_samples=n_rows, poses=poses, extra=list(head.extra),
                   metadata=dict(head.metadata))
