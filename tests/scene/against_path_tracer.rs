//! The whole render of a scene (SceneRenderer: the `brdf` environment model of a real map, the
//! lights with their shadows, SPEC §6's integral of the light between objects, the denoise)
//! against the brute-force path tracer (`oracle::path_tracer`) under the same map: the issue's
//! sphere resting on a board, lit by the built-in studio and a directional light. The path
//! tracer reads the map's pixels and integrates the incoming light; the renderer reads its
//! prefiltered layers and integrates the difference the objects make: nothing but the scene is
//! shared. BENCHMARKS.md ("Against the path tracer on a real map") has the same at 64².

use std::path::Path;

use crate::common::{assert_no_validation_messages, validated_gpu};
use shikki::environment::{load_environment, EnvironmentSource};
use shikki::oracle::path_tracer::{self, PathEnvironment, PathImage, PathScene};
use shikki::oracle::shadows::TracedObject;
use shikki::output::HdrImage;
use shikki::raster::mesh_io::transform_mesh;
use shikki::scene::{parse_scene_str, EnvironmentSpec, MeshSource, Scene, SceneRenderer};

/// The issue's scene at 32², one sample per pixel (the path tracer shoots one ray through each
/// pixel centre), `brdf` model.
const SPHERE_ON_BOARD: &str = r#"
[camera]
eye = [0.4, 2.6, 3.2]
target = [0.0, 0.3, 0.0]
fov_deg = 40
[[object]]
mesh = "builtin:sphere"
scale = 0.5
translate = [0.0, 0.5, 0.0]
material = { preset = "smooth-red" }
[[object]]
mesh = "builtin:board"
scale = [1.5, 1.0, 1.5]
material = { preset = "smooth-black" }
[[light]]
kind = "dir"
to_light = [0.6, 0.7, 0.4]
irradiance = [2.0, 1.9, 1.8]
[environment]
source = "builtin:studio"
rotation_deg = 40
[render]
environment_model = "brdf"
[output]
size = "32x32"
samples = 1
"#;

/// Paths per pixel of the reference: its own noise (printed, ~1.3 %) is taken out of each
/// figure before the bound.
const REFERENCE_PATHS: u32 = 8192;

/// The path tracer's image of `scene` with `bounces` sampled reflections.
fn path_traced(scene: &Scene, bounces: u32) -> PathImage {
    let meshes: Vec<_> = scene
        .objects
        .iter()
        .map(|object| match &object.mesh {
            MeshSource::Builtin(builtin) => transform_mesh(&builtin.mesh(), object.transform),
            other => panic!("the scene has built-in meshes only, not {other:?}"),
        })
        .collect();
    let materials: Vec<_> = scene
        .objects
        .iter()
        .map(|o| {
            (
                o.material.brdf_params().unwrap(),
                o.material.fresnel_table().unwrap(),
            )
        })
        .collect();
    let objects: Vec<_> = meshes
        .iter()
        .zip(&materials)
        .map(|(mesh, (brdf, fresnel))| TracedObject {
            mesh,
            brdf,
            fresnel,
        })
        .collect();
    let EnvironmentSpec::Map {
        source: EnvironmentSource::Named(name),
        light,
    } = &scene.environment
    else {
        panic!("the scene names its map");
    };
    let image = load_environment(name).unwrap().image;
    path_tracer::render(
        &PathScene {
            objects: &objects,
            camera: &scene.camera,
            lights: &scene.lights,
            environment: PathEnvironment::Map {
                image: &image,
                light: *light,
            },
        },
        (scene.output.width, scene.output.height),
        bounces,
        REFERENCE_PATHS,
        3,
    )
}

/// Whole-image relative RMSE √(Σ (a − b)² / Σ b²) over every channel of the pixels both cover.
fn relative_rmse(image: &HdrImage, reference: &HdrImage) -> f64 {
    let (mut squares, mut norm) = (0.0, 0.0);
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        if a[3] == 1.0 && b[3] == 1.0 {
            for c in 0..3 {
                squares += (f64::from(a[c]) - f64::from(b[c])).powi(2);
                norm += f64::from(b[c]).powi(2);
            }
        }
    }
    (squares / norm).sqrt()
}

/// The reference's own noise as a relative RMSE: its standard errors against its values.
fn reference_noise(reference: &PathImage) -> f64 {
    let (mut noise, mut norm) = (0.0, 0.0);
    for (pixel, error) in reference.mean.pixels.iter().zip(&reference.std_error) {
        if pixel[3] == 1.0 {
            noise += 3.0 * error * error;
            norm += pixel[..3]
                .iter()
                .map(|&c| f64::from(c).powi(2))
                .sum::<f64>();
        }
    }
    (noise / norm).sqrt()
}

/// The issue's held-out bound at 256 rays, on the issue's scene under a real map (turned, so
/// that a light box's reflection in the board meets the sphere), one and two bounces:
/// whole-image relative RMSE beyond the reference's noise ≤ 3 %. Measured 2.7 / 2.8 % here
/// (32768 paths); what remains is mostly the sphere's shadow terminator, where the path
/// tracer's shadow rays leave the flat triangles and the renderer's the smooth surface, and the
/// quadrature of the `brdf` model at the light boxes' edges. The default rays' figure is
/// printed, not asserted: at 32² the denoise's 2-pixel blur spans the edges of the sphere's
/// shadow in the board's mirror image (7.7 % here; BENCHMARKS.md has it by resolution).
#[test]
fn the_sphere_on_a_board_under_a_map_agrees_with_the_path_tracer() {
    let gpu = validated_gpu();
    let scene = parse_scene_str(SPHERE_ON_BOARD, "sphere-on-board.toml", Path::new(".")).unwrap();
    if scene.render.ray_tracing_on(&gpu).is_none() {
        eprintln!("skipped: {} traces no rays", gpu.info().name);
        return;
    }
    let mut renderer = SceneRenderer::new(&gpu).unwrap();
    for bounces in [1, 2] {
        let reference = path_traced(&scene, bounces);
        let noise = reference_noise(&reference);
        eprintln!(
            "bounces {bounces}: path tracer, {REFERENCE_PATHS} paths: noise {:.2} %",
            100.0 * noise
        );
        for rays in [scene.render.rays, 256] {
            let mut scene = scene.clone();
            scene.render.bounces = bounces;
            scene.render.rays = rays;
            let image = renderer.render(&gpu, &scene).unwrap();
            assert_no_validation_messages(&gpu);
            let rmse = relative_rmse(&image, &reference.mean);
            let beyond_noise = (rmse * rmse - noise * noise).max(0.0).sqrt();
            eprintln!(
                "bounces {bounces}, rays {rays}: relative RMSE {:.2} % ({:.2} % beyond the \
                 reference's noise)",
                100.0 * rmse,
                100.0 * beyond_noise
            );
            assert!(
                rays != 256 || beyond_noise <= 0.03,
                "bounces {bounces}, rays {rays}: {:.2} % > 3 %",
                100.0 * beyond_noise
            );
        }
    }
}
