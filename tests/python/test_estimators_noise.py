"""The estimators with a device file that holds only the contract's fields (no
``noise_mps2``): their rest tests take the noise from the recording (issue 13).

The stop-to-stop recordings here are written with numpy from the physics alone (a
level triad, a one-period sine of acceleration along x: distance A T^2 / (2 pi)), not
by the package's simulator."""
import dataclasses
import json
import math

import numpy as np
import pytest

from accelcal import estimators as E
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.cli.main import main
from accelcal.io.device import Device, default_device
from accelcal.errors import InputError
from accelcal.io.recording import recording_from_arrays, write_recording
from accelcal.simulate import run_simulation
from estimator_devices import G, adxl_pendulum_device

PEAK = 2.0          # m/s^2
TRAVEL = 2.0        # s
DISTANCE = PEAK * TRAVEL ** 2 / (2 * math.pi)


def contract_triad(rate, signed):
    """An MPU-6050-like signed 16-bit triad (+-2 g) or an ADXL-like 0..10000 one."""
    if signed:
        return Device(name="mpu6050", sample_rate_hz=rate, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                      positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 16384 / G),
                      zero_counts=np.zeros(3))
    return Device(name="adxl", sample_rate_hz=rate, gravity_mps2=G, raw_min=0, raw_max=10000,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1250 / G),
                  zero_counts=np.full(3, 5000.0))


def stop_to_stop(d, sigma, seed, rest_s=2.0):
    rate = d.sample_rate_hz
    rng = np.random.default_rng(seed)
    n1, nm = int(rest_s * rate), int(TRAVEL * rate)
    a = np.zeros(2 * n1 + nm)
    a[n1:n1 + nm] = PEAK * np.sin(2 * np.pi * np.arange(nm) / nm)
    f = np.column_stack([a, np.zeros_like(a), np.full_like(a, G)])
    f = f + rng.normal(0, sigma, f.shape) + np.array([0.03, -0.02, 0.01])   # noise and a zero-point error
    raw = np.round(f * d.counts_per_mps2 + d.zero_counts).astype(np.int64)
    return recording_from_arrays(np.arange(len(a)) / rate, raw)


@pytest.mark.parametrize("signed", [True, False])
@pytest.mark.parametrize("rate", [50.0, 1000.0])
@pytest.mark.parametrize("sigma", [0.002, 0.05])
def test_displacement_finds_rest_at_any_noise_without_noise_mps2(signed, rate, sigma):
    d = contract_triad(rate, signed)
    assert d.noise_mps2 == 0.0
    for seed in range(2):
        rec = stop_to_stop(d, sigma, seed)
        c = E.displacement_from_recording(d, Calibration.nominal(d), rec, "float", axis="x")
        assert c["rest"][int(rate)] == 1 and c["rest"][-1] == 1     # 1 s into each rest
        assert c["corrected"].any()
        # the velocity random walk of white noise over the travel: sigma dt sqrt(n) ~ 0.002 m/s at
        # 50 Hz, 0.05 m/s^2, i.e. ~ 0.3 % of the distance; 1 % leaves room for the rest edges
        assert abs(c["p_x"][-1] - DISTANCE) <= 0.01 * DISTANCE


def contract_files(tmp_path) -> None:
    """dev.json (the contract's fields only: an ADXL-like 0..10000 triad at 100 Hz), rec.csv (the
    issue's stop-to-stop case: 2 s rest / 2 s travel / 2 s rest, 0.02 m/s^2) and cal.json (nominal)."""
    d = contract_triad(100.0, signed=False)
    dev = {"name": d.name, "sample_rate_hz": 100.0, "gravity_mps2": G, "raw_min": 0, "raw_max": 10000,
           "channels": [{"position_m": [0, 0, 0], "axis": list(np.eye(3)[i]), "counts_per_mps2": 1250 / G,
                         "zero_counts": 5000} for i in range(3)]}
    (tmp_path / "dev.json").write_text(json.dumps(dev))
    write_recording(tmp_path / "rec.csv", stop_to_stop(d, 0.02, 7))
    save_calibration(Calibration.nominal(d), tmp_path / "cal.json")


def test_cli_displacement_with_a_contract_only_device_file(tmp_path):
    """The issue's case: level triad, 100 Hz, 0.02 m/s^2, 2 s rest / 2 s travel / 2 s rest."""
    contract_files(tmp_path)
    rc = main(["displacement", "--device", str(tmp_path / "dev.json"), "--calibration", str(tmp_path / "cal.json"),
               "--output", str(tmp_path / "out.csv"), "--axis", "x", str(tmp_path / "rec.csv")])
    assert rc == 0
    lines = [ln for ln in (tmp_path / "out.csv").read_text().splitlines() if not ln.startswith("#")]
    last = dict(zip(lines[0].split(","), lines[-1].split(",")))
    assert abs(float(last["p_x"]) - DISTANCE) <= 0.01 * DISTANCE


def test_cli_calibration_nominal_is_the_device_file_s_datasheet_values(tmp_path, capfd, monkeypatch):
    """--calibration nominal: the device file's values, without writing a calibration JSON by
    hand (a new user's first run, before any calibration exists): the same output as the saved
    Calibration.nominal."""
    contract_files(tmp_path)
    for cal, out in ((str(tmp_path / "cal.json"), "a.csv"), ("nominal", "b.csv")):
        assert main(["displacement", "--device", str(tmp_path / "dev.json"), "--calibration", cal,
                     "--output", str(tmp_path / out), "--axis", "x", str(tmp_path / "rec.csv")]) == 0
    body = [[ln for ln in (tmp_path / o).read_text().splitlines() if not ln.startswith("#")] for o in ("a.csv", "b.csv")]
    assert body[0] == body[1] and len(body[0]) > 100
    # a directory of that name beside does not stand in for it
    (tmp_path / "nominal").mkdir()
    monkeypatch.chdir(tmp_path)
    assert main(["displacement", "--device", str(tmp_path / "dev.json"), "--calibration", "nominal",
                 "--output", str(tmp_path / "c.csv"), "--axis", "x", str(tmp_path / "rec.csv")]) == 0


def test_no_rest_names_the_stillest_stretch_and_why_it_is_no_rest():
    """An uncalibrated chip reading 7.7 % high (a real LSM303 with its nominal scale: |f| =
    10.56 m/s^2) had "no rest was detected anywhere" with no word of its |f|; the error names the
    stillest stretch, its |f| and the cause.  A body that never stops: how far its stillest
    stretch strays."""
    d = contract_triad(100.0, signed=False)
    rec = stop_to_stop(d, 0.02, 3)
    high = dataclasses.replace(rec, raw=np.round(5000 + 1.077 * (rec.raw - 5000)).astype(np.int64))
    with pytest.raises(InputError) as ei:
        E.displacement_from_recording(d, Calibration.nominal(d), high, "float", axis="x")
    msg = str(ei.value)
    assert "no rest was detected anywhere" in msg and "the calibration's scale is off" in msg, msg
    norm = float(msg.split("read |f| = ")[1].split(" ")[0])
    assert abs(norm - 1.077 * G) < 0.05, msg
    with pytest.raises(InputError) as ei:                  # the C core's f, in its fixed point, said in m/s^2
        E.displacement_from_recording(d, Calibration.nominal(d), high, "fixed")
    assert "the calibration's scale is off" in str(ei.value), str(ei.value)
    assert abs(float(str(ei.value).split("read |f| = ")[1].split(" ")[0]) - 1.077 * G) < 0.05
    # a body that turns slowly throughout: each short stretch is nearly still at |f| = g, but
    # the detector's running mean never settles (it had been blamed on the calibration's scale)
    dd = default_device()
    t = np.arange(1200) / 60.0
    th = np.radians(-20 + 5.0 * t)
    f = G * np.column_stack([np.sin(th), np.zeros_like(th), np.cos(th)])
    raw = dd.zero_counts + (f @ dd.axes.T) * dd.counts_per_mps2 + np.random.default_rng(0).normal(0, 1, (1200, 6))
    turning = recording_from_arrays(t, np.round(raw).astype(np.int64))
    with pytest.raises(InputError) as ei:
        E.displacement_from_recording(dd, Calibration.nominal(dd), turning, "float")
    assert "creeps or turns slowly" in str(ei.value) and "scale is off" not in str(ei.value), str(ei.value)
    t = np.arange(600) / 100.0
    moving = recording_from_arrays(t, np.round(5000 + 1250 * np.column_stack(
        [np.sin(2 * np.pi * t), np.cos(2 * np.pi * t), np.ones_like(t)])).astype(np.int64))
    with pytest.raises(InputError, match=r"stray [0-9.]+ m/s\^2 from their mean, beyond the rest's .*never stops"):
        E.displacement_from_recording(d, Calibration.nominal(d), moving, "float", axis="x")


def test_rate_without_noise_mps2_matches_the_stated_noise():
    d = default_device()
    rec = run_simulation(d, "lane_change", seed=3).recording
    bare = dataclasses.replace(d, noise_mps2=0.0)
    cal = Calibration.nominal(d)
    stated = E.rate_from_recording(d, cal, rec, "float", leak_tau_s=5.0)
    est = E.rate_from_recording(bare, cal, rec, "float", leak_tau_s=5.0)
    e = [np.sqrt(np.mean((c["w_z"] - rec.w[:, 2]) ** 2)) for c in (stated, est)]
    assert e[1] < 0.03 and e[1] <= 1.2 * e[0]
    assert abs(est["rest"].mean() - stated["rest"].mean()) < 0.05


def test_no_rest_found_in_a_recording_that_moves_throughout():
    """A pendulum swings all the time: no window is at rest, so the noise is not taken from
    the motion's window std (that would call the turning points rest and reset omega)."""
    d = default_device()
    rec = run_simulation(d, "pendulum", seed=3).recording
    bare = dataclasses.replace(d, noise_mps2=0.0)
    cal = Calibration.nominal(d)
    est = E.rate_from_recording(bare, cal, rec, "float", leak_tau_s=5.0)
    assert est["rest"].sum() == 0
    w = np.column_stack([est["w_x"], est["w_y"], est["w_z"]])
    assert np.sqrt(np.mean((w - rec.w) ** 2)) < 0.2


def test_attitude_without_noise_mps2():
    d = adxl_pendulum_device()
    rec = run_simulation(d, "pendulum", seed=11, duration_s=20.0, amplitude_deg=40.0, freq_hz=0.5).recording
    bare = dataclasses.replace(d, noise_mps2=0.0)
    cols = E.attitude_from_recording(bare, Calibration.nominal(d), rec, "float")
    th_ref = np.arctan2(-rec.f[:, 0], rec.f[:, 2])
    e_th = np.degrees(np.angle(np.exp(1j * (cols["theta_rad"] - th_ref))))
    assert np.sqrt(np.mean(e_th ** 2)) <= 0.3
    assert np.sqrt(np.mean((cols["w_y"] - rec.w[:, 1]) ** 2)) <= 0.03


@pytest.mark.parametrize("sigma,warned", [(0.05, False), (0.15, True)])
def test_a_rest_test_as_wide_as_vibration_is_warned_of(sigma, warned):
    """A rocket's vibration throughout (RocketPy's CATS log) made the noise estimated from the data
    0.13 m/s^2 and the rest test 0.67 m/s^2 wide: a moment of coasting at |f| ~ g passed for a
    rest, and 370 km came out.  A test wider than 0.4 m/s^2 is warned of; the noisiest sensor at
    rest of issue 13's range (0.05 m/s^2) is not."""
    d = contract_triad(100.0, signed=False)
    c = E.displacement_from_recording(d, Calibration.nominal(d), stop_to_stop(d, sigma, 2), "float", axis="x")
    assert any("so a slow motion may pass for a rest" in w for w in c.warnings) == warned, c.warnings
