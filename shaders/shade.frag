#version 450
// The lacquer shading pass for single-sampled draws (common/shade_body.glsl).
#include "shade_body.glsl"
