//! CPU parts of shikki under criterion (`cargo bench --bench cpu`): the BRDF model, building a
//! material's Fresnel table (the CIE spectral path), tone mapping + PNG encoding of a 512² image,
//! parsing an OBJ of the ~100k-triangle bowl, and angle-weighted vertex normals of that mesh.

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::DVec3;
use shikki::model::{lacquer_brdf, LacquerMaterial};
use shikki::output::{png::encode_png, HdrImage, PngSettings};
use shikki::raster::mesh_io::{load_mesh, normals::angle_weighted_normals};
use shikki::raster::BuiltinMesh;
use std::fmt::Write as _;

fn brdf(c: &mut Criterion) {
    let material = LacquerMaterial::preset("smooth-red").unwrap();
    let params = material.brdf_params().unwrap();
    let fresnel = material.fresnel_table().unwrap();
    // 1024 direction triples over the upper hemisphere, fixed.
    let triples: Vec<[DVec3; 3]> = (0..1024)
        .map(|i| {
            let a = i as f64 * 0.61803;
            let b = i as f64 * 0.38197;
            let v = DVec3::new(a.sin() * 0.6, 0.7, a.cos() * 0.6).normalize();
            let l = DVec3::new(b.cos() * 0.5, 0.8, b.sin() * 0.5).normalize();
            [DVec3::Y, v, l]
        })
        .collect();
    c.bench_function("brdf: lacquer_brdf × 1024", |bench| {
        bench.iter(|| {
            let mut sum = 0.0;
            for [n, v, l] in &triples {
                sum += lacquer_brdf(&params, &fresnel, *n, *v, *l)[0];
            }
            black_box(sum)
        })
    });
}

fn fresnel_table(c: &mut Criterion) {
    let material = LacquerMaterial::preset("smooth-red").unwrap();
    c.bench_function("fresnel: table build (smooth-red)", |bench| {
        bench.iter(|| black_box(material.fresnel_table().unwrap()))
    });
}

fn tonemap_png(c: &mut Criterion) {
    let mut image = HdrImage::new(512, 512);
    for (i, p) in image.pixels.iter_mut().enumerate() {
        let x = (i % 512) as f32 / 512.0;
        let y = (i / 512) as f32 / 512.0;
        *p = [x * 4.0, y * 2.0, (x * y) * 8.0, 1.0];
    }
    let settings = PngSettings::default();
    c.bench_function("output: tone map + PNG encode 512²", |bench| {
        bench.iter(|| black_box(encode_png(&image, &settings).unwrap()))
    });
}

fn bowl_obj() -> std::path::PathBuf {
    let mesh = BuiltinMesh::Bowl.mesh();
    let mut text = String::with_capacity(mesh.positions.len() * 80);
    for p in &mesh.positions {
        let _ = writeln!(text, "v {} {} {}", p[0], p[1], p[2]);
    }
    for n in &mesh.normals {
        let _ = writeln!(text, "vn {} {} {}", n[0], n[1], n[2]);
    }
    for t in mesh.indices.chunks_exact(3) {
        let (a, b, c) = (t[0] + 1, t[1] + 1, t[2] + 1);
        let _ = writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    let path = std::env::temp_dir().join(format!("shikki-bench-bowl-{}.obj", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path
}

fn meshes(c: &mut Criterion) {
    let path = bowl_obj();
    let mut group = c.benchmark_group("mesh");
    group.sample_size(20);
    group.bench_function("OBJ parse: bowl (~100k triangles)", |bench| {
        bench.iter(|| black_box(load_mesh(&path).unwrap()))
    });
    let mesh = BuiltinMesh::Bowl.mesh();
    group.bench_function("angle-weighted normals: bowl", |bench| {
        bench.iter(|| black_box(angle_weighted_normals(&mesh.positions, &mesh.indices)))
    });
    group.finish();
    let _ = std::fs::remove_file(&path);
}

criterion_group!(benches, brdf, fresnel_table, tonemap_png, meshes);
criterion_main!(benches);
