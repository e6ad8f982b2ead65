"""rate --omega array and attitude with the array's omega in chunks (accelcal.estimators.rate_stream,
attitude_stream, omega.FusedOmega, firmware.omega_table.OmegaCore; docs/streaming.md):
the whole-file output byte for byte with chunk boundaries inside a rest and inside a turn, on
recordings of the independent generator (indep_model.make_spin_array: a 12-channel tetrahedron,
whose readings fix all six rate products, and a 9-channel layout that fixes three, where the
filter starts from the integrated alpha); CSV and Parquet in and out; bad input refused with the
whole-file command's line and nothing written; what the chunked pass does not take (engine fixed,
a layout that does not observe omega, a lost sample) the whole-file way."""
from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

import indep_model as im
from accelcal.errors import InputError
from accelcal.estimators.attitude_stream import attitude_stream
from accelcal.estimators.omega import row_products
from accelcal.estimators.rate_stream import rate_stream
from accelcal.io.calibration import Calibration, save_calibration
from accelcal.io.chunks import csv_chunks, csv_head
from accelcal.io.device import axes_device, default_device, save_device, tetrahedron_device
from accelcal.io.parquet import parquet_chunks, parquet_head
from accelcal.io.recording import read_recording, write_recording
from accelcal.io.recording_type import Recording

from cli_run import edited_copy, run

LAYOUTS = {"tetra": tetrahedron_device, "axes9": lambda: axes_device(origin=False)}


@pytest.fixture(scope="module", params=sorted(LAYOUTS))
def spin(request, tmp_path_factory):
    """A recording that rests, turns (up to 40 rad/s) and rests again, its device and calibration files."""
    d = tmp_path_factory.mktemp(f"rate_array_{request.param}")
    dev = LAYOUTS[request.param]()
    s = im.make_spin_array(dev, 5, n_turns=3)
    save_device(dev, d / "dev.json")
    save_calibration(s["cal"], d / "cal.json")
    write_recording(d / "rec.csv", s["recording"])
    return {**s, "dir": d, "csv": d / "rec.csv", "dev_path": d / "dev.json", "cal_path": d / "cal.json"}


def rate_cli(capfd, s, rec, out, *args):
    rc, _, err, _ = run(["rate", "--device", s["dev_path"], "--calibration", s["cal_path"], rec, "-o", out,
                         "--omega", "array", "--quiet", *args], capfd)
    return rc, err


def whole(capfd, s, name, rec=None):
    ref = s["dir"] / name
    if not ref.exists():
        rc, err = rate_cli(capfd, s, rec or s["csv"], ref, "--whole-file")
        assert rc == 0, err
    return ref


def boundaries_inside_rest_and_turn(s, starts):
    speed = np.linalg.norm(s["w"], axis=1)
    inner = [k for k in starts if k > 0]
    assert any(speed[k] == 0 and speed[k - 1] == 0 for k in inner)            # inside a rest
    assert any(speed[k] > 1.0 and speed[k - 1] > 1.0 for k in inner)          # inside a turn (> 1 rad/s)


@pytest.mark.parametrize("block", [120, 997, 1 << 22])
def test_chunks_give_the_whole_file_bytes(spin, capfd, block):
    s = spin
    ref = whole(capfd, s, "whole.csv")
    out = s["dir"] / f"s_{block}.csv"
    assert rate_stream(s["device"], s["cal"], s["csv"], out, omega="array", block_bytes=block) == []   # streamed
    starts = [c.start for c in csv_chunks(s["csv"], csv_head(s["csv"], s["device"].n_channels, None), block)]
    if block < 5000:
        assert len(starts) > 20
        boundaries_inside_rest_and_turn(s, starts)
    assert out.read_bytes() == ref.read_bytes()
    # and the filter did its work: the turns' rate within a few of its sigma of the truth
    got = np.loadtxt(ref, delimiter=",", comments="#", skiprows=3)
    moving = np.linalg.norm(s["w"], axis=1) > 3.0
    z = (got[moving, 1:4] - s["w"][moving]) / got[moving, 4:7]
    assert np.sqrt(np.mean(z ** 2)) < 3.0


@pytest.mark.parametrize("rows", [1, 250])
def test_parquet_in_and_out(spin, capfd, rows):
    s = spin
    rec_pq = s["dir"] / "rec.parquet"
    if not rec_pq.exists():
        write_recording(rec_pq, s["recording"])
    ref = whole(capfd, s, "whole.parquet", rec_pq)
    out = s["dir"] / f"ps_{rows}.parquet"
    assert rate_stream(s["device"], s["cal"], rec_pq, out, omega="array", batch_rows=rows) == []
    head, pf = parquet_head(rec_pq, s["device"].n_channels)
    starts = [c.start for c in parquet_chunks(pf, head, rows)]
    boundaries_inside_rest_and_turn(s, starts)
    a, b = pq.read_table(ref), pq.read_table(out)
    assert a.schema == b.schema and a.schema.metadata == b.schema.metadata and a.equals(b)
    # CSV in, Parquet out
    out_csv_in = s["dir"] / f"cs_{rows}.parquet"
    assert rate_stream(s["device"], s["cal"], s["csv"], out_csv_in, omega="array", block_bytes=97 * rows + 200) == []
    assert pq.read_table(whole(capfd, s, "whole_from_csv.parquet")).equals(pq.read_table(out_csv_in))


def no_whole_read(monkeypatch):
    def whole_read(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr("accelcal.cli.estimator_command.read_recording", whole_read)


def test_cli_streams_without_reading_the_whole_file(spin, capfd, monkeypatch):
    s = spin
    ref = whole(capfd, s, "whole.csv")
    no_whole_read(monkeypatch)
    out = s["dir"] / "cli.csv"
    assert rate_cli(capfd, s, s["csv"], out) == (0, "")
    assert out.read_bytes() == ref.read_bytes()


def edited_lines(s, name, edit):
    lines = s["csv"].read_text().splitlines(keepends=True)
    edit(lines)
    path = s["dir"] / name
    path.write_text("".join(lines))
    return path


def bad_cell(lines):
    cells = lines[-30].split(",")
    cells[5] = "12x4"
    lines[-30] = ",".join(cells)


def t_backwards(lines):
    a, b = lines[-41].split(",", 1), lines[-40].split(",", 1)
    lines[-40] = a[0] + "," + b[1]


@pytest.mark.parametrize("case, edit, words", [("cell", bad_cell, "raw_4"), ("t", t_backwards, "strictly increasing")])
def test_bad_row_late_in_the_file_is_the_whole_file_error(spin, capfd, monkeypatch, case, edit, words):
    s = spin
    path = edited_lines(s, f"bad_{case}.csv", edit)
    rc_w, err_w = rate_cli(capfd, s, path, s["dir"] / f"bw_{case}.csv", "--whole-file")
    assert rc_w == 2 and words in err_w and len(err_w.strip().splitlines()) == 1
    out = s["dir"] / f"bs_{case}.csv"
    with pytest.raises(InputError):
        rate_stream(s["device"], s["cal"], path, out, omega="array", block_bytes=997)
    assert not out.exists()
    no_whole_read(monkeypatch)
    assert rate_cli(capfd, s, path, out) == (rc_w, err_w)
    assert not out.exists() and not list(s["dir"].glob("bs_*"))


def edited_recording(s, name, edit):
    return edited_copy(s["csv"], s["device"].n_channels, s["dir"] / name, edit)


def drop_sample(t, raw):
    keep = np.ones(t.size, bool)
    keep[1200] = False
    return t[keep], raw[keep]


def out_of_range(t, raw):
    raw[-10, 7] = 70000
    return t, raw


def lost_and_out_of_range(t, raw):
    return drop_sample(*out_of_range(t, raw))


def in_milliseconds(t, raw):
    return t * 1000.0, out_of_range(t, raw)[1]


@pytest.mark.parametrize("case, edit", [("lost", drop_sample), ("lost_range", lost_and_out_of_range)])
def test_what_the_whole_recording_tells_goes_the_whole_file_way(spin, capfd, case, edit):
    """A lost sample (filled, with a warning), and with it a reading outside the device's range (the
    whole-file command puts t on its grid, filling the sample, before it checks the range): nothing
    written by the chunked pass, and the command's output and lines are the whole-file command's."""
    s = spin
    path = edited_recording(s, f"{case}.csv", edit)
    out = s["dir"] / f"{case}_s.csv"
    assert rate_stream(s["device"], s["cal"], path, out, omega="array", block_bytes=997) is None
    assert not out.exists()
    ref = s["dir"] / f"{case}_w.csv"
    rc_w, err_w = rate_cli(capfd, s, path, ref, "--whole-file")
    assert rate_cli(capfd, s, path, out) == (rc_w, err_w)
    if case == "lost":
        assert rc_w == 0 and "filled" in ref.read_text() and out.read_bytes() == ref.read_bytes()
    else:
        assert rc_w == 2 and "outside" in err_w and not out.exists()


def test_a_reading_out_of_range_on_the_grid_is_refused_in_chunks(spin, capfd, monkeypatch):
    """Stamps on the grid: the range error, found by the scan and held until the stamps are read again,
    is the whole-file command's line, without reading the file whole."""
    s = spin
    path = edited_recording(s, "range.csv", out_of_range)
    out = s["dir"] / "range_s.csv"
    rc_w, err_w = rate_cli(capfd, s, path, s["dir"] / "range_w.csv", "--whole-file")
    assert rc_w == 2 and "outside" in err_w and len(err_w.strip().splitlines()) == 1
    with pytest.raises(InputError) as e:
        rate_stream(s["device"], s["cal"], path, out, omega="array", block_bytes=997)
    assert str(e.value) in err_w and not out.exists()
    no_whole_read(monkeypatch)
    assert rate_cli(capfd, s, path, out) == (rc_w, err_w) and not out.exists()


@pytest.mark.parametrize("omega", ["alpha", "array"])
def test_t_in_milliseconds_with_a_reading_out_of_range_is_noted_first(spin, capfd, omega):
    """The whole-file command notes t's unit, then refuses the reading: the chunked pass leaves it to it
    (before: the streamed rate (--omega alpha) gave the error without the note)."""
    s = spin
    path = edited_recording(s, "ms_range.csv", in_milliseconds)
    lines = []
    for extra in (["--whole-file"], []):
        rc, _, err, _ = run(["rate", "--device", s["dev_path"], "--calibration", s["cal_path"], path, "-o",
                             s["dir"] / "ms_out.csv", "--omega", omega, "--quiet", *extra], capfd)
        lines.append((rc, err))
    assert lines[0][0] == 2 and "milliseconds" in lines[0][1] and "outside" in lines[0][1]
    assert lines[1] == lines[0] and not (s["dir"] / "ms_out.csv").exists()


def test_engine_fixed_and_a_layout_without_omega_are_the_whole_file_refusals(spin, capfd, tmp_path):
    s = spin
    out = s["dir"] / "fixed.csv"
    assert rate_stream(s["device"], s["cal"], s["csv"], out, omega="array", engine="fixed") is None
    rc, err = rate_cli(capfd, s, s["csv"], out, "--engine", "fixed")
    assert rc == 2 and "float engine only" in err and not out.exists()
    six = default_device()
    assert rate_stream(six, Calibration.nominal(six), s["csv"], out, omega="array") is None
    save_device(six, tmp_path / "six.json")
    rec = tmp_path / "six.csv"
    write_recording(rec, Recording(t=np.arange(50) / 60.0, raw=np.full((50, 6), 5000)))
    rc, _, err, _ = run(["rate", "--device", tmp_path / "six.json", "--calibration", "nominal", rec, "-o", out,
                         "--omega", "array", "--quiet"], capfd)
    assert rc == 2 and "not observable" in err and not out.exists()


@pytest.mark.parametrize("seed", range(3))
def test_row_products_do_not_depend_on_the_other_rows(seed):
    """Each row of x A^T summed in one order whatever rows come with it (numpy's matmul does not:
    its lone last row of an odd block rounds otherwise, which a chunk of one row meets)."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(257, 12)) * 3000.0
    a = rng.normal(size=(6, 12))
    whole_rows = row_products(x, a)
    cuts = np.sort(rng.choice(np.arange(1, 257), size=9, replace=False))
    assert np.array_equal(np.vstack([row_products(p, a) for p in np.split(x, cuts)]), whole_rows)
    assert np.array_equal(np.vstack([row_products(x[i:i + 1], a) for i in range(257)]), whole_rows)
    np.testing.assert_allclose(whole_rows, x @ a.T, rtol=1e-12, atol=1e-9)


def attitude_cli(capfd, s, rec, out, *args):
    rc, _, err, _ = run(["attitude", "--device", s["dev_path"], "--calibration", s["cal_path"], rec, "-o", out,
                         "--quiet", *args], capfd)
    return rc, err


@pytest.mark.parametrize("engine", ["float", "fixed"])
@pytest.mark.parametrize("block", [120, 4099])
def test_attitude_with_the_array_omega_in_chunks(spin, capfd, monkeypatch, engine, block):
    """The spins are no swing about y: f at the pivot is off g in the swing's plane on many samples,
    which the warning counts. --omega array and auto (no w columns), both engines; the CLI without
    the whole-file read."""
    s = spin
    if engine == "fixed" and s["device"].n_channels < 12:   # three of the six rate products: refused whole-file
        out = s["dir"] / f"att_refused_{block}.csv"
        assert attitude_stream(s["device"], s["cal"], s["csv"], out, engine=engine, omega="array") is None
        rc, err = attitude_cli(capfd, s, s["csv"], out, "--engine", engine)
        assert rc == 2 and "all six rate products" in err and not out.exists()
        return
    ref = s["dir"] / f"att_{engine}.csv"
    if not ref.exists():
        rc, err = attitude_cli(capfd, s, s["csv"], ref, "--engine", engine, "--omega", "array", "--whole-file")
        assert rc == 0 and "f at the pivot is more than 20 % off" in err
    for omega in ("array", "auto"):
        out = s["dir"] / f"att_{engine}_{omega}_{block}.csv"
        warnings = attitude_stream(s["device"], s["cal"], s["csv"], out, engine=engine, omega=omega, block_bytes=block)
        assert len(warnings) == 1 and "f at the pivot is more than 20 % off" in warnings[0]
        assert out.read_bytes() == ref.read_bytes()
    no_whole_read(monkeypatch)
    out = s["dir"] / f"att_cli_{engine}_{block}.csv"
    rc, err = attitude_cli(capfd, s, s["csv"], out, "--engine", engine)
    assert rc == 0 and "f at the pivot is more than 20 % off" in err and out.read_bytes() == ref.read_bytes()


def test_attitude_parquet_and_a_bad_cell_late(spin, capfd, monkeypatch):
    s = spin
    rec_pq = s["dir"] / "att_rec.parquet"
    write_recording(rec_pq, s["recording"])
    ref = s["dir"] / "att_whole.parquet"
    assert attitude_cli(capfd, s, rec_pq, ref, "--whole-file")[0] == 0
    out = s["dir"] / "att_s.parquet"
    assert attitude_stream(s["device"], s["cal"], rec_pq, out, batch_rows=7)
    a, b = pq.read_table(ref), pq.read_table(out)
    assert a.schema == b.schema and a.schema.metadata == b.schema.metadata and a.equals(b)
    path = edited_lines(s, "att_bad.csv", bad_cell)
    rc_w, err_w = attitude_cli(capfd, s, path, s["dir"] / "att_bw.csv", "--whole-file")
    assert rc_w == 2 and "raw_4" in err_w
    no_whole_read(monkeypatch)
    out = s["dir"] / "att_bs.csv"
    assert attitude_cli(capfd, s, path, out) == (rc_w, err_w) and not out.exists()
