"""Device description JSON: validation messages, built-in devices, round trips;
plus the errors module (messages, core_error, atomic_write)."""

import copy
import json
import math
import os
import pickle

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from accelcal.io.device import (
    Device,
    default_device,
    default_triad,
    device_from_dict,
    load_device,
    pendulum_device,
    save_device,
)
from accelcal.errors import (
    AccelcalError,
    CoreError,
    FormatError,
    IllConditionedError,
    InputError,
    NullError,
    RangeError,
    SingularError,
    SizeError,
    atomic_write,
    core_error,
)

from json_strategies import json_paths, json_values

# Properties that touch files: capped so that the CI profile (10,000 examples)
# stays within the CI time budget.
IO = settings(max_examples=min(settings().max_examples, 1000))


def write_json(tmp_path, obj, name="dev.json"):
    p = tmp_path / name
    p.write_text(obj if isinstance(obj, str) else json.dumps(obj))
    return p


def expect_error(tmp_path, obj, field, *fragments):
    """Load ``obj`` as a device file; the one-line message names file + field."""
    p = write_json(tmp_path, obj)
    with pytest.raises(InputError) as ei:
        load_device(p)
    msg = str(ei.value)
    assert msg.startswith(str(p) + ": "), msg
    assert "\n" not in msg
    if field is not None:
        assert f"field {field}:" in msg, msg
        assert ei.value.field == field
    for frag in fragments:
        assert frag in msg, msg
    return msg


@pytest.fixture
def good():
    return default_device().to_dict()


# ---------------------------------------------------------------- errors module


def test_input_error_formats():
    e = InputError("rec.csv", "expected an integer, got 'abc'", row=14, column="raw_3")
    assert str(e) == "rec.csv: row 14, column raw_3: expected an integer, got 'abc'"
    assert (e.source, e.row, e.column) == ("rec.csv", 14, "raw_3")
    e = InputError("dev.json", "expected 3 numbers", field="channels[2].axis")
    assert str(e) == "dev.json: field channels[2].axis: expected 3 numbers"
    assert e.field == "channels[2].axis" and e.row is None
    assert str(InputError("x.csv", "line\nbreak")) == "x.csv: line break"
    assert isinstance(e, AccelcalError)
    e2 = pickle.loads(pickle.dumps(e))
    assert str(e2) == str(e) and e2.field == e.field


@pytest.mark.parametrize(
    "status,cls",
    [(-1, NullError), (-2, SizeError), (-3, SingularError), (-4, IllConditionedError), (-5, RangeError), (-6, FormatError)],
)
def test_core_error_mapping(status, cls):
    e = core_error(status, "ac_resolve_batch")
    assert type(e) is cls and isinstance(e, CoreError) and isinstance(e, AccelcalError)
    assert e.status == status
    assert str(e).startswith("ac_resolve_batch: ") and f"status {status}" in str(e)
    assert pickle.loads(pickle.dumps(e)).status == status


def test_core_error_unknown_and_non_errors():
    e = core_error(-99, "ctx")
    assert type(e) is CoreError and e.status == -99
    for s in (0, 1):  # ok and saturated are not errors
        with pytest.raises(ValueError):
            core_error(s, "ctx")


def test_atomic_write_success_and_failure(tmp_path):
    p = tmp_path / "out.txt"
    atomic_write(p, lambda f: f.write("first\n"))
    assert p.read_text() == "first\n"
    umask = os.umask(0)
    os.umask(umask)
    assert os.stat(p).st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's 0600

    def boom(f):
        f.write("partial")
        raise RuntimeError("disk on fire")

    with pytest.raises(RuntimeError):
        atomic_write(p, boom)
    assert p.read_text() == "first\n"  # old content intact
    assert sorted(os.listdir(tmp_path)) == ["out.txt"]  # no temp file left
    atomic_write(p, lambda f: f.write(b"\x00\x01"), mode="wb")
    assert p.read_bytes() == b"\x00\x01"
    with pytest.raises(ValueError):
        atomic_write(p, lambda f: None, mode="a")


def test_atomic_write_new_file_failure_leaves_nothing(tmp_path):
    p = tmp_path / "new.json"
    with pytest.raises(KeyError):
        atomic_write(p, lambda f: {}["x"])
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------- built-in devices


def test_default_device_geometry():
    d = default_device()
    assert d.name == "seed-6ch-r60" and d.n_channels == 6
    assert d.sample_rate_hz == 60.0 and d.gravity_mps2 == 9.80665
    assert (d.raw_min, d.raw_max) == (0, 10000)
    assert np.all(d.zero_counts == 5000) and np.allclose(d.counts_per_mps2, 1250 / 9.80665)
    assert d.noise_mps2 == 0.02
    for k in range(3):
        phi = math.radians(120 * k)
        assert np.allclose(d.positions[2 * k], [0.06 * math.cos(phi), 0.06 * math.sin(phi), 0])
        assert np.allclose(d.positions[2 * k + 1], d.positions[2 * k])
        assert np.allclose(d.axes[2 * k], [-math.sin(phi), math.cos(phi), 0])
        assert np.allclose(d.axes[2 * k + 1], [0, 0, 1])
    assert d.is_array() and not d.is_triad()
    assert np.allclose(d.nominal_sensitivity(), d.counts_per_mps2[:, None] * d.axes)
    assert d.nominal_offsets().dtype == np.float64
    assert np.allclose(d.noise_counts(), 0.02 * 1250 / 9.80665)


def test_triad_and_pendulum():
    t = default_triad()
    assert t.is_triad() and not t.is_array() and t.n_channels == 3
    assert (t.raw_min, t.raw_max) == (0, 65535) and np.all(t.zero_counts == 32768)
    assert abs(t.counts_per_mps2[0] - 1670) < 2 and t.sample_rate_hz == 100 and t.noise_mps2 == 0.005
    p = pendulum_device(0.1, 0.3)
    assert p.name == "pendulum-2triad" and p.triads() == [(0, 1, 2), (3, 4, 5)]
    assert np.allclose(p.positions[:3], [0.1, 0, 0]) and np.allclose(p.positions[3:], [0.3, 0, 0])
    assert np.allclose(p.axes, np.vstack([np.eye(3)] * 2))
    # a pendulum device is a valid file (two triads), though not a 6-DOF array
    assert device_from_dict(p.to_dict()) == p
    with pytest.raises(ValueError):
        pendulum_device(0.2, 0.2)


def test_device_is_frozen():
    d = default_device()
    with pytest.raises(Exception):
        d.name = "x"
    with pytest.raises(ValueError):
        d.positions[0, 0] = 1.0


def test_save_load_round_trip(tmp_path):
    for d in (default_device(), default_triad(), pendulum_device()):
        p = tmp_path / f"{d.name}.json"
        save_device(d, p)
        back = load_device(p)
        assert back == d
        assert json.loads(p.read_text())["channels"][0]["zero_counts"] == int(d.zero_counts[0])


def test_axis_normalised_and_extra_fields_ignored(tmp_path, good):
    good["channels"][0]["axis"] = [0, 2.0, 0]
    good["channels"][0]["comment"] = "chip A"
    good["vendor"] = {"anything": [1, 2]}
    d = load_device(write_json(tmp_path, good))
    assert np.allclose(d.axes[0], [0, 1, 0])


@pytest.mark.parametrize("axis", [[0, 0, 5e-324], [1e153, 0, 1.3e154], [0, 1e299, 1e300]])
def test_extreme_axis_lengths_normalised(tmp_path, good, axis):
    # channel 1 is a z channel: keep it z-dominant so the array stays rank 6
    good["channels"][1]["axis"] = axis
    d = load_device(write_json(tmp_path, good))
    a = np.array(axis) / max(axis)
    assert np.allclose(d.axes[1], a / np.linalg.norm(a))


def test_noise_optional(tmp_path, good):
    del good["noise_mps2"]
    assert load_device(write_json(tmp_path, good)).noise_mps2 == 0.0


def test_an_unknown_noise_is_not_written_as_zero(tmp_path, good):
    """A device whose noise is unknown (0: estimated from each recording) is written without
    noise_mps2 -- convert --device-out had written "noise_mps2": 0.0, which reads as zero noise
    though the README calls the field an override -- and a file that holds 0.0 (written so
    before) reads the same; a stated noise is kept."""
    good["noise_mps2"] = 0.0
    old = load_device(write_json(tmp_path, good))
    assert old.noise_mps2 == 0.0 and "noise_mps2" not in old.to_dict()
    save_device(old, tmp_path / "again.json")
    assert "noise_mps2" not in json.loads((tmp_path / "again.json").read_text())
    assert load_device(tmp_path / "again.json") == old
    good["noise_mps2"] = 0.02
    assert load_device(write_json(tmp_path, good)).to_dict()["noise_mps2"] == 0.02


# ---------------------------------------------------------------- bad files


def test_missing_file(tmp_path):
    p = tmp_path / "nope.json"
    with pytest.raises(InputError, match="nope.json: cannot read the file"):
        load_device(p)


def test_not_json(tmp_path):
    msg = expect_error(tmp_path, '{"name": "x",\n  "sample_rate_hz": }', None, "not valid JSON at line 2")
    assert "column" in msg


def test_empty_file(tmp_path):
    expect_error(tmp_path, "", None, "empty")


def test_not_utf8(tmp_path):
    p = tmp_path / "dev.json"
    p.write_bytes(b'{"name": "\xff"}')
    with pytest.raises(InputError, match="dev.json: line 1: not valid UTF-8"):
        load_device(p)


def test_not_an_object(tmp_path):
    expect_error(tmp_path, [1, 2, 3], None, "expected a JSON object at the top level, got a list of 3")


@pytest.mark.parametrize("key", ["name", "sample_rate_hz", "gravity_mps2", "raw_min", "raw_max", "channels"])
def test_missing_top_field(tmp_path, good, key):
    del good[key]
    expect_error(tmp_path, good, key, "missing")


@pytest.mark.parametrize("key", ["position_m", "axis", "counts_per_mps2", "zero_counts"])
def test_missing_channel_field(tmp_path, good, key):
    del good["channels"][3][key]
    expect_error(tmp_path, good, f"channels[3].{key}", "missing")


@pytest.mark.parametrize(
    "key,value,frag",
    [
        ("name", 5, "expected a string, got 5"),
        ("sample_rate_hz", "60", 'expected a number, got "60"'),
        ("sample_rate_hz", True, "expected a number, got true"),
        ("gravity_mps2", None, "expected a number, got null"),
        ("raw_min", 0.5, "expected an integer, got 0.5"),
        ("raw_max", "10000", "expected an integer"),
        ("raw_max", False, "expected an integer, got false"),
        ("channels", {"a": 1}, "expected a list of channel objects"),
        ("noise_mps2", -0.1, "expected a number >= 0"),
        ("noise_mps2", [1], "expected a number"),
    ],
)
def test_wrong_type(tmp_path, good, key, value, frag):
    good[key] = value
    expect_error(tmp_path, good, key, frag)


def test_bool_is_not_a_number_in_channels(tmp_path, good):
    good["channels"][2]["counts_per_mps2"] = True
    expect_error(tmp_path, good, "channels[2].counts_per_mps2", "expected a number, got true")


@pytest.mark.parametrize("token", ["NaN", "Infinity", "-Infinity", "1e400"])
def test_nonfinite_tokens_rejected(tmp_path, good, token):
    text = json.dumps(good).replace('"gravity_mps2": 9.80665', f'"gravity_mps2": {token}')
    expect_error(tmp_path, text, "gravity_mps2", f"expected a finite number, got {token}")


def test_nan_inside_vector(tmp_path, good):
    text = json.dumps(good, indent=1)
    good["channels"][1]["axis"] = [0, 0, 12345.5]
    text = json.dumps(good).replace("12345.5", "NaN")
    expect_error(tmp_path, text, "channels[1].axis[2]", "got NaN")


def test_nan_in_unknown_field_rejected(tmp_path, good):
    text = json.dumps(good)[:-1] + ', "vendor": {"x": [1, NaN]}}'
    expect_error(tmp_path, text, "vendor.x[1]", "NaN")


def test_duplicate_key(tmp_path, good):
    text = json.dumps(good)[:-1] + ', "raw_max": 5}'
    expect_error(tmp_path, text, "raw_max", "given more than once")


@pytest.mark.parametrize("key,value", [("sample_rate_hz", 0), ("sample_rate_hz", -60.0), ("gravity_mps2", 0.0), ("gravity_mps2", -9.8)])
def test_nonpositive(tmp_path, good, key, value):
    good[key] = value
    expect_error(tmp_path, good, key, "expected a number > 0")


def test_raw_range(tmp_path, good):
    good["raw_min"] = 10000
    expect_error(tmp_path, good, "raw_max", "expected raw_max > raw_min (10000), got 10000")


def test_integral_float_raw_limits_accepted(tmp_path, good):
    good["raw_max"] = 10000.0
    assert load_device(write_json(tmp_path, good)).raw_max == 10000


def test_empty_channels(tmp_path, good):
    good["channels"] = []
    expect_error(tmp_path, good, "channels", "expected at least 3 channels, got an empty list")


def test_too_few_channels(tmp_path, good):
    good["channels"] = good["channels"][:2]
    expect_error(tmp_path, good, "channels", "expected at least 3 channels, got 2")


def test_channel_not_object(tmp_path, good):
    good["channels"][4] = [1, 2]
    expect_error(tmp_path, good, "channels[4]", "expected a JSON object")


@pytest.mark.parametrize(
    "axis,field,frag",
    [
        ([0, 0, 0], "channels[2].axis", "non-zero vector"),
        ([1, 0], "channels[2].axis", "expected 3 numbers, got 2"),
        ([1, 0, 0, 0], "channels[2].axis", "expected 3 numbers, got 4"),
        ("x", "channels[2].axis", 'expected 3 numbers, got "x"'),
        ([1, "0", 0], "channels[2].axis[1]", "expected a number"),
    ],
)
def test_bad_axis(tmp_path, good, axis, field, frag):
    good["channels"][2]["axis"] = axis
    expect_error(tmp_path, good, field, frag)


def test_bad_position(tmp_path, good):
    good["channels"][5]["position_m"] = [0.1, 0.2]
    expect_error(tmp_path, good, "channels[5].position_m", "expected 3 numbers, got 2")


@pytest.mark.parametrize("k", [0, -127.5])
def test_bad_counts_per_mps2(tmp_path, good, k):
    good["channels"][1]["counts_per_mps2"] = k
    expect_error(tmp_path, good, "channels[1].counts_per_mps2", "expected a number > 0")


@pytest.mark.parametrize("z", [-1, 10001])
def test_zero_counts_outside_range(tmp_path, good, z):
    good["channels"][0]["zero_counts"] = z
    expect_error(tmp_path, good, "channels[0].zero_counts", "[raw_min, raw_max] = [0, 10000]", str(z))


def test_rank_deficient_array(tmp_path, good):
    # every channel along z: rows [u, r x u] have rank 3
    for ch in good["channels"]:
        ch["axis"] = [0, 0, 1]
    expect_error(tmp_path, good, "channels", "rows [u_i, r_i x u_i] have rank 3 < 6")


def test_rank_deficient_all_at_origin(tmp_path, good):
    for ch in good["channels"]:
        ch["position_m"] = [0, 0, 0]
    expect_error(tmp_path, good, "channels", "rank 3 < 6")


def test_rank_4_message(tmp_path, good):
    # points on the x axis only: rows [x,0], [y, r1 z], [y, r2 z], [z, -r2 y] span 4 dims
    layout = [([0.06, 0, 0], [1, 0, 0]), ([0.06, 0, 0], [0, 1, 0]), ([0.12, 0, 0], [0, 1, 0]),
              ([0.12, 0, 0], [0, 0, 1]), ([0.06, 0, 0], [1, 0, 0]), ([0.06, 0, 0], [0, 1, 0])]
    for ch, (pos, axis) in zip(good["channels"], layout):
        ch["position_m"], ch["axis"] = pos, axis
    expect_error(tmp_path, good, "channels", "rows [u_i, r_i x u_i] have rank 4 < 6")


def test_all_at_one_point_rank_3(tmp_path, good):
    for ch in good["channels"]:
        ch["position_m"] = [0.06, 0, 0]
    expect_error(tmp_path, good, "channels", "rank 3 < 6")


def test_triad_positions_differ(tmp_path):
    d = default_triad().to_dict()
    d["channels"][2]["position_m"] = [0.01, 0, 0]
    expect_error(tmp_path, d, "channels", "share one position")


def test_triad_axes_dependent(tmp_path):
    d = default_triad().to_dict()
    d["channels"][2]["axis"] = [1, 1, 0]
    expect_error(tmp_path, d, "channels", "rank 2 < 3")


def test_four_channels_neither(tmp_path):
    d = default_triad().to_dict()
    d["channels"].append(copy.deepcopy(d["channels"][0]))
    expect_error(tmp_path, d, "channels", "4 channels are neither a triad")


def test_device_from_dict_source_name():
    with pytest.raises(InputError, match=r"^<dict>: field name: missing"):
        device_from_dict({})
    with pytest.raises(InputError, match=r"^cfg: field name"):
        device_from_dict({}, source="cfg")


def test_device_constructor_shape_checks():
    d = default_device()
    with pytest.raises(ValueError):
        Device(d.name, 60, 9.8, 0, 10, np.zeros((6, 3)), np.zeros((5, 3)), np.ones(6), np.zeros(6))
    with pytest.raises(ValueError):
        Device(d.name, 60, 9.8, 0, 10, np.zeros((6, 3)), np.zeros((6, 3)), np.ones(6), np.zeros(6))


# ---------------------------------------------------------------- properties

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
vec = st.lists(finite, min_size=3, max_size=3)


@st.composite
def valid_devices(draw):
    """Random 6..9-channel arrays: random axes/positions (almost surely rank 6)."""
    n = draw(st.integers(6, 9))
    raw_min = draw(st.integers(-40000, 0))
    raw_max = raw_min + draw(st.integers(1, 70000))
    chans = []
    for _ in range(n):
        axis = draw(vec.filter(lambda v: np.linalg.norm(v) > 1e-3))
        chans.append(
            {
                "position_m": draw(st.lists(st.floats(-1, 1, allow_nan=False), min_size=3, max_size=3)),
                "axis": axis,
                "counts_per_mps2": draw(st.floats(1e-3, 1e5)),
                "zero_counts": draw(st.integers(raw_min, raw_max) | st.floats(raw_min, raw_max)),
            }
        )
    return {
        "name": draw(st.text(max_size=20)),
        "sample_rate_hz": draw(st.floats(1e-3, 1e6)),
        "gravity_mps2": draw(st.floats(0.1, 100)),
        "raw_min": raw_min,
        "raw_max": raw_max,
        "noise_mps2": draw(st.floats(0, 10)),
        "channels": chans,
    }


@IO
@given(valid_devices())
def test_property_round_trip(tmp_path_factory, d):
    try:
        dev = device_from_dict(d)
    except InputError as e:
        # random geometry can be (numerically) rank deficient; nothing else may fail
        assert "rank" in str(e), str(e)
        return
    p = tmp_path_factory.getbasetemp() / "test_io_device_dev_d.json"
    save_device(dev, p)
    back = load_device(p)
    assert back == dev
    assert np.allclose(np.linalg.norm(back.axes, axis=1), 1.0)


@IO
@given(st.data())
def test_property_corrupted_dict_gives_input_error(data):
    d = default_device().to_dict()
    paths = [p for p in json_paths(d) if p]
    path = data.draw(st.sampled_from(paths))
    action = data.draw(st.sampled_from(["replace", "delete"]))
    target = d
    for k in path[:-1]:
        target = target[k]
    if action == "delete":
        del target[path[-1]]
    else:
        target[path[-1]] = data.draw(json_values)
    text = json.dumps(d)  # floats('nan') become NaN tokens: must be rejected cleanly too
    try:
        dev = device_from_dict(json.loads(text))
    except InputError as e:
        assert str(e).startswith("<dict>: ") and "\n" not in str(e)
        return
    assert isinstance(dev, Device)


@IO
@given(st.binary(max_size=300) | st.text(max_size=300).map(str.encode))
def test_property_random_bytes_gives_input_error(tmp_path_factory, blob):
    p = tmp_path_factory.getbasetemp() / "test_io_device_junk_dev.json"
    p.write_bytes(blob)
    with pytest.raises(InputError):
        load_device(p)


@IO
@given(st.data())
def test_property_truncated_file_gives_input_error(tmp_path_factory, data):
    text = json.dumps(default_device().to_dict(), indent=2)
    cut = data.draw(st.integers(0, len(text) - 2))
    p = tmp_path_factory.getbasetemp() / "test_io_device_cut_dev.json"
    p.write_text(text[:cut])
    with pytest.raises(InputError, match=r"dev\.json: "):
        load_device(p)
