// The lacquer draw's geometry pass (gbuffer.frag, gbuffer_rt.frag): each covered sample keeps
// what lacquer shading needs, the position and normal interpolated at the pixel centre (what a
// forward fragment shader would receive) and the object, for shade.frag to shade once per
// distinct surface (SPEC §2, §4). With RAY_TRACING it also keeps the triangle, for the rays that
// leave the surface.

#include "frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec4 out_position; // xyz: world position; w: object index + 1 (0: empty)
// xyz: interpolated normal, not yet normalised; w: the triangle's index in its mesh with
// RAY_TRACING (exact as a float below 2^24, which the draw checks), else 0.
layout(location = 1) out vec4 out_normal;

void main() {
    out_position = vec4(in_position, float(frame.draw_info.x));
#ifdef RAY_TRACING
    out_normal = vec4(in_normal, float(gl_PrimitiveID));
#else
    out_normal = vec4(in_normal, 0.0);
#endif
}
