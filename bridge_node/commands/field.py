"""``icebridge field CHART_OR_CONFIG [--json]``: lay out the ice regions of a SIGRID-3 chart
or of a config (its chart and its ``[[ice_field.regions]]``) and report, per region, the
concentration measured in the floes laid, the floe sizes against the WMO ranges and the ice
types; and write a top view of the field (``field.png`` in ``--out``)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import shapely
from rich.console import Console
from rich.progress import Progress

from bridge_node.charts.field_regions import chart_field, configured_regions, configured_ridges, regime_model
from bridge_node.common.errors import UserError
from bridge_node.node.config import load_config
from bridge_node.reports.field import plot_field, survey_json, survey_table
from sim_core.fracture.tile_template import FractureSettings
from sim_core.regimes.survey import survey_region

DEFAULT_SEED = FractureSettings.model_fields["seed"].default


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("source", help="a SIGRID-3 chart (.shp) or a config (.toml) with ice_field.chart or regions")
    p.add_argument("--json", action="store_true", help="print the report as one JSON object")
    p.add_argument("--out", default="out", help="folder for the top view, field.png (default: out)")


def run(args: argparse.Namespace) -> int:
    source = Path(args.source)
    if args.config is not None:
        raise UserError("--config: give the config as the argument (icebridge field CONFIG.toml)")
    if source.suffix.lower() == ".toml":
        cfg = load_config(source)
        field = shapely.box(0.0, 0.0, cfg.ice_field.width, cfg.ice_field.height)
        model = regime_model(configured_regions(cfg.ice_field, cfg.exercise.origin_deg()), field, cfg.fracture.seed,
                             str(source), cfg.fracture.tile_side)
        ridges = configured_ridges(cfg.ice_field, cfg.exercise.origin_deg())
    else:
        ridges = ()
        regions, field, _ = chart_field(source)
        model = regime_model(regions, field, DEFAULT_SEED, str(source), FractureSettings().tile_side)
    with Progress(transient=True, disable=args.json) as progress:
        task = progress.add_task("laying out the regions", total=len(model.regions))
        surveys = []
        for r in range(len(model.regions)):
            surveys.append(survey_region(model, r))
            progress.advance(task)
    picture = Path(args.out) / "field.png"
    plot_field(model, surveys, field, picture, ridges)
    if args.json:
        print(json.dumps(survey_json(model, surveys, picture)))
        return 0
    console = Console()
    console.print(survey_table(model, surveys))
    console.print(f"top view: {picture}")
    return 0
