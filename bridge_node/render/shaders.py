"""GLSL 3.30 programs of the scene: the environment pass (sky, sea, level ice: the
unbreakable slab and the intact cells of breakable tiles), broken floes, and the own ship.
World frame: x east, y north, z up, metres. The channel's edge blending is a last pass over
the blend bands only, multiplying what is there by each column's factor."""

_COMMON = """
uniform vec3 eye;
uniform float visibility;
uniform vec3 fog_colour;
vec3 fogged(vec3 colour, vec3 world) {
    // meteorological visibility: contrast falls to 5 % (exp(-3)) at that distance
    float f = exp(-3.0 * distance(world, eye) / visibility);
    return mix(fog_colour, colour, f);
}
vec4 opaque(vec3 colour) { return vec4(colour, 1.0); }
"""

ENV_VS = """
#version 330
in vec2 in_ndc;
in vec3 in_ray;                  // world direction through this corner (linear in the screen)
out vec3 ray;
void main() { ray = in_ray; gl_Position = vec4(in_ndc, 0.9999, 1.0); }
"""
# One full-screen pass draws sky, sea and level ice. Each pixel's view ray is intersected
# with the water plane and with the ice top: on an unbreakable tile that is ice; on a
# breakable or frozen tile the template's cell raster names the cell under the point, and
# the cell's status (from the pose texture) says intact ice or water between broken floes.
# Level ice thus costs no triangles, and far ice does not z-fight with the water.
ENV_FS = "#version 330\n" + _COMMON + """
uniform vec3 horizon_colour;
uniform vec3 zenith_colour;
uniform vec3 water_colour;
uniform vec3 ice_colour;
uniform float slab_z;
uniform float far;
uniform isampler2D tile_info;    // per tile: first floe row (-1: unbreakable), template | quarter turns << 16
uniform usampler2D cell_raster;  // templates stacked in y: 1 + cell index, 0 in a crack
uniform int raster_size;
uniform usampler2D status;       // per floe row: 0 intact, 1 free, 2 frozen
uniform int pose_width;
uniform vec2 field_size;         // m
uniform float tile_side;
in vec3 ray;
out vec4 colour;
bool level_ice(vec2 p) {
    ivec2 tile = ivec2(floor(p / tile_side));
    ivec2 info = texelFetch(tile_info, tile, 0).rg;
    if (info.x < 0) return true;                                        // the unbreakable slab
    vec2 local = p - vec2(tile) * tile_side - 0.5 * tile_side;          // about the tile centre
    int k = info.y >> 16;                                               // undo the quarter turns
    float c = k == 0 ? 1.0 : (k == 2 ? -1.0 : 0.0), s = k == 1 ? 1.0 : (k == 3 ? -1.0 : 0.0);
    local = vec2(c * local.x + s * local.y, c * local.y - s * local.x);
    vec2 uv = clamp((local / tile_side + 0.5) * float(raster_size), vec2(0.0), vec2(float(raster_size) - 1.0));
    uint cell = texelFetch(cell_raster, ivec2(uv) + ivec2(0, (info.y & 0xFFFF) * raster_size), 0).r;
    if (cell == 0u) return false;
    int row = info.x + int(cell) - 1;
    return texelFetch(status, ivec2(row % pose_width, row / pose_width), 0).r == 0u;
}
void main() {
    vec3 r = normalize(ray);
    if (r.z >= 0.0) {
        colour = opaque(mix(horizon_colour, zenith_colour, sqrt(r.z)));
        return;
    }
    float t_sea = -eye.z / r.z;
    if (t_sea > far) { colour = opaque(fog_colour); return; }
    vec3 hit = eye + r * ((slab_z - eye.z) / r.z);
    bool on_field = hit.x >= 0.0 && hit.y >= 0.0 && hit.x < field_size.x && hit.y < field_size.y;
    if (on_field && level_ice(hit.xy)) colour = opaque(fogged(ice_colour, hit));
    else colour = opaque(fogged(water_colour, eye + r * t_sea));
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
in int in_row;                   // the floe's row in the state arrays
out vec3 world;
out vec3 normal;
void main() {
    ivec2 at = ivec2(in_row % pose_width, in_row / pose_width);
    vec4 a = texelFetch(pose_a, at, 0);
    vec4 b = texelFetch(pose_b, at, 0);
    float cr = cos(b.x), sr = sin(b.x), cp = cos(b.y), sp = sin(b.y), cy = cos(a.w), sy = sin(a.w);
    mat3 rx = mat3(1, 0, 0,  0, cr, sr,  0, -sr, cr);     // columns
    mat3 ry = mat3(cp, 0, -sp,  0, 1, 0,  sp, 0, cp);
    mat3 rz = mat3(cy, sy, 0,  -sy, cy, 0,  0, 0, 1);
    mat3 r = rz * ry * rx;
    world = r * in_pos + vec3(a.x, a.y, a.z);
    normal = r * in_normal;
    gl_ClipDistance[0] = world.z;                       // opaque water hides what is under it
    gl_Position = view_proj * vec4(world, 1.0);
}
"""
# Flat faces, lit by the sun: horizontal faces in one colour, vertical ones in another.
_SHADED = "#version 330\n" + _COMMON + """
uniform vec3 sun;
uniform vec3 top_colour;
uniform vec3 side_colour;
uniform float ambient;
in vec3 world;
in vec3 normal;
out vec4 colour;
void main() {
    vec3 n = normalize(normal);
    vec3 base = abs(n.z) > 0.5 ? top_colour : side_colour;
    colour = opaque(fogged(base * (ambient + (1.0 - ambient) * max(dot(n, sun), 0.0)), world));
}
"""
FLOE_FS = _SHADED

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
SHIP_FS = _SHADED

BAND_VS = """
#version 330
in vec2 in_ndc;
void main() { gl_Position = vec4(in_ndc, 0.0, 1.0); }
"""
# drawn with blending (zero, source colour): the framebuffer is multiplied by the factor
BAND_FS = """
#version 330
uniform sampler2D blend_ramp;    // per pixel column: the channel's edge-blend factor
out vec4 colour;
void main() { colour = vec4(vec3(texelFetch(blend_ramp, ivec2(gl_FragCoord.x, 0), 0).r), 1.0); }
"""
