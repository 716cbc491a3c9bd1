"""Channel windows on the bridge's monitors (glfw), for channels whose output is "window".

The scene is drawn into each channel's framebuffer in one OpenGL context: that of a hidden
glfw window, which every channel window shares. Textures are shared between the contexts,
framebuffers and vertex arrays are not, so each channel window gets a small program that
shows its channel's colour texture full-screen.
"""
from __future__ import annotations

import moderngl
import numpy as np

from bridge_node.render.settings import ChannelSettings

_SHOW_VS = """
#version 330
in vec2 in_ndc;
out vec2 uv;
void main() { uv = in_ndc * 0.5 + 0.5; gl_Position = vec4(in_ndc, 0.0, 1.0); }
"""
_SHOW_FS = """
#version 330
uniform sampler2D image;
in vec2 uv;
out vec4 colour;
void main() { colour = texture(image, uv); }
"""


class WindowError(RuntimeError):
    """No display, no monitor of that number, or no OpenGL 3.3 through glfw."""


def _glfw():
    import glfw

    return glfw


def window_context() -> tuple[moderngl.Context, object]:
    """An OpenGL 3.3 context of a hidden glfw window, for drawing channels shown in windows."""
    glfw = _glfw()
    if not glfw.init():
        raise WindowError("glfw cannot start: no display (is DISPLAY set?)")
    glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
    glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
    glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
    glfw.window_hint(glfw.VISIBLE, glfw.FALSE)
    hidden = glfw.create_window(16, 16, "icebridge", None, None)
    if not hidden:
        raise WindowError("glfw cannot create an OpenGL 3.3 context on this display")
    glfw.make_context_current(hidden)
    return moderngl.create_context(), hidden


class ChannelWindow:
    """One channel's window: on monitor ``channel.monitor``, full-screen or at its corner."""

    def __init__(self, main_ctx: moderngl.Context, hidden_window, channel: ChannelSettings,
                 image: moderngl.Texture) -> None:
        glfw = _glfw()
        monitors = glfw.get_monitors()
        if channel.monitor >= len(monitors):
            raise WindowError(f"channel {channel.name!r}: monitor {channel.monitor} does not exist "
                              f"({len(monitors)} monitor(s) on this display)")
        monitor = monitors[channel.monitor]
        glfw.window_hint(glfw.VISIBLE, glfw.TRUE)
        glfw.window_hint(glfw.DECORATED, glfw.FALSE)
        self.window = glfw.create_window(channel.width, channel.height, f"icebridge {channel.name}",
                                         monitor if channel.fullscreen else None, hidden_window)
        if not channel.fullscreen:
            glfw.set_window_pos(self.window, *glfw.get_monitor_pos(monitor))
        self.main_ctx, self.hidden = main_ctx, hidden_window
        self.channel = channel
        glfw.make_context_current(self.window)
        self.ctx = moderngl.create_context()
        self.image = self.ctx.external_texture(image.glo, image.size, image.components, 0, "f1")
        program = self.ctx.program(vertex_shader=_SHOW_VS, fragment_shader=_SHOW_FS)
        quad = self.ctx.buffer(np.array([[-1, -1], [3, -1], [-1, 3]], dtype="f4").tobytes())
        self.vao = self.ctx.vertex_array(program, [(quad, "2f", "in_ndc")])
        glfw.make_context_current(self.hidden)

    def _draw(self):
        """Draw the channel's image into the window's back buffer (its context current)."""
        glfw = _glfw()
        glfw.make_context_current(self.window)
        self.ctx.screen.use()
        self.ctx.screen.viewport = (0, 0, *glfw.get_framebuffer_size(self.window))
        self.image.use(0)
        self.vao.render()
        self.ctx.finish()
        return glfw

    def present(self) -> None:
        """Show the channel's last frame (the main context must have finished drawing it)."""
        glfw = self._draw()
        glfw.swap_buffers(self.window)
        glfw.poll_events()
        glfw.make_context_current(self.hidden)

    def shown(self) -> np.ndarray:
        """What the window shows, read back from its back buffer after drawing it there the
        way ``present`` does: (height, width, 3) uint8, top row first."""
        glfw = self._draw()
        raw = self.ctx.screen.read(components=3, alignment=1)
        w, h = glfw.get_framebuffer_size(self.window)
        glfw.make_context_current(self.hidden)
        return np.frombuffer(raw, dtype=np.uint8).reshape(h, w, 3)[::-1]
