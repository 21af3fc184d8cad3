//! The denoise of SPEC §6's integral on the device (denoise_guide.comp, denoise_filter.comp)
//! against its host twin (`raster::draw::denoise::denoise`, the same constants from
//! `denoise_params`), pixel by pixel, on ray-traced draws whose integral is not 0. Skipped, with a
//! line on stderr, on a device without ray queries.

use super::shadows::{
    bowl_in_bowl, camera_looking_down, draw_objects, gpu_or_skip, lights, material, scene,
    settings, sphere_on_board, Material, RADIANCE_FLOOR,
};
use crate::common::{assert_no_validation_messages, write_failure_images};
use shikki::environment::EnvironmentModel;
use shikki::gpu::GpuContext;
use shikki::output::HdrImage;
use shikki::raster::draw::{DrawOptions, GpuMesh, LacquerRenderer, RayTracing};
use shikki::raster::mesh::Mesh;

/// Relative to the pixel's light level. The two run the same f32 arithmetic in the same order;
/// what differs is the GPU's exp and log (a few ulp) and fused multiply-adds: measured 1.4e-6
/// (below). A tap or a pixel taken by one side and not the other moves a pixel by 1e-2 or more.
const BOUND: f64 = 1e-4;

/// The draw with the denoise on, on the device or on the host, from one renderer each.
fn denoised(
    gpu: &GpuContext,
    objects: (&[Mesh], &[&Material]),
    rt: RayTracing,
    size: u32,
    on_host: bool,
) -> HdrImage {
    let drawn = draw_objects(objects);
    let meshes: Vec<GpuMesh> = objects
        .0
        .iter()
        .map(|m| GpuMesh::upload(gpu, m).unwrap())
        .collect();
    let meshes: Vec<&GpuMesh> = meshes.iter().collect();
    let (camera, lights) = (camera_looking_down(), lights());
    let options = DrawOptions {
        denoise_on_host: on_host,
        ..DrawOptions::default()
    };
    let scene = scene(
        &drawn,
        (&camera, &lights),
        (None, EnvironmentModel::Paper),
        Some(rt),
    );
    let (image, _) = LacquerRenderer::new()
        .render_meshes(gpu, &scene, &meshes, &settings(size), options)
        .unwrap();
    assert_no_validation_messages(gpu);
    image
}

fn compare(name: &str, meshes: &[Mesh], materials: &[&Material]) {
    let Some(gpu) = gpu_or_skip() else {
        return;
    };
    // 90 px: not a whole number of the shaders' 8 × 8 tiles.
    let size = 90;
    let rt = RayTracing {
        shadows: true,
        bounces: 1,
        rays: 4,
        seed: 3,
        denoise: true,
    };
    let device = denoised(&gpu, (meshes, materials), rt, size, false);
    let host = denoised(&gpu, (meshes, materials), rt, size, true);
    let undenoised = denoised(
        &gpu,
        (meshes, materials),
        RayTracing {
            denoise: false,
            ..rt
        },
        size,
        true,
    );
    let mut worst: f64 = 0.0;
    let mut filtered = 0;
    for ((d, h), u) in device
        .pixels
        .iter()
        .zip(&host.pixels)
        .zip(&undenoised.pixels)
    {
        // Pixels no object covers are the draw's on both sides, bit for bit.
        assert_eq!(d[3], h[3], "{name}: coverage");
        if h[3] < 1.0 {
            assert_eq!(d, h, "{name}: an uncovered pixel changed");
            continue;
        }
        for c in 0..3 {
            let scale = f64::from(h[c].max(u[c])).max(RADIANCE_FLOOR);
            worst = worst.max(f64::from((d[c] - h[c]).abs()) / scale);
        }
        if (0..3).any(|c| (h[c] - u[c]).abs() > 1e-3 * u[c].max(1e-3)) {
            filtered += 1;
        }
    }
    println!("{name}: worst relative device vs host {worst:.2e}, {filtered} pixels filtered");
    if worst > BOUND {
        write_failure_images(&format!("denoise-{name}"), &device, &host);
    }
    assert!(worst <= BOUND, "{name}: {worst}");
    // The filter did something (the comparison is not of two unfiltered images).
    assert!(filtered > 500, "{name}: {filtered} pixels filtered");
}

#[test]
fn sphere_on_board_denoised_on_the_device_matches_the_host() {
    let (red, black) = (material("smooth-red"), material("smooth-black"));
    compare("sphere-on-board", &sphere_on_board(), &[&red, &black]);
}

#[test]
fn bowl_in_bowl_denoised_on_the_device_matches_the_host() {
    let (red, black) = (material("rough-red"), material("smooth-black"));
    compare("bowl-in-bowl", &bowl_in_bowl(), &[&red, &black]);
}
