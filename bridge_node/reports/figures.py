"""The one matplotlib setup of the node: the Agg backend (no display needed), and saving."""
from __future__ import annotations

from pathlib import Path

import matplotlib

from bridge_node.common.output_files import OutputFile

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

__all__ = ["plt", "save_figure"]


def save_figure(fig, path: Path, dpi: int = 110) -> Path:
    """Write the figure as PNG (folders created; atomically, replacing only a regular file)
    and close it; returns the path."""
    output = OutputFile(path, "plot")
    try:
        with output as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
    finally:
        plt.close(fig)
    return output.path
