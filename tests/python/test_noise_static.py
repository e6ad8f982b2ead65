"""Noise from the data, static intervals as a user sees them, clipped readings set aside
(issue 13, items 1-3), on recordings whose shape the detector did not choose: coloured
tremor, coarse quantization, instant steps, clipping inside the range."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.signal import lfilter
from scipy.stats import chi2
from scipy.spatial.transform import Rotation, Slerp

import accelcal as ac
from accelcal.calibrate import calibrate_recordings
from accelcal.readings.clipping import clip_levels
from accelcal.convert.formats import convert_file
from accelcal.io.device import default_device, default_triad
from accelcal.errors import InputError
from accelcal.readings.noise import estimate_noise, noise_before_rounding, rounding_bias_var
from accelcal.io.recording import Recording
from accelcal.readings.static import detect_static, poses_from_recording
from accelcal.readings.steps import logger_steps
from accelcal.convert.xsens import load_xsens
from shared_data import XSENS_ACC
import indep_model as im

G = 9.80665


def bare(dev):
    """The device as a file with only the contract's fields has it (no noise_mps2)."""
    return dataclasses.replace(dev, noise_mps2=0.0)


def recording(raw, rate, pose=None, source="x.csv"):
    n = raw.shape[0]
    nan = np.full((n, 3), np.nan)
    return Recording(t=np.arange(n) / rate, raw=np.asarray(raw, np.int64), f=nan, w=nan.copy(), dw=nan.copy(),
                     temp_c=np.full(n, np.nan), pose=np.full(n, -1) if pose is None else pose, source=source)


def tremor(rng, n, rate, hz=8.0):
    """Unit-variance coloured noise resonant near ``hz`` (an AR(2) process)."""
    r, th = 0.95, 2 * np.pi * min(hz, 0.4 * rate) / rate
    x = lfilter([1.0], [1.0, -2 * r * np.cos(th), r * r], rng.standard_normal((n, 3)), axis=0)
    return x / x.std(axis=0)


def hand_held(rng, P=60, hold=200, rate=100.0, k=None):
    """P random poses held ``hold`` samples each, joined by instant steps (no samples in
    between), with tremor whose size differs from pose to pose."""
    dev = bare(default_triad())
    k = dev.counts_per_mps2[0] if k is None else k
    F = Rotation.random(P, random_state=int(rng.integers(1 << 30))).apply([0.0, 0.0, G])
    f = np.repeat(F, hold, axis=0)
    amp = np.repeat(rng.uniform(0.02, 0.08, P), hold)[:, None]
    f = f + amp * tremor(rng, f.shape[0], rate) + 0.01 * rng.standard_normal(f.shape)
    raw = np.round(32768 + k * f).astype(np.int64)
    return dev, raw, np.repeat(np.arange(P), hold)


@pytest.mark.parametrize("rate", [50.0, 1000.0])
@pytest.mark.parametrize("noise_mps2", [0.002, 0.05])
def test_noise_estimate_follows_white_noise_with_motion_between(rate, noise_mps2):
    rng = np.random.default_rng(int(rate) + int(1e4 * noise_mps2))
    k = default_triad().counts_per_mps2[0]
    n = int(40 * rate)
    t = np.arange(n) / rate
    moving = (t % 8.0) > 5.0                                 # 5 s rest, 3 s motion
    f = np.column_stack([np.zeros(n), np.zeros(n), np.full(n, G)])
    f[moving] += 3.0 * np.sin(2 * np.pi * 1.3 * t[moving])[:, None] * np.array([1.0, 0.5, -0.3])
    raw = np.round(32768 + k * (f + noise_mps2 * rng.standard_normal((n, 3)))).astype(np.int64)
    est = estimate_noise(raw, int(0.5 * rate))
    truth = np.sqrt((noise_mps2 * k) ** 2 + 1 / 12)
    np.testing.assert_allclose(est, truth, rtol=0.1)


def test_noise_of_a_dither_between_coarse_codes_is_about_the_step():
    rng = np.random.default_rng(2)
    for q in (2, 8, 34, 64):
        raw = (q * np.round((32768 + 0.3 * q * rng.standard_normal((3000, 3))) / q)).astype(np.int64)
        est = estimate_noise(raw, 50)
        assert np.all(est >= q / np.sqrt(12) - 1e-9) and np.all(est <= 0.6 * q), (q, est)


@pytest.mark.parametrize("make", [default_device, default_triad])
@pytest.mark.parametrize("step", [2, 8, 16, 34, 64])
def test_labelled_jig_with_coarse_quantization_is_calibrated(make, step):
    dev = make()
    rec = ac.simulate(dev, "static_poses", effects=[f"quantization:step={step}"], seed=3)
    cal = calibrate_recordings(bare(dev), [rec])
    assert "set_aside" not in cal.extra
    # a reading stuck between codes is biased by up to half a step, no more
    assert np.max(np.abs(cal.offsets - dev.zero_counts)) <= step / 2 + 1.0


@pytest.mark.parametrize("sigma", [0.0, 0.05, 0.15, 0.3, 0.6])
def test_rounding_bias_of_a_mean_follows_a_monte_carlo(sigma):
    """The bias rounding leaves in a pose's mean, and the noise before the rounding from the
    rounded readings' std, against a brute-force draw (levels uniform between codes)."""
    rng = np.random.default_rng(int(100 * sigma))
    x = rng.uniform(0, 1, 3000)
    r = np.round(x[:, None] + sigma * rng.standard_normal((3000, 2000)))
    # the means' scatter less the part the draw's noise leaves in a mean of 2000 readings
    bias_var = float(np.var(r.mean(axis=1) - x) - np.mean(r.var(axis=1, ddof=1)) / 2000)
    assert abs(float(rounding_bias_var(sigma, 1.0)) - bias_var) <= 0.05 * abs(bias_var) + 2e-5
    s = np.sqrt(np.mean(r.var(axis=1, ddof=1)))
    assert abs(float(noise_before_rounding(s, 1.0)) - sigma) <= 0.02
    # a coarse step scales both
    assert np.isclose(float(rounding_bias_var(64 * sigma, 64.0)), 64 ** 2 * float(rounding_bias_var(sigma, 1.0)))


def sub_code_jig(q, sigma, k, lo, hi, seed=4):
    """26 known poses (faces, edges, corners) held 3 s at 100 Hz, read with a gain and offset
    error, noise ``sigma`` counts before a rounding to step ``q``: each pose on one or two codes."""
    rng = np.random.default_rng(seed)
    ups = [s * e for e in np.eye(3) for s in (1, -1)]
    ups += [np.array(v) / np.linalg.norm(v) for v in ((1, 1, 0), (1, -1, 0), (-1, 1, 0), (-1, -1, 0), (1, 0, 1),
                                                      (1, 0, -1), (-1, 0, 1), (-1, 0, -1), (0, 1, 1), (0, 1, -1),
                                                      (0, -1, 1), (0, -1, -1))]
    ups += [np.array([x, y, z]) / np.sqrt(3) for x in (1, -1) for y in (1, -1) for z in (1, -1)]
    f = np.repeat(G * np.array(ups), 300, axis=0)
    S = k * (np.diag([1.01, 0.995, 1.02]) + np.array([[0, .002, -.001], [.001, 0, .003], [-.002, .001, 0]]))
    x = f @ S.T + [4.6, -3.1, 7.7] + sigma * rng.standard_normal(f.shape)
    raw = np.clip(q * np.round(x / q), lo, hi).astype(np.int64)
    pose = np.repeat(np.arange(26), 300)
    n = raw.shape[0]
    rec = Recording(t=np.arange(n) / 100.0, raw=raw, f=f, w=np.zeros((n, 3)), dw=np.zeros((n, 3)),
                    temp_c=np.full(n, np.nan), pose=pose, source="jig.csv")
    dev = dataclasses.replace(bare(default_triad()), raw_min=lo, raw_max=hi, counts_per_mps2=np.full(3, k),
                              zero_counts=np.zeros(3))
    return dev, rec


@pytest.mark.parametrize("q,sigma,k,lo,hi", [(1, 0.05, 256 / G, -512, 511),       # a 10-bit chip: 0.002 m/s^2
                                             (64, 0.3, 16384 / G, -32768, 32767)])  # 64-count steps, no dither
def test_poses_on_one_code_are_weighted_by_their_rounding(q, sigma, k, lo, hi):
    """Where the noise before the rounding is well below the code step, each pose sits on one
    code and its mean is off by up to half a step however long it is held: the pose means'
    standard error is the rounding's (q/sqrt(12) rms), not the noise over sqrt(n). chi2/dof had
    been 112 (the 10-bit chip) and 8.9e4 (64-count steps, blamed on a hand's tremor)."""
    dev, rec = sub_code_jig(q, sigma, k, lo, hi)
    cal = calibrate_recordings(dev, [rec])
    fit = cal.extra["fit"]
    assert fit["chi2"] / fit["dof"] <= chi2.ppf(0.999, fit["dof"]) / fit["dof"]
    assert not any("tremor" in w for w in cal.extra.get("warnings", []))


def test_instant_steps_split_static_blocks_and_tremor_is_not_motion():
    rng = np.random.default_rng(5)
    dev, raw, lab = hand_held(rng)
    unl = recording(raw, 100.0)
    iv = detect_static(unl, dev)
    P = lab.max() + 1
    assert len(iv) >= 0.95 * P
    # every interval lies inside one block: no two poses merged
    assert all(lab[a] == lab[b - 1] for a, b in iv)
    cal = calibrate_recordings(dev, [unl], method="jigfree")
    assert len(cal.poses_used) == len(iv)
    labelled = calibrate_recordings(dev, [recording(raw, 100.0, pose=lab)], method="jigfree")
    assert len(labelled.poses_used) == P


def test_mains_aliased_to_half_the_sampling_rate_is_not_motion():
    """50 Hz mains on a logger sampling at 100 Hz whose clock runs 0.02 % fast: the tone sits
    in the spectrum's last bin and swells and fades over tens of seconds.  The static poses
    between moves are still found (each one inside its pose, none merged), as without it."""
    rng = np.random.default_rng(3)
    dev = bare(default_triad())
    k = dev.counts_per_mps2[0]
    P, hold, move, rate = 20, 400, 100, 100.0
    F = Rotation.random(P, random_state=7).apply([0.0, 0.0, G])
    segs, lab = [], []
    for p in range(P):
        segs.append(np.repeat(F[p][None, :], hold, axis=0))
        lab += [p] * hold
        if p + 1 < P:
            a = np.linspace(0.0, 1.0, move)[:, None]
            segs.append((1 - a) * F[p] + a * F[p + 1])
            lab += [-1] * move
    f = np.concatenate(segs) + 0.01 * rng.standard_normal((len(lab), 3))
    t = np.arange(f.shape[0]) / (rate * 1.0002)
    tone = 0.3 * np.sin(2 * np.pi * 50.0 * t[:, None] + rng.uniform(0, 2 * np.pi, 3))   # m/s^2
    lab = np.asarray(lab)
    for with_tone in (False, True):
        raw = np.round(32768 + k * (f + (tone if with_tone else 0.0))).astype(np.int64)
        iv = detect_static(recording(raw, rate), dev)
        assert len(iv) == P, (with_tone, len(iv))
        # each interval inside one pose, up to the 2 samples at each end where the move has
        # not yet left the pose by more than the noise
        bad = [(a, b) for a, b in iv if not (lab[a + 2] >= 0 and lab[a + 2] == lab[b - 3])]
        assert not bad, (with_tone, bad)


@pytest.mark.parametrize("rate", [3.0, 12.0, 100.0])
def test_rows_pointing_in_unrelated_directions_are_no_rest(rate):
    """A file of pose means in random order (Magneto's input shuffled: 178 orientations, one a
    row), no noise stated.  It has no rest and no motion apart, so its noise estimate was the
    rows' own scatter, and rows tens of degrees apart within twice that were one "pose" (the
    real file: 4 of them at 12 Hz, an offset-only fit at 3 Hz).  That noise, 10-60 % of |f|, is
    no still sensor's: no interval, and the error says why.  A sensor whose noise is 2.5 % of
    |f| (beyond any real rest: 0.1-1 %, a robot arm's quiet windows 1.9 %) keeps its poses."""
    dev = bare(default_triad())
    k = dev.counts_per_mps2[0]
    rng = np.random.default_rng(int(rate))
    F = Rotation.random(178, random_state=int(rate)).apply([0.0, 0.0, G])
    rows = np.round(32768 + k * (F + 0.02 * rng.standard_normal(F.shape))).astype(np.int64)
    rec = recording(rows, rate)
    dev_r = dataclasses.replace(dev, sample_rate_hz=rate)
    assert detect_static(rec, dev_r) == []
    with pytest.raises(InputError, match="beyond a still sensor's 5 %: its readings scatter throughout"):
        poses_from_recording(rec, dev_r)
    # 12 poses of 2 s at 100 Hz joined by eased moves, white noise 0.25 m/s^2 (2.5 % of |f|)
    f = eased_poses(3, pause=0)
    raw = np.round(32768 + k * (f + 0.25 * rng.standard_normal(f.shape))).astype(np.int64)
    assert len(detect_static(recording(raw, 100.0), dev)) == 12


def test_readings_without_gravity_are_named_so_where_no_rest_is_found():
    """A phone app's user acceleration (Sensor Logger's Accelerometer.csv: gravity taken out, a hand's
    motion of 0.3 g throughout) has no rest; calibrate's error had named only its scatter, and
    diagnose's only the missing reference.  Both now say that its median |f| is far below 1 g and
    which export holds gravity; the same motion with gravity in gets no such clause."""
    dev = bare(default_triad())
    k = dev.counts_per_mps2[0]
    rng = np.random.default_rng(5)
    a = lfilter([0.02], [1.0, -0.98], rng.standard_normal((3000, 3)), axis=0)
    a *= 0.3 * G / np.median(np.linalg.norm(a, axis=1))
    for f, said in ((a, True), (a + [0.0, 0.0, G], False)):
        rows = np.round(32768 + k * (f + 0.01 * rng.standard_normal(f.shape))).astype(np.int64)
        with pytest.raises(InputError, match="no static pose found") as e:
            poses_from_recording(recording(rows, 100.0), dev)
        assert ("gravity looks removed" in str(e.value)) == said, str(e.value)
        assert ("TotalAcceleration.csv" in str(e.value)) == said
        with pytest.raises(InputError, match="no reference to diagnose against") as e:   # diagnose alike
            ac.diagnose(dev, ac.Calibration.nominal(dev), [recording(rows, 100.0)])
        assert ("gravity looks removed" in str(e.value)) == said, str(e.value)


def test_a_mains_line_beyond_a_still_sensors_share_keeps_the_rests():
    """A hand-held session at 200 Hz with 50 Hz mains picked up at 0.6 m/s^2 rms (6 % of |f|: the
    independent benchmark's strongest line) had no rest by REST_NOISE_MAX, and diagnose refused
    it.  A line averages out within a window and the rests hold their means: its 12 poses are
    found; shuffled rows (white scatter) stay no rest (above)."""
    dev = dataclasses.replace(bare(default_triad()), sample_rate_hz=200.0)
    k = dev.counts_per_mps2[0]
    faces = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1],
             [1, 1, 0], [0, 1, 1], [1, 0, 1], [-1, 1, 0], [0, -1, 1], [-1, 0, -1]]   # 60-180 deg apart in turn
    F = G * np.array(faces, float) / np.linalg.norm(faces, axis=1)[:, None]
    s = np.linspace(0.0, 1.0, 100)[:, None]
    segs = []
    for i in range(11):
        segs += [np.repeat(F[i][None], 400, 0), F[i] + (F[i + 1] - F[i]) * (3 * s ** 2 - 2 * s ** 3)]
    f = np.concatenate(segs + [np.repeat(F[11][None], 400, 0)])
    t = np.arange(f.shape[0]) / 200.0
    line = 0.6 * np.sqrt(2) * np.sin(2 * np.pi * 50.0 * t + 0.3)[:, None] * np.array([0.5, 1.0, 0.7])
    rng = np.random.default_rng(8)
    raw = np.round(32768 + k * (f + line + 0.02 * rng.standard_normal(f.shape))).astype(np.int64)
    assert len(detect_static(recording(raw, 200.0), dev)) == 12


def eased_poses(seed, pause):
    """f (m/s^2) of 12 random poses held 2 s at 100 Hz, joined by moves eased over 0.5 s to
    the half-way direction, held there ``pause`` samples, and eased over 0.5 s on."""
    F = Rotation.random(12, random_state=seed).apply([0.0, 0.0, G])
    s = np.linspace(0.0, 1.0, 50)[:, None]
    ease = 3 * s ** 2 - 2 * s ** 3
    segs = []
    for i in range(11):
        mid = 0.5 * (F[i] + F[i + 1])
        segs += [np.repeat(F[i][None], 200, 0), F[i] + (mid - F[i]) * ease, np.repeat(mid[None], pause, 0),
                 mid + (F[i + 1] - mid) * ease]
    return np.concatenate(segs + [np.repeat(F[11][None], 200, 0)])


def test_static_blocks_shorter_than_the_minimum_hold_are_poses_where_instant_steps_join_them():
    """A logger that records only static blocks (CK-Explorer's acc_log.csv: 160 blocks of
    100 samples, no time column) joins its poses by instant steps: a block shorter than
    MIN_POSE_S is a pose, as no motion touches it.  A pause of the same length inside a
    movement is not (the window test sees a block that holds two windows)."""
    rng = np.random.default_rng(11)
    dev, raw, lab = hand_held(rng, P=60, hold=int(0.75 * 100))
    iv = detect_static(recording(raw, 100.0), dev)
    assert len(iv) >= 0.5 * 60                      # none of them before
    assert all(lab[a] == lab[b - 1] for a, b in iv)
    # 12 poses of 2 s joined by 1 s moves that pause for 0.6 s half-way
    f = eased_poses(3, pause=60)
    f = f + 0.02 * rng.standard_normal(f.shape)
    iv = detect_static(recording(np.round(32768 + dev.counts_per_mps2[0] * f).astype(np.int64), 100.0), dev)
    assert len(iv) == 12
    assert min(b - a for a, b in iv) >= 200


@pytest.mark.parametrize("seed,hold", [(100, 100), (101, 100), (102, 75)])
def test_a_logger_of_static_blocks_gives_every_block_however_the_hand_trembles(seed, hold):
    """A logger that records only static blocks joined by instant steps, with tremor 2-8 x
    the white noise that differs from pose to pose (CK-Explorer's acc_log.csv: 64 of its 160
    blocks were found at 100 Hz, tremor peaks cutting the ends and every window of 28 blocks
    over the threshold).  Its large changes are nearly all isolated steps, so it is read as
    blocks: each one whose mean holds still is a pose, to the sample (70-75 of 80 before)."""
    rng = np.random.default_rng(seed)
    dev, raw, lab = hand_held(rng, P=80, hold=hold)
    iv = detect_static(recording(raw, 100.0), dev)
    assert iv == [(p * hold, (p + 1) * hold) for p in range(80)]


def test_motions_between_poses_are_no_logger_of_blocks(shared_data):
    """Recordings with motions between their poses (the real MPU-6050 and Xsens ones, and
    poses joined by eased moves) make runs of large changes, not isolated steps."""
    dev = bare(default_triad())
    f = eased_poses(4, pause=0)
    raw = np.round(32768 + dev.counts_per_mps2[0] * (f + 0.02 * np.random.default_rng(4).standard_normal(f.shape)))
    raw = raw.astype(np.int64)
    assert logger_steps(raw, estimate_noise(raw, 50), 50) is None
    mpu = convert_file(shared_data / "mpu6050_tomisuarez" / "example_data_calibration.csv.gz", scale=None).recording
    _, xs = load_xsens(shared_data.joinpath(*XSENS_ACC))
    # the independent model's hand-held session at 50 Hz and 0.047 m/s^2 whose quick moves peak in
    # isolated large changes (18 of 36 passed for steps before their sides' spread was asked)
    quick = im.make_handheld(["saturation"], 456036)["recordings"][0]
    for rec in (mpu, xs, quick):
        raw = np.asarray(rec.raw)
        w = int(round(0.5 / float(np.median(np.diff(rec.t)))))      # 0.5 s
        assert logger_steps(raw, estimate_noise(raw, w), w) is None


def test_a_block_that_spans_a_smooth_turn_is_not_one_pose():
    """26 poses of a 10-bit chip at 50 Hz (6 faces, 12 edges, 8 corners) held 3 s, joined by
    1.5 s turns with 0.3 m/s^2 of jerk: smooth ones, except that a 180 deg turn flips f at once
    (a tester's generator did so). The flips are isolated steps, so the recording looked like a
    logger's blocks, and each block then spanned the smooth turns: 8 intervals, several holding
    3-4 poses and the turns between them, the 'offset' model only. A block that holds the window
    test's intervals at different levels is a motion."""
    dev = bare(default_triad())
    rate, k = 50.0, 256 / G
    dev = dataclasses.replace(dev, raw_min=-512, raw_max=511, counts_per_mps2=np.full(3, k),
                              zero_counts=np.zeros(3))
    faces = [s * e for e in np.eye(3) for s in (1, -1)]
    edges = [np.array(v) / np.sqrt(2) for v in ((1, 1, 0), (1, -1, 0), (-1, 1, 0), (-1, -1, 0), (1, 0, 1),
                                              (1, 0, -1), (-1, 0, 1), (-1, 0, -1), (0, 1, 1), (0, 1, -1),
                                              (0, -1, 1), (0, -1, -1))]
    corners = [np.array([x, y, z]) / np.sqrt(3) for x in (1, -1) for y in (1, -1) for z in (1, -1)]
    ups = faces + edges + corners
    jerk, noise = np.random.default_rng(2), np.random.default_rng(3)
    s = 0.5 - 0.5 * np.cos(np.linspace(0, np.pi, 77)[1:-1])[:, None]
    segs, lab = [], []
    for p, u in enumerate(ups):
        if p:
            w = ups[p - 1] * (1 - s) + u * s          # through 0 (an instant flip) where u = -previous
            segs.append(G * w / np.linalg.norm(w, axis=1)[:, None] + jerk.normal(0, 0.3, (75, 3)))
            lab.append(np.full(75, -1))
        segs.append(np.tile(G * u, (150, 1)))
        lab.append(np.full(150, p))
    f, lab = np.concatenate(segs), np.concatenate(lab)
    S = k * (np.diag([1.01, 0.995, 1.02]) + np.array([[0, .002, -.001], [.001, 0, .003], [-.002, .001, 0]]))
    raw = np.clip(np.round(f @ S.T + [4.6, -3.1, 7.7] + noise.normal(0, 0.05 * k, f.shape)), -512, 511)
    raw = raw.astype(np.int64)
    iv = detect_static(recording(raw, rate), dev)
    assert len(iv) == 26                                 # 8 before
    held = [np.unique(lab[a:b][lab[a:b] >= 0]) for a, b in iv]
    # one pose each (with at most the half of a flip's turn that stays at the pose's f)
    assert [h.tolist() for h in held] == [[p] for p in range(26)]


def test_labelled_pose_with_strong_tremor_is_not_motion_but_a_slow_turn_is():
    """One labelled pose sways at 2 Hz four times as hard as the others shake (its eighths'
    means swing with it, as in CK-Explorer's hand-held blocks): it is a pose (refused
    before).  A slow 8 deg turn across a pose of ordinary tremor moves its eighths' means by
    many times what each eighth varies within: refused."""
    rng = np.random.default_rng(12)
    dev, raw, lab = hand_held(rng, P=20)
    k = dev.counts_per_mps2[0]
    shaky = raw.copy()
    idx = np.flatnonzero(lab == 5)
    shaky[idx] += np.round(0.2 * k * tremor(rng, idx.size, 100.0, hz=2.0)).astype(np.int64)  # others: 0.02-0.08
    cal = calibrate_recordings(dev, [recording(shaky, 100.0, pose=lab)], method="jigfree")
    assert len(cal.poses_used) == 20
    turned = raw.copy()
    idx = np.flatnonzero(lab == 7)
    ang = np.radians(np.linspace(0.0, 8.0, idx.size))
    turned[idx, 0] += np.round(k * G * np.sin(ang)).astype(np.int64)
    with pytest.raises(InputError, match=r"pose 7 .* is labelled static but moves: on raw_0 its mean moves"):
        calibrate_recordings(dev, [recording(turned, 100.0, pose=lab, source="slow.csv")], method="jigfree")


def test_labelled_pose_that_turns_is_refused_naming_label_time_and_channel():
    rng = np.random.default_rng(6)
    dev, raw, lab = hand_held(rng, P=20)
    k = dev.counts_per_mps2[0]
    idx = np.flatnonzero(lab == 7)
    turn = np.round(k * G * np.array([np.sin(np.radians(10)), 0, np.cos(np.radians(10)) - 1])).astype(np.int64)
    raw[idx[len(idx) // 2:]] += turn                    # the hand turns it by 10 deg half-way
    rec = recording(raw, 100.0, pose=lab, source="turned.csv")
    with pytest.raises(InputError, match=r"^turned\.csv: column pose: pose 7 \(t = 14 \.\. 15\.99 s, samples "
                                         r"1400\.\.1599\) is labelled static but moves: on raw_0 its mean moves"):
        calibrate_recordings(dev, [rec], method="jigfree")


def test_unlabelled_data_is_never_called_labelled():
    rng = np.random.default_rng(7)
    dev, raw, lab = hand_held(rng, P=20)
    raw[lab == 3] += np.linspace(0, 400, np.count_nonzero(lab == 3)).astype(np.int64)[:, None]   # slow slide
    try:
        calibrate_recordings(dev, [recording(raw, 100.0)], method="jigfree")
    except InputError as e:              # pragma: no cover - only its wording is checked
        assert "labelled" not in str(e)


def test_clip_levels_inside_the_range_are_found_and_a_coarse_pose_is_not_a_clip():
    rng = np.random.default_rng(8)
    dev, raw, lab = hand_held(rng, P=40)
    k = dev.counts_per_mps2[0]
    top, bot = int(32768 + 0.93 * G * k), int(32768 - 0.93 * G * k)
    clipped = np.clip(raw, bot, top)
    noise = estimate_noise(clipped, 50)
    lv = clip_levels(clipped, dev, noise, 50)
    hit_top = (raw >= top).any(axis=0)
    hit_bot = (raw <= bot).any(axis=0)
    np.testing.assert_array_equal(lv.inside_hi, hit_top & ((raw >= top).sum(axis=0) >= 10))
    assert np.all(lv.hi[lv.inside_hi] == top) and np.all(lv.lo[lv.inside_lo] == bot)
    assert lv.inside_hi.any() and lv.inside_lo.any() and np.all(lv.inside_lo <= hit_bot)
    # a coarsely quantised channel whose pose sits on one code: no clip claimed
    q = 64 * np.round(np.asarray(raw, float) / 64)
    assert not clip_levels(q.astype(np.int64), dev, estimate_noise(q.astype(np.int64), 50), 50).any_inside()


def quiet_session(rng, rate=200.0, k=40.0, pulse=8.0, up_x=False, push_z=False, noise=0.2):
    """A triad quieter than one code (k = 40 counts per m/s^2, ``noise`` counts, +g on a code's
    centre): 12 rests of
    1.5 s joined by 0.75 s turns, each turn with a linear push of ``pulse`` m/s^2 along a
    random direction.  ``up_x``: the first rest holds +x up (channel 0 at +g, its largest
    reading, with no pushes).  ``push_z``: a 2 s push along x between two z-up rests (channel 2
    steady at +g throughout)."""
    rest, turn = int(1.5 * rate), int(0.75 * rate)
    R = Rotation.random(12, random_state=int(rng.integers(1 << 30)))
    if up_x:
        R = Rotation.concatenate([Rotation.align_vectors([[0, 0, 1.0]], [[1.0, 0, 0]])[0], R[1:]])
    parts = []
    for p in range(12):
        parts.append(np.repeat(R[p].inv().apply([0.0, 0.0, G])[None], rest, axis=0))
        if p < 11:
            s = np.linspace(0.0, 1.0, turn)
            key = Rotation.concatenate([R[p], R[p + 1]])
            Rt = Slerp([0.0, 1.0], key)(s)
            push = pulse * np.sin(np.pi * s)[:, None] * rng.normal(size=3) / np.sqrt(3)
            parts.append(Rt.inv().apply([0.0, 0.0, G]) + push)
    if push_z:
        m = int(2 * rate)
        s = np.linspace(0.0, 1.0, m)
        zpush = np.column_stack([3.0 * np.sin(2 * np.pi * s), np.zeros(m), np.full(m, G)])
        z = np.repeat([[0.0, 0.0, G]], rest, axis=0)
        parts += [z, zpush, z]
    f = np.concatenate(parts)
    zero = 32768 - (k * G - round(k * G))
    raw = np.round(zero + k * f + noise * rng.standard_normal(f.shape)).astype(np.int64)
    dev = bare(default_triad())
    return dev, raw, int(0.5 * rate)


def test_a_clip_that_only_the_motion_reaches_on_a_channel_quieter_than_a_code():
    """On channels quieter than one code a pose sits on one code, which looks like a pile at
    the extreme; it is a clip only where the device moves throughout its hold and the channel
    comes to it from far (the independent bench's hand-held clip reached only in motion, on a
    channel with 0.5 counts of noise, had 504 readings at its level and was not claimed)."""
    rng = np.random.default_rng(21)
    dev, raw, w = quiet_session(rng)
    rests = np.zeros(raw.shape[0], bool)
    for p in range(12):
        rests[p * 450:p * 450 + 300] = True
    level = int(raw[rests, 0].max()) + 40                  # 1 m/s^2 above every rest
    clipped = raw.copy()
    clipped[:, 0] = np.minimum(raw[:, 0], level)
    n_clip = int(np.count_nonzero(raw[:, 0] >= level))
    assert n_clip >= 20
    noise = estimate_noise(clipped, w)
    assert noise[0] < 1.0
    lv = clip_levels(clipped, dev, noise, w)
    assert lv.inside_hi[0] and lv.hi[0] == level
    assert int(np.count_nonzero(lv.mask(clipped)[:, 0])) == n_clip
    assert not clip_levels(raw, dev, estimate_noise(raw, w), w).any_inside()
    # a rest on one code at the channel's largest reading: every channel rests there
    dev, raw, w = quiet_session(np.random.default_rng(22), pulse=0.0, up_x=True, noise=0.1)
    assert int(np.count_nonzero(raw[:, 0] == raw[:, 0].max())) >= 100
    assert not clip_levels(raw, dev, estimate_noise(raw, w), w).inside_hi[0]
    # channel 2 steady at +g from a rest on through a push across its axis: the rest shows it
    dev, raw, w = quiet_session(np.random.default_rng(23), pulse=0.0, push_z=True, noise=0.1)
    assert int(np.count_nonzero(raw[:, 2] == raw[:, 2].max())) >= 500
    assert not clip_levels(raw, dev, estimate_noise(raw, w), w).inside_hi[2]


def test_clipped_poses_are_set_aside_and_the_rest_calibrated():
    rng = np.random.default_rng(9)
    dev, raw, lab = hand_held(rng, P=40)
    k = dev.counts_per_mps2[0]
    top, bot = int(32768 + 0.93 * G * k), int(32768 - 0.93 * G * k)
    rec = recording(np.clip(raw, bot, top), 100.0)
    ps = poses_from_recording(rec, dev)
    hit = {int(lab[int(round(d["t_start"] * 100))]) for d in ps.set_aside}
    truly = {p for p in range(40) if ((raw[lab == p] >= top) | (raw[lab == p] <= bot)).any()}
    assert hit and hit <= truly
    cal = calibrate_recordings(dev, [rec], method="jigfree")
    assert len(cal.extra["set_aside"]) == len(ps.set_aside)
    assert np.max(np.abs(cal.offsets - 32768)) < 5.0
