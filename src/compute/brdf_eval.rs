//! Evaluates the GLSL lacquer BRDF (shaders/common/lacquer_brdf.glsl, the same code the fragment
//! shader runs) for a list of (N, V, L) triples in a compute shader.

use crate::gpu::shaders::interface::{
    BrdfEvalParams, ObjectMaterial, BRDF_EVAL_DIRECTIONS_BINDING, BRDF_EVAL_PARAMS_BINDING,
    BRDF_EVAL_VALUES_BINDING, BRDF_EVAL_WORKGROUP, FRESNEL_KNOTS_BINDING,
};
use crate::gpu::{
    Access, Binding, BindingKind, BufferDesc, BufferUsage, ComputePipeline, GpuContext, Resource,
};
use crate::model::{BrdfParams, FresnelTable};
use crate::raster::draw::frame::fresnel_knots;
use crate::Result;
use glam::DVec3;

/// Rows per submit, so a huge input never needs one enormous buffer. Vulkan guarantees a storage
/// buffer range of at least 2^27 bytes; 2^20 rows × 48 bytes is under half of that.
const ROWS_PER_BATCH: usize = 1 << 20;

/// brdf_eval.comp's set.
const BINDINGS: [Binding; 4] = [
    Binding::new(BRDF_EVAL_PARAMS_BINDING, BindingKind::UniformBuffer),
    Binding::new(FRESNEL_KNOTS_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(BRDF_EVAL_DIRECTIONS_BINDING, BindingKind::StorageBuffer),
    Binding::new(BRDF_EVAL_VALUES_BINDING, BindingKind::StorageBuffer),
];

/// The compute pipeline, made once and reused for every call.
pub struct BrdfEvaluator {
    pipeline: ComputePipeline,
}

impl BrdfEvaluator {
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        let pipeline = gpu.create_compute_pipeline(
            "brdf_eval.comp",
            crate::gpu::shaders::BRDF_EVAL_COMP,
            &BINDINGS,
            0,
        )?;
        Ok(Self { pipeline })
    }

    /// f_r (RGB) for each (n, v, l); the vectors are normalised here, in f64, before the
    /// conversion to f32, so the GPU sees the same unit vectors as the CPU model.
    pub fn evaluate(
        &self,
        gpu: &GpuContext,
        brdf: &BrdfParams,
        fresnel: &FresnelTable,
        triples: &[[DVec3; 3]],
    ) -> Result<Vec<[f32; 3]>> {
        let mut out = Vec::with_capacity(triples.len());
        for chunk in triples.chunks(ROWS_PER_BATCH) {
            out.extend(self.evaluate_batch(gpu, brdf, fresnel, chunk)?);
        }
        Ok(out)
    }

    fn evaluate_batch(
        &self,
        gpu: &GpuContext,
        brdf: &BrdfParams,
        fresnel: &FresnelTable,
        triples: &[[DVec3; 3]],
    ) -> Result<Vec<[f32; 3]>> {
        let rows = triples.len();
        if rows == 0 {
            return Ok(Vec::new());
        }
        let params = BrdfEvalParams {
            material: ObjectMaterial::new(brdf, fresnel),
            row_count: [rows as u32, 0, 0, 0],
        };
        let knots = fresnel_knots(fresnel);
        let directions: Vec<[f32; 4]> = triples
            .iter()
            .flat_map(|triple| {
                triple.map(|d| {
                    let u = d.normalize_or_zero();
                    [u.x as f32, u.y as f32, u.z as f32, 0.0]
                })
            })
            .collect();

        let mut params_buf = gpu.create_buffer(BufferDesc::upload(
            "brdf_eval params",
            std::mem::size_of_val(&params) as u64,
            BufferUsage::UNIFORM,
        ))?;
        params_buf.write(std::slice::from_ref(&params))?;
        let mut knots_buf = gpu.create_buffer(BufferDesc::upload(
            "brdf_eval fresnel",
            (knots.len() * 16) as u64,
            BufferUsage::UNIFORM_TEXEL,
        ))?;
        knots_buf.write(&knots)?;
        let mut dirs_buf = gpu.create_buffer(BufferDesc::upload(
            "brdf_eval directions",
            (directions.len() * 16) as u64,
            BufferUsage::STORAGE,
        ))?;
        dirs_buf.write(&directions)?;
        let values_buf =
            gpu.create_buffer(BufferDesc::readback("brdf_eval values", (rows * 16) as u64))?;
        let set = gpu.create_descriptor_set(
            self.pipeline.layout(),
            &[
                (BRDF_EVAL_PARAMS_BINDING, Resource::Buffer(&params_buf)),
                (FRESNEL_KNOTS_BINDING, Resource::TexelBuffer(&knots_buf)),
                (BRDF_EVAL_DIRECTIONS_BINDING, Resource::Buffer(&dirs_buf)),
                (BRDF_EVAL_VALUES_BINDING, Resource::Buffer(&values_buf)),
            ],
        )?;
        gpu.submit_and_wait(|rec| {
            rec.bind_compute(&self.pipeline, &set);
            rec.dispatch((rows as u32).div_ceil(BRDF_EVAL_WORKGROUP), 1, 1);
            rec.memory_barrier(Access::ComputeShaderWrite, Access::HostRead);
            Ok(())
        })?;
        let values: Vec<[f32; 4]> = values_buf.read()?;
        Ok(values.iter().map(|v| [v[0], v[1], v[2]]).collect())
    }
}
