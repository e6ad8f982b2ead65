"""A simulated sensor held by a simulated person, for the capture's tests and benchmark.

The sensor: the independent generator's devices and true parameters (tests/python/indep_model.py:
offsets +-2 % of full scale, gains +-3 %, axes off by up to 1.5 deg), white noise before the ADC,
rounding, clipping.  The person: told where gravity should point in the sensor frame (the
capture's ``next_pose`` event), reacts after 0.3-0.8 s, turns there in 1-2 s with the hand
moving the sensor by 5-15 cm (a minimum-jerk profile), and lands 2-5 deg off the requested orientation (a tilt
about a random horizontal axis) at a random heading; still in between (sensor noise only).
"""
from __future__ import annotations

import math
import threading
import time

import numpy as np

from indep_model import DEVICES, expm_so3, logm_so3, random_rotation, rotation_for_direction, true_parameters

Z = np.array([0.0, 0.0, 1.0])


class Person:
    """A simulated person holding a simulated sensor; :meth:`samples` gives the next readings."""

    def __init__(self, dev, truth: dict, noise_mps2: float, rng, off_deg=(2.0, 5.0)):
        self.dev = dev
        self.truth = truth
        self.noise = noise_mps2
        self.rng = rng
        self.off_deg = off_deg
        self.R = random_rotation(rng)
        self.segments: list[tuple] = []      # queued (kind, duration_s, R0, R1, d)
        self.seg_t = 0.0
        self.n = 0
        self.lock = threading.Lock()

    @property
    def t(self) -> float:
        return self.n / self.dev.sample_rate_hz

    def on_event(self, ev: dict) -> None:
        if ev.get("event") != "next_pose":
            return
        up = -np.asarray(ev["gravity_in_sensor"], float)
        R1 = rotation_for_direction(up, self.rng.uniform(0.0, 2.0 * math.pi))
        a = self.rng.normal(size=3)
        a[2] = 0.0
        a /= np.linalg.norm(a)
        R1 = expm_so3(a * math.radians(self.rng.uniform(*self.off_deg))) @ R1
        d = self.rng.normal(size=3)
        d *= self.rng.uniform(0.05, 0.15) / np.linalg.norm(d)
        with self.lock:
            self.segments = [("still", self.rng.uniform(0.3, 0.8), None, None, None),
                             ("move", self.rng.uniform(1.0, 2.0), None, R1, d)]

    def forces(self, m: int) -> np.ndarray:
        """(m, 3) the specific force in the sensor frame for the next m samples."""
        dt = 1.0 / self.dev.sample_rate_hz
        out = np.empty((m, 3))
        g = self.dev.gravity_mps2
        with self.lock:
            for j in range(m):
                acc = np.zeros(3)
                while self.segments and self.seg_t >= self.segments[0][1]:
                    kind, dur, R0, R1, d = self.segments.pop(0)
                    if kind == "move":
                        self.R = R1
                    self.seg_t = 0.0
                if self.segments and self.segments[0][0] == "move":
                    kind, dur, R0, R1, d = self.segments[0]
                    if R0 is None:
                        R0 = (self.R, logm_so3(self.R.T @ R1))
                        self.segments[0] = (kind, dur, R0, R1, d)
                    x = self.seg_t / dur
                    s = x ** 3 * (10.0 - 15.0 * x + 6.0 * x * x)          # minimum jerk
                    sdd = (60.0 * x - 180.0 * x ** 2 + 120.0 * x ** 3) / dur ** 2
                    R = R0[0] @ expm_so3(R0[1] * s)
                    acc = d * sdd
                else:
                    R = self.R
                out[j] = R.T @ (acc + g * Z)
                if self.segments:
                    self.seg_t += dt
        return out

    def samples(self, m: int) -> np.ndarray:
        """(m, N) the next m raw readings (counts)."""
        f = self.forces(m)
        S, b = self.truth["S"], self.truth["b"]
        x = b[None, :] + f @ S.T + self.rng.normal(size=(m, len(b))) * self.noise * np.linalg.norm(S, axis=1)
        self.n += m
        return np.clip(np.round(x), self.dev.raw_min, self.dev.raw_max).astype(np.int64)


def make_setup(device: str = "triad16", seed: int = 0):
    """(device, truth, rng): an independent device and its true parameters."""
    rng = np.random.default_rng(seed)
    dev = DEVICES[device]()
    return dev, true_parameters(dev, rng), rng


def fixed_plan(rng, rounds: int = 4) -> list[np.ndarray]:
    """Six faces then six random directions, repeated ``rounds`` times (gravity in the sensor frame)."""
    faces = [np.array(v, float) for v in ([0, 0, -1], [0, 0, 1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0])]
    out = []
    for _ in range(rounds):
        out += faces
        for _ in range(6):
            v = rng.normal(size=3)
            out.append(v / np.linalg.norm(v))
    return out


def run_in_process(loop_cls, events_cls, dev, truth, rng, noise_mps2: float, plan=None, max_s: float = 600.0, quiet=True,
                   **kw):
    """Run one capture in-process: the person reacts to the loop's events.  Returns (loop, seconds)."""
    person = Person(dev, truth, noise_mps2, rng)
    events = events_cls(listener=person.on_event, quiet=quiet)
    loop = loop_cls(dev, events, plan=plan, **kw)
    loop.start()
    chunk = max(1, int(round(0.25 * dev.sample_rate_hz)))
    while not loop.finished and person.t < max_s:
        loop.feed(None, person.samples(chunk))
    return loop, person.t


def run_on_pty(args: list, person: Person, *, env: dict, bad_every: int = 0, interrupt_after: int | None = None,
               close_after: int | None = None, timeout: float = 120.0, speed: float = 10.0):
    """Run ``accelcal capture --port <pty> ... --json`` with ``person`` writing the sensor's lines to the
    pseudo-terminal's master side from a thread and moving on the ``next_pose`` events it prints.
    ``bad_every``: every so many lines one line that does not parse; ``interrupt_after`` /
    ``close_after``: after that many poses, SIGINT the capture / close the master (the port lost).
    ``speed``: the sensor runs this many times faster than real time.
    Returns (exit status, events, stderr text, lines written, bad lines written)."""
    import json
    import os
    import select
    import signal
    import subprocess
    import sys
    import tty

    master, slave = os.openpty()
    tty.setraw(slave)
    path = os.ttyname(slave)
    # Ctrl-C as at a terminal: a shell's background job (a CI runner's) inherits SIGINT ignored, and
    # Python then leaves it ignored; the capture under test gets the default action back
    proc = subprocess.Popen([sys.executable, "-m", "accelcal.cli", "capture", "--port", path, "--json"] + args,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    # a capture that never ends fails the test after ``timeout`` s rather than hanging the suite
    watchdog = threading.Timer(timeout, proc.kill)
    watchdog.start()
    stop = threading.Event()
    counts = {"lines": 0, "bad": 0}
    started = threading.Event()

    def write():
        pending = b""
        t0 = None
        while not stop.is_set():
            if not pending:
                if not started.is_set():
                    started.wait(0.05)
                    continue
                t0 = time.monotonic() - person.t / speed if t0 is None else t0
                ahead = person.t / speed - (time.monotonic() - t0)
                if ahead > 0:
                    time.sleep(ahead)
                lines = []
                for row in person.samples(10):
                    counts["lines"] += 1
                    if bad_every and counts["lines"] % bad_every == 0:
                        lines.append("1,2,x")
                        counts["bad"] += 1
                    lines.append(",".join(str(int(v)) for v in row))
                pending = ("\n".join(lines) + "\n").encode()
            try:
                _, ready, _ = select.select([], [master], [], 0.1)
                if ready:
                    pending = pending[os.write(master, pending):]
            except OSError:
                return

    th = threading.Thread(target=write, daemon=True)
    th.start()
    events = []
    master_open = True
    try:
        for line in proc.stdout:
            ev = json.loads(line)
            events.append(ev)
            person.on_event(ev)
            started.set()
            if ev["event"] == "pose_captured":
                k = ev["index"] + 1
                if interrupt_after is not None and k == interrupt_after:
                    # the person stops feeding the port at Ctrl-C, as a hand on the keyboard does
                    stop.set()
                    th.join()
                    proc.send_signal(signal.SIGINT)
                if close_after is not None and k == close_after and master_open:
                    stop.set()
                    th.join()
                    os.close(master)
                    master_open = False
        proc.wait(timeout=timeout)
    finally:
        watchdog.cancel()
        stop.set()
        th.join()
        if proc.poll() is None:
            proc.kill()
        if master_open:
            os.close(master)
        os.close(slave)
    return proc.returncode, events, proc.stderr.read(), counts["lines"], counts["bad"]
