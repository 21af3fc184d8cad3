#version 450
// Coverage and background for single-sampled draws (common/coverage_body.glsl).
#include "coverage_body.glsl"
