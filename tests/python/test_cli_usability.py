"""What a user notices at the command line: help for every option, a summary on
success, one-line errors for unusable output paths, ignored columns mentioned."""
import argparse
import json

import numpy as np
import pytest

from accelcal.cli.main import build_parser, main
from accelcal.io.device import default_device
from accelcal.io.recording import read_recording, write_recording
from accelcal.io.recording_checks import seconds


def _subparsers(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            yield from action.choices.items()


def test_every_option_has_help():
    missing = []
    for name, sub in _subparsers(build_parser()):
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            if not action.help:
                missing.append(f"{name} {'/'.join(action.option_strings) or action.dest}")
    assert not missing, f"options without help text: {missing}"


@pytest.fixture(scope="module")
def poses(tmp_path_factory):
    d = tmp_path_factory.mktemp("poses")
    rec = d / "poses.csv"
    assert main(["simulate", "--device", "default", "--motion", "static_poses", "--param", 'poses="24"',
                 "--seed", "3", "-o", str(rec)]) == 0
    return rec


def test_calibrate_prints_a_summary(poses, tmp_path, capsys):
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--device", "default", str(poses), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    cal = json.loads(out.read_text())
    assert f"from {len(cal['poses_used'])} static poses" in text
    chi2, dof = cal["fit"]["chi2"], cal["fit"]["dof"]
    assert f"chi2/dof {chi2 / dof:.3g} ({dof} dof)" in text
    rms = np.sqrt(np.mean(np.square(cal["residual_rms_counts"]["per_channel"])))
    assert f"Residual rms {rms:.3g} counts" in text


@pytest.mark.parametrize("command", ["calibrate", "simulate", "diagnose", "header", "displacement"])
def test_output_in_a_missing_directory_is_one_line_exit_2(command, poses, tmp_path, capsys):
    target = tmp_path / "no" / "such" / "dir" / "out"
    cal = tmp_path / "cal.json"
    assert main(["calibrate", "--device", "default", str(poses), "-o", str(cal)]) == 0
    capsys.readouterr()
    args = {"calibrate": ["calibrate", "--device", "default", str(poses), "-o", str(target)],
            "simulate": ["simulate", "--device", "default", "--motion", "static_poses", "-o", str(target)],
            "diagnose": ["diagnose", "--device", "default", "--calibration", str(cal), str(poses),
                         "--json", str(target)],
            "header": ["header", "--device", "default", "--calibration", str(cal), "-o", str(target)],
            "displacement": ["displacement", "--device", "default", "--calibration", str(cal), str(poses),
                             "-o", str(target)]}[command]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert "does not exist" in err[0] and "internal error" not in err[0]
    assert not (tmp_path / "no").exists()


def test_output_that_is_a_directory_is_refused(poses, tmp_path, capsys):
    assert main(["calibrate", "--device", "default", str(poses), "-o", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err


def test_ignored_columns_are_named_once(poses, tmp_path, capsys):
    rec = read_recording(poses, 6)
    n = rec.t.shape[0]
    rec.extra = {"gyro_x": ["0.0"] * n, "gyro_y": ["0.0"] * n}
    path, copy = tmp_path / "with_gyro.csv", tmp_path / "with_gyro_2.csv"
    write_recording(path, rec)
    write_recording(copy, rec)                  # two recordings (one file twice is refused)
    assert main(["calibrate", "--device", "default", str(path), str(copy), "-o", str(tmp_path / "c.json")]) == 0
    err = capsys.readouterr().err
    assert err.count("ignored columns gyro_x, gyro_y") == 1


def test_jig_warning_only_with_cross_axis_terms(tmp_path, capsys):
    # a jig off by 2 deg: with the references stated exact (--jig-accuracy 0) the full model is
    # told to state the jig accuracy; the gain model (no cross-axis terms) is told what it lacks
    # instead.  The default estimates it: no warning for full, the gain model still told
    rec = tmp_path / "tilted.csv"
    assert main(["simulate", "--device", "default", "--motion", "static_poses", "--param", 'poses="24"',
                 "--effect", "pose_error:angle_deg=2", "--seed", "5", "-o", str(rec)]) == 0
    capsys.readouterr()
    assert main(["calibrate", "--device", "default", str(rec), "--jig-accuracy", "0",
                 "-o", str(tmp_path / "f.json")]) == 0
    err = capsys.readouterr().err
    assert "--jig-accuracy" in err
    assert main(["calibrate", "--device", "default", "--method", "gain", str(rec), "--jig-accuracy", "0",
                 "-o", str(tmp_path / "g.json")]) == 0
    err = capsys.readouterr().err
    assert "--jig-accuracy" not in err
    assert "no cross-axis terms" in err
    assert main(["calibrate", "--device", "default", str(rec), "-o", str(tmp_path / "fa.json")]) == 0
    out = capsys.readouterr()
    assert "--jig-accuracy" not in out.err and "scatter" not in out.err, out.err
    assert "Jig accuracy estimated from the poses' scatter" in out.out, out.out
    assert main(["calibrate", "--device", "default", "--method", "gain", str(rec),
                 "-o", str(tmp_path / "ga.json")]) == 0
    err = capsys.readouterr().err
    assert "no cross-axis terms" in err and "jig accuracy estimated" in err, err


@pytest.mark.parametrize("factor,unit", [(1e3, "milliseconds"), (1e6, "microseconds")])
def test_time_stamps_in_milliseconds_are_read_as_such(poses, tmp_path, capsys, factor, unit):
    """A logger's millis() or micros() as t: every command reads it in seconds and says so once;
    resolve writes the same rows as from the file in seconds."""
    cal = tmp_path / "cal.json"
    assert main(["calibrate", "--device", "default", str(poses), "-o", str(cal)]) == 0
    rec = read_recording(poses, 6)
    scaled = tmp_path / "scaled.csv"
    rec.t = rec.t * factor
    write_recording(scaled, rec)
    capsys.readouterr()
    out_s, out_x = tmp_path / "s.csv", tmp_path / "x.csv"
    assert main(["resolve", "--device", "default", "--calibration", str(cal), str(poses), "-o", str(out_s)]) == 0
    assert capsys.readouterr().err == ""
    assert main(["resolve", "--device", "default", "--calibration", str(cal), str(scaled), "-o", str(out_x)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"t read as {unit}" in err[0], err
    a, b = (np.array([[float(v) for v in line.split(",")]
                      for line in [x for x in p.read_text().splitlines() if x and not x.startswith("#")][1:]])
            for p in (out_s, out_x))
    assert np.allclose(a, b, rtol=1e-9, atol=1e-9)
    js = tmp_path / "d.json"
    assert main(["diagnose", "--device", "default", "--calibration", str(cal), str(scaled), "--json", str(js)]) == 0
    assert f"t read as {unit}" in capsys.readouterr().err
    assert any(f"t read as {unit}" in n for n in json.loads(js.read_text())["notes"])


def test_a_rate_that_differs_otherwise_leaves_t_alone(poses):
    """Steps twice the device's period (a logger at half the rate) are not a unit: t stays."""
    rec = read_recording(poses, 6)
    rec.t = rec.t * 2
    t = rec.t.copy()
    assert seconds(rec, default_device()) is None and np.array_equal(rec.t, t) and rec.notes == []
    rec.t = rec.t * 500                                   # now milliseconds of the device's period
    assert "milliseconds" in seconds(rec, default_device())
    assert seconds(rec, default_device()) is None and len(rec.notes) == 1   # a second call finds seconds
