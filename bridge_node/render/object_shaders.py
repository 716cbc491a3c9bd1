"""GLSL 3.30 programs of the scene's objects: broken floes, the own ship, its navigation
lights, and the channel's last passes (edge blend bands, warp). What they share with the
environment pass (noise, light, fog, the pose texture layout) is in ``shaders``."""
from bridge_node.render.shaders import COMMON, ENTRIES

SEEN_DEPTH = 4.0  # m: floes are drawn down to this depth (deeper ice is lost in the sea)
FLOE_VS = f"\n#version 330\nconst float SEEN_DEPTH = {SEEN_DEPTH};" + """
uniform mat4 view_proj;
uniform sampler2D pose_q;        // per floe row (and frozen floe): its attitude as a unit quaternion (x, y,
uniform sampler2D pose_t;        // z, w), and its place (x, y, heave, m); made on the CPU from the yaw, roll
                                 // and pitch, sparing each vertex six sines and cosines
""" + ENTRIES + """
uniform usampler2D status;       // per floe row its status (and crack label), per cell of a frozen tile 1 + its floe
uniform int first;               // the tile's first row; frozen, its first status entry (negative)
uniform int first_floe;          // frozen, the number of its first floe's pose entry
uniform bool frozen;
uniform int patch_base;          // the tile's first snow patch
uniform bool reflected;          // drawn mirrored in the water plane: the floes' reflections
in vec3 in_pos;                  // about the cell's centroid, template frame, m
in vec3 in_normal;
in int in_cell;                  // the cell's index in its template
out vec3 world;                  // the point itself (also when its reflection is drawn), m
out vec3 normal;
out vec2 local;                  // relief coordinates that move with the floe, m
flat out int top;
flat out float centre_z;         // the floe's centre of mass above the water, m
void main() {
    int row = first + in_cell;   // a live tile's floe; a frozen tile's: -1 - its pose entry's number
    if (frozen) {
        uint floe = texelFetch(status, entry_texel(entry_of_cell(first, in_cell), textureSize(status, 0).y), 0).r;
        row = -1 - (first_floe + int(floe) - 1);
    }
    ivec2 at = entry_texel(row, textureSize(pose_q, 0).y);
    vec4 q = texelFetch(pose_q, at, 0);
    vec3 t = texelFetch(pose_t, at, 0).xyz;
    vec3 q2 = 2.0 * q.xyz, wq = q.w * q2, xq = q.x * q2, yq = q.y * q2;
    float zz = q.z * q2.z;
    mat3 r = mat3(1.0 - yq.y - zz, xq.y + wq.z, xq.z - wq.y,       // columns
                  xq.y - wq.z, 1.0 - xq.x - zz, yq.z + wq.x,
                  xq.z + wq.y, yq.z - wq.x, 1.0 - xq.x - yq.y);
    world = r * in_pos + t;
    normal = r * in_normal;
    centre_z = t.z;
    int snow_patch = (patch_base + in_cell) % (61 * 59);  // each floe its own patch of snow
    local = in_pos.xy + 31.7 * vec2(snow_patch % 61, snow_patch / 61);
    top = in_normal.z > 0.5 ? 1 : 0;
    // ice deeper than SEEN_DEPTH is lost in the sea; only what is above the water is mirrored
    gl_ClipDistance[0] = reflected ? world.z : world.z + SEEN_DEPTH;
    gl_Position = view_proj * vec4(world.xy, reflected ? -world.z : world.z, 1.0);
}
"""
# Floe tops are the level ice they broke from; sides show the blue-green of sea ice,
# darkened at the waterline. Under the water (floes the bow turned under) the ice is seen
# through the surface as pale blue-green slabs, fading into the sea's body with depth.
# Reflected (drawn mirrored, blended over the sea as premultiplied colour and alpha: the
# Fresnel share), a floe's part above the water shows in the sea below its waterline.
FLOE_FS = "#version 330\n" + COMMON + """
const vec3 UNDER_WATER = vec3(0.55, 0.88, 0.85);  // ice seen through the sea: the red absorbed first
const float FADE_DEPTH = 1.2;    // m: depth over which submerged ice fades into the sea's body (1/e)
uniform float thickness;         // m: the tile's level ice
uniform bool reflected;
in vec3 world;
in vec3 normal;
in vec2 local;
flat in int top;
flat in float centre_z;
out vec4 colour;
float waterline(float z) { return mix(0.45, 1.0, smoothstep(0.0, 0.06, z)); }  // wet and dark at the water
void main() {
    if (classes) {  // a floe whose top (its centre plus half its thickness) is under the water: turned under
        colour = CLASS_COLOUR[centre_z + 0.5 * thickness < 0.0 ? CLASS_SUBMERGED_FLOE : CLASS_BROKEN_FLOE];
        return;
    }
    vec3 n = normalize(normal);
    vec3 c;
    if (top == 1) {  // the snow only on tops (side faces and their reflections need none)
        vec3 snow = snow_under(local, distance(world, eye), texture(noise, OCTAVE[0] * local).xyz);
        float albedo;
        vec3 bump = relief(snow, snow_depth(thickness), albedo);
        c = lit(ice_albedo(thickness) * albedo, normalize(n + vec3(bump.xy, 0.0)), world);
    } else {
        c = lit(mix(vec3(0.42, 0.50, 0.53), vec3(0.30, 0.62, 0.64), smoothstep(0.1, 0.5, thickness)), n, world);
    }
    if (reflected) {
        vec3 image = vec3(world.xy, -world.z);
        float share = fresnel(normalize(image - eye), vec3(0.0, 0.0, 1.0));
        colour = vec4(share * fogged(c * waterline(world.z), image), share);
        return;
    }
    if (world.z < 0.0)
        c = through_surface(normalize(world - eye), vec3(0.0, 0.0, 1.0),
                            mix(water_body(world), c * UNDER_WATER, exp(world.z / FADE_DEPTH)));
    else
        c *= waterline(world.z);
    colour = opaque(fogged(c, world));
}
"""

SHIP_VS = """
#version 330
uniform mat4 view_proj;
uniform mat4 ship_to_world;
in vec3 in_pos;
in vec3 in_normal;
in vec3 in_colour;
out vec3 world;
out vec3 normal;
out vec3 albedo;
void main() {
    world = (ship_to_world * vec4(in_pos, 1.0)).xyz;
    normal = normalize(inverse(transpose(mat3(ship_to_world))) * in_normal);  // scaled for other vessels
    albedo = in_colour;
    gl_Position = view_proj * vec4(world, 1.0);
}
"""
SHIP_FS = "#version 330\n" + COMMON + """
uniform int ship_class;          // the class pass: own ship or other vessel
in vec3 world;
in vec3 normal;
in vec3 albedo;
out vec4 colour;
void main() {
    if (classes) { colour = CLASS_COLOUR[ship_class]; return; }
    vec3 n = normalize(normal);
    n = dot(n, eye - world) < 0.0 ? -n : n;  // two-sided: a bulwark's inside is lit as its inside
    colour = opaque(fogged(lit(albedo, n, world), world));
}
"""

# Navigation lights: points of a few pixels, shown only where the eye is inside a light's
# sector, added to the image as strongly as the daylight leaves them visible, fogged
NAV_VS = """
#version 330
uniform mat4 view_proj;
uniform mat4 ship_to_world;
uniform vec3 eye;
uniform float visibility;
uniform float point_px;
in vec3 in_pos;                  // ship frame, m
in vec3 in_colour;
in vec2 in_sector;               // centre and half width, rad from the bow, + to starboard
out vec3 colour;
void main() {
    vec3 world = (ship_to_world * vec4(in_pos, 1.0)).xyz;
    vec3 seen = inverse(mat3(ship_to_world)) * (eye - world);   // towards the eye, ship frame
    float off = abs(mod(atan(seen.y, seen.x) - in_sector.x + 3.14159265, 6.28318531) - 3.14159265);
    colour = in_colour * exp(-3.0 * distance(world, eye) / visibility);
    gl_PointSize = point_px;
    gl_Position = off <= in_sector.y ? view_proj * vec4(world, 1.0) : vec4(2.0, 2.0, 2.0, 1.0);
}
"""
NAV_FS = """
#version 330
uniform float strength;          // 0 by day, 1 at night
in vec3 colour;
out vec4 frag;
void main() {
    vec2 c = 2.0 * gl_PointCoord - 1.0;
    frag = vec4(colour * strength * max(1.0 - dot(c, c), 0.0), 1.0);
}
"""

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

WARP_VS = """
#version 330
in vec2 in_ndc;                  // a grid node on the projector's output
in vec2 in_uv;                   // the point of the flat image it shows (0..1; outside: black)
out vec2 uv;
void main() { uv = in_uv; gl_Position = vec4(in_ndc, 0.0, 1.0); }
"""
WARP_FS = """
#version 330
uniform sampler2D flat_image;    // the channel's image, drawn flat
in vec2 uv;
out vec4 colour;
void main() {
    bool inside = all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
    colour = inside ? vec4(texture(flat_image, uv).rgb, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
"""
