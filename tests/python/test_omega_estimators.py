"""attitude and displacement with the array's own omega (issue 36): recordings from the
independent generator (indep_model's Trajectory, Scene, analog and adc: a 12-channel array swung
about body y through its origin, or moved and then spun about the vertical through its origin),
each command's result against the generator's truth, float and fixed engines, the Python API and
the CLI; the refusal on a layout that does not observe omega."""
from __future__ import annotations

import math

import numpy as np
import pytest

import accelcal as ac
import indep_model as im
from accelcal.cli.main import main
from accelcal.errors import InputError
from accelcal.estimators import alpha_noise, attitude_from_recording, displacement_from_recording
from accelcal.estimators.common import force_noise_axes
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.io.device import axes_device, pendulum_device, save_device, tetrahedron_device
from accelcal.io.recording import recording_from_arrays, write_recording


def _make(device, segments, seed=0, lead_s=2.0):
    """The generator's rigid motion: a rest of ``lead_s``, then each (body axis, angle rad, origin's
    move m (world), duration s, rest after s) as a quintic segment; true parameters drawn about the
    nominal, the device's white noise, rounding and clipping."""
    rng = np.random.default_rng(seed + 3600)
    p = im.true_parameters(device, rng)
    tr = im.Trajectory(g=device.gravity_mps2)
    tr.hold(np.eye(3), lead_s)
    for e, phi, move, dur, hold in segments:
        tr._add(tr.R_end, dur, np.asarray(e, float), phi, np.asarray(move, float), -1, np.full(3, np.nan))
        tr.hold(tr.R_end, hold)
    t = im._sample_times(tr, device.sample_rate_hz)
    sc = im.Scene(dev=device, p=p, traj=tr, t=t, noise_mps2=device.noise_mps2,
                  noise=rng.normal(size=(t.size, device.n_channels)))
    raw = im.adc(sc, im.analog(sc, {}), {})
    f, w, dw = tr.evaluate(t)
    return {"device": device, "cal": im.as_calibration(device, p), "recording": recording_from_arrays(t, raw),
            "f": f, "w": w, "dw": dw}


def _noise_counts(dev, cal):
    # each channel's sd in counts, the rounding's 1/12 count^2 included
    return np.sqrt((dev.noise_mps2 * np.linalg.norm(cal.sensitivity, axis=1)) ** 2 + 1.0 / 12.0)


@pytest.fixture(scope="module")
def swing():
    rng = np.random.default_rng(7)
    # 8 swings about body y of 1-2 rad in 0.4-0.8 s: peak rates 2.3-9.4 rad/s
    segs = [((0.0, 1.0, 0.0), (-1) ** k * rng.uniform(1.0, 2.0), (0, 0, 0), rng.uniform(0.4, 0.8), 0.0)
            for k in range(8)]
    return _make(tetrahedron_device(), segs, seed=1, lead_s=1.0)


@pytest.fixture(scope="module")
def move_and_spin():
    # 0.2 m along x without turning, a rest, then two full turns about the vertical through the origin
    # (peak 19.6 rad/s; the origin does not move), a rest: the truth is p = (0.2, 0, 0) from the first
    # motion's end on
    return _make(axes_device(), [((0, 0, 1), 0.0, (0.2, 0, 0), 1.0, 2.0),
                                 ((0, 0, 1), 4 * math.pi, (0, 0, 0), 1.2, 2.0)], seed=2)


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_attitude_with_the_array_omega_meets_the_noise(swing, engine):
    """A 12-channel array (which the two-triad estimator refuses) swung about y: theta within the
    f noise's sd / g, w_y within its stated sigma, dw_y within the alpha noise."""
    dev, cal, rec = swing["device"], swing["cal"], swing["recording"]
    c = attitude_from_recording(dev, cal, rec, engine, omega="array")
    assert c.meta["omega"] == "array" and not c.warnings
    theta_true = np.arctan2(-swing["f"][:, 0], swing["f"][:, 2])
    err = np.angle(np.exp(1j * (c["theta_rad"] - theta_true)))
    sf = force_noise_axes(dev, cal, _noise_counts(dev, cal))
    # theta's sd from f's x and z noise at |f| = g
    assert np.sqrt(np.mean(err ** 2)) < 1.2 * max(sf[0], sf[2]) / dev.gravity_mps2
    z = (c["w_y"] - swing["w"][:, 1]) / c["w_y_sigma"]
    assert np.all(np.abs(z) < 5.0) and 0.5 < np.sqrt(np.mean(z ** 2)) < 1.5
    a_sd = alpha_noise(dev, cal, np.sqrt((dev.noise_mps2 * np.linalg.norm(cal.sensitivity, axis=1)) ** 2
                                         + 1.0 / 12.0))
    assert np.sqrt(np.mean((c["dw_y"] - swing["dw"][:, 1]) ** 2)) < 1.2 * a_sd
    # "auto" (no w columns, a layout that observes omega) is "array"; "none" is the two-triad estimator
    a = attitude_from_recording(dev, cal, rec, engine)
    np.testing.assert_array_equal(a["theta_rad"], c["theta_rad"])
    with pytest.raises(InputError, match="two triads"):
        attitude_from_recording(dev, cal, rec, engine, omega="none")


def test_attitude_array_omega_from_the_api_and_the_cli(swing, tmp_path):
    c = ac.attitude(swing["device"], swing["cal"], swing["recording"], omega="array")
    paths = [str(tmp_path / n) for n in ("dev.json", "cal.json", "rec.csv")]
    save_device(swing["device"], paths[0])
    save_calibration(swing["cal"], paths[1])
    write_recording(paths[2], swing["recording"])
    out = tmp_path / "att.csv"
    assert main(["attitude", "--device", paths[0], "--calibration", paths[1], paths[2], "--omega", "array",
                 "-o", str(out)]) == 0
    lines = [ln for ln in open(out, encoding="utf-8") if not ln.startswith("#")]
    got = np.genfromtxt(lines, delimiter=",", names=True)
    assert got.dtype.names[:4] == ("t", "theta_rad", "w_y", "dw_y")
    np.testing.assert_allclose(got["w_y"], c["w_y"], atol=1e-6)
    np.testing.assert_allclose(got["theta_rad"], c["theta_rad"], atol=1e-6)
    # without --omega ("auto"): the same, the whole-file way (the chunked attitude knows two triads only)
    assert main(["attitude", "--device", paths[0], "--calibration", paths[1], paths[2], "-o", str(tmp_path / "a.csv")]) == 0
    lines = [ln for ln in open(tmp_path / "a.csv", encoding="utf-8") if not ln.startswith("#")]
    np.testing.assert_array_equal(np.genfromtxt(lines, delimiter=",", names=True), got)


def test_array_omega_refused_on_two_triads(tmp_path, capsys):
    """The pendulum's two triads (collinear): "array" gets the observability line (naming a layout
    that would), in the API and the CLI (exit 2, nothing written); "auto" is the two-triad
    estimator as before."""
    dev = pendulum_device()
    cal = Calibration.nominal(dev)
    t = np.arange(200) / dev.sample_rate_hz
    raw = np.tile(np.round(np.asarray(cal.offsets) + np.asarray(cal.sensitivity) @ [0.0, 0.0, 9.81]), (200, 1))
    rec = recording_from_arrays(t, raw.astype(np.int64))
    for fn in (attitude_from_recording, displacement_from_recording):
        with pytest.raises(InputError, match="omega is not observable.*tetrahedron"):
            fn(dev, cal, rec, omega="array")
    a, n = (attitude_from_recording(dev, cal, rec), attitude_from_recording(dev, cal, rec, omega="none"))
    for k in n:
        np.testing.assert_array_equal(a[k], n[k])
    save_device(dev, tmp_path / "dev.json")
    write_recording(tmp_path / "rec.csv", rec)
    for cmd in ("attitude", "displacement"):
        out = tmp_path / f"{cmd}.csv"
        assert main([cmd, "--device", str(tmp_path / "dev.json"), "--calibration", "nominal",
                     str(tmp_path / "rec.csv"), "--omega", "array", "-o", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "omega is not observable" in err[0], err
        assert not out.exists()


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_displacement_through_a_spin_with_the_array_omega(move_and_spin, engine):
    """Without the centripetal term the spin's omega^2 leaks into f: a turned motion that ends the
    output at the rest before it (or, kept, positions off by decimetres).  With the array's omega
    the spin about the origin is no motion of the origin: the whole recording, p within 1 % of the
    0.2 m travel, no warning."""
    d = move_and_spin
    n = d["recording"].n_samples
    moved = d["recording"].t >= 3.0 + 0.5          # after the move's end, in the rest before the spin
    for omega in ("array", "auto"):
        c = displacement_from_recording(d["device"], d["cal"], d["recording"], engine, omega=omega)
        assert len(c["t"]) == n and not c.warnings, c.warnings
        p = np.stack([c["p_x"], c["p_y"], c["p_z"]], axis=1)
        assert np.max(np.abs(p[moved] - [0.2, 0.0, 0.0])) <= 0.01 * 0.2
    c = displacement_from_recording(d["device"], d["cal"], d["recording"], engine, omega="none")
    assert len(c["t"]) < n and any("turned" in w for w in c.warnings)
    api = ac.displacement(d["device"], d["cal"], d["recording"], engine, omega="array")
    assert len(api["t"]) == n
