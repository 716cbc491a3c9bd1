#version 330
#include "blocks.glsl"
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
