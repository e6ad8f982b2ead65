"""``accelcal refine``: the calibration refitted with the terms a diagnosis's model says the
firmware can correct (docs/refine.md).  Exit 0 with one paragraph, 1 when nothing is
correctable (nothing written), 2 on bad input (one line, nothing written)."""
from __future__ import annotations

import sys

from ..calibrate.refine import NothingToCorrect, refine_calibration
from ..io.calibration import load_calibration, save_calibration
from ..io.device import default_device, load_device
from ..io.recording import read_recording
from .paths import check_output

__all__ = ["add_refine_parser", "cmd_refine", "EXIT_NOTHING"]

#: the exit status when the diagnosis's model holds nothing a calibration term corrects
EXIT_NOTHING = 1


def cmd_refine(a) -> int:
    """Run ``accelcal refine`` on the parsed arguments ``a``."""
    check_output(a.output)
    dev = default_device() if a.device in (None, "default") else load_device(a.device)
    cal = load_calibration(a.calibration, dev)
    recs = [read_recording(p, dev.n_channels) for p in a.recordings]
    try:
        res = refine_calibration(dev, cal, a.diagnosis, recs)
    except NothingToCorrect as e:
        print(f"accelcal refine: {e}; nothing written", file=sys.stderr)
        return EXIT_NOTHING
    save_calibration(res.calibration, a.output)
    print(res.paragraph)
    print(f"wrote {a.output}")
    return 0


def add_refine_parser(sub) -> None:
    """The ``refine`` subcommand's parser, on the subparsers ``sub``."""
    s = sub.add_parser("refine", help="refit the calibration with the diagnosed effects the firmware can correct "
                       "(nonlinearity, temperature offset and gain with their lag, time skew) as terms")
    s.add_argument("--device", required=True, metavar="D.json", help="device JSON ('default': the seed prototype)")
    s.add_argument("--calibration", required=True, metavar="CAL.json", help="the calibration to refine")
    s.add_argument("--diagnosis", required=True, metavar="DIAG.json",
                   help="accelcal diagnose's JSON (its model.effects and model.params)")
    s.add_argument("recordings", nargs="+", metavar="REC.csv",
                   help="recordings with a reference (the jig's stated f, a reference motion; temp_c for the "
                   "temperature terms)")
    s.add_argument("-o", "--output", required=True, metavar="CAL2.json", help="the refined calibration to write")
    s.set_defaults(func=cmd_refine)
