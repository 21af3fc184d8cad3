//! Every scene in examples/ parses and renders (at 64², one sample) with a check that can fail:
//! the analytic sphere and board against the CPU oracle, the others by image statistics.

use crate::common;

use common::{assert_no_validation_messages, validated_gpu, write_failure_images};
use shikki::oracle::{self, intersect, AnalyticShape, OracleScene};
use shikki::output::HdrImage;
use shikki::scene::{MeshSource, Scene, SceneDocument, SceneRenderer};
use std::path::{Path, PathBuf};

const SIZE: u32 = 64;

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples")
}

fn small(path: &Path) -> Scene {
    let mut document = SceneDocument::load(path).unwrap();
    for set in [
        format!("output.size={SIZE}x{SIZE}"),
        "output.samples=1".into(),
    ] {
        document.set(&set, Path::new(".")).unwrap();
    }
    document.build().unwrap()
}

/// Relative error of the GPU against the oracle over pixels whose centre and 4 neighbours' centres
/// hit the analytic shape (edges excluded: rasterisation rules and tessellation differ there).
fn oracle_errors(scene: &Scene, shape: AnalyticShape, actual: &HdrImage) -> (usize, f64, f64) {
    let material = &scene.objects[0].material;
    let expected = oracle::render(
        &OracleScene {
            shape,
            camera: &scene.camera,
            lights: &scene.lights,
            brdf: &material.brdf_params().unwrap(),
            fresnel: &material.fresnel_table().unwrap(),
        },
        SIZE,
        SIZE,
    );
    let hits = |x: f64, y: f64| {
        intersect(
            shape,
            scene.camera.eye,
            scene.camera.primary_ray(x, y, SIZE, SIZE),
        )
        .is_some()
    };
    let mut errors = Vec::new();
    for y in 1..SIZE - 1 {
        for x in 1..SIZE - 1 {
            let (fx, fy) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
            let inside = [(0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
                .iter()
                .all(|(dx, dy)| hits(fx + dx, fy + dy));
            if !inside {
                continue;
            }
            let (g, o) = (actual.get(x, y), expected.get(x, y));
            let err = (0..3)
                .map(|c| (f64::from(g[c]) - f64::from(o[c])).abs() / f64::from(o[c]).max(1e-4))
                .fold(0.0, f64::max);
            errors.push(err);
        }
    }
    errors.sort_by(f64::total_cmp);
    let p99 = errors[(errors.len() - 1) * 99 / 100];
    let max = *errors.last().unwrap();
    if p99 > 0.01 {
        write_failure_images(&format!("scene-example-{shape:?}"), actual, &expected);
    }
    (errors.len(), p99, max)
}

fn coverage(image: &HdrImage) -> f64 {
    image.pixels.iter().filter(|p| p[3] > 0.5).count() as f64 / image.pixels.len() as f64
}

#[test]
fn every_example_scene_renders_and_passes_its_check() {
    let gpu = validated_gpu();
    let mut renderer = SceneRenderer::new(&gpu).unwrap();
    let mut seen = Vec::new();
    for entry in std::fs::read_dir(examples()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !name.ends_with(".toml") || name.ends_with(".jobs.toml") {
            continue;
        }
        let scene = small(&path);
        let image = renderer.render(&gpu, &scene).unwrap();
        assert_no_validation_messages(&gpu);
        assert!(
            image.first_non_finite().is_none(),
            "{name}: non-finite pixel"
        );
        match name.as_str() {
            "sphere.toml" | "board.toml" => {
                let shape = if name == "sphere.toml" {
                    AnalyticShape::Sphere
                } else {
                    AnalyticShape::Board
                };
                let (count, p99, max) = oracle_errors(&scene, shape, &image);
                // The raster-vs-oracle bound of the core issue (1 % at the 99th percentile),
                // over at least a few hundred interior pixels so the percentile means something.
                assert!(count > 300, "{name}: only {count} interior pixels");
                assert!(p99 <= 0.01, "{name}: p99 relative error {p99} (max {max})");
            }
            "default.toml" => {
                // Environment background: every pixel opaque. A red bowl: some pixels clearly
                // red (R > 2·G, R > 2·B in radiance), and the black bowl/tray: dark pixels.
                assert_eq!(coverage(&image), 1.0, "{name}");
                let red = image
                    .pixels
                    .iter()
                    .filter(|p| p[0] > 2.0 * p[1] && p[0] > 2.0 * p[2] && p[0] > 0.02)
                    .count();
                assert!(red > 64, "{name}: {red} red pixels");
                assert!(image.pixels.iter().any(|p| p[0].max(p[1]).max(p[2]) < 0.02));
            }
            "plate-and-files.toml" => {
                // Files resolved relative to the scene: the OBJ and the material file loaded.
                assert!(
                    matches!(&scene.objects[1].mesh, MeshSource::File(p) if p.ends_with("meshes/tetra.obj"))
                );
                assert_eq!(scene.objects[0].material.lacquer_ratio, 3.0);
                assert!(scene.objects[0].material.fresnel_file.is_some());
                assert_eq!(
                    coverage(&image),
                    1.0,
                    "{name}: background is the environment"
                );
                let mean_r = image.pixels.iter().map(|p| f64::from(p[0])).sum::<f64>()
                    / image.pixels.len() as f64;
                assert!(mean_r > 0.0 && mean_r.is_finite());
            }
            other => panic!("examples/{other} has no check in tests/scene/examples.rs"),
        }
        seen.push(name);
    }
    seen.sort();
    assert_eq!(
        seen,
        [
            "board.toml",
            "default.toml",
            "plate-and-files.toml",
            "sphere.toml"
        ]
    );
}

#[test]
fn default_scene_is_the_shipped_example() {
    let shipped = small(&examples().join("default.toml"));
    let mut built = shikki::scene::default_scene();
    built.output.width = SIZE;
    built.output.height = SIZE;
    built.output.samples = 1;
    assert_eq!(format!("{shipped:?}"), format!("{built:?}"));
}
