"""Stop-to-stop displacement on what real recordings do to it: a body that turns during a
motion (its zero point beyond any calibration or tilt error), a rest detector fooled by a
steady trend under vibration, the rows between a motion and a rest, rests dated back, and
samples a logger wrote twice.  Every recording is built here."""
import dataclasses
import math

import numpy as np
import pytest
from scipy.special import j0

from accelcal import estimators as E
from accelcal.io.calibration import Calibration
from accelcal.io.device import Device, default_triad, save_device
from accelcal.errors import InputError
from accelcal.io.recording import recording_from_arrays, write_recording
from accelcal.simulate import run_simulation
from cli_run import one_refusal, run
from estimator_devices import G

RATE = 100.0


def _counts(d, body, sigma, seed):
    """Counts of the triad ``d`` reading the specific force ``body`` (n, 3), m/s^2, with white
    noise of ``sigma`` m/s^2."""
    rng = np.random.default_rng(seed)
    raw = np.round(d.zero_counts + (body + sigma * rng.standard_normal(body.shape)) * d.counts_per_mps2)
    return raw.astype(np.int64)


def _rocking_body(amp_deg, rest_s=2.0, move_s=10.0, hz=1.0, dist=0.0):
    """f = R^T (a + g z), m/s^2 (n, 3), of a body at rest, then ``move_s`` s rocking about body y
    by amp_deg sin(2 pi hz t) (whole periods: it ends as it began) while it travels ``dist`` m
    along x (min-jerk), then at rest."""
    t = np.arange(int((2 * rest_s + move_s) * RATE)) / RATE
    u = np.clip((t - rest_s) / move_s, 0.0, 1.0)
    inside = (t >= rest_s) & (t <= rest_s + move_s)
    acc = dist * (60 * u - 180 * u**2 + 120 * u**3) / move_s**2 * inside
    th = np.radians(amp_deg) * np.sin(2 * np.pi * hz * (t - rest_s)) * inside
    c, s = np.cos(th), np.sin(th)
    return np.column_stack([c * acc - s * G, np.zeros_like(t), s * acc + c * G])


def _rocking(d, amp_deg, rest_s=2.0, move_s=10.0, hz=1.0, dist=0.0, seed=0):
    """The counts of the triad ``d`` for :func:`_rocking_body`."""
    body = _rocking_body(amp_deg, rest_s, move_s, hz, dist)
    return recording_from_arrays(np.arange(body.shape[0]) / RATE, _counts(d, body, 0.005, seed))


def _turn_warnings(c):
    return [w for w in c.warnings if "likely turned during the motion" in w]


def _span(line):
    """The motion's first and last time (s) a turned motion's line names."""
    return tuple(float(x) for x in line.split("motion at t = ")[1].split(" s")[0].split("-"))


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
def test_a_body_rocking_during_a_motion_is_left_out_unless_kept(engine, form):
    """A triad rocked by +-45 deg for 10 s between two rests (a hand oscillating an x-IMU: 93 m
    for decimetres, exit 0 and only a warning): no accelerometer alone tells the tilt from an
    acceleration, and the gravity that leaks in is g (1 - J0(45 deg)) = 1.45 m/s^2 on average --
    the motion's zero point, far beyond a calibration error.  The stop-to-stop method assumes the
    same attitude at both rests and none between: the motion is left out, and with no other motion
    the recording is refused, naming the motion, |zp| and the tilt it equals.  keep_turned writes
    it with the same words as a warning; the same travel without rocking has none."""
    d = default_triad()
    cal = Calibration.nominal(d)
    rec = _rocking(d, 45.0, dist=0.3)
    with pytest.raises(InputError, match="no motion can be reported") as ei:
        E.displacement_from_recording(d, cal, rec, engine, form=form)
    msg = str(ei.value)
    assert "likely turned during the motion" in msg and "--keep-turned" in msg and "is left out" in msg
    c = E.displacement_from_recording(d, cal, rec, engine, form=form, keep_turned=True)
    w = _turn_warnings(c)
    assert len(w) == 1, c.warnings
    assert _span(w[0]) == _span(msg)
    assert float(msg.split("a tilt of ")[1].split(" deg")[0]) == float(w[0].split("a tilt of ")[1].split(" deg")[0])
    t0, t1 = _span(w[0])
    rp = E.default_rest_params(d)
    # from the rest before the rocking to the closing rest's declaration, at most hold samples
    # into that rest (dated back to where it began) -- pad more offline, after its first quiet
    # sample; offline the window starts its pad sample (at rest) before the rest's last sample
    rest = c["rest"].astype(bool)
    i0, i1 = np.searchsorted(c["t"], [t0, t1])
    began = i1 - int(np.argmin(rest[i1::-1]))
    pad = E.DisplaceParams(dt=0.01).pad if form == "offline" else 0
    assert t0 <= 2.0 and rest[:i0 + 1 + pad].all() and not rest[i0 + 1 + pad:began].any()
    assert c["t"][began] >= 12.0 and i1 - began + 1 <= rp.hold + 2
    # the velocity the leak leaves at the end, g (1 - J0(A)) over the 10 s, spread over the
    # integrated t1 - t0 (zp written to 3 digits: 0.5 %; the travel's part is 1e-3 of it)
    zp = float(w[0].split("|zp| = ")[1].split(" m/s^2")[0])
    leak = G * (1.0 - j0(math.radians(45.0))) * 10.0
    assert zp == pytest.approx(leak / (t1 - t0), rel=0.01)
    tilt = float(w[0].split("a tilt of ")[1].split(" deg")[0])
    assert abs(tilt - math.degrees(math.asin(zp / G))) <= 0.05 + 1e-9
    # (a travel of 2 s: over 10 s its middle, near constant speed, would be as quiet as a rest)
    c = E.displacement_from_recording(d, cal, _rocking(d, 0.0, move_s=2.0, dist=0.3), engine, form=form)
    assert not _turn_warnings(c) and not any("left out" in w for w in c.warnings), c.warnings
    assert abs(c["p_x"][-1] - 0.3) <= 0.01 * 0.3


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("fixed", "stream")])
def test_motions_before_a_turned_one_are_written_up_to_the_rest_before_it(engine, form):
    """A clean travel of 0.3 m, then a motion rocked by +-45 deg, then a third travel: the first
    is written; the output ends in the rest before the rocked one (the third's position would
    carry the rocked motion's unknown displacement), with one line naming the rocked motion and
    the one after it."""
    d = default_triad()
    cal = Calibration.nominal(d)
    body = np.vstack([_rocking_body(0.0, move_s=2.0, dist=0.3), _rocking_body(45.0, dist=0.3),
                      _rocking_body(0.0, move_s=2.0, dist=0.3)])
    rec = recording_from_arrays(np.arange(body.shape[0]) / RATE, _counts(d, body, 0.005, 1))
    c = E.displacement_from_recording(d, cal, rec, engine, form=form)
    line = [w for w in c.warnings if "is left out" in w]
    assert len(line) == 1 and "likely turned during the motion" in line[0], c.warnings
    assert "the 1 motion(s) after it are not reported" in line[0]
    t0, _ = _span(line[0])
    assert 6.0 + 1.5 <= t0 <= 6.0 + 2.0                         # in the rest before the rocking
    assert c["t"][-1] <= t0 + 0.5 and c["t"][-1] >= 6.0 + 1.5 and c["rest"][-1] == 1
    assert abs(c["p_x"][-1] - 0.3) <= 0.01 * 0.3 and c.meta["segments"] == "1"
    assert f"the output ends at t = {c['t'][-1] - c['t'][0]:.3f} s" in line[0]


def test_the_zero_point_a_rest_shows_is_no_turn():
    """1-D along a rail tilted by 10 deg (nothing removed): zp = g sin 10 deg = 1.7 m/s^2, but
    the rest before the motion reads it too -- a tilt held, not a turn: no warning, and the
    correction gives the distance."""
    d = default_triad()
    sim = run_simulation(d, "linear_actuator", seed=3, distance_m=0.5, travel_s=2.0, rest_s=2.0, tilt_deg=10.0)
    c = E.displacement_from_recording(d, Calibration.nominal(d), sim.recording, "float", axis="x")
    zp = abs(float(c.meta["zero_point_mps2"].strip("()").split(",")[0]))
    assert zp > 3 * E.ZP_TURN_MPS2
    assert not _turn_warnings(c), c.warnings


def test_the_zero_point_limit_is_the_turn_plus_the_noise_and_the_detector_s_lag():
    """zp_limit: ZP_TURN_MPS2 (a 2.9 deg tilt) for a long motion; 5 sigma / sqrt(n) of zp's own
    noise and the lag term 2 dev_max hold / n on top (a one-sample 'motion' between two rests
    is never a turn)."""
    rp = E.RestParams(dev_max=0.9, hold=64)
    assert math.degrees(math.asin(E.ZP_TURN_MPS2 / G)) == pytest.approx(2.92, abs=0.01)
    assert E.zp_limit(4400, 0.18, rp) == pytest.approx(0.5 + 5 * 0.18 / math.sqrt(4400) + 2 * 0.9 * 64 / 4400)
    assert E.zp_limit(1, 0.18, rp) > 100


def test_the_cli_refuses_a_turned_motion_and_keeps_it_with_keep_turned(tmp_path, capfd):
    d = default_triad()
    save_device(d, tmp_path / "dev.json")
    write_recording(tmp_path / "rec.csv", _rocking(d, 45.0))
    out = tmp_path / "out.csv"
    args = ["displacement", "--device", tmp_path / "dev.json", "--calibration", "nominal", tmp_path / "rec.csv",
            "-o", out]
    rc, _, err, _ = run(args, capfd)
    assert rc == 2 and not out.exists() and one_refusal(err)
    assert "likely turned during the motion" in err and "--keep-turned" in err
    rc, _, err, _ = run(args + ["--keep-turned"], capfd)
    assert rc == 0
    assert sum("likely turned during the motion" in ln for ln in err.splitlines()) == 1
    head = [ln for ln in out.read_text().splitlines() if ln.startswith("#")]
    assert sum(ln.startswith("# warning_") and "likely turned during the motion" in ln for ln in head) == 1


def _flight_triad():
    """A signed 16-bit triad at +-16 g (2048 counts per g), 100 Hz, no noise stated: the
    thresholds take it from the data, as for a flight log."""
    return Device(name="flight", sample_rate_hz=RATE, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 2048 / G),
                  zero_counts=np.zeros(3))


def _flight(d, ramp_mps3, sigma=0.134, seed=5):
    """3 s on the pad (at rest), 2 s of boost (f_z from g up to 2 g), then f_z falls steadily at
    ``ramp_mps3`` (m/s^2 a second) from 2 g to 0, through g (a slow change of thrust); 0: f_z back
    at g for 8 s (a true rest in flight).  All under white vibration of ``sigma`` m/s^2 per axis.
    Returns the recording and the first sample after the boost."""
    pad, boost = int(3 * RATE), int(2 * RATE)
    rise = G + G * (1 - np.cos(np.pi * np.arange(boost) / boost)) / 2
    after = 2 * G - ramp_mps3 * np.arange(int(2 * G / ramp_mps3 * RATE)) / RATE if ramp_mps3 else \
        np.full(int(8 * RATE), G)
    fz = np.concatenate([np.full(pad, G), rise, after])
    body = np.column_stack([np.zeros_like(fz), np.zeros_like(fz), fz])
    return recording_from_arrays(np.arange(fz.size) / RATE, _counts(d, body, sigma, seed)), pad + boost


@pytest.mark.parametrize("ramp", [0.5, 1.7])
@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
def test_a_steady_change_through_g_under_vibration_is_no_rest(engine, form, ramp):
    """Under vibration (0.134 m/s^2 rms: the rest test's dev_max 5 sigma = 0.67 m/s^2) the running
    mean follows a slow steady change of f: a rocket log's thrust falling through |f| = g mid-flight
    was declared a rest (-370 km).  Fitted over blocks of 1 s, that change (0.5 m/s^2 a second) is
    beyond 5 sigma of what the noise gives (0.23 m/s^2); the pad's rest, under the same vibration, is
    still a rest.  The streaming forms (the firmware's, which cannot look back) are warned of.
    At the rocket's own 1.7 m/s^2 a second the rest declared is 12 samples long, too short to
    show the change; it is tested from where it began (its quiet run before the declaration,
    36 samples in the real log)."""
    d = _flight_triad()
    if ramp > 1.0:
        # the rocket's vibration as its own log shows it (a ramp this steep over most of a short
        # synthetic flight would itself widen the noise estimated from the data)
        d = dataclasses.replace(d, noise_mps2=0.134)
    rec, lift = _flight(d, ramp)
    if form == "offline":
        # the flight never comes to rest: its one motion cannot be reported, and the refusal says why
        with pytest.raises(InputError, match="no motion can be reported") as ei:
            E.displacement_from_recording(d, Calibration.nominal(d), rec, engine, form=form)
        assert str(ei.value).count("f changes steadily") == 1 and "not taken as rests" in str(ei.value)
        assert "the last motion (t = 3." in str(ei.value)
    else:
        # (the motion the streamed 'rest' ends carries the boost's speed: kept to see the rests)
        c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine, form=form, keep_turned=True)
        rest = c["rest"].astype(bool)
        assert rest[:int(2.5 * RATE)].all()                          # the pad
        trend = [w for w in c.warnings if "f changes steadily" in w]
        assert len(trend) == 1, c.warnings
        assert "taken as rests by the streaming detector" in trend[0]
    # the same flight held at g (no change): a rest, and no word of a trend
    rec, lift = _flight(d, 0.0)
    # (a rest in flight is no standstill: the boost's speed is left in its zero point, kept here)
    c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine, form=form, keep_turned=True)
    rest = c["rest"].astype(bool)
    assert rest[:int(2.5 * RATE)].all() and rest[lift + int(2 * RATE):].mean() > 0.9
    assert not any("f changes steadily" in w for w in c.warnings), c.warnings


def test_the_trend_bound_is_5_sigma_of_the_fitted_change_of_white_noise():
    """trend_bound(n, sigma) / 5 is the rms change over n samples of the line fitted to white noise
    (2000 windows: the rms is known to 1/sqrt(2 x 2000) = 1.6 %; 5 of those allowed)."""
    rng = np.random.default_rng(7)
    n, sigma = 100, 0.3
    x = rng.standard_normal((n, 2000)) * sigma
    change = np.polyfit(np.arange(n, dtype=float), x, 1)[0] * (n - 1)
    assert np.sqrt(np.mean(change**2)) == pytest.approx(E.trend_bound(n, sigma) / 5, rel=5 * 0.016)


def _runs(mask):
    e = np.diff(np.concatenate([[0], np.asarray(mask, np.int8), [0]]))
    return list(zip(np.flatnonzero(e == 1).tolist(), np.flatnonzero(e == -1).tolist()))


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
def test_a_sample_is_part_of_a_motion_or_of_a_rest(engine, form):
    """The integration of a motion runs to its closing rest's declaration, hold - 1 samples after
    the rest began (offline, pad samples past its first quiet sample, and from an anchor pad
    samples inside the opening rest): those rows had both rest = 1 and corrected = 1, with a v
    that was not 0.  Each row is now one or the other: at rest v = 0 and p holds (the motion's
    end point), the corrected span ends where the rest began; the distance is unchanged (the
    correction ends at the declaration as before)."""
    d = default_triad()
    rec = _rocking(d, 0.0, move_s=2.0, dist=0.3)
    c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine, form=form)
    rest, corr = c["rest"].astype(bool), c["corrected"].astype(bool)
    assert not (rest & corr).any() and (rest | corr).all()
    v = np.column_stack([c["v_x"], c["v_y"], c["v_z"]])
    assert np.all(v[rest] == 0.0)
    for s, e in _runs(rest):
        assert np.ptp(c["p_x"][s:e]) == 0.0 and np.ptp(c["p_raw_x"][s:e]) == 0.0
    (s1, e1), (s2, e2) = _runs(rest)
    assert _runs(corr) == [(e1, s2)]
    assert abs(c["p_x"][-1] - 0.3) <= 0.01 * 0.3


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
def test_a_later_rest_is_dated_back_to_its_quiet_run(engine, form):
    """A rest after a motion is reported from the first sample of the quiet run that declared it
    (hold - 1 samples before the declaration), as the first rest is: the detector's own quiet
    decisions on the same f say where."""
    d = default_triad()
    rec = _rocking(d, 0.0, move_s=2.0, dist=0.3)
    c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine, form=form)
    rp = E.default_rest_params(d)
    f = E.triad_apply_float(d.zero_counts, d.nominal_sensitivity(), rec.raw)
    flags = E.rest_detect(f, rp)[0]
    at = (flags & E.REST_AT_REST) != 0
    starts = np.flatnonzero(at[1:] & ~at[:-1]) + 1
    declared = int(starts[rec.t[starts] > 3.0][0])                     # the closing rest's declaration
    began = declared - rp.hold + 1
    assert ((flags[began:declared + 1] & E.REST_QUIET) != 0).all() and not flags[began - 1] & E.REST_QUIET
    s2 = _runs(c["rest"].astype(bool))[1][0]
    assert s2 == began


def _with_rows(rec, path, copies, changed=()):
    """``rec`` written to ``path`` with the rows ``copies`` written twice, and the rows ``changed``
    written twice with the same time stamp and other readings (one count more on raw_0)."""
    lines = path.parent / "tmp.csv"
    write_recording(lines, rec)
    text = lines.read_text().splitlines()
    head = next(i for i, ln in enumerate(text) if not ln.startswith("#")) + 1
    out = []
    for i, ln in enumerate(text):
        out.append(ln)
        k = i - head
        if k in copies:
            out.append(ln)
        if k in changed:
            cells = ln.split(",")
            cells[1] = str(int(cells[1]) + 1)
            out.append(",".join(cells))
    path.write_text("\n".join(out) + "\n")
    return head


def test_a_sample_written_twice_is_left_out_with_a_note(tmp_path, capfd):
    """A logger that writes a sample twice (time stamp and readings alike: 1.2 % of x-io's logs)
    was refused ('t must be strictly increasing'); the copies are left out, with a note naming
    how many and the first, on stderr and in the output's comments, and the result is the one
    of the recording without them.  The same stamp with other readings is still refused, naming
    its row, and nothing is written."""
    d = default_triad()
    save_device(d, tmp_path / "dev.json")
    rec = _rocking(d, 0.0, move_s=2.0, dist=0.3)
    write_recording(tmp_path / "clean.csv", rec)
    head = _with_rows(rec, tmp_path / "twice.csv", copies=(50, 51, 300))
    outs = {}
    for name in ("clean", "twice"):
        out = tmp_path / f"{name}.out.csv"
        rc, _, err, _ = run(["displacement", "--device", tmp_path / "dev.json", "--calibration", "nominal",
                             tmp_path / f"{name}.csv", "-o", out], capfd)
        assert rc == 0, err
        outs[name] = out.read_text().splitlines()
    first = head + 1 + 50 + 1                                     # the line of the first copy
    note = f"3 row(s) repeat the row before exactly, time stamp and readings (a sample written twice), " \
           f"the first at row {first}: left out"
    assert sum(note in ln for ln in err.splitlines()) == 1, err
    assert any(ln.startswith("# note_") and note in ln for ln in outs["twice"])
    body = {k: [ln for ln in v if not ln.startswith("#")] for k, v in outs.items()}
    assert body["twice"] == body["clean"]
    head = _with_rows(rec, tmp_path / "other.csv", copies=(50,), changed=(300,))
    rc, _, err, _ = run(["displacement", "--device", tmp_path / "dev.json", "--calibration", "nominal",
                         tmp_path / "other.csv", "-o", tmp_path / "other.out.csv"], capfd)
    assert rc == 2 and err.count("\n") == 1
    assert f"row {head + 1 + 300 + 2}, column t: t must be strictly increasing" in err, err
    assert not (tmp_path / "other.out.csv").exists()


#: the z channel's gain error of a chip read with its nominal scale (a real MPU-6050 read 0.949 g: |f|
#: 0.50 m/s^2 below g, at the rest test's edge); here 0.54 m/s^2 below, beyond it
LOW_GAIN = 0.945


def _low_z(d, turn_deg, sigma=0.04, seed=3, gain=LOW_GAIN):
    """A triad whose z channel reads ``gain`` of its nominal scale, still for 3 s with f along
    body z, then turned by ``turn_deg`` about y (2 s, smooth), still for 3 s, 2 s of travel
    (0.3 m, min-jerk, along the world's horizontal), still for 3 s; white noise of ``sigma`` m/s^2."""
    t = np.arange(int(13 * RATE)) / RATE
    u = np.clip((t - 3.0) / 2.0, 0.0, 1.0)
    th = np.radians(turn_deg) * (10 * u**3 - 15 * u**4 + 6 * u**5)
    s = np.clip((t - 8.0) / 2.0, 0.0, 1.0)
    acc = 0.3 * (60 * s - 180 * s**2 + 120 * s**3) / 4.0 * ((t >= 8.0) & (t <= 10.0))
    c, sn = np.cos(th), np.sin(th)
    body = np.column_stack([c * acc + sn * G, np.zeros_like(t), -sn * acc + c * G])
    rng = np.random.default_rng(seed)
    body = (body + sigma * rng.standard_normal(body.shape)) * np.array([1.0, 1.0, gain])
    return recording_from_arrays(t, np.round(d.zero_counts + body * d.counts_per_mps2).astype(np.int64))


@pytest.mark.parametrize("engine, form", [("float", "offline"), ("float", "stream"), ("fixed", "stream")])
def test_a_still_start_whose_f_is_off_g_is_said_to_be_the_scale_not_a_turn(engine, form):
    """A chip read with its nominal scale whose z reads 0.945 g (9.267 m/s^2, 0.54 m/s^2 below g, beyond
    the rest test's g +- 0.5 for a rest's mean) is still for 3 s, then turned: 'does not start at rest'
    had named no reason and the next warning called the still start 'turned from the first rest'.  The
    offline form leaves the still start out (its mean |f|) and starts at the still stretch after the
    turn, with a warning that blames the scale; the streaming forms, whose detector took the start for
    its first rest (each of its samples within the band widened by the noise), have no rest at |f| = g
    after it (their reference is that start's f) and refuse, blaming the scale.  Still throughout at
    that scale: no rest at all, and the error says why (it had blamed a body that "creeps or turns
    slowly throughout")."""
    d = dataclasses.replace(default_triad(), noise_mps2=0.04)
    cal = Calibration.nominal(d)
    if form == "offline":
        c = E.displacement_from_recording(d, cal, _low_z(d, 90.0), engine, form=form)
        start = [w for w in c.warnings if "does not start at rest" in w]
        assert len(start) == 1, c.warnings
        w = start[0]
        assert not any("turned from the first rest" in x and "t = 0.000" in x for x in c.warnings), c.warnings
    else:
        with pytest.raises(InputError) as ei:
            E.displacement_from_recording(d, cal, _low_z(d, 90.0), engine, form=form)
        w = str(ei.value)
        assert "turned" not in w, w
    assert "the calibration's scale is off" in w and "calibrate it first" in w, w
    t0, t1 = (float(x) for x in w.split("still at t = ")[1].split(" s")[0].split("-"))
    assert t0 == 0.0 and 2.5 <= t1 <= 3.5, w            # (the smooth turn's first 0.5 s: < 3 deg)
    norm = float(w.split("read |f| = ")[1].split(" ")[0])
    assert abs(norm - LOW_GAIN * G) < 5 * 0.04 / math.sqrt(250), w
    assert f"{G:g} +- 0.5 m/s^2" in w, w
    with pytest.raises(InputError) as ei:
        E.displacement_from_recording(d, cal, _low_z(d, 0.0), engine, form=form)
    msg = str(ei.value)
    assert "the calibration's scale is off" in msg and "creeps" not in msg, msg
    assert abs(float(msg.split("read |f| = ")[1].split(" ")[0]) - LOW_GAIN * G) < 0.05, msg


def _eight_bit():
    """An Empatica E4-like triad: signed 8-bit at +-2 g (64 counts per g: one code 0.153 m/s^2),
    32 Hz, no noise stated (the thresholds take it from the data)."""
    return Device(name="e4", sample_rate_hz=32.0, gravity_mps2=G, raw_min=-128, raw_max=127,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 64 / G),
                  zero_counts=np.zeros(3))


def _coarse_stop_to_stop(d, sigma_counts, seed=2):
    """4 s at rest (f along z), 2 s of travel (1 m along x, min-jerk: up to 1.44 m/s^2), 4 s at rest; each
    channel's true value half a code off the grid (64.5, 0.5, 0.5 counts at rest: the worst
    case, a reading that flips between two codes) plus white noise of ``sigma_counts``."""
    rate = float(d.sample_rate_hz)
    t = np.arange(int(10 * rate)) / rate
    s = np.clip((t - 4.0) / 2.0, 0.0, 1.0)
    acc = (60 * s - 180 * s**2 + 120 * s**3) / 4.0 * ((t >= 4.0) & (t <= 6.0))
    body = np.column_stack([acc, np.zeros_like(t), np.full_like(t, G)])
    rng = np.random.default_rng(seed)
    raw = np.round(0.5 + body * d.counts_per_mps2 + sigma_counts * rng.standard_normal(body.shape))
    return recording_from_arrays(t, raw.astype(np.int64))


@pytest.mark.parametrize("sigma_counts, warned", [(0.3, False), (2.0, True)])
def test_a_rest_test_wide_only_by_coarse_codes_is_no_vibration(sigma_counts, warned):
    """An 8-bit E4 at rest on a wrist (2-4 codes a pose) was told its rest test of 0.472 m/s^2 is
    'beyond what a sensor at rest shows (0.01-0.25) ... vibration throughout'.  A still channel's
    rounding error is at most half a code (0.077 m/s^2), so its window std is at most sigma + q/2,
    and the estimate adds q^2/12: with sigma = 0.05 m/s^2 (the noisiest sensor at rest) up to
    hypot(0.05 + 0.077, 0.044) = 0.134 m/s^2, whose 8 sigma (1.07 m/s^2) is the warning's bound
    here (0.4 with fine codes).  Noise of 0.3 codes (0.046 m/s^2) half a code off the grid: an
    estimate of sqrt(0.5^2 + 1/12) = 0.58 codes, a test of 0.44 m/s^2 (warned on the old code),
    no warning; vibration of 2 codes (0.31 m/s^2, a test of 1.5 m/s^2): warned."""
    d = _eight_bit()
    c = E.displacement_from_recording(d, Calibration.nominal(d), _coarse_stop_to_stop(d, sigma_counts), "float")
    wide = [w for w in c.warnings if "beyond what most sensors at rest show" in w]
    assert len(wide) == int(warned), c.warnings
    q = G / 64
    assert E.displacement_checks.rest_noise_max(q) == pytest.approx(math.hypot(0.05 + q / 2, q / math.sqrt(12)))
    if warned:
        assert "code step of 0.153 m/s^2" in wide[0] and "vibration throughout" in wide[0], wide[0]
    else:
        noise = E.common.channel_noise(d, _coarse_stop_to_stop(d, sigma_counts))
        f_sigma = E.common.force_noise(d, Calibration.nominal(d), noise, [0, 1, 2])
        dev = E.default_rest_params(d, f_sigma=f_sigma).dev_max
        assert 0.4 < dev < 8 * E.displacement_checks.rest_noise_max(q), dev
        assert abs(c["p_x"][-1] - 1.0) < 0.05, c["p_x"][-1]


def _sine_stroke(rate, sigma, tip_deg=0.0, seed=1):
    """A level triad (16384 counts per g, no noise stated), 2 s at rest, 0.5 m along x with one sine
    period of acceleration (peak 0.785 m/s^2) in 2 s, 2 s at rest; with ``tip_deg``, the body then tips
    about y by that much (0.5 s, smooth), holds still 2 s, tips back (0.5 s) and rests 2 s.  White
    noise of ``sigma`` m/s^2."""
    d = Device(name="triad", sample_rate_hz=rate, gravity_mps2=G, raw_min=-32768, raw_max=32767,
               positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 16384 / G),
               zero_counts=np.zeros(3))
    t = np.arange(int((6.0 if tip_deg == 0.0 else 11.0) * rate)) / rate
    a = np.where((t >= 2.0) & (t < 4.0), 0.5 * 2 * np.pi / 4.0 * np.sin(np.pi * (t - 2.0)), 0.0)
    up, down = np.clip((t - 6.0) / 0.5, 0.0, 1.0), np.clip((t - 8.5) / 0.5, 0.0, 1.0)
    th = np.radians(tip_deg) * ((3 * up**2 - 2 * up**3) - (3 * down**2 - 2 * down**3))
    body = np.column_stack([a * np.cos(th) - G * np.sin(th), np.zeros_like(t), a * np.sin(th) + G * np.cos(th)])
    rng = np.random.default_rng(seed)
    raw = np.round((body + sigma * rng.standard_normal(body.shape)) * d.counts_per_mps2)
    return d, recording_from_arrays(t, raw.astype(np.int64))


@pytest.mark.parametrize("rate, sigma", [(50.0, 0.01), (50.0, 0.05), (200.0, 0.05), (1000.0, 0.05), (100.0, 0.02)])
def test_the_flat_peak_of_a_smooth_strokes_acceleration_is_no_turn(rate, sigma):
    """One sine period of acceleration moves a level triad 0.5 m: its flat peak (0.785 m/s^2) holds
    still for a block or two of the rest test, and was called a still body 'turned from the first
    rest (by up to 4.5 deg) ... the result after it is not valid' on a right answer (a tester's grid:
    50 Hz at 0.01 and 0.05 m/s^2 of noise, 200 and 1000 Hz at 0.05).  A turned body stays still, at
    least TREND_BLOCK_HOLDS blocks (1 s): no warning on the stroke, in every engine and seed, and the
    offline form's answer right; a body that tips by 10 deg and holds for 2 s is still warned of.  (At
    0.05 m/s^2 the streaming detector, whose test is then 0.25 m/s^2 wide, finds a rest about the
    stroke's zero crossing, which the trend test names: its answer is not held to 0.5 m here.)"""
    for engine in ("float", "fixed"):
        for seed in (1, 2, 3):
            d, rec = _sine_stroke(rate, sigma, seed=seed)
            c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine)
            assert not any("turned" in w for w in c.warnings), (engine, seed, c.warnings)
            assert engine == "fixed" or abs(c["p_x"][-1] - 0.5) < 0.01, (engine, seed, c["p_x"][-1])
        d, rec = _sine_stroke(rate, sigma, tip_deg=10.0)
        c = E.displacement_from_recording(d, Calibration.nominal(d), rec, engine)
        turned = [w for w in c.warnings if "turned from the first rest" in w]
        assert len(turned) == 1, (engine, c.warnings)
        assert abs(float(turned[0].split("by up to ")[1].split(" deg")[0]) - 10.0) < 1.0, turned
        assert 6.0 <= float(turned[0].split("still at t = ")[1].split("-")[0]) <= 7.0, turned
