"""The one plotting home: matplotlib on the Agg backend and PNGs written atomically.

Every figure the package writes (the diagnosis report, the estimators' plots) is
made with :func:`pyplot` and written with :func:`save_figure`, so a failed or
interrupted write leaves no partial file.

matplotlib is imported on the first call of :func:`pyplot`, not with this module:
it costs about 0.3 s, and every ``accelcal`` command would pay it at start-up
although only ``--report`` writes figures (the package's one deliberate import
inside a function; tests/python/test_layers.py names it).
"""
from __future__ import annotations

import io
from typing import Any

from .errors import atomic_write

__all__ = ["pyplot", "save_figure"]


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg backend."""
    import matplotlib  # noqa: PLC0415 - deferred: see the module doc

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt  # noqa: PLC0415

    return plt


def save_figure(fig: Any, path: Any, dpi: int = 110) -> None:
    """Render ``fig`` to PNG and write it to ``path`` atomically, then close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure to write.
    path : str or os.PathLike
        Destination file; replaced only once the whole PNG is rendered.
    dpi : int, optional
        Resolution in dots per inch.
    """
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    finally:
        pyplot().close(fig)
    data = buf.getvalue()
    atomic_write(path, lambda f: f.write(data), mode="wb")
