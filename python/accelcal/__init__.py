"""accelcal: calibration, 6-DOF resolution and sim-to-real diagnosis for
accelerometer-only motion sensors.

``import accelcal as ac`` gives the Python API (:mod:`accelcal.api`, docs/api.md):
``ac.load_device``, ``ac.read_recording``, ``ac.calibrate``, ``ac.resolve``,
``ac.diagnose``, ``ac.header``, ``ac.simulate``, ``ac.attitude``,
``ac.displacement``, ``ac.rate`` and the dataclasses.

The API's ``calibrate``, ``diagnose``, ``simulate``, ``header`` and ``resolve`` are
functions on the package; the modules of the same names are reached as
``from accelcal.calibrate import ...`` (``import accelcal.calibrate as m`` would
give the function).
"""
__version__ = "0.1.0"

from .api import *  # noqa: E402,F401,F403  (the public API, after __version__ which modules import)
from .api import __all__ as _api_names  # noqa: E402

__all__ = ["__version__", *_api_names]
