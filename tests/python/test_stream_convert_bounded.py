"""convert of a recording CSV in bounded memory (accelcal.convert.bounded; docs/streaming.md,
"convert in bounded memory"): with a stated scale the first pass keeps histograms and counts, not
t, the counts and the labels, and the output, device, notes and summary are the whole-file
command's byte for byte at chunks of one row to more than the file (boundaries inside still
poses and inside motions); where a summary cannot give the whole-file answer the arrays path runs
(the same bytes)."""
from __future__ import annotations

import numpy as np
import pytest

from accelcal.convert import bounded, stream
from accelcal.convert.formats import convert_file
from accelcal.convert.common import held_note
from accelcal.io.chunks import Fallback
from accelcal.io.device import save_device
from accelcal.io.recording import Recording, write_recording
from accelcal.readings.clipping import pile_level_counts
from accelcal.readings.held import RunCounts, held_runs
from accelcal.readings import noise_stream
from accelcal.readings.noise import code_step, estimate_noise

from cli_run import run
from indep_model import make_jig
from shared_data import shared_file
from test_stream_convert import BLOCKS, poses, whole, whole_scale

#: real recordings (other tools' files) made contract CSVs first: (folder, file)
REAL = (("imu_tk_xsens", "xsens_acc.txt.gz"), ("mpu6050_tomisuarez", "example_data_calibration.csv.gz"),
        ("mpu6050_tomisuarez", "example_data_tinit_calc.csv.gz"))


def write_common_cases(d, seeds: tuple) -> None:
    """The recordings both bounded convert paths (with and without a stated scale) are checked on,
    in the directory d: plain.csv, labelled.csv (the independent generator's jig: pose, f),
    rail.csv, pile.csv, held.csv, ms.csv; ``seeds`` the five poses() seeds."""
    rec = poses(1800, seeds[0])
    write_recording(d / "plain.csv", Recording(t=rec.t, raw=rec.raw, metadata={"device": "x"}))
    jig = make_jig(seed=5, device="triad16", rate=100.0, n_poses=6, repeats=False, hold_s=(1.0, 1.5))["recording"]
    write_recording(d / "labelled.csv", jig)                         # the independent generator's: pose, f
    signed = poses(1800, seeds[1], signed=True)
    signed.raw[700:760, 1] = 2 ** 15 - 1                            # at the rail: counted in the note
    signed.raw[900:905, 2] = -(2 ** 15)
    write_recording(d / "rail.csv", Recording(t=signed.t, raw=signed.raw))
    pile = poses(1800, seeds[2])
    pile.raw[200:230, 0] = int(pile.raw[:, 0].max()) + 50           # held at a level inside the range
    write_recording(d / "pile.csv", Recording(t=pile.t, raw=pile.raw))
    held = poses(1800, seeds[3])
    held.raw[1::2] = held.raw[0::2]                                 # each reading held for two rows
    write_recording(d / "held.csv", Recording(t=held.t, raw=held.raw))
    ms = poses(1800, seeds[4])
    write_recording(d / "ms.csv", Recording(t=1000.0 * ms.t + 5.0, raw=ms.raw))   # t in ms: told, noted


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("bounded_convert")
    write_common_cases(d, (11, 12, 15, 17, 18))
    paused = poses(1800, 13)
    t = paused.t.copy()
    t[1000:] += 0.5                                                 # a pause of 50 samples: the gap note
    write_recording(d / "paused.csv", Recording(t=t + 12.25, raw=paused.raw))
    step4 = poses(1800, 14)
    write_recording(d / "step4.csv", Recording(t=step4.t, raw=step4.raw * 4))     # the code-step note
    uneven = poses(3000, 19)
    runs = np.cumsum(np.where(np.arange(3000) % 5 == 0, 2, 3))      # runs of 3, 3, 3, 3, 2 rows: 2.8 on average
    first = runs[runs < 3000]
    idx = np.searchsorted(first, np.arange(3000), side="right") - 1
    uneven.raw[first[0]:] = uneven.raw[first[idx[first[0]:]]]
    write_recording(d / "uneven.csv", Recording(t=uneven.t, raw=uneven.raw))
    lead = poses(1800, 20)
    lead.raw[:3] = 0
    write_recording(d / "lead.csv", Recording(t=lead.t, raw=lead.raw))
    return d


#: (file, options): each goes the bounded way ("pile": an extreme held inside the range, the noise pass)
CASES = [("plain", ("--full-scale", "2")), ("labelled", ("--full-scale", "8")), ("rail", ("--full-scale", "4")),
         ("paused", ("--full-scale", "2")), ("step4", ("--full-scale", "2", "--bits", "16")),
         ("plain", ("--full-scale", "2", "--rate", "101")), ("plain", ("--units", "counts", "--lsb", "0.001g")),
         ("pile", ("--full-scale", "2")), ("held", ("--full-scale", "2")), ("ms", ("--full-scale", "2")),
         ("uneven", ("--full-scale", "2")), ("plain", ("--full-scale", "2", "--time-unit", "s"))]


def no_arrays(monkeypatch):
    """The arrays path's first pass fails where it is called."""
    def fail(*a, **k):
        raise AssertionError("the first pass kept the arrays")
    monkeypatch.setattr(stream, "first_pass", fail)


def same_as_whole(capfd, tmp_path, src, args, blocks=BLOCKS):
    """The command's output, device, stderr and stdout, and convert_file's at each block size, against
    the whole-file command's."""
    ref, ref_dev, ref_err, ref_said = whole(capfd, tmp_path, src, "w", *args)
    o, dev = tmp_path / "s.csv", tmp_path / "s.json"
    rc, said, err, _ = run(["convert", src, *args, "-o", o, "--device-out", dev, "--quiet"], capfd)
    assert rc == 0, err
    assert (o.read_bytes(), dev.read_text(), err) == (ref, ref_dev, ref_err)
    assert said.replace("s.csv", "W").replace("s.json", "D") == ref_said.replace("whole_w.csv", "W").replace(
        "whole_w.json", "D")
    scale = whole_scale(args)
    rate = next((float(args[i + 1]) for i, a in enumerate(args) if a == "--rate"), None)
    for block in blocks:
        conv = convert_file(src, stream=True, block_bytes=block, scale=scale, rate_hz=rate, bits=16)
        assert conv.writer is not None
        conv.write(o)
        assert o.read_bytes() == ref, block
        save_device(conv.device, dev)
        assert dev.read_text() == ref_dev, block
    return ref_err


@pytest.mark.parametrize("case", range(len(CASES)))
def test_bounded_gives_the_whole_file_bytes(files, capfd, tmp_path, monkeypatch, case):
    name, args = CASES[case]
    no_arrays(monkeypatch)          # on the code before, every recording CSV went through the arrays
    err = same_as_whole(capfd, tmp_path, files / f"{name}.csv", args)
    if name == "rail":
        assert "clipped" in err and "raw_max" in err and "raw_min" in err
    if name == "paused":
        assert "longer than" in err
    if name == "step4":
        assert "multiple of 4" in err
    if name == "pile":
        assert "a pile inside the range" in err
    if name in ("held", "uneven"):
        assert "repeat the row before" in err and ("on average" in err) == (name == "uneven")
    if name == "ms":
        assert "t read in ms" in err


def test_fallback_gives_the_same_bytes(files, capfd, tmp_path, monkeypatch):
    """Where a summary cannot tell (a leading 0, 0, 0 placeholder), the arrays path runs: the
    whole-file bytes still (without a stated scale the bounded path runs now:
    test_stream_convert_scale.py)."""
    called = []
    arrays = stream.first_pass

    def counted(*a, **k):
        called.append(1)
        return arrays(*a, **k)
    monkeypatch.setattr(stream, "first_pass", counted)
    for name, args in (("lead", ()), ("lead", ("--full-scale", "2"))):
        called.clear()
        same_as_whole(capfd, tmp_path, files / f"{name}.csv", args, blocks=(97, 1 << 30))
        assert called, name


def test_summaries_do_not_grow(files, tmp_path):
    """The first pass's summaries of a recording repeated 20 times hold no more entries than of one."""
    rec = poses(1800, 16)
    sizes = []
    for reps in (1, 20):
        n = 1800 * reps
        path = tmp_path / f"r{reps}.csv"
        write_recording(path, Recording(t=np.arange(n) / 100.0, raw=np.tile(rec.raw, (reps, 1))))
        head = stream.contract_head(path, None)
        s = bounded.first_pass_sums(path, head, 4096, None)
        assert s.n == n
        sizes.append((sum(len(h) for h in s.hist), len(s.runs.hist)))
    assert sizes[1] == sizes[0]


@pytest.mark.parametrize("chunk", (1, 7, 333, 1 << 20))
def test_noise_pass_is_estimate_noise(monkeypatch, chunk):
    """NoisePass fed in chunks gives estimate_noise's floats exactly (rests, motions, a held rail,
    windows of 3 to 80 samples; the Otsu split in slices of 50 windows)."""
    monkeypatch.setattr(noise_stream, "SLICE", 50)
    rng = np.random.default_rng(chunk)
    for trial in range(25):
        n = int(rng.integers(5, 4000))
        raw = np.round(rng.normal(0, rng.uniform(0.3, 30), (n, 3))).astype(np.int64) + 2048
        if trial % 3 == 0:
            raw[: n // 2] += np.round(500 * np.sin(np.arange(n // 2) / 20)[:, None]).astype(np.int64)
        if trial % 4 == 1:
            raw[n // 3: n // 3 + 50, 1] = raw[:, 1].max()
        w = int(rng.integers(3, 80))
        q = np.array([code_step(raw[:, i]) for i in range(3)])
        p = noise_stream.NoisePass(n, w, raw.min(0), raw.max(0), q)
        for a in range(0, n, chunk):
            p.add(raw[a:a + chunk])
        assert np.array_equal(p.noise(slice_windows=7), estimate_noise(raw, w, integer=True)), trial


def test_median_counts_is_numpys():
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 10, 11, 1000):
        v = rng.integers(-5, 5, n) / 7.0
        counts: dict = {}
        noise_stream.add_counts(counts, v)
        assert noise_stream.median_of_counts(counts) == float(np.median(v))


def test_pile_free_holds_for_every_noise():
    """Where pile_free says no pile for a noise interval, the whole-file pile test finds none at any
    noise in it; and it says so for no histogram the pile test flags."""
    rng = np.random.default_rng(4)
    seen = [0, 0]
    for _ in range(300):
        v = np.round(rng.normal(0, rng.uniform(0.5, 40), rng.integers(200, 3000))).astype(np.int64)
        v = np.concatenate([v, np.full(rng.integers(0, 40), v.max() + rng.integers(0, 30))])
        u, cnt = np.unique(v, return_counts=True)
        q = code_step(v)
        lo, hi = q / np.sqrt(12.0), float(rng.uniform(1, 30))
        free = bounded.pile_free(u, cnt, 1, q, lo, hi)
        found = [pile_level_counts(u, cnt, 1, s, q) is not None for s in np.linspace(lo, hi, 60)]
        seen[free] += 1
        if free:
            assert not any(found)
    assert min(seen) > 20        # both answers occur


@pytest.mark.parametrize("which", range(len(REAL)))
def test_real_recordings(capfd, tmp_path, monkeypatch, which):
    """Real recordings (../shared/data), made contract CSVs by convert, converted again with a stated scale in
    bounded memory: the whole-file bytes."""
    rec = real_as_contract(capfd, tmp_path, which)
    no_arrays(monkeypatch)
    same_as_whole(capfd, tmp_path, rec, ("--full-scale", "2"), blocks=(1000, 1 << 16, 1 << 30))


def real_as_contract(capfd, tmp_path, which: int):
    """REAL[which] (../shared/data) made a contract CSV by convert (its path); skips without the data."""
    path = shared_file(*REAL[which])
    if path is None:
        pytest.skip("no ../shared/data beside the repository")
    rec = tmp_path / "real.csv"
    rc, _, err, _ = run(["convert", path, "-o", rec, "--quiet"], capfd)
    assert rc == 0, err
    return rec


def test_held_counts_are_held_runs():
    """held_counts (runs counted chunk by chunk) gives held_runs' k and held_note's words: rows held
    for k rows, runs of uneven lengths, chance repeats of a quiet sensor, a run per pose."""
    rng = np.random.default_rng(6)
    told = set()
    for trial in range(120):
        n_runs = int(rng.integers(3, 400))
        kind = trial % 4
        if kind == 0:
            lengths = np.full(n_runs, int(rng.integers(2, 6)))
            lengths[rng.random(n_runs) < 0.1] += 1
        elif kind == 1:
            lengths = rng.integers(2, 5, n_runs)
        elif kind == 2:
            lengths = rng.geometric(0.7, n_runs)
        else:
            lengths = rng.integers(1, 40, n_runs)
        values = np.cumsum(rng.integers(1, 5, (n_runs, 3)), axis=0)
        if kind == 3:
            values[:, 1:] = 7                                   # one channel changes where a run ends
        raw = np.repeat(values, lengths, axis=0)
        n = raw.shape[0]
        k, first = held_runs(raw)
        runs = RunCounts()
        cut = np.sort(rng.choice(np.arange(1, n), size=min(n - 1, 5), replace=False))
        for part in np.split(raw, cut):
            runs.add(part)
        try:
            k2, inner, total = bounded.held_counts(runs, n, 3)
        except Fallback:
            continue
        assert k2 == k, trial
        told.add(k > 1)
        if k > 1:
            assert bounded.held_note_counts(k, inner, total, n, 50.0) == held_note(k, first, n, 50.0)
    assert told == {True, False}
