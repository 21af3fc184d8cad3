// The G-buffer gbuffer.frag wrote, as the shading pass reads it (bindings 5 and 6 of
// raster/draw.rs's SHADE_BINDINGS): the includer defines MULTISAMPLED (sampler2DMS, SAMPLE_COUNT
// from specialization constant 1) or not (sampler2D, one sample). FETCH(image, texel, s) reads
// sample s of a texel.
#ifndef GBUFFER_SAMPLES_GLSL
#define GBUFFER_SAMPLES_GLSL

const int MAX_SAMPLES = 4;
#ifdef MULTISAMPLED
layout(set = 0, binding = 5) uniform sampler2DMS gbuffer_position;
layout(set = 0, binding = 6) uniform sampler2DMS gbuffer_normal;
layout(constant_id = 1) const int SAMPLE_COUNT = MAX_SAMPLES;
#define FETCH(image, texel, s) texelFetch(image, texel, s)
#else
layout(set = 0, binding = 5) uniform sampler2D gbuffer_position;
layout(set = 0, binding = 6) uniform sampler2D gbuffer_normal;
const int SAMPLE_COUNT = 1;
#define FETCH(image, texel, s) texelFetch(image, texel, 0)
#endif

#endif
