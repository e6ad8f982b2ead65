"""What ``calibrate`` warns of beyond the fit itself: channels whose offset or gain the poses
determine poorly (whatever the span), the warnings recorded in the calibration JSON and
carried by ``header``, the real recordings that deserve no such warning; and a file of pose
means (one row a pose), which needs a ``pose`` column and must leak no library warning.

Simulated data come from the generator of test_calibrate (model.predict_counts + Gaussian
noise + rounding).
"""
from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np

from accelcal import model
from accelcal.calibrate import calibrate_recordings, static_force
from accelcal.calibrate.checks import far_from_nominal, gain_sigma
from accelcal.calibrate.settings import EXCITATION_MIN_SPAN_G, POORLY_DETERMINED_MG
from accelcal.cli.calibrate_command import calibrate_warnings
from accelcal.io.device import default_triad, save_device
from accelcal.firmware.header import calibration_header
from accelcal.simulate import simulate
from accelcal.io.recording import recording_from_arrays, write_recording
from accelcal.readings.steps import MOVE_PARTS, MOVE_RANGE, part_spread

from cli_run import run
from test_calibrate import draw_truth, fib_dirs, make_recording


def wrist_triad():
    """An 8-bit +-2 g triad at 32 Hz (64 counts per g, 1 count = 15.6 mg) with a worn
    wristband's noise (0.15 m/s^2: a hand's tremor on top of the sensor's), as an Empatica E4."""
    d = default_triad()
    g = d.gravity_mps2
    return dataclasses.replace(d, name="wrist-8bit", sample_rate_hz=32.0, raw_min=-128, raw_max=127,
                               counts_per_mps2=np.full(3, 64.0 / g), zero_counts=np.zeros(3), noise_mps2=0.15)


def wrist_poses(P, rng):
    """P directions a wrist takes: never near +x, f along z within -0.4..+0.65 g (the first two
    at its ends: every axis turned through 1 g or more)."""
    out = [np.array([-0.5, math.sqrt(1 - 0.25 - z * z), z]) for z in (-0.4, 0.64)]
    while len(out) < P:
        v = rng.normal(size=3)
        v /= np.linalg.norm(v)
        if v[0] < 0.2 and -0.4 < v[2] < 0.65:
            out.append(v)
    return np.array(out)


def wrist_calibration(hold_s, seed=1, P=12):
    d = wrist_triad()
    rng = np.random.default_rng(seed)
    b, S = draw_truth(d, rng, offset=0.02)
    F = d.gravity_mps2 * wrist_poses(P, rng)
    rec = make_recording(d, b, S, F, rng, labels=False, hold=int(hold_s * d.sample_rate_hz),
                         move=int(0.5 * d.sample_rate_hz))
    return d, b, rec, calibrate_recordings(d, [rec], "jigfree")


def mg_of(d, cal):
    """(offset 1-sigma in mg, gain 1-sigma in mg at 1 g) per channel."""
    off = 1000.0 * cal.offset_sigma / (d.counts_per_mps2 * d.gravity_mps2)
    return off, 1000.0 * gain_sigma(cal.sensitivity, cal.sensitivity_sigma)


def test_a_poorly_determined_channel_is_warned_of_whatever_the_span():
    """An Empatica E4 (8-bit, 26 wrist poses) was calibrated with offsets +-19 and +-24 mg and
    gains +-2 % and nothing said: every axis had turned through 1 g or more, so the "hardly
    turns" check (span < 1 g and sigma > 2 mg) stayed silent.  Twelve such poses of 1.5 s give
    sigmas of several mg: the channels beyond POORLY_DETERMINED_MG are named with their sigma
    and the causes (the axis never turned to +x, the coarse LSB, short poses); the same poses
    held 20 x as long shrink every sigma by sqrt(20) (white noise over the codes' dither) to
    below it, and nothing is said."""
    d, b, rec, cal = wrist_calibration(1.5)
    F = np.array([p["f_mps2"] for p in cal.extra["poses"]]) @ d.axes.T / d.gravity_mps2
    assert np.all(np.ptp(F, axis=0) >= EXCITATION_MIN_SPAN_G), np.ptp(F, axis=0)   # the old check is silent
    # the sigmas are honest: the truth within 4 of them
    assert np.all(np.abs(cal.offsets - b) < 4 * cal.offset_sigma), ((cal.offsets - b), cal.offset_sigma)
    off, gain = mg_of(d, cal)
    bad = np.flatnonzero((off > POORLY_DETERMINED_MG) | (gain > POORLY_DETERMINED_MG))
    assert bad.size, (off, gain)
    w = [x for x in calibrate_warnings(d, cal) if "poorly determined" in x]
    assert len(w) == 1, calibrate_warnings(d, cal)
    w = w[0]
    assert f"poorly determined on {bad.size} channel(s)" in w, w
    for i in range(3):
        assert (f"channel {i}'s f along its axis" in w) == (i in bad), (i, off, gain, w)
    i = int(bad[0])
    sig = cal.offset_sigma[i]
    assert f"offset +-{sig:.3g} counts ({off[i]:.2g} mg)" in w, w
    assert "no pose within 20 deg of +x" in w and "a coarse LSB (1 count = 15.6 mg" in w, w
    assert "few or short poses (12 poses" in w and "add poses with f along +x" in w, w
    _, _, _, long = wrist_calibration(30.0)
    off_l, gain_l = mg_of(d, long)
    ratio = off / off_l
    assert np.all(np.abs(ratio / math.sqrt(20.0) - 1.0) < 0.25), ratio
    assert np.all(off_l < POORLY_DETERMINED_MG) and np.all(gain_l < POORLY_DETERMINED_MG), (off_l, gain_l)
    assert not [x for x in calibrate_warnings(d, long) if "poorly determined" in x]


def test_the_calibration_records_its_warnings_and_the_header_carries_them(tmp_path, capfd):
    """``header`` had written such a calibration into firmware without a word: the calibration
    JSON now holds what ``calibrate`` warned of (``warnings``, one line each) and the header's
    opening comment carries it (a ``*/`` in a warning cannot close the comment); a calibration
    without warnings has neither.  A ``warnings`` that is no list of texts is one line naming
    the field."""
    d, _, rec, _ = wrist_calibration(1.5)
    save_device(d, tmp_path / "d.json")
    write_recording(tmp_path / "r.csv", rec)
    rc, out, err, caught = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "r.csv", "-o",
                                tmp_path / "c.json"], capfd)
    assert rc == 0 and not caught, (err, caught)
    lines = [ln for ln in err.splitlines() if "poorly determined" in ln]
    assert len(lines) == 1 and lines[0].startswith("accelcal calibrate: warning: "), err
    doc = json.loads((tmp_path / "c.json").read_text())
    assert doc["warnings"] == [ln[len("accelcal calibrate: warning: "):] for ln in err.splitlines()
                               if ln.startswith("accelcal calibrate: warning: ")]
    doc["warnings"].append("a warning that says */ in it")
    (tmp_path / "c.json").write_text(json.dumps(doc))
    rc, _, err, _ = run(["header", "--device", tmp_path / "d.json", "--calibration", tmp_path / "c.json", "-o",
                         tmp_path / "c.h"], capfd)
    assert rc == 0, err
    text = (tmp_path / "c.h").read_text()
    comment = text[:text.index("*/")]
    assert "WARNING (accelcal calibrate): the calibration is poorly determined" in comment, comment
    lines = comment.splitlines()
    first = next(k for k, ln in enumerate(lines) if "WARNING" in ln)
    block = lines[first:lines.index(" *", first)]
    assert max(len(ln) for ln in block) <= 100 and sum("WARNING" in ln for ln in block) == 2, block
    assert "a warning that says * / in it" in " ".join(block), block
    # a good calibration: no warnings key, no WARNING in its header
    _, _, rec, _ = wrist_calibration(30.0)
    write_recording(tmp_path / "r2.csv", rec)
    rc, _, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "r2.csv", "-o",
                         tmp_path / "c2.json"], capfd)
    assert rc == 0 and "warning" not in err, err
    assert "warnings" not in json.loads((tmp_path / "c2.json").read_text())
    run(["header", "--device", tmp_path / "d.json", "--calibration", tmp_path / "c2.json", "-o", tmp_path / "c2.h"],
        capfd)
    assert "WARNING" not in (tmp_path / "c2.h").read_text()
    doc["warnings"] = "not a list"
    (tmp_path / "c.json").write_text(json.dumps(doc))
    rc, _, err, _ = run(["header", "--device", tmp_path / "d.json", "--calibration", tmp_path / "c.json", "-o",
                         tmp_path / "c3.h"], capfd)
    assert rc == 2 and "warnings" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "c3.h").exists()


def test_the_real_recordings_are_not_poorly_determined(real_model):
    """The suite's real calibrations are not warned of: their offsets' 1-sigma is 0.03..0.06 mg
    (Xsens, 40 hand-held poses), 0.6..1.3 mg (imucal's six faces, known poses, inflated by a
    chi2/dof of 1.5e3), 0.3..2.9 mg (MPU-6050, 11 poses, 2 dof), gains 0.003..0.44 %: all below
    POORLY_DETERMINED_MG, whose margin over the MPU-6050's x offset (2.9 mg) this checks."""
    for name in ("xsens", "imucal", "mpu6050"):
        dev, _, _, cal = real_model(name)
        off, gain = mg_of(dev, cal)
        assert np.all(off < POORLY_DETERMINED_MG) and np.all(gain < POORLY_DETERMINED_MG), (name, off, gain)
        assert not [w for w in calibrate_warnings(dev, cal) if "poorly determined" in w], name


def pose_mean_rows(d, b, S, F, rng, sem_counts):
    """A file of pose means (Magneto's input): one row per orientation F (P,3), each the mean of
    a pose with ``sem_counts`` of noise, rounded to counts; t one second apart (--rate 1)."""
    m = np.round(model.predict_counts(b, S, d.positions, F) + sem_counts * rng.normal(size=(len(F), 3)))
    return np.arange(len(F), dtype=float), m.astype(np.int64)


def test_a_file_of_pose_means_is_told_to_label_its_rows_and_leaks_no_library_warning(tmp_path, capfd):
    """Magneto's input (178 hand-held orientations, one mean a row, no time) made ``calibrate``
    print two numpy RuntimeWarnings (the std of one-sample parts of a 3-row "static block") and
    then "needs at least 9 static poses ..., got 2; add poses".  Now: no library warning, and
    the error says first that such rows need a 'pose' column and that the detector needs several
    samples a pose, with no advice to add poses -- for rows in the order a hand turns the sensor (neighbours alike: a few
    found) and in no order (none found).  In no order, rows tens of degrees apart had made 3-row
    "poses" within twice a noise estimated from the rows' own scatter, and an offset-only fit
    (exit 0, two warnings): now that noise, 10-40 % of |f|, is no still sensor's, and the error
    says so.  With the column every row is a pose and the fit holds the truth within 4 sigma."""
    d = dataclasses.replace(default_triad(), noise_mps2=0.0)      # no noise stated: estimated from the rows
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(5)
    b, S = draw_truth(d, rng)
    u = np.linspace(0, 1, 120)
    turn = np.stack([np.cos(9 * np.pi * u) * np.sin(np.pi * u), np.sin(9 * np.pi * u) * np.sin(np.pi * u),
                     np.cos(np.pi * u)], 1)                       # a slow spiral from +z to -z
    for name, F in (("ordered", turn), ("shuffled", rng.permutation(turn))):
        t, m = pose_mean_rows(d, b, S, d.gravity_mps2 * F, rng, 2.0)
        write_recording(tmp_path / f"{name}.csv", recording_from_arrays(t, m))
        rc, _, err, caught = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / f"{name}.csv", "-o",
                                  tmp_path / f"{name}.json"], capfd)
        assert not caught and "RuntimeWarning" not in err, (name, err, caught)
        assert "the static detector takes a pose from a still stretch of several samples" in err, err
        assert "of 120 rows" in err and "if each row is already one pose's mean" in err and "'pose' column" in err
        if name == "ordered":       # neighbours alike: a few 3-row "poses", too few for any model
            assert rc == 2 and len(err.strip().splitlines()) == 1 and "got 2" in err, err
            assert not (tmp_path / f"{name}.json").exists()
            # the real hint first, and no advice to add poses to a file that holds 120 (it had come first)
            msg = err.split("field poses: ")[1]
            assert msg.startswith("if each row is already one pose's mean") and "add poses" not in msg, err
            assert msg.index("of 120 rows") < msg.index("got 2"), err
        else:                       # no rest in rows that scatter as a motion's: no fit from false poses
            assert rc == 2 and len(err.strip().splitlines()) == 1, err
            assert not (tmp_path / f"{name}.json").exists()
            assert "found 0, holding 0 of 120 rows" in err and "its readings scatter throughout" in err, err
    write_recording(tmp_path / "labelled.csv", recording_from_arrays(t, m, pose=np.arange(len(t))))
    rc, out, err, caught = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "labelled.csv", "-o",
                                tmp_path / "c.json"], capfd)
    assert rc == 0 and not caught and "from 120 static poses" in out, (err, caught)
    cal = json.loads((tmp_path / "c.json").read_text())
    got = np.array([c["offset_counts"] for c in cal["channels"]])
    sig = np.array([c["offset_sigma_counts"] for c in cal["channels"]])
    assert np.all(np.abs(got - b) < 4 * sig), (got - b, sig)


def test_the_mean_test_of_too_few_readings_is_no_library_warning():
    """part_spread cut three readings (a 3-row "static block" of a file of pose means) into
    eight parts and took the std of one-sample parts: numpy's "Degrees of freedom <= 0"
    reached the user.  Fewer than two samples a part cannot tell that they hold still: inf
    (the mean test fails, as the NaN had), and no warning; 16 readings are tested as before."""
    x = np.array([[0.0, 1.0], [2.0, 1.0], [1.0, 3.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        spread, sig = part_spread(x, np.array([1.0, 1.0]))
        assert np.all(np.isinf(spread)) and np.all(sig == 1.0)
        still = np.random.default_rng(0).normal(size=(2 * MOVE_PARTS, 2))
        spread, _ = part_spread(still, np.array([1.0, 1.0]))
        assert np.all(np.isfinite(spread))
    # white noise of unit std: eight 2-sample means (std 0.71) span well within MOVE_RANGE
    assert np.all(spread < MOVE_RANGE), spread


def knocked_recording(d, b, S, F, rng, knocked, factor):
    """Poses F held 1 s each, labelled 0..P-1; the poses ``knocked`` read ``factor`` x their
    force (a pose not at rest, a wrong row: |f| off g by (factor - 1) g)."""
    rec = make_recording(d, b, S, F, rng, hold=int(d.sample_rate_hz), move=int(0.3 * d.sample_rate_hz))
    rec.f = np.full_like(rec.f, np.nan)                                   # jig-free: no reference
    for p in knocked:
        m = rec.pose == p
        rec.raw[m] = np.round(b + factor * (rec.raw[m] - b)).astype(np.int64)
    return rec


def test_poses_far_off_the_fit_are_named_with_what_they_change_and_left_to_the_user(tmp_path, capfd):
    """Magneto's 178 pose means fit well but for three at |f| - g = -0.77 m/s^2 (the next
    worst -0.054): the warning put chi2/dof 1.13e4 down to "a hand's tremor".  Two of 40 poses
    read 5 % low here (|f| - g = -0.49 m/s^2, hundreds of times their noise): the warning names
    exactly those two with their |f| error, and the offsets' change without them, which is the
    fit of the other 38 poses (made here); the poses are kept, --drop-outliers leaves them out
    and gives that fit.  The same poses unknocked name none (the rule's false alarm: median + 8
    robust sd)."""
    d = default_triad()
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(8)
    b, S = draw_truth(d, rng)
    F = d.gravity_mps2 * fib_dirs(40)
    rec = knocked_recording(d, b, S, F, rng, (7, 23), 0.95)
    cal = calibrate_recordings(d, [rec], "jigfree")
    out = cal.extra["outliers"]
    assert sorted(p["name"] for p in out["poses"]) == [7, 23] and not out["dropped"], out
    knock = -0.05 * d.gravity_mps2                                       # -0.49 m/s^2
    for p in out["poses"]:        # the fit with them pulls towards them: part of the knock is absorbed
        assert knock - 0.05 < p["norm_error_mps2"] < knock / 2, p
    # the others, pulled along, stay well short of them
    assert abs(out["others_worst_norm_error_mps2"]) < min(abs(p["norm_error_mps2"]) for p in out["poses"]) / 2, out
    kept = np.isin(rec.pose, (7, 23))
    rest = recording_from_arrays(rec.t, rec.raw, pose=np.where(kept, -1, rec.pose))
    alone = calibrate_recordings(d, [rest], "jigfree")
    # read with the other 38 poses' fit, the knocked poses are off by the knock (noise: 1e-4 m/s^2)
    for p in (7, 23):
        f = static_force(alone.offsets, alone.sensitivity, rec.raw[rec.pose == p].mean(axis=0))
        assert abs(np.linalg.norm(f) - d.gravity_mps2 - knock) < 0.01, (p, np.linalg.norm(f) - d.gravity_mps2)
    np.testing.assert_allclose(out["without"]["offset_change_counts"], alone.offsets - cal.offsets, atol=1e-6)
    w = [x for x in calibrate_warnings(d, cal) if "sit far off the fit" in x]
    assert len(w) == 1 and w[0].startswith("2 pose(s) sit far off the fit"), w
    assert "pose 7 (t = " in w[0] and "pose 23 (t = " in w[0] and "--drop-outliers" in w[0], w[0]
    assert not any("a hand's tremor" in x for x in calibrate_warnings(d, cal)), calibrate_warnings(d, cal)
    assert any("because of the 2 pose(s) far off the fit" in x for x in calibrate_warnings(d, cal))
    write_recording(tmp_path / "r.csv", rec)
    rc, _, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "r.csv", "--method", "jigfree",
                         "--drop-outliers", "-o", tmp_path / "c.json"], capfd)
    assert rc == 0 and "left out (--drop-outliers)" in err, err
    dropped = json.loads((tmp_path / "c.json").read_text())
    np.testing.assert_allclose([c["offset_counts"] for c in dropped["channels"]], alone.offsets, atol=1e-6)
    assert sorted(s["name"] for s in dropped["set_aside"]) == ["pose 23", "pose 7"], dropped["set_aside"]
    assert dropped["outliers"]["dropped"] and len(dropped["poses_used"]) == 38
    clean = calibrate_recordings(d, [knocked_recording(d, b, S, F, rng, (), 1.0)], "jigfree")
    assert "outliers" not in clean.extra
    assert not any("far off the fit" in x for x in calibrate_warnings(d, clean))


def test_a_recording_in_motion_is_not_told_its_rows_are_pose_means(tmp_path, capfd):
    """A 200 Hz flight in one orientation (EuRoC's MAV: still only at the start) has its poses
    holding few of its rows, as a file of pose means does, and was told first to give every row
    its own 'pose' label.  Its rows turn by a fraction of a degree from one to the next: the
    error names the one orientation and gives no such hint."""
    d = dataclasses.replace(default_triad(), noise_mps2=0.0)
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(2)
    b, S = draw_truth(d, rng)
    n, rate = 6000, 200.0
    t = np.arange(n) / rate
    wob = np.where(t < 3.0, 0.0, 0.15 * np.sin(2 * np.pi * 0.7 * t) + 0.05 * np.sin(2 * np.pi * 2.3 * t))
    F = d.gravity_mps2 * np.stack([np.sin(wob), 0.3 * np.sin(wob), np.cos(wob)], 1)
    F += np.where(t[:, None] < 3.0, 0.0, 0.8 * np.sin(2 * np.pi * 1.1 * t)[:, None] * np.array([1.0, -0.5, 0.2]))
    m = np.round(model.predict_counts(b, S, d.positions, F) + 2.0 * rng.normal(size=(n, 3))).astype(np.int64)
    write_recording(tmp_path / "flight.csv", recording_from_arrays(t, m))
    rc, _, err, caught = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "flight.csv", "-o",
                              tmp_path / "f.json"], capfd)
    assert rc == 2 and not caught, err
    assert "the static detector takes a pose from a still stretch" in err and "'pose' column" not in err, err


def test_a_vibrating_flight_is_not_told_its_rows_are_pose_means(tmp_path, capfd):
    """A 250 Hz flight whose motors shake the sensor (a PX4 log's sensor_combined: |f| 0.37-3.6 g,
    1-99 %) turns by tens of degrees from one row to the next, as a file of pose means does, and
    was told first to give every row its own 'pose' label.  Pose means each read |f| ~ g: its rows
    do not, and the error leads with what is true: 3 still stretches in one orientation."""
    d = default_triad()
    d = dataclasses.replace(d, sample_rate_hz=250.0, raw_min=-32768, raw_max=32767, zero_counts=np.zeros(3),
                            counts_per_mps2=np.full(3, 2048.0 / d.gravity_mps2), noise_mps2=0.03)    # +-16 g
    save_device(d, tmp_path / "d.json")
    rng = np.random.default_rng(6)
    b, S = draw_truth(d, rng, offset=0.02)
    g = d.gravity_mps2
    parts = []
    for still_s, fly_s in ((2.0, 20.0), (2.0, 20.0), (2.0, 20.0)):        # on the ground between flights
        n_still, n_fly = int(still_s * d.sample_rate_hz), int(fly_s * d.sample_rate_hz)
        parts.append(np.repeat([[0.0, 0.0, g]], n_still, 0))
        parts.append(np.array([0.0, 0.0, g]) + 0.9 * g * rng.normal(size=(n_fly, 3)))   # motor vibration
    F = np.vstack(parts)
    t = np.arange(len(F)) / d.sample_rate_hz
    sig = d.noise_mps2 * d.counts_per_mps2
    m = np.round(model.predict_counts(b, S, d.positions, F) + sig * rng.normal(size=F.shape)).astype(np.int64)
    write_recording(tmp_path / "flight.csv", recording_from_arrays(t, m))
    rc, _, err, caught = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "flight.csv", "-o",
                              tmp_path / "f.json"], capfd)
    assert rc == 2 and not caught and len(err.strip().splitlines()) == 1, err
    assert "'pose' column" not in err and "pose means" not in err, err
    msg = err.split("field poses: ")[1]
    assert msg.startswith("jig-free 'full' calibration") and "(3 poses, 1 orientations" in msg, err
    assert "found 3, holding" in err, err


def test_a_robots_short_stops_are_counted_and_taken_with_min_static(tmp_path, capfd):
    """A robot arm that stops 0.75-1 s at each pose (AhmedFouad23/Accelerometer_Calibration's
    ALI runs: an MPU-6050 at 86.6 Hz, stops of 56-91 samples): the 1 s a still stretch needs
    where a motion touches it (a pause in a hand's movement is no pose) left them out unsaid.
    Now the error counts them, with their lengths and the --min-static that takes them; with it
    the 12 stops of 0.8 s in 12 orientations give the full model, holding the truth within 4
    sigma.  A --min-static that is no number of seconds >= 0 is refused in one line."""
    rate = 86.6
    d = dataclasses.replace(default_triad(), sample_rate_hz=rate, noise_mps2=0.04)
    rng = np.random.default_rng(3)
    b, S = draw_truth(d, rng)
    rec = make_recording(d, b, S, d.gravity_mps2 * fib_dirs(12), rng, labels=False, hold=int(0.8 * rate),
                         move=int(1.5 * rate))
    d = dataclasses.replace(d, noise_mps2=0.0)                     # no noise stated: estimated from the recording
    save_device(d, tmp_path / "d.json")
    write_recording(tmp_path / "arm.csv", rec)
    rc, _, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "arm.csv", "-o",
                         tmp_path / "c.json"], capfd)
    assert rc == 2 and len(err.strip().splitlines()) == 1 and not (tmp_path / "c.json").exists(), err
    assert "found 0" in err and "12 still stretch(es) of 0.8" in err and "shorter than 1 s" in err, err
    told = err.split("--min-static ")[1].split()[0]
    assert 0.75 <= float(told) <= 0.85, told
    rc, out, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "arm.csv", "--min-static", told,
                           "-o", tmp_path / "c.json"], capfd)
    assert rc == 0 and "from 12 static poses" in out and "'offset' model" not in err, (out, err)
    cal = calibrate_recordings(d, [rec], min_static_s=float(told))
    assert cal.extra["fit"]["model"] == "full" and "fallback" not in cal.extra["fit"]
    assert np.all(np.abs(cal.offsets - b) < 4 * cal.offset_sigma), (cal.offsets - b) / cal.offset_sigma
    for bad in ("-0.5", "nan", "1s"):
        rc, _, err, _ = run(["calibrate", "--device", tmp_path / "d.json", tmp_path / "arm.csv", "--min-static", bad,
                             "-o", tmp_path / "x.json"], capfd)
        assert rc == 2 and len(err.strip().splitlines()) == 1 and f"--min-static '{bad}'" in err, err
        assert not (tmp_path / "x.json").exists()


def test_a_gain_beyond_any_chips_tolerance_is_warned_of():
    """A channel whose gain is 14 % below the device file's (within the 1.25 x that marks a wrong
    scale) passed unsaid: datasheets hold a chip's sensitivity within +-3 % (MPU-6050) to +-10 %
    (ADXL345's 230-282 LSB/g), so the device file's counts_per_mps2 is not this chip's or the
    chip is out of its specification.  Warned of, naming the channel and the gain; a gain within
    the tolerance, or one whose 1-sigma could bring it within, is not."""
    d = default_triad()
    rng = np.random.default_rng(4)
    b, S = draw_truth(d, rng)
    S[1] *= 0.86 / np.linalg.norm(S[1]) * d.counts_per_mps2[1]
    rec = make_recording(d, b, S, d.gravity_mps2 * fib_dirs(24), rng, labels=False, hold=int(d.sample_rate_hz),
                         move=int(0.5 * d.sample_rate_hz))
    cal = calibrate_recordings(d, [rec], "jigfree")
    w = [x for x in calibrate_warnings(d, cal) if "gain is" in x]
    assert len(w) == 1 and w[0].startswith("channel 1's gain is -14 % from the device file's"), w
    assert "(1 of 3 channels)" in w[0] and "check the device file's counts_per_mps2" in w[0], w[0]
    S0 = d.nominal_sensitivity()
    assert far_from_nominal(d, S0 * 1.09) is None
    assert far_from_nominal(d, S0 * 0.86, np.full(3, 0.02)) is None     # -14 % +- 3 x 2 % reaches -8 %
    assert "is 0.5 x the device file's" in far_from_nominal(d, S0 * 0.5, np.full(3, 0.02))


def test_the_header_says_what_the_method_did_not_fit():
    """A header from `--method offset` or `gain` carried the tables without a word that the
    sensitivities (or their directions) were held at the device file's nominal, not fitted:
    the calibration's `fit.not_fitted_note` goes into the opening comment as a NOTE; `full`
    fits everything and has none."""
    dev = default_triad()
    rec = simulate(dev, "static_poses", seed=4)
    for method in ("offset", "gain", "full"):
        cal = calibrate_recordings(dev, [rec], method=method)
        text = calibration_header(dev, cal)
        comment = " ".join(text[:text.index("*/")].split())
        if method == "full":
            assert "NOTE" not in comment
        else:
            assert f"NOTE (accelcal calibrate): the '{method}' model" in comment, comment
            assert "not fitted" in comment
