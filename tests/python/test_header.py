"""The emitted calibration header compiles warning-free for every target and,
linked with the C core, reproduces the quantizer's tables and the float
reference within the core's bound."""
import subprocess
from types import SimpleNamespace

import numpy as np
import pytest

from accelcal import model
from accelcal.readings.clipping import at_rails
from accelcal.io.device import default_device
from accelcal.firmware.header import render_header
from accelcal.firmware.quantize import FORMATS, exact_fixed_semantics, quantize
from toolchains import build_host, cross_compile


DRIVER = r"""
#define AC_CAL_IMPLEMENTATION
#include "cal.h"
#include <stdio.h>
int main(void) {
    uint16_t raw[AC_CAL_N_CHANNELS];
    int16_t w[3];
    int32_t out[6];
    ac_resolver built;
    ac_build_work work;
    int i, j;
    unsigned v;
    int wv[3];
    /* the on-device build from the header's raw parameters must equal the table */
    if (ac_resolver_build(AC_CAL_CHANNELS, AC_CAL_N_CHANNELS, &work, &built, 0) != AC_OK) return 10;
    for (j = 0; j < 6; j++) {
        if (built.m_shift[j] != AC_CAL_RESOLVER.m_shift[j] || built.k[j] != AC_CAL_RESOLVER.k[j]) return 11;
        for (i = 0; i < AC_CAL_N_CHANNELS; i++) if (built.m[j][i] != AC_CAL_RESOLVER.m[j][i]) return 12;
    }
    for (;;) {
        for (i = 0; i < AC_CAL_N_CHANNELS; i++) { if (scanf("%u", &v) != 1) return 0; raw[i] = (uint16_t)v; }
        if (scanf("%d %d %d", &wv[0], &wv[1], &wv[2]) != 3) return 13;
        for (i = 0; i < 3; i++) w[i] = (int16_t)wv[i];
        printf("%d", (int)ac_process(&AC_CAL_RESOLVER, AC_CAL_TRIM, raw, w, out));
        for (j = 0; j < 6; j++) printf(" %ld", (long)out[j]);
        printf("\n");
    }
}
"""


def drawn_calibration(d, rng):
    """Offsets (counts) and sensitivities (counts per m/s^2) of the default array as tools/bench_core.py
    draws them: gains -0.7..+3.6 % off nominal, cross-axis terms of 1.75 % rms, offsets within 0.28 g."""
    s = d.nominal_sensitivity() * (1 + rng.uniform(-0.007, 0.036, (6, 1))) + \
        d.counts_per_mps2[:, None] * rng.normal(0, 0.0175, (6, 3))
    b = d.zero_counts + rng.uniform(-0.28, 0.28, 6) * 9.80665 * d.counts_per_mps2
    return b, s


@pytest.fixture(scope="module")
def case(tmp_path_factory):
    d = default_device()
    rng = np.random.default_rng(7)
    b, s = drawn_calibration(d, rng)
    t = quantize(b, s, d.positions, d.name, rails=(d.raw_min, d.raw_max))
    tmp = tmp_path_factory.mktemp("hdr")
    (tmp / "cal.h").write_text(render_header(t, offset_tc=rng.normal(0, 0.5, 6),
                                             gain_tc=rng.normal(0, 1e-4, 6), temp_ref_c=25.0))
    (tmp / "main.c").write_text(DRIVER)
    return d, t, b, s, tmp


def test_host_build_reproduces_reference(case):
    d, t, b, s, tmp = case
    exe = tmp / "drv"
    build_host(tmp / "main.c", exe)
    rng = np.random.default_rng(3)
    n = 2000
    f = rng.normal(0, 9.8, (n, 3))
    al = rng.normal(0, 50, (n, 3))
    w = rng.normal(0, 3, (n, 3))
    raw = np.clip(np.round(model.predict_counts(b, s, d.positions, f, al, w)), 0, 10000).astype(int)
    w_q = np.round(w * 2**FORMATS.omega_frac).astype(int)
    stdin = "\n".join(" ".join(map(str, list(raw[i]) + list(w_q[i]))) for i in range(n)) + "\n"
    res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True)
    assert res.returncode == 0, res.returncode
    rows = np.array([list(map(int, line.split())) for line in res.stdout.splitlines()])
    assert rows.shape == (n, 7)
    status, out = rows[:, 0], rows[:, 1:]
    exact, bound, _ = exact_fixed_semantics(t, raw, w_q)
    # the header's rails are the device's: AC_AT_RAIL on the samples the host's at_rails names
    assert np.array_equal(status & 2 != 0, at_rails(SimpleNamespace(raw=raw), d))
    ok = status & 1 == 0
    assert ok.mean() > 0.99
    assert np.all(np.abs(out[ok] - exact[ok]) <= 0.5 + bound[ok] + 1e-9)
    # and the float reference with the unquantised calibration, in physical units
    fr, ar = model.resolve(b, s, d.positions, raw, w_q / 2**FORMATS.omega_frac)
    lsb = 2.0**-FORMATS.out_frac
    assert np.abs(out[ok, :3] * lsb - fr[ok]).max() < 0.01          # m/s^2 (noise: 0.02)
    assert np.abs(out[ok, 3:] * lsb - ar[ok]).max() < 0.01 / 0.06 * 2  # rad/s^2


@pytest.mark.parametrize("target", ["h8", "avr"])
def test_cross_compiles_warning_free(case, target):
    *_, tmp = case
    src = tmp / "unit.c"
    src.write_text('#define AC_CAL_IMPLEMENTATION\n#include "cal.h"\n'
                   "int32_t out[6];\nint run(const uint16_t *raw) {\n"
                   "    return (int)ac_process(&AC_CAL_RESOLVER, AC_CAL_TRIM, raw, 0, out);\n}\n")
    cross_compile(target, src)


def stated_counts(text):
    """The header's statement of its input: (raw_min, raw_max), {channel: (counts per m/s^2,
    m/s^2 per count, mg per count)}, the right shift a left-justified register needs or None,
    and the mg divisor."""
    import re
    rng = re.search(r"\* Input: raw\[i\] in the device file's counts, (-?\d+)\.\.(-?\d+) \(raw_min\.\.raw_max\)", text)
    per = {}
    for m in re.finditer(r"\*     raw\[(\d+)(?:\.\.(\d+))?\]: ([0-9.e+-]+) counts per m/s\^2: one count = "
                         r"([0-9.e+-]+) m/s\^2 = ([0-9.e+-]+) mg", text):
        for i in range(int(m.group(1)), int(m.group(2) or m.group(1)) + 1):
            per[i] = tuple(float(m.group(k)) for k in (3, 4, 5))
    shift = re.search(r"needs its value \((?:u?int16_t)\) >> (\d+) first", text)
    mg = re.search(r"a reading a driver gives in mg is divided by ([0-9.e+-]+) mg first", text)
    return ((int(rng.group(1)), int(rng.group(2))) if rng else None, per, int(shift.group(1)) if shift else None,
            float(mg.group(1)) if mg else None)


@pytest.mark.parametrize("chip", ["microbit", "lis3dh", "array", "mixed"])
def test_the_header_states_the_size_of_one_count(chip):
    """F8: the header never said what one count is (4 mg for a micro:bit, 1/1024 g for a LIS3DH's
    12 bits), nor that a left-justified register must be shifted: a firmware author passed mg or
    the register.  It states the input range raw_min..raw_max, one count per channel in m/s^2 and
    mg from the device's counts_per_mps2, the divisor of a reading in mg, and the shift of a
    left-justified 12-bit register."""
    from accelcal.io.calibration import Calibration
    from accelcal.io.device import Device
    from accelcal.firmware.header import calibration_header
    g = 9.80665
    d0 = default_device()
    if chip == "microbit":      # accelcal convert --units mg --lsb 4: one count = 4 mg, the default 16-bit rails
        d = Device(name="mb", sample_rate_hz=44.0, gravity_mps2=g, raw_min=-32768, raw_max=32767,
                   positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1 / (4e-3 * g)),
                   zero_counts=np.zeros(3))
        want = (-32768, 32767), None, 4.0
    elif chip == "lis3dh":      # 12 bits, +-2 g: 1024 counts per g
        d = Device(name="lis", sample_rate_hz=100.0, gravity_mps2=g, raw_min=-2048, raw_max=2047,
                   positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 1024 / g),
                   zero_counts=np.zeros(3))
        want = (-2048, 2047), 4, 1000 / 1024
    elif chip == "array":
        d = d0
        want = (0, 10000), None, 1000 / (d0.counts_per_mps2[0] * g)
    else:                       # channels of two scales, an unsigned 12-bit converter
        k = np.array([100.0, 100.0, 100.0, 200.0, 200.0, 100.0])
        d = Device(name="mixed", sample_rate_hz=60.0, gravity_mps2=g, raw_min=0, raw_max=4095,
                   positions=d0.positions, axes=d0.axes, counts_per_mps2=k, zero_counts=np.full(6, 2048.0))
        want = (0, 4095), 4, None
    text = calibration_header(d, Calibration.nominal(d))
    rails, per, shift, mg = stated_counts(text)
    assert rails == want[0] and shift == want[1]
    assert sorted(per) == list(range(d.n_channels))
    for i, (k_i, mps2, mg_i) in per.items():
        assert k_i == pytest.approx(d.counts_per_mps2[i], rel=1e-5)
        assert mps2 == pytest.approx(1 / d.counts_per_mps2[i], rel=1e-5)
        assert mg_i == pytest.approx(1000 / (d.counts_per_mps2[i] * g), rel=1e-5)
    if want[2] is None:
        assert mg is None and "its channel's mg per count" in text
    else:
        assert mg == pytest.approx(want[2], rel=1e-5)
    # the rails are also macros in the chip's counts (what ac_trim_rails_s16 takes for a signed chip)
    macro = {ln.split()[1]: eval(ln.split(None, 2)[2].rstrip("u")) for ln in text.splitlines()
             if ln.startswith("#define AC_CAL_RAW_")}
    assert (macro["AC_CAL_RAW_MIN"], macro["AC_CAL_RAW_MAX"]) == (d.raw_min, d.raw_max)
