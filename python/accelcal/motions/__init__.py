"""Motion profiles: exact rigid-body kinematics for the simulator.

Every motion is a function ``(device, rng, **params) -> Trajectory`` registered
in ``MOTIONS`` with its parameters (names, defaults, units, docs).  Each is
built from an analytic *evaluator* (times -> attitude, position, f, omega,
alpha), so the sampled arrays are exactly consistent with each other and the
same evaluator gives the motion at shifted times (``time_skew``).

Conventions (docs/data-contract.md)
-------------------------------------------
* World frame: z up; gravity ``g_vec = (0, 0, -g)`` with ``g`` the device's
  ``gravity_mps2``.
* ``attitude`` C (n, 3, 3) rotates body to world: ``v_world = C v_body``;
  ``dC/dt = C [omega]x`` (omega in BODY axes); ``alpha = d omega / dt``.
* ``position`` (n, 3): world position of the body origin O (m), starting at 0.
* ``f`` (n, 3): specific force at O in BODY axes, ``f = C^T (a_O - g_vec)``;
  at rest ``f = C^T (0, 0, g)``, magnitude g, pointing up.
* ``pose`` (n,): label >= 0 while the body is in a static pose, -1 moving.
* ``temp_c`` (n,): degC, from the temperature profile (default constant 25).

All times in s, angles in the parameters in degrees, lengths in m unless the
name says otherwise (``_cm``, ``_mm``).

Modules: ``trajectory`` (kinematics, the Trajectory object, attitude helpers, evaluators),
``poses`` (pose direction sets), ``profiles`` (the motion generators), and the registry here.
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, Callable, Mapping

import numpy as np

from ..errors import AccelcalError
from ..spec import Param, check_params, parse_spec, with_defaults
from .profiles import (TEMP_PROFILES, handheld, lane_change, linear_actuator, pendulum, random_6dof, random_poses,
                       rate_table, static_poses, temperature_profile)
from .poses import POSE_SETS, pose_directions
from .trajectory import Kinematics, Trajectory


_TEMP_PARAMS = (
    Param("temp_profile", "constant", "-", "temperature profile: constant, ramp (temp_c -> temp_end_c over the "
          "recording) or sine (temp_c +- temp_amplitude_c, period temp_period_s)", "choice", choices=TEMP_PROFILES),
    Param("temp_c", 25.0, "degC", "constant / start / mean temperature"),
    Param("temp_end_c", 45.0, "degC", "ramp: temperature at the last sample"),
    Param("temp_amplitude_c", 5.0, "degC", "sine: amplitude"),
    Param("temp_period_s", 600.0, "s", "sine: period", minimum=0.0, exclusive_min=True),
)


@dataclass(frozen=True, eq=False)
class Motion:
    """A registered motion: ``motion(device, rng, **params) -> Trajectory``."""

    name: str
    summary: str
    params: tuple[Param, ...]
    build: Callable[..., tuple]

    @property
    def all_params(self) -> tuple[Param, ...]:
        return self.params + _TEMP_PARAMS

    def check(self, given: Mapping[str, Any]) -> dict[str, Any]:
        return check_params(self.all_params, given, f"motion {self.name!r}")

    def __call__(self, device: Any, rng: np.random.Generator | None = None, **params: Any) -> Trajectory:
        given = self.check(params)
        full = with_defaults(self.all_params, given)
        temp = {p.name: full.pop(p.name) for p in _TEMP_PARAMS}
        rng = np.random.default_rng(0) if rng is None else rng
        out = self.build(device, rng, **full)
        if len(out) == 2:
            times, ev = out
            labels = ev.labels(times)
        else:
            times, ev, labels = out
        if times.size < 2:
            raise AccelcalError(f"motion {self.name!r}: fewer than 2 samples at {device.sample_rate_hz:g} Hz; "
                                "make it longer")
        k = ev(times)
        T = temperature_profile(times, temp["temp_profile"], temp["temp_c"], temp["temp_end_c"],
                                temp["temp_amplitude_c"], temp["temp_period_s"])
        # (+ 0.0 turns -0.0 into 0.0, so the CSV shows no "-0")
        return Trajectory(t=times, attitude=k.attitude, f=k.f + 0.0, omega=k.omega + 0.0, alpha=k.alpha + 0.0,
                          pose=np.asarray(labels, np.int64), temp_c=T, position=k.position,
                          gravity_mps2=float(device.gravity_mps2), name=self.name, params=dict(given),
                          evaluator=ev)

    def help(self) -> str:
        lines = [f"{self.name}: {self.summary}"]
        lines += [f"    {p.help()}" for p in self.params]
        return "\n".join(lines)


_SPP = Param("samples_per_pose", 60, "samples", "samples recorded in each pose", "int", minimum=1)


_DWELL = Param("dwell_s", None, "s", "time from one pose's first sample to the next's (the jig moves, unrecorded, "
               "after the samples); auto = samples_per_pose / rate + 1 s", "float", minimum=0.0, exclusive_min=True)


_ALL = (
    Motion("static_poses", "jig poses, each held still (f = g d for the pose's up direction d)", (
        Param("poses", "6", "-", "preset 4 (seed eq. 19), 6, 18, 24, 26, or a list of up directions like "
              "[x,y,z,-z] or [[1,0,1],...]", "poses"),
        _SPP, _DWELL,
        Param("heading_deg", 0.0, "deg", "turn of every pose about the vertical"),
    ), static_poses),
    Motion("random_poses", "static poses in random orientations (uniform on the sphere, random heading)", (
        Param("n_poses", 24, "-", "number of poses", "int", minimum=1),
        _SPP, _DWELL,
    ), random_poses),
    Motion("handheld", "hand-held session: a rest, then random poses held still with smooth hand moves "
           "between (min-jerk rotation and translation), like imu_tk's Xsens recording", (
        Param("n_poses", 40, "-", "number of poses after the initial rest", "int", minimum=1),
        Param("hold_s", 4.0, "s", "time held still in each pose", minimum=0.0, exclusive_min=True),
        Param("move_s", 2.0, "s", "duration of each move", minimum=0.0, exclusive_min=True),
        Param("initial_rest_s", 20.0, "s", "initial static period (body z up)", minimum=0.0, exclusive_min=True),
        Param("move_cm", 5.0, "cm", "hand positions wander within a ball of this radius", minimum=0.0),
    ), handheld),
    Motion("rate_table", "sinusoidal rotation about a body axis: theta = A sin(2 pi f t)", (
        Param("axis", "z", "-", "body rotation axis", "direction"),
        Param("freq_hz", 2.0, "Hz", "frequency", minimum=0.0, exclusive_min=True),
        Param("amplitude_deg", 10.0, "deg", "angle amplitude A"),
        Param("duration_s", 10.0, "s", "duration of the oscillation", minimum=0.0, exclusive_min=True),
        Param("mount", None, "-", "body direction that points up (auto = axis: a vertical-axis table)", "direction"),
        Param("center_m", [0.0, 0.0, 0.0], "m", "a body point on the table axis (the body origin is off-axis "
              "when non-zero)", "vector"),
        Param("rest_s", 0.0, "s", "rest before the motion starts (pose label 0)", minimum=0.0),
        Param("ramp_s", 0.0, "s", "smooth (min-jerk) amplitude ramp-in time; 0 = start at full amplitude",
              minimum=0.0),
    ), rate_table),
    Motion("pendulum", "swing about body y with the pivot at the body origin: theta = center + A e^(-t/decay) "
           "cos(2 pi f t), gravity in body axes g (-sin theta, 0, cos theta)", (
        Param("amplitude_deg", 40.0, "deg", "swing amplitude A"),
        Param("freq_hz", 0.5, "Hz", "swing frequency", minimum=0.0, exclusive_min=True),
        Param("center_deg", 0.0, "deg", "mean attitude (0: body z up at the centre, the seed's case; 90: body x "
              "points down, a hanging arm)"),
        Param("duration_s", 20.0, "s", "duration", minimum=0.0, exclusive_min=True),
        Param("decay_s", 0.0, "s", "amplitude e-folding time (0 = undamped)", minimum=0.0),
    ), pendulum),
    Motion("linear_actuator", "stop-to-stop travel along a body axis: rest, smooth travel, rest "
           "(strokes alternate direction)", (
        Param("axis", "x", "-", "body axis of travel", "direction"),
        Param("distance_m", 0.2, "m", "travel of one stroke"),
        Param("travel_s", 1.0, "s", "duration of one stroke", minimum=0.0, exclusive_min=True),
        Param("rest_s", 2.0, "s", "rest before, between and after strokes (pose labels 0, 1, ...)",
              minimum=0.0, exclusive_min=True),
        Param("strokes", 1, "-", "number of strokes (back and forth)", "int", minimum=1),
        Param("tilt_deg", 0.0, "deg", "rail tilt: the body is turned by this about tilt_axis"),
        Param("tilt_axis", "y", "-", "body axis of the tilt", "direction"),
        Param("profile", "minjerk", "-", "travel profile: minjerk (quintic) or cycloid (sine acceleration)",
              "choice", choices=("minjerk", "cycloid")),
    ), linear_actuator),
    Motion("lane_change", "vehicle double lane change (ISO 3888-1-like course) at constant forward speed; "
           "body x forward, z up", (
        Param("speed_mps", 16.667, "m/s", "forward speed (60 km/h)", minimum=0.0, exclusive_min=True),
        Param("offset_m", 3.5, "m", "lateral offset of the second lane"),
        Param("lead_m", 15.0, "m", "straight before the change", minimum=0.0),
        Param("shift_m", 30.0, "m", "length of the change-over", minimum=0.0, exclusive_min=True),
        Param("hold_m", 25.0, "m", "length driven in the other lane", minimum=0.0),
        Param("return_m", 25.0, "m", "length of the return", minimum=0.0, exclusive_min=True),
        Param("exit_m", 30.0, "m", "straight after the return", minimum=0.0),
    ), lane_change),
    Motion("random_6dof", "band-limited random rotation (Euler angles as sums of tones) and translation "
           "(world acceleration as sums of tones), attitude exactly consistent", (
        Param("duration_s", 60.0, "s", "duration", minimum=0.0, exclusive_min=True),
        Param("bandwidth_hz", 1.0, "Hz", "highest tone frequency", minimum=0.0, exclusive_min=True),
        Param("angle_rms_deg", 30.0, "deg", "rms of each Euler angle", minimum=0.0),
        Param("accel_rms_mps2", 1.0, "m/s^2", "rms of each world acceleration component", minimum=0.0),
        Param("tones", 8, "-", "tones per signal", "int", minimum=1),
    ), random_6dof),
)


#: name -> Motion
MOTIONS: dict[str, Motion] = {m.name: m for m in _ALL}


MOTION_NAMES: tuple[str, ...] = tuple(MOTIONS)


def get_motion(name: str) -> Motion:
    if isinstance(name, Motion):
        return name
    key = str(name).strip()
    if key in MOTIONS:
        return MOTIONS[key]
    close = difflib.get_close_matches(key, MOTION_NAMES, n=1)
    hint = f" (did you mean {close[0]!r}?)" if close else ""
    raise AccelcalError(f"unknown motion {key!r}{hint}; motions: {', '.join(MOTION_NAMES)}")


def parse_motion_spec(spec: str) -> tuple[Motion, dict[str, Any]]:
    """``"rate_table:freq_hz=2,axis=x"`` -> (Motion, checked params)."""
    name, raw = parse_spec(spec, "motion")
    m = get_motion(name)
    return m, m.check(raw)


def describe_motions() -> str:
    """Help text: every motion with its parameters, plus the temperature parameters."""
    parts = [MOTIONS[n].help() for n in MOTION_NAMES]
    parts.append("every motion also takes:\n" + "\n".join(f"    {p.help()}" for p in _TEMP_PARAMS))
    return "\n".join(parts)


__all__ = [
    "Trajectory",
    "Kinematics",
    "Motion",
    "MOTIONS",
    "MOTION_NAMES",
    "POSE_SETS",
    "pose_directions",
    "get_motion",
    "parse_motion_spec",
    "describe_motions",
    "temperature_profile",
]
