#version 450
// The lacquer shading pass for multisampled draws (common/shade_body.glsl).
#define MULTISAMPLED
#include "shade_body.glsl"
