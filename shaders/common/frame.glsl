// Per-draw uniforms and resources shared by mesh.vert, lacquer.frag and the background pass
// (std140). The host side is `FrameUniforms` in src/shading.rs: change both together.
#ifndef FRAME_GLSL
#define FRAME_GLSL

const int MAX_LIGHTS = 16;
const int MAX_ENV_LAYERS = 16;

layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 view_projection;
    vec4 eye;              // xyz: camera position
    vec4 material;         // m, a, b, g(r)
    vec4 albedo_count;     // k_d.rgb, fresnel knot count
    vec4 material_lo;      // (a_lo, b_lo, 0, 0): what rounding a and b to f32 lost
    ivec4 light_count;     // x: number of lights
    vec4 light_vector[MAX_LIGHTS]; // w = 0: directional, xyz towards the light; w = 1: point, xyz position
    vec4 light_color[MAX_LIGHTS];  // rgb: irradiance E (directional) or intensity I (point)
    vec4 view_blur;        // β_normal, β_grazing, p (SPEC §4 β(nv)), 0
    ivec4 environment;     // x: 1 if an environment lights the scene, y: number of layers K
    vec4 layer_beta[MAX_ENV_LAYERS / 4]; // β_k, four per vec4
    vec4 camera_right;     // camera basis (world), for background rays
    vec4 camera_up;
    vec4 camera_back;      // −view direction
    vec4 camera_params;    // tan(fov/2), aspect W/H, width, height
} frame;

layout(set = 0, binding = 2) uniform samplerCube env_layers[MAX_ENV_LAYERS];
layout(set = 0, binding = 3) uniform samplerCube env_irradiance;

float layer_beta(int k) {
    return frame.layer_beta[k / 4][k % 4];
}

// Constant indices only: a per-fragment index into a sampler array would need nonuniformEXT.
vec3 sample_layer(int k, vec3 dir) {
    switch (k) {
    case 0: return textureLod(env_layers[0], dir, 0.0).rgb;
    case 1: return textureLod(env_layers[1], dir, 0.0).rgb;
    case 2: return textureLod(env_layers[2], dir, 0.0).rgb;
    case 3: return textureLod(env_layers[3], dir, 0.0).rgb;
    case 4: return textureLod(env_layers[4], dir, 0.0).rgb;
    case 5: return textureLod(env_layers[5], dir, 0.0).rgb;
    case 6: return textureLod(env_layers[6], dir, 0.0).rgb;
    case 7: return textureLod(env_layers[7], dir, 0.0).rgb;
    case 8: return textureLod(env_layers[8], dir, 0.0).rgb;
    case 9: return textureLod(env_layers[9], dir, 0.0).rgb;
    case 10: return textureLod(env_layers[10], dir, 0.0).rgb;
    case 11: return textureLod(env_layers[11], dir, 0.0).rgb;
    case 12: return textureLod(env_layers[12], dir, 0.0).rgb;
    case 13: return textureLod(env_layers[13], dir, 0.0).rgb;
    case 14: return textureLod(env_layers[14], dir, 0.0).rgb;
    default: return textureLod(env_layers[15], dir, 0.0).rgb;
    }
}

// Lpre(dir, β) of SPEC §4 from the layers: linear in β between layers 0 and 1, linear in log β
// above, the last layer beyond β_max. Twin of environment::params::layer_blend.
vec3 prefiltered_radiance(vec3 dir, float beta) {
    int count = frame.environment.y;
    if (count <= 1 || beta <= 0.0) {
        return sample_layer(0, dir);
    }
    float beta1 = layer_beta(1);
    if (beta < beta1) {
        return mix(sample_layer(0, dir), sample_layer(1, dir), beta / beta1);
    }
    for (int k = 1; k < count - 1; ++k) {
        float lo = layer_beta(k);
        float hi = layer_beta(k + 1);
        if (beta < hi) {
            float t = (log(beta) - log(lo)) / (log(hi) - log(lo));
            return mix(sample_layer(k, dir), sample_layer(k + 1, dir), t);
        }
    }
    return sample_layer(count - 1, dir);
}

#endif
