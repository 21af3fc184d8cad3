#version 450
// Step 4: the cosine-convolved irradiance E(n) = ∫ L(s)·max(n·s, 0) dω (SPEC §4), by brute force
// over the whole source cube, normalised by its own quadrature of ∫ max(n·s, 0) dω = π so a
// constant environment c gives exactly π·c. CPU twin: environment::oracle::irradiance.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "cubemap.glsl"

layout(push_constant) uniform Params {
    uint face_size;
} params;

layout(std430, set = 0, binding = 0) readonly buffer Source { vec4 src[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Dest { vec4 dst[]; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint n = params.face_size;
    if (id.x >= n || id.y >= n) {
        return;
    }
    int face = int(id.z);
    float unused;
    vec3 normal = texel_direction(face, id.x, id.y, n, unused);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int f = 0; f < 6; ++f) {
        for (uint j = 0u; j < n; ++j) {
            for (uint i = 0u; i < n; ++i) {
                float solid_angle;
                vec3 s = texel_direction(f, i, j, n, solid_angle);
                float w = max(dot(normal, s), 0.0) * solid_angle;
                sum += w * src[cube_index(f, i, j, n)].rgb;
                weight += w;
            }
        }
    }
    dst[cube_index(face, id.x, id.y, n)] = vec4(PI * sum / weight, 1.0);
}
