"""``python -m accelcal.cli``: the ``accelcal`` command."""
import sys

from .main import main

sys.exit(main())
