// The lacquer BRDF of SPEC §2 with the Fresnel table of SPEC §3: the one GLSL definition, included
// by shade_body.glsl (raster) and brdf_eval.comp (the compute evaluator tests compare with the CPU
// model in src/model/brdf.rs). Keep the two in step formula by formula.
//
// The includer's pipeline binds the Fresnel knots at FRESNEL_KNOTS_BINDING of set 0.

#ifndef LACQUER_BRDF_GLSL
#define LACQUER_BRDF_GLSL

#include "interface.glsl"
#include "math.glsl"

// Set per pipeline when every table of the draw has its knots at exactly i·step degrees with step
// a power of two, checked on the host: then θ/step is exact and its integer part is the interval,
// with no check or search (a search loop's body runs even where no lane needs it: quirk
// `loop_body_runs_when_no_lane_enters`).
layout(constant_id = FRESNEL_POW2_GRID_ID) const bool FRESNEL_POW2_GRID = false;

// Knots of the Fresnel table: (angle_deg, r, g, b), angles strictly increasing from 0 to 90.
#include "texel_buffer.glsl"
layout(set = 0, binding = FRESNEL_KNOTS_BINDING) uniform textureBuffer fresnel_knots;

struct LacquerParams {
    float beckmann_m;
    float diffuse_a;    // a, rounded to f32 ...
    float diffuse_b;    // b, rounded to f32 ...
    float diffuse_a_lo; // ... and what the rounding lost (a = diffuse_a + diffuse_a_lo)
    float diffuse_b_lo;
    float lacquer_g;   // g(r), evaluated on the host
    vec3 albedo;       // k_d
    int fresnel_first; // index of the table's first knot in fresnel_knots (tables are concatenated)
    int fresnel_count; // number of knots
    float fresnel_step; // the angle between the table's first two knots (fresnel_table's guess)
    int albedo_first;  // index of the first A(nv) knot in fresnel_knots (the `brdf` model)
};

// The BRDF's parameters of an object's material: the one unpacking of ObjectMaterial.
LacquerParams lacquer_params(ObjectMaterial m) {
    LacquerParams p;
    p.beckmann_m = m.beckmann_m;
    p.diffuse_a = m.diffuse_a;
    p.diffuse_b = m.diffuse_b;
    p.diffuse_a_lo = m.diffuse_a_lo;
    p.diffuse_b_lo = m.diffuse_b_lo;
    p.lacquer_g = m.lacquer_g;
    p.albedo = m.albedo;
    p.fresnel_first = int(m.fresnel_first);
    p.albedo_first = int(m.albedo_first);
    p.fresnel_count = int(m.fresnel_count);
    // Read once here, not by every lookup of the table (the `brdf` model makes ~100 a pixel).
    p.fresnel_step = texelFetch(fresnel_knots, p.fresnel_first + 1).x
        - texelFetch(fresnel_knots, p.fresnel_first).x;
    return p;
}

// --- Error-free transformations (Knuth TwoSum, Dekker/Veltkamp TwoProduct) -------------------
// Why: the smooth preset has f(nv) = a + b·nv with a < 0, which crosses zero at nv = -a/b ≈ 0.029.
// Near that crossing, fp32 rounding of nv (~1e-8) becomes a large relative error of the diffuse
// term. Carrying nv and a + b·nv as unevaluated float pairs (hi + lo, ~46 bits) removes it.
// `precise` forbids the compiler from re-associating or contracting these operations, which would
// silently cancel the error terms. No fma: Vulkan lets fma be unfused, Veltkamp's split is exact.

vec2 two_sum(float a, float b) {
    precise float s = a + b;
    precise float bb = s - a;
    precise float err = (a - (s - bb)) + (b - bb);
    return vec2(s, err);
}

vec2 veltkamp_split(float a) {
    precise float c = 4097.0 * a; // 2^12 + 1 splits a 24-bit significand into 12 + 12 bits
    precise float hi = c - (c - a);
    precise float lo = a - hi;
    return vec2(hi, lo);
}

vec2 two_prod(float a, float b) {
    precise float p = a * b;
    vec2 sa = veltkamp_split(a);
    vec2 sb = veltkamp_split(b);
    precise float err = ((sa.x * sb.x - p) + sa.x * sb.y + sa.y * sb.x) + sa.y * sb.y;
    return vec2(p, err);
}

// dot(a, b) as hi + lo, exact up to ~2^-46 relative to the largest product.
vec2 dot_compensated(vec3 a, vec3 b) {
    vec2 px = two_prod(a.x, b.x);
    vec2 py = two_prod(a.y, b.y);
    vec2 pz = two_prod(a.z, b.z);
    vec2 s1 = two_sum(px.x, py.x);
    vec2 s2 = two_sum(s1.x, pz.x);
    precise float lo = (px.y + py.y) + (pz.y + s1.y) + s2.y;
    return vec2(s2.x, lo);
}

// f(nv) = a + b·nv from the compensated nv, rounded once at the end.
float view_factor(LacquerParams p, vec2 nv) {
    vec2 bn = two_prod(p.diffuse_b, nv.x);
    vec2 s = two_sum(p.diffuse_a, bn.x);
    precise float tail = s.y + bn.y + p.diffuse_a_lo + p.diffuse_b * nv.y + p.diffuse_b_lo * nv.x;
    precise float f = s.x + tail;
    return f;
}

// F(θ): linear interpolation in the table of `count` knots from texelFetch(fresnel_knots, first),
// whose first two knots are `step` degrees apart; θ in degrees, clamped to [0, 90].
vec3 fresnel_table(float theta_deg, int first, int count, float step) {
    float theta = clamp(theta_deg, 0.0, 90.0);
    // The interval is [lo, lo + 1] with lo the last knot ≤ θ among 0..count-2. Evenly spaced
    // tables (every built-in one: a knot per degree) are indexed directly; the guess is checked
    // against that definition, and anything else (uneven knots, a rounding at a knot) falls back
    // to the binary search, so the result is the search's exactly. Why: the search is a divergent
    // loop of dependent buffer reads, run four times per fragment.
    int last = count - 2;
    int lo = min(whole_to_int(floor(theta / step)), last);
    bool found = FRESNEL_POW2_GRID
        || (texelFetch(fresnel_knots, first + lo).x <= theta
            && (lo == last || texelFetch(fresnel_knots, first + lo + 1).x > theta));
    int hi = lo + 1;
    if (!found) {
        // Binary search for the last knot with angle <= theta (log2(91) ≈ 7 steps).
        lo = 0;
        hi = count - 1;
        while (hi - lo > 1) {
            int mid = (lo + hi) / 2;
            if (texelFetch(fresnel_knots, first + mid).x <= theta) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    vec4 k0 = texelFetch(fresnel_knots, first + lo);
    vec4 k1 = texelFetch(fresnel_knots, first + hi);
    float span = k1.x - k0.x;
    float t = span > 0.0 ? clamp((theta - k0.x) / span, 0.0, 1.0) : 0.0;
    return mix(k0.yzw, k1.yzw, t);
}

// F(θ) of the material's table (θ in degrees).
vec3 lacquer_fresnel(LacquerParams p, float theta_deg) {
    return fresnel_table(theta_deg, p.fresnel_first, p.fresnel_count, p.fresnel_step);
}

// Angle in degrees of a cosine in [0, 1], for the Fresnel lookup (acos_unit: see math.glsl;
// the steep part of the Fresnel curve turns GLSL acos's error into a visible one).
float angle_deg_of_cos(float c) {
    return degrees(acos_unit(c));
}

// Normalised Beckmann D. exp((nh² - 1)/(m² nh²)) is written with tan²α = |N×H|²/nh²: when nh → 1,
// nh² - 1 cancels catastrophically in fp32, |N×H|² does not.
float beckmann_d(vec3 n, vec3 h, float nh, float m) {
    if (nh <= 0.0) {
        return 0.0;
    }
    vec3 c = cross(n, h);
    float nh2 = nh * nh;
    float m2 = m * m;
    // nh⁴ underflows to 0 for nh below ~1e-10, where exp is 0 too: 0/0 was NaN (an audit's
    // nv = nl = 6e-17, 2026-12-06). D there is below exp(-1e19), i.e. 0.
    float denominator = PI * m2 * nh2 * nh2;
    if (denominator <= 0.0) {
        return 0.0;
    }
    float tan2 = dot(c, c) / nh2;
    return exp(-tan2 / m2) / denominator;
}

// Cook-Torrance geometric attenuation.
float cook_torrance_g(float nh, float nv, float nl, float vh) {
    if (vh <= 0.0) {
        return 0.0;
    }
    return min(1.0, min(2.0 * nh * nv / vh, 2.0 * nh * nl / vh));
}

// k_d · max(a + b·nv, 0) · g(r) / π: the paper's view-dependent diffuse term. nv as hi + lo.
vec3 view_dependent_diffuse(LacquerParams p, vec2 nv) {
    return p.albedo * (max(view_factor(p, nv), 0.0) * p.lacquer_g / PI);
}

// f_r(N, V, L) [1/sr] given the light-independent parts: nv2 = dot_compensated(n, v) and
// f_diff = view_dependent_diffuse(p, nv2). lacquer_shade.glsl computes those once per point, not
// once per light; the result is the same operations on the same values as lacquer_brdf.
vec3 lacquer_brdf_view(LacquerParams p, vec3 n, vec3 v, vec3 l, vec2 nv2, vec3 f_diff) {
    float nv = nv2.x + nv2.y;
    float nl = dot(n, l);
    if (nv <= 0.0 || nl <= 0.0) {
        return vec3(0.0);
    }
    vec3 half_sum = v + l;
    float half_len = length(half_sum);
    if (half_len <= 0.0) {
        return f_diff;
    }
    vec3 h = half_sum / half_len;
    float nh = dot(n, h);
    float vh = dot(v, h);
    float d = beckmann_d(n, h, nh, p.beckmann_m);
    float g = cook_torrance_g(nh, nv, nl, vh);
    vec3 f = lacquer_fresnel(p, angle_deg_of_cos(vh));
    // 4·nv·nl underflows below nv·nl ~ 3e-39, where G (≤ 2·nh·min(nv, nl)/vh) makes d·g 0 too.
    float denominator = 4.0 * nv * nl;
    vec3 f_spec = denominator > 0.0 ? f * (d * g / denominator) : vec3(0.0);
    return f_diff + f_spec;
}

// f_r(N, V, L) [1/sr]; n, v, l unit vectors.
vec3 lacquer_brdf(LacquerParams p, vec3 n, vec3 v, vec3 l) {
    vec2 nv2 = dot_compensated(n, v);
    return lacquer_brdf_view(p, n, v, l, nv2, view_dependent_diffuse(p, nv2));
}

#endif
