#version 450
// Lacquer surface: Σ over lights of f_r · E · (N·L) (SPEC §2, §4), plus the environment term
// L_env = F(acos nv)·Lpre(R, β(nv)) + k_d·max(a + b·nv, 0)·g(r)·E_irr(N)/π (SPEC §4).

#include "frame.glsl"
#define FRESNEL_SET 0
#define FRESNEL_BINDING 1
#include "lacquer_brdf.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec4 out_radiance;

vec3 environment_light(LacquerParams p, vec3 n, vec3 v) {
    vec2 nv2 = dot_compensated(n, v);
    float nv = nv2.x + nv2.y;
    if (nv <= 0.0) {
        return vec3(0.0);
    }
    vec3 r = 2.0 * nv * n - v;
    float beta = frame.view_blur.y
        + (frame.view_blur.x - frame.view_blur.y) * pow(min(nv, 1.0), frame.view_blur.z);
    vec3 specular = fresnel_table(angle_deg_of_cos(nv), p.fresnel_count)
        * prefiltered_radiance(r, beta);
    vec3 irradiance = textureLod(env_irradiance, n, 0.0).rgb;
    return specular + view_dependent_diffuse(p, nv2) * irradiance;
}

void main() {
    LacquerParams p;
    p.beckmann_m = frame.material.x;
    p.diffuse_a = frame.material.y;
    p.diffuse_b = frame.material.z;
    p.diffuse_a_lo = frame.material_lo.x;
    p.diffuse_b_lo = frame.material_lo.y;
    p.lacquer_g = frame.material.w;
    p.albedo = frame.albedo_count.xyz;
    p.fresnel_count = int(frame.albedo_count.w);

    vec3 n = normalize(in_normal);
    vec3 v = normalize(frame.eye.xyz - in_position);
    // Light-independent parts of f_r, once per fragment (see lacquer_brdf_view).
    vec2 nv2 = dot_compensated(n, v);
    vec3 f_diff = view_dependent_diffuse(p, nv2);
    vec3 radiance = vec3(0.0);
    for (int i = 0; i < frame.light_count.x; ++i) {
        vec4 lv = frame.light_vector[i];
        vec3 l;
        vec3 irradiance;
        if (lv.w == 0.0) {
            l = normalize(lv.xyz);
            irradiance = frame.light_color[i].rgb;
        } else {
            vec3 to_light = lv.xyz - in_position;
            float d2 = dot(to_light, to_light);
            if (d2 <= 0.0) {
                continue;
            }
            l = to_light * inversesqrt(d2);
            irradiance = frame.light_color[i].rgb / d2;
        }
        float nl = dot(n, l);
        if (nl <= 0.0) {
            continue;
        }
        radiance += lacquer_brdf_view(p, n, v, l, nv2, f_diff) * irradiance * nl;
    }
    if (frame.environment.x != 0) {
        radiance += environment_light(p, n, v);
    }
    out_radiance = vec4(radiance, 1.0);
}
