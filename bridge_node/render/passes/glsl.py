"""The passes' GLSL sources: the files beside each pass, put together for one program.

GLSL 3.30 has no include: ``#include "name"`` pulls in another file of this folder (once per
source, as a header guard would), and ``#include <name>`` a snippet generated from the
Python that owns its numbers (the relief octaves, the class colours, the rubble look).
``#define`` lines for the constants a program is compiled with (the searchlights, the
rubble, the tile table's flags) go after ``#version``. Written by hand because moderngl
compiles source strings only, and a preprocessor library would add a dependency for these
two directives.
"""
from __future__ import annotations

import math
import re
from functools import cache
from pathlib import Path

import moderngl
import numpy as np

from bridge_node.render import classes, rubble_look
from bridge_node.render.textures import NOISE_RANGE
from sim_core.ice.bending import PIECE

FOLDER = Path(__file__).parent
POSE_WIDTH = 2048  # texels per line of the pose textures: a power of two, a constant in the shaders (on
                   # llvmpipe, division by a uniform is done lane by lane and cost the level ice a tenth)
UNPLACED_FLOE_FIELD = 2  # tile table flag of a floe field's tile not simulated (its floes drawn at home)
FROZEN_CRACKED = 0xF000  # a frozen tile's status entry of a cracked intact cell: this | its crack label (no
# tile has this many cells, so no floe number reaches it)
PERIODS = (23.0, 290.0, 2100.0)  # m: of the relief's three noise fetches
_INCLUDE = re.compile(r'^#include\s+(?:"([\w.]+)"|<(\w+)>)\s*$', re.MULTILINE)


def _octaves() -> str:
    """GLSL constants of the relief fetches: world (m) to noise texture coordinates (rotation
    over period), and each fetch's slope amplitude times period (m) and relative albedo
    variation. The periods (23, 290 and 2100 m) and angles share no ratio, so the sum never
    repeats; each fetch spans five octaves (features of 1/8 to 1/256 of its period)."""
    rows = []
    for k, (period, slope, albedo) in enumerate(zip(PERIODS, (0.16, 0.08, 0.03), (0.03, 0.04, 0.05))):
        angle = 1.13 * k
        c, s = math.cos(angle) / period, math.sin(angle) / period
        rows.append((f"mat2({c:.6g}, {-s:.6g}, {s:.6g}, {c:.6g})", f"vec2({slope * period:.6g}, {albedo})"))
    return (f"const int OCTAVES = {len(rows)};\n"
            f"const mat2 OCTAVE[OCTAVES] = mat2[]({', '.join(r[0] for r in rows)});\n"
            f"const vec2 OCTAVE_AMP[OCTAVES] = vec2[]({', '.join(r[1] for r in rows)});\n"
            f"const vec3 NOISE_RANGE = vec3{NOISE_RANGE};\n"
            f"const float OCTAVE_SCALE[OCTAVES] = float[]({', '.join(f'{p / PERIODS[0]:.6g}' for p in PERIODS)});\n")


GENERATED = {"octaves": _octaves(), "classes": classes.GLSL, "rubble": rubble_look.GLSL}


def scene_defines(searchlights: int, brash: bool, ridges: bool) -> dict[str, int | str]:
    """The constants the scene's programs are compiled with. The number of searchlights is
    fixed: on llvmpipe a loop to a uniform bound costs as much as the ice's relief, even when
    the bound is 0, while a loop to a constant 0 costs nothing (and GLSL has no empty arrays:
    LIGHT_SLOTS is at least 1). Brash and ridge code is compiled in only where the field has
    them: on llvmpipe a branch does not skip work, so a field without them would pay for
    them in every ground pixel."""
    return {"LIGHTS": searchlights, "LIGHT_SLOTS": max(searchlights, 1), "BRASH": int(brash), "RIDGES": int(ridges),
            "POSE_WIDTH": POSE_WIDTH, "UNPLACED_FLOE_FIELD": UNPLACED_FLOE_FIELD,
            "FROZEN_CRACKED_ENTRY": f"{FROZEN_CRACKED}u", "PIECE_BIT": f"{PIECE}u"}


@cache
def _file(name: str) -> str:
    return (FOLDER / name).read_text()


def source(name: str, **defines: int | float | str) -> str:
    """The file's source with its includes resolved and the defines after its ``#version``."""
    seen: set[str] = set()

    def resolve(match: re.Match) -> str:
        file, generated = match.groups()
        if generated is not None:
            return GENERATED[generated]
        if file in seen:
            return ""
        seen.add(file)
        return _INCLUDE.sub(resolve, _file(file))

    text = _INCLUDE.sub(resolve, _file(name))
    lines = "".join(f"#define {key} {value}\n" for key, value in defines.items())
    return text.replace("#version 330\n", "#version 330\n" + lines, 1)


def program(ctx: moderngl.Context, vertex: str, fragment: str, **defines: int | float | str) -> moderngl.Program:
    """A program of two files of this folder, both compiled with the defines."""
    return ctx.program(vertex_shader=source(vertex, **defines), fragment_shader=source(fragment, **defines))


def set_present(prog: moderngl.Program, **values: int | float | tuple) -> None:
    """Set the program's uniforms that it has of these (a sampler's texture unit, a constant
    of the scene): once, when it is made; the compiler drops those a program does not use."""
    names = set(prog)
    for name, value in values.items():
        if name not in names:
            continue
        if isinstance(value, np.ndarray):  # a uniform array, written whole
            prog[name].write(value.astype("f4").tobytes())
        else:
            prog[name].value = value
