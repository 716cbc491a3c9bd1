#version 330
in vec2 in_ndc;                  // a grid node on the projector's output
in vec2 in_uv;                   // the point of the flat image it shows (0..1; outside: black)
out vec2 uv;
void main() { uv = in_uv; gl_Position = vec4(in_ndc, 0.0, 1.0); }
