#version 330
// A broken floe's vertex: its floe found from the tile's first row (a frozen tile's, from
// its status entries) and the vertex's cell, placed by the pose textures.
#include "blocks.glsl"
#include "tile.glsl"
uniform sampler2D pose_q;        // per floe row (and frozen floe): its attitude as a unit quaternion (x, y,
uniform sampler2D pose_t;        // z, w), and its place (x, y, heave, m); made on the CPU from the yaw, roll
                                 // and pitch, sparing each vertex six sines and cosines
#include "entries.glsl"

uniform usampler2D status;       // per floe row its status (and crack label), per cell of a frozen tile 1 + its floe
uniform bool reflected;          // drawn mirrored in the water plane: the floes' reflections
in vec3 in_pos;                  // about the cell's centroid, template frame, m
in vec3 in_normal;
in int in_cell;                  // the cell's index in its template
out vec3 world;                  // the point itself (also when its reflection is drawn), m
out vec3 normal;
out vec2 local;                  // relief coordinates that move with the floe, m
flat out int top;                // 1: a top face, 2: a bottom face (a floe's underside), 0: a side
flat out float centre_z;         // the floe's centre of mass above the water, m
void main() {
    int row = first + in_cell;   // a live tile's floe; a frozen tile's: -1 - its pose entry's number
    if (frozen) {
        uint floe = texelFetch(status, entry_texel(entry_of_cell(first, in_cell), textureSize(status, 0).y), 0).r;
        row = -1 - (first_floe + int(floe) - 1);
    }
    ivec2 at = entry_texel(row, textureSize(pose_q, 0).y);
    vec4 q = texelFetch(pose_q, at, 0);
    vec3 t = texelFetch(pose_t, at, 0).xyz;
    vec3 q2 = 2.0 * q.xyz, wq = q.w * q2, xq = q.x * q2, yq = q.y * q2;
    float zz = q.z * q2.z;
    mat3 r = mat3(1.0 - yq.y - zz, xq.y + wq.z, xq.z - wq.y,       // columns
                  xq.y - wq.z, 1.0 - xq.x - zz, yq.z + wq.x,
                  xq.z + wq.y, yq.z - wq.x, 1.0 - xq.x - yq.y);
    world = r * in_pos + t;
    normal = r * in_normal;
    centre_z = t.z;
    int snow_patch = (patch_base + in_cell) % (61 * 59);  // each floe its own patch of snow
    local = in_pos.xy + 31.7 * vec2(snow_patch % 61, snow_patch / 61);
    top = in_normal.z > 0.5 ? 1 : (in_normal.z < -0.5 ? 2 : 0);
    // ice deeper than SEEN_DEPTH is lost in the sea; only what is above the water is mirrored
    gl_ClipDistance[0] = reflected ? world.z : world.z + SEEN_DEPTH;
    gl_Position = view_proj * vec4(world.xy, reflected ? -world.z : world.z, 1.0);
}
