"""The libFuzzer harness and its seed corpus work, even where clang is absent.

fuzz/fuzz_core.c is built with the host C compiler (gcc or cc), AddressSanitizer
and UndefinedBehaviorSanitizer, and without libFuzzer: fuzz/replay_main.c feeds
each file of fuzz/corpus/ to LLVMFuzzerTestOneInput once.  Every property the
harness checks (statuses, exact results, the resolve bound, the build against a
double-precision reference, ...) runs on every seed; a violation or a sanitizer
report aborts the replay.  tools/fuzz.sh does the real fuzzing with clang.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CORPUS = ROOT / "fuzz" / "corpus"
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]


def _compiler() -> str | None:
    for cc in (os.environ.get("CC"), "gcc", "cc", "clang"):
        if cc and shutil.which(cc):
            return cc
    return None


def _compile_all(cc: str, jobs: list[tuple[Path, Path, str]]) -> None:
    """Compile (source, object, opt) pairs, two at a time (CI boxes have 2 cores)."""
    pending = list(jobs)
    running: list[tuple[subprocess.Popen, list[str]]] = []
    while pending or running:
        while pending and len(running) < 2:
            src, obj, opt = pending.pop(0)
            cmd = [cc, "-c", "-g", opt, *SAN, "-std=c99", "-Wall", "-Wextra", "-Werror",
                   f"-I{ROOT / 'include'}", f"-I{ROOT / 'csrc'}", str(src), "-o", str(obj)]
            running.append((subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True), cmd))
        proc, cmd = running.pop(0)
        _, err = proc.communicate()
        assert proc.returncode == 0, f"build failed:\n{' '.join(cmd)}\n{err}"


def _link(cc: str, objs: list[Path], exe: Path) -> None:
    r = subprocess.run([cc, *SAN, *map(str, objs), "-lm", "-o", str(exe)], capture_output=True, text=True)
    assert r.returncode == 0, f"link failed:\n{r.stderr}"


@pytest.fixture(scope="module")
def build(tmp_path_factory) -> dict:
    """The core (-O1) and the harness (-O0: it only checks) as sanitizer objects."""
    cc = _compiler()
    if cc is None:
        pytest.skip("no C compiler")
    d = tmp_path_factory.mktemp("fuzz_replay")
    probe = d / "probe.c"
    probe.write_text("int main(void) { return 0; }\n")
    r = subprocess.run([cc, *SAN, str(probe), "-o", str(d / "probe")], capture_output=True, text=True)
    if r.returncode != 0:
        pytest.skip(f"{cc} cannot build with -fsanitize=address,undefined: {r.stderr.strip()[:200]}")
    core = [(p, d / f"core_{p.stem}.o", "-O1") for p in sorted((ROOT / "csrc").glob("*.c"))]
    harness = [(ROOT / "fuzz" / "fuzz_core.c", d / "fuzz_core.o", "-O0"),
               (ROOT / "fuzz" / "replay_main.c", d / "replay_main.o", "-O0")]
    _compile_all(cc, harness + core)
    exe = d / "replay"
    _link(cc, [o for _, o, _ in harness + core], exe)
    return {"cc": cc, "dir": d, "exe": exe, "core": [o for _, o, _ in core], "main": d / "replay_main.o"}


@pytest.fixture(scope="module")
def replay(build) -> Path:
    return build["exe"]


def _env() -> dict:
    env = dict(os.environ)
    env["ASAN_OPTIONS"] = "detect_leaks=1:abort_on_error=0"
    env["UBSAN_OPTIONS"] = "print_stacktrace=1:halt_on_error=1"
    return env


def test_corpus_present_and_small():
    files = [p for p in CORPUS.iterdir() if p.is_file()]
    assert len(files) >= 100
    assert sum(p.stat().st_size for p in files) < 200_000
    # every harness target has seeds (the first byte selects it, mod 16)
    assert {p.read_bytes()[0] % 16 for p in files if p.stat().st_size} == set(range(16))


def test_corpus_matches_its_generator(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "fuzz" / "make_corpus.py"), "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    made = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    committed = {p.name: p.read_bytes() for p in CORPUS.glob("seed_*")}
    assert made == committed, "fuzz/corpus is stale: run python3 fuzz/make_corpus.py"


def test_replay_corpus(replay):
    n = sum(1 for p in CORPUS.iterdir() if p.is_file() and not p.name.startswith("."))
    r = subprocess.run([str(replay), str(CORPUS)], capture_output=True, text=True, timeout=120, env=_env())
    assert r.returncode == 0, f"replay failed (exit {r.returncode}):\n{r.stderr[-4000:]}"
    assert f"replay: {n} inputs ran" in r.stdout
    assert "runtime error" not in r.stderr


def test_replay_empty_and_short_inputs(replay, tmp_path):
    # every prefix of a seed is an input too (reads past the end give zeros)
    seeds = sorted(p for p in CORPUS.iterdir() if p.is_file())[::10]
    k = 0
    for p in seeds:
        data = p.read_bytes()
        for cut in (0, 1, 2, 5, len(data) // 2):
            (tmp_path / f"{k:04d}").write_bytes(data[:cut])
            k += 1
    r = subprocess.run([str(replay), str(tmp_path)], capture_output=True, text=True, timeout=120, env=_env())
    assert r.returncode == 0, f"replay failed (exit {r.returncode}):\n{r.stderr[-4000:]}"
    assert f"replay: {k} inputs ran" in r.stdout


def _mutant(build, tmp_path, name: str, old: str, new: str):
    """The replay program built from a copy of the harness whose fuzz/NAME has ``old`` replaced
    by ``new`` (fuzz_core.c includes its terms and omega targets from its own directory)."""
    src = (ROOT / "fuzz" / name).read_text()
    bad = src.replace(old, new)
    assert bad != src
    for other in ("fuzz_core.c", "fuzz_terms.c", "fuzz_omega.c"):
        (tmp_path / other).write_text(bad if other == name else (ROOT / "fuzz" / other).read_text())
    _compile_all(build["cc"], [(tmp_path / "fuzz_core.c", tmp_path / "fuzz_bad.o", "-O0")])
    exe = tmp_path / "replay_bad"
    _link(build["cc"], [tmp_path / "fuzz_bad.o", build["main"], *build["core"]], exe)
    return exe


def _replay(exe, path):
    return subprocess.run([str(exe), str(path)], capture_output=True, text=True, timeout=60, env=_env())


def test_harness_catches_a_violation(build, tmp_path):
    """The replay really runs the properties: a harness whose own reference is
    deliberately wrong must abort (guards against a harness that checks nothing)."""
    # break the reference of ac_trim's clipping in a copy of the harness
    exe = _mutant(build, tmp_path, "fuzz_core.c", "int32_t e = d > 32767 ? 32767 : (d < -32768 ? -32768 : d);",
                  "int32_t e = d > 32766 ? 32766 : (d < -32768 ? -32768 : d);")
    data = bytes([0, 1, 0xFF, 0xFF, 0, 0])  # ac_trim, n = 1: raw 65535, trim 0 -> clipped to 32767
    (tmp_path / "in").write_bytes(data)
    r = _replay(exe, tmp_path / "in")
    assert r.returncode != 0
    assert "property failed" in r.stderr


def test_omega_target_checks_its_properties(build, tmp_path):
    """Target 15 (ac_omega, fuzz/fuzz_omega.c) runs its checks: with its q16 -> q10 rescaling
    deliberately wrong (/ 32 for / 64) the vectors' table and readings abort the replay."""
    exe = _mutant(build, tmp_path, "fuzz_omega.c", "floor_div_p2((i128)w2[i] + 32, 6)",
                  "floor_div_p2((i128)w2[i] + 32, 5)")
    seed = next(CORPUS.glob("seed_omega_mb5_plain_*"))     # the vectors' rest and mid-turn readings
    r = _replay(exe, seed)
    assert r.returncode != 0 and "omega_q10" in r.stderr, r.stderr[-2000:]


def test_terms_target_checks_the_fractional_output(build, tmp_path):
    """The terms target's ac_temp_correct runs its tables at frac 0..8 (the output in 2^-frac
    counts, as a header with a temperature term writes it): with the reference's final rounding
    at frac > 0 deliberately a floor, the corpus's temperature seeds abort the replay."""
    exe = _mutant(build, tmp_path, "fuzz_terms.c", "FT_C16(ft_round(w, 16 - t.frac), &sat)",
                  "FT_C16(ft_floor(w, 16 - t.frac), &sat)")
    failed = [s.name for s in sorted(CORPUS.glob("seed_terms_m*")) if _replay(exe, s).returncode]
    assert failed, "no terms seed reached ac_temp_correct at frac > 0"
