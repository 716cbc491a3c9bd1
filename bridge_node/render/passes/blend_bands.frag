#version 330
// drawn with blending (zero, source colour): the framebuffer is multiplied by the factor
uniform sampler2D blend_ramp;    // per pixel column: the channel's edge-blend factor
out vec4 colour;
void main() { colour = vec4(vec3(texelFetch(blend_ramp, ivec2(gl_FragCoord.x, 0), 0).r), 1.0); }
