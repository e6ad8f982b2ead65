"""The README is the front page: at most 300 lines (everything else is in docs/, the site's
pages), its links lead to files of the repository, and its Python examples run as written.
(It had been 1,733 lines; the Python session of its "Python" section is also run by
test_api.test_readme_python_session_runs.)"""
import json
import re
import shlex
from pathlib import Path

import pytest

from accelcal.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text()
MAX_LINES = 300


def test_readme_fits_in_300_lines():
    n = len(README.splitlines())
    assert n <= MAX_LINES, f"README.md has {n} lines; move sections into docs/ pages (at most {MAX_LINES})"


def test_readme_keeps_the_set_up_and_test_commands():
    """.ci/run runs `bash tools/test_all.sh`, the README's test command; the install line is the
    first of the set-up block."""
    block = re.search(r"```sh\n(.*?)```", README, re.S).group(1).splitlines()
    assert block == ["pip install . && accelcal demo", "bash tools/test_all.sh"]
    assert "bash tools/test_all.sh" in (ROOT / ".ci" / "run").read_text()


def test_readme_links_lead_into_the_repository():
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README)
    local = [u for u in links if not re.match(r"[a-z]+:", u)]
    assert any(u.startswith("docs/") for u in local)
    missing = [u for u in local if not (ROOT / u).exists()]
    assert not missing, missing


@pytest.mark.parametrize("k", range(len(re.findall(r"```python\n", README))))
def test_readme_python_examples_run(k, tmp_path, monkeypatch, capsys):
    block = re.findall(r"```python\n(.*?)```", README, re.S)[k]
    monkeypatch.chdir(tmp_path)
    exec(compile(block, f"README.md python block {k}", "exec"), {})
    if "travel" in block:                         # the displacement example prints its travel
        travel = float(re.search(r"travel ([-\d.]+) m", capsys.readouterr().out).group(1))
        assert abs(travel - 0.5) < 0.0025        # the benchmark's worst case is 0.193 %


def test_readme_diagnosis_commands_run(tmp_path, monkeypatch):
    """The README's diagnosis example as written: the simulated effect is the verdict, and the
    report's figures are written."""
    block = next(b for b in re.findall(r"```sh\n(.*?)```", README, re.S) if "accelcal diagnose" in b)
    monkeypatch.chdir(tmp_path)
    for line in block.strip().splitlines():
        args = shlex.split(line.split("#")[0])
        assert args[0] == "accelcal"
        assert main(args[1:]) in (0, None), line
    effect = re.search(r"--effect (\w+)", block).group(1)
    assert json.loads((tmp_path / "diag.json").read_text())["verdict"] == effect
    assert sorted(p.name for p in (tmp_path / "diag").glob("*.png"))
