// Radiance leaving a lacquer surface point towards the camera: Σ over lights of f_r · E · (N·L)
// · vis (SPEC §2, §4, §6) plus the environment term of the pipeline's model (SPEC §4; the includer
// defines BRDF_ENVIRONMENT_MODEL for `brdf`):
// `paper`: L_env = F(acos nv)·Lpre(R, β(nv)) + k_d·max(a + b·nv, 0)·g(r)·E_irr(N)/π;
// `brdf`: the same diffuse half, and the specular integral of brdf_environment.glsl.
//
// The includer includes frame.glsl and lacquer_brdf.glsl first.

#ifndef LACQUER_SHADE_GLSL
#define LACQUER_SHADE_GLSL

#include "brdf_environment.glsl"
#include "visibility.glsl"

// view_blur: (β_normal, β_grazing, p) of SPEC §4's β(nv), per material; nv2 = dot_compensated(n, v)
// and f_diff = view_dependent_diffuse(p, nv2), shared with the lights; env_samples: the `brdf`
// model's lobe samples (ENV_SAMPLES where the camera looks, ENV_HIT_SAMPLES at a path's hit).
vec3 environment_light(LacquerParams p, vec3 view_blur, vec3 n, vec3 v, vec2 nv2, vec3 f_diff,
    int env_samples) {
    float nv = nv2.x + nv2.y;
    if (nv <= 0.0) {
        return vec3(0.0);
    }
    vec3 specular;
    // A define, not a specialization constant: the `brdf` model's code behind a constant that
    // is false still cost lavapipe's `paper` pipelines ~5 % (BENCHMARKS.md).
#ifdef BRDF_ENVIRONMENT_MODEL
    specular = brdf_environment_specular(p, n, v, nv, env_samples);
#else
    {
        vec3 r = 2.0 * nv * n - v;
        float beta = view_blur.y + (view_blur.x - view_blur.y) * pow(min(nv, 1.0), view_blur.z);
        specular = lacquer_fresnel(p, angle_deg_of_cos(nv))
            * prefiltered_radiance(r, beta);
    }
#endif
    vec3 irradiance = textureLod(env_irradiance, n, 0.0).rgb;
    return specular + f_diff * irradiance;
}

// Light i as it reaches `position`: towards it (l) and its irradiance there. False for a point
// light at the position itself.
bool incident_light(int i, vec3 position, out vec3 l, out vec3 irradiance) {
    vec4 lv = frame.light_vector[i];
    if (lv.w == 0.0) {
        l = normalize(lv.xyz);
        irradiance = frame.light_color[i].rgb;
        return true;
    }
    vec3 to_light = lv.xyz - position;
    float d2 = dot(to_light, to_light);
    l = vec3(0.0, 0.0, 1.0);
    irradiance = vec3(0.0);
    if (d2 <= 0.0) {
        return false;
    }
    l = to_light * inversesqrt(d2);
    irradiance = frame.light_color[i].rgb / d2;
    return true;
}

// Light i's f_r·E·(N·L) at the point, unshadowed (0 where it does not reach it).
vec3 unshadowed_light(LacquerParams p, int i, vec3 position, vec3 n, vec3 v, vec2 nv2,
    vec3 f_diff) {
    vec3 l;
    vec3 irradiance;
    if (!incident_light(i, position, l, irradiance)) {
        return vec3(0.0);
    }
    float nl = dot(n, l);
    if (nl <= 0.0) {
        return vec3(0.0);
    }
    return lacquer_brdf_view(p, n, v, l, nv2, f_diff) * irradiance * nl;
}

// The lights with visibility by one shadow ray (next-event estimation at a path's hit): light k
// is chosen with probability w_k / W, w_k the sum of its unshadowed f_r·E·(N·L) over r, g, b, by
// `choice` in [0, 1), and counts c_k·vis_k·W/w_k, which is the sum of all lights exactly where
// none is shadowed. The twin is `oracle::light_between`'s `one_light`.
vec3 one_light(LacquerParams p, vec3 position, vec3 n, vec3 v, vec2 nv2, vec3 f_diff,
    RaySurface surface, float choice) {
    float total = 0.0;
    for (int i = 0; i < frame.light_count.x; ++i) {
        vec3 c = unshadowed_light(p, i, position, n, v, nv2, f_diff);
        total += c.r + c.g + c.b;
    }
    if (!(total > 0.0)) {
        return vec3(0.0);
    }
    // The choice first, the shadow ray after the loop: one query for every lane, whichever light
    // it chose (a query inside the loop would run once per light under llvmpipe's lane masks).
    float target = choice * total;
    float below = 0.0;
    int chosen = -1;
    vec3 chosen_c = vec3(0.0);
    for (int i = 0; i < frame.light_count.x; ++i) {
        vec3 c = unshadowed_light(p, i, position, n, v, nv2, f_diff);
        float w = c.r + c.g + c.b;
        below += w;
        if (chosen < 0 && w > 0.0 && (target < below || i == frame.light_count.x - 1)) {
            chosen = i;
            chosen_c = c;
        }
    }
    if (chosen < 0) {
        return vec3(0.0);
    }
    float w = chosen_c.r + chosen_c.g + chosen_c.b;
    return chosen_c * (light_visibility(surface, frame.light_vector[chosen]) * (total / w));
}

// Radiance leaving `position` (unit normal n) towards v; `surface`: where its shadow rays start
// (visibility.glsl; unused without RAY_TRACING). `next_event` false: every light with its own
// shadow ray; true: one of them (`one_light`), chosen by `light_choice` in [0, 1). Callers pass
// a constant for `next_event`, so each pipeline keeps one side of the branch: llvmpipe would run
// both, and each side traces (quirk `loop_body_runs_when_no_lane_enters`). env_samples: as
// `environment_light`. `environment`: the environment term's share of the result (0 without an
// environment).
vec3 lacquer_radiance_towards(LacquerParams p, vec3 view_blur, vec3 position, vec3 n, vec3 v,
    RaySurface surface, bool next_event, float light_choice, int env_samples,
    out vec3 environment) {
    // Light-independent parts of f_r, once per point (see lacquer_brdf_view).
    vec2 nv2 = dot_compensated(n, v);
    vec3 f_diff = view_dependent_diffuse(p, nv2);
    vec3 radiance = vec3(0.0);
    if (next_event) {
        radiance += one_light(p, position, n, v, nv2, f_diff, surface, light_choice);
    } else {
        for (int i = 0; i < frame.light_count.x; ++i) {
            vec3 c = unshadowed_light(p, i, position, n, v, nv2, f_diff);
            if (c != vec3(0.0)) {
                // SPEC §6: lights with visibility (always 1 without ray tracing).
                radiance += c * light_visibility(surface, frame.light_vector[i]);
            }
        }
    }
    environment = vec3(0.0);
    if (frame.environment.x != 0) {
        environment = environment_light(p, view_blur, n, v, nv2, f_diff, env_samples);
    }
    return radiance + environment;
}

#ifdef RAY_TRACING
// The environment term the light between objects' control variate takes (light_between.glsl):
// ∫ f_r·L·(N·s) dω over every direction, at unit n, v. In `brdf` that is the model's own term,
// `environment` (what lacquer_radiance_towards gave). `paper`'s term is not that integral, so
// the `brdf` model's quadrature stands in for it, on the bright split of `paper`'s layers (the
// renderer attaches one to the environment of a `paper` draw that estimates the integral,
// EnvironmentPreparer::attach_bright; a map uploaded without one is read whole): the variate
// then adds h·(this − the integral), the quadrature's error where the environment is hidden.
// It reads ENV_VARIATE_SAMPLES lobe samples, not ENV_SAMPLES: the variate needs only an estimate
// of the integral, and `paper` renders of wide lobes should not pay the `brdf` model's accuracy.
vec3 integral_environment(LacquerParams p, vec3 n, vec3 v, vec3 environment) {
#ifdef BRDF_ENVIRONMENT_MODEL
    return environment;
#else
    vec2 nv2 = dot_compensated(n, v);
    float nv = nv2.x + nv2.y;
    if (frame.environment.x == 0 || nv <= 0.0) {
        return vec3(0.0);
    }
    vec3 f_diff = view_dependent_diffuse(p, nv2);
    return brdf_environment_specular(p, n, v, nv, ENV_VARIATE_SAMPLES)
        + f_diff * textureLod(env_irradiance, n, 0.0).rgb;
#endif
}
#endif

// Radiance towards the camera, `position` and `interpolated_normal` as the rasteriser
// interpolated them at a pixel centre; `environment` as in `lacquer_radiance_towards`.
vec3 lacquer_radiance(LacquerParams p, vec3 view_blur, vec3 position, vec3 interpolated_normal,
    RaySurface surface, out vec3 environment) {
    vec3 n = normalize(interpolated_normal);
    vec3 v = normalize(frame.eye.xyz - position);
    return lacquer_radiance_towards(p, view_blur, position, n, v, surface, false, 0.0,
        ENV_SAMPLES, environment);
}

#endif
