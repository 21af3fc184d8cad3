#version 460
#extension GL_EXT_ray_query : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// The lacquer shading pass in the `brdf` environment model (SPEC §4) for
// single-sampled draws, with ray-query shadows (SPEC §6).
#define RAY_TRACING
#define BRDF_ENVIRONMENT_MODEL
#include "shade_body.glsl"
