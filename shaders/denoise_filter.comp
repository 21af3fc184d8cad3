#version 450
// The denoise's second step (raster/draw/denoise.rs; twin: `denoise`'s filter): each covered
// pixel's integral replaced by the joint-bilateral mean of its neighbours' (spatial Gaussian ×
// guide similarity × estimate similarity, in one exp), added back to the base and clamped at 0,
// in place in the image buffer (each invocation reads and writes only its own pixel there).
// Uncovered pixels keep the draw's value.

#include "interface.glsl"

layout(local_size_x = DENOISE_WORKGROUP, local_size_y = DENOISE_WORKGROUP, local_size_z = 1) in;

layout(push_constant) uniform PushConstants {
    DenoiseParams params;
};

layout(std430, set = 0, binding = DENOISE_IMAGE_BINDING) buffer Image { vec4 image[]; };
layout(std430, set = 0, binding = DENOISE_INTEGRAL_BINDING) readonly buffer Integral {
    vec4 integral[];
};
layout(std430, set = 0, binding = DENOISE_GUIDE_BINDING) readonly buffer Guide { vec4 guide[]; };

float grey(vec3 c) {
    return (c.r + c.g + c.b) / 3.0;
}

void main() {
    uint width = params.size.x;
    uint height = params.size.y;
    uint radius = params.size.z;
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= width || p.y >= height) {
        return;
    }
    uint i = p.y * width + p.x;
    vec4 own = guide[i];
    if (own.w < 0.0) {
        return;
    }
    vec3 own_integral = integral[i].rgb;
    float own_grey = grey(own_integral);
    vec3 sum = vec3(0.0);
    float weights = 0.0;
    for (uint qy = max(p.y, radius) - radius; qy < min(p.y + radius + 1u, height); ++qy) {
        uint dy = qy > p.y ? qy - p.y : p.y - qy;
        float from_y = float(dy * dy) * params.weights.x;
        for (uint qx = max(p.x, radius) - radius; qx < min(p.x + radius + 1u, width); ++qx) {
            uint q = qy * width + qx;
            vec4 other = guide[q];
            if (other.w < 0.0) {
                continue;
            }
            vec3 other_integral = integral[q].rgb;
            vec3 d = own.xyz - other.xyz;
            float difference = d.x * d.x + d.y * d.y + d.z * d.z;
            float spread = params.weights.z * (own.w + other.w);
            float estimate = (own_grey - grey(other_integral)) * (own_grey - grey(other_integral));
            // No noise on either side (every ray agreed): only an equal estimate joins.
            float from_estimate = 0.0;
            if (spread > 0.0) {
                from_estimate = estimate / spread;
            } else if (estimate != 0.0) {
                continue;
            }
            uint dx = qx > p.x ? qx - p.x : p.x - qx;
            float exponent = from_y + float(dx * dx) * params.weights.x
                + difference * params.weights.y + from_estimate;
            if (exponent > params.weights.w) {
                continue;
            }
            float w = exp(-exponent);
            sum += w * other_integral;
            weights += w;
        }
    }
    // The pixel itself weighs 1 (covered, no difference to itself): weights ≥ 1.
    vec4 drawn = image[i];
    image[i] = vec4(max(drawn.rgb - own_integral + sum / weights, vec3(0.0)), drawn.a);
}
