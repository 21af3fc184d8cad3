//! Long runs in one process: many renders through one `SceneRenderer` (varying meshes, presets,
//! sizes, samples and environments, more distinct environments than its cache keeps, so it
//! evicts) must not leak host memory, device memory or Vulkan objects, and must keep validation
//! (with its synchronisation checks) silent, including at shutdown.
//!
//! `SHIKKI_SOAK_RENDERS` sets the number of renders (default 120, small images: under two minutes
//! in the dev profile). The full run of docs/reliability.md:
//! `SHIKKI_SOAK_RENDERS=2000 cargo test --release --test soak -- --nocapture`.

#[path = "../common/mod.rs"]
mod common;

use std::alloc::System;
use std::path::Path;

use stats_alloc::{StatsAlloc, INSTRUMENTED_SYSTEM};

use common::{assert_no_validation_messages, validated_gpu, Rng};
use shikki::gpu::{ContextOptions, GpuContext};
use shikki::output::HdrImage;
use shikki::scene::{Scene, SceneDocument, SceneRenderer};

/// Counts every byte this process's Rust code allocates and frees: shikki's host memory, exact,
/// beside VmRSS (which also holds lavapipe's and LLVM's heaps, and is noisy).
#[global_allocator]
static HEAP: &StatsAlloc<System> = &INSTRUMENTED_SYSTEM;

/// Bytes of Rust heap alive now.
fn heap_bytes() -> i64 {
    let stats = HEAP.stats();
    stats.bytes_allocated as i64 - stats.bytes_deallocated as i64
}

const DEFAULT_RENDERS: usize = 120;
const MESHES: [&str; 4] = [
    "builtin:sphere",
    "builtin:board",
    "builtin:bowl",
    "builtin:plate",
];
const PRESETS: [&str; 4] = ["smooth-red", "rough-black", "smooth", "rough-red"];
const SIZES: [(u32, u32); 4] = [(32, 24), (48, 32), (40, 40), (64, 48)];
/// Three small maps × four rotations = 12 distinct environments, more than the renderer's cache
/// of 8, so the soak also exercises eviction (freeing a prefiltered cube mid-run).
const ENV_FILES: usize = 3;
const ROTATIONS: [f64; 4] = [0.0, 90.0, 180.0, 270.0];

/// VmRSS of this process in KiB.
fn resident_kib() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

/// Small equirectangular EXR maps, each a different sky, so each prefilters to a different cube.
fn write_environments(dir: &Path) -> Vec<String> {
    (0..ENV_FILES)
        .map(|k| {
            let mut image = HdrImage::new(64, 32);
            for (i, p) in image.pixels.iter_mut().enumerate() {
                let (x, y) = ((i % 64) as f32 / 64.0, (i / 64) as f32 / 32.0);
                let sky = 1.0 - y;
                *p = match k {
                    0 => [sky, 0.5 * sky + 0.2, 0.3, 1.0],
                    1 => [0.3 + x, 0.4, 0.9 * sky, 1.0],
                    _ => [
                        if (x * 8.0) as u32 % 2 == 0 { 4.0 } else { 0.1 },
                        sky,
                        0.5,
                        1.0,
                    ],
                };
            }
            let path = dir.join(format!("sky{k}.exr"));
            let bytes = shikki::output::exr::encode_exr(&image).unwrap();
            std::fs::write(&path, bytes).unwrap();
            path.display().to_string()
        })
        .collect()
}

/// Renders 1..=COVERING use every environment, mesh and sample count once, so the caches are full
/// before resident memory is first measured.
const COVERING: usize = ENV_FILES * ROTATIONS.len();

/// Scene `i` of the soak: drawn from a seeded RNG, so a failure reproduces.
fn soak_scene(i: usize, environments: &[String]) -> Scene {
    let mut rng = Rng::new(0x5eed_0000 + i as u64);
    let mut pick = |n: usize| (rng.next_u64() % n as u64) as usize;
    if (1..=COVERING).contains(&i) {
        let k = i - 1;
        return scene_from(
            i,
            SIZES[k % SIZES.len()],
            [1, 4][k % 2],
            MESHES[k % MESHES.len()],
            PRESETS[pick(PRESETS.len())],
            15 * pick(24),
            Some((&environments[k % ENV_FILES], ROTATIONS[k / ENV_FILES])),
        );
    }
    let (w, h) = SIZES[pick(SIZES.len())];
    let samples = if pick(2) == 0 { 1 } else { 4 };
    let mesh = MESHES[pick(MESHES.len())];
    let preset = PRESETS[pick(PRESETS.len())];
    let orbit = 15 * pick(24);
    // One job in four without environment light.
    let environment = match pick(4) {
        0 => None,
        _ => Some((
            environments[pick(environments.len())].as_str(),
            ROTATIONS[pick(ROTATIONS.len())],
        )),
    };
    scene_from(i, (w, h), samples, mesh, preset, orbit, environment)
}

fn scene_from(
    i: usize,
    (w, h): (u32, u32),
    samples: u32,
    mesh: &str,
    preset: &str,
    orbit: usize,
    environment: Option<(&str, f64)>,
) -> Scene {
    let environment = match environment {
        None => "environment = \"none\"".to_string(),
        Some((source, rotation)) => {
            format!("[environment]\nsource = {source:?}\nrotation_deg = {rotation}")
        }
    };
    // The environment first: `environment = "none"` is a top-level key.
    let text = format!(
        "{environment}\n[output]\nsize = \"{w}x{h}\"\nsamples = {samples}\n\
         [camera]\norbit_deg = {orbit}\n\
         [[object]]\nmesh = \"{mesh}\"\nmaterial = {{ preset = \"{preset}\" }}\n"
    );
    SceneDocument::parse(&text, &format!("soak-{i}.toml"), Path::new(""))
        .and_then(|d| d.build())
        .unwrap_or_else(|e| panic!("soak scene {i}: {e}\n{text}"))
}

fn render(renderer: &mut SceneRenderer, gpu: &GpuContext, scene: &Scene, i: usize) {
    let image = renderer
        .render(gpu, scene)
        .unwrap_or_else(|e| panic!("render {i}: {e}"));
    assert_eq!(
        (image.width, image.height),
        (scene.output.width, scene.output.height)
    );
    assert_no_validation_messages(gpu);
}

/// Twice, one after the other: with validation (and its synchronisation checks) every message,
/// device memory, the Rust heap and the leak report at shutdown are checked; without it, resident
/// memory too.
/// The layer's own bookkeeping grows with every object ever created (measured over 2,000
/// renders: +7.8% VmRSS with it, +1.2% without), which is not shikki's memory.
#[test]
fn many_renders_in_one_process_leak_nothing() {
    let renders: usize = std::env::var("SHIKKI_SOAK_RENDERS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(DEFAULT_RENDERS)
        .max(4 * COVERING);
    let dir = tempfile::tempdir().unwrap();
    let environments = write_environments(dir.path());
    soak(validated_gpu(), renders, &environments, false);
    let plain = GpuContext::new(&ContextOptions {
        device_name: std::env::var("SHIKKI_DEVICE").ok(),
        ..ContextOptions::default()
    })
    .unwrap();
    soak(plain, renders, &environments, true);
}

/// `renders` renders on `gpu` (see the module doc); `check_resident` asserts the VmRSS bound.
fn soak(gpu: GpuContext, renders: usize, environments: &[String], check_resident: bool) {
    // Resident memory is compared from the end of the warm-up (10% of the renders, at least the
    // COVERING renders): by then every pipeline and mesh exists and the environment cache is
    // full, so further growth is a leak. VmRSS is noisy on lavapipe: it steps between levels
    // 10-20 MB apart (its threads' malloc arenas, LLVM) and may stay on the higher one for the
    // rest of a run, so a bound on "end vs start" fails on noise (CI saw 189 -> 203 MB, +7.4%,
    // with the 5th tenth of that run already at 203 MB). A leak instead makes the end higher than
    // anything before it: the lower median of the last two windows must stay within 3% of the
    // highest window median of the first half after the warm-up. Two windows, because a step can
    // also come and go: CI saw the last window's median at 347 MB (+4.9%) with the tenth before
    // it back at 331 MB, the first half's ceiling, and the heap flat. (At ~330 MB a leak of
    // 180 KiB a render shows in the default 120 renders; the Rust heap's check below is exact,
    // and smaller leaks of the driver's show in the 2,000-render run of docs/reliability.md.)
    let warm_up = (renders / 10).max(COVERING + 4);
    let window = (renders / 10).max(8);
    let checkpoints = 4;
    let log = gpu.validation_log();
    // Device memory with no renderer alive: what every renderer must give back when dropped.
    let idle = gpu.memory_in_use();
    let first = soak_scene(0, environments);
    let mut renderer = SceneRenderer::new(&gpu).unwrap();
    render(&mut renderer, &gpu, &first, 0);
    // Device memory after job 0 on a fresh renderer: its caches hold exactly job 0's pipelines,
    // mesh and environment. Job 0 on every fresh renderer must come back to this.
    let after_first = gpu.memory_in_use();
    let started = std::time::Instant::now();
    let (mut repeats, mut peak) = (0, after_first);
    let mut rss = Vec::with_capacity(renders);
    let mut heap = Vec::with_capacity(renders);
    // The Rust heap with no renderer alive, at each cache clear (printed: what a renderer's drop
    // does not give back, the allocator's retained blocks).
    let mut heap_without_renderer = Vec::with_capacity(checkpoints);
    for i in 1..renders {
        let scene = soak_scene(i, environments);
        render(&mut renderer, &gpu, &scene, i);
        let in_use = gpu.memory_in_use();
        peak = peak.max(in_use);
        if i % 4 == 0 {
            // The same job again, everything it needs now cached: it must allocate nothing that
            // outlives it.
            render(&mut renderer, &gpu, &scene, i);
            assert_eq!(
                gpu.memory_in_use(),
                in_use,
                "render {i} repeated changed device memory in use"
            );
            repeats += 1;
        }
        if renders / checkpoints > 0 && i % (renders / checkpoints).max(1) == 0 {
            // Clearing the caches (a fresh renderer): all device memory comes back, and job 0
            // costs what it cost at the start.
            drop(renderer);
            assert_eq!(gpu.memory_in_use(), idle, "render {i}: renderer leaked");
            heap_without_renderer.push(heap_bytes());
            renderer = SceneRenderer::new(&gpu).unwrap();
            render(&mut renderer, &gpu, &first, 0);
            assert_eq!(gpu.memory_in_use(), after_first, "render {i}: job 0 again");
        }
        rss.push(resident_kib());
        heap.push(heap_bytes());
    }
    let median = |samples: &[u64]| {
        let mut sorted = samples.to_vec();
        sorted.sort_unstable();
        sorted[sorted.len() / 2]
    };
    // rss[k] was taken after render k + 1.
    let rss_warm = median(&rss[warm_up - 1..warm_up - 1 + window]);
    let rss_end = median(&rss[rss.len() - window..])
        .min(median(&rss[rss.len() - 2 * window..rss.len() - window]));
    let first_half = &rss[warm_up - 1..warm_up - 1 + (rss.len() - warm_up) / 2];
    let rss_ceiling = first_half
        .windows(window)
        .map(median)
        .max()
        .unwrap_or(rss_warm);
    let deciles: Vec<String> = rss
        .chunks(rss.len().div_ceil(10))
        .map(|c| median(c).to_string())
        .collect();
    // The Rust heap is exact: it plateaus once the caches are full (it falls back after each cache
    // clear), so after the last render it may not exceed the highest value seen in the first half
    // by more than the plateau's own steps. One outlives every renderer: the heap with no renderer
    // alive (printed below) stepped by 45.7 KB once in a run (render 75 of 120, render 145 of 400)
    // and stayed level after, as the plateau did. Its likely owner is gpu-allocator, which keeps
    // the last general block of each memory type when all is freed, with that block's chunk table
    // at the most chunks it ever held (a hash table that grows by doubling, never shrinks). A
    // cache that grows without bound, 1.1 KB a render, exceeds this slack over the second half of
    // the default run; the 2,000-render run of docs/reliability.md sees 70 bytes a render.
    let heap_slack = 64 * 1024;
    let heap_ceiling = heap[..heap.len() / 2].iter().copied().max().unwrap_or(0);
    let heap_end = heap.last().copied().unwrap_or(0);
    let seconds = started.elapsed().as_secs_f64();
    drop(renderer);
    assert_eq!(
        gpu.memory_in_use(),
        idle,
        "device memory after the last renderer"
    );
    drop(gpu);
    let at_shutdown = log.take();
    assert!(
        at_shutdown.is_empty(),
        "validation at shutdown (leaked Vulkan objects?):\n{}",
        at_shutdown.join("\n")
    );
    eprintln!(
        "soak (validation {}): {renders} renders (+{repeats} repeats, {checkpoints} cache clears) in {seconds:.1} \
         s; VmRSS median {rss_warm} KiB over renders {warm_up}..{}, {rss_end} KiB over the last \
         {window} or the {window} before, the lower ({:+.2}%), first-half ceiling {rss_ceiling} KiB, min {} max {} KiB; device memory idle {idle} B, after job 0 \
         {after_first} B, peak {peak} B\nVmRSS medians by tenth of the run (KiB): {}\nRust heap after the last render {heap_end} B, \
         highest in the first half {heap_ceiling} B; without a renderer at the cache clears \
         {heap_without_renderer:?} B",
        if check_resident { "off" } else { "on" },
        warm_up + window,
        (rss_end as f64 / rss_warm as f64 - 1.0) * 100.0,
        rss.iter().min().unwrap(),
        rss.iter().max().unwrap(),
        deciles.join(", ")
    );
    assert!(
        heap_end <= heap_ceiling + heap_slack,
        "Rust heap grew to {heap_end} B after the last render, more than {heap_slack} B above \
         {heap_ceiling} B, the highest in the first half of the run"
    );
    assert!(
        !check_resident || rss_end as f64 <= rss_ceiling as f64 * 1.03,
        "resident memory grew to {rss_end} KiB (median of the last {window} renders, or of the \
         {window} before if lower), more than 3% above {rss_ceiling} KiB, the highest {window}-render median in the first half after the \
         {warm_up}-render warm-up"
    );
}
