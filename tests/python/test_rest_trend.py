"""The rests' trend test (estimators.trend): each axis against its own noise, widened by the
noise's correlation as the rests show it.  A rest of white noise with one noisy axis, and a rest
of AR(1)-filtered noise (a low-pass chip, a hand's tremor), hold no trend: over many draws the
blocks taken for one stay within a binomial bound at the stated false-alarm rate; a real trend is
still found.  Every recording is built here."""
import warnings

import numpy as np
from scipy.signal import lfilter
from scipy.stats import binom, norm

from accelcal import estimators as E
from accelcal.io.calibration import Calibration
from accelcal.io.device import Device
from accelcal.estimators.rest import RestParams
from accelcal.estimators.trend import (TREND_FALSE_ALARM, noise_correlation, rest_widening, rest_without_trend,
                                      trend_bound, trend_widening)
from accelcal.io.recording import recording_from_arrays
from estimator_devices import G

RATE = 100.0
HOLD = 25                     # the default 0.25 s at 100 Hz: blocks of 100 samples
BLOCK = 4 * HOLD
DRAWS = 300
REST_N = 2000                 # 20 s rests: 20 blocks each


def _rest(rng, sigma, phi):
    """A rest of REST_N samples (m/s^2, (n, 3)): g along z plus AR(1) noise with coefficient ``phi``
    (0: white) whose marginal std on each axis is ``sigma`` (3,)."""
    e = lfilter([1.0], [1.0, -phi], rng.standard_normal((REST_N + 300, 3)), axis=0)[300:]
    return np.array([0.0, 0.0, G]) + e * np.sqrt(1.0 - phi * phi) * np.asarray(sigma)


def _false_alarms(sigma, phi, seed):
    """Blocks taken for a trend over DRAWS rests without one, and the blocks tested."""
    rng = np.random.default_rng(seed)
    p = RestParams(hold=HOLD)
    count = 0
    for _ in range(DRAWS):
        f = _rest(rng, sigma, phi)
        count += len(rest_without_trend(np.ones(REST_N, bool), f, p, sigma)[1])
    return count, DRAWS * REST_N // BLOCK


def _binomial_top(tests):
    """The most false alarms among ``tests`` blocks the stated rate allows (a chance of 1e-3 to see more)."""
    return int(binom.isf(1e-3, tests, TREND_FALSE_ALARM))


def test_a_rest_of_white_noise_with_one_noisy_axis_holds_no_trend():
    sigma = np.array([0.01, 0.01, 0.1])
    count, tests = _false_alarms(sigma, 0.0, 1)
    assert count <= _binomial_top(tests), (count, tests)
    # and the stated rate is what 5 sigma of Gaussian noise gives, per block of three axes
    assert TREND_FALSE_ALARM >= 3 * 2 * norm.sf(5.0)


def test_a_rest_of_correlated_noise_holds_no_trend():
    """AR(1) noise with phi = 0.9 (a chip's low-pass filter, ~10 samples of memory): taken as white
    noise of its sigma, a line fitted to 100 of its samples changes 3.7 x more than the test allows
    for, and about one block in five was taken for a trend."""
    sigma = np.array([0.02, 0.02, 0.05])
    count, tests = _false_alarms(sigma, 0.9, 2)
    assert count <= _binomial_top(tests), (count, tests)


def test_the_widening_is_the_slope_variance_of_the_noise():
    """For AR(1) noise (rho(k) = phi^k) the widening is the slope's variance over white noise's, which
    the fitted changes over many draws show.  The rests' estimate of it falls short, by up to a quarter
    (the line fitted to each 4 s stretch takes some of the slow noise with it): 10.3-11.7 of 13.8 here."""
    rng = np.random.default_rng(3)
    phi = 0.9
    truth = trend_widening(np.column_stack([phi ** np.arange(BLOCK)] * 3), BLOCK)
    changes = []
    for _ in range(400):
        x = lfilter([1.0], [1.0, -phi], rng.standard_normal(BLOCK + 300))[300:] * np.sqrt(1 - phi * phi)
        changes.append(np.polyfit(np.arange(BLOCK, dtype=float), x, 1)[0] * (BLOCK - 1))
    white = trend_bound(BLOCK, 1.0) / 5.0
    measured = np.mean(np.square(changes)) / white ** 2
    assert abs(measured / truth[0] - 1.0) < 3.0 * np.sqrt(2.0 / 400)        # the mean of 400 chi2_1
    est = rest_widening(np.ones(REST_N, bool), _rest(rng, np.full(3, 0.02), phi), BLOCK, HOLD)
    assert np.all((est > 0.75 * truth) & (est <= truth)), (est, truth)


def test_a_real_trend_is_still_found():
    """A change of twice the (widened) test within one block of a correlated rest: found in every draw,
    on its axis."""
    rng = np.random.default_rng(4)
    phi, sigma = 0.9, np.array([0.02, 0.02, 0.05])
    truth = trend_widening(np.column_stack([phi ** np.arange(BLOCK)] * 3), BLOCK)
    step = 2.0 * trend_bound(BLOCK, sigma[0], truth[0])
    p = RestParams(hold=HOLD)
    found = 0
    for _ in range(100):
        f = _rest(rng, sigma, phi)
        f[1000:1100, 0] += np.linspace(0.0, step, BLOCK)
        f[1100:, 0] += step
        trends = rest_without_trend(np.ones(REST_N, bool), f, p, sigma)[1]
        found += any(b == 1000 and s == sigma[0] for b, _, _, _, s in trends)
    assert found == 100


def _triad():
    """A signed 16-bit triad at +-16 g, 100 Hz, no noise stated (taken from the data, per channel)."""
    return Device(name="trend", sample_rate_hz=RATE, gravity_mps2=G, raw_min=-32768, raw_max=32767,
                  positions=np.zeros((3, 3)), axes=np.eye(3), counts_per_mps2=np.full(3, 2048 / G),
                  zero_counts=np.zeros(3))


def test_a_trend_on_a_quiet_axis_is_not_hidden_by_a_noisy_one():
    """x and y read 0.01 m/s^2 of noise, z 0.1: a rest in which f_x changes by 0.05 m/s^2 over 1 s is
    a slow motion by x's noise (5 sigma of the change over 1 s: 0.017 m/s^2), which the test of all
    axes against the noisiest one (0.17) let pass as a rest.  (The correlation is the median over
    4 s stretches of the rests: the ramp lies within one of the final rest's four.)"""
    d = _triad()
    rng = np.random.default_rng(5)
    n0, n1, n2 = int(3 * RATE), int(1 * RATE), int(16 * RATE)
    body = np.tile([0.0, 0.0, G], (n0 + n1 + n2, 1))
    body[n0:n0 + n1, 0] = 2.0 * np.sin(2 * np.pi * np.arange(n1) / n1)
    ramp = slice(n0 + n1 + int(6 * RATE), n0 + n1 + int(7 * RATE))
    body[ramp, 0] += np.linspace(0.0, 0.05, int(1 * RATE))
    body[ramp.stop:, 0] += 0.05
    raw = np.round((body + np.array([0.01, 0.01, 0.1]) * rng.standard_normal(body.shape)) * d.counts_per_mps2)
    rec = recording_from_arrays(np.arange(body.shape[0]) / RATE, raw.astype(np.int64))
    c = E.displacement_from_recording(d, Calibration.nominal(d), rec, keep_turned=True)
    trend = [w for w in c.warnings if "f changes steadily" in w]
    assert len(trend) == 1, c.warnings
    rest = c["rest"].astype(bool)
    assert not rest[ramp.start + HOLD:ramp.stop - HOLD].any() and rest[:int(2.5 * RATE)].all()


def test_a_constant_axis_reads_as_white_noise_without_a_warning():
    """Noise below the code step leaves an axis constant at rest: its autocorrelation has no estimate
    at any lag (0 / 0), and numpy's nanmedian printed 'RuntimeWarning: All-NaN slice encountered' to
    the user of accelcal displacement (a 1600 Hz triad at 0.003 m/s^2 of noise); an axis constant at
    9.8 m/s^2 left the line fit's rounding (~1e-15, smooth), read as correlation 0.998 at lag 1 (its
    trend test widened ~20x).  White noise on such axes, no warning."""
    rng = np.random.default_rng(0)
    f = np.column_stack([rng.standard_normal(400), np.zeros(400), np.full(400, 9.8)])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rho = noise_correlation([f[:200], f[200:]], 10)
    assert rho[0].tolist() == [1.0, 1.0, 1.0] and np.all(rho[1:, 1:] == 0.0)
