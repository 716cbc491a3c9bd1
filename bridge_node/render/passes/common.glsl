// What the fragment shaders of the scene share: the uniform blocks, the noise, and light,
// sky, fog, snow and sea functions.
#include "blocks.glsl"
uniform sampler2D noise;         // height, d/du, d/dv: tileable noise over five octaves
#include <octaves>
#include <classes>

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
// the searchlights' light on a surface at `world` facing n (a xenon lamp's white), soft at
// the beam's edge and falling with the square of the distance
vec3 searchlit(vec3 world, vec3 n) {
    float e = 0.0;
    for (int k = 0; k < LIGHTS; k++) {  // LIGHTS: see glsl.scene_defines
        vec3 d = world - light_pos[k].xyz;
        float dist2 = max(dot(d, d), 1.0);
        vec3 l = d * inversesqrt(dist2);
        float cone = smoothstep(light_beam[k].x, 0.5 * (light_beam[k].x + 1.0), dot(l, light_axis[k].xyz));
        e += light_beam[k].y * cone * max(dot(n, -l), 0.0) / dist2;
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
