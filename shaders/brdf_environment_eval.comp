#version 450
// Evaluates the `brdf` environment model's specular integral (brdf_environment.glsl, the code
// the shading pass runs) for a list of (N, V) pairs, so that the quadrature can be compared with
// its CPU twin number by number (src/compute/brdf_environment_eval.rs, tests).

#include "interface.glsl"

layout(local_size_x = BRDF_EVAL_WORKGROUP) in;

#include "frame.glsl"
#include "lacquer_brdf.glsl"
#include "brdf_environment.glsl"

layout(std140, set = 0, binding = ENV_EVAL_PARAMS_BINDING) uniform ParamsBlock {
    BrdfEvalParams params;
};

// Per row: N, V as vec4 (w unused).
layout(std430, set = 0, binding = ENV_EVAL_DIRECTIONS_BINDING) readonly buffer Directions {
    vec4 directions[];
};
layout(std430, set = 0, binding = ENV_EVAL_VALUES_BINDING) writeonly buffer Values {
    vec4 values[];
};

void main() {
    uint row = gl_GlobalInvocationID.x;
    if (row >= params.row_count.x) {
        return;
    }
    LacquerParams p = lacquer_params(params.material);
    vec3 n = directions[2u * row + 0u].xyz;
    vec3 v = directions[2u * row + 1u].xyz;
    float nv = dot(n, v);
    vec3 specular = nv > 0.0 ? brdf_environment_specular(p, n, v, nv, ENV_SAMPLES) : vec3(0.0);
    values[row] = vec4(specular, 0.0);
}
