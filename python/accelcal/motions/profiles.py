"""The motion generators: static and random poses, hand-held, rate table, pendulum, linear actuator, lane change, random 6-DOF; temperature profiles."""
from __future__ import annotations

import math

import numpy as np

from ..errors import AccelcalError
from ..sensor import rotation_matrix
from .poses import pose_directions, random_directions, static_segments, static_times
from .trajectory import (AxisRotation, EZ, Kinematics, Segments, random_tones, rot_z, rotvecs_between, sample_times,
                         sincos, smooth_profile, sum_of_tones, to_body, up_attitude, up_attitudes)


def static_poses(device, rng, *, poses, samples_per_pose, dwell_s, heading_deg):
    d, heads = pose_directions(poses)
    C = up_attitudes(d, heads + math.radians(heading_deg))
    t, period = static_times(C.shape[0], samples_per_pose, float(device.sample_rate_hz), dwell_s)
    return t, static_segments(C, period, device.gravity_mps2)


def random_poses(device, rng, *, n_poses, samples_per_pose, dwell_s):
    d = random_directions(rng, n_poses)
    C = up_attitudes(d, rng.uniform(0.0, 2.0 * math.pi, n_poses))
    t, period = static_times(n_poses, samples_per_pose, float(device.sample_rate_hz), dwell_s)
    return t, static_segments(C, period, device.gravity_mps2)


def handheld(device, rng, *, n_poses, hold_s, move_s, initial_rest_s, move_cm):
    g = device.gravity_mps2
    P = n_poses + 1  # pose 0 is the initial rest, body z up
    d = np.vstack([EZ, random_directions(rng, n_poses)])
    C = up_attitudes(d, rng.uniform(0.0, 2.0 * math.pi, P))
    # hand positions: random points in a ball of radius move_cm around the start
    r = 0.01 * move_cm
    pts = np.zeros((P, 3))
    if r > 0:
        v = random_directions(rng, n_poses)
        pts[1:] = v * (r * rng.uniform(0.0, 1.0, n_poses) ** (1.0 / 3.0))[:, None]
    rv = rotvecs_between(C[:-1], C[1:])  # move i: from pose i to pose i + 1
    ang = np.linalg.norm(rv, axis=1)
    ax = np.where(ang[:, None] > 0, rv / np.where(ang > 0, ang, 1.0)[:, None], EZ)
    # segments: hold 0, move 0, hold 1, move 1, ..., hold P-1
    S = 2 * P - 1
    dur = np.empty(S)
    dur[0::2] = hold_s
    dur[0] = initial_rest_s
    dur[1::2] = move_s
    t0 = np.concatenate([[0.0], np.cumsum(dur)[:-1]])
    Cs = np.repeat(C, 2, axis=0)[:S]
    axes = np.tile(EZ, (S, 1))
    axes[1::2] = ax
    angles = np.zeros(S)
    angles[1::2] = ang
    p0 = np.repeat(pts, 2, axis=0)[:S]
    dp = np.zeros((S, 3))
    dp[1::2] = pts[1:] - pts[:-1]
    labels = np.full(S, -1)
    labels[0::2] = np.arange(P)
    ev = Segments(t0, dur, Cs, axes, angles, p0, dp, labels, g)
    rate = float(device.sample_rate_hz)
    total = float(t0[-1] + dur[-1])
    times = sample_times(total, rate)
    return times, ev


def rate_table(device, rng, *, axis, freq_hz, amplitude_deg, duration_s, mount, center_m, rest_s, ramp_s):
    A = math.radians(amplitude_deg)
    w = 2.0 * math.pi * freq_hz
    M = up_attitude(axis if mount is None else mount)

    def theta(t):
        tt = t - rest_s
        on = tt > 0
        s, c = np.sin(w * tt), np.cos(w * tt)
        if ramp_s > 0:
            e, e1, e2 = smooth_profile(tt / ramp_s, "minjerk")
            e1, e2 = e1 / ramp_s, e2 / ramp_s**2
        else:
            e, e1, e2 = np.ones_like(tt), np.zeros_like(tt), np.zeros_like(tt)
        th = A * e * s
        th1 = A * (e1 * s + e * w * c)
        th2 = A * (e2 * s + 2.0 * e1 * w * c - e * w * w * s)
        return np.where(on, th, 0.0), np.where(on, th1, 0.0), np.where(on, th2, 0.0)

    ev = AxisRotation(M, axis, center_m, theta, device.gravity_mps2)
    rate = float(device.sample_rate_hz)
    times = sample_times(rest_s + duration_s, rate)
    labels = np.where(times < rest_s, 0, -1)
    return times, ev, labels


def pendulum(device, rng, *, amplitude_deg, freq_hz, center_deg, duration_s, decay_s):
    A = math.radians(amplitude_deg)
    th0 = math.radians(center_deg)
    w = 2.0 * math.pi * freq_hz
    lam = 0.0 if decay_s == 0 else 1.0 / decay_s

    def theta(t):
        E = np.exp(-lam * t)
        c, s = np.cos(w * t), np.sin(w * t)
        th = th0 + A * E * c
        th1 = A * E * (-lam * c - w * s)
        th2 = A * E * ((lam * lam - w * w) * c + 2.0 * lam * w * s)
        return th, th1, th2

    ev = AxisRotation(np.eye(3), np.array([0.0, 1.0, 0.0]), np.zeros(3), theta, device.gravity_mps2)
    rate = float(device.sample_rate_hz)
    times = sample_times(duration_s, rate)
    return times, ev, np.full(times.shape, -1)


def linear_actuator(device, rng, *, axis, distance_m, travel_s, rest_s, strokes, tilt_deg, tilt_axis, profile):
    C0 = rotation_matrix(np.asarray(tilt_axis) * math.radians(tilt_deg))
    step = C0 @ (np.asarray(axis) * distance_m)  # world displacement of one stroke
    t0, dur, Cs, ax, ang, p0, dp, lab = [], [], [], [], [], [], [], []
    t, p = 0.0, np.zeros(3)
    for k in range(strokes + 1):
        t0.append(t); dur.append(rest_s); Cs.append(C0); ax.append(EZ); ang.append(0.0)
        p0.append(p.copy()); dp.append(np.zeros(3)); lab.append(k)
        t += rest_s
        if k < strokes:
            d = step if k % 2 == 0 else -step
            t0.append(t); dur.append(travel_s); Cs.append(C0); ax.append(EZ); ang.append(0.0)
            p0.append(p.copy()); dp.append(d); lab.append(-1)
            t += travel_s
            p = p + d
    ev = Segments(t0, dur, Cs, ax, ang, p0, dp, lab, device.gravity_mps2, profile)
    rate = float(device.sample_rate_hz)
    times = sample_times(t, rate)
    return times, ev


class LaneChange:
    """Planar vehicle, forward speed component v constant along world x, path
    y(x) = Y [S((x - x1)/L1) - S((x - x3)/L3)] (min-jerk steps); body x
    forward, z up, heading psi = atan(y')."""

    def __init__(self, v, Y, x1, L1, x3, L3, g):
        self.v, self.Y, self.x1, self.L1, self.x3, self.L3, self.g = v, Y, x1, L1, x3, L3, g

    @staticmethod
    def _step(u: np.ndarray):
        inside = (u > 0) & (u < 1)
        uc = np.clip(u, 0.0, 1.0)
        S = uc**3 * (10.0 - 15.0 * uc + 6.0 * uc * uc)
        S1 = 30.0 * uc * uc * (1.0 - uc) ** 2
        S2 = 60.0 * uc * (1.0 - uc) * (1.0 - 2.0 * uc)
        S3 = 60.0 - 360.0 * uc + 360.0 * uc * uc
        return S, np.where(inside, S1, 0.0), np.where(inside, S2, 0.0), np.where(inside, S3, 0.0)

    def __call__(self, times: np.ndarray, position: bool = True) -> Kinematics:
        times = np.asarray(times, float)
        v = self.v
        x = v * times
        a1 = self._step((x - self.x1) / self.L1)
        a3 = self._step((x - self.x3) / self.L3)
        y = self.Y * (a1[0] - a3[0])
        y1 = self.Y * (a1[1] / self.L1 - a3[1] / self.L3)
        y2 = self.Y * (a1[2] / self.L1**2 - a3[2] / self.L3**2)
        y3 = self.Y * (a1[3] / self.L1**3 - a3[3] / self.L3**3)
        q = 1.0 + y1 * y1
        psi = np.arctan(y1)
        r = v * y2 / q
        r1 = v * v * (y3 * q - 2.0 * y1 * y2 * y2) / (q * q)
        C = rot_z(psi)
        z = np.zeros_like(times)
        omega = np.column_stack([z, z, r])
        alpha = np.column_stack([z, z, r1])
        acc = np.column_stack([z, v * v * y2, z])
        f = to_body(C, acc + self.g * EZ)
        pos = np.column_stack([x, y, z])
        return Kinematics(C, pos, f, omega, alpha)


def lane_change(device, rng, *, speed_mps, offset_m, lead_m, shift_m, hold_m, return_m, exit_m):
    x1 = lead_m
    x3 = lead_m + shift_m + hold_m
    ev = LaneChange(speed_mps, offset_m, x1, shift_m, x3, return_m, device.gravity_mps2)
    total = (x3 + return_m + exit_m) / speed_mps
    rate = float(device.sample_rate_hz)
    times = sample_times(total, rate, extra=1)
    return times, ev, np.full(times.shape, -1)


class Random6Dof:
    """C = Rz(psi) Ry(theta) Rx(phi) with band-limited random Euler angles (sums
    of tones) and a band-limited random world acceleration of O."""

    def __init__(self, tones_angles, tones_acc, g):
        self.ta = tones_angles  # [(amp, w, ph)] for phi, theta, psi
        self.tc = tones_acc  # [(amp, w, ph)] for a_x, a_y, a_z (world)
        self.g = g

    def __call__(self, times: np.ndarray, position: bool = True) -> Kinematics:
        times = np.asarray(times, float)
        (ph, ph1, ph2), (th, th1, th2), (ps, ps1, ps2) = (sum_of_tones(times, *k) for k in self.ta)
        sf, cf, st, ct, sp, cp = np.sin(ph), np.cos(ph), np.sin(th), np.cos(th), np.sin(ps), np.cos(ps)
        C = np.empty((times.size, 3, 3))
        C[:, 0, 0] = cp * ct
        C[:, 0, 1] = cp * st * sf - sp * cf
        C[:, 0, 2] = cp * st * cf + sp * sf
        C[:, 1, 0] = sp * ct
        C[:, 1, 1] = sp * st * sf + cp * cf
        C[:, 1, 2] = sp * st * cf - cp * sf
        C[:, 2, 0] = -st
        C[:, 2, 1] = ct * sf
        C[:, 2, 2] = ct * cf
        p = ph1 - ps1 * st
        q = th1 * cf + ps1 * ct * sf
        r = -th1 * sf + ps1 * ct * cf
        p1 = ph2 - ps2 * st - ps1 * th1 * ct
        q1 = (th2 * cf - th1 * ph1 * sf + ps2 * ct * sf - ps1 * th1 * st * sf + ps1 * ph1 * ct * cf)
        r1 = (-th2 * sf - th1 * ph1 * cf + ps2 * ct * cf - ps1 * th1 * st * cf - ps1 * ph1 * ct * sf)
        omega = np.column_stack([p, q, r])
        alpha = np.column_stack([p1, q1, r1])
        acc = np.empty((times.size, 3))
        pos = np.empty((times.size, 3)) if position else None
        for k, (amp, w, phs) in enumerate(self.tc):
            s, _ = sincos(times, w, phs)
            acc[:, k] = s @ amp
            if position:
                # position = -sum a/w^2 sin(w t + ph), relative to t = 0
                pos[:, k] = float(np.sum(amp / (w * w) * np.sin(phs))) - s @ (amp / (w * w))
        f = to_body(C, acc + self.g * EZ)
        return Kinematics(C, pos, f, omega, alpha)


def random_6dof(device, rng, *, duration_s, bandwidth_hz, angle_rms_deg, accel_rms_mps2, tones):
    lo = 0.05 * bandwidth_hz
    ta = [random_tones(rng, tones, lo, bandwidth_hz, math.radians(angle_rms_deg)) for _ in range(3)]
    tc = [random_tones(rng, tones, max(lo, 0.2 * bandwidth_hz), bandwidth_hz, accel_rms_mps2) for _ in range(3)]
    ev = Random6Dof(ta, tc, device.gravity_mps2)
    rate = float(device.sample_rate_hz)
    times = sample_times(duration_s, rate)
    return times, ev, np.full(times.shape, -1)


TEMP_PROFILES = ("constant", "ramp", "sine")


def temperature_profile(t: np.ndarray, kind: str = "constant", temp_c: float = 25.0, temp_end_c: float = 45.0,
                        temp_amplitude_c: float = 5.0, temp_period_s: float = 600.0) -> np.ndarray:
    """degC at times t: constant temp_c; ramp from temp_c at the first sample to
    temp_end_c at the last; sine temp_c + amplitude sin(2 pi (t - t0) / period)."""
    t = np.asarray(t, float)
    if kind == "constant" or t.size == 0:
        return np.full(t.shape, float(temp_c))
    t0, t1 = float(t[0]), float(t[-1])
    if kind == "ramp":
        if t1 == t0:
            return np.full(t.shape, float(temp_c))
        return temp_c + (temp_end_c - temp_c) * (t - t0) / (t1 - t0)
    if kind == "sine":
        return temp_c + temp_amplitude_c * np.sin(2.0 * math.pi * (t - t0) / temp_period_s)
    raise AccelcalError(f"unknown temperature profile {kind!r}; profiles: {', '.join(TEMP_PROFILES)}")
