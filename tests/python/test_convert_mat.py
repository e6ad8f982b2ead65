"""``accelcal convert`` of MATLAB files (format ``mat``), both layouts MATLAB writes: version 5
(scipy.io) and 7.3 (HDF5 with MATLAB's 512-byte header block, arrays stored transposed), as
two public recordings hold their readings (a phone's LIS3DH in m/s^2; an MPU-6050's t, x, y,
z in g).  The files are written here from known counts."""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest
import scipy.io

from accelcal.io.recording import read_recording
from cli_run import run

LSB_G = 1.0 / 4096                      # +-8 g at 16 bits


def _counts(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.round([30.0, -20.0, 4096.0] + 12.0 * rng.standard_normal((n, 3))).astype(int)


def write_v73(path, arrays):
    """A MATLAB 7.3 file: HDF5 behind a 512-byte block that begins with MATLAB's header."""
    with h5py.File(path, "w", userblock_size=512) as f:
        for name, a in arrays.items():
            f[name] = np.asarray(a, float).T          # MATLAB's column-major array, as HDF5 holds it
    head = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Thu Nov 26 10:00:00 2026 HDF5 schema 1.00 ."
    with open(path, "r+b") as f:
        f.write(head.ljust(128, b" "))


def _convert(tmp_path, capfd, src, *args):
    out, dev = tmp_path / "o.csv", tmp_path / "d.json"
    rc, said, err, _ = run(["convert", src, *args, "-o", out, "--device-out", dev], capfd)
    assert rc == 0, err
    assert said.startswith("mat: ")
    return read_recording(out), json.loads(dev.read_text()), err


@pytest.mark.parametrize("layout", ["v5", "v7.3"])
def test_t_x_y_z_in_g(tmp_path, capfd, layout):
    c, rate = _counts(300), 100.0
    a = np.column_stack([np.arange(300) / rate, c * LSB_G])
    src = tmp_path / "accel.mat"
    if layout == "v5":
        scipy.io.savemat(src, {"accelBuffer": a})
    else:
        write_v73(src, {"accelBuffer": a})
    rec, dev, _ = _convert(tmp_path, capfd, src, "--units", "g", "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    np.testing.assert_allclose(rec.t, a[:, 0])
    assert dev["sample_rate_hz"] == pytest.approx(rate) and rec.metadata["mat.variable"] == "accelBuffer"


@pytest.mark.parametrize("layout", ["v5", "v7.3"])
def test_three_columns_need_a_rate_and_several_arrays_a_name(tmp_path, capfd, layout):
    c = _counts(200, seed=1)
    src = tmp_path / "phone.mat"
    arrays = {"acc": c * 9.80665 * LSB_G, "gyro": np.zeros((200, 3)), "note": np.ones((1, 2))}
    scipy.io.savemat(src, arrays) if layout == "v5" else write_v73(src, arrays)
    out = tmp_path / "out"
    out.mkdir()
    rc, _, err, _ = run(["convert", src, "--units", "mps2", "--full-scale", "8", "--rate", "50", "-o", out / "o.csv"],
                        capfd)
    assert rc == 2 and "2 arrays (acc, gyro)" in err and "--variable NAME" in err and not list(out.iterdir())
    rc, _, err, _ = run(["convert", src, "--units", "mps2", "--full-scale", "8", "--variable", "acc", "-o",
                         out / "o.csv"], capfd)
    assert rc == 2 and "no time column" in err and "--rate" in err
    rec, dev, _ = _convert(tmp_path, capfd, src, "--units", "mps2", "--full-scale", "8", "--rate", "50",
                           "--variable", "acc")
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["sample_rate_hz"] == 50.0


def test_a_text_file_is_not_a_mat_file(tmp_path, capfd):
    src = tmp_path / "a.csv"
    src.write_text("t,raw_0,raw_1,raw_2\n0,1,2,3\n")
    rc, _, err, _ = run(["convert", src, "--format", "mat", "-o", tmp_path / "o.csv"], capfd)
    assert rc == 2 and "does not begin with a MATLAB header" in err
    rc, _, err, _ = run(["convert", src, "--variable", "x", "-o", tmp_path / "o.csv"], capfd)
    assert rc == 2 and "--variable names an array of a MATLAB file" in err


def test_time_stamps_that_go_back_are_refused_naming_the_row(tmp_path, capfd):
    c = _counts(50, seed=2)
    t = np.arange(50) / 100.0
    t[20] = t[19]
    src = tmp_path / "a.mat"
    scipy.io.savemat(src, {"buf": np.column_stack([t, c * LSB_G])})
    rc, _, err, _ = run(["convert", src, "--units", "g", "--full-scale", "8", "-o", tmp_path / "o.csv"], capfd)
    assert rc == 2 and "row 21, column buf(:,1)" in err and "must increase" in err


def _bad_checksums(path):
    """Break the adler32 checksum of every compressed element of a version-5 MAT-file (some
    acquisition programs write them wrong; MATLAB ignores them, zlib refuses them)."""
    data = bytearray(path.read_bytes())
    pos, broken = 128, 0
    while pos + 8 <= len(data):
        kind, size = np.frombuffer(bytes(data[pos:pos + 8]), "<u4")
        if kind == 15:
            data[pos + 8 + size - 1] ^= 0xFF
            broken += 1
        pos += 8 + int(size) + (0 if kind == 15 else (-int(size)) % 8)
    path.write_bytes(bytes(data))
    return broken


def test_a_file_with_wrong_zlib_checksums_is_read_as_matlab_reads_it(tmp_path, capfd):
    """A DAQ program's MAT-file whose compressed elements fail their adler32 check: convert
    had stopped with 'internal error: Error -3 while decompressing data', exit 3.  It reads
    them as MATLAB does, with a note; data that do not inflate stay one line naming the file."""
    c, rate = _counts(120, seed=5), 80.0
    src = tmp_path / "daq.mat"
    scipy.io.savemat(src, {"acc": np.column_stack([np.arange(120) / rate, c * LSB_G])}, do_compression=True)
    assert _bad_checksums(src) == 1
    rec, dev, err = _convert(tmp_path, capfd, src, "--units", "g", "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    assert "fail their zlib checksum" in err and "as MATLAB reads them" in err
    data = bytearray(src.read_bytes())
    data[150:170] = b"\xff" * 20                       # the deflate stream itself damaged
    src.write_bytes(bytes(data))
    rc, _, err, _ = run(["convert", src, "--units", "g", "--full-scale", "8", "-o", tmp_path / "x.csv"], capfd)
    assert rc == 2 and err.startswith("accelcal convert: error: ") and "daq.mat" in err and "cannot read the MATLAB" \
        in err and len(err.splitlines()) == 1, err
    assert not (tmp_path / "x.csv").exists()


def test_readings_held_one_vector_per_channel_are_put_side_by_side(tmp_path, capfd):
    """A data-acquisition export of one 1xn vector per channel (time and amplitude of each):
    --variable T,X,Y,Z names the vectors; without it the refusal says so and lists at most 8
    of the arrays; vectors of different lengths are refused naming them."""
    c, rate = _counts(90, seed=6), 80.0
    arrays = {f"Canal_{k}_g_{part}": (np.arange(90) / rate if part == "Tempo" else c[:, k % 3] * LSB_G)[None, :]
              for k in range(6) for part in ("Tempo", "Amplitude")}
    src = tmp_path / "daq.mat"
    scipy.io.savemat(src, arrays)
    names = "Canal_0_g_Tempo,Canal_0_g_Amplitude,Canal_1_g_Amplitude,Canal_2_g_Amplitude"
    rec, dev, _ = _convert(tmp_path, capfd, src, "--variable", names, "--units", "g", "--full-scale", "8")
    np.testing.assert_array_equal(rec.raw, c)
    assert dev["sample_rate_hz"] == pytest.approx(rate)
    rc, _, err, _ = run(["convert", src, "--units", "g", "--full-scale", "8", "-o", tmp_path / "x.csv"], capfd)
    assert rc == 2 and "--variable X,Y,Z (T,X,Y,Z)" in err and "and 4 more" in err, err
    scipy.io.savemat(src, {**arrays, "Canal_2_g_Amplitude": arrays["Canal_2_g_Amplitude"][:, :80]})
    rc, _, err, _ = run(["convert", src, "--variable", names, "--units", "g", "--full-scale", "8",
                         "-o", tmp_path / "x.csv"], capfd)
    assert rc == 2 and "the vectors differ in length" in err and "Canal_2_g_Amplitude 80" in err, err


def _elements(path):
    """A version-5 MAT-file's data elements (everything after its 128-byte header)."""
    return path.read_bytes()[128:]


def test_the_readers_warnings_become_one_note(tmp_path, capfd):
    """A robot lab's files repeat a variable name (scipy's MatReadWarning, 3 lines with a
    site-packages path, had reached stderr on every conversion): caught, and said as one note
    where the name is one of the arrays read.  An ABB robot's 4xN quaternion, whose first row
    is no time, is no t, x, y, z candidate: the 3xN readings are the only array."""
    c = _counts(200, seed=7)
    quat = np.vstack([np.cos(np.linspace(0, 1, 200)), np.zeros((2, 200)), np.sin(np.linspace(0, 1, 200))])
    quat[0, 100:] = quat[0, :100]                    # w: not increasing
    one, two = tmp_path / "one.mat", tmp_path / "two.mat"
    scipy.io.savemat(one, {"SENSacc": (c * LSB_G).T, "ABBquaternion": quat})
    scipy.io.savemat(two, {"SENSacc": (c * LSB_G).T})
    src = tmp_path / "MPU6050RM3100.mat"
    src.write_bytes(one.read_bytes() + _elements(two))       # SENSacc twice
    out, dev = tmp_path / "o.csv", tmp_path / "d.json"
    rc, said, err, caught = run(["convert", src, "--units", "g", "--lsb", repr(LSB_G), "--rate", "100", "-o", out,
                                 "--device-out", dev], capfd)
    assert rc == 0 and not caught and "Warning" not in err, err
    assert "note: the file holds more than one variable named 'SENSacc': the last of them is read" in err
    np.testing.assert_array_equal(read_recording(out).raw, c)
    assert json.loads(dev.read_text())["sample_rate_hz"] == 100.0
