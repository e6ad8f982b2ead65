"""Misspelt keys in the device and calibration JSON are named with the closest valid one."""
import json

import pytest

from accelcal.io.calibration import calibration_from_dict, calibration_to_dict
from accelcal.io.device import default_device, device_from_dict
from accelcal.errors import InputError
from accelcal.api import calibrate, simulate


def _dev():
    return default_device().to_dict()


@pytest.mark.parametrize("wrong,right", [("noise_mps", "noise_mps2"), ("sample_rate", "sample_rate_hz"),
                                         ("gravity_mps", "gravity_mps2"), ("raw_mx", "raw_max")])
def test_misspelt_top_level_key(wrong, right):
    d = _dev()
    d[wrong] = d.pop(right) if right in d else 0.02
    with pytest.raises(InputError) as e:
        device_from_dict(json.loads(json.dumps(d)), "D.json")
    msg = str(e.value)
    assert wrong in msg and repr(right) in msg and "\n" not in msg


def test_misspelt_channel_key_names_the_channel():
    d = _dev()
    d["channels"][4]["counts_per_mps"] = d["channels"][4].pop("counts_per_mps2")
    with pytest.raises(InputError, match=r"channels\[4\]\.counts_per_mps.*'counts_per_mps2'"):
        device_from_dict(d, "D.json")


def test_missing_required_key_names_the_near_key_present():
    d = _dev()
    del d["raw_min"]
    d["raw_minimum"] = 0
    with pytest.raises(InputError, match=r"raw_min: missing \(required\); the object has 'raw_minimum'"):
        device_from_dict(d, "D.json")


def test_extension_keys_far_from_every_known_key_pass():
    d = _dev()
    d["vendor"] = "acme"
    d["channels"][0]["chip"] = "ADXL202E"
    assert device_from_dict(d, "D.json").n_channels == 6


def test_misspelt_calibration_channel_key():
    dev = default_device()
    cal = calibrate(dev, simulate(dev, "static_poses", poses="6", seed=1))
    d = calibration_to_dict(cal)
    d["channels"][1]["offset_count"] = d["channels"][1].pop("offset_counts")
    with pytest.raises(InputError, match=r"channels\[1\]\.offset_count.*'offset_counts'"):
        calibration_from_dict(d, "C.json", dev)
