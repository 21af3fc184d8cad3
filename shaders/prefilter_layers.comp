#version 450
// Step 3: one blurred layer (SPEC §4). For every output texel direction d, the brute-force sum over
// the source cube (the mip of the same face size) of L(s)·w(d·s)·dω_s / Σ w·dω_s, with
// w = exp((c − 1)/β²) written as exp(−|d − s|²/(2β²)) (no cancellation near c = 1) and texels with
// |d − s|²/2 > cutoff·β² skipped. Only source texels inside a conservative per-face bounding box of
// that cone are visited; the result is the full sum. CPU twin: environment::oracle::blur_layer.

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "cubemap.glsl"

layout(push_constant) uniform Params {
    uint face_size;
    float beta;
    float cutoff;   // LOBE_CUTOFF: skip q > cutoff·β²
} params;

layout(std430, set = 0, binding = 0) readonly buffer Source { vec4 src[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Dest { vec4 dst[]; };

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
// is not only faster but necessary on lavapipe, whose loop limiter ends any loop after 65535
// iterations per invocation (see gpu/mod.rs, driver quirks).
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

    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int f = 0; f < 6; ++f) {
        ivec2 lo, hi;
        face_window(f, d, theta_c, n, lo, hi);
        for (int j = lo.y; j <= hi.y; ++j) {
            for (int i = lo.x; i <= hi.x; ++i) {
                float solid_angle;
                vec3 s = texel_direction(f, uint(i), uint(j), n, solid_angle);
                vec3 diff = d - s;
                float q = 0.5 * dot(diff, diff);
                if (q <= q_max) {
                    float w = exp(-q / beta2) * solid_angle;
                    sum += w * src[cube_index(f, uint(i), uint(j), n)].rgb;
                    weight += w;
                }
            }
        }
    }
    dst[cube_index(face, id.x, id.y, n)] = vec4(sum / weight, 1.0);
}
