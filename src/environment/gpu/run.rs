//! One prefilter run's device memory, made before recording so it outlives the submit: the
//! equirect's texels, the mip chain, the blurred layers and the irradiance as buffers the steps
//! write, step 1's near-edge list, every step's descriptor set, and the sampled cube images the
//! buffers end in.

use super::{copy_to_image, cube_bytes, cube_image_usage, GpuPrefilter};
use crate::environment::image::Equirect;
use crate::environment::params::{LayerPlan, PrefilterParams};
use crate::gpu::shaders::interface::{
    NearHeader, NEAR_TEXELS_BINDING, PREFILTER_DEST_BINDING, PREFILTER_SOURCE_BINDING,
};
use crate::gpu::{
    Buffer, BufferDesc, BufferUsage, ComputePipeline, DescriptorSet, GpuContext, Image, ImageDesc,
    Recorder, Resource,
};
use crate::{Error, Result};
use std::mem::size_of;

/// One run's device memory and descriptor sets.
pub(super) struct PrefilterRun {
    pub buffers: CubeBuffers,
    pub sets: StepSets,
    /// The sampled cube images the buffers are copied to: layer 0 (the base mip), the blurred
    /// layers.
    pub images: Vec<Image>,
    pub irradiance_image: Image,
}

/// The buffers the steps read and write.
pub(super) struct CubeBuffers {
    /// The equirect's texels; read by step 1.
    source: Buffer,
    /// Step 1's near-edge list: a [`NearHeader`], then texel indices.
    pub near_texels: Buffer,
    /// The source mip chain (the base cube first) and its face sizes.
    pub mips: Vec<Buffer>,
    pub mip_faces: Vec<u32>,
    /// The blurred layers k = 1..K.
    pub layers: Vec<(LayerPlan, Buffer)>,
    pub irradiance_face: u32,
    pub irradiance: Buffer,
}

/// Each step's descriptor set.
pub(super) struct StepSets {
    pub to_cube: DescriptorSet,
    pub near: Option<DescriptorSet>,
    /// Mip i → mip i + 1.
    pub downsample: Vec<DescriptorSet>,
    pub blur: Vec<DescriptorSet>,
    pub irradiance: DescriptorSet,
}

impl PrefilterRun {
    pub fn new(
        gpu: &GpuContext,
        prefilter: &GpuPrefilter,
        source: &Equirect,
        params: &PrefilterParams,
    ) -> Result<Self> {
        let buffers = CubeBuffers::new(gpu, source, params, prefilter.equirect_near.is_some())?;
        let sets = StepSets::new(gpu, prefilter, &buffers)?;
        let sampled = cube_image_usage();
        let image = |name, face| gpu.create_image(ImageDesc::cube(name, face).usage(sampled));
        let mut images = vec![image("layer 0", params.face_size)?];
        for (layer, _) in &buffers.layers {
            images.push(image("layer", layer.face_size)?);
        }
        let irradiance_image = image("irradiance", buffers.irradiance_face)?;
        Ok(PrefilterRun {
            buffers,
            sets,
            images,
            irradiance_image,
        })
    }

    /// Step 5: the buffers → the sampled cube images (layer 0 is the base mip itself).
    pub fn copy_to_images(&self, rec: &mut Recorder<'_>) {
        let b = &self.buffers;
        let buffers = std::iter::once(&b.mips[0]).chain(b.layers.iter().map(|(_, buffer)| buffer));
        for (buffer, image) in buffers.zip(&self.images) {
            copy_to_image(rec, buffer, image);
        }
        copy_to_image(rec, &b.irradiance, &self.irradiance_image);
    }
}

impl CubeBuffers {
    /// `near`: step 1 has a near pass, whose list may hold every texel of the base cube.
    fn new(
        gpu: &GpuContext,
        source: &Equirect,
        params: &PrefilterParams,
        near: bool,
    ) -> Result<Self> {
        let pixels: Vec<[f32; 4]> = source
            .pixels
            .iter()
            .map(|p| [p[0], p[1], p[2], 1.0])
            .collect();
        let mut source_buffer = gpu.create_buffer(BufferDesc::upload(
            "environment equirect",
            (pixels.len() * 16) as u64,
            BufferUsage::UNIFORM_TEXEL,
        ))?;
        source_buffer.write(&pixels)?;
        let storage = BufferUsage::STORAGE | BufferUsage::TRANSFER_SRC | BufferUsage::UNIFORM_TEXEL;
        let cube = |name, face| {
            gpu.create_buffer(BufferDesc::device_local(name, cube_bytes(face), storage))
        };
        let mip_faces = params.mip_faces();
        let mips = mip_faces
            .iter()
            .map(|&m| cube("mip", m))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let layers = params
            .plan()
            .into_iter()
            .skip(1)
            .map(|layer| Ok((layer, cube("layer", layer.face_size)?)))
            .collect::<Result<Vec<_>>>()?;
        let irradiance_face = params.irradiance_face();
        let irradiance = cube("irradiance", irradiance_face)?;
        let near_capacity = match near {
            true => 6 * u64::from(params.face_size) * u64::from(params.face_size),
            false => 0,
        };
        let mut near_texels = gpu.create_buffer(BufferDesc::upload(
            "near-edge texels",
            size_of::<NearHeader>() as u64 + 4 * near_capacity,
            BufferUsage::STORAGE | BufferUsage::INDIRECT,
        ))?;
        // No texels yet; the near pass's dispatch is (0, 1, 1) groups, counted up by step 1.
        near_texels.write(&[NearHeader {
            count: 0,
            dispatch_x: 0,
            dispatch_y: 1,
            dispatch_z: 1,
        }])?;
        Ok(CubeBuffers {
            source: source_buffer,
            near_texels,
            mips,
            mip_faces,
            layers,
            irradiance_face,
            irradiance,
        })
    }

    /// The source mip a step of face `face` reads.
    fn mip_of(&self, face: u32) -> Result<&Buffer> {
        self.mip_faces
            .iter()
            .position(|&m| m == face)
            .map(|i| &self.mips[i])
            .ok_or_else(|| {
                Error::Internal(format!(
                    "the prefilter plan has no source mip of face {face}"
                ))
            })
    }
}

impl StepSets {
    fn new(gpu: &GpuContext, prefilter: &GpuPrefilter, buffers: &CubeBuffers) -> Result<Self> {
        let set =
            |pipeline: &ComputePipeline, src: &Buffer, dst: &Buffer| -> Result<DescriptorSet> {
                Ok(gpu.create_descriptor_set(
                    pipeline.layout(),
                    &[
                        (PREFILTER_SOURCE_BINDING, Resource::TexelBuffer(src)),
                        (PREFILTER_DEST_BINDING, Resource::Buffer(dst)),
                    ],
                )?)
            };
        let to_cube_resources = [
            (
                PREFILTER_SOURCE_BINDING,
                Resource::TexelBuffer(&buffers.source),
            ),
            (PREFILTER_DEST_BINDING, Resource::Buffer(&buffers.mips[0])),
            (NEAR_TEXELS_BINDING, Resource::Buffer(&buffers.near_texels)),
        ];
        let near = match &prefilter.equirect_near {
            Some(near) => Some(gpu.create_descriptor_set(near.layout(), &to_cube_resources)?),
            None => None,
        };
        Ok(StepSets {
            to_cube: gpu
                .create_descriptor_set(prefilter.equirect_to_cube.layout(), &to_cube_resources)?,
            near,
            downsample: buffers
                .mips
                .windows(2)
                .map(|pair| set(&prefilter.downsample, &pair[0], &pair[1]))
                .collect::<Result<_>>()?,
            blur: buffers
                .layers
                .iter()
                .map(|(layer, dst)| {
                    set(&prefilter.blur_layer, buffers.mip_of(layer.face_size)?, dst)
                })
                .collect::<Result<_>>()?,
            irradiance: set(
                &prefilter.irradiance,
                buffers.mip_of(buffers.irradiance_face)?,
                &buffers.irradiance,
            )?,
        })
    }
}
