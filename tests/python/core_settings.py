"""Example counts for the C core's property tests: 10,000 each in CI."""
import os

from hypothesis import settings

CORE_EXAMPLES = 10_000 if os.environ.get("ACCELCAL_HYPOTHESIS", "dev") == "ci" else 300
core = settings(max_examples=CORE_EXAMPLES)

# The estimators' properties (issue 5) run 2,000 examples each in CI: their
# per-example cost is dominated by hypothesis's own engine, and the suite must
# stay well inside CI's time.
EST_EXAMPLES = 2_000 if os.environ.get("ACCELCAL_HYPOTHESIS", "dev") == "ci" else 200
estimator = settings(max_examples=EST_EXAMPLES)
