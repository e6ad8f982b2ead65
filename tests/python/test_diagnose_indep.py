"""The diagnosis on data it did not make: the independent forward model of indep_model.py
(written from the data contract alone) and effects injected into the real Xsens recording.

Only what the diagnosis was seen to do on every one of several seeds is asserted here
(each case below runs 3 seeds).  Cases it gets wrong are measured by
tools/bench_diagnose_indep.py, not asserted: a digital second-order low-pass close to the
Nyquist frequency is often time_skew (with bandwidth listed),
crosstalk misalignment (the same change of every reading), an offset of half a coarse step
on six poses that each sit on one code a pose error.
"""
from __future__ import annotations

import importlib

import numpy as np
import pytest

import indep_model as im
from accelcal.diagnose import diagnose

SEEDS = (0, 1, 2)


def _diagnose(ds, seed):
    return diagnose(ds["device"], ds["cal"], ds["recordings"], seed=seed)


def _ambiguous(res) -> list:
    """ambiguous_with at the top level (the contract) or, before it is there, on effects[0]."""
    amb = res.get("ambiguous_with")
    if amb is None and res.get("effects"):
        amb = res["effects"][0].get("ambiguous_with")
    return list(amb or [])


# ------------------------------------------------------------------ the model itself
def test_kinematics_match_finite_differences():
    """f(r) = R^T (d^2/dt^2 (p + R r) + g z) and ω from R^T dR/dt, to 1e-5 (m/s^2, rad/s)."""
    rng = np.random.default_rng(3)
    tr = im.Trajectory(g=9.81)
    tr.hold(im.random_rotation(rng), 0.5)
    tr.move_to(im.random_rotation(rng), 0.7, d=[0.1, -0.05, 0.02])
    tr.hold(tr.R_end, 0.5)
    r = np.array([0.06, 0.02, -0.01])

    def pose(t):
        k = int(tr.segment(np.array([t]))[0])
        h = im._h(np.array([(t - tr.t0[k]) / tr.dur[k]]))[0][0]
        R = tr.R0[k] @ im.expm_so3(tr.e[k] * tr.phi[k] * h)
        p = sum(tr.d[j] * im._h(np.array([(t - tr.t0[j]) / tr.dur[j]]))[0][0] for j in range(len(tr.t0)))
        return R, p + R @ r

    h = 1e-4
    for t in (0.6, 0.8, 0.95, 1.1, 1.5):
        f, w, dw = tr.evaluate(np.array([t]))
        R, x = pose(t)
        acc = (pose(t + h)[1] - 2 * x + pose(t - h)[1]) / h ** 2
        f_num = R.T @ (acc + np.array([0.0, 0.0, 9.81]))
        f_r = f[0] + np.cross(dw[0], r) + np.cross(w[0], np.cross(w[0], r))
        W = R.T @ (pose(t + h)[0] - pose(t - h)[0]) / (2 * h)
        assert np.abs(f_num - f_r).max() < 1e-5
        assert np.abs(np.array([W[2, 1], W[0, 2], W[1, 0]]) - w[0]).max() < 1e-5


def test_stated_ratio_is_the_contribution():
    """The ratio a dataset states is in the drawn 3-30x range for an effect linear in its size."""
    ds = im.make_jig(["gain"], 5, device="triad16", rate=100.0, noise=0.01, motion=False, temperature=False)
    assert 2.9 < ds["ratio"]["gain"] < 30.5
    raw = ds["recording"].raw
    assert raw.min() >= 0 and raw.max() <= 65535


# ------------------------------------------------------------------ independent jig / hand-held
@pytest.mark.parametrize("seed", SEEDS)
def test_jig_clean_is_none(seed):
    ds = im.make_jig([], seed, device="triad16", rate=100.0, noise=0.01, temperature=False)
    assert _diagnose(ds, seed)["verdict"] == "none"


@pytest.mark.parametrize("seed", SEEDS)
def test_jig_offset_is_offset(seed):
    ds = im.make_jig(["offset"], seed, device="triad16", rate=100.0, noise=0.01, motion=False, temperature=False)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "offset", (res["verdict"], ds["ratio"])
    assert res["effects"][0]["shrink"] > 0.6


@pytest.mark.parametrize("seed", SEEDS)
def test_jig_random_walk_drift_with_repeated_poses_is_bias_drift(seed):
    ds = im.make_jig(["bias_drift"], seed, device="triad16", rate=100.0, noise=0.01, motion=False,
                     temperature=False, repeats=True)
    assert ds["effects"]["bias_drift"]["shape"] == "random_walk"
    assert _diagnose(ds, seed)["verdict"] == "bias_drift"


@pytest.mark.parametrize("seed", SEEDS)
def test_jig_in_range_clip_is_saturation(seed):
    ds = im.make_jig(["saturation"], seed, device="triad16", rate=100.0, noise=0.01, motion=False, temperature=False)
    assert _diagnose(ds, seed)["verdict"] == "saturation"


@pytest.mark.parametrize("seed", SEEDS)
def test_jig_skew_with_jitter_on_the_array_is_time_skew(seed):
    ds = im.make_jig(["time_skew"], seed, device="seed6", rate=100.0, noise=0.01, motion=True, temperature=False)
    assert _diagnose(ds, seed)["verdict"] == "time_skew"


@pytest.mark.parametrize("kind", ["pose_error", "bias_drift"])
@pytest.mark.parametrize("seed", SEEDS)
def test_six_poses_held_once_name_the_effect_or_flag_it(kind, seed):
    """+-x, +-y, +-z each held once: a table tilt and a linear drift; the diagnosis names
    the effect or lists it in ambiguous_with."""
    ds = im.make_six_pose(kind, seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] == kind or kind in _ambiguous(res), (res["verdict"], _ambiguous(res))


@pytest.mark.parametrize("seed", SEEDS)
def test_handheld_offset_is_offset(seed):
    ds = im.make_handheld(["offset"], seed, device="triad16", rate=100.0, noise=0.01, temperature=False)
    assert _diagnose(ds, seed)["verdict"] == "offset"


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("session", ["jig", "handheld"])
def test_a_cubic_nonlinearity_is_nonlinearity(session, seed):
    """The independent model bends the reading by k3 u^3 (odd: at +-1 g a gain change); the
    registry's square term alone left it to gain.  With poses between the axes it is named
    nonlinearity, with the cube term's sign right on the channel that bends most."""
    make = im.make_jig if session == "jig" else im.make_handheld
    ds = make(["nonlinearity"], seed, device="triad16", rate=100.0, noise=0.01, temperature=False)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "nonlinearity", (res["verdict"], ds["ratio"])
    k3_true = np.asarray(ds["effects"]["nonlinearity"]["k3"])
    i = int(np.argmax(np.abs(k3_true)))
    assert np.sign(res["model"]["params"]["nonlinearity"]["k3"][i]) == np.sign(k3_true[i])


@pytest.mark.parametrize("seed", SEEDS)
def test_on_six_face_poses_a_gain_is_flagged_as_a_possible_bend(seed):
    """On +-x, +-y, +-z alone a cube is a gain (x^3 = g^2 x at 0 and +-g): the verdict for a
    gain error stays gain, and nonlinearity is listed as what the data cannot tell it from,
    with poses at 45 deg to separate them."""
    ds = im.make_jig(["gain"], seed, device="triad16", rate=100.0, noise=0.01, directions=list(im.FACES),
                     motion=False, temperature=False)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "gain"
    assert "nonlinearity" in _ambiguous(res)
    assert "45 deg" in res["separate_by"]


@pytest.mark.parametrize("seed", SEEDS)
def test_a_misalignment_on_six_faces_is_flagged_as_a_possible_tilt(seed):
    """On the six faces of a box a tilt of each pose reproduces a misalignment to first order:
    the verdict is misalignment with pose_error listed; with edge and corner poses it is not."""
    kw = dict(device="triad16", rate=100.0, noise=0.01, motion=False, temperature=False)
    res = _diagnose(im.make_jig(["misalignment"], seed, directions=list(im.FACES), **kw), seed)
    assert res["verdict"] == "misalignment" and "pose_error" in _ambiguous(res)
    assert "45 deg" in res["separate_by"]
    res = _diagnose(im.make_jig(["misalignment"], seed, **kw), seed)
    assert res["verdict"] == "misalignment" and "pose_error" not in _ambiguous(res)


# ------------------------------------------------------------------ the real Xsens recording
@pytest.fixture(scope="module")
def xsens(real_model):
    return real_model("xsens")


def test_xsens_clean_against_its_own_calibration_is_none(xsens):
    dev, rec, _, cal = xsens
    for seed in SEEDS:
        assert diagnose(dev, cal, [rec], seed=seed)["verdict"] == "none"


@pytest.mark.parametrize("effect", ["offset", "gain", "bias_drift"])
@pytest.mark.parametrize("seed", SEEDS)
def test_xsens_injected_effect_is_named(xsens, effect, seed):
    dev, rec, step, cal = xsens
    rec2, _, ratio = im.inject(dev, cal, rec, effect, seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == effect, (res["verdict"], ratio)


@pytest.mark.parametrize("seed", SEEDS)
def test_xsens_with_mains_pickup_is_unexplained_at_50_hz(xsens, seed):
    """50 Hz on a 100 Hz recording sits in the spectrum's last (Nyquist) bin, which must not
    be its own background."""
    dev, rec, step, cal = xsens
    rec2, _, ratio = im.inject(dev, cal, rec, "mains", seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == "unexplained" or res["unexplained"] is not None, (res["verdict"], ratio)
    assert res["unexplained"]["lines"]["peak_hz"] == pytest.approx(50.0, abs=1.0)


@pytest.mark.parametrize("seed", [pytest.param(0, marks=pytest.mark.xfail(strict=True, reason=(
    "known failure (docs/limitations.md): jig-free, a 363 counts/degC offset (a 4,600-count change) leaves the "
    "relinearised model (temperature_offset + nonlinearity + misalignment, not converged after 1 iteration, "
    "held-out residual 142 of 1,632 counts) refitting the lag to 48 s against the true 77 s; the effect alone "
    "fits 95 s (interval 91-99 s)"))), 1, 2])
def test_an_offset_through_a_thermal_lag_is_temperature_offset(seed):
    """The sensor's own temperature follows the recorded one through a 30-120 s lag (the
    independent model's shape): named temperature_offset, not a drift, with the lag of the
    model (the chosen effects refitted together) within 30 %."""
    ds = im.make_handheld(["temperature_offset"], seed)
    res = diagnose(ds["device"], ds["cal"], ds["recordings"], seed=seed)
    assert res["verdict"] == "temperature_offset"
    tau = res["model"]["params"]["temperature_offset"]["tau_s"]
    true_tau = ds["effects"]["temperature_offset"]["tau_s"]
    assert abs(tau - true_tau) <= 0.3 * true_tau


@pytest.mark.parametrize("seed", [90140, 90141, 90143])
def test_on_the_jig_a_lagged_temperature_takes_the_first_step_over_a_drift_path(seed):
    """The jig's offset through a 50-115 s thermal lag: a drift path (many knots) follows it
    a little closer than the first-order lag does, but the temperature is the measured cause
    and takes the first step (the bench's seeds; 90141 and 90143 went to bias_drift while the
    simpler rival's first step was refused wherever each form held the other's; 90149 still
    does, README)."""
    ds = im.make_jig(["temperature_offset"], seed)
    res = diagnose(ds["device"], ds["cal"], ds["recordings"], seed=seed)
    assert res["verdict"] == "temperature_offset", (res["verdict"], res["model"]["effects"])


# ------------------------------------------------------------------ the other real recordings
@pytest.mark.parametrize("seed", [872050, 872051, 872053])
def test_imucal_an_offset_through_a_thermal_lag_is_temperature_offset(real_model, seed):
    """imucal's six poses (the model holding their real tilt) with an offset through a 30-120 s
    lag: the lag is fitted across the samples between the poses, which the diagnosis leaves
    out (it was fitted as ~20 s there and the verdict was bias_drift)."""
    dev, rec, step, cal = real_model("imucal")
    rec = im.as_posed(rec, cal)
    rec2, params, ratio = im.inject(dev, cal, rec, "temperature_offset", seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == "temperature_offset", (res["verdict"], ratio)
    tau = res["model"]["params"]["temperature_offset"]["tau_s"]
    assert abs(tau - params["temperature_offset"]["tau_s"]) <= 0.3 * params["temperature_offset"]["tau_s"]


@pytest.mark.parametrize("seed", [636270, 636271, 636272])
def test_mpu6050_a_large_gain_error_is_gain_not_a_bend(real_model, seed):
    """A 5-14 % gain change injected into the MPU-6050's hand-turned poses: the calibration
    terms, fitted together before they are folded into the calibration, leave the bend
    nothing (fitted one by one and folded at once they overshot, the re-linearisation ran
    away and the bend kept the verdict: seed 636271)."""
    dev, rec, step, cal = real_model("mpu6050")
    rec2, _, ratio = im.inject(dev, cal, rec, "gain", seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == "gain", (res["verdict"], res["model"]["effects"], ratio)


@pytest.mark.parametrize("seed", [140133, 140136, 140138])
def test_mpu6050_a_drift_beside_a_gain_is_named_or_listed(real_model, seed):
    """A linear drift and a gain change injected together into the MPU-6050's hand-turned
    poses, each held once: the bend's square term (or an offset) takes the level the drift
    left in each pose, and the model held no term of time.  The readings change with time
    inside the poses, so the drift is listed in ambiguous_with where the model leaves it out
    (seeds 140133 and 140138 were named nonlinearity and offset with nothing listed), and where
    the model has it after a verdict that varies by pose (140136: nonlinearity, with the drift
    third).  Injected alone, the gain keeps ambiguous_with free of a drift: a drift fitted to
    it takes only the poses' levels and meets a slope of ~0 within them."""
    dev, rec, step, cal = real_model("mpu6050")
    rec2, _, ratio = im.inject(dev, cal, rec, ("bias_drift", "gain"), seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    named = [res["verdict"]] + _ambiguous(res)
    assert "bias_drift" in named, (res["verdict"], named, res["model"]["effects"], ratio)
    rec3, _, ratio = im.inject(dev, cal, rec, "gain", seed, step=step)
    res = diagnose(dev, cal, [rec3], seed=seed)
    assert res["verdict"] == "gain" and "bias_drift" not in _ambiguous(res), (res["verdict"], _ambiguous(res), ratio)


@pytest.mark.parametrize("seed", [140133, 140136])
def test_mpu6050_a_drift_fitted_beside_the_terms_lets_the_gain_take_the_bend_s_step(real_model, seed):
    """The same drift and gain: fitted alone, the drift's ramp also took the pattern the gain
    leaves over the poses, and its change within the poses ran against the data's (-0.25 of
    what it claimed), so the bend's check left it out; fitted beside the calibration terms it
    is borne out within the poses (3.1 of its claim) and joins them.  The re-linearisation of
    the terms and the drift ran away (1,578 counts held out before it, 5,033 after): the bend
    is judged at the step's linearisation, where it adds nothing beyond them.  Both were named
    nonlinearity, the drift at most listed."""
    dev, rec, step, cal = real_model("mpu6050")
    rec2, _, ratio = im.inject(dev, cal, rec, ("bias_drift", "gain"), seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == "gain", (res["verdict"], res["model"]["effects"], ratio)
    assert "bias_drift" in res["model"]["effects"], (res["model"]["effects"], ratio)


@pytest.mark.parametrize("tau", [10.0, 60.0, 150.0])
def test_the_thermal_lag_is_the_same_in_seconds_with_samples_left_out(tau):
    """temperature.lagged on the samples a diagnosis keeps (rests, gaps between them) equals
    the lag run over the whole recording at those samples, to 1 % of the temperature step;
    the independent model's own first-order lag is the reference."""
    lagged = importlib.import_module("accelcal.effects.temperature").lagged
    ds = im.make_handheld(["temperature_offset"], 0)
    sc = ds["scene"]
    keep = im.static_mask(ds["recordings"][0].raw, ds["rate_hz"])
    assert np.count_nonzero(np.diff(keep.astype(int)) == 1) >= 5     # gaps to cross
    truth = im.sensor_temperature(sc, tau)
    step = float(np.ptp(sc.temp_amb))
    assert np.max(np.abs(lagged(sc.temp_amb, sc.t, tau) - truth)) <= 0.01 * step
    assert np.max(np.abs(lagged(sc.temp_amb[keep], sc.t[keep], tau) - truth[keep])) <= 0.01 * step


@pytest.mark.parametrize("seed", SEEDS)
def test_jig_quantization_and_offset_are_not_a_drift(seed):
    """A jig's readings on a coarse lattice (steps 2-16 counts, the noise well below a step)
    with an offset: each pose keeps the quantiser's error of its reading, the same at a repeated
    orientation.  A drift's path through the poses visited in turn took that pattern along with
    the offset and was named (4 of 10 such jig cases); the data at the repeats do not change as
    the path says, so the verdict is one of the two effects, and both are in the model."""
    ds = im.make_jig(["quantization", "offset"], seed, device="seed6", rate=100.0, noise=0.004, motion=False,
                     temperature=False, repeats=True)
    res = _diagnose(ds, seed)
    assert res["verdict"] in ("quantization", "offset"), (res["verdict"], res["model"]["effects"], ds["ratio"])
    assert {"quantization", "offset"} <= set(res["model"]["effects"]), (res["model"]["effects"], ds["ratio"])


@pytest.mark.parametrize("seed", SEEDS)
def test_jig_offset_and_gain_with_a_recorded_temperature_are_not_a_temperature_effect(seed):
    """An offset and a gain error on a 12-bit jig (noise well below a count, so each pose also
    keeps its rounding) with a temperature column that the readings do not follow: a temperature
    gain through its lag took the gain along with part of the pattern over the poses and was named
    (2 of 10 such bench cases).  The poses repeated at the end, at another temperature, read as
    before, so neither temperature effect is the verdict and both true effects are in the model."""
    ds = im.make_jig(["offset", "gain"], seed, device="adxl12", rate=100.0, noise=0.006, motion=False,
                     temperature=True, repeats=True)
    res = _diagnose(ds, seed)
    assert res["verdict"] in ("offset", "gain"), (res["verdict"], res["model"]["effects"], ds["ratio"])
    assert {"offset", "gain"} <= set(res["model"]["effects"]), (res["model"]["effects"], ds["ratio"])


def test_jig_thermal_lag_is_temperature_offset_over_a_drift_path():
    """An offset that follows the recorded temperature through a 53 s lag, on a 12-bit jig whose
    poses also keep their rounding (the independent benchmark's case indep-jig /
    temperature_offset, seed 90149): a drift's path took the temperature's change and a little
    more (what the fitted lag misses) and displaced the temperature, the measured cause.  The
    temperature is the verdict; the path's rest may follow."""
    ds = im.make_jig(["temperature_offset"], 90149)
    res = _diagnose(ds, 90149)
    assert res["verdict"] == "temperature_offset", (res["verdict"], res["model"]["effects"], ds["ratio"])


@pytest.mark.parametrize("seed", (0, 1, 2, 7))
def test_six_poses_on_a_coarse_lattice_keep_the_rounding_in_the_floor(real_model, seed):
    """imucal's six hand-placed poses with their readings on a lattice of 32 counts (its noise is
    ~3 counts, so each pose sits on one code of a channel or two) and an offset.  Within the poses
    such a channel does not move, yet each pose reads up to 16 counts off its true value: the floor
    is at least the rounding noise q/sqrt(12) (it was 1/sqrt(12), and every fit that moved a
    pose's level scored thousands of chi2 on that channel), and a pose held on one code at the
    channel's extreme is no clip (saturation had been named with the model 4-6 counts beyond)."""
    dev, rec, step, cal = real_model("imucal")
    rec = im.as_posed(rec, cal)
    rec2, params, ratio = im.inject(dev, cal, rec, ("quantization", "offset"), seed, step=step)
    q = params["quantization"]["step"]
    assert q == 32
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert min(res["gap"]["noise_floor_per_channel"]) >= q / np.sqrt(12.0) * (1 - 1e-9)
    assert "saturation" not in res["model"]["effects"], (res["model"]["effects"], params)


@pytest.mark.parametrize("seed", (313502, 313504, 313506))
def test_hand_held_offset_on_a_lattice_is_not_a_temperature_offset(seed):
    """The independent benchmark's hand-held sessions (readings on a lattice of 10-16 counts,
    an offset, a temperature column the readings do not follow) where the offset and a temperature
    offset through its lag shrink the gap as far (0.516 each) and the temperature adds only each
    pose's rounding.  Ranked first the temperature had yielded to the simpler offset, ranked second
    it displaced it: now the simpler is the verdict either way, and the pair is named.  313504
    (0.465 and 0.475): since the poses' design effect neither adds anything significant after the
    other, and the paired test that names them together (compare.separable) counted each block
    as independent, so a pose's rounding, the same in all its blocks, told them apart (t 3.11;
    1.28 over the poses, as each gain's own t counts them): temperature_offset, offset unnamed."""
    ds = im.make_handheld(["quantization", "offset"], seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] in ("offset", "quantization"), (res["verdict"], res["model"]["effects"], ds["ratio"])
    assert {"quantization", "offset"} <= set(res["model"]["effects"]), (res["model"]["effects"], ds["ratio"])


@pytest.mark.parametrize("seed", (154077, 154078))
def test_an_offset_with_a_drift_beside_it_says_the_drift_may_have_reached_it(seed):
    """The independent benchmark's hand-held sessions with a random-walk drift: the verdict is
    offset, the level the walk had reached when the recording began, with the drift in the model
    (154078: offset, gain, bias_drift) or significant after the offset in the nested test
    (154077, where three steps went to offset, misalignment and gain).  The data cannot say
    which the constant part is, and the verdict says so, with a recording from right after the
    calibration as what would tell."""
    ds = im.make_handheld(["bias_drift"], seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "bias_drift" or "bias_drift" in _ambiguous(res), \
        (res["verdict"], res["model"]["effects"], _ambiguous(res))
    if res["verdict"] == "offset":
        assert "right after the calibration" in res["separate_by"]
        assert any("reached since the calibration" in n for n in res["notes"])


def test_a_cube_that_yields_to_a_gain_and_then_to_the_calibration_terms_is_flagged(real_model):
    """The independent benchmark's cubic bend in the real Xsens recording (910764): the gain
    alone shrinks the gap as far as the cube (0.966 against 0.969), so it takes the first step
    and what the cube adds is left to the next; there the offset and the misalignment take it.
    The model then explains the gap as the cube alone does, and the verdict lists it."""
    dev, rec, step, cal = real_model("xsens")
    seed = 910764
    rec2, params, ratio = im.inject(dev, cal, rec, "nonlinearity", seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == "nonlinearity" or "nonlinearity" in _ambiguous(res), \
        (res["verdict"], res["model"]["effects"], _ambiguous(res))


def test_a_skew_beyond_the_first_grid_is_found():
    """The independent benchmark's jig with one channel 139 ms late at 200 Hz (28 samples, 264308;
    the motion is slow, so the skew that makes its contribution is large): the search grid
    ended at 12 samples, the skew fit took a third of the gap and a low-pass the rest, and the
    verdict was bandwidth.  The grid grows where its minimum lies at an end."""
    seed = 264308
    ds = im.make_jig(["time_skew"], seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "time_skew", (res["verdict"], res["model"]["effects"])
    tau = np.asarray(ds["effects"]["time_skew"]["tau"], float)
    i = int(np.argmax(np.abs(tau)))
    got = np.asarray(res["model"]["params"]["time_skew"]["tau"], float)
    assert got[i] == pytest.approx(tau[i], rel=0.1), (got, tau)


def test_a_temperature_verdict_the_poses_outrun_lists_a_drift():
    """The independent benchmark's hand-held session with a random-walk drift and a temperature
    column the readings do not follow (154073): the temperature through its lag is the closest
    smooth shape and is named, but within the poses the readings change 2.8 times as fast as it
    says.  What changes with time is not the temperature's alone: bias_drift is listed."""
    seed = 154073
    ds = im.make_handheld(["bias_drift"], seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "bias_drift" or "bias_drift" in _ambiguous(res), \
        (res["verdict"], res["model"]["effects"], _ambiguous(res))


@pytest.mark.parametrize("seed", SEEDS)
def test_a_second_order_low_pass_is_bandwidth_or_a_common_lag_that_lists_it(seed):
    """The independent model's low-pass is scipy's digital second-order Butterworth at the
    sample rate: below its cut-off it is a delay of about sqrt(2) / (2 pi fc), and close to the
    Nyquist frequency a pure delay fits it better than an analog filter does.  Either the
    verdict is bandwidth, or it is a skew common to every channel that lists bandwidth."""
    ds = im.make_jig(["bandwidth"], seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "bandwidth" or "bandwidth" in _ambiguous(res), \
        (res["verdict"], res["model"]["effects"], _ambiguous(res))


def test_a_second_order_low_pass_is_fitted_as_one():
    """The independent benchmark's jig with a 12.6 Hz second-order low-pass at 50 Hz (513100):
    with the contract's first-order shape alone, a time skew took more of the gap (0.861
    against 0.771) and was named.  The fit tries the second-order Butterworth too: it takes
    0.869 and is named, with the order and a cut-off near the truth."""
    seed = 513100
    ds = im.make_jig(["bandwidth"], seed)
    res = _diagnose(ds, seed)
    assert res["verdict"] == "bandwidth", (res["verdict"], res["model"]["effects"])
    p = res["model"]["params"]["bandwidth"]
    assert p["order"] == 2
    fc = np.asarray(p["fc_hz"], float)
    assert np.all(np.abs(fc / ds["effects"]["bandwidth"]["fc_hz"] - 1) < 0.3), (fc, ds["effects"]["bandwidth"])


def test_an_offset_and_coarse_steps_refitted_together_beat_a_per_pose_tilt():
    """The independent benchmark's jig with an offset and 7-count steps (798611): fitted one
    after another, the offset carried each pose's rounding and the rounding predicted from it
    missed, so the per-pose tilt (68 parameters), which takes the offset and each pose's
    rounding at once, won the first step and the verdict was pose_error, with no word of doubt.
    Refitted together, the offset and the steps leave less with 6 parameters: they are the
    model (diagnose.parsimony), and scored as the model holds them (each after the other's
    joint fit) they leave nothing beyond the noise; after the stepwise fits 9 % of the gap was
    reported unexplained.  (Since the poses' design effect, diagnose.floor.pose_design_effect, the
    tilt's 68 parameters cost what each pose's rounding, the same in all its samples, gives them,
    and it no longer wins the first step: the steps are the model without the parsimony's swap.)"""
    seed = 798611
    ds = im.make_jig(["quantization", "offset"], seed)
    res = _diagnose(ds, seed)
    assert set(res["model"]["effects"]) >= {"offset", "quantization"}, (res["verdict"], res["model"]["effects"])
    assert "pose_error" not in res["model"]["effects"]
    assert res["verdict"] != "pose_error"
    assert res["unexplained"] is None, res["unexplained"]


def test_mpu6050_coarse_steps_that_a_bend_outranked_are_the_verdict(real_model):
    """512-count steps injected into the MPU-6050's hand-turned poses (773720): a bend ranked
    first, the calibration terms left it nothing and the step went to the strongest term, an
    offset of shrink 0.07, although the lattice, proven from the raw values, ranked above it.
    A candidate proven on its own evidence that ranks above the terms takes the step.  (Since the
    poses' design effect, diagnose.floor.pose_design_effect, the bend's penalty counts each pose's
    rounding to the steps, the same in all its samples, and the lattice ranks first itself.)"""
    dev, rec, step, cal = real_model("mpu6050")
    seed = 773720
    rec2, params, _ = im.inject(dev, cal, rec, "quantization", seed, step=step)
    res = diagnose(dev, cal, [rec2], seed=seed)
    assert res["verdict"] == "quantization", (res["verdict"], res["model"]["effects"], params)
    assert res["effects"][0]["contest"]["first_ranked"] in ("nonlinearity", "quantization")
