//! The `brdf` environment model's specular term, as the renderer computes it (both bright splits,
//! the lattice, the grid and filtered importance sampling, the CPU twin of the shader), against
//! the brute-force integral over every pixel of a map (SPEC §4), on the geometry BENCHMARKS.md
//! reports ("The `brdf` environment model", "Maps the project has not tuned on"):
//!
//! - the issue's 112 points (tests/environment/brdf_model.rs): mean, p99 and relative RMSE;
//! - an orthographic sphere of 40 × 40 pixels seen from +Z: relative RMSE of its inner part
//!   (N·V > 0.55) and of every covered pixel;
//! - a board (N = +Y, 2 × 2 units) seen from 4 units away at 25° and 60° elevation, 32 × 32 points:
//!   relative RMSE.
//!
//! With `--images`, instead: the issue's images, mean and p99 relative difference and relative
//! RMSE of an orthographic sphere of 128 × 128 pixels seen from +Z (every covered pixel's
//! centre) and of the board seen at 10°, 45° and 80° from its normal (32 × 32 points each).
//!
//! Green channel, the map at intensity 1 and rotation 0.
//!
//! ```text
//! cargo run --release --example brdf_accuracy -- assets/env/courtyard.hdr 0.05,0.2 [--images]
//! ```
//!
//! The reference splits each pixel into as many cells as resolve the lobe where it is narrowest
//! (`converged_subsamples`: up to 64 × 64 within a few degrees of the horizon at small m), which
//! makes it slow: several minutes per m on two cores for `--images`.

use glam::DVec3;
use shikki::environment::brdf_definition::{converged_subsamples, specular_integral_definition};
use shikki::environment::brdf_quadrature::{
    albedo_knots, brdf_specular, BrdfSources, BRDF_SAMPLES,
};
use shikki::environment::bright::{split_bright, split_bright_rough};
use shikki::environment::sharp_source::SharpSource;
use shikki::environment::{
    load_environment, prefilter_cpu, EnvironmentLight, EnvironmentModel, PrefilterParams,
};
use shikki::model::{BrdfParams, FresnelTable};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let (Some(path), Some(list)) = (args.get(1), args.get(2)) else {
        return Err(
            "usage: brdf_accuracy MAP M[,M…] [--images]   (e.g. assets/env/studio.hdr 0.05,0.2)"
                .into(),
        );
    };
    let images = match args.get(3).map(String::as_str) {
        None => false,
        Some("--images") => true,
        Some(other) => return Err(format!("unknown option '{other}' (only --images)").into()),
    };
    let ms = list
        .split(',')
        .map(|m| m.parse::<f64>().map_err(|e| format!("m '{m}': {e}")))
        .collect::<Result<Vec<f64>, String>>()?;
    let source = load_environment(path)?.image;
    let light = EnvironmentLight::default();
    let prefilter = PrefilterParams::for_model(source.width, EnvironmentModel::Brdf);
    let split = split_bright(&source);
    let rough = split_bright_rough(&source);
    let (lights, rough_lights) = (split.lights_in_world(light), rough.lights_in_world(light));
    let residual = prefilter_cpu(&split.residual, &prefilter, light)?;
    let rough_residual = prefilter_cpu(&rough.residual, &prefilter, light)?;
    let sharp = SharpSource::new(&split.residual, light);
    let rough_sharp = SharpSource::new(&rough.residual, light);
    let sources = BrdfSources {
        residual: &residual,
        lights: &lights,
        rough_residual: &rough_residual,
        rough_lights: &rough_lights,
        rough_block_angle: rough.block_angle,
        sharp: sharp.as_ref(),
        rough_sharp: rough_sharp.as_ref(),
    };
    let fresnel = FresnelTable::dielectric(1.5, 0.0045)?;
    println!("{path}");
    for m in ms {
        let brdf = BrdfParams {
            beckmann_m: m,
            diffuse_a: 0.01,
            diffuse_b: 0.96,
            lacquer_g: 1.0159,
            albedo: [0.5, 0.06, 0.03],
        };
        let albedo = albedo_knots(&brdf, &fresnel);
        let pair = |(n, v): (DVec3, DVec3)| {
            let cells = converged_subsamples(source.width, m, n.normalize().dot(v.normalize()));
            let want = specular_integral_definition(&source, light, &brdf, &fresnel, n, v, cells);
            let material = (&brdf, &fresnel, &albedo[..]);
            let got = brdf_specular(sources, BRDF_SAMPLES, material, n, v);
            (got[1], want[1])
        };
        if images {
            let stats = |name: &str, pairs: &[(DVec3, DVec3)]| {
                println!("m {m}: {name}: {}", summary(&evaluate(pairs, &pair)));
            };
            stats("sphere 128²", &sphere_pixels(128));
            for angle in [10.0, 45.0, 80.0] {
                stats(
                    &format!("board {angle}° from its normal"),
                    &board_points(90.0 - angle),
                );
            }
            continue;
        }
        let points = evaluate(&issue_points(), &pair);
        println!("m {m}: 112 points {}", summary(&points));
        let sphere = sphere_pixels(40);
        let got = evaluate(&sphere, &pair);
        let inner: Vec<(f64, f64)> = sphere
            .iter()
            .zip(&got)
            .filter(|((n, _), _)| n.z > 0.55)
            .map(|(_, g)| *g)
            .collect();
        println!(
            "m {m}: sphere 40² relative RMSE inner {:.2} %, whole {:.2} %",
            100.0 * relative_rmse(&inner),
            100.0 * relative_rmse(&got)
        );
        for elevation in [25.0, 60.0] {
            let board = evaluate(&board_points(elevation), &pair);
            println!(
                "m {m}: board at {elevation}° relative RMSE {:.2} %",
                100.0 * relative_rmse(&board)
            );
        }
    }
    Ok(())
}

/// (got, want) per (n, v), on every core.
fn evaluate(
    pairs: &[(DVec3, DVec3)],
    pair: &(impl Fn((DVec3, DVec3)) -> (f64, f64) + Sync),
) -> Vec<(f64, f64)> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let chunk = pairs.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        let handles: Vec<_> = pairs
            .chunks(chunk)
            .map(|part| scope.spawn(move || part.iter().map(|&p| pair(p)).collect::<Vec<_>>()))
            .collect();
        handles
            .into_iter()
            .flat_map(|h| {
                h.join()
                    .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            })
            .collect()
    })
}

/// "mean M %, p99 P %, relative RMSE R %" of (got, want) pairs: the relative difference's mean and
/// 99th percentile, and the relative RMSE.
fn summary(values: &[(f64, f64)]) -> String {
    let mut rel: Vec<f64> = values.iter().map(|(g, w)| (g - w).abs() / w).collect();
    rel.sort_by(f64::total_cmp);
    format!(
        "mean {:.2} %, p99 {:.1} %, relative RMSE {:.2} %",
        100.0 * rel.iter().sum::<f64>() / rel.len() as f64,
        100.0 * rel[rel.len() * 99 / 100],
        100.0 * relative_rmse(values)
    )
}

fn relative_rmse(values: &[(f64, f64)]) -> f64 {
    let se: f64 = values.iter().map(|(g, w)| (g - w).powi(2)).sum();
    let sw: f64 = values.iter().map(|(_, w)| w * w).sum();
    (se / sw).sqrt()
}

/// The issue's points, as tests/environment/brdf_model.rs has them: 100 sphere normals (a
/// Fibonacci lattice down to N·V = 0.03, V = +Z) and the board seen at 10°, 45° and 80° from its
/// normal from four azimuths.
fn issue_points() -> Vec<(DVec3, DVec3)> {
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    let mut pairs: Vec<(DVec3, DVec3)> = (0..100)
        .map(|i| {
            let z = 0.03 + 0.97 * (f64::from(i) + 0.5) / 100.0;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * f64::from(i);
            (DVec3::new(r * phi.cos(), r * phi.sin(), z), DVec3::Z)
        })
        .collect();
    for angle in [10.0_f64, 45.0, 80.0] {
        for k in 0..4 {
            let phi = f64::from(k) * std::f64::consts::FRAC_PI_2 + 0.3;
            let (s, c) = angle.to_radians().sin_cos();
            pairs.push((DVec3::Y, DVec3::new(s * phi.cos(), c, s * phi.sin())));
        }
    }
    pairs
}

/// The covered pixels of a `size` × `size` orthographic sphere seen from +Z: (n, v = +Z).
fn sphere_pixels(size: u32) -> Vec<(DVec3, DVec3)> {
    let centre = |i: u32| (f64::from(i) + 0.5) / f64::from(size / 2) - 1.0;
    (0..size * size)
        .map(|k| (centre(k % size), centre(k / size)))
        .filter(|(x, y)| x * x + y * y < 1.0)
        .map(|(x, y)| (DVec3::new(x, y, (1.0 - x * x - y * y).sqrt()), DVec3::Z))
        .collect()
}

/// A 2 × 2 board on y = 0 seen from (0, 4 sin e, 4 cos e): 32 × 32 points, (+Y, v).
fn board_points(elevation_deg: f64) -> Vec<(DVec3, DVec3)> {
    let (s, c) = elevation_deg.to_radians().sin_cos();
    let eye = DVec3::new(0.0, 4.0 * s, 4.0 * c);
    let centre = |i: u32| (f64::from(i) + 0.5) / 16.0 - 1.0;
    (0..32 * 32)
        .map(|k| {
            let position = DVec3::new(centre(k % 32), 0.0, centre(k / 32));
            (DVec3::Y, (eye - position).normalize())
        })
        .collect()
}
