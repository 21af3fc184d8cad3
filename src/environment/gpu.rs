//! The prefilter on the GPU: the four compute steps of `mod.rs` in one submit, with barriers
//! between the steps, ending in sampled cube images for the fragment shader. No CPU fallback:
//! the CPU twin (`oracle.rs`) exists for tests and benchmarks only.

use super::image::{CubeImage, Equirect, PrefilteredEnvironment};
use super::params::{
    equirect_supersample, PrefilterParams, LOBE_CUTOFF, MAX_FACE_SIZE, MIN_LAYER_FACE,
};
use crate::gpu::{
    Access, AdapterInfo, Binding, BindingKind, Buffer, BufferDesc, BufferUsage, ComputePipeline,
    DescriptorSet, GpuContext, Image, ImageDesc, ImageUsage, ImageUse, Layout, Recorder, Resource,
};
use crate::{Error, Result};

mod upload;

/// Threads per workgroup side; must equal local_size_x/y in the prefilter shaders.
const WORKGROUP: u32 = 8;

/// Steps that gather from a cube read it as a texel buffer (see `BindingKind::UniformTexelBuffer`).
const TEXEL_IO_BINDINGS: [Binding; 2] = [
    Binding::new(0, BindingKind::UniformTexelBuffer),
    Binding::new(1, BindingKind::StorageBuffer),
];

/// Step 1: the equirect (texel buffer), the cube, and the list of texels the near pass finishes
/// (see `equirect_to_cube_body.glsl`).
const TO_CUBE_BINDINGS: [Binding; 3] = [
    Binding::new(0, BindingKind::UniformTexelBuffer),
    Binding::new(1, BindingKind::StorageBuffer),
    Binding::new(2, BindingKind::StorageBuffer),
];

/// Byte offset of the near pass's indirect dispatch arguments in the near-texel list (after its
/// count), and of the texel indices (after the four-word header).
const NEAR_DISPATCH_OFFSET: u64 = 4;
const NEAR_HEADER_BYTES: u64 = 16;

/// The four prefilter pipelines, made once.
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
}

/// What the sampled cube images are used for: sampled by the draws, filled by a copy, copied back
/// by [`GpuEnvironment::read_back`].
pub(crate) fn cube_image_usage() -> ImageUsage {
    ImageUsage::SAMPLED | ImageUsage::TRANSFER_DST | ImageUsage::TRANSFER_SRC
}

fn cube_bytes(face: u32) -> u64 {
    6 * u64::from(face) * u64::from(face) * 16
}

fn groups(face: u32) -> u32 {
    face.div_ceil(WORKGROUP)
}

impl GpuPrefilter {
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        use crate::gpu::shaders::*;
        let f64 = gpu.info().shader_float64;
        Ok(Self {
            equirect_to_cube: gpu.create_compute_pipeline(
                if f64 {
                    "equirect_to_cube_f64.comp"
                } else {
                    "equirect_to_cube.comp"
                },
                if f64 {
                    EQUIRECT_TO_CUBE_F64_COMP
                } else {
                    EQUIRECT_TO_CUBE_COMP
                },
                &TO_CUBE_BINDINGS,
                28,
            )?,
            equirect_near: if f64 {
                Some(gpu.create_compute_pipeline(
                    "equirect_to_cube_near.comp",
                    EQUIRECT_TO_CUBE_NEAR_COMP,
                    &TO_CUBE_BINDINGS,
                    28,
                )?)
            } else {
                None
            },
            downsample: gpu.create_compute_pipeline(
                "downsample.comp",
                DOWNSAMPLE_COMP,
                &TEXEL_IO_BINDINGS,
                4,
            )?,
            blur_layer: gpu.create_compute_pipeline(
                "prefilter_layers.comp",
                PREFILTER_LAYERS_COMP,
                &TEXEL_IO_BINDINGS,
                12,
            )?,
            irradiance: gpu.create_compute_pipeline(
                "irradiance.comp",
                IRRADIANCE_COMP,
                &TEXEL_IO_BINDINGS,
                4,
            )?,
        })
    }

    /// Runs equirect → cube → mips → layers + irradiance, all on the GPU.
    pub fn run(
        &self,
        gpu: &GpuContext,
        source: &Equirect,
        params: &PrefilterParams,
        intensity: f64,
        rotation_deg: f64,
    ) -> Result<GpuEnvironment> {
        self.run_timed(gpu, source, params, intensity, rotation_deg)
            .map(|(env, _)| env)
    }

    /// [`run`](Self::run), also returning the GPU time of each step.
    pub fn run_timed(
        &self,
        gpu: &GpuContext,
        source: &Equirect,
        params: &PrefilterParams,
        intensity: f64,
        rotation_deg: f64,
    ) -> Result<(GpuEnvironment, PrefilterTimings)> {
        params.validate()?;
        check_source(source, intensity, rotation_deg)?;
        check_device_limits(gpu.info(), source, params)?;
        let plan = params.plan();
        let mip_faces = params.mip_faces();

        let pixels: Vec<[f32; 4]> = source
            .pixels
            .iter()
            .map(|p| [p[0], p[1], p[2], 1.0])
            .collect();
        let mut source_buf = gpu.create_buffer(BufferDesc::upload(
            "environment equirect",
            (pixels.len() * 16) as u64,
            BufferUsage::UNIFORM_TEXEL,
        ))?;
        source_buf.write(&pixels)?;

        let storage = BufferUsage::STORAGE | BufferUsage::TRANSFER_SRC | BufferUsage::UNIFORM_TEXEL;
        let mips: Vec<Buffer> = mip_faces
            .iter()
            .map(|&m| gpu.create_buffer(BufferDesc::device_local("mip", cube_bytes(m), storage)))
            .collect::<std::result::Result<_, _>>()?;
        let mip_of = |face: u32| -> Result<&Buffer> {
            mip_faces
                .iter()
                .position(|&m| m == face)
                .map(|i| &mips[i])
                .ok_or_else(|| Error::invalid("face size", face, "internal: no mip of that size"))
        };
        let mut layer_buffers = Vec::new();
        for layer in plan.iter().skip(1) {
            let buf = gpu.create_buffer(BufferDesc::device_local(
                "layer",
                cube_bytes(layer.face_size),
                storage,
            ))?;
            layer_buffers.push((layer.face_size, buf));
        }
        let irr_face = params.irradiance_face();
        let irradiance_buf = gpu.create_buffer(BufferDesc::device_local(
            "irradiance",
            cube_bytes(irr_face),
            storage,
        ))?;

        // Texels whose sub-samples lie near a pixel edge: at most every texel of the base cube.
        let near_capacity = if self.equirect_near.is_some() {
            6 * u64::from(params.face_size) * u64::from(params.face_size)
        } else {
            0
        };
        let mut near_texels = gpu.create_buffer(BufferDesc::upload(
            "near-edge texels",
            NEAR_HEADER_BYTES + 4 * near_capacity,
            BufferUsage::STORAGE | BufferUsage::INDIRECT,
        ))?;
        // Count 0; the near pass's dispatch (0, 1, 1) groups, counted up by step 1.
        near_texels.write(&[0u32, 0, 1, 1])?;

        // Descriptor sets, made before recording so they outlive the submit.
        let set =
            |pipeline: &ComputePipeline, src: &Buffer, dst: &Buffer| -> Result<DescriptorSet> {
                Ok(gpu.create_descriptor_set(
                    pipeline.layout(),
                    &[(0, Resource::TexelBuffer(src)), (1, Resource::Buffer(dst))],
                )?)
            };
        let to_cube_resources = [
            (0, Resource::TexelBuffer(&source_buf)),
            (1, Resource::Buffer(&mips[0])),
            (2, Resource::Buffer(&near_texels)),
        ];
        let to_cube_set =
            gpu.create_descriptor_set(self.equirect_to_cube.layout(), &to_cube_resources)?;
        let near_set = match &self.equirect_near {
            Some(near) => Some(gpu.create_descriptor_set(near.layout(), &to_cube_resources)?),
            None => None,
        };
        let down_sets: Vec<DescriptorSet> = mips
            .windows(2)
            .map(|pair| set(&self.downsample, &pair[0], &pair[1]))
            .collect::<Result<_>>()?;
        let blur_sets: Vec<DescriptorSet> = layer_buffers
            .iter()
            .map(|(face, dst)| set(&self.blur_layer, mip_of(*face)?, dst))
            .collect::<Result<_>>()?;
        let irr_set = set(&self.irradiance, mip_of(irr_face)?, &irradiance_buf)?;

        // The sampled cube images: layer 0 is the base mip itself.
        let sampled = cube_image_usage();
        let mut layers =
            vec![gpu.create_image(ImageDesc::cube("layer 0", params.face_size).usage(sampled))?];
        for (face, _) in &layer_buffers {
            layers.push(gpu.create_image(ImageDesc::cube("layer", *face).usage(sampled))?);
        }
        let irradiance =
            gpu.create_image(ImageDesc::cube("irradiance", irr_face).usage(sampled))?;

        let (rot_sin, rot_cos) = rotation_deg.to_radians().sin_cos();
        // Timestamps: start, after step 1, after the mips, after each layer, after irradiance, end.
        let stamps = gpu.create_timestamp_pool(layer_buffers.len() as u32 + 5)?;
        let mut stamp = 0u32;
        gpu.submit_and_wait(|rec| {
            rec.reset_timestamps(&stamps);
            let mut mark = |rec: &mut Recorder<'_>| {
                rec.timestamp(&stamps, stamp);
                stamp += 1;
            };
            mark(rec);
            // 1. equirect → cube
            let to_cube_constants = [
                source.width,
                source.height,
                params.face_size,
                (intensity as f32).to_bits(),
                (rot_cos as f32).to_bits(),
                (rot_sin as f32).to_bits(),
                equirect_supersample(source.width, params.face_size),
            ];
            rec.bind_compute(&self.equirect_to_cube, &to_cube_set);
            rec.push_constants(
                &self.equirect_to_cube,
                bytemuck::cast_slice(&to_cube_constants),
            );
            rec.dispatch(groups(params.face_size), groups(params.face_size), 6);
            if let (Some(near), Some(near_set)) = (&self.equirect_near, &near_set) {
                // The list and its dispatch size, and the partial texels it rewrites.
                rec.memory_barrier(Access::ComputeShaderWrite, Access::IndirectCommandRead);
                rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
                rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderWrite);
                rec.bind_compute(near, near_set);
                rec.push_constants(near, bytemuck::cast_slice(&to_cube_constants));
                rec.dispatch_indirect(&near_texels, NEAR_DISPATCH_OFFSET);
            }
            rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
            mark(rec);
            // 2. mip chain, each level from the previous one
            for (level, down_set) in down_sets.iter().enumerate() {
                let face = mip_faces[level + 1];
                rec.bind_compute(&self.downsample, down_set);
                rec.push_constants(&self.downsample, bytemuck::bytes_of(&face));
                rec.dispatch(groups(face), groups(face), 6);
                rec.memory_barrier(Access::ComputeShaderWrite, Access::ComputeShaderRead);
            }
            mark(rec);
            // 3. blurred layers and 4. irradiance: independent of each other
            for ((layer, (face, _)), blur_set) in
                plan.iter().skip(1).zip(&layer_buffers).zip(&blur_sets)
            {
                rec.bind_compute(&self.blur_layer, blur_set);
                rec.push_constants(
                    &self.blur_layer,
                    bytemuck::cast_slice(&[
                        *face,
                        (layer.beta as f32).to_bits(),
                        (LOBE_CUTOFF as f32).to_bits(),
                    ]),
                );
                rec.dispatch(groups(*face), groups(*face), 6);
                mark(rec);
            }
            rec.bind_compute(&self.irradiance, &irr_set);
            rec.push_constants(&self.irradiance, bytemuck::bytes_of(&irr_face));
            rec.dispatch(groups(irr_face), groups(irr_face), 6);
            mark(rec);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::TransferRead);
            // 5. buffers → sampled cube images
            copy_to_image(rec, &mips[0], &layers[0]);
            for ((_, buf), image) in layer_buffers.iter().zip(&layers[1..]) {
                copy_to_image(rec, buf, image);
            }
            copy_to_image(rec, &irradiance_buf, &irradiance);
            mark(rec);
            Ok(())
        })?;
        let t = stamps.read_ns(stamps.capacity())?;
        let span = |a: usize, b: usize| (t[b] - t[a]).max(0.0) * 1e-9;
        let blurred = layer_buffers.len();
        let timings = PrefilterTimings {
            equirect_to_cube: span(0, 1),
            mip_chain: span(1, 2),
            layers: (0..blurred).map(|k| span(2 + k, 3 + k)).collect(),
            irradiance: span(2 + blurred, 3 + blurred),
            copy_to_images: span(3 + blurred, 4 + blurred),
        };

        let env = GpuEnvironment {
            betas: plan.iter().map(|l| l.beta).collect(),
            layers,
            irradiance,
        };
        Ok((env, timings))
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
    if source.width < 2 || source.height < 1 {
        return Err(Error::invalid(
            "environment size",
            format!("{}x{}", source.width, source.height),
            "must be at least 2x1 pixels",
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
    /// Copies every layer and the irradiance back to the host (tests, `shikki prefilter`).
    pub fn read_back(&self, gpu: &GpuContext) -> Result<PrefilteredEnvironment> {
        let sources: Vec<&Image> = self
            .layers
            .iter()
            .chain(std::iter::once(&self.irradiance))
            .collect();
        let targets: Vec<(u32, Buffer)> = sources
            .iter()
            .map(|image| {
                let face = image.desc().width;
                Ok((
                    face,
                    gpu.create_buffer(BufferDesc::readback("env readback", cube_bytes(face)))?,
                ))
            })
            .collect::<Result<_>>()?;
        let sampled = ImageUse::new(Access::GraphicsShaderRead, Layout::ShaderRead);
        let transfer_src = ImageUse::new(Access::TransferRead, Layout::TransferSrc);
        gpu.submit_and_wait(|rec| {
            for (image, (_, dst)) in sources.iter().zip(&targets) {
                // Draws may have sampled the image; it goes back to being sampled after.
                rec.image_barrier(image, sampled, transfer_src);
                rec.copy_image_to_buffer(image, dst);
                rec.image_barrier(image, transfer_src, sampled);
            }
            rec.memory_barrier(Access::TransferWrite, Access::HostRead);
            Ok(())
        })?;
        let mut cubes = targets
            .iter()
            .map(|(face, buf)| {
                Ok(CubeImage {
                    face_size: *face,
                    texels: buf.read()?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let irradiance = cubes.pop().ok_or_else(|| {
            Error::invalid("environment", "empty", "internal: no irradiance read back")
        })?;
        Ok(PrefilteredEnvironment {
            betas: self.betas.clone(),
            layers: cubes,
            irradiance,
        })
    }
}
