#version 450
// Step 2: one level of the source mip chain, face M → M/2; each parent is the solid-angle
// weighted mean of its 2×2 children. CPU twin: environment::oracle::downsample.

#include "interface.glsl"

layout(local_size_x = PREFILTER_WORKGROUP, local_size_y = PREFILTER_WORKGROUP, local_size_z = 1) in;

#include "cubemap.glsl"

layout(push_constant) uniform PushConstants {
    DownsampleParams params;
};

// RGBA32F texels.
#include "texel_buffer.glsl"
layout(set = 0, binding = PREFILTER_SOURCE_BINDING) uniform textureBuffer src;
layout(std430, set = 0, binding = PREFILTER_DEST_BINDING) writeonly buffer Dest { vec4 dst[]; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint m = params.dst_face_size;
    if (id.x >= m || id.y >= m) {
        return;
    }
    int face = int(id.z);
    uint src_size = 2u * m;
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint dj = 0u; dj < 2u; ++dj) {
        for (uint di = 0u; di < 2u; ++di) {
            uint i = 2u * id.x + di;
            uint j = 2u * id.y + dj;
            float solid_angle;
            texel_direction(face, i, j, src_size, solid_angle);
            sum += texelFetch(src, int(cube_index(face, i, j, src_size))).rgb * solid_angle;
            weight += solid_angle;
        }
    }
    dst[cube_index(face, id.x, id.y, m)] = vec4(sum / weight, 1.0);
}
