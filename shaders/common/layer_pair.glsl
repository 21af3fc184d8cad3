// The `brdf` model's layer texels, two horizontally adjacent texels of a face in one RGBA32UI
// texel, each channel in LAYER_CODE_BITS bits: its f32 less the sign and the lowest mantissa
// bits, rounded to nearest even (0 outside the normal numbers and +∞). A bilinear lookup then
// reads two texels instead of four. The CPU twin, whose doc has the layout, is
// src/environment/layer_pair.rs: change both together.
//
// The includer includes interface.glsl first.

#ifndef LAYER_PAIR_GLSL
#define LAYER_PAIR_GLSL

const uint LAYER_DROPPED = 31u - uint(LAYER_CODE_BITS);
const uint LAYER_CODE_MASK = (1u << uint(LAYER_CODE_BITS)) - 1u;
const uint LAYER_LOW_BITS = 32u - uint(LAYER_CODE_BITS);
const uint LAYER_HIGH_BITS = uint(LAYER_CODE_BITS) - LAYER_LOW_BITS;
// The smallest positive normal f32's bits, and the largest finite f32's code.
const uint LAYER_SMALLEST_NORMAL = 0x00800000u;
const uint LAYER_MAX_CODE = 0x7F7FFFFFu >> LAYER_DROPPED;

// The code of each channel of x (twin: `encode`): 0 for a negative value, −0, NaN or a value
// below the smallest normal f32 (whose subtraction wraps).
uvec3 layer_encode(vec3 x) {
    uvec3 bits = floatBitsToUint(x);
    uvec3 round = (1u << (LAYER_DROPPED - 1u)) - 1u + ((bits >> LAYER_DROPPED) & 1u);
    uvec3 code = min((bits + round) >> LAYER_DROPPED, uvec3(LAYER_MAX_CODE));
    bvec3 outside = greaterThan(bits - LAYER_SMALLEST_NORMAL,
        uvec3(0x7F800000u - LAYER_SMALLEST_NORMAL));
    return mix(code, uvec3(0u), outside);
}

// Texels a and b in one texel (twin: `pack`).
uvec4 layer_pack(vec3 a, vec3 b) {
    uvec3 ca = layer_encode(a);
    uvec3 cb = layer_encode(b);
    uvec3 high = (cb >> LAYER_LOW_BITS) << (uvec3(0u, 1u, 2u) * LAYER_HIGH_BITS);
    return uvec4(ca | (cb << uint(LAYER_CODE_BITS)), high.x | high.y | high.z);
}

// The first texel of a pair (twin: `unpack`).
vec3 layer_first(uvec4 w) {
    return uintBitsToFloat((w.xyz & LAYER_CODE_MASK) << LAYER_DROPPED);
}

// The second texel of a pair.
vec3 layer_second(uvec4 w) {
    uvec3 high = (uvec3(w.w) >> (uvec3(0u, 1u, 2u) * LAYER_HIGH_BITS))
        & ((1u << LAYER_HIGH_BITS) - 1u);
    return uintBitsToFloat(((w.xyz >> uint(LAYER_CODE_BITS)) | (high << LAYER_LOW_BITS))
        << LAYER_DROPPED);
}

#endif
