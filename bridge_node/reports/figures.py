"""The one matplotlib setup of the node: the Agg backend (no display needed), and saving."""
from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

__all__ = ["plt", "save_figure"]


def save_figure(fig, path: Path, dpi: int = 110) -> Path:
    """Write the figure as PNG (folders created) and close it; returns the path."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path
