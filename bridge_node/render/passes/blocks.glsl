// The uniform blocks every program of the scene shares (passes.blocks writes them).
layout(std140) uniform Scene {   // per frame, shared by every channel and program
    vec3 sun;                    // unit, towards the sun
    float visibility;            // m: meteorological visibility
    vec3 direct;                 // the sun's light
    float relief_reach;          // m: how far the finest relief octave is fetched
    vec3 ambient;                // the sky's light
    float time;                  // s: the exercise's clock
    vec3 zenith_colour;
    vec3 horizon_colour;         // also the fog's colour
    vec3 water_colour;           // the sea's body colour
    vec4 light_pos[LIGHT_SLOTS];     // xyz: a searchlight's place, world m
    vec4 light_axis[LIGHT_SLOTS];    // xyz: its beam's axis, unit
    vec4 light_beam[LIGHT_SLOTS];    // x: cosine of half the beam; y: intensity over the illuminance the eye
                                     // sees as white, m2 (0: off)
};
layout(std140) uniform View {    // per channel
    mat4 view_proj;
    vec3 eye;                    // world, m
    bool classes;                // the class pass: flat class colours, no shading
};
