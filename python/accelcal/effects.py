"""The effects registry: every unmodelled effect of the data contract, as data.

One :class:`Effect` object per contract name (``EFFECTS``, in the contract's
order) carries the effect's parameters (names, defaults, units, docs) and how
it changes a channel's reading.  The simulator applies it to the truth; the
diagnosis fits the very same object to a recording.  Adding an effect here adds
it to both.

Two levels of parameters
------------------------
* **Spec parameters** (``Effect.params``): what a user writes,
  ``--effect gain:scale=0.01,channel=2``.  They may leave values to defaults
  derived from the device (e.g. "1 % of g in counts"), select channels, or ask
  for random per-channel values.  :meth:`Effect.resolve` turns them, with a
  device context and a random generator, into
* **concrete parameters** (``Effect.fit``): a dict of numpy arrays, one value
  per channel (or per pose), in fixed units, with no randomness left.
  :meth:`Effect.apply` is a deterministic function of (context, concrete
  parameters); :meth:`Effect.identity` gives the concrete parameters that leave
  the readings unchanged (the starting point of a fit).

The reading model and the context
---------------------------------
A :class:`Context` holds the truth (``t, f, omega, alpha, temp_c, pose,
attitude`` in body axes and SI units, see ``motions.Trajectory``; a recording's
reference columns work as well), the device, the channel state and the current
noise-free readings ``counts`` (n, N), float, before rounding.  The channel
state (:class:`ChannelState`) is everything the sensor equation needs::

    counts_i(t) = b_i + bias_i(t) + gain_i(t) * c_sensed_i(t + tau_i)
    c_sensed_i  = s_i . ( f + alpha x r_i + m_i * omega x (omega x r_i) )

with ``b`` offsets (counts), ``s`` sensitivity vectors (counts per m/s^2),
``r`` positions (m), ``m`` the centripetal multiplier (1 = physics), ``tau``
per-channel time skews (s), ``bias`` a time-varying extra offset (counts) and
``gain`` a time-varying gain factor (1 = none).  :func:`evaluate` computes it.

Stages (the simulator's pipeline, in this order)
------------------------------------------------
1. ``state``  -- offset, gain, misalignment, position_error, centripetal,
   time_skew, temperature_offset, temperature_gain, bias_drift: they change the
   channel state; the readings are then evaluated exactly from the truth.
2. ``signal`` -- nonlinearity, then bandwidth: they act on the noise-free
   readings (n, N).
3. (simulator) Gaussian noise in counts is added.
4. ``adc``    -- quantization (instead of rounding to 1 count), then
   saturation; then the simulator rounds and clips to [raw_min, raw_max].
5. ``reference`` -- pose_error: changes only the recorded reference ``f`` of
   static poses, never the readings.

``Effect.apply(ctx, p)`` is the single entry point for the diagnosis: for a
``state`` effect it re-evaluates the readings from ``ctx.truth`` with the
modified state; for ``signal``/``adc`` effects it transforms ``ctx.counts``;
for ``pose_error`` it predicts the readings from the *corrected* reference
(the recorded one rotated back by the fitted pose rotations).

Spec strings
------------
``NAME[:k=v,k=v,...]``; values are numbers, words (``x``, ``-z``, ``random``,
``all``) or bracketed lists (``db=[10,20,0,0,0,0]``, ``toward=[0,1,1]``;
commas inside brackets do not split parameters); ``;`` or ``|`` also separate
list items (``channel=0;2``).  :func:`parse_effect_spec` checks names and
values and raises :class:`~accelcal.errors.AccelcalError` with a one-line
message for anything unknown or malformed.
"""

from __future__ import annotations

import difflib
import json
import math
import zlib
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from .errors import AccelcalError
from .sensor import ChannelState, Context, evaluate, lowpass_first_order, make_context, rotation_matrix
from .spec import Param, check_params, format_spec, parse_spec, with_defaults

__all__ = [
    "Param",
    "FitParam",
    "Effect",
    "EffectSpec",
    "ChannelState",
    "Context",
    "EFFECTS",
    "EFFECT_NAMES",
    "PIPELINE_ORDER",
    "STAGES",
    "get_effect",
    "parse_spec",
    "format_spec",
    "parse_effect_spec",
    "parse_effect_specs",
    "params_to_json",
    "effect_rng",
    "random_walk",
    "make_context",
    "evaluate",
    "lowpass_first_order",
    "rotation_matrix",
    "describe_effects",
]

STAGES = ("state", "signal", "adc", "reference")


# ==========================================================================
# Spec parsing and parameter coercion (shared with motions.py)
# ==========================================================================


























# ==========================================================================
# Channel state, context, evaluation
# ==========================================================================


















# ==========================================================================
# First-order low-pass, exact (ramp-invariant) discretisation
# ==========================================================================








# ==========================================================================
# Effects
# ==========================================================================


@dataclass(frozen=True)
class FitParam:
    """One concrete (fitted) parameter: ``shape`` is 'channel' (N,),
    'channel3' (N, 3), 'pose' (P,), 'pose3' (P, 3), 'knot' (K,), 'channel_knot' (N, K) or
    'scalar'; ``free`` False
    for bookkeeping values a fit keeps fixed (reference temperature, seeds)."""

    name: str
    shape: str
    unit: str
    doc: str
    free: bool = True


_CHANNEL = Param("channel", "all", "-", "channels that get the effect: all, an index or a list", "channels")
_RANDOM = Param("random", False, "-", "1: each selected channel draws value x N(0, 1) instead of the value", "bool")


def _owner(name: str) -> str:
    return f"effect {name!r}"


class Effect:
    """One contract effect.  Subclasses set the class attributes and implement
    the stage's hook (``modify_state`` / ``apply_signal`` / ``apply_reference``)
    plus ``_resolve`` and ``identity``."""

    name: str = ""
    summary: str = ""  # the contract's line
    doc: str = ""  # parameterisation, units, how it is applied
    stage: str = "state"
    linear: bool = False  # readings affine in the free concrete parameters
    params: tuple[Param, ...] = ()
    fit: tuple[FitParam, ...] = ()

    # -- user-facing ------------------------------------------------------

    def check(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """Coerce user parameters (strings or values); unknown names raise AccelcalError."""
        return check_params(self.params, given, _owner(self.name))

    def resolve(self, given: Mapping[str, Any], ctx: Context, rng: np.random.Generator | None = None) -> dict[str, Any]:
        """Spec parameters (checked or raw) -> concrete parameters for ``ctx``
        (defaults filled from the device, channels selected, random draws made)."""
        spec = with_defaults(self.params, self.check(given))
        rng = np.random.default_rng(0) if rng is None else rng
        return self._resolve(spec, ctx, rng)

    def help(self) -> str:
        lines = [f"{self.name}: {self.summary}"]
        lines += [f"    {p.help()}" for p in self.params]
        return "\n".join(lines)

    # -- the model --------------------------------------------------------

    def identity(self, ctx: Context) -> dict[str, Any]:
        """Concrete parameters that leave ``ctx``'s readings unchanged."""
        raise NotImplementedError

    def apply(self, ctx: Context, p: Mapping[str, Any]) -> np.ndarray:
        """Readings (n, N) float, noise-free, with this effect (parameters ``p``,
        concrete) added to ``ctx`` (see the module doc for each stage)."""
        if self.stage == "state":
            return evaluate(ctx.truth, self.modify_state(ctx.state, p, ctx))
        if self.stage in ("signal", "adc"):
            return self.apply_signal(ctx.counts, p, ctx)
        raise NotImplementedError

    def modify_state(self, state: ChannelState, p: Mapping[str, Any], ctx: Context) -> ChannelState:
        raise NotImplementedError(f"{self.name} is not a state effect")

    def apply_signal(self, counts: np.ndarray, p: Mapping[str, Any], ctx: Context) -> np.ndarray:
        raise NotImplementedError(f"{self.name} is not a signal effect")

    def apply_reference(self, f_ref: np.ndarray, p: Mapping[str, Any], ctx: Context) -> np.ndarray:
        """Recorded reference f (n, 3) with this effect (reference stage only);
        other stages leave it alone."""
        return f_ref

    def _resolve(self, spec: dict[str, Any], ctx: Context, rng: np.random.Generator) -> dict[str, Any]:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"<Effect {self.name} ({self.stage})>"


# -- helpers for per-channel values ------------------------------------------


def _mask(spec: Mapping[str, Any], ctx: Context, name: str) -> np.ndarray:
    N = ctx.n_channels
    sel = spec.get("channel")
    m = np.zeros(N, bool)
    if sel is None:
        m[:] = True
        return m
    bad = [c for c in sel if c >= N]
    if bad:
        raise AccelcalError(
            f"{_owner(name)} parameter 'channel': channel {bad[0]} is out of range "
            f"(the device has {N} channels: 0..{N - 1})"
        )
    m[list(sel)] = True
    return m


def _per_channel(value: Any, default: np.ndarray, mask: np.ndarray, rng: np.random.Generator | None,
                 name: str, pname: str, off_value: float = 0.0) -> np.ndarray:
    """(N,) values: ``value`` (None = ``default``), scalar or a list of length N
    or of the number of selected channels; ``rng`` given: value x N(0,1) per
    channel; channels outside ``mask`` get ``off_value``."""
    N = mask.shape[0]
    if value is None:
        v = np.asarray(default, float) * np.ones(N)
    elif np.ndim(value) == 0:
        v = np.full(N, float(value))
    else:
        arr = np.asarray(value, float).ravel()
        k = int(mask.sum())
        if arr.size == N:
            v = arr.copy()
        elif arr.size == k:
            v = np.full(N, off_value)
            v[mask] = arr
        else:
            raise AccelcalError(
                f"{_owner(name)} parameter {pname!r}: expected 1 value or {N} (one per channel)"
                + (f" or {k} (one per selected channel)" if k != N else "")
                + f", got {arr.size}"
            )
    if rng is not None:
        v = v * rng.standard_normal(N)
    return np.where(mask, v, off_value)


def _random_perpendicular(u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Unit vectors (N,3) perpendicular to the unit rows of u, uniformly random around them."""
    out = np.empty_like(u)
    for i in range(u.shape[0]):
        while True:
            v = rng.standard_normal(3)
            v -= np.dot(v, u[i]) * u[i]
            nv = np.linalg.norm(v)
            if nv > 1e-6:
                out[i] = v / nv
                break
    return out


def _unit_rows(a: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(a, axis=1, keepdims=True)
    return a / np.where(n > 0, n, 1.0)


def _t0(ctx: Context) -> float:
    return float(np.asarray(ctx.truth.t, float)[0])


def _temp(ctx: Context, name: str) -> np.ndarray:
    T = getattr(ctx.truth, "temp_c", None)
    T = None if T is None else np.asarray(T, float)
    if T is None or not np.all(np.isfinite(T)):
        raise AccelcalError(f"{_owner(name)} needs the temperature at every sample (temp_c)")
    return T


# -- state effects -------------------------------------------------------------


class _Offset(Effect):
    name = "offset"
    summary = "b_i differs from the calibrated value (a constant shift)"
    doc = "b_i -> b_i + db_i (counts)."
    stage = "state"
    linear = True
    params = (
        Param("db", None, "counts", "offset change; auto = 1 % of g in counts (per channel, from |s_i|)", "floats"),
        _CHANNEL,
        _RANDOM,
    )
    fit = (FitParam("db", "channel", "counts", "offset change"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        db = _per_channel(spec["db"], 0.01 * ctx.g_counts(), m, rng if spec["random"] else None, self.name, "db")
        return {"db": db}

    def identity(self, ctx):
        return {"db": np.zeros(ctx.n_channels)}

    def modify_state(self, state, p, ctx):
        return state.replace(offsets=state.offsets + np.asarray(p["db"], float))


class _Gain(Effect):
    name = "gain"
    summary = "the magnitude of s_i differs (scale error along the axis)"
    doc = "s_i -> (1 + scale_i) s_i (scale: fraction)."
    stage = "state"
    linear = True
    params = (
        Param("scale", 0.01, "fraction", "relative gain change delta k_i / k_i", "floats", minimum=-0.99),
        _CHANNEL,
        _RANDOM,
    )
    fit = (FitParam("scale", "channel", "fraction", "relative gain change"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        return {"scale": _per_channel(spec["scale"], 0.0, m, rng if spec["random"] else None, self.name, "scale")}

    def identity(self, ctx):
        return {"scale": np.zeros(ctx.n_channels)}

    def modify_state(self, state, p, ctx):
        return state.replace(sensitivity=state.sensitivity * (1.0 + np.asarray(p["scale"], float))[:, None])


class _Misalignment(Effect):
    name = "misalignment"
    summary = "the direction of s_i differs (cross-axis sensitivity)"
    doc = ("s_i -> Exp(rot_i) s_i: s_i rotated by the small rotation vector rot_i (rad, body axes); "
           "only the part of rot_i perpendicular to s_i matters (2 free values per channel).")
    stage = "state"
    linear = False  # affine to first order in rot
    params = (
        Param("angle_deg", 0.5, "deg", "tilt of each selected channel's sensitive axis", "floats", minimum=0.0),
        Param("toward", "random", "-", "direction the axis tilts toward: random (per channel) or a body direction",
              "direction_or_random"),
        _CHANNEL,
    )
    fit = (FitParam("rot", "channel3", "rad", "rotation vector applied to s_i"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        ang = np.radians(_per_channel(spec["angle_deg"], 0.0, m, None, self.name, "angle_deg"))
        u = _unit_rows(ctx.state.sensitivity)
        if isinstance(spec["toward"], str):
            d = _random_perpendicular(u, rng)
        else:
            d = np.broadcast_to(spec["toward"], u.shape)
            d = d - np.sum(d * u, axis=1, keepdims=True) * u
            small = np.linalg.norm(d, axis=1) < 1e-9
            if np.any(small & m):
                i = int(np.flatnonzero(small & m)[0])
                raise AccelcalError(
                    f"{_owner(self.name)} parameter 'toward': channel {i}'s axis already points that way"
                )
            d = _unit_rows(d)
        axis = _unit_rows(np.cross(u, d))  # rotating u about u x d tilts it toward d
        return {"rot": axis * ang[:, None]}

    def identity(self, ctx):
        return {"rot": np.zeros((ctx.n_channels, 3))}

    def modify_state(self, state, p, ctx):
        R = rotation_matrix(np.asarray(p["rot"], float))
        return state.replace(sensitivity=np.einsum("nij,nj->ni", R, state.sensitivity))


class _PositionError(Effect):
    name = "position_error"
    summary = "the true position is r_i + dr_i: shows only under rotation"
    doc = "r_i -> r_i + dr_i (m, body axes)."
    stage = "state"
    linear = True
    params = (
        Param("mm", 1.0, "mm", "size of each selected channel's position error", "floats", minimum=0.0),
        Param("direction", "random", "-", "direction of dr_i: random (per channel) or a body direction",
              "direction_or_random"),
        _CHANNEL,
    )
    fit = (FitParam("dr", "channel3", "m", "position error"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        size = 1e-3 * _per_channel(spec["mm"], 0.0, m, None, self.name, "mm")
        N = ctx.n_channels
        if isinstance(spec["direction"], str):
            d = _unit_rows(rng.standard_normal((N, 3)))
        else:
            d = np.broadcast_to(spec["direction"], (N, 3))
        return {"dr": d * size[:, None]}

    def identity(self, ctx):
        return {"dr": np.zeros((ctx.n_channels, 3))}

    def modify_state(self, state, p, ctx):
        return state.replace(positions=state.positions + np.asarray(p["dr"], float))


class _Centripetal(Effect):
    name = "centripetal"
    summary = "the model leaves out the omega x (omega x r_i) term"
    doc = ("Sets the multiplier of s_i . (omega x (omega x r_i)) in the readings to scale_i.  The physical "
           "truth always has the term (multiplier 1), so in the simulator the default scale=1 changes "
           "nothing and scale<1 withholds (part of) the term from the data.  The diagnosis's base model "
           "is the contract's, with the term (multiplier 1), and the fit recovers the data's scale; "
           "diagnose(model_centripetal=False) starts from the paper's model without it (multiplier 0).")
    stage = "state"
    linear = True
    params = (
        Param("scale", 1.0, "-", "multiplier of the centripetal term (1 = physics, 0 = withheld)", "floats"),
        _CHANNEL,
    )
    fit = (FitParam("scale", "channel", "-", "multiplier of the centripetal term (set, not added)"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        v = _per_channel(spec["scale"], 1.0, m, None, self.name, "scale")
        return {"scale": np.where(m, v, ctx.state.centripetal)}

    def identity(self, ctx):
        return {"scale": np.array(ctx.state.centripetal, float)}

    def modify_state(self, state, p, ctx):
        return state.replace(centripetal=np.broadcast_to(np.asarray(p["scale"], float), state.centripetal.shape).copy())


class _TimeSkew(Effect):
    name = "time_skew"
    summary = "channel i is sampled at t + tau_i instead of t"
    doc = ("tau_i -> tau_i + tau (s): the motion is evaluated at t + tau_i (exactly from the analytic "
           "trajectory when the truth has one, else by cubic-spline interpolation of the reference).")
    stage = "state"
    linear = False
    params = (
        Param("tau", None, "s", "skew; auto = a quarter of the sample period", "floats"),
        Param("sequential", False, "-", "1: channel i is skewed by i x tau (a multiplexed ADC)", "bool"),
        _CHANNEL,
        _RANDOM,
    )
    fit = (FitParam("tau", "channel", "s", "time skew"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        default = 0.25 / float(ctx.device.sample_rate_hz)
        tau = _per_channel(spec["tau"], default, m, rng if spec["random"] else None, self.name, "tau")
        if spec["sequential"]:
            tau = tau * np.arange(ctx.n_channels)
        return {"tau": tau}

    def identity(self, ctx):
        return {"tau": np.zeros(ctx.n_channels)}

    def modify_state(self, state, p, ctx):
        return state.replace(tau=state.tau + np.asarray(p["tau"], float))


class _TemperatureOffset(Effect):
    name = "temperature_offset"
    summary = "b_i changes linearly with temperature"
    doc = "bias_i(t) += coeff_i (T(t) - t_ref) (coeff: counts per degC)."
    stage = "state"
    linear = True
    params = (
        Param("coeff", None, "counts/degC", "offset tempco; auto = 0.2 % of g per degC in counts", "floats"),
        Param("t_ref", 25.0, "degC", "temperature at which the offset is the calibrated one (the effect shows "
              "only when the motion's temperature moves away from it: temp_profile=ramp or sine)"),
        _CHANNEL,
        _RANDOM,
    )
    fit = (
        FitParam("coeff", "channel", "counts/degC", "offset temperature coefficient"),
        FitParam("t_ref", "scalar", "degC", "reference temperature", free=False),
    )

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        c = _per_channel(spec["coeff"], 0.002 * ctx.g_counts(), m, rng if spec["random"] else None, self.name, "coeff")
        return {"coeff": c, "t_ref": float(spec["t_ref"])}

    def identity(self, ctx):
        return {"coeff": np.zeros(ctx.n_channels), "t_ref": 25.0}

    def modify_state(self, state, p, ctx):
        T = _temp(ctx, self.name)
        add = (T - float(p["t_ref"]))[:, None] * np.asarray(p["coeff"], float)[None, :]
        return state.replace(bias=add if state.bias is None else state.bias + add)


class _TemperatureGain(Effect):
    name = "temperature_gain"
    summary = "the magnitude of s_i changes linearly with temperature"
    doc = "gain_i(t) *= 1 + coeff_i (T(t) - t_ref) (coeff: fraction per degC)."
    stage = "state"
    linear = True
    params = (
        Param("coeff", 3e-4, "1/degC", "gain tempco (fraction per degC)", "floats"),
        Param("t_ref", 25.0, "degC", "temperature at which the gain is the calibrated one (the effect shows "
              "only when the motion's temperature moves away from it: temp_profile=ramp or sine)"),
        _CHANNEL,
        _RANDOM,
    )
    fit = (
        FitParam("coeff", "channel", "1/degC", "gain temperature coefficient"),
        FitParam("t_ref", "scalar", "degC", "reference temperature", free=False),
    )

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        c = _per_channel(spec["coeff"], 0.0, m, rng if spec["random"] else None, self.name, "coeff")
        return {"coeff": c, "t_ref": float(spec["t_ref"])}

    def identity(self, ctx):
        return {"coeff": np.zeros(ctx.n_channels), "t_ref": 25.0}

    def modify_state(self, state, p, ctx):
        T = _temp(ctx, self.name)
        fac = 1.0 + (T - float(p["t_ref"]))[:, None] * np.asarray(p["coeff"], float)[None, :]
        return state.replace(gain=fac if state.gain is None else state.gain * fac)


def random_walk(t: np.ndarray, sigma: np.ndarray, seed: int) -> np.ndarray:
    """(n, N) Brownian paths W_i(t), W_i(t_0) = 0, Var W_i(t) = sigma_i^2 (t - t_0),
    from a fixed seed (the same seed and times give the same path)."""
    t = np.asarray(t, float)
    sigma = np.asarray(sigma, float)
    g = np.random.default_rng(int(seed))
    z = g.standard_normal((t.shape[0], sigma.shape[0]))
    z[0] = 0.0
    dt = np.diff(t, prepend=t[0])
    return np.cumsum(z * np.sqrt(dt)[:, None], axis=0) * sigma[None, :]


class _BiasDrift(Effect):
    name = "bias_drift"
    summary = "b_i changes with time (ramp or random walk)"
    doc = ("bias_i(t) += rate_i (t - t0) + rw_i W(t) + path_i(t): a ramp (counts/s) plus a random walk of "
           "rw_i counts per sqrt(s) (W standard Brownian, from a fixed seed; W(t0) = 0); t0 is the first "
           "sample time.  path_i (fitted only): the piecewise-linear bias path through the knots path_t, "
           "held at its end values outside them (a random walk the diagnosis has estimated).")
    stage = "state"
    linear = True  # in rate and rw for a fixed path
    params = (
        Param("rate", None, "counts/s", "ramp; auto = 0.01 % of g per s in counts", "floats"),
        Param("rw", 0.0, "counts/sqrt(s)", "random-walk intensity", "floats", minimum=0.0),
        _CHANNEL,
        _RANDOM,
    )
    fit = (
        FitParam("rate", "channel", "counts/s", "ramp rate"),
        FitParam("rw", "channel", "counts/sqrt(s)", "random-walk intensity (path from seed)"),
        FitParam("seed", "scalar", "-", "seed of the random-walk path", free=False),
        FitParam("t0", "scalar", "s", "start of the ramp", free=False),
        FitParam("path_t", "knot", "s", "knot times of the bias path (empty: none)", free=False),
        FitParam("path", "channel_knot", "counts", "bias path at the knots (N, knots)"),
    )

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        rnd = rng if spec["random"] else None
        rate = _per_channel(spec["rate"], 1e-4 * ctx.g_counts(), m, rnd, self.name, "rate")
        rw = np.abs(_per_channel(spec["rw"], 0.0, m, None, self.name, "rw"))
        return {"rate": rate, "rw": rw, "seed": int(rng.integers(0, 2**31 - 1)), "t0": _t0(ctx)}

    def identity(self, ctx):
        N = ctx.n_channels
        return {"rate": np.zeros(N), "rw": np.zeros(N), "seed": 0, "t0": _t0(ctx), "path_t": np.zeros(0),
                "path": np.zeros((N, 0))}

    def modify_state(self, state, p, ctx):
        t = np.asarray(ctx.truth.t, float)
        add = (t - float(p["t0"]))[:, None] * np.asarray(p["rate"], float)[None, :]
        rw = np.asarray(p["rw"], float)
        if np.any(rw):
            add = add + random_walk(t, rw, int(p["seed"]))
        knots = np.asarray(p.get("path_t", ()), float).ravel()
        if knots.size:
            path = np.asarray(p["path"], float).reshape(-1, knots.size)
            add = add + np.stack([np.interp(t, knots, v) for v in path], axis=1)
        return state.replace(bias=add if state.bias is None else state.bias + add)


# -- signal effects --------------------------------------------------------------


class _Nonlinearity(Effect):
    name = "nonlinearity"
    summary = "the reading gains a term in the square of the channel's input"
    doc = ("counts_i += k2_i x_i^2, x_i = (counts_i - b_i - bias_i) / |s_i| the channel's input in m/s^2 "
           "(k2: counts per (m/s^2)^2).  Applied before bandwidth.")
    stage = "signal"
    linear = True
    params = (
        Param("k2", None, "counts/(m/s^2)^2", "quadratic coefficient; auto = 0.5 % of the reading at 1 g", "floats"),
        _CHANNEL,
        _RANDOM,
    )
    fit = (FitParam("k2", "channel", "counts/(m/s^2)^2", "quadratic coefficient"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        g = float(ctx.device.gravity_mps2)
        k = np.linalg.norm(ctx.state.sensitivity, axis=1)
        k2 = _per_channel(spec["k2"], 0.005 * k / g, m, rng if spec["random"] else None, self.name, "k2")
        return {"k2": k2}

    def identity(self, ctx):
        return {"k2": np.zeros(ctx.n_channels)}

    def apply_signal(self, counts, p, ctx):
        k = np.linalg.norm(ctx.state.sensitivity, axis=1)
        x = (counts - ctx.state.total_offset()) / k
        return counts + np.asarray(p["k2"], float) * x * x


class _Bandwidth(Effect):
    name = "bandwidth"
    summary = "the channel responds through a first-order low-pass of cut-off f_c"
    doc = ("y' = 2 pi fc (x - y) on the noise-free readings, exact ramp-invariant discretisation at "
           "the sample times, starting in steady state (fc = inf: no filter).")
    stage = "signal"
    linear = False
    params = (
        Param("fc_hz", 5.0, "Hz", "cut-off frequency", "floats", minimum=0.0, exclusive_min=True),
        _CHANNEL,
    )
    fit = (FitParam("fc_hz", "channel", "Hz", "cut-off frequency (inf = none)"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        return {"fc_hz": _per_channel(spec["fc_hz"], 5.0, m, None, self.name, "fc_hz", off_value=math.inf)}

    def identity(self, ctx):
        return {"fc_hz": np.full(ctx.n_channels, math.inf)}

    def apply_signal(self, counts, p, ctx):
        return lowpass_first_order(np.asarray(ctx.truth.t, float), counts, np.asarray(p["fc_hz"], float))


# -- ADC effects ---------------------------------------------------------------------


class _Saturation(Effect):
    name = "saturation"
    summary = "readings clip at limits inside [raw_min, raw_max]"
    doc = ("counts_i -> clip(counts_i, lo_i, hi_i) (counts).  By default the limits are the "
           "channel's offset -+ limit_g g in counts; lo/hi give them directly.")
    stage = "adc"
    linear = False
    params = (
        Param("limit_g", 1.5, "g", "symmetric limit around each channel's offset", "floats", minimum=0.0,
              exclusive_min=True),
        Param("lo", None, "counts", "lower clip level (overrides limit_g)", "floats"),
        Param("hi", None, "counts", "upper clip level (overrides limit_g)", "floats"),
        _CHANNEL,
    )
    fit = (
        FitParam("lo", "channel", "counts", "lower clip level (-inf = none)"),
        FitParam("hi", "channel", "counts", "upper clip level (+inf = none)"),
    )

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        lim = _per_channel(spec["limit_g"], 1.5, m, None, self.name, "limit_g", off_value=0.0)
        half = lim * ctx.g_counts()
        lo = ctx.state.offsets - half if spec["lo"] is None else _per_channel(spec["lo"], 0.0, m, None, self.name, "lo")
        hi = ctx.state.offsets + half if spec["hi"] is None else _per_channel(spec["hi"], 0.0, m, None, self.name, "hi")
        lo = np.where(m, lo, -math.inf)
        hi = np.where(m, hi, math.inf)
        dev = ctx.device
        for i in np.flatnonzero(m):
            if not lo[i] < hi[i]:
                raise AccelcalError(f"{_owner(self.name)}: channel {i}: expected lo < hi, got lo={lo[i]:g}, hi={hi[i]:g}")
        lo = np.where(m, np.maximum(lo, dev.raw_min), lo)
        hi = np.where(m, np.minimum(hi, dev.raw_max), hi)
        return {"lo": lo, "hi": hi}

    def identity(self, ctx):
        N = ctx.n_channels
        return {"lo": np.full(N, -math.inf), "hi": np.full(N, math.inf)}

    def apply_signal(self, counts, p, ctx):
        return np.clip(counts, np.asarray(p["lo"], float), np.asarray(p["hi"], float))


_ERFC = np.frompyfunc(math.erfc, 1, 1)


def _normal_tail(z: np.ndarray) -> np.ndarray:
    """P(N(0, 1) > z), elementwise."""
    return 0.5 * _ERFC(np.asarray(z, float) / math.sqrt(2.0)).astype(float)


class _Quantization(Effect):
    name = "quantization"
    summary = "readings are quantised in steps coarser than one count"
    doc = ("counts_i -> step_i round(counts_i / step_i) (step in counts, >= 1), instead of rounding to 1 "
           "count; step 0 (unselected channels, identity) leaves the channel alone.")
    stage = "adc"
    linear = False
    params = (
        Param("step", 8.0, "counts", "quantisation step", "floats", minimum=1.0),
        _CHANNEL,
    )
    fit = (FitParam("step", "channel", "counts", "quantisation step (0 = none, 1 = plain rounding)"),)

    def _resolve(self, spec, ctx, rng):
        m = _mask(spec, ctx, self.name)
        return {"step": _per_channel(spec["step"], 8.0, m, None, self.name, "step", off_value=0.0)}

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
                up = _normal_tail((k0 + 0.5 - u) / r)
                down = _normal_tail((u - k0 + 0.5) / r)
                out[:, i] = q * (k0 - u + up - down)
                continue
            k = np.arange(1, int(math.ceil(0.84 / r)) + 1)  # exp(-2 pi^2 k^2 r^2) < 1e-6 beyond
            coef = (-1.0) ** k / (math.pi * k) * np.exp(-2.0 * math.pi ** 2 * k ** 2 * r * r)
            out[:, i] = q * (np.sin(2.0 * math.pi * np.outer(u, k)) @ coef)
        return out


# -- reference effect -------------------------------------------------------------------


class _PoseError(Effect):
    name = "pose_error"
    summary = "the stated reference orientation of static poses is off by a small rotation"
    doc = ("For each static pose label p, f_true = Exp(rot_p) f_stated (rot_p in rad, body axes): "
           "the simulator writes f_stated = Exp(rot_p)^T f_true in the reference f columns of the "
           "pose's samples and leaves the readings alone; by default rot_p tilts the pose's gravity "
           "direction by angle_deg in a random direction.  apply() (the diagnosis) predicts the "
           "readings from the recorded reference rotated back, Exp(rot_p) f_recorded.")
    stage = "reference"
    linear = False
    params = (
        Param("angle_deg", 1.0, "deg", "tilt of each static pose's stated orientation", "float", minimum=0.0),
    )
    fit = (
        FitParam("labels", "pose", "-", "pose labels the rotations belong to", free=False),
        FitParam("rot", "pose3", "rad", "rotation from the stated to the true orientation"),
    )

    def _resolve(self, spec, ctx, rng):
        pose = np.asarray(ctx.truth.pose)
        labels = np.unique(pose[pose >= 0])
        f = np.asarray(ctx.truth.f, float)
        rot = np.zeros((labels.size, 3))
        ang = math.radians(spec["angle_deg"])
        for j, lab in enumerate(labels):
            fm = f[pose == lab].mean(axis=0)
            if np.linalg.norm(fm) > 1e-9:
                ax = _random_perpendicular(_unit_rows(fm[None, :]), rng)[0]
            else:
                ax = _unit_rows(rng.standard_normal((1, 3)))[0]
            rot[j] = ax * ang
        return {"labels": labels.astype(np.int64), "rot": rot}

    def identity(self, ctx):
        pose = np.asarray(ctx.truth.pose)
        labels = np.unique(pose[pose >= 0])
        return {"labels": labels.astype(np.int64), "rot": np.zeros((labels.size, 3))}

    def _rotate(self, f: np.ndarray, p: Mapping[str, Any], ctx: Context, inverse: bool) -> np.ndarray:
        pose = np.asarray(ctx.truth.pose)
        out = np.array(f, float, copy=True)
        labels = np.asarray(p["labels"]).astype(np.int64)
        R = rotation_matrix(np.asarray(p["rot"], float).reshape(-1, 3))
        for j, lab in enumerate(labels.tolist()):
            sel = pose == lab
            if np.any(sel):
                # rows: f_true_row = f_stated_row @ R^T; f_stated_row = f_true_row @ R
                out[sel] = out[sel] @ (R[j] if inverse else R[j].T)
        return out

    def apply_reference(self, f_ref, p, ctx):
        return self._rotate(f_ref, p, ctx, inverse=True)

    def apply(self, ctx, p):
        f_corr = self._rotate(np.asarray(ctx.truth.f, float), p, ctx, inverse=False)
        return evaluate(ctx.truth, ctx.state, f=f_corr)


# ==========================================================================
# Registry
# ==========================================================================

_ALL: tuple[Effect, ...] = (
    _Offset(),
    _Gain(),
    _Misalignment(),
    _PositionError(),
    _Centripetal(),
    _TimeSkew(),
    _Bandwidth(),
    _Nonlinearity(),
    _TemperatureOffset(),
    _TemperatureGain(),
    _BiasDrift(),
    _Saturation(),
    _Quantization(),
    _PoseError(),
)

#: name -> Effect, in the contract's table order.
EFFECTS: dict[str, Effect] = {e.name: e for e in _ALL}
#: The contract's effect names (without the verdict ``none``).
EFFECT_NAMES: tuple[str, ...] = tuple(EFFECTS)

#: Order in which the simulator applies effects within and across stages.
PIPELINE_ORDER: tuple[str, ...] = (
    "offset", "gain", "misalignment", "position_error", "centripetal", "time_skew",
    "temperature_offset", "temperature_gain", "bias_drift",  # state
    "nonlinearity", "bandwidth",  # signal
    "quantization", "saturation",  # adc (after noise)
    "pose_error",  # reference
)


@dataclass(frozen=True, eq=False)
class EffectSpec:
    """A parsed effect request: the Effect and its checked spec parameters
    (only those given; defaults are filled by ``resolve``)."""

    effect: Effect
    params: dict[str, Any] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.effect.name

    def resolve(self, ctx: Context, rng: np.random.Generator | None = None) -> dict[str, Any]:
        return self.effect.resolve(self.params, ctx, rng)

    def __str__(self) -> str:
        return format_spec(self.effect.name, self.params)


def get_effect(name: str) -> Effect:
    """The registry entry for ``name``; AccelcalError listing the names otherwise."""
    if isinstance(name, Effect):
        return name
    key = str(name).strip()
    if key in EFFECTS:
        return EFFECTS[key]
    if key == "none":
        raise AccelcalError("effect 'none' is a diagnosis verdict, not an effect to simulate")
    close = difflib.get_close_matches(key, EFFECT_NAMES, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise AccelcalError(f"unknown effect {key!r}{hint}; effects: {', '.join(EFFECT_NAMES)}")


def parse_effect_spec(spec: Any) -> EffectSpec:
    """``"gain:scale=0.01,channel=2"`` -> EffectSpec; also accepts an EffectSpec,
    an Effect, or a (name, {params}) pair.  Raises AccelcalError."""
    if isinstance(spec, EffectSpec):
        return spec
    if isinstance(spec, Effect):
        return EffectSpec(spec, {})
    if isinstance(spec, tuple) and len(spec) == 2 and isinstance(spec[1], Mapping):
        eff = get_effect(spec[0])
        return EffectSpec(eff, eff.check(dict(spec[1])))
    name, raw = parse_spec(spec, "effect")
    eff = get_effect(name)
    return EffectSpec(eff, eff.check(raw))


def parse_effect_specs(specs: Iterable[Any]) -> list[EffectSpec]:
    """Parse several; an effect named twice is an error (combine the parameters instead)."""
    if isinstance(specs, (str, EffectSpec, Effect)):
        specs = [specs]
    out = [parse_effect_spec(s) for s in specs]
    seen = set()
    for s in out:
        if s.name in seen:
            raise AccelcalError(f"effect {s.name!r} is given more than once (give it once, with all its parameters)")
        seen.add(s.name)
    return out


def describe_effects() -> str:
    """Help text: every effect with its parameters, defaults and units."""
    return "\n".join(EFFECTS[n].help() for n in EFFECT_NAMES)


def params_to_json(p: Mapping[str, Any]) -> str:
    """Concrete parameters as one line of JSON (arrays as lists, inf as strings)."""

    def conv(v: Any) -> Any:
        if isinstance(v, np.ndarray):
            return conv(v.tolist())
        if isinstance(v, (list, tuple)):
            return [conv(x) for x in v]
        if isinstance(v, (np.floating, float)):
            x = float(v)
            return x if math.isfinite(x) else ("inf" if x > 0 else "-inf" if x < 0 else "nan")
        if isinstance(v, np.integer):
            return int(v)
        return v

    return json.dumps({k: conv(v) for k, v in p.items()}, separators=(",", ":"))


def effect_rng(seed: int, name: str) -> np.random.Generator:
    """The random stream of one effect in a simulation: depends only on the
    seed and the effect's name, so adding another effect changes nothing here."""
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, 0xEFFEC7, zlib.crc32(name.encode())])
