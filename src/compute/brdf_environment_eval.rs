//! Evaluates the `brdf` environment model's specular integral in GLSL
//! (shaders/common/brdf_environment.glsl, the code the shading pass runs) for a list of (N, V)
//! pairs in a compute shader, so tests can hold it against its CPU twin
//! (`environment::brdf_quadrature`) number by number.

use crate::environment::brdf_quadrature::{albedo_knots, BRDF_HIT_SAMPLES};
use crate::environment::gpu::{GpuEnvironment, LayerApronPass};
use crate::gpu::shaders::interface::{
    BrdfEvalParams, DrawConstants, Frame, ObjectMaterial, BACKGROUND_COLOR, BRDF_EVAL_WORKGROUP,
    ENV_EVAL_DIRECTIONS_BINDING, ENV_EVAL_PARAMS_BINDING, ENV_EVAL_VALUES_BINDING,
    ENV_LAYER_TEXELS_BINDING, FRAME_BINDING, FRESNEL_KNOTS_BINDING,
};
use crate::gpu::{
    Access, Binding, BindingKind, BufferDesc, BufferUsage, ComputePipeline, GpuContext, Resource,
};
use crate::model::{BrdfParams, FresnelTable};
use crate::raster::draw::frame::fresnel_knots;
use crate::Result;
use bytemuck::Zeroable;
use glam::DVec3;

/// brdf_environment_eval.comp's set.
const BINDINGS: [Binding; 6] = [
    Binding::new(FRAME_BINDING, BindingKind::UniformBuffer),
    Binding::new(FRESNEL_KNOTS_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(ENV_LAYER_TEXELS_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(ENV_EVAL_PARAMS_BINDING, BindingKind::UniformBuffer),
    Binding::new(ENV_EVAL_DIRECTIONS_BINDING, BindingKind::StorageBuffer),
    Binding::new(ENV_EVAL_VALUES_BINDING, BindingKind::StorageBuffer),
];

/// The specular integral of the `brdf` model, in GLSL, at (n, v) pairs (the material's
/// directional albedo from `albedo_knots`) (world frame; v towards
/// the eye), for one environment (with its bright split when one is attached, as a draw reads it):
/// RGB per pair. The vectors are normalised in f64 before the
/// conversion to f32, so the GPU sees the unit vectors the CPU twin sees. `samples` lobe samples
/// where the draw has `BRDF_SAMPLES`: `ENV_VARIATE_SAMPLES` evaluates what `paper`'s control
/// variate reads (its grid too, `brdf_quadrature::grid_for`).
pub fn brdf_environment_specular_gpu(
    gpu: &GpuContext,
    env: &GpuEnvironment,
    (brdf, fresnel): (&BrdfParams, &FresnelTable),
    pairs: &[[DVec3; 2]],
    samples: u32,
) -> Result<Vec<[f32; 3]>> {
    let rows = pairs.len();
    if rows == 0 {
        return Ok(Vec::new());
    }
    let constants = DrawConstants {
        env_layer_count: env.layers.len() as u32,
        sample_count: 1,
        background_kind: BACKGROUND_COLOR,
        fresnel_pow2_grid: 0,
        env_samples: samples,
        env_hit_samples: BRDF_HIT_SAMPLES,
        shadows: 0,
        integral: 0,
    };
    let pipeline: ComputePipeline = gpu.create_specialized_compute_pipeline(
        "brdf_environment_eval.comp",
        crate::gpu::shaders::BRDF_ENVIRONMENT_EVAL_COMP,
        &BINDINGS,
        constants.words(),
    )?;
    // The draw's sources: an attached bright split's residuals and lights, else the map itself.
    let sources = env.brdf_sources(gpu, &LayerApronPass::new(gpu)?)?;
    let mut frame = Frame::zeroed();
    frame.environment = [1, env.layers.len() as i32, 0, 0];
    frame.set_environment_layers(&env.betas, &env.layer_faces());
    frame.set_brdf_quadrature();
    frame.set_brdf_lights(&sources.lights);
    let mut knots = fresnel_knots(fresnel);
    let material = ObjectMaterial {
        albedo_first: knots.len() as f32,
        ..ObjectMaterial::new(brdf, fresnel)
    };
    knots.extend(albedo_knots(brdf, fresnel));
    frame.append_light_bins(&mut knots, [brdf.beckmann_m], &mut Default::default());
    let params = BrdfEvalParams {
        material,
        row_count: [rows as u32, 0, 0, 0],
    };
    let upload = |name: &str, bytes: usize, usage| {
        gpu.create_buffer(BufferDesc::upload(name, bytes as u64, usage))
    };
    let mut frame_buf = upload(
        "env eval frame",
        std::mem::size_of::<Frame>(),
        BufferUsage::UNIFORM,
    )?;
    frame_buf.write(std::slice::from_ref(&frame))?;
    let mut params_buf = upload(
        "env eval params",
        std::mem::size_of_val(&params),
        BufferUsage::UNIFORM,
    )?;
    params_buf.write(std::slice::from_ref(&params))?;
    let mut knots_buf = upload(
        "env eval fresnel",
        knots.len() * 16,
        BufferUsage::UNIFORM_TEXEL,
    )?;
    knots_buf.write(&knots)?;
    let directions: Vec<[f32; 4]> = pairs
        .iter()
        .flat_map(|pair| {
            pair.map(|d| {
                let u = d.normalize_or_zero();
                [u.x as f32, u.y as f32, u.z as f32, 0.0]
            })
        })
        .collect();
    let mut dirs_buf = upload(
        "env eval directions",
        directions.len() * 16,
        BufferUsage::STORAGE,
    )?;
    dirs_buf.write(&directions)?;
    let values_buf =
        gpu.create_buffer(BufferDesc::readback("env eval values", (rows * 16) as u64))?;
    let texels = sources.texels;
    let set = gpu.create_descriptor_set(
        pipeline.layout(),
        &[
            (FRAME_BINDING, Resource::Buffer(&frame_buf)),
            (FRESNEL_KNOTS_BINDING, Resource::TexelBuffer(&knots_buf)),
            (ENV_LAYER_TEXELS_BINDING, Resource::UintTexelBuffer(texels)),
            (ENV_EVAL_PARAMS_BINDING, Resource::Buffer(&params_buf)),
            (ENV_EVAL_DIRECTIONS_BINDING, Resource::Buffer(&dirs_buf)),
            (ENV_EVAL_VALUES_BINDING, Resource::Buffer(&values_buf)),
        ],
    )?;
    gpu.submit_and_wait(|rec| {
        rec.bind_compute(&pipeline, &set);
        rec.dispatch((rows as u32).div_ceil(BRDF_EVAL_WORKGROUP), 1, 1);
        rec.memory_barrier(Access::ComputeShaderWrite, Access::HostRead);
        Ok(())
    })?;
    let values: Vec<[f32; 4]> = values_buf.read()?;
    Ok(values.iter().map(|v| [v[0], v[1], v[2]]).collect())
}
