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


import pytest  # noqa: E402

import indep_model as im  # noqa: E402
from shared_data import SHARED_DATA, shared_data_dir, shared_file  # noqa: E402


@pytest.fixture(scope="session")
def shared_data():
    """The real recordings' directory (``../shared/data`` beside the repository).

    Skips, naming the path it looked for, when this checkout has none beside it.
    """
    base = shared_data_dir()
    if base is None:
        pytest.skip(f"real recordings not found: {SHARED_DATA} does not exist "
                    "(CI has it; a bare clone skips the tests that need it)")
    return base


@pytest.fixture(scope="session")
def real_model(shared_data):
    """name -> (device, recording, native code step, its own calibration) of a real recording
    of ``../shared/data`` (:func:`indep_model.real_model`, loaded and calibrated once a
    session; the tests must not change what it returns).  Skips, naming the file, when that
    recording is missing."""
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = im.real_model(name, shared_file)
        if cache[name] is None:
            pytest.skip(f"{'/'.join(im.REAL[name][0])} not in {shared_data}")
        return cache[name]

    return get
