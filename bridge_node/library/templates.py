"""Template library: pre-fractured tiles stored per thickness class, and floe fields' tiles
per regime, in a cache folder.

Each template is one uncompressed .npz (fast to load: a few ms). The file name carries the
thickness (or the regime's digest), the variant and a digest of every setting that changes
the tile, so a config change never serves a stale tile. Writes are atomic (temporary file,
then rename).
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
from pathlib import Path
from typing import Callable

import numpy as np

from bridge_node.common.output_files import OutputFile
from sim_core.fracture.tile_template import FractureSettings, TileTemplate, build_tile, template_seed
from sim_core.material import IceMaterial
from sim_core.regimes.floe_layout import RegimeModel
from sim_core.regimes.pack_tiles import pack_template

PACK_FORMAT = 2  # raise when pack_tiles lays a regime's templates otherwise: older files are not served


def template_path(
    cache_dir: Path, thickness: float, variant: int, settings: FractureSettings, material: IceMaterial
) -> Path:
    """Cache file of one template."""
    spec = json.dumps(
        {"fracture": settings.model_dump(exclude={"variants"}), "material": material.model_dump()},
        sort_keys=True,
    )
    return Path(cache_dir) / f"tile_h{round(thickness * 1000):04d}mm_v{variant}_{_digest(spec)}.npz"


def pack_template_path(cache_dir: Path, regimes: RegimeModel, region: int, variant: int, settings: FractureSettings,
                       material: IceMaterial, big_floe: float) -> Path:
    """Cache file of one of a floe-field region's templates: named by a digest of its
    layers (spacing, shrink, hash salt, thickness, repeat: the layout they lay), the tile
    side and repeat, the fracture and material settings and the pre-fractured floe size."""
    spec = json.dumps(
        {"format": PACK_FORMAT, "layers": [dataclasses.asdict(layer) for layer in regimes.layers[region]],
         "tile_side": regimes.tile_side, "repeat": regimes.repeat[region],
         "fracture": settings.model_dump(exclude={"variants"}), "material": material.model_dump(),
         "big_floe": big_floe}, sort_keys=True)
    return Path(cache_dir) / f"pack_{_digest(spec)}_v{variant}.npz"


def _digest(spec: str) -> str:
    return hashlib.sha256(spec.encode()).hexdigest()[:12]


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
    return _cached(template_path(cache_dir, thickness, variant, settings, material), rebuild,
                   lambda: build_tile(thickness, template_seed(settings.seed, thickness, variant), settings, material))


def library_pack_template(cache_dir: Path, regimes: RegimeModel, region: int, variant: int,
                          settings: FractureSettings, material: IceMaterial, big_floe: float) -> TileTemplate:
    """A floe-field region's template ``variant`` (``pack_tiles.pack_template``) from the
    library, laid and stored first if missing."""
    path = pack_template_path(cache_dir, regimes, region, variant, settings, material, big_floe)
    return _cached(path, False, lambda: pack_template(regimes, region, variant, settings, material, big_floe))[0]


def _cached(path: Path, rebuild: bool, build: Callable[[], TileTemplate]) -> tuple[TileTemplate, str]:
    """The template stored at ``path``, else built and stored; and "cache" or "built"."""
    if path.exists() and not rebuild:
        return load_template(path), "cache"
    tile = build()
    save_template(path, tile)
    return tile, "built"
