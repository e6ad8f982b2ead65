"""The 6-channel core stays within the figure its header states of the float reference.

|out - M (raw - b - C p(omega)) 2^AC_OUT_FRAC| <= 0.5 + linear_j + centripetal_j max_a omega_a^2 + E_j
(quantize.resolver_rounding_bound; E_j the squared rates' rounding of ac_resolve.h), for every
reading the trim does not clip and every omega, the float reference with the unquantised
calibration and the same (quantised) omega."""
import numpy as np
from core_settings import core
from hypothesis import assume, given, strategies as st

from accelcal import model
from accelcal.io.device import default_device
from accelcal.errors import IllConditionedError, SingularError
from accelcal.firmware.header import render_header
from accelcal.firmware.native import process_batch
from accelcal.firmware.quantize import FORMATS, QuantizeError, exact_fixed_semantics, quantize, resolver_rounding_bound
from test_core_resolve import random_geometry
from test_header import drawn_calibration

OUT = 2.0 ** FORMATS.out_frac


def float_error_slack(ref):
    """float64's own rounding in evaluating the reference (|ref| < 2^31 LSB): 2^-40 relative."""
    return 2.0 ** -40 * (1.0 + np.abs(ref))


@core
@given(st.data())
def test_core_within_the_stated_bound_of_the_float_reference(data):
    seed = data.draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 13))
    raw_min, raw_max = data.draw(st.sampled_from([(0, 65535), (0, 4095), (0, 10000), (1000, 60000)]))
    pos, ax = random_geometry(rng, n)
    k = 10 ** rng.uniform(0, 3.4)
    sens = k * ax * (1 + rng.uniform(-0.01, 0.04, (n, 1))) + k * rng.normal(0, 0.0175, (n, 3))
    b = rng.uniform(raw_min, raw_max, n)
    try:
        t = quantize(b, sens, pos, "bound", rails=(raw_min, raw_max))
    except (IllConditionedError, SingularError, QuantizeError):
        assume(False)
    lin, cen = resolver_rounding_bound(t, b, sens, pos, raw_min, raw_max)
    trim = t.trim.astype(np.int64)
    lo, hi = np.maximum(raw_min, trim - 32768), np.minimum(raw_max, trim + 32767)
    count = 8
    raw = rng.integers(lo, hi + 1, (count, n))
    corner = rng.integers(0, 2, (count, n)).astype(bool)
    raw[:4] = np.where(corner[:4], lo, hi)                          # the box's corners
    wmax = data.draw(st.sampled_from([0, 100, 2000, 32767]))
    w = rng.integers(-wmax, wmax + 1, (count, 3))
    w[0] = data.draw(st.sampled_from([[0, 0, 0], [-32768, -32768, -32768], [32767, -32768, 5]]))
    out, flags = process_batch(t.resolver(), t.trim, raw, w)
    ok = (flags & 3) == 0                                           # outputs not clipped
    assume(ok.any())
    f, a = model.resolve(b, sens, pos, raw, w / 2.0 ** FORMATS.omega_frac)
    ref = np.hstack([f, a]) * OUT
    _, e_runtime, _ = exact_fixed_semantics(t, raw, w)
    w2 = np.max((w / 2.0 ** FORMATS.omega_frac) ** 2, axis=1, keepdims=True)
    bound = 0.5 + lin + cen * w2 + e_runtime + float_error_slack(ref)
    err = np.abs(out - ref)
    assert np.all(err[ok] <= bound[ok]), (err - bound)[ok].max()


def test_header_states_the_figure():
    d = default_device()
    b, s = drawn_calibration(d, np.random.default_rng(7))
    t = quantize(b, s, d.positions, d.name, rails=(d.raw_min, d.raw_max))
    lin, cen = resolver_rounding_bound(t, b, s, d.positions, d.raw_min, d.raw_max)
    text = render_header(t, rounding_lsb=(lin, cen))
    assert f"{lin[:3].max() + 0.5:.3g} LSB" in text and f"{cen[3:].max():.3g}" in text
