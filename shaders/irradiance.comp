#version 450
// Step 4: the cosine-convolved irradiance E(n) = ∫ L(s)·max(n·s, 0) dω (SPEC §4), by brute force
// over the whole source cube, normalised by its own quadrature of ∫ max(n·s, 0) dω = π so a
// constant environment c gives exactly π·c. CPU twin: environment::oracle::irradiance.
//
// Texels with n·s ≤ 0 add exactly zero, so each row visits only the columns on the lit side of
// the plane n·p = 0 (plus a texel of margin; max(·, 0) still decides): on row tc of a face the
// centres p(sc) = axis + tc·t_dir + sc·s_dir have n·p linear in sc, a half-line. Each visit
// computes n·ŝ·dω = n·p·(2/M)²/|p|⁴ from p (as texel_direction does), cheaper than loading
// precomputed directions (quirk `ssbo_gather_is_per_lane`).

#include "interface.glsl"

layout(local_size_x = PREFILTER_WORKGROUP, local_size_y = PREFILTER_WORKGROUP, local_size_z = 1) in;

#include "cubemap.glsl"

layout(push_constant) uniform PushConstants {
    IrradianceParams params;
};

// RGBA32F texels.
#include "texel_buffer.glsl"
layout(set = 0, binding = PREFILTER_SOURCE_BINDING) uniform textureBuffer src;
layout(std430, set = 0, binding = PREFILTER_DEST_BINDING) writeonly buffer Dest { vec4 dst[]; };

void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint n = params.face_size;
    if (id.x >= n || id.y >= n) {
        return;
    }
    int face = int(id.z);
    float unused;
    vec3 normal = texel_direction(face, id.x, id.y, n, unused);
    float scale = 0.5 * float(n);
    float h = 2.0 / float(n);
    float h2 = h * h;
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    // Loop trip counts: 6, then n ≤ IRRADIANCE_FACE (params.rs bounds 6·n² below the quirk
    // `loop_iteration_limit`).
    for (int f = 0; f < 6; ++f) {
        vec3 axis, s_dir, t_dir;
        face_frame(f, axis, s_dir, t_dir);
        float slope = dot(normal, s_dir);
        for (uint j = 0u; j < n; ++j) {
            float offset = dot(normal, axis) + texel_coord(j, n) * dot(normal, t_dir);
            // n·p = offset + slope·sc > 0: sc beyond the root −offset/slope, on the side of its
            // sign; in texels, the root is at column (root + 1)·n/2 − ½.
            int lo = 0;
            int hi = int(n) - 1;
            // |slope| > 1e-4 keeps the root's rounding (~1e-7/slope) far below the margin.
            if (abs(slope) > 1e-4) {
                float column = clamp((1.0 - offset / slope) * scale - 0.5, -2.0, float(n) + 1.0);
                if (slope > 0.0) {
                    lo = max(int(floor(column)) - 1, 0);
                } else {
                    hi = min(int(ceil(column)) + 1, int(n) - 1);
                }
            } else if (offset + abs(slope) < -1e-5) {
                hi = -1;
            }
            uint row = cube_index(f, 0u, j, n);
            vec3 row_base = axis + texel_coord(j, n) * t_dir;
            for (int i = lo; i <= hi; ++i) {
                // texel_coord(i, n) without its division: n is a power of two, so h = 2/n and
                // (i + ½)·h are exact and this is the same float.
                vec3 p = row_base + ((float(i) + 0.5) * h - 1.0) * s_dir;
                float inv_len = inversesqrt(dot(p, p));
                float w = max(dot(normal, p), 0.0) * (h2 * inv_len * inv_len * inv_len * inv_len);
                sum += w * texelFetch(src, int(row) + i).rgb;
                weight += w;
            }
        }
    }
    dst[cube_index(face, id.x, id.y, n)] = vec4(PI * sum / weight, 1.0);
}
