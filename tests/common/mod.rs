//! Shared by the integration tests: a validated GPU context, a deterministic RNG, image
//! comparison statistics and failure artefacts under target/test-output/.
#![allow(dead_code, unused_imports)]

use shikki::gpu::{ContextOptions, GpuContext};
use shikki::output::{HdrImage, PngSettings, ToneCurve};
use std::path::PathBuf;

/// A context with VK_LAYER_KHRONOS_validation on: tests always run validated.
pub fn validated_gpu() -> GpuContext {
    let options = ContextOptions {
        validation: true,
        device_name: std::env::var("SHIKKI_DEVICE").ok(),
        // The layer's synchronisation checks too: every test also checks the barriers.
        synchronization_validation: true,
        pipeline_cache: None,
        // `SHIKKI_RAY_QUERY=0` runs the suite as on a device without ray queries.
        ray_tracing: ContextOptions::ray_tracing_by_env(),
    };
    match GpuContext::new(&options) {
        Ok(gpu) => gpu,
        Err(e) => panic!("cannot create a validated Vulkan context: {e}"),
    }
}

/// Fails the test if the validation layer said anything.
pub fn assert_no_validation_messages(gpu: &GpuContext) {
    let messages = gpu.take_validation_messages();
    assert!(
        messages.is_empty(),
        "{} validation message(s):\n{}",
        messages.len(),
        messages.join("\n")
    );
}

/// SplitMix64 (the library's, from `shikki synth`): deterministic, so a failure reproduces exactly.
pub use shikki::fit::synth::Rng;

/// Where failing tests leave their pictures.
pub fn artefact_dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/test-output");
    let _ = std::fs::create_dir_all(&dir);
    dir
}

/// Writes `<name>-actual.png`, `<name>-expected.png` and `<name>-diff.png` (|a-e| × 10).
pub fn write_failure_images(name: &str, actual: &HdrImage, expected: &HdrImage) {
    let dir = artefact_dir();
    let settings = PngSettings {
        exposure_ev: 0.0,
        tone_curve: ToneCurve::Aces,
    };
    let mut diff = HdrImage::new(actual.width, actual.height);
    for (d, (a, e)) in diff
        .pixels
        .iter_mut()
        .zip(actual.pixels.iter().zip(&expected.pixels))
    {
        *d = [
            (a[0] - e[0]).abs() * 10.0,
            (a[1] - e[1]).abs() * 10.0,
            (a[2] - e[2]).abs() * 10.0,
            1.0,
        ];
    }
    for (suffix, image) in [("actual", actual), ("expected", expected), ("diff", &diff)] {
        let path = dir.join(format!("{name}-{suffix}.png"));
        if let Err(e) = shikki::output::write_image(&path, image, &settings) {
            eprintln!("could not write {}: {e}", path.display());
        }
    }
    eprintln!("wrote failure images to {}", dir.display());
}

/// The q-quantile (0..=1) of `values` (nearest rank).
pub fn quantile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(|a, b| a.total_cmp(b));
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}

/// A test environment with the features that break naive prefilters: a small bright disc
/// (radius 3°, 50× the sky, towards (0.3, 0.5, −0.81)), a smooth gradient in the sky, and a hard
/// horizon (ground 10× darker than the sky just above it).
pub fn synthetic_environment(width: u32, height: u32) -> shikki::environment::Equirect {
    use glam::DVec3;
    let sun = DVec3::new(0.3, 0.5, -0.81).normalize();
    let cos_disc = 3f64.to_radians().cos();
    shikki::environment::Equirect::from_fn(width, height, move |d: DVec3| {
        if d.dot(sun) >= cos_disc {
            return [50.0, 45.0, 40.0];
        }
        if d.y < 0.0 {
            return [0.08, 0.06, 0.04];
        }
        let t = d.y as f32;
        let azimuth = (0.5 + 0.5 * d.x) as f32;
        [0.8 + 0.4 * azimuth - 0.3 * t, 0.9 - 0.2 * t, 1.0 + 0.5 * t]
    })
}

/// Relative error |a − b| / max(|b|, floor), per channel, worst of the three.
pub fn rel_err(a: [f32; 4], b: [f32; 4], floor: f64) -> f64 {
    (0..3)
        .map(|c| (f64::from(a[c]) - f64::from(b[c])).abs() / f64::from(b[c]).abs().max(floor))
        .fold(0.0, f64::max)
}

/// The bad-input corpus's helpers (running the CLI on hostile files, error-kind matching).
pub mod corpus;
/// The property tests' shared budget, properties and mutations.
pub mod prop;
