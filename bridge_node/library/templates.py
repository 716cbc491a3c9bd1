"""Template library: pre-fractured tiles stored per thickness class in a cache folder.

Each template is one uncompressed .npz (fast to load: a few ms). The file name carries the
thickness, the variant and a digest of every setting that changes the tile, so a config
change never serves a stale tile. Writes are atomic (temporary file, then rename).
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np

from bridge_node.common.output_files import OutputFile
from sim_core.fracture.tile_template import FractureSettings, TileTemplate, build_tile, template_seed
from sim_core.material import IceMaterial


def template_path(
    cache_dir: Path, thickness: float, variant: int, settings: FractureSettings, material: IceMaterial
) -> Path:
    """Cache file of one template."""
    spec = json.dumps(
        {"fracture": settings.model_dump(exclude={"variants"}), "material": material.model_dump()},
        sort_keys=True,
    )
    digest = hashlib.sha256(spec.encode()).hexdigest()[:12]
    return Path(cache_dir) / f"tile_h{round(thickness * 1000):04d}mm_v{variant}_{digest}.npz"


def save_template(path: Path, template: TileTemplate) -> None:
    """Write a template atomically, through a temporary file of its own: processes that
    build the same template at once (a node and its render processes on a cold library)
    each write whole files, and the last rename wins with identical content."""
    with OutputFile(path, "template library file") as tmp, open(tmp, "wb") as f:
        np.savez(f, **template.to_arrays())


def load_template(path: Path) -> TileTemplate:
    """Read a template written by ``save_template``."""
    with np.load(path, allow_pickle=False) as data:
        return TileTemplate.from_arrays({k: data[k] for k in data.files})


def library_template(cache_dir: Path, thickness: float, variant: int, settings: FractureSettings,
                     material: IceMaterial, rebuild: bool = False) -> tuple[TileTemplate, str]:
    """A template from the library, built and stored first if missing (or if rebuild).
    Returns the template and where it came from: "cache" or "built"."""
    path = template_path(cache_dir, thickness, variant, settings, material)
    if path.exists() and not rebuild:
        return load_template(path), "cache"
    tile = build_tile(thickness, template_seed(settings.seed, thickness, variant), settings, material)
    save_template(path, tile)
    return tile, "built"
