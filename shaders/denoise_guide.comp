#version 450
// The denoise's first step (raster/draw/denoise.rs; twin: `Pixel::new` and the variance's 3×3
// mean in `denoise`): per pixel of a ray-traced draw, xyz the guide ln(max(base, 0) + 1e-6) of
// the image without the integral (base = image − integral), w the 3×3 mean of the integral's
// variance over covered pixels; w = −1 where no object covers the pixel.

#include "interface.glsl"

layout(local_size_x = DENOISE_WORKGROUP, local_size_y = DENOISE_WORKGROUP, local_size_z = 1) in;

layout(push_constant) uniform PushConstants {
    DenoiseParams params;
};

layout(std430, set = 0, binding = DENOISE_IMAGE_BINDING) readonly buffer Image { vec4 image[]; };
layout(std430, set = 0, binding = DENOISE_INTEGRAL_BINDING) readonly buffer Integral {
    vec4 integral[];
};
layout(std430, set = 0, binding = DENOISE_GUIDE_BINDING) writeonly buffer Guide { vec4 guide[]; };

void main() {
    uint width = params.size.x;
    uint height = params.size.y;
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= width || p.y >= height) {
        return;
    }
    uint i = p.y * width + p.x;
    vec4 own = integral[i];
    if (own.a < 0.0) {
        guide[i] = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    // The variance's 3×3 mean over covered pixels: one pixel's few rays estimate it poorly.
    float sum = 0.0;
    float count = 0.0;
    for (uint qy = max(p.y, 1u) - 1u; qy < min(p.y + 2u, height); ++qy) {
        for (uint qx = max(p.x, 1u) - 1u; qx < min(p.x + 2u, width); ++qx) {
            float variance = integral[qy * width + qx].a;
            if (variance >= 0.0) {
                sum += variance;
                count += 1.0;
            }
        }
    }
    vec3 base = image[i].rgb - own.rgb;
    guide[i] = vec4(log(max(base, vec3(0.0)) + 1e-6), sum / max(count, 1.0));
}
