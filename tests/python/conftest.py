import os

from hypothesis import HealthCheck, settings

# CI runs every core property with 10,000 examples; a quick local run uses fewer.
settings.register_profile("ci", max_examples=10_000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", max_examples=300, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("ACCELCAL_HYPOTHESIS", "dev"))
