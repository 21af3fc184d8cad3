// What a ray of the ray-tracing pipeline path (RAY_TRACING_PIPELINE: devices with
// VK_KHR_ray_tracing_pipeline but no VK_KHR_ray_query, e.g. NVIDIA's H100/H200) carries back from
// trace_hit.rchit or trace_miss.rmiss to visibility.glsl's trace_nearest and unoccluded: the
// same fields a ray query's committed intersection gives.
#ifndef RAY_PAYLOAD_GLSL
#define RAY_PAYLOAD_GLSL

struct RayPayload {
    // 1: a triangle was hit (or, for a shadow ray, not yet known to be missed); 0: nothing.
    int hit;
    int object;
    int triangle;
    // Of vertices 1 and 2 (vertex 0 has 1 − u − v).
    vec2 barycentrics;
};

// The shader binding table's record indices (raster/draw/ray_pipeline.rs).
const uint RAY_MISS_INDEX = 0u;
const uint RAY_HIT_GROUP_OFFSET = 0u;

#endif
