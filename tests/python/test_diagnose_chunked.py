"""diagnose on a recording read in chunks (``accelcal.io.chunks.read_chunked``, the reader
``accelcal diagnose`` uses for a plain CSV) gives the diagnosis of the recording read whole
(``read_recording(..., whole=True)``): the same JSON, number for number, at several chunk
sizes (blocks of whole lines that end inside poses and inside the motion), on a recording of
the independent generator (tests/python/indep_model.py) and on a real one (shared data)."""
from __future__ import annotations

import importlib
import json

import numpy as np
import pytest

import indep_model as im
from accelcal.diagnose import diagnose
from accelcal.diagnose.prepare import prepare
from accelcal.io.chunks import read_chunked
from accelcal.io.recording import read_recording, write_recording

result = importlib.import_module("accelcal.diagnose.result")   # accelcal.diagnose is also a function's name
BLOCKS = (300, 4096, 1 << 16)     # bytes of text per chunk (whole lines)


def _json(res) -> str:
    out = dict(res)
    out.pop("elapsed_s")
    return json.dumps(out, sort_keys=True, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))


def _compare(path, dev, cal, seed=0):
    whole = read_recording(path, dev.n_channels, whole=True)
    ref = _json(diagnose(dev, cal, [whole], seed=seed))
    for block in BLOCKS:
        rec = read_chunked(path, dev.n_channels, None, block_bytes=block)
        assert np.array_equal(rec.raw, whole.raw) and np.array_equal(rec.t, whole.t)
        got = _json(diagnose(dev, cal, [rec], seed=seed))
        assert got == ref, f"chunks of {block} B: the diagnosis differs from the whole-file read's"


def test_generator_jig_with_motion_read_in_chunks_diagnoses_as_whole(tmp_path):
    """A jig recording with an offset step and a moving part (f, w, dw known), read in chunks."""
    jig = im.make_jig(["offset"], seed=3701, motion=True, n_poses=12, repeats=False)
    path = tmp_path / "jig.csv"
    write_recording(path, jig["recording"])
    assert path.stat().st_size > 20 * max(BLOCKS[:2])      # many chunks at the small sizes
    _compare(path, jig["device"], jig["cal"])


def test_real_recording_read_in_chunks_diagnoses_as_whole(real_model, tmp_path):
    """The MPU-6050's hand-turned poses (shared data) written as a recording CSV, read in chunks."""
    dev, rec, step, cal = real_model("mpu6050")
    path = tmp_path / "mpu.csv"
    write_recording(path, rec)
    _compare(path, dev, cal)


def test_one_offset_for_every_sample_is_held_once(tmp_path):
    """Without a bias in time (no temperature offset in the calibration) the fit data's offset
    is one row seen by every sample (a read-only view), not n copies: 48 bytes a sample less
    in each FitData the diagnosis holds (the first, each step's, the re-linearised)."""
    jig = im.make_jig(["offset"], seed=3702, n_poses=12, repeats=False)
    dev, cal = jig["device"], jig["cal"]
    D = prepare(dev, cal, [jig["recording"]], 5, 0, 1.0)
    assert D.offset_t.shape == (D.n, D.N) and D.offset_t.strides[0] == 0
    assert np.array_equal(D.offset_t[0], np.asarray(cal.offsets, float))
    assert np.array_equal(D.sensed, D.pred - np.asarray(cal.offsets, float))


def test_the_first_target_is_the_residual_itself_not_a_copy(monkeypatch):
    """The first round of fits takes the residual e and the prediction p0 as read-only views, not
    copies (96 bytes a sample less at the diagnosis's peak, which is in that round): no fit
    writes into them (a write would raise), and the diagnosis is the same."""
    jig = im.make_jig(["offset"], seed=3703, n_poses=12, repeats=False)
    seen = []
    run = result.run_candidates

    def spy(D, cands, names, y, pcur, progress):
        seen.append((D, y, pcur))
        return run(D, cands, names, y, pcur, progress)
    monkeypatch.setattr(result, "run_candidates", spy)
    res = diagnose(jig["device"], jig["cal"], [jig["recording"]])
    D, y, pcur = seen[0]
    assert not y.flags.writeable and not pcur.flags.writeable
    assert np.shares_memory(pcur, D.p0)
    assert res["verdict"] == "offset", res["verdict"]
