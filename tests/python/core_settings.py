"""Example counts for the C core's property tests: 10,000 each in CI."""
import os

from hypothesis import settings

CORE_EXAMPLES = 10_000 if os.environ.get("ACCELCAL_HYPOTHESIS", "dev") == "ci" else 300
core = settings(max_examples=CORE_EXAMPLES)
