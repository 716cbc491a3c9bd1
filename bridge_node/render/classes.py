"""The class mask: each channel drawn from the same camera with every pixel coloured by what
it shows (sky, open water, level ice, crack, broken floe, submerged floe, own ship, other
vessel), for measurements and tests of what the trainee sees (``icebridge render-snapshot
--classes``). Drawn without multisampling, fog, reflections, lights or edge blending, so
each pixel holds exactly one class colour.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

# name, colour (sRGB): far apart, so that a pixel's class is its nearest colour
CLASSES: tuple[tuple[str, tuple[int, int, int]], ...] = (
    ("sky", (140, 200, 255)),
    ("open_water", (0, 40, 140)),
    ("level_ice", (255, 255, 255)),
    ("crack", (255, 0, 0)),
    ("broken_floe", (255, 200, 0)),
    ("submerged_floe", (0, 200, 150)),
    ("own_ship", (200, 0, 200)),
    ("other_vessel", (110, 60, 0)),
)
CLASS_INDEX = {name: k for k, (name, _) in enumerate(CLASSES)}

# GLSL: the class colours and indices, for the fragment shaders' class pass (whether a draw is one:
# ``classes`` in the View block, passes/blocks.glsl)
GLSL = (f"const vec4 CLASS_COLOUR[{len(CLASSES)}] = vec4[]("
        + ", ".join(f"vec4({r / 255:.6f}, {g / 255:.6f}, {b / 255:.6f}, 1.0)" for _, (r, g, b) in CLASSES) + ");\n"
        + "".join(f"const int CLASS_{name.upper()} = {k};\n" for k, (name, _) in enumerate(CLASSES)))


def class_of_pixels(image: np.ndarray) -> np.ndarray:
    """Class index (h, w) of each pixel of a class image (h, w, 3) uint8: its nearest colour."""
    palette = np.array([c for _, c in CLASSES], dtype=np.int32)
    d = ((image[..., None, :].astype(np.int32) - palette) ** 2).sum(axis=-1)
    return d.argmin(axis=-1)


def class_shares(image: np.ndarray, where: np.ndarray | None = None) -> dict[str, float]:
    """Share of each class among the pixels of a class image (of those ``where`` marks)."""
    index = class_of_pixels(image)
    if where is not None:
        index = index[where]
    counts = np.bincount(index.ravel(), minlength=len(CLASSES))
    total = max(int(counts.sum()), 1)
    return {name: float(counts[k]) / total for k, (name, _) in enumerate(CLASSES)}


def save_legend(path: Path) -> Path:
    """A PNG legend of the class colours and names."""
    row, width = 22, 200
    image = Image.new("RGB", (width, row * len(CLASSES) + 8), (40, 40, 40))
    draw = ImageDraw.Draw(image)
    for k, (name, colour) in enumerate(CLASSES):
        y = 4 + k * row
        draw.rectangle((6, y + 2, 30, y + row - 4), fill=colour, outline=(0, 0, 0))
        draw.text((38, y + 4), name.replace("_", " "), fill=(240, 240, 240))
    path.parent.mkdir(parents=True, exist_ok=True)
    image.save(path)
    return path
