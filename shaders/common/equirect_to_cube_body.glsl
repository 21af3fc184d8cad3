// Step 1 of the prefilter: equirectangular radiance → cube face texels, each the mean of S × S
// sub-samples (the source pixel containing each), × intensity, the environment rotated about +Y.
// CPU twin: environment::oracle::equirect_to_cube.
//
// Included by equirect_to_cube.comp (fp32), equirect_to_cube_f64.comp (PRECISE_COORDINATES) and
// equirect_to_cube_near.comp (PRECISE_COORDINATES, NEAR_PASS):
// in fp32 the source position px ≈ u·W carries ~3e-5 px of rounding at W = 1024, so a sub-sample
// near a pixel boundary can read the neighbouring pixel, which at a hard HDR edge (neighbours 100×
// apart) is a visible error against the oracle. With shaderFloat64 the fp32 position decides only
// where it is farther than its error bound from every pixel boundary (~99 % of sub-samples); the
// rest are recomputed in double — direction, angles and px (GLSL has no double atan: the fp32
// angle is refined by one Newton step with double sin/cos polynomials). Those texels are listed
// and finished by a second dispatch, equirect_to_cube_near.comp (NEAR_PASS), whose lanes all have
// work; see NearTexels below.

#include "interface.glsl"

layout(local_size_x = PREFILTER_WORKGROUP, local_size_y = PREFILTER_WORKGROUP, local_size_z = 1) in;

#include "cubemap.glsl"

// S = equirect_supersample(W, N) (src/environment/params.rs), from the push constants.
#define SUPERSAMPLE params.supersample

layout(push_constant) uniform PushConstants {
    EquirectToCubeParams params;
};

// RGBA32F texels.
#include "texel_buffer.glsl"
layout(set = 0, binding = PREFILTER_SOURCE_BINDING) uniform textureBuffer equirect;
layout(std430, set = 0, binding = PREFILTER_DEST_BINDING) buffer Cube { vec4 cube[]; };

// Texels with sub-samples near a pixel edge, which equirect_to_cube_near.comp finishes in double
// precision: the header (count, then the near pass's indirect dispatch), then texel indices.
// Why a second pass: the double path inline would cost every lane group its full price, where
// only a few percent of texels need it (quirk `loop_body_runs_when_no_lane_enters`).
layout(std430, set = 0, binding = NEAR_TEXELS_BINDING) buffer NearTexels {
    NearHeader near_header;
    uint near_texels[];
};
const uint NEAR_GROUP_SIZE = PREFILTER_WORKGROUP * PREFILTER_WORKGROUP;

vec3 fetch(int x, int y) {
    int w = int(params.src_width);
    int h = int(params.src_height);
    // Longitude wraps: cells are in 0..=W (u ∈ [0, 1], ± rounding), so one conditional add or
    // subtract is the remainder — integer % is not vectorised on lavapipe (BENCHMARKS.md).
    x = x < 0 ? x + w : (x >= w ? x - w : x);
    y = clamp(y, 0, h - 1);       // latitude clamps at the poles
    return texelFetch(equirect, y * w + x).rgb;
}

#ifdef PRECISE_COORDINATES
const double PI_D = 3.14159265358979323846LF;

// sin and cos for |x| ≤ π: quadrant reduction, then Taylor series to x¹⁷ on |r| ≤ π/4
// (truncation < 2e-17).
dvec2 sincos_d(double x) {
    double q = floor(x / (0.5LF * PI_D) + 0.5LF);
    double r = x - q * (0.5LF * PI_D);
    double r2 = r * r;
    double s = 1.0LF / 355687428096000.0LF; // 1/17!
    s = s * r2 - 1.0LF / 1307674368000.0LF;
    s = s * r2 + 1.0LF / 6227020800.0LF;
    s = s * r2 - 1.0LF / 39916800.0LF;
    s = s * r2 + 1.0LF / 362880.0LF;
    s = s * r2 - 1.0LF / 5040.0LF;
    s = s * r2 + 1.0LF / 120.0LF;
    s = s * r2 - 1.0LF / 6.0LF;
    s = r + r * r2 * s;
    double c = 1.0LF / 20922789888000.0LF; // 1/16!
    c = c * r2 - 1.0LF / 87178291200.0LF;
    c = c * r2 + 1.0LF / 479001600.0LF;
    c = c * r2 - 1.0LF / 3628800.0LF;
    c = c * r2 + 1.0LF / 40320.0LF;
    c = c * r2 - 1.0LF / 720.0LF;
    c = c * r2 + 1.0LF / 24.0LF;
    c = c * r2 - 0.5LF;
    c = 1.0LF + r2 * c;
    int quadrant = int(q) & 3;
    if (quadrant == 0) return dvec2(s, c);
    if (quadrant == 1) return dvec2(c, -s);
    if (quadrant == 2) return dvec2(-s, -c);
    return dvec2(-c, s);
}

// atan2 in double: the fp32 angle a0 (~1e-7 rad) plus the Newton correction
// atan(r·sin(φ − a0) / r·cos(φ − a0)) ≈ its argument (the cube of 1e-7 is negligible).
double atan2_d(double y, double x) {
    double a0 = double(atan2_accurate(float(y), float(x)));
    dvec2 sc = sincos_d(a0);
    double num = y * sc.y - x * sc.x;
    double den = x * sc.y + y * sc.x;
    return den > 0.0LF ? a0 + num / den : a0;
}

// Source position (px, py) in pixels of sub-sample (a, b) of cube texel (face, i, j), through
// a double atan2: for the sub-samples source_cell flags as near a pixel boundary.
dvec2 source_position(int face, uint i, uint j, uint n, uint a, uint b) {
    double sc = 2.0LF * (double(i) + (double(a) + 0.5LF) / double(SUPERSAMPLE)) / double(n) - 1.0LF;
    double tc = 2.0LF * (double(j) + (double(b) + 0.5LF) / double(SUPERSAMPLE)) / double(n) - 1.0LF;
    dvec3 d;
    switch (face) {
    case 0: d = dvec3(1.0LF, -tc, -sc); break;
    case 1: d = dvec3(-1.0LF, -tc, sc); break;
    case 2: d = dvec3(sc, 1.0LF, tc); break;
    case 3: d = dvec3(sc, -1.0LF, -tc); break;
    case 4: d = dvec3(sc, -tc, 1.0LF); break;
    default: d = dvec3(-sc, -tc, -1.0LF); break;
    }
    d = d / sqrt(dot(d, d));
    double c = double(params.rotation_cos);
    double s = double(params.rotation_sin);
    dvec3 e = dvec3(d.x * c - d.z * s, d.y, d.x * s + d.z * c);
    double u = 0.5LF + atan2_d(e.x, -e.z) / (2.0LF * PI_D);
    double v = atan2_d(sqrt(e.x * e.x + e.z * e.z), e.y) / PI_D;
    return dvec2(u * double(params.src_width), v * double(params.src_height));
}

// Bound on |fp32 position − exact position| in pixels, ×10: the direction's x and z carry ~3e-7
// of rounding (coordinates, normalize, rotation), which atan2 turns into 3e-7/|xz| rad, plus its
// own 1e-7; u = ½ + angle/2π and px = u·W add half an ulp each. So u is off by ≤ 5e-8/|xz| +
// 1.4e-7 (in units of W) and v, an angle/π whose atan2 is well conditioned, by ≤ 2e-7 (in H).
// Measured: step_one_reads_exactly_the_oracles_source_pixels still passes with 1/20 of it.
// Within 1e-3 of the poles the fp32 longitude is meaningless: always the double path there.
vec2 fp32_margin(float xz_length) {
    float w = float(params.src_width);
    float h = float(params.src_height);
    return vec2(w * (5e-7 / max(xz_length, 1e-3) + 1.4e-6), h * 2e-6);
}
#endif

// The source cell of sub-sample (a, b) of texel (face, i, j) in fp32. `near`: it may be wrong
// (double path only; see fp32_margin).
ivec2 source_cell(int face, uint i, uint j, uint n, uint a, uint b, out bool near) {
    float sc = 2.0 * (float(i) + (float(a) + 0.5) / float(SUPERSAMPLE)) / float(n) - 1.0;
    float tc = 2.0 * (float(j) + (float(b) + 0.5) / float(SUPERSAMPLE)) / float(n) - 1.0;
    vec3 d = normalize(face_direction(face, sc, tc));
    vec3 e = world_to_environment(d, params.rotation_cos, params.rotation_sin);
    vec2 uv = direction_to_equirect(e);
    vec2 p = vec2(uv.x * float(params.src_width), uv.y * float(params.src_height));
    vec2 cell = floor(p);
#ifdef PRECISE_COORDINATES
    vec2 frac = p - cell;
    float xz_length = length(e.xz);
    near = xz_length < 1e-3 || any(lessThan(min(frac, 1.0 - frac), fp32_margin(xz_length)));
#else
    near = false;
#endif
    return ivec2(cell);
}

// One bit per sub-sample b·S + a, S ≤ MAX_STEP_ONE_SUPERSAMPLE.
const uint NEAR_WORDS = (MAX_STEP_ONE_SUPERSAMPLE * MAX_STEP_ONE_SUPERSAMPLE + 31u) / 32u;

// The texel's sub-samples in fp32 (b, then a), leaving out those near a pixel boundary, whose
// bits it sets in `near_bits` (all clear without PRECISE_COORDINATES); true if any was near.
bool far_sum(int face, uint i, uint j, uint n, out vec3 sum, out uint near_bits[NEAR_WORDS]) {
    sum = vec3(0.0);
    for (uint w = 0u; w < NEAR_WORDS; ++w) {
        near_bits[w] = 0u;
    }
    bool any_near = false;
    for (uint b = 0u; b < SUPERSAMPLE; ++b) {
        for (uint a = 0u; a < SUPERSAMPLE; ++a) {
            bool near;
            ivec2 cell = source_cell(face, i, j, n, a, b, near);
            uint k = b * SUPERSAMPLE + a;
            near_bits[k / 32u] |= near ? 1u << (k % 32u) : 0u;
            any_near = any_near || near;
            sum += near ? vec3(0.0) : fetch(cell.x, cell.y);
        }
    }
    return any_near;
}

#ifndef NEAR_PASS
void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint n = params.face_size;
    if (id.x >= n || id.y >= n) {
        return;
    }
    int face = int(id.z);
    vec3 sum;
    uint near_bits[NEAR_WORDS];
    bool any_near = far_sum(face, id.x, id.y, n, sum, near_bits);
    uint index = cube_index(face, id.x, id.y, n);
    if (!any_near) {
        cube[index] = vec4(sum * (params.intensity / float(SUPERSAMPLE * SUPERSAMPLE)), 1.0);
    } else {
        // Listed for the near pass, which sums the texel again on its own (so that it never
        // depends on this pass's fp32 agreeing with its own bit for bit).
        uint slot = atomicAdd(near_header.count, 1u);
        near_texels[slot] = index;
        if (slot % NEAR_GROUP_SIZE == 0u) {
            atomicAdd(near_header.dispatch_x, 1u);
        }
    }
}
#else
// The near pass: one invocation per listed texel, every lane with work. The sub-samples far from
// a pixel boundary in fp32 as step 1 sums them, then the near ones in double, in order.
void main() {
    uint slot = gl_WorkGroupID.x * NEAR_GROUP_SIZE + gl_LocalInvocationIndex;
    if (slot >= near_header.count) {
        return;
    }
    uint index = near_texels[slot];
    uint n = params.face_size;
    int face = int(index / (n * n));
    uint j = (index / n) % n;
    uint i = index % n;
    vec3 sum;
    uint near_bits[NEAR_WORDS];
    far_sum(face, i, j, n, sum, near_bits);
    for (uint w = 0u; w < NEAR_WORDS; ++w) {
        uint bits = near_bits[w];
        while (bits != 0u) {
            uint bit = uint(findLSB(bits));
            bits &= ~(1u << bit);
            uint k = w * 32u + bit;
            ivec2 cell = ivec2(floor(source_position(
                face, i, j, n, k % SUPERSAMPLE, k / SUPERSAMPLE)));
            sum += fetch(cell.x, cell.y);
        }
    }
    cube[index] = vec4(sum * (params.intensity / float(SUPERSAMPLE * SUPERSAMPLE)), 1.0);
}
#endif
