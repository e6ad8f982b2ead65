"""Forward simulation: a device, a motion and effects -> a recording per the contract.

    rec = simulate(default_device(), "rate_table", effects=["gain:scale=0.01,channel=2"],
                   seed=1, freq_hz=2.0)

Pipeline (see ``effects`` for the stages):

1. truth: the motion's exact trajectory (``motions``);
2. true channel parameters: the given calibration (offsets, sensitivity,
   positions; its temperature coefficients too, when it has them) or the
   device's nominal ones; the centripetal term is always in the truth;
3. ``state`` effects change the channel state; the noise-free readings are
   evaluated exactly, ``b_i + s_i . f(r_i)`` at ``t + tau_i``;
4. ``signal`` effects (nonlinearity, bandwidth);
5. Gaussian noise, ``device.noise_mps2 * k_i`` counts rms per channel;
6. ``adc`` effects (quantization replaces rounding to 1 count; saturation),
   then rounding and clipping to [raw_min, raw_max]:
   ``raw = clip(round(x + noise))``;
7. reference columns f, w, dw, temp_c, pose written exactly from the truth;
   ``pose_error`` changes only the recorded f of static poses.

Reproducibility: the motion, each effect's random draws and the noise come
from separate streams derived from ``seed`` (an effect's stream from the seed
and its name), so the same seed gives the same recording, and adding an effect
leaves the motion, the noise and the other effects' draws unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable

import numpy as np

from . import __version__
from .effects import (
    PIPELINE_ORDER,
    EffectSpec,
    effect_rng,
    params_to_json,
    parse_effect_specs,
)
from .io.calibration import Calibration
from .errors import AccelcalError
from .sensor import ChannelState, Context, evaluate, true_state
from .spec import format_spec
from .motions import Motion, Trajectory, get_motion, parse_motion_spec
from .io.recording import Recording, recording_from_arrays

__all__ = ["simulate", "run_simulation", "Simulation", "true_state", "seed_prototype_truth", "SEED_TABLE1"]

#: The seed's Table 1 (ADXL202E maker's figures): gain error range (fraction),
#: absolute alignment error (fraction, each of two cross components), offset
#: error range (fraction of g).
SEED_TABLE1 = {"gain": (-0.0069, 0.0358), "alignment": 0.0175, "offset_g": (-0.283, 0.254)}


@dataclass(eq=False)
class Simulation:
    """Everything a simulation made: the recording and the truth behind it.

    ``clean_counts`` (n, N): noise-free, unrounded readings after the signal
    effects (before noise and ADC).  ``state`` is the true channel state after
    the state effects, ``base_state`` before them.  ``effects`` maps each
    effect name to its concrete parameters (see ``effects.Effect.fit``).
    ``unchanged``: the signal and ADC effects that changed no reading (a clip
    limit the motion never reaches), for a note.
    """

    recording: Recording
    trajectory: Trajectory
    base_state: ChannelState
    state: ChannelState
    clean_counts: np.ndarray
    effects: dict[str, dict[str, Any]] = field(default_factory=dict)
    context: Context | None = None
    unchanged: list[str] = field(default_factory=list)


def _rngs(seed: int) -> tuple[np.random.Generator, np.random.Generator]:
    ss = np.random.SeedSequence(int(seed) & 0xFFFFFFFFFFFFFFFF)
    motion_ss, noise_ss = ss.spawn(2)
    return np.random.default_rng(motion_ss), np.random.default_rng(noise_ss)


def _resolve_motion(motion: Any, motion_params: dict[str, Any]) -> tuple[Motion | None, dict[str, Any], Trajectory | None]:
    if isinstance(motion, Trajectory):
        if motion_params:
            raise AccelcalError("motion parameters were given with a ready-made trajectory")
        return None, {}, motion
    if isinstance(motion, Motion):
        return motion, motion.check(motion_params), None
    if isinstance(motion, str) and ":" in motion:
        m, given = parse_motion_spec(motion)
        extra = m.check(motion_params)
        dup = sorted(set(given) & set(extra))
        if dup:
            raise AccelcalError(f"motion parameter {dup[0]!r} is given twice (in the spec and separately)")
        given.update(extra)
        return m, given, None
    m = get_motion(motion)
    return m, m.check(motion_params), None


def run_simulation(device: Any, motion: Any, *, effects: Iterable[Any] = (), seed: int = 0,
                   calibration: Any = None, reference: bool = True, **motion_params: Any) -> Simulation:
    """Simulate and return the recording with its truth (see :class:`Simulation`).

    ``motion``: a registered name (``motions.MOTIONS``), a spec string
    ``"name:k=v,..."``, a :class:`~accelcal.motions.Motion`, or a ready
    :class:`~accelcal.motions.Trajectory`.  ``effects``: spec strings
    (``"gain:scale=0.01,channel=2"``), ``EffectSpec``s or ``(name, {params})``.
    ``reference`` False leaves out every reference column (a jig-free
    recording: t and raw only).
    """
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise AccelcalError(f"seed: expected an integer, got {seed!r}")
    specs: list[EffectSpec] = parse_effect_specs(effects)
    m, given, traj = _resolve_motion(motion, dict(motion_params))
    rng_motion, rng_noise = _rngs(int(seed))
    if traj is None:
        traj = m(device, rng_motion, **given)
    n, N = traj.n_samples, device.n_channels

    base = true_state(device, calibration, traj.temp_c)
    ctx = Context(device=device, truth=traj, state=base, counts=np.empty((0, N)))
    ordered = sorted(specs, key=lambda s: PIPELINE_ORDER.index(s.name))
    concrete: dict[str, dict[str, Any]] = {}
    for s in ordered:
        # resolve against the state so far (e.g. saturation limits around the true offsets)
        p = s.effect.resolve(s.params, ctx, effect_rng(int(seed), s.name))
        concrete[s.name] = p
        if s.effect.stage == "state":
            ctx = ctx.replace(state=s.effect.modify_state(ctx.state, p, ctx))
    counts = evaluate(traj, ctx.state)
    ctx = ctx.replace(counts=counts)
    unchanged = []
    for s in ordered:
        if s.effect.stage == "signal":
            before = ctx.counts
            ctx = ctx.replace(counts=s.effect.apply_signal(ctx.counts, concrete[s.name], ctx))
            if np.array_equal(before, ctx.counts):
                unchanged.append(s.name)
    clean = ctx.counts

    noise = device.noise_counts()
    x = clean + rng_noise.standard_normal((n, N)) * noise[None, :] if np.any(noise > 0) else clean.copy()
    for s in ordered:
        if s.effect.stage == "adc":
            before = x
            x = s.effect.apply_signal(x, concrete[s.name], ctx)
            if np.array_equal(before, x):
                unchanged.append(s.name)
    raw = np.clip(np.rint(x), device.raw_min, device.raw_max).astype(np.int64)

    f_ref = traj.f
    for s in ordered:
        if s.effect.stage == "reference":
            f_ref = s.effect.apply_reference(f_ref, concrete[s.name], ctx)

    meta = {
        "generator": f"accelcal.simulate {__version__}",
        "device": str(device.name),
        "motion": traj.spec() if m is None else format_spec(m.name, given),
        "effects": "; ".join(str(s) for s in specs) if specs else "none",
        "seed": str(int(seed)),
        "truth": "nominal" if calibration is None else f"calibration ({getattr(calibration, 'method', 'given')})",
    }
    for s in ordered:
        meta[f"effect.{s.name}"] = params_to_json(concrete[s.name])
    if reference:
        rec = recording_from_arrays(traj.t, raw, f=f_ref, w=traj.omega, dw=traj.alpha, temp_c=traj.temp_c,
                                    pose=traj.pose, metadata=meta)
    else:
        rec = recording_from_arrays(traj.t, raw, metadata=meta)
    return Simulation(recording=rec, trajectory=traj, base_state=base, state=ctx.state, clean_counts=clean,
                      effects=concrete, context=ctx, unchanged=unchanged)


def simulate(device: Any, motion: Any, *, effects: Iterable[Any] = (), seed: int = 0,
             calibration: Any = None, reference: bool = True, **motion_params: Any) -> Recording:
    """A simulated recording per the data contract (see :func:`run_simulation`).

    Metadata comments: ``generator``, ``device``, ``motion`` (the spec as
    given), ``effects`` (the specs as given), ``seed``, ``truth``, and
    ``effect.NAME`` with each effect's concrete parameters as JSON."""
    return run_simulation(device, motion, effects=effects, seed=seed, calibration=calibration,
                          reference=reference, **motion_params).recording


def seed_prototype_truth(device: Any, rng: np.random.Generator | int | None = None, *,
                         position_error_mm: float = 0.0) -> Any:
    """A random "true" calibration shaped like the seed's Table 1 (ADXL202E):
    gain error uniform in -0.69 ... +3.58 %, the sensitive axis tilted by two
    cross components each uniform in +-1.75 % (of |s|, i.e. ~ rad), offsets
    uniform in -28.3 ... +25.4 % of g (in counts) around the nominal zero,
    positions nominal (or off by up to ``position_error_mm`` per component,
    uniform; the paper's housings: 0.1 mm).  Returns a
    :class:`~accelcal.io.calibration.Calibration` (method ``truth``)."""
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    N = device.n_channels
    k = np.asarray(device.counts_per_mps2, float)
    u = np.asarray(device.axes, float)
    gain = rng.uniform(*SEED_TABLE1["gain"], N)
    # two unit vectors across each axis
    helper = np.where(np.abs(u[:, 0:1]) < 0.9, np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    e1 = np.cross(u, helper)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = np.cross(u, e1)
    a = SEED_TABLE1["alignment"]
    d = u + rng.uniform(-a, a, (N, 1)) * e1 + rng.uniform(-a, a, (N, 1)) * e2
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    sens = (k * (1.0 + gain))[:, None] * d
    off = np.asarray(device.zero_counts, float) + rng.uniform(*SEED_TABLE1["offset_g"], N) * device.gravity_mps2 * k
    off = np.clip(off, device.raw_min, device.raw_max)
    pos = np.array(device.positions, float)
    if position_error_mm > 0:
        pos = pos + rng.uniform(-1.0, 1.0, (N, 3)) * 1e-3 * position_error_mm
    return Calibration(device=device.name, method="truth", offsets=off, sensitivity=sens,
                       positions=pos if position_error_mm > 0 else None)
