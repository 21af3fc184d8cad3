// The ray-traced shading pass as a ray-tracing pipeline's ray generation shader (shade_rt*.rgen),
// for devices with VK_KHR_ray_tracing_pipeline but no VK_KHR_ray_query (NVIDIA's H100 and H200):
// fragment shaders cannot trace without ray queries. One launch per pixel of the strip's shaded
// rectangle, after the coverage draw wrote the background; shade_body.glsl's shade_pixel does
// what shade_rt*.frag does, its traces through traceRayEXT (visibility.glsl), and the covered
// pixels are stored where the fragment pass writes its colour attachments.
//
// The includer defines MULTISAMPLED and BRDF_ENVIRONMENT_MODEL or not.
#define RAY_TRACING
#define RAY_TRACING_PIPELINE
#include "shade_body.glsl"

layout(set = 0, binding = SHADED_IMAGE_BINDING, rgba32f) uniform writeonly image2D shaded_image;
layout(set = 0, binding = SHADED_INTEGRAL_BINDING, rgba32f) uniform writeonly image2D
    integral_image;

layout(push_constant) uniform PushConstants {
    TraceOrigin trace;
};

void main() {
    ivec2 texel = ivec2(gl_LaunchIDEXT.xy) + ivec2(trace.origin_x, trace.origin_y);
    vec4 radiance;
    vec4 integral;
    // Uncovered pixels keep what the coverage draw left: the background and NO_INTEGRAL.
    if (shade_pixel(texel, vec2(texel) + 0.5, radiance, integral)) {
        imageStore(shaded_image, texel, radiance);
        imageStore(integral_image, texel, integral);
    }
}
