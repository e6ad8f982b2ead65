"""convert of a recording CSV in chunks, two passes (accelcal.convert.stream; docs/streaming.md):
the whole-file output byte for byte, its notes and device, at chunks of one row to more than the
file; never the file whole; the whole-file refusal word for word, exit 2, no output file."""
from __future__ import annotations

import json

import numpy as np
import pytest

from accelcal.cli.main import build_parser
from accelcal.convert import bounded, bounded_scale, formats, stream
from accelcal.convert.formats import convert_file
from accelcal.io.device import save_device
from accelcal.io.units_cli import scale_from_args
from accelcal.io.recording import Recording, write_recording

from cli_run import one_refusal, run
from indep_model import make_jig
from shared_data import XSENS_ACC, shared_file

#: bytes of text per chunk: one row a chunk, a few rows, some thousand rows, more than the file
BLOCKS = (1, 97, 1 << 14, 1 << 30)


def poses(n: int, seed: int, rate: float = 100.0, signed: bool = False, zero: int = 2048) -> Recording:
    """Still poses of 300 samples (4096 counts per g, noise 6 counts), each begun by 40 samples
    of motion (pose -1), in counts: unsigned about ``zero`` unless ``signed``."""
    rng = np.random.default_rng(seed)
    dirs = np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 0, -1], [0, -1, 0], [-1, 0, 0]], float)
    pose = (np.arange(n) // 300) % 6
    raw = np.round(dirs[pose] * 4096 + rng.normal(0, 6, (n, 3))).astype(np.int64) + (0 if signed else zero)
    moving = (np.arange(n) % 300) < 40
    raw[moving] += rng.integers(-900, 900, (int(moving.sum()), 3))
    return Recording(t=np.arange(n) / rate, raw=raw, pose=np.where(moving, -1, pose))


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("stream_convert")
    out = {}
    rec = poses(1800, 1)
    write_recording(d / "plain.csv", Recording(t=rec.t, raw=rec.raw, metadata={"device": "x"}))
    jig = make_jig(seed=7, device="triad16", rate=100.0, n_poses=6, repeats=False, hold_s=(1.0, 1.5))["recording"]   # the independent generator's
    write_recording(d / "labelled.csv", jig)     # labelled poses with their stated f, and a temp_c column maybe
    signed = poses(1800, 2, signed=True)
    signed.raw[:5] = 0                                              # a logger's 0, 0, 0 before the first value
    signed.raw[700:760, 1] = 2 ** 15 - 1                            # clipped at the rail
    write_recording(d / "lead_clip.csv", Recording(t=signed.t, raw=signed.raw))
    ms = poses(1800, 3)
    write_recording(d / "ms.csv", Recording(t=1000.0 * ms.t + 5.0, raw=ms.raw))      # t in ms: told, noted
    held = poses(1800, 4)
    held.raw[1::2] = held.raw[0::2]                                 # each reading held for two rows
    write_recording(d / "held.csv", Recording(t=held.t, raw=held.raw))
    (d / "regions.json").write_text(json.dumps({"z_p": {"start": 40, "end": 300}, "y_p": {"start": 340, "end": 600},
                                                "x_p": {"start": 640, "end": 900}}))
    for name in ("plain", "labelled", "lead_clip", "ms", "held"):
        out[name] = d / f"{name}.csv"
    out["dir"] = d
    return out


def whole(capfd, d, src, tag, *args):
    """The whole-file command's output, device and stderr."""
    o, dev = d / f"whole_{tag}.csv", d / f"whole_{tag}.json"
    rc, said, err, _ = run(["convert", src, *args, "-o", o, "--device-out", dev, "--whole-file", "--quiet"], capfd)
    assert rc == 0, err
    return o.read_bytes(), dev.read_text(), err, said


CASES = [("plain", ()), ("labelled", ()), ("lead_clip", ("--bits", "16")), ("ms", ()), ("held", ()),
         ("plain", ("--full-scale", "2")), ("plain", ("--regions", "REGIONS", "--stated-f")),
         ("labelled", ("--regions", "REGIONS"))]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_chunks_give_the_whole_file_bytes(files, capfd, case, tmp_path):
    name, args = CASES[case]
    args = tuple(str(files["dir"] / "regions.json") if a == "REGIONS" else a for a in args)
    src = files[name]
    ref, ref_dev, ref_err, ref_said = whole(capfd, tmp_path, src, name, *args)
    o, dev = tmp_path / "s.csv", tmp_path / "s.json"
    rc, said, err, _ = run(["convert", src, *args, "-o", o, "--device-out", dev, "--quiet"], capfd)
    assert rc == 0, err
    assert (o.read_bytes(), dev.read_text(), err) == (ref, ref_dev, ref_err)
    assert said.replace("s.csv", "W").replace("s.json", "D") == \
        ref_said.replace(f"whole_{name}.csv", "W").replace(f"whole_{name}.json", "D")
    regions = next((args[i + 1] for i, a in enumerate(args) if a == "--regions"), None)
    for block in BLOCKS:
        conv = convert_file(src, stream=True, block_bytes=block, regions=regions, stated_f="--stated-f" in args,
                            bits=16, scale=None if "--full-scale" not in args else whole_scale(args))
        assert conv.writer is not None                      # it went the chunked way
        conv.write(o)
        assert o.read_bytes() == ref, block
        save_device(conv.device, dev)
        assert dev.read_text() == ref_dev


def whole_scale(args):
    """The Scale the command line's units options give."""
    a = build_parser().parse_args(["convert", "x", "-o", "y", *args])
    return scale_from_args(a)


def test_notes_are_made(files, capfd, tmp_path):
    """The cases above exercise the inference: the placeholder, clip, ms, held notes are there."""
    for name, words in (("lead_clip", ("0, 0, 0", "clipped")), ("ms", ("ms",)), ("held", ("repeat the row before",))):
        err = whole(capfd, tmp_path, files[name], name)[2]
        assert all(w in err for w in words), (name, err)


def test_never_read_whole(files, monkeypatch, tmp_path):
    """The chunked path holds the rows of a chunk of text at a time: neither the whole-file text reader nor the
    whole-file recording reader is called (the old convert called both)."""
    def whole_read(*a, **k):
        raise AssertionError("read whole")
    monkeypatch.setattr(formats, "read_text_bytes", whole_read)
    monkeypatch.setattr(formats, "read_recording", whole_read)
    seen = []
    chunks = stream.csv_chunks

    def counted(*a, **k):
        for ch in chunks(*a, **k):
            seen.append(ch.n)
            yield ch
    for module in (stream, bounded, bounded_scale):
        monkeypatch.setattr(module, "csv_chunks", counted)
    conv = convert_file(files["plain"], stream=True, block_bytes=4096)
    conv.write(tmp_path / "o.csv")
    # without a stated scale four passes (the sums, the noise, the still stretches, the write), each chunk
    # 4 KiB of rows (of 15 bytes and more)
    assert sum(seen) == 4 * 1800 and max(seen) <= 4096 // 15


def bad_files(d):
    good = poses(800, 5)
    lines = ["t,raw_0,raw_1,raw_2"] + [f"{t!r},{a},{b},{c}" for t, (a, b, c) in zip(good.t, good.raw.tolist())]
    cases = {}
    cell = list(lines)
    cell[500] = cell[500].replace(",", ",x", 1)
    cases["cell"] = cell
    back = list(lines)
    back[600], back[601] = back[601], back[600]
    cases["t_back"] = back
    big = list(lines)
    big[700] = "7.0,70000,2048,2048"
    cases["range"] = big
    for k, v in cases.items():
        (d / f"{k}.csv").write_text("\n".join(v) + "\n")
    return list(cases)


def test_refusals_are_the_whole_file_ones(capfd, tmp_path):
    for k in bad_files(tmp_path):
        src = tmp_path / f"{k}.csv"
        rc_w, _, err_w, _ = run(["convert", src, "-o", tmp_path / "w.csv", "--whole-file", "--quiet"], capfd)
        rc_s, _, err_s, _ = run(["convert", src, "-o", tmp_path / "s.csv", "--quiet"], capfd)
        assert rc_w == rc_s == 2 and err_s == err_w and one_refusal(err_s), (k, err_s)
        assert not (tmp_path / "s.csv").exists() and not (tmp_path / "w.csv").exists()
        assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".") or "tmp" in p.name] == []


def test_real_recording(capfd, tmp_path):
    """A real recording (imu_tk's Xsens log) made a contract CSV, then converted in chunks and whole."""
    path = shared_file(*XSENS_ACC)
    if path is None:
        pytest.skip("no ../shared/data beside the repository")
    rec = tmp_path / "xsens.csv"
    rc, _, err, _ = run(["convert", path, "-o", rec, "--quiet"], capfd)
    assert rc == 0, err
    ref = whole(capfd, tmp_path, rec, "xsens")
    for block in (1000, 1 << 20):
        conv = convert_file(rec, stream=True, block_bytes=block)
        assert conv.writer is not None
        conv.write(tmp_path / "s.csv")
        assert (tmp_path / "s.csv").read_bytes() == ref[0]
