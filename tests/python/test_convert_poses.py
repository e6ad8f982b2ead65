"""``accelcal convert`` of pose-means tables and slow loggers (a tester's public recordings: a
ground station's six-position result ``Position,AvgX,AvgY,AvgZ``, one row per pose).

Each file is written here in the recording's shape from known values, so the expected
recording is those values; bad files give one line naming the file and row, exit 2, and no
output.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from cli_run import convert_ok, write_lines

G = 9.80665
#: six poses, each axis up then down, as a six-position calibration holds them
SIX = [("+X UP", (1, 0, 0)), ("-X UP", (-1, 0, 0)), ("+Y UP", (0, 1, 0)), ("-Y UP", (0, -1, 0)),
       ("+Z UP", (0, 0, 1)), ("-Z UP", (0, 0, -1))]


def _means(scale=(1.002, 0.997, 1.004), offset=(0.03, -0.07, 0.02)):
    """The six poses' mean readings, m/s^2: |f| 0.99-1.01 g each (gains and offsets off)."""
    return np.array([np.asarray(u) * G * np.asarray(scale) + np.asarray(offset) for _, u in SIX])


@pytest.mark.parametrize("regions", [False, True])
def test_pose_means_are_not_told_gravity_removed(tmp_path, capfd, regions):
    """A file of six pose means (one row each, |f| about 1 g) read at --rate 1 had been told
    'gravity looks removed': the stillest window spanned three poses and the magnitude of their
    mean vector, 0.33 g, was taken for |f|.  Each row's own |f| is now averaged, within one pose
    where regions label them."""
    m = _means()
    src = write_lines(tmp_path / "means.csv", ["ax,ay,az"] + [",".join(f"{v:.6f}" for v in r) for r in m])
    args = ["--units", "mps2", "--lsb", "0.000001", "--bits", "32", "--rate", "1"]
    if regions:
        reg = tmp_path / "regions.json"
        reg.write_text(json.dumps({n: {"start": k, "end": k + 1} for k, n in
                                   enumerate(["x_p", "x_a", "y_p", "y_a", "z_p", "z_a"])}))
        args += ["--regions", str(reg), "--stated-f"]
    rec, _, err, _ = convert_ok(tmp_path, capfd, src, *args)
    np.testing.assert_array_equal(rec.raw, np.round(m / 1e-6).astype(np.int64))
    assert "gravity looks removed" not in err, err


def test_slow_logger_turned_between_rows_is_not_told_gravity_removed(tmp_path, capfd):
    """A logger stamping every 2 s (0.5 Hz), turned to another face between rows: a window of
    three rows spans three poses; |f| = 1 g in every row, so no note.  (Readings with gravity taken out still get it:
    test_convert_exports.test_gravity_removed_readings_are_named.)"""
    rng = np.random.default_rng(3)
    u = np.tile(np.array([d for _, d in SIX], float), (2, 1))
    m = np.round(u * G + 0.01 * rng.standard_normal(u.shape), 3)
    src = write_lines(tmp_path / "slow.csv", ["t,ax,ay,az"] + [f"{2 * k},{a:.3f},{b:.3f},{c:.3f}" for k, (a, b, c)
                                                               in enumerate(m)])
    _, _, err, _ = convert_ok(tmp_path, capfd, src, "--units", "mps2", "--lsb", "0.001", "--time-unit", "s")
    assert "gravity looks removed" not in err, err
