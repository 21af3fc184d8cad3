#version 460
#extension GL_EXT_ray_tracing : require
// The closest hit of a ray of the ray-tracing pipeline path (ray_payload.glsl): what a ray query's
// committed triangle intersection gives.
#include "ray_payload.glsl"

layout(location = 0) rayPayloadInEXT RayPayload payload;
hitAttributeEXT vec2 barycentrics;

void main() {
    payload.hit = 1;
    payload.object = gl_InstanceCustomIndexEXT;
    payload.triangle = gl_PrimitiveID;
    payload.barycentrics = barycentrics;
}
