"""The Effect base class (simulation, fit, report and benchmark hooks) and the helpers
its subclasses share to resolve a user's spec into per-channel parameters."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ..errors import AccelcalError
from ..sensor import ChannelState, Context, evaluate
from ..spec import Param, check_params, with_defaults


STAGES = ("state", "signal", "adc", "reference")


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


CHANNEL_PARAM = Param("channel", "all", "-", "channels that get the effect: all, an index or a list", "channels")


RANDOM_PARAM = Param("random", False, "-", "1: each selected channel draws value x N(0, 1) instead of the value", "bool")


def owner(name: str) -> str:
    return f"effect {name!r}"


class Effect:
    """One contract effect.  Subclasses set the class attributes and implement
    the stage's hook (``modify_state`` / ``apply_signal`` / ``apply_reference``)
    plus ``_resolve`` and ``identity``."""

    name: str = ""
    summary: str = ""  # the contract's line
    doc: str = ""  # parameterisation, units, how it is applied
    stage: str = "state"
    params: tuple[Param, ...] = ()
    fit: tuple[FitParam, ...] = ()
    #: True when the reading's change follows time (drift, temperature), not the pose or the motion:
    #: the diagnosis does not claim it from data that cannot tell it from a pose-dependent effect
    time_dependent: bool = False
    #: the recorded column a time-dependent effect follows (temperature: ``temp_c``), None for one
    #: that follows time alone (drift): where the two describe the same change, the one tied to a
    #: measurement is the more specific explanation
    covariate: str | None = None
    #: True when, in static poses, the effect's change is fixed within a pose but differs from pose to
    #: pose (gain, misalignment, nonlinearity, a tilt of the jig): such an effect and a time-dependent one
    #: explain the same on poses each held once
    varies_by_pose: bool = False
    #: the pose or motion that shows this effect distinctly (the diagnosis's ``separate_by``)
    tell_apart: str = ""
    #: the effects ``tell_apart`` tells this one from (empty: any); for a pair the diagnosis cannot
    #: separate, only the hints that speak to that pair are given (a gain's "each axis up and
    #: down" tells it from an offset, not from a bend, which six face poses already hold)
    tells_from: tuple[str, ...] = ()
    #: effects whose constant change this one's level at the recording also makes, since the
    #: calibration was made at another time (a drift since then reads as an offset): a verdict
    #: among them with this effect also in the model is reported ambiguous with it
    reaches_level_of: tuple[str, ...] = ()
    #: True when the effect has parameters of its own for each static pose (a tilt of each pose):
    #: on few poses that freedom takes parts of the sensor's constant errors (offsets on the other
    #: channels, a misalignment), so where the calibration's terms together shrink the gap as far
    #: (within the diagnosis's OCCAM_SHRINK) with fewer parameters, they are the first step and what
    #: this effect adds beyond them is tested after them (:meth:`mimics_calibration` must say so)
    free_per_pose: bool = False

    def takes_pose_levels(self, fit) -> bool:
        """Whether a time-dependent fit ``fit`` (a Cand) has the freedom to take a level of its
        own at each of the poses visited in turn (a drift's path through many knots), so that
        a pattern fixed per pose can pass for it even where the data could tell time from
        pose.  False for the fixed shapes (a ramp, a temperature through its lag)."""
        return False

    def alike(self, D, fit) -> tuple[str, ...]:
        """Effects that this one's fit ``fit`` (a Cand) on the data ``D`` cannot be told from,
        although their held-out gains differ (its parameters have the other's signature: every
        channel late by the same time is a skew and a low-pass's delay): a verdict with such a
        fit is reported ambiguous with them."""
        return ()

    def mimics_calibration(self, fit) -> bool:
        """Whether this effect's fit ``fit`` (a Cand) can take parts of several calibration terms at
        once (a cube of the input: part of a gain, of an offset and of a drift): it is then named
        only when significant after the significant calibration candidates (offset, gain, misalignment)
        together."""
        return False

    def looks_like(self, D) -> tuple[str, ...]:
        """Effects that this one cannot be told from on the data ``D`` although the held-out
        test does not show it (on poses along the axes alone a cube is a gain, and a tilt of
        each pose a misalignment): a verdict named here is reported ambiguous with this effect."""
        return ()

    # -- user-facing ------------------------------------------------------

    def check(self, given: Mapping[str, Any]) -> dict[str, Any]:
        """Coerce user parameters (strings or values); unknown names raise AccelcalError."""
        return check_params(self.params, given, owner(self.name))

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

    # -- a calibration parameter (the diagnosis's re-linearisation) -------------

    #: True when the effect is a change of the calibration's own parameters (offsets, sensitivity):
    #: the diagnosis then folds its fit into the calibration and fits again (re-linearisation)
    absorbs: bool = False

    #: True when, with a reference f, the fit's change of the readings is exactly the change the
    #: absorbed parameters make (an offset; a gain, which scales s.f): folding it into the
    #: calibration and fitting again changes nothing there, and the diagnosis skips it
    exact_with_reference: bool = False

    def absorb(self, cal, p: Mapping[str, Any]):
        """The calibration ``cal`` with this effect's fitted parameters ``p`` built in."""
        raise NotImplementedError(f"{self.name} is not a calibration parameter")

    def params_between(self, cal0, cal1) -> dict[str, Any]:
        """The parameters of this effect that take calibration ``cal0`` to ``cal1`` (in what
        this effect changes; the rest of the calibration is ignored)."""
        raise NotImplementedError(f"{self.name} is not a calibration parameter")

    # -- the benchmark (tools/bench_diagnose.py) ---------------------------------

    #: size the benchmark's pilot simulation scales from (None: drawn directly)
    bench_size: float | None = None

    def bench_spec(self, m: float, z: np.ndarray, aux: Mapping[str, Any]) -> dict[str, Any]:
        """Spec parameters of size ``m`` with per-channel standard normal draws ``z``."""
        raise NotImplementedError(f"{self.name}: the benchmark draws it directly")

    #: the fitted parameter the default bench_pair compares (None: the effect defines its own)
    bench_key: str | None = None

    def bench_pair(self, est: Mapping[str, Any], truth: Mapping[str, Any],
                   sig: Mapping[str, Any] | None) -> Any:
        """(estimate, truth) arrays the relative error compares, a ready error (float), or None.
        By default ``bench_key``'s values over the entries the data determine."""
        if self.bench_key is None:
            return None
        k = self.bench_key
        e, t = as_float_array(est[k]), np.asarray(truth[k], float)
        return determined(e, t, sig[k]) if sig is not None and k in sig else (e, t)

    def param_error(self, est: Mapping[str, Any], truth: Mapping[str, Any],
                    sig: Mapping[str, Any] | None = None) -> float | None:
        """How far the fitted parameters are from the truth: |est - true| / |true| over the
        entries the data determine (an effect may define its own measure); None when it
        cannot be told."""
        try:
            pair = self.bench_pair(est, truth, sig)
        except (KeyError, ValueError, TypeError):
            return None
        if pair is None or isinstance(pair, float):
            return pair
        e, t = pair
        nt = float(np.linalg.norm(t))
        return None if nt == 0 else float(np.linalg.norm(e - t) / nt)

    def __repr__(self) -> str:
        return f"<Effect {self.name} ({self.stage})>"


def channel_mask(spec: Mapping[str, Any], ctx: Context, name: str) -> np.ndarray:
    N = ctx.n_channels
    sel = spec.get("channel")
    m = np.zeros(N, bool)
    if sel is None:
        m[:] = True
        return m
    bad = [c for c in sel if c >= N]
    if bad:
        raise AccelcalError(
            f"{owner(name)} parameter 'channel': channel {bad[0]} is out of range "
            f"(the device has {N} channels: 0..{N - 1})"
        )
    m[list(sel)] = True
    return m


def per_channel(value: Any, default: np.ndarray, mask: np.ndarray, rng: np.random.Generator | None,
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
                f"{owner(name)} parameter {pname!r}: expected 1 value or {N} (one per channel)"
                + (f" or {k} (one per selected channel)" if k != N else "")
                + f", got {arr.size}"
            )
    if rng is not None:
        v = v * rng.standard_normal(N)
    return np.where(mask, v, off_value)


def random_perpendicular(u: np.ndarray, rng: np.random.Generator) -> np.ndarray:
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


def unit_rows(a: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(a, axis=1, keepdims=True)
    return a / np.where(n > 0, n, 1.0)


def start_time(ctx: Context) -> float:
    return float(np.asarray(ctx.truth.t, float)[0])


def temperature_of(ctx: Context, name: str) -> np.ndarray:
    T = getattr(ctx.truth, "temp_c", None)
    T = None if T is None else np.asarray(T, float)
    if T is None or not np.all(np.isfinite(T)):
        raise AccelcalError(f"{owner(name)} needs the temperature at every sample (temp_c)")
    return T


def strongest(v: np.ndarray) -> int:
    """Index of the largest finite |v| (the channel a report line names)."""
    v = np.asarray(v, float)
    a = np.where(np.isfinite(v), np.abs(v), -1.0)
    return int(np.argmax(a))


def as_float_array(v: Any) -> np.ndarray:
    """A JSON value (lists with "inf", "-inf" and null) as a float array of the same shape."""
    a = np.asarray([np.inf if x == "inf" else (-np.inf if x == "-inf" else (np.nan if x is None else x))
                    for x in np.asarray(v, dtype=object).ravel()], float)
    return a.reshape(np.shape(v)) if np.ndim(v) else a


def as_list(v: Any) -> list[float]:
    """Floats for a spec parameter."""
    return [float(x) for x in np.asarray(v, float)]


def determined(e: np.ndarray, t: np.ndarray, sd: Any) -> tuple[np.ndarray, np.ndarray]:
    """The entries the data determine: 1-sigma below a tenth of the truth's RMS (a channel that
    barely sees the effect has a wide, uninformative estimate)."""
    sd = as_float_array(sd)
    if sd.shape != e.shape:
        return e, t
    ok = np.isfinite(sd) & (sd <= 0.1 * float(np.sqrt(np.mean(t ** 2))))
    if e.ndim == 2:
        ok = np.all(ok, axis=1)
    return e[ok], t[ok]
