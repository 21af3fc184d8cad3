use glam::DVec3;
use shikki::environment::cube::texel_direction;
use shikki::environment::definition::prefiltered_radiance_definition;
use shikki::environment::gpu::GpuPrefilter;
use shikki::environment::{Equirect, PrefilterParams};
use shikki::gpu::{ContextOptions, GpuContext};
fn synthetic_environment(width: u32, height: u32) -> Equirect {
    let sun = DVec3::new(0.3, 0.5, -0.81).normalize();
    let cos_disc = 3f64.to_radians().cos();
    Equirect::from_fn(width, height, move |d: DVec3| {
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
fn main() {
    let gpu = GpuContext::new(&ContextOptions {
        validation: false,
        device_name: None,
    })
    .unwrap();
    let src = synthetic_environment(512, 256);
    for face in [128u32, 256] {
        let params = PrefilterParams {
            face_size: face,
            layers: 8,
            beta_min: 0.02,
            beta_max: 1.0,
        };
        let t = std::time::Instant::now();
        let env = GpuPrefilter::new(&gpu)
            .unwrap()
            .run(&gpu, &src, &params, 1.0, 0.0)
            .unwrap();
        let g = env.read_back(&gpu).unwrap();
        eprintln!("face {face}: gpu {:?}", t.elapsed());
        for k in 1..3 {
            let layer = &g.layers[k];
            let m = layer.face_size;
            let mut worst = (0.0, 0, 0, 0, 0.0, 0.0);
            for index in (0..6 * m * m).step_by(3) {
                let (f, j, i) = (index / (m * m), (index / m) % m, index % m);
                let d = texel_direction(f as usize, i, j, m);
                if d.dot(DVec3::new(0.3, 0.5, -0.81).normalize()) < 0.95 && d.y.abs() > 0.2 {
                    continue;
                }
                let want = prefiltered_radiance_definition(&src, d, g.betas[k]);
                let got = layer.get(f as usize, i, j);
                let e = (got[0] as f64 - want[0]).abs() / want[0];
                if e > worst.0 {
                    worst = (e, f, i, j, got[0] as f64, want[0]);
                }
            }
            eprintln!("  layer {k} face {m}: worst {:?}", worst);
        }
    }
}
