#version 450
// The lacquer draw's geometry pass: each covered sample keeps what lacquer shading needs, the
// position and normal interpolated at the pixel centre (what a forward fragment shader would
// receive) and the object, for shade.frag to shade once per distinct surface (SPEC §2, §4).

#include "frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec4 out_position; // xyz: world position; w: object index + 1 (0: empty)
layout(location = 1) out vec4 out_normal;   // xyz: interpolated normal, not yet normalised

void main() {
    out_position = vec4(in_position, float(frame.draw_info.x));
    out_normal = vec4(in_normal, 0.0);
}
