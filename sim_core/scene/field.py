"""Ice field layout: a W x H metre field of square tiles, each with a level-ice thickness."""
from __future__ import annotations

import math
from typing import Literal

import numpy as np
from pydantic import Field, model_validator

from sim_core.fracture.fragment_count import MAX_THICKNESS
from sim_core.params import Params
from sim_core.regimes.ridge_settings import RidgeFieldSettings
from sim_core.regimes.settings import RegionSettings


class IceFieldSettings(Params):
    """Field extent, thickness profile, and the ice regions over it (a chart's and the
    config's: ``icebridge field`` lays them out). Gradients run from the south edge (y = 0,
    ``thickness``) to the north edge (y = H, ``thickness_end``); a grid gives one value per
    tile, row 0 at the south edge."""

    width: float = Field(6400.0, ge=100.0, le=1.0e6, description="east-west extent, m")
    height: float = Field(6400.0, ge=100.0, le=1.0e6, description="north-south extent, m")
    thickness_profile: Literal["uniform", "gradient", "grid"] = "uniform"
    thickness: float = Field(gt=0.0, le=MAX_THICKNESS, description="level-ice thickness, m")
    thickness_end: float | None = Field(None, gt=0.0, le=MAX_THICKNESS, description="gradient end, m")
    thickness_grid: str | None = Field(None, description="CSV of per-tile thickness, m")
    class_step: float = Field(0.1, ge=0.01, le=0.5, description="thickness class width, m")
    chart: str | None = Field(None, description="SIGRID-3 ice chart (.shp) whose regions lie over the field")
    regions: list[RegionSettings] = Field(default_factory=list, description="regions drawn over the chart")
    ridges: list[RidgeFieldSettings] = Field(default_factory=list, description="ridge fields over the ice")

    @model_validator(mode="after")
    def _profile_inputs(self) -> "IceFieldSettings":
        if self.thickness_profile == "gradient" and self.thickness_end is None:
            raise ValueError("thickness_end is required when thickness_profile = 'gradient'")
        if self.thickness_profile == "grid" and not self.thickness_grid:
            raise ValueError("thickness_grid (a CSV file) is required when thickness_profile = 'grid'")
        return self


def tile_counts(field: IceFieldSettings, tile_side: float) -> tuple[int, int]:
    """Tiles along x (east) and y (north): the field rounded up to whole tiles."""
    return math.ceil(field.width / tile_side - 1e-9), math.ceil(field.height / tile_side - 1e-9)


def tile_thickness(
    field: IceFieldSettings, tile_side: float, grid: np.ndarray | None = None
) -> np.ndarray:
    """Thickness (m) of every tile as an (ny, nx) array, row 0 at the south edge."""
    nx, ny = tile_counts(field, tile_side)
    if field.thickness_profile == "uniform":
        return np.full((ny, nx), field.thickness)
    if field.thickness_profile == "gradient":
        y = (np.arange(ny) + 0.5) / ny
        column = field.thickness + (field.thickness_end - field.thickness) * y
        return np.repeat(column[:, None], nx, axis=1)
    if grid is None or grid.shape != (ny, nx):
        got = None if grid is None else grid.shape
        raise ValueError(f"thickness grid must have shape {(ny, nx)} (rows, columns), got {got}")
    if not np.all(np.isfinite(grid) & (grid > 0.0) & (grid <= MAX_THICKNESS)):
        raise ValueError(f"thickness grid values must lie in (0, {MAX_THICKNESS}] m")
    return grid.astype(float)


def thickness_class(h: np.ndarray | float, step: float) -> np.ndarray:
    """Round thickness to its class (multiples of step, at least one step, at most 1.5 m)."""
    return np.clip(np.round(np.asarray(h) / step) * step, step, MAX_THICKNESS).round(6)


def tile_classes(field: IceFieldSettings, tile_side: float, grid: np.ndarray | None = None,
                 regions: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Thickness class of every tile: (class index (ny, nx) uint8, row 0 at the south edge;
    class thicknesses (k,) m). Uniform and gradient fields are built a row at a time, so a
    640 km field costs one byte per tile. ``regions`` (ny, nx) m, where given, overrides the
    profile where it is not NaN: a level-ice region's thickness, or 0 for open water (a
    class of its own, thickness 0, that no template is built for)."""
    nx, ny = tile_counts(field, tile_side)
    if field.thickness_profile == "grid" or regions is not None:
        classes = thickness_class(tile_thickness(field, tile_side, grid), field.class_step)
        if regions is not None:
            given = ~np.isnan(regions)
            classes = np.where(given & (regions > 0.0), thickness_class(np.nan_to_num(regions), field.class_step),
                               np.where(given, 0.0, classes))
    else:
        column = tile_thickness(field.model_copy(update={"width": tile_side}), tile_side)[:, 0]
        classes = thickness_class(column, field.class_step)[:, None]
    values, index = np.unique(classes, return_inverse=True)
    if len(values) > 256:
        raise ValueError(f"{len(values)} thickness classes; at most 256 (raise class_step)")
    index = index.reshape(classes.shape).astype(np.uint8)
    return np.ascontiguousarray(np.broadcast_to(index, (ny, nx))), values
