"""The effects: every unmodelled effect of the data contract, one class each.

One :class:`~accelcal.effects.base.Effect` object per contract name (``EFFECTS``, in
the contract's order) is the one home of the effect: its parameters (names,
defaults, units, docs), how it changes a channel's reading (the simulator), how it
is fitted to a residual (the diagnosis: ``skip``, ``cv``, with the fitting toolkit of
:mod:`.fitting` on the data of :mod:`.fitdata`), how its parameters read in the
report (``describe``) and how the benchmark sizes it and scores its estimate
(``bench_spec``, ``param_error``).  Adding an effect is adding one class (in a module
of its family: ``channel``, ``geometry``, ``timing``, ``nonlinearity``, ``temperature``,
``session``, ``drift``, ``adc``, ``pose``) to ``ALL_EFFECTS`` below, and its tests.

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
   time_skew, temperature_offset, temperature_gain, session_offset, session_gain, bias_drift: they change the
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

import math
import difflib
import json
import zlib
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping

import numpy as np

from ..errors import AccelcalError
from ..sensor import Context
from ..spec import format_spec, parse_spec
from .adc import Quantization, Saturation
from .base import STAGES, Effect, FitParam
from .channel import Gain, Misalignment, Offset
from .drift import BiasDrift, random_walk
from .geometry import Centripetal, PositionError
from .nonlinearity import Nonlinearity
from .pose import PoseError
from .session import SessionGain, SessionOffset
from .temperature import TemperatureGain, TemperatureOffset
from .timing import Bandwidth, TimeSkew


ALL_EFFECTS: tuple[Effect, ...] = (
    Offset(),
    Gain(),
    Misalignment(),
    PositionError(),
    Centripetal(),
    TimeSkew(),
    Bandwidth(),
    Nonlinearity(),
    TemperatureOffset(),
    TemperatureGain(),
    BiasDrift(),
    Saturation(),
    Quantization(),
    PoseError(),
    SessionOffset(),   # project extensions beyond the contract's table (docs/data-contract.md)
    SessionGain(),
)


#: name -> Effect, in the contract's table order.
EFFECTS: dict[str, Effect] = {e.name: e for e in ALL_EFFECTS}


#: The contract's effect names (without the verdict ``none``).
EFFECT_NAMES: tuple[str, ...] = tuple(EFFECTS)


#: Order in which the simulator applies effects within and across stages.
PIPELINE_ORDER: tuple[str, ...] = (
    "offset", "gain", "misalignment", "position_error", "centripetal", "time_skew",
    "temperature_offset", "temperature_gain", "session_offset", "session_gain", "bias_drift",  # state
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


__all__ = ["Effect", "FitParam", "EffectSpec", "EFFECTS", "EFFECT_NAMES", "PIPELINE_ORDER", "STAGES", "ALL_EFFECTS",
           "get_effect", "parse_effect_spec", "parse_effect_specs", "describe_effects", "params_to_json",
           "effect_rng", "random_walk"]
