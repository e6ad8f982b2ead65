"""The one plotting home: matplotlib on the Agg backend and PNGs written atomically.

Every figure the package writes (the diagnosis report, the estimators' plots) goes
through :func:`save_figure`, so a failed or interrupted write leaves no partial file.
"""
from __future__ import annotations

import io
from typing import Any

import matplotlib

matplotlib.use("Agg", force=True)
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

from .errors import atomic_write  # noqa: E402

__all__ = ["plt", "save_figure"]


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
        plt.close(fig)
    data = buf.getvalue()
    atomic_write(path, lambda f: f.write(data), mode="wb")
