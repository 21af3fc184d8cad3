//! The prefilter's parameters and the plan derived from them (SPEC §4): which β each blurred layer
//! has, at what face size it is stored, and which downsampled source it is convolved from. The GPU
//! prefilter (`gpu.rs`) and the CPU oracle (`oracle.rs`) both run exactly this plan.

use crate::error::show_number;
use crate::gpu::shaders::interface::MAX_STEP_ONE_SUPERSAMPLE;
use crate::model::limits;
use crate::{Error, Result};

/// Layers whose weight exp(-(1-c)/β²) falls below exp(-LOBE_CUTOFF) are not summed: 12.5 is 5σ of
/// the Gaussian the lobe approximates (1 - cos θ ≈ θ²/2), a relative weight of 3.7e-6, far below
/// the accuracy the layers are held to (mean 2 % against the untruncated definition).
pub const LOBE_CUTOFF: f64 = 12.5;

/// The smallest face size a blurred layer is stored at. At 8 texels per face the β = 0.27 layer
/// (K = 8) was 10.7 % from the definition at its worst texel; at 16 it is 1.1 %.
pub const MIN_LAYER_FACE: u32 = 16;

/// Step 1 reads S × S sub-samples per cube texel (the source pixel containing each) and averages
/// them: a box filter over the texel's footprint, which adds about half the extra blur of a
/// bilinear point sample (measured against the definition: layer-1 worst error 7.9 % vs 10.7 %).
/// S is what it takes to put about `scale`·π sub-samples across one source pixel at the face
/// centre: a cube texel spans 2/N there, a source pixel 2π/W, so S = `scale`·⌈W/N⌉, at most
/// `scale`·[`MAX_EQUIRECT_SUPERSAMPLE`] ([`PrefilterParams::supersample_scale`]: 1 for SPEC's
/// `paper` layers, [`BRDF_SUPERSAMPLE_SCALE`] for `brdf`'s). Passed to equirect_to_cube.comp as a
/// push constant.
pub fn equirect_supersample(source_width: u32, face_size: u32, scale: u32) -> u32 {
    let scale = scale.clamp(1, MAX_SUPERSAMPLE_SCALE);
    scale
        * source_width
            .div_ceil(face_size.max(1))
            .clamp(1, MAX_EQUIRECT_SUPERSAMPLE)
}

/// Beyond 4 × 4 sub-samples the box filter is exact to well below the `paper` layers' accuracy;
/// a source far larger than the cube is better downsampled first.
pub const MAX_EQUIRECT_SUPERSAMPLE: u32 = 4;

/// The largest [`PrefilterParams::supersample_scale`]: S ≤ `MAX_STEP_ONE_SUPERSAMPLE` (16),
/// which step 1's near pass is sized for.
pub const MAX_SUPERSAMPLE_SCALE: u32 = MAX_STEP_ONE_SUPERSAMPLE / MAX_EQUIRECT_SUPERSAMPLE;

/// [`PrefilterParams::supersample_scale`] of the `brdf` model's layers: S = 16 at the usual
/// W = 4N, about 12.6 sub-samples across a source pixel at the face centre instead of `paper`'s
/// π. A line one pixel wide (a lamp stand at the studio's horizon, 25× its surround), which π
/// sub-samples count 4.5 % short or 27 % over row by row, is counted within a few percent, and the
/// studio board seen 80° from its normal at m = 0.05 went from 2.96 / 16.6 % to 2.02 / 11.8 %
/// (mean / p99; BENCHMARKS.md, "Step 1 counts thin lines"). Step 1 then costs 1.5 s instead of
/// 0.08 s a map on lavapipe (2 cores), once per map and light.
pub const BRDF_SUPERSAMPLE_SCALE: u32 = 4;

/// Face size of the irradiance cube, and of the source it integrates: E(N) is a cosine-weighted
/// integral over a hemisphere, so 32² texels per face resolve it far below 1e-3 (measured in the
/// irradiance tests).
pub const IRRADIANCE_FACE: u32 = 32;

// irradiance.comp loops over all 6·M² source texels; lavapipe cuts loops off at 65535 iterations.
const _: () = assert!(6 * IRRADIANCE_FACE * IRRADIANCE_FACE < 65535);

/// The variance the texels of a layer of face size `face_size` add when it is read: h²/4 for
/// texels h = (π/2)/`face_size` radians wide, each the box average of the source mip's (h²/12)
/// and read bilinearly (a tent, h²/6). The `brdf` model's blend between the sharp layer 0 and
/// layer 1 counts it as layer 0's (brdf_quadrature.rs `layered_radiance`; the shaders read it
/// from `Frame::layer_variance`).
pub fn texel_read_variance(face_size: u32) -> f64 {
    let h = std::f64::consts::FRAC_PI_2 / f64::from(face_size.max(1));
    h * h / 4.0
}

/// Limits on what a user may ask for.
pub const MAX_FACE_SIZE: u32 = 4096;
pub use crate::gpu::shaders::interface::MAX_ENV_LAYERS;

/// What the user chooses (`shikki prefilter --face-size --layers --beta-min --beta-max`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrefilterParams {
    /// Face size N of layer 0 (the sharp map); a power of two.
    pub face_size: u32,
    /// K, the number of layers including the sharp layer 0.
    pub layers: u32,
    pub beta_min: f64,
    pub beta_max: f64,
    /// The widest a blurred layer's texel, (π/2)/M, may be as a share of the layer's β
    /// ([`layer_face_size`]): 1 for SPEC's `paper` layers, [`BRDF_LAYER_TEXEL`] for `brdf`'s.
    pub layer_texel: f64,
    /// The finer texel (a share of β) a blurred layer gets where that keeps its face at most
    /// [`SMALL_LAYER_FACE`] ([`layer_face_size`]): [`BRDF_SMALL_LAYER_TEXEL`] for `brdf`'s
    /// layers; `layer_texel` itself (no change) for SPEC's `paper` layers.
    pub small_layer_texel: f64,
    /// Layers between the sharp layer 0 and β_min: the series continued below β_min at its own
    /// ratio, β_min/r, β_min/r², … (the `brdf` model's [`BRDF_FINE_LAYERS`]); 0 for SPEC's
    /// series.
    pub fine_layers: u32,
    /// Each blurred layer convolved by its β less its texels' read ([`LayerPlan::blur`]), so that
    /// a bilinear read of it is blurred by β: the `brdf` model's layers
    /// ([`BRDF_BLUR_NET_OF_READ`]); false for SPEC's `paper` layers, convolved by β itself.
    pub blur_net_of_read: bool,
    /// Step 1's sub-samples a side per texel, as a multiple of the `paper` rule
    /// ([`equirect_supersample`]): 1 for SPEC's `paper` layers, [`BRDF_SUPERSAMPLE_SCALE`] for
    /// `brdf`'s.
    pub supersample_scale: u32,
}

/// [`PrefilterParams::blur_net_of_read`] of the `brdf` model's layers. A layer's texels are box
/// means of the source (h²/12 of variance per axis, h = (π/2)/M) and a bilinear read between them
/// adds a tent's h²/6 on average: a lookup of a layer convolved by β_k reads β_k² + h²/4
/// ([`texel_read_variance`], what the lookups' blend already counts for the sharp layer 0),
/// 3–13 % more variance than asked at the `brdf` layers' texels of 0.35–0.71 β, and a dark point
/// beside a bright patch is all the lookups' tails. Convolved by √(β_k² − h²/4) instead, with the
/// lattice's reach of 4 σ, the 112 points at m = 0.05 read 0.81 / 4.5 % (mean / p99, courtyard)
/// against 1.10 / 10.3 % convolved by β_k; netting out 0.12, 0.2 or 0.3·h² instead of h²/4 gave
/// 6.6, 4.5 and 5.1 % p99 (BENCHMARKS.md, "Layers net of their read").
pub const BRDF_BLUR_NET_OF_READ: bool = true;

/// [`PrefilterParams::layer_texel`] of the `brdf` model's layers: two thirds of β, so at least
/// 1.5 texels across σ. Its lookups read a layer at the blur of their own node or sample, and a
/// bilinear read between texels as wide as σ is off by up to h²/(8σ²) ≈ 12 % on the peak of a
/// narrow feature (the studio board at 25°, m = 0.05: 9.2 % relative RMSE, 3.3 % at 2/3 of β);
/// half of β was a little better still (3.0 %) but took a cold `brdf` start of the default scene
/// from 2.45 to 5.75 s (BENCHMARKS.md, "Layers that resolve the lattice's blur").
pub const BRDF_LAYER_TEXEL: f64 = 2.0 / 3.0;

/// [`PrefilterParams::small_layer_texel`] of the `brdf` model's layers, up to faces of
/// [`SMALL_LAYER_FACE`]. At 2/3 of β the layers at β 0.08–0.19 (faces of 16–32) read a dark
/// point between bright patches up to 11.5 % too bright against the Gaussian of their β (the
/// centre of the courtyard's sphere at m = 0.05, looking back at its camera): a bilinear read
/// interpolates linearly over texels 0.6 β wide, above a convex dip, which no net blur undoes.
/// At 0.4 of β those layers read within 1 %, and the sphere's pixels facing the camera went from
/// 1.15 / 6.8 % to 1.09 / 5.2 % (mean / p99). A face of 64 costs the prefilter little beside
/// layer 0's 256 (the window grows as the face squared, the texels too: 16× a face of 32).
pub const BRDF_SMALL_LAYER_TEXEL: f64 = 0.4;

/// The largest face [`PrefilterParams::small_layer_texel`] applies to.
pub const SMALL_LAYER_FACE: u32 = 64;

/// The `brdf` model's [`PrefilterParams::fine_layers`]. Its lookups narrower than β_min (the
/// lattice across the plane of incidence at m ≤ 0.03, or towards grazing) blend the layers
/// below it, and a blend of two blurs is a blur of the blended variance but not of a Gaussian's
/// shape: its tails are the wider layer's, and a dark point beside a bright edge is all tails.
/// One layer at β_min/2 (until 2026-12-05) left ratios of 2 and ~3 between the sharp layer, it
/// and β_min; three layers on the series' own ratio took the courtyard's 112 points at m = 0.02
/// from 1.05 to 0.74 % mean and the studio's from 1.40 to 1.20 % (BENCHMARKS.md, "The series
/// continued below β_min"). A fourth, at 0.0065, is coarser than its face of 256 can hold and
/// gave nothing.
pub const BRDF_FINE_LAYERS: u32 = 3;

/// The `brdf` model's widest layer: 14 layers from β_min to it keep the ratio of SPEC's K = 16
/// series, 50^(1/14) ≈ 1.32 per layer ([`PrefilterParams::for_model`]).
pub const BRDF_BETA_MAX: f64 = 0.76;

/// The `brdf` model's layer count: the sharp map, [`BRDF_FINE_LAYERS`], then β_min …
/// [`BRDF_BETA_MAX`] in 13 steps of ×1.32.
pub const BRDF_LAYERS: u32 = 1 + BRDF_FINE_LAYERS + 14;

impl PrefilterParams {
    /// SPEC defaults (K = 8, β 0.02 … 1.0) with the face size chosen from the source width.
    pub fn for_source_width(width: u32) -> Self {
        Self {
            face_size: default_face_size(width),
            layers: 8,
            beta_min: 0.02,
            beta_max: 1.0,
            layer_texel: 1.0,
            small_layer_texel: 1.0,
            fine_layers: 0,
            blur_net_of_read: false,
            supersample_scale: 1,
        }
    }

    /// [`for_source_width`](Self::for_source_width) for the environment model that draws with
    /// the layers: SPEC §4's K = 8 for `paper`; for `brdf`, whose lookups read the layer whose
    /// blur matches each node's or sample's, [`BRDF_LAYERS`] at [`BRDF_LAYER_TEXEL`]: the sharp
    /// map, then the series of ×1.32 instead of ×1.92 (the blend of two layers is further from
    /// the blur between them the further apart they are; BENCHMARKS.md, "The `brdf` environment
    /// model") from [`BRDF_FINE_LAYERS`] steps below β_min up to [`BRDF_BETA_MAX`].
    pub fn for_model(width: u32, model: EnvironmentModel) -> Self {
        let paper = Self::for_source_width(width);
        match model {
            EnvironmentModel::Paper => paper,
            EnvironmentModel::Brdf => Self {
                layers: BRDF_LAYERS,
                layer_texel: BRDF_LAYER_TEXEL,
                small_layer_texel: BRDF_SMALL_LAYER_TEXEL,
                fine_layers: BRDF_FINE_LAYERS,
                beta_max: BRDF_BETA_MAX,
                blur_net_of_read: BRDF_BLUR_NET_OF_READ,
                supersample_scale: BRDF_SUPERSAMPLE_SCALE,
                ..paper
            },
        }
    }

    pub fn validate(&self) -> Result<()> {
        let n = self.face_size;
        if !(MIN_LAYER_FACE..=MAX_FACE_SIZE).contains(&n) || !n.is_power_of_two() {
            return Err(Error::invalid(
                "face size",
                n,
                format!(
                    "must be a power of two in {MIN_LAYER_FACE}..={MAX_FACE_SIZE} (e.g. 256, 512)"
                ),
            ));
        }
        if !(2..=MAX_ENV_LAYERS as u32).contains(&self.layers) {
            return Err(Error::invalid(
                "layers",
                self.layers,
                format!("K must be in 2..={MAX_ENV_LAYERS} (layer 0 is the sharp map)"),
            ));
        }
        for (field, value) in [("beta_min", self.beta_min), ("beta_max", self.beta_max)] {
            if !(value.is_finite() && value > 0.0 && value <= 4.0) {
                return Err(Error::invalid(field, value, "must be in (0, 4]"));
            }
        }
        if !(0.25..=1.0).contains(&self.layer_texel) {
            return Err(Error::invalid(
                "layer_texel",
                self.layer_texel,
                "must be in [0.25, 1] (a blurred layer's texel as a share of its β)",
            ));
        }
        if !(0.25..=self.layer_texel).contains(&self.small_layer_texel) {
            return Err(Error::invalid(
                "small_layer_texel",
                self.small_layer_texel,
                format!(
                    "must be in [0.25, layer_texel = {}] (a small layer's texel as a share of its β)",
                    self.layer_texel
                ),
            ));
        }
        if !(1..=MAX_SUPERSAMPLE_SCALE).contains(&self.supersample_scale) {
            return Err(Error::invalid(
                "supersample_scale",
                self.supersample_scale,
                format!(
                    "must be in 1..={MAX_SUPERSAMPLE_SCALE} (step 1's sub-samples as a multiple \
                     of the `paper` rule)"
                ),
            ));
        }
        if self.fine_layers + 2 > self.layers {
            return Err(Error::invalid(
                "fine_layers",
                self.fine_layers,
                format!(
                    "must leave β_min a layer: at most K − 2 = {}",
                    self.layers.saturating_sub(2)
                ),
            ));
        }
        if self.beta_max < self.beta_min {
            return Err(Error::invalid(
                "beta_max",
                self.beta_max,
                format!("must be ≥ beta_min = {}", self.beta_min),
            ));
        }
        Ok(())
    }

    /// β_k of SPEC §4: β_0 = 0; β_k = β_min·(β_max/β_min)^((k-1)/(K-2)) for k ≥ 1 (K = 2: β_1 = β_min).
    /// With F [`fine_layers`](Self::fine_layers), β_min is layer F + 1 and the series runs from
    /// layer 1 at its own ratio r = (β_max/β_min)^(1/(K−2−F)): β_k = β_min·r^(k−1−F). Where β_min
    /// is the last layer (K = F + 2) there is no ratio, and each fine layer halves the one above.
    pub fn beta(&self, k: u32) -> f64 {
        if k == 0 {
            return 0.0;
        }
        let first = 1 + self.fine_layers;
        if self.layers <= first + 1 {
            return self.beta_min * 0.5f64.powi(first as i32 - k as i32);
        }
        let steps = f64::from(self.layers - 1 - first);
        let t = (f64::from(k) - f64::from(first)) / steps;
        self.beta_min * (self.beta_max / self.beta_min).powf(t)
    }

    /// The plan for every layer, 0..K.
    pub fn plan(&self) -> Vec<LayerPlan> {
        (0..self.layers)
            .map(|k| {
                let beta = self.beta(k);
                let face_size = match k {
                    0 => self.face_size,
                    _ => {
                        let small = layer_face_size(beta, self.small_layer_texel, self.face_size);
                        let face = layer_face_size(beta, self.layer_texel, self.face_size);
                        face.max(small.min(SMALL_LAYER_FACE))
                    }
                };
                let blur = match self.blur_net_of_read && k > 0 {
                    true => (beta * beta - texel_read_variance(face_size))
                        .max(0.0)
                        .sqrt(),
                    false => beta,
                };
                LayerPlan {
                    beta,
                    blur,
                    face_size,
                }
            })
            .collect()
    }

    /// The face sizes of the source mip chain: N, N/2, …, down to the smallest any layer or the
    /// irradiance needs.
    /// Step 1's S for a source `source_width` pixels wide ([`equirect_supersample`]).
    pub fn supersample(&self, source_width: u32) -> u32 {
        equirect_supersample(source_width, self.face_size, self.supersample_scale)
    }

    pub fn mip_faces(&self) -> Vec<u32> {
        let smallest = self
            .plan()
            .iter()
            .map(|l| l.face_size)
            .chain(std::iter::once(IRRADIANCE_FACE.min(self.face_size)))
            .min()
            .unwrap_or(self.face_size);
        let mut faces = vec![self.face_size];
        while let Some(&last) = faces.last() {
            if last / 2 < smallest {
                break;
            }
            faces.push(last / 2);
        }
        faces
    }

    /// Face size of the irradiance cube.
    pub fn irradiance_face(&self) -> u32 {
        IRRADIANCE_FACE.min(self.face_size)
    }
}

/// SPEC §4's environment models: `paper`, the paper's multi-layer cube picked by β(nv) (the
/// default), or `brdf`, the integral of §2's BRDF itself by a fixed quadrature
/// (`brdf_quadrature.rs` and its shader twin brdf_environment.glsl).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum EnvironmentModel {
    #[default]
    Paper,
    Brdf,
}

impl EnvironmentModel {
    pub const ALL: [EnvironmentModel; 2] = [EnvironmentModel::Paper, EnvironmentModel::Brdf];

    /// The name scene files, the CLI and the C API use.
    pub fn name(self) -> &'static str {
        match self {
            EnvironmentModel::Paper => "paper",
            EnvironmentModel::Brdf => "brdf",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(name))
    }

    /// "`paper` or `brdf`", for error messages.
    pub fn choices() -> String {
        let names: Vec<String> = Self::ALL
            .iter()
            .map(|m| format!("`{}`", m.name()))
            .collect();
        names.join(" or ")
    }
}

/// How an environment map lights the world (SPEC §4): its radiance × `intensity`, turned by
/// `rotation_deg` about +Y. Applied when the map is resampled to the cube, so both are part of a
/// prefiltered environment's identity (its cache key) although they change none of the plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvironmentLight {
    pub intensity: f64,
    pub rotation_deg: f64,
}

impl Default for EnvironmentLight {
    /// The map as stored, unrotated.
    fn default() -> Self {
        Self {
            intensity: 1.0,
            rotation_deg: 0.0,
        }
    }
}

impl EnvironmentLight {
    pub const fn new(intensity: f64, rotation_deg: f64) -> Self {
        Self {
            intensity,
            rotation_deg,
        }
    }

    /// Checks the map `image` (called `name`) lit by this light stays within the light levels
    /// the device carries ([`limits::MAX_LIGHT_LEVEL`]): its brightest pixel times `intensity`.
    /// A map of 1e38 was prefiltered to infinities and drew black.
    pub fn check_levels(&self, image: &super::Equirect, name: &str) -> Result<()> {
        if !(self.intensity.is_finite() && self.intensity >= 0.0) {
            return Err(Error::invalid(
                "environment intensity",
                self.intensity,
                "must be a finite number >= 0 (1 = the map as stored)",
            ));
        }
        let brightest = image
            .pixels
            .iter()
            .flatten()
            .fold(0.0_f32, |max, &c| max.max(c));
        let level = f64::from(brightest) * self.intensity;
        match limits::light_level_problem(level) {
            None => Ok(()),
            Some(_) => Err(Error::invalid(
                "environment intensity",
                self.intensity,
                format!(
                    "{name}'s brightest pixel ({}) times the intensity is {}: the product must \
                     be at most {:e}, the light level the renderer's f32 arithmetic carries; \
                     lower the intensity (or scale the map and the exposure together)",
                    show_number(f64::from(brightest)),
                    show_number(level),
                    limits::MAX_LIGHT_LEVEL
                ),
            )),
        }
    }

    /// Bit-exact equality: two lights that prefilter to different bytes (0° and −0° included)
    /// are never taken for one another by a cache.
    pub fn same_bits(&self, other: &Self) -> bool {
        self.intensity.to_bits() == other.intensity.to_bits()
            && self.rotation_deg.to_bits() == other.rotation_deg.to_bits()
    }
}

/// One blurred layer: its lobe width, the width its convolution uses and the face size it is
/// stored at. A blurred layer is convolved from the source mip of the same face size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerPlan {
    /// β_k: what a lookup of the layer reads.
    pub beta: f64,
    /// The convolution's β: `beta`, or with [`PrefilterParams::blur_net_of_read`]
    /// √(β_k² − h²/4), h the layer's texel; 0 for the sharp layer 0.
    pub blur: f64,
    pub face_size: u32,
}

/// Face size for lobe width β: the smallest power of two whose texel, (π/2)/M radians (its mean
/// width along a face's centre line: 2/M at the face centre, 1/M at the middle of an edge), is no
/// wider than `texel`·β, clamped to [MIN_LAYER_FACE, N]. Texels as wide as the
/// lobe's σ (`texel` = 1, SPEC's layers) add only h²/12 ≈ 8 % of σ² of extra variance from the
/// box-filtered source (≈ 4 % in width), and keep the brute-force convolution's window at
/// ~(10β/h)² ≈ 100–300 texels per output texel; finer texels cost that window's growth on top
/// of the texels' ([`BRDF_LAYER_TEXEL`]).
pub fn layer_face_size(beta: f64, texel: f64, face_size: u32) -> u32 {
    let wanted = (std::f64::consts::FRAC_PI_2 / (texel * beta))
        .ceil()
        .max(1.0);
    let pow2 = if wanted >= f64::from(face_size) {
        face_size
    } else {
        (wanted as u32).next_power_of_two()
    };
    pow2.clamp(MIN_LAYER_FACE.min(face_size), face_size)
}

/// Default face size for an equirectangular source of the given width: the power of two nearest
/// to width/4 (one cube texel per source texel at the equator), in 16..=2048.
pub fn default_face_size(width: u32) -> u32 {
    let target = (f64::from(width) / 4.0).max(1.0);
    let lower = 1u32 << (target.log2().floor() as u32).min(31);
    let upper = lower.saturating_mul(2);
    let nearest = if target / f64::from(lower) <= f64::from(upper) / target {
        lower
    } else {
        upper
    };
    nearest.clamp(16, 2048)
}

/// The blur β(nv) a fragment sees (SPEC §4): β_grazing + (β_normal - β_grazing)·nv^p.
pub fn view_beta(beta_normal: f64, beta_grazing: f64, beta_power: f64, nv: f64) -> f64 {
    beta_grazing + (beta_normal - beta_grazing) * nv.clamp(0.0, 1.0).powf(beta_power)
}

/// A material's view-dependent blur parameters (SPEC §4 `beta_normal`, `beta_grazing`,
/// `beta_power`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewBlur {
    pub beta_normal: f64,
    pub beta_grazing: f64,
    pub beta_power: f64,
}

impl Default for ViewBlur {
    /// The `smooth` preset's values.
    fn default() -> Self {
        Self {
            beta_normal: 0.1,
            beta_grazing: 0.1,
            beta_power: 1.0,
        }
    }
}

impl ViewBlur {
    pub fn of(material: &crate::model::LacquerMaterial) -> Self {
        Self {
            beta_normal: material.beta_normal,
            beta_grazing: material.beta_grazing,
            beta_power: material.beta_power,
        }
    }

    /// β at this nv.
    pub fn beta(&self, nv: f64) -> f64 {
        view_beta(self.beta_normal, self.beta_grazing, self.beta_power, nv)
    }
}

/// Where a lookup at `beta` falls between layers (SPEC §4): (k, t) meaning
/// mix(layer k, layer k+1, t). Linear in β between layers 0 and 1, linear in log β above; clamped
/// to the last layer beyond β_max.
pub fn layer_blend(betas: &[f64], beta: f64) -> (usize, f64) {
    let last = betas.len().saturating_sub(1);
    if last == 0 || beta <= 0.0 {
        return (0, 0.0);
    }
    if beta < betas[1] {
        return (0, beta / betas[1]);
    }
    for k in 1..last {
        if beta < betas[k + 1] {
            let t = (beta.ln() - betas[k].ln()) / (betas[k + 1].ln() - betas[k].ln());
            return (k, t);
        }
    }
    (last, 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn betas_follow_spec_geometric_series() {
        let p = PrefilterParams::for_source_width(1024);
        assert_eq!(p.face_size, 256);
        assert_eq!(p.beta(0), 0.0);
        assert!((p.beta(1) - 0.02).abs() < 1e-15);
        assert!((p.beta(7) - 1.0).abs() < 1e-12);
        // β_4 = 0.02·50^(1/2) by hand.
        assert!((p.beta(4) - 0.02 * 50f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn step_one_takes_the_paper_rule_of_sub_samples_times_its_scale_a_side() {
        // The `paper` rule: S = ⌈W/N⌉ in 1..=4; a scale of 4 takes 4× that a side.
        let paper = PrefilterParams::for_model(1024, EnvironmentModel::Paper);
        let brdf = PrefilterParams::for_model(1024, EnvironmentModel::Brdf);
        assert_eq!((paper.face_size, brdf.face_size), (256, 256));
        assert_eq!(paper.supersample(1024), 4);
        assert_eq!(brdf.supersample(1024), 4 * BRDF_SUPERSAMPLE_SCALE);
        let scaled = PrefilterParams {
            supersample_scale: 4,
            ..brdf
        };
        assert_eq!(scaled.supersample(1024), 16);
        assert_eq!(equirect_supersample(300, 256, 1), 2);
        assert_eq!(equirect_supersample(300, 256, 4), 8);
        assert_eq!(equirect_supersample(64, 256, 4), 4);
        assert_eq!(
            equirect_supersample(1 << 16, 256, 4),
            MAX_STEP_ONE_SUPERSAMPLE
        );
        for (scale, ok) in [(0, false), (1, true), (4, true), (5, false)] {
            let p = PrefilterParams {
                supersample_scale: scale,
                ..brdf
            };
            assert_eq!(p.validate().is_ok(), ok, "scale {scale}");
        }
        let err = PrefilterParams {
            supersample_scale: 5,
            ..brdf
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("supersample_scale") && err.contains("1..=4"),
            "{err}"
        );
    }

    #[test]
    fn layer_faces_resolve_their_lobe() {
        let p = PrefilterParams {
            face_size: 512,
            layers: 8,
            beta_min: 0.02,
            beta_max: 1.0,
            layer_texel: 1.0,
            small_layer_texel: 1.0,
            fine_layers: 0,
            blur_net_of_read: false,
            supersample_scale: 1,
        };
        let faces: Vec<u32> = p.plan().iter().map(|l| l.face_size).collect();
        // π/2/0.02 = 78.5 → 128; β_2 = 0.0384 → 40.9 → 64; … β_5 = 0.27 → 5.8 → 8 → clamped to 16.
        assert_eq!(faces, vec![512, 128, 64, 32, 16, 16, 16, 16]);
        assert_eq!(p.mip_faces(), vec![512, 256, 128, 64, 32, 16]);
    }

    #[test]
    fn brdf_layers_have_a_texel_of_two_thirds_of_beta_and_small_ones_finer() {
        let p = PrefilterParams::for_model(1024, EnvironmentModel::Brdf);
        let faces: Vec<u32> = p.plan().iter().map(|l| l.face_size).collect();
        // β_k = 0.02·38^((k−4)/13); M ≥ 1.5·(π/2)/β_k: the fine layers β_1..3 = 0.0086, 0.0114,
        // 0.0151 → 273, 206, 156 → 512, 256, 256, each clamped to N = 256; β_4 = 0.02 → 117.8 →
        // 128, β_5 = 0.0265 → 89.1 → 128, β_6 = 0.0350 → 67.3 → 128, β_7 = 0.0463 → 50.9 → 64,
        // β_8 = 0.0613 → 38.5 → 64, … β_12 = 0.188 → 12.6 → 16. Where M ≥ 2.5·(π/2)/β_k is at
        // most 64 it is taken instead: β_9 = 0.081 → 48.5 → 64 (not 32), β_10 = 0.107 → 36.6 →
        // 64, β_11 = 0.142 → 27.7 → 32, β_12 → 20.9 → 32 (not 16), β_13 = 0.248 → 15.8 → 16.
        assert_eq!(
            faces,
            vec![256, 256, 256, 256, 128, 128, 128, 64, 64, 64, 64, 32, 32, 16, 16, 16, 16, 16]
        );
        // Every layer at 2/3 of β at most (but the fine layers, held at N), and at 0.4 of β
        // unless that needs a face above `SMALL_LAYER_FACE` (layers 4–8, which keep 128 and 64).
        for layer in &p.plan()[1..] {
            let texel = std::f64::consts::FRAC_PI_2 / f64::from(layer.face_size);
            assert!(texel <= BRDF_LAYER_TEXEL * layer.beta || layer.face_size == p.face_size);
            assert!(
                texel <= BRDF_SMALL_LAYER_TEXEL * layer.beta || layer.face_size >= SMALL_LAYER_FACE
            );
        }
        let paper = PrefilterParams::for_model(1024, EnvironmentModel::Paper);
        assert_eq!(paper, PrefilterParams::for_source_width(1024));
    }

    #[test]
    fn brdf_layers_are_convolved_net_of_their_read() {
        let brdf = PrefilterParams::for_model(1024, EnvironmentModel::Brdf);
        for (k, layer) in brdf.plan().iter().enumerate() {
            let read = texel_read_variance(layer.face_size);
            match k {
                0 => assert_eq!(layer.blur, 0.0),
                // What a bilinear read of the layer adds brings it back to β_k.
                _ => assert!((layer.blur.powi(2) + read - layer.beta.powi(2)).abs() < 1e-15),
            }
            assert!(layer.blur <= layer.beta);
        }
        // At the `brdf` layers' texels (≤ 0.71 β) the read is at most 13 % of β².
        let worst = brdf.plan()[1..]
            .iter()
            .map(|l| texel_read_variance(l.face_size) / l.beta.powi(2))
            .fold(0.0, f64::max);
        assert!(worst > 0.12 && worst < 0.13, "{worst}");
        // SPEC's `paper` layers are convolved by β_k itself.
        let paper = PrefilterParams::for_model(1024, EnvironmentModel::Paper);
        assert!(paper.plan().iter().all(|l| l.blur == l.beta));
    }

    #[test]
    fn the_fine_layers_continue_the_series_below_beta_min() {
        let p = PrefilterParams::for_model(1024, EnvironmentModel::Brdf);
        assert_eq!(p.layers, 18);
        assert_eq!(p.beta(0), 0.0);
        let first = 1 + BRDF_FINE_LAYERS;
        assert!((p.beta(first) - 0.02).abs() < 1e-15);
        assert!((p.beta(17) - BRDF_BETA_MAX).abs() < 1e-12);
        // One ratio from layer 1 to the last, (0.76/0.02)^(1/13) = 1.322884 by hand, so the
        // shaders' `layer_pair_of_run` finds every pair on the run.
        for k in 1..17 {
            let ratio = p.beta(k + 1) / p.beta(k);
            assert!((ratio - 1.322_884).abs() < 1e-6, "layer {k}: {ratio}");
        }
        // The ratio of SPEC's K = 16 series, 50^(1/14), within 0.1 %.
        let ratio = p.beta(first + 1) / p.beta(first);
        assert!(
            (ratio / 50f64.powf(1.0 / 14.0) - 1.0).abs() < 1e-3,
            "{ratio}"
        );
    }

    #[test]
    fn fine_layers_must_leave_beta_min_a_layer() {
        let p = PrefilterParams {
            layers: 4,
            fine_layers: 3,
            ..PrefilterParams::for_source_width(1024)
        };
        let message = p.validate().unwrap_err().to_string();
        assert!(
            message.contains("fine_layers") && message.contains("K − 2 = 2"),
            "{message}"
        );
        let p = PrefilterParams {
            fine_layers: 2,
            ..p
        };
        p.validate().unwrap();
        // β_min is layer 3, the last: the fine layers halve below it.
        assert_eq!(p.beta(3), 0.02);
        assert_eq!(p.beta(1), 0.005);
    }

    #[test]
    fn blend_is_linear_below_layer_one_and_log_linear_above() {
        let betas = [0.0, 0.02, 0.04, 0.08];
        assert_eq!(layer_blend(&betas, 0.01), (0, 0.5));
        let (k, t) = layer_blend(&betas, 0.02 * 2f64.sqrt());
        assert_eq!(k, 1);
        assert!((t - 0.5).abs() < 1e-12);
        assert_eq!(layer_blend(&betas, 5.0), (3, 0.0));
    }

    #[test]
    fn view_beta_matches_spec_presets() {
        // rough: β_normal 0.6, β_grazing 0.05, p = 1.
        assert!((view_beta(0.6, 0.05, 1.0, 1.0) - 0.6).abs() < 1e-15);
        assert!((view_beta(0.6, 0.05, 1.0, 0.0) - 0.05).abs() < 1e-15);
        assert!((view_beta(0.6, 0.05, 1.0, 0.5) - 0.325).abs() < 1e-15);
    }

    #[test]
    fn invalid_params_are_rejected_with_the_range() {
        let mut p = PrefilterParams::for_source_width(1024);
        p.face_size = 300;
        assert!(p
            .validate()
            .unwrap_err()
            .to_string()
            .contains("power of two"));
        p.face_size = 256;
        p.layers = 1;
        assert!(p.validate().unwrap_err().to_string().contains("2..=20"));
        p.layers = 8;
        p.beta_min = f64::NAN;
        assert!(p.validate().is_err());
    }
}
