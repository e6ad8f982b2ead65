"""The command's help cites its documentation where a user has it: pages of the repository
(docs/*.md, which the site of tools/build_docs.sh is built from), never a path outside it
(the help had cited shared/spec/data-contract.md, a path of the project's workspace)."""
import re
from pathlib import Path

import pytest

from accelcal.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
COMMANDS = ["demo", "simulate", "calibrate", "header", "resolve", "attitude", "displacement", "rate",
            "diagnose", "convert"]


def help_text(args, capsys):
    with pytest.raises(SystemExit) as e:
        main([*args, "--help"])
    assert e.value.code == 0
    return capsys.readouterr().out


def cited_paths(text):
    return re.findall(r"[\w./-]+\.(?:md|html|json|csv|h)\b", text)


def test_the_main_help_names_the_docs_in_the_repository(capsys):
    text = help_text([], capsys)
    for cmd in COMMANDS:
        assert re.search(rf"^\s+{cmd}\b", text, re.M), cmd
    assert "docs/data-contract.md" in text and "tools/build_docs.sh" in text
    assert "shared/" not in text and "../" not in text
    for path in cited_paths(text):
        if path.startswith("docs/"):
            assert (ROOT / path).is_file(), path


@pytest.mark.parametrize("cmd", COMMANDS)
def test_no_help_cites_a_path_outside_the_repository(cmd, capsys):
    text = help_text([cmd], capsys)
    assert "shared/" not in text and "../" not in text, text
    for path in cited_paths(text):
        if path.startswith("docs/"):
            assert (ROOT / path).is_file(), path
