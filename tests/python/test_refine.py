"""accelcal refine / ac.refine (issue 35, item 1): a diagnosis's correctable effects become
calibration terms, refitted on the independent generator's recordings (tests/python/loop_cases.py
on indep_model), with the command's exit codes."""
from __future__ import annotations

import json

import numpy as np
import pytest

import accelcal as ac
import loop_cases as lc
from accelcal.io.device import save_device
from accelcal.io.recording import recording_from_arrays
from cli_run import one_refusal, run


@pytest.fixture(scope="module")
def square_law():
    """The seed's 6-channel array with a square-law nonlinearity (15 x the noise floor):
    recording 0 calibrated (jig poses), recordings 1 and 2 with a reference motion."""
    case = next(c for c in lc.CASES if c.name == "nonlinearity (square law)")
    b = lc.build(case, 11)
    b["cal0"] = ac.calibrate(b["device"], b["rec0"])
    return b


def nonlin_diagnosis(dev, effects=("nonlinearity",), params=None):
    """A diagnosis JSON object with the fields refine reads (docs/diagnosis-json.md)."""
    params = params if params is not None else {"nonlinearity": {"k2": [0.0] * dev.n_channels,
                                                                 "k3": [0.0] * dev.n_channels}}
    return {"format": "accelcal-diagnosis", "verdict": effects[0] if effects else "none", "device": dev.name,
            "n_channels": dev.n_channels, "unexplained": None,
            "model": {"effects": list(effects), "params": params}}


@pytest.fixture(scope="module")
def files(square_law, tmp_path_factory):
    d = tmp_path_factory.mktemp("refine")
    dev = square_law["device"]
    save_device(dev, d / "dev.json")
    ac.save_calibration(square_law["cal0"], d / "cal.json")
    ac.write_recording(d / "rec1.csv", square_law["rec1"])
    (d / "diag.json").write_text(json.dumps(nonlin_diagnosis(dev)))
    return d


def refine_args(d, diag="diag.json", rec="rec1.csv", out="cal2.json"):
    return ["refine", "--device", d / "dev.json", "--calibration", d / "cal.json", "--diagnosis", d / diag,
            d / rec, "-o", d / out]


def test_refine_recovers_the_square_law_within_its_sigma(square_law):
    """The terms recovered on the independent generator: each channel's k2 within 3 of its 1-sigma
    of the truth, the sigma under 5 % of the truth's size; the held-out gap shrinks to the noise."""
    dev, cal0 = square_law["device"], square_law["cal0"]
    res = ac.refine(dev, cal0, nonlin_diagnosis(dev), square_law["rec1"])
    truth = lc.true_terms(dev, square_law["params"], square_law["effects"])["nonlin_k2"]
    est, sd = res.added["nonlinearity"]["k2"], res.added["nonlinearity"]["sigma"]["k2"]
    assert np.all(sd < 0.05 * np.abs(truth))
    assert np.all(np.abs(est - truth) <= 3.0 * sd), (est, truth, sd)
    assert res.heldout_rms_after < 0.5 * res.heldout_rms_before
    assert res.heldout_rms_after < 1.2 * res.noise_counts
    assert "nonlinearity" in res.paragraph and "Held-out" in res.paragraph
    assert np.allclose(res.calibration.nonlin_k2, est)


def test_loop_square_law_on_the_fixed_engine(square_law):
    """The loop: calibrate -> diagnose recording 1 -> refine -> the fixed engine on a fresh
    recording 2: the f error was over twice the floor with the calibration, within 1.5x after;
    and the diagnosis of recording 2 against the refined calibration finds nothing."""
    dev, cal0, rec1 = square_law["device"], square_law["cal0"], square_law["rec1"]
    d1 = ac.diagnose(dev, cal0, rec1)
    assert "nonlinearity" in d1["model"]["effects"]
    cal2 = ac.refine(dev, cal0, d1, rec1).calibration
    rec2, F = lc.with_full_reference(square_law["sc2"], square_law["rec2"])
    clean = recording_from_arrays(rec2.t, square_law["clean2"], f=F, w=rec2.w, dw=rec2.dw)

    def err(cal, rec):
        return float(np.sqrt(np.mean((ac.resolve(dev, cal, rec, engine="fixed").f[5:-5] - F[5:-5]) ** 2)))
    floor = err(lc.truth_calibration(dev, square_law["params"]), clean)
    assert err(cal0, rec2) > 2.0 * floor
    assert err(cal2, rec2) <= 1.5 * floor
    assert ac.diagnose(dev, cal2, square_law["rec2"])["verdict"] == "none"


def test_cli_writes_the_refined_calibration(files, capfd):
    rc, out, err, _ = run(refine_args(files), capfd)
    assert rc == 0, err
    assert out.startswith("Refined: nonlinearity k2 [")
    cal2 = json.loads((files / "cal2.json").read_text())
    assert cal2["method"].endswith("+refine")
    assert all("nonlin_k2_counts_per_mps2_2" in ch for ch in cal2["channels"])


def test_cli_nothing_correctable_exits_1(files, capfd):
    dev = ac.load_device(files / "dev.json")
    (files / "drift.json").write_text(json.dumps(nonlin_diagnosis(dev, ("bias_drift", "bandwidth"), {})))
    rc, out, err, _ = run(refine_args(files, diag="drift.json", out="none.json"), capfd)
    assert rc == 1
    assert "nothing to correct" in err and "re-zero at rest" in err and "amplifying the noise" in err
    assert not (files / "none.json").exists()


@pytest.mark.parametrize("edit,field", [
    (lambda d: d.pop("model"), "model"),
    (lambda d: d.__setitem__("modle", d.pop("model")), "model"),
    (lambda d: d["model"].pop("effects"), "model.effects"),
    (lambda d: d["model"].__setitem__("efects", d["model"].pop("effects")), "model.effects"),
    (lambda d: d["model"].pop("params"), "model.params"),
    (lambda d: d["model"]["params"].pop("nonlinearity"), "model.params.nonlinearity"),
    (lambda d: d["model"].__setitem__("effects", ["nonlinearty"]), "model.effects"),
    (lambda d: d.__setitem__("device", "another-device"), "device"),
    (lambda d: d.__setitem__("n_channels", 9), "n_channels"),
])
def test_cli_bad_diagnosis_exits_2_naming_the_field(files, capfd, edit, field):
    d = json.loads((files / "diag.json").read_text())
    edit(d)
    (files / "bad.json").write_text(json.dumps(d))
    rc, _, err, _ = run(refine_args(files, diag="bad.json", out="bad_out.json"), capfd)
    assert rc == 2 and one_refusal(err), err
    assert "bad.json" in err and field in err
    assert not (files / "bad_out.json").exists()


def test_cli_recording_of_another_device_exits_2(files, capfd):
    rec = recording_from_arrays(np.arange(50) / 100.0, np.full((50, 3), 5000), f=np.zeros((50, 3)))
    ac.write_recording(files / "rec3.csv", rec)
    rc, _, err, _ = run(refine_args(files, rec="rec3.csv", out="o3.json"), capfd)
    assert rc == 2 and one_refusal(err) and "rec3.csv" in err, err
    assert not (files / "o3.json").exists()


def test_cli_recording_without_reference_exits_2(files, square_law, capfd):
    r = square_law["rec1"]
    ac.write_recording(files / "noref.csv", recording_from_arrays(r.t, r.raw))
    rc, _, err, _ = run(refine_args(files, rec="noref.csv", out="o4.json"), capfd)
    assert rc == 2 and one_refusal(err) and "noref.csv" in err and "reference" in err, err
    assert not (files / "o4.json").exists()


def test_cli_unwritable_output_exits_2(files, capfd):
    rc, _, err, _ = run(refine_args(files, out="no/such/dir/cal2.json"), capfd)
    assert rc == 2 and one_refusal(err) and "does not exist" in err, err


def test_api_exports_refine():
    assert "refine" in ac.__all__ and "RefineResult" in ac.__all__
    assert ac.refine.__doc__ and "Returns" in ac.refine.__doc__


def test_a_term_the_recordings_do_not_pin_is_left_out(square_law):
    """A diagnosis (of another recording) with a temperature offset, refined on a recording whose
    temperature never changes: the tempco and its lag are not determined there (their Jacobian
    columns are zero). The old fit's pseudo-inverse read that as a 1-sigma of 0 and wrote the
    diagnosis's start value (3 counts/degC, lag 30 s) into the calibration; now the term is left
    out, said in the paragraph and in ``extra.fit``, and the nonlinearity is still refitted."""
    dev, cal0, r = square_law["device"], square_law["cal0"], square_law["rec1"]
    rec = recording_from_arrays(r.t, r.raw, f=r.f, w=r.w, dw=r.dw, temp_c=np.full(r.t.size, 25.0), pose=r.pose)
    n = dev.n_channels
    diag = nonlin_diagnosis(dev, ("nonlinearity", "temperature_offset"),
                            {"nonlinearity": {"k2": [0.0] * n, "k3": [0.0] * n},
                             "temperature_offset": {"coeff": [3.0] * n, "tau_s": 30.0}})
    res = ac.refine(dev, cal0, diag, rec)
    assert res.calibration.offset_tc is None and res.calibration.temp_offset_tau_s is None
    assert "temperature_offset" not in res.added and "temperature_offset" in res.not_added
    assert "not determined" in res.paragraph and "offset tempco" in res.paragraph
    assert res.calibration.extra["fit"]["refine_not_determined"] == {"offset tempco": list(range(n))}
    truth = lc.true_terms(dev, square_law["params"], square_law["effects"])["nonlin_k2"]
    est, sd = res.added["nonlinearity"]["k2"], res.added["nonlinearity"]["sigma"]["k2"]
    assert np.all(np.abs(est - truth) <= 3.0 * sd)


def test_a_well_posed_refine_leaves_nothing_out(square_law):
    """The control of the rule above: on the recording the square law was diagnosed on, every
    channel's k2 is pinned (finite 1-sigma, nothing said to be undetermined)."""
    dev, cal0, r = square_law["device"], square_law["cal0"], square_law["rec1"]
    res = ac.refine(dev, cal0, nonlin_diagnosis(dev), r)
    assert np.all(np.isfinite(res.added["nonlinearity"]["sigma"]["k2"]))
    assert "not determined" not in res.paragraph
    assert "refine_not_determined" not in res.calibration.extra["fit"]
