//! SPEC §6's integral (light_between.glsl in the ray-traced shading pass) against its CPU twin
//! (`oracle::light_between`: the same sample sequence, lobes and paths over the same triangles)
//! under lights and a constant environment, pixel by pixel at one sample per pixel; the lone
//! convex object that must not change; determinism of the seed. Skipped, with a line on stderr,
//! on a device without ray queries.

use super::shadows::{
    bowl_in_bowl, camera_looking_down, draw, draw_objects, draw_with_integral, gpu_or_skip, lights,
    material, ray_pipeline_gpu_or_skip, relative_errors, scene, sphere_on_board, traced_objects,
    Material, RADIANCE_FLOOR,
};
use crate::common::{quantile, write_failure_images};
use glam::DVec3;
use shikki::environment::brdf_quadrature::albedo_knots;
use shikki::environment::gpu::{GpuEnvironment, GpuPrefilter};
use shikki::environment::{EnvironmentLight, EnvironmentModel, Equirect, PrefilterParams};
use shikki::gpu::GpuContext;
use shikki::oracle::light_between::{ConstantEnvironment, Twin};
use shikki::oracle::path_tracer::{self, PathEnvironment, PathImage, PathScene};
use shikki::oracle::shadows::TracedScene;
use shikki::output::HdrImage;
use shikki::raster::camera::Camera;
use shikki::raster::draw::denoise::denoise_sigma;
use shikki::raster::draw::RayTracing;
use shikki::raster::draw::{Background, LacquerRenderer, RenderSettings};
use shikki::raster::lights::Light;
use shikki::raster::mesh::{self, Mesh};

/// GPU against twin, p99 of the per-pixel relative difference (`errors_at_light_level`): the
/// issue's bound. The twin
/// follows the shader's f32 directions; what remains is f32 vs f64 shading (≤ 1e-5, measured in
/// shadows.rs) and a few rays that graze an edge and hit on one side only.
const P99_BOUND: f64 = 1e-3;

/// Per pixel covered by both: max over channels of |gpu − twin| / max(plain, floor), the
/// difference against the light level the pixel has without ray tracing. Plain relative error
/// is ill-posed where the integral takes nearly all the light away (inside a bowl its sky is
/// hidden by the other bowl and the estimate nears 0), and it is the error in the light there
/// that a viewer sees.
fn errors_at_light_level(gpu: &HdrImage, twin: &HdrImage, plain: &HdrImage) -> Vec<f64> {
    gpu.pixels
        .iter()
        .zip(&twin.pixels)
        .zip(&plain.pixels)
        .filter(|((a, b), _)| a[3] == 1.0 && b[3] == 1.0)
        .map(|((a, b), p)| {
            (0..3)
                .map(|c| {
                    let scale = f64::from(p[c].max(b[c])).max(RADIANCE_FLOOR);
                    f64::from((a[c] - b[c]).abs()) / scale
                })
                .fold(0.0, f64::max)
        })
        .collect()
}

/// The sky: constant radiance, so both environment models have exact values on the CPU.
const SKY: [f32; 3] = [0.5, 0.6, 0.8];

/// A prefiltered constant environment and the irradiance its cube holds (mean over texels; the
/// cube's quadrature gives π·c to 1e-3, environment/gpu.rs).
fn constant_environment(gpu: &GpuContext) -> (GpuEnvironment, [f64; 3]) {
    let source = Equirect::constant(128, 64, SKY);
    let env = GpuPrefilter::new(gpu)
        .unwrap()
        .run(
            gpu,
            &source,
            &PrefilterParams::for_source_width(source.width),
            EnvironmentLight::default(),
        )
        .unwrap();
    let cubes = env.read_back(gpu).unwrap();
    let texels = &cubes.irradiance.texels;
    let irradiance = [0, 1, 2]
        .map(|c| texels.iter().map(|t| f64::from(t[c])).sum::<f64>() / texels.len() as f64);
    (env, irradiance)
}

struct Case<'a> {
    meshes: &'a [Mesh],
    materials: &'a [&'a Material],
    camera: &'a Camera,
    lights: &'a [Light],
    model: EnvironmentModel,
    size: u32,
}

fn gpu_render(
    gpu: &GpuContext,
    case: &Case<'_>,
    env: &GpuEnvironment,
    rt: Option<RayTracing>,
) -> HdrImage {
    draw(
        gpu,
        (case.meshes, case.materials),
        (case.camera, case.lights),
        (Some(env), case.model),
        rt,
        case.size,
    )
}

/// The twin's image and integral image.
fn twin_render(case: &Case<'_>, irradiance: [f64; 3], rt: &RayTracing) -> (HdrImage, HdrImage) {
    let objects = traced_objects(case.meshes, case.materials);
    let albedo: Vec<_> = case
        .materials
        .iter()
        .map(|m| albedo_knots(&m.brdf, &m.fresnel))
        .collect();
    let scene = TracedScene::new(&objects);
    Twin {
        scene: &scene,
        lights: case.lights,
        environment: Some(ConstantEnvironment {
            radiance: SKY.map(f64::from),
            irradiance,
            model: case.model,
        }),
        albedo: &albedo,
    }
    .render_with_integral(case.camera, (case.size, case.size), rt)
}

/// Per pixel covered by both: |σ_gpu − σ_twin| / max(plain, floor) over the integral images'
/// standard deviations √alpha: the noise estimate the denoise reads, against the light level
/// (`errors_at_light_level`).
fn spread_errors(gpu: &HdrImage, twin: &HdrImage, plain: &HdrImage) -> Vec<f64> {
    gpu.pixels
        .iter()
        .zip(&twin.pixels)
        .zip(&plain.pixels)
        .filter(|((a, b), _)| a[3] >= 0.0 && b[3] >= 0.0)
        .map(|((a, b), p)| {
            let level = f64::from((p[0] + p[1] + p[2]) / 3.0).max(RADIANCE_FLOOR);
            (f64::from(a[3]).sqrt() - f64::from(b[3]).sqrt()).abs() / level
        })
        .collect()
}

fn compare_with_twin(name: &str, case: &Case<'_>, rt: RayTracing) {
    if let Some(gpu) = gpu_or_skip() {
        compare_with_twin_on(&gpu, name, case, rt);
    }
}

fn compare_with_twin_on(gpu: &GpuContext, name: &str, case: &Case<'_>, rt: RayTracing) {
    let (env, irradiance) = constant_environment(gpu);
    let (traced, integral) = draw_with_integral(
        gpu,
        (case.meshes, case.materials),
        (case.camera, case.lights),
        (Some(&env), case.model),
        Some(rt),
        case.size,
    );
    let integral = integral.expect("a ray-traced draw has an integral image");
    let plain = gpu_render(gpu, case, &env, None);
    let (twin, twin_integral) = twin_render(case, irradiance, &rt);
    assert!(
        traced.pixels.iter().flatten().all(|v| v.is_finite())
            && integral.pixels.iter().flatten().all(|v| v.is_finite()),
        "{name}: non-finite pixel"
    );
    for (i, (p, e)) in traced.pixels.iter().zip(&integral.pixels).enumerate() {
        // Covered (alpha 1 at one sample per pixel) ⇔ a variance ≥ 0; else exactly −1.
        let covered = p[3] == 1.0;
        assert!(
            (covered && e[3] >= 0.0) || (!covered && e[3] == -1.0),
            "{name}: pixel {i}: image {p:?}, integral {e:?}"
        );
    }
    let mut errors = errors_at_light_level(&traced, &twin, &plain);
    let mut integral_errors = errors_at_light_level(
        &integral_image(&integral),
        &integral_image(&twin_integral),
        &plain,
    );
    let mut spreads = spread_errors(&integral, &twin_integral, &plain);
    let covered = errors.len();
    // Pixels the integral (and shadows) change by more than 1%: the test means something only
    // if objects do see one another here.
    let changed = relative_errors(&traced, &plain)
        .iter()
        .filter(|&&e| e > 0.01)
        .count();
    let noisy = integral.pixels.iter().filter(|e| e[3] > 0.0).count();
    let p99 = quantile(&mut errors, 0.99);
    let integral_p99 = quantile(&mut integral_errors, 0.99);
    let spread_p99 = quantile(&mut spreads, 0.99);
    eprintln!(
        "{name}: {covered} covered, {changed} changed by ray tracing, {noisy} with a variance; \
         GPU vs twin p99 {p99:.2e}, integral {integral_p99:.2e}, its σ {spread_p99:.2e}"
    );
    if p99 > P99_BOUND {
        write_failure_images(name, &traced, &twin);
    }
    assert!(covered > 4_000, "{name}: {covered} covered pixels");
    assert!(
        changed * 5 > covered && noisy * 5 > covered,
        "{name}: ray tracing changed only {changed} ({noisy} noisy) of {covered} pixels"
    );
    assert!(p99 <= P99_BOUND, "{name}: p99 {p99:.3e} > {P99_BOUND}");
    assert!(
        integral_p99 <= P99_BOUND,
        "{name}: integral p99 {integral_p99:.3e} > {P99_BOUND}"
    );
    assert!(
        spread_p99 <= P99_BOUND,
        "{name}: the integral's σ p99 {spread_p99:.3e} > {P99_BOUND}"
    );
}

/// An integral image as an image (alpha 1 where covered), for `errors_at_light_level`.
fn integral_image(integral: &HdrImage) -> HdrImage {
    let mut image = integral.clone();
    for p in &mut image.pixels {
        p[3] = if p[3] >= 0.0 { 1.0 } else { 0.0 };
    }
    image
}

/// Sphere on board in both environment models (`paper` 1 bounce, `brdf` 2), compared by `compare`.
fn sphere_on_board_cases(compare: impl Fn(&str, &Case<'_>, RayTracing)) {
    let (red, black) = (material("smooth-red"), material("rough-black"));
    let meshes = sphere_on_board();
    let lights = lights();
    let camera = camera_looking_down();
    for (model, bounces) in [(EnvironmentModel::Paper, 1), (EnvironmentModel::Brdf, 2)] {
        let case = Case {
            meshes: &meshes,
            materials: &[&red, &black],
            camera: &camera,
            lights: &lights,
            model,
            size: 96,
        };
        let rt = RayTracing {
            shadows: true,
            bounces,
            rays: 8,
            seed: 7,
            denoise: false,
        };
        compare(&format!("between-sphere-board-{}", model.name()), &case, rt);
    }
}

/// A bowl in a bowl (concave self-reflection), `brdf`, 2 bounces, compared by `compare`.
fn bowl_in_bowl_case(compare: impl Fn(&str, &Case<'_>, RayTracing)) {
    let (red, black) = (material("smooth-red"), material("smooth-black"));
    let meshes = bowl_in_bowl();
    let lights = lights();
    let camera = Camera {
        eye: DVec3::new(0.3, 1.7, 1.3),
        target: DVec3::new(0.0, 0.2, 0.0),
        up: DVec3::Y,
        fov_deg: 45.0,
    };
    let case = Case {
        meshes: &meshes,
        materials: &[&black, &red],
        camera: &camera,
        lights: &lights,
        model: EnvironmentModel::Brdf,
        size: 96,
    };
    let rt = RayTracing {
        shadows: true,
        bounces: 2,
        rays: 4,
        seed: 1,
        denoise: false,
    };
    compare("between-bowl-in-bowl", &case, rt);
}

#[test]
fn sphere_on_board_matches_its_cpu_twin() {
    sphere_on_board_cases(compare_with_twin);
}

#[test]
fn bowl_in_bowl_matches_its_cpu_twin() {
    bowl_in_bowl_case(compare_with_twin);
}

/// The ray-tracing pipeline path (shade_rt*.rgen: devices with no ray queries, NVIDIA's
/// H100/H200) against the same twin with the same bounds: lavapipe has both paths.
#[test]
fn sphere_on_board_in_a_ray_tracing_pipeline_matches_its_cpu_twin() {
    let Some(gpu) = ray_pipeline_gpu_or_skip() else {
        return;
    };
    sphere_on_board_cases(|name, case, rt| {
        compare_with_twin_on(&gpu, &format!("{name}-pipeline"), case, rt)
    });
}

#[test]
fn bowl_in_bowl_in_a_ray_tracing_pipeline_matches_its_cpu_twin() {
    let Some(gpu) = ray_pipeline_gpu_or_skip() else {
        return;
    };
    bowl_in_bowl_case(|name, case, rt| {
        compare_with_twin_on(&gpu, &format!("{name}-pipeline"), case, rt)
    });
}

/// The two ways of tracing draw the same image at 4× MSAA (shade_rt_brdf_ms.rgen against
/// shade_rt_brdf_ms.frag, with the environment as background: the coverage draw's pixels the
/// ray generation shader must leave alone) and 1× (the `paper` variants): the same shading code,
/// the same sequence, the same rays, compiled into another stage.
#[test]
fn a_ray_tracing_pipeline_draws_what_ray_queries_draw() {
    let Some(queries) = gpu_or_skip().filter(|g| !g.info().ray_query.uses_pipeline()) else {
        return;
    };
    let Some(pipeline) = ray_pipeline_gpu_or_skip() else {
        return;
    };
    let (red, black) = (material("smooth-red"), material("rough-black"));
    let meshes = sphere_on_board();
    let lights = lights();
    let camera = camera_looking_down();
    let objects = draw_objects((&meshes, &[&red, &black]));
    for (model, samples) in [(EnvironmentModel::Brdf, 4), (EnvironmentModel::Paper, 1)] {
        let rt = RayTracing {
            shadows: true,
            bounces: 2,
            rays: 4,
            seed: 3,
            denoise: false,
        };
        let render = |gpu: &GpuContext| {
            let (env, _) = constant_environment(gpu);
            let mut scene = scene(&objects, (&camera, &lights), (Some(&env), model), Some(rt));
            scene.background = Background::Environment;
            let settings = RenderSettings {
                width: 80,
                height: 72,
                samples,
            };
            let drawn = LacquerRenderer::new()
                .render_with_integral(gpu, &scene, &settings)
                .unwrap();
            crate::common::assert_no_validation_messages(gpu);
            drawn
        };
        let (a, a_integral) = render(&queries);
        let (b, b_integral) = render(&pipeline);
        let (a_integral, b_integral) = (a_integral.unwrap(), b_integral.unwrap());
        let worst = |x: &HdrImage, y: &HdrImage| {
            x.pixels
                .iter()
                .zip(&y.pixels)
                .flat_map(|(p, q)| (0..4).map(move |c| (p[c] - q[c]).abs() / q[c].abs().max(1e-3)))
                .fold(0.0_f32, f32::max)
        };
        let (image, integral) = (worst(&b, &a), worst(&b_integral, &a_integral));
        eprintln!(
            "{} at {samples}×: pipeline vs ray queries, worst {image:.2e} (image), {integral:.2e} \
             (integral)",
            model.name()
        );
        if image > 1e-5 {
            write_failure_images(&format!("ray-pipeline-{}", model.name()), &b, &a);
        }
        assert!(
            image <= 1e-5 && integral <= 1e-5,
            "{image:.3e} {integral:.3e}"
        );
    }
}

/// One renderer, its targets and pipelines reused, on the ray-tracing pipeline path: a traced
/// draw, a plain one, a traced one again (the shading pass's G-buffer reads move between the
/// fragment and the ray-tracing stages, its outputs between colour attachments and storage
/// images), validated, each the image a fresh renderer draws.
#[test]
fn a_ray_tracing_pipeline_renderer_alternates_traced_and_plain_draws() {
    let Some(gpu) = ray_pipeline_gpu_or_skip() else {
        return;
    };
    let (env, _) = constant_environment(&gpu);
    let (red, black) = (material("smooth-red"), material("rough-black"));
    let meshes = sphere_on_board();
    let lights = lights();
    let camera = camera_looking_down();
    let objects = draw_objects((&meshes, &[&red, &black]));
    let rt = RayTracing {
        shadows: true,
        bounces: 1,
        rays: 2,
        seed: 5,
        denoise: true,
    };
    let settings = RenderSettings {
        width: 48,
        height: 40,
        samples: 4,
    };
    let mut renderer = LacquerRenderer::new();
    for traced in [Some(rt), None, Some(rt)] {
        let scene = scene(
            &objects,
            (&camera, &lights),
            (Some(&env), EnvironmentModel::Paper),
            traced,
        );
        let again = renderer.render(&gpu, &scene, &settings).unwrap();
        let fresh = LacquerRenderer::new()
            .render(&gpu, &scene, &settings)
            .unwrap();
        crate::common::assert_no_validation_messages(&gpu);
        assert!(again.pixels == fresh.pixels, "traced {}", traced.is_some());
    }
}

/// A lone sphere under the sky: no ray it sends can meet another object, so the integral is 0
/// and the image is the one without ray tracing.
#[test]
fn a_lone_sphere_has_nothing_between() {
    let Some(gpu) = gpu_or_skip() else { return };
    let (env, _) = constant_environment(&gpu);
    let sphere = [mesh::sphere(128, 64)];
    let red = material("rough-red");
    let camera = Camera::default();
    let case = Case {
        meshes: &sphere,
        materials: &[&red],
        camera: &camera,
        lights: &[],
        model: EnvironmentModel::Brdf,
        size: 128,
    };
    let rt = RayTracing {
        shadows: true,
        bounces: 2,
        rays: 16,
        seed: 0,
        denoise: false,
    };
    let traced = gpu_render(&gpu, &case, &env, Some(rt));
    let plain = gpu_render(&gpu, &case, &env, None);
    let errors = relative_errors(&traced, &plain);
    let changed = errors.iter().filter(|&&e| e > 1e-6).count();
    let worst = errors.iter().copied().fold(0.0, f64::max);
    eprintln!(
        "lone sphere: {} covered, {changed} changed, worst {worst:.2e}",
        errors.len()
    );
    assert!(errors.len() > 4_000);
    assert!(
        changed == 0,
        "{changed} pixels changed, worst by {worst:.3e}"
    );
    // The denoise filters an integral that is 0 everywhere: the same image, bit for bit.
    let denoised = gpu_render(
        &gpu,
        &case,
        &env,
        Some(RayTracing {
            denoise: true,
            ..rt
        }),
    );
    assert!(
        denoised.pixels == traced.pixels,
        "the denoise changed an image with nothing between"
    );
}

/// Same seed, same bytes (two renderers); another seed, another noise.
#[test]
fn the_seed_decides_the_image() {
    let Some(gpu) = gpu_or_skip() else { return };
    let (env, _) = constant_environment(&gpu);
    let meshes = sphere_on_board();
    let (red, black) = (material("rough-red"), material("rough-black"));
    let lights = lights();
    let camera = camera_looking_down();
    let case = Case {
        meshes: &meshes,
        materials: &[&red, &black],
        camera: &camera,
        lights: &lights,
        model: EnvironmentModel::Paper,
        size: 64,
    };
    let rt = |seed| RayTracing {
        shadows: true,
        bounces: 1,
        rays: 4,
        seed,
        denoise: false,
    };
    let a = gpu_render(&gpu, &case, &env, Some(rt(3)));
    let b = gpu_render(&gpu, &case, &env, Some(rt(3)));
    let c = gpu_render(&gpu, &case, &env, Some(rt(4)));
    assert!(a.pixels == b.pixels, "same seed, different images");
    let differing = a
        .pixels
        .iter()
        .zip(&c.pixels)
        .filter(|(a, c)| a != c)
        .count();
    assert!(
        differing > 500,
        "another seed changed only {differing} pixels"
    );
}

/// Whole-image relative RMSE of `image` against `reference` over the pixels both cover:
/// sqrt(Σ d² / Σ r²) over pixels and channels.
fn relative_rmse(image: &HdrImage, reference: &HdrImage) -> f64 {
    let (mut err, mut norm) = (0.0, 0.0);
    for (g, r) in image.pixels.iter().zip(&reference.pixels) {
        if g[3] != 1.0 || r[3] != 1.0 {
            continue;
        }
        for c in 0..3 {
            let d = f64::from(g[c] - r[c]);
            err += d * d;
            norm += f64::from(r[c]) * f64::from(r[c]);
        }
    }
    (err / norm).sqrt()
}

/// The reference's own noise in the same measure: sqrt(Σ σ² / Σ r²), σ its standard error per
/// pixel (max over channels, so an upper bound).
fn reference_noise(reference: &PathImage) -> f64 {
    let (mut var, mut norm) = (0.0, 0.0);
    for (r, sigma) in reference.mean.pixels.iter().zip(&reference.std_error) {
        if r[3] == 1.0 {
            var += 3.0 * sigma * sigma;
            norm += (0..3).map(|c| f64::from(r[c]).powi(2)).sum::<f64>();
        }
    }
    (var / norm).sqrt()
}

/// SPEC §6 on a 64² sphere resting on a board, `brdf` model, one bounce, under the constant sky
/// and a directional light: the estimator converges to the brute-force path tracer
/// (`oracle::path_tracer`, an independent formulation: it integrates the incoming light, not the
/// difference the objects make), its error falling about as 1/√rays.
#[test]
fn converges_to_the_path_tracer() {
    let Some(gpu) = gpu_or_skip() else { return };
    let (env, irradiance) = constant_environment(&gpu);
    let meshes = sphere_on_board();
    let (red, black) = (material("smooth-red"), material("rough-black"));
    let lights = vec![Light::Directional {
        to_light: DVec3::new(0.6, 0.7, 0.4).normalize(),
        irradiance: DVec3::new(2.0, 1.9, 1.8),
    }];
    let camera = camera_looking_down();
    let case = Case {
        meshes: &meshes,
        materials: &[&red, &black],
        camera: &camera,
        lights: &lights,
        model: EnvironmentModel::Brdf,
        size: 64,
    };
    let objects = traced_objects(&meshes, &[&red, &black]);
    // The GPU's irradiance cube holds π·c to 1e-3 (its quadrature); the path tracer's sky is c.
    let _ = irradiance;
    let reference = path_tracer::render(
        &PathScene {
            objects: &objects,
            camera: &camera,
            lights: &lights,
            environment: PathEnvironment::Constant(SKY.map(f64::from)),
        },
        (64, 64),
        1,
        REFERENCE_PATHS,
        11,
    );
    let noise = reference_noise(&reference);
    eprintln!(
        "path tracer, {REFERENCE_PATHS} paths per pixel: noise {:.2} %",
        100.0 * noise
    );
    let mut errors = Vec::new();
    let (mut raw_errors, mut denoised_errors) = (Vec::new(), Vec::new());
    // 8 is printed (the default's neighbour), not asserted on.
    for rays in [4, 8, 16, 64, 256] {
        let rt = RayTracing {
            shadows: true,
            bounces: 1,
            rays,
            seed: 5,
            denoise: false,
        };
        let image = gpu_render(&gpu, &case, &env, Some(rt));
        let rmse = relative_rmse(&image, &reference.mean);
        let beyond_noise = (rmse * rmse - noise * noise).max(0.0).sqrt();
        eprintln!(
            "rays {rays}: relative RMSE vs the path tracer {:.2} % ({:.2} % beyond its noise)",
            100.0 * rmse,
            100.0 * beyond_noise
        );
        raw_errors.push(rmse);
        if rays != 8 {
            errors.push(rmse);
        }
        let denoised = gpu_render(
            &gpu,
            &case,
            &env,
            Some(RayTracing {
                denoise: true,
                ..rt
            }),
        );
        let rmse = relative_rmse(&denoised, &reference.mean);
        eprintln!(
            "rays {rays}, denoised: relative RMSE vs the path tracer {:.2} %",
            100.0 * rmse
        );
        denoised_errors.push(rmse);
        if denoise_sigma(rays).is_none() {
            assert!(
                denoised.pixels == image.pixels,
                "rays {rays}: filter not off"
            );
        }
    }
    // The denoise: below the estimate's error where the noise dominates (measured 6.83 → 3.45 %
    // at 4 rays, 4.19 → 2.32 % at 8, 2.53 → 1.67 % at 16; the bounds leave ~15 %), still below
    // it and falling as the rays grow (the filter narrows as 1/√rays: 1.10 → 0.88 % at 64), and
    // off at 256 (asserted above: the same image, on the floor that wobbles as above).
    assert!(
        denoised_errors[0] < 0.6 * raw_errors[0]
            && denoised_errors[1] < 0.65 * raw_errors[1]
            && denoised_errors[3] < raw_errors[3],
        "denoised {denoised_errors:?} vs {raw_errors:?}"
    );
    for pair in denoised_errors[..4].windows(2) {
        assert!(
            pair[1] <= pair[0] * 1.05,
            "denoised error rose: {denoised_errors:?}"
        );
    }
    // 1/√rays: 2× less error per 4× the rays while the estimator's noise dominates (measured
    // 2.7× and 2.3×; at least 1.6× asserted); from 64 rays on the figure sits on the floor of
    // the reference's own noise (printed) and ~1 % of bias between the two formulations (the
    // terminator: the path tracer's shadow rays leave the flat triangles, the renderer's the
    // smooth surface), so the last step may only not rise beyond that floor's wobble (measured
    // 1.10 → 1.27 %, and 1.17 → 1.27 % with the earlier D·(N·H) sampler: the 256-ray figure is
    // the floor, whatever the sampler).
    assert!(errors[1] * 1.6 <= errors[0], "4 → 16 rays: {errors:?}");
    assert!(errors[2] * 1.6 <= errors[1], "16 → 64 rays: {errors:?}");
    assert!(errors[3] <= errors[2] * 1.25, "64 → 256 rays: {errors:?}");
    assert!(
        errors[3] <= 0.02,
        "rays 256: {:.2} % > 2 %",
        100.0 * errors[3]
    );
}

/// Paths per pixel of the reference: its noise (printed) must stay well below the 2 % bound.
const REFERENCE_PATHS: u32 = 8192;
