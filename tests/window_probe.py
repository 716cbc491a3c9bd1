"""Run in its own process by test_render_window.py (Mesa cannot hold an EGL and a GLX
context in one process, and the other render tests use EGL): render a small exercise to a
channel window on the X display in $DISPLAY and print what the window shows against what
the channel rendered, as JSON."""
import json
import sys
from pathlib import Path

import numpy as np

from bridge_node.node.config import load_config
from bridge_node.node.world_setup import build_world, start_world
from bridge_node.render.channels import ChannelSet, context_for
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import ChannelSettings, RenderSettings
from bridge_node.render.windows import WindowError
from bridge_node.stream.world_view import WorldView
from sim_core.world import snapshot, step


def main(cache: str) -> None:
    base = load_config()
    cfg = base.model_copy(update={
        "ice_field": base.ice_field.model_copy(update={"width": 400.0, "height": 400.0}),
        "paths": base.paths.model_copy(update={"cache_dir": cache}),
        "exercise": base.exercise.model_copy(update={"start_north": -60.0}),
    })
    model = build_world(cfg, None)
    data = start_world(model, cfg)
    for _ in range(100):
        step(model, data, 0.1)
    channels = [ChannelSettings(name="bow", width=160, height=90, output="window", pitch_deg=-10.0,
                                blend_right_deg=5.0),
                ChannelSettings(name="stern", width=160, height=90, yaw_deg=180.0)]
    ctx, hidden = context_for(channels)
    cs = ChannelSet(SceneRenderer(ctx, model, RenderSettings(channels=channels)), channels, hidden)
    view = WorldView()
    view.apply(snapshot(model, data))
    cs.render(view)
    shown, rendered = cs.windows[0].shown(), cs.targets[0].image()
    try:
        missing = [ChannelSettings(name="wing", width=64, height=36, output="window", monitor=3)]
        ChannelSet(cs.renderer, missing, hidden)
        error = None
    except WindowError as exc:
        error = str(exc)
    print(json.dumps({"windows": len(cs.windows), "shape": list(shown.shape), "rendered_shape": list(rendered.shape),
                      "max_diff": int(np.abs(shown.astype(int) - rendered.astype(int)).max()),
                      "rendered_std": float(rendered.std()), "missing_monitor_error": error}))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else str(Path.home() / ".cache" / "icebridge"))
