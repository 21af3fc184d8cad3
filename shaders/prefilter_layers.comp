#version 450
// Step 3: one blurred layer (SPEC §4). For every output texel direction d, the brute-force sum over
// the source cube (the mip of the same face size) of L(s)·w(d·s)·dω_s / Σ w·dω_s, with
// w = exp((c − 1)/β²) written as exp(−|d − s|²/(2β²)) (no cancellation near c = 1) and texels with
// |d − s|²/2 > cutoff·β² skipped. Only source texels that can pass that test are visited — the
// faces and rows of a conservative bounding box of the cone, and in each row the span of the cone
// (`row_span`) — so the result is the full sum. CPU twin: environment::oracle::blur_layer.
//
// Texel directions and solid angles are computed per visit from the row's base point: faster
// than reading them from a precomputed table, whose per-lane loads (gathers) cost more than the
// dozen vector instructions they replace (quirk `ssbo_gather_is_per_lane`).

#include "interface.glsl"

layout(local_size_x = PREFILTER_WORKGROUP, local_size_y = PREFILTER_WORKGROUP, local_size_z = 1) in;

#include "cubemap.glsl"

layout(push_constant) uniform PushConstants {
    BlurLayerParams params;
};

// RGBA32F texels.
#include "texel_buffer.glsl"
layout(set = 0, binding = PREFILTER_SOURCE_BINDING) uniform textureBuffer src;
layout(std430, set = 0, binding = PREFILTER_DEST_BINDING) writeonly buffer Dest { vec4 dst[]; };

const float FACE_CORNER_ANGLE = 0.9553166 + 1e-3;

// Range of cos(angle(e, x)) for e within angle θc of d, given cos(angle(d, x)).
vec2 cos_range(float cos_dx, float theta_c) {
    float a = acos_unit(abs(cos_dx));
    a = cos_dx < 0.0 ? PI - a : a;
    return vec2(cos(min(a + theta_c, PI)), cos(max(a - theta_c, 0.0)));
}

// Texel bounds [lo, hi] on `face` that contain every direction within θc of d; lo > hi if none.
// sc = e·S/e·A: with e·S ∈ [s0, s1] and e·A ∈ [a0, a1] (a0 > 0) the quotient's extremes are at
// the interval ends. Widened by a texel for rounding; the full face when the cone reaches the
// face plane's horizon (e·A ≤ 0 possible). Faces the cone cannot reach are skipped outright: that
// is not only faster but necessary under the quirk `loop_iteration_limit`.
void face_window(int face, vec3 d, float theta_c, uint n, out ivec2 lo, out ivec2 hi) {
    vec3 axis, s_dir, t_dir;
    face_frame(face, axis, s_dir, t_dir);
    // A direction on this face is at most acos(1/√3) = 54.74° from its axis (the corners).
    float axis_angle = dot(d, axis) >= 0.0 ? acos_unit(dot(d, axis)) : PI - acos_unit(-dot(d, axis));
    vec2 a = cos_range(dot(d, axis), theta_c);
    if (a.y <= 0.0 || axis_angle - theta_c > FACE_CORNER_ANGLE) {
        lo = ivec2(1);
        hi = ivec2(0);
        return;
    }
    if (a.x <= 1e-3) {
        lo = ivec2(0);
        hi = ivec2(int(n) - 1);
        return;
    }
    vec2 s = cos_range(dot(d, s_dir), theta_c);
    vec2 t = cos_range(dot(d, t_dir), theta_c);
    float s_min = s.x / (s.x >= 0.0 ? a.y : a.x);
    float s_max = s.y / (s.y >= 0.0 ? a.x : a.y);
    float t_min = t.x / (t.x >= 0.0 ? a.y : a.x);
    float t_max = t.y / (t.y >= 0.0 ? a.x : a.y);
    float scale = 0.5 * float(n);
    // Face coordinate c covers texel (c + 1)·M/2 − ½; one texel of margin each side.
    vec2 lo_f = (vec2(s_min, t_min) + 1.0) * scale - 1.5;
    vec2 hi_f = (vec2(s_max, t_max) + 1.0) * scale + 0.5;
    lo = clamp(ivec2(floor(lo_f)), ivec2(0), ivec2(int(n) - 1));
    hi = clamp(ivec2(ceil(hi_f)), ivec2(0), ivec2(int(n) - 1));
    if (s_max < -1.0 || s_min > 1.0 || t_max < -1.0 || t_min > 1.0) {
        lo = ivec2(1);
        hi = ivec2(0);
    }
}

// Columns [lo, hi] of row tc (face frame axis, s_dir, t_dir) whose texel centres can lie within
// the cone around d of sin²(half-angle) = sin2; lo > hi if none. The row is the line
// p(sc) = axis + tc·t_dir + sc·s_dir; p is inside the cone iff |p × d|² ≤ sin2·|p|² and d·p > 0.
// With U = (axis + tc·t_dir) × d and V = s_dir × d the first is the quadratic
// (V·V − sin2)·sc² + 2(U·V)·sc + U·U − sin2·(1 + tc²) ≤ 0 — written with cross products, so a
// small cone does not cancel. When V·V > sin2 (the cone holds neither ±s_dir) its solutions are
// one interval in a single nappe of the double cone, whose sign of d·p the midpoint tells; else
// the whole row. The caller's sin2 is widened and the span gets a texel of margin each side, so
// fp32 rounding never drops a texel the exact test keeps.
ivec2 row_span(vec3 d, vec3 axis, vec3 s_dir, vec3 t_dir, float tc, float sin2, uint n) {
    vec3 u = cross(axis + tc * t_dir, d);
    vec3 v = cross(s_dir, d);
    float qa = dot(v, v) - sin2;
    if (qa <= 1e-4) {
        return ivec2(0, int(n) - 1);
    }
    float qb = dot(u, v);
    float qc = dot(u, u) - sin2 * (1.0 + tc * tc);
    float disc = qb * qb - qa * qc;
    if (disc < 0.0) {
        return ivec2(1, 0);
    }
    float mid = -qb / qa;
    float half_width = sqrt(disc) / qa;
    if (dot(d, axis + tc * t_dir + mid * s_dir) <= 0.0) {
        return ivec2(1, 0);
    }
    // Centre sc of column i is 2(i + ½)/n − 1.
    float scale = 0.5 * float(n);
    float lo_f = (mid - half_width + 1.0) * scale - 0.5;
    float hi_f = (mid + half_width + 1.0) * scale - 0.5;
    // Clamp in float first: the roots can be far outside the face.
    lo_f = clamp(lo_f, -1.0, float(n));
    hi_f = clamp(hi_f, -1.0, float(n));
    return ivec2(max(int(ceil(lo_f)) - 1, 0), min(int(floor(hi_f)) + 1, int(n) - 1));
}

void main() {
    uvec3 id = gl_GlobalInvocationID;
    uint n = params.face_size;
    if (id.x >= n || id.y >= n) {
        return;
    }
    int face = int(id.z);
    float unused;
    vec3 d = texel_direction(face, id.x, id.y, n, unused);
    float beta2 = params.beta * params.beta;
    float q_max = params.cutoff * beta2;
    // Cone half-angle of the cutoff (1 − cos θc = q_max); a little wider so rounding never
    // excludes a texel the CPU oracle includes.
    float theta_c = q_max >= 2.0 ? PI : acos_unit(1.0 - q_max) * 1.02 + 2.0 / float(n);
    // sin²θc = q(2 − q) of the cut-off, 10 % wider (5 % in angle) plus an absolute floor, for
    // the per-row spans.
    float sin2 = q_max >= 1.0 ? 1.0 : 1.1 * q_max * (2.0 - q_max) + 1e-6;
    float inv_beta2 = 1.0 / beta2;
    float h = 2.0 / float(n);
    float h2 = h * h;   // the solid angle (2/M)²/|p|³ of texel_direction

    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int f = 0; f < 6; ++f) {
        ivec2 lo, hi;
        face_window(f, d, theta_c, n, lo, hi);
        vec3 axis, s_dir, t_dir;
        face_frame(f, axis, s_dir, t_dir);
        // Quirk `loop_iteration_limit`, bounded here in total as params.rs does for the
        // irradiance: the plan's face sizes (layer_face_size) keep the cone within ~10 texels of
        // d — a few hundred visits — or make the cube 16² (6·16² = 1536 texels) for wide lobes.
        for (int j = lo.y; j <= hi.y; ++j) {
            ivec2 span = q_max >= 1.0
                ? ivec2(lo.x, hi.x)
                : row_span(d, axis, s_dir, t_dir, texel_coord(uint(j), n), sin2, n);
            span = ivec2(max(span.x, lo.x), min(span.y, hi.x));
            uint row = cube_index(f, 0u, uint(j), n);
            vec3 row_base = axis + texel_coord(uint(j), n) * t_dir;
            for (int i = span.x; i <= span.y; ++i) {
                // texel_coord(i, n) without its division: n is a power of two, so h = 2/n and
                // (i + ½)·h are exact and this is the same float.
                vec3 p = row_base + ((float(i) + 0.5) * h - 1.0) * s_dir;
                float inv_len = inversesqrt(dot(p, p));
                vec3 diff = d - p * inv_len;
                float q = 0.5 * dot(diff, diff);
                if (q <= q_max) {
                    float w = exp(-q * inv_beta2) * (h2 * inv_len * inv_len * inv_len);
                    sum += w * texelFetch(src, int(row) + i).rgb;
                    weight += w;
                }
            }
        }
    }
    dst[cube_index(face, id.x, id.y, n)] = vec4(sum / weight, 1.0);
}
