"""The correctable terms in the generated header: the recipe its comment gives, compiled for
the host with the core, is bit for bit ``resolve --engine fixed`` (which runs the same tables
through cffi), for a 6-channel array with unsigned readings and a 3-axis chip with signed
ones; the header cross-compiles warning-free for the H8/300H and the AVR; and both engines
take the terms out of readings made by the independent generator (tests/python/indep_model.py)."""
import dataclasses
import subprocess

import numpy as np
import pytest

from accelcal.io.calibration import Calibration
from accelcal.io.device import Device, default_device
from accelcal.firmware.terms_fixed import TEMP_FRAC
from accelcal.firmware.header import calibration_header
from accelcal.firmware.native import FORMATS
from accelcal.io.recording import recording_from_arrays
from accelcal.resolve import resolve_recording
from toolchains import build_host, cross_compile

DRIVER = r"""
#define AC_CAL_IMPLEMENTATION
#include "cal.h"
#include <stdio.h>
int main(void) {
    %(raw_t)s raw[%(n)d];
    int16_t x[%(n)d], temp = 0, t_off = 0, t_gain = 0;
    int32_t out[6];
    long v;
    int i, st;
    ac_temp_lag lag_off, lag_gain;
    static int16_t line_buf[%(skew_len)s * %(n)d];
    ac_skew_line line;
    (void)t_off; (void)t_gain; (void)lag_off; (void)lag_gain; (void)line; (void)line_buf;
%(init)s
    for (;;) {
        for (i = 0; i < %(n)d; i++) { if (scanf("%%ld", &v) != 1) return 0; raw[i] = (%(raw_t)s)v; }
        if (scanf("%%ld", &v) != 1) return 13;
        temp = (int16_t)v;
        st = (int)%(trim)s;
%(per_sample)s
        st |= (int)%(resolve)s;
        printf("%%d", st);
        for (i = 0; i < %(nout)d; i++) printf(" %%ld", (long)out[i]);
        printf("\n");
    }
}
"""


def signed_triad() -> Device:
    """An MPU-6050-like 3-axis chip: signed 16-bit, 1670 counts per m/s^2 (+-2 g), 100 Hz."""
    return Device(name="signed-triad", sample_rate_hz=100.0, gravity_mps2=9.80665, raw_min=-32768, raw_max=32767,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1670.0),
                  zero_counts=np.zeros(3))


def with_terms(dev: Device, rng) -> Calibration:
    n = dev.n_channels
    cal = Calibration.nominal(dev)
    g1 = np.linalg.norm(cal.sensitivity, axis=1) * 9.80665          # counts at 1 g
    return dataclasses.replace(
        cal, offsets=cal.offsets + rng.uniform(-30, 30, n) * g1 / 1000,
        nonlin_k2=0.005 * g1 / 9.80665 ** 2 * rng.choice([-1, 1], n),
        nonlin_k3=0.002 * g1 / 9.80665 ** 3 * rng.choice([-1, 1], n),
        time_skew_s=rng.uniform(-0.6, 1.4, n) / dev.sample_rate_hz,
        offset_tc=rng.normal(0, 0.002, n) * g1, gain_tc=rng.normal(0, 3e-4, n), temp_ref_c=25.0,
        temp_offset_tau_s=20.0, temp_gain_tau_s=5.0)


def driver(dev: Device, cal: Calibration) -> str:
    n, signed, triad = dev.n_channels, dev.raw_min < 0, dev.is_triad()
    return DRIVER % dict(
        raw_t="int16_t" if signed else "uint16_t", n=n, skew_len="AC_CAL_SKEW_LEN", nout=3 if triad else 6,
        init="\n".join([
            "    ac_temp_lag_init(&lag_off, AC_CAL_TEMP_OFF_LAG_K, AC_CAL_TEMP_OFF_LAG_SHIFT);",
            "    ac_temp_lag_init(&lag_gain, AC_CAL_TEMP_GAIN_LAG_K, AC_CAL_TEMP_GAIN_LAG_SHIFT);",
            f"    ac_skew_init(&line, &AC_CAL_SKEW, line_buf, AC_CAL_SKEW_LEN * {n});"]),
        trim=(f"ac_trim_rails_s16(raw, AC_CAL_TRIM, {n}, AC_CAL_RAW_MIN, AC_CAL_RAW_MAX, x)" if signed else
              f"ac_trim_rails(raw, AC_CAL_TRIM, {n}, AC_CAL_RAW_MIN, AC_CAL_RAW_MAX, x)"),
        per_sample="\n".join([
            "        st |= (int)ac_temp_lag_step(&lag_off, temp, &t_off);",
            "        st |= (int)ac_temp_lag_step(&lag_gain, temp, &t_gain);",
            "        st |= (int)ac_temp_correct(&AC_CAL_TEMP, t_off, t_gain, x, x);",
            "        st |= (int)ac_skew_step(&AC_CAL_SKEW, &line, x, x);",
            "        st |= (int)ac_nonlin_invert(&AC_CAL_NONLIN, x, x);"]),
        resolve="ac_triad_resolve(&AC_CAL_TRIAD, x, out)" if triad else "ac_resolve(&AC_CAL_RESOLVER, x, 0, out)")


def readings(dev: Device, cal: Calibration, rng, n=1500):
    """Random-walk specific force and a temperature ramp: raw counts within the converter's range."""
    f = np.cumsum(rng.normal(0, 0.4, (n, 3)), axis=0)
    f = 9.80665 * 1.5 * np.tanh(f / 15.0)
    raw = f @ cal.sensitivity.T + cal.offsets + rng.normal(0, 2, (n, dev.n_channels))
    raw = np.clip(np.round(raw), dev.raw_min, dev.raw_max).astype(np.int64)
    temp = 15.0 + 25.0 * np.arange(n) / n
    return raw, temp


def triad12() -> Device:
    """An ADXL-like 12-bit 3-axis chip, unsigned 0..4095 about 2048, 41.8 counts per m/s^2, 50 Hz: the
    terms hand on 2^-3 counts (AC_CAL_TERMS_FRAC 3)."""
    return Device(name="triad12", sample_rate_hz=50.0, gravity_mps2=9.80665, raw_min=0, raw_max=4095,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 41.8),
                  zero_counts=np.full(3, 2048.0))


#: each device's hand-off fraction bits (firmware.terms_fixed.terms_frac): the seed's 0..10000 array 2,
#: the 12-bit chip 3, the signed 16-bit chip 0 (whole counts, the arithmetic before the fraction bits)
FRAC = {"array": 2, "signed_triad": 0, "triad12": 3}


@pytest.fixture(scope="module", params=["array", "signed_triad", "triad12"])
def built(request, tmp_path_factory):
    dev = {"array": default_device, "signed_triad": signed_triad, "triad12": triad12}[request.param]()
    rng = np.random.default_rng(11)
    cal = with_terms(dev, rng)
    tmp = tmp_path_factory.mktemp(f"terms_{request.param}")
    text = calibration_header(dev, cal)
    assert f"#define AC_CAL_TERMS_FRAC {FRAC[request.param]}\n" in text
    (tmp / "cal.h").write_text(text)
    (tmp / "main.c").write_text(driver(dev, cal))
    return dev, cal, tmp


def test_header_recipe_is_the_fixed_engine_bit_for_bit(built):
    dev, cal, tmp = built
    exe = tmp / "drv"
    build_host(tmp / "main.c", exe)
    raw, temp = readings(dev, cal, np.random.default_rng(5))
    rec = recording_from_arrays(np.arange(raw.shape[0]) / dev.sample_rate_hz, raw, temp_c=temp)
    f, _, flags = resolve_recording(dev, cal, rec, "fixed", omega_source="none")
    m = int(cal.time_skew_s.min() < 0)          # the skew's latency: one sample for delays down to -0.6
    temp_q = np.floor(temp * 2 ** TEMP_FRAC + 0.5).astype(int)
    pad_raw = np.concatenate([raw, np.repeat(raw[-1:], m, axis=0)])
    pad_t = np.concatenate([temp_q, np.repeat(temp_q[-1:], m)])
    stdin = "\n".join(" ".join(map(str, list(r) + [t])) for r, t in zip(pad_raw, pad_t)) + "\n"
    res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True)
    assert res.returncode == 0, res.returncode
    rows = np.array([list(map(int, line.split())) for line in res.stdout.splitlines()])[m:]
    assert rows.shape[0] == raw.shape[0]
    assert np.array_equal(rows[:, 1:4], np.round(f * 2 ** FORMATS.out_frac).astype(int))
    assert np.mean(rows[:, 0] & 1) < 0.01          # clipping is rare on these readings


@pytest.mark.parametrize("target", ["h8", "avr"])
def test_header_with_terms_cross_compiles(built, target):
    *_, tmp = built
    src = tmp / f"unit_{target}.c"
    src.write_text('#define AC_CAL_IMPLEMENTATION\n#include "cal.h"\n'
                   "int run(int16_t *x, int16_t t) {\n"
                   "    return (int)ac_temp_correct(&AC_CAL_TEMP, t, t, x, x) | (int)ac_nonlin_invert(&AC_CAL_NONLIN, x, x)\n"
                   "        | (int)AC_CAL_SKEW.len;\n}\n")
    cross_compile(target, src)


# ---------------------------------------------------------------- the independent generator


def indep_terms(ds) -> dict:
    """The calibration fields of the independent generator's effect (its own parameterisation:
    nonlinearity k2 u^2 + k3 u^3 in counts of the input u, temperature_offset beta counts per
    degC of the lagged sensor temperature, time_skew tau per channel plus an uncorrectable
    per-sample jitter)."""
    eff = ds["effects"]
    s = np.linalg.norm(ds["params"]["S"], axis=1)
    if "nonlinearity" in eff:
        return dict(nonlin_k2=eff["nonlinearity"]["k2"] * s ** 2, nonlin_k3=eff["nonlinearity"]["k3"] * s ** 3)
    if "temperature_offset" in eff:
        te = eff["temperature_offset"]
        return dict(offset_tc=te["beta"], temp_ref_c=te["t_ref_c"], temp_offset_tau_s=te["tau_s"])
    return dict(time_skew_s=eff["time_skew"]["tau"])


def f_error(dev, cal, rec, truth, engine, rows):
    f, _, _ = resolve_recording(dev, cal, rec, engine, omega_source="none")
    return float(np.sqrt(np.mean((f[rows] - truth[rows]) ** 2)))


@pytest.mark.parametrize("effect,shape,ratio", [("nonlinearity", "cubic+quadratic", 20.0),
                                                ("temperature_offset", None, 40.0), ("time_skew", None, 20.0)])
@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_terms_take_the_independent_effect_out(effect, shape, ratio, engine):
    """On the independent generator's seed array (its truth calibration): the f error with the
    effect and the term in the calibration is within 1.25x that of the same scene without the
    effect (+ 2 mm/s^2 for the skew's jitter and the fixed engine's extra roundings), while
    without the term it is over twice that (the effect's size, ``ratio`` times the noise floor in
    counts, is chosen for that; the temperature's shows less in f at the same ratio)."""
    import indep_model as im
    ds = im.make_jig([effect], seed=3, device="seed6", ratio={effect: ratio}, shapes={effect: shape} if shape else None,
                     motion=True)
    dev, cal, sc, rec = ds["device"], ds["cal"], ds["scene"], ds["recording"]
    truth, _, _ = sc.traj.evaluate(sc.t)
    clean = recording_from_arrays(rec.t, im.adc(sc, im.analog(sc, {}), {}), temp_c=rec.temp_c)
    rows = slice(5, -5)                       # the skew's padded end and the filters' start
    floor = f_error(dev, cal, clean, truth, engine, rows)
    before = f_error(dev, cal, rec, truth, engine, rows)
    after = f_error(dev, dataclasses.replace(cal, **indep_terms(ds)), rec, truth, engine, rows)
    assert before > 2.0 * floor
    assert after <= 1.25 * floor + 0.002


def test_terms_json_round_trip_and_bad_input(tmp_path):
    """The terms' fields survive save and load; a negative lag is refused naming its key; a
    calibration with tempcos needs temp_c on every sample to resolve (one line naming it)."""
    from accelcal.errors import InputError
    from accelcal.io.calibration import load_calibration, save_calibration
    dev = default_device()
    cal = with_terms(dev, np.random.default_rng(2))
    path = tmp_path / "cal.json"
    save_calibration(cal, path)
    back = load_calibration(path, dev)
    assert back == cal
    for attr in ("nonlin_k2", "nonlin_k3", "time_skew_s"):
        assert np.array_equal(getattr(back, attr), getattr(cal, attr))
    assert (back.temp_offset_tau_s, back.temp_gain_tau_s) == (20.0, 5.0)
    text = path.read_text().replace('"temperature_gain_tau_s": 5.0', '"temperature_gain_tau_s": -5.0')
    path.write_text(text)
    with pytest.raises(InputError, match="temperature_gain_tau_s"):
        load_calibration(path, dev)
    raw, _ = readings(dev, cal, np.random.default_rng(1), n=50)
    rec = recording_from_arrays(np.arange(50) / dev.sample_rate_hz, raw)
    for engine in ("float", "fixed"):
        with pytest.raises(InputError, match="temp_c"):
            resolve_recording(dev, cal, rec, engine, omega_source="none")
