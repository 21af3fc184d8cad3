use shikki::environment::gpu::GpuPrefilter;
use shikki::environment::load::load_environment;
use shikki::environment::{oracle, PrefilterParams};
use shikki::gpu::{ContextOptions, GpuContext};
fn main() {
    let gpu = GpuContext::new(&ContextOptions {
        validation: true,
        device_name: None,
    })
    .unwrap();
    let src = load_environment("builtin:studio").unwrap().image;
    let params = PrefilterParams::for_source_width(src.width);
    let env = GpuPrefilter::new(&gpu)
        .unwrap()
        .run(&gpu, &src, &params, 1.0, 0.0)
        .unwrap();
    let g = env.read_back(&gpu).unwrap();
    let l1 = &g.layers[1];
    for (i, j) in [(55u32, 56u32), (56, 56), (60, 60), (64, 64), (72, 72)] {
        eprintln!("({i},{j}): {:?}", l1.get(4, i, j));
    }
    let t = std::time::Instant::now();
    let c = oracle::prefilter_cpu(&src, &params, 1.0, 0.0).unwrap();
    eprintln!("cpu {:?}", t.elapsed());
    for (k, (a, b)) in g.layers.iter().zip(&c.layers).enumerate() {
        let nan = a
            .texels
            .iter()
            .filter(|t| t.iter().any(|x| !x.is_finite()))
            .count();
        let mut worst = 0f64;
        for (x, y) in a.texels.iter().zip(&b.texels) {
            for ch in 0..3 {
                let r = ((x[ch] - y[ch]).abs() / y[ch].abs().max(1e-6)) as f64;
                if r.is_finite() {
                    worst = worst.max(r);
                }
            }
        }
        eprintln!(
            "layer {k} face {} nan {nan} worst rel {worst:.3e}",
            a.face_size
        );
        let m = a.face_size as usize;
        let mut shown = 0;
        for (idx, t) in a.texels.iter().enumerate() {
            if t.iter().any(|x| !x.is_finite()) && shown < 12 {
                shown += 1;
                eprintln!(
                    "  nan at face {} i {} j {}",
                    idx / (m * m),
                    idx % m,
                    (idx / m) % m
                );
            }
        }
    }
    eprintln!("{:?}", gpu.take_validation_messages());
}
