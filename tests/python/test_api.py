"""The Python API (``import accelcal as ac``): the same results as the command line,
numpy arrays accepted, bad arrays refused with one line, docstring examples run."""
import argparse
import doctest
import importlib
import inspect
import json

import numpy as np
import pytest

import accelcal as ac
from accelcal.cli.main import main
from accelcal.cli.convert_command import add_convert_parser
from accelcal.errors import AccelcalError


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    d = tmp_path_factory.mktemp("api")
    dev = ac.default_device()
    rec = ac.simulate(dev, "static_poses", poses="24", seed=2)
    ac.write_recording(d / "poses.csv", rec)
    return d, dev, rec


def test_calibrate_equals_the_command(setup):
    d, dev, rec = setup
    assert main(["calibrate", "--device", "default", str(d / "poses.csv"), "-o", str(d / "cal.json")]) == 0
    via_cli = ac.load_calibration(d / "cal.json", dev)
    via_api = ac.calibrate(dev, ac.read_recording(d / "poses.csv", dev))
    np.testing.assert_array_equal(via_api.offsets, via_cli.offsets)
    np.testing.assert_array_equal(via_api.sensitivity, via_cli.sensitivity)


def test_header_equals_the_command(setup):
    d, dev, rec = setup
    cal = ac.calibrate(dev, rec)
    ac.save_calibration(cal, d / "c2.json")
    assert main(["header", "--device", "default", "--calibration", str(d / "c2.json"), "-o", str(d / "c.h")]) == 0
    assert ac.header(dev, d / "c2.json") == (d / "c.h").read_text()


def test_resolve_takes_a_raw_array(setup):
    _, dev, rec = setup
    cal = ac.calibrate(dev, rec)
    a = ac.resolve(dev, cal, rec, engine="fixed")
    b = ac.resolve(dev, cal, np.asarray(rec.raw, dtype=np.int32), engine="fixed")
    np.testing.assert_array_equal(a.f, b.f)
    assert b.t[1] == pytest.approx(1.0 / dev.sample_rate_hz)
    # integral floats are counts too; anything else is refused in one line naming the row
    c = ac.resolve(dev, cal, rec.raw.astype(float))
    np.testing.assert_array_equal(c.f, ac.resolve(dev, cal, rec).f)
    bad = rec.raw.astype(float)
    bad[7, 2] += 0.5
    with pytest.raises(AccelcalError, match="row 8: "):     # index 7: rows count from 1, as in every message
        ac.resolve(dev, cal, bad)
    with pytest.raises(AccelcalError, match=r"\(n, 6\)"):
        ac.resolve(dev, cal, rec.raw[:, :3])


def test_public_names_are_documented():
    for name in ac.__all__:
        obj = getattr(ac, name)
        if callable(obj):
            assert obj.__doc__, name


@pytest.mark.parametrize("call, function, wrong, right", [
    (lambda d, dev, rec, cal: ac.calibrate(dev, rec, jig_acuracy_deg=1), "calibrate", "jig_acuracy_deg",
     "jig_accuracy_deg"),
    (lambda d, dev, rec, cal: ac.diagnose(dev, cal, rec, fold=3), "diagnose", "fold", "folds"),
    (lambda d, dev, rec, cal: ac.resolve(dev, cal, rec, engin="fixed"), "resolve", "engin", "engine"),
    (lambda d, dev, rec, cal: ac.convert(d / "absent.csv", rate=100), "convert", "rate", "rate_hz"),
    (lambda d, dev, rec, cal: ac.read_recording(d / "poses.csv", unit="g"), "read_recording", "unit", "units"),
    (lambda d, dev, rec, cal: ac.header(dev, cal, prefx="X"), "header", "prefx", "prefix"),
    (lambda d, dev, rec, cal: ac.simulate(dev, "static_poses", efects=["x"]), "simulate", "efects", "effects"),
    (lambda d, dev, rec, cal: ac.simulate(dev, "static_poses", pose="24"), "simulate", "pose", "poses"),
    (lambda d, dev, rec, cal: ac.attitude(dev, cal, rec, gian=2.0), "attitude", "gian", "gain"),
    (lambda d, dev, rec, cal: ac.displacement(dev, cal, rec, axs="x"), "displacement", "axs", "axis"),
    (lambda d, dev, rec, cal: ac.rate(dev, cal, rec, leak_tau=1.0), "rate", "leak_tau", "leak_tau_s"),
])
def test_a_misspelt_option_names_the_public_function_and_the_closest(setup, call, function, wrong, right):
    """A misspelt keyword option: Python's TypeError had named the internal function it was
    forwarded to (``attitude_from_recording() got an unexpected keyword argument``) and suggested
    nothing.  Now an OptionError -- a TypeError, as Python's convention has it, and an
    AccelcalError, one line, as every accelcal error -- naming ``accelcal.<function>()``, the
    option and the closest valid one, raised before any work (convert's file is absent)."""
    d, dev, rec = setup
    cal = ac.calibrate(dev, rec)
    with pytest.raises(TypeError) as e:
        call(d, dev, rec, cal)
    msg = str(e.value)
    assert isinstance(e.value, AccelcalError) and "\n" not in msg, msg
    assert msg.startswith(f"accelcal.{function}(): unknown option {wrong!r} (did you mean {right!r}?)"), msg


def test_public_dataclasses_document_every_field():
    """Each public dataclass's numpydoc Attributes section names every field (with its unit there)."""
    import dataclasses
    import inspect
    import re
    for name in ac.__all__:
        obj = getattr(ac, name)
        if not (inspect.isclass(obj) and dataclasses.is_dataclass(obj)):
            continue
        doc = inspect.getdoc(obj) or ""
        assert "Attributes\n----------\n" in doc, f"{name}: no Attributes section"
        section = doc.split("Attributes\n----------\n", 1)[1]
        named = {w.strip() for line in section.splitlines() if line and not line.startswith(" ")
                 for w in re.split(r",", line.split(" : ")[0])}
        missing = [f.name for f in dataclasses.fields(obj) if f.name not in named]
        assert not missing, f"{name}: fields not in its Attributes section: {missing}"


def test_docstring_examples_run():
    api = importlib.import_module("accelcal.api")
    result = doctest.testmod(api, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_api_page_is_generated_from_the_docstrings():
    import subprocess
    import sys
    from pathlib import Path
    tool = Path(__file__).resolve().parents[2] / "tools" / "gen_api_doc.py"
    r = subprocess.run([sys.executable, str(tool), "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_readme_python_session_runs(tmp_path, monkeypatch):
    """The README's Python session, run as written (in a scratch directory)."""
    import re
    from pathlib import Path
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text()
    block = re.search(r"## Python\n\n```python\n(.*?)```", readme, re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    assert (tmp_path / "cal.json").exists() and (tmp_path / "calibration.h").exists()


def test_writing_into_a_missing_directory_is_an_accelcal_error(tmp_path):
    """The README promises AccelcalError for bad input from Python too: an output in a
    directory that does not exist was a FileNotFoundError naming a temporary file."""
    dev = ac.default_device()
    cal = ac.Calibration.nominal(dev)
    with pytest.raises(ac.AccelcalError, match="does not exist"):
        ac.header(dev, cal, output=tmp_path / "nope" / "x.h")
    with pytest.raises(ac.AccelcalError, match="is a directory"):
        ac.header(dev, cal, output=tmp_path)


@pytest.mark.parametrize("deg", [25.0, 90.0])
def test_a_jig_accuracy_no_jig_has_is_refused(deg):
    with pytest.raises(ac.AccelcalError, match="small-angle"):
        ac.calibrate(ac.default_device(), ac.simulate(ac.default_device(), "static_poses", poses="24", seed=1),
                     jig_accuracy_deg=deg)


def test_calibrate_reads_a_list_of_rows_as_one_array(setup):
    """``ac.calibrate(dev, raw.tolist())`` had been read as n recordings of one sample each
    (no usable static pose in any); a list of equal-length rows of numbers is one array, as
    resolve reads it; a list of arrays stays a list of recordings."""
    _, dev, rec = setup
    raw = rec.raw[rec.pose >= 0]
    want = ac.calibrate(dev, raw)
    got = ac.calibrate(dev, raw.tolist())
    np.testing.assert_array_equal(got.offsets, want.offsets)
    np.testing.assert_array_equal(ac.calibrate(dev, [tuple(r) for r in raw.tolist()]).offsets, want.offsets)
    half = raw.shape[0] // 2
    assert ac.calibrate(dev, [raw[:half], raw[half:]]).offsets.shape == want.offsets.shape


def test_several_recordings_without_a_pose_give_each_one_s_reason(tmp_path):
    """Calibrate given several recordings none of which has a static pose had said one bare line
    naming the first file and lever arms (a triad has none); now it gives each file's own
    reason, the one-recording refusal's text, on one line."""
    (tmp_path / "d.json").write_text(json.dumps({
        "name": "bike", "sample_rate_hz": 208.0, "gravity_mps2": 9.80665, "raw_min": -32768, "raw_max": 32767,
        "channels": [{"position_m": [0, 0, 0], "axis": a, "counts_per_mps2": 835.35, "zero_counts": 0}
                     for a in ([1, 0, 0], [0, 1, 0], [0, 0, 1])]}))
    dev = ac.load_device(tmp_path / "d.json")
    rng = np.random.default_rng(2)
    recs = []
    for k in (1, 2):                           # a ride: the force swings, no still stretch
        t = np.arange(2000) / 208.0
        f = np.c_[3 * np.sin(2 * np.pi * 1.3 * t), 2 * np.sin(2 * np.pi * 0.7 * t), 9.8 + 4 * np.sin(2 * np.pi * 2.1 * t)]
        raw = np.rint(f * 835.35 + rng.normal(0, 400, (t.size, 3))).astype(np.int64)
        recs.append(ac.Recording(t=t, raw=raw, source=f"ride{k}.csv"))
    with pytest.raises(AccelcalError) as e:
        ac.calibrate(dev, recs)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("2 recordings: no usable static pose in any recording"), msg
    assert "lever arms" not in msg, msg
    for k in (1, 2):
        assert f"ride{k}.csv: no static pose found" in msg and "its noise on raw_0" in msg, msg


def test_convert_takes_every_option_of_the_command(tmp_path):
    """ac.convert lacked time_column, time_unit, round, columns, repeated_stamps and variable
    (each an OptionError), so the API could not convert files the command can; every option of
    ``accelcal convert`` but its outputs is now a keyword of ac.convert, and they act alike."""
    parser = argparse.ArgumentParser()
    add_convert_parser(parser.add_subparsers(), lambda *a: None)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices["convert"]
    renamed = {"input": "path", "format": "fmt", "rate": "rate_hz", "gravity": "gravity_mps2",
               "full_scale": "full_scale_g"}
    # (--whole-file, --quiet: how the command reads the file and writes its output; ac.convert returns the
    # recording in memory, read whole)
    dests = {renamed.get(a.dest, a.dest) for a in sub._actions
             if a.dest not in ("help", "output", "device_out", "whole_file", "quiet")}
    assert dests <= set(inspect.signature(ac.convert).parameters), dests - set(inspect.signature(ac.convert).parameters)
    src = tmp_path / "tw.csv"
    src.write_text("ms,ax,ay,az\n" + "".join(f"{10 * i},{0.01 * i:.2f},0.0,1.0\n" for i in range(50)))
    c = ac.convert(src, columns="ax,ay,az", time_column="ms", time_unit="2ms", units="g", lsb=0.01, rate_hz=None)
    assert c.recording.t[1] == pytest.approx(0.02) and c.recording.raw[5, 0] == 5
    doc = ac.convert.__doc__
    assert '"mmps2", "g", "mg"' in doc and '"table", "mat", "e4"' in doc


def test_a_misspelt_nominal_is_suggested(setup):
    """ac.resolve(dev, "nomimal", ...) said "cannot read the file"; it now suggests 'nominal'."""
    _, dev, rec = setup
    with pytest.raises(AccelcalError, match=r"^nomimal: no such calibration file; did you mean 'nominal'"):
        ac.resolve(dev, "nomimal", rec)
    with pytest.raises(AccelcalError, match="cannot read the file"):
        ac.resolve(dev, "cal.json", rec)
