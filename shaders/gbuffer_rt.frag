#version 450
// The geometry pass of ray-traced draws (common/gbuffer_body.glsl), keeping each sample's
// triangle too.
#define RAY_TRACING
#include "gbuffer_body.glsl"
