"""The accelcal command: the contract's forms, exit codes, one-line errors, no
partial outputs."""
import json
import subprocess
import sys

import numpy as np
import pytest

from accelcal.cli.main import main


def run(*args):
    return subprocess.run([sys.executable, "-m", "accelcal.cli.main", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    r = run("demo", "--out", out)
    assert r.returncode == 0, r.stderr
    return out, r.stdout


def test_demo_end_to_end(demo_dir):
    out, stdout = demo_dir
    s = json.loads((out / "summary.json").read_text())
    # calibration removes most of the nominal error (seed Table 1: tens of % of g offsets)
    assert s["pose_mean_abs_f_minus_g_rms_mps2"]["calibrated"] < 0.1 * s["pose_mean_abs_f_minus_g_rms_mps2"]["nominal"]
    assert s["rate_table_f_rms_error_mps2"]["calibrated_fixed_core"] < 0.1 * s["rate_table_f_rms_error_mps2"]["nominal"]
    assert s["fixed_saturated_samples"] == 0
    for name in ("device.json", "poses.csv", "calibration.json", "accelcal_calibration.h", "rate_table.csv"):
        assert (out / name).exists()
    assert "C core vs float reference" in stdout


def test_resolve_engines_agree(demo_dir, tmp_path):
    out, _ = demo_dir
    res = {}
    for engine in ("float", "fixed"):
        o = tmp_path / f"{engine}.csv"
        r = run("resolve", "--device", out / "device.json", "--calibration", out / "calibration.json",
                out / "rate_table.csv", "--engine", engine, "-o", o)
        assert r.returncode == 0, r.stderr
        lines = [ln for ln in o.read_text().splitlines() if not ln.startswith("#")]
        assert lines[0].startswith("t,f_x,f_y,f_z,dw_x,dw_y,dw_z")
        res[engine] = np.array([[float(v) for v in ln.split(",")[:7]] for ln in lines[1:]])
    assert res["float"].shape == res["fixed"].shape
    # f within a few output LSB (1/1024 m/s^2) plus the table rounding
    assert np.abs(res["float"][:, 1:4] - res["fixed"][:, 1:4]).max() < 0.01


def test_header_command(demo_dir, tmp_path):
    out, _ = demo_dir
    h = tmp_path / "cal.h"
    r = run("header", "--device", out / "device.json", "--calibration", out / "calibration.json", "-o", h)
    assert r.returncode == 0, r.stderr
    assert "#define AC_CAL_N_CHANNELS 6" in h.read_text()


@pytest.mark.parametrize("case", ["missing_file", "bad_json", "wrong_device", "nan_raw"])
def test_bad_input_one_line_no_output(demo_dir, tmp_path, case):
    out, _ = demo_dir
    dev, cal, rec = out / "device.json", out / "calibration.json", out / "rate_table.csv"
    if case == "missing_file":
        rec = tmp_path / "nope.csv"
    elif case == "bad_json":
        cal = tmp_path / "cal.json"
        cal.write_text("{not json")
    elif case == "wrong_device":
        d = json.loads(dev.read_text())
        d["name"] = "another-device"
        dev = tmp_path / "dev.json"
        dev.write_text(json.dumps(d))
    else:
        text = rec.read_text().splitlines()
        hdr = [i for i, ln in enumerate(text) if not ln.startswith("#")][0]
        cells = text[hdr + 5].split(",")
        cells[text[hdr].split(",").index("raw_2")] = "nan"
        text[hdr + 5] = ",".join(cells)
        rec = tmp_path / "rec.csv"
        rec.write_text("\n".join(text) + "\n")
    o = tmp_path / "out.csv"
    r = run("resolve", "--device", dev, "--calibration", cal, rec, "-o", o)
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "Traceback" not in r.stderr
    assert not o.exists()
    assert not list(tmp_path.glob(".out.csv*"))


def test_every_subcommand_has_help():
    for cmd in ("demo", "simulate", "calibrate", "header", "resolve"):
        with pytest.raises(SystemExit) as e:
            main([cmd, "--help"])
        assert e.value.code == 0


def test_simulate_then_calibrate_commands(tmp_path):
    rec = tmp_path / "poses.csv"
    r = run("simulate", "--device", "default", "--motion", "static_poses", "--param", "poses=\"24\"",
            "--effect", "offset:db=3", "--seed", "4", "-o", rec)
    assert r.returncode == 0, r.stderr
    cal = tmp_path / "cal.json"
    r = run("calibrate", "--device", "default", rec, "--method", "full", "-o", cal)
    assert r.returncode == 0, r.stderr
    c = json.loads(cal.read_text())
    assert c["method"] == "full" and len(c["channels"]) == 6
    # the same data without any reference: jig-free is the default, and needs no jig
    r = run("simulate", "--device", "default", "--motion", "handheld", "--param", "n_poses=16",
            "--seed", "5", "-o", tmp_path / "hand.csv")
    assert r.returncode == 0, r.stderr


def test_simulate_rejects_unknown_effect(tmp_path):
    out = tmp_path / "x.csv"
    r = run("simulate", "--device", "default", "--motion", "rate_table", "--effect", "gian:scale=0.1", "-o", out)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and not out.exists()


def test_attitude_command_tracks_the_pendulum(tmp_path):
    from accelcal.io.calibration import Calibration, save_calibration
    from accelcal.io.device import pendulum_device, save_device
    from accelcal.io.recording import read_recording
    d = pendulum_device()
    save_device(d, tmp_path / "dev.json")
    save_calibration(Calibration.nominal(d), tmp_path / "cal.json")
    rec = tmp_path / "p.csv"
    assert run("simulate", "--device", tmp_path / "dev.json", "--motion", "pendulum", "--seed", 3,
               "-o", rec).returncode == 0
    out = tmp_path / "att.csv"
    r = run("attitude", "--device", tmp_path / "dev.json", "--calibration", tmp_path / "cal.json", rec,
            "--engine", "fixed", "-o", out)
    assert r.returncode == 0, r.stderr
    lines = [ln for ln in out.read_text().splitlines() if not ln.startswith("#")]
    assert lines[0].startswith("t,theta_rad,w_y,dw_y")
    theta = np.array([float(ln.split(",")[1]) for ln in lines[1:]])
    truth = read_recording(rec)
    theta_true = np.arctan2(-truth.f[:, 0], truth.f[:, 2])
    assert np.degrees(np.sqrt(np.mean((theta - theta_true) ** 2))) < 0.3


def test_pendulum_with_equal_radii_is_refused(tmp_path):
    d = {"name": "bad-pendulum", "sample_rate_hz": 100.0, "gravity_mps2": 9.80665, "raw_min": 0,
         "raw_max": 65535, "channels": [
             {"position_m": [0.2, 0, 0], "axis": ax, "counts_per_mps2": 1670.0, "zero_counts": 32768}
             for ax in ([1, 0, 0], [0, 1, 0], [0, 0, 1])] * 2}
    (tmp_path / "dev.json").write_text(json.dumps(d))
    from accelcal.io.calibration import Calibration, save_calibration
    from accelcal.io.device import load_device
    save_calibration(Calibration.nominal(load_device(tmp_path / "dev.json")), tmp_path / "cal.json")
    rec = tmp_path / "p.csv"
    rec.write_text("t," + ",".join(f"raw_{i}" for i in range(6)) + "\n" +
                   "".join(f"{k / 100},32768,32768,49152,32768,32768,49152\n" for k in range(50)))
    out = tmp_path / "att.csv"
    r = run("attitude", "--device", tmp_path / "dev.json", "--calibration", tmp_path / "cal.json", rec,
            "-o", out)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and not out.exists(), r.stderr


def test_diagnose_command_finds_a_withheld_gain(tmp_path, demo_dir):
    out, _ = demo_dir
    rec = tmp_path / "r.csv"
    truth = out / "calibration.json"  # simulate with the calibrated parameters as the truth
    r = run("simulate", "--device", out / "device.json", "--calibration", truth, "--motion", "rate_table",
            "--param", "amplitude_deg=30", "--param", "rest_s=2", "--effect", "gain:scale=0.03,channel=0",
            "--seed", 2, "-o", rec)
    assert r.returncode == 0, r.stderr
    j = tmp_path / "d.json"
    r = run("diagnose", "--device", out / "device.json", "--calibration", truth, rec, "--json", j,
            "--report", tmp_path / "rep")
    assert r.returncode == 0, r.stderr
    assert r.stderr == ""  # no progress bar when stderr is not a terminal
    d = json.loads(j.read_text())
    assert d["verdict"] == "gain"
    assert d["effects"][0]["shrink"] > 0.5
    assert (tmp_path / "rep" / "summary.md").exists()
    # on a terminal: progress bars for the candidate fits and the report's files
    import os
    import pty
    import fcntl
    import struct
    import termios
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))  # a pty starts 0 columns wide
    chunks = []
    try:
        p = subprocess.Popen([sys.executable, "-m", "accelcal.cli.main", "diagnose", "--device", str(out / "device.json"),
                              "--calibration", str(truth), str(rec), "--json", str(tmp_path / "d2.json"),
                              "--report", str(tmp_path / "rep2")], stdout=subprocess.DEVNULL, stderr=slave)
        os.close(slave)
        while True:  # read while it runs: a pty drops what is unread when the child side closes
            try:
                b = os.read(master, 65536)
            except OSError:  # EIO: the child side is closed
                break
            if not b:
                break
            chunks.append(b)
        p.wait(timeout=300)
    finally:
        os.close(master)
    tty = b"".join(chunks).decode("utf-8", "replace")
    assert p.returncode == 0, tty
    assert "diagnose: scoring candidates" in tty and "fits" in tty, tty
    assert "diagnose: writing the report" in tty and "/4 " in tty, tty
    assert json.loads((tmp_path / "d2.json").read_text())["verdict"] == "gain"
