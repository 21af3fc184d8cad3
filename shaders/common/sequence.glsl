// The deterministic sample sequence of SPEC §6's integral: no state between frames, the same
// numbers on every run for a seed. Integer hashing and bit tricks only, so the CPU twin
// (`oracle::light_between::sequence`) computes the same bits.

#ifndef SEQUENCE_GLSL
#define SEQUENCE_GLSL

// Wellons' "lowbias32": a bijection of u32 with a strong avalanche.
uint hash_u32(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// [0, 1) from the top 24 bits: exact in f32.
float unit_from_bits(uint x) {
    return float(x >> 8) * (1.0 / 16777216.0);
}

// Van der Corput in base 2 (the bits of i mirrored).
float radical_inverse_2(uint i) {
    return unit_from_bits(bitfieldReverse(i));
}

// Van der Corput in base 3: the base-3 digits of i mirrored, as digits / 3^k (i < 3^20).
float radical_inverse_3(uint i) {
    uint mirrored = 0u;
    uint scale = 1u;
    for (int k = 0; k < 20 && i > 0u; ++k) {
        mirrored = mirrored * 3u + i % 3u;
        i /= 3u;
        scale *= 3u;
    }
    return float(mirrored) / float(scale);
}

// A pixel's key: the seed, then the pixel's column and row (whole-image), through the hash.
uint pixel_key(uvec2 pixel, uint seed) {
    return hash_u32(pixel.y ^ hash_u32(pixel.x ^ hash_u32(seed)));
}

// Three numbers in [0, 1) for ray `ray` of `rays` at bounce `depth` of the pixel with `key`: at
// the first bounce the 3-D Hammersley set (i + ½)/N, Φ2(i), Φ3(i), shifted per pixel modulo 1
// (Cranley–Patterson rotation), so the N rays of a pixel are stratified; at later bounces hashed
// numbers (each path is already placed by its first bounce).
vec3 sample_numbers(uint key, uint ray, uint rays, uint depth) {
    if (depth == 0u) {
        vec3 shift = vec3(unit_from_bits(hash_u32(key)),
            unit_from_bits(hash_u32(key ^ 0x9e3779b9u)),
            unit_from_bits(hash_u32(key ^ 0x7f4a7c15u)));
        vec3 point = vec3((float(ray) + 0.5) / float(rays), radical_inverse_2(ray),
            radical_inverse_3(ray));
        return fract(point + shift);
    }
    uint h = hash_u32(key ^ hash_u32(ray * 8u + depth));
    return vec3(unit_from_bits(hash_u32(h)), unit_from_bits(hash_u32(h + 1u)),
        unit_from_bits(hash_u32(h + 2u)));
}

// The number that picks the light of ray `ray`'s hit at bounce `depth` (next-event estimation,
// lacquer_shade.glsl's `one_light`): hashed, after sample_numbers' three.
float light_number(uint key, uint ray, uint depth) {
    uint h = hash_u32(key ^ hash_u32(ray * 8u + depth));
    return unit_from_bits(hash_u32(h + 3u));
}

#endif
