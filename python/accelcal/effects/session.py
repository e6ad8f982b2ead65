"""Changes between recordings: an offset or a gain that differs from one recording (session) to
the next, constant within each (turn-on repeatability, a re-mount, a sensor re-powered since the
calibration).

The diagnosis knows which recording each sample comes from (``FitData.rec``): the fit gives each
recording its own offset change (``session_offset``) or gain change (``session_gain``) per channel,
relative to the calibration, so a recording in which nothing moved (the calibration's own session)
reads ~0 and the one that moved reads its shift.  A plain ``offset`` / ``gain`` is this fit with
every recording's value equal (nested in it); a temperature effect reads the same where the
recordings differ in temperature and nothing changes within one (the diagnosis's
:func:`~accelcal.diagnose.compare.contest` prefers the temperature only where it explains change
within a recording beyond the per-recording shift).

Simulation: a simulated recording is one session; ``db`` (``scale``) is its change against the
calibration, applied as an offset (gain) change of that whole recording.
"""
from __future__ import annotations

import numpy as np

from ..spec import Param
from .base import CHANNEL_PARAM, Effect, FitParam, RANDOM_PARAM, as_list, channel_mask, per_channel
from .fitdata import FitData
from .fitting import LinearCandidate

#: what tells a shift between recordings from a temperature effect (``separate_by``)
SESSION_TELL = ("a pose held while the temperature changes slowly (a shift between recordings stays constant "
                "within one, a temperature effect follows the temperature); or a recording at the calibration's "
                "temperature (a shift between sessions remains there, a temperature effect vanishes)")


def n_recordings(D: FitData) -> int:
    """How many recordings the diagnosis was given (``D.rec_info``)."""
    return len(D.rec_info)


def per_recording_columns(D: FitData, z: np.ndarray) -> np.ndarray:
    """(n, N, R) columns: ``z`` (n, N) where the sample belongs to recording r, else 0."""
    R = n_recordings(D)
    onehot = (np.asarray(D.rec)[:, None] == np.arange(R)[None, :]).astype(float)   # (n, R)
    return z[:, :, None] * onehot[:, None, :]


def source_names(D: FitData) -> list[str]:
    """"recording k" for each recording given, with its file where it has one."""
    out = []
    for k, ri in enumerate(D.rec_info):
        src = str(ri.get("source") or "")
        out.append(f"recording {k}" + (f" ({src})" if src and not src.startswith("<") else ""))
    return out


class SessionFit(LinearCandidate):
    """One value per channel for each recording (the fit's columns, :func:`per_recording_columns`)."""

    #: one constant change per recording (the diagnosis's rule against a temperature effect)
    between_recordings = True

    def skip(self, D):
        if n_recordings(D) < 2:
            return "needs two recordings or more (with one, a change since the calibration is an offset or a gain)"
        used = [int(ri.get("n_used", 1)) for ri in D.rec_info]
        if sum(u > 0 for u in used) < 2:
            return "needs samples from two recordings or more"
        return None

    def _z(self, D):
        raise NotImplementedError

    def columns(self, D):
        return per_recording_columns(D, self._z(D))

    def to_params(self, D, theta, cov):
        sd = np.sqrt(np.maximum(np.einsum("nkk->nk", cov), 0.0))
        # (N, R) -> (R, N): one row per recording, in the order given
        return {self.pname: theta.T.copy()}, {self.pname: sd.T.copy()}

    def param_columns(self, D, params):
        """None: the values are (recording, channel), not the (channel, component) the diagnosis's
        not-determined marking indexes (:mod:`accelcal.diagnose.determined`); they are not judged there."""
        return None

    def modify_state(self, state, p, ctx):
        v = np.asarray(p[self.pname], float)
        return self._apply(state, v[-1] if v.ndim == 2 else v)

    def _apply(self, state, v):
        raise NotImplementedError

    def identity(self, ctx):
        return {self.pname: np.zeros((1, ctx.n_channels))}

    def bench_spec(self, m, z, aux):
        return {self.pname: as_list(m * z)}

    def bench_pair(self, est, truth, sig):
        """The diagnosed recordings' values (the last row: the shifted session) against the truth."""
        e = np.atleast_2d(np.asarray(est[self.pname], float))[-1]
        t = np.atleast_2d(np.asarray(truth[self.pname], float))[-1]
        return e, t

    def _spread(self, p, s, D, unit, scale, fmt):
        v = np.atleast_2d(np.asarray(p[self.pname], float)) * scale
        sd = np.atleast_2d(np.asarray(s[self.pname], float)) * scale
        if v.shape[0] < 2:
            i = int(np.argmax(np.abs(v[0])))
            return (f"{self.what} of this recording against the calibration up to {v[0, i]:{fmt}} +- {sd[0, i]:.2g} "
                    f"{unit} on channel {i}")
        d = np.ptp(v, axis=0)
        i = int(np.argmax(d))
        names = source_names(D) if D is not None else []
        per = "; ".join(f"{names[k] if k < len(names) else f'recording {k}'}: {v[k, i]:{fmt}} +- {sd[k, i]:.2g}"
                        for k in range(v.shape[0]))
        return (f"{self.what} changed between recordings by up to {d[i]:.4g} {unit} on channel {i} "
                f"(against the calibration, {unit}: {per})")


class SessionOffset(SessionFit, Effect):
    name = "session_offset"
    what = "offset"
    tell_apart = SESSION_TELL
    tells_from = ("temperature_offset", "temperature_gain", "bias_drift")
    summary = "b_i differs between recordings (one constant shift per recording against the calibration)"
    doc = ("b_i -> b_i + db_i in each recording (counts; db (R, N): one row per recording in the order given, "
           "relative to the calibration; a simulated recording takes its last row).")
    stage = "state"
    params = (
        Param("db", None, "counts", "the recording's offset change against the calibration; auto = 1 % of g in "
              "counts (per channel, from |s_i|)", "floats"),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("db", "recording_channel", "counts", "offset change of each recording (rows) and channel"),)
    pname = "db"
    bench_size = 1.0
    bench_key = "db"

    def _z(self, D):
        return np.ones((D.n, D.N))

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        db = per_channel(spec["db"], 0.01 * ctx.g_counts(), m, rng if spec["random"] else None, self.name, "db")
        return {"db": db[None, :]}

    def _apply(self, state, v):
        return state.replace(offsets=state.offsets + v)

    def describe(self, p, s, D):
        return self._spread(p, s, D, "counts", 1.0, "+.4g")


class SessionGain(SessionFit, Effect):
    name = "session_gain"
    what = "gain"
    varies_by_pose = True
    tell_apart = SESSION_TELL
    tells_from = ("temperature_gain", "temperature_offset", "bias_drift")
    summary = "the magnitude of s_i differs between recordings (one gain change per recording against the calibration)"
    doc = ("s_i -> (1 + scale_i) s_i in each recording (scale (R, N): one row per recording in the order given, "
           "relative to the calibration; a simulated recording takes its last row).")
    stage = "state"
    params = (
        Param("scale", 0.01, "fraction", "the recording's relative gain change against the calibration", "floats",
              minimum=-0.99),
        CHANNEL_PARAM,
        RANDOM_PARAM,
    )
    fit = (FitParam("scale", "recording_channel", "fraction", "relative gain change of each recording (rows) and "
                    "channel"),)
    pname = "scale"
    bench_size = 0.001
    bench_key = "scale"

    def _z(self, D):
        return D.sensed

    def _resolve(self, spec, ctx, rng):
        m = channel_mask(spec, ctx, self.name)
        return {"scale": per_channel(spec["scale"], 0.0, m, rng if spec["random"] else None, self.name,
                                     "scale")[None, :]}

    def _apply(self, state, v):
        return state.replace(sensitivity=state.sensitivity * (1.0 + v)[:, None])

    def describe(self, p, s, D):
        return self._spread(p, s, D, "%", 100.0, "+.3g")
