"""The omega table in the calibration header (issue 36): `accelcal header` writes it for a layout
that fixes all six rate products; it compiles for the host, the H8/300H and the AVR; linked
with the core on the host it gives, bit for bit, what ``resolve --engine fixed --omega array``
gives (the fixed engine is the header's arithmetic)."""
from __future__ import annotations

import subprocess

import numpy as np
import pytest

import indep_model as im
from accelcal.cli.main import main
from accelcal.estimators.omega_fixed import omega_fixed_from_recording, pretrim, table_for_recording
from accelcal.firmware.header import calibration_header
from accelcal.firmware.native import FORMATS
from accelcal.firmware.omega_table import omega_run
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.io.device import default_device, save_device, tetrahedron_device
from accelcal.io.recording import write_recording
from accelcal.resolve import resolve_recording
from toolchains import build_host, cross_compile

DRIVER = r"""
#define AC_CAL_IMPLEMENTATION
#include "cal.h"
#include <stdio.h>
int main(void) {
    ac_omega_state st;
    int16_t x[AC_CAL_N_CHANNELS], w10[3];
    int32_t w[3];
    uint8_t fl;
    int i, v;
    if (ac_omega_init(&st, &AC_CAL_OMEGA) != AC_OK) return 10;
    for (;;) {
        for (i = 0; i < AC_CAL_N_CHANNELS; i++) { if (scanf("%d", &v) != 1) return 0; x[i] = (int16_t)v; }
        printf("%d", (int)ac_omega_step(&st, &AC_CAL_OMEGA, x, w, w10, &fl));
        for (i = 0; i < 3; i++) printf(" %ld %d", (long)w[i], (int)w10[i]);
        printf(" %u\n", (unsigned)fl);
    }
}
"""


@pytest.fixture(scope="module")
def spin(tmp_path_factory):
    d = im.make_spin_array(tetrahedron_device(), 11, n_turns=2)
    tmp = tmp_path_factory.mktemp("omega_hdr")
    (tmp / "cal.h").write_text(calibration_header(d["device"], d["cal"]))
    (tmp / "main.c").write_text(DRIVER)
    return d, tmp


def test_header_has_the_table_and_compiles_for_the_targets(spin):
    d, tmp = spin
    text = (tmp / "cal.h").read_text()
    assert "const ac_omega_table AC_CAL_OMEGA = {" in text and "extern const ac_omega_table AC_CAL_OMEGA;" in text
    # the driver uses stdio; the header alone for the targets
    (tmp / "only.c").write_text('#define AC_CAL_IMPLEMENTATION\n#include "cal.h"\n'
                                "int omega_ok(void) { return ac_omega_check(&AC_CAL_OMEGA); }\n")
    cross_compile("h8", tmp / "only.c")
    cross_compile("avr", tmp / "only.c")


def test_header_is_the_fixed_engine_bit_for_bit(spin):
    d, tmp = spin
    exe = tmp / "drv"
    build_host(tmp / "main.c", exe)
    tables, table = table_for_recording(d["device"], d["cal"], d["recording"])
    x, _ = pretrim(tables, d["recording"].raw)
    stdin = "\n".join(" ".join(map(str, row)) for row in x.tolist()) + "\n"
    res = subprocess.run([str(exe)], input=stdin, capture_output=True, text=True)
    assert res.returncode == 0, res.returncode
    rows = np.array([list(map(int, line.split())) for line in res.stdout.splitlines()])
    assert rows.shape == (len(x), 8)
    w16, w10, _, flags, _ = omega_run(table, x)
    assert np.array_equal(rows[:, [1, 3, 5]], w16) and np.array_equal(rows[:, [2, 4, 6]], w10)
    assert np.array_equal(rows[:, 7], flags)
    est = omega_fixed_from_recording(d["device"], d["cal"], d["recording"])
    assert np.array_equal(est.w * 2 ** 16, rows[:, [1, 3, 5]])


def test_no_table_for_six_channels():
    d = default_device()
    cal = Calibration(device=d.name, method="nominal", offsets=d.nominal_offsets(), sensitivity=d.nominal_sensitivity())
    assert "ac_omega_table" not in calibration_header(d, cal)


def test_cli_resolve_fixed_array(spin, tmp_path):
    """``resolve --engine fixed --omega array``: w columns the core's, f and alpha resolved by the
    core with the core's Q5.10 rate (the header's recipe)."""
    d, _ = spin
    save_device(d["device"], tmp_path / "dev.json")
    save_calibration(d["cal"], tmp_path / "cal.json")
    write_recording(tmp_path / "rec.csv", d["recording"])
    out = tmp_path / "out.csv"
    assert main(["resolve", "--device", str(tmp_path / "dev.json"), "--calibration", str(tmp_path / "cal.json"),
                 str(tmp_path / "rec.csv"), "--omega", "array", "--engine", "fixed", "-o", str(out)]) == 0
    got = np.genfromtxt([ln for ln in open(out, encoding="utf-8") if not ln.startswith("#")], delimiter=",",
                        names=True)
    est = omega_fixed_from_recording(d["device"], d["cal"], d["recording"])
    w = np.column_stack([got["w_x"], got["w_y"], got["w_z"]])
    assert np.allclose(w, est.w, rtol=1e-8, atol=1e-12)  # the CSV's %.9g
    assert np.max(np.abs(est.w_core - np.round(est.w * 2 ** FORMATS.omega_frac) / 2 ** FORMATS.omega_frac)) <= 2 ** -10
    f, a, _ = resolve_recording(d["device"], d["cal"], d["recording"], "fixed", "array", est.w_core)
    assert np.allclose(np.column_stack([got["f_x"], got["f_y"], got["f_z"]]), f, rtol=1e-8, atol=1e-12)  # the CSV's %.9g
    assert np.allclose(np.column_stack([got["dw_x"], got["dw_y"], got["dw_z"]]), a, rtol=1e-8, atol=1e-12)  # the CSV's %.9g
    rms = np.sqrt(np.mean((w - d["w"]) ** 2))
    assert rms < 0.02
