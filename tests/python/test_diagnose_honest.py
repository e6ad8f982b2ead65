"""An honest verdict (issue 13): effects the data cannot tell apart are named as such, a
gap no effect explains is reported as unexplained, clipped readings are evidence.

The six-pose sessions here are written with numpy from the contract's sensor equation
alone (a 16-bit triad, raw = zero + k f + noise), not by the package's simulator."""
import importlib
import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from accelcal.calibrate import calibrate_recordings
from accelcal.io.calibration import Calibration
from accelcal.io.device import Device
from accelcal.diagnose import diagnose
from accelcal.effects import EFFECTS
from accelcal.io.recording import recording_from_arrays
from accelcal.report import summary_text
from accelcal.convert.xsens import load_xsens
import diag_datasets as B

G = 9.80665
K = 16384 / G          # counts per m/s^2 (+-2 g)
RATE = 100.0
AXES = [(0, 1), (0, -1), (1, 1), (1, -1), (2, 1), (2, -1)]


def triad():
    return Device(name="triad", sample_rate_hz=RATE, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, K), zero_counts=np.zeros(3))


def six_poses(seed, *, tilt_deg=0.0, drift_mps2=0.0, repeat_first=False, hold_s=4.0, noise=0.01,
              sensor=np.eye(3), bias_mps2=np.zeros(3)):
    """Poses +-x, +-y, +-z (each held once; the first repeated at the end with
    ``repeat_first``), stated f exact; the true f tilted by ``tilt_deg`` per pose (a
    hand-placed table), the offsets ramping by ``drift_mps2`` over the session; the sensor
    reads ``sensor @ f + bias_mps2`` (its own gain, misalignment and offset)."""
    rng = np.random.default_rng(seed)
    order = AXES + ([AXES[0]] if repeat_first else [])
    n1 = int(hold_s * RATE)
    t_all, raw_all, f_all, pose_all = [], [], [], []
    T = len(order) * (hold_s + 2.0)
    slope = drift_mps2 * rng.choice([-1.0, 1.0], 3) / T
    for p, (ax, sgn) in enumerate(order):
        t = p * (hold_s + 2.0) + np.arange(n1) / RATE          # 2 s gaps (the turn is not recorded)
        f = np.zeros(3)
        f[ax] = sgn * G
        rot = Rotation.from_rotvec(np.radians(tilt_deg) * rng.normal(size=3) / np.sqrt(3))
        ftrue = rot.apply(f)
        y = (sensor @ ftrue + bias_mps2)[None, :] + slope[None, :] * t[:, None] + rng.normal(0, noise, (n1, 3))
        raw_all.append(np.round(y * K).astype(np.int64))
        t_all.append(t)
        f_all.append(np.tile(f, (n1, 1)))
        pose_all.append(np.full(n1, p))
    rec = recording_from_arrays(np.concatenate(t_all), np.vstack(raw_all), f=np.vstack(f_all),
                                pose=np.concatenate(pose_all))
    rec.source = f"six poses seed {seed}"
    return rec


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_six_poses_tilt_is_not_called_a_drift(seed):
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(seed, tilt_deg=1.0)])
    assert res["verdict"] == "pose_error"
    # a drift that stepped during the (unrecorded) turns cannot be excluded: listed when it is a rival;
    # on the six faces a tilt of each pose is also a misalignment of the axes to first order
    assert "misalignment" in res["ambiguous_with"]
    assert set(res["ambiguous_with"]) <= {"bias_drift", "misalignment"}
    assert not EFFECTS[res["verdict"]].time_dependent
    assert "bias_drift" not in res["model"]["effects"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_six_poses_sensor_errors_are_not_tilts_of_each_pose(seed):
    """The sensor's own errors on six poses held once (a real MPU-6050 session against its
    nominal calibration: offsets of 39 / -13 / 45 mg, the axes turned by 3 deg, z's gain
    +1.7 %), placed by hand to 0.2 deg.  A tilt of each pose takes the side channels' offsets
    and the turn (two angles a pose): it had been the verdict, "poses off by up to 5.6 deg",
    with a square term standing in for the offset.  The calibration's terms together shrink
    the gap as far with fewer parameters: they are the model, with the sizes the sensor has."""
    d = triad()
    turn = Rotation.from_rotvec(np.radians([0.0, 3.0, 0.0])).as_matrix()
    sensor = np.diag([1.0, 1.0, 1.017]) @ turn
    bias = np.array([0.039, -0.013, 0.045]) * G
    res = diagnose(d, Calibration.nominal(d), [six_poses(seed, tilt_deg=0.2, sensor=sensor, bias_mps2=bias)])
    assert res["verdict"] != "pose_error"
    assert set(res["model"]["effects"]) == {"offset", "misalignment", "gain"}
    p = res["model"]["params"]
    # the offset in counts at the readings (the sensor reads bias + (sensor - I) f: at f = 0 the bias)
    np.testing.assert_allclose(np.asarray(p["offset"]["db"], float) / K, bias, atol=0.002 * G)
    assert p["gain"]["scale"][2] == pytest.approx(0.017, abs=0.002)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_six_poses_drift_is_flagged_as_ambiguous(seed):
    """Each pose held once, a drift too slow to show within a pose (0.01 m/s^2 over 36 s:
    ~1 count in a 4 s pose against 17 counts of noise): it takes each pose's level as a tilt
    would; the verdict is not the drift, and the JSON names it as what the data cannot tell
    apart, with the pose that would."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(seed, drift_mps2=0.01)])
    assert res["verdict"] != "bias_drift" and not EFFECTS[res["verdict"]].time_dependent
    assert "bias_drift" in res["ambiguous_with"]
    assert "repeated at the end" in res["separate_by"]
    assert "bias_drift" not in res["model"]["effects"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_repeated_pose_lets_the_drift_be_named(seed):
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(seed, drift_mps2=0.01, repeat_first=True)])
    assert res["verdict"] == "bias_drift"
    assert res["ambiguous_with"] == [] and res["separate_by"] == ""


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_drift_that_shows_within_the_poses_is_named(seed):
    """0.05 m/s^2 over 36 s changes a 4 s pose by ~7 counts: the slopes within the poses bear
    the drift out, so six poses held once are enough."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(seed, drift_mps2=0.05)])
    assert res["verdict"] == "bias_drift"
    within = res["effects"][0]["contest"]["rivals"]["pose_error"]["within_poses"]
    assert "change by 0.9" in within or "change by 1.0" in within
    # found over 34 s of data: quoted per second, not per hour
    assert "m/s^2 per s, over 3" in res["effects"][0]["summary"]


@pytest.mark.parametrize("seed", [2, 3, 4])
def test_motion_excited_oscillation_is_unexplained(seed):
    """An oscillation at 0.3 fs on channel 0 while the body rotates (a resonance the table
    has no effect for): the verdict is unexplained, on channel 0, while moving."""
    ds = B.make_dataset("none", seed)
    dev = ds["device"]
    sig = float(np.sqrt(np.mean(dev.noise_counts() ** 2)))
    recs = []
    n_moving = 0
    for r in ds["recordings"]:
        raw = r.raw.astype(float)
        moving = np.linalg.norm(np.nan_to_num(r.w), axis=1) > 0.05
        n_moving += int(moving.sum())
        raw[:, 0] += np.where(moving, 5 * sig * np.sin(2 * np.pi * 0.3 * dev.sample_rate_hz * r.t), 0.0)
        recs.append(recording_from_arrays(r.t, np.round(raw).astype(np.int64), f=r.f, w=r.w, dw=r.dw, pose=r.pose,
                                          temp_c=r.temp_c))
    assert n_moving > 0
    res = diagnose(dev, ds["cal"], recs)
    assert res["verdict"] == "unexplained" and res["model"]["effects"] == []
    u = res["unexplained"]
    assert u["where"]["channels"] == [0] and u["where"]["regime"] != "static"
    assert u["fraction"] >= 0.1 and u["heldout_rms_left"] > 0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_clean_data_leaves_nothing_unexplained(seed):
    ds = B.make_dataset("none", seed)
    res = diagnose(ds["device"], ds["cal"], ds["recordings"])
    assert res["verdict"] == "none" and res["unexplained"] is None
    assert res["ambiguous_with"] == [] and res["separate_by"] == ""


# ---------------------------------------------------------------- real recordings

def test_xsens_clipped_inside_the_range_is_saturation(shared_data):
    """The real Xsens recording clipped at +-0.93 g on each axis (most poses do not clip):
    diagnosed, the clipped samples counted, the verdict saturation."""
    dev, rec = load_xsens(shared_data / "imu_tk_xsens" / "xsens_acc.txt.gz")
    cal = calibrate_recordings(dev, [rec], "jigfree")
    lvl = np.round(0.93 * G * dev.counts_per_mps2).astype(np.int64)
    z = dev.zero_counts.astype(np.int64)
    raw = np.clip(rec.raw.astype(np.int64), z - lvl, z + lvl)
    n_clip = (raw != rec.raw).sum(axis=0)
    res = diagnose(dev, cal, [recording_from_arrays(rec.t, raw)])
    assert res["verdict"] == "saturation"
    # the readings at the level and beyond it: at least those changed by the clip
    assert np.all(np.asarray(res["clipped_per_channel"]) >= n_clip)
    assert res["recordings"][0]["clipping"]["inside_range"] == [True, True, True]
    clean = diagnose(dev, cal, [rec])
    assert clean["verdict"] == "none" and clean["clipped_per_channel"] == [0, 0, 0]


def imucal_ferraris(base):
    """imucal's six-pose session as a recording with the stated f of each labelled pose."""
    d = np.genfromtxt(base / "example_ferraris_session.csv", delimiter=",", names=True)
    regions = json.loads((base / "example_ferraris_session_list.json").read_text())
    raw = np.round(np.column_stack([d["acc_x"], d["acc_y"], d["acc_z"]]) * 2048 / 9.81).astype(np.int64)
    n = len(raw)
    pose = np.full(n, -1)
    f = np.full((n, 3), np.nan)
    for k, name in enumerate(sorted(nm for nm in regions if not nm.endswith("rot"))):
        a, b = int(regions[name]["start"]), int(regions[name]["end"])
        pose[a:b] = k
        f[a:b] = 0.0
        f[a:b, "xyz".index(name[0])] = G if name[2] == "p" else -G
    dev = Device(name="imucal", sample_rate_hz=102.4, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 2048 / 9.81),
                 zero_counts=np.zeros(3))
    return dev, recording_from_arrays(np.arange(n) / 102.4, raw, f=f, pose=pose)


@pytest.mark.parametrize("method", ["full", "gain"])
def test_imucal_six_poses_tilt_or_drift_is_ambiguous(shared_data, method):
    """The issue's case: the hand-placed six-pose session was called bias_drift (20.9 %) over
    pose_error (18.1 %) with no word on ambiguity."""
    dev, rec = imucal_ferraris(shared_data / "imucal")
    res = diagnose(dev, calibrate_recordings(dev, [rec], method), [rec])
    assert res["verdict"] == "pose_error"
    assert "bias_drift" in res["ambiguous_with"] and "bias_drift" not in res["model"]["effects"]
    assert res["separate_by"].startswith("To tell pose_error from bias_drift")


def test_xsens_nominal_parameters_do_not_depend_on_the_start(shared_data):
    """Against its nominal calibration (offsets ~400 counts off, gains ~1 % off) the real
    Xsens recording's offset, gain and misalignment were -0.27..-0.42 % in gain where its
    jig-free calibration has +0.5..+1.1 %, and the gap stopped at twice the floor.
    Re-linearised, the parameters are those of the jig-free calibration and the gap reaches
    what that calibration leaves."""
    dev, rec = load_xsens(shared_data / "imu_tk_xsens" / "xsens_acc.txt.gz")
    nom = Calibration.nominal(dev)
    jf = calibrate_recordings(dev, [rec], "jigfree")
    res = diagnose(dev, nom, [rec])
    m = res["model"]
    assert m["effects"][:2] == ["offset", "gain"]
    gain_jf = np.linalg.norm(jf.sensitivity, axis=1) / np.linalg.norm(nom.sensitivity, axis=1) - 1
    assert np.max(np.abs(np.asarray(m["params"]["gain"]["scale"]) - gain_jf)) < 1e-3          # 0.1 % of gain
    assert np.max(np.abs(np.asarray(m["params"]["offset"]["db"]) - (jf.offsets - nom.offsets))) < 2.0   # counts
    own = diagnose(dev, jf, [rec])
    assert m["heldout_rms_after"] <= 1.02 * own["model"]["heldout_rms_after"]
    assert m["relinearised"]["converged"]


@pytest.mark.parametrize("seed", [2, 3, 5])
@pytest.mark.parametrize("kind", ["mains", "resonance"])
def test_a_tone_at_rest_is_unexplained(seed, kind):
    """A tone present at rest as much as in motion (mains pickup on every channel, or a
    ringing on channel 0 that decays after each knock) is in the within-segment scatter, so
    only the spectral-line test sees it: unexplained, with the line's frequency."""
    ds = B.make_dataset("none", seed)
    dev = ds["device"]
    fs = dev.sample_rate_hz
    sig = float(np.sqrt(np.mean(dev.noise_counts() ** 2)))
    recs = []
    for r in ds["recordings"]:
        raw = r.raw.astype(float)
        if kind == "mains":
            raw += 3 * sig * np.sin(2 * np.pi * 0.17 * fs * r.t)[:, None]
        else:
            raw[:, 0] += 6 * sig * np.sin(2 * np.pi * 0.38 * fs * r.t) * np.exp(-(r.t % 3.0) / 0.5)
        recs.append(recording_from_arrays(r.t, np.round(raw).astype(np.int64), f=r.f, w=r.w, dw=r.dw, pose=r.pose,
                                          temp_c=r.temp_c))
    res = diagnose(dev, ds["cal"], recs)
    u = res["unexplained"]
    assert res["verdict"] == "unexplained" and u is not None
    peak = 0.17 * fs if kind == "mains" else 0.38 * fs
    assert abs(u["lines"]["peak_hz"] - peak) <= 2 * fs / 64
    assert u["where"]["band"].startswith("a line at")
    if kind == "resonance":
        assert u["where"]["channels"] == [0]


def test_bands_a_recording_cannot_resolve_are_not_measurable():
    """Six 1 s poses with gaps between them: no run resolves 0.1-1 Hz (its lowest bin is 1 Hz),
    so that band is 'not measurable', not 0; the report says so."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(1, tilt_deg=1.0, hold_s=1.0)])
    bands = {b["label"]: b for b in res["where"]["frequency_bands"]}
    assert bands["0.1-1 Hz"]["measurable"] is False and bands["0.1-1 Hz"]["rms_counts"] is None
    assert bands["1-3 Hz"]["measurable"] is True and bands["1-3 Hz"]["rms_counts"] > 0
    assert "0.1-1 Hz: not measurable" in summary_text(res)


def test_separate_by_gives_the_hints_that_speak_to_the_pair():
    """A hint is given for the pair the data cannot tell apart: a gain's "each axis up and
    down" tells it from an offset, not from a bend (six face poses already hold each axis up
    and down); a drift's repeated pose, not an offset's up and down; a misalignment and a tilt
    of the jig each have a hint that tells them apart, and both are given."""
    separate_by = importlib.import_module("accelcal.diagnose.text").separate_by
    up_down = "both up and down"
    s = separate_by(EFFECTS, "gain", ["nonlinearity"])
    assert "45 deg" in s and up_down not in s
    s = separate_by(EFFECTS, "offset", ["bias_drift"])
    assert "repeated at the end" in s and up_down not in s
    s = separate_by(EFFECTS, "misalignment", ["pose_error"])
    assert "45 deg" in s and "re-placing" in s
    s = separate_by(EFFECTS, "offset", ["gain"])
    assert up_down in s
    for e in EFFECTS.values():
        assert set(e.tells_from) <= set(EFFECTS), e.name


def test_a_drift_over_several_recordings_quotes_the_time_they_cover():
    """Recordings are laid end to end with a gap between them that is no time the sensor was
    read: the drift's summary quotes the time the recordings cover (twelve 1 s poses had read
    "over 160 s of data")."""
    d = triad()
    rec = six_poses(1, drift_mps2=0.05)
    half = rec.pose < 3
    parts = [recording_from_arrays(rec.t[m], rec.raw[m], f=rec.f[m], pose=rec.pose[m]) for m in (half, ~half)]
    covered = sum(float(np.ptp(p.t)) + 1.0 / RATE for p in parts)
    res = diagnose(d, Calibration.nominal(d), parts)
    drift = next(e for e in res["effects"] if e["name"] == "bias_drift")
    said = float(drift["summary"].split("over ")[1].split(" s of data")[0])
    assert said == pytest.approx(covered, rel=0.01) and "s of data in 2 recordings" in drift["summary"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_poses_in_one_orientation_give_the_smallest_offset_and_say_so(seed):
    """A board put down seven times on a desk (z up, each within 1.4 deg), read jig-free against
    a nominal calibration whose z offset is 0.06 m/s^2 off: only |f| along z is seen.  The
    verdict's offset is that z offset, not -1.6 m/s^2 on y (the poses' small tilts had kept
    combinations that change 1e-6..6e-5 of their readings' change), and a note says the poses
    hold one orientation (it was given only under 6 poses).  (Tilts within 1.4 deg: the poses are
    one orientation within SAME_ORIENTATION_DEG.)"""
    rng = np.random.default_rng(seed)
    t_all, raw_all, pose_all = [], [], []
    for p in range(7):
        f = Rotation.from_rotvec(np.radians(1.0) * rng.uniform(-1, 1, 3) * [1, 1, 0]).apply([0.0, 0.0, G])
        t = p * 6.0 + np.arange(400) / RATE
        y = f[None, :] + [0.0, 0.0, 0.06] + rng.normal(0, 0.01, (400, 3))
        t_all.append(t)
        raw_all.append(np.round(y * K).astype(np.int64))
        pose_all.append(np.full(400, p))
    rec = recording_from_arrays(np.concatenate(t_all), np.vstack(raw_all), pose=np.concatenate(pose_all))
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [rec])
    # along z alone an offset and a gain (or a bend) change the readings alike
    assert res["verdict"] in ("offset", "gain") and res["ambiguous_with"]
    offset = next(e for e in res["effects"] if e["name"] == "offset")
    db = np.asarray(offset["params"]["db"]) / K                  # m/s^2
    assert db[2] == pytest.approx(0.06, abs=0.01) and np.all(np.abs(db[:2]) < 0.01), db
    assert any(n.startswith("only 1 distinct orientation(s) among 7 static pose(s)") for n in res["notes"])


def test_readings_on_a_grid_of_no_whole_count_are_named_as_such():
    """A logger that printed m/s^2 to two decimals (0.01 m/s^2 = 16.7 counts at +-2 g), each
    reading then rounded to a count: its codes fall unevenly mod 2..4, which had been noted as
    "missing or doubled codes ... a rescaled or differentially nonlinear ADC".  The note names
    the grid instead, within 0.1 %."""
    d = triad()
    rec = six_poses(4, noise=0.03)
    rec.raw = np.round(np.round(rec.raw / K, 2) * K).astype(np.int64)
    res = diagnose(d, Calibration.nominal(d), [rec])
    said = [n for n in res["notes"] if "sit on a grid of" in n]
    assert len(said) == 3 and not any("lowest bits are unevenly used" in n for n in res["notes"]), res["notes"]
    grid = float(said[0].split("grid of ")[1].split(" counts")[0])
    assert grid == pytest.approx(0.01 * K, rel=1e-3)


@pytest.mark.parametrize("factor, said", [(1.42, True), (1.10, False)])
def test_a_gain_beyond_any_chip_is_said_to_be_a_wrong_scale(factor, said):
    """A device file whose scale is 30 % low (convert's guess on a wrist watch whose z never
    pointed up) read as a +42 % gain of every channel, with no word that no chip is that far
    off; a 10 % gain is a chip's and gets none."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(1, sensor=factor * np.eye(3))])
    assert res["verdict"] == "gain"
    note = [n for n in res["notes"] if "beyond what a real chip differs from its nominal" in n]
    assert bool(note) == said, res["notes"]
    if said:
        assert "channel(s) 0, 1, 2" in note[0] and "+42 %" in note[0]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_drift_the_repeated_pose_rules_out_is_no_rival(seed):
    """An offset and a gain error on six poses with the first repeated at the end (a real tumble
    session holds -x three times and -z twice): a drift fitted over the poses takes part of the
    gain's pattern and was listed in ambiguous_with, "record a pose repeated at the end", though
    the repeated pose met its claim with -0.00 +- 0.00.  Ruled out by the data, it is no rival."""
    d = triad()
    rec = six_poses(seed, repeat_first=True, sensor=np.diag([1.0, 1.0, 1.005]),
                    bias_mps2=np.array([0.0, 0.0, 0.035 * G]), hold_s=10.0)
    res = diagnose(d, Calibration.nominal(d), [rec])
    assert res["verdict"] == "offset" and res["model"]["effects"] == ["offset", "gain"]
    # (a bend, square and cube, is an offset and a gain at +-g along the axes: since issue 33 a later
    # step's rivals are stated too, so the gain's nonlinearity may be listed; the drift may not)
    assert "bias_drift" not in res["ambiguous_with"] and "repeated" not in res["separate_by"]
    assert set(res["ambiguous_with"]) <= {"nonlinearity"}
    assert res["effects"][0]["contest"]["rivals"]["bias_drift"]["ruled_out"] is True


def test_the_report_says_what_is_left_unexplained_and_where_in_time(tmp_path):
    """A verdict 'unexplained' had its report open with "# Diagnosis: unexplained" and then say
    "**none**: no candidate explains ...", never saying what was left; its time bins read
    "6.727e+05-6.727e+05 s" for stamps since a boot.  A 31 Hz line on six poses stamped from
    t = 672,706 s: the report names the line and says the bins from the recording's start."""
    d = triad()
    rec = six_poses(1)
    rec.t = rec.t + 672706.0
    rec.raw = rec.raw + np.round(40 * np.sin(2 * np.pi * 31.0 * rec.t)[:, None]).astype(np.int64)
    res = diagnose(d, Calibration.nominal(d), [rec])
    text = summary_text(res)
    assert res["verdict"] == "unexplained" and "**none**" not in text
    said = text.split("## Unexplained")[1].split("\n\n")[1]
    assert float(said.split("A line at ")[1].split(" Hz")[0]) == pytest.approx(31.0, abs=0.5), said
    assert "e+05" not in text and "s from its start" in text


def _one_orientation(seed, short=0.027, noise=0.11, rate=256.0):
    """Three still stretches of a foot-worn triad in one orientation (z up, tilted by up to 4
    deg), |f| 2.7 % short of g, noise 0.11 m/s^2, readings on an 8-count grid (a real x-IMU's),
    no reference and no labels: jig-free."""
    rng = np.random.default_rng(seed)
    t, raw, t0 = [], [], 0.0
    for _ in range(3):
        n = int(6 * rate)
        tilt = Rotation.from_rotvec(np.radians(rng.uniform(-4, 4, 3) * np.array([1.0, 1.0, 0.0])))
        y = tilt.apply([0.0, 0.0, G]) * (1 - short) + rng.normal(0, noise, (n, 3))
        t.append(t0 + np.arange(n) / rate)
        raw.append((8 * np.round(y * K / 8)).astype(np.int64))
        t0 += n / rate + 3.0
    return recording_from_arrays(np.concatenate(t), np.vstack(raw))


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_one_orientation_names_the_simplest_term_and_its_equals(seed):
    """In one orientation the data see |f| alone: an offset, a gain, a bend and a tilt of the axes
    move it alike.  A real x-IMU's 2.7 % short |f| had been "axis tilt up to 35.6 deg"; here a bend
    of +75 % had been the verdict.  The verdict is a one-parameter term of the calibration and the
    other one is named with it."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [_one_orientation(seed)])
    assert res["verdict"] in ("offset", "gain"), (res["verdict"], res["effects"][0]["summary"])
    other = "gain" if res["verdict"] == "offset" else "offset"
    assert other in res["ambiguous_with"], res["ambiguous_with"]


def test_a_clip_on_one_side_is_described_without_infinities():
    """A channel clipped on one side only was described as '-inf..36512' (a tester's clipped Xsens)."""
    class Fit:
        N = 3
    text = EFFECTS["saturation"].describe({"lo": [-np.inf, -np.inf, 29024.0], "hi": [36512.0, 36512.0, np.inf]},
                                          {}, Fit)
    assert "inf" not in text
    assert "ch 0: 36512 (above)" in text and "ch 2: 29024 (below)" in text
