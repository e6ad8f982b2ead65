"""Example counts for the C core's property tests: 10,000 each in CI.

The batched properties (tests/python/core_batch.py) check a batch of input vectors per example:
the first drawn by the property's hypothesis strategy, the rest by numpy over the same ranges and
edge values.  ``BATCHED[name] = (examples in CI, vectors per example)``; their product is the
vectors each property checks in CI, at least what it checked with one hypothesis-drawn input per
example at CORE_EXAMPLES (the "before" column; docs/testing.md has the table)."""
import os

from hypothesis import settings

CI = os.environ.get("ACCELCAL_HYPOTHESIS", "dev") == "ci"
CORE_EXAMPLES = 10_000 if CI else 300
core = settings(max_examples=CORE_EXAMPLES)

#: name: (examples in CI, vectors per example).  Before batching (10,000 examples, CI), per property:
#: lag 10,000 runs (78,188 temperatures); temp 10,000 samples; skew 10,000 runs; nonlin 10,000
#: samples (test_nonlin_realistic_tight: the examples its assume() kept); frac 10,000 samples; trim,
#: unknown 10,000 samples; process 10,000 tables x 4 samples; triad 10,000 tables x 5 samples.
BATCHED = {
    "lag": (250, 40),
    "temp": (200, 100),
    "skew": (125, 100),
    "nonlin": (200, 100),
    "frac": (200, 100),              # test_terms_frac.py's Q.k temperature correction
    "trim": (200, 100),
    "process": (1_000, 40),          # samples per table (4 before batching)
    "triad": (250, 10),              # tables per example, of TRIAD_READINGS = 20 samples (5 before)
}
#: examples of a batched property in the dev profile
DEV_BATCHED_EXAMPLES = 30


class Batched:
    """``@batched(name)``: the hypothesis settings of a batched property; ``batched.size(name)``
    its vectors per example."""

    def __call__(self, name: str):
        examples, _ = BATCHED[name]
        return settings(max_examples=examples if CI else DEV_BATCHED_EXAMPLES)

    @staticmethod
    def size(name: str) -> int:
        return BATCHED[name][1]


batched = Batched()

# The estimators' properties (issue 5) run 2,000 examples each in CI: their
# per-example cost is dominated by hypothesis's own engine, and the suite must
# stay well inside CI's time.
EST_EXAMPLES = 2_000 if CI else 200
estimator = settings(max_examples=EST_EXAMPLES)
