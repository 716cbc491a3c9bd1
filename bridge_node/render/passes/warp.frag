#version 330
uniform sampler2D flat_image;    // the channel's image, drawn flat
in vec2 uv;
out vec4 colour;
void main() {
    bool inside = all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
    colour = inside ? vec4(texture(flat_image, uv).rgb, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
