"""Rate with reset on rest against its float twin and the simulator; the command-line
runner, the CSV writer and the plots; the estimators' imports."""
import ast
import io
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, strategies as st

from accelcal import estimators as E, model
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.cli.main import main, run_estimator
from accelcal.io.device import default_device, default_triad, save_device
from accelcal.errors import InputError
from accelcal.io.recording import write_columns_csv, write_recording
from accelcal.simulate import run_simulation
from core_settings import estimator
from estimator_devices import G, adxl_pendulum_device


@st.composite
def rate_runs(draw):
    n = draw(st.integers(1, 200))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    alpha = rng.normal(0, draw(st.sampled_from([0.01, 0.5, 5.0])), (n, 3))
    f = np.tile([0.0, 0.0, G], (n, 1)) + rng.normal(0, 0.01, (n, 3))
    if draw(st.booleans()):
        s = int(rng.integers(0, n))
        f[s:s + 30] += 1.0
    rest = E.RestParams(dev_max=0.05, hold=draw(st.integers(1, 20)), ema_shift=3,
                        alpha_max=draw(st.sampled_from([math.inf, 1.0])))
    return E.q_out(alpha), E.q_out(f), 1 / draw(st.sampled_from([60.0, 100.0])), draw(st.integers(0, 2000)), rest


@estimator
@given(rate_runs())
def test_rate_rest_fixed_vs_twin(run):
    a_q, f_q, dt, leak_q, rest = run
    w, fl, sat = E.rate_rest_fixed(a_q, f_q, dt, leak_q, rest)
    dm, dsh = E.dt_fixed(dt)
    tw, _ = E.rate_rest_float(a_q / 1024.0, None, dm * 2.0**-dsh, leak_q / 65536.0, rest, rest_flags=fl)
    # two roundings of at most 2^-27 per step (ac_rate.h) since the last reset, + output rounding
    since = np.zeros(len(fl))
    k = 0
    for i in range(len(fl)):
        k = 0 if fl[i] & E.REST_AT_REST else k + 1
        since[i] = k
    bound = 2.0**-11 + since * 2.0**-26
    ok = ~sat
    assert np.all(np.abs(w / 1024.0 - tw)[ok] <= bound[ok, None])
    assert np.all(w[(fl & E.REST_AT_REST) != 0] == 0)


def test_lane_change_rate_with_rest_reset_beats_plain_integration():
    d = default_device()
    sim = run_simulation(d, "lane_change", seed=3)
    rec = sim.recording
    cal = Calibration.nominal(d)
    for engine in ("float", "fixed"):
        c = E.rate_from_recording(d, cal, rec, engine, leak_tau_s=5.0)
        e = np.sqrt(np.mean((c["w_z"] - rec.w[:, 2]) ** 2))
        assert e < 0.03
        assert 0.1 < c["rest"].mean() < 0.8        # the straights look like rest (omega = 0 there)
    f, a = model.resolve(cal.offsets, cal.sensitivity, d.positions, rec.raw, None)
    plain = model.rate_integrate(a, 1 / d.sample_rate_hz)[:, 2]
    assert np.sqrt(np.mean((plain - rec.w[:, 2]) ** 2)) > e


# ---- host plumbing ----

def test_report_plots(tmp_path):
    d = adxl_pendulum_device()
    rec = run_simulation(d, "pendulum", seed=1, duration_s=4.0).recording
    cols = E.attitude_from_recording(d, Calibration.nominal(d), rec)
    files = E.report_plots(tmp_path, cols, rec)
    t = default_triad()
    rec2 = run_simulation(t, "linear_actuator", seed=1).recording
    files += E.report_plots(tmp_path, E.displacement_from_recording(t, Calibration.nominal(t), rec2), rec2)
    for f in files:
        assert f.exists() and f.stat().st_size > 1000


def test_run_estimator_writes_csv_and_plots(tmp_path):
    dev = adxl_pendulum_device()
    save_device(dev, tmp_path / "d.json")
    save_calibration(Calibration.nominal(dev), tmp_path / "c.json")
    write_recording(tmp_path / "r.csv", run_simulation(dev, "pendulum", seed=1, duration_s=3.0).recording)
    warn = run_estimator("attitude", tmp_path / "d.json", tmp_path / "c.json", tmp_path / "r.csv",
                           tmp_path / "o.csv", engine="fixed", report=tmp_path / "rep")
    assert warn == []
    lines = [ln for ln in (tmp_path / "o.csv").read_text().splitlines() if not ln.startswith("#")]
    assert lines[0].split(",")[:4] == ["t", "theta_rad", "w_y", "dw_y"]
    assert (tmp_path / "rep" / "attitude.png").exists()
    # bad input: nothing written
    with pytest.raises(InputError):
        run_estimator("displacement", tmp_path / "d.json", tmp_path / "c.json", tmp_path / "r.csv",
                      tmp_path / "bad.csv")
    assert not (tmp_path / "bad.csv").exists()


def test_write_columns_csv_text(tmp_path):
    """'# key: value' comments, the header, then '%.9g' per cell (NaN as 'nan'), as
    numpy.savetxt(fmt='%.9g') writes the rows; t exactly (repr), as an epoch in seconds needs
    16 digits (at 9 every row of a recording stamped 1.7e9 s read 1.7e+09)."""
    cols = {"t": np.array([0.0, 1 / 3, 1.7e9 + 0.01]), "x": np.array([math.pi, np.nan, -1e300])}
    write_columns_csv(tmp_path / "o.csv", cols, {"engine": "float", "note": "a, b"})
    text = (tmp_path / "o.csv").read_text()
    buf = io.StringIO()
    np.savetxt(buf, cols["x"][:, None], fmt="%.9g", delimiter=",")
    rows = [f"{float(t)!r},{x}" for t, x in zip(cols["t"], buf.getvalue().splitlines())]
    assert text == "# engine: float\n# note: a, b\nt,x\n" + "\n".join(rows) + "\n"
    back = np.loadtxt(tmp_path / "o.csv", delimiter=",", skiprows=3, usecols=0)
    np.testing.assert_array_equal(back, cols["t"])
    write_columns_csv(tmp_path / "e.csv", {})
    assert (tmp_path / "e.csv").read_text() == "\n"


def test_cli_estimator_bad_input_writes_nothing(tmp_path, capsys):
    dev = default_triad()
    save_device(dev, tmp_path / "d.json")
    save_calibration(Calibration.nominal(dev), tmp_path / "c.json")
    write_recording(tmp_path / "r.csv", run_simulation(dev, "linear_actuator", seed=1).recording)
    assert main(["rate", "--device", str(tmp_path / "d.json"), "--calibration", str(tmp_path / "c.json"),
                 str(tmp_path / "r.csv"), "-o", str(tmp_path / "o.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "6-DOF array" in err[0]
    assert not (tmp_path / "o.csv").exists()


def test_rate_float_is_the_recursion():
    """lfilter between rests gives the recursion w = (1 - leak) w + dt alpha, reset at rest,
    bit for bit (the twin's arithmetic)."""
    rng = np.random.default_rng(7)
    a = rng.normal(0, 2.0, (3000, 3))
    fl = np.where(rng.random(3000) < 0.02, E.REST_AT_REST, 0)
    fl[1000:1100] = E.REST_AT_REST
    for leak in (0.0, 1 / 300, 0.5, 1.0):
        w, _ = E.rate_rest_float(a, None, 1 / 60, leak, E.RestParams(), rest_flags=fl)
        ref, x = np.zeros_like(a), np.zeros(3)
        for i in range(len(a)):
            x = x * (1.0 - leak) + (1 / 60) * a[i]
            if fl[i] & E.REST_AT_REST:
                x = np.zeros(3)
            ref[i] = x
        assert np.array_equal(w, ref)


PACKAGE = Path(E.__file__).resolve().parent
METHOD_AND_TOP = {"calibrate", "diagnose", "simulate", "cli", "demo", "resolve", "xsens"}


@pytest.mark.parametrize("module", sorted(p.name for p in PACKAGE.glob("*.py")))
def test_estimator_modules_import_at_the_top_and_only_public_names(module):
    """Imports at module level only; no method package or top module (the estimators sit
    beside calibrate, diagnose and simulate); no private name from another module."""
    tree = ast.parse((PACKAGE / module).read_text())
    top = set(id(n) for n in tree.body)
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            assert id(node) in top, f"{module}:{node.lineno}: import inside a function"
        if isinstance(node, ast.ImportFrom) and node.module and node.level:
            parts = node.module.split(".")
            if node.level == 2:       # accelcal.<module>
                assert parts[0] not in METHOD_AND_TOP, f"{module}:{node.lineno}: imports {node.module}"
            assert not any(p.startswith("_") for p in parts), f"{module}:{node.lineno}: {node.module}"
            for a in node.names:
                assert not a.name.startswith("_"), f"{module}:{node.lineno}: private {a.name}"
