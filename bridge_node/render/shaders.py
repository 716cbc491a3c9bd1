"""GLSL 3.30 programs of the scene: sky, sea, level-ice slab, floes (instanced per tile),
own ship, and the channel's edge-blend pass. World frame: x east, y north, z up, metres."""

_FOG = """
uniform vec3 eye;
uniform float visibility;
uniform vec3 fog_colour;
vec3 fogged(vec3 colour, vec3 world) {
    // meteorological visibility: contrast falls to 5 % (exp(-3)) at that distance
    float f = exp(-3.0 * distance(world, eye) / visibility);
    return mix(fog_colour, colour, f);
}
"""

ENV_VS = """
#version 330
in vec2 in_ndc;
out vec2 ndc;
void main() { ndc = in_ndc; gl_Position = vec4(in_ndc, 0.9999, 1.0); }
"""
# One full-screen pass draws sky, sea and the unbreakable ice slab: each pixel's view ray
# is intersected with the water plane (and the slab's top), so far ice neither z-fights
# with the water nor costs three full-screen passes on a software rasteriser.
ENV_FS = "#version 330\n" + _FOG + """
uniform mat4 inv_view_proj;
uniform vec3 horizon_colour;
uniform vec3 zenith_colour;
uniform vec3 water_colour;
uniform vec3 ice_colour;
uniform float slab_z;
uniform float far;
uniform usampler2D tile_state;   // 0: unbreakable slab; else the tile's cells are drawn
uniform vec2 field_size;         // m
uniform float tile_side;
in vec2 ndc;
out vec4 colour;
void main() {
    vec4 a = inv_view_proj * vec4(ndc, -1.0, 1.0);
    vec4 b = inv_view_proj * vec4(ndc, 1.0, 1.0);
    vec3 ray = normalize(b.xyz / b.w - a.xyz / a.w);
    if (ray.z >= 0.0) {
        colour = vec4(mix(horizon_colour, zenith_colour, pow(ray.z, 0.6)), 1.0);
        return;
    }
    float t_sea = -eye.z / ray.z;
    if (t_sea > far) { colour = vec4(fog_colour, 1.0); return; }
    vec3 hit = eye + ray * ((slab_z - eye.z) / ray.z);
    bool on_field = hit.x >= 0.0 && hit.y >= 0.0 && hit.x < field_size.x && hit.y < field_size.y;
    if (on_field && texelFetch(tile_state, ivec2(floor(hit.xy / tile_side)), 0).r == 0u) {
        colour = vec4(fogged(ice_colour, hit), 1.0);
    } else {
        colour = vec4(fogged(water_colour, eye + ray * t_sea), 1.0);
    }
}
"""

FLOE_VS = """
#version 330
uniform mat4 view_proj;
uniform sampler2D pose_a;        // x, y, heave, yaw
uniform sampler2D pose_b;        // roll, pitch, status, unused
uniform int pose_width;
in vec3 in_pos;                  // about the cell's centroid, template frame, m
in vec3 in_normal;
in int in_cell;                  // cell index within the template
in int in_row_start;             // per instance: first floe row of the placed tile
out vec3 world;
out vec3 normal;
flat out float status;
void main() {
    int row = in_row_start + in_cell;
    ivec2 at = ivec2(row % pose_width, row / pose_width);
    vec4 a = texelFetch(pose_a, at, 0);
    vec4 b = texelFetch(pose_b, at, 0);
    float cr = cos(b.x), sr = sin(b.x), cp = cos(b.y), sp = sin(b.y), cy = cos(a.w), sy = sin(a.w);
    mat3 rx = mat3(1, 0, 0,  0, cr, sr,  0, -sr, cr);     // columns
    mat3 ry = mat3(cp, 0, -sp,  0, 1, 0,  sp, 0, cp);
    mat3 rz = mat3(cy, sy, 0,  -sy, cy, 0,  0, 0, 1);
    mat3 r = rz * ry * rx;
    world = r * in_pos + vec3(a.x, a.y, a.z);
    normal = r * in_normal;
    status = b.z;
    gl_ClipDistance[0] = world.z;                       // opaque water hides what is under it
    gl_Position = view_proj * vec4(world, 1.0);
}
"""
FLOE_FS = "#version 330\n" + _FOG + """
uniform vec3 sun;
uniform vec3 intact_colour;
uniform vec3 broken_colour;
uniform vec3 edge_colour;
in vec3 world;
in vec3 normal;
flat in float status;
out vec4 colour;
void main() {
    vec3 n = normalize(normal);
    vec3 base = abs(n.z) > 0.5 ? (status > 0.5 ? broken_colour : intact_colour) : edge_colour;
    float light = 0.7 + 0.3 * max(dot(n, sun), 0.0);
    colour = vec4(fogged(base * light, world), 1.0);
}
"""

SHIP_VS = """
#version 330
uniform mat4 view_proj;
uniform mat4 ship_to_world;
in vec3 in_pos;
in vec3 in_normal;
out vec3 world;
out vec3 normal;
void main() {
    world = (ship_to_world * vec4(in_pos, 1.0)).xyz;
    normal = mat3(ship_to_world) * in_normal;
    gl_Position = view_proj * vec4(world, 1.0);
}
"""
SHIP_FS = "#version 330\n" + _FOG + """
uniform vec3 sun;
in vec3 world;
in vec3 normal;
out vec4 colour;
void main() {
    vec3 n = normalize(normal);
    vec3 base = n.z > 0.5 ? vec3(0.35, 0.38, 0.36) : vec3(0.55, 0.12, 0.10);   // grey deck, red hull
    colour = vec4(fogged(base * (0.55 + 0.45 * max(dot(n, sun), 0.0)), world), 1.0);
}
"""

BLEND_VS = """
#version 330
in vec2 in_ndc;
out vec2 uv;
void main() { uv = in_ndc * 0.5 + 0.5; gl_Position = vec4(in_ndc, 0.0, 1.0); }
"""
BLEND_FS = """
#version 330
uniform sampler2D scene;
uniform float tan_half_hfov;
uniform float half_hfov;         // rad
uniform float blend_left;        // rad
uniform float blend_right;       // rad
uniform float gamma;
in vec2 uv;
out vec4 colour;
// Edge blending: in each band the light falls linearly with azimuth, so that where two
// channels overlap their light sums to one; the projector's gamma is undone on the ramp.
void main() {
    float azimuth = atan((2.0 * uv.x - 1.0) * tan_half_hfov);
    float ramp = 1.0;
    if (blend_left > 0.0) ramp *= clamp((azimuth + half_hfov) / blend_left, 0.0, 1.0);
    if (blend_right > 0.0) ramp *= clamp((half_hfov - azimuth) / blend_right, 0.0, 1.0);
    vec3 c = texture(scene, uv).rgb;
    colour = vec4(c * pow(ramp, 1.0 / gamma), 1.0);
}
"""
