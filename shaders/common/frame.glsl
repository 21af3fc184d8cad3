// Per-draw uniforms and resources shared by mesh.vert, gbuffer.frag, the shading pass and the
// background pass (std140). The host side is `FrameUniforms` in src/shading.rs: change both together.
#ifndef FRAME_GLSL
#define FRAME_GLSL

const int MAX_LIGHTS = 16;
const int MAX_ENV_LAYERS = 16;
// K, the bound environment's layer count, set per pipeline (raster/draw.rs): lavapipe has no
// shaderSampledImageArrayDynamicIndexing, so env_layers takes constant indices only, and a
// constant K removes the absent layers' lookups at pipeline creation.
layout(constant_id = 0) const int ENV_LAYER_COUNT = MAX_ENV_LAYERS;

layout(std140, set = 0, binding = 0) uniform Frame {
    mat4 view_projection;
    vec4 eye;              // xyz: camera position
    ivec4 light_count;     // x: number of lights
    vec4 light_vector[MAX_LIGHTS]; // w = 0: directional, xyz towards the light; w = 1: point, xyz position
    vec4 light_color[MAX_LIGHTS];  // rgb: irradiance E (directional) or intensity I (point)
    ivec4 environment;     // x: 1 if an environment lights the scene, y: number of layers K
    vec4 layer_beta[MAX_ENV_LAYERS / 4]; // β_k, four per vec4
    vec4 layer_log_beta[MAX_ENV_LAYERS / 4]; // ln β_k (k ≥ 1), computed on the host
    vec4 camera_right;     // camera basis (world), for background rays
    vec4 camera_up;
    vec4 camera_back;      // −view direction
    vec4 camera_params;    // tan(fov/2), aspect W/H, width, height
    vec4 strip_offset;     // y: image row of the target's row 0 (tall images render in strips)
    ivec4 draw_info;       // x: object index + 1 (G-buffer pass)
    vec4 background_color; // the constant background (rgba; transparent is 0)
} frame;

layout(set = 0, binding = 2) uniform samplerCube env_layers[MAX_ENV_LAYERS];
layout(set = 0, binding = 3) uniform samplerCube env_irradiance;

// What pixels no mesh covers show, set per pipeline (raster/draw.rs): 0, frame.background_color;
// 1, the sharp environment along the pixel's ray. A constant, so the cube lookup is not run (under
// a lane mask, as llvmpipe runs both sides of a branch) when the background is a colour.
layout(constant_id = 2) const int BACKGROUND_KIND = 0;

float layer_beta(int k) {
    return frame.layer_beta[k / 4][k % 4];
}

float layer_log_beta(int k) {
    return frame.layer_log_beta[k / 4][k % 4];
}

// Lpre(dir, β) of SPEC §4 from the layers: linear in β between layers 0 and 1, linear in log β
// above, the last layer beyond β_max. Twin of environment::params::layer_blend.
//
// Why a weighted sum over all K layers instead of sampling the two that matter: the pair differs
// between fragments, and indexing a sampler array with anything but a constant needs
// shaderSampledImageArrayDynamicIndexing, which lavapipe 22.3 does not have (so not even a
// dynamically uniform loop index is allowed). The old form (a 16-case `switch` per lookup, called
// up to twice per candidate layer) made llvmpipe, which runs every case of a divergent switch under
// a lane mask, do ~240 cube fetches per fragment; this does K, each at a constant index. Exact:
// the weights are (1 − t, t) on layers (k0, k0 + 1) and 0 elsewhere, so the sum is
// mix(L_k0, L_k0+1, t) plus exact zeros.
vec3 prefiltered_radiance(vec3 dir, float beta) {
    int count = ENV_LAYER_COUNT;
    int k0 = 0;
    float t = 0.0;
    if (count > 1 && beta > 0.0) {
        float beta1 = layer_beta(1);
        if (beta < beta1) {
            t = beta / beta1;
        } else {
            // k0: the last layer k ≥ 1 with β_k ≤ β (β_k increase with k), and t = 0 on the last
            // layer. Written as a fixed run of selects over the constant K, not a search loop:
            // llvmpipe runs a loop until every lane has left it, with its bookkeeping per lap.
            k0 = 1;
            float log_lo = layer_log_beta(1);
            float log_hi = layer_log_beta(min(2, count - 1));
            for (int k = 2; k < count; ++k) {
                if (beta >= layer_beta(k)) {
                    k0 = k;
                    log_lo = layer_log_beta(k);
                    log_hi = layer_log_beta(min(k + 1, count - 1));
                }
            }
            if (k0 < count - 1) {
                t = (log(beta) - log_lo) / (log_hi - log_lo);
            }
        }
    }
    vec3 sum = vec3(0.0);
#define ADD_LAYER(K)                                                            \
    if (K < ENV_LAYER_COUNT) {                                                  \
        float w = K == k0 ? 1.0 - t : (K == k0 + 1 ? t : 0.0);                 \
        if (w != 0.0) {                                                         \
            sum += textureLod(env_layers[K], dir, 0.0).rgb * w;                 \
        }                                                                       \
    }
    ADD_LAYER(0) ADD_LAYER(1) ADD_LAYER(2) ADD_LAYER(3)
    ADD_LAYER(4) ADD_LAYER(5) ADD_LAYER(6) ADD_LAYER(7)
    ADD_LAYER(8) ADD_LAYER(9) ADD_LAYER(10) ADD_LAYER(11)
    ADD_LAYER(12) ADD_LAYER(13) ADD_LAYER(14) ADD_LAYER(15)
#undef ADD_LAYER
    return sum;
}

// The sharp layer along `dir` (the background).
vec3 sharp_radiance(vec3 dir) {
    return textureLod(env_layers[0], dir, 0.0).rgb;
}

// The primary ray through `pixel` (whole-image coordinates of a pixel centre, (i + ½, j + ½),
// row 0 at the top): SPEC §1's camera rays.
vec3 camera_ray(vec2 pixel) {
    float tan_half = frame.camera_params.x;
    float aspect = frame.camera_params.y;
    vec2 size = frame.camera_params.zw;
    float x = (2.0 * pixel.x / size.x - 1.0) * tan_half * aspect;
    float y = (1.0 - 2.0 * pixel.y / size.y) * tan_half;
    return normalize(x * frame.camera_right.xyz + y * frame.camera_up.xyz - frame.camera_back.xyz);
}

// What pixels no mesh covers show (SPEC §1 camera ray for the environment): BACKGROUND_KIND.
vec4 background_radiance(vec2 pixel) {
    if (BACKGROUND_KIND == 1) {
        return vec4(sharp_radiance(camera_ray(pixel)), 1.0);
    }
    return frame.background_color;
}

#endif
