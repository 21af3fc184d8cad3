//! The raster path (mesh.vert, gbuffer.frag, coverage.frag and shade.frag on lavapipe) against the CPU oracle's ray-cast of the
//! analytic shapes, pixel by pixel, at one sample per pixel.

use crate::common;

use common::{assert_no_validation_messages, quantile, validated_gpu, write_failure_images};
use glam::DVec3;
use shikki::environment::params::ViewBlur;
use shikki::gpu::GpuContext;
use shikki::model::LacquerMaterial;
use shikki::oracle::{self, intersect, AnalyticShape, OracleScene};
use shikki::output::HdrImage;
use shikki::raster::camera::Camera;
use shikki::raster::draw::{Background, DrawObject, DrawScene, LacquerRenderer, RenderSettings};
use shikki::raster::lights::Light;
use shikki::raster::mesh::{self, Mesh};

/// Radiance below this is compared absolutely: 1e-4 is a third of one 8-bit sRGB code at exposure
/// 0 (sRGB(1e-4) ≈ 0.0013 = 0.33/255), invisible, and keeps the terminator (nl → 0, where the
/// tessellated normal's 7.5e-5 rad deviation is a large *relative* error) from dominating.
const RADIANCE_FLOOR: f64 = 1e-4;

/// The bound: relative error ≤ 1 % at the 99th percentile of interior pixels.
const P99_BOUND: f64 = 0.01;

fn test_lights() -> Vec<Light> {
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

/// Interior pixels: the oracle's rays through the pixel's four corners and the centres of its
/// eight neighbours all hit the analytic shape. That excludes every pixel the exact silhouette
/// touches plus one ring, which covers the tessellated sphere's silhouette (at most 7.5e-5 of the
/// radius inside the exact one, ≈ 0.01 px here) and rasterisation's edge rules.
fn interior_mask(shape: AnalyticShape, camera: &Camera, w: u32, h: u32) -> Vec<bool> {
    let hits =
        |px: f64, py: f64| intersect(shape, camera.eye, camera.primary_ray(px, py, w, h)).is_some();
    let mut mask = vec![false; (w * h) as usize];
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let (fx, fy) = (f64::from(x), f64::from(y));
            let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .all(|(dx, dy)| hits(fx + dx, fy + dy));
            let neighbours = (-1..=1).all(|dy| {
                (-1..=1).all(|dx| hits(fx + 0.5 + f64::from(dx), fy + 0.5 + f64::from(dy)))
            });
            mask[(y * w + x) as usize] = corners && neighbours;
        }
    }
    mask
}

struct Comparison {
    interior: usize,
    p99: f64,
    max: f64,
}

/// Per pixel: max over channels of |gpu − oracle| / max(oracle, RADIANCE_FLOOR).
fn compare(gpu: &HdrImage, oracle: &HdrImage, mask: &[bool]) -> Comparison {
    let mut errors = Vec::new();
    for ((g, o), &inside) in gpu.pixels.iter().zip(&oracle.pixels).zip(mask) {
        if !inside {
            continue;
        }
        assert_eq!(
            g[3], 1.0,
            "an interior pixel is not covered by the GPU draw"
        );
        let err = (0..3)
            .map(|c| {
                let (g, o) = (f64::from(g[c]), f64::from(o[c]));
                (g - o).abs() / o.max(RADIANCE_FLOOR)
            })
            .fold(0.0, f64::max);
        errors.push(err);
    }
    let interior = errors.len();
    let max = errors.iter().copied().fold(0.0, f64::max);
    Comparison {
        interior,
        p99: quantile(&mut errors, 0.99),
        max,
    }
}

fn render_both(
    gpu: &GpuContext,
    name: &str,
    shape: AnalyticShape,
    mesh: &Mesh,
    camera: &Camera,
    preset: &str,
    size: u32,
) {
    let material = LacquerMaterial::preset(preset).unwrap();
    let brdf = material.brdf_params().unwrap();
    let fresnel = material.fresnel_table().unwrap();
    let lights = test_lights();
    let actual = LacquerRenderer::new()
        .render(
            gpu,
            &DrawScene {
                objects: &[DrawObject {
                    mesh,
                    brdf: &brdf,
                    fresnel: &fresnel,
                    view_blur: ViewBlur::default(),
                }],
                camera,
                lights: &lights,
                environment: None,
                environment_model: Default::default(),
                ray_tracing: None,
                background: Background::Transparent,
            },
            &RenderSettings {
                width: size,
                height: size,
                samples: 1,
            },
        )
        .unwrap();
    let expected = oracle::render(
        &OracleScene {
            shape,
            camera,
            lights: &lights,
            brdf: &brdf,
            fresnel: &fresnel,
        },
        size,
        size,
    );
    assert!(
        actual.pixels.iter().flatten().all(|v| v.is_finite()),
        "{name}: non-finite pixel"
    );
    let mask = interior_mask(shape, camera, size, size);
    let result = compare(&actual, &expected, &mask);
    eprintln!(
        "{name}: {} interior pixels, relative error p99 {:.2e}, max {:.2e}",
        result.interior, result.p99, result.max
    );
    if result.p99 > P99_BOUND {
        write_failure_images(name, &actual, &expected);
    }
    assert!(
        result.interior > 2_000,
        "{name}: only {} interior pixels",
        result.interior
    );
    assert!(
        result.p99 <= P99_BOUND,
        "{name}: p99 relative error {:.3e} > {P99_BOUND}",
        result.p99
    );
    assert_no_validation_messages(gpu);
}

#[test]
fn sphere_matches_oracle_smooth_black_and_rough_red() {
    let gpu = validated_gpu();
    let sphere = mesh::sphere(256, 128);
    let camera = Camera::default();
    for preset in ["smooth-black", "rough-red"] {
        render_both(
            &gpu,
            &format!("sphere-{preset}"),
            AnalyticShape::Sphere,
            &sphere,
            &camera,
            preset,
            512,
        );
    }
}

#[test]
fn board_matches_oracle_from_three_elevations() {
    let gpu = validated_gpu();
    let board = mesh::board();
    for elevation_deg in [10.0f64, 45.0, 80.0] {
        let t = elevation_deg.to_radians();
        // Angle between the view direction and the board's normal (+Y).
        let camera = Camera {
            eye: DVec3::new(0.0, 4.0 * t.cos(), 4.0 * t.sin()),
            target: DVec3::ZERO,
            up: DVec3::new(0.0, 0.0, -1.0)
                .lerp(DVec3::Y, t.sin())
                .normalize(),
            fov_deg: 35.0,
        };
        for preset in ["smooth-black", "rough-red"] {
            render_both(
                &gpu,
                &format!("board-{elevation_deg}deg-{preset}"),
                AnalyticShape::Board,
                &board,
                &camera,
                preset,
                512,
            );
        }
    }
}
