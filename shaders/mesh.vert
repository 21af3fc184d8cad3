#version 450
// The meshes' vertices (GpuMesh's interleaved buffer) through the camera; the position and normal
// go on to the fragment shader, interpolated.
#include "frame.glsl"

layout(location = VERTEX_POSITION_LOCATION) in vec3 in_position;
layout(location = VERTEX_NORMAL_LOCATION) in vec3 in_normal;

layout(location = 0) out vec3 out_position;
layout(location = 1) out vec3 out_normal;

void main() {
    // Meshes are in world space (object transforms arrive with the scene work).
    out_position = in_position;
    out_normal = in_normal;
    gl_Position = frame.view_projection * vec4(in_position, 1.0);
}
