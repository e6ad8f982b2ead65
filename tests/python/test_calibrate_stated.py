"""Known poses whose readings contradict their stated f, refused before the fit
(accelcal.calibrate.stated_poses): a six-position session with one pose mislabelled, the
device file's axis reversed or its channels swapped; and the bound that keeps a device within
its description (any zero-g offset, gains within device.NOMINAL_FACTOR) from being refused.

Data: a six-position session of an MPU-type triad in int16 counts (+-2 g), one recording a
pose, each written as accelcal convert --regions --stated-f writes it (a 'pose' column, f on
it, the label's name in the ``pose_names`` metadata), as Aniruddh5502/3D-Mouse's was.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from accelcal import model
from accelcal.calibrate.stated_poses import MISLABEL_SLACK_DEG, allowed_deg, reading_angles
from accelcal.io.device import NOMINAL_FACTOR, default_triad, save_device
from accelcal.io.recording import recording_from_arrays, write_recording

from cli_run import run

FACES = {"x_p": (1, 0, 0), "x_a": (-1, 0, 0), "y_p": (0, 1, 0), "y_a": (0, -1, 0), "z_p": (0, 0, 1), "z_a": (0, 0, -1)}


def mpu_triad():
    """A +-2 g int16 triad at 880 Hz (16384 counts per g), zero 0."""
    d = default_triad()
    return dataclasses.replace(d, name="mpu", sample_rate_hz=880.0, raw_min=-32768, raw_max=32767,
                               counts_per_mps2=np.full(3, 16384.0 / d.gravity_mps2), zero_counts=np.zeros(3),
                               noise_mps2=0.04)


def chip(d, rng, gain=0.03, cross=0.02, offset_g=0.08):
    """A chip's (b, S): gains within +-gain, cross-axis within +-cross, zero-g offsets within
    +-offset_g (an MPU-6050: +-3 %, +-2 %, +-50..80 mg)."""
    k = d.counts_per_mps2
    cr = rng.uniform(-cross, cross, (3, 3))
    cr -= np.sum(cr * d.axes, axis=1, keepdims=True) * d.axes
    S = (k * (1 + rng.uniform(-gain, gain, 3)))[:, None] * d.axes + k[:, None] * cr
    b = d.zero_counts + rng.uniform(-offset_g, offset_g, 3) * d.gravity_mps2 * k
    return b, S


def tilted(f, deg, rng):
    """f turned by ``deg`` about a random axis across it (a jig or table out of level)."""
    a = np.cross(f, rng.normal(size=3))
    a /= np.linalg.norm(a)
    t = math.radians(deg)
    return f * math.cos(t) + np.cross(a, f) * math.sin(t)


def session(tmp_path, d, b, S, rng, held=None, tilt_deg=2.0, n=2000):
    """One recording a face, labelled and stated as FACES says; ``held``: {label: the face it
    really holds}.  Returns the files in FACES' order."""
    g = d.gravity_mps2
    files = []
    for name, face in FACES.items():
        real = g * tilted(np.asarray(FACES[(held or {}).get(name, name)], float), tilt_deg, rng)
        clean = model.predict_counts(b, S, d.positions, np.repeat(real[None], n, 0))
        raw = np.round(clean + rng.normal(size=clean.shape) * d.noise_mps2 * d.counts_per_mps2).astype(np.int64)
        rec = recording_from_arrays(np.arange(n) / d.sample_rate_hz, raw, pose=np.zeros(n, dtype=np.int64),
                                    f=np.repeat(g * np.asarray(face, float)[None], n, 0),
                                    metadata={"pose_names": f"0={name}"})
        files.append(tmp_path / f"k_{name}.csv")
        write_recording(files[-1], rec)
    return files


def calibrate(tmp_path, capfd, d, files, *extra):
    save_device(d, tmp_path / "dev.json")
    out = tmp_path / "cal.json"
    rc, said, err, caught = run(["calibrate", "--device", tmp_path / "dev.json", *files, "-o", out, *extra], capfd)
    assert not caught, caught
    return rc, said, err, out


def test_a_mislabelled_pose_is_named_before_the_fit(tmp_path, capfd):
    """The file stated +z holds the -z pose (as 3D-Mouse's imu_data_posZ.csv): calibrate had
    written a calibration (exit 0) with a z sensitivity 0.07 x nominal, chi2/dof 6.5e7, and a
    warning to check --full-scale/--lsb.  Now: exit 2, one line naming the pose, its file, the
    direction it reads and its angle from the stated +z, and no calibration."""
    d = mpu_triad()
    rng = np.random.default_rng(3)
    b, S = chip(d, rng)
    files = session(tmp_path, d, b, S, rng, held={"z_p": "z_a"})
    rc, _, err, out = calibrate(tmp_path, capfd, d, files)
    assert rc == 2 and len(err.strip().splitlines()) == 1, err
    assert not out.exists()
    assert "k_z_p.csv" in err and "pose 0 (z_p)" in err, err
    assert "mislabelled or recorded in another orientation" in err, err
    assert "--full-scale" not in err and "k_z_a.csv" not in err, err
    deg = float(err.split(" deg from its stated")[0].rsplit(" ", 1)[1])
    assert 170 <= deg <= 180, err
    assert "(+0.00, +0.00, +1.00) g" in err, err
    fz = float(err.split("reads f = (")[1].split(")")[0].split(", ")[2])
    assert -1.1 < fz < -0.9, err
    # a face taken for a neighbour (90 deg) too, whichever method
    files = session(tmp_path, d, b, S, rng, held={"x_p": "y_p"})
    for method in ("full", "gain", "offset"):
        rc, _, err, out = calibrate(tmp_path, capfd, d, files, "--method", method)
        assert rc == 2 and "pose 0 (x_p)" in err and "k_x_p.csv" in err and " 90 deg from" in err, (method, err)
        assert not out.exists()


def test_a_device_within_its_description_is_not_refused(tmp_path, capfd):
    """The bound holds what the nominal description can be off by: a chip's zero-g offset of
    any size (here 0.6 g on z: an ADXL335's z may be +-1 g) and a device file's gains off by up
    to NOMINAL_FACTOR (here 1.2 x and 1 / 1.2), faces out of level by 8 deg: no refusal (the
    fit then warns of the scale where it is beyond a chip's, as before)."""
    d = mpu_triad()
    rng = np.random.default_rng(4)
    b, S = chip(d, rng)
    b[2] += 0.6 * d.gravity_mps2 * d.counts_per_mps2[2]
    S[0] *= 1.2
    S[1] /= 1.2
    files = session(tmp_path, d, b, S, rng, tilt_deg=8.0)
    rc, said, err, out = calibrate(tmp_path, capfd, d, files)
    assert rc == 0 and out.exists() and "from 6 static poses" in said, err


def test_the_scale_bound_holds_for_any_gains_within_the_factor():
    """allowed_deg less its slack bounds the angle a device with exact axes, any offsets and
    gains within NOMINAL_FACTOR either way gives, on the six faces and on general pose sets."""
    d = mpu_triad()
    rng = np.random.default_rng(7)
    g = d.gravity_mps2
    worst = 0.0
    for trial in range(400):
        P = 6 if trial % 2 else int(rng.integers(4, 15))
        F = np.array(list(FACES.values()), float) if P == 6 else rng.normal(size=(P, 3))
        F = g * F / np.linalg.norm(F, axis=1, keepdims=True)
        K = np.exp(rng.uniform(-1, 1, 3) * math.log(NOMINAL_FACTOR))
        K[rng.integers(3)] = NOMINAL_FACTOR ** rng.choice([-1.0, 1.0])      # one at the bound
        b = rng.uniform(-0.9, 0.9, 3) * g * d.counts_per_mps2
        means = b + F @ (K[:, None] * d.counts_per_mps2[:, None] * d.axes).T
        ang = reading_angles(d, means, F)[1]
        bound = allowed_deg(d, F) - MISLABEL_SLACK_DEG
        assert np.all(ang <= bound + 1e-6), (ang, bound)
        worst = max(worst, float(np.max(ang / bound)))
    assert worst > 0.5          # the bound is not idle


def test_a_reversed_axis_or_swapped_channels_blame_the_device_file(tmp_path, capfd):
    """The device file's x axis reversed: the +-x poses both read 180 deg off, and with x
    reversed every pose agrees: the axis sign is named.  x and y swapped in the device file: 4
    of 6 poses disagree: the device file is the suspect, not the poses."""
    d = mpu_triad()
    rng = np.random.default_rng(5)
    b, S = chip(d, rng)
    files = session(tmp_path, d, b, S, rng)
    flipped = dataclasses.replace(d, axes=np.diag([-1.0, 1.0, 1.0]))
    rc, _, err, out = calibrate(tmp_path, capfd, flipped, files)
    assert rc == 2 and len(err.strip().splitlines()) == 1 and not out.exists(), err
    assert "2 of 6 poses read their f reversed along channel 0's axis -x" in err, err
    assert "with channel 0's axis +x every pose agrees" in err and "axis signs" in err, err
    swapped = dataclasses.replace(d, axes=np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    rc, _, err, out = calibrate(tmp_path, capfd, swapped, files)
    assert rc == 2 and len(err.strip().splitlines()) == 1 and not out.exists(), err
    assert "4 of 6 poses read f far from their stated f" in err and "the device file is the suspect" in err, err
    assert "mislabelled" not in err, err
