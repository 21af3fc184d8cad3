//! The frame data: the one place that packs a draw's camera, lights, environment and the lacquer
//! model (SPEC §2–4) into the blocks the interface declares (`Frame`, `ObjectMaterial`, the
//! Fresnel knots), and the buffers they are written to. The compute BRDF evaluator packs its
//! material here too, so a number the shader needs is packed once.
//!
//! To add a material field: declare it in `ObjectMaterial` (src/gpu/shaders/interface.rs; a pad
//! field makes room without adding a texel), pack it in [`ObjectMaterial::new`] or
//! [`ObjectMaterial::of_object`] here, and read it in lacquer_brdf.glsl's `lacquer_params`.

use super::gpu_mesh::upload;
use super::types::{DrawScene, RenderSettings};
use crate::environment::brdf_quadrature::rough_lattice_m;
use crate::environment::bright::BrightLight;
use crate::environment::gpu::{layer_texel_offsets, BrdfLights, GpuEnvironment};
use crate::environment::light_bins::light_bin_texels;
use crate::environment::params::{texel_read_variance, ViewBlur};
use crate::gpu::shaders::interface::{
    Frame, ObjectMaterial, MAX_ENV_LAYERS, MAX_ENV_LIGHTS, MAX_LIGHTS, ROUGH_MAX_ENV_LIGHTS,
};
use crate::gpu::{Buffer, BufferUsage, GpuContext};
use crate::model::{BrdfParams, FresnelTable};
use crate::raster::camera::{Camera, SceneSphere};
use crate::raster::lights::Light;
use crate::Result;
use bytemuck::Zeroable;
use glam::DVec3;

/// A Fresnel table's knots as the shaders read them, one RGBA32F texel each:
/// (angle_deg, r, g, b).
pub(crate) fn fresnel_knots(table: &FresnelTable) -> Vec<[f32; 4]> {
    table
        .angles_deg()
        .iter()
        .zip(table.rgb())
        .map(|(&angle, rgb)| [angle as f32, rgb[0] as f32, rgb[1] as f32, rgb[2] as f32])
        .collect()
}

/// x ≈ hi + lo with hi = x rounded to f32 and lo the f32 nearest to the remainder.
fn split_f64(x: f64) -> (f32, f32) {
    let hi = x as f32;
    (hi, (x - f64::from(hi)) as f32)
}

impl ObjectMaterial {
    /// The BRDF of `brdf` with the Fresnel table `fresnel` as the only table (its first knot at
    /// 0) and no view-dependent blur. a and b travel as f32 pairs (hi + lo) because the shader
    /// evaluates a + b·nv in compensated arithmetic (see lacquer_brdf.glsl).
    pub(crate) fn new(brdf: &BrdfParams, fresnel: &FresnelTable) -> Self {
        let (diffuse_a, diffuse_a_lo) = split_f64(brdf.diffuse_a);
        let (diffuse_b, diffuse_b_lo) = split_f64(brdf.diffuse_b);
        ObjectMaterial {
            beckmann_m: brdf.beckmann_m as f32,
            diffuse_a,
            diffuse_b,
            lacquer_g: brdf.lacquer_g as f32,
            albedo: brdf.albedo.map(|c| c as f32),
            // Exact as f32: tables are far shorter than 2^24 knots.
            fresnel_count: fresnel.angles_deg().len() as f32,
            diffuse_a_lo,
            diffuse_b_lo,
            fresnel_first: 0.0,
            ..ObjectMaterial::zeroed()
        }
    }

    /// One object of a draw: its table starts at `first_knot` of the draw's concatenated knots,
    /// and the environment is blurred by SPEC §4's β(nv) of `view_blur`.
    pub(crate) fn of_object(
        brdf: &BrdfParams,
        fresnel: &FresnelTable,
        (first_knot, albedo_first): (usize, usize),
        view_blur: &ViewBlur,
    ) -> Self {
        ObjectMaterial {
            // Exact as f32: the renderer limits the knots of one draw to MAX_DRAW_KNOTS = 2^24.
            fresnel_first: first_knot as f32,
            albedo_first: albedo_first as f32,
            beta_normal: view_blur.beta_normal as f32,
            beta_grazing: view_blur.beta_grazing as f32,
            beta_power: view_blur.beta_power as f32,
            ..ObjectMaterial::new(brdf, fresnel)
        }
    }
}

/// The environment as a draw sees it: whether there is one and the β of each layer.
#[derive(Clone, Debug, Default)]
pub(crate) struct EnvironmentUniforms<'a> {
    pub enabled: bool,
    pub layer_betas: Vec<f64>,
    /// Each layer's face size (the `brdf` model's texel lookups).
    pub layer_faces: Vec<u32>,
    /// The `brdf` model's two splits' lights (world frame); none in the `paper` model.
    pub brdf_lights: Option<BrdfLights<'a>>,
}

fn vec4(v: glam::DVec3, w: f32) -> [f32; 4] {
    [v.x as f32, v.y as f32, v.z as f32, w]
}

/// A bright light as the shaders read it (brdf_environment.glsl `bright_light`): (direction,
/// spread σ²) and (irradiance, 0).
fn pack_light(light: &BrightLight) -> ([f32; 4], [f32; 4]) {
    (
        vec4(light.direction, light.spread as f32),
        vec4(DVec3::from(light.irradiance), 0.0),
    )
}

/// The layers' geometric run as the shader's `layer_pair_of_run` reads it: (ln β_1, Δ) where
/// ln β_k = ln β_1 + (k − 1)·Δ from layer 1 to the last, within 1e-5 (the f32 β the shader
/// compares against: its `layer_pair` finds the same pair up to rounding at a boundary, where
/// either pair gives the same blend). `None` with fewer than two layers in the run, or none: the
/// shader then searches (`layer_pair`).
fn geometric_run(betas: &[f64]) -> Option<(f64, f64)> {
    let logs: Vec<f64> = betas.iter().map(|&b| f64::from(b as f32).ln()).collect();
    let last = logs.len().checked_sub(1)?;
    if last <= 1 || !betas[1..].iter().all(|&b| b > 0.0) {
        return None;
    }
    let step = (logs[last] - logs[1]) / (last - 1) as f64;
    let on_run = (1..=last).all(|k| (logs[k] - (logs[1] + (k - 1) as f64 * step)).abs() <= 1e-5);
    (step > 0.0 && on_run).then_some((logs[1], step))
}

impl Frame {
    /// Packs the environment layers' β, ln β, face sizes and first texels (the `brdf` model's
    /// lookups); also used by the compute evaluator of the `brdf` model.
    pub(crate) fn set_environment_layers(&mut self, betas: &[f64], faces: &[u32]) {
        for (k, &beta) in betas.iter().take(MAX_ENV_LAYERS).enumerate() {
            self.layer_beta[k / 4][k % 4] = beta as f32;
            // Of the f32 β the shader compares against, so both describe the same layer.
            let beta = f64::from(beta as f32);
            self.layer_log_beta[k / 4][k % 4] = if beta > 0.0 { beta.ln() as f32 } else { 0.0 };
        }
        let (firsts, _) = layer_texel_offsets(faces.iter().copied());
        for (k, (&face, first)) in faces.iter().zip(firsts).enumerate().take(MAX_ENV_LAYERS) {
            self.layer_face_size[k / 4][k % 4] = face as i32;
            // GpuEnvironment::layer_texels refuses more texels than an i32 indexes.
            self.layer_first_texel[k / 4][k % 4] = first as i32;
        }
        let run = geometric_run(&betas[..betas.len().min(MAX_ENV_LAYERS)]);
        self.layer_run = match run {
            Some((log_beta, step)) => [log_beta as f32, (1.0 / step) as f32, 1.0, 0.0],
            None => [0.0; 4],
        };
        let ratio = run.map_or(0.0, |(_, step)| (2.0 * step).exp() - 1.0);
        let read = faces.first().map_or(0.0, |&face| texel_read_variance(face));
        self.layer_variance = [read as f32, ratio as f32, 0.0, 0.0];
    }

    /// Packs the `brdf` model's quadrature constants (the lattice's, from brdf_lattice.rs, and
    /// the grid's and their roughness bands, from brdf_quadrature.rs);
    /// also used by the compute evaluator.
    pub(crate) fn set_brdf_quadrature(&mut self) {
        use crate::environment::brdf_lattice as lattice;
        use crate::environment::brdf_quadrature as q;
        self.env_lattice = [
            lattice::LATTICE_SPACING as f32,
            lattice::LATTICE_REACH as f32,
            q::LATTICE_TAPER as f32,
            lattice::LATTICE_MAX_HALF as f32,
        ];
        self.env_lattice_band = [
            q::LATTICE_M_LO as f32,
            q::LATTICE_M_HI as f32,
            q::FIS_M_LO as f32,
            q::FIS_M_HI as f32,
        ];
        // y, the rough split's lattice threshold, is the lights' (`set_brdf_lights`); z the
        // light bins' (`append_light_bins`).
        self.env_lattice_share[0] = lattice::LATTICE_BLUR_SHARE as f32;
        self.env_lattice_share[3] = lattice::LATTICE_MAX_STEP as f32;
        self.env_lattice_across = [
            lattice::LATTICE_ACROSS_MEAN as f32,
            lattice::LATTICE_NODE_BLUR_FLOOR as f32,
            lattice::LATTICE_OWN_WIDTHS.0 as f32,
            lattice::LATTICE_OWN_WIDTHS.1 as f32,
        ];
        let pack = |grid: &q::GridConstants| {
            [
                grid.blur_share as f32,
                grid.spacing as f32,
                grid.reach as f32,
                grid.max_half as f32,
            ]
        };
        let (all, none) = crate::environment::sharp_source::SHARP_NODES;
        self.env_sharp_read = [
            crate::environment::sharp_source::SHARP_SIGMA as f32,
            crate::environment::sharp_source::SHARP_REACH as f32,
            all as f32,
            none as f32,
        ];
        self.env_grid = pack(&q::GRID);
        self.env_variate_grid = pack(&q::VARIATE_GRID);
        let grazing = &q::GRID_GRAZING;
        self.env_grid_grazing = [
            grazing.share as f32,
            grazing.nv_full as f32,
            grazing.nv_none as f32,
            0.0,
        ];
    }

    /// Packs the `brdf` model's lights: the bright split's (at most `MAX_ENV_LIGHTS`, which
    /// `bright::split_bright` never exceeds) and the rough split's (at most
    /// `ROUGH_MAX_ENV_LIGHTS`, which `bright::split_bright_rough` never exceeds), where the rough
    /// residual's texels start, and the least m whose lattice reads it; also used by the compute
    /// evaluator. After [`set_brdf_quadrature`](Self::set_brdf_quadrature).
    pub(crate) fn set_brdf_lights(&mut self, lights: &BrdfLights<'_>) {
        let count = lights.lights.len().min(MAX_ENV_LIGHTS);
        self.environment[2] = count as i32;
        for (i, light) in lights.lights.iter().take(count).enumerate() {
            (self.env_light_direction[i], self.env_light_irradiance[i]) = pack_light(light);
        }
        let count = lights.rough_lights.len().min(ROUGH_MAX_ENV_LIGHTS);
        // GpuEnvironment's texel buffers hold at most i32::MAX texels.
        let first_texel = lights.rough_first_texel.min(i32::MAX as u64) as i32;
        self.env_rough = [first_texel, count as i32, 0, 0];
        for (i, light) in lights.rough_lights.iter().take(count).enumerate() {
            (
                self.env_rough_light_direction[i],
                self.env_rough_light_irradiance[i],
            ) = pack_light(light);
        }
        self.env_lattice_share[1] = rough_lattice_m(lights.rough_block_angle);
        // The texel buffer holds at most i32::MAX texels (`concatenated_texels`).
        let texel = |first: u64| first.min(i32::MAX as u64) as i32;
        (self.env_sharp, self.env_sharp_rotation) = match lights.sharp {
            Some(sharp) => {
                let (sin, cos) = sharp.rotation_deg.to_radians().sin_cos();
                let [first, rough] = sharp.first_texel.map(texel);
                let size = |n: u32| n.min(i32::MAX as u32) as i32;
                (
                    [first, rough, size(sharp.width), size(sharp.height)],
                    [cos as f32, sin as f32, 0.0, 0.0],
                )
            }
            None => ([-1, -1, 0, 0], [1.0, 0.0, 0.0, 0.0]),
        };
    }

    /// Appends the direction bins of the packed rough lights (environment/light_bins.rs) to the
    /// draw's knots for the draw's materials `ms`: for every m up to the largest of them that
    /// the bins serve (at most `LATTICE_M_LO`, the lattice's: the narrower the lobes, the fewer
    /// lights a cell lists), which goes to `env_lattice_share.z`; and points `env_rough.z` at
    /// them. The bins are made from the f32 lights the frame holds.
    pub(crate) fn append_light_bins(
        &mut self,
        knots: &mut Vec<[f32; 4]>,
        ms: impl IntoIterator<Item = f64>,
        cache: &mut LightBinCache,
    ) {
        let limit = crate::environment::brdf_quadrature::LATTICE_M_LO as f32;
        let binned = ms
            .into_iter()
            .map(|m| m as f32)
            .filter(|&m| m <= limit)
            .fold(0.0, f32::max);
        self.env_lattice_share[2] = binned;
        let count = self.env_rough[1].max(0) as usize;
        let lights: Vec<([f32; 4], [f32; 4])> = self.env_rough_light_direction[..count]
            .iter()
            .copied()
            .zip(self.env_rough_light_irradiance[..count].iter().copied())
            .collect();
        self.env_rough[2] = knots.len() as i32;
        knots.extend_from_slice(cache.texels(lights, binned));
    }

    /// Packs one draw's camera, lights and environment. `lights.len()` must be ≤ MAX_LIGHTS
    /// (checked by the renderer before this is called; extra lights are ignored here).
    pub(crate) fn new(
        camera: &Camera,
        width: u32,
        height: u32,
        scene_sphere: SceneSphere,
        lights: &[Light],
        environment: &EnvironmentUniforms<'_>,
    ) -> Self {
        let (right, up, forward) = camera.basis();
        let mut frame = Frame {
            view_projection: camera
                .view_projection(width, height, scene_sphere)
                .to_cols_array(),
            eye: vec4(camera.eye, 1.0),
            light_count: [lights.len().min(MAX_LIGHTS) as i32, 0, 0, 0],
            environment: [
                i32::from(environment.enabled),
                environment.layer_betas.len().min(MAX_ENV_LAYERS) as i32,
                0,
                0,
            ],
            camera_right: vec4(right, 0.0),
            camera_up: vec4(up, 0.0),
            camera_back: vec4(-forward, 0.0),
            camera_params: [
                (0.5 * camera.fov_deg.to_radians()).tan() as f32,
                (f64::from(width) / f64::from(height)) as f32,
                width as f32,
                height as f32,
            ],
            ..Frame::zeroed()
        };
        frame.set_environment_layers(&environment.layer_betas, &environment.layer_faces);
        frame.set_brdf_quadrature();
        if let Some(lights) = &environment.brdf_lights {
            frame.set_brdf_lights(lights);
        }
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
            frame.light_color[i] = vec4(color, 0.0);
        }
        frame
    }
}

/// One object's knots (Fresnel table or directional albedo), RGBA32F texels.
pub(super) type Knots = Vec<[f32; 4]>;

/// Fresnel knots the knot buffer holds before it must grow (the built-in tables have 91 each).
const INITIAL_KNOTS: usize = 512;
/// The last direction bins made for a draw ([`Frame::append_light_bins`]), kept with the draw's
/// buffers: they depend only on the map's rough lights and the draw's largest binned m, so the
/// draws of a batch over one map make them once (each making took ~3 ms and ~57k texels with 128
/// lights).
#[derive(Default)]
pub(crate) struct LightBinCache {
    /// The packed lights and the bits of the f32 m the texels were made for.
    key: Option<(Vec<PackedLight>, u32)>,
    texels: Vec<[f32; 4]>,
}

/// A light as the frame packs it ([`pack_light`]).
type PackedLight = ([f32; 4], [f32; 4]);

impl LightBinCache {
    /// The bins of `lights` (as the frame packs them) for every m up to `max_m`, made unless the
    /// last call had the same lights and m.
    fn texels(&mut self, lights: Vec<PackedLight>, max_m: f32) -> &[[f32; 4]] {
        let key = (lights, max_m.to_bits());
        if self.key.as_ref() != Some(&key) {
            self.texels = light_bin_texels(&key.0, f64::from(max_m));
            self.key = Some(key);
        }
        &self.texels
    }
}

/// Objects the material buffer holds before it must grow.
const INITIAL_OBJECTS: usize = 8;

/// The buffers the frame data is written to, rewritten by every draw (the previous draw has
/// finished: `submit_and_wait` waits on its fence before returning) and grown when a draw needs
/// more.
pub(super) struct DrawBuffers {
    /// The shared frame of the background and shading passes.
    pub scene_frame: Buffer,
    /// Object i's frame for the G-buffer or forward pass (`draw_info.x` = i + 1).
    pub object_frames: Vec<Buffer>,
    /// Every object's Fresnel table, concatenated.
    pub knots: Buffer,
    /// Every object's [`ObjectMaterial`].
    pub materials: Buffer,
    /// The `brdf` model's light bins of the last draw.
    light_bins: LightBinCache,
}

impl DrawBuffers {
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        Ok(DrawBuffers {
            scene_frame: upload(
                gpu,
                "scene frame uniforms",
                &[Frame::zeroed()],
                BufferUsage::UNIFORM,
            )?,
            object_frames: Vec::new(),
            knots: upload(
                gpu,
                "fresnel knots",
                &[[0.0f32; 4]; INITIAL_KNOTS],
                BufferUsage::UNIFORM_TEXEL,
            )?,
            materials: upload(
                gpu,
                "object materials",
                &[ObjectMaterial::zeroed(); INITIAL_OBJECTS],
                BufferUsage::UNIFORM_TEXEL,
            )?,
            light_bins: LightBinCache::default(),
        })
    }

    /// Writes the frames (shared and per object), the materials and the Fresnel knots
    /// (`object_knots[i]` of object i); returns the shared frame, whose strip offset the caller
    /// sets per strip.
    pub fn write(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
        environment: &GpuEnvironment,
        (object_knots, object_albedo, scene_sphere): (&[Knots], &[Knots], SceneSphere),
    ) -> Result<Frame> {
        let brdf_lights = scene
            .reads_brdf_quadrature()
            .then(|| environment.brdf_lights());
        let mut knots: Vec<[f32; 4]> = Vec::new();
        let mut materials: Vec<ObjectMaterial> = Vec::new();
        for (i, (object, object_knots)) in scene.objects.iter().zip(object_knots).enumerate() {
            let first_knot = knots.len();
            knots.extend_from_slice(object_knots);
            let albedo_first = knots.len();
            if let Some(albedo) = object_albedo.get(i) {
                knots.extend_from_slice(albedo);
            }
            materials.push(ObjectMaterial::of_object(
                object.brdf,
                object.fresnel,
                (first_knot, albedo_first),
                &object.view_blur,
            ));
        }
        let mut frame = Frame::new(
            scene.camera,
            settings.width,
            settings.height,
            scene_sphere,
            scene.lights,
            &EnvironmentUniforms {
                enabled: scene.environment.is_some(),
                layer_betas: environment.betas.clone(),
                layer_faces: environment.layer_faces(),
                brdf_lights,
            },
        );
        if brdf_lights.is_some() {
            let ms = scene.objects.iter().map(|object| object.brdf.beckmann_m);
            frame.append_light_bins(&mut knots, ms, &mut self.light_bins);
        }
        for i in 0..materials.len() {
            frame.draw_info = [i as i32 + 1, 0, 0, 0];
            match self.object_frames.get_mut(i) {
                Some(buffer) => buffer.write(std::slice::from_ref(&frame))?,
                None => self.object_frames.push(upload(
                    gpu,
                    "object frame uniforms",
                    std::slice::from_ref(&frame),
                    BufferUsage::UNIFORM,
                )?),
            }
        }
        frame.draw_info = [0; 4];
        frame.background_color = scene.background.clear_color();
        let limit = u64::from(gpu.info().max_texel_buffer_elements);
        if knots.len() as u64 > limit {
            let fix = match brdf_lights {
                Some(_) => "use the `paper` environment model (no light bins) or fewer objects",
                None => "use fewer objects",
            };
            return Err(crate::Error::invalid(
                "objects",
                scene.objects.len(),
                format!(
                    "the draw's tables (each object's Fresnel and albedo knots, and the `brdf` \
                     model's light bins) take {} texels, and this device's texel buffers hold at \
                     most {limit}; {fix}",
                    knots.len()
                ),
            ));
        }
        self.scene_frame.write(std::slice::from_ref(&frame))?;
        let texel = BufferUsage::UNIFORM_TEXEL;
        write_growing(gpu, &mut self.knots, "fresnel knots", &knots, texel)?;
        write_growing(
            gpu,
            &mut self.materials,
            "object materials",
            &materials,
            texel,
        )?;
        Ok(frame)
    }
}

/// Writes `data` into `buffer`, replacing it with one that fits when it is too small.
fn write_growing<T: bytemuck::Pod>(
    gpu: &GpuContext,
    buffer: &mut Buffer,
    name: &str,
    data: &[T],
    usage: BufferUsage,
) -> Result<()> {
    if buffer.size() < std::mem::size_of_val(data) as u64 {
        *buffer = upload(gpu, name, data, usage)?;
    } else {
        buffer.write(data)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lights(count: usize, spread: f32) -> Vec<([f32; 4], [f32; 4])> {
        (0..count)
            .map(|i| {
                let a = i as f32 * 0.7;
                ([a.cos(), 0.3, a.sin(), spread], [i as f32, 1.0, 1.0, 0.0])
            })
            .map(|(d, e)| {
                let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                ([d[0] / n, d[1] / n, d[2] / n, d[3]], e)
            })
            .collect()
    }

    /// The cache hands back what the bins of its lights and m are, and makes them again when
    /// either changes.
    #[test]
    fn light_bin_cache_is_the_bins_of_its_last_key() {
        let mut cache = LightBinCache::default();
        let first = lights(20, 0.0);
        assert_eq!(
            cache.texels(first.clone(), 0.05),
            light_bin_texels(&first, 0.05)
        );
        assert_eq!(
            cache.texels(first.clone(), 0.05),
            light_bin_texels(&first, 0.05)
        );
        // Another m: the cull, and with it the lists, change.
        let wider = light_bin_texels(&first, 0.06);
        assert_ne!(wider, light_bin_texels(&first, 0.05));
        assert_eq!(cache.texels(first.clone(), 0.06), wider);
        // Other lights (a spread on each).
        let spread = lights(20, 1e-3);
        assert_ne!(light_bin_texels(&spread, 0.06), wider);
        assert_eq!(
            cache.texels(spread.clone(), 0.06),
            light_bin_texels(&spread, 0.06)
        );
    }

    /// SPEC's series and the `brdf` model's (its fine layers continue it below β_min) are
    /// geometric runs from layer 1; a series that is not one has none, and the shader searches.
    #[test]
    fn geometric_run_of_the_prefilters_layers() {
        use crate::environment::{EnvironmentModel, PrefilterParams};
        let betas = |p: PrefilterParams| (0..p.layers).map(|k| p.beta(k)).collect::<Vec<_>>();
        let run = geometric_run;
        let paper = betas(PrefilterParams::for_model(1024, EnvironmentModel::Paper));
        let (log, step) = run(&paper).unwrap();
        assert!((log - f64::from(paper[1] as f32).ln()).abs() < 1e-12);
        assert!((step - 50f64.ln() / 6.0).abs() < 1e-6, "{step}");
        let brdf = betas(PrefilterParams::for_model(1024, EnvironmentModel::Brdf));
        let (log, step) = run(&brdf).unwrap();
        assert!((log - f64::from(brdf[1] as f32).ln()).abs() < 1e-12);
        assert!((step - (brdf[3] / brdf[2]).ln()).abs() < 1e-6);
        assert_eq!(run(&[0.0, 0.1, 0.2, 0.5, 0.6]), None);
        // A series that doubles from layer 2 on but not from layer 1 (the old fine layer at
        // β_min/2 before a ×1.32 series would be one): none.
        assert_eq!(run(&[0.0, 0.05, 0.2, 0.4, 0.8]), None);
        assert_eq!(run(&[0.0, 0.1]), None);
    }

    /// The blend in variance's constants, packed once a draw: layer 0's read variance and the
    /// run's ratio of neighbouring variances less one (f32: 1e-6 relative).
    #[test]
    fn layer_variance_of_the_brdf_layers() {
        use crate::environment::{EnvironmentModel, PrefilterParams};
        let p = PrefilterParams::for_model(1024, EnvironmentModel::Brdf);
        let plan = p.plan();
        let betas: Vec<f64> = plan.iter().map(|l| l.beta).collect();
        let faces: Vec<u32> = plan.iter().map(|l| l.face_size).collect();
        let mut frame = Frame::zeroed();
        frame.set_environment_layers(&betas, &faces);
        let [read, ratio, ..] = frame.layer_variance.map(f64::from);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * b.abs();
        assert!(close(read, texel_read_variance(faces[0])), "{read}");
        assert!(close(ratio, (betas[2] / betas[1]).powi(2) - 1.0), "{ratio}");
    }
}
