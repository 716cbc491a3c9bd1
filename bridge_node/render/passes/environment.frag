#version 330
// The environment pass: one pass below the horizon (and over its anti-aliased band) draws
// sea and level ice, and the sky in the band's pixels above the horizon. Each pixel's view
// ray is intersected with the water plane and with the ice top: on an unbreakable tile that
// is ice (sea where the tile's thickness is 0: open water a chart or region lays); on a
// breakable or frozen tile the template's cell raster names the cell under the point, and
// the cell's status (from the status texture) says intact ice or water between broken
// floes. Level ice thus costs no triangles, and far ice does not z-fight with the water.
#include "common.glsl"

#include <rubble>

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
#include "entries.glsl"

uniform vec2 field_size;         // m
uniform float tile_side;
in vec3 ray;
out vec4 colour;
uint cell_status(int first, int cell) {
    return texelFetch(status, entry_texel(entry_of_cell(first, cell), textureSize(status, 0).y), 0).r;
}
const uint PIECE = PIECE_BIT;  // crack label bit of a piece (sim_core.ice.bending)
const uint FROZEN_CRACKED = FROZEN_CRACKED_ENTRY;  // a frozen tile's cracked intact cell's flag
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
    if (flag == UNPLACED_FLOE_FIELD) return cell.r != 0u;
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
// the sea at `world` seen along r; `wave`: the finest relief octave's derivatives (its
// texel's .yz) under the place moving with the waves, which are slight
vec3 sea(vec3 r, vec3 world, vec2 wave) {
    vec2 slope = WAVE_SLOPE / length(OCTAVE[0][0]) * ((wave - 0.5) * NOISE_RANGE.yz * OCTAVE[0]);
    return through_surface(r, normalize(vec3(-slope, 1.0)), water_body(world));
}
// the level ice at p (on the field) under its snow: wet along open water, a crack's slush,
// and a ridge's sail where its meshes do not reach
vec3 ice_ground(vec2 p, vec3 snow, ivec4 info, float rim, bool crack, float pixel_m) {
    vec3 surface = ice_surface(snow, intBitsToFloat(info.z), vec3(p, slab_z));
    vec3 ground = mix(surface, surface * WET, rim);   // wet, darker along open water
    if (crack) ground = surface * CRACK;              // a crack: sea water welled up into the snow
#if RIDGES
    int ridge = (info.w >> 16) & 0xFF;
    vec3 block_n;
    float gap, fresh;
    float sail = ridge > 0 ? sail_at(p, ridge - 1, pixel_m, block_n, gap, fresh) : 0.0;
    if (sail > 0.0) {                                 // a ridge's sail beyond the meshes: tumbled blocks
        vec3 albedo = mix(ice_albedo(intBitsToFloat(info.z)), FRESH_ICE, fresh);
        ground = lit(albedo, block_n, vec3(p, slab_z)) * (1.0 - 0.7 * gap);
    }
#endif
    return ground;
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
        ground = ice_ground(p, snow, info, rim, crack, pixel_m);
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
