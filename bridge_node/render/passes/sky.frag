#version 330
// The sky above the horizon band (see environment.frag), a pass of its own: on llvmpipe a
// branch does not skip work, so within one pass every sky pixel would pay for the ground.
#include "common.glsl"

in vec3 ray;
out vec4 colour;
void main() { colour = classes ? CLASS_COLOUR[CLASS_SKY] : opaque(sky(normalize(ray))); }
