#!/usr/bin/env python3
"""Accuracy and firmware cost of the motion estimators (the README's figures).

Accuracy (simulated with accelcal.simulate, several seeds each):
* pendulum +-40 deg at 0.5 Hz, two ADXL202E-like triads (1250 counts/g, 60 Hz,
  0.02 m/s^2 rms noise) at r1 = 0.1 m, r2 = 0.3 m: attitude, rate and alpha RMS error;
* stop-to-stop 1-D travel of 0.5 m in 2 s with a 0.05 m/s^2 zero-point error:
  final displacement error with and without the correction;
* the same on a rail tilted by 20 deg (3-axis, gravity removed);
* lane change (the seed's 6-channel array): yaw rate from alpha, reset on rest;
* fixed point against the float twins (bounds of the headers) and the float reference.
Firmware cost: AVR cycles per sample under simavr (tools/bench/bench_estimators.c,
Timer1), H8/300H text of each module and of a minimal firmware per estimator
(linked with -nostdlib, so only what it needs), and the libgcc check.
Writes build/bench_estimators.md and prints it.
"""
from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BUILD = ROOT / "build" / "bench_est"
INC = ROOT / "include"
SEEDS = range(1, 11)


sys.path[:0] = [str(Path(__file__).resolve().parent), str(ROOT / "python"), str(ROOT / "tests" / "python")]
# the shared bench helpers, the package, and the devices of the estimators' tests
from accelcal import estimators as E, model  # noqa: E402
from accelcal.io.calibration import Calibration  # noqa: E402
from accelcal.io.device import default_device, default_triad  # noqa: E402
from accelcal.estimators.attitude import LEAK_FRAC  # noqa: E402
from accelcal.firmware.native import FORMATS  # noqa: E402
from accelcal.firmware.quantize import round_half_up  # noqa: E402
from accelcal.simulate import run_simulation  # noqa: E402
from bench_core import avr_stack_ram, parse_bench, run  # noqa: E402
from estimator_devices import adxl_pendulum_device as adxl_triads, adxl_triad  # noqa: E402

# the estimators' per-sample routines, for the worst-case stack
PER_SAMPLE = ("ac_triad_apply", "ac_att_step", "ac_disp_step", "ac_rest_step", "ac_rest_rate_step")


def rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


# ------------------------------------------------------------------------------------
# accuracy
# ------------------------------------------------------------------------------------

def pendulum_accuracy():
    d = adxl_triads()
    cal = Calibration.nominal(d)
    res = {k: [] for k in ("th_f", "th_x", "w_f", "w_x", "dw_f", "sqrt", "th_max", "dth_ref_lsb", "dw_ref",
                           "th_twin", "w_twin_ratio", "w_twin_lsb", "dw_twin", "gated")}
    for seed in SEEDS:
        rec = run_simulation(d, "pendulum", seed=seed, duration_s=20.0, amplitude_deg=40.0, freq_hz=0.5).recording
        th_ref = np.arctan2(-rec.f[:, 0], rec.f[:, 2])
        a = E.attitude_from_recording(d, cal, rec, "float")
        b = E.attitude_from_recording(d, cal, rec, "fixed")
        ea = np.degrees(np.angle(np.exp(1j * (a["theta_rad"] - th_ref))))
        eb = np.degrees(np.angle(np.exp(1j * (b["theta_rad"] - th_ref))))
        res["th_f"].append(rms(ea))
        res["th_x"].append(rms(eb))
        res["th_max"].append(float(np.max(np.abs(eb))))
        res["w_f"].append(rms(a["w_y"] - rec.w[:, 1]))
        res["w_x"].append(rms(b["w_y"] - rec.w[:, 1]))
        res["dw_f"].append(rms(a["dw_y"] - rec.dw[:, 1]))
        res["gated"].append(float(np.mean(a["gated"])))
        # the bare square root (seed eq. 2), magnitude only
        f1 = E.triad_apply_float(cal.offsets[:3], cal.sensitivity[:3], rec.raw[:, :3])
        f2 = E.triad_apply_float(cal.offsets[3:], cal.sensitivity[3:], rec.raw[:, 3:])
        w2 = (f2[:, 0] - f1[:, 0]) / (0.1 - 0.3)
        res["sqrt"].append(rms(np.sqrt(np.maximum(w2, 0)) - np.abs(rec.w[:, 1])))
        res["dth_ref_lsb"].append(float(np.max(np.abs(a["theta_rad"] - b["theta_rad"]))) * 2**E.ANGLE_FRAC)
        res["dw_ref"].append(float(np.max(np.abs(a["w_y"] - b["w_y"]))))
        # against the twin (same quantised triad outputs)
        tab1 = E.quantize_triad(cal.offsets[:3], cal.sensitivity[:3])
        tab2 = E.quantize_triad(cal.offsets[3:], cal.sensitivity[3:])
        q1, _ = E.triad_apply_fixed(tab1, rec.raw[:, :3])
        q2, _ = E.triad_apply_fixed(tab2, rec.raw[:, 3:])
        p = E.AttitudeParams(r1=0.1, r2=0.3, dt=1 / 60, noise_mps2=0.02)
        fx = E.attitude_fixed(q1, q2, p)
        tw = E.attitude_twin(q1, q2, fx)
        res["th_twin"].append(float(np.max(np.abs(fx["theta"] - tw["theta"] * 2**E.ANGLE_FRAC))))
        bound = E.attitude_rate_bound(fx, tw)
        dw_ = np.abs(fx["w"] / 2**E.OMEGA_FRAC - tw["w"])
        res["w_twin_ratio"].append(float(np.max(dw_ / bound)))
        res["w_twin_lsb"].append(float(np.max(dw_)) * 2**E.OMEGA_FRAC)
        res["dw_twin"].append(float(np.max(np.abs(fx["dw"] - tw["dw"] * 2**E.OUT_FRAC))))
    return {k: (float(np.mean(v)), float(np.max(v))) for k, v in res.items()}


def displacement_accuracy(device, axis, tilt_deg=0.0, offset=0.05, strokes=1, seeds=SEEDS):
    cal = Calibration.nominal(device)
    k = float(device.counts_per_mps2[0])
    eff = [f"offset:db={offset * k},channel=0"] if offset else []
    out = {}
    for engine, form in (("float", "offline"), ("float", "stream"), ("fixed", "stream")):
        ec, eu = [], []
        for seed in seeds:
            sim = run_simulation(device, "linear_actuator", seed=seed, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                                 tilt_deg=tilt_deg, strokes=strokes, effects=eff)
            c = E.displacement_from_recording(device, cal, sim.recording, engine, form=form, axis=axis)
            tr = sim.trajectory.position
            if axis is None:
                R = E.tilt_frame(sim.trajectory.f[0])
                tr = (tr @ sim.trajectory.attitude[0]) @ R.T
                p = np.column_stack([c["p_x"], c["p_y"], c["p_z"]])[-1]
                pr = np.column_stack([c["p_raw_x"], c["p_raw_y"], c["p_raw_z"]])[-1]
                ec.append(np.linalg.norm(p - tr[-1]) / 0.5)
                eu.append(np.linalg.norm(pr - tr[-1]) / 0.5)
            else:
                ec.append(abs(c["p_x"][-1] - tr[-1, 0]) / 0.5)
                eu.append(abs(c["p_raw_x"][-1] - tr[-1, 0]) / 0.5)
        out[(engine, form)] = (100 * float(np.mean(ec)), 100 * float(np.max(ec)), 100 * float(np.mean(eu)))
    return out


def displacement_fixed_vs_float():
    d = default_triad()
    cal = Calibration.nominal(d)
    worst_ratio, worst_p, worst_ref = 0.0, 0.0, 0.0
    for seed in SEEDS:
        sim = run_simulation(d, "linear_actuator", seed=seed, distance_m=0.5, travel_s=2.0, rest_s=2.0,
                             tilt_deg=20.0, strokes=2)
        tab = E.quantize_triad(cal.offsets, cal.sensitivity)
        fq, _ = E.triad_apply_fixed(tab, sim.recording.raw)
        p = E.DisplaceParams(dt=0.01, rest=E.default_rest_params(d))
        fx = E.displace_fixed(fq, p)
        tw = E.displace_twin(fq, fx, p)
        bv, bp = E.displace_error_bound(fx, tw, True)
        dp = np.abs(fx["p"] / 2**E.P_FRAC - tw["p"]).max(axis=1)
        worst_ratio = max(worst_ratio, float(np.max(dp / np.maximum(bp, 1e-30))))
        worst_p = max(worst_p, float(np.max(dp)))
        a = E.displacement_from_recording(d, cal, sim.recording, "float", form="stream")
        b = E.displacement_from_recording(d, cal, sim.recording, "fixed")
        worst_ref = max(worst_ref, max(float(np.max(np.abs(a[f"p_{c}"] - b[f"p_{c}"]))) for c in "xyz"))
    return worst_ratio, worst_p, worst_ref


def lane_change_rate():
    d = default_device()
    cal = Calibration.nominal(d)
    e_reset, e_plain, e_fixed = [], [], []
    for seed in range(1, 6):
        rec = run_simulation(d, "lane_change", seed=seed).recording
        c = E.rate_from_recording(d, cal, rec, "float", leak_tau_s=5.0)
        cx = E.rate_from_recording(d, cal, rec, "fixed", leak_tau_s=5.0)
        _, a = model.resolve(cal.offsets, cal.sensitivity, d.positions, rec.raw, None)
        plain = model.rate_integrate(a, 1 / 60)[:, 2]
        e_reset.append(rms(c["w_z"] - rec.w[:, 2]))
        e_fixed.append(rms(cx["w_z"] - rec.w[:, 2]))
        e_plain.append(rms(plain - rec.w[:, 2]))
    return float(np.mean(e_reset)), float(np.mean(e_fixed)), float(np.mean(e_plain)), \
        float(np.max(np.abs(rec.w[:, 2])))


# ------------------------------------------------------------------------------------
# firmware cost
# ------------------------------------------------------------------------------------

def c_array(vals):
    return "{" + ", ".join(str(int(v)) for v in vals) + "}"


def make_data(n=16):
    d = adxl_triads()
    cal = Calibration.nominal(d)
    rec = run_simulation(d, "pendulum", seed=1, duration_s=3.0).recording
    raw = rec.raw[100:100 + n]       # mid-swing
    t1 = E.quantize_triad(cal.offsets[:3], cal.sensitivity[:3])
    t2 = E.quantize_triad(cal.offsets[3:], cal.sensitivity[3:])
    p = E.AttitudeParams(r1=0.1, r2=0.3, dt=1 / 60, noise_mps2=0.02)
    dm, dsh = E.dt_fixed(p.dt)

    def triad(name, t):
        return (f"static const ac_triad {name} = {{{c_array(t.trim)}, {c_array(t.shift)}, {c_array(t.k)}, "
                f"{{{', '.join(c_array(r) for r in t.m)}}}}};")
    lines = ["/* generated by tools/bench_estimators.py */", f"#define BENCH_N {n}",
             f"#define BENCH_R1 {round(0.1 * 2**FORMATS.pos_frac)}L",
             f"#define BENCH_R2 {round(0.3 * 2**FORMATS.pos_frac)}L",
             f"#define BENCH_DT_M {dm}u", f"#define BENCH_DT_SHIFT {dsh}u",
             f"#define BENCH_W2_GATE {int(round_half_up(p.gate() * 2**E.W2_FRAC))}L",
             f"#define BENCH_LEAK {int(round_half_up(p.leak() * 2**LEAK_FRAC))}u",
             triad("BENCH_TRIAD1", t1), triad("BENCH_TRIAD2", t2),
             f"static const uint16_t BENCH_RAW[{n}][6] = {{{', '.join(c_array(r) for r in raw)}}};"]
    BUILD.mkdir(parents=True, exist_ok=True)
    (BUILD / "est_data.h").write_text("\n".join(lines) + "\n")


def avr_cycles():
    """Cycles from the AVR bench and the worst-case stack of PER_SAMPLE in it."""
    elf = BUILD / "bench_est.elf"
    run(["avr-gcc", "-mmcu=atmega328p", "-Os", "-std=c99", "-Wall", "-Wextra", "-DF_CPU=16000000UL",
         "-ffunction-sections", "-fdata-sections", "-Wl,--gc-sections",
         f"-I{INC}", f"-I{ROOT / 'csrc'}", f"-I{BUILD}", str(ROOT / "tools/bench/bench_estimators.c"),
         *map(str, sorted((ROOT / "csrc").glob("*.c"))), "-o", str(elf)])
    res = subprocess.run(["simavr", "-m", "atmega328p", "-f", "16000000", str(elf)],
                         capture_output=True, text=True, timeout=300)
    _, stack = avr_stack_ram(elf, PER_SAMPLE)
    return parse_bench(res.stdout + res.stderr), stack


def host_smoke():
    exe = BUILD / "bench_est_host"
    run(["gcc", "-O2", "-std=c99", "-Wall", "-Wextra", f"-I{INC}", f"-I{ROOT / 'csrc'}", f"-I{BUILD}",
         str(ROOT / "tools/bench/bench_estimators.c"), *map(str, sorted((ROOT / "csrc").glob("*.c"))),
         "-o", str(exe)])
    return parse_bench(run([str(exe)]).stdout)


FW_MAINS = {
    "attitude (2 x triad apply + ac_att_step)": """
volatile uint16_t raw[6]; volatile int16_t th, w; static ac_att st; static const ac_triad t1, t2;
int main(void) { uint16_t r[6]; int32_t f1[3], f2[3]; ac_att_out o; uint8_t i;
  (void)ac_att_init(&st, 104858L, 314573L, 34953u, 21u, 512u, 100000L, 273u);
  for (;;) { for (i = 0; i < 6; i++) r[i] = raw[i];
    (void)ac_triad_apply(&t1, r, f1); (void)ac_triad_apply(&t2, r + 3, f2);
    (void)ac_att_step(&st, f1, f2, &o); th = o.theta; w = o.w; } }""",
    "displacement (ac_disp_step, 3-axis or 1-D)": """
volatile int32_t fin[3]; volatile int32_t pout; static ac_disp st;
int main(void) { ac_disp_cfg c; ac_disp_out o; int32_t f[3];
  c.rest.dev_max = 51; c.rest.g2_lo = 0; c.rest.g2_hi = 0xFFFFFFFFUL; c.rest.alpha_max = 0; c.rest.ref_max = 154; c.rest.hold = 25u;
  c.rest.ema_shift = 3u; c.dt_m = 34953u; c.dt_shift = 21u; c.axis = -1;
  (void)ac_disp_init(&st, &c);
  for (;;) { f[0] = fin[0]; f[1] = fin[1]; f[2] = fin[2]; (void)ac_disp_step(&st, f, &o); pout = o.p[0]; } }""",
    "rate with rest reset (ac_rest_rate_step)": """
volatile int32_t fin[3], ain[3]; volatile int16_t wout; static ac_rest rs; static ac_rate rt;
int main(void) { ac_rest_cfg c; int32_t f[3], a[3]; int16_t w[3]; uint8_t fl;
  c.dev_max = 51; c.g2_lo = 0; c.g2_hi = 0xFFFFFFFFUL; c.alpha_max = 500; c.ref_max = 0; c.hold = 25u; c.ema_shift = 3u;
  (void)ac_rest_init(&rs, &c); (void)ac_rate_init(&rt, 34953u, 21u, 218u);
  for (;;) { f[0] = fin[0]; f[1] = fin[1]; f[2] = fin[2]; a[0] = ain[0]; a[1] = ain[1]; a[2] = ain[2];
    (void)ac_rest_rate_step(&rs, &rt, f, a, w, &fl); wout = w[2]; } }""",
}


def h8_sizes():
    cc = ["h8300-hms-gcc", "-mh", "-mn", "-O2", "-fomit-frame-pointer", "-std=c99", "-Wall", "-Wextra", "-Werror", f"-I{INC}",
          f"-I{ROOT / 'csrc'}"]
    objdir = BUILD / "h8"
    objdir.mkdir(parents=True, exist_ok=True)
    objs, sizes = [], {}
    for c in sorted((ROOT / "csrc").glob("*.c")):
        o = objdir / f"{c.stem}.o"
        run(cc + ["-c", str(c), "-o", str(o)])
        objs.append(o)
        tx = run(["h8300-hms-size", str(o)]).stdout.splitlines()[1].split()
        sizes[c.stem] = tuple(int(v) for v in tx[:3])
    defined = set(re.findall(r"[TDB] (\S+)", run(["h8300-hms-nm", "-g", "--defined-only", *map(str, objs)]).stdout))
    mine = [objdir / f"{m}.o" for m in ("ac_trig", "ac_rest", "ac_attitude", "ac_displace")]
    undef = set(re.findall(r"U (\S+)", run(["h8300-hms-nm", "-u", *map(str, mine)]).stdout))
    external = sorted(u for u in undef if u not in defined)
    lib_ = objdir / "libaccelcal.a"
    if lib_.exists():
        lib_.unlink()
    run(["h8300-hms-ar", "rcs", str(lib_), *map(str, objs)])
    fw = {}
    for i, (name, src) in enumerate(FW_MAINS.items()):
        c = objdir / f"fw{i}.c"
        c.write_text("#include <accelcal/accelcal.h>\n" + src + "\n")
        o = objdir / f"fw{i}.o"
        run(cc + ["-c", str(c), "-o", str(o)])
        out = objdir / f"fw{i}.out"
        run(["h8300-hms-gcc", "-mh", "-mn", "-nostdlib", "-nostartfiles", "-Wl,-e,_main", "-o", str(out), str(o),
             str(lib_)])
        total = int(run(["h8300-hms-size", str(out)]).stdout.splitlines()[1].split()[0])
        own = int(run(["h8300-hms-size", str(o)]).stdout.splitlines()[1].split()[0])
        fw[name] = (total, total - own)
    return sizes, fw, external


# ------------------------------------------------------------------------------------

def main():
    rows = ["| measure | value | goal |", "| --- | --- | --- |"]
    pa = pendulum_accuracy()
    rows += [
        f"| pendulum +-40 deg 0.5 Hz, ADXL202E-like (0.02 m/s^2, 60 Hz), r1 = 0.1 m, r2 = 0.3 m, {len(SEEDS)} seeds x 20 s: "
        f"attitude RMS error, float / fixed | {pa['th_f'][0]:.3f} / {pa['th_x'][0]:.3f} deg (worst seed "
        f"{pa['th_x'][1]:.3f}; worst sample {pa['th_max'][1]:.2f} deg) | <= 0.3 deg |",
        f"| same: rate w_y RMS error (integrated alpha corrected by the square root), float / fixed | "
        f"{pa['w_f'][0]:.4f} / {pa['w_x'][0]:.4f} rad/s ({math.degrees(pa['w_x'][0]):.2f} deg/s; peak rate 2.19 rad/s) | stated |",
        f"| same: bare square root (seed eq. 2), error of \\|w\\| | {pa['sqrt'][0]:.4f} rad/s | |",
        f"| same: alpha dw_y RMS error (eq. 3) | {pa['dw_f'][0]:.3f} rad/s^2 | |",
        f"| same: fraction of samples gated (\\|w\\| not measurable, integrated) | {100 * pa['gated'][0]:.0f} % | |",
    ]
    for dev_name, dev in (("16-bit triad, 0.005 m/s^2, 100 Hz", None), ("ADXL202E-like, 0.02 m/s^2, 60 Hz", adxl_triad())):
        d = dev or default_triad()
        r = displacement_accuracy(d, "x")
        for (engine, form), (mean_c, max_c, mean_u) in r.items():
            rows.append(f"| stop-to-stop 1-D 0.5 m in 2 s, 0.05 m/s^2 zero-point error, {dev_name}, {engine} {form}: "
                        f"final error corrected (mean / worst of {len(SEEDS)}) vs uncorrected | {mean_c:.3f} % / "
                        f"{max_c:.3f} % vs {mean_u:.1f} % | <= 0.5 % |")
    r = displacement_accuracy(default_triad(), None, tilt_deg=20.0, offset=0.0, strokes=2)
    for (engine, form), (mean_c, max_c, mean_u) in r.items():
        rows.append(f"| tilted rail 20 deg, 3-axis (gravity removed in the first rest's frame), two strokes of 0.5 m, "
                    f"16-bit triad, {engine} {form}: final error corrected (mean / worst) vs uncorrected | "
                    f"{mean_c:.3f} % / {max_c:.3f} % vs {mean_u:.2f} % | |")
    e_reset, e_fixed, e_plain, wmax = lane_change_rate()
    rows.append(f"| lane change (seed 6-ch array, 60 Hz): yaw rate RMS error, leaky integration (tau 5 s) reset on "
                f"rest, float / fixed vs plain integration | {e_reset:.4f} / {e_fixed:.4f} vs {e_plain:.4f} rad/s "
                f"(peak {wmax:.2f} rad/s) | |")
    rows += [
        f"| fixed vs float twin: theta, max | {pa['th_twin'][1]:.2f} LSB (1 LSB = 0.0070 deg) | <= 1 LSB |",
        f"| fixed vs float twin: w_y, max (and as a fraction of the stated bound) | {pa['w_twin_lsb'][1]:.2f} LSB "
        f"({pa['w_twin_ratio'][1]:.2f} of the bound) | <= bound |",
        f"| fixed vs float twin: dw_y, max | {pa['dw_twin'][1]:.2f} LSB | <= 0.5 LSB |",
        f"| fixed vs float reference (exact geometry, float triads): theta / w_y, max | {pa['dth_ref_lsb'][1]:.1f} LSB / "
        f"{pa['dw_ref'][1]:.4f} rad/s | |",
    ]
    ratio, dp, dref = displacement_fixed_vs_float()
    rows += [f"| fixed vs float twin: displacement p, max over the tilted-rail runs (fraction of the stated bound) | "
             f"{dp * 1e6:.2f} um = {dp * 2**E.P_FRAC:.1f} LSB ({ratio:.2f} of the bound) | <= bound |",
             f"| fixed vs float reference (streaming, float triad): p, max | {dref * 1e6:.1f} um | |"]
    make_data()
    if shutil.which("simavr") and shutil.which("avr-gcc"):
        c, stack = avr_cycles()
        rows += [f"| AVR cycles per sample, attitude: 2 x `ac_triad_apply` + `ac_att_step` | "
                 f"{c['triad_apply_x2']} + {c['att_step']} = {c['triad_apply_x2'] + c['att_step']} | |",
                 f"| AVR cycles, `ac_atan2` / `ac_isqrt32` alone | {c['atan2']} / {c['isqrt32']} | |",
                 f"| AVR cycles per sample, displacement `ac_disp_step` in motion, 3-axis / 1-D | "
                 f"{c['disp_step_3axis']} / {c['disp_step_1d']} | |",
                 f"| AVR cycles, the step that ends a motion (correction) / `ac_tilt_frame` (once) | "
                 f"{c['disp_segment_end']} / {c['tilt_frame']} | |",
                 f"| AVR cycles per sample, `ac_rest_step` / rate with rest reset `ac_rest_rate_step` (3 axes) | "
                 f"{c['rest_step']} / {c['rest_rate_step']} | |"]
        for f in PER_SAMPLE:
            w, indirect = stack.get(f, (None, False))
            rows.append(f"| AVR worst-case stack (-Os), `{f}` (bytes, incl. its return address) | "
                        f"{'unbounded (recursion)' if w is None else w}{' (+ indirect calls)' if indirect else ''} | |")
    host_smoke()
    if shutil.which("h8300-hms-gcc"):
        sizes, fw, external = h8_sizes()
        for m in ("ac_trig", "ac_rest", "ac_attitude", "ac_displace"):
            tx, da, bs = sizes[m]
            rows.append(f"| H8/300H {m}.o text/data/bss (bytes) | {tx}/{da}/{bs} | |")
        for name, (total, lib_part) in fw.items():
            rows.append(f"| H8/300H text linked, {name} (core part) | {lib_part} | |")
        rows.append(f"| H8/300H libgcc / libc symbols needed by the estimators | {', '.join(external) or 'none'} | none |")
    table = "\n".join(rows)
    print(table)
    (ROOT / "build").mkdir(exist_ok=True)
    (ROOT / "build" / "bench_estimators.md").write_text(table + "\n")


if __name__ == "__main__":
    main()
