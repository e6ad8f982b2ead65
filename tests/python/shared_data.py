"""Where the real recordings are: ``../shared/data`` beside the repository.

The recordings are never copied into the repository. CI has them; a clone without
them skips the tests that need them (the ``shared_data`` fixture says why). Tools
(benchmarks) import :func:`shared_data_dir` from here, the tests through the fixture.
"""
from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SHARED_DATA = REPO.parent / "shared" / "data"


def shared_data_dir() -> Path | None:
    """The shared data directory, or None when this checkout has none beside it."""
    return SHARED_DATA if SHARED_DATA.is_dir() else None


def shared_file(*parts: str) -> Path | None:
    """A file under the shared data directory, or None when it is not there."""
    base = shared_data_dir()
    if base is None:
        return None
    p = base.joinpath(*parts)
    return p if p.is_file() else None


XSENS_ACC = ("imu_tk_xsens", "xsens_acc.txt.gz")
