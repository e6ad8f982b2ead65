"""The compilers the header tests build with: the host's gcc with the core linked in, and
the firmware targets (h8300-hms-gcc for the seed's H8/300H, avr-gcc for a 16-bit-int AVR)
with the flags firmware uses, warnings as errors."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CORE = sorted(str(p) for p in (ROOT / "csrc").glob("*.c"))
WARN = ["-std=c99", "-Wall", "-Wextra", "-Werror"]
TARGETS = {"h8": ["h8300-hms-gcc", "-mh", "-mn", "-O2", "-fomit-frame-pointer"],
           "avr": ["avr-gcc", "-mmcu=atmega328p", "-Os"]}


def need(tool: str) -> None:
    """Skip without ``tool``; in CI (which installs it) fail instead."""
    if shutil.which(tool) is None:
        if os.environ.get("CI"):
            pytest.fail(f"{tool} is required in CI (tools/test_all.sh installs it)")
        pytest.skip(f"{tool} not installed")


def build_host(main_c: Path, exe: Path, *flags: str) -> None:
    """main_c with the whole core for the host (its directory on the include path)."""
    subprocess.run(["gcc", *WARN, "-Wconversion", *flags, "-I", str(ROOT / "include"), "-I", str(main_c.parent),
                    str(main_c), *CORE, "-o", str(exe)], check=True)


def cross_compile(target: str, src: Path) -> None:
    """Compile src (its directory on the include path) for ``target`` ("h8" or "avr")."""
    cmd = TARGETS[target]
    need(cmd[0])
    subprocess.run(cmd + WARN + ["-I", str(ROOT / "include"), "-I", str(src.parent), "-c", str(src),
                                 "-o", str(src.parent / f"{src.stem}_{target}.o")], check=True)
