#version 330

#include "common.glsl"

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
