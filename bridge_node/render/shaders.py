"""GLSL 3.30 programs of the scene: the environment pass (sky, sea, level ice: the
unbreakable slab and the intact cells of breakable tiles), and what the other programs share
(the pose texture layout, noise, light, fog: ``COMMON``, ``ENTRIES``); broken floes, the
own ship, its navigation lights, the blend bands and the warp are in ``object_shaders``.
World frame: x east, y north, z up, metres. The channel's edge blending is a last pass over
the blend bands only, multiplying what is there by each column's factor.

Looks: level ice and floe tops are snow (or, thin, grey nilas) with relief and albedo from
octaves of procedural noise; floe sides show the blue-green of sea ice, darkened at the
waterline, and ice under the water shows through it, pale blue-green, fading with depth;
the sea reflects the sky and the floes by Fresnel through slight waves; everything is lit by the sun and the sky of the moment and the own ship's
searchlights, and fogged by the visibility.
"""
import math

from bridge_node.render import classes, rubble_look
from bridge_node.render.textures import NOISE_RANGE
from sim_core.ice.bending import PIECE


PERIODS = (23.0, 290.0, 2100.0)  # m: of the relief's three noise fetches
POSE_WIDTH = 2048  # texels per line of the pose textures: a power of two, a constant in the shaders (on
                   # llvmpipe, division by a uniform is done lane by lane and cost the level ice a tenth)
UNPLACED_FLOE_FIELD = 2  # tile table flag of a floe field's tile not simulated (its floes drawn at home)
FROZEN_CRACKED = 0xF000  # a frozen tile's status entry of a cracked intact cell: this | its crack label (no
# tile has this many cells, so no floe number reaches it)
# Where an entry of the pose and status textures lies: live rows (i >= 0) fill lines from the
# first up, frozen tiles' entries (coded i = -1 - k) from the last down, so that either part
# grows without moving the other's numbers. A frozen tile's k-th cell is first - k.
ENTRIES = "const int POSE_WIDTH = " + str(POSE_WIDTH) + """;
ivec2 entry_texel(int i, int lines) {
    int k = i >= 0 ? i : -1 - i;
    return ivec2(k % POSE_WIDTH, i >= 0 ? k / POSE_WIDTH : lines - 1 - k / POSE_WIDTH);
}
int entry_of_cell(int first, int cell) { return first >= 0 ? first + cell : first - cell; }
"""


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


COMMON = """
uniform vec3 eye;
uniform float visibility;
uniform vec3 sun;                // unit, towards the sun
uniform vec3 direct;             // the sun's light
uniform vec3 ambient;            // the sky's light
uniform vec3 zenith_colour;
uniform vec3 horizon_colour;     // also the fog's colour
uniform sampler2D noise;         // height, d/du, d/dv: tileable noise over five octaves
""" + _octaves() + classes.GLSL + """
vec3 fogged(vec3 colour, vec3 world) {
    // meteorological visibility: contrast falls to 5 % (exp(-3)) at that distance
    float f = exp(-3.0 * distance(world, eye) / visibility);
    return mix(horizon_colour, colour, f);
}
// (powers by products: on llvmpipe pow is exp2 and log2, and took a tenth of the ground pass)
vec3 sky(vec3 dir) {
    float c = max(dot(dir, sun), 0.0), c2 = c * c, c4 = c2 * c2;
    vec3 glow = direct * (0.25 * c4 * c4 + 4.0 * smoothstep(0.99996, 0.99999, c));
    return mix(horizon_colour, zenith_colour, sqrt(max(dir.z, 0.0))) + glow;
}
uniform vec3 light_pos[LIGHT_SLOTS];     // world, m
uniform vec3 light_axis[LIGHT_SLOTS];    // unit
uniform float light_cos[LIGHT_SLOTS];    // cosine of half the beam
uniform float light_power[LIGHT_SLOTS];  // intensity over the illuminance the eye sees as white, m2
// the searchlights' light on a surface at `world` facing n (a xenon lamp's white), soft at
// the beam's edge and falling with the square of the distance
vec3 searchlit(vec3 world, vec3 n) {
    float e = 0.0;
    for (int k = 0; k < LIGHTS; k++) {  // LIGHTS: see with_lights
        vec3 d = world - light_pos[k];
        float dist2 = max(dot(d, d), 1.0);
        vec3 l = d * inversesqrt(dist2);
        float cone = smoothstep(light_cos[k], 0.5 * (light_cos[k] + 1.0), dot(l, light_axis[k]));
        e += light_power[k] * cone * max(dot(n, -l), 0.0) / dist2;
    }
    return vec3(1.0, 0.97, 0.92) * e;
}
vec3 lit(vec3 albedo, vec3 n, vec3 world) {
    // soft (wrapped) diffuse light: faces turned a little away from the sun still get some
    float d = max((dot(n, sun) + 0.25) / 1.25, 0.0);
    return albedo * (direct * d + ambient + searchlit(world, n));
}
// The snow relief under p (m) seen from `dist` m: the sum over the octaves of their slope
// (before the depth) and albedo variation, one fetch each within its reach (relief_reach
// times its period over the finest's; beyond it, the mip level is the features' mean, 0, so
// it fades to 0 over the last 30 % and is not fetched). The branch is smooth on the screen,
// so the derivatives that pick the mip levels stay those of neighbours on the same side.
// The caller fetches the finest octave's texel (`finest`): the environment pass shares it
// with the sea's waves.
uniform float relief_reach;      // m: how far the finest octave is fetched
vec3 snow_under(vec2 p, float dist, vec3 finest) {
    vec3 sum = vec3(0.0);        // slope x, y; albedo
    for (int k = 0; k < OCTAVES; k++) {
        float reach = relief_reach * OCTAVE_SCALE[k];
        if (dist < reach) {
            vec3 texel = k == 0 ? finest : texture(noise, OCTAVE[k] * p).xyz;
            vec3 h = (texel - 0.5) * NOISE_RANGE * (1.0 - smoothstep(0.7 * reach, reach, dist));
            sum += vec3(OCTAVE_AMP[k].x * (h.yz * OCTAVE[k]), OCTAVE_AMP[k].y * h.x);  // chain rule: d/dp = (d/duv) M
        }
    }
    return sum;
}
// The relief's normal for a snow depth (1: full), and its albedo factor.
vec3 relief(vec3 snow, float depth, out float albedo) {
    albedo = 1.0 + snow.z;
    return normalize(vec3(-depth * snow.xy, 1.0));
}
// Sea ice by thickness (m): dark nilas, grey and grey-white young ice, snow-covered white
vec3 ice_albedo(float h) {
    vec3 c = mix(vec3(0.26, 0.29, 0.31), vec3(0.50, 0.54, 0.57), smoothstep(0.03, 0.12, h));
    c = mix(c, vec3(0.72, 0.75, 0.78), smoothstep(0.12, 0.25, h));
    return mix(c, vec3(0.93, 0.95, 0.97), smoothstep(0.25, 0.45, h));
}
// snow relief depth by thickness: slight on nilas, full on snow-covered ice
float snow_depth(float h) { return mix(0.15, 1.0, smoothstep(0.1, 0.4, h)); }
vec3 ice_surface(vec3 snow, float h, vec3 world) {
    float albedo;
    vec3 n = relief(snow, snow_depth(h), albedo);
    return lit(ice_albedo(h) * albedo, n, world);
}
uniform vec3 water_colour;
// the share of the light the sea mirrors along r off a surface of normal n: Schlick's
// Fresnel (2 % at normal incidence), which the waves' roughness (shadowing and masking)
// keeps below 70 % at grazing angles (Lagarde 2011)
float fresnel(vec3 r, vec3 n) {
    float x = 1.0 - max(dot(-r, n), 0.0), x2 = x * x;
    return 0.02 + 0.68 * x2 * x2 * x;
}
// the sea seen along r through a surface of normal n: its body (what is under it) and the
// sky it mirrors
vec3 through_surface(vec3 r, vec3 n, vec3 body) {
    vec3 mirror = reflect(r, n);
    mirror.z = abs(mirror.z);
    return mix(body, sky(mirror), fresnel(r, n));
}
vec3 water_body(vec3 world) {
    return water_colour * (direct * max(sun.z, 0.0) + ambient + searchlit(world, vec3(0.0, 0.0, 1.0)));
}
vec4 opaque(vec3 colour) { return vec4(colour, 1.0); }
"""

def with_rubble(source: str, brash: bool, ridges: bool) -> str:
    """The environment pass's source with its brash and ridge code compiled in only where
    the field has them: on llvmpipe a branch does not skip work, so a field without them
    would pay for them in every ground pixel."""
    return _defined(source, BRASH=int(brash), RIDGES=int(ridges))


def with_lights(source: str, searchlights: int) -> str:
    """A fragment shader's source with its number of searchlights fixed when it compiles:
    on llvmpipe a loop to a uniform bound costs as much as the ice's relief, even when the
    bound is 0, while a loop to a constant 0 costs nothing."""
    return _defined(source, LIGHTS=searchlights, LIGHT_SLOTS=max(searchlights, 1))  # GLSL has no empty arrays


def _defined(source: str, **defines: int) -> str:
    """The source with ``#define NAME value`` lines after its ``#version``."""
    lines = "".join(f"#define {name} {value}\n" for name, value in defines.items())
    return source.replace("#version 330\n", "#version 330\n" + lines, 1)


ENV_VS = """
#version 330
in vec2 in_ndc;
in vec3 in_ray;                  // world direction through this corner (linear in the screen)
out vec3 ray;
void main() { ray = in_ray; gl_Position = vec4(in_ndc, 0.9999, 1.0); }
"""
# The sky above the horizon band (see ENV_FS) is a pass of its own: on llvmpipe a branch
# does not skip work, so within one pass every sky pixel would pay for the ground.
SKY_FS = "#version 330\n" + COMMON + """
in vec3 ray;
out vec4 colour;
void main() { colour = classes ? CLASS_COLOUR[CLASS_SKY] : opaque(sky(normalize(ray))); }
"""
# One pass below the horizon (and over its anti-aliased band) draws sea and level ice, and
# the sky in the band's pixels above the horizon. Each pixel's view ray is intersected
# with the water plane and with the ice top: on an unbreakable tile that is ice (sea where
# the tile's thickness is 0: open water a chart or region lays); on a
# breakable or frozen tile the template's cell raster names the cell under the point, and
# the cell's status (from the status texture) says intact ice or water between broken floes.
# Level ice thus costs no triangles, and far ice does not z-fight with the water.
ENV_FS = "#version 330\n" + COMMON + rubble_look.GLSL + """
uniform float slab_z;
uniform float far;               // m: level ice is looked up this far
uniform isampler2D tile_info;    // per tile: its first status entry, template | quarter turns << 16, level-ice
                                 // thickness (m, float bits), and a flag byte: 1 if breakable (0: the unbreakable
                                 // slab; 2: a floe field's tile not simulated, its floes where its template lays
                                 // them) | brash share << 8 | (1 + ridge field) << 16 (rubble_look): one fetch
uniform usampler2D cell_raster;  // templates stacked in y: 1 + cell index (0 in a crack), 1 + the nearest
                                 // other cell's within rim_px (0: none), distance to it (1/256 px)
uniform float rim_px;
uniform int raster_size;
uniform usampler2D status;       // per floe row its status | its crack label << 8 (see scene_uploads), per
                                 // cell of a frozen tile 1 + its floe: 0 intact
""" + ENTRIES + """
uniform vec2 field_size;         // m
uniform float tile_side;
in vec3 ray;
out vec4 colour;
uint cell_status(int first, int cell) {
    return texelFetch(status, entry_texel(entry_of_cell(first, cell), textureSize(status, 0).y), 0).r;
}
const uint PIECE = """ + str(PIECE) + """u;  // crack label bit of a piece (sim_core.ice.bending)
const uint FROZEN_CRACKED = """ + str(FROZEN_CRACKED) + """u;  // a frozen tile's cracked intact cell's flag
// a cell's status entry: a live tile's row's status | crack label << 8; a frozen tile's
// 1 + its floe, or FROZEN_CRACKED | its crack label (first < 0)
bool broken(uint entry, int first) {
    return first >= 0 ? (entry & 0xFFu) != 0u : entry != 0u && entry < FROZEN_CRACKED;
}
uint crack_label(uint entry, int first) {
    return first >= 0 ? entry >> 8 : (entry >= FROZEN_CRACKED ? entry & 0xFFu : 0u);
}
// Whether level ice lies at p; its rim: 1 at the edge of a broken neighbour (open water),
// falling to 0 at rim_px pixels of the raster from it; and whether a crack runs there: on
// the raster pixels at an edge between cells of different crack labels with a piece on
// either side or both cracked (sim_core.ice.bending.crack_lines), within half the
// `footprint` (raster pixels a screen pixel covers, at least 1) of the edge, so that a crack
// stays a line about a pixel wide in the distance.
// the raster texel of the tile's template under p
uvec3 raster_cell(vec2 p, ivec2 tile, ivec4 info) {
    vec2 local = p - vec2(tile) * tile_side - 0.5 * tile_side;          // about the tile centre
    int k = info.y >> 16;                                               // undo the quarter turns
    float c = k == 0 ? 1.0 : (k == 2 ? -1.0 : 0.0), s = k == 1 ? 1.0 : (k == 3 ? -1.0 : 0.0);
    local = vec2(c * local.x + s * local.y, c * local.y - s * local.x);
    vec2 uv = clamp((local / tile_side + 0.5) * float(raster_size), vec2(0.0), vec2(float(raster_size) - 1.0));
    return texelFetch(cell_raster, ivec2(uv) + ivec2(0, (info.y & 0xFFFF) * raster_size), 0).rgb;
}
bool level_ice(vec2 p, ivec2 tile, ivec4 info, float footprint, out float rim, out bool crack) {
    rim = 0.0;
    crack = false;
    int flag = info.w & 0xFF;
    if (flag == 0) return intBitsToFloat(info.z) > 0.0;                // the unbreakable slab (none: open water)
    uvec3 cell = raster_cell(p, tile, info);
    // a floe field's tile not simulated: its floes where the template lays them
    if (flag == """ + str(UNPLACED_FLOE_FIELD) + """) return cell.r != 0u;
    if (cell.r == 0u) return false;
    uint own = cell_status(info.x, int(cell.r) - 1);
    if (broken(own, info.x)) return false;
    if (cell.g != 0u) {
        uint other = cell_status(info.x, int(cell.g) - 1);
        if (broken(other, info.x)) {
            rim = rim_px > 0.0 ? max(0.0, 1.0 - float(cell.b) / (256.0 * rim_px)) : 0.0;  // none beyond rim_px
        } else if (float(cell.b) < 128.0 * footprint) {  // within half a footprint of the edge
            uint a = crack_label(own, info.x), b = crack_label(other, info.x);
            crack = a != b && ((a != 0u && b != 0u) || ((a | b) & PIECE) != 0u);
        }
    }
    return true;
}
const vec3 WET = vec3(0.55, 0.62, 0.68);  // wet snow and slush against the dry
const vec3 CRACK = vec3(0.28, 0.36, 0.42);  // a crack's wet slush against the dry snow
const vec3 FRESH_ICE = vec3(0.70, 0.85, 0.88);  // a broken block's face: the blue-green of sea ice
const vec3 WET_BRASH = vec3(0.86, 0.90, 0.93);  // brash: snow and slush, wet, greyer than dry snow
const vec3 SUBMERGED = vec3(0.25, 0.52, 0.52);  // ice just under the water, pale blue-green
const float WAVE_SLOPE = 0.04;
const vec2 WAVE_DRIFT = vec2(0.6, 0.35);  // m/s: ripples travelling before a light air
uniform float time;                       // s: the exercise's clock
// the sea at `world` seen along r; `wave`: the finest relief octave's derivatives (its
// texel's .yz) under the place moving with the waves, which are slight
vec3 sea(vec3 r, vec3 world, vec2 wave) {
    vec2 slope = WAVE_SLOPE / length(OCTAVE[0][0]) * ((wave - 0.5) * NOISE_RANGE.yz * OCTAVE[0]);
    return through_surface(r, normalize(vec3(-slope, 1.0)), water_body(world));
}
void main() {
    vec3 r = normalize(ray);
    // the horizon is anti-aliased: the share of the pixel below it shows the ground seen
    // through the middle of that share
    float fw = max(fwidth(r.z), 1e-6);
    float below = clamp(0.5 - r.z / fw, 0.0, 1.0);
    if (below <= 0.0) { colour = classes ? CLASS_COLOUR[CLASS_SKY] : opaque(sky(r)); return; }
    vec3 above = below < 1.0 ? sky(r) : vec3(0.0);  // the sky only in the horizon's pixels
    vec3 g = normalize(vec3(r.xy, min(r.z, 0.5 * (r.z - 0.5 * fw))));
    float t = (slab_z - eye.z) / g.z;
    vec2 p = eye.xy + g.xy * t;
    ivec2 tile = ivec2(floor(p / tile_side));
    bool on_field = t < far && p.x >= 0.0 && p.y >= 0.0 && p.x < field_size.x && p.y < field_size.y;
    float rim;
    bool crack;
    // clamped: off the field the fetch is unused, and one outside the texture is undefined
    ivec4 info = texelFetch(tile_info, clamp(tile, ivec2(0), textureSize(tile_info, 0) - 1), 0);
    float pixel_m = 0.5 * (fwidth(p.x) + fwidth(p.y));
    float footprint = max(1.0, pixel_m * float(raster_size) / tile_side);
    bool ice = on_field && level_ice(p, tile, info, footprint, rim, crack);
    vec3 at = eye - g * eye.z / g.z;  // on the water
    float brash_share = on_field ? float((info.w >> 8) & 0xFF) / 255.0 : 0.0, brash_rim = 0.0, brash = 0.0;
    vec3 piece_n;
    float tone;
#if BRASH
    if (!ice && brash_share > 0.0) brash = brash_at(at.xy, brash_share, pixel_m, brash_rim, piece_n, tone);
#endif
    if (classes) {  // the class pass: the pixel's class, no shading
        int ground_class = ice ? (crack ? CLASS_CRACK : CLASS_LEVEL_ICE)
                               : (brash > 0.5 ? CLASS_BROKEN_FLOE : CLASS_OPEN_WATER);
        colour = CLASS_COLOUR[below < 0.5 ? CLASS_SKY : ground_class];
        return;
    }
    // one fetch of the finest octave, under the snow on ice, under the moving waves on the sea
    // (on llvmpipe, both branches cost every pixel); its mip level from the snow's coordinates
    vec2 u = OCTAVE[0] * p;
    vec3 finest = textureGrad(noise, ice ? u : OCTAVE[0] * (at.xy - WAVE_DRIFT * time), dFdx(u), dFdy(u)).xyz;
    vec3 snow = snow_under(p, t, finest);
    vec3 ground;
    if (ice) {
        vec3 surface = ice_surface(snow, intBitsToFloat(info.z), vec3(p, slab_z));
        ground = mix(surface, surface * WET, rim);   // wet, darker along open water
        if (crack) ground = surface * CRACK;         // a crack: sea water welled up into the snow
#if RIDGES
        int ridge = on_field ? (info.w >> 16) & 0xFF : 0;
        vec3 block_n;
        float gap, fresh;
        float sail = ridge > 0 ? sail_at(p, ridge - 1, pixel_m, block_n, gap, fresh) : 0.0;
        if (sail > 0.0) {                            // a ridge's sail beyond the meshes: tumbled blocks
            vec3 albedo = mix(ice_albedo(intBitsToFloat(info.z)), FRESH_ICE, fresh);
            ground = lit(albedo, block_n, vec3(p, slab_z)) * (1.0 - 0.7 * gap);
        }
#endif
    } else {  // the sea, out to the horizon; brash on it
        ground = sea(g, at, finest.yz);
#if BRASH
        if (brash_share > 0.0) {
            ground = mix(ground, lit(SUBMERGED, vec3(0.0, 0.0, 1.0), at), 0.6 * brash_rim);
            ground = mix(ground, lit(WET_BRASH * tone, piece_n, at), brash);
        }
#endif
    }
    colour = opaque(mix(above, fogged(ground, vec3(p, slab_z)), below));  // fogged once: ice and sea alike
}
"""
