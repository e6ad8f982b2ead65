"""calibrate on a labelled recording reduced while it is read (accelcal.calibrate.pose_stream;
docs/streaming.md): the pose statistics and the calibration against the whole-file path.

The recordings come from the independent generator's seed6 device with a stated noise, poses at
Fibonacci directions with noise and rounding, swings between them (numpy here, not
accelcal.simulate)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from accelcal.calibrate import calibrate_recordings
from accelcal.calibrate.pose_stream import reduce_labelled
from accelcal.cli import main as cli_main
from accelcal.io.device import save_device
from accelcal.io.recording import read_recording, recording_from_arrays, write_recording
from accelcal.readings.static import poses_from_recording

from cli_run import spy
from indep_model import seed6, true_parameters

P = 12


def directions(n):
    i = np.arange(n) + 0.5
    z = 1 - 2 * i / n
    phi = np.pi * (1 + 5 ** 0.5) * i
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], 1)


def device():
    return dataclasses.replace(seed6(), noise_mps2=0.02)


def labelled(dev, rng, hold=(37, 90), move=23, ref=True, temps=True):
    """Poses of ``hold`` samples (a range: not multiples of 8) joined by swings; (t, raw, f, pose, temp)."""
    p = true_parameters(dev, rng)
    F = directions(P) * dev.gravity_mps2
    fs, pose, tc = [], [], []
    for k in range(P):
        h = int(rng.integers(*hold))
        fs.append(np.repeat(F[k][None], h, 0))
        pose.append(np.full(h, k))
        tc.append(np.full(h, 20.0 + k))
        u = np.linspace(0, 1, move + 2)[1:-1, None]
        fs.append((1 - u) * F[k] + u * F[(k + 1) % P] + 4.0 * np.sin(np.pi * u) * np.array([1.0, -0.7, 0.4]))
        pose.append(np.full(move, -1))
        tc.append(np.full(move, 20.0 + k))
    f = np.vstack(fs)
    pose = np.concatenate(pose)
    x = p["b"] + f @ p["S"].T + rng.normal(0, 0.02 * dev.counts_per_mps2, (f.shape[0], 6))
    raw = np.clip(np.rint(x), dev.raw_min, dev.raw_max).astype(np.int64)
    t = np.arange(raw.shape[0]) / dev.sample_rate_hz
    kw = {"pose": pose}
    if ref:
        kw["f"] = np.where((pose >= 0)[:, None], F[np.maximum(pose, 0)], np.nan)
    if temps:
        kw["temp_c"] = np.concatenate(tc)
    return recording_from_arrays(t, raw, **kw)


@pytest.mark.parametrize("block", [300, 1000, 4096])
@pytest.mark.parametrize("ref", [True, False])
def test_reduced_poses_equal_the_whole_file_ones(tmp_path, block, ref):
    """Means, counts, std, code steps bit for bit; f_ref and temp within 1e-12 relative, the colour
    ratios within 1e-9;
    chunk boundaries fall inside poses and inside swings (blocks of 300 B to 4 KiB, ~40-byte rows)."""
    dev = device()
    rec = labelled(dev, np.random.default_rng(5), ref=ref)
    path = tmp_path / "r.csv"
    write_recording(path, rec)
    red = reduce_labelled(path, dev, block_bytes=block)
    assert red is not None
    whole = poses_from_recording(read_recording(path, 6), dev)
    got = red.poses
    assert np.array_equal(got.means, whole.means) and np.array_equal(got.n, whole.n)
    assert np.array_equal(got.std, whole.std)
    assert np.array_equal(got.step, whole.step)
    # the whole-file ratios come from float means of readings ~5000 counts (measured: 1.6e-10 relative
    # off the exact integer sums used here)
    np.testing.assert_allclose(got.colour_r2, whole.colour_r2, rtol=1e-9)
    np.testing.assert_allclose(got.f_ref, whole.f_ref, rtol=1e-12)
    np.testing.assert_allclose(got.temp, whole.temp, rtol=1e-12)
    assert got.info == whole.info
    assert red.n_samples == rec.n_samples


def test_calibration_from_the_reduced_path_equals_the_whole_file_one(tmp_path):
    """Every parameter within 1e-12 relative (measured: 0, the same floats: the pose means and std
    are bit-identical), jig-free and known poses."""
    dev = device()
    for ref in (True, False):
        rec = labelled(dev, np.random.default_rng(11), ref=ref, temps=False)
        path = tmp_path / f"r{ref}.csv"
        write_recording(path, rec)
        red = reduce_labelled(path, dev, block_bytes=2000)
        a = calibrate_recordings(dev, [red])
        b = calibrate_recordings(dev, [read_recording(path, 6)])
        for name in ("offsets", "sensitivity"):
            x, y = np.asarray(getattr(a, name)), np.asarray(getattr(b, name))
            assert np.max(np.abs(x - y) / np.maximum(np.abs(y), 1e-300)) <= 1e-12, name


def test_unlabelled_or_moving_goes_the_whole_file_way(tmp_path):
    """No pose labels (the static detector needs the samples): None, the caller reads the file."""
    dev = device()
    rec = labelled(dev, np.random.default_rng(3))
    rec2 = recording_from_arrays(rec.t, rec.raw)
    path = tmp_path / "u.csv"
    write_recording(path, rec2)
    assert reduce_labelled(path, dev) is None


def run_cli(args, capsys):
    code = cli_main.main(args)
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("stated", [True, False])
def test_cli_json_equals_the_whole_file_one(tmp_path, capsys, monkeypatch, stated):
    """accelcal calibrate on two labelled recordings (CSV and Parquet): the reduced path is taken
    (its reader is called and returns poses) and the written calibration, stdout and stderr equal
    the whole-file command's (reduced path disabled) byte for byte; the device's noise_mps2 stated,
    or not (the noise estimated from the data in a third pass: pose_stream.data_noise)."""
    dev = device() if stated else dataclasses.replace(device(), noise_mps2=0.0)
    dpath = tmp_path / "dev.json"
    save_device(dev, dpath)
    paths = []
    for k, name in enumerate(("a.csv", "b.parquet")):
        p = tmp_path / name
        write_recording(p, labelled(dev, np.random.default_rng(20 + k), temps=False))
        paths.append(str(p))
    calls = spy(monkeypatch, cli_main, "reduced_recordings")
    got = run_cli(["calibrate", "--device", str(dpath), *paths, "-o", str(tmp_path / "r.json")], capsys)
    assert calls and calls[0] is not None and len(calls[0]) == 2
    monkeypatch.setattr(cli_main, "reduced_recordings", lambda *args: None)
    whole = run_cli(["calibrate", "--device", str(dpath), *paths, "-o", str(tmp_path / "w.json")], capsys)
    assert got[0] == whole[0] == 0
    assert got[1].replace("r.json", "w.json") == whole[1] and got[2] == whole[2]
    assert (tmp_path / "r.json").read_bytes() == (tmp_path / "w.json").read_bytes()


def test_held_readings_go_the_whole_file_way(tmp_path):
    """Each reading held for two rows (a logger faster than the sensor): the whole-file path counts
    them once (readings.held), so the reduced reader leaves them to it; the same recording not held
    reduces."""
    dev = device()
    rec = labelled(dev, np.random.default_rng(4))
    n = rec.n_samples // 2 * 2
    held = recording_from_arrays(rec.t[:n], np.repeat(rec.raw[:n:2], 2, axis=0), pose=rec.pose[:n], f=rec.f[:n])
    path = tmp_path / "h.csv"
    write_recording(path, held)
    assert reduce_labelled(path, dev) is None
    write_recording(path, recording_from_arrays(rec.t[:n], rec.raw[:n], pose=rec.pose[:n], f=rec.f[:n]))
    assert reduce_labelled(path, dev) is not None


def test_a_reading_outside_the_range_goes_the_whole_file_way(tmp_path):
    """A reading outside the device's range: None (the whole-file reader words the error), not an
    internal error."""
    dev = device()
    rec = labelled(dev, np.random.default_rng(6))
    raw = rec.raw.copy()
    raw[50, 2] = dev.raw_max + 5
    path = tmp_path / "o.csv"
    write_recording(path, recording_from_arrays(rec.t, raw, pose=rec.pose, f=rec.f))
    assert reduce_labelled(path, dev, block_bytes=1000) is None


def test_rotating_samples_go_the_whole_file_way(tmp_path):
    """Samples with f, w, dw given and |w| above ROTATION_MIN_RADPS (the lever arms take them): None;
    the same recording with w = 0 reduces."""
    dev = device()
    rec = labelled(dev, np.random.default_rng(8))
    f = np.where(np.isfinite(rec.f), rec.f, 0.0)
    w = np.zeros_like(f)
    for spin, want_none in ((0.0, False), (0.3, True)):
        w[rec.pose < 0, 2] = spin
        path = tmp_path / f"w{spin}.csv"
        write_recording(path, recording_from_arrays(rec.t, rec.raw, pose=rec.pose, f=f, w=w, dw=np.zeros_like(f)))
        assert (reduce_labelled(path, dev, block_bytes=1500) is None) == want_none
