// SPEC §6's vis(x, L): whether anything lies between a shaded point and a light, by a ray query
// against the draw's top-level acceleration structure (SCENE_TLAS_BINDING), or by traceRayEXT in
// the ray-tracing pipeline's shading (shade_rt*.rgen, RAY_TRACING_PIPELINE). Only the ray-traced
// shading pipelines (shade_rt*.frag, which enable GL_EXT_ray_query, and shade_rt*.rgen) define
// RAY_TRACING; the others see every light.
//
// The CPU twin is `oracle::shadows` (same offset, same ray): keep the two alike.

#ifndef VISIBILITY_GLSL
#define VISIBILITY_GLSL

#include "ray_surface.glsl"

#ifdef RAY_TRACING
layout(set = 0, binding = SCENE_TLAS_BINDING) uniform accelerationStructureEXT scene_tlas;

// Shadow rays to the lights (else every light is seen; the pass may still trace for §6's
// integral).
layout(constant_id = SHADOWS_ID) const bool SHADOWS = true;
// SPEC §6's integral (bounces ≥ 1), else shadow rays alone: light_between.glsl's code is folded
// away.
layout(constant_id = INTEGRAL_ID) const bool INTEGRAL = true;

// Far enough for a directional light ("to infinity") and finite for every implementation.
const float RAY_FAR = 1e30;

// The ray origin for leaving the surface at `p` on the side `n` points to: Wächter & Binder's
// bound (Ray Tracing Gems, ch. 6). The G-buffer position is a rasteriser-interpolated point whose
// error is a few ulps of its coordinates, so the origin moves 256 ulps (relative to each
// coordinate) along n; near the world origin, where ulps vanish but the interpolation error of
// the triangle's vertices does not, by 2^-16 absolute instead (below 1/32).
vec3 offset_ray_origin(vec3 p, vec3 n) {
    ivec3 ulps = ivec3(256.0 * n);
    vec3 moved = vec3(
        intBitsToFloat(floatBitsToInt(p.x) + (p.x < 0.0 ? -ulps.x : ulps.x)),
        intBitsToFloat(floatBitsToInt(p.y) + (p.y < 0.0 ? -ulps.y : ulps.y)),
        intBitsToFloat(floatBitsToInt(p.z) + (p.z < 0.0 ? -ulps.z : ulps.z)));
    vec3 near_origin = p + n * (1.0 / 65536.0);
    return vec3(
        abs(p.x) < 1.0 / 32.0 ? near_origin.x : moved.x,
        abs(p.y) < 1.0 / 32.0 ? near_origin.y : moved.y,
        abs(p.z) < 1.0 / 32.0 ? near_origin.z : moved.z);
}

// The instance mask of a ray leaving `surface`: every object, or all but the surface's own where
// its mesh is convex on the side the surface is shaded from (raster/self_hits.rs: every vertex on
// or behind every face's plane, seen from that side). Such a mesh stands for a smooth convex
// surface, which a ray leaving it never meets again, whatever its direction: a ray below the flat
// face's plane but above the shading normal's horizon would otherwise enter the mesh and meet its
// far side, and a lone sphere's silhouette and terminator would differ from the image without
// ray tracing, which SPEC §6 says they equal. The CPU twin makes the same choice
// (`oracle::shadows::RaySurface::own`).
uint trace_mask(RaySurface surface) {
    if (surface.object < 0) {
        return TRACE_MASK_ALL;
    }
    ObjectGeometry own = object_geometry[surface.object];
    uint side = dot(surface.geometric_normal, surface.face_normal) > 0.0
        ? SELF_HITS_FRONT_CLEAR : SELF_HITS_BACK_CLEAR;
    return (own.clear_sides & side) != 0u ? TRACE_MASK_ALL & ~own.own_mask : TRACE_MASK_ALL;
}

// The nearest surface along origin + t·direction, t ≥ 0.
struct RayHit {
    bool hit;
    int object;
    int triangle;
    // Of vertices 1 and 2 (vertex 0 has 1 − u − v).
    vec2 barycentrics;
};

#ifdef RAY_TRACING_PIPELINE
// The ray-tracing pipeline path: the same two traces through traceRayEXT, answered by
// trace_hit.rchit and trace_miss.rmiss (ray_payload.glsl).
#include "ray_payload.glsl"
layout(location = 0) rayPayloadEXT RayPayload payload;

RayHit trace_nearest(vec3 origin, vec3 direction, uint mask) {
    payload.hit = 0;
    traceRayEXT(scene_tlas, gl_RayFlagsOpaqueEXT, mask, RAY_HIT_GROUP_OFFSET, 0, RAY_MISS_INDEX,
        origin, 0.0, direction, RAY_FAR, 0);
    RayHit hit;
    hit.hit = payload.hit != 0;
    hit.object = hit.hit ? payload.object : 0;
    hit.triangle = hit.hit ? payload.triangle : 0;
    hit.barycentrics = hit.hit ? payload.barycentrics : vec2(0.0);
    return hit;
}

// A shadow ray skips the closest-hit shader: only the miss shader clears `hit`.
bool unoccluded(vec3 origin, vec3 direction, float t_max, uint mask) {
    payload.hit = 1;
    traceRayEXT(scene_tlas,
        gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsOpaqueEXT | gl_RayFlagsSkipClosestHitShaderEXT,
        mask, RAY_HIT_GROUP_OFFSET, 0, RAY_MISS_INDEX, origin, 0.0, direction, t_max, 0);
    return payload.hit == 0;
}
#else
RayHit trace_nearest(vec3 origin, vec3 direction, uint mask) {
    rayQueryEXT query;
    rayQueryInitializeEXT(query, scene_tlas, gl_RayFlagsOpaqueEXT, mask, origin, 0.0, direction,
        RAY_FAR);
    while (rayQueryProceedEXT(query)) {
    }
    RayHit hit;
    hit.hit = rayQueryGetIntersectionTypeEXT(query, true)
        == gl_RayQueryCommittedIntersectionTriangleEXT;
    // Without a hit the committed values are undefined, and llvmpipe runs a branch's loads for
    // lanes that do not take it (quirk `loop_body_runs_when_no_lane_enters`): triangle 0 of
    // object 0 keeps every address the hit's shading reads valid.
    hit.object = hit.hit ? rayQueryGetIntersectionInstanceCustomIndexEXT(query, true) : 0;
    hit.triangle = hit.hit ? rayQueryGetIntersectionPrimitiveIndexEXT(query, true) : 0;
    hit.barycentrics = hit.hit ? rayQueryGetIntersectionBarycentricsEXT(query, true) : vec2(0.0);
    return hit;
}

// Nothing is hit along origin + t·direction for t in [0, t_max].
bool unoccluded(vec3 origin, vec3 direction, float t_max, uint mask) {
    rayQueryEXT query;
    rayQueryInitializeEXT(query, scene_tlas,
        gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsOpaqueEXT, mask,
        origin, 0.0, direction, t_max);
    // Every geometry is opaque: the query has no candidates to confirm.
    while (rayQueryProceedEXT(query)) {
    }
    return rayQueryGetIntersectionTypeEXT(query, true) == gl_RayQueryCommittedIntersectionNoneEXT;
}
#endif
#endif

// 1 when light `light_vector` (Frame::light_vector: w = 0 directional, 1 point) is seen from
// `surface` (ray_surface.glsl), else 0. The ray leaves on the side of the geometric normal the
// light is on.
float light_visibility(RaySurface surface, vec4 light_vector) {
#ifdef RAY_TRACING
    if (!SHADOWS) {
        return 1.0;
    }
    vec3 towards = light_vector.w == 0.0 ? light_vector.xyz : light_vector.xyz - surface.point;
    vec3 side = dot(towards, surface.geometric_normal) < 0.0 ? -surface.geometric_normal
                                                              : surface.geometric_normal;
    vec3 origin = offset_ray_origin(surface.point, side);
    // One query for either kind of light: llvmpipe runs both sides of a branch, and a query on
    // each side would cost two traversal loops (quirk `loop_body_runs_when_no_lane_enters`).
    vec3 to_light = light_vector.xyz - origin;
    float distance = length(to_light);
    bool directional = light_vector.w == 0.0;
    vec3 direction = directional ? normalize(light_vector.xyz) : to_light / distance;
    return unoccluded(origin, direction, directional ? RAY_FAR : distance,
               trace_mask(surface))
        ? 1.0
        : 0.0;
#else
    return 1.0;
#endif
}

#endif
