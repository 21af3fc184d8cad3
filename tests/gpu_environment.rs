//! The GPU prefilter (compute) against closed forms, the CPU oracle and SPEC §4's definition.

mod common;

use common::{assert_no_validation_messages, validated_gpu};
use shikki::environment::gpu::GpuPrefilter;
use shikki::environment::{Equirect, PrefilterParams};

#[test]
fn white_furnace_layers_are_constant_and_irradiance_is_pi_c() {
    let gpu = validated_gpu();
    let prefilter = GpuPrefilter::new(&gpu).unwrap();
    let c = [0.75f32, 1.5, 3.0];
    let source = Equirect::constant(256, 128, c);
    let params = PrefilterParams {
        face_size: 64,
        layers: 8,
        beta_min: 0.02,
        beta_max: 1.0,
    };
    let env = prefilter.run(&gpu, &source, &params, 1.0, 30.0).unwrap();
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
