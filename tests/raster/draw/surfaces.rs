//! The shading pass's surfaces per pixel (shade_body.glsl): at 4× MSAA the samples of
//! neighbouring triangles of one smooth mesh are shaded once, at their mean (`same_surface`),
//! while a mesh's silhouette over another part of the same mesh stays two surfaces, as a forward
//! draw with an MSAA resolve shades them.

use crate::common;

use super::deferred::environment;
use super::shadows::{draw_objects, material, scene};
use common::{assert_no_validation_messages, rel_err, validated_gpu};
use glam::DVec3;
use shikki::environment::gpu::GpuEnvironment;
use shikki::environment::EnvironmentModel;
use shikki::gpu::GpuContext;
use shikki::output::HdrImage;
use shikki::raster::draw::{LacquerRenderer, RenderSettings};
use shikki::raster::mesh::{self, Mesh};
use shikki::raster::{BuiltinMesh, Camera};

/// `meshes` as objects of one smooth red lacquer, identity transforms, under the default lights
/// and `env` (`paper` model), on a transparent background (shadows.rs's draw, at `settings`).
fn render(
    gpu: &GpuContext,
    env: &GpuEnvironment,
    meshes: &[Mesh],
    camera: &Camera,
    settings: RenderSettings,
) -> HdrImage {
    let red = material("smooth-red");
    let objects = draw_objects((meshes, &vec![&red; meshes.len()]));
    let lights = shikki::raster::default_lights();
    let scene = scene(
        &objects,
        (camera, &lights),
        (Some(env), EnvironmentModel::Paper),
        None,
    );
    LacquerRenderer::new()
        .render(gpu, &scene, &settings)
        .unwrap()
}

fn settings(size: u32, samples: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        samples,
    }
}

/// Inside a finely tessellated sphere (65k triangles, ~3 pixels each, so most pixels hold a
/// triangle edge), a 4× MSAA pixel is the 1-sample pixel to rounding at the 99th percentile:
/// both shade the sphere at the pixel centre, the 1-sample draw on the triangle holding the
/// centre, the multisampled one at the mean of its samples' triangles extended to the centre
/// (before the merge: the mean of their shadings). Measured: 7e-4 at the 99th percentile, up to
/// 2.3e-2 at a highlight's edge, with or without the merge (the triangles' planes and normals part
/// there by more than the lobe's curvature allows). A sum weighed by anything but the sample
/// counts, a surface shaded with another object's material, or a NaN breaks it by far more.
#[test]
fn a_smooth_meshs_samples_are_shaded_at_the_pixel_centre() {
    let gpu = validated_gpu();
    let env = environment(&gpu);
    let sphere = [mesh::sphere(256, 128)];
    let camera = Camera {
        eye: DVec3::new(0.3, 0.8, 2.4),
        target: DVec3::ZERO,
        up: DVec3::Y,
        fov_deg: 40.0,
    };
    let multi = render(&gpu, &env, &sphere, &camera, settings(192, 4));
    let single = render(&gpu, &env, &sphere, &camera, settings(192, 1));
    let width = multi.width as usize;
    let inside = |i: usize| {
        let (x, y) = (i % width, i / width);
        (x > 0 && y > 0 && x + 1 < width && y + 1 < width)
            && (0..9).all(|k| multi.pixels[(y + k / 3 - 1) * width + x + k % 3 - 1][3] == 1.0)
    };
    let mut errors = Vec::new();
    for (i, (a, b)) in multi.pixels.iter().zip(&single.pixels).enumerate() {
        if inside(i) {
            errors.push(rel_err(*a, *b, 1e-3));
        }
    }
    let worst = errors.iter().copied().fold(0.0, f64::max);
    eprintln!("{} inner pixels, worst {worst:.3e}", errors.len());

    assert!(errors.len() > 15_000, "the sphere fills the image");
    let p99 = common::quantile(&mut errors, 0.99);
    assert!(
        p99 <= 1e-3 && worst <= 3e-2,
        "4× MSAA pixels from their centre's shading: p99 {p99:.3e}, worst {worst:.3e}"
    );
    assert_no_validation_messages(&gpu);
}

/// Two overlapping bowls drawn as two objects and as one mesh holding both: where the front
/// bowl's silhouette lies over the back one, a pixel's samples see two surfaces of one object in
/// the second draw, and they must stay two shadings, as across two objects. With identity
/// transforms both draws rasterise the same vertices, so the images are the same bits.
#[test]
fn a_silhouette_over_the_same_mesh_stays_two_surfaces() {
    let gpu = validated_gpu();
    let env = environment(&gpu);
    let front = BuiltinMesh::Bowl.mesh();
    let mut back = front.clone();
    for p in &mut back.positions {
        p[0] += 0.45;
        p[2] -= 0.7;
    }
    let mut both = front.clone();
    let first = both.positions.len() as u32;
    both.positions.extend(&back.positions);
    both.normals.extend(&back.normals);
    both.indices.extend(back.indices.iter().map(|i| i + first));
    let camera = Camera {
        eye: DVec3::new(0.2, 1.1, 2.6),
        target: DVec3::new(0.2, 0.2, -0.3),
        up: DVec3::Y,
        fov_deg: 35.0,
    };
    let settings = settings(256, 4);
    let two = render(&gpu, &env, &[front.clone(), back], &camera, settings);
    let one = render(&gpu, &env, &[both], &camera, settings);
    // The pixels where the front bowl's silhouette lies over the back bowl: partly covered by the
    // front bowl alone, fully covered with both.
    let alone = render(&gpu, &env, &[front], &camera, settings);
    let over = (alone.pixels.iter().zip(&two.pixels))
        .filter(|(a, b)| a[3] > 0.0 && a[3] < 1.0 && b[3] == 1.0)
        .count();
    assert!(
        over > 100,
        "the front bowl's silhouette over the back one: {over} pixels"
    );
    for (i, (a, b)) in one.pixels.iter().zip(&two.pixels).enumerate() {
        assert_eq!(
            a,
            b,
            "pixel ({}, {}): one mesh vs two objects",
            i % 256,
            i / 256
        );
    }
    assert_no_validation_messages(&gpu);
}
