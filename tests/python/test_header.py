"""The emitted calibration header compiles warning-free for every target and,
linked with the C core, reproduces the quantizer's tables and the float
reference within the core's bound."""
import subprocess
from types import SimpleNamespace

import numpy as np
import pytest

from accelcal import model
from accelcal.clipping import at_rails
from accelcal.device import default_device
from accelcal.header import render_header
from accelcal.quantize import FORMATS, exact_fixed_semantics, quantize
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
