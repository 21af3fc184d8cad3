#version 450
// The lacquer draw's geometry pass (common/gbuffer_body.glsl).
#include "gbuffer_body.glsl"
