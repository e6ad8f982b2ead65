"""Running the command line in-process for the tests (one home for it)."""
from __future__ import annotations

import warnings

from accelcal.cli import main


def run(argv, capfd):
    """main(argv) in-process: (exit code, stdout, stderr, Python warnings)."""
    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rc = main([str(a) for a in argv])
    out, err = capfd.readouterr()
    return rc, out, err, [str(w.message) for w in caught]


def one_refusal(err):
    """Whether stderr is one refusal: its error line last, after nothing but note lines (the notes
    made before it)."""
    lines = err.splitlines()
    return bool(lines) and ": error: " in lines[-1] and all(": note: " in line for line in lines[:-1])
