"""``--units``, ``--lsb``, ``--full-scale`` (with ``--bits``, ``--gravity``) on every command
that reads recordings (issue 14, "left"): a recording in m/s^2 or g read with them gives the
result of the same recording in integer counts; a reading that is not a whole number of
LSBs is refused with its row and column; an option that contradicts the file's ``# units:``
/ ``# lsb:`` comment is refused naming the comment's line (``convert`` too: one rule,
units.file_scale); ``--help`` shows them.  Bad input: one line, exit 2, nothing written."""
from __future__ import annotations

import contextlib
import io
import json
import os
import re
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal.io.calibration import Calibration, save_calibration
from accelcal.cli.main import main
from accelcal.io.device import pendulum_device, save_device
from accelcal.io.recording import write_recording
from accelcal.simulate import run_simulation
from cli_run import convert_ok, convert_refused, run, write_lines

FAST = settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                         HealthCheck.too_slow])
READERS = ["calibrate", "resolve", "diagnose", "attitude", "displacement", "rate"]
G = 9.80665
# (units, LSB in those units, the options that state it)
FORMS = {
    "mps2-lsb": ("mps2", 9.81 / 2048, ["--units", "mps2", "--lsb", repr(9.81 / 2048)]),
    "g-lsb": ("g", 1 / 16384, ["--units", "g", "--lsb", repr(1 / 16384)]),
    "g-full-scale": ("g", 1 / 16384, ["--units", "g", "--full-scale", "2"]),  # 2*2/2**16 g
    "mps2-full-scale": ("mps2", 9.81 / 2048, ["--units", "mps2", "--full-scale", "16", "--gravity", "9.81"]),
}


@pytest.fixture(scope="module")
def good(tmp_path_factory):
    """Counts recordings: the default 6-channel device (static poses, a calibration from
    them, a short rate-table run) and the pendulum device (nominal calibration, a swing)."""
    d = tmp_path_factory.mktemp("units")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["simulate", "--device", "default", "--motion", "static_poses", "--param", 'poses="6"',
                     "--seed", "1", "-o", str(d / "poses.csv")]) == 0
        assert main(["calibrate", "--device", "default", str(d / "poses.csv"), "-o", str(d / "cal.json")]) == 0
        assert main(["simulate", "--device", "default", "--motion", "rate_table", "--param", "duration_s=3",
                     "--seed", "2", "-o", str(d / "motion.csv")]) == 0
    pd = pendulum_device()
    save_device(pd, d / "pend.json")
    save_calibration(Calibration.nominal(pd), d / "pend_cal.json")
    write_recording(d / "swing.csv", run_simulation(pd, "pendulum", seed=5, duration_s=3.0).recording)
    return d


def inputs(good: Path, cmd: str) -> tuple[list[str], str]:
    """(the command's arguments before the recording, the counts recording's name)."""
    if cmd == "calibrate":
        return ["calibrate", "--device", "default"], "poses.csv"
    if cmd == "attitude":
        return ["attitude", "--device", good / "pend.json", "--calibration", good / "pend_cal.json"], "swing.csv"
    return [cmd, "--device", "default", "--calibration", good / "cal.json"], "motion.csv"


def outputs(cmd: str) -> list[str]:
    if cmd == "calibrate":
        return ["-o", "out.json"]
    if cmd == "diagnose":
        return ["--folds", "3", "--json", "out.json"]
    return ["-o", "out.csv"] + (["--engine", "fixed"] if cmd == "resolve" else [])


def physical(text: str, units: str, lsb: float, comments=()) -> tuple[str, int]:
    """The recording with every raw_k reading written as count * lsb (shortest repr), the
    comment lines ``comments`` before the header; and the header's line number."""
    lines = text.splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    names = lines[k].split(",")
    raw = [j for j, n in enumerate(names) if n.startswith("raw_")]
    rows = []
    for ln in lines[k + 1:]:
        cells = ln.split(",")
        for j in raw:
            cells[j] = repr(int(cells[j]) * lsb)
        rows.append(",".join(cells))
    head = lines[:k] + list(comments)
    return "\n".join(head + [lines[k]] + rows) + "\n", len(head) + 1


@contextlib.contextmanager
def workdir(good: Path):
    """A fresh directory, the current one while it lasts (the outputs have the same
    relative names whatever the input), with an empty out/ for the outputs."""
    with tempfile.TemporaryDirectory(dir=good) as d:
        old = Path.cwd()
        try:
            os.chdir(d)
            Path("out").mkdir()
            yield Path(d)
        finally:
            os.chdir(old)


def stable(text: str) -> str:
    """An output's text without what varies from run to run (diagnose's elapsed_s)."""
    return re.sub(r'"elapsed_s": [0-9.e-]+', '"elapsed_s": ...', text)


def run_in(good, cmd, rec_text, options, capfd, name="rec.csv"):
    """Run ``cmd`` on a recording with that text in a fresh directory: (rc, stdout, stderr,
    warnings, {output file: text}, the directory's out/ listing)."""
    pre, _ = inputs(good, cmd)
    with workdir(good) as d:
        (d / name).write_text(rec_text)
        argv = pre + [name] + [a.replace("out.", "out/out.") for a in outputs(cmd)] + options
        rc, out, err, caught = run(argv, capfd)
        files = {p.name: stable(p.read_text()) for p in (d / "out").iterdir()}
    return rc, out, err, caught, files


def check_rejected(rc, err, caught, files, what):
    assert rc == 2, f"{what}: exit {rc}: {err!r}"
    assert len(err.splitlines()) == 1 and "Traceback" not in err, f"{what}: {err!r}"
    assert not caught, f"{what}: {caught}"
    assert not files, f"{what}: left {sorted(files)}"


@pytest.mark.parametrize("form", sorted(FORMS))
@pytest.mark.parametrize("cmd", READERS)
def test_physical_units_give_the_counts_result(good, cmd, form, capfd):
    """The same readings in counts and in m/s^2 or g (with the options): the same output,
    byte for byte, and the same stdout."""
    units, lsb, options = FORMS[form]
    _, name = inputs(good, cmd)
    text = (good / name).read_text()
    base = run_in(good, cmd, text, [], capfd)
    assert base[0] == 0, base[2]
    phys, _ = physical(text, units, lsb)
    got = run_in(good, cmd, phys, options, capfd)
    assert got[0] == 0, got[2]
    assert got[1] == base[1] and got[4] == base[4], f"{cmd} {form}: the outputs differ"
    assert got[4], "no output written"
    # without the options the floats are not counts: refused, one line
    rc, _, err, caught, files = run_in(good, cmd, phys, [], capfd)
    check_rejected(rc, err, caught, files, f"{cmd} without options")
    # the same scale stated by the file's comments instead, or by both (agreeing)
    meta = [f"# units: {units}", f"# lsb: {lsb!r}"]
    phys_meta, _ = physical(text, units, lsb, meta)
    for opts in ([], options):
        got = run_in(good, cmd, phys_meta, opts, capfd)
        assert got[0] == 0 and got[4] == base[4], (opts, got[2])


@pytest.mark.parametrize("cmd", READERS)
@FAST
@given(data=st.data())
def test_not_a_whole_number_of_lsbs_is_refused_with_its_row(good, cmd, data, capfd):
    form = data.draw(st.sampled_from(sorted(FORMS)), label="form")
    units, lsb, options = FORMS[form]
    _, name = inputs(good, cmd)
    text, header_line = physical((good / name).read_text(), units, lsb)
    lines = text.splitlines()
    names = lines[header_line - 1].split(",")
    i = data.draw(st.integers(header_line, len(lines) - 1), label="line index")
    j = data.draw(st.sampled_from([k for k, n in enumerate(names) if n.startswith("raw_")]), label="column")
    cells = lines[i].split(",")
    bad = data.draw(st.sampled_from(["third", "half", "x", "", "nan", "1e999", "-inf"]), label="cell")
    if bad in ("third", "half"):
        cells[j] = repr((round(float(cells[j]) / lsb) + {"third": 1 / 3, "half": 0.5}[bad]) * lsb)
    else:
        cells[j] = bad
    lines[i] = ",".join(cells)
    rc, _, err, caught, files = run_in(good, cmd, "\n".join(lines) + "\n", options, capfd)
    what = f"{cmd} {form}: line {i + 1} {names[j]} = {cells[j]!r}"
    check_rejected(rc, err, caught, files, what)
    assert f"rec.csv: row {i + 1}, column {names[j]}:" in err, f"{what}: {err!r}"
    if bad in ("third", "half"):
        assert "not a whole number" in err, err


# (the file's comments, the options, the comment that must be named)
CONTRADICTIONS = [
    (["# units: g", f"# lsb: {1 / 16384!r}"], ["--units", "mps2", "--lsb", repr(9.81 / 2048)], "# units: g"),
    (["# units: g", f"# lsb: {1 / 16384!r}"], ["--units", "g", "--lsb", repr(1 / 8192)], "# lsb:"),
    (["# units: g", f"# lsb: {1 / 16384!r}"], ["--units", "g", "--full-scale", "4"], "# lsb:"),
    (["# units: g", f"# lsb: {1 / 16384!r}"], ["--units", "counts"], "# units: g"),
    (["# units: g", f"# lsb: {1 / 16384!r}"], ["--full-scale", "4"], "# lsb:"),
    (["# units: g", f"# lsb: {1 / 16384!r}"], ["--lsb", repr(1 / 8192)], "# lsb:"),
    (["# units: mps2", "# full_scale_g: 16", "# gravity_mps2: 9.81"],
     ["--units", "mps2", "--lsb", repr(9.80665 / 2048)], "# full_scale_g:"),
    (["# units: g"], ["--units", "mps2", "--lsb", repr(9.81 / 2048)], "# units: g"),
]


@pytest.mark.parametrize("case", range(len(CONTRADICTIONS)))
@pytest.mark.parametrize("cmd", READERS + ["convert"])
def test_an_option_that_contradicts_a_comment_is_refused(good, cmd, case, capfd):
    comments, options, named = CONTRADICTIONS[case]
    units = "mps2" if "mps2" in comments[0] else "g"
    lsb = 9.81 / 2048 if units == "mps2" else 1 / 16384
    name = "poses.csv" if cmd in ("calibrate", "convert") else inputs(good, cmd)[1]
    text, header_line = physical((good / name).read_text(), units, lsb, comments)
    line = header_line - len(comments) + next(k for k, c in enumerate(comments) if c.startswith(named))
    if cmd == "convert":
        with workdir(good) as d:
            (d / "rec.csv").write_text(text)
            rc, _, err, caught = run(["convert", "rec.csv", "--format", "csv", *options, "-o", "out/o.csv"], capfd)
            files = list((d / "out").iterdir())
    else:
        rc, _, err, caught, files = run_in(good, cmd, text, options, capfd)
    check_rejected(rc, err, caught, files, f"{cmd} {options} on {comments}")
    assert f"rec.csv: row {line}: the comment '{named}" in err and "contradicts" in err, err


def test_a_comment_that_agrees_in_another_form_is_accepted(good, capfd):
    """# full_scale_g: 16 with # gravity_mps2: 9.81 is the LSB 9.81/2048 m/s^2: --lsb agrees."""
    text, _ = physical((good / "poses.csv").read_text(), "mps2", 9.81 / 2048,
                       ["# units: mps2", "# full_scale_g: 16", "# gravity_mps2: 9.81"])
    base = run_in(good, "calibrate", (good / "poses.csv").read_text(), [], capfd)
    got = run_in(good, "calibrate", text, FORMS["mps2-lsb"][2], capfd)
    assert got[0] == 0 and got[4] == base[4], got[2]


ALONE = [["--full-scale", "4"], ["--lsb", repr(G / 8192)], ["--lsb", "0.1220703125mg"]]   # 2*4/2**16 g


@pytest.mark.parametrize("options", ALONE)
def test_full_scale_or_lsb_alone_take_the_comments_unit(good, options, capfd):
    """--full-scale G or --lsb VALUE without --units states no unit: a file's '# units: mps2'
    comment gives it (as a table's column names do), not refused as contradicting a
    '--units counts' the user never gave; the result is the counts file's."""
    text = (good / "poses.csv").read_text()
    phys, _ = physical(text, "mps2", G / 8192, ["# units: mps2"])
    base = run_in(good, "calibrate", text, [], capfd)
    got = run_in(good, "calibrate", phys, options, capfd)
    assert got[0] == 0 and got[4] == base[4], got[2]


@pytest.mark.parametrize("options", ALONE)
def test_convert_full_scale_or_lsb_alone_take_the_comments_unit(tmp_path, options, capfd):
    """convert: the same for a table whose '# units: mps2' comment states the unit."""
    counts = np.array([[0, 0, 8192], [10, -20, 8190], [-8192, 5, 3], [4, 8191, -7]] * 5)
    write_lines(tmp_path / "m.csv", ["# units: mps2", "t,ax,ay,az"] +
                [f"{i / 100!r}," + ",".join(repr(int(c) * G / 8192) for c in row) for i, row in enumerate(counts)])
    rec, dev, err, _ = convert_ok(tmp_path, capfd, tmp_path / "m.csv", *options)
    assert rec.raw.tolist() == counts.tolist(), err
    assert dev["channels"][0]["counts_per_mps2"] == pytest.approx(8192 / G)


@pytest.mark.parametrize("options", [["--lsb", "0.001"], ["--lsb", "1mg"]])
def test_lsb_alone_over_a_file_that_states_no_unit_is_refused(good, options, capfd):
    """Without --units nor a unit in the file, --lsb divides readings of no known unit."""
    rc, _, err, caught, files = run_in(good, "calibrate", (good / "poses.csv").read_text(), options, capfd)
    check_rejected(rc, err, caught, files, f"{options}")
    assert "state the unit of the readings it divides with --units mps2|g" in err, err


@pytest.mark.parametrize("options,frag", [
    (["--bits", "12"], "--bits 12: it sizes only --full-scale's LSB"),
    (["--gravity", "9.81", "--units", "g", "--lsb", "0.001"], "--gravity 9.81: it sizes only"),
    (["--units", "mps2"], "--lsb VALUE"),
    (["--lsb", "0.001"], "--units mps2|g"),
    (["--units", "g", "--lsb", "0.001", "--full-scale", "2"], "both given"),
    (["--units", "g", "--lsb", "-1"], "--lsb '-1'"),
    (["--units", "g", "--full-scale", "2", "--bits", "40"], "--bits '40'"),
])
def test_bad_options_one_line(good, options, frag, capfd):
    rc, _, err, caught, files = run_in(good, "resolve", (good / "motion.csv").read_text(), options, capfd)
    check_rejected(rc, err, caught, files, str(options))
    assert frag in err, err


@pytest.mark.parametrize("cmd", READERS + ["convert"])
def test_help_shows_the_options(cmd, capsys):
    with pytest.raises(SystemExit):
        main([cmd, "--help"])
    text = capsys.readouterr().out
    assert "readings in physical units" in text
    for opt in ("--units {counts,mps2,mmps2,g,mg}", "--lsb VALUE", "--full-scale G", "--bits N", "--gravity MPS2"):
        assert opt in text, f"{cmd} --help: no {opt}"
    assert "must agree" in " ".join(text.split())


@pytest.mark.parametrize("cmd", ["header", "simulate", "demo"])
def test_commands_that_read_no_recording_have_none(cmd, capsys):
    with pytest.raises(SystemExit):
        main([cmd, "--help"])
    assert "--lsb" not in capsys.readouterr().out


def test_python_read_recording_takes_the_same_units(good):
    """ac.read_recording(..., units=, lsb=, full_scale_g=): the counts, the same rule."""
    import accelcal as ac
    from accelcal.errors import AccelcalError

    counts = ac.read_recording(good / "poses.csv", ac.default_device())
    text, _ = physical((good / "poses.csv").read_text(), "g", 1 / 16384)
    (good / "api_g.csv").write_text(text)
    for kw in (dict(units="g", lsb=1 / 16384), dict(units="g", full_scale_g=2)):
        back = ac.read_recording(good / "api_g.csv", 6, **kw)
        assert (back.raw == counts.raw).all()
    text, header_line = physical((good / "poses.csv").read_text(), "g", 1 / 16384, ["# units: g"])
    (good / "api_g.csv").write_text(text)
    with pytest.raises(AccelcalError, match=rf"row {header_line - 1}: the comment '# units: g' contradicts"):
        ac.read_recording(good / "api_g.csv", 6, units="mps2", lsb=9.81 / 2048)
    with pytest.raises(AccelcalError, match="not a whole number"):
        ac.read_recording(good / "api_g.csv", 6, units="g", lsb=1 / 12000)


def _mg_counts(path, n=250, seed=1):
    """Integer readings of a watch in counts of 1 mg (a Garmin export: 1037 counts at rest): five
    still poses of 50 rows, f along +-x, +z, -y, -z, with 3 counts of noise; returns them."""
    rng = np.random.default_rng(seed)
    dirs = np.array([[1, 0, 0], [-1, 0, 0], [0, 0, 1], [0, -1, 0], [0, 0, -1]])
    raw = np.round(np.repeat(dirs * 1000, n // 5, axis=0) + 3 * rng.standard_normal((n, 3))).astype(int)
    path.write_text("ax,ay,az\n" + "".join("%d,%d,%d\n" % tuple(r) for r in raw))
    return raw


def test_counts_of_a_stated_size_are_taken_as_they_are(tmp_path, capfd):
    """'1 count = 1 mg' for integer readings could not be said: --lsb 0.001 with counts was refused
    ('use --full-scale', which had to be bent: --full-scale 32.768 --bits 16).  --units counts with
    the count's size and its unit (--lsb 1mg, 0.001g, 0.00980665mps2) keeps the readings as they are
    and sets the nominal scale, 1 / (0.001 g) = 101.97 counts per m/s^2; the size without its unit is
    refused with counts (it cannot be told from an LSB of readings in g), and so are readings that
    are not integers (floats in g are never rounded into counts by it) and --round."""
    raw = _mg_counts(tmp_path / "w.csv")
    for k, lsb in enumerate(("1mg", "0.001g", f"{0.001 * G!r}mps2", "1 MG")):
        out, dev = tmp_path / f"o{k}.csv", tmp_path / f"o{k}.json"
        rc, _, err, caught = run(["convert", tmp_path / "w.csv", "--rate", "25", "--units", "counts", "--lsb", lsb,
                                  "-o", out, "--device-out", dev], capfd)
        assert rc == 0 and not caught, (lsb, err)
        body = [ln for ln in out.read_text().splitlines() if not ln.startswith("#")][1:]
        assert np.array_equal(np.array([[int(v) for v in ln.split(",")[1:]] for ln in body]), raw), lsb
        cpm = json.loads(dev.read_text())["channels"][0]["counts_per_mps2"]
        assert cpm == pytest.approx(1.0 / (0.001 * G), rel=1e-12), (lsb, cpm)
    floats = tmp_path / "f.csv"
    floats.write_text("ax,ay,az\n" + "".join("%.3f,%.3f,%.3f\n" % tuple(r / 1000) for r in raw))
    for src, options, frag in ((tmp_path / "w.csv", ["--lsb", "0.001"], "--lsb 0.001 with --units counts: give one "
                                "count's size with its unit (--lsb 0.001g, or in mg or mps2)"),
                               (floats, ["--lsb", "1mg"], "row 2, column ax: expected an integer"),
                               (tmp_path / "w.csv", ["--lsb", "1mg", "--round"], "readings in counts are integers")):
        out = tmp_path / "bad.csv"
        rc, _, err, caught = run(["convert", src, "--rate", "25", "--units", "counts", *options, "-o", out,
                                  "--device-out", tmp_path / "bad.json"], capfd)
        assert rc == 2 and len(err.strip().splitlines()) == 1 and frag in err, (options, err)
        assert not out.exists() and not (tmp_path / "bad.json").exists()
    # the same size in the readings' own unit converts floats in g as before
    rc, _, err, _ = run(["convert", floats, "--rate", "25", "--units", "g", "--lsb", "1mg", "-o", tmp_path / "g.csv"],
                        capfd)
    assert rc == 0, err
    body = [ln for ln in (tmp_path / "g.csv").read_text().splitlines() if not ln.startswith("#")][1:]
    assert np.array_equal(np.array([[int(v) for v in ln.split(",")[1:]] for ln in body]), raw)


@pytest.mark.parametrize("header, unit", [
    ("timestamp,accelerometer_m_s2[0],accelerometer_m_s2[1],accelerometer_m_s2[2]", "mps2"),  # PX4's ulog2csv
    ('"Time (s)","X (m/s^2)","Y (m/s^2)","Z (m/s^2)"', "mps2"),                                 # phyphox
    ("t,accX (g),accY (g),accZ (g)", "g")])
def test_round_takes_the_unit_the_names_state(tmp_path, capfd, header, unit):
    """A header that states the unit, over calibrated floats on no grid: the refusal without an LSB
    advises --full-scale G and --round, and following it converts (the LSB --full-scale states, in
    the names' unit); --round had been refused asking for --full-scale, which was given.  Readings
    in counts with --full-scale and --round: refused, asking for no option given."""
    rng = np.random.default_rng(3)
    per = G if unit == "mps2" else 1.0
    f = (np.array([0.2, -0.1, -1.0]) + 0.01 * rng.standard_normal((300, 3))) * per
    src = write_lines(tmp_path / "f.csv", [header] + [f"{(k * 0.004 if k else 0):.6f}," + ",".join(
        f"{v:.8f}" for v in r) for k, r in enumerate(f)])
    err = convert_refused(tmp_path, capfd, src, name="bare")
    assert "give --full-scale G" in err and "--round" in err, err
    rec, dev, err, _ = convert_ok(tmp_path, capfd, src, "--full-scale", "16", "--round")
    lsb = 32.0 / 2 ** 16 * per
    np.testing.assert_array_equal(rec.raw, np.round(np.round(f, 8) / lsb).astype(int))
    assert "--round" in err and dev["channels"][0]["counts_per_mps2"] == pytest.approx(1 / (32.0 / 2 ** 16 * G))
    counts = write_lines(tmp_path / "c.csv", ["t,ax,ay,az"] + [f"{k * 0.004:.3f},1,2,3" for k in range(20)])
    for options, said in ((["--full-scale", "16", "--round"], "--units mps2|g"),
                          (["--units", "counts", "--full-scale", "16", "--round"], "--units mps2|g")):
        err = convert_refused(tmp_path, capfd, counts, *options, name=options[1])
        last = err.splitlines()[-1]
        assert "--round" in last and "nothing to round" in last and said in last, err
        for stated in options[1:]:
            if stated.startswith("--") and stated != "--round":
                assert f"give {stated}" not in last and f"or {stated}" not in last, (stated, last)
