"""diagnose on a long recording cut down to about ``max_samples`` samples (``accelcal.io.thinned``),
read in bounded memory: evenly spaced windows with a reference f, every k-th sample jig-free.
The samples kept are the same from a file (CSV in chunks of any size, Parquet in batches) as from
the Recording held whole; every row is still checked; the diagnosis of what is kept names the
effect the independent generator put in; the JSON and the notes say what was kept."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import indep_model as im
from accelcal.diagnose import diagnose
from accelcal.errors import InputError
from accelcal.io import thinned as T
from accelcal.io.calibration import save_calibration
from accelcal.io.device import default_device, save_device
from accelcal.io.parquet import write_parquet_recording
from accelcal.io.recording import check_for_device, read_recording, write_recording
from accelcal.io.recording_type import Recording


def _json(res) -> str:
    out = dict(res)
    out.pop("elapsed_s")
    return json.dumps(out, sort_keys=True, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o))


@pytest.mark.parametrize("n,rate,m", [(10_001, 60.0, 10_000), (100_001, 60.0, 100_000), (10**7, 60.0, 100_000),
                                      (10**8, 1000.0, 100_000), (5_000, 100.0, 200), (123_457, 400.0, 3_000)])
def test_windows_are_at_most_the_budget_and_spread_evenly(n, rate, m):
    th = T.thinning(n, rate, m)
    assert th is not None and th.n_read == n
    keep = th.keep(0, n) if n <= 2 * 10**7 else None
    assert th.n_kept <= m and th.n_kept >= m - 2 * th.window       # the budget, less under two windows
    if keep is not None:
        assert int(keep.sum()) == th.n_kept
        assert keep[0]                                             # from the first sample
    j = np.flatnonzero(th.kept_windows(np.arange(th.windows)))
    assert j.size == th.kept and j[0] == 0
    gaps = np.diff(j)
    assert gaps.max() - gaps.min() <= 1                            # evenly spread over the recording
    assert j[-1] >= th.windows - 1 - gaps.max()                    # to its end
    lo, hi = (max(1, round(s * rate)) for s in T.WINDOW_S)
    assert min(lo, m // T.MIN_WINDOWS) <= th.window <= hi and th.kept >= T.MIN_WINDOWS


@pytest.mark.parametrize("m", [0, None, 10_000])
def test_no_thinning_at_or_under_the_budget_or_without_one(m):
    assert T.thinning(10_000, 60.0, m) is None
    rec = Recording(t=np.arange(500) / 60.0, raw=np.zeros((500, 3), np.int64))
    assert T.thin_recordings([rec], 60.0, m)[0] is rec


def test_max_samples_is_checked():
    for bad in (-1, 50, 1.5, True, "100"):
        with pytest.raises(ValueError, match="max_samples"):
            T.check_max_samples(bad)
    assert T.check_max_samples(0) == 0 and T.check_max_samples(100) == 100


@pytest.fixture(scope="module")
def drift_jig():
    """An independent-generator jig recording (labelled poses, a bias drift), 10^4-odd samples."""
    return im.make_jig(["bias_drift"], seed=3, n_poses=12, repeats=False, hold_s=12.0)


def test_file_windows_are_the_recordings_windows(drift_jig, tmp_path):
    dev, rec = drift_jig["device"], drift_jig["recording"]
    m = rec.n_samples // 4
    want = T.thin_recordings([read_recording(_csv(tmp_path, rec), dev.n_channels, whole=True)], dev.sample_rate_hz, m)[0]
    assert want.thinning is not None and want.n_samples < rec.n_samples // 3
    for block in (300, 4096, 1 << 16, 1 << 26):       # boundaries inside windows and inside the gaps
        got = T.read_thinned(tmp_path / "rec.csv", dev, m, block_bytes=block)
        assert got == want and got.thinning == want.thinning
        assert np.array_equal(got.lines, want.lines)  # each kept sample names its file line
    write_parquet_recording(tmp_path / "rec.parquet", rec)
    whole = read_recording(tmp_path / "rec.parquet", dev.n_channels)
    want_pq = T.thin_recordings([whole], dev.sample_rate_hz, m)[0]
    for rows in (7, 250, 1 << 20):
        got = T.read_thinned(tmp_path / "rec.parquet", dev, m, batch_rows=rows)
        assert got == want_pq and got.thinning == want_pq.thinning and np.array_equal(got.lines, want_pq.lines)


def _csv(tmp_path, rec):
    path = tmp_path / "rec.csv"
    write_recording(path, rec)
    return path


def test_a_plain_csv_is_thinned_while_read_not_read_whole(drift_jig, tmp_path, monkeypatch):
    """The bounded-memory route: the whole-file reader is not called for a plain CSV."""
    dev, rec = drift_jig["device"], drift_jig["recording"]
    path = _csv(tmp_path, rec)

    def whole(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr(T, "read_recording", whole)
    got = T.read_thinned(path, dev, rec.n_samples // 4)
    assert got.thinning is not None


def _bad_row_in_a_dropped_window(drift_jig, tmp_path, edit):
    dev, rec = drift_jig["device"], drift_jig["recording"]
    m = rec.n_samples // 4
    th = T.thinning(rec.n_samples, dev.sample_rate_hz, m)
    i = int(np.flatnonzero(~th.keep(0, rec.n_samples))[len(rec.t) // 3])    # a sample not kept
    path = _csv(tmp_path, rec)
    lines = path.read_text().splitlines(keepends=True)
    k = next(j for j, s in enumerate(lines) if s.startswith("t,")) + 1 + i      # the sample's line (0-based)
    lines[k] = edit(lines[k])
    path.write_text("".join(lines))
    with pytest.raises(InputError) as whole:
        check_for_device(read_recording(path, dev.n_channels, whole=True), dev, min_samples=2)
    with pytest.raises(InputError) as thin:
        T.read_thinned(path, dev, m, block_bytes=4096)
    assert str(thin.value) == str(whole.value)
    return str(thin.value), k + 1


def test_a_bad_cell_in_a_dropped_window_is_refused_as_whole(drift_jig, tmp_path):
    msg, line = _bad_row_in_a_dropped_window(drift_jig, tmp_path, lambda s: s.replace(",", ",x", 1))
    assert str(line) in msg


def test_a_reading_out_of_range_in_a_dropped_window_is_refused_as_whole(drift_jig, tmp_path):
    dev = drift_jig["device"]

    def out_of_range(s):
        cells = s.rstrip("\n").split(",")
        cells[1] = str(dev.raw_max + 5)
        return ",".join(cells) + "\n"
    msg, line = _bad_row_in_a_dropped_window(drift_jig, tmp_path, out_of_range)
    assert "outside" in msg and str(line) in msg


def test_diagnosis_of_the_windows_from_a_file_equals_from_the_recording(drift_jig, tmp_path):
    dev, cal, rec = drift_jig["device"], drift_jig["cal"], drift_jig["recording"]
    m = rec.n_samples // 3
    path = _csv(tmp_path, rec)
    from_file = diagnose(dev, cal, [path], max_samples=m)
    from_rec = diagnose(dev, cal, [read_recording(path, dev.n_channels, whole=True)], max_samples=m)
    assert _json(from_file) == _json(from_rec)
    th = from_file["recordings"][0]["thinned"]
    assert th["n_read"] == rec.n_samples and from_file["n_samples"] <= th["n_kept"] <= m     # n_samples: those used
    assert th["window_s"] * th["windows"] < th["spacing_s"] * th["windows"] <= rec.t[-1] - rec.t[0] + th["spacing_s"]
    assert sum("diagnosed on" in n for n in from_file["notes"]) == 1
    full = diagnose(dev, cal, [rec], max_samples=0)
    assert "thinned" not in full["recordings"][0] and full["recordings"][0]["n_samples"] == rec.n_samples
    assert from_file["recordings"][0]["n_samples"] == th["n_kept"]
    # the effect the generator put in is named from a third of the samples as from all of them
    assert from_file["verdict"] == full["verdict"] == "bias_drift"


def test_dropping_outlier_poses_keeps_the_thinning_said_once(drift_jig):
    dev, cal, rec = drift_jig["device"], drift_jig["cal"], drift_jig["recording"]
    res = diagnose(dev, cal, [rec], max_samples=rec.n_samples // 3, outliers="drop")
    assert "thinned" in res["recordings"][0]
    assert sum("diagnosed on" in n for n in res["notes"]) == 1


def test_cli_max_samples(drift_jig, tmp_path):
    dev, rec = drift_jig["device"], drift_jig["recording"]
    path = _csv(tmp_path, rec)
    save_device(dev, tmp_path / "dev.json")
    save_calibration(drift_jig["cal"], tmp_path / "cal.json")
    base = [sys.executable, "-m", "accelcal.cli.main", "diagnose", "--device", str(tmp_path / "dev.json"), "--calibration",
            str(tmp_path / "cal.json"), str(path), "--quiet", "--json"]
    bad = subprocess.run(base + [str(tmp_path / "bad.json"), "--max-samples", "50"], capture_output=True, text=True)
    last = bad.stderr.strip().splitlines()[-1]        # argparse's usage, then the one line
    assert bad.returncode == 2 and "--max-samples" in last and "at least 100, got 50" in last
    assert not (tmp_path / "bad.json").exists()
    ok = subprocess.run(base + [str(tmp_path / "d.json"), "--max-samples", str(rec.n_samples // 3)],
                        capture_output=True, text=True)
    assert ok.returncode == 0, ok.stderr
    d = json.loads((tmp_path / "d.json").read_text())
    assert d["recordings"][0]["thinned"]["n_read"] == rec.n_samples


def test_default_budget_leaves_the_shared_recordings_whole(real_model):
    """The real recordings of ../shared/data are under the default budget: diagnosed on every sample."""
    for name in ("mpu6050", "xsens"):
        dev, rec, step, cal = real_model(name)
        assert rec.n_samples <= T.MAX_SAMPLES
        assert T.thin_recordings([rec], dev.sample_rate_hz, T.MAX_SAMPLES)[0] is rec
    assert default_device().sample_rate_hz > 0


@pytest.mark.parametrize("effect,seed", [("misalignment", 5), ("nonlinearity", 3)])
def test_jigfree_keeps_every_kth_sample_of_every_pose(effect, seed, tmp_path):
    """Jig-free (no reference f): every pose's orientation counts, so every k-th sample is kept
    (a recording at rate / k), not windows (windows of a hand-held session lose most of its
    2-4 s poses: this case was named ``gain`` from windows of a third of the samples)."""
    ds = im.make_handheld([effect], seed, n_poses=60, labels=False)
    dev, cal, rec = ds["device"], ds["cal"], ds["recording"]
    m = rec.n_samples // 3
    path = _csv(tmp_path, rec)
    got = T.read_thinned(path, dev, m, block_bytes=1 << 14)
    k = -(-rec.n_samples // m)
    assert got.thinning.step == k and np.array_equal(got.t, rec.t[::k]) and np.array_equal(got.raw, rec.raw[::k])
    res = diagnose(dev, cal, [path], max_samples=m)
    assert res["recordings"][0]["thinned"] == {"n_read": rec.n_samples, "n_kept": len(rec.t[::k]), "every": k,
                                               "rate_hz": dev.sample_rate_hz / k}
    assert res["mode"] == "jigfree" and res["verdict"] == effect
    assert _json(res) == _json(diagnose(dev, cal, [read_recording(path, dev.n_channels, whole=True)], max_samples=m))


def test_jigfree_plan_one_k_for_all_recordings_down_to_min_rate_then_windows():
    short, long_ = T.plan([(50_000, False), (300_000, False)], 100.0, 100_000)
    assert short.step == long_.step == 3 and not short.windowed and not long_.windowed
    assert long_.n_kept == 100_000 and short.n_kept == 16_667
    (th,) = T.plan([(10**7, False)], 60.0, 100_000)
    assert th.step == int(60.0 / T.MIN_RATE_HZ) and th.windowed and th.n_kept <= 100_000
    keep = th.keep(0, 10**6)
    assert np.all(np.flatnonzero(keep) % th.step == 0)
    (ref,) = T.plan([(10**7, True)], 60.0, 100_000)       # with a reference: windows of full-rate samples
    assert ref.step == 1 and ref.windowed
    assert T.plan([(90_000, False), (80_000, True)], 60.0, 100_000) == [None, None]
