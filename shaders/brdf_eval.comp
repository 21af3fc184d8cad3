#version 450
// Evaluates f_r for a list of direction triples, with the same GLSL as the fragment shader, so the
// BRDF can be compared with the CPU model number by number (`shikki brdf --backend gpu`, tests).

layout(local_size_x = 64) in;

#define FRESNEL_SET 0
#define FRESNEL_BINDING 1
#include "lacquer_brdf.glsl"

layout(std140, set = 0, binding = 0) uniform Params {
    vec4 material;      // m, a, b, g(r)
    vec4 albedo_count;  // k_d.rgb, fresnel knot count (as float, exact below 2^24)
    vec4 material_lo;   // what rounding a and b to f32 lost: (a_lo, b_lo, 0, 0)
    uvec4 row_count;    // x: rows
} params;

// Per row: N, V, L as vec4 (w unused).
layout(std430, set = 0, binding = 2) readonly buffer Directions { vec4 directions[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Values { vec4 values[]; };

void main() {
    uint row = gl_GlobalInvocationID.x;
    if (row >= params.row_count.x) {
        return;
    }
    LacquerParams p;
    p.beckmann_m = params.material.x;
    p.diffuse_a = params.material.y;
    p.diffuse_b = params.material.z;
    p.diffuse_a_lo = params.material_lo.x;
    p.diffuse_b_lo = params.material_lo.y;
    p.lacquer_g = params.material.w;
    p.albedo = params.albedo_count.xyz;
    p.fresnel_first = 0;
    p.fresnel_count = int(params.albedo_count.w);
    vec3 n = directions[3u * row + 0u].xyz;
    vec3 v = directions[3u * row + 1u].xyz;
    vec3 l = directions[3u * row + 2u].xyz;
    values[row] = vec4(lacquer_brdf(p, n, v, l), 0.0);
}
