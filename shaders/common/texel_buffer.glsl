// Gathered reads go through uniform texel buffers (quirk `ssbo_gather_is_per_lane`),
// declared as `textureBuffer` and read with texelFetch: the samplerless form, because Mesa 25's
// SPIR-V parser reports a sampled image of Dim Buffer (`samplerBuffer`) as invalid. Same
// descriptor type (VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER), same fetch.
#ifndef SHIKKI_TEXEL_BUFFER_GLSL
#define SHIKKI_TEXEL_BUFFER_GLSL
#extension GL_EXT_samplerless_texture_functions : require
#endif
