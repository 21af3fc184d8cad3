// The lacquer BRDF of SPEC §2 with the Fresnel table of SPEC §3: the one GLSL definition, included
// by lacquer.frag (raster) and brdf_eval.comp (the compute evaluator tests compare with the CPU
// model in src/model/brdf.rs). Keep the two in step formula by formula.
//
// The includer defines FRESNEL_SET and FRESNEL_BINDING before including this file.

#ifndef LACQUER_BRDF_GLSL
#define LACQUER_BRDF_GLSL

#ifndef FRESNEL_BINDING
#error "define FRESNEL_SET and FRESNEL_BINDING before including lacquer_brdf.glsl"
#endif

const float PI = 3.14159265358979323846;

// Knots of the Fresnel table: (angle_deg, r, g, b), angles strictly increasing from 0 to 90.
layout(std430, set = FRESNEL_SET, binding = FRESNEL_BINDING) readonly buffer FresnelTable {
    vec4 fresnel_knots[];
};

struct LacquerParams {
    float beckmann_m;
    float diffuse_a;
    float diffuse_b;
    float lacquer_g;   // g(r), evaluated on the host
    vec3 albedo;       // k_d
    int fresnel_count; // number of knots
};

// F(θ): linear interpolation in the table; θ in degrees, clamped to [0, 90].
vec3 fresnel_table(float theta_deg, int count) {
    float theta = clamp(theta_deg, 0.0, 90.0);
    // Binary search for the last knot with angle <= theta (tables are short; log2(91) ≈ 7 steps).
    int lo = 0;
    int hi = count - 1;
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (fresnel_knots[mid].x <= theta) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    vec4 k0 = fresnel_knots[lo];
    vec4 k1 = fresnel_knots[hi];
    float span = k1.x - k0.x;
    float t = span > 0.0 ? clamp((theta - k0.x) / span, 0.0, 1.0) : 0.0;
    return mix(k0.yzw, k1.yzw, t);
}

// Angle in degrees of a cosine, for the Fresnel lookup.
float angle_deg_of_cos(float c) {
    return degrees(acos(clamp(c, 0.0, 1.0)));
}

// Normalised Beckmann D. exp((nh² - 1)/(m² nh²)) is written with tan²α = |N×H|²/nh²: when nh → 1,
// nh² - 1 cancels catastrophically in fp32, |N×H|² does not.
float beckmann_d(vec3 n, vec3 h, float nh, float m) {
    if (nh <= 0.0) {
        return 0.0;
    }
    vec3 c = cross(n, h);
    float nh2 = nh * nh;
    float tan2 = dot(c, c) / nh2;
    float m2 = m * m;
    return exp(-tan2 / m2) / (PI * m2 * nh2 * nh2);
}

// Cook-Torrance geometric attenuation.
float cook_torrance_g(float nh, float nv, float nl, float vh) {
    if (vh <= 0.0) {
        return 0.0;
    }
    return min(1.0, min(2.0 * nh * nv / vh, 2.0 * nh * nl / vh));
}

// k_d · max(a + b·nv, 0) · g(r) / π: the paper's view-dependent diffuse term.
vec3 view_dependent_diffuse(LacquerParams p, float nv) {
    return p.albedo * (max(p.diffuse_a + p.diffuse_b * nv, 0.0) * p.lacquer_g / PI);
}

// f_r(N, V, L) [1/sr]; n, v, l unit vectors.
vec3 lacquer_brdf(LacquerParams p, vec3 n, vec3 v, vec3 l) {
    float nv = dot(n, v);
    float nl = dot(n, l);
    if (nv <= 0.0 || nl <= 0.0) {
        return vec3(0.0);
    }
    vec3 half_sum = v + l;
    float half_len = length(half_sum);
    vec3 f_diff = view_dependent_diffuse(p, nv);
    if (half_len <= 0.0) {
        return f_diff;
    }
    vec3 h = half_sum / half_len;
    float nh = dot(n, h);
    float vh = dot(v, h);
    float d = beckmann_d(n, h, nh, p.beckmann_m);
    float g = cook_torrance_g(nh, nv, nl, vh);
    vec3 f = fresnel_table(angle_deg_of_cos(vh), p.fresnel_count);
    vec3 f_spec = f * (d * g / (4.0 * nv * nl));
    return f_diff + f_spec;
}

#endif
