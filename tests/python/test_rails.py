"""Readings at the ADC's rails: the chip clipped there, whatever the fixed-point core's own
saturation flag says (it reports its arithmetic: a pre-trim beyond 16 bits, set or not by the
sign of a rail reading's trim).  A tester's MPU-6050 row 32767,-32768,-32768 had come out of
`resolve` unflagged, and a calibration whose z offset left 0.94 g before the rail had no warning."""
import dataclasses

import numpy as np
import pytest

import accelcal as ac
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.cli.calibrate_command import clipping_warnings
from accelcal.io.device import default_triad, save_device
from accelcal.errors import AccelcalError
from accelcal.io.recording import recording_from_arrays, write_recording
from cli_run import run

G = 9.80665


def _still_with_rails(d):
    """A triad lying level (z up) for 200 samples, rows 50-59 with x at raw_max and rows 120-124
    with y at raw_min (the chip clipped on a knock)."""
    raw = np.round(d.zero_counts + np.array([0.0, 0.0, G]) * d.counts_per_mps2) + np.zeros((200, 3))
    raw[50:60, 0] = d.raw_max
    raw[120:125, 1] = d.raw_min
    return recording_from_arrays(np.arange(200) / d.sample_rate_hz, raw.astype(np.int64))


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_readings_at_the_rails_are_flagged_in_either_engine(tmp_path, capfd, engine):
    d = default_triad()
    rec = _still_with_rails(d)
    r = ac.resolve(d, Calibration.nominal(d), rec, engine=engine)
    want = np.zeros(200, bool)
    want[50:60] = want[120:125] = True
    np.testing.assert_array_equal(r.clipped, want)
    save_device(d, tmp_path / "d.json")
    save_calibration(Calibration.nominal(d), tmp_path / "c.json")
    write_recording(tmp_path / "r.csv", rec)
    rc, _, err, _ = run(["resolve", "--device", tmp_path / "d.json", "--calibration", tmp_path / "c.json",
                         tmp_path / "r.csv", "--engine", engine, "-o", tmp_path / "out.csv"], capfd)
    assert rc == 0 and "15 samples read a channel at the ADC's rail" in err, err
    assert "raw_0: 0 at 0, 10 at 65535" in err and "raw_1: 5 at 0, 0 at 65535" in err, err
    lines = [ln for ln in (tmp_path / "out.csv").read_text().splitlines() if not ln.startswith("#")]
    col = lines[0].split(",").index("clipped")
    np.testing.assert_array_equal([float(ln.split(",")[col]) for ln in lines[1:]], want.astype(float))


def test_a_recording_off_the_rails_gets_no_column_and_an_unknown_engine_is_an_accelcal_error(tmp_path, capfd):
    d = default_triad()
    rec = _still_with_rails(d)
    clean = recording_from_arrays(rec.t, np.tile(rec.raw[0], (200, 1)))
    assert not ac.resolve(d, Calibration.nominal(d), clean).clipped.any()
    with pytest.raises(AccelcalError, match="unknown engine 'fast'"):
        ac.resolve(d, Calibration.nominal(d), clean, engine="fast")


def test_a_calibration_whose_offset_leaves_less_than_g_before_the_rail_is_warned_of():
    """z's offset 17,000 counts above the middle of a +-2 g 16-bit range (16384 counts per g) leaves
    (32767 - 17000) / 16384 = 0.962 g before the rail: lying level the chip clips."""
    d = dataclasses.replace(default_triad(), raw_min=-32768, raw_max=32767,
                            zero_counts=np.zeros(3), counts_per_mps2=np.full(3, 16384 / G))
    cal = Calibration.nominal(d)
    assert clipping_warnings(d, cal) == []
    cal = dataclasses.replace(cal, offsets=np.array([0.0, 0.0, 17000.0]))
    w, = clipping_warnings(d, cal)
    assert "does not reach 1 g on channel 2 (-3.04 to +0.962 g" in w and "0.962 g before the rail" in w, w


def test_one_reading_is_one_sample_and_array_rows_count_from_one():
    """A notebook's first try, one reading (shape (3,)), had been refused ('expected an (n, 3)
    array'); and a NaN in an array's first row was 'row 0' where an out-of-range value there was
    'row 1'."""
    d = default_triad()
    cal = Calibration.nominal(d)
    raw = np.array([[32768, 32768, 49152], [40000, 32768, 32768]])
    one = ac.resolve(d, cal, raw[0])
    np.testing.assert_array_equal(one.f, ac.resolve(d, cal, raw[:1]).f)
    assert one.f.shape == (1, 3)
    with pytest.raises(AccelcalError, match=r"<array>: row 1: not integer counts"):
        ac.resolve(d, cal, np.array([[np.nan, 1.0, 2.0]]))
    with pytest.raises(AccelcalError, match=r"row 1, column raw_0"):
        ac.resolve(d, cal, np.array([[70000, 1, 2]]))


def _microbit_log():
    """A micro:bit log as `accelcal convert --units mg --lsb 4` makes it: counts of 4 mg inside the
    device's default 16-bit rails, x swinging beyond +-2 g so that its readings pile at +-2040 mg
    (+-510 counts), rests at either end."""
    rng = np.random.default_rng(4)
    n = 900
    i = np.arange(n)
    f = np.c_[2600 * np.sin(i / 7), 300 * np.cos(i / 5), -980 + 900 * np.sin(i / 11)]
    f[:150] = [60, -60, -1000]
    f[750:] = [-40, 20, -1000]
    counts = np.clip(np.rint((f + rng.normal(0, 12, f.shape)) / 4), -510, 510).astype(np.int64)
    d = dataclasses.replace(default_triad(), name="microbit", sample_rate_hz=44.34, raw_min=-32768, raw_max=32767,
                            zero_counts=np.zeros(3), counts_per_mps2=np.full(3, 1 / (4e-3 * G)))
    t = np.cumsum(rng.integers(21, 25, n)) / 1000.0
    return d, recording_from_arrays(t - t[0], counts)


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_resolve_flags_the_piles_convert_and_diagnose_call_clipped(tmp_path, capfd, engine):
    """F7: on a micro:bit log clipping at +-2040 mg (+-510 counts, inside the device's 16-bit rails)
    convert and diagnose noted the readings piled at the clip levels, but resolve wrote f ~ +-20 m/s^2
    there with no `clipped` column and no warning (it knew only the rails).  It flags the samples at
    the levels clipping.clip_levels finds (the ones convert's note counts), in either engine."""
    from accelcal.readings.clipping import clip_note
    d, rec = _microbit_log()
    want = np.abs(rec.raw[:, 0]) == 510
    assert 100 < want.sum() < 400 and not np.any(np.abs(rec.raw[:, 1:]) == 510)
    note = clip_note(rec.raw, d, 44)
    assert note and f"{int(want.sum())} reading(s) sit at the ends of the range" in note
    save_device(d, tmp_path / "d.json")
    save_calibration(Calibration.nominal(d), tmp_path / "c.json")
    write_recording(tmp_path / "r.csv", rec)
    rc, _, err, _ = run(["resolve", "--device", tmp_path / "d.json", "--calibration", tmp_path / "c.json",
                         tmp_path / "r.csv", "--engine", engine, "-o", tmp_path / "out.csv"], capfd)
    assert rc == 0 and f"{int(want.sum())} samples read a channel at a clip level inside the range" in err, err
    assert f"raw_0: {int((rec.raw[:, 0] == -510).sum())} at -510, {int((rec.raw[:, 0] == 510).sum())} at 510" in err
    assert "ADC's rail" not in err
    lines = [ln for ln in (tmp_path / "out.csv").read_text().splitlines() if not ln.startswith("#")]
    col = lines[0].split(",").index("clipped")
    np.testing.assert_array_equal([float(ln.split(",")[col]) for ln in lines[1:]], want.astype(float))
    # the API's ResolveResult.clipped is the command's column
    got = ac.resolve(d, Calibration.nominal(d), rec, engine=engine).clipped
    np.testing.assert_array_equal(got, want)
