#version 450
// The lacquer shading pass in the `brdf` environment model (SPEC §4) for
// single-sampled draws (common/shade_body.glsl).
#define BRDF_ENVIRONMENT_MODEL
#include "shade_body.glsl"
