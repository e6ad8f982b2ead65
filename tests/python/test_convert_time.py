"""Time columns in other units and time stamps taken by a host (``accelcal convert``).

Loggers write t as millis(), micros() or an epoch in nanoseconds, and a host that reads
the sensor in bursts stamps each burst's samples a few microseconds apart.  Either way
``convert`` must write t in seconds and give the device the sensor's rate (a rate 1000 x
too low made ``displacement`` report kilometres).  The files are written here; the
expected values come from the times they were written with.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from accelcal.convert.formats import convert_file, unit_in_name
from accelcal.io.device import load_device
from accelcal.io.recording import read_recording
from accelcal.io.recording_checks import rate_for
from cli_run import run

FACTOR = {"s": 1.0, "ms": 1e3, "us": 1e6, "ns": 1e9}


def _write(path, t_text, counts, header="t,raw_0,raw_1,raw_2"):
    lines = [header] + [f"{a},{b},{c},{d}" for a, (b, c, d) in zip(t_text, counts)]
    path.write_text("\n".join(lines) + "\n")


def _counts(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.round([100.0, -50.0, 16384.0] + 3.0 * rng.standard_normal((n, 3))).astype(int)


@pytest.mark.parametrize("unit", ["ms", "us", "ns"])
@pytest.mark.parametrize("rate", [50.0, 100.0, 1000.0])
@pytest.mark.parametrize("epoch", [False, True])
def test_finer_time_units_are_read_as_such(tmp_path, capfd, unit, rate, epoch):
    n = 400
    t_s = np.arange(n) / rate + (1.73e9 if epoch else 0.0)
    ticks = t_s * FACTOR[unit]
    text = [f"{int(round(v))}" for v in ticks] if unit == "ns" else [f"{v:.3f}" for v in ticks]
    src = tmp_path / "log.csv"
    _write(src, text, _counts(n))
    rc, out, err, _ = run(["convert", src, "-o", tmp_path / "r.csv", "--device-out", tmp_path / "d.json"], capfd)
    assert rc == 0, err
    assert f"t read in {unit}" in err
    rec = read_recording(tmp_path / "r.csv")
    np.testing.assert_allclose(rec.t - rec.t[0], t_s - t_s[0], atol=2e-6)
    dev = json.loads((tmp_path / "d.json").read_text())
    assert dev["sample_rate_hz"] == pytest.approx(rate, rel=1e-4)
    # the stamps come from float64 seconds since the epoch (~0.2 us apart at best), so the rate to 1e-4
    said = float(out.split(" Hz")[0].rsplit(", ", 1)[1])
    assert said == pytest.approx(rate, rel=1e-4)


@pytest.mark.parametrize("header", ["t,raw_0,raw_1,raw_2", "timestamp,accX,accY,accZ"])
def test_epoch_nanoseconds_are_read_exactly(tmp_path, capfd, header):
    """A 1 kHz log stamped in epoch ns (a LORD log's ``timestamp``; the csv format's t too):
    float64 keeps such a stamp to 256 ns, so the rate came out 1e-4 off (999.936 Hz here).
    The stamps are read as integers and the first subtracted before they become seconds:
    1000 Hz to 1e-9, and the steps written exact to float64's rounding of the seconds."""
    n, t0 = 2000, 1_700_000_000_123_456_789
    ticks = [t0 + k * 1_000_000 for k in range(n)]
    src = tmp_path / "log.csv"
    _write(src, [str(v) for v in ticks], _counts(n), header=header)
    rc, out, err, _ = run(["convert", src, "-o", tmp_path / "r.csv", "--device-out", tmp_path / "d.json"], capfd)
    assert rc == 0, err
    assert "t read in ns" in err
    assert json.loads((tmp_path / "d.json").read_text())["sample_rate_hz"] == pytest.approx(1000.0, rel=1e-9)
    assert float(out.split(" Hz")[0].rsplit(", ", 1)[1]) == pytest.approx(1000.0, rel=1e-9)
    conv = convert_file(src)
    assert conv.device.sample_rate_hz == pytest.approx(1000.0, rel=1e-9)
    t = conv.recording.t
    assert t[0] == pytest.approx(t0 / 1e9, abs=1e-6)
    np.testing.assert_allclose(t - t[0], np.arange(n) / 1000.0, atol=5e-7)   # float64 of 1.7e9 s: 2.4e-7


def test_integer_stamps_too_close_for_float64_are_still_in_order(tmp_path):
    """Stamps 100 ns apart in epoch ns are one float64 (256 ns apart): read as integers they
    are distinct and increasing (a table refused them as 'not after' the stamp before)."""
    n, t0 = 50, 1_700_000_000_000_000_000
    src = tmp_path / "fast.csv"
    _write(src, [str(t0 + 100 * k) for k in range(n)], _counts(n), header="t_ns,accX,accY,accZ")
    conv = convert_file(src)
    assert conv.device.sample_rate_hz == pytest.approx(1e7, rel=1e-9)


@pytest.mark.parametrize("rate", [10.0, 100.0, 400.0])
def test_seconds_stay_seconds_without_a_note(tmp_path, capfd, rate):
    n = 300
    t = np.arange(n) / rate
    src = tmp_path / "log.csv"
    _write(src, [f"{v:.6f}" for v in t], _counts(n))
    rc, out, err, _ = run(["convert", src, "-o", tmp_path / "r.csv", "--device-out", tmp_path / "d.json"], capfd)
    assert rc == 0, err
    assert "t read in" not in err and "bursts" not in err
    np.testing.assert_allclose(read_recording(tmp_path / "r.csv").t, t, atol=1e-6)
    assert json.loads((tmp_path / "d.json").read_text())["sample_rate_hz"] == pytest.approx(rate, rel=1e-6)


def test_a_stated_unit_wins_over_the_guess(tmp_path, capfd):
    """A 1 Hz logger in seconds is read as milliseconds by the guess (the note says how to
    state otherwise); --time-unit s keeps it, --time-unit ms on a 10 Hz log in ms divides."""
    n = 50
    src = tmp_path / "slow.csv"
    _write(src, [f"{v:.1f}" for v in np.arange(n, dtype=float)], _counts(n))
    conv = convert_file(src)
    assert conv.device.sample_rate_hz == pytest.approx(1000.0) and any("--time-unit" in m for m in conv.notes)
    conv = convert_file(src, time_unit="s")
    assert conv.device.sample_rate_hz == pytest.approx(1.0) and not conv.notes
    np.testing.assert_allclose(conv.recording.t, np.arange(n))
    src2 = tmp_path / "ten.csv"
    _write(src2, [f"{100 * k}" for k in range(n)], _counts(n))
    conv = convert_file(src2, time_unit="ms")
    np.testing.assert_allclose(conv.recording.t, np.arange(n) / 10.0)
    assert conv.device.sample_rate_hz == pytest.approx(10.0)


@pytest.mark.parametrize("name, unit", [("t", None), ("Time (s)", "s"), ("Time (ms)", "ms"), ("timestamp_us", "us"),
                                        ("t[ns]", "ns"), ("time_usec", "us"), ("millis", "ms"), ("timestamp", None),
                                        ("seconds_elapsed", "s")])
def test_the_unit_a_column_name_states(name, unit):
    assert unit_in_name(name) == unit


@pytest.mark.parametrize("burst", [4, 10])
def test_host_time_stamps_in_bursts_give_the_sensor_s_rate(tmp_path, capfd, burst):
    """A 100 Hz sensor read by a host every ``burst`` samples: the samples of a read are
    stamped 50 us apart, so t's median step says ~20 kHz.  The device gets the rate of the
    samples over the duration, and a note says why; --rate states it outright.  t is written
    on that rate's grid (the estimators need the even spacing: they refused the host's
    stamps as 11 M missing samples), the host's stamps as column t_host."""
    n, rate = 1000, 100.0
    k = np.arange(n)
    t = (k // burst) * burst / rate + (k % burst) * 50e-6
    src = tmp_path / "host.csv"
    _write(src, [f"{v:.6f}" for v in t], _counts(n))
    rc, out, err, _ = run(["convert", src, "-o", tmp_path / "r.csv", "--device-out", tmp_path / "d.json"], capfd)
    assert rc == 0, err
    assert "bursts" in err
    got = json.loads((tmp_path / "d.json").read_text())["sample_rate_hz"]
    assert got == pytest.approx(rate, rel=1e-6)      # (n - 1) / duration said 100.3 Hz for bursts of 4
    rec = read_recording(tmp_path / "r.csv")
    np.testing.assert_allclose(rec.t, t[0] + np.arange(n) / got, atol=1e-9)
    np.testing.assert_allclose(np.array(rec.extra["t_host"], float), t, atol=1e-9)
    conv = convert_file(src, rate_hz=100.0)
    assert conv.device.sample_rate_hz == pytest.approx(100.0)
    np.testing.assert_allclose(conv.recording.t, np.arange(n) / 100.0, atol=1e-9)


def _host_stamps(n, rate, stamp_at, seed):
    """Time stamps a host gives a ``rate`` Hz sensor read in bursts of 5 to 12 samples: each
    burst stamped when its first sample was taken ("first") or when the host read the buffer,
    0 to 1 ms after its last ("last"), and its samples 20 us apart from there."""
    rng = np.random.default_rng(seed)
    sizes = []
    while sum(sizes) < n:
        sizes.append(int(rng.integers(5, 13)))
    t, k = [], 0
    for size in sizes:
        anchor = k if stamp_at == "first" else k + size - 1
        at = 1000.0 + anchor / rate + (0.0 if stamp_at == "first" else rng.uniform(0.0, 1e-3))
        t += [at + 20e-6 * j for j in range(size)]
        k += size
    return np.array(t[:n])


@pytest.mark.parametrize("stamp_at", ["first", "last"])
@pytest.mark.parametrize("n, tol", [(50, 5e-3), (5000, 5e-4)])
def test_bursty_stamps_give_an_unbiased_rate(tmp_path, stamp_at, n, tol):
    """(n - 1) / duration counted the last burst's other samples over no time: 50 rows of a
    100 Hz sensor in bursts said up to ~117 Hz ((burst - 1) / n too high).  The samples between
    the bursts' stamps over their time give 100 Hz within 0.5 % (50 rows) and 0.05 % (5000),
    whether a burst is stamped at its first sample or when the host read it."""
    for seed in range(5):
        t = _host_stamps(n, 100.0, stamp_at, seed)
        src = tmp_path / f"host_{seed}.csv"
        _write(src, [f"{v:.6f}" for v in t], _counts(n))
        conv = convert_file(src)
        assert any("bursts" in m for m in conv.notes)
        assert conv.device.sample_rate_hz == pytest.approx(100.0, rel=tol), (seed, (n - 1) / (t[-1] - t[0]))


def test_a_time_unit_for_a_file_without_time_is_refused(tmp_path, capfd):
    src = tmp_path / "imucal.csv"
    src.write_text("acc_x,acc_y,acc_z\n1,2,3\n4,5,6\n")
    rc, _, err, _ = run(["convert", src, "--rate", "100", "--time-unit", "ms", "-o", tmp_path / "r.csv"], capfd)
    assert rc == 2 and err.count("\n") == 1 and "--time-unit" in err and "no time column" in err
    assert not (tmp_path / "r.csv").exists()


def test_a_single_sample_says_its_rate_is_a_placeholder(tmp_path):
    src = tmp_path / "one.csv"
    _write(src, ["0.5"], _counts(1))
    conv = convert_file(src)
    assert conv.device.sample_rate_hz == 1.0 and any("a single sample" in n for n in conv.notes)
    assert convert_file(src, rate_hz=100.0).device.sample_rate_hz == 100.0


@pytest.mark.parametrize("fmt, header", [("table", "Timestamp(Ms),accX,accY,accZ"), ("csv", "t,raw_0,raw_1,raw_2")])
def test_a_stated_rate_that_the_time_column_contradicts_puts_t_on_its_grid(tmp_path, capfd, fmt, header):
    """A logger whose millis() clock runs slow (TWLogger: 16 ms steps, 62.5 Hz, for a 50 Hz
    sensor; here 15 ms, 66.7 Hz): --rate 50 puts t on the 50 Hz grid from the first stamp with
    a note giving both rates, the stamps kept as t_host, so that the commands keep 50 Hz
    (rate_for took the stamps' rate); a rate within 20 % of the stamps' (60 Hz) leaves t as
    written, no note."""
    n = 300
    ms = 15225 + 15 * np.arange(n)
    ms[100:] += 80                                   # a pause for a flush: no sample lost
    src = tmp_path / "tw.csv"
    _write(src, [str(v) for v in ms], _counts(n), header)
    args = ["--time-unit", "ms"] if fmt == "csv" else []
    out, dev = tmp_path / "r.csv", tmp_path / "d.json"
    rc, _, err, _ = run(["convert", src, "--rate", "50", *args, "-o", out, "--device-out", dev], capfd)
    assert rc == 0, err
    assert ("the time column's steps give 66.6667 Hz (median step), more than 20 % from --rate 50 Hz: its clock "
            "is not the sensor's; t is written on the 50 Hz grid from the first stamp") in err
    rec = read_recording(out)
    np.testing.assert_allclose(rec.t, 15.225 + np.arange(n) / 50.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(rec.extra["t_host"], float), ms / 1e3, rtol=0, atol=1e-9)
    device = load_device(dev)
    assert device.sample_rate_hz == 50.0
    assert rate_for([rec], device) == (device, None)          # the device's 50 Hz stands
    conv = convert_file(src, fmt, rate_hz=60.0, time_unit="ms")
    np.testing.assert_allclose(conv.recording.t, ms / 1e3, rtol=0, atol=1e-9)
    assert "t_host" not in conv.recording.extra and not any("grid" in n for n in conv.notes)


def test_a_paused_recording_keeps_its_stamps_and_its_rate(tmp_path, capfd):
    """A phone app paused and resumed (Sensor Logger: steady 9.58 ms steps, one of 163 s): the
    median and mean steps disagree as a host's bursts do, but the runs' starts do not keep
    time with their samples.  It had been taken for bursts and t rewritten at 46 Hz; it keeps
    its stamps, the rate is the runs' 104.36 Hz, and a note names the pause."""
    rate = 1.0 / 0.0095825
    t = np.concatenate([np.arange(9000), 9000 + 163.0 * rate + np.arange(6000)]) / rate
    t += np.random.default_rng(4).uniform(-2e-4, 2e-4, t.size)        # the host's jitter
    src = tmp_path / "paused.csv"
    _write(src, [f"{int(round(v * 1e9)) + 1_700_000_000_000_000_000}" for v in t], _counts(t.size, seed=8),
           header="time,accX,accY,accZ")
    rc, out, err, _ = run(["convert", src, "--units", "counts", "-o", tmp_path / "r.csv", "--device-out",
                           tmp_path / "d.json"], capfd)
    assert rc == 0, err
    rec = read_recording(tmp_path / "r.csv")
    np.testing.assert_allclose(rec.t - rec.t[0], t - t[0], atol=1e-6)
    assert json.loads((tmp_path / "d.json").read_text())["sample_rate_hz"] == pytest.approx(rate, rel=1e-4)
    assert "bursts" not in err and "1 step longer than 1.8 x its median step" in err and "t_host" not in err, err


def test_a_clock_with_periodic_corrections_gives_its_mean_rate(tmp_path, capfd):
    """An x-IMU3's stamps step 10.079 ms with a shorter step every 32nd (its clock corrected):
    100.00 Hz over the file, where the median step gave 99.21 Hz."""
    n = 3200
    steps = np.where(np.arange(1, n) % 32 == 0, 0.0075528, 0.0100794)
    steps *= (n - 1) * 0.01 / steps.sum()                          # 100 Hz over the file
    t = np.concatenate([[0.0], np.cumsum(steps)])
    src = tmp_path / "ximu3.csv"
    _write(src, [f"{v:.7f}" for v in t], _counts(n, seed=9), header="Time (s),accX,accY,accZ")
    rc, out, err, _ = run(["convert", src, "--units", "counts", "-o", tmp_path / "r.csv", "--device-out",
                           tmp_path / "d.json"], capfd)
    assert rc == 0, err
    assert json.loads((tmp_path / "d.json").read_text())["sample_rate_hz"] == pytest.approx(100.0, rel=1e-5)


@pytest.mark.parametrize("name,start,step", [("unix_timestamp", 1764754394388530, 15625),
                                             ("epoch", 1764754394.388530, 1 / 64), ("unix_time", 1764754394388.53, 15.625),
                                             ("SensorTimestamp_ms", 1000.0, 15.625), ("time_s", 0.0, 1 / 64),
                                             ("timestamp_us", 0, 15625)])
def test_time_columns_of_other_spellings_are_found(tmp_path, capfd, name, start, step):
    """Empatica EmbracePlus's ``unix_timestamp`` (us since 1970) had not been taken for a time
    column ('the table has no time column'), nor ``epoch`` or ``unix_time``: a name with a time
    word among others is one where it states a unit or its stamps are an epoch's (the unit then
    from the steps)."""
    counts = _counts(64)
    t = [f"{start + k * step:.6f}" for k in range(64)]
    rows = [f"{tt},{a},{b},{c}" for tt, (a, b, c) in zip(t, counts)]
    src = tmp_path / "acc.csv"
    src.write_text("\n".join([f"{name},accX,accY,accZ"] + rows) + "\n")
    conv = convert_file(src)
    np.testing.assert_array_equal(conv.recording.raw, counts)
    np.testing.assert_allclose(np.diff(conv.recording.t), 1 / 64.0, rtol=1e-6)


@pytest.mark.parametrize("name", ["elapsed_time", "delta_time"])
def test_a_time_word_without_unit_or_epoch_is_no_time_column(tmp_path, capfd, name):
    """A name with a time word but neither a unit nor epoch stamps (``elapsed_time`` 0, 0.01, ...)
    is not guessed at: the refusal names it and --time-column; ``delta_time`` (a step between
    samples) is no time column at all."""
    rows = [f"{k / 100:.2f},{a},{b},{c}" for k, (a, b, c) in enumerate(_counts(20))]
    src = tmp_path / "acc.csv"
    src.write_text("\n".join([f"{name},accX,accY,accZ"] + rows) + "\n")
    rc, _, err, _ = run(["convert", str(src), "-o", str(tmp_path / "o.csv")], capfd)
    assert rc == 2 and "has no time column" in err, err
    assert (f"'{name}' has a time's name" in err) == (name == "elapsed_time"), err


def _packet_log(path, n=2400, gaps=False, tick_us=25.0, seed=1):
    """An LSM6DSOX log of EMGesture's shape: ``timestamp`` the chip's clock in 25 us ticks (192 a
    sample: 208.33 Hz), ``pkt_time_ns`` the host's epoch in ns shared by each packet of 12
    samples; with ``gaps`` 9 samples lost at sample 700 and a 3.25 s pause at sample 1500."""
    rng = np.random.default_rng(seed)
    tick = 121313 + 192 * np.arange(n)
    if gaps:
        tick[700:] += 192 * 9
        tick[1500:] += 130000
    t_s = (tick - tick[0]) * tick_us * 1e-6
    first = np.arange(n) // 12 * 12
    pkt = 1745203091567360040 + np.round((t_s[np.minimum(first + 11, n - 1)] + 0.004) * 1e9).astype(np.int64)
    acc = np.rint([0, 0, 8197] + rng.normal(0, 8, (n, 3))).astype(int)
    gyr = np.rint(rng.normal(0, 20, (n, 3))).astype(int)
    path.write_text("timestamp,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,pkt_time_ns\n" + "".join(
        f"{tick[i]},{gyr[i, 0]},{gyr[i, 1]},{gyr[i, 2]},{acc[i, 0]},{acc[i, 1]},{acc[i, 2]},{pkt[i]}\n"
        for i in range(n)))
    return tick, t_s


@pytest.mark.parametrize("gaps", [False, True])
def test_packet_stamps_give_way_to_the_chip_s_clock(tmp_path, capfd, gaps):
    """A host's stamp for each packet of 12 samples (pkt_time_ns) is no sample's time: it had been
    taken for the time column (its name states a unit) and refused, advising --repeated-stamps drop
    (one sample in 12 kept, 17 Hz from a 208 Hz sensor).  The chip's clock, which times every
    sample, is used; its unit (no unit in its name) is measured against the packets' stamps, so t
    keeps the lost samples and the pause."""
    tick, t_s = _packet_log(tmp_path / "dsox.csv", gaps=gaps, tick_us=25.4)
    out, dev = tmp_path / "r.csv", tmp_path / "d.json"
    rc, _, err, _ = run(["convert", tmp_path / "dsox.csv", "--full-scale", "4", "-o", out, "--device-out", dev], capfd)
    assert rc == 0, err
    assert "time column 'timestamp' used: 'pkt_time_ns' repeats its stamp in packets of 12 rows" in err, err
    assert "its unit is 25.4 us" in err, err
    rec = read_recording(out)
    assert rec.t.size == 2400
    np.testing.assert_allclose(rec.t - rec.t[0], t_s, rtol=2e-3)
    assert json.loads(dev.read_text())["sample_rate_hz"] == pytest.approx(1e6 / (192 * 25.4), rel=2e-3)


def test_packet_stamps_chosen_are_refused_naming_the_chip_s_clock(tmp_path, capfd):
    """--time-column naming the packet stamps: refused, naming the column that times each sample,
    not advising --repeated-stamps drop (a sample a packet kept)."""
    _packet_log(tmp_path / "dsox.csv")
    rc, _, err, _ = run(["convert", tmp_path / "dsox.csv", "--full-scale", "4", "--time-column", "pkt_time_ns",
                         "-o", tmp_path / "r.csv"], capfd)
    assert rc == 2 and not (tmp_path / "r.csv").exists()
    line = err.strip().splitlines()[-1]
    assert "packets of 12 rows" in line and "--time-column NAME ('timestamp')" in line and "drop" not in line, err


@pytest.mark.parametrize("unit, factor", [("25us", 4e4), ("0.5ms", 2e3), ("1e-4s", 1e4), ("2 ns", 5e8)])
def test_a_time_unit_may_be_a_tick(tmp_path, unit, factor):
    """--time-unit 25us reads a chip's clock in 25 us ticks (before, only s, ms, us, ns, and a
    clock in ticks could be read only with --rate, which put t on a grid that erased its gaps)."""
    n = 300
    t = 1000 + 4 * np.arange(n)
    t[150:] += 400                                    # a pause of 100 ticks
    src = tmp_path / "ticks.csv"
    _write(src, [str(v) for v in t], _counts(n))
    conv = convert_file(src, time_unit=unit)
    np.testing.assert_allclose(conv.recording.t, t / factor, rtol=1e-12)


def test_a_stated_rate_over_a_tick_clock_notes_the_gaps_the_grid_drops(tmp_path, capfd):
    """--rate with a time column whose steps disagree puts t on the grid; the stamps' long steps (9
    samples lost, a 3.25 s pause) vanished without a note.  Now a note counts them and names
    --time-unit, which keeps them."""
    _packet_log(tmp_path / "dsox.csv", gaps=True)
    rc, _, err, _ = run(["convert", tmp_path / "dsox.csv", "--full-scale", "4", "--time-column", "timestamp",
                         "--rate", "208", "-o", tmp_path / "r.csv"], capfd)
    assert rc == 0, err
    assert "the time column has 2 steps longer than 1.8 x its median step" in err and "--time-unit" in err, err


def test_a_ms_column_is_written_as_the_stamps_say(tmp_path, capfd):
    """t from a ms column had been written 0.024999999999999998 for 25 ms (the first stamp over
    1000 plus the steps over 1000); each stamp divided by its unit is written as its shortest
    repr (0.025)."""
    src = tmp_path / "ms.csv"
    src.write_text("time,x,y,z\n3,60,-64,-1000\n25,64,-60,-1004\n46,60,-64,-996\n")
    out = tmp_path / "r.csv"
    rc, _, err, _ = run(["convert", src, "--units", "mg", "--lsb", "4", "--rate", "45", "-o", out], capfd)
    assert rc == 0, err
    rows = [line.split(",")[0] for line in out.read_text().splitlines() if line[:1].isdigit()]
    assert rows == ["0.003", "0.025", "0.046"], rows
