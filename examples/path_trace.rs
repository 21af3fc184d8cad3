//! The brute-force path tracer (`oracle::path_tracer`) on any scene file, and the whole-image
//! relative RMSE of renders against it: how BENCHMARKS.md measures the light between objects on
//! a real HDRI ("Against the path tracer on a real map").
//!
//! ```text
//! cargo run --release --example path_trace -- SCENE.toml REFERENCE.exr BOUNCES PATHS [SEED]
//! cargo run --release --example path_trace -- --compare REFERENCE.exr RENDER.exr…
//! ```
//!
//! The reference shoots one ray through each pixel centre, so render the scene to compare with
//! `samples = 1` in `[output]` (no anti-aliasing) and `environment_model = "brdf"` (the model the
//! path tracer closes its paths with). The path tracer reads the map's pixels as they are
//! (piecewise constant) and traces the flat triangles. The relative RMSE is
//! √(Σ (a − b)² / Σ b²) over the three channels of every pixel both images cover.

use std::path::Path;

use shikki::oracle::path_scene::OwnedPathScene;
use shikki::output::exr::{decode_exr, encode_exr};
use shikki::output::HdrImage;
use shikki::scene::load_scene_file;

type Failure = Box<dyn std::error::Error>;

fn main() -> Result<(), Failure> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("--compare") if args.len() >= 3 => compare(&args[1], &args[2..]),
        Some(_) if args.len() >= 4 => {
            let number = |i: usize, what: &str| -> Result<u64, Failure> {
                args[i]
                    .parse::<u64>()
                    .map_err(|e| format!("{what} '{}': {e}", args[i]).into())
            };
            let seed = match args.get(4) {
                Some(_) => number(4, "seed")?,
                None => 1,
            };
            reference(
                Path::new(&args[0]),
                Path::new(&args[1]),
                u32::try_from(number(2, "bounces")?)?,
                u32::try_from(number(3, "paths")?)?,
                seed,
            )
        }
        _ => Err(
            "usage: path_trace SCENE.toml REFERENCE.exr BOUNCES PATHS [SEED]\n       \
                  path_trace --compare REFERENCE.exr RENDER.exr…"
                .into(),
        ),
    }
}

fn reference(
    scene_path: &Path,
    out: &Path,
    bounces: u32,
    paths: u32,
    seed: u64,
) -> Result<(), Failure> {
    let scene = load_scene_file(scene_path)?;
    let size = (scene.output.width, scene.output.height);
    let started = std::time::Instant::now();
    let traced = OwnedPathScene::of(&scene)?.render(size, bounces, paths, seed);
    std::fs::write(out, encode_exr(&traced.mean)?)?;
    println!(
        "{}: {} × {}, {bounces} bounces, {paths} paths, {:.1} s; its noise ≤ {:.2} % relative RMSE",
        out.display(),
        size.0,
        size.1,
        started.elapsed().as_secs_f64(),
        100.0 * traced.relative_noise()
    );
    Ok(())
}

fn compare(reference: &str, renders: &[String]) -> Result<(), Failure> {
    let want = read(reference)?;
    for path in renders {
        let got = read(path)?;
        if (got.width, got.height) != (want.width, want.height) {
            return Err(format!("{path}: size differs from {reference}").into());
        }
        let (mut squares, mut norm) = (0.0, 0.0);
        let (mut difference, mut total) = ([0.0; 3], [0.0; 3]);
        let mut per_pixel = Vec::new();
        let mut worst_pixels = Vec::new();
        for (i, (a, b)) in got.pixels.iter().zip(&want.pixels).enumerate() {
            if a[3] == 1.0 && b[3] == 1.0 {
                let mut pixel = 0.0;
                for c in 0..3 {
                    let d = f64::from(a[c]) - f64::from(b[c]);
                    pixel += d * d;
                    norm += f64::from(b[c]).powi(2);
                    difference[c] += d;
                    total[c] += f64::from(b[c]);
                }
                squares += pixel;
                per_pixel.push(pixel);
                worst_pixels.push((
                    pixel,
                    i % got.width as usize,
                    i / got.width as usize,
                    *a,
                    *b,
                ));
            }
        }
        // How concentrated the error is: the share of Σ (a − b)² in the worst 1 % of pixels.
        per_pixel.sort_by(|a, b| b.total_cmp(a));
        let worst: f64 = per_pixel[..per_pixel.len().div_ceil(100)].iter().sum();
        println!(
            "{path}: relative RMSE {:.2} %; mean difference r/g/b {:+.2} / {:+.2} / {:+.2} %; \
             worst 1 % of pixels hold {:.0} % of the squared error",
            100.0 * (squares / norm).sqrt(),
            100.0 * difference[0] / total[0],
            100.0 * difference[1] / total[1],
            100.0 * difference[2] / total[2],
            100.0 * worst / squares.max(f64::MIN_POSITIVE)
        );
        if std::env::var_os("WORST").is_some() {
            worst_pixels.sort_by(|a, b| b.0.total_cmp(&a.0));
            for (_, x, y, a, b) in worst_pixels.iter().take(8) {
                println!(
                    "  ({x}, {y}): {:.4} {:.4} {:.4} against {:.4} {:.4} {:.4}",
                    a[0], a[1], a[2], b[0], b[1], b[2]
                );
            }
        }
    }
    Ok(())
}

fn read(path: &str) -> Result<HdrImage, Failure> {
    Ok(decode_exr(&std::fs::read(path)?)?)
}
