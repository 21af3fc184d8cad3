#version 460
#extension GL_EXT_ray_tracing : require
// A ray of the ray-tracing pipeline path (ray_payload.glsl) that met nothing.
#include "ray_payload.glsl"

layout(location = 0) rayPayloadInEXT RayPayload payload;

void main() {
    payload.hit = 0;
}
