"""``accelcal convert`` does each piece of work once and says each thing in one wording: the
headerless rows' time-stamp test (detection and the table's reading), the noise of the readings
(the nominal device's still stretches and the clipping note), the held rows' share, the
sentence on readings with gravity removed.  A ``--full-scale`` without ``--units`` is told by
its Scale (``unit_stated``), through the API as through the command line."""
from __future__ import annotations

import datetime as dt
import importlib

import numpy as np

import accelcal as ac
from accelcal.convert.formats import convert_file
from accelcal.convert.common import gravity_removed_note, held_note
from accelcal.io.device import GRAVITY_REMOVED_TEXT, default_triad
from accelcal.readings.held import held_runs, held_share
from accelcal.readings.no_rest import gravity_removed_clause
from accelcal.io.units import Scale
from cli_run import write_lines

convert_mod = importlib.import_module("accelcal.convert.formats")   # (ac.convert is the API's function)
noise_mod = importlib.import_module("accelcal.readings.noise")


def _rest_then_turn(n=600, seed=0):
    """Counts of a triad at 100 Hz: still on z up, then turned to x up (noise 3 counts)."""
    rng = np.random.default_rng(seed)
    c = np.zeros((n, 3))
    c[: n // 2, 2] = 2048.0
    c[n // 2:, 0] = 2048.0
    return np.round(c + 3.0 * rng.standard_normal((n, 3))).astype(int)


def test_headerless_time_stamps_are_tested_once(tmp_path, monkeypatch):
    """Rows of ``ISO date-time,x,y,z`` without a header: detection tells them by their stamps
    and the table is read by the same test; it ran twice (its scan of the first cells too)."""
    c = _rest_then_turn(200)
    start = dt.datetime(2021, 5, 7, 10, 29, 56)
    src = write_lines(tmp_path / "ax.csv", [f"{(start + dt.timedelta(milliseconds=10 * k)).isoformat()},{a},{b},{d}"
                                           for k, (a, b, d) in enumerate(c)])
    calls = []
    real = convert_mod.timed_rows
    monkeypatch.setattr(convert_mod, "timed_rows", lambda *a: calls.append(1) or real(*a))
    conv = convert_file(src)
    np.testing.assert_array_equal(conv.recording.raw, c)
    assert len(calls) == 1


def test_the_noise_is_estimated_once(tmp_path, monkeypatch):
    """Counts without a stated scale: the nominal device's still stretches and the clipping
    note take the same noise (the nominal device states none), estimated once; it was twice."""
    c = _rest_then_turn()
    src = write_lines(tmp_path / "t.csv", ["t,accX,accY,accZ"] + [f"{k / 100:.2f},{a},{b},{d}"
                                                                   for k, (a, b, d) in enumerate(c)])
    calls = []
    real = noise_mod.estimate_noise
    monkeypatch.setattr(noise_mod, "estimate_noise", lambda *a, **k: calls.append(1) or real(*a, **k))
    conv = convert_file(src)
    assert "median |reading| of" in " ".join(conv.device_notes)     # the still stretches gave the scale
    assert len(calls) == 1


def test_held_share_is_the_note_and_the_log_metadata():
    """One home for the share of rows that repeat the row before (the log's held_share and the
    held-readings note)."""
    raw = np.repeat(_rest_then_turn(100), 4, axis=0)
    k, first = held_runs(raw)
    share = held_share(first, raw.shape[0])
    assert k == 4 and share == (400 - 100) / 399
    assert held_note(k, first, raw.shape[0], None).startswith(f"{100 * share:.0f} % of the rows repeat")
    assert held_share(first[:1], 1) == 0.0


def test_gravity_removed_is_said_in_one_wording():
    """convert's note and the no-rest refusal's clause end in the same sentence."""
    rng = np.random.default_rng(1)
    raw = np.round(20.0 * rng.standard_normal((600, 3))).astype(int)        # |f| ~ 0: user acceleration
    note = gravity_removed_note(raw, Scale("g", 1 / 2048, 1 / 2048), 100.0, lambda i: i + 2)
    assert len(note) == 1 and note[0].endswith(GRAVITY_REMOVED_TEXT), note
    dev = default_triad()
    clause = gravity_removed_clause(dev.nominal_offsets() + raw, dev)
    assert clause.endswith(GRAVITY_REMOVED_TEXT), clause


def test_api_full_scale_alone_takes_the_names_unit(tmp_path):
    """``ac.convert(path, full_scale_g=2)`` over a table whose names say g: the full scale is
    read in the names' unit, as ``accelcal convert --full-scale 2`` reads it.  The API had
    passed no ``units_stated`` and convert_file's default (True) took the Scale's placeholder
    unit, counts, for a stated one: 'overrides the unit the header's columns state', then the
    g readings refused as not whole counts."""
    c = _rest_then_turn(200)
    lsb_g = 4.0 / 2 ** 16
    src = write_lines(tmp_path / "p.csv", ["Time (s),Acceleration x (g),Acceleration y (g),Acceleration z (g)"] +
                      [f"{k / 100:.2f}," + ",".join(repr(float(v * lsb_g)) for v in r) for k, r in enumerate(c)])
    conv = ac.convert(src, full_scale_g=2)
    np.testing.assert_array_equal(conv.recording.raw, c)
    assert not any("overrides" in n for n in conv.notes), conv.notes
