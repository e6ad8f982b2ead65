"""convert of a recording CSV without a stated scale in bounded memory (accelcal.convert.bounded_scale,
accelcal.readings.still_stream; docs/streaming.md, "convert without a stated scale"): the nominal scale from the static detector's
still stretches found over passes in chunks, the output, device file, notes and summary the
whole-file command's byte for byte at chunks of one row to more than the file (boundaries inside
still stretches and inside motions); where the passes cannot give the detector's answer, the arrays
path runs (the same bytes)."""
from __future__ import annotations

import importlib

import numpy as np
import pytest

from accelcal.readings import still_stream
from accelcal.convert.nominal_device import triad_device
from accelcal.io.chunks import Fallback
from accelcal.io.recording import Recording, write_recording
from accelcal.readings.noise import MAD_TO_STD, code_step, estimate_noise, nyquist_tone
from accelcal.readings.static import detect_static
from accelcal.readings.steps import logger_steps
from accelcal.readings.still_stream import DiffSums, LoggerBound, percentiles_of_counts

from cli_run import run
from indep_model import make_handheld
from shared_data import shared_file
from test_stream_convert import poses
from test_stream_convert_bounded import REAL, real_as_contract, same_as_whole, write_common_cases

# accelcal.convert is also a function of the package's top: the module by its name
stream = importlib.import_module("accelcal.convert.stream")


def arrays_counted(monkeypatch) -> list:
    """The arrays path's first pass, counted where it is called."""
    called: list = []
    arrays = stream.first_pass

    def counted(*a, **k):
        called.append(1)
        return arrays(*a, **k)
    monkeypatch.setattr(stream, "first_pass", counted)
    return called


def no_arrays(monkeypatch):
    def fail(*a, **k):
        raise AssertionError("the first pass kept the arrays")
    monkeypatch.setattr(stream, "first_pass", fail)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("scale_convert")
    write_common_cases(d, (31, 32, 33, 34, 35))
    hand = make_handheld(seed=3, device="triad16", rate=100.0, n_poses=8, labels=False)["recording"]
    write_recording(d / "handheld.csv", Recording(t=hand.t, raw=hand.raw))   # smooth turns between the poses
    quiet = poses(1800, 36)
    quiet.raw[:] = quiet.raw[0]                                     # no range: the scale is a guess
    write_recording(d / "flat.csv", Recording(t=quiet.t, raw=quiet.raw))
    moving = np.round(2048 + 900 * np.sin(np.arange(1800)[:, None] / np.array([7.0, 11.0, 13.0]))).astype(np.int64)
    write_recording(d / "moving.csv", Recording(t=np.arange(1800) / 100.0, raw=moving))   # no still stretch
    # fallbacks: a tone at half the rate; a logger's static blocks joined by instant steps
    rng = np.random.default_rng(38)
    tone = np.round(2048 + np.array([0, 0, 4096]) + rng.normal(0, 6, (1800, 3))).astype(np.int64)
    tone[:, 0] += np.where(np.arange(1800) % 2 == 0, 30, -30)      # mains aliased to half the rate
    write_recording(d / "tone.csv", Recording(t=np.arange(1800) / 100.0, raw=tone))
    dirs = np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 0, -1], [0, -1, 0], [-1, 0, 0]], float)
    blocks = np.round(np.repeat(dirs[np.arange(12) % 6] * 4096, 150, axis=0) + rng.normal(0, 6, (1800, 3)))
    write_recording(d / "blocks.csv", Recording(t=np.arange(1800) / 100.0, raw=blocks.astype(np.int64) + 2048))
    inner = poses(1800, 39)
    inner.raw[150:300] += 35                                        # an instant step of 6 x the noise in a pose
    write_recording(d / "inner_step.csv", Recording(t=inner.t, raw=inner.raw))
    return d


#: (file, options): each goes the bounded way without a stated scale
CASES = [("plain", ()), ("labelled", ()), ("handheld", ()), ("rail", ("--bits", "16")), ("pile", ()),
         ("held", ()), ("ms", ()), ("flat", ()), ("moving", ()), ("plain", ("--rate", "101"))]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_no_scale_bounded_gives_the_whole_file_bytes(files, capfd, tmp_path, monkeypatch, case):
    """On the code before, a recording CSV without a stated scale kept the first pass's arrays: the
    arrays path made to fail fails there."""
    name, args = CASES[case]
    no_arrays(monkeypatch)
    err = same_as_whole(capfd, tmp_path, files / f"{name}.csv", args)
    words = {"flat": "span no range", "moving": "spread, 1st to 99th percentile", "pile": "a pile inside the range",
             "rail": "raw_max", "held": "repeat the row before", "ms": "t read in ms"}
    assert words.get(name, "still stretches over g") in err, err


def test_fallbacks_give_the_same_bytes(files, capfd, tmp_path, monkeypatch):
    """A tone at half the rate, a logger's blocks, a still stretch not held (longer than
    MAX_STILL_ROWS) with a candidate instant step in it: the arrays path runs (the rules of
    docs/streaming.md) and gives the whole-file bytes."""
    called = arrays_counted(monkeypatch)
    for name in ("tone", "blocks"):
        called.clear()
        same_as_whole(capfd, tmp_path, files / f"{name}.csv", (), blocks=(97, 1 << 30))
        assert called, name
    monkeypatch.setattr(still_stream, "MAX_STILL_ROWS", 0)
    called.clear()
    same_as_whole(capfd, tmp_path, files / "inner_step.csv", (), blocks=(97, 1 << 30))
    assert called


@pytest.mark.parametrize("name", ("plain", "labelled", "handheld"))
def test_long_stretches_not_held(files, capfd, tmp_path, monkeypatch, name):
    """Every run of static blocks longer than MAX_STILL_ROWS (0 here: none held; 2^18 rows by
    default): kept as its end rows, a subsample and sums (LongRun), the whole-file bytes still."""
    monkeypatch.setattr(still_stream, "MAX_STILL_ROWS", 0)
    no_arrays(monkeypatch)
    err = same_as_whole(capfd, tmp_path, files / f"{name}.csv", (), blocks=(97, 4096, 1 << 30))
    assert "still stretches over g" in err


@pytest.mark.parametrize("which", range(len(REAL)))
def test_real_recordings_without_scale(capfd, tmp_path, monkeypatch, which):
    """Real recordings (../shared/data: imu_tk's Xsens log, the two MPU-6050 logs) made contract CSVs by
    convert, converted again without a stated scale in bounded memory: the whole-file bytes."""
    rec = real_as_contract(capfd, tmp_path, which)
    no_arrays(monkeypatch)
    err = same_as_whole(capfd, tmp_path, rec, (), blocks=(1000, 1 << 16, 1 << 30))
    assert "still stretch" in err


def test_ck_explorer_blocks_fall_back(capfd, tmp_path, monkeypatch):
    """CK-Explorer's 160 hand-placed poses (a logger of static blocks, in g) in counts: the logger's
    blocks take the samples, so the arrays path runs; the whole-file bytes."""
    path = shared_file("ckexplorer_160poses", "acc_log.csv.gz")
    if path is None:
        pytest.skip("no ../shared/data beside the repository")
    rec = tmp_path / "ck.csv"
    rc, _, err, _ = run(["convert", path, "-o", rec, "--units", "g", "--lsb", "0.00006103515625g", "--rate", "100",
                         "--quiet"], capfd)
    assert rc == 0, err
    called = arrays_counted(monkeypatch)
    same_as_whole(capfd, tmp_path, rec, (), blocks=(1 << 16,))
    assert called


def chunked(raw: np.ndarray, rng) -> list:
    cuts = np.sort(rng.choice(np.arange(1, raw.shape[0]), size=min(raw.shape[0] - 1, 9), replace=False))
    return np.split(raw, cuts)


@pytest.mark.parametrize("hold", (None, 0, 150))
def test_still_stretches_are_detect_statics(monkeypatch, hold):
    """still_stretches over chunks cut anywhere gives detect_static's intervals (poses with motions,
    small instant steps inside poses, hand-held turns of the independent generator) and numpy's
    means of them; with runs held (``hold`` None: 2^18 rows) or not (longer than 0 or 150 rows: a
    LongRun, which falls back only where a step may split it)."""
    if hold is not None:
        monkeypatch.setattr(still_stream, "MAX_STILL_ROWS", hold)
    rng = np.random.default_rng(41)
    seen, fell = 0, 0
    for trial in range(15):
        if trial % 3 == 2:
            rec = make_handheld(seed=trial, device="triad16", rate=100.0, n_poses=6, labels=False)["recording"]
            raw = rec.raw.astype(np.int64)
        else:
            raw = poses(int(rng.integers(900, 3000)), 50 + trial).raw
            if trial % 3 == 1:
                raw[400:550] += int(rng.integers(20, 40))          # an instant step inside a pose
        n = raw.shape[0]
        probe = triad_device("csv-triad", 100.0, 9.80665, 16, False, 400.0)
        hists = [np.unique(raw[:, i], return_counts=True) for i in range(3)]
        diffs = DiffSums()
        parts = chunked(raw, rng)
        for part in parts:
            diffs.add(part)

        def passes(*feeds):
            for part in chunked(raw, rng):
                for feed in feeds:
                    feed(part)
        try:
            out, means, noise = still_stream.still_stretches(passes, n, probe, hists, diffs)
        except Fallback:
            fell += 1
            continue
        sig = estimate_noise(raw, 50, integer=True)
        assert np.array_equal(noise, sig)
        want = detect_static(Recording(t=np.arange(n) / 100.0, raw=raw), probe, noise=sig)
        assert out == want, trial
        for (a, b), m in zip(out, means):
            assert np.array_equal(m, raw[a:b].mean(axis=0))
        seen += bool(out)
    assert seen >= 9
    assert (fell > 0) == (hold is not None)      # held runs never fall back; some not held hold a step


def test_percentiles_of_counts_are_numpys():
    rng = np.random.default_rng(42)
    for n in (1, 2, 3, 99, 100, 101, 1000, 12345):
        for _ in range(5):
            x = rng.integers(-3000, 3000, n) if n % 2 else np.round(rng.normal(0, 40, n)).astype(np.int64)
            u, c = np.unique(x, return_counts=True)
            assert np.array_equal(percentiles_of_counts(u, c), np.percentile(x, [1.0, 99.0]))


def test_diff_sums_are_the_whole_arrays():
    """The tone test and the changes' robust std from sums kept chunk by chunk: nyquist_tone's and
    logger_steps' floats."""
    rng = np.random.default_rng(43)
    tones = set()
    for trial in range(40):
        n = int(rng.integers(3, 2000))
        raw = np.round(rng.normal(0, rng.uniform(0.5, 20), (n, 3))).astype(np.int64) + 1000
        if trial % 2:
            raw[:, 1] += np.where(np.arange(n) % 2 == 0, 25, -25)
        s = DiffSums()
        for part in chunked(raw, rng) if n > 1 else [raw]:
            s.add(part)
        tone = s.tone()
        assert np.array_equal(tone, nyquist_tone(raw)), trial
        tones.add(bool(tone.any()))
        d = np.diff(raw.astype(float), axis=0)
        if n > 1:
            want = np.maximum(MAD_TO_STD * np.median(np.abs(d - np.median(d, axis=0)), axis=0), 1.0)
            assert np.array_equal(s.change_std(), want)
    assert tones == {True, False}


def test_logger_bound_holds():
    """Where LoggerBound says no logger, logger_steps finds none; blocks joined by instant steps are
    told as maybe a logger."""
    rng = np.random.default_rng(44)
    said = set()
    for trial in range(60):
        kind = trial % 3
        if kind == 0:
            raw = poses(int(rng.integers(600, 2400)), 60 + trial).raw
        elif kind == 1:
            k = int(rng.integers(3, 12))
            lv = rng.integers(-4000, 4000, (k, 3))
            raw = np.repeat(lv, rng.integers(40, 200, k), axis=0) + np.round(rng.normal(0, 5, (1, 3))).astype(np.int64)
            raw = raw + np.round(rng.normal(0, 5, raw.shape)).astype(np.int64)
        else:
            raw = np.round(rng.normal(0, 5, (int(rng.integers(100, 1500)), 3))).astype(np.int64)
            raw[rng.integers(0, raw.shape[0], 6)] += 500                # lone spikes
        n = raw.shape[0]
        w = int(rng.integers(3, 60))
        s = DiffSums()
        s.add(raw)
        sig = np.array([code_step(raw[:, i]) for i in range(3)], float) * 3.0
        lb = LoggerBound(n, s.change_std(), max(2, w // 4))
        for part in chunked(raw, rng):
            lb.add(part)
        maybe = lb.maybe_logger()
        said.add(maybe)
        if not maybe:
            assert logger_steps(raw, sig, w) is None, trial
    assert said == {True, False}
