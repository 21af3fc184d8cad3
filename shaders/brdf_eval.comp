#version 450
// Evaluates f_r for a list of direction triples, with the same GLSL as the fragment shader, so the
// BRDF can be compared with the CPU model number by number (`shikki brdf --backend gpu`, tests).

#include "interface.glsl"

layout(local_size_x = BRDF_EVAL_WORKGROUP) in;

#include "lacquer_brdf.glsl"

layout(std140, set = 0, binding = BRDF_EVAL_PARAMS_BINDING) uniform ParamsBlock {
    BrdfEvalParams params;
};

// Per row: N, V, L as vec4 (w unused).
layout(std430, set = 0, binding = BRDF_EVAL_DIRECTIONS_BINDING) readonly buffer Directions {
    vec4 directions[];
};
layout(std430, set = 0, binding = BRDF_EVAL_VALUES_BINDING) writeonly buffer Values {
    vec4 values[];
};

void main() {
    uint row = gl_GlobalInvocationID.x;
    if (row >= params.row_count.x) {
        return;
    }
    LacquerParams p = lacquer_params(params.material);
    vec3 n = directions[3u * row + 0u].xyz;
    vec3 v = directions[3u * row + 1u].xyz;
    vec3 l = directions[3u * row + 2u].xyz;
    values[row] = vec4(lacquer_brdf(p, n, v, l), 0.0);
}
