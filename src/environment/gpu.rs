//! The prefilter on the GPU: the oracle's steps (`oracle.rs`), each a function of the same name
//! recording one compute step, all in one submit with barriers between them, ending in sampled
//! cube images for the fragment shader. No CPU fallback: the CPU twin exists for tests and
//! benchmarks only.
//!
//! ```text
//! equirect ──equirect_to_cube──► base (face N) ──downsample──► mips N/2 … ──┬─ blur_layer(β_k) ─► layer k
//!                                   └──────────────────────────► layer 0     └─ irradiance ──────► E(n)
//! ```
//!
//! Every cube lives in a storage buffer while the steps write it and is read as a texel buffer
//! (quirk `ssbo_gather_is_per_lane`); the last step copies the buffers into the cube images.

use super::bright::BrightLight;
use super::image::{CubeImage, Equirect, PrefilteredEnvironment};
use super::params::{
    EnvironmentLight, EnvironmentModel, LayerPlan, PrefilterParams, LOBE_CUTOFF, MAX_FACE_SIZE,
    MIN_LAYER_FACE,
};
use super::sharp_source::SharpSource;
use crate::gpu::shaders::interface::{
    BlurLayerParams, DownsampleParams, EquirectToCubeParams, IrradianceParams, LayerApronParams,
    NearHeader, NEAR_TEXELS_BINDING, PREFILTER_DEST_BINDING, PREFILTER_SOURCE_BINDING,
    PREFILTER_WORKGROUP,
};
use crate::gpu::{
    Access, AdapterInfo, Binding, BindingKind, Buffer, BufferDesc, BufferUsage, ComputePipeline,
    DescriptorSet, GpuContext, Image, ImageUsage, ImageUse, Layout, Recorder, Resource,
};
use crate::{Error, Result};
use std::mem::{offset_of, size_of};

mod run;
mod upload;

use run::PrefilterRun;

/// The smallest equirectangular source the prefilter takes, in pixels: [`MIN_SOURCE_WIDTH`] ×
/// [`MIN_SOURCE_HEIGHT`]. The C API holds caller arrays to it when an environment is made
/// (`shikki_environment_create_rgb`), so a map no render can draw is refused there, once, and
/// not by every render that uses it.
pub const MIN_SOURCE_WIDTH: u32 = 2;
/// See [`MIN_SOURCE_WIDTH`].
pub const MIN_SOURCE_HEIGHT: u32 = 1;

/// Steps 2–4 read the cube they gather from as a texel buffer and write a storage buffer.
const TEXEL_IO_BINDINGS: [Binding; 2] = [
    Binding::new(PREFILTER_SOURCE_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(PREFILTER_DEST_BINDING, BindingKind::StorageBuffer),
];

/// The apron pass (layer_apron.comp): the layers as copied, and the layers with aprons, written
/// through a storage texel buffer: the texels of a large map's layers exceed what a storage
/// buffer may bind (maxStorageBufferRange, 128 MiB on lavapipe), not what a texel buffer holds.
const APRON_BINDINGS: [Binding; 2] = [
    Binding::new(PREFILTER_SOURCE_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(PREFILTER_DEST_BINDING, BindingKind::StorageTexelBuffer),
];

/// Step 1: the equirect (texel buffer), the cube, and the list of texels the near pass finishes
/// (see `equirect_to_cube_body.glsl`).
const TO_CUBE_BINDINGS: [Binding; 3] = [
    Binding::new(PREFILTER_SOURCE_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(PREFILTER_DEST_BINDING, BindingKind::StorageBuffer),
    Binding::new(NEAR_TEXELS_BINDING, BindingKind::StorageBuffer),
];

/// Byte offset of the near pass's indirect dispatch arguments in the near-texel list.
const NEAR_DISPATCH_OFFSET: u64 = offset_of!(NearHeader, dispatch_x) as u64;

/// The size of a push-constant block, for its pipeline layout.
fn push_size<T>() -> u32 {
    size_of::<T>() as u32
}

/// The prefilter pipelines, one per step, made once.
pub struct GpuPrefilter {
    equirect_to_cube: ComputePipeline,
    /// Step 1's second dispatch, which finishes near-edge sub-samples in double precision; only
    /// with shaderFloat64 (the fp32 shader has no near sub-samples).
    equirect_near: Option<ComputePipeline>,
    downsample: ComputePipeline,
    blur_layer: ComputePipeline,
    irradiance: ComputePipeline,
}

/// GPU time of each step of the last run, from timestamp queries (seconds).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrefilterTimings {
    pub equirect_to_cube: f64,
    pub mip_chain: f64,
    /// One entry per blurred layer k = 1..K.
    pub layers: Vec<f64>,
    pub irradiance: f64,
    pub copy_to_images: f64,
}

/// The prefiltered environment on the device: cube images ready to sample (and to copy back,
/// for tests and `shikki prefilter`). The buffers the prefilter wrote are freed once copied.
pub struct GpuEnvironment {
    pub betas: Vec<f64>,
    pub layers: Vec<Image>,
    pub irradiance: Image,
    /// Every layer's texels in one texel buffer (the `brdf` model's lookups), made by the first
    /// draw that needs it: [`GpuEnvironment::layer_texels`].
    layer_texels: std::sync::OnceLock<Buffer>,
    /// The `brdf` model's sources, attached by the renderer the first time a draw in that model
    /// uses this map: [`GpuEnvironment::brdf_sources`].
    bright: std::sync::OnceLock<Box<BrightEnvironment>>,
}

/// What the `brdf` model reads of a map (bright.rs): the residual's layers, and the bright parts
/// taken out of it as directional lights (world frame); and the same for the rough materials'
/// split (`split_bright_rough`: every bright block a light), which the grid and filtered
/// importance sampling read where the camera looks.
pub struct BrightEnvironment {
    residual: GpuEnvironment,
    lights: Vec<BrightLight>,
    rough_residual: GpuEnvironment,
    rough_lights: Vec<BrightLight>,
    /// The rough split's blocks' size (radians, `BrightSplit::block_angle`).
    rough_block_angle: f64,
    /// Both residuals' own pixels for the lattice's sharp reads (sharp_source.rs), or none.
    sharp: Option<[SharpSource; 2]>,
    /// The residual's layer texels, then the rough residual's, then their pixels:
    /// [`BrightEnvironment::texels`].
    texels: std::sync::OnceLock<Buffer>,
}

impl BrightEnvironment {
    /// The two splits of one map (the rough one with its blocks' size), with both residuals' own
    /// pixels for the sharp reads (`None`: the layers alone). Both residuals must have the same
    /// layers (β and face sizes), and their pixels the same size: the lookups read them through
    /// one layer table.
    pub fn new(
        (residual, lights): (GpuEnvironment, Vec<BrightLight>),
        (rough_residual, rough_lights, rough_block_angle): (GpuEnvironment, Vec<BrightLight>, f64),
        sharp: Option<[SharpSource; 2]>,
    ) -> Result<Self> {
        same_layers(&residual, &rough_residual, "the rough split's residual")?;
        if let Some([a, b]) = &sharp {
            if (a.width, a.height, a.rotation_deg) != (b.width, b.height, b.rotation_deg) {
                return Err(Error::Internal(
                    "the two residuals' sharp sources differ in size or rotation".into(),
                ));
            }
        }
        Ok(Self {
            residual,
            lights,
            rough_residual,
            rough_lights,
            rough_block_angle,
            sharp,
            texels: std::sync::OnceLock::new(),
        })
    }

    /// The residual's and then the rough residual's layer texels in one texel buffer, then their
    /// pixels, made on first use and kept.
    fn texels(&self, gpu: &GpuContext, apron: &LayerApronPass) -> Result<&Buffer> {
        let pixels: Vec<&[[u32; 4]]> = self
            .sharp
            .iter()
            .flatten()
            .map(|source| &source.texels[..])
            .collect();
        kept_texels(
            &self.texels,
            (gpu, apron),
            (&[&self.residual, &self.rough_residual], &pixels),
        )
    }

    /// Where the sharp sources' pixels start in [`texels`](Self::texels), and their size.
    fn sharp_layout(&self) -> Option<SharpLayout> {
        let [residual, rough] = self.sharp.as_ref()?;
        let layers = 2 * layer_texel_offsets(self.residual.layer_faces()).1;
        Some(SharpLayout {
            first_texel: [layers, layers + residual.texels.len() as u64],
            width: rough.width,
            height: rough.height,
            rotation_deg: rough.rotation_deg,
        })
    }
}

/// `Err` unless `theirs` has `ours`'s layers (the same β and face sizes).
fn same_layers(ours: &GpuEnvironment, theirs: &GpuEnvironment, what: &str) -> Result<()> {
    let (our_faces, their_faces) = (ours.layer_faces(), theirs.layer_faces());
    if theirs.betas != ours.betas || our_faces != their_faces {
        return Err(Error::Internal(format!(
            "{what} has layers β {:?} at faces {their_faces:?}, the map β {:?} at faces \
             {our_faces:?}: prefilter both with the same parameters",
            theirs.betas, ours.betas
        )));
    }
    Ok(())
}

/// What the `brdf` model's shaders read of a map: the layer texels (the residual's, then the
/// rough residual's from `lights.rough_first_texel`), and the two splits' lights.
pub struct BrdfSources<'a> {
    pub texels: &'a Buffer,
    pub lights: BrdfLights<'a>,
}

/// The two splits' lights, where the rough residual's texels start, and the rough split's blocks'
/// size (radians; the lattice reads that split from `brdf_quadrature::rough_lattice_m` of it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BrdfLights<'a> {
    pub lights: &'a [BrightLight],
    pub rough_lights: &'a [BrightLight],
    pub rough_first_texel: u64,
    pub rough_block_angle: f64,
    /// Where the residuals' own pixels are, for the lattice's sharp reads (none: layers alone).
    pub sharp: Option<SharpLayout>,
}

/// The residuals' own pixels in the `brdf` model's texel buffer (sharp_source.rs): the first
/// texel of the residual's and of the rough residual's, the map's size, and its rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SharpLayout {
    pub first_texel: [u64; 2],
    pub width: u32,
    pub height: u32,
    pub rotation_deg: f64,
}

/// The index of each layer's first texel when the layers of `faces` are stored one after the
/// other with a one-texel apron around each face (layer_apron.comp), 6·(M + 2)² texels each (what
/// `ENV_LAYER_TEXELS_BINDING` holds), and the total.
pub fn layer_texel_offsets(faces: impl IntoIterator<Item = u32>) -> (Vec<u64>, u64) {
    texel_offsets(faces.into_iter().map(|face| face + 2))
}

/// The first texel of each cube of `faces` stored one after the other, 6·M² texels each, and the
/// total.
fn texel_offsets(faces: impl IntoIterator<Item = u32>) -> (Vec<u64>, u64) {
    let mut next = 0;
    let offsets = faces
        .into_iter()
        .map(|face| {
            let first = next;
            next += 6 * u64::from(face) * u64::from(face);
            first
        })
        .collect();
    (offsets, next)
}

/// What the sampled cube images are used for: sampled by the draws, filled by a copy, copied back
/// by [`GpuEnvironment::read_back`].
pub(crate) fn cube_image_usage() -> ImageUsage {
    ImageUsage::SAMPLED | ImageUsage::TRANSFER_DST | ImageUsage::TRANSFER_SRC
}

fn cube_bytes(face: u32) -> u64 {
    6 * u64::from(face) * u64::from(face) * 16
}

/// Workgroups along each side of a face: one per `PREFILTER_WORKGROUP`² tile.
fn groups(face: u32) -> u32 {
    face.div_ceil(PREFILTER_WORKGROUP)
}

impl GpuEnvironment {
    /// The environment as the prefilter or an upload leaves it (no texel copy yet).
    pub(crate) fn new(betas: Vec<f64>, layers: Vec<Image>, irradiance: Image) -> Self {
        Self {
            betas,
            layers,
            irradiance,
            layer_texels: std::sync::OnceLock::new(),
            bright: std::sync::OnceLock::new(),
        }
    }

    /// Attaches the map's bright split (the first one attached stays). The residual must have
    /// this map's layers (the same β and face sizes): a draw reads both through one layer table.
    pub fn attach_bright(&self, bright: BrightEnvironment) -> Result<()> {
        same_layers(self, &bright.residual, "the bright split's residual")?;
        let _ = self.bright.set(Box::new(bright));
        Ok(())
    }

    /// Whether a bright split is attached.
    pub fn has_bright(&self) -> bool {
        self.bright.get().is_some()
    }

    /// What the `brdf` model's lookups read and the lights it adds: the attached splits'
    /// residuals and lights, or without them this map itself for both and no lights (an
    /// environment uploaded by hand, as tests do). `apron` writes the texels on first use.
    pub fn brdf_sources(
        &self,
        gpu: &GpuContext,
        apron: &LayerApronPass,
    ) -> Result<BrdfSources<'_>> {
        let texels = match self.bright.get() {
            Some(bright) => bright.texels(gpu, apron)?,
            None => self.layer_texels(gpu, apron)?,
        };
        Ok(BrdfSources {
            texels,
            lights: self.brdf_lights(),
        })
    }

    /// The lights of [`brdf_sources`](Self::brdf_sources), without making the texel buffer.
    pub fn brdf_lights(&self) -> BrdfLights<'_> {
        match self.bright.get() {
            Some(bright) => BrdfLights {
                lights: &bright.lights,
                rough_lights: &bright.rough_lights,
                rough_first_texel: layer_texel_offsets(bright.residual.layer_faces()).1,
                rough_block_angle: bright.rough_block_angle,
                sharp: bright.sharp_layout(),
            },
            // The map itself for both splits: whichever the lattice reads, the same layers.
            None => BrdfLights {
                lights: &[],
                rough_lights: &[],
                rough_first_texel: 0,
                rough_block_angle: 0.0,
                sharp: None,
            },
        }
    }

    /// Face size of each layer.
    pub fn layer_faces(&self) -> Vec<u32> {
        self.layers.iter().map(|image| image.desc().width).collect()
    }

    /// The layers' texels concatenated in one device-local texel buffer (layer k from
    /// `layer_texel_offsets(layer_faces())[k]`), copied from the images with their aprons by
    /// `apron` on first use and kept. Refused when the device's texel buffers cannot hold them
    /// all.
    pub fn layer_texels(&self, gpu: &GpuContext, apron: &LayerApronPass) -> Result<&Buffer> {
        kept_texels(&self.layer_texels, (gpu, apron), (&[self], &[]))
    }
}

/// The pipeline of layer_apron.comp, which writes an environment's `brdf` layer texels with a
/// one-texel apron around each face ([`concatenated_texels`]). Made once by whoever draws (a
/// renderer keeps one), not per environment: a batch that sweeps the map's rotation makes an
/// environment per job.
pub struct LayerApronPass {
    pipeline: ComputePipeline,
}

impl LayerApronPass {
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        Ok(Self {
            pipeline: gpu.create_compute_pipeline(
                "layer_apron.comp",
                crate::gpu::shaders::LAYER_APRON_COMP,
                &APRON_BINDINGS,
                push_size::<LayerApronParams>(),
            )?,
        })
    }
}

/// The buffer `kept` holds, or [`concatenated_texels`] of `envs` made now and kept there.
fn kept_texels<'a>(
    kept: &'a std::sync::OnceLock<Buffer>,
    (gpu, apron): (&GpuContext, &LayerApronPass),
    parts: (&[&GpuEnvironment], &[&[[u32; 4]]]),
) -> Result<&'a Buffer> {
    if let Some(buffer) = kept.get() {
        return Ok(buffer);
    }
    let _ = kept.set(concatenated_texels(gpu, apron, parts)?);
    kept.get()
        .ok_or_else(|| Error::Internal("the layer texel buffer was not kept".into()))
}

/// The layers of `envs`, one environment after the other, in one device-local texel buffer
/// (layer k of the first from `layer_texel_offsets(layer_faces())[k]`): copied from the images
/// into a buffer face after face, then written with their aprons by `apron` (twin:
/// `brdf_quadrature::apron_texels`), and after them the texels of `pixels` (the residuals' own,
/// sharp_source.rs) copied from the host. Refused when the device's texel buffers cannot hold
/// them all.
fn concatenated_texels(
    gpu: &GpuContext,
    apron: &LayerApronPass,
    (envs, pixels): (&[&GpuEnvironment], &[&[[u32; 4]]]),
) -> Result<Buffer> {
    let layers: Vec<&Image> = envs.iter().flat_map(|env| env.layers.iter()).collect();
    let faces: Vec<u32> = layers.iter().map(|image| image.desc().width).collect();
    let (offsets, layer_total) = layer_texel_offsets(faces.iter().copied());
    let pixel_texels: Vec<[u32; 4]> = pixels.concat();
    let total = layer_total + pixel_texels.len() as u64;
    let (sources, source_total) = texel_offsets(faces.iter().copied());
    let limit = u64::from(gpu.info().max_texel_buffer_elements).min(i32::MAX as u64);
    if total > limit {
        return Err(Error::invalid(
            "environment_model",
            "brdf",
            format!(
                "the `brdf` model reads the environment's {total} layer texels from one \
                 texel buffer, and this device holds at most {limit}; use a smaller \
                 environment face size, or the `paper` model"
            ),
        ));
    }
    let faces_copied = gpu.create_buffer(BufferDesc::device_local(
        "environment layer texels without aprons",
        source_total * 16,
        BufferUsage::UNIFORM_TEXEL | BufferUsage::TRANSFER_DST,
    ))?;
    let buffer = gpu.create_buffer(BufferDesc::device_local(
        "environment layer texels",
        total * 16,
        BufferUsage::UNIFORM_TEXEL
            | BufferUsage::STORAGE_TEXEL
            | BufferUsage::TRANSFER_SRC
            | BufferUsage::TRANSFER_DST,
    ))?;
    let staged = match pixel_texels.is_empty() {
        true => None,
        false => {
            let mut staging = gpu.create_buffer(BufferDesc::upload(
                "environment residual pixels (staging)",
                pixel_texels.len() as u64 * 16,
                BufferUsage::TRANSFER_SRC,
            ))?;
            staging.write(&pixel_texels)?;
            Some(staging)
        }
    };
    let set = gpu.create_descriptor_set(
        apron.pipeline.layout(),
        &[
            (
                PREFILTER_SOURCE_BINDING,
                Resource::TexelBuffer(&faces_copied),
            ),
            (PREFILTER_DEST_BINDING, Resource::UintTexelBuffer(&buffer)),
        ],
    )?;
    let sampled = ImageUse::new(Access::GraphicsShaderRead, Layout::ShaderRead);
    let transfer_src = ImageUse::new(Access::TransferRead, Layout::TransferSrc);
    gpu.submit_and_wait(|rec| {
        for (image, &first) in layers.iter().zip(&sources) {
            // Draws may have sampled the image; it goes back to being sampled after.
            rec.image_barrier(image, sampled, transfer_src);
            rec.copy_image_rows_to_buffer(image, image.desc().height, &faces_copied, first * 16);
            rec.image_barrier(image, transfer_src, sampled);
        }
        rec.memory_barrier(Access::TransferWrite, Access::ComputeShaderRead);
        rec.bind_compute(&apron.pipeline, &set);
        for ((&face_size, &source), &dest) in faces.iter().zip(&sources).zip(&offsets) {
            // Both below `total`, which the limit keeps within an i32.
            let constants = LayerApronParams {
                face_size,
                source_first: source as u32,
                dest_first: dest as u32,
            };
            rec.push_constants(&apron.pipeline, bytemuck::bytes_of(&constants));
            rec.dispatch(groups(face_size + 2), groups(face_size + 2), 6);
        }
        if let Some(staging) = &staged {
            // After every layer's texels: other bytes than the apron pass writes, but a texel
            // buffer's shader writes are tracked over its whole range, so the copy waits.
            rec.memory_barrier(Access::ComputeShaderWrite, Access::TransferWrite);
            rec.copy_buffer_at(staging, &buffer, layer_total * 16);
            rec.memory_barrier(Access::TransferWrite, Access::GraphicsShaderRead);
            rec.memory_barrier(Access::TransferWrite, Access::ComputeShaderRead);
        }
        // The draws (and the compute evaluator) that read the buffer are later submits; the
        // barriers make the pass's writes visible to their shaders.
        rec.memory_barrier(Access::ComputeShaderWrite, Access::GraphicsShaderRead);
        rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
        Ok(())
    })?;
    Ok(buffer)
}

impl GpuPrefilter {
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        use crate::gpu::shaders::*;
        let f64 = gpu.info().shader_float64;
        let to_cube = push_size::<EquirectToCubeParams>();
        let (to_cube_name, to_cube_spirv) = match f64 {
            true => ("equirect_to_cube_f64.comp", EQUIRECT_TO_CUBE_F64_COMP),
            false => ("equirect_to_cube.comp", EQUIRECT_TO_CUBE_COMP),
        };
        let step =
            |name, spirv, push| gpu.create_compute_pipeline(name, spirv, &TEXEL_IO_BINDINGS, push);
        Ok(Self {
            equirect_to_cube: gpu.create_compute_pipeline(
                to_cube_name,
                to_cube_spirv,
                &TO_CUBE_BINDINGS,
                to_cube,
            )?,
            equirect_near: if f64 {
                Some(gpu.create_compute_pipeline(
                    "equirect_to_cube_near.comp",
                    EQUIRECT_TO_CUBE_NEAR_COMP,
                    &TO_CUBE_BINDINGS,
                    to_cube,
                )?)
            } else {
                None
            },
            downsample: step(
                "downsample.comp",
                DOWNSAMPLE_COMP,
                push_size::<DownsampleParams>(),
            )?,
            blur_layer: step(
                "prefilter_layers.comp",
                PREFILTER_LAYERS_COMP,
                push_size::<BlurLayerParams>(),
            )?,
            irradiance: step(
                "irradiance.comp",
                IRRADIANCE_COMP,
                push_size::<IrradianceParams>(),
            )?,
        })
    }

    /// Runs equirect → cube → mips → layers + irradiance, all on the GPU.
    pub fn run(
        &self,
        gpu: &GpuContext,
        source: &Equirect,
        params: &PrefilterParams,
        light: EnvironmentLight,
    ) -> Result<GpuEnvironment> {
        self.run_timed(gpu, source, params, light)
            .map(|(env, _)| env)
    }

    /// [`run`](Self::run), also returning the GPU time of each step.
    pub fn run_timed(
        &self,
        gpu: &GpuContext,
        source: &Equirect,
        params: &PrefilterParams,
        light: EnvironmentLight,
    ) -> Result<(GpuEnvironment, PrefilterTimings)> {
        let EnvironmentLight {
            intensity,
            rotation_deg,
        } = light;
        params.validate()?;
        check_source(source, intensity, rotation_deg)?;
        check_device_limits(gpu.info(), source, params)?;
        let run = PrefilterRun::new(gpu, self, source, params)?;
        let (rot_sin, rot_cos) = rotation_deg.to_radians().sin_cos();
        let to_cube = EquirectToCubeParams {
            src_width: source.width,
            src_height: source.height,
            face_size: params.face_size,
            intensity: intensity as f32,
            rotation_cos: rot_cos as f32,
            rotation_sin: rot_sin as f32,
            supersample: params.supersample(source.width),
        };
        // Timestamps: start, after step 1, after the mips, after each layer, after irradiance, end.
        let stamps = gpu.create_timestamp_pool(run.buffers.layers.len() as u32 + 5)?;
        gpu.submit_and_wait(|rec| {
            rec.reset_timestamps(&stamps);
            let mut stamp = 0;
            let mut mark = |rec: &mut Recorder<'_>| {
                rec.timestamp(&stamps, stamp);
                stamp += 1;
            };
            mark(rec);
            self.equirect_to_cube(rec, &run, &to_cube);
            mark(rec);
            for (set, &face) in run.sets.downsample.iter().zip(&run.buffers.mip_faces[1..]) {
                self.downsample(rec, set, face);
            }
            mark(rec);
            // Steps 3 and 4 are independent of each other.
            for ((layer, _), set) in run.buffers.layers.iter().zip(&run.sets.blur) {
                self.blur_layer(rec, set, layer);
                mark(rec);
            }
            self.irradiance(rec, &run.sets.irradiance, run.buffers.irradiance_face);
            mark(rec);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::TransferRead);
            run.copy_to_images(rec);
            mark(rec);
            Ok(())
        })?;
        let t = stamps.read_ns(stamps.capacity())?;
        let span = |a: usize, b: usize| (t[b] - t[a]).max(0.0) * 1e-9;
        let blurred = run.buffers.layers.len();
        let timings = PrefilterTimings {
            equirect_to_cube: span(0, 1),
            mip_chain: span(1, 2),
            layers: (0..blurred).map(|k| span(2 + k, 3 + k)).collect(),
            irradiance: span(2 + blurred, 3 + blurred),
            copy_to_images: span(3 + blurred, 4 + blurred),
        };
        let betas = params.plan().iter().map(|l| l.beta).collect();
        let env = GpuEnvironment::new(betas, run.images, run.irradiance_image);
        Ok((env, timings))
    }

    /// Step 1, twin of [`oracle::equirect_to_cube`](super::oracle::equirect_to_cube): the base
    /// cube from the equirect (equirect_to_cube*.comp), with shaderFloat64 finished by the near
    /// pass over the texels the first dispatch listed.
    fn equirect_to_cube(
        &self,
        rec: &mut Recorder<'_>,
        run: &PrefilterRun,
        constants: &EquirectToCubeParams,
    ) {
        rec.bind_compute(&self.equirect_to_cube, &run.sets.to_cube);
        rec.push_constants(&self.equirect_to_cube, bytemuck::bytes_of(constants));
        let groups = groups(constants.face_size);
        rec.dispatch(groups, groups, 6);
        if let (Some(near), Some(near_set)) = (&self.equirect_near, &run.sets.near) {
            // The list and its dispatch size, and the partial texels it rewrites.
            rec.memory_barrier(Access::ComputeShaderWrite, Access::IndirectCommandRead);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderWrite);
            rec.bind_compute(near, near_set);
            rec.push_constants(near, bytemuck::bytes_of(constants));
            rec.dispatch_indirect(&run.buffers.near_texels, NEAR_DISPATCH_OFFSET);
        }
        rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
    }

    /// Step 2, twin of [`oracle::downsample`](super::oracle::downsample): one level of the mip
    /// chain, face 2·`dst_face_size` → `dst_face_size` (downsample.comp).
    fn downsample(&self, rec: &mut Recorder<'_>, set: &DescriptorSet, dst_face_size: u32) {
        rec.bind_compute(&self.downsample, set);
        let constants = DownsampleParams { dst_face_size };
        rec.push_constants(&self.downsample, bytemuck::bytes_of(&constants));
        rec.dispatch(groups(dst_face_size), groups(dst_face_size), 6);
        rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
    }

    /// Step 3, twin of [`oracle::blur_layer`](super::oracle::blur_layer): one blurred layer from
    /// the mip of its face size (prefilter_layers.comp).
    fn blur_layer(&self, rec: &mut Recorder<'_>, set: &DescriptorSet, layer: &LayerPlan) {
        rec.bind_compute(&self.blur_layer, set);
        let constants = BlurLayerParams {
            face_size: layer.face_size,
            beta: layer.blur as f32,
            cutoff: LOBE_CUTOFF as f32,
        };
        rec.push_constants(&self.blur_layer, bytemuck::bytes_of(&constants));
        rec.dispatch(groups(layer.face_size), groups(layer.face_size), 6);
    }

    /// Step 4, twin of [`oracle::irradiance`](super::oracle::irradiance): the irradiance cube
    /// from the mip of its face size (irradiance.comp).
    fn irradiance(&self, rec: &mut Recorder<'_>, set: &DescriptorSet, face_size: u32) {
        rec.bind_compute(&self.irradiance, set);
        let constants = IrradianceParams { face_size };
        rec.push_constants(&self.irradiance, bytemuck::bytes_of(&constants));
        rec.dispatch(groups(face_size), groups(face_size), 6);
    }
}

/// TransferDst → copy → ShaderRead for the fragment shader.
fn copy_to_image(rec: &mut Recorder<'_>, buffer: &Buffer, image: &Image) {
    rec.image_barrier(
        image,
        ImageUse::new(Access::Nothing, Layout::Undefined),
        ImageUse::new(Access::TransferWrite, Layout::TransferDst),
    );
    rec.copy_buffer_to_image(buffer, image);
    rec.image_barrier(
        image,
        ImageUse::new(Access::TransferWrite, Layout::TransferDst),
        ImageUse::new(Access::GraphicsShaderRead, Layout::ShaderRead),
    );
}

/// Whether the device can hold a cube of face `n` in the prefilter's buffers: each cube is written
/// as one storage buffer and read as one RGBA32F texel buffer.
fn cube_fits(info: &AdapterInfo, n: u32) -> bool {
    cube_bytes(n) <= u64::from(info.max_storage_buffer_range)
        && 6 * u64::from(n) * u64::from(n) <= u64::from(info.max_texel_buffer_elements)
        && n <= info.max_image_dimension_cube
}

/// The largest layer-0 face size (a power of two) this device can prefilter: 1024 on lavapipe,
/// whose storage buffers hold at most 128 MiB. Default face sizes are clamped to it.
pub fn largest_face_size(info: &AdapterInfo) -> u32 {
    let mut n = MAX_FACE_SIZE;
    while n > MIN_LAYER_FACE && !cube_fits(info, n) {
        n /= 2;
    }
    n
}

/// [`PrefilterParams::for_source_width`] with the face size clamped to [`largest_face_size`]: an
/// 8K source (default face 2048) prefilters at face 1024 on lavapipe instead of failing.
pub fn default_params(gpu: &GpuContext, source_width: u32) -> PrefilterParams {
    let mut params = PrefilterParams::for_source_width(source_width);
    params.face_size = params.face_size.min(largest_face_size(gpu.info()));
    params
}

/// [`default_params`] for the environment model that draws with them: SPEC §4's K = 8 for
/// `paper`, [`PrefilterParams::for_model`]'s finer series for `brdf`.
pub fn model_params(
    gpu: &GpuContext,
    source_width: u32,
    model: EnvironmentModel,
) -> PrefilterParams {
    let mut params = PrefilterParams::for_model(source_width, model);
    params.face_size = params.face_size.min(largest_face_size(gpu.info()));
    params
}

/// Refuses, before allocating, a prefilter whose buffers exceed the device's limits (which
/// Vulkan leaves undefined rather than failing).
fn check_device_limits(
    info: &AdapterInfo,
    source: &Equirect,
    params: &PrefilterParams,
) -> Result<()> {
    if !cube_fits(info, params.face_size) {
        let largest = largest_face_size(info);
        return Err(Error::invalid(
            "face size",
            params.face_size,
            format!(
                "{} holds at most face {largest} in one buffer (maxStorageBufferRange {} bytes, \
                 maxTexelBufferElements {}); use --face-size {largest} or smaller",
                info.name, info.max_storage_buffer_range, info.max_texel_buffer_elements,
            ),
        ));
    }
    let pixels = u64::from(source.width) * u64::from(source.height);
    if pixels > u64::from(info.max_texel_buffer_elements) {
        return Err(Error::invalid(
            "environment size",
            format!("{}x{}", source.width, source.height),
            format!(
                "{} reads at most {} source pixels (maxTexelBufferElements); downscale the image",
                info.name, info.max_texel_buffer_elements
            ),
        ));
    }
    Ok(())
}

fn check_source(source: &Equirect, intensity: f64, rotation_deg: f64) -> Result<()> {
    if source.width < MIN_SOURCE_WIDTH || source.height < MIN_SOURCE_HEIGHT {
        return Err(Error::invalid(
            "environment size",
            format!("{}x{}", source.width, source.height),
            format!("must be at least {MIN_SOURCE_WIDTH}x{MIN_SOURCE_HEIGHT} pixels"),
        ));
    }
    if source.pixels.len() != (source.width as usize) * (source.height as usize) {
        return Err(Error::invalid(
            "environment pixels",
            source.pixels.len(),
            "must equal width × height",
        ));
    }
    if !(intensity.is_finite() && intensity >= 0.0) {
        return Err(Error::invalid(
            "env-intensity",
            intensity,
            "must be a finite number ≥ 0",
        ));
    }
    if !rotation_deg.is_finite() {
        return Err(Error::invalid(
            "env-rotation",
            rotation_deg,
            "must be finite (degrees)",
        ));
    }
    Ok(())
}

impl GpuEnvironment {
    /// Copies [`layer_texels`](Self::layer_texels) back to the host (tests): the layers with
    /// their aprons, from `layer_texel_offsets(layer_faces())`, two texels in each
    /// (environment/layer_pair.rs).
    pub fn read_layer_texels(
        &self,
        gpu: &GpuContext,
        apron: &LayerApronPass,
    ) -> Result<Vec<[u32; 4]>> {
        let texels = self.layer_texels(gpu, apron)?;
        let readback =
            gpu.create_buffer(BufferDesc::readback("layer texel readback", texels.size()))?;
        gpu.submit_and_wait(|rec| {
            // layer_texels' submit made its writes visible to later transfers' reads too.
            rec.memory_barrier(Access::ComputeShaderWrite, Access::TransferRead);
            rec.copy_buffer(texels, &readback);
            rec.memory_barrier(Access::TransferWrite, Access::HostRead);
            Ok(())
        })?;
        Ok(readback.read()?)
    }

    /// Copies every layer and the irradiance back to the host (tests, `shikki prefilter`).
    pub fn read_back(&self, gpu: &GpuContext) -> Result<PrefilteredEnvironment> {
        let readback = |image: &Image| -> Result<Buffer> {
            let bytes = cube_bytes(image.desc().width);
            Ok(gpu.create_buffer(BufferDesc::readback("env readback", bytes))?)
        };
        let layers = self
            .layers
            .iter()
            .map(|image| Ok((image, readback(image)?)))
            .collect::<Result<Vec<_>>>()?;
        let irradiance = (&self.irradiance, readback(&self.irradiance)?);
        let sampled = ImageUse::new(Access::GraphicsShaderRead, Layout::ShaderRead);
        let transfer_src = ImageUse::new(Access::TransferRead, Layout::TransferSrc);
        gpu.submit_and_wait(|rec| {
            for (image, dst) in layers.iter().chain(std::iter::once(&irradiance)) {
                // Draws may have sampled the image; it goes back to being sampled after.
                rec.image_barrier(image, sampled, transfer_src);
                rec.copy_image_to_buffer(image, dst);
                rec.image_barrier(image, transfer_src, sampled);
            }
            rec.memory_barrier(Access::TransferWrite, Access::HostRead);
            Ok(())
        })?;
        // Each readback buffer goes as soon as it is read: the host copies and the buffers
        // together would be twice the environment (a cold render's peak memory).
        let cube = |(image, buffer): (&Image, Buffer)| -> Result<CubeImage> {
            Ok(CubeImage {
                face_size: image.desc().width,
                texels: buffer.read()?,
            })
        };
        Ok(PrefilteredEnvironment {
            betas: self.betas.clone(),
            layers: layers.into_iter().map(cube).collect::<Result<_>>()?,
            irradiance: cube(irradiance)?,
        })
    }
}
