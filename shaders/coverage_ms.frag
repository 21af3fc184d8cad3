#version 450
// Coverage and background for multisampled draws (common/coverage_body.glsl).
#define MULTISAMPLED
#include "coverage_body.glsl"
