//! Rendering the fitted material matches rendering the source material (issue 6, acceptance),
//! with the core issue's image metric: p99 over covered pixels of the per-pixel maximum over
//! channels of |fitted − source| / max(source, 1e-4) must be ≤ 1 %. The fitted material goes
//! through its files (TOML + Fresnel CSV) and [`load_material_file`], as `render` will read it,
//! and uses the default normalisation (f(1) = g(1) = 1), so its parameters differ from the
//! source's while the product k_d·g·f — what renders — must not. Checked on the CPU oracle and on
//! the GPU raster path with a validated Vulkan context.

use crate::common;

use common::{assert_no_validation_messages, quantile, validated_gpu, write_failure_images};
use glam::DVec3;
use shikki::environment::params::ViewBlur;
use shikki::fit::synth::{synthesize, Noise, DEFAULT_RATIOS};
use shikki::fit::{fit_measurements, FitOptions};
use shikki::model::material_file::{load_material_file, material_to_toml};
use shikki::model::{BrdfParams, FresnelTable, LacquerMaterial};
use shikki::oracle::{self, AnalyticShape, OracleScene};
use shikki::output::HdrImage;
use shikki::raster::camera::Camera;
use shikki::raster::draw::{Background, DrawObject, DrawScene, LacquerRenderer, RenderSettings};
use shikki::raster::lights::Light;
use shikki::raster::mesh;

/// The core issue's floor and bound (tests/raster/draw/forward.rs).
const RADIANCE_FLOOR: f64 = 1e-4;
const P99_BOUND: f64 = 0.01;
const SIZE: u32 = 128;

fn lights() -> Vec<Light> {
    vec![
        Light::Directional {
            to_light: DVec3::new(1.0, 1.0, 1.0).normalize(),
            irradiance: DVec3::new(1.5, 1.4, 1.3),
        },
        Light::Directional {
            to_light: DVec3::new(-1.0, 0.3, 0.6).normalize(),
            irradiance: DVec3::new(0.4, 0.45, 0.5),
        },
        Light::Point {
            position: DVec3::new(-0.5, 2.5, 2.5),
            intensity: DVec3::new(6.0, 6.0, 6.5),
        },
    ]
}

/// Fits data of `preset` with `noise`, writes the material files into `dir`, reads them back.
fn fitted_material(preset: &str, noise: f64, dir: &std::path::Path) -> LacquerMaterial {
    let source = LacquerMaterial::preset(preset).unwrap();
    let noise = Noise {
        relative: noise,
        seed: 1,
    };
    let (data, _) = synthesize(&source, &DEFAULT_RATIOS, noise).unwrap();
    let fit = fit_measurements(&data, &FitOptions::default()).unwrap();
    let toml_path = dir.join(format!("{preset}.toml"));
    let csv_name = format!("{preset}.fresnel.csv");
    std::fs::write(dir.join(&csv_name), fit.fresnel.to_csv()).unwrap();
    std::fs::write(&toml_path, material_to_toml(&fit.material, Some(&csv_name))).unwrap();
    let material = load_material_file(&toml_path).unwrap();
    // The split really differs from the source's (the test would be vacuous otherwise).
    assert!((material.diffuse_b - source.diffuse_b).abs() > 1e-3);
    material
}

/// p99 and max of the metric over pixels both images cover.
fn compare(name: &str, fitted: &HdrImage, source: &HdrImage) -> f64 {
    let mut errors = Vec::new();
    for (f, s) in fitted.pixels.iter().zip(&source.pixels) {
        assert_eq!(f[3], s[3], "{name}: coverage differs");
        if s[3] < 1.0 {
            continue;
        }
        let e = (0..3)
            .map(|c| {
                (f64::from(f[c]) - f64::from(s[c])).abs() / f64::from(s[c]).max(RADIANCE_FLOOR)
            })
            .fold(0.0, f64::max);
        errors.push(e);
    }
    assert!(
        errors.len() > 5_000,
        "{name}: only {} covered pixels",
        errors.len()
    );
    let max = errors.iter().copied().fold(0.0, f64::max);
    let p99 = quantile(&mut errors, 0.99);
    eprintln!("{name}: p99 {p99:.2e}, max {max:.2e}");
    if p99 > P99_BOUND {
        write_failure_images(name, fitted, source);
    }
    p99
}

fn parts(material: &LacquerMaterial) -> (BrdfParams, FresnelTable) {
    (
        material.brdf_params().unwrap(),
        material.fresnel_table().unwrap(),
    )
}

#[test]
fn fitted_material_renders_like_the_source_on_the_oracle_and_the_gpu() {
    let dir = tempfile::tempdir().unwrap();
    let gpu = validated_gpu();
    let sphere = mesh::sphere(256, 128);
    let camera = Camera::default();
    let lights = lights();
    for preset in ["smooth-red", "rough-black"] {
        let fitted = parts(&fitted_material(preset, 0.0, dir.path()));
        let source = parts(&LacquerMaterial::preset(preset).unwrap());

        let oracle_render = |(brdf, fresnel): &(BrdfParams, FresnelTable)| {
            let scene = OracleScene {
                shape: AnalyticShape::Sphere,
                camera: &camera,
                lights: &lights,
                brdf,
                fresnel,
            };
            oracle::render(&scene, SIZE, SIZE)
        };
        let p99 = compare(
            &format!("fit-oracle-{preset}"),
            &oracle_render(&fitted),
            &oracle_render(&source),
        );
        assert!(p99 <= P99_BOUND, "oracle {preset}: p99 {p99}");

        let mut renderer = LacquerRenderer::new();
        let mut gpu_render = |(brdf, fresnel): &(BrdfParams, FresnelTable)| {
            let objects = [DrawObject {
                mesh: &sphere,
                brdf,
                fresnel,
                view_blur: ViewBlur::default(),
            }];
            let scene = DrawScene {
                objects: &objects,
                camera: &camera,
                lights: &lights,
                environment: None,
                environment_model: Default::default(),
                ray_tracing: None,
                background: Background::Transparent,
            };
            let settings = RenderSettings {
                width: SIZE,
                height: SIZE,
                samples: 1,
            };
            renderer.render(&gpu, &scene, &settings).unwrap()
        };
        let (fitted_image, source_image) = (gpu_render(&fitted), gpu_render(&source));
        let p99 = compare(&format!("fit-gpu-{preset}"), &fitted_image, &source_image);
        assert!(p99 <= P99_BOUND, "GPU {preset}: p99 {p99}");
        assert_no_validation_messages(&gpu);
    }
}

#[test]
fn material_fitted_from_noisy_data_renders_within_the_metric() {
    // 2 % noise moves m, f, g by < 1e-3 and F by < 0.005 (tests/fit/recovery.rs); rendered, that
    // stays inside the 1 % bound (oracle only: the GPU path is checked above).
    let dir = tempfile::tempdir().unwrap();
    let camera = Camera::default();
    let lights = lights();
    for preset in ["smooth-red", "rough-black"] {
        let fitted = parts(&fitted_material(preset, 0.02, dir.path()));
        let source = parts(&LacquerMaterial::preset(preset).unwrap());
        let render = |(brdf, fresnel): &(BrdfParams, FresnelTable)| {
            let scene = OracleScene {
                shape: AnalyticShape::Sphere,
                camera: &camera,
                lights: &lights,
                brdf,
                fresnel,
            };
            oracle::render(&scene, SIZE, SIZE)
        };
        let p99 = compare(
            &format!("fit-noisy-{preset}"),
            &render(&fitted),
            &render(&source),
        );
        assert!(p99 <= P99_BOUND, "noisy {preset}: p99 {p99}");
    }
}
