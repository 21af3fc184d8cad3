// Per-draw uniforms and resources shared by mesh.vert, gbuffer.frag, the shading pass and the
// background pass. `Frame` and every number here come from the interface declaration
// (src/gpu/shaders/interface.rs); the host packs the frame in raster/draw/frame.rs.
#ifndef FRAME_GLSL
#define FRAME_GLSL

#include "interface.glsl"
#include "math.glsl"

// K, the bound environment's layer count, set per pipeline: env_layers may be indexed by
// constants only (lavapipe has no shaderSampledImageArrayDynamicIndexing), and a constant K
// removes the absent layers' lookups at pipeline creation.
layout(constant_id = ENV_LAYER_COUNT_ID) const int ENV_LAYER_COUNT = MAX_ENV_LAYERS;

layout(std140, set = 0, binding = FRAME_BINDING) uniform FrameBlock {
    Frame frame;
};

layout(set = 0, binding = ENV_LAYERS_BINDING) uniform samplerCube env_layers[MAX_ENV_LAYERS];
layout(set = 0, binding = ENV_IRRADIANCE_BINDING) uniform samplerCube env_irradiance;

// What pixels no mesh covers show, set per pipeline: BACKGROUND_COLOR, frame.background_color;
// BACKGROUND_ENVIRONMENT, the sharp environment along the pixel's ray. A constant, so the cube
// lookup is not run under a lane mask (quirk `loop_body_runs_when_no_lane_enters`) when the
// background is a colour.
layout(constant_id = BACKGROUND_KIND_ID) const int BACKGROUND_KIND = BACKGROUND_COLOR;

float layer_beta(int k) {
    return frame.layer_beta[k / 4][k % 4];
}

float layer_log_beta(int k) {
    return frame.layer_log_beta[k / 4][k % 4];
}

// The layers SPEC §4's Lpre(·, β) blends: mix(L_k0, L_k0+1, t), linear in β between layers 0 and
// 1, linear in log β above, the last layer beyond β_max. Twin of environment::params::layer_blend.
void layer_pair(float beta, out int k0, out float t) {
    int count = ENV_LAYER_COUNT;
    k0 = 0;
    t = 0.0;
    if (count > 1 && beta > 0.0) {
        float beta1 = layer_beta(1);
        if (beta < beta1) {
            t = beta / beta1;
        } else {
            // k0: the last layer k ≥ 1 with β_k ≤ β (β_k increase with k), and t = 0 on the last
            // layer. Written as a fixed run of selects over the constant K, not a search loop:
            // a divergent loop runs until every lane has left it, with its bookkeeping per lap.
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
}

// The `brdf` model's layer pair for a lookup at β (up to 2,048 a pixel, where `layer_pair`'s
// run over the layers was a quarter of the time): from layer 1 the layers' β are a geometric run
// (frame.layer_run; the `brdf` model's fine layers continue it below β_min), so the pair is where
// ln β falls on it. At a boundary rounding may give the neighbouring pair with t at 1 or 0
// instead, the same blend. Where the layers are not such a run (never, from PrefilterParams) the
// pair is `layer_pair`'s. The blend is in variance, (1 − t)·β_k² + t·β_(k+1)² = β², with layer
// 0's β_0² its texels' read variance (twin: brdf_quadrature.rs `layered_radiance`, whose doc says
// why). The `paper` model's one lookup a pixel keeps `layer_pair`, so its images stay what they
// were.
void layer_pair_of_run(float beta, out int k0, out float t) {
    vec4 run = frame.layer_run;
    float beta2 = beta * beta;
    float e0 = frame.layer_variance.x;
    if (run.z == 0.0) {
        layer_pair(beta, k0, t);
        float lo = k0 == 0 ? e0 : layer_beta(k0) * layer_beta(k0);
        float hi = layer_beta(min(k0 + 1, ENV_LAYER_COUNT - 1));
        t = t > 0.0 ? (beta2 - lo) / max(hi * hi - lo, 1e-30) : 0.0;
    } else {
        int count = ENV_LAYER_COUNT;
        float x = (log(beta) - run.x) * run.y;
        float whole = floor(x);
        // Below 0 (x < 0) k0 is 0 whatever k is: `below`.
        int k = 1 + whole_to_int(whole);
        bool past = k >= count - 1;
        k0 = past ? count - 1 : k;
        // On the run (β_(k+1)/β_k)² − 1 = frame.layer_variance.y and β/β_k = e^((x − whole)/run.y).
        t = past ? 0.0 : (exp(2.0 * (x - whole) / run.y) - 1.0) / frame.layer_variance.y;
        // Below the run: between the sharp layer 0 and layer 1.
        bool below = x < 0.0;
        float beta1 = layer_beta(1);
        float under_1 = clamp((beta2 - e0) / max(beta1 * beta1 - e0, 1e-30), 0.0, 1.0);
        k0 = below ? 0 : k0;
        t = below ? under_1 : t;
    }
    k0 = beta > 0.0 ? k0 : 0;
    t = beta > 0.0 ? clamp(t, 0.0, 1.0) : 0.0;
}

// Lpre(dir, β) of SPEC §4 from the layers (`layer_pair`), with the sampler's filtering.
//
// Why a weighted sum over all K layers instead of sampling the two that matter: the pair differs
// between fragments, and indexing a sampler array with anything but a constant needs
// shaderSampledImageArrayDynamicIndexing, which lavapipe does not have (so not even a dynamically
// uniform loop index is allowed). A `switch` over the layer index would run every case under a
// lane mask (quirk `loop_body_runs_when_no_lane_enters`); this does K lookups, each at a constant
// index. Exact: the weights are (1 − t, t) on layers (k0, k0 + 1) and 0 elsewhere, so the sum is
// mix(L_k0, L_k0+1, t) plus exact zeros.
vec3 prefiltered_radiance(vec3 dir, float beta) {
    int k0;
    float t;
    layer_pair(beta, k0, t);
    vec3 sum = vec3(0.0);
#if MAX_ENV_LAYERS != 20
#error "prefiltered_radiance adds layers 0..19: list one ADD_LAYER per layer below"
#endif
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
    ADD_LAYER(16) ADD_LAYER(17) ADD_LAYER(18) ADD_LAYER(19)
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
    if (BACKGROUND_KIND == BACKGROUND_ENVIRONMENT) {
        return vec4(sharp_radiance(camera_ray(pixel)), 1.0);
    }
    return frame.background_color;
}

#endif
