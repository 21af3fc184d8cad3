// SPEC §6's integral in the ray-traced shading pass: ∫ f_r·[L_hit − L(s)]·hit·(N·s) dω, what
// the objects change about the light a point receives (the light they send minus the
// environment they hide), estimated with frame.light_transport.x rays per shaded point and
// frame.light_transport.y bounces. Each ray samples the BRDF's two lobes (cosine-weighted
// diffuse, Beckmann visible normals for the specular lobe) and weighs by the mixture's pdf
// (one-sample multiple importance sampling, balance heuristic). A ray that meets nothing adds
// nothing, so the term adds no noise where no object is in sight.
//
// The includer includes frame.glsl, lacquer_brdf.glsl, lacquer_shade.glsl and declares
// `object_material`. The CPU twin is `oracle::light_between`: keep the two alike.

#ifndef LIGHT_BETWEEN_GLSL
#define LIGHT_BETWEEN_GLSL

#include "sequence.glsl"
#include "visible_normals.glsl"

// An orthonormal basis (t, b, n) (Duff et al., "Building an Orthonormal Basis, Revisited").
void tangent_frame(vec3 n, out vec3 t, out vec3 b) {
    float sign_z = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sign_z + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + sign_z * n.x * n.x * a, sign_z * c, -sign_z * n.x);
    b = vec3(c, sign_z + n.y * n.y * a, -n.y);
}

// The probability of sampling the specular lobe: its share of the reflected light under a
// uniform sky (Fresnel at nv against the diffuse albedo), kept in [0.1, 0.9] so neither lobe is
// starved.
float specular_lobe_probability(LacquerParams p, float nv, vec3 f_diff) {
    vec3 f = lacquer_fresnel(p, angle_deg_of_cos(nv));
    float specular = f.r + f.g + f.b;
    float diffuse = (f_diff.r + f_diff.g + f_diff.b) * PI;
    return clamp(specular / max(specular + diffuse, 1e-30), 0.1, 0.9);
}

// One sample of the lobes at (n, v) from the numbers u: the direction s and the weight
// f_r·(N·s)/pdf(s), pdf the mixture of both lobes' densities. False when the sample is lost
// (below the surface, or a density of 0); it still counts in the mean.
bool sample_lobes(LacquerParams p, vec3 n, vec3 v, vec2 nv2, vec3 f_diff, vec3 u, out vec3 s,
    out vec3 weight, out float pdf) {
    float nv = nv2.x + nv2.y;
    weight = vec3(0.0);
    s = n;
    pdf = 0.0;
    if (nv <= 0.0) {
        return false;
    }
    float p_specular = specular_lobe_probability(p, nv, f_diff);
    vec3 t, b;
    tangent_frame(n, t, b);
    float m = p.beckmann_m;
    if (u.x < p_specular) {
        vec3 h = sample_visible_normal(vec3(dot(v, t), dot(v, b), nv), m, u.yz);
        h = t * h.x + b * h.y + n * h.z;
        s = 2.0 * dot(v, h) * h - v;
    } else {
        float phi = 2.0 * PI * u.z;
        s = (t * cos(phi) + b * sin(phi)) * sqrt(u.y) + n * sqrt(max(1.0 - u.y, 0.0));
    }
    float ns = dot(n, s);
    if (ns <= 0.0) {
        return false;
    }
    vec3 h = normalize(v + s);
    float nh = dot(n, h);
    float vh = dot(v, h);
    float pdf_specular = nh > 0.0
        ? visible_normal_pdf(beckmann_d(n, h, nh, m), beckmann_g1(nv, m), nv, vh)
        : 0.0;
    pdf = p_specular * pdf_specular + (1.0 - p_specular) * ns / PI;
    if (!(pdf > 0.0)) {
        return false;
    }
    weight = lacquer_brdf_view(p, n, v, s, nv2, f_diff) * (ns / pdf);
    return true;
}

// L(s), the environment a hit hides along s (after intensity and rotation), read as filtered
// importance sampling reads it (Křivánek & Colbert): from the layer whose blur β covers the
// sample's share of the lobe, 2πβ² = 1/(n·pdf) for n rays. The sharp map behind a sample would
// carry the studio's edges into the estimate as noise; the footprint shrinks as rays grow, so
// the estimate still converges to the integral.
vec3 hidden_environment(vec3 s, float pdf, int n) {
    if (frame.environment.x == 0) {
        return vec3(0.0);
    }
    return prefiltered_radiance(s, sqrt(1.0 / (2.0 * PI * float(n) * pdf)));
}

// The integral at a shaded point: material p, unit normal n, view v, rays leaving from
// `surface`; `key` the pixel's (sequence.glsl); `environment` E, the integral of f_r·L over
// every direction at the point (`integral_environment`). Each ray is a path of up to `bounces`
// reflections: at each surface y it meets it adds throughput·w·(L_o(y) − L(s)), L_o(y) the
// lights with visibility plus the environment model at y, which is SPEC §6's recursion with one
// sample per level.
// Returns the mean over the rays (rgb) and the variance of that mean's grey value
// (r + g + b)/3 estimated from the rays' spread (w; with one ray, its square).
//
// The hidden environment. Each first-bounce ray that meets an object subtracts c_i = w_i·L(s_i),
// an estimate of H = ∫ f_r·L(s)·hit(s)·(N·s) dω. E is ∫ f_r·L·(N·s) dω over every direction
// (the `brdf` model's term, SPEC §4), so H = E − ∫ f_r·L·(1 − hit)·(N·s) dω too, estimated by
// the same rays as E − mean of c_i·(1 − hit_i). Where most rays meet an object (inside a bowl)
// that one has far less noise: a light box the object hides is subtracted as E has it instead
// of being found by a few rays. Ray i takes it in the share h_i of the other rays that met an
// object (leaving ray i out keeps h_i independent of it), i.e. adds h_i·(c_i − E) to its path.
// With no ray meeting an object nothing changes (SPEC §6: no noise there); with all of them,
// H = E.
// The limit differs from SPEC's integral by h·(E − ∫ f_r·L), the quadrature's own error where
// the environment is hidden (in `brdf` that error then leaves the image there).
vec4 light_between(LacquerParams p0, vec3 n0, vec3 v0, RaySurface surface0, uint key,
    vec3 environment) {
    int rays = frame.light_transport.x;
    int bounces = frame.light_transport.y;
    vec3 total = vec3(0.0);
    // Σ of each ray's grey value and of its square.
    vec2 moments = vec2(0.0);
    // The first bounce's rays: how many met an object, Σ d_i and Σ hit_i·d_i with
    // d_i = c_i − E; and the grey sums the variance of the blend needs. A ray that met nothing
    // has no path, so its value is h·D (D the grey of d_i): Σ D and Σ D² over those rays. One
    // that met an object has P + h·D = Q − (1 − h)·D with Q = P + D (P the grey of its path):
    // Σ Q, Σ Q², Σ Q·D, Σ D, Σ D² over those. Q, not P: where most rays meet an object P ≈ −D
    // is large (a hidden light box) and P² + 2h·P·D + h²·D² would cancel in f32.
    float hits = 0.0;
    vec3 sum_d = vec3(0.0);
    vec3 sum_hit_d = vec3(0.0);
    vec2 missed = vec2(0.0);
    vec4 met = vec4(0.0);
    float met_d2 = 0.0;
    for (int i = 0; i < rays; ++i) {
        vec3 path = vec3(0.0);
        LacquerParams p = p0;
        vec3 n = n0;
        vec3 v = v0;
        RaySurface surface = surface0;
        vec3 throughput = vec3(1.0);
        vec3 c = vec3(0.0);
        float hit_first = 0.0;
        for (int depth = 0; depth < bounces; ++depth) {
            vec2 nv2 = dot_compensated(n, v);
            vec3 f_diff = view_dependent_diffuse(p, nv2);
            vec3 u = sample_numbers(key, uint(i), uint(rays), uint(depth));
            vec3 s;
            vec3 weight;
            float pdf;
            if (!sample_lobes(p, n, v, nv2, f_diff, u, s, weight, pdf)) {
                break;
            }
            // The first bounce's rays share the lobe; a later bounce is one ray.
            vec3 hidden = hidden_environment(s, pdf, depth == 0 ? rays : 1);
            if (depth == 0) {
                c = weight * hidden;
            }
            vec3 side = dot(s, surface.geometric_normal) < 0.0 ? -surface.geometric_normal
                                                                 : surface.geometric_normal;
            vec3 origin = offset_ray_origin(surface.point, side);
            RayHit hit = trace_nearest(origin, s, trace_mask(surface));
            if (!hit.hit) {
                break;
            }
            if (depth == 0) {
                hit_first = 1.0;
            }
            vec3 position;
            vec3 normal;
            surface = hit_surface(hit.object, hit.triangle, hit.barycentrics, position, normal);
            ObjectMaterial m = FETCH_OBJECT_MATERIAL(object_material, hit.object);
            vec3 view_blur = vec3(m.beta_normal, m.beta_grazing, m.beta_power);
            p = lacquer_params(m);
            n = normal;
            v = -s;
            // One shadow ray at the hit, to one light (with shadows on; without, every light
            // unshadowed is exact already).
            // SHADOWS is a specialization constant: the pipeline keeps one side.
            float choice = SHADOWS ? light_number(key, uint(i), uint(depth)) : 0.0;
            vec3 hit_environment;
            vec3 radiance = lacquer_radiance_towards(p, view_blur, position, n, v, surface,
                SHADOWS, choice, ENV_HIT_SAMPLES, hit_environment);
            path += throughput * weight * (radiance - hidden);
            throughput *= weight;
        }
        total += path;
        float grey = (path.r + path.g + path.b) / 3.0;
        moments += vec2(grey, grey * grey);
        vec3 d = c - environment;
        float grey_d = (d.r + d.g + d.b) / 3.0;
        hits += hit_first;
        sum_d += d;
        sum_hit_d += hit_first * d;
        if (hit_first > 0.0) {
            float q = grey + grey_d;
            met += vec4(q, q * q, q * grey_d, grey_d);
            met_d2 += grey_d * grey_d;
        } else {
            missed += vec2(grey_d, grey_d * grey_d);
        }
    }
    float n = float(max(rays, 1));
    if (rays > 1 && hits > 0.0) {
        // Σ_i h_i·d_i with h_i = (hits − hit_i)/(n − 1): h_miss for a ray that met nothing,
        // h_met for one that met an object; and the grey moments of the rays' values.
        float h_miss = hits / (n - 1.0);
        float h_met = (hits - 1.0) / (n - 1.0);
        total += h_miss * (sum_d - sum_hit_d) + h_met * sum_hit_d;
        float g = 1.0 - h_met;
        moments = vec2(h_miss * missed.x + met.x - g * met.w,
            h_miss * h_miss * missed.y + met.y - 2.0 * g * met.z + g * g * met_d2);
    }
    return vec4(total / n, sample_variance_of_mean(moments, n));
}

#endif
