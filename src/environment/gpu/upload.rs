//! Host → device for an already prefiltered environment (e.g. one read from an on-disk cache):
//! checks that the host data has the shape [`GpuPrefilter::run`](super::GpuPrefilter::run)
//! produces, then builds the same [`GpuEnvironment`]: host buffers copied into sampled cube
//! images, freed once copied.

use super::{copy_to_image, cube_bytes, cube_image_usage, GpuEnvironment};
use crate::environment::image::{CubeImage, PrefilteredEnvironment};
use crate::environment::params::{MAX_FACE_SIZE, MIN_LAYER_FACE};
use crate::gpu::shaders::interface::MAX_ENV_LAYERS;
use crate::gpu::{Buffer, BufferDesc, BufferUsage, GpuContext, ImageDesc};
use crate::{Error, Result};

impl GpuEnvironment {
    /// Uploads `env` (layers with their β, and the irradiance cube) to the device. The input is
    /// validated first: K in 2..=`MAX_ENV_LAYERS` (20) layers, one β per layer (β_0 = 0, then
    /// finite, in (0, 4], non-decreasing), power-of-two faces (layer 0 in 16..=4096, the others
    /// and the irradiance no larger than layer 0, none larger than the one before), 6·M² texels
    /// per cube, all finite.
    pub fn upload(gpu: &GpuContext, env: &PrefilteredEnvironment) -> Result<GpuEnvironment> {
        validate(env)?;
        let layer_buffers = env
            .layers
            .iter()
            .map(|cube| Ok((cube.face_size, storage_buffer(gpu, "layer", cube)?)))
            .collect::<Result<Vec<_>>>()?;
        let irradiance_buffer = (
            env.irradiance.face_size,
            storage_buffer(gpu, "irradiance", &env.irradiance)?,
        );
        let sampled = cube_image_usage();
        let layers = env
            .layers
            .iter()
            .map(|cube| gpu.create_image(ImageDesc::cube("layer", cube.face_size).usage(sampled)))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let irradiance = gpu
            .create_image(ImageDesc::cube("irradiance", env.irradiance.face_size).usage(sampled))?;
        // The buffers were written through their mapping before the submit, which makes the host
        // writes visible to the copies.
        gpu.submit_and_wait(|rec| {
            for ((_, buffer), image) in layer_buffers.iter().zip(&layers) {
                copy_to_image(rec, buffer, image);
            }
            copy_to_image(rec, &irradiance_buffer.1, &irradiance);
            Ok(())
        })?;
        Ok(GpuEnvironment::new(env.betas.clone(), layers, irradiance))
    }
}

/// A host-visible buffer with the usage `run`'s cube buffers have, holding `cube`'s texels.
fn storage_buffer(gpu: &GpuContext, name: &str, cube: &CubeImage) -> Result<Buffer> {
    let mut buffer = gpu.create_buffer(BufferDesc::upload(
        name,
        cube_bytes(cube.face_size),
        BufferUsage::STORAGE | BufferUsage::TRANSFER_SRC,
    ))?;
    buffer.write(&cube.texels)?;
    Ok(buffer)
}

/// The shape `GpuPrefilter::run` produces, so the renderer can sample the result.
pub(crate) fn validate(env: &PrefilteredEnvironment) -> Result<()> {
    let k = env.layers.len();
    if !(2..=MAX_ENV_LAYERS).contains(&k) {
        return Err(Error::invalid(
            "environment layers",
            k,
            format!(
                "K must be in 2..={MAX_ENV_LAYERS} (layer 0 is the sharp map); re-run the prefilter"
            ),
        ));
    }
    if env.betas.len() != k {
        return Err(Error::invalid(
            "environment betas",
            env.betas.len(),
            format!("must hold one β per layer ({k} layers)"),
        ));
    }
    if env.betas[0] != 0.0 {
        return Err(Error::invalid(
            "environment betas[0]",
            env.betas[0],
            "must be 0 (layer 0 is the unblurred map)",
        ));
    }
    for (index, pair) in env.betas.windows(2).enumerate() {
        let beta = pair[1];
        if !(beta.is_finite() && beta > 0.0 && beta <= 4.0) {
            return Err(Error::invalid(
                format!("environment betas[{}]", index + 1),
                beta,
                "must be finite and in (0, 4]",
            ));
        }
        if beta < pair[0] {
            return Err(Error::invalid(
                format!("environment betas[{}]", index + 1),
                beta,
                format!("must be ≥ betas[{index}] = {} (β grows with k)", pair[0]),
            ));
        }
    }
    let base = env.layers[0].face_size;
    if !(MIN_LAYER_FACE..=MAX_FACE_SIZE).contains(&base) || !base.is_power_of_two() {
        return Err(Error::invalid(
            "environment layers[0] face size",
            base,
            format!("must be a power of two in {MIN_LAYER_FACE}..={MAX_FACE_SIZE}"),
        ));
    }
    let mut previous = base;
    for (index, cube) in env.layers.iter().enumerate() {
        let field = format!("environment layers[{index}]");
        check_face(&field, cube.face_size, previous)?;
        check_texels(&field, cube)?;
        previous = cube.face_size;
    }
    check_face("environment irradiance", env.irradiance.face_size, base)?;
    check_texels("environment irradiance", &env.irradiance)
}

fn check_face(field: &str, face: u32, largest: u32) -> Result<()> {
    if face == 0 || face > largest || !face.is_power_of_two() {
        return Err(Error::invalid(
            format!("{field} face size"),
            face,
            format!("must be a power of two in 1..={largest} (no larger than the layer before)"),
        ));
    }
    Ok(())
}

fn check_texels(field: &str, cube: &CubeImage) -> Result<()> {
    let m = cube.face_size as usize;
    if cube.texels.len() != 6 * m * m {
        return Err(Error::invalid(
            format!("{field} texel count"),
            cube.texels.len(),
            format!("must be 6·M² = {} for face size M = {m}", 6 * m * m),
        ));
    }
    if let Some(index) = cube
        .texels
        .iter()
        .position(|t| !t.iter().all(|c| c.is_finite()))
    {
        return Err(Error::invalid(
            format!("{field} texel {index}"),
            format!("{:?}", cube.texels[index]),
            "every channel must be finite (the data is corrupt; re-run the prefilter)",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(face_size: u32, value: f32) -> CubeImage {
        CubeImage {
            face_size,
            texels: vec![[value, value, value, 1.0]; 6 * (face_size as usize).pow(2)],
        }
    }

    fn good() -> PrefilteredEnvironment {
        PrefilteredEnvironment {
            betas: vec![0.0, 0.02, 0.1],
            layers: vec![cube(64, 1.0), cube(64, 1.0), cube(16, 1.0)],
            irradiance: cube(32, 3.0),
        }
    }

    fn message(env: &PrefilteredEnvironment) -> String {
        validate(env).unwrap_err().to_string()
    }

    #[test]
    fn a_prefilter_shaped_environment_is_accepted() {
        validate(&good()).unwrap();
    }

    #[test]
    fn each_malformed_field_is_named() {
        let mut env = good();
        env.layers.truncate(1);
        env.betas.truncate(1);
        assert!(message(&env).contains("2..=20"), "{}", message(&env));

        let mut env = good();
        env.betas.pop();
        assert!(message(&env).contains("one β per layer"));

        let mut env = good();
        env.betas[0] = 0.01;
        assert!(message(&env).contains("betas[0]"));

        let mut env = good();
        env.betas[2] = 0.01;
        assert!(message(&env).contains("betas[2]"), "{}", message(&env));

        let mut env = good();
        env.betas[1] = f64::NAN;
        assert!(message(&env).contains("betas[1]"));

        let mut env = good();
        env.layers[0] = cube(48, 1.0);
        assert!(message(&env).contains("layers[0] face size"));

        let mut env = good();
        env.layers[2] = cube(128, 1.0);
        assert!(message(&env).contains("layers[2] face size"));

        let mut env = good();
        env.layers[1].texels.pop();
        assert!(message(&env).contains("layers[1] texel count"));

        let mut env = good();
        env.irradiance.texels[7][1] = f32::INFINITY;
        assert!(
            message(&env).contains("irradiance texel 7"),
            "{}",
            message(&env)
        );

        let mut env = good();
        env.irradiance = cube(128, 1.0);
        assert!(message(&env).contains("irradiance face size"));
    }
}
