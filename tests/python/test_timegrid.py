"""The estimators' time grid (estimators.timegrid.on_uniform_grid) on the stamp patterns of real
logs, written here synthetically: runs of samples stamped late, a host clock that drifts against
the sensor's, a rate that changes part-way, a sample delivered twice."""
import numpy as np
import pytest

from accelcal import estimators as E
from accelcal.io.calibration import Calibration
from accelcal.io.device import default_triad
from accelcal.errors import InputError
from accelcal.estimators.timegrid import on_uniform_grid
from accelcal.io.recording import recording_from_arrays
from accelcal.io.recording_checks import chance_repeats, regular_step
from accelcal.simulate import run_simulation


def _walk(n, seed=0):
    """n samples of three channels that change from sample to sample (no two rows alike)."""
    rng = np.random.default_rng(seed)
    return np.cumsum(rng.integers(20, 200, (n, 3)), axis=0)


@pytest.mark.parametrize("engine", ["float", "fixed"])
def test_a_run_of_samples_stamped_late_keeps_its_places(engine):
    """Oxford-step-counter's Samsung S6 log has two samples in a row stamped 0.65 and 0.66 of a step
    late, the next on time: the grid took one late sample, not a run, and refused it.  Runs of two
    and three are taken at their places, with a note, and the path is the whole recording's."""
    d = default_triad()
    rec = run_simulation(d, "linear_actuator", seed=2).recording
    cal = Calibration.nominal(d)
    dt = float(np.median(np.diff(rec.t)))
    t = rec.t.copy()
    t[[60, 61, 200, 201, 202, 350, 351]] += np.array([0.65, 0.66, 0.6, 0.7, 0.62, 0.74, 0.55]) * dt
    whole = E.displacement_from_recording(d, cal, rec, engine)
    c = E.displacement_from_recording(d, cal, recording_from_arrays(t, rec.raw), engine)
    assert len(c["t"]) == rec.n_samples and "filled" not in c
    note = [w for w in c.warnings if "stamped late" in w]
    assert note and "7 sample(s) stamped late by up to 0.74" in note[0] and "the longest 3 in a row" in note[0]
    np.testing.assert_allclose(c["t"], whole["t"], rtol=0, atol=1e-9)
    for ax in ("p_x", "p_y", "p_z"):
        assert c[ax][-1] == pytest.approx(whole[ax][-1], abs=1e-9)


def test_stamps_that_drift_against_the_sensor_clock_are_put_on_one_grid():
    """A flight controller's log (PX4 sensor_combined) drifts -0.38..+0.2 of a step from any straight
    grid over 68 s, and a phone's (Sensor Logger, 100 Hz) -0.23..+0.22 over 300 s: the straight-line
    fit refused them at their first row (-0.39, -0.46 steps).  Stamps whose local mean drifts up to
    0.4 of a step, with jitter of 0.1 about it and a dropped sample now and then, are taken, with a
    note; a drift of a whole step (the rate itself changes) is still refused."""
    n, dt = 6000, 0.004
    places = np.delete(np.arange(n + 6), [700, 1900, 2500, 3300, 4800, 5500])
    rng = np.random.default_rng(5)
    drift = 0.4 * np.sin(2 * np.pi * places / 5000.0)
    t = 100.0 + dt * (places + drift + rng.uniform(-0.1, 0.1, n))
    raw = _walk(n)
    out, filled, note = on_uniform_grid(recording_from_arrays(t, raw))
    assert out.n_samples == n + 6 and int(filled.sum()) == 6
    np.testing.assert_array_equal(out.raw[~filled], raw)
    assert np.flatnonzero(filled).tolist() == [700, 1900, 2500, 3300, 4800, 5500]
    assert "drifts by up to 0.4" in note, note
    assert abs(float(np.median(np.diff(out.t))) - dt) < 1e-4 * dt
    t2 = 100.0 + dt * (places + 1.2 * np.sin(2 * np.pi * places / 5000.0))
    with pytest.raises(InputError, match="not uniform") as ei:
        on_uniform_grid(recording_from_arrays(t2, raw))
    assert "steps off the uniform grid of the rows before it" in str(ei.value)


def test_a_rate_that_changes_part_way_is_named_where_it_changes():
    """A phone's log refused at row 6 (-0.46 steps off the one straight line through the whole
    recording) for what happened later in the file: a rate that changes part-way is named where the
    stamps leave the grid of the rows before, not at the first row."""
    n, dt = 6000, 0.01
    i = np.arange(n)
    t = dt * (i + 0.002 * np.maximum(i - 4000, 0))       # 0.2 % slower from row 4001
    with pytest.raises(InputError, match="not uniform") as ei:
        on_uniform_grid(recording_from_arrays(t, _walk(n)))
    assert 4000 <= ei.value.row <= 4500, str(ei.value)       # where its drift passes the limit
    assert "steps off the uniform grid of the rows before it" in str(ei.value)


def test_a_sample_delivered_twice_with_no_place_of_its_own_is_named():
    """Oxford-step-counter's S6 log, rows 8678-8681: the same readings three times (on time, on time,
    0.68 of a step later), then a new sample 0.33 of a step later -- four samples for three places.
    The refusal names the copy's row and says it repeats the row before (the old one named the next
    row, 0.33 of a step after it, as if it were the odd one); the copy is not left out: the test
    above (a copy 0.3 of a step after its row) and the README keep a duplicated sample refused."""
    n, dt = 2000, 0.01
    raw = _walk(n)
    t = dt * np.arange(n)
    k = 1000
    raw[k] = raw[k - 1]                                    # on time, the readings of the row before
    t2 = np.insert(t, k + 1, t[k] + 0.68 * dt)             # the copy, 0.68 of a step after it
    raw2 = np.insert(raw, k + 1, raw[k], axis=0)
    t2[k + 2] = t2[k + 1] + 0.33 * dt
    with pytest.raises(InputError, match="delivered twice") as ei:
        on_uniform_grid(recording_from_arrays(t2, raw2))
    assert ei.value.row == k + 2                            # sample k + 1: the copy
    assert f"row {k + 2} repeats the readings of the row before exactly (rows {k}-{k + 2} alike)" in str(ei.value)
    # without the copy it is taken as it is
    out, filled, _ = on_uniform_grid(recording_from_arrays(np.delete(t2, k + 1), np.delete(raw2, k + 1, axis=0)))
    assert out.n_samples == n and not filled.any()


@pytest.mark.parametrize("seed", [2, 3])
def test_a_host_clock_that_catches_up_with_a_short_step_keeps_the_sensor_s_rate(seed):
    """A host that stamps a 100 Hz sensor 10.24 ms apart and catches up with a 5.2 ms step every
    ~20 samples (ChanghyeonKim93's tumble sessions): the median step is 2.4 % long, and a grid on
    it refused the recording at a row where two samples fell within half a step.  On the regular
    steps' period (10.00 ms) every stamp is within about 0.26 of a step of its place: taken whole,
    the grid at 100 Hz."""
    n = 4200
    rng = np.random.default_rng(seed)
    lag = np.empty(n)
    a = 0.0
    for k in range(n):                      # the host's lag (s): 0.24 +- 0.2 ms more a sample, 4.88 ms
        a += 0.00024 + rng.normal(0, 2e-4)  # less at a catch-up (every ~10-30 samples, as the real)
        if a > 0.0025:
            a -= 0.00488
        lag[k] = a
    t = 1.5e9 + 0.01 * np.arange(n) + lag
    raw = _walk(n)
    out, filled, note = on_uniform_grid(recording_from_arrays(t, raw))
    assert out.n_samples == n and not filled.any()
    np.testing.assert_array_equal(out.raw, raw)
    assert float(np.median(np.diff(out.t))) == pytest.approx(0.01, rel=1e-4)
EPOCH_S = 1620380000.0     # unix time of a real phone log's first stamp (2021-05-07)


def test_a_place_in_epoch_stamps_is_named_in_seconds_from_the_start_and_by_row(tmp_path):
    """A survey logger's stamps in unix time: 'the step to t = 1.62038e+09 s' named no place (6
    digits of 1.6e9 s are 1000 s).  Times are said from the first sample, to the ms: the sample
    0.3 of a step after sample 299 (t = 2.993 s at 100 Hz) is named at 2.993 s from the start,
    and its row.  The same in a dropped-sample note, and in the displacement's warnings."""
    d = default_triad()
    rec = run_simulation(d, "linear_actuator", seed=2).recording
    cal = Calibration.nominal(d)
    dt = float(np.median(np.diff(rec.t)))
    t2 = np.insert(rec.t, 300, rec.t[299] + 0.3 * dt) + EPOCH_S
    raw2 = np.insert(rec.raw, 300, rec.raw[299] + 1, axis=0)
    with pytest.raises(InputError) as ei:
        E.displacement_from_recording(d, cal, recording_from_arrays(t2, raw2))
    msg = str(ei.value)
    want = f"the step to t = {rec.t[299] + 0.3 * dt - rec.t[0]:.3f} s from the start is"
    assert want in msg and "e+09" not in msg and ei.value.row == 301, msg
    # a dropped sample: where, from the start
    keep = np.ones(rec.n_samples, bool)
    keep[400] = False
    _, filled, note = on_uniform_grid(recording_from_arrays(rec.t[keep] + EPOCH_S, rec.raw[keep]))
    assert filled.sum() == 1 and f"after t = {rec.t[399] - rec.t[0]:.3f} s from the start" in note, note
    # a recording cut in mid-motion (the actuator moves from 2.0 s): its first rest, from the start
    c = E.displacement_from_recording(d, cal, recording_from_arrays(rec.t[220:] + EPOCH_S, rec.raw[220:]))
    start = [w for w in c.warnings if "does not start at rest" in w]
    assert len(start) == 1 and "e+09" not in start[0], c.warnings
    first = float(start[0].split("from t = ")[1].split(" s from the start")[0])
    rest = c["rest"].astype(bool)
    assert first == pytest.approx(c["t"][np.argmax(rest)] - c["t"][0], abs=5e-4), start[0]


def test_a_refusal_of_stamps_off_the_grid_names_the_remedy():
    """A polled logger whose stamps wander by 41 steps was refused with "the integrators need a
    constant rate" and no word of what to do.  Stamps that wander (the wander test: a drift of 1.2
    steps; a host whose local mean leaves the grid by 41 steps over the log), that jitter by +-0.45
    of a step, that come from a loop whose period varies +-40 %, and whose rate changes part-way are
    each refused naming accelcal convert --rate HZ; samples missing beyond filling (no remedy of the
    stamps: the samples are gone) are not."""
    n, dt = 6000, 0.004
    i = np.arange(n)
    rng = np.random.default_rng(11)
    stamps = {
        "drift": dt * (i + 1.2 * np.sin(2 * np.pi * i / 5000.0)),
        "wander": dt * (i + 41.0 * np.sin(np.pi * i / n) ** 2),
        "jitter": dt * (i + rng.uniform(-0.45, 0.45, n)),
        "loop": dt * np.concatenate([[0.0], np.cumsum(rng.uniform(0.6, 1.4, n - 1))]),
        "rate change": dt * (i + 0.002 * np.maximum(i - 4000, 0)),
    }
    for what, t in stamps.items():
        with pytest.raises(InputError, match="not uniform") as ei:
            on_uniform_grid(recording_from_arrays(t, _walk(n)))
        assert str(ei.value).count("accelcal convert --rate HZ") == 1, (what, str(ei.value))
    with pytest.raises(InputError, match=r"sample\(s\) missing") as ei:
        on_uniform_grid(recording_from_arrays(dt * np.delete(i, np.arange(300, 320)), _walk(n - 20)))
    assert "--rate" not in str(ei.value)


def _uneven_stamps(rec, seed=7):
    """``rec``'s samples as a polling loop whose period varies +-30 % takes them: stamps 0.7-1.3
    steps apart over the same span, the counts interpolated at them (rounded)."""
    t0 = np.asarray(rec.t, float)
    rng = np.random.default_rng(seed)
    dt = float(np.median(np.diff(t0)))
    t = t0[0] + dt * np.concatenate([[0.0], np.cumsum(rng.uniform(0.7, 1.3, t0.size - 1))])
    t = t[t <= t0[-1]]
    raw = np.rint(np.column_stack([np.interp(t, t0, np.asarray(rec.raw, float)[:, j]) for j in range(3)]))
    return t, raw.astype(np.int64)


def test_samples_taken_at_uneven_stamps_are_resampled_on_request():
    """A buoy's logger (8.5 Hz, ms stamps, steps 0.96-1.18 of the mean) and PX4's sensor_combined
    (250 Hz) were refused by displacement with a remedy that did not work (convert --rate keeps stamps
    within 20 % of the rate).  Samples taken at their stamps by a loop whose period varies +-30 % are
    refused naming displacement --resample; with it they are interpolated onto a uniform grid of as
    many samples and the stroke comes out as from uniform samples.  A step of 3 samples lost is
    refused, naming its row: interpolation would bridge it."""
    d = default_triad()
    rec = run_simulation(d, "linear_actuator", seed=2).recording
    cal = Calibration.nominal(d)
    whole = E.displacement_from_recording(d, cal, rec)
    t, raw = _uneven_stamps(rec)
    uneven = recording_from_arrays(t, raw)
    with pytest.raises(InputError, match="not uniform") as ei:
        E.displacement_from_recording(d, cal, uneven)
    assert "accelcal displacement --resample" in str(ei.value) and "convert --rate" not in str(ei.value)
    c = E.displacement_from_recording(d, cal, uneven, resample=True)
    assert any("--resample: " in w and "interpolated" in w for w in c.warnings), c.warnings
    stroke = float(np.max(np.abs(whole["p_x"])))
    for ax in ("p_x", "p_y", "p_z"):
        assert c[ax][-1] == pytest.approx(whole[ax][-1], abs=0.01 * stroke), ax
    gap = recording_from_arrays(np.delete(t, [400, 401, 402]), np.delete(raw, [400, 401, 402], axis=0).astype(np.int64))
    with pytest.raises(InputError, match="about 3 sample[(]s[)] lost there") as ei:
        E.displacement_from_recording(d, cal, gap, resample=True)
    assert ei.value.row == 401, str(ei.value)


def _coarse(n, seed):
    """n rows of a LIS2DW at rest on a coarse grid (1.95 mg): 2.5 counts of noise, so that each
    channel repeats its reading on ~11 % of the rows and whole rows repeat by chance."""
    rng = np.random.default_rng(seed)
    return np.rint(np.array([89, 503, 11]) + rng.normal(0, 2.5, (n, 3))).astype(np.int64)


def test_a_chance_repeat_on_a_coarse_grid_is_not_called_a_sample_delivered_twice():
    """Klipper's LIS2DW captures (1.95 mg grid, 2.5 counts of noise): rows 858-892 are 35 samples
    within 33.68 steps (a batch 1.1 % fast), and row 890 repeating row 889 was named 'a sample delivered
    twice' -- 7 such rows in 3,971 where the channels' own repeat rates give 4.0 by chance.  A repeat
    is a copy only off the grid (within half a step of the row before) or where repeats are far
    beyond chance; here the refusal names the crowded rows and the late sample instead."""
    n, dt = 2000, 0.002541
    raw = _coarse(n, 3)
    steps = np.full(n - 1, dt)
    steps[1000:1034] = 0.96 * dt                  # a batch 4 % fast: one sample more than places
    t = 10.0 + np.concatenate([[0.0], np.cumsum(steps)])
    raw[1015] = raw[1014]                         # a chance repeat among the crowded rows
    count, expected, p = chance_repeats(raw)
    assert count >= 1 and p > 0.1, (count, expected, p)
    with pytest.raises(InputError, match="one more than the uniform grid has places for") as ei:
        on_uniform_grid(recording_from_arrays(t, raw))
    assert "delivered twice" not in str(ei.value) and "of a step late" in str(ei.value), str(ei.value)
    # a copy stamped within half a step of its row is still named, chance or not
    t2 = np.insert(t, 1500, t[1499] + 0.3 * dt)
    raw2 = np.insert(raw, 1500, raw[1499], axis=0)
    with pytest.raises(InputError, match="delivered twice") as ei:
        on_uniform_grid(recording_from_arrays(t2, raw2))
    assert ei.value.row == 1501, str(ei.value)


def test_captures_joined_by_long_gaps_are_refused_for_the_gaps_first():
    """Klipper's ACCELEROMETER_MEASURE file: 11 captures of 0.92 s (~365 samples, each batch on its
    own clock estimate, rates 1 % apart) joined by 10 gaps of ~1.6 s, 61 % of the span without samples.
    The first refusal had been a duplicate (above) or a rate change; the dominant defect, gaps no
    filling bridges, is now named first: at the row after the first gap, with their count, the
    longest and the share of the span they leave empty."""
    rng = np.random.default_rng(4)
    t, start = [], 100.0
    for k in range(11):
        step = 0.002541 * (1.0 + rng.uniform(-0.01, 0.01))
        t.append(start + step * np.arange(365) + rng.uniform(-0.1, 0.1, 365) * step)
        start = t[-1][-1] + 1.6 + rng.uniform(-0.03, 0.05)
    t = np.concatenate(t)
    with pytest.raises(InputError, match="not uniform") as ei:
        on_uniform_grid(recording_from_arrays(t, _coarse(t.size, 5)))
    msg = str(ei.value)
    d = np.diff(t)
    empty = 100 * float(np.sum(d[d > 1.0] - np.median(d))) / float(t[-1] - t[0])
    assert ei.value.row == 366 and "sample(s) missing in 10 gap(s), the longest" in msg and "beyond 1.8 x the median" in msg, msg
    assert f"({d.max():.6g} s against" in msg and f"{empty:.2g} % of the span" in msg, msg
    assert f"the first beyond filling is the step to t = {t[365] - t[0]:.3f} s" in msg and "cut the recording" in msg


def test_resample_bridges_one_lost_sample_and_names_longer_gaps_against_the_regular_step():
    """A 161 Hz hand-held capture with host stamps 3.5-12 ms (charge-imu-challenge) was refused by
    --resample for one step of 1.96 of the mean (beyond 1.5), where convert notes only steps beyond
    1.8 x the median: one rule now (recording_checks.GAP_STEPS), and a gap of one lost sample is
    bridged, with a note and column filled.  What a straight line across one lost sample costs, on a
    0.2 m stroke at 100 Hz with stamps 0.7-1.3 steps apart, at 71 places (every 5th where deleting a
    sample leaves a step of 1.85-2.4): median 3e-7 m (most at rest), at most 1.9e-4 m in the stroke's
    fastest part -- not tiny there: as much as the resampling itself errs (1.2e-4 m against uniform
    samples) and the noise's spread over 8 noise draws (1.5e-4 m), 0.1 % of the stroke; within the
    error bound the output states (1.12e-3 m), which is asserted.  Klipper's captures joined by gaps
    of 1.6 s were refused as '249 of the mean step' (a mean the gaps inflate): now against the
    regular step, 650."""
    d = default_triad()
    rec = run_simulation(d, "linear_actuator", seed=2).recording
    cal = Calibration.nominal(d)
    t, raw = _uneven_stamps(rec)
    dt = float(np.median(np.diff(rec.t)))
    full = E.displacement_from_recording(d, cal, recording_from_arrays(t, raw), resample=True)
    bound = float(full.meta["error_bound_m"])
    pair = t[2:] - t[:-2]
    places = (np.flatnonzero((pair > 1.85 * dt) & (pair < 2.4 * dt)) + 1)[::5]
    errs = []
    for k in places:
        c = E.displacement_from_recording(d, cal, recording_from_arrays(np.delete(t, k), np.delete(raw, k, axis=0)),
                                          resample=True)
        assert any("1 gap(s), 1 lost sample(s)" in w and "bridged with a straight line" in w for w in c.warnings)
        assert 1 <= int(c["filled"].sum()) <= 3 and len(c["t"]) == len(full["t"])
        err = max(abs(c[a][-1] - full[a][-1]) for a in ("p_x", "p_y", "p_z"))
        errs.append(err)
    assert len(errs) > 50 and max(errs) < bound, (len(errs), max(errs), bound)
    # a step of 1.7 x the median (jitter by convert's rule) is the loop's: no gap, no note of one
    t17 = t.copy()
    t17[300:] += 0.7 * dt
    c = E.displacement_from_recording(d, cal, recording_from_arrays(t17, raw), resample=True)
    assert not any("lost sample" in w for w in c.warnings) and "filled" not in c
    # a gap of 1.6 s between two captures: against the regular step, not the mean the gap inflates
    tg = t.copy()
    tg[250:] += 1.6
    step = regular_step(tg)[0]
    with pytest.raises(InputError, match="--resample") as ei:
        E.displacement_from_recording(d, cal, recording_from_arrays(tg, raw), resample=True)
    assert ei.value.row == 251 and f"{(tg[250] - tg[249]) / step:.3g} of the regular step {step:.6g} s" in str(ei.value)
