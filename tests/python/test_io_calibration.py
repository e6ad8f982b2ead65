"""Calibration JSON: layout per the contract, validation messages, device
checks, round trips and fuzzed corruptions."""

import difflib
import json
import os

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from accelcal.io.calibration import (
    KNOWN_KEYS,
    Calibration,
    calibration_from_dict,
    calibration_to_dict,
    load_calibration,
    save_calibration,
)
from accelcal.io.device import default_device, default_triad
from accelcal.errors import InputError
from accelcal.io.jsonfields import KEY_CUTOFF

from json_strategies import json_paths, json_values

# Properties that touch files: capped so that the CI profile (10,000 examples)
# stays within the CI time budget.
IO = settings(max_examples=min(settings().max_examples, 1000))


def full_cal(n=6, seed=0):
    rng = np.random.default_rng(seed)
    return Calibration(
        device="seed-6ch-r60",
        method="full",
        offsets=5000 + rng.normal(size=n),
        sensitivity=rng.normal(size=(n, 3)) * 100,
        positions=rng.normal(size=(n, 3)) * 0.05,
        offset_sigma=rng.uniform(0, 1, n),
        sensitivity_sigma=rng.uniform(0, 1, (n, 3)),
        position_sigma=rng.uniform(0, 1e-3, (n, 3)),
        temp_ref_c=25.0,
        offset_tc=rng.normal(size=n),
        gain_tc=rng.normal(size=n) * 1e-4,
        residual_rms_per_channel=rng.uniform(0, 3, n),
        residual_rms_per_pose={"0": 1.5, "recA.csv:3": 2.0},
        poses_used=[0, 1, 2, "recA.csv:3"],
        extra={"software": {"version": "0.1.0"}},
    )


def write_json(tmp_path, obj, name="cal.json"):
    p = tmp_path / name
    p.write_text(obj if isinstance(obj, str) else json.dumps(obj))
    return p


def expect_error(tmp_path, obj, field, *fragments, device=None):
    p = write_json(tmp_path, obj)
    with pytest.raises(InputError) as ei:
        load_calibration(p, device)
    msg = str(ei.value)
    assert msg.startswith(str(p) + ": ") and "\n" not in msg, msg
    if field is not None:
        assert f"field {field}:" in msg, msg
        assert ei.value.field == field
    for frag in fragments:
        assert frag in msg, msg
    return msg


@pytest.fixture
def good():
    return calibration_to_dict(full_cal())


# ---------------------------------------------------------------- layout and round trip


def test_minimal_contract_example(tmp_path):
    doc = {
        "device": "example-6ch",
        "method": "npose",
        "channels": [{"offset_counts": 5012.3, "sensitivity": [0.9, 127.1, -1.2], "position_m": [0.06, 0.0, 0.0]}],
    }
    cal = load_calibration(write_json(tmp_path, doc))
    assert cal.device == "example-6ch" and cal.method == "npose" and cal.n_channels == 1
    assert cal.offsets.tolist() == [5012.3] and cal.sensitivity.tolist() == [[0.9, 127.1, -1.2]]
    assert cal.positions.tolist() == [[0.06, 0.0, 0.0]]
    assert cal.offset_sigma is None and cal.temp_ref_c is None and cal.poses_used is None
    assert calibration_to_dict(cal) == doc


def test_full_layout(tmp_path):
    cal = full_cal()
    p = tmp_path / "cal.json"
    save_calibration(cal, p)
    doc = json.loads(p.read_text())
    assert set(doc) == {"device", "method", "channels", "temperature_ref_c", "residual_rms_counts", "poses_used", "software"}
    assert set(doc["channels"][0]) == {
        "offset_counts", "sensitivity", "position_m", "offset_sigma_counts", "sensitivity_sigma",
        "position_sigma_m", "offset_tc_counts_per_c", "gain_tc_per_c",
    }
    assert set(doc["residual_rms_counts"]) == {"per_channel", "per_pose"}
    assert p.read_text().startswith('{\n  "device"')  # indent 2
    assert load_calibration(p) == cal


def test_nominal_and_positions_or_nominal(tmp_path):
    dev = default_device()
    cal = Calibration.nominal(dev)
    assert cal.method == "nominal" and cal.device == dev.name and cal.positions is None
    assert np.array_equal(cal.offsets, dev.zero_counts)
    assert np.array_equal(cal.sensitivity, dev.nominal_sensitivity())
    assert np.array_equal(cal.positions_or_nominal(dev), dev.positions)
    doc = calibration_to_dict(cal)
    assert "position_m" not in doc["channels"][0]
    p = tmp_path / "nom.json"
    save_calibration(cal, p)
    assert load_calibration(p, dev) == cal
    with pytest.raises(ValueError):
        cal.positions_or_nominal(default_triad())


def test_partial_positions(tmp_path):
    dev = default_device()
    doc = calibration_to_dict(Calibration.nominal(dev))
    doc["channels"][2]["position_m"] = [0.1, 0.2, 0.3]
    p = write_json(tmp_path, doc)
    cal = load_calibration(p)  # without the device: unknown rows are NaN
    assert np.isnan(cal.positions[0]).all() and cal.positions[2].tolist() == [0.1, 0.2, 0.3]
    expected = dev.positions.copy()
    expected[2] = [0.1, 0.2, 0.3]
    assert np.array_equal(cal.positions_or_nominal(dev), expected)
    cal_d = load_calibration(p, dev)  # with it: filled with nominal
    assert np.array_equal(cal_d.positions, expected)
    # saving the NaN form writes position_m only where it was estimated
    assert [("position_m" in c) for c in calibration_to_dict(cal)["channels"]] == [i == 2 for i in range(6)]


def test_save_partly_nan_row_rejected(tmp_path):
    cal = full_cal()
    cal.positions[1, 1] = np.nan
    p = tmp_path / "c.json"
    p.write_text("old")
    with pytest.raises(ValueError):
        save_calibration(cal, p)
    assert p.read_text() == "old" and os.listdir(tmp_path) == ["c.json"]


def test_save_nonfinite_rejected(tmp_path):
    cal = full_cal()
    cal.offsets[0] = np.inf
    with pytest.raises(ValueError):
        save_calibration(cal, tmp_path / "c.json")
    assert os.listdir(tmp_path) == []


def test_device_checks(tmp_path, good):
    dev = default_device()
    assert load_calibration(write_json(tmp_path, good), dev).n_channels == 6
    good["device"] = "other-board"
    msg = expect_error(tmp_path, good, "device", device=dev)
    assert msg.endswith("field device: calibration is for 'other-board' but the device is 'seed-6ch-r60'")
    good["device"] = dev.name
    good["channels"] = good["channels"][:5]
    expect_error(tmp_path, good, "channels", "calibration has 5 channels but the device 'seed-6ch-r60' has 6", device=dev)


# ---------------------------------------------------------------- bad files


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match="nope.json: cannot read the file"):
        load_calibration(tmp_path / "nope.json")


def test_not_json(tmp_path):
    expect_error(tmp_path, "{", None, "not valid JSON at line 1")


def test_not_object(tmp_path):
    expect_error(tmp_path, "[]", None, "expected a JSON object at the top level")


@pytest.mark.parametrize("key", ["device", "method", "channels"])
def test_missing_top(tmp_path, good, key):
    del good[key]
    expect_error(tmp_path, good, key, "missing")


@pytest.mark.parametrize("key", ["offset_counts", "sensitivity"])
def test_missing_channel_field(tmp_path, good, key):
    del good["channels"][4][key]
    expect_error(tmp_path, good, f"channels[4].{key}", "missing")


@pytest.mark.parametrize(
    "path,value,field,frag",
    [
        (("device",), 3, "device", "expected a string"),
        (("method",), None, "method", "expected a string, got null"),
        (("channels",), {}, "channels", "expected a list"),
        (("channels",), [], "channels", "empty list"),
        (("channels", 1), "x", "channels[1]", "expected a JSON object"),
        (("channels", 1, "offset_counts"), "5000", "channels[1].offset_counts", "expected a number"),
        (("channels", 1, "offset_counts"), True, "channels[1].offset_counts", "got true"),
        (("channels", 1, "sensitivity"), [1, 2], "channels[1].sensitivity", "expected 3 numbers, got 2"),
        (("channels", 1, "sensitivity"), [0, 0, 0], "channels[1].sensitivity", "non-zero"),
        (("channels", 1, "sensitivity"), [1, None, 2], "channels[1].sensitivity[1]", "got null"),
        (("channels", 1, "position_m"), [1, 2, 3, 4], "channels[1].position_m", "expected 3 numbers, got 4"),
        (("channels", 1, "offset_sigma_counts"), -1, "channels[1].offset_sigma_counts", ">= 0"),
        (("channels", 1, "sensitivity_sigma"), [1, -2, 3], "channels[1].sensitivity_sigma", ">= 0"),
        (("channels", 1, "gain_tc_per_c"), "x", "channels[1].gain_tc_per_c", "expected a number"),
        (("temperature_ref_c",), "25", "temperature_ref_c", "expected a number"),
        (("residual_rms_counts",), [1], "residual_rms_counts", "expected a JSON object"),
        (("residual_rms_counts", "per_channel"), [1, 2], "residual_rms_counts.per_channel", "expected 6 numbers"),
        (("residual_rms_counts", "per_channel"), [1, 2, 3, 4, 5, -6], "residual_rms_counts.per_channel[5]", ">= 0"),
        (("residual_rms_counts", "per_pose"), {"a": "x"}, "residual_rms_counts.per_pose.a", "expected a number"),
        (("poses_used",), 3, "poses_used", "expected a list"),
        (("poses_used",), [1, 2.5], "poses_used[1]", "expected an integer"),
    ],
)
def test_bad_values(tmp_path, good, path, value, field, frag):
    target = good
    for k in path[:-1]:
        target = target[k]
    target[path[-1]] = value
    expect_error(tmp_path, good, field, frag)


def test_temperature_coefficients_need_reference(tmp_path, good):
    del good["temperature_ref_c"]
    expect_error(tmp_path, good, "temperature_ref_c", "missing (required when channels give offset_tc_counts_per_c)")


@pytest.mark.parametrize("token", ["NaN", "Infinity", "-Infinity"])
def test_nonfinite(tmp_path, good, token):
    good["channels"][3]["offset_counts"] = 123456.75
    text = json.dumps(good).replace("123456.75", token)
    expect_error(tmp_path, text, "channels[3].offset_counts", f"got {token}")


def test_duplicate_key(tmp_path, good):
    text = json.dumps(good)[:-1] + ', "method": "x"}'
    expect_error(tmp_path, text, "method", "given more than once")


def test_from_dict_source():
    with pytest.raises(InputError, match=r"^<dict>: field device: missing"):
        calibration_from_dict({})


def test_constructor_shapes():
    with pytest.raises(ValueError):
        Calibration("d", "m", np.zeros(3), np.zeros((2, 3)))
    with pytest.raises(ValueError):
        Calibration("d", "m", np.zeros(3), np.zeros((3, 3)), positions=np.zeros((3, 2)))


# ---------------------------------------------------------------- properties

fin = st.floats(-1e6, 1e6, allow_nan=False)


def extension_key(k: str) -> bool:
    """A key the reader keeps in ``extra``: not one of the calibration's own fields, and not
    so close to a key it knows (jsonfields.KEY_CUTOFF) that it is refused as its misspelling
    ('poes' for 'poses')."""
    if k in {"device", "method", "channels", "temperature_ref_c", "residual_rms_counts", "poses_used"}:
        return False
    return k in KNOWN_KEYS or not difflib.get_close_matches(k, KNOWN_KEYS, n=1, cutoff=KEY_CUTOFF)


@st.composite
def calibrations(draw):
    n = draw(st.integers(1, 8))

    def arr(shape, elements=fin, optional=True):
        if optional and draw(st.booleans()):
            return None
        return np.array(draw(st.lists(elements, min_size=int(np.prod(shape)), max_size=int(np.prod(shape))))).reshape(shape)

    sens = arr((n, 3), optional=False)
    sens[np.all(sens == 0, axis=1)] = [1.0, 0, 0]
    pos = arr((n, 3), st.floats(-1e3, 1e3, allow_nan=False))  # device.LIMITS["position_m"]
    if pos is not None and n > 1:
        pos[0] = np.nan  # channel 0 at nominal
    off_tc, gain_tc = arr((n,)), arr((n,))
    temp = draw(fin) if (off_tc is not None or gain_tc is not None or draw(st.booleans())) else None
    return Calibration(
        device=draw(st.text(max_size=10)),
        method=draw(st.text(max_size=10)),
        offsets=arr((n,), optional=False),
        sensitivity=sens,
        positions=pos,
        offset_sigma=arr((n,), st.floats(0, 1e3)),
        sensitivity_sigma=arr((n, 3), st.floats(0, 1e3)),
        position_sigma=arr((n, 3), st.floats(0, 1)),
        temp_ref_c=temp,
        offset_tc=off_tc,
        gain_tc=gain_tc,
        residual_rms_per_channel=arr((n,), st.floats(0, 1e3)),
        residual_rms_per_pose=draw(st.none() | st.dictionaries(st.text(max_size=5), st.floats(0, 1e3), max_size=3)),
        poses_used=draw(st.none() | st.lists(st.integers(-5, 100) | st.text(max_size=5), max_size=4)),
        extra=draw(st.dictionaries(st.text(max_size=5).filter(extension_key), st.integers() | st.text(max_size=5),
                                   max_size=2)),
    )


@IO
@given(calibrations())
def test_property_round_trip(tmp_path_factory, cal):
    p = tmp_path_factory.getbasetemp() / "test_io_calibration_cal_c.json"
    save_calibration(cal, p)
    assert load_calibration(p) == cal


@IO
@given(st.data())
def test_property_corruption_gives_input_error(tmp_path_factory, data):
    d = calibration_to_dict(full_cal())
    path = data.draw(st.sampled_from([p for p in json_paths(d) if p]))
    target = d
    for k in path[:-1]:
        target = target[k]
    if data.draw(st.booleans()):
        del target[path[-1]]
    else:
        target[path[-1]] = data.draw(json_values)
    p = tmp_path_factory.getbasetemp() / "test_io_calibration_bad_c.json"
    p.write_text(json.dumps(d))
    dev = data.draw(st.sampled_from([None, default_device()]))
    try:
        cal = load_calibration(p, dev)
    except InputError as e:
        assert str(e).startswith(str(p) + ": ") and "\n" not in str(e)
        return
    assert isinstance(cal, Calibration)


@IO
@given(st.binary(max_size=200))
def test_property_random_bytes(tmp_path_factory, blob):
    p = tmp_path_factory.getbasetemp() / "test_io_calibration_junk_c.json"
    p.write_bytes(blob)
    try:
        load_calibration(p)
    except InputError:
        pass


@pytest.mark.parametrize("field, value", [("sensitivity", [1e30, 0, 0]), ("position_m", [0, 0, 1e300]),
                                          ("offset_counts", 1e300)])
def test_values_beyond_the_limits_are_refused(tmp_path, field, value):
    from accelcal.io.calibration import load_calibration
    d = {"device": "x", "method": "full", "channels": [
        {"offset_counts": 5000.0, "sensitivity": [127.0, 0, 0]} for _ in range(3)]}
    d["channels"][1][field] = value
    p = tmp_path / "c.json"
    p.write_text(json.dumps(d))
    with pytest.raises(InputError) as e:
        load_calibration(p)
    assert f"channels[1].{field}" in str(e.value) and "expected values in" in str(e.value)
