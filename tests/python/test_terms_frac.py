"""The terms' hand-off to the resolver in 2^-k counts (firmware.terms_fixed.terms_frac,
ac_temp.h's frac): the choice of k, ac_temp_correct's Q.k output against the float reference
(hypothesis), and the fixed engine's per-pose bias on static poses of a 12-bit chip, which
whole counts make a constant fraction of a count per pose (docs/firmware-terms.md)."""
import dataclasses

import numpy as np
from core_batch import floats, generator, ints, rows_hold, seeds, stack
from core_settings import batched
from hypothesis import given, strategies as st

from accelcal.firmware import native, terms
from accelcal.firmware.triad import quantize_triad, triad_rounding_bound
from accelcal.firmware.terms_fixed import GC_FRAC, OC_FRAC, TEMP_FRAC, temp_bound, terms_frac, terms_tables
from accelcal.io.calibration import Calibration
from accelcal.io.device import Device
from accelcal.io.recording import recording_from_arrays
from accelcal.resolve import resolve_recording

O_LSB = 2.0 ** -native.FORMATS.offset_frac
G0 = 9.80665


def adxl12() -> Device:
    """A 12-bit 3-axis chip about mid-scale (0..4095, 41.8 counts per m/s^2), 50 Hz."""
    return Device(name="adxl12", sample_rate_hz=50.0, gravity_mps2=G0, raw_min=0, raw_max=4095,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 41.8),
                  zero_counts=np.full(3, 2048.0))


def test_terms_frac_from_the_span():
    """k: the most bits (<= 4) that keep span 2^k within 24576: 3 for a 12-bit converter about
    mid-scale, 2 for the seed's 0..10000, 0 for a 16-bit one or unknown rails."""
    assert terms_frac((0, 4095), [2048, 2050, 2047]) == 3
    assert terms_frac((0, 10000), [5000] * 6) == 2
    assert terms_frac((0, 1023), [512] * 3) == 4
    assert terms_frac((-32768, 32767), [0, 0, 0]) == 0
    assert terms_frac(None, [0]) == 0


def q_k_rows(rng, n, count):
    """``count`` rows (k (B,), oc, gc, o, u (B, N), dto, dtg (B,)) of n channels as the strategies
    below draw them."""
    return (ints(rng, 1, 8, count), ints(rng, -600, 600, (count, n)), ints(rng, -8000, 8000, (count, n)),
            ints(rng, -128, 128, (count, n)), floats(rng, -1.0, 1.0, (count, n)),
            ints(rng, -10 * 256, 10 * 256, count), ints(rng, -10 * 256, 10 * 256, count))


@batched("frac")
@given(st.integers(1, 8), st.lists(st.tuples(st.integers(-600, 600), st.integers(-8000, 8000),
                                             st.integers(-128, 128), st.floats(-1.0, 1.0)), min_size=1, max_size=12),
       st.integers(-10 * 256, 10 * 256), st.integers(-10 * 256, 10 * 256), seeds)
def test_temp_correct_q_k_within_bound(k, chans, dto, dtg, seed):
    """ac_temp_correct with frac k: y 2^-k within temp_bound(x, e, k) (the final rounding 2^-(k+1)
    counts instead of 1/2) of the float reference, on readings that fit Q.k (|x| < 0.7 2^(15-k)),
    and no clip there.  A batch per example (core_batch.py): the first row drawn by hypothesis."""
    oc, gc, o, u = (list(v) for v in zip(*chans))
    rows = q_k_rows(generator(seed), len(chans), batched.size("frac") - 1)
    k, oc, gc, o, u, dto, dtg = (stack(a, r) for a, r in zip((k, oc, gc, o, u, dto, dtg), rows))
    x = np.round(u * 0.7 * 2.0 ** (15 - k[:, None])).astype(np.int64)
    y, sat = np.zeros(x.shape, np.int16), np.zeros(len(x), bool)
    for i in range(len(x)):
        y[i], sat[i] = native.temp_correct(native.new_temp_table(0, oc[i], gc[i], o[i], k[i]), dto[i], dtg[i], x[i])
    occ, gcc = oc * 2.0 ** -OC_FRAC, gc * 2.0 ** -GC_FRAC
    e = gcc * dtg[:, None] * 2.0 ** -TEMP_FRAC
    ref = terms.temperature_correct(x.astype(float), o * O_LSB, 0.0, occ, gcc, dto * 2.0 ** -TEMP_FRAC,
                                    dtg * 2.0 ** -TEMP_FRAC)
    err = np.abs(y * 2.0 ** -k[:, None] - ref)
    within = np.all(err <= temp_bound(np.maximum(np.abs(x), np.abs(ref)), e, k[:, None]), axis=1)
    rows_hold(~sat & within, k=k, oc=oc, gc=gc, o=o, x=x, dto=dto, dtg=dtg, y=y, sat=sat)


def static_poses(dev, cal, rng, n_poses=16, per_pose=300, noise=0.15):
    """Static poses (random directions of 1 g) each at its own constant temperature, readings with
    ``noise`` counts of white noise, rounded to whole counts: the recording and its pose labels."""
    d = rng.normal(size=(n_poses, 3))
    f = G0 * d / np.linalg.norm(d, axis=1, keepdims=True)
    temps = rng.uniform(5.0, 45.0, n_poses)
    dt = temps - cal.temp_ref_c
    raw, temp, pose = [], [], []
    for p in range(n_poses):
        lin = cal.sensitivity @ f[p] * (1.0 + cal.gain_tc * dt[p]) + cal.offsets + cal.offset_tc * dt[p]
        raw.append(np.rint(lin + rng.normal(0, noise, (per_pose, 3))))
        temp.append(np.full(per_pose, temps[p]))
        pose.append(np.full(per_pose, p))
    raw = np.clip(np.concatenate(raw), dev.raw_min, dev.raw_max).astype(np.int64)
    t = np.arange(raw.shape[0]) / dev.sample_rate_hz
    return recording_from_arrays(t, raw, temp_c=np.concatenate(temp)), np.concatenate(pose)


def test_fixed_engine_pose_means_unbiased():
    """A 12-bit chip with offset and gain tempcos (no lag) on 16 static poses at 16 temperatures,
    noise 0.15 counts: the fixed engine's f, averaged over each pose, within 2^-(k+1) counts (the
    hand-off's rounding, k = 3) + the resolver's half output LSB + 2^-8 of the float engine's.  With
    whole counts the per-pose difference is the rounding of raw + c(T), the same fraction on every
    sample of a pose (up to half a count)."""
    dev = adxl12()
    rng = np.random.default_rng(7)
    cal = Calibration.nominal(dev)
    cal = dataclasses.replace(cal, offsets=cal.offsets + rng.uniform(-20, 20, 3),
                              offset_tc=rng.uniform(-0.9, 0.9, 3), gain_tc=rng.uniform(-4e-4, 4e-4, 3),
                              temp_ref_c=25.0)
    t, tt = terms_tables(dev, cal)
    assert tt.frac == 3
    rec, pose = static_poses(dev, cal, rng)
    f_fix = resolve_recording(dev, cal, rec, "fixed", omega_source="none")[0]
    f_flt = resolve_recording(dev, cal, rec, "float", omega_source="none")[0]
    s = np.linalg.norm(cal.sensitivity, axis=1)          # counts per m/s^2 along each axis
    bias = np.array([(f_fix[pose == p] - f_flt[pose == p]).mean(axis=0) for p in np.unique(pose)]) * s
    # the per-sample bound: the hand-off's rounding and ac_temp_correct's own (temp_bound at e = 0 and
    # the gain terms' 2^-18 per count), the resolver's final half LSB and its table's rounding (the
    # whole-count table's: the same m, a coarser k)
    lsb = 2.0 ** -native.FORMATS.out_frac
    table = triad_rounding_bound(quantize_triad(cal.offsets, cal.sensitivity, False, (0, 4095)), cal.offsets,
                                 cal.sensitivity, 0, 4095)
    e = np.abs(cal.gain_tc).max() * 20.0
    bound = float(temp_bound(2048.0, e, tt.frac)) + (0.5 + table.max()) * lsb * s.max()
    assert np.max(np.abs(bias)) <= bound, (np.abs(bias).max(), bound)
