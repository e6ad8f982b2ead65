"""Running the command line in-process for the tests (one home for it)."""
from __future__ import annotations

import json
import warnings

from accelcal.cli.main import main
from accelcal.io.recording import read_recording, write_recording
from accelcal.io.recording_type import Recording


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


def write_lines(path, lines):
    """A text file of ``lines`` (each ended by a newline); returns ``path``."""
    path.write_text("".join(line + "\n" for line in lines))
    return path


def convert_ok(tmp_path, capfd, src, *args):
    """``accelcal convert SRC ARGS -o o.csv --device-out d.json`` in ``tmp_path``, which must
    succeed with no Python warning: (the recording, the device JSON, stderr, stdout)."""
    out, dev = tmp_path / "o.csv", tmp_path / "d.json"
    rc, said, err, caught = run(["convert", src, *args, "-o", out, "--device-out", dev], capfd)
    assert rc == 0 and not caught, err
    return read_recording(out), json.loads(dev.read_text()), err, said


def convert_refused(tmp_path, capfd, src, *args, name="refused"):
    """``accelcal convert SRC ARGS`` into a fresh directory ``tmp_path / name``, which must be
    refused: exit 2, one refusal on stderr (notes before it allowed), no traceback, nothing
    written; returns stderr."""
    out = tmp_path / name
    out.mkdir()
    rc, _, err, _ = run(["convert", src, *args, "-o", out / "o.csv"], capfd)
    assert rc == 2 and one_refusal(err) and "Traceback" not in err, err
    assert not list(out.iterdir())
    return err


def edited_copy(src, n_channels, dst, edit):
    """The recording ``src`` with ``(t, raw) = edit(t, raw)`` (copies) written to ``dst`` (t and raw
    only); returns ``dst``."""
    rec = read_recording(src, n_channels)
    t, raw = edit(rec.t.copy(), rec.raw.copy())
    write_recording(dst, Recording(t=t, raw=raw))
    return dst


def spy(monkeypatch, owner, name):
    """Replace ``owner.name`` by a wrapper recording each call's result; returns that list."""
    calls = []
    real = getattr(owner, name)

    def wrapper(*args, **kwargs):
        out = real(*args, **kwargs)
        calls.append(out)
        return out

    monkeypatch.setattr(owner, name, wrapper)
    return calls
