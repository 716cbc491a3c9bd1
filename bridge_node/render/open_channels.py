"""Open the configured projector channels: an OpenGL context (EGL headless, or a hidden glfw
window when a channel is shown in a window), the scene renderer and the channel targets.
A missing display or EGL is the user's to fix, and said so."""
from __future__ import annotations

from bridge_node.common.errors import UserError
from bridge_node.render.channels import ChannelSet, context_for
from bridge_node.render.renderer import SceneRenderer
from bridge_node.render.settings import RenderSettings
from bridge_node.render.ship_mesh import ShipModelError
from bridge_node.render.warp import WarpError
from bridge_node.render.windows import WindowError
from sim_core.world import WorldModel


def select_channels(render: RenderSettings, names: list[str] | None) -> RenderSettings:
    """The render settings with only the named channels (all when names is None); an
    unknown name is the user's error."""
    if names is None:
        return render
    known = [c.name for c in render.channels]
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        raise UserError(f"--channels: unknown channel(s) {unknown}; configured: {', '.join(known)}")
    return render.model_copy(update={"channels": [c for c in render.channels if c.name in names]})


def open_channels(render: RenderSettings, model: WorldModel) -> ChannelSet:
    """Context, scene renderer and channel set (with the channel windows); a missing display
    or EGL is a clear error."""
    no_display = "set the channels' output to \"png\" on a node without a display"
    try:
        ctx, hidden = context_for(render.channels)
    except WindowError as exc:
        raise UserError(f"render: {exc}; {no_display}") from None
    except (ShipModelError, WarpError) as exc:
        raise UserError(str(exc)) from None
    except Exception as exc:  # moderngl raises plain Exception when EGL cannot start
        raise UserError(f"cannot open a headless OpenGL context through EGL ({exc}); install the EGL and "
                        "Mesa libraries (scripts/setup.sh installs libegl1, libgl1, libegl-mesa0, "
                        "libgl1-mesa-dri)") from None
    try:
        return ChannelSet(SceneRenderer(ctx, model, render), render.channels, hidden)
    except WindowError as exc:
        raise UserError(f"render: {exc}; {no_display}") from None
    except (ShipModelError, WarpError) as exc:
        raise UserError(str(exc)) from None