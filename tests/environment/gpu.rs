//! The GPU prefilter (compute) against closed forms, the CPU oracle (same algorithm) and
//! SPEC §4's definition, and the environment-lit render against the white-furnace closed form.

use crate::common;
use shikki::environment::EnvironmentLight;

use common::{
    assert_no_validation_messages, quantile, rel_err, synthetic_environment, validated_gpu,
    write_failure_images,
};
use glam::DVec3;
use rayon::prelude::*;
use shikki::environment::brdf_quadrature::apron_texels;
use shikki::environment::cube::{
    direction_to_equirect, face_direction, texel_direction, world_to_environment,
};
use shikki::environment::definition::{irradiance_definition, prefiltered_radiance_definition};
use shikki::environment::gpu::{
    default_params, largest_face_size, layer_texel_offsets, GpuEnvironment, GpuPrefilter,
    LayerApronPass,
};
use shikki::environment::params::ViewBlur;
use shikki::environment::{oracle, CubeImage, Equirect, PrefilterParams};
use shikki::model::brdf::view_dependent_diffuse;
use shikki::model::LacquerMaterial;
use shikki::oracle::{intersect, AnalyticShape};
use shikki::output::HdrImage;
use shikki::raster::camera::Camera;
use shikki::raster::draw::{Background, DrawObject, DrawScene, LacquerRenderer, RenderSettings};
use shikki::raster::mesh;

fn small_params(face_size: u32) -> PrefilterParams {
    PrefilterParams {
        face_size,
        layers: 8,
        beta_min: 0.02,
        beta_max: 1.0,
        layer_texel: 1.0,
        small_layer_texel: 1.0,
        fine_layers: 0,
        blur_net_of_read: false,
        supersample_scale: 1,
    }
}

#[test]
fn white_furnace_layers_are_constant_and_irradiance_is_pi_c() {
    let gpu = validated_gpu();
    let prefilter = GpuPrefilter::new(&gpu).unwrap();
    let c = [0.75f32, 1.5, 3.0];
    let source = Equirect::constant(256, 128, c);
    let env = prefilter
        .run(
            &gpu,
            &source,
            &small_params(64),
            EnvironmentLight::new(1.0, 30.0),
        )
        .unwrap();
    let cubes = env.read_back(&gpu).unwrap();
    assert_eq!(cubes.layers.len(), 8);
    for (k, layer) in cubes.layers.iter().enumerate() {
        for texel in &layer.texels {
            for ch in 0..3 {
                // Issue bound 1e-4: the normalised sum of equal values is c up to fp32 rounding.
                let rel = (texel[ch] - c[ch]).abs() / c[ch];
                assert!(rel <= 1e-4, "layer {k}: {texel:?} vs {c:?}");
            }
        }
    }
    for texel in &cubes.irradiance.texels {
        for ch in 0..3 {
            let want = std::f32::consts::PI * c[ch];
            let rel = (texel[ch] - want).abs() / want;
            // Issue bound 1e-3.
            assert!(rel <= 1e-3, "irradiance {texel:?} vs π·{c:?}");
        }
    }
    assert_no_validation_messages(&gpu);
}

#[test]
fn gpu_layers_match_the_cpu_oracle_every_texel() {
    let gpu = validated_gpu();
    let source = synthetic_environment(512, 256);
    let prefilter = GpuPrefilter::new(&gpu).unwrap();
    // SPEC's layers, and the `brdf` model's convolved net of their texels' read.
    for blur_net_of_read in [false, true] {
        let params = PrefilterParams {
            blur_net_of_read,
            ..small_params(128)
        };
        let env = prefilter
            .run(&gpu, &source, &params, EnvironmentLight::new(1.5, 25.0))
            .unwrap();
        let got = env.read_back(&gpu).unwrap();
        let want =
            oracle::prefilter_cpu(&source, &params, EnvironmentLight::new(1.5, 25.0)).unwrap();
        let cubes = |e: &shikki::environment::PrefilteredEnvironment| -> Vec<CubeImage> {
            e.layers.iter().chain([&e.irradiance]).cloned().collect()
        };
        for (k, (g, w)) in cubes(&got).iter().zip(cubes(&want).iter()).enumerate() {
            assert_eq!(g.face_size, w.face_size, "cube {k}");
            let worst = g
                .texels
                .iter()
                .zip(&w.texels)
                // Issue bound: 1e-3 relative, every texel (no floor needed: the map has no zeros).
                .map(|(a, b)| rel_err(*a, *b, 0.0))
                .fold(0.0, f64::max);
            eprintln!(
                "net of read {blur_net_of_read}, cube {k} (face {}): worst relative error \
                 {worst:.2e}",
                g.face_size
            );
            assert!(
                worst <= 1e-3,
                "net of read {blur_net_of_read}, cube {k}: {worst:.3e}"
            );
        }
    }
    assert_no_validation_messages(&gpu);
}

#[test]
fn gpu_layers_match_the_definition_on_a_hard_map() {
    let gpu = validated_gpu();
    let source = synthetic_environment(512, 256);
    let params = small_params(128);
    let env = GpuPrefilter::new(&gpu)
        .unwrap()
        .run(&gpu, &source, &params, EnvironmentLight::default())
        .unwrap();
    let got = env.read_back(&gpu).unwrap();
    for (k, layer) in got.layers.iter().enumerate().skip(1) {
        let beta = got.betas[k];
        let m = layer.face_size;
        // On faces above 32, every other texel near the disc and the horizon (where the errors
        // are) and every 11th elsewhere; on smaller faces every 3rd. The definition sums the whole
        // 512×256 source per texel (rows beyond the lobe's reach skipped).
        let sun = DVec3::new(0.3, 0.5, -0.81).normalize();
        let total = 6 * m * m;
        let errors: Vec<f64> = (0..total)
            .into_par_iter()
            .filter_map(|index| {
                let (face, j, i) = (index / (m * m), (index / m) % m, index % m);
                let d = texel_direction(face as usize, i, j, m);
                let near_feature = d.dot(sun) > 12f64.to_radians().cos() || d.y.abs() < 0.04;
                let keep = if m > 32 {
                    (near_feature && index % 2 == 0) || index % 11 == 0
                } else {
                    // Small faces (wide lobes, whole-sphere sums): every 3rd texel, all faces.
                    index % 3 == 0
                };
                if !keep {
                    return None;
                }
                let want = prefiltered_radiance_definition(&source, d, beta);
                let g = layer.get(face as usize, i, j);
                Some(
                    (0..3)
                        .map(|c| (f64::from(g[c]) - want[c]).abs() / want[c])
                        .fold(0.0, f64::max),
                )
            })
            .collect();
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        let max = errors.iter().copied().fold(0.0, f64::max);
        eprintln!("layer {k} (β {beta:.4}, face {m}): mean {mean:.2e}, max {max:.2e}");
        // The bounds.
        assert!(
            mean <= 0.02,
            "layer {k}: mean relative error {mean:.3e} > 2 %"
        );
        assert!(
            max <= 0.10,
            "layer {k}: max relative error {max:.3e} > 10 %"
        );
    }
    // Irradiance against ∫ L max(n·s, 0) dω at full resolution: the issue asks ≤ 1e-3 only of the
    // furnace; here the 32² cube quadrature of a 3° disc is held to 1 %.
    let m = got.irradiance.face_size;
    let mut worst: f64 = 0.0;
    for index in (0..6 * m * m).step_by(7) {
        let (face, j, i) = (index / (m * m), (index / m) % m, index % m);
        let n = texel_direction(face as usize, i, j, m);
        let want = irradiance_definition(&source, n);
        let g = got.irradiance.get(face as usize, i, j);
        for c in 0..3 {
            worst = worst.max((f64::from(g[c]) - want[c]).abs() / want[c]);
        }
    }
    eprintln!("irradiance: max relative error {worst:.2e}");
    assert!(worst <= 0.01, "irradiance vs definition {worst:.3e}");
    assert_no_validation_messages(&gpu);
}

/// The texel across the edge from texel (face, i, j) in direction (di, dj) (one of them ±1),
/// found by stepping the direction just past the face boundary and asking which texel of which
/// face contains it (the Vulkan face-selection table).
fn neighbour_across_edge(
    m: u32,
    face: usize,
    i: u32,
    j: u32,
    di: i32,
    dj: i32,
) -> (usize, u32, u32) {
    use shikki::environment::cube::{direction_to_face, face_direction};
    let sc = 2.0 * (f64::from(i) + 0.5 + f64::from(di)) / f64::from(m) - 1.0;
    let tc = 2.0 * (f64::from(j) + 0.5 + f64::from(dj)) / f64::from(m) - 1.0;
    let d = face_direction(face, sc, tc);
    let (f, s, t) = direction_to_face(d);
    let to_texel = |c: f64| {
        (((c + 1.0) / 2.0 * f64::from(m)).floor() as i64).clamp(0, i64::from(m) - 1) as u32
    };
    (f, to_texel(s), to_texel(t))
}

#[test]
fn layers_have_no_seams_at_cube_edges() {
    let gpu = validated_gpu();
    let source = synthetic_environment(512, 256);
    let env = GpuPrefilter::new(&gpu)
        .unwrap()
        .run(
            &gpu,
            &source,
            &small_params(128),
            EnvironmentLight::default(),
        )
        .unwrap();
    let got = env.read_back(&gpu).unwrap();
    let luminance = |t: [f32; 4]| f64::from(0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2]);
    for (k, layer) in got.layers.iter().enumerate() {
        let m = layer.face_size;
        let mut inside: f64 = 0.0;
        let mut across: f64 = 0.0;
        for face in 0..6 {
            for j in 0..m {
                for i in 0..m {
                    let here = luminance(layer.get(face, i, j));
                    for (di, dj) in [(1i32, 0i32), (0, 1), (-1, 0), (0, -1)] {
                        let (ni, nj) = (i as i64 + i64::from(di), j as i64 + i64::from(dj));
                        let jump = if (0..i64::from(m)).contains(&ni)
                            && (0..i64::from(m)).contains(&nj)
                        {
                            let d = (here - luminance(layer.get(face, ni as u32, nj as u32))).abs();
                            inside = inside.max(d);
                            continue;
                        } else {
                            let (f, a, b) = neighbour_across_edge(m, face, i, j, di, dj);
                            (here - luminance(layer.get(f, a, b))).abs()
                        };
                        across = across.max(jump);
                    }
                }
            }
        }
        eprintln!("layer {k}: largest jump inside a face {inside:.4}, across an edge {across:.4}");
        // The criterion, verbatim.
        assert!(
            across <= inside,
            "layer {k}: seam jump {across} > interior jump {inside}"
        );
    }
    assert_no_validation_messages(&gpu);
}

fn render_sphere(
    gpu: &shikki::gpu::GpuContext,
    source: &Equirect,
    preset: &str,
    size: u32,
) -> (HdrImage, Camera, LacquerMaterial) {
    let env = GpuPrefilter::new(gpu)
        .unwrap()
        .run(
            gpu,
            source,
            &PrefilterParams::for_source_width(source.width),
            EnvironmentLight::default(),
        )
        .unwrap();
    let material = LacquerMaterial::preset(preset).unwrap();
    let camera = Camera::default();
    let image = LacquerRenderer::new()
        .render(
            gpu,
            &DrawScene {
                objects: &[DrawObject {
                    mesh: &mesh::sphere(256, 128),
                    brdf: &material.brdf_params().unwrap(),
                    fresnel: &material.fresnel_table().unwrap(),
                    view_blur: ViewBlur::of(&material),
                }],
                camera: &camera,
                lights: &[],
                environment: Some(&env),
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
    (image, camera, material)
}

/// Surface normal and view direction at pixel (x, y) of the analytic sphere, if the pixel and
/// its neighbours are inside its silhouette.
fn sphere_frame(camera: &Camera, size: u32, x: u32, y: u32) -> Option<(DVec3, DVec3)> {
    for (dx, dy) in [
        (0.5, 0.5),
        (-0.5, -0.5),
        (1.5, -0.5),
        (-0.5, 1.5),
        (1.5, 1.5),
    ] {
        let ray = camera.primary_ray(f64::from(x) + dx, f64::from(y) + dy, size, size);
        intersect(AnalyticShape::Sphere, camera.eye, ray)?;
    }
    let ray = camera.primary_ray(f64::from(x) + 0.5, f64::from(y) + 0.5, size, size);
    let hit = intersect(AnalyticShape::Sphere, camera.eye, ray)?;
    Some((hit.normal, (camera.eye - hit.position).normalize()))
}

#[test]
fn sphere_in_a_white_furnace_matches_the_closed_form() {
    let gpu = validated_gpu();
    let c = [0.6f32, 0.8, 1.0];
    let source = Equirect::constant(256, 128, c);
    for preset in ["smooth-black", "rough-red"] {
        let size = 256;
        let (image, camera, material) = render_sphere(&gpu, &source, preset, size);
        let brdf = material.brdf_params().unwrap();
        let fresnel = material.fresnel_table().unwrap();
        let mut expected = HdrImage::new(size, size);
        let mut errors = Vec::new();
        for y in 0..size {
            for x in 0..size {
                let Some((n, v)) = sphere_frame(&camera, size, x, y) else {
                    continue;
                };
                let nv = n.dot(v);
                // L = F(acos nv)·c + k_d·max(a + b·nv, 0)·g(r)·c (the closed form).
                let f = fresnel.eval(nv.clamp(0.0, 1.0).acos().to_degrees());
                let diffuse = view_dependent_diffuse(&brdf, nv);
                let want: [f32; 4] = [0, 1, 2, 3].map(|ch| {
                    if ch == 3 {
                        1.0
                    } else {
                        ((f[ch] + diffuse[ch] * std::f64::consts::PI) * f64::from(c[ch])) as f32
                    }
                });
                expected.set(x, y, want);
                errors.push(rel_err(image.get(x, y), want, 1e-4));
            }
        }
        let count = errors.len();
        let p99 = quantile(&mut errors, 0.99);
        eprintln!("{preset}: {count} interior pixels, p99 relative error {p99:.2e}");
        if p99 > 0.005 {
            write_failure_images(&format!("furnace-{preset}"), &image, &expected);
        }
        // The bound: 0.5 % at the 99th percentile.
        assert!(p99 <= 0.005, "{preset}: p99 {p99:.3e}");
    }
    assert_no_validation_messages(&gpu);
}

/// Michelson-style contrast of the pixels whose nv falls in `range`: (p95 − p5)/(p95 + p5) of
/// luminance, robust to a few edge pixels.
fn contrast(image: &HdrImage, camera: &Camera, range: std::ops::Range<f64>) -> f64 {
    let size = image.width;
    let mut lum = Vec::new();
    for y in 0..size {
        for x in 0..size {
            if let Some((n, v)) = sphere_frame(camera, size, x, y) {
                if range.contains(&n.dot(v)) {
                    let p = image.get(x, y);
                    lum.push(f64::from(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]));
                }
            }
        }
    }
    assert!(lum.len() > 200, "too few pixels in nv ∈ {range:?}");
    let hi = quantile(&mut lum.clone(), 0.95);
    let lo = quantile(&mut lum, 0.05);
    (hi - lo) / (hi + lo)
}

#[test]
fn rough_lacquer_reflects_sharply_only_at_grazing_angles() {
    let gpu = validated_gpu();
    // A checkerboard of 12 × 6 squares (30° each), 20:1.
    let checker = Equirect::from_fn(512, 256, |d: DVec3| {
        let (u, v) = shikki::environment::cube::direction_to_equirect(world_to_environment(d, 0.0));
        let odd = ((u * 12.0).floor() as i64 + (v * 6.0).floor() as i64) % 2 == 0;
        if odd {
            [2.0; 3]
        } else {
            [0.1; 3]
        }
    });
    let size = 384;
    let (rough, camera, _) = render_sphere(&gpu, &checker, "rough-black", size);
    let (smooth, _, _) = render_sphere(&gpu, &checker, "smooth-black", size);
    let rough_grazing = contrast(&rough, &camera, 0.0..0.2);
    let rough_face_on = contrast(&rough, &camera, 0.9..1.01);
    let smooth_grazing = contrast(&smooth, &camera, 0.0..0.2);
    let smooth_face_on = contrast(&smooth, &camera, 0.9..1.01);
    eprintln!(
        "contrast rough: grazing {rough_grazing:.3}, face-on {rough_face_on:.3}; \
         smooth: grazing {smooth_grazing:.3}, face-on {smooth_face_on:.3}"
    );
    // β(rough) is 0.05 at grazing and 0.6 face-on (SPEC §4): the face-on reflection of 30°
    // squares is washed out, the grazing one is not. "Measurably higher": at least twice.
    assert!(rough_grazing > 2.0 * rough_face_on);
    // smooth: β = 0.1 everywhere, so both regions show the checkerboard, equally clearly
    // (measured ≈ 0.48 each; 0.3 is a contrast the eye reads as a crisp pattern).
    assert!(smooth_face_on > 0.3 && smooth_grazing > 0.3);
    let ratio = smooth_grazing / smooth_face_on;
    assert!(
        (0.5..2.0).contains(&ratio),
        "smooth grazing/face-on contrast {ratio}"
    );
    assert_no_validation_messages(&gpu);
}

/// A face whose cube exceeds the device's buffer limits is refused up front with the largest face
/// that fits (Vulkan would leave it undefined: on lavapipe face 2048 needs 384 MiB against a
/// 128 MiB maxStorageBufferRange), and default face sizes are clamped to that face.
#[test]
fn a_face_beyond_the_device_limits_is_refused_and_defaults_are_clamped() {
    let gpu = validated_gpu();
    let largest = largest_face_size(gpu.info());
    assert!(
        largest.is_power_of_two() && largest >= 16,
        "largest face {largest}"
    );
    // An 8K source asks for face 2048 by default; clamped, it never exceeds the device.
    assert_eq!(default_params(&gpu, 8192).face_size, largest.min(2048));
    assert_eq!(default_params(&gpu, 1024).face_size, 256);
    if largest < shikki::environment::params::MAX_FACE_SIZE {
        let mut params = small_params(16);
        params.face_size = 2 * largest;
        let err = GpuPrefilter::new(&gpu)
            .unwrap()
            .run(
                &gpu,
                &synthetic_environment(64, 32),
                &params,
                EnvironmentLight::default(),
            )
            .err()
            .expect("a face beyond the device's limits must be refused");
        let text = err.to_string();
        assert!(
            text.contains("face size") && text.contains(&format!("--face-size {largest}")),
            "{text}"
        );
    }
    assert_no_validation_messages(&gpu);
}

#[test]
fn one_prefilter_runs_many_times_without_hazards() {
    let gpu = validated_gpu();
    let prefilter = GpuPrefilter::new(&gpu).unwrap();
    let source = synthetic_environment(128, 64);
    let mut first = None;
    for _ in 0..3 {
        let env = prefilter
            .run(
                &gpu,
                &source,
                &small_params(32),
                EnvironmentLight::default(),
            )
            .unwrap();
        let cubes = env.read_back(&gpu).unwrap();
        // Deterministic: every run gives the same texels.
        match &first {
            None => first = Some(cubes),
            Some(f) => assert!(f == &cubes, "a second run differs"),
        }
        assert_no_validation_messages(&gpu);
    }
}

#[test]
fn an_uploaded_environment_reads_back_identical_texels_and_renders_the_same() {
    let gpu = validated_gpu();
    let source = synthetic_environment(128, 64);
    let env = GpuPrefilter::new(&gpu)
        .unwrap()
        .run(
            &gpu,
            &source,
            &small_params(32),
            EnvironmentLight::new(1.0, 10.0),
        )
        .unwrap();
    let host = env.read_back(&gpu).unwrap();
    let uploaded = GpuEnvironment::upload(&gpu, &host).unwrap();
    // A copy, not a computation: bit-identical.
    assert!(uploaded.read_back(&gpu).unwrap() == host);
    assert_eq!(uploaded.layers.len(), env.layers.len());
    // The sampled images hold the same data: a render with either is the same image.
    let draw = |environment: &GpuEnvironment| {
        let material = LacquerMaterial::preset("smooth-black").unwrap();
        LacquerRenderer::new()
            .render(
                &gpu,
                &DrawScene {
                    objects: &[DrawObject {
                        mesh: &mesh::sphere(32, 16),
                        brdf: &material.brdf_params().unwrap(),
                        fresnel: &material.fresnel_table().unwrap(),
                        view_blur: ViewBlur::of(&material),
                    }],
                    camera: &Camera::default(),
                    lights: &[],
                    environment: Some(environment),
                    environment_model: Default::default(),
                    ray_tracing: None,
                    background: Background::Environment,
                },
                &RenderSettings {
                    width: 64,
                    height: 64,
                    samples: 1,
                },
            )
            .unwrap()
    };
    assert!(draw(&uploaded) == draw(&env), "renders differ");
    // Malformed input is an error naming the field, not a panic.
    let mut broken = host.clone();
    broken.layers[1].texels[3][0] = f32::NAN;
    let message = GpuEnvironment::upload(&gpu, &broken)
        .err()
        .unwrap()
        .to_string();
    assert!(message.contains("layers[1] texel 3"), "{message}");
    assert_no_validation_messages(&gpu);
}

#[test]
fn the_brdf_models_layer_texels_carry_the_seam_rule_in_their_aprons() {
    // The `brdf` model reads each face with a one-texel apron (layer_apron.comp); every texel of
    // it, apron and face, must be the CPU twin's, bit for bit: a copy and an integer rounding
    // (two texels to each, layer_pair.rs), nothing else.
    let gpu = validated_gpu();
    let env = GpuPrefilter::new(&gpu)
        .unwrap()
        .run(
            &gpu,
            &hashed_equirect(128, 64),
            &small_params(32),
            EnvironmentLight::new(1.0, 10.0),
        )
        .unwrap();
    let host = env.read_back(&gpu).unwrap();
    let want: Vec<[u32; 4]> = host.layers.iter().flat_map(apron_texels).collect();
    let (offsets, total) = layer_texel_offsets(env.layer_faces());
    assert_eq!(total as usize, want.len());
    assert_eq!(offsets.len(), host.layers.len());
    let got = env
        .read_layer_texels(&gpu, &LayerApronPass::new(&gpu).unwrap())
        .unwrap();
    assert_eq!(got.len(), want.len());
    let wrong = got.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(wrong, 0, "{wrong} of {} texels differ", want.len());
    assert_no_validation_messages(&gpu);
}

#[test]
fn the_layer_texels_round_every_kind_of_value_as_the_twin_does() {
    // Two texels to a texel, each channel rounded to 21 bits by integer operations
    // (layer_pair.glsl, twin layer_pair.rs), at the values where a rounding rule shows: ties
    // between two codes (even and odd), the neighbours of a tie, a carry into the next binade,
    // the largest finite f32 and the ones that would round past it, the smallest normal and the
    // subnormals below it, zeros and negatives (stored as 0). Uploaded as the layers themselves,
    // so every value reaches the apron pass as it is.
    let gpu = validated_gpu();
    let mut values: Vec<f32> = vec![
        0.0,
        -0.0,
        -1.0,
        -3e38,
        1.0,
        0.1,
        65_504.0,
        1e-30,
        f32::MIN_POSITIVE,
        f32::from_bits(1),
        f32::from_bits(0x007F_FFFF),
        f32::MAX,
        f32::from_bits(0x7F7F_FDFF),
        f32::from_bits(0x7F7F_FE00),
        // A mantissa whose kept bits are all ones, at and past half a code: carries.
        f32::from_bits(0x3FFF_FE00),
        f32::from_bits(0x3FFF_FDFF),
    ];
    for code in [1u32, 2, 3, 0x1234, 0x1F_DFFE] {
        let base = code << 10;
        values.extend([0x1FF, 0x200, 0x201].map(|low| f32::from_bits(base | low)));
    }
    let n = values.len();
    let cube = |shift: usize| {
        let mut cube = CubeImage::new(16);
        for (k, texel) in cube.texels.iter_mut().enumerate() {
            let at = |step: usize| values[(k * step + shift) % n];
            *texel = [at(1), at(7), at(13), 1.0];
        }
        cube
    };
    let env = shikki::environment::PrefilteredEnvironment {
        betas: vec![0.0, 0.5],
        layers: vec![cube(0), cube(5)],
        irradiance: CubeImage::new(1),
    };
    let on_gpu = GpuEnvironment::upload(&gpu, &env).unwrap();
    let got = on_gpu
        .read_layer_texels(&gpu, &LayerApronPass::new(&gpu).unwrap())
        .unwrap();
    let want: Vec<[u32; 4]> = env.layers.iter().flat_map(apron_texels).collect();
    assert_eq!(got.len(), want.len());
    let wrong: Vec<_> = got.iter().zip(&want).filter(|(g, w)| g != w).collect();
    assert!(
        wrong.is_empty(),
        "{} of {} texels differ, first {:x?}",
        wrong.len(),
        want.len(),
        wrong.first()
    );
    assert_no_validation_messages(&gpu);
}

/// A map whose every pixel differs from its neighbours by a large random factor (1 … 1000), so a
/// sub-sample that reads the wrong source pixel shows.
fn hashed_equirect(width: u32, height: u32) -> Equirect {
    let pixels = (0..u64::from(width) * u64::from(height))
        .map(|index| {
            let h = index.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40;
            let x = 1.0 + (h % 1000) as f32;
            [x, 1001.0 - x, 1.0 + ((h >> 10) % 100) as f32]
        })
        .collect();
    Equirect {
        width,
        height,
        pixels,
    }
}

/// How far texel (face, i, j) of step 1 may move if each sub-sample lying exactly on a source
/// pixel boundary reads the pixel on the other side: per channel, Σ |L(here) − L(there)| / S².
/// A sub-sample is on a boundary when its exact position is within 1e-9 px of one (f64's rounding
/// of u·W is ~1e-13 px); such ties happen by symmetry, e.g. on the diagonals of the ±Y faces, where
/// x = ±z makes u a multiple of 1/8, a boundary for any W divisible by 8. Which side an exact tie
/// rounds to is an accident of the last bit (the oracle's libm atan2 against the shader's Newton
/// step, fused multiply-adds on one driver and not on another), so neither side is wrong; NVIDIA
/// 580 reads some of them the other way from lavapipe and the CPU. A turned map's sub-samples are
/// ties as far out as the shader's f32 rotation moves them.
fn boundary_tie_slack(
    source: &Equirect,
    (face_size, s): (u32, u32),
    rotation_deg: f64,
    (face, i, j): (usize, u32, u32),
) -> ([f64; 3], u32) {
    let coordinate = |t: u32, sub: u32| {
        2.0 * (f64::from(t) + (f64::from(sub) + 0.5) / f64::from(s)) / f64::from(face_size) - 1.0
    };
    let (w, h) = (i64::from(source.width), i64::from(source.height));
    let pixel = |x: i64, y: i64| {
        let rgb = source.get(x.rem_euclid(w) as u32, y.clamp(0, h - 1) as u32);
        rgb.map(f64::from)
    };
    let (mut slack, mut ties) = ([0.0; 3], 0);
    for b in 0..s {
        for a in 0..s {
            let world = face_direction(face, coordinate(i, a), coordinate(j, b)).normalize();
            let e = world_to_environment(world, rotation_deg);
            let (u, v) = direction_to_equirect(e);
            let (px, py) = (u * w as f64, v * h as f64);
            let (x, y) = (px.floor() as i64, py.floor() as i64);
            let (fx, fy) = (px - x as f64, py - y as f64);
            // The shader turns the map by the rotation's cos and sin in f32, 6e-8 rad from the
            // oracle's: W/2π·6e-8/|xz| px in u, H/π·6e-8 px in v (1.5e-6 px of a sub-sample
            // from a row's edge read the other row at S = 16, ρ = 25°). 0 unturned.
            let turn = match rotation_deg == 0.0 {
                true => (0.0, 0.0),
                false => (1e-8 * w as f64 / e.x.hypot(e.z).max(1e-3), 2e-8 * h as f64),
            };
            let others = [
                (fx < 1e-9 + turn.0, (x - 1, y)),
                (1.0 - fx < 1e-9 + turn.0, (x + 1, y)),
                (fy < 1e-9 + turn.1, (x, y - 1)),
                (1.0 - fy < 1e-9 + turn.1, (x, y + 1)),
            ]
            .into_iter()
            .filter_map(|(tie, other)| tie.then_some(other));
            for (ox, oy) in others {
                ties += 1;
                let (here, there) = (pixel(x, y), pixel(ox, oy));
                for c in 0..3 {
                    slack[c] += (here[c] - there[c]).abs() / f64::from(s * s);
                }
            }
        }
    }
    (slack, ties)
}

#[test]
fn step_one_reads_exactly_the_oracles_source_pixels() {
    let gpu = validated_gpu();
    let prefilter = GpuPrefilter::new(&gpu).unwrap();
    // S = 4 (16 sub-samples per texel, `paper`'s step 1) and S = 16 (256, the `brdf` model's:
    // supersample_scale 4) on both; rotations put pixel boundaries anywhere, and rotation 0 with
    // W divisible by 8 puts sub-samples exactly on them (boundary_tie_slack).
    for (width, face, rotation, scale) in [
        (1024, 128, 25.0, 1),
        (2048, 128, -131.0, 1),
        (512, 64, 0.0, 1),
        (1024, 128, 25.0, 4),
        (512, 64, 0.0, 4),
    ] {
        let source = hashed_equirect(width, width / 2);
        let params = PrefilterParams {
            face_size: face,
            layers: 2,
            beta_min: 1.0,
            beta_max: 1.0,
            layer_texel: 1.0,
            small_layer_texel: 1.0,
            fine_layers: 0,
            blur_net_of_read: false,
            supersample_scale: scale,
        };
        let s = params.supersample(width);
        assert_eq!(s, 4 * scale);
        let env = prefilter
            .run(&gpu, &source, &params, EnvironmentLight::new(1.0, rotation))
            .unwrap();
        let got = &env.read_back(&gpu).unwrap().layers[0];
        let want = oracle::equirect_to_cube(&source, (face, s), 1.0, rotation);
        let (mut worst, mut ties, mut tie_texels_apart) = (0.0_f64, 0, 0);
        for f in 0..6 {
            for j in 0..face {
                for i in 0..face {
                    let (a, b) = (got.get(f, i, j), want.get(f, i, j));
                    // The mean of S² values in fp32 vs f64: ≤ S² roundings of 6e-8, so 1e-5 per
                    // 16 of them is generous; one misread sub-sample among S² moves a texel by
                    // ~(1/S²)·(a ~2× change), ≥ 4e-3 ≫ 1.6e-4. Only an exact tie may read the
                    // other pixel.
                    let (slack, n) = boundary_tie_slack(&source, (face, s), rotation, (f, i, j));
                    ties += n;
                    let mut apart = false;
                    for c in 0..3 {
                        let d = (f64::from(a[c]) - f64::from(b[c])).abs();
                        let rounding = 1e-5 * f64::from(s * s / 16) * f64::from(b[c]).abs();
                        assert!(
                            d <= rounding + slack[c],
                            "{width}: face {f} texel ({i}, {j}) channel {c}: {} vs {} \
                             (ties {n}, slack {:.3e})",
                            a[c],
                            b[c],
                            slack[c]
                        );
                        apart |= d > rounding;
                        worst = worst.max(if n == 0 {
                            d / f64::from(b[c]).abs()
                        } else {
                            0.0
                        });
                    }
                    tie_texels_apart += u32::from(apart);
                }
            }
        }
        eprintln!(
            "{width}×{}, face {face}, S {s}, ρ {rotation}°: worst {worst:.2e} away from ties; \
             {ties} sub-samples on a boundary, {tie_texels_apart} texels read a tie the other way",
            width / 2
        );
    }
    assert_no_validation_messages(&gpu);
}
