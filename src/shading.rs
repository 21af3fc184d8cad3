//! The host side of the shaders' parameter blocks: the one place that packs the lacquer model
//! (SPEC §2–3) into the layouts `shaders/common/*.glsl` declare. The raster draw and the compute
//! BRDF evaluator both use it, so a number the shader needs is packed once, not retyped.

use crate::environment::params::ViewBlur;
use crate::model::{BrdfParams, FresnelTable};
use crate::raster::camera::Camera;
use crate::raster::lights::{Light, MAX_LIGHTS};
use bytemuck::{Pod, Zeroable};

/// Fresnel table knots as the GLSL `vec4 fresnel_knots[]`: (angle_deg, r, g, b).
pub fn fresnel_knots(table: &FresnelTable) -> Vec<[f32; 4]> {
    table
        .angles_deg()
        .iter()
        .zip(table.rgb())
        .map(|(&angle, rgb)| [angle as f32, rgb[0] as f32, rgb[1] as f32, rgb[2] as f32])
        .collect()
}

/// (m, a, b, g(r)), (k_d, knot count) and (a_lo, b_lo, 0, 0): the three vec4s `LacquerParams`
/// is unpacked from. a and b travel as f32 pairs (hi + lo) because the shader evaluates a + b·nv
/// in compensated arithmetic (see lacquer_brdf.glsl).
pub fn material_vec4s(brdf: &BrdfParams, fresnel: &FresnelTable) -> [[f32; 4]; 3] {
    let (a, a_lo) = split_f64(brdf.diffuse_a);
    let (b, b_lo) = split_f64(brdf.diffuse_b);
    [
        [brdf.beckmann_m as f32, a, b, brdf.lacquer_g as f32],
        [
            brdf.albedo[0] as f32,
            brdf.albedo[1] as f32,
            brdf.albedo[2] as f32,
            // Exact as f32: tables are far shorter than 2^24 knots.
            fresnel.angles_deg().len() as f32,
        ],
        [a_lo, b_lo, 0.0, 0.0],
    ]
}

/// x ≈ hi + lo with hi = x rounded to f32 and lo the f32 nearest to the remainder.
fn split_f64(x: f64) -> (f32, f32) {
    let hi = x as f32;
    (hi, (x - f64::from(hi)) as f32)
}

/// One object's material as shade_body.glsl's `object_material[4 * object + i]`: the three vec4s
/// of [`material_vec4s`] with the index of the object's first Fresnel knot in the concatenated
/// knot buffer (`material_lo.z`), then (β_normal, β_grazing, p, 0) of SPEC §4's β(nv).
pub fn object_material_vec4s(
    brdf: &BrdfParams,
    fresnel: &FresnelTable,
    first_knot: usize,
    view_blur: &ViewBlur,
) -> [[f32; 4]; 4] {
    let [material, albedo_count, mut material_lo] = material_vec4s(brdf, fresnel);
    // Exact as f32: the renderer limits the knots of one draw far below 2^24.
    material_lo[2] = first_knot as f32;
    [
        material,
        albedo_count,
        material_lo,
        [
            view_blur.beta_normal as f32,
            view_blur.beta_grazing as f32,
            view_blur.beta_power as f32,
            0.0,
        ],
    ]
}

/// `Frame` in shaders/common/frame.glsl (std140; every member is a multiple of 16 bytes, so the
/// C layout is the std140 layout): what every object of a draw shares.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_projection: [f32; 16],
    pub eye: [f32; 4],
    pub light_count: [i32; 4],
    pub light_vector: [[f32; 4]; MAX_LIGHTS],
    pub light_color: [[f32; 4]; MAX_LIGHTS],
    pub environment: [i32; 4],
    pub layer_beta: [[f32; 4]; MAX_ENV_LAYERS / 4],
    /// ln β_k for k ≥ 1 (0 where β_k ≤ 0): the shader interpolates layers linearly in ln β.
    pub layer_log_beta: [[f32; 4]; MAX_ENV_LAYERS / 4],
    pub camera_right: [f32; 4],
    pub camera_up: [f32; 4],
    pub camera_back: [f32; 4],
    pub camera_params: [f32; 4],
    /// (0, first image row of the render target, 0, 0): the draw renders tall images in strips.
    pub strip_offset: [f32; 4],
    /// (object index + 1 in the G-buffer pass, 0, 0, 0).
    pub draw_info: [i32; 4],
    /// The constant background (linear rgba; transparent is all 0).
    pub background_color: [f32; 4],
}

/// Most environment layers a draw can sample (`MAX_ENV_LAYERS` in frame.glsl).
pub const MAX_ENV_LAYERS: usize = crate::environment::params::MAX_LAYERS as usize;

/// The environment as a draw sees it: whether there is one and the β of each layer.
#[derive(Clone, Debug, Default)]
pub struct EnvironmentUniforms {
    pub enabled: bool,
    pub layer_betas: Vec<f64>,
}

fn vec4(v: glam::DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

impl FrameUniforms {
    /// Packs one draw's camera, lights and environment. `lights.len()` must be ≤ MAX_LIGHTS
    /// (checked by the renderer before this is called; extra lights are ignored here).
    pub fn new(
        camera: &Camera,
        width: u32,
        height: u32,
        scene_radius: f64,
        lights: &[Light],
        environment: &EnvironmentUniforms,
    ) -> Self {
        let (right, up, forward) = camera.basis();
        let mut layer_beta = [[0.0f32; 4]; MAX_ENV_LAYERS / 4];
        let mut layer_log_beta = [[0.0f32; 4]; MAX_ENV_LAYERS / 4];
        for (k, &beta) in environment
            .layer_betas
            .iter()
            .take(MAX_ENV_LAYERS)
            .enumerate()
        {
            layer_beta[k / 4][k % 4] = beta as f32;
            // Of the f32 β the shader compares against, so both describe the same layer.
            let beta = f64::from(beta as f32);
            layer_log_beta[k / 4][k % 4] = if beta > 0.0 { beta.ln() as f32 } else { 0.0 };
        }
        let mut frame = FrameUniforms {
            view_projection: camera
                .view_projection(width, height, scene_radius)
                .to_cols_array(),
            eye: [
                camera.eye.x as f32,
                camera.eye.y as f32,
                camera.eye.z as f32,
                1.0,
            ],
            light_count: [lights.len().min(MAX_LIGHTS) as i32, 0, 0, 0],
            light_vector: [[0.0; 4]; MAX_LIGHTS],
            light_color: [[0.0; 4]; MAX_LIGHTS],
            environment: [
                i32::from(environment.enabled),
                environment.layer_betas.len().min(MAX_ENV_LAYERS) as i32,
                0,
                0,
            ],
            layer_beta,
            layer_log_beta,
            camera_right: vec4(right, 0.0),
            camera_up: vec4(up, 0.0),
            camera_back: vec4(-forward, 0.0),
            camera_params: [
                (0.5 * camera.fov_deg.to_radians()).tan() as f32,
                (f64::from(width) / f64::from(height)) as f32,
                width as f32,
                height as f32,
            ],
            strip_offset: [0.0; 4],
            draw_info: [0; 4],
            background_color: [0.0; 4],
        };
        for (i, light) in lights.iter().take(MAX_LIGHTS).enumerate() {
            let (vector, color) = match *light {
                Light::Directional {
                    to_light,
                    irradiance,
                } => {
                    let d = to_light.normalize();
                    ([d.x, d.y, d.z, 0.0], irradiance)
                }
                Light::Point {
                    position,
                    intensity,
                } => ([position.x, position.y, position.z, 1.0], intensity),
            };
            frame.light_vector[i] = vector.map(|v| v as f32);
            frame.light_color[i] = [color.x as f32, color.y as f32, color.z as f32, 0.0];
        }
        frame
    }
}
