// The G-buffer gbuffer.frag wrote, as the shading pass reads it: the includer defines
// MULTISAMPLED (sampler2DMS, SAMPLE_COUNT a specialization constant) or not (sampler2D, one
// sample). FETCH(image, texel, s) reads sample s of a texel.
#ifndef GBUFFER_SAMPLES_GLSL
#define GBUFFER_SAMPLES_GLSL

#include "interface.glsl"

#ifdef MULTISAMPLED
layout(set = 0, binding = GBUFFER_POSITION_BINDING) uniform sampler2DMS gbuffer_position;
layout(set = 0, binding = GBUFFER_NORMAL_BINDING) uniform sampler2DMS gbuffer_normal;
layout(constant_id = SAMPLE_COUNT_ID) const int SAMPLE_COUNT = MAX_SAMPLES;
#define FETCH(image, texel, s) texelFetch(image, texel, s)
#else
layout(set = 0, binding = GBUFFER_POSITION_BINDING) uniform sampler2D gbuffer_position;
layout(set = 0, binding = GBUFFER_NORMAL_BINDING) uniform sampler2D gbuffer_normal;
const int SAMPLE_COUNT = 1;
#define FETCH(image, texel, s) texelFetch(image, texel, 0)
#endif

#endif
