"""The capture loop: samples in, stillness found by the project's static detector (noise from
the data unless the device file states it), each still pose captured and labelled, the
calibration refitted jig-free with its uncertainty, the next orientation chosen by
:mod:`accelcal.capture.plan`, until the target or the pose limit.

A pose is a still stretch of at least ``hold_s`` seconds (:func:`accelcal.readings.static.detect_static`
over the samples since the last pose) that follows a motion: after a pose the person must move
before the next one counts (holding on does not capture the same pose twice).  The fit is the one
``accelcal calibrate`` makes of the written recording (its pose labels; jig-free, the channel model
``auto``): the target counts only when the full model (offset and sensitivity vector of each
channel) is determined.
"""
from __future__ import annotations

import math
import re
from types import SimpleNamespace
from typing import Callable, Sequence

import numpy as np
from scipy.stats import chi2 as chi2_dist

from ..calibrate.recordings import fit_jigfree
from ..errors import InputError
from ..io.recording import recording_from_arrays
from ..readings.noise import noise_for
from ..readings.static import detect_static, pose_means, poses_from_recording, window_len, STATIC_WINDOW_S
from .events import Events
from .plan import next_direction, pose_information, prior_information, target_sigmas, words, worst_ratio

#: the refit's refusal of a labelled pose that moves (readings.static.pose_means)
MOVES = re.compile(r"pose (\d+) \(.*is labelled static but moves")
HOLD_S = 2.0          # a pose: still for this long (s)
SETTLE_S = 0.25       # the first this much of a still stretch after a motion is left out (the hand settles)
CHECK_S = 0.25        # look for a pose every this much of new samples (s)
NOISE_EVERY_S = 2.0   # the detector's noise (the device file's, else from the data) renewed this often (s)
CHI2_QUANTILE = 0.99  # the fit's chi2 beyond this quantile of its distribution inflates the sigmas
BUFFER_S = 30.0       # keep at most this much of the samples since the last pose for the detector (s)


class CaptureLoop:
    """One capture session, fed samples as they come.

    Parameters
    ----------
    device : Device
        The device (channels, rate, nominal scale).
    events : Events
        Where the events and the human text go.
    target_mg : float
        Target 1-sigma of every offset (mg).
    target_pct : float
        Target 1-sigma of every gain |s_i| (%).
    max_poses : int
        Stop after this many poses.
    plan : sequence of array_like, optional
        A fixed plan: the gravity directions to ask for, in order (then the guided choice);
        None (default): every pose guided.
    hold_s : float
        Seconds of stillness that make a pose.
    bad_lines : callable, optional
        Gives the source's count of lines that did not parse (reported in ``progress``).
    """

    def __init__(self, device, events: Events, *, target_mg: float = 1.0, target_pct: float = 0.1,
                 max_poses: int = 40, plan: Sequence | None = None, hold_s: float = HOLD_S,
                 bad_lines: Callable[[], int] | None = None):
        self.device = device
        self.events = events
        self.target_mg = float(target_mg)
        self.target_pct = float(target_pct)
        self.max_poses = int(max_poses)
        self.plan = [np.asarray(d, float) / np.linalg.norm(d) for d in plan] if plan is not None else None
        self.hold_n = max(3, int(round(hold_s * device.sample_rate_hz)))
        self.check_n = max(1, int(round(CHECK_S * device.sample_rate_hz)))
        self.settle_n = int(round(SETTLE_S * device.sample_rate_hz))
        self.max_buf = max(4 * self.hold_n, int(BUFFER_S * device.sample_rate_hz))
        self.w = window_len(device, STATIC_WINDOW_S, 10 ** 9)
        N = device.n_channels
        self.t = np.zeros(1024)
        self.raw = np.zeros((1024, N), dtype=np.int64)
        self.pose = np.full(1024, -1, dtype=np.int64)
        self.n = 0
        self.buf_start = 0
        self.checked = 0
        self.n_poses = 0          # poses held (labelled)
        self.next_label = 0       # the next pose's label (a pose dropped keeps its number unused)
        self.dropped_stamps = 0
        self.fit = None
        self.model = None
        self.offset_sigma_mg = np.full(N, np.inf)
        self.gain_sigma_pct = np.full(N, np.inf)
        self.requested: np.ndarray | None = None
        self.noise: np.ndarray | None = None
        self.noise_at = 0
        self.done_reason: str | None = None
        self.bad_lines = bad_lines or (lambda: 0)

    # ------------------------------------------------------------------ samples
    def start(self) -> None:
        """Ask for the first pose."""
        self.ask()

    def feed(self, t: np.ndarray | None, raw: np.ndarray) -> None:
        """Take samples and look for a pose every CHECK_S seconds of them.

        Parameters
        ----------
        t : ndarray, shape (n,), or None
            Their time stamps (s); None: the sample index over the device's rate.
        raw : ndarray, shape (n, N)
            Raw readings (counts).
        """
        raw = np.asarray(raw, dtype=np.int64).reshape(-1, self.device.n_channels)
        if t is None:
            t = (self.n + np.arange(raw.shape[0])) / self.device.sample_rate_hz
        else:
            t = np.asarray(t, float)
            last = self.t[self.n - 1] if self.n else -np.inf
            keep = t > np.maximum.accumulate(np.concatenate([[last], t[:-1]]))
            self.dropped_stamps += int(np.count_nonzero(~keep))
            t, raw = t[keep], raw[keep]
        m = raw.shape[0]
        while self.n + m > self.t.size:
            self.t = np.concatenate([self.t, np.zeros(self.t.size)])
            self.raw = np.concatenate([self.raw, np.zeros_like(self.raw)])
            self.pose = np.concatenate([self.pose, np.full(self.pose.size, -1, dtype=np.int64)])
        self.t[self.n:self.n + m] = t
        self.raw[self.n:self.n + m] = raw
        self.n += m
        while not self.finished and self.n - self.checked >= self.check_n:
            self.checked += self.check_n
            self.look(self.checked)

    @property
    def finished(self) -> bool:
        """Whether the session has stopped (target, pose limit)."""
        return self.done_reason is not None

    def look(self, upto: int) -> None:
        """Look for a pose among the samples since the last one, up to ``upto``."""
        if upto - self.buf_start > self.max_buf:
            self.buf_start = upto - self.max_buf
        raw = self.raw[self.buf_start:upto]
        if raw.shape[0] < self.hold_n:
            return
        if self.noise is None or upto - self.noise_at >= NOISE_EVERY_S * self.device.sample_rate_hz:
            new = noise_for(self.device, raw, self.w)[0]
            self.noise = new if self.noise is None else np.minimum(self.noise, new)   # motion only adds
            self.noise_at = upto
        for a, b in detect_static(SimpleNamespace(raw=raw), self.device, noise=self.noise,
                                  min_s=self.hold_n / self.device.sample_rate_hz):
            if self.next_label and a < self.w:
                continue    # no motion seen before it: still the last pose (or the buffer's start)
            a += self.settle_n if a > 0 else 0      # a motion's end settles
            if b - a < self.hold_n or self.moves(self.buf_start + a, self.buf_start + b):
                continue
            self.capture(self.buf_start + a, self.buf_start + b)
            return

    def moves(self, a: int, b: int) -> bool:
        """Whether samples [a, b) move by the rule a labelled pose is held to
        (:func:`accelcal.readings.static.pose_means`), which the refit applies to the written poses."""
        rec = SimpleNamespace(raw=self.raw[a:b], t=self.t[a:b], source="<capture>")
        try:
            pose_means(rec, [(0, b - a)], self.device, labels=[self.n_poses], noise=self.noise, check_motion=True)
        except InputError:
            return True
        return False

    # ------------------------------------------------------------------ poses
    def capture(self, a: int, b: int) -> None:
        """Label samples [a, b) as the next pose, refit, and stop or ask for the next."""
        k = self.next_label
        self.next_label += 1
        self.pose[a:b] = k
        self.buf_start = b
        mean = self.raw[a:b].mean(axis=0)
        self.n_poses += 1
        S, off = self.current_model()
        f = np.linalg.lstsq(S, mean - off, rcond=None)[0]
        grav = -f / np.linalg.norm(f)
        angle = (math.degrees(math.acos(float(np.clip(grav @ self.requested, -1.0, 1.0))))
                 if self.requested is not None else None)
        self.events.emit("pose_captured", index=k, n_samples=b - a, mean_counts=mean,
                         t_start=float(self.t[a]), t_stop=float(self.t[b - 1]),
                         gravity_in_sensor=grav, off_request_deg=angle)
        self.refit()
        if self.n_poses == 0 and self.next_label:
            self.ask()
            return
        ratio = worst_ratio(self.offset_sigma_mg, self.gain_sigma_pct, self.target_mg, self.target_pct)
        self.events.emit("progress", poses=self.n_poses, model=self.model, offset_sigma_mg=self.offset_sigma_mg,
                         gain_sigma_pct=self.gain_sigma_pct, worst_over_target=ratio,
                         bad_lines=self.bad_lines())
        self.events.say(self.progress_line(ratio))
        if self.model == "full" and ratio <= 1.0:
            self.done_reason = "target"
        elif self.n_poses >= self.max_poses:
            self.done_reason = "max_poses"
        else:
            self.ask()

    def progress_line(self, ratio: float) -> str:
        """The human progress line: poses, worst sigmas against the targets."""
        if not np.all(np.isfinite(self.offset_sigma_mg)):
            return (f"pose {self.n_poses}: captured; the {self.model or 'no'} model so far "
                    f"(the full model needs 9 poses in general directions)")
        gain = (f"{np.max(self.gain_sigma_pct):.3g} %" if np.all(np.isfinite(self.gain_sigma_pct)) else "not fitted")
        return (f"pose {self.n_poses}: worst offset sigma {np.max(self.offset_sigma_mg):.3g} mg "
                f"(target {self.target_mg:g}), worst gain sigma {gain} (target {self.target_pct:g} %), "
                f"model {self.model}" + (f": {ratio:.2f} x target" if math.isfinite(ratio) else "")
                + (f"; {self.bad_lines()} bad line(s) so far" if self.bad_lines() else ""))

    def current_model(self) -> tuple[np.ndarray, np.ndarray]:
        """(S, b): the latest fit's sensitivity and offsets, else the device's nominal ones."""
        if self.fit is not None:
            return self.fit.sensitivity, self.fit.offsets
        return self.device.nominal_sensitivity(), self.device.nominal_offsets()

    def recording(self):
        """All samples so far as a Recording, the captured poses labelled.

        Returns
        -------
        Recording
        """
        n = self.n
        return recording_from_arrays(self.t[:n].copy(), self.raw[:n].copy(), pose=self.pose[:n].copy(),
                                     metadata={"source_format": "accelcal capture"})

    def refit(self) -> None:
        """The jig-free fit of the poses so far and its sigmas (the full model's only count)."""
        N = self.device.n_channels
        while True:
            rec = self.recording()
            try:
                poses = poses_from_recording(rec, self.device, use_labels=True)
                fit, fallback = fit_jigfree(self.device, poses, "auto", False)
                break
            except InputError as e:
                if e.source not in ("<poses>", rec.source):
                    raise
                moved = MOVES.match(e.detail)
                if moved:
                    self.drop(int(moved.group(1)), e.detail)
                    if self.n_poses:
                        continue
                self.model = None
                if not moved:
                    self.events.say(f"  (no fit yet: {e.detail[:120]})")
                return
        self.fit = fit
        self.model = fit.method if fallback is None else fallback["to"]
        g = self.device.gravity_mps2
        off, gain = target_sigmas(fit.cov[:, :4, :4] * self.inflation(fit), fit.sensitivity, g)
        self.offset_sigma_mg = off
        self.gain_sigma_pct = gain if self.model in ("full", "gain") else np.full(N, np.inf)

    def drop(self, label: int, why: str) -> None:
        """Unlabel pose ``label`` (its samples moved, by the rule the refit holds every pose to)."""
        self.pose[:self.n][self.pose[:self.n] == label] = -1
        self.n_poses -= 1
        self.events.emit("pose_dropped", index=label, reason=why)
        self.events.say(f"  pose {label + 1} dropped: it moved ({why.split(': ', 1)[-1][:100]}); {self.n_poses} poses kept")

    @staticmethod
    def inflation(fit) -> float:
        """The factor from the fit's covariance to the stated one: the fit's is inflated by chi2/dof
        where that exceeds 1 (the Birge rule of :mod:`accelcal.calibrate`); the capture's by chi2/dof
        only where chi2 exceeds its CHI2_QUANTILE quantile for the dof (with the few dof of ten poses,
        chi2/dof swings from 0.1 to 3 by chance, and stating sigma from it would stop the capture
        by chance)."""
        if fit.dof <= 0:
            return 1.0
        birge = max(1.0, fit.chi2 / fit.dof)
        keep = fit.chi2 > chi2_dist.ppf(CHI2_QUANTILE, fit.dof)
        return (birge if keep else 1.0) / birge

    # ------------------------------------------------------------------ next pose
    def information(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(info, S, sigma): the planning information of the poses so far (with the prior), the
        sensitivity it is linearised at and the expected 1-sigma of a new pose's mean (counts)."""
        S, off = self.current_model()
        g = self.device.gravity_mps2
        info = prior_information(S, g)
        if self.fit is not None:
            sem = self.fit.poses.sem()
            birge = math.sqrt(max(1.0, self.fit.chi2 / self.fit.dof) * self.inflation(self.fit)) if self.fit.dof > 0 else 1.0
            for p in range(sem.shape[0]):
                info += pose_information(S, sem[p] * birge, self.fit.f[p], g)
            sigma = np.median(sem, axis=0) * birge
        else:
            sd = self.device.noise_mps2 * np.linalg.norm(S, axis=1) if self.device.noise_mps2 > 0 else np.ones(len(S))
            sigma = np.sqrt(sd ** 2 + 1.0 / 12.0) / math.sqrt(self.hold_n)
            for k in np.unique(self.pose[:self.n][self.pose[:self.n] >= 0]):
                m = self.raw[:self.n][self.pose[:self.n] == k].mean(axis=0)
                info += pose_information(S, sigma, np.linalg.lstsq(S, m - off, rcond=None)[0], g)
        return info, S, sigma

    def ask(self) -> None:
        """Choose the next orientation and tell the person."""
        k = self.next_label
        if self.plan is not None and k < len(self.plan):
            grav = self.plan[k]
            expect = None
        else:
            info, S, sigma = self.information()
            u, expect = next_direction(info, S, sigma, self.device.gravity_mps2, self.target_mg, self.target_pct)
            grav = -u
        self.requested = grav
        text = words(grav)
        self.events.emit("next_pose", index=k, gravity_in_sensor=grav, words=text, expected_worst_over_target=expect)
        self.events.say(f"pose {k + 1}: {text}, and hold still for {self.hold_n / self.device.sample_rate_hz:g} s")

    def stop(self, reason: str) -> None:
        """Stop the session for ``reason`` (interrupted, port_lost, end_of_input) unless it has stopped.

        Parameters
        ----------
        reason : str
            Why it stops.
        """
        if self.done_reason is None:
            self.done_reason = reason
