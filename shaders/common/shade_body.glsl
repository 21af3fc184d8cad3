// The lacquer draw's shading pass (shade.frag, shade_ms.frag), a full-screen triangle over a
// single-sampled target: each pixel reads the G-buffer samples gbuffer.frag wrote, shades each
// distinct surface once (lacquer_shade.glsl; neighbouring triangles of one smooth mesh are one
// surface, `same_surface`), gives uncovered samples the background and writes the average of its
// samples: what forward shading followed by an MSAA resolve gives.
//
// Why a separate pass: llvmpipe shades a triangle in whole 4×4 blocks, so on a mesh of ~6-pixel
// triangles a forward lacquer shader ran on every block each triangle touched (and on hidden
// surfaces); here each pixel is shaded once per visible surface (BENCHMARKS.md). Pixels no mesh
// covers already hold the background and fail the early depth test (coverage_body.glsl), which is
// how llvmpipe skips a block of pixels: a branch would run under a lane mask (quirk
// `loop_body_runs_when_no_lane_enters`). The draw is also scissored to the meshes' screen bounds
// (raster/draw/passes.rs).
//
// The includer defines MULTISAMPLED (sampler2DMS G-buffer) or not (sampler2D).

#include "frame.glsl"
#include "lacquer_brdf.glsl"
#include "lacquer_shade.glsl"

// Every object's ObjectMaterial, OBJECT_MATERIAL_TEXELS texels each.
#include "texel_buffer.glsl"
layout(set = 0, binding = OBJECT_MATERIAL_BINDING) uniform textureBuffer object_material;

#include "gbuffer_samples.glsl"
#include "sequence.glsl"

// `same_surface`'s bounds: normals within 0.26° (cos 0.99999) and points within an eighth of the
// pixel's footprint. Neighbouring triangles of the built-in bowl, extended to the pixel centre,
// part by far less in nine pixels of ten; a silhouette by far more (BENCHMARKS.md, "Surfaces
// shaded once a pixel").
const float SURFACE_MERGE_COS = 0.99999;
const float SURFACE_MERGE_SHARE = 0.125;

#ifdef RAY_TRACING
#include "light_between.glsl"
#endif

// The pass's outputs. out_radiance: linear radiance, alpha = coverage. out_integral, where rays
// are traced, the integral image (raster/draw/denoise.rs): rgb the integral's share of
// out_radiance, alpha the variance of its grey value as the rays estimate it (the clear value −1
// where no sample is covered: this pass runs only where one is). With it out_radiance is not
// clamped at 0: the host clamps it (raster/draw/mod.rs).
// A ray-tracing pipeline's ray generation shader (RAY_TRACING_PIPELINE, shade_rt*.rgen) writes
// them to storage images instead of colour attachments: shade_rt_pipeline.glsl.
#ifndef RAY_TRACING_PIPELINE
layout(location = 0) out vec4 out_radiance;
#ifdef RAY_TRACING
layout(location = 1) out vec4 out_integral;
#endif
#endif

// `normal`: the G-buffer's (w: the triangle, with RAY_TRACING); `key`: the pixel's
// (sequence.glsl). `integral`: what SPEC §6's integral added (rgb) and its variance (w).
vec3 shade_object(int object, vec3 position, vec4 normal, uint key, out vec4 integral) {
    ObjectMaterial m = FETCH_OBJECT_MATERIAL(object_material, object);
    vec3 view_blur = vec3(m.beta_normal, m.beta_grazing, m.beta_power);
    LacquerParams p = lacquer_params(m);
    integral = vec4(0.0);
#ifdef RAY_TRACING
    vec3 n = normalize(normal.xyz);
    RaySurface surface = ray_surface(object, int(normal.w), position, n);
    vec3 environment;
    vec3 radiance = lacquer_radiance(p, view_blur, position, normal.xyz, surface, environment);
    if (INTEGRAL && frame.light_transport.y > 0) {
        vec3 v = normalize(frame.eye.xyz - position);
        // Unclamped: the integral's estimate can exceed what the environment gave (few rays,
        // most of them hiding a bright sky), but the clamp at 0 of the radiance it estimates is
        // the host's, after the denoise: a noisy estimate clamped pixel by pixel is biased
        // upwards where the radiance is near 0 (a black bowl mirrored in a black tray).
        integral = light_between(p, n, v, surface, key, integral_environment(p, n, v,
            environment));
        radiance += integral.rgb;
    }
    return radiance;
#else
    vec3 environment;
    return lacquer_radiance(p, view_blur, position, normal.xyz, untraced_surface(position, normal.xyz),
        environment);
#endif
}

// Whether G-buffer sample (q, m) lies on the surface of sample (p, n), both interpolated at the
// same pixel centre (w: the object; the normals need not be unit): the same object, normals
// within SURFACE_MERGE_COS, points within SURFACE_MERGE_SHARE of the pixel's `footprint`.
// Neighbouring triangles of a smooth mesh pass; a silhouette over the same mesh (a bowl's rim
// before its inside) and a crease do not, and stay shaded apart, as a forward draw with an MSAA
// resolve shades them.
bool same_surface(vec4 q, vec4 m, vec4 p, vec4 n, float footprint) {
    vec3 d = q.xyz - p.xyz;
    float reach = SURFACE_MERGE_SHARE * footprint;
    float nm = dot(n.xyz, m.xyz);
    float bound = SURFACE_MERGE_COS * SURFACE_MERGE_COS * dot(n.xyz, n.xyz) * dot(m.xyz, m.xyz);
    return q.w == p.w && dot(d, d) <= reach * reach && nm > 0.0 && nm * nm >= bound;
}

// Pixel `texel` of the target, whose centre is `centre` (gl_FragCoord.xy): the average of its
// samples (`radiance`) and, with RAY_TRACING, the integral's share and variance (`integral`).
// False, with nothing written, where no sample is covered.
bool shade_pixel(ivec2 texel, vec2 centre, out vec4 radiance, out vec4 integral_out) {
    vec4 position[MAX_SAMPLES];
    vec4 normal[MAX_SAMPLES];
    uint covered = 0u;
    for (int s = 0; s < SAMPLE_COUNT; ++s) {
        position[s] = FETCH(gbuffer_position, texel, s);
        normal[s] = FETCH(gbuffer_normal, texel, s);
        if (position[s].w != 0.0) {
            covered |= 1u << s;
        }
    }
    vec4 sum = vec4(0.0);
    // The integral's share of `sum` and the variance of the pixel's mean: Σ (count/N)²·v.
    vec4 integral_sum = vec4(0.0);
    // The pixel in whole-image coordinates keys its sample sequence.
    uint key = pixel_key(uvec2(texel.x, texel.y + int(frame.strip_offset.y)),
        uint(frame.light_transport.z));
    int uncovered = SAMPLE_COUNT - bitCount(covered);
    if (uncovered > 0) {
        // The pixel centre in whole-image coordinates, as in background.frag.
        vec2 pixel = vec2(centre.x, centre.y + frame.strip_offset.y);
        sum += background_radiance(pixel) * float(uncovered);
    }
    // Each surface the pixel's samples see is shaded once and weighted by its sample count.
    // Samples of one triangle hold bit-identical values (interpolated at the pixel centre); so,
    // nearly, do the samples of neighbouring triangles of one smooth mesh, and those are shaded
    // once too, at their mean (`same_surface`). Shaded apart, a mesh of pixel-sized triangles
    // was shaded twice or more in one pixel of six, and llvmpipe runs a block's shading again
    // wherever one of its pixels does (BENCHMARKS.md, "Surfaces shaded once a pixel").
    // A loop, not a branch per sample: a loop repeats only while some lane needs it, but both
    // sides of every branch run (quirk `loop_body_runs_when_no_lane_enters`).
    // coverage_body.glsl's depth test lets through only pixels with a covered sample; were one to
    // have none, the loop body below adds nothing (weight 0) and reads a valid object.
    // The pixel's footprint at unit distance from the eye.
    float pixel_angle = 2.0 * frame.camera_params.x / frame.camera_params.w;
    uint todo = covered;
    do {
        int first = max(findLSB(todo), 0);
        vec4 p = position[0];
        vec4 n = normal[0];
        for (int s = 1; s < SAMPLE_COUNT; ++s) {
            if (s == first) {
                p = position[s];
                n = normal[s];
            }
        }
        float footprint = pixel_angle * length(p.xyz - frame.eye.xyz);
        uint same = 0u;
        // The mean as offsets from the first sample's values: exactly those where every sample
        // of the surface is bit-identical (one triangle), so such pixels shade as before.
        vec3 offset_p = vec3(0.0);
        vec3 offset_n = vec3(0.0);
        for (int s = 0; s < SAMPLE_COUNT; ++s) {
            bool member = ((todo >> uint(s)) & 1u) != 0u
                && same_surface(position[s], normal[s], p, n, footprint);
            if (member) {
                same |= 1u << s;
                offset_p += position[s].xyz - p.xyz;
                offset_n += normal[s].xyz - n.xyz;
            }
        }
        // `first` always: a NaN (never written by gbuffer.frag) must not stall the loop.
        same |= todo != 0u ? 1u << first : 0u;
        float count = float(bitCount(same));
        p.xyz += offset_p / count;
        n.xyz += offset_n / count;
        vec4 integral;
        vec3 radiance = shade_object(max(int(p.w) - 1, 0), p.xyz, n, key, integral);
        float share = count / float(SAMPLE_COUNT);
        sum += vec4(radiance, 1.0) * count;
        integral_sum += integral * vec4(vec3(share), share * share);
        todo &= ~same;
    } while (todo != 0u);
    radiance = sum / float(SAMPLE_COUNT);
    integral_out = integral_sum;
    return covered != 0u;
}

#ifndef RAY_TRACING_PIPELINE
// A fragment shader: the shading pass's depth test already let through only covered pixels.
void main() {
    vec4 radiance;
    vec4 integral;
    shade_pixel(ivec2(gl_FragCoord.xy), gl_FragCoord.xy, radiance, integral);
    out_radiance = radiance;
#ifdef RAY_TRACING
    out_integral = integral;
#endif
}
#endif
