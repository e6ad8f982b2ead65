"""The nonlinearity's iteration count chosen from the coefficients (issue 35): a strong bend
(contraction L = 0.5 at the converter's ends) is inverted to within the documented bound by the
C core and the float reference, where the old fixed 3 iterations leave over ten counts (24 here)."""
from types import SimpleNamespace

import numpy as np
import pytest

from accelcal.firmware import native, terms
from accelcal.firmware.native import lib
from accelcal.firmware.terms_fixed import nonlin_bound, quantize_terms
from accelcal.firmware.terms_header import terms_header_parts

S = 127.4          # counts per m/s^2 (1250 counts per g)
B = 2048.0         # offset, counts: a 12-bit converter's middle
RAILS = (0, 4095)
SPAN = 2048.0
# c2, c3 (1/counts, 1/counts^2): L = 2 c2 SPAN + 3 c3 SPAN^2 = 0.4 + 0.1 at the ends
C2 = 0.4 / (2 * SPAN)
C3 = 0.1 / (3 * SPAN ** 2)


def _cal(c2=C2, c3=C3):
    return SimpleNamespace(n_channels=1, offsets=np.array([B]), sensitivity=np.array([[S, 0.0, 0.0]]),
                           nonlin_k2=np.array([c2 * S ** 2]), nonlin_k3=np.array([c3 * S ** 3]),
                           offset_tc=None, gain_tc=None, time_skew_s=None, temp_ref_c=None,
                           temp_offset_tau_s=None, temp_gain_tau_s=None)


def _exact_inverse(z, c2, c3):
    """z* with z* + c2 z*^2 + c3 z*^3 = z (Newton from z, 60 steps; the map is monotonic here)."""
    u = np.asarray(z, float).copy()
    for _ in range(60):
        f = u + c2 * u * u + c3 * u ** 3 - z
        u = u - f / (1.0 + 2.0 * c2 * u + 3.0 * c3 * u * u)
    assert np.all(np.abs(u + c2 * u * u + c3 * u ** 3 - z) < 1e-9)
    return u


def _contraction(c2, c3, z):
    return float(2 * abs(c2) * z + 3 * abs(c3) * z * z), float(abs(c2) * z * z + abs(c3) * z ** 3)


def test_iteration_count_meets_the_tolerance_and_is_the_least():
    L, e = _contraction(C2, C3, SPAN)
    k = terms.nonlinearity_iterations([C2], [C3], SPAN)
    assert k > terms.NONLIN_ITERATIONS
    assert L ** k * e <= terms.NONLIN_TOLERANCE_COUNTS < L ** (k - 1) * e
    # a weak bend keeps the default; no span keeps the default; L >= 1 takes the cap
    assert terms.nonlinearity_iterations([1e-7], [1e-11], SPAN) == terms.NONLIN_ITERATIONS
    assert terms.nonlinearity_iterations([C2], [C3], None) == terms.NONLIN_ITERATIONS
    assert terms.nonlinearity_iterations([1.0 / SPAN], [0.0], SPAN) == terms.NONLIN_MAX_ITERATIONS
    assert terms.nonlinearity_span([B], RAILS) == SPAN


def test_core_limits_match_the_reference():
    assert lib.AC_NONLIN_MAX_ITERATIONS == terms.NONLIN_MAX_ITERATIONS
    assert lib.AC_NONLIN_ITERATIONS == terms.NONLIN_ITERATIONS
    t = native.new_nonlin_table(15, [100], [100], terms.NONLIN_MAX_ITERATIONS + 1)
    assert lib.ac_nonlin_check(t) == lib.AC_ERR_FORMAT
    with pytest.raises(Exception):
        native.nonlin_invert(t, np.array([5], np.int16))
    assert lib.ac_nonlin_check(native.new_nonlin_table(15, [100], [100], terms.NONLIN_MAX_ITERATIONS)) == lib.AC_OK


def test_strong_bend_is_inverted_by_the_core_and_the_reference():
    tt = quantize_terms(_cal(), 1, 0.01, [0], RAILS)
    k = int(tt.nonlin["iterations"])
    assert k > terms.NONLIN_ITERATIONS
    c2q, c3q = (float(v[0]) for v in tt.nonlin_coefficients())
    x = np.arange(RAILS[0], RAILS[1] + 1) - B            # every code of the converter, about b
    exact = _exact_inverse(x, c2q, c3q)
    L, e = _contraction(c2q, c3q, SPAN)
    table = tt.cdata()["nonlin"]
    core = np.array([native.nonlin_invert(table, np.array([v], np.int16))[0][0] for v in x.astype(np.int16)], float)
    bound = L ** k * e + nonlin_bound(np.abs(x), c2q, c3q, tt.nonlin["shift"], k)
    assert np.all(np.abs(core - exact) <= bound)
    assert float(np.max(np.abs(core - exact))) < 2.0
    # the old fixed count on the same table: over ten counts off at the ends
    old = native.new_nonlin_table(tt.nonlin["shift"], tt.nonlin["a2"], tt.nonlin["a3"], 3)
    core3 = np.array([native.nonlin_invert(old, np.array([v], np.int16))[0][0] for v in x.astype(np.int16)], float)
    assert float(np.max(np.abs(core3 - exact))) > 10.0
    # the float reference with the converter's rails runs the same count
    ref = terms.correct_readings(_cal(), (x + B)[:, None], rails=RAILS)[:, 0] - B
    ex = _exact_inverse(x, C2, C3)
    assert np.all(np.abs(ref - ex) <= terms.NONLIN_TOLERANCE_COUNTS)
    assert float(np.max(np.abs(terms.correct_readings(_cal(), (x + B)[:, None])[:, 0] - B - ex))) > 10.0


def test_header_carries_the_count():
    tt = quantize_terms(_cal(), 1, 0.01, [0], RAILS)
    dec, dfn = terms_header_parts(tt, "AC_CAL", SPAN, False, "ac_resolve(&AC_CAL_RESOLVER, x, 0, out)")
    assert f"    {int(tt.nonlin['iterations'])}u /* iterations */" in dfn
    assert any(f"ac_nonlin_invert ({int(tt.nonlin['iterations'])} iterations)" in line for line in dec)
