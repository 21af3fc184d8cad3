//! The deferred lacquer draw (G-buffer pass, coverage depth, shading pass limited to the meshes'
//! screen bounds) against the forward rasteriser (trivial.frag with an MSAA resolve) on the same
//! geometry: which samples are covered and what fills the rest must not depend on how the pixels
//! are shaded.
//!
//! Every number compared here is exact on both paths, so the tests compare bit for bit:
//! - alpha is the covered fraction of a pixel's samples, k/4 (or 0/1), in both: the forward
//!   resolve averages 1.0 and 0.0 samples, the shading pass sums one per covered sample and
//!   divides by the sample count;
//! - a pixel no mesh covers is the clear colour or the sharp environment along the same ray, from
//!   the same GLSL (frame.glsl's camera_ray and sharp_radiance) on both paths.

use crate::common;
use shikki::environment::EnvironmentLight;

use common::{assert_no_validation_messages, synthetic_environment, validated_gpu};
use glam::DVec3;
use shikki::environment::gpu::{GpuEnvironment, GpuPrefilter};
use shikki::environment::params::{PrefilterParams, ViewBlur};
use shikki::gpu::GpuContext;
use shikki::model::LacquerMaterial;
use shikki::output::HdrImage;
use shikki::raster::draw::{
    Background, DrawObject, DrawOptions, DrawScene, LacquerRenderer, MeshShading, RenderSettings,
};
use shikki::raster::{BuiltinMesh, Camera, GpuMesh, Mesh};

/// A bowl in front, and a 20 × 20 board reaching behind the camera, so that one object's screen
/// bounds are a small rectangle and the other's the whole image (a box corner behind the eye).
fn meshes() -> Vec<Mesh> {
    let bowl = BuiltinMesh::Bowl.mesh();
    let mut floor = BuiltinMesh::Board.mesh();
    for p in &mut floor.positions {
        p[0] *= 10.0;
        p[2] *= 10.0;
        p[1] -= 0.05;
    }
    vec![bowl, floor]
}

fn camera() -> Camera {
    Camera {
        eye: DVec3::new(0.4, 0.9, 2.6),
        target: DVec3::new(0.0, 0.3, 0.0),
        up: DVec3::Y,
        fov_deg: 35.0,
    }
}

/// A small prefiltered test environment (also the shading-pass tests' in `surfaces.rs`).
pub(super) fn environment(gpu: &GpuContext) -> GpuEnvironment {
    let params = PrefilterParams {
        face_size: 32,
        layers: 4,
        ..PrefilterParams::for_source_width(128)
    };
    GpuPrefilter::new(gpu)
        .expect("prefilter pipelines")
        .run(
            gpu,
            &synthetic_environment(128, 64),
            &params,
            EnvironmentLight::default(),
        )
        .expect("prefiltered environment")
}

/// Renders `meshes` (only the first `objects` of them) with both shadings.
fn render_both(
    gpu: &GpuContext,
    objects: usize,
    background: Background,
    environment: Option<&GpuEnvironment>,
    settings: RenderSettings,
) -> (HdrImage, HdrImage) {
    let meshes = meshes();
    let material = LacquerMaterial::preset("smooth-red").unwrap();
    let (brdf, fresnel) = (
        material.brdf_params().unwrap(),
        material.fresnel_table().unwrap(),
    );
    let draw_objects: Vec<DrawObject> = meshes[..objects]
        .iter()
        .map(|mesh| DrawObject {
            mesh,
            brdf: &brdf,
            fresnel: &fresnel,
            view_blur: ViewBlur::of(&material),
        })
        .collect();
    let gpu_meshes: Vec<GpuMesh> = meshes[..objects]
        .iter()
        .map(|m| GpuMesh::upload(gpu, m).unwrap())
        .collect();
    let gpu_meshes: Vec<&GpuMesh> = gpu_meshes.iter().collect();
    let camera = camera();
    let lights = shikki::raster::default_lights();
    let scene = DrawScene {
        objects: &draw_objects,
        camera: &camera,
        lights: &lights,
        environment,
        environment_model: Default::default(),
        ray_tracing: None,
        background,
    };
    let mut renderer = LacquerRenderer::new();
    let mut render = |shading| {
        let options = DrawOptions {
            shading,
            ..DrawOptions::default()
        };
        renderer
            .render_meshes(gpu, &scene, &gpu_meshes, &settings, options)
            .unwrap()
            .0
    };
    (render(MeshShading::Lacquer), render(MeshShading::Trivial))
}

fn assert_same_alpha(deferred: &HdrImage, forward: &HdrImage, what: &str) -> usize {
    let mut partial = 0;
    for (i, (d, f)) in deferred.pixels.iter().zip(&forward.pixels).enumerate() {
        assert_eq!(
            d[3],
            f[3],
            "{what}: pixel ({}, {}) covered {} (deferred) vs {} (forward)",
            i as u32 % deferred.width,
            i as u32 / deferred.width,
            d[3],
            f[3]
        );
        if d[3] > 0.0 && d[3] < 1.0 {
            partial += 1;
        }
    }
    partial
}

/// Coverage is the rasteriser's: per pixel, the deferred draw's alpha equals the forward draw's,
/// with 4× MSAA (partly covered pixels at k/4), without, with the bowl alone (its screen bounds
/// limit the shading pass) and with the floor (bounds of the whole image), in an image 2048 wide
/// so that a 4× MSAA draw takes three strips.
#[test]
fn deferred_coverage_is_the_rasterisers() {
    let gpu = validated_gpu();
    for (objects, samples, width, height) in
        [(1, 4, 2048, 300), (2, 4, 2048, 300), (2, 1, 320, 240)]
    {
        let settings = RenderSettings {
            width,
            height,
            samples,
        };
        let (deferred, forward) =
            render_both(&gpu, objects, Background::Transparent, None, settings);
        let what = format!("{objects} object(s), {samples} sample(s)");
        let partial = assert_same_alpha(&deferred, &forward, &what);
        let covered = forward.pixels.iter().filter(|p| p[3] > 0.0).count();
        assert!(
            covered > 2000,
            "{what}: the meshes cover the image ({covered} pixels)"
        );
        if samples == 4 {
            // The test must see silhouettes, where the shading pass blends surfaces and the
            // uncovered samples' background.
            assert!(partial > 200, "{what}: {partial} partly covered pixels");
        }
        // No shading may leak into what no sample covers, nor be missing where one does.
        for (d, f) in deferred.pixels.iter().zip(&forward.pixels) {
            if f[3] == 0.0 {
                assert_eq!(
                    *d, [0.0; 4],
                    "{what}: an uncovered pixel is not transparent"
                );
            }
            assert!(
                d.iter().all(|c| c.is_finite()),
                "{what}: non-finite pixel {d:?}"
            );
        }
    }
    assert_no_validation_messages(&gpu);
}

/// What no sample covers is the background on both paths: the clear colour, or the sharp
/// environment along the pixel's ray, inside and outside the meshes' screen bounds.
#[test]
fn deferred_background_is_the_forward_background() {
    let gpu = validated_gpu();
    let env = environment(&gpu);
    let settings = RenderSettings {
        width: 256,
        height: 192,
        samples: 4,
    };
    let (coverage, _) = render_both(&gpu, 1, Background::Transparent, Some(&env), settings);
    let uncovered: Vec<usize> = (0..coverage.pixels.len())
        .filter(|&i| coverage.pixels[i][3] == 0.0)
        .collect();
    assert!(
        uncovered.len() > 10_000,
        "the bowl leaves background around it"
    );
    let colour = [0.25, 0.5, 0.125];
    let (deferred, forward) = render_both(&gpu, 1, Background::Color(colour), Some(&env), settings);
    for &i in &uncovered {
        assert_eq!(
            deferred.pixels[i],
            [0.25, 0.5, 0.125, 1.0],
            "colour at pixel {i}"
        );
        assert_eq!(forward.pixels[i], deferred.pixels[i], "colour at pixel {i}");
    }
    let (deferred, forward) = render_both(&gpu, 1, Background::Environment, Some(&env), settings);
    for &i in &uncovered {
        assert_eq!(
            deferred.pixels[i], forward.pixels[i],
            "environment at pixel {i}"
        );
        assert!(deferred.pixels[i][..3].iter().any(|&c| c > 0.0));
    }
    // Covered pixels are opaque against either opaque background.
    assert!(deferred.pixels.iter().all(|p| p[3] == 1.0));
    assert_no_validation_messages(&gpu);
}

/// The shading pass has two Fresnel lookups: without a search when every table's knots lie on a
/// power-of-two grid (the built-in tables: a knot per degree), and the general one with its
/// check and binary search. The same curve given with an extra knot at 0.5° (off any grid, its
/// value the linear interpolation there) must render the same image to rounding: 1e-5 relative,
/// where the two lookups differ only in which pair of knots the interpolation starts from.
#[test]
fn fresnel_lookup_without_search_matches_the_general_one() {
    let gpu = validated_gpu();
    let material = LacquerMaterial::preset("smooth-black").unwrap();
    let brdf = material.brdf_params().unwrap();
    let on_grid = material.fresnel_table().unwrap();
    let mut angles = on_grid.angles_deg().to_vec();
    let mut rgb = on_grid.rgb().to_vec();
    let mid = [0, 1, 2].map(|c| 0.5 * (rgb[0][c] + rgb[1][c]));
    angles.insert(1, 0.5);
    rgb.insert(1, mid);
    let off_grid = shikki::model::FresnelTable::new(angles, rgb).unwrap();
    let mesh = BuiltinMesh::Bowl.mesh();
    let env = environment(&gpu);
    let camera = camera();
    let lights = shikki::raster::default_lights();
    let settings = RenderSettings {
        width: 160,
        height: 120,
        samples: 4,
    };
    let mut renderer = LacquerRenderer::new();
    let mut render = |fresnel| {
        let objects = [DrawObject {
            mesh: &mesh,
            brdf: &brdf,
            fresnel,
            view_blur: ViewBlur::of(&material),
        }];
        let scene = DrawScene {
            objects: &objects,
            camera: &camera,
            lights: &lights,
            environment: Some(&env),
            environment_model: Default::default(),
            ray_tracing: None,
            background: Background::Transparent,
        };
        renderer.render(&gpu, &scene, &settings).unwrap()
    };
    let (grid, general) = (render(&on_grid), render(&off_grid));
    let mut lit = 0;
    for (i, (a, b)) in grid.pixels.iter().zip(&general.pixels).enumerate() {
        assert_eq!(a[3], b[3], "coverage of pixel {i}");
        for c in 0..3 {
            let scale = a[c].abs().max(b[c].abs()).max(1e-4);
            assert!(
                (a[c] - b[c]).abs() <= 1e-5 * scale,
                "pixel {i} channel {c}: grid lookup {} vs general {}",
                a[c],
                b[c]
            );
        }
        if a[3] > 0.0 && a[0] > 1e-3 {
            lit += 1;
        }
    }
    assert!(lit > 1000, "the bowl is lit ({lit} pixels)");
    assert_no_validation_messages(&gpu);
}
