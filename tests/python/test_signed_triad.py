"""Signed readings and 3-axis sensors through the firmware path (issue 14): the signed
pre-trim, the triad table against the float reference, the triad and signed headers
compiled with the C core on every compiler, and the command line from calibration to
header and fixed-point resolve."""
import json
import subprocess

import numpy as np
import pytest
from hypothesis import example, given, strategies as st

from accelcal import estimators as E
from accelcal.io.calibration import Calibration, load_calibration
from accelcal.readings.clipping import at_rails
from accelcal.cli.main import main
from accelcal.io.device import Device
from accelcal.firmware.header import calibration_header
from accelcal.firmware.native import cptr, ffi, lib, offset_binary
from accelcal.io.recording import recording_from_arrays, write_recording
from accelcal.resolve import resolve_recording
from accelcal.firmware.triad import build_triad_on_device, triad_rounding_bound
from core_settings import estimator
from toolchains import build_host, cross_compile

G = 9.80665
I16 = st.integers(-32768, 32767)


# ---------------------------------------------------------------- the signed pre-trim

def trim_s16(raw, trim):
    raw = np.ascontiguousarray(raw, np.int16)
    trim = np.ascontiguousarray(trim, np.int16)
    x = np.zeros(len(raw), np.int16)
    st_ = lib.ac_trim_s16(cptr("int16_t *", raw), cptr("int16_t *", trim), len(raw), cptr("int16_t *", x))
    return x, st_


@given(st.lists(st.tuples(I16, I16), min_size=1, max_size=12))
@example([(-32768, 32767), (32767, -32768), (0, 0), (-1, 0), (0, -1), (-32768, 0), (32767, 0)])
@example([(-32768, -32768), (32767, 32767)])
def test_trim_s16_is_the_clipped_difference(pairs):
    raw = np.array([p[0] for p in pairs])
    trim = np.array([p[1] for p in pairs])
    x, status = trim_s16(raw, trim)
    d = raw.astype(np.int64) - trim
    assert np.array_equal(x, np.clip(d, -32768, 32767))
    assert status == (lib.AC_SATURATED if np.any((d < -32768) | (d > 32767)) else lib.AC_OK)
    # bit for bit ac_trim on the offset-binary codes (what the batch path and ac_triad_apply use)
    xu = np.zeros(len(raw), np.int16)
    ru, tu = offset_binary(raw), offset_binary(trim)
    assert lib.ac_trim(cptr("uint16_t *", ru), cptr("uint16_t *", tu), len(raw), cptr("int16_t *", xu)) == status
    assert np.array_equal(x, xu)


def test_trim_s16_bad_arguments():
    x = ffi.new("int16_t[3]")
    r = ffi.new("int16_t[3]")
    assert lib.ac_trim_s16(ffi.NULL, r, 3, x) == lib.AC_ERR_NULL
    assert lib.ac_trim_s16(r, r, 0, x) == lib.AC_ERR_SIZE


# ---------------------------------------------------------------- a signed triad's table

@st.composite
def signed_triads(draw):
    k = draw(st.floats(200.0, 4000.0))          # counts per m/s^2: +-16 g ... +-2 g at 16 bits
    gain = np.array(draw(st.lists(st.floats(-0.05, 0.05), min_size=3, max_size=3)))
    mis = np.array(draw(st.lists(st.floats(-0.03, 0.03), min_size=9, max_size=9))).reshape(3, 3)
    S = k * (np.diag(1.0 + gain) + mis - np.diag(np.diag(mis)))
    b = np.array(draw(st.lists(st.floats(-3000.0, 3000.0), min_size=3, max_size=3)))
    return b, S


def check_triad_table(tab, b, S, raw):
    """The core's triad result against its exact semantics (0.5 LSB) and the float reference
    (the table's rounding bound), unless it saturated."""
    f_q, sat = E.triad_apply_fixed(tab, raw)
    exact = E.triad_exact(tab, raw)
    x = raw - tab.trim.astype(np.int64)
    clipped = np.any((x < -32768) | (x > 32767))
    if not sat[0]:
        assert np.all(np.abs(f_q - exact) <= 0.5)
    else:
        assert clipped or np.any(np.abs(exact) > 2**31 - 1)
    if not clipped and not sat[0]:
        ref = E.triad_apply_float(b, S, raw) * 1024.0
        half = 0.5 * 2.0 ** (-tab.shift.astype(float))
        # the entries' rounding, the final rounding, the residual offset in Q.8 (half an LSB of
        # 2^-8 counts through M), and s in Q.16 (relative, far below 1e-6)
        o_err = (np.abs(tab.m).astype(float) * 2.0 ** (-tab.shift.astype(float))[:, None]).sum(axis=1) * 2.0 ** -9
        assert np.all(np.abs(f_q - ref) <= (np.abs(x).sum() + 1.0) * half + 0.5 + o_err + 1e-6 * np.abs(ref))
    return f_q, sat


@estimator
@given(signed_triads(), st.lists(I16, min_size=3, max_size=3))
@example((np.zeros(3), np.eye(3) * 16384 / G), [-32768, 32767, 0])
def test_signed_triad_against_the_float_reference(tri, raw):
    b, S = tri
    tab = E.quantize_triad(b, S, signed=True)
    assert tab.trim.dtype == np.int16
    raw = np.array([raw])
    f_q, sat = check_triad_table(tab, b, S, raw)
    # the unsigned path on offset-binary codes is the same table and the same numbers
    tab_u = E.TriadTable(trim=tab.trim_code(), m=tab.m, shift=tab.shift, k=tab.k, sens_q=tab.sens_q,
                         offset_q=tab.offset_q)
    f_u, sat_u = E.triad_apply_fixed(tab_u, offset_binary(raw))
    assert np.array_equal(f_u, f_q) and np.array_equal(sat_u, sat)


@st.composite
def unsigned_triads(draw):
    b, S = draw(signed_triads())
    return b + draw(st.floats(4000.0, 61000.0)), S


@estimator
@given(unsigned_triads(), st.lists(st.integers(0, 65535), min_size=3, max_size=3))
def test_triad_against_the_float_reference(tri, raw):
    b, S = tri
    check_triad_table(E.quantize_triad(b, S), b, S, np.array([raw]))


@estimator
@given(st.one_of(signed_triads().map(lambda t: (t, True)), unsigned_triads().map(lambda t: (t, False))),
       st.booleans())
@example(((np.array([32767.0, 32767.0, 32767.5]), np.eye(3) * 200.0), False), False)
def test_triad_device_build_matches_host_quantizer(drawn, signed):
    """ac_triad_build from the header's channel entries gives the host's table: the same
    shifts, and m and k within one mantissa LSB (30-bit soft-float against float64).  The
    offsets move by 32768 between the signed and the offset-binary form as asked (an
    unsigned triad whose offsets all sit below 32768 stays unsigned: it had been taken for a
    signed one and moved out of range)."""
    (b, S), drawn_signed = drawn
    if signed != drawn_signed:
        b = b - 32768 if signed else b + 32768
    tab = E.quantize_triad(b, S, signed)
    dev = build_triad_on_device(tab)
    assert np.array_equal(dev.shift, tab.shift)
    assert np.all(np.abs(dev.m.astype(int) - tab.m) <= 1) and np.all(np.abs(dev.k.astype(np.int64) - tab.k) <= 1)


# ---------------------------------------------------------------- headers with the C core

def mpu_triad(signed=True):
    if signed:
        return Device(name="mpu6050", sample_rate_hz=100.0, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                      positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 16384 / G),
                      zero_counts=np.zeros(3))
    return Device(name="adxl", sample_rate_hz=100.0, gravity_mps2=G, raw_min=0, raw_max=4095,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 256 / G),
                  zero_counts=np.full(3, 2048.0))


def a_calibration(d, seed=5):
    rng = np.random.default_rng(seed)
    S = np.diag(d.counts_per_mps2) @ (np.eye(3) + rng.normal(0, 0.01, (3, 3)))
    b = d.zero_counts + rng.normal(0, 0.02 * G, 3) * d.counts_per_mps2
    return Calibration(device=d.name, method="full", offsets=b, sensitivity=S)


TRIAD_DRIVER = r"""
#define AC_CAL_IMPLEMENTATION
#include "cal.h"
#include <stdio.h>
int main(void) {
    int v[3], i;
    int32_t f[3];
    ac_status s;
    ac_triad built;
    ac_build_work work;
    if (ac_triad_check(&AC_CAL_TRIAD) != AC_OK) return 10;
    /* the on-device build from the header's channel entries must equal the table */
    if (ac_triad_build(AC_CAL_CHANNELS, AC_CAL_TRIAD.trim, &work, &built) != AC_OK) return 11;
    for (i = 0; i < 3; i++) {
        int q;
        if (built.shift[i] != AC_CAL_TRIAD.shift[i] || built.k[i] != AC_CAL_TRIAD.k[i]) return 12;
        for (q = 0; q < 3; q++) if (built.m[i][q] != AC_CAL_TRIAD.m[i][q] || built.trim[q] != AC_CAL_TRIAD.trim[q]) return 13;
    }
    while (scanf("%d %d %d", &v[0], &v[1], &v[2]) == 3) {
#ifdef SIGNED
        int16_t raw[3], x[3];
        ac_status s2;
        for (i = 0; i < 3; i++) raw[i] = (int16_t)v[i];
        /* the header's recipe for a signed chip */
        s = ac_trim_rails_s16(raw, AC_CAL_TRIM, 3u, AC_CAL_RAW_MIN, AC_CAL_RAW_MAX, x);
        s2 = ac_triad_resolve(&AC_CAL_TRIAD, x, f);
        s = s2 < 0 ? s2 : (ac_status)(s | s2);
#else
        uint16_t raw[3];
        for (i = 0; i < 3; i++) raw[i] = (uint16_t)v[i];
        s = ac_triad_apply(&AC_CAL_TRIAD, raw, f);
#endif
        printf("%d %ld %ld %ld\n", (int)s, (long)f[0], (long)f[1], (long)f[2]);
    }
    return 0;
}
"""


@pytest.mark.parametrize("signed", [True, False])
def test_triad_header_on_the_host_equals_resolve_fixed(tmp_path, signed):
    d = mpu_triad(signed)
    cal = a_calibration(d)
    (tmp_path / "cal.h").write_text(calibration_header(d, cal))
    (tmp_path / "main.c").write_text(TRIAD_DRIVER)
    exe = tmp_path / "drv"
    build_host(tmp_path / "main.c", exe, *(["-DSIGNED"] if signed else []))
    rng = np.random.default_rng(1)
    lo, hi = d.raw_min, d.raw_max
    raw = np.vstack([rng.integers(lo, hi + 1, (300, 3)), [[lo, lo, lo], [hi, hi, hi], [lo, hi, 0]]])
    res = subprocess.run([str(exe)], input="\n".join(" ".join(map(str, r)) for r in raw) + "\n",
                         capture_output=True, text=True)
    assert res.returncode == 0
    rows = np.array([list(map(int, ln.split())) for ln in res.stdout.splitlines()])
    rec = recording_from_arrays(np.arange(len(raw)) / 100.0, raw)
    f, a, flags = resolve_recording(d, cal, rec, "fixed")
    assert np.array_equal(rows[:, 1:], np.round(f * 1024).astype(np.int64))
    assert np.array_equal((rows[:, 0] & 1) != 0, flags.astype(bool))     # AC_SATURATED
    # AC_AT_RAIL: ac_triad_apply, or for a signed chip ac_trim_rails_s16, flags the host's at_rails samples
    assert np.array_equal((rows[:, 0] & 2) != 0, at_rails(rec, d)) and at_rails(rec, d).sum() >= 3
    assert np.all(np.isnan(a))
    ff, _, _ = resolve_recording(d, cal, rec, "float")
    ok = flags == 0
    tab = E.quantize_triad(cal.offsets, cal.sensitivity, signed)
    x = np.abs(raw - tab.trim.astype(np.int64)).sum(axis=1, keepdims=True)
    bound = ((x + 1.0) * 0.5 * 2.0 ** (-tab.shift.astype(float)) + 0.5) / 1024.0      # m/s^2
    assert ok.mean() > 0.9 and np.all(np.abs(f - ff)[ok] <= bound[ok] + 1e-9)


@pytest.mark.parametrize("target", ["h8", "avr"])
@pytest.mark.parametrize("kind", ["signed_triad", "triad", "signed_array"])
def test_triad_and_signed_headers_cross_compile(tmp_path, target, kind):
    if kind == "signed_array":
        from accelcal.io.device import default_device
        d0 = default_device()
        d = Device(name="signed-array", sample_rate_hz=60.0, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                   positions=d0.positions, axes=d0.axes, counts_per_mps2=d0.counts_per_mps2,
                   zero_counts=d0.zero_counts - 32768)
        cal = Calibration.nominal(d)
        call = ("int16_t x[6];\n    ac_status s = ac_trim_rails_s16(raw, AC_CAL_TRIM, 6u, AC_CAL_RAW_MIN, "
                "AC_CAL_RAW_MAX, x);\n    return (int)s | (int)ac_resolve(&AC_CAL_RESOLVER, x, 0, out);")
        rt = "int16_t"
    else:
        d = mpu_triad(kind == "signed_triad")
        cal = a_calibration(d)
        if kind == "signed_triad":
            call = ("int16_t x[3];\n    ac_status s = ac_trim_rails_s16(raw, AC_CAL_TRIM, 3u, AC_CAL_RAW_MIN, "
                    "AC_CAL_RAW_MAX, x);\n    return (int)s | (int)ac_triad_resolve(&AC_CAL_TRIAD, x, out);")
            rt = "int16_t"
        else:
            call = "return (int)ac_triad_apply(&AC_CAL_TRIAD, raw, out);"
            rt = "uint16_t"
    text = calibration_header(d, cal)
    assert (f"const {rt} AC_CAL_TRIM" in text)
    (tmp_path / "cal.h").write_text(text)
    src = tmp_path / "unit.c"
    src.write_text('#define AC_CAL_IMPLEMENTATION\n#include "cal.h"\n'
                   f"int32_t out[6];\nint run(const {rt} *raw) {{\n    {call}\n}}\n")
    cross_compile(target, src)


# ---------------------------------------------------------------- the command line

def test_mpu6050_signed_triad_from_calibration_to_header_and_fixed_resolve(tmp_path):
    """A signed triad: calibrate (known poses), header, resolve --engine fixed: no +32768 by hand."""
    d = mpu_triad(True)
    dev = {"name": d.name, "sample_rate_hz": 100.0, "gravity_mps2": G, "raw_min": -32768, "raw_max": 32767,
           "channels": [{"position_m": [0, 0, 0], "axis": list(np.eye(3)[i]), "counts_per_mps2": 16384 / G,
                         "zero_counts": 0} for i in range(3)]}
    (tmp_path / "dev.json").write_text(json.dumps(dev))
    truth = a_calibration(d)
    rng = np.random.default_rng(3)
    dirs = [np.eye(3)[i] * s for i in range(3) for s in (1, -1)]
    dirs += [v / np.linalg.norm(v) for v in rng.normal(size=(6, 3))]
    t, raw, f, pose = [], [], [], []
    for p, u in enumerate(dirs):
        fi = np.tile(G * u, (200, 1))
        raw.append(np.round(truth.offsets + fi @ truth.sensitivity.T + rng.normal(0, 8, (200, 3))).astype(int))
        f.append(fi)
        t.append(p * 3.0 + np.arange(200) / 100.0)
        pose.append(np.full(200, p))
    rec = recording_from_arrays(np.concatenate(t), np.vstack(raw), f=np.vstack(f), pose=np.concatenate(pose))
    write_recording(tmp_path / "rec.csv", rec)
    assert main(["calibrate", "--device", str(tmp_path / "dev.json"), str(tmp_path / "rec.csv"),
                 "-o", str(tmp_path / "cal.json")]) == 0
    cal = load_calibration(tmp_path / "cal.json")
    assert np.max(np.abs(cal.offsets - truth.offsets)) < 5.0
    assert main(["header", "--device", str(tmp_path / "dev.json"), "--calibration", str(tmp_path / "cal.json"),
                 "-o", str(tmp_path / "cal.h")]) == 0
    assert "const int16_t AC_CAL_TRIM[3]" in (tmp_path / "cal.h").read_text()
    assert main(["resolve", "--device", str(tmp_path / "dev.json"), "--calibration", str(tmp_path / "cal.json"),
                 "--engine", "fixed", str(tmp_path / "rec.csv"), "-o", str(tmp_path / "out.csv")]) == 0
    lines = [ln for ln in (tmp_path / "out.csv").read_text().splitlines() if not ln.startswith("#")]
    hdr = lines[0].split(",")
    vals = np.array([[float(v) if v else np.nan for v in ln.split(",")] for ln in lines[1:]])
    fr = vals[:, hdr.index("f_x"):hdr.index("f_x") + 3]
    assert np.sqrt(np.mean((np.linalg.norm(fr, axis=1) - G) ** 2)) < 0.01


@estimator
@given(st.one_of(signed_triads().map(lambda t: (t, True)), unsigned_triads().map(lambda t: (t, False))),
       st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3))
@example(((np.zeros(3), np.eye(3) * 16384 / G), True), [0.0, 1.0, 0.5])
def test_the_headers_rounding_figure_bounds_every_reading(drawn, u):
    """The triad header states the table's rounding as a figure (a tester had to measure it:
    0.894 LSB for an MPU-6050's calibration, nowhere in the header): the largest |exact - float|
    over the readings the trim does not clip, at a corner of that box (both sides affine).  The
    core's output stays within 0.5 LSB of it for any reading in the box, and the header says it."""
    (b, S), signed = drawn
    lo_r, hi_r = (-32768, 32767) if signed else (0, 65535)
    tab = E.quantize_triad(b, S, signed=signed)
    bound = triad_rounding_bound(tab, b, S, lo_r, hi_r)
    trim = tab.trim.astype(np.int64)
    lo, hi = np.maximum(lo_r, trim - 32768), np.minimum(hi_r, trim + 32767)
    raw = np.rint(lo + np.asarray(u) * (hi - lo)).astype(np.int64)[None, :]
    f_q, sat = E.triad_apply_fixed(tab, raw)
    if not sat[0]:
        ref = E.triad_apply_float(b, S, raw) * 1024.0
        assert np.all(np.abs(f_q - ref) <= 0.5 + bound + 1e-6 * (1.0 + np.abs(ref))), (f_q - ref, bound)
    dev = Device(name="t", sample_rate_hz=100.0, gravity_mps2=G, raw_min=lo_r, raw_max=hi_r,
                 positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1000.0),
                 zero_counts=np.zeros(3))
    text = calibration_header(dev, Calibration(device="t", method="full", offsets=b, sensitivity=S))
    assert "the table's rounding, which is at most " + ", ".join(f"{v:.3g}" for v in bound) + " LSB" in text


def recipe_lines(text):
    """The C statements of a header's per-sample recipe ("then per sample:" up to its first
    line of prose), as written in its comment."""
    lines = text.splitlines()
    start = next(i for i, ln in enumerate(lines) if "then per sample" in ln) + 1
    code = []
    for ln in lines[start:]:
        if not ln.startswith(" *     "):
            break
        code.append(ln[len(" *     "):].split("   (")[0])
    return code


RECIPE_DRIVER = r"""
#define AC_CAL_IMPLEMENTATION
#include "cal.h"
#include <stdio.h>
int main(void) {
    int v, i;
    int16_t raw[NCH];
    int32_t OUTDECL;
    const int16_t *omega_or_NULL = 0;
    for (;;) {
        for (i = 0; i < NCH; i++) { if (scanf("%d", &v) != 1) return 0; raw[i] = (int16_t)v; }
        {
            RECIPE
            printf("%d %d\n", (int)s, (int)r);
        }
    }
}
"""


@pytest.mark.parametrize("kind", ["triad", "array"])
def test_the_signed_headers_recipe_as_written_flags_the_rails(tmp_path, kind):
    """F6: the header's recipe for a signed chip (then ac_trim_s16 + ac_triad_resolve / ac_resolve,
    which never look at the rails: -2048 on a 12-bit chip came out as a plain f) compiled as the
    comment writes it: its pre-trim's status has AC_AT_RAIL exactly on the samples the host's
    at_rails names, over the whole 12-bit range, its rails and the codes next to them included."""
    from accelcal.io.device import default_device
    if kind == "triad":
        d = Device(name="lis3dh-12bit", sample_rate_hz=100.0, gravity_mps2=G, raw_min=-2048, raw_max=2047,
                   positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1024 / G),
                   zero_counts=np.zeros(3))
        cal, n, out = a_calibration(d), 3, "f[3]"
    else:
        d0 = default_device()
        d = Device(name="signed-array-12bit", sample_rate_hz=60.0, gravity_mps2=G, raw_min=-2048, raw_max=2047,
                   positions=d0.positions, axes=d0.axes, counts_per_mps2=np.full(6, 100.0),
                   zero_counts=np.zeros(6))
        cal, n, out = Calibration.nominal(d), 6, "out[6]"
    text = calibration_header(d, cal)
    code = recipe_lines(text)
    assert any("ac_trim_rails_s16" in c for c in code) and not any("ac_trim_s16(" in c for c in code)
    (tmp_path / "cal.h").write_text(text)
    (tmp_path / "main.c").write_text(RECIPE_DRIVER.replace("RECIPE", "\n            ".join(code))
                                     .replace("OUTDECL", out).replace("NCH", str(n)))
    exe = tmp_path / "drv"
    build_host(tmp_path / "main.c", exe, "-Wno-unused-variable")
    rng = np.random.default_rng(2)
    lo, hi = d.raw_min, d.raw_max
    edge = np.array([lo, lo + 1, hi - 1, hi])
    raw = np.where(rng.random((600, n)) < 0.1, rng.choice(edge, (600, n)), rng.integers(lo, hi + 1, (600, n)))
    raw = np.vstack([raw, np.full(n, lo), np.full(n, hi), np.full(n, lo + 1), np.full(n, hi - 1)])
    res = subprocess.run([str(exe)], input="\n".join(" ".join(map(str, r)) for r in raw) + "\n",
                         capture_output=True, text=True)
    assert res.returncode == 0
    st_ = np.array([list(map(int, ln.split())) for ln in res.stdout.splitlines()])
    assert st_.shape == (len(raw), 2) and np.all(st_ >= 0)
    rails = at_rails(recording_from_arrays(np.arange(len(raw)) / 100.0, raw), d)
    assert 0 < rails.sum() < len(raw)
    assert np.array_equal((st_[:, 0] & lib.AC_AT_RAIL) != 0, rails)
