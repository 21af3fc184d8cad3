// Sampling the Beckmann distribution of visible normals (Heitz & d'Eon, "Importance Sampling
// Microfacet-Based BSDFs using the Distribution of Visible Normals", 2014; the slope inversion
// as Jakob, "An Improved Visible Normal Sampling Routine for the Beckmann Distribution", 2014,
// describes it): half vectors h drawn with density D(h)·G1(V)·max(0, V·H)/(N·V), G1 Smith's
// masking for Beckmann. The reflected direction's density is then D·G1/(4·N·V), so the specular
// weight f_spec·(N·s)/pdf = F·G/G1 stays bounded at grazing views, where sampling D·(N·H) gave
// weights without bound.
//
// The CPU twin is `oracle::visible_normals`: keep the two alike, formula by formula.

#ifndef VISIBLE_NORMALS_GLSL
#define VISIBLE_NORMALS_GLSL

#include "math.glsl"

const float INV_SQRT_PI = 0.56418958354775628695;

// erfc(x) for x ≥ 0 (Abramowitz & Stegun 7.1.26, |error| ≤ 1.5e-7), written as erfc so that
// erf(x) − 1 keeps its relative precision for large x.
float erfc_positive(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    float p = 1.061405429;
    p = p * t - 1.453152027;
    p = p * t + 1.421413741;
    p = p * t - 0.284496736;
    p = p * t + 0.254829592;
    return p * t * exp(-x * x);
}

float erf_odd(float x) {
    float e = 1.0 - erfc_positive(abs(x));
    return x < 0.0 ? -e : e;
}

// erf⁻¹(x) on (−1, 1) (Giles, "Approximating the erfinv function", GPU Computing Gems, 2011:
// single precision, relative error ≤ 4e-7 away from ±1).
float erfinv_odd(float x) {
    float w = -log(max((1.0 - x) * (1.0 + x), 1e-30));
    float p;
    if (w < 5.0) {
        w -= 2.5;
        p = 2.81022636e-08;
        p = 3.43273939e-07 + p * w;
        p = -3.5233877e-06 + p * w;
        p = -4.39150654e-06 + p * w;
        p = 0.00021858087 + p * w;
        p = -0.00125372503 + p * w;
        p = -0.00417768164 + p * w;
        p = 0.246640727 + p * w;
        p = 1.50140941 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -0.000200214257;
        p = 0.000100950558 + p * w;
        p = 0.00134934322 + p * w;
        p = -0.00367342844 + p * w;
        p = 0.00573950773 + p * w;
        p = -0.0076224613 + p * w;
        p = 0.00943887047 + p * w;
        p = 1.00167406 + p * w;
        p = 2.83297682 + p * w;
    }
    return p * x;
}

// Smith's G1 for Beckmann roughness m at a view with N·V = nv > 0: 1/(1 + Λ(a)),
// a = 1/(m·tan θ_V), Λ(a) = (e^{−a²}/(a√π) − erfc(a))/2.
float beckmann_g1(float nv, float m) {
    float sin_v = sqrt(max(1.0 - nv * nv, 0.0));
    if (sin_v <= 0.0) {
        return 1.0;
    }
    float a = nv / (m * sin_v);
    float lambda = 0.5 * (exp(-a * a) * INV_SQRT_PI / a - erfc_positive(a));
    return 1.0 / (1.0 + max(lambda, 0.0));
}

// The density of the reflected direction s when h is drawn by `sample_visible_normal`:
// D(h)·G1(V)/(4·N·V), 0 where V·H ≤ 0. `d` = D(h).
float visible_normal_pdf(float d, float g1, float nv, float vh) {
    return vh > 0.0 ? d * g1 / (4.0 * nv) : 0.0;
}

// Slopes (x̃, ỹ) of the visible-slope distribution of the unit-roughness Beckmann surface seen
// from θ in the xz-plane: ỹ ~ N(0, ½) directly; x̃ has density ∝ (1 − x̃·tan θ)·e^{−x̃²}, below
// cot θ, whose CDF is inverted by VISIBLE_SLOPE_STEPS safeguarded Newton steps in the erf
// domain b = erf(x̃), from a fitted first guess. A fixed count (no tolerance test): the GPU and
// its twin take the same steps.
vec2 visible_slopes(float theta, vec2 u) {
    float ux = clamp(u.x, 1e-6, 1.0 - 1e-6);
    float uy = clamp(u.y, 1e-6, 1.0 - 1e-6);
    float y = erfinv_odd(2.0 * uy - 1.0);
    if (theta < 1e-4) {
        // Face on: the slope distribution itself, e^{−x̃²} in x̃ too.
        return vec2(erfinv_odd(2.0 * ux - 1.0), y);
    }
    float tan_t = tan(theta);
    float cot_t = 1.0 / tan_t;
    float lo = -1.0;
    float hi = erf_odd(cot_t);
    float fit = 1.0 + theta * (-0.876 + theta * (0.4265 - 0.0594 * theta));
    float b = hi - (1.0 + hi) * pow(1.0 - ux, fit);
    float norm = 1.0 / (1.0 + hi + INV_SQRT_PI * tan_t * exp(-cot_t * cot_t));
    for (int i = 0; i < VISIBLE_SLOPE_STEPS; ++i) {
        // Written to be true for a NaN too: a step that left the bracket bisects.
        if (!(b >= lo && b <= hi)) {
            b = 0.5 * (lo + hi);
        }
        float x = erfinv_odd(b);
        float value = norm * (1.0 + b + INV_SQRT_PI * tan_t * exp(-x * x)) - ux;
        float derivative = norm * (1.0 - x * tan_t);
        if (value > 0.0) {
            hi = b;
        } else {
            lo = b;
        }
        b -= value / derivative;
    }
    if (!(b >= lo && b <= hi)) {
        b = 0.5 * (lo + hi);
    }
    return vec2(erfinv_odd(b), y);
}

// A half vector of the Beckmann lobe (roughness m) drawn from the visible normals seen from
// `v_local` (the view in the frame (t, b, n), z along n, z > 0), in that frame: stretch the view
// by m, draw unit-roughness slopes about it, rotate them to the view's azimuth, unstretch.
vec3 sample_visible_normal(vec3 v_local, float m, vec2 u) {
    vec3 stretched = normalize(vec3(m * v_local.x, m * v_local.y, v_local.z));
    float r = length(stretched.xy);
    float theta = atan2_accurate(r, stretched.z);
    float cos_phi = r > 0.0 ? stretched.x / r : 1.0;
    float sin_phi = r > 0.0 ? stretched.y / r : 0.0;
    vec2 slope = visible_slopes(theta, u);
    slope = vec2(cos_phi * slope.x - sin_phi * slope.y, sin_phi * slope.x + cos_phi * slope.y);
    slope *= m;
    return normalize(vec3(-slope.x, -slope.y, 1.0));
}

#endif
