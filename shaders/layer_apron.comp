#version 450
// One layer of the `brdf` model's layer texels (environment/gpu.rs `concatenated_texels`) with a
// one-texel apron around each face: texel (i, j), i, j ∈ [−1, M], of face f holds the texel of the
// direction through (i, j)'s centre on the face that direction selects. Inside the face that is
// texel (i, j) itself; in the apron, the seam rule of the lookups' bilinear taps
// (brdf_environment.glsl `layer_bilinear`), which then never leave a face's rows. Each texel
// written holds two of them, (i, j) and (i + 1, j) (layer_pair.glsl; beyond the apron, 0). CPU
// twin: environment::brdf_quadrature::apron_texels.

#include "interface.glsl"

layout(local_size_x = PREFILTER_WORKGROUP, local_size_y = PREFILTER_WORKGROUP, local_size_z = 1) in;

#include "cubemap.glsl"

layout(push_constant) uniform PushConstants {
    LayerApronParams params;
};

#include "layer_pair.glsl"

// RGBA32F texels.
#include "texel_buffer.glsl"
layout(set = 0, binding = PREFILTER_SOURCE_BINDING) uniform textureBuffer src;
// A storage texel buffer, not a storage buffer: a large map's layers exceed
// maxStorageBufferRange (environment/gpu.rs APRON_BINDINGS).
layout(set = 0, binding = PREFILTER_DEST_BINDING, rgba32ui) uniform writeonly uimageBuffer dst;

// The texel of face `face`'s apron texel (i, j), i, j ∈ [−1, M]: the source texel of the
// direction through its centre on the face that direction selects.
vec3 apron_texel(int face, int i, int j, int m) {
    // Face coordinates of the centre, 2·(i + ½)/M − 1.
    vec2 c = 2.0 * (vec2(i, j) + 0.5) / float(m) - 1.0;
    int held;
    vec2 st;
    select_face(face_direction(face, c.x, c.y), held, st);
    ivec2 ij = clamp(ivec2(floor((st + 1.0) * 0.5 * float(m))), ivec2(0), ivec2(m - 1));
    return texelFetch(src, int(params.source_first) + (held * m + ij.y) * m + ij.x).rgb;
}

void main() {
    uvec3 id = gl_GlobalInvocationID;
    int m = int(params.face_size);
    int padded = m + 2;
    if (id.x >= uint(padded) || id.y >= uint(padded)) {
        return;
    }
    int face = int(id.z);
    ivec2 ij = ivec2(id.xy) - 1;
    vec3 first = apron_texel(face, ij.x, ij.y, m);
    vec3 second = ij.x < m ? apron_texel(face, ij.x + 1, ij.y, m) : vec3(0.0);
    int index = int(params.dest_first) + (face * padded + int(id.y)) * padded + int(id.x);
    imageStore(dst, index, layer_pack(first, second));
}
