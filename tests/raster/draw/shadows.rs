//! Lights with visibility (SPEC §6): the ray-traced shading pass (gbuffer_rt.frag, shade_rt.frag
//! with ray queries against the draw's acceleration structures) against its CPU twin
//! (`oracle::shadows`: the same triangles through a BVH, the same ray origins), pixel by pixel at
//! one sample per pixel; and the cases the ray origin must get right: grazing light on a board
//! (no acne), a sphere touching a board (no leak), a lone convex object (nothing changes).
//! Skipped, with a line on stderr, on a device without ray queries.

use crate::common;

use common::{assert_no_validation_messages, quantile, validated_gpu, write_failure_images};
use glam::{DMat4, DVec3};
use shikki::environment::gpu::GpuEnvironment;
use shikki::environment::params::ViewBlur;
use shikki::environment::EnvironmentModel;
use shikki::gpu::{ContextOptions, GpuContext, RayTracingChoice};
use shikki::model::{BrdfParams, FresnelTable, LacquerMaterial};
use shikki::oracle::shadows::{TracedObject, TracedScene};
use shikki::output::HdrImage;
use shikki::raster::camera::Camera;
use shikki::raster::draw::{
    Background, DrawObject, DrawScene, LacquerRenderer, RayTracing, RenderSettings,
};
use shikki::raster::lights::Light;
use shikki::raster::mesh::{self, BuiltinMesh, Mesh};
use shikki::raster::mesh_io::transform_mesh;

/// Radiance below this is compared absolutely (as in forward.rs: a third of one 8-bit code).
pub(super) const RADIANCE_FLOOR: f64 = 1e-4;

/// GPU (f32 shading) against the twin (f64 BRDF, f32 geometry) where both see the same lights:
/// forward.rs measures the shading alone at p99 ≤ 2e-4 on these presets; 1e-3 (the bound
/// for the twin) leaves room for the terminator, where nl → 0 magnifies rounding.
const P99_BOUND: f64 = 1e-3;

/// A shadow ray grazing an occluder's edge may hit on one side and miss on the other (lavapipe's
/// triangle test against the twin's watertight one): at most this fraction of covered pixels may
/// disagree on a light (each such pixel differs by that light's whole contribution).
const EDGE_DISAGREEMENT: f64 = 0.003;

pub(super) fn gpu_or_skip() -> Option<GpuContext> {
    let gpu = validated_gpu();
    if !gpu.info().ray_query.is_enabled() {
        eprintln!(
            "skipped: {} has no ray queries ({})",
            gpu.info().name,
            gpu.info().ray_query.summary()
        );
        return None;
    }
    Some(gpu)
}

/// A validated context that traces rays by a ray-tracing pipeline even where the device has ray
/// queries (`RayTracingChoice::Pipeline`, the path of NVIDIA's H100/H200, which have no ray
/// queries); None, with a line on stderr, where the device has no ray-tracing pipelines.
pub(super) fn ray_pipeline_gpu_or_skip() -> Option<GpuContext> {
    let gpu = GpuContext::new(&ContextOptions {
        validation: true,
        synchronization_validation: true,
        device_name: std::env::var("SHIKKI_DEVICE").ok(),
        ray_tracing: RayTracingChoice::Pipeline,
        ..ContextOptions::default()
    })
    .expect("a validated Vulkan context");
    if !gpu.info().ray_query.uses_pipeline() {
        eprintln!(
            "skipped: {} has no ray-tracing pipelines ({})",
            gpu.info().name,
            gpu.info().ray_query.summary()
        );
        return None;
    }
    Some(gpu)
}

pub(super) struct Material {
    pub brdf: BrdfParams,
    pub fresnel: FresnelTable,
}

pub(super) fn material(preset: &str) -> Material {
    let m = LacquerMaterial::preset(preset).unwrap();
    Material {
        brdf: m.brdf_params().unwrap(),
        fresnel: m.fresnel_table().unwrap(),
    }
}

/// A sphere of radius 0.5 resting on the board (scaled to 3 × 3) at the origin.
pub(super) fn sphere_on_board() -> Vec<Mesh> {
    let sphere = transform_mesh(
        &mesh::sphere(128, 64),
        DMat4::from_translation(DVec3::new(0.0, 0.5, 0.0)) * DMat4::from_scale(DVec3::splat(0.5)),
    );
    let board = transform_mesh(&mesh::board(), DMat4::from_scale(DVec3::new(1.5, 1.0, 1.5)));
    vec![sphere, board]
}

/// A bowl with a smaller bowl inside it: concave self-shadowing and shadows between the two.
pub(super) fn bowl_in_bowl() -> Vec<Mesh> {
    let outer = BuiltinMesh::Bowl.mesh_with_segments(96).unwrap();
    let inner = transform_mesh(
        &outer,
        DMat4::from_translation(DVec3::new(0.1, 0.25, 0.05))
            * DMat4::from_scale(DVec3::splat(0.45)),
    );
    vec![outer, inner]
}

pub(super) fn lights() -> Vec<Light> {
    vec![
        Light::Directional {
            to_light: DVec3::new(0.6, 0.7, 0.4).normalize(),
            irradiance: DVec3::new(2.0, 1.9, 1.8),
        },
        Light::Point {
            position: DVec3::new(-1.5, 2.0, 1.0),
            intensity: DVec3::new(5.0, 5.0, 5.5),
        },
    ]
}

pub(super) fn camera_looking_down() -> Camera {
    Camera {
        eye: DVec3::new(0.4, 2.6, 3.2),
        target: DVec3::new(0.0, 0.3, 0.0),
        up: DVec3::Y,
        fov_deg: 40.0,
    }
}

fn gpu_render(
    gpu: &GpuContext,
    meshes: &[Mesh],
    materials: &[&Material],
    view: (&Camera, &[Light]),
    size: u32,
    shadows: bool,
) -> HdrImage {
    // Shadows alone: SPEC §6's integral is tested in light_between.rs.
    let rt = shadows.then_some(RayTracing {
        shadows: true,
        bounces: 0,
        rays: 1,
        seed: 0,
        denoise: false,
    });
    draw(
        gpu,
        (meshes, materials),
        view,
        (None, Default::default()),
        rt,
        size,
    )
}

/// The draw every test here and in light_between.rs makes: `meshes[i]` in `materials[i]`, one
/// sample per pixel, transparent background, validation checked.
pub(super) fn draw(
    gpu: &GpuContext,
    objects: (&[Mesh], &[&Material]),
    view: (&Camera, &[Light]),
    environment: (Option<&GpuEnvironment>, EnvironmentModel),
    ray_tracing: Option<RayTracing>,
    size: u32,
) -> HdrImage {
    let objects = draw_objects(objects);
    let image = LacquerRenderer::new()
        .render(
            gpu,
            &scene(&objects, view, environment, ray_tracing),
            &settings(size),
        )
        .unwrap();
    assert_no_validation_messages(gpu);
    image
}

/// The draw without the denoise and its integral image (`render_with_integral`).
pub(super) fn draw_with_integral(
    gpu: &GpuContext,
    objects: (&[Mesh], &[&Material]),
    view: (&Camera, &[Light]),
    environment: (Option<&GpuEnvironment>, EnvironmentModel),
    ray_tracing: Option<RayTracing>,
    size: u32,
) -> (HdrImage, Option<HdrImage>) {
    let objects = draw_objects(objects);
    let drawn = LacquerRenderer::new()
        .render_with_integral(
            gpu,
            &scene(&objects, view, environment, ray_tracing),
            &settings(size),
        )
        .unwrap();
    assert_no_validation_messages(gpu);
    drawn
}

pub(super) fn draw_objects<'a>(
    (meshes, materials): (&'a [Mesh], &[&'a Material]),
) -> Vec<DrawObject<'a>> {
    meshes
        .iter()
        .zip(materials)
        .map(|(mesh, m)| DrawObject {
            mesh,
            brdf: &m.brdf,
            fresnel: &m.fresnel,
            view_blur: ViewBlur::default(),
        })
        .collect()
}

pub(super) fn scene<'a>(
    objects: &'a [DrawObject<'a>],
    (camera, lights): (&'a Camera, &'a [Light]),
    (environment, environment_model): (Option<&'a GpuEnvironment>, EnvironmentModel),
    ray_tracing: Option<RayTracing>,
) -> DrawScene<'a> {
    DrawScene {
        objects,
        camera,
        lights,
        environment,
        environment_model,
        ray_tracing,
        background: Background::Transparent,
    }
}

pub(super) fn settings(size: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        samples: 1,
    }
}

/// `meshes[i]` in `materials[i]` as the CPU twins trace them.
pub(super) fn traced_objects<'a>(
    meshes: &'a [Mesh],
    materials: &[&'a Material],
) -> Vec<TracedObject<'a>> {
    meshes
        .iter()
        .zip(materials)
        .map(|(mesh, m)| TracedObject {
            mesh,
            brdf: &m.brdf,
            fresnel: &m.fresnel,
        })
        .collect()
}

fn twin_render(
    meshes: &[Mesh],
    materials: &[&Material],
    (camera, lights): (&Camera, &[Light]),
    size: u32,
    shadows: bool,
) -> HdrImage {
    TracedScene::new(&traced_objects(meshes, materials)).render(
        camera,
        lights,
        (size, size),
        shadows,
    )
}

/// Per pixel covered by both: max over channels of |a − b| / max(b, RADIANCE_FLOOR).
pub(super) fn relative_errors(a: &HdrImage, b: &HdrImage) -> Vec<f64> {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(a, b)| a[3] == 1.0 && b[3] == 1.0)
        .map(|(a, b)| {
            (0..3)
                .map(|c| {
                    let (a, b) = (f64::from(a[c]), f64::from(b[c]));
                    (a - b).abs() / b.max(RADIANCE_FLOOR)
                })
                .fold(0.0, f64::max)
        })
        .collect()
}

/// Pixels where `a` and `b` differ by more than rounding.
fn changed_pixels(a: &HdrImage, b: &HdrImage) -> usize {
    relative_errors(a, b).iter().filter(|&&e| e > 1e-3).count()
}

fn compare_with_twin(
    name: &str,
    meshes: &[Mesh],
    materials: &[&Material],
    camera: &Camera,
    size: u32,
) {
    let Some(gpu) = gpu_or_skip() else { return };
    let lights = lights();
    let view = (camera, lights.as_slice());
    let gpu_image = gpu_render(&gpu, meshes, materials, view, size, true);
    let twin = twin_render(meshes, materials, view, size, true);
    let unshadowed = twin_render(meshes, materials, view, size, false);
    assert!(
        gpu_image.pixels.iter().flatten().all(|v| v.is_finite()),
        "{name}: non-finite pixel"
    );
    let mut errors = relative_errors(&gpu_image, &twin);
    let covered = errors.len();
    let shadowed = changed_pixels(&twin, &unshadowed);
    let disagreeing = errors.iter().filter(|&&e| e > 0.05).count();
    let p99 = quantile(&mut errors, 0.99);
    eprintln!(
        "{name}: {covered} covered pixels, {shadowed} in some shadow (twin), GPU vs twin p99 \
         {p99:.2e}, {disagreeing} pixels > 5% apart"
    );
    if p99 > P99_BOUND || disagreeing as f64 > EDGE_DISAGREEMENT * covered as f64 {
        write_failure_images(name, &gpu_image, &twin);
    }
    // The scene must have shadows for the test to mean anything.
    assert!(
        shadowed as f64 > 0.05 * covered as f64,
        "{name}: only {shadowed} of {covered} pixels shadowed"
    );
    assert!(covered > 4_000, "{name}: only {covered} covered pixels");
    assert!(p99 <= P99_BOUND, "{name}: p99 {p99:.3e} > {P99_BOUND}");
    assert!(
        disagreeing as f64 <= EDGE_DISAGREEMENT * covered as f64,
        "{name}: {disagreeing} of {covered} pixels disagree on a shadow"
    );
}

#[test]
fn sphere_on_board_matches_its_cpu_twin() {
    let (red, black) = (material("smooth-red"), material("rough-black"));
    compare_with_twin(
        "shadows-sphere-on-board",
        &sphere_on_board(),
        &[&red, &black],
        &camera_looking_down(),
        128,
    );
}

#[test]
fn bowl_in_bowl_matches_its_cpu_twin() {
    let (red, black) = (material("smooth-red"), material("smooth-black"));
    let camera = Camera {
        eye: DVec3::new(0.3, 1.7, 1.3),
        target: DVec3::new(0.0, 0.2, 0.0),
        up: DVec3::Y,
        fov_deg: 45.0,
    };
    compare_with_twin(
        "shadows-bowl-in-bowl",
        &bowl_in_bowl(),
        &[&black, &red],
        &camera,
        128,
    );
}

/// A board alone under light 2° above its plane: no ray from it can meet anything, so every
/// pixel must be what the draw without ray tracing gives (no acne).
#[test]
fn a_board_under_grazing_light_has_no_acne() {
    let Some(gpu) = gpu_or_skip() else { return };
    let board = vec![mesh::board()];
    let black = material("smooth-black");
    let camera = camera_looking_down();
    let lights = vec![Light::Directional {
        to_light: DVec3::new(1.0, 2f64.to_radians().tan(), 0.3).normalize(),
        irradiance: DVec3::splat(3.0),
    }];
    let view = (&camera, lights.as_slice());
    let traced = gpu_render(&gpu, &board, &[&black], view, 128, true);
    let plain = gpu_render(&gpu, &board, &[&black], view, 128, false);
    let errors = relative_errors(&traced, &plain);
    assert!(errors.len() > 4_000);
    let worst = errors.iter().copied().fold(0.0, f64::max);
    assert!(worst <= 1e-6, "acne: a board pixel changed by {worst:.3e}");
}

/// The sphere touches the board at one point; with the light straight above, the board is dark
/// right up to the contact (no light leaks under the sphere) and lit outside the shadow disc.
#[test]
fn no_light_leaks_at_the_sphere_board_contact() {
    let Some(gpu) = gpu_or_skip() else { return };
    let meshes = sphere_on_board();
    let (red, black) = (material("smooth-red"), material("rough-black"));
    // Looking at the contact from low down, so the board next to it is visible.
    let camera = Camera {
        eye: DVec3::new(0.0, 0.35, 2.5),
        target: DVec3::new(0.0, 0.0, 0.0),
        up: DVec3::Y,
        fov_deg: 30.0,
    };
    let lights = vec![Light::Directional {
        to_light: DVec3::Y,
        irradiance: DVec3::splat(3.0),
    }];
    let size = 128;
    let image = gpu_render(
        &gpu,
        &meshes,
        &[&red, &black],
        (&camera, &lights),
        size,
        true,
    );
    // Board pixels: the twin's primary ray hits the board (object 1) at a point; inside the
    // sphere's shadow disc (|xz| < 0.5, less a pixel's footprint) the board must be black.
    let objects = [
        TracedObject {
            mesh: &meshes[0],
            brdf: &red.brdf,
            fresnel: &red.fresnel,
        },
        TracedObject {
            mesh: &meshes[1],
            brdf: &black.brdf,
            fresnel: &black.fresnel,
        },
    ];
    let twin = TracedScene::new(&objects);
    let (mut in_shadow, mut lit) = (0, 0);
    for y in 0..size {
        for x in 0..size {
            let dir = camera.primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, size, size);
            let eye = camera.eye.as_vec3();
            let Some(hit) = twin.bvh().intersect(eye, dir.as_vec3(), 0.0, f32::INFINITY) else {
                continue;
            };
            if hit.object != 1 {
                continue;
            }
            let point = camera.eye + dir * f64::from(hit.t);
            let r = point.x.hypot(point.z);
            let radiance = image.pixels[(y * size + x) as usize];
            if r < 0.47 {
                in_shadow += 1;
                assert!(
                    radiance[..3].iter().all(|&v| v == 0.0),
                    "light leaks under the sphere at r = {r:.4}: {radiance:?}"
                );
            } else if r > 0.53 {
                lit += 1;
                assert!(
                    radiance[0] > 0.0,
                    "board unlit outside the shadow at r = {r:.4}"
                );
            }
        }
    }
    assert!(
        in_shadow > 200 && lit > 200,
        "{in_shadow} shadowed, {lit} lit"
    );
}

/// A lone sphere: nothing else for its shadow rays to meet, so the image is the one without ray
/// tracing. A ray grazing the terminator (N·L → 0) that dips under its flat face meets no
/// triangle of the sphere either: a convex mesh stands for the smooth surface its normals
/// describe (raster/self_hits.rs). Before that rule 1 pixel of 6,460 changed, by 0.5 %.
#[test]
fn a_lone_sphere_renders_as_without_ray_tracing() {
    let Some(gpu) = gpu_or_skip() else { return };
    let sphere = vec![mesh::sphere(128, 64)];
    let red = material("smooth-red");
    let camera = Camera::default();
    let lights = lights();
    let view = (&camera, lights.as_slice());
    let traced = gpu_render(&gpu, &sphere, &[&red], view, 128, true);
    let plain = gpu_render(&gpu, &sphere, &[&red], view, 128, false);
    let errors = relative_errors(&traced, &plain);
    let changed = errors.iter().filter(|&&e| e > 1e-6).count();
    let worst = errors.iter().copied().fold(0.0, f64::max);
    eprintln!(
        "lone sphere: {} covered, {changed} changed by ray tracing, worst by {worst:.2e}",
        errors.len()
    );
    assert!(errors.len() > 4_000);
    assert!(
        changed == 0,
        "{changed} of {} pixels changed by ray tracing, worst by {worst:.3e}",
        errors.len()
    );
}
