"""The renderer's passes: one object per effect, its GLSL beside it, each made (its program
compiled, its constants set) once and drawn per channel.

| pass | GLSL | draws |
|---|---|---|
| ``ShipPass`` | ``ship.vert``, ``ship.frag`` | the own ship, other vessels, the ridges' sails |
| ``FloePass`` | ``floes.vert``, ``floes.frag``, ``tile.glsl`` | broken floes: tops, sides, reflections |
| ``EnvironmentPass`` | ``screen.vert``, ``environment.frag``, ``sky.frag`` | sea, level ice, brash, far sails; sky |
| ``NavLightPass`` | ``nav_lights.vert``, ``nav_lights.frag`` | navigation lights |
| ``BlendBandPass`` | ``blend_bands.vert``, ``blend_bands.frag`` | the channel's edge-blend bands |

``warp.vert`` and ``warp.frag`` are the projector warp's (``bridge_node.render.warp``).
``SceneRenderer`` sequences the passes near to far (ships, sails, floes, then the environment
behind them, so that the depth test spares the full-screen pass every pixel already
covered), then the reflections, the navigation lights and the blend bands. What every
program reads (the frame's sun, sky, clock and searchlights; the channel's camera) is in two
uniform buffers (``blocks``, ``blocks.glsl``); ``common.glsl`` and ``entries.glsl`` hold the
functions the programs share (``glsl`` puts the sources together).

World frame: x east, y north, z up, metres. Looks: level ice and floe tops are snow (or,
thin, grey nilas) with relief and albedo from octaves of procedural noise; floe sides show
the blue-green of sea ice, darkened at the waterline, and ice under the water shows through
it, pale blue-green, fading with depth; the sea reflects the sky and the floes by Fresnel
through slight waves; everything is lit by the sun and the sky of the moment and the own
ship's searchlights, and fogged by the visibility.
"""
