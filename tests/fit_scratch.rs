use shikki::fit::synth::{synthesize, Noise, DEFAULT_RATIOS};
use shikki::fit::{fit_measurements, FitOptions};
use shikki::model::{FresnelTable, LacquerMaterial};

#[test]
fn scratch() {
    for preset in ["smooth-black", "rough-red", "smooth-red"] {
        for (noise, seed) in [(0.0, 0), (0.02, 1), (0.02, 2)] {
            let truth = LacquerMaterial::preset(preset).unwrap();
            let t0 = std::time::Instant::now();
            let (data, _) = synthesize(
                &truth,
                &DEFAULT_RATIOS,
                Noise {
                    relative: noise,
                    seed,
                },
            )
            .unwrap();
            let t1 = t0.elapsed();
            let fit = fit_measurements(
                &data,
                &FitOptions {
                    reference: Some(truth.clone()),
                },
            )
            .unwrap();
            let t2 = t0.elapsed();
            let m = &fit.material;
            let tf = FresnelTable::dielectric(1.5, 0.0045).unwrap();
            let mut worst = (0.0f64, 0usize);
            for k in 0..=85 {
                let a = fit.fresnel.eval(k as f64);
                let b = tf.eval(k as f64);
                for c in 0..3 {
                    let e = (a[c] - b[c]).abs();
                    if e > worst.0 {
                        worst = (e, k);
                    }
                }
            }
            eprintln!(
                "{preset} noise {noise} seed {seed}: rows {} synth {:?} fit {:?}",
                data.rows.len(),
                t1,
                t2 - t1
            );
            eprintln!(
                "  m {:.6} a {:.6} b {:.6} c {:?} kd {:?} r {}",
                m.beckmann_m, m.diffuse_a, m.diffuse_b, m.lacquer_law, m.albedo, m.lacquer_ratio
            );
            eprintln!(
                "  fresnel worst 0..85 {:.2e} at {}  rms {:.4} notes {:?}",
                worst.0, worst.1, fit.relative_rms, fit.notes
            );
            let info: Vec<String> = fit
                .fresnel_information
                .iter()
                .map(|i| format!("{:.1e}", i[1]))
                .collect();
            eprintln!("  info {}", info.join(" "));
            if noise > 0.0 {
                let errs: Vec<String> = (0..=90)
                    .map(|k| {
                        format!(
                            "{:.3}",
                            (fit.fresnel.eval(k as f64)[1] - tf.eval(k as f64)[1])
                        )
                    })
                    .collect();
                eprintln!("  ferr {}", errs.join(" "));
            }
        }
    }
}
