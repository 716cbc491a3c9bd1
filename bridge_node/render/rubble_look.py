"""How brash and ridges look from the bridge: drawn per pixel by the environment pass, from
the world's static rubble (``sim_core.regimes.rubble``), which costs no triangles however
long the ridges or wide the brash.

Each tile's table entry carries, above its flag byte, its brash share (a byte, 0-255) and its
ridge field (1 + index; 0: none). Brash is a field of wet, greyish pieces about a metre
across (WMO: fragments under 2 m) with water between them, as many as the share covers,
each with a slight tilt of its own, and the pale blue-green of its submerged part at its
edge. A ridge's sail is a band of tumbled blocks along each ridge line: its base four times
the sail height wide (sail slopes of about 27 degrees), each block facing the sky at an angle
of its own, the blue-green of fresh broken ice on its steep faces, dark gaps between blocks.
Far away, where a pixel covers many pieces, both fade to their mean shade, so they do not
shimmer.
"""
from __future__ import annotations

import numpy as np

from sim_core.regimes.rubble import RubbleModel

RIDGE_SLOTS = 4  # ridge fields the renderer draws; more are refused (``ridge_uniforms``)
SAIL_BASE = 4.0  # a sail's base width over its height
BRASH_PIECE = 1.2  # m: the pieces' grid, the mean brash size of WMO's 0-2 m
BLOCK = 1.5  # m: the sail's blocks' grid


def rubble_tile_bits(rubble: RubbleModel) -> np.ndarray:
    """Per tile (n_tiles,) int32: brash share << 8 | (1 + ridge field) << 16, for the tile
    table's flag entry."""
    share = np.clip(np.rint(rubble.brash_share * 255.0), 0, 255).astype(np.int32)
    return share << 8 | (rubble.ridge_tile.astype(np.int32) + 1) << 16


def ridge_uniforms(rubble: RubbleModel) -> dict[str, np.ndarray]:
    """The environment program's ridge uniforms: per slot the anchor (m), the unit normal
    across the lines, and spacing, sail half base width and sail height (m). ValueError for
    more ridge fields than ``RIDGE_SLOTS``."""
    if len(rubble.ridges) > RIDGE_SLOTS:
        raise ValueError(f"the renderer draws up to {RIDGE_SLOTS} ridge fields; this field has {len(rubble.ridges)}")
    anchor, normal, shape = np.zeros((RIDGE_SLOTS, 2)), np.zeros((RIDGE_SLOTS, 2)), np.ones((RIDGE_SLOTS, 3))
    for k, r in enumerate(rubble.ridges):
        anchor[k], normal[k] = r.anchor, r.normal
        shape[k] = r.spacing, 0.5 * SAIL_BASE * r.sail_height, r.sail_height
    return {"ridge_anchor": anchor, "ridge_normal": normal, "ridge_shape": shape}


GLSL = f"""
const int RIDGE_SLOTS = {RIDGE_SLOTS};
uniform vec2 ridge_anchor[RIDGE_SLOTS];  // m: a point of a ridge line
uniform vec2 ridge_normal[RIDGE_SLOTS];  // unit, across the lines
uniform vec3 ridge_shape[RIDGE_SLOTS];   // spacing, sail half base width, sail height (m)
// eight pseudo-random values in [0, 1] of a cell (and a salt), a byte each of the two words
// of pcg2d (Jarzynski & Olano 2020, "Hash functions for GPU rendering", JCGT 9(3)): on
// llvmpipe far cheaper than a sine-based hash per value
void cell_random(vec2 c, uint salt, out vec4 a, out vec4 b) {{
    uvec2 v = uvec2(ivec2(c)) ^ uvec2(salt, salt * 747796405u);
    v = v * 1664525u + 1013904223u;
    v.x += v.y * 1664525u; v.y += v.x * 1664525u;
    v ^= v >> 16u;
    v.x += v.y * 1664525u; v.y += v.x * 1664525u;
    v ^= v >> 16u;
    a = vec4((uvec4(v.x) >> uvec4(0u, 8u, 16u, 24u)) & 255u) / 255.0;
    b = vec4((uvec4(v.y) >> uvec4(0u, 8u, 16u, 24u)) & 255u) / 255.0;
}}
// one layer of brash pieces on the grid q: 1 on a piece (`mean` where a pixel's footprint `w`,
// in cells, spans pieces), `rim` 1 at its submerged edge, `n` its normal, `tone` its shade
// (slush to snow)
float brash_layer(vec2 q, uint salt, float share, float mean, float w, out float rim, out vec3 n, out float tone) {{
    vec2 c = floor(q);
    vec4 r, t;
    cell_random(c, salt, r, t);
    float a = 6.2832 * r.x, s = sin(a), k = cos(a);
    vec2 f = mat2(k, s, -s, k) * (fract(q) - 0.5 - 0.35 * (r.yz - 0.5));
    float half_side = 0.5 * sqrt(share) * (0.6 + 0.8 * r.w);
    float d = max(abs(f.x) * (1.0 + 0.5 * t.x), abs(f.y)) * 0.7 + length(f) * 0.35;
    float piece = 1.0 - smoothstep(half_side - w, half_side + w, d);
    rim = (1.0 - smoothstep(half_side + 0.05, half_side + 0.12 + w, d)) * (1.0 - piece);
    float far = smoothstep(0.25, 0.8, w);
    n = normalize(vec3((t.yz - 0.5) * (1.0 - far), 2.5));
    tone = 0.8 + 0.2 * t.w;
    rim = mix(rim, 0.0, far);
    tone = mix(tone, 0.9, far);
    return mix(piece, mean, far);
}}
// the brash under p of a tile covered `share` (0-1): pieces of about {BRASH_PIECE} m on two
// turned grids, the smaller filling the gaps of the larger; a pixel's footprint in m
float brash_at(vec2 p, float share, float footprint, out float rim, out vec3 n, out float tone) {{
    rim = 0.0; n = vec3(0.0, 0.0, 1.0); tone = 0.9;
    float mean = 0.9 * share;  // the two layers' cover, 0.87-0.93 of the share (sampled in Python)
    if (footprint > 0.8 * {BRASH_PIECE}) return mean;  // far: both layers at their mean
    float rim_b = 0.0, tone_b = 0.9, small = mean;
    vec3 n_b = n;
    float big = brash_layer(mat2(0.83, 0.56, -0.56, 0.83) * p / {BRASH_PIECE}, 1u, share, mean,
                            footprint / {BRASH_PIECE}, rim, n, tone);
    if (footprint < {0.8 * 0.45 * BRASH_PIECE})  // the small pieces, where they are not at their mean
        small = brash_layer(mat2(0.31, -0.95, 0.95, 0.31) * p / {0.45 * BRASH_PIECE} + 0.37, 2u, share, mean,
                            footprint / {0.45 * BRASH_PIECE}, rim_b, n_b, tone_b);
    float cover = max(big, share * small * (1.0 - big));
    rim = max(rim, rim_b * (1.0 - big));
    if (small * (1.0 - big) > big) {{ n = n_b; tone = tone_b; }}
    return cover;
}}
// the sail of the tile's ridge field k (0-based) under p: 0 off it, 1 on a ridge line;
// `n` the normal of the block there (the sail's slope and the block's own tilt), `gap` 1 in
// the dark gap between blocks, `fresh` the share of blue-green broken faces
float sail_at(vec2 p, int k, float footprint, out vec3 n, out float gap, out float fresh) {{
    vec2 nn = ridge_normal[k];
    vec3 shape = ridge_shape[k];
    float s = dot(p - ridge_anchor[k], nn);
    float d = s - shape.x * floor(s / shape.x + 0.5);
    float on = 1.0 - abs(d) / shape.y;
    gap = 0.0; fresh = 0.0; n = vec3(0.0, 0.0, 1.0);
    if (on <= 0.0) return 0.0;
    vec2 q = vec2(dot(p, vec2(-nn.y, nn.x)), d) / {BLOCK};
    q.x += 0.5 * floor(q.y);                           // rows of blocks laid over each other
    vec2 c = floor(q), f = fract(q) - 0.5;
    vec4 r, spare;  // (a block needs three of the eight values)
    cell_random(c, uint(3 + k), r, spare);
    vec2 tilt = 1.4 * (r.xy - 0.5);
    vec2 slope = -sign(d) * shape.z / shape.y * nn;
    float near = 1.0 - smoothstep(0.25, 0.8, footprint / {BLOCK});
    n = normalize(vec3(slope + near * (tilt.x * vec2(-nn.y, nn.x) + tilt.y * nn), 1.0));
    gap = near * smoothstep(0.38, 0.5, max(abs(f.x), abs(f.y)));
    fresh = near * step(0.85, r.z);
    return on;
}}
"""
