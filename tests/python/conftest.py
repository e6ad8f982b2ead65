import os

from hypothesis import HealthCheck, settings

# The C core's properties run 10,000 examples each in CI (tests/python/core_settings.py);
# every other property test runs the profile's count.
PROFILE = os.environ.get("ACCELCAL_HYPOTHESIS", "dev")
settings.register_profile("ci", max_examples=200, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", max_examples=100, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(PROFILE)
