#version 330
in vec2 in_ndc;
in vec3 in_ray;                  // world direction through this corner (linear in the screen)
out vec3 ray;
void main() { ray = in_ray; gl_Position = vec4(in_ndc, 0.9999, 1.0); }
