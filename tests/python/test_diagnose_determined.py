"""A parameter the data do not determine gets no 1-sigma (diagnose/determined.py)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from accelcal.io.calibration import Calibration
from accelcal.diagnose import diagnose
from accelcal.io.recording import recording_from_arrays
from test_diagnose_honest import G, K, RATE, _one_orientation, six_poses, triad


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_gains_of_axes_that_never_see_gravity_have_no_sigma(seed):
    """A foot-worn triad in one orientation (z up within 4 deg), jig-free: the data see |f| alone,
    so the x and y gains are not measured.  Their figures are the smallest change that fits; the
    sigma had been read off the covariance of the combination the data fix (-2.705 +- 0.017 % on
    x and y alike, z's figure).  Now: null sigma, named in not_determined, said in the summary;
    z's gain keeps its sigma."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [_one_orientation(seed)])
    gain = next(e for e in res["effects"] if e["name"] == "gain")
    nd = gain["not_determined"]["scale"]
    assert nd and 2 not in nd
    assert all(gain["params_sigma"]["scale"][i] is None for i in nd)
    assert isinstance(gain["params_sigma"]["scale"][2], float) and gain["params_sigma"]["scale"][2] > 0
    assert "not determined by these data" in gain["summary"] and "+- nan" not in gain["summary"]
    if gain["selected"]:
        assert all(res["model"]["params_sigma"]["gain"]["scale"][i] is None for i in nd)


def test_parameters_the_poses_fix_keep_their_sigma():
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [six_poses(1, bias_mps2=np.array([0.05, 0.0, -0.03]))])
    assert res["verdict"] == "offset"
    # on the six faces with a reference only the cube is not determined (it is a gain there)
    assert all("not_determined" not in e for e in res["effects"] if e["name"] != "nonlinearity")
    assert next(e for e in res["effects"] if e["name"] == "nonlinearity")["not_determined"] == {"k3": [0, 1, 2]}
    assert all(isinstance(s, float) for s in res["model"]["params_sigma"]["offset"]["db"])


FACES = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
#: poses in the x-z plane alone: no force ever has a y component
XZ_PLANE = [(1, 0, 0), (-1, 0, 0), (0, 0, 1), (0, 0, -1), (1, 0, 1), (-1, 0, 1)]
TERMS = ["offset", "gain", "misalignment", "nonlinearity"]


def held_poses(dirs, seed, *, stated=True, hold_s=3.0, noise=0.01, tilt_deg=0.2):
    """Static poses along ``dirs`` (placed by hand to ``tilt_deg``), read by a triad with gains of
    +0.2 / -0.2 / +1 %, axes turned by ~0.4 deg and a cube on z (2e-4 (m/s^2)^-2 of the input:
    2 % of the reading at 1 g); the force stated (reference) or not (jig-free)."""
    rng = np.random.default_rng(seed)
    sensor = np.diag([1.002, 0.998, 1.01]) @ Rotation.from_rotvec(np.radians([0.3, 0.5, -0.4])).as_matrix()
    k3 = np.array([0.0, 0.0, 2e-4])
    n1 = int(hold_s * RATE)
    t_all, raw_all, f_all, pose_all = [], [], [], []
    for p, d in enumerate(dirs):
        f = G * np.asarray(d, float) / np.linalg.norm(d)
        x = sensor @ Rotation.from_rotvec(np.radians(tilt_deg) * rng.normal(size=3) / np.sqrt(3)).apply(f)
        y = x + k3 * x ** 3
        t_all.append(p * (hold_s + 2.0) + np.arange(n1) / RATE)
        raw_all.append(np.round((y[None, :] + rng.normal(0, noise, (n1, 3))) * K).astype(np.int64))
        f_all.append(np.tile(f, (n1, 1)))
        pose_all.append(np.full(n1, p))
    kw = {"f": np.vstack(f_all)} if stated else {}
    return recording_from_arrays(np.concatenate(t_all), np.vstack(raw_all), pose=np.concatenate(pose_all), **kw)


def _diagnose_terms(rec):
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [rec], candidates=TERMS)
    return res, {e["name"]: e for e in res["effects"]}


def _sigma_of(res, ent, pname):
    sig = [ent["params_sigma"][pname]]
    if ent["selected"]:
        sig.append(res["model"]["params_sigma"][ent["name"]][pname])
    return sig


def test_six_faces_do_not_determine_a_cube_with_a_reference():
    """On poses along the axes a cube is a gain (x^3 = g^2 x there): the fit carries no cube, and
    its k3 had been 0 +- 0 on every channel.  Now: not determined, null sigma; k2 keeps its."""
    res, e = _diagnose_terms(held_poses(FACES, 1))
    nl = e["nonlinearity"]
    assert nl["not_determined"] == {"k3": [0, 1, 2]}
    for s in _sigma_of(res, nl, "k3"):
        assert s == [None, None, None]
    assert all(isinstance(v, float) and v > 0 for v in nl["params_sigma"]["k2"])
    assert "not determined by these data: k3 on channel(s) 0, 1, 2" in nl["summary"]
    # every tilt is seen with a reference on the six faces
    assert "not_determined" not in e["misalignment"]


def test_six_faces_jig_free_see_no_misalignment():
    """Jig-free, each face pose's angles absorb the change a tilt of the axes makes (to first order
    it is across the force): every tilt keeps < 6e-4 of its change, yet the fit had kept them
    (its cut is relative to the best-seen direction) and quoted a 95 deg tilt at +- 2.4 deg."""
    res, e = _diagnose_terms(held_poses(FACES, 1, stated=False))
    mis = e["misalignment"]
    assert sorted(map(tuple, mis["not_determined"]["rot"])) == [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]
    for s in _sigma_of(res, mis, "rot"):
        assert all(s[i][c] is None for i in range(3) for c in range(3) if c != i)
    assert "+- nan" not in mis["summary"] and "(+-" not in mis["summary"]
    # the gains are seen: kept
    assert "not_determined" not in e["gain"]


def test_no_pose_with_a_y_component_determines_nothing_of_y():
    """Poses in the x-z plane with a reference: channel y's input is always 0 (its gain and bend
    are not measured), and no force has a component along y, so x's tilt toward y (rot about z)
    and z's tilt toward y (rot about x) are not measured either.  They had been 0 +- 0."""
    res, e = _diagnose_terms(held_poses(XZ_PLANE, 2))
    assert e["gain"]["not_determined"] == {"scale": [1]}
    assert e["nonlinearity"]["not_determined"] == {"k2": [1], "k3": [1]}
    assert sorted(map(tuple, e["misalignment"]["not_determined"]["rot"])) == [(0, 2), (2, 0)]
    for s in _sigma_of(res, e["misalignment"], "rot"):
        assert s[0][2] is None and s[2][0] is None
        assert isinstance(s[0][1], float) and s[0][1] > 0 and isinstance(s[1][2], float) and s[1][2] > 0
    assert "not_determined" not in e["offset"]


def test_general_poses_determine_every_term():
    """24 poses in general directions with a reference: every parameter of every term is measured
    and keeps its sigma (the tilt's part along its own axis is no parameter: 0 by the form)."""
    dirs = [tuple(v) for v in np.random.default_rng(7).normal(size=(24, 3))]
    res, e = _diagnose_terms(held_poses(dirs, 1))
    assert all("not_determined" not in ent for ent in e.values())
    for name in TERMS:
        for pname, sig in e[name]["params_sigma"].items():
            flat = np.asarray(sig, float)
            if name == "misalignment":
                flat = flat[~np.eye(3, dtype=bool)]
            assert np.all(flat > 0), (name, pname, sig)


def test_general_poses_jig_free_leave_the_common_rotation():
    """The same poses jig-free: the gains and the bend are measured; each single tilt is not (the
    poses' angles absorb a common rotation of the axes, half of each tilt's direction), only the
    angles between the axes are."""
    dirs = [tuple(v) for v in np.random.default_rng(7).normal(size=(24, 3))]
    res, e = _diagnose_terms(held_poses(dirs, 1, stated=False))
    assert "not_determined" not in e["gain"] and "not_determined" not in e["nonlinearity"]
    assert len(e["misalignment"]["not_determined"]["rot"]) == 6


def _one_still_pose(n=3000):
    """One still pose of an MPU-6050 at +-2 g (readings on a 4-count grid), 0.946 g along z with
    a little x and y, noise 91 / 57 / 83 counts: jig-free, one pose (a sensor_noise.txt's shape)."""
    rng = np.random.default_rng(0)
    raw = 4 * np.round((np.array([108.0, 369.0, 15500.0]) + rng.normal(0, [91, 57, 83], (n, 3))) / 4)
    return recording_from_arrays(np.arange(n) / RATE, raw.astype(np.int64))


def test_an_effect_none_of_whose_values_is_determined_says_so_first():
    """One still pose, nominal calibration: no tilt is determined (the pose's angles take them
    all), yet misalignment's summary began "axis tilt up to 228 deg on channel 2" and said only
    after it that none is determined; gain's "up to" named an undetermined channel.  Now a
    summary whose values are all undetermined begins with that and gives the fit's figure as no
    measurement; where some are determined the figure is theirs alone."""
    d = triad()
    res = diagnose(d, Calibration.nominal(d), [_one_still_pose()])
    e = {ent["name"]: ent for ent in res["effects"]}
    mis = e["misalignment"]
    assert len(mis["not_determined"]["rot"]) == 6
    assert mis["summary"].startswith("not determined by these data: rot on channel(s) 0, 1, 2")
    assert "no measurement" in mis["summary"].split("axis tilt")[0]
    for name in ("gain", "offset", "bias_drift"):
        nd = next(iter(e[name]["not_determined"].values()))
        assert nd == [0, 1]
        assert not e[name]["summary"].startswith("not determined")
        assert e[name]["summary"].split(";")[0].endswith("on channel 2"), e[name]["summary"]
    assert e["nonlinearity"]["summary"].split(";")[0].endswith("on channel 2")
