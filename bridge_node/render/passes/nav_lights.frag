#version 330
uniform float strength;          // 0 by day, 1 at night
in vec3 colour;
out vec4 frag;
void main() {
    vec2 c = 2.0 * gl_PointCoord - 1.0;
    frag = vec4(colour * strength * max(1.0 - dot(c, c), 0.0), 1.0);
}
