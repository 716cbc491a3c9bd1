#version 330
// Floe tops are the level ice they broke from; sides show the blue-green of sea ice,
// darkened at the waterline; an underside (a floe turned up on edge or over) is wet, rough
// ice, tinged brown where ice algae grow at the bottom of first-year ice (Arrigo, "Sea ice
// ecosystems", Annual Review of Marine Science 6, 2014). Under the water (floes the bow turned under) the ice is seen
// through the surface as pale blue-green slabs, fading into the sea's body with depth.
// Reflected (drawn mirrored, blended over the sea as premultiplied colour and alpha: the
// Fresnel share), a floe's part above the water shows in the sea below its waterline.
#include "common.glsl"

const vec3 UNDER_WATER = vec3(0.55, 0.88, 0.85);  // ice seen through the sea: the red absorbed first
const vec3 UNDERSIDE = vec3(0.50, 0.52, 0.44);    // a floe's bottom: wet, grey-green, brown-tinged
const float FADE_DEPTH = 1.2;    // m: depth over which submerged ice fades into the sea's body (1/e)
#include "tile.glsl"
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
    } else if (top == 2) {
        c = lit(UNDERSIDE * (0.85 + 0.3 * texture(noise, OCTAVE[0] * local).x), n, world);
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
