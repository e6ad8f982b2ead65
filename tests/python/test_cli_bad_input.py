"""Every file-reading ``accelcal`` subcommand under generated bad input.

The contract (docs/data-contract.md, "Command line"): on bad input a
subcommand prints ONE line to stderr (no traceback), exits non-zero, and leaves
no output file.  Here every run must also exit 2 (an input error), never 3
(``internal error``: an exception the library did not turn into an input
error), must not emit a Python warning (a warning is at least one more stderr
line when the command runs for real), and must leave the output directory
empty (no output file, no ``.NAME.*`` temporary).

The bad files are derived from valid ones made in a module fixture (``accelcal
demo`` for the 6-channel device, the Python API for the pendulum device that
``attitude`` needs).  Unknown JSON keys and unknown CSV columns are allowed by
the contract and are checked to be accepted.  The CLI runs in-process through
``accelcal.cli.main`` with stderr captured at the file-descriptor level.
"""
from __future__ import annotations

import contextlib
import copy
import json
import os
import tempfile
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from accelcal.cli.main import main

# per (command, file kind): 3 kinds x 40 = ~120 runs per command; raise it to hunt
EXAMPLES = int(os.environ.get("ACCELCAL_BAD_INPUT_EXAMPLES", "40"))
SETTINGS = settings(max_examples=EXAMPLES, deadline=None, derandomize=False,
                    suppress_health_check=[HealthCheck.function_scoped_fixture,
                                           HealthCheck.too_slow])

SIX = {"dev": "device.json", "cal": "calibration.json", "rec": "small.csv", "poses": "poses.csv"}


# ---- valid inputs ------------------------------------------------------------

@pytest.fixture(scope="module")
def good(tmp_path_factory):
    import io

    from accelcal.io.calibration import Calibration, save_calibration
    from accelcal.io.device import pendulum_device, save_device
    from accelcal.io.recording import write_recording
    from accelcal.simulate import run_simulation

    d = tmp_path_factory.mktemp("good")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["demo", "--out", str(d / "demo")]) == 0
    demo = d / "demo"
    # a shorter recording keeps the runs that get past parsing cheap
    lines = (demo / "rate_table.csv").read_text().splitlines()
    n_comment = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    (demo / "small.csv").write_text("\n".join(lines[:n_comment + 1 + 150]) + "\n")
    lines = (demo / "poses.csv").read_text().splitlines()
    n_comment = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    (demo / "poses_small.csv").write_text("\n".join(lines[:n_comment + 1] + lines[n_comment + 1::3]) + "\n")

    pend = d / "pend"
    pend.mkdir()
    pd = pendulum_device()
    save_device(pd, pend / "device.json")
    save_calibration(Calibration.nominal(pd), pend / "calibration.json")
    write_recording(pend / "small.csv", run_simulation(pd, "pendulum", seed=5, duration_s=3.0).recording)
    return {"six": demo, "pend": pend, "root": d}


def argv_for(cmd: str, dev: Path, cal: Path, rec: Path, out: Path, engine: str = "float") -> list[str]:
    """The command line of ``cmd`` on these inputs, writing into ``out``."""
    dev, cal, rec = str(dev), str(cal), str(rec)
    if cmd == "simulate":
        return ["simulate", "--device", dev, "--calibration", cal, "--motion", "static_poses",
                "--param", "poses=6", "--seed", "1", "-o", str(out / "sim.csv")]
    if cmd == "calibrate":
        return ["calibrate", "--device", dev, rec, "-o", str(out / "cal.json")]
    if cmd == "header":
        return ["header", "--device", dev, "--calibration", cal, "-o", str(out / "cal.h")]
    if cmd == "resolve":
        return ["resolve", "--device", dev, "--calibration", cal, rec, "--engine", engine,
                "-o", str(out / "res.csv")]
    if cmd == "diagnose":
        return ["diagnose", "--device", dev, "--calibration", cal, rec, "--folds", "3",
                "--json", str(out / "diag.json"), "--report", str(out / "report")]
    if cmd in ("attitude", "displacement", "rate"):
        return [cmd, "--device", dev, "--calibration", cal, rec, "--engine", engine,
                "-o", str(out / "est.csv")]
    raise AssertionError(cmd)


def inputs_for(good, cmd: str) -> dict[str, Path]:
    base = good["pend"] if cmd == "attitude" else good["six"]
    files = {"dev": base / "device.json", "cal": base / "calibration.json", "rec": base / "small.csv"}
    if cmd == "calibrate":
        files["rec"] = base / "poses_small.csv"
        # calibrate takes no calibration; simulate's --calibration is optional but used here
    return files


def run_cli(argv, capfd):
    """main(argv) in-process: (exit code, stderr text, warnings raised)."""
    capfd.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            rc = main(argv)
        except SystemExit as e:  # argparse; should not happen with these argv
            rc = e.code if isinstance(e.code, int) else 1
    err = capfd.readouterr().err
    return rc, err, [f"{w.category.__name__}: {w.message}" for w in caught]


@contextlib.contextmanager
def scratch(good):
    """(input dir, empty output dir), removed afterwards (tmp_path_factory's
    numbered directories get slower to make with every example)."""
    with tempfile.TemporaryDirectory(dir=good["root"]) as d:
        d = Path(d)
        (d / "in").mkdir()
        (d / "out").mkdir()
        yield d / "in", d / "out"


def check_rejected(rc, err, caught, out: Path, what: str):
    lines = err.splitlines()
    assert rc == 2, f"{what}: exit {rc}, stderr {err!r}"
    assert "Traceback" not in err, f"{what}: traceback on stderr: {err!r}"
    assert len(lines) == 1 and lines[0].strip(), f"{what}: {len(lines)} stderr lines: {err!r}"
    assert not caught, f"{what}: Python warnings would add stderr lines: {caught}"
    left = sorted(p.name for p in out.iterdir())
    assert not left, f"{what}: left files behind in the output directory: {left}"


def check_clean(rc, err, caught, out: Path, what: str):
    """Either a success (exit 0, output written) or a clean rejection.  (On
    success the contract does not limit stderr: warnings are allowed.)"""
    if rc == 0:
        assert any(out.iterdir()), f"{what}: exit 0 but no output"
        assert "Traceback" not in err, f"{what}: {err!r}"
    else:
        check_rejected(rc, err, caught, out, what)


class Bad:
    """A bad file's content with a short description (what hypothesis prints)."""

    def __init__(self, what: str, data):
        self.what, self.data = what, data

    def __repr__(self):
        d = self.data
        return f"<{self.what}: {len(d)} {'chars' if isinstance(d, str) else 'bytes'}: {d[:160]!r}...>"


# ---- JSON mutations ----------------------------------------------------------

NAN, INF = float("nan"), float("inf")
HUGE_TOKEN = "__ACCELCAL_HUGE__"
BAD_NUMBERS = [NAN, INF, -INF, HUGE_TOKEN, "abc", "", None, [], {}, True, [1.0, 2.0]]
BAD_STRINGS = [None, 12, [], {}, 1.5]


def dump_json(obj) -> str:
    text = json.dumps(obj, indent=2, allow_nan=True)  # NaN / Infinity tokens: not JSON
    return text.replace(json.dumps(HUGE_TOKEN), "1e999")  # parses to inf


def _paths(obj, prefix=()):
    """Every (path, leaf) under obj."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from _paths(v, prefix + (i,))
    else:
        yield prefix, obj


def _set(obj, path, value):
    for p in path[:-1]:
        obj = obj[p]
    obj[path[-1]] = value


def _del(obj, path):
    for p in path[:-1]:
        obj = obj[p]
    del obj[path[-1]]


DEVICE_NUMBER_KEYS = ("sample_rate_hz", "gravity_mps2", "raw_min", "raw_max")
DEVICE_CHANNEL_KEYS = ("position_m", "axis", "counts_per_mps2", "zero_counts")
CAL_CHANNEL_KEYS = ("offset_counts", "sensitivity")


def _diff(a, b, path="") -> str:
    """Where two JSON values differ (first few places), for messages."""
    if type(a) is not type(b) or not isinstance(a, (dict, list)):
        return "" if (a == b or (a != a and b != b)) else f"{path or '.'}={b!r:.60}"
    if isinstance(a, dict):
        parts = [f"{path}.{k} removed" for k in a if k not in b]
        parts += [_diff(a[k], b[k], f"{path}.{k}") for k in a if k in b]
    else:
        parts = [] if len(a) == len(b) else [f"{path} len {len(a)}->{len(b)}"]
        parts += [_diff(x, y, f"{path}[{i}]") for i, (x, y) in enumerate(zip(a, b))]
    return "; ".join(p for p in parts if p)[:200]


def bad_text_strategy(valid: str):
    """Whole-file damage: empty, truncated, binary garbage, wrong top type."""
    body = valid.rstrip()
    return st.one_of(
        st.just(""),
        st.just("   \n"),
        st.integers(1, len(body) - 1).map(lambda k: body[:k]),
        st.binary(min_size=1, max_size=200).map(lambda b: b"\xff\x00" + b),
        st.sampled_from(["[]", "null", "42", '"device"', "[{}]", "{}"]),
    )


@st.composite
def bad_device(draw, valid: dict, cmd: str):
    d = copy.deepcopy(valid)
    n = len(d["channels"])
    kinds = ["top_number", "channel_value", "missing", "vector_len", "name_type", "text",
             "physics", "channels_type"]
    if cmd not in ("simulate", "calibrate"):
        kinds.append("channel_count")
    kind = draw(st.sampled_from(kinds))
    if kind == "text":
        return Bad("device text", draw(bad_text_strategy(json.dumps(valid, indent=2))))
    if kind == "top_number":
        d[draw(st.sampled_from(DEVICE_NUMBER_KEYS))] = draw(st.sampled_from(BAD_NUMBERS))
    elif kind == "channel_value":
        i, key = draw(st.integers(0, n - 1)), draw(st.sampled_from(DEVICE_CHANNEL_KEYS))
        if isinstance(d["channels"][i][key], list):
            d["channels"][i][key][draw(st.integers(0, 2))] = draw(st.sampled_from(BAD_NUMBERS))
        else:
            d["channels"][i][key] = draw(st.sampled_from(BAD_NUMBERS))
    elif kind == "missing":
        if draw(st.booleans()):
            del d[draw(st.sampled_from(("name", "channels") + DEVICE_NUMBER_KEYS))]
        else:
            del d["channels"][draw(st.integers(0, n - 1))][draw(st.sampled_from(DEVICE_CHANNEL_KEYS))]
    elif kind == "vector_len":
        i, key = draw(st.integers(0, n - 1)), draw(st.sampled_from(("position_m", "axis")))
        v = d["channels"][i][key]
        d["channels"][i][key] = draw(st.sampled_from([v[:2], v + [0.0], [], v[:1]]))
    elif kind == "name_type":
        d["name"] = draw(st.sampled_from(BAD_STRINGS))
    elif kind == "physics":
        what = draw(st.sampled_from(["rate0", "rate_neg", "g0", "raw_swap", "axis0", "k0", "k_neg"]))
        i = draw(st.integers(0, n - 1))
        if what == "rate0":
            d["sample_rate_hz"] = 0.0
        elif what == "rate_neg":
            d["sample_rate_hz"] = -d["sample_rate_hz"]
        elif what == "g0":
            d["gravity_mps2"] = draw(st.sampled_from([0.0, -9.8]))
        elif what == "raw_swap":
            d["raw_min"], d["raw_max"] = d["raw_max"], d["raw_min"]
        elif what == "axis0":
            d["channels"][i]["axis"] = [0.0, 0.0, 0.0]
        elif what == "k0":
            d["channels"][i]["counts_per_mps2"] = 0.0
        else:
            d["channels"][i]["counts_per_mps2"] = -abs(d["channels"][i]["counts_per_mps2"])
    elif kind == "channels_type":
        d["channels"] = draw(st.sampled_from([[], {}, None, "abc", [1, 2, 3, 4, 5, 6], [[]] * n]))
    elif kind == "channel_count":
        if cmd == "calibrate" or draw(st.booleans()):
            d["channels"].append(copy.deepcopy(d["channels"][0]))  # recording lacks raw_N
        else:
            del d["channels"][draw(st.integers(0, n - 1))]
    return Bad(f"device {kind}: {_diff(valid, d)}", dump_json(d))


@st.composite
def bad_calibration(draw, valid: dict):
    c = copy.deepcopy(valid)
    n = len(c["channels"])
    kind = draw(st.sampled_from(["channel_value", "missing", "vector_len", "device_name", "text",
                                 "channel_count", "channels_type", "position"]))
    if kind == "text":
        return Bad("calibration text", draw(bad_text_strategy(json.dumps(valid, indent=2))))
    if kind == "channel_value":
        i, key = draw(st.integers(0, n - 1)), draw(st.sampled_from(CAL_CHANNEL_KEYS))
        if key == "sensitivity":
            c["channels"][i][key][draw(st.integers(0, 2))] = draw(st.sampled_from(BAD_NUMBERS))
        else:
            c["channels"][i][key] = draw(st.sampled_from(BAD_NUMBERS))
    elif kind == "missing":
        if draw(st.booleans()):
            del c["channels"]
        else:
            del c["channels"][draw(st.integers(0, n - 1))][draw(st.sampled_from(CAL_CHANNEL_KEYS))]
    elif kind == "vector_len":
        i = draw(st.integers(0, n - 1))
        v = c["channels"][i]["sensitivity"]
        c["channels"][i]["sensitivity"] = draw(st.sampled_from([v[:2], v + [0.0], [], v[:1]]))
    elif kind == "device_name":
        c["device"] = draw(st.sampled_from(["another-device", ""] + BAD_STRINGS))
    elif kind == "channel_count":
        if draw(st.booleans()):
            c["channels"].append(copy.deepcopy(c["channels"][0]))
        else:
            del c["channels"][draw(st.integers(0, n - 1))]
    elif kind == "channels_type":
        c["channels"] = draw(st.sampled_from([[], {}, None, "abc", [1, 2, 3, 4, 5, 6], [[]] * n]))
    elif kind == "position":
        i = draw(st.integers(0, n - 1))
        c["channels"][i]["position_m"] = draw(st.sampled_from(
            [[NAN, 0.0, 0.0], [0.0, INF, 0.0], [0.1, 0.0], "abc", None, [0.0, 0.0, 0.0, 0.0],
             [HUGE_TOKEN, 0.0, 0.0]]))
    return Bad(f"calibration {kind}: {_diff(valid, c)}", dump_json(c))


# ---- CSV mutations -----------------------------------------------------------

RAW_BAD = ["nan", "inf", "-inf", "abc", "1.5", "", "1e30", "0x10", "--1", "99999999999999999999999",
           "1 2", '"', "NaN"]
T_BAD = ["nan", "inf", "-inf", "abc", "", "1e400", "0..1"]
REF_BAD = ["abc", "1.2.3", "--", "0x"]


def _split_csv(text: str):
    lines = text.splitlines()
    h = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    return lines[:h], lines[h].split(","), [ln.split(",") for ln in lines[h + 1:]]


def _join_csv(comments, header, rows) -> str:
    return "\n".join(comments + [",".join(header)] + [",".join(r) for r in rows]) + "\n"


@st.composite
def bad_recording(draw, valid: str, n_channels: int, raw_max: int):
    notes = []
    blob = _bad_recording(draw, valid, n_channels, raw_max, notes)
    return Bad("recording " + " ".join(notes), blob)


def _bad_recording(draw, valid, n_channels, raw_max, notes):
    comments, header, rows = _split_csv(valid)
    n = len(rows)
    kind = draw(st.sampled_from(["raw_cell", "t_cell", "ref_cell", "t_order", "drop_column",
                                 "cell_count", "truncate", "no_rows", "text", "bad_utf8"]))
    r = draw(st.integers(1, n - 2))
    if kind == "raw_cell":
        j = header.index(f"raw_{draw(st.integers(0, n_channels - 1))}")
        rows[r][j] = draw(st.sampled_from(RAW_BAD))
        notes.append(f"row {r} {header[j]}={rows[r][j]!r}")
    elif kind == "t_cell":
        rows[r][header.index("t")] = draw(st.sampled_from(T_BAD))
        notes.append(f"row {r} t={rows[r][header.index('t')]!r}")
    elif kind == "ref_cell":
        cols = [c for c in ("f_x", "f_y", "w_z", "dw_y", "temp_c", "pose") if c in header]
        col = draw(st.sampled_from(cols))
        rows[r][header.index(col)] = draw(st.sampled_from(REF_BAD + (["1.5", "inf"] if col == "pose" else [])))
        notes.append(f"row {r} {col}={rows[r][header.index(col)]!r}")
    elif kind == "raw_range":
        j = header.index(f"raw_{draw(st.integers(0, n_channels - 1))}")
        rows[r][j] = str(draw(st.sampled_from([-1, raw_max + 1, 2**31, -2**31, 2**63])))
        notes.append(f"row {r} {header[j]}={rows[r][j]!r} (raw_max {raw_max})")
    elif kind == "t_order":
        jt = header.index("t")
        how = draw(st.sampled_from(["equal", "swap", "back", "all_zero"]))
        notes.append(f"t {how} at row {r}")
        if how == "equal":
            rows[r][jt] = rows[r - 1][jt]
        elif how == "swap":
            rows[r][jt], rows[r + 1][jt] = rows[r + 1][jt], rows[r][jt]
        elif how == "back":  # below the previous row's t (a fixed step back could land in a gap)
            rows[r][jt] = repr(float(rows[r - 1][jt]) - 0.5)
        else:
            for row in rows:
                row[jt] = "0"
    elif kind == "drop_column":
        col = draw(st.sampled_from(["t"] + [f"raw_{i}" for i in range(n_channels)]))
        j = header.index(col)
        notes.append(f"drop column {col}")
        header = header[:j] + header[j + 1:]
        rows = [row[:j] + row[j + 1:] for row in rows]
    elif kind == "cell_count":
        notes.append(f"cell count of row {r}")
        if draw(st.booleans()):
            rows[r] = rows[r][:-draw(st.integers(1, len(rows[r]) - 1))]
        else:
            rows[r] = rows[r] + ["1"] * draw(st.integers(1, 3))
    elif kind == "truncate":
        # cut inside a row, before its last separator, so the row is short; the line then ends
        # (a last line cut short with no line end after it is a logger stopped mid-write: it is
        # left out with a note, test_io_recording)
        line = ",".join(rows[r])
        cut = draw(st.integers(1, line.rfind(",") - 1))
        notes.append(f"truncated in row {r} at char {cut}, then a line end")
        return _join_csv(comments, header, rows[:r]).encode() + line[:cut].encode() + b"\n"
    elif kind == "no_rows":
        how = draw(st.sampled_from(["header_only", "comments_only", "cut_header"]))
        notes.append(how)
        if how == "header_only":
            return _join_csv(comments, header, []).encode()
        if how == "comments_only":
            return ("\n".join(comments) + "\n").encode()
        hl = ",".join(header)
        return ("\n".join(comments) + "\n" + hl[:draw(st.integers(0, hl.index("raw_") + 4))]).encode()
    elif kind == "text":
        notes.append("empty/garbage")
        return draw(st.one_of(st.just(b""), st.just(b"\n\n"),
                              st.binary(min_size=1, max_size=300).map(lambda b: b"\xff\xfe\x00" + b)))
    else:  # invalid UTF-8 inside a cell
        notes.append(f"invalid utf-8 in row {r}")
        j = header.index(f"raw_{draw(st.integers(0, n_channels - 1))}")
        data = _join_csv(comments, header, rows[:r]).encode()
        row = rows[r][:]
        row[j] = "\x00"
        return data + ",".join(row).replace("\x00", "\udcff").encode("utf-8", "surrogateescape") + b"\n"
    return _join_csv(comments, header, rows).encode()


# ---- the tests -----------------------------------------------------------------

ALL = ["simulate", "calibrate", "header", "resolve", "diagnose", "attitude", "displacement", "rate"]
WITH_CAL = [c for c in ALL if c != "calibrate"]
WITH_REC = [c for c in ALL if c not in ("simulate", "header")]
ENGINES = st.sampled_from(["float", "fixed"])


def _write(path: Path, data):
    data = getattr(data, "data", data)
    if isinstance(data, str):
        path.write_text(data, encoding="utf-8")
    else:
        path.write_bytes(data)


@pytest.mark.parametrize("cmd", ALL)
@SETTINGS
@given(data=st.data())
def test_bad_device_json(good, cmd, data, capfd):
    f = inputs_for(good, cmd)
    text = data.draw(bad_device(json.loads(f["dev"].read_text()), cmd), label="device")
    with scratch(good) as (ind, out):
        _write(ind / "device.json", text)
        rc, err, caught = run_cli(argv_for(cmd, ind / "device.json", f["cal"], f["rec"], out,
                                           data.draw(ENGINES)), capfd)
        check_rejected(rc, err, caught, out, f"{cmd} with {text!r}")


@pytest.mark.parametrize("cmd", WITH_CAL)
@SETTINGS
@given(data=st.data())
def test_bad_calibration_json(good, cmd, data, capfd):
    f = inputs_for(good, cmd)
    text = data.draw(bad_calibration(json.loads(f["cal"].read_text())), label="calibration")
    with scratch(good) as (ind, out):
        _write(ind / "calibration.json", text)
        rc, err, caught = run_cli(argv_for(cmd, f["dev"], ind / "calibration.json", f["rec"], out,
                                           data.draw(ENGINES)), capfd)
        check_rejected(rc, err, caught, out, f"{cmd} with {text!r}")


@pytest.mark.parametrize("cmd", WITH_REC)
@SETTINGS
@given(data=st.data())
def test_bad_recording_csv(good, cmd, data, capfd):
    f = inputs_for(good, cmd)
    dev = json.loads(f["dev"].read_text())
    blob = data.draw(bad_recording(f["rec"].read_text(), len(dev["channels"]), dev["raw_max"]),
                     label="recording")
    with scratch(good) as (ind, out):
        _write(ind / "rec.csv", blob)
        rc, err, caught = run_cli(argv_for(cmd, f["dev"], f["cal"], ind / "rec.csv", out,
                                           data.draw(ENGINES)), capfd)
        check_rejected(rc, err, caught, out, f"{cmd} with {blob!r}")


# A raw reading outside the device's [raw_min, raw_max] cannot come from that
# device (it clips there, data contract "Sensor model"): every command refuses
# it, naming the file line (comments and header counted) and the column.
@pytest.mark.parametrize("cmd", WITH_REC)
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_raw_out_of_range_refused(good, cmd, data, capfd):
    f = inputs_for(good, cmd)
    dev = json.loads(f["dev"].read_text())
    comments, header, rows = _split_csv(f["rec"].read_text())
    r = data.draw(st.integers(0, len(rows) - 1))
    col = f"raw_{data.draw(st.integers(0, len(dev['channels']) - 1))}"
    j = header.index(col)
    rows[r][j] = str(data.draw(st.sampled_from([dev["raw_min"] - 1, dev["raw_max"] + 1, 65536, 2**31, -2**31])))
    line = len(comments) + 1 + r + 1
    with scratch(good) as (ind, out):
        _write(ind / "rec.csv", _join_csv(comments, header, rows))
        rc, err, caught = run_cli(argv_for(cmd, f["dev"], f["cal"], ind / "rec.csv", out,
                                           data.draw(ENGINES)), capfd)
        what = f"{cmd} with row {r} {col}={rows[r][j]}"
        check_rejected(rc, err, caught, out, what)
        assert f"row {line}, column {col}:" in err and "[raw_min, raw_max]" in err, f"{what}: {err!r}"


# ---- extreme (well-formed but absurd) values -------------------------------------

EXTREME = [1e300, -1e300, 1e30, 1e-300, 5e-324, 2.0**63, 1e9]
DEV_EXTREME_KEYS = DEVICE_CHANNEL_KEYS + ("sample_rate_hz", "gravity_mps2", "raw_max")
CAL_EXTREME_KEYS = CAL_CHANNEL_KEYS + ("position_m",)


def with_extreme(obj: dict, key: str, value: float, channel: int = 0, index: int = 0) -> dict:
    obj = copy.deepcopy(obj)
    ch = obj["channels"][channel]
    if key in ("sample_rate_hz", "gravity_mps2", "raw_max"):
        obj[key] = value
    elif isinstance(ch.get(key), list) or key == "position_m":
        v = list(ch.get(key) or [0.0, 0.0, 0.0])
        v[index] = value
        ch[key] = v
    else:
        ch[key] = value
    return obj


# Values that are legal in form but extreme: the command may run or refuse, but
# a refusal must be clean (exit 2, one line, no output) -- never exit 3.
@pytest.mark.parametrize("cmd", WITH_CAL + ["calibrate"])
@settings(max_examples=max(15, EXAMPLES // 3), deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_extreme_values_clean(good, cmd, data, capfd):
    f = inputs_for(good, cmd)
    which = "dev" if cmd == "calibrate" else data.draw(st.sampled_from(["dev", "cal"]))
    key = data.draw(st.sampled_from(DEV_EXTREME_KEYS if which == "dev" else CAL_EXTREME_KEYS))
    value = data.draw(st.sampled_from(EXTREME))
    obj = json.loads(f[which].read_text())
    channel = data.draw(st.integers(0, len(obj["channels"]) - 1))
    index = data.draw(st.integers(0, 2))
    obj = with_extreme(obj, key, value, channel, index)
    with scratch(good) as (ind, out):
        _write(ind / f"{which}.json", dump_json(obj))
        files = dict(f, **{which: ind / f"{which}.json"})
        rc, err, caught = run_cli(argv_for(cmd, files["dev"], files["cal"], files["rec"], out,
                                           data.draw(ENGINES)), capfd)
        check_clean(rc, err, caught, out, f"{cmd} with {which} channels[{channel}].{key}[{index}]={value!r}")


def _bug(cmd, which, key, value, engine, reason):
    """A bad-input bug found by this file and fixed (field limits in the loaders, numerical
    failures turned into input errors): kept as a regression test."""
    return pytest.param(cmd, which, key, value, engine, id=f"{cmd}-{which}-{key}-{value:g}-{engine}")


B1 = ("B1: device position_m of 1e300 overflows in the 6-DOF rank check: numpy RuntimeWarnings "
      "(2 lines each) go to stderr before the one-line error")
FIXED_BUGS = [
    *[_bug(c, "dev", "position_m", 1e300, "float", B1) for c in ALL],
    _bug("simulate", "dev", "sample_rate_hz", 1e30, "float",
         "B2: simulate with sample_rate_hz=1e30: exit 3, internal error: ValueError: Recording.t: "
         "not strictly increasing at sample 61"),
    _bug("calibrate", "dev", "gravity_mps2", 5e-324, "float",
         "B3: calibrate with gravity_mps2=5e-324: exit 3, internal error: LinAlgError: SVD did not "
         "converge, LAPACK '** On entry to DLASCL' lines and RuntimeWarnings on stderr"),
    *[_bug(c, "dev", "gravity_mps2", 1e300, "float",
           f"B4: {c} with gravity_mps2=1e300: exit 3, internal error: OverflowError: (34, "
           "'Numerical result out of range')") for c in ("displacement", "rate")],
    *[_bug(c, "cal", k, 1e30, "float",
           f"B5: {c} --engine float with calibration channels[0].{k}[0]=1e30: exit 3, internal "
           "error: LinAlgError: sensor matrix has rank < 6")
      for c in ("resolve", "displacement", "rate") for k in ("sensitivity", "position_m")],
    _bug("rate", "cal", "sensitivity", 1e30, "fixed",
         "B5: rate --engine fixed with calibration sensitivity 1e30: exit 3, LinAlgError"),
    _bug("attitude", "cal", "sensitivity", 1e300, "float",
         "B6: attitude with calibration sensitivity 1e300: RuntimeWarning 'overflow encountered in "
         "scalar power' on stderr before the one-line error"),
    _bug("diagnose", "cal", "sensitivity", 1e300, "float",
         "B7: diagnose with calibration sensitivity 1e300: exit 3, internal error: LinAlgError: "
         "Eigenvalues did not converge (plus RuntimeWarnings)"),
]


@pytest.mark.parametrize("cmd, which, key, value, engine", FIXED_BUGS)
def test_fixed_bad_input_bugs(good, cmd, which, key, value, engine, capfd):
    """Regression tests of the bad-input bugs found here (B1-B7): each must now refuse cleanly."""
    f = inputs_for(good, cmd)
    obj = with_extreme(json.loads(f[which].read_text()), key, value)
    with scratch(good) as (ind, out):
        _write(ind / f"{which}.json", dump_json(obj))
        files = dict(f, **{which: ind / f"{which}.json"})
        rc, err, caught = run_cli(argv_for(cmd, files["dev"], files["cal"], files["rec"], out, engine),
                                  capfd)
        check_clean(rc, err, caught, out, f"{cmd} with {which} {key}={value!r}")
        # rc 0 with RuntimeWarnings is allowed by check_clean; these cases refuse
        assert rc == 2


# Unknown keys and columns are the contract's extension point: never an error.
@pytest.mark.parametrize("cmd", ["header", "resolve", "calibrate"])
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(key=st.text("abcdefghijklmnopqrstuvwxyz_", min_size=3, max_size=12).map(lambda s: "x_" + s),
       value=st.sampled_from([1, "text", [1, 2], {"a": None}, None]))
def test_unknown_fields_accepted(good, cmd, key, value, capfd):
    f = inputs_for(good, cmd)
    dev, cal = json.loads(f["dev"].read_text()), json.loads(f["cal"].read_text())
    dev[key] = value
    dev["channels"][0][key] = value
    cal[key] = value
    cal["channels"][1][key] = value
    comments, header, rows = _split_csv(f["rec"].read_text())
    header = header[:1] + [key] + header[1:]
    rows = [row[:1] + ["hello"] + row[1:] for row in rows]
    with scratch(good) as (ind, out):
        _write(ind / "dev.json", json.dumps(dev))
        _write(ind / "cal.json", json.dumps(cal))
        _write(ind / "rec.csv", _join_csv(comments, header, rows))
        rc, err, caught = run_cli(argv_for(cmd, ind / "dev.json", ind / "cal.json", ind / "rec.csv", out),
                                  capfd)
        assert rc == 0, err
        assert any(out.iterdir())
        assert "Traceback" not in err


@pytest.mark.parametrize("argv", [
    ["resolve", "--device", "{six}/device.json", "--calibration", "{six}/calibration.json", "{rec}", "-o", "{rec}"],
    ["calibrate", "--device", "{six}/device.json", "{poses}", "-o", "{poses}"],
    ["calibrate", "--device", "{six}/device.json", "{poses}", "-o", "{six}/device.json"],
    ["diagnose", "--device", "{six}/device.json", "--calibration", "{six}/calibration.json", "{rec}",
     "--json", "{six}/calibration.json"],
])
def test_an_output_that_is_an_input_is_refused(good, argv, capfd, tmp_path):
    """-o on the recording it reads would replace the recording by the result (it did, exit 0)."""
    import shutil

    from cli_run import run
    six = tmp_path / "six"
    shutil.copytree(good["six"], six)
    paths = {"six": six, "rec": six / "small.csv", "poses": six / "poses_small.csv"}
    argv = [x.format(**paths) for x in argv]
    before = {p: p.read_bytes() for p in six.iterdir() if p.is_file()}
    rc, _, err, _ = run(argv, capfd)
    assert rc == 2 and err.count("\n") == 1 and "is also an input of this command" in err, err
    assert {p: p.read_bytes() for p in six.iterdir() if p.is_file()} == before


def test_a_recording_given_twice_is_refused(good, capfd):
    """Its poses would count twice (the calibration's chi2 and uncertainties as for twice the
    data); it went through without a word."""
    from cli_run import run
    six = good["six"]
    rc, _, err, _ = run(["calibrate", "--device", six / "device.json", six / "poses_small.csv",
                         f"{six}/./poses_small.csv", "-o", good["root"] / "twice.json"], capfd)
    assert rc == 2 and err.count("\n") == 1 and "given twice" in err
    assert not (good["root"] / "twice.json").exists()
