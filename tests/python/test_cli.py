"""The accelcal command: the contract's forms, exit codes, one-line errors, no
partial outputs."""
import json
import subprocess
import sys

import numpy as np
import pytest

from accelcal.cli import main


def run(*args):
    return subprocess.run([sys.executable, "-m", "accelcal.cli", *map(str, args)],
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
