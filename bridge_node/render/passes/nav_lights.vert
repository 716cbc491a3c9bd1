#version 330
// Navigation lights: points of a few pixels, shown only where the eye is inside a light's
// sector, added to the image as strongly as the daylight leaves them visible, fogged.
#include "blocks.glsl"
uniform mat4 ship_to_world;
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
