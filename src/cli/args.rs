//! The argument surface (clap derive) of every subcommand and the small value parsers it needs.
//! The files that run the commands import this one, never the reverse: it names only library
//! types and constants.

use crate::bench::Stage;
use crate::environment::EnvironmentModel;
use crate::output::ToneCurve;
use crate::raster::draw::Background;
use crate::raster::draw::{MAX_BOUNCES, MAX_RAYS};
use crate::raster::mesh::{BuiltinMesh, BUILTIN_SEGMENTS};
use crate::scene::RenderSpec;
use crate::{Error, Result};
use clap::{Args, Parser, Subcommand, ValueEnum};
use glam::DVec3;
use std::path::PathBuf;

#[derive(Debug, Parser)]
#[command(
    name = "shikki",
    version,
    about = "Render Japanese lacquer ware (urushi) headless on Vulkan"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

// Parsed once per process: the size of the largest variant (render's many flags) costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a mesh with the lacquer BRDF to PNG or EXR (the default command).
    Render(RenderArgs),
    /// Evaluate f_r for direction triples read from a CSV (columns nx,ny,nz,vx,vy,vz,lx,ly,lz).
    Brdf(BrdfArgs),
    /// Print a material's Fresnel table as angle_deg,r,g,b (whole degrees 0..90; a CSV's own angles).
    Fresnel(MaterialArgs),
    /// Print the Vulkan device, driver and the limits shikki relies on.
    Info,
    /// Prefilter an environment on the GPU and write its layers and irradiance as EXR strips.
    Prefilter(PrefilterArgs),
    /// Fit the lacquer model to goniophotometer CSV or MERL data; write a material TOML.
    Fit(FitArgs),
    /// Generate synthetic goniophotometer measurements from a material.
    Synth(SynthArgs),
    /// Render every job of a jobs file (a base scene plus sweeps): images, manifest.csv and
    /// contact_sheet.png.
    Batch(BatchArgs),
    /// Measure every stage (render, prefilter, batch, start-up, memory): medians of repeated runs
    /// and same-run ratios against the performance targets (BENCHMARKS.md).
    Bench(BenchArgs),
    /// Export a built-in mesh as OBJ or GLB (for Blender or another renderer); the file loads
    /// back in shikki to the same triangles.
    Mesh(MeshArgs),
}

/// A preset and `--set` overrides: the material of SPEC §2–3.
#[derive(Debug, Clone, Args)]
pub struct MaterialArgs {
    /// Material preset: smooth, rough, smooth-black, smooth-red, rough-black, rough-red.
    #[arg(long, default_value = "smooth-red")]
    pub preset: String,
    /// A material file (TOML, docs/measurements.md; e.g. written by `shikki fit`); replaces
    /// --preset, and --set still applies on top.
    #[arg(long)]
    pub material: Option<PathBuf>,
    /// Override a material field by its SPEC name: m, a, b, c0, c1, c2, r, kd=r,g,b,
    /// fresnel=PATH.csv, ior_a, ior_b, extrapolate_g=true, beta_normal, beta_grazing, beta_power.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Backend {
    Cpu,
    Gpu,
}

#[derive(Debug, Args)]
pub struct BrdfArgs {
    #[command(flatten)]
    pub material: MaterialArgs,
    /// CSV with header nx,ny,nz,vx,vy,vz,lx,ly,lz.
    #[arg(long)]
    pub input: PathBuf,
    /// Evaluate with the CPU model or with the GLSL BRDF in a compute shader.
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Backend,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// A scene file (docs/scene.md). With it, `--set PATH=VALUE` overrides scene fields
    /// (e.g. camera.fov_deg=30, object.0.material.r=2) and the other scene flags are ignored.
    pub scene: Option<PathBuf>,
    /// Output file: .png (tone-mapped sRGB) or .exr (linear radiance).
    #[arg(short = 'o', long = "output", default_value = "shikki.png")]
    pub output: PathBuf,
    /// Image size WxH in pixels.
    #[arg(long, default_value = "1024x1024", value_parser = parse_size)]
    pub size: (u32, u32),
    #[command(flatten)]
    pub material: MaterialArgs,
    // The help lists `BuiltinMesh::ALL`, so a new built-in appears in it without an edit here.
    #[arg(long, default_value = "builtin:sphere", help = mesh_help())]
    pub mesh: String,
    /// Camera position x,y,z.
    #[arg(long, value_parser = parse_vec3_arg, allow_hyphen_values = true)]
    pub eye: Option<DVec3>,
    /// Point the camera looks at, x,y,z.
    #[arg(long, value_parser = parse_vec3_arg, allow_hyphen_values = true)]
    pub target: Option<DVec3>,
    /// Vertical field of view in degrees.
    #[arg(long)]
    pub fov: Option<f64>,
    /// dir:x,y,z:r,g,b (towards the light; irradiance) or point:x,y,z:r,g,b (position;
    /// intensity). Repeatable; without any, a default key, fill and rim light; `none` for no
    /// lights at all (only the environment), on its own.
    #[arg(long = "light", allow_hyphen_values = true)]
    pub lights: Vec<String>,
    /// MSAA samples per pixel: 1 or 4.
    #[arg(long, default_value_t = 4)]
    pub samples: u32,
    /// Exposure in EV for PNG output (radiance × 2^EV).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Tone curve for PNG output.
    #[arg(long, default_value = "aces", value_parser = parse_tone_curve)]
    pub tonemap: ToneCurve,
    #[command(flatten)]
    pub environment: EnvironmentArgs,
    /// What fills the pixels the mesh does not cover: env (the sharp environment),
    /// transparent, or a linear colour r,g,b.
    #[arg(long, default_value = "env", value_parser = parse_background)]
    pub background: Background,
    /// How the environment lights the objects (SPEC §4): paper (the paper's multi-layer cube,
    /// the default) or brdf (the integral of the BRDF itself, what a path tracer converges to).
    /// With a scene file it overrides `[render] environment_model`.
    #[arg(long = "env-model", value_parser = parse_env_model)]
    pub env_model: Option<EnvironmentModel>,
    /// Lights seen from everywhere: no shadow rays (SPEC §6). With a scene file it overrides
    /// `[render] shadows`.
    #[arg(long = "no-shadows")]
    pub no_shadows: bool,
    /// No ray tracing at all: every object shaded as if it were alone, the image of a device
    /// without ray queries. With a scene file it overrides `[render] ray_tracing`.
    #[arg(long = "no-ray-tracing")]
    pub no_ray_tracing: bool,
    /// Depth of the light between objects (SPEC §6): 0 (shadows only) to 4; default 1. With a
    /// scene file it overrides `[render] bounces`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_BOUNCES)))]
    pub bounces: Option<u32>,
    /// Rays per shaded point for the light between objects, 1 to 4096; default 8. With a scene
    /// file it overrides `[render] rays`.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_RAYS)))]
    pub rays: Option<u32>,
    /// The light between objects as traced, without the filter of its noise (which is on below
    /// 256 rays). With a scene file it overrides `[render] denoise`.
    #[arg(long = "no-denoise")]
    pub no_denoise: bool,
}

impl RenderArgs {
    /// The `[render]` settings these flags override, as scene paths and values (`--set`).
    pub fn render_overrides(&self) -> Vec<String> {
        let mut sets = Vec::new();
        if let Some(model) = self.env_model {
            sets.push(format!("render.environment_model={}", model.name()));
        }
        if self.no_shadows {
            sets.push("render.shadows=false".into());
        }
        if self.no_ray_tracing {
            sets.push("render.ray_tracing=false".into());
        }
        if let Some(bounces) = self.bounces {
            sets.push(format!("render.bounces={bounces}"));
        }
        if let Some(rays) = self.rays {
            sets.push(format!("render.rays={rays}"));
        }
        if self.no_denoise {
            sets.push("render.denoise=false".into());
        }
        sets
    }

    /// The same overrides applied to a scene built without a file.
    pub fn apply_render_overrides(&self, spec: &mut RenderSpec) {
        if let Some(model) = self.env_model {
            spec.environment_model = model;
        }
        spec.shadows &= !self.no_shadows;
        spec.ray_tracing &= !self.no_ray_tracing;
        spec.bounces = self.bounces.unwrap_or(spec.bounces);
        spec.rays = self.rays.unwrap_or(spec.rays);
        spec.denoise &= !self.no_denoise;
    }
}

/// The environment light (SPEC §4).
#[derive(Debug, Clone, Args)]
pub struct EnvironmentArgs {
    /// Environment map: a .hdr or .exr file (equirectangular), builtin:studio, or none.
    #[arg(long = "env", default_value = "builtin:studio")]
    pub env: String,
    /// Multiplies the environment's radiance.
    #[arg(long = "env-intensity", default_value_t = 1.0)]
    pub intensity: f64,
    /// Turns the environment about +Y, in degrees.
    #[arg(
        long = "env-rotation",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub rotation_deg: f64,
}

#[derive(Debug, Args)]
pub struct PrefilterArgs {
    /// Environment map: a .hdr or .exr file, or builtin:studio.
    pub env: String,
    /// Output directory (created if missing) for layer_<k>.exr, irradiance.exr and preview.png.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    /// Face size of layer 0 (a power of two); default from the source width, clamped to the
    /// largest face the device holds in one buffer.
    #[arg(long = "face-size")]
    pub face_size: Option<u32>,
    /// Number of layers K, including the sharp layer 0.
    #[arg(long, default_value_t = 8)]
    pub layers: u32,
    #[arg(long = "beta-min", default_value_t = 0.02)]
    pub beta_min: f64,
    #[arg(long = "beta-max", default_value_t = 1.0)]
    pub beta_max: f64,
    /// Multiplies the environment's radiance.
    #[arg(long = "env-intensity", default_value_t = 1.0)]
    pub intensity: f64,
    /// Turns the environment about +Y, in degrees.
    #[arg(
        long = "env-rotation",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub rotation_deg: f64,
}

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Measurements: a goniophotometer CSV (.csv, see docs/measurements.md) or a MERL BRDF
    /// (.binary).
    pub data: PathBuf,
    /// The material TOML to write; the Fresnel table goes beside it as <name>.fresnel.csv.
    #[arg(short = 'o', long = "output", value_name = "MATERIAL.toml")]
    pub output: PathBuf,
    /// Also write a report (residuals, tables, PNG plots) into this directory.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,
    /// Split k_d·g(r)·f(N·V), which the data fix only as a product, with this material's
    /// f(1) = a + b and g at the least-lacquer board (a preset name or a material TOML); it also
    /// supplies β_* and the IOR, which reflectance data cannot show. Default: f(1) = g(1) = 1.
    #[arg(long = "normalise-like", value_name = "PRESET|FILE.toml")]
    pub normalise_like: Option<String>,
}

#[derive(Debug, Args)]
#[command(group(clap::ArgGroup::new("source").required(true).args(["material", "preset"])))]
pub struct SynthArgs {
    /// A material TOML to generate data from.
    pub material: Option<PathBuf>,
    /// A preset instead of a file: smooth, rough, smooth-black, smooth-red, rough-black,
    /// rough-red.
    #[arg(long)]
    pub preset: Option<String>,
    /// Output: goniophotometer CSV (.csv) or MERL BRDF (.binary, one board).
    #[arg(short = 'o', long = "output", value_name = "DATA.csv")]
    pub output: PathBuf,
    /// Multiplicative Gaussian noise σ (0.02 = 2 %).
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Seed of the noise; the same seed gives the same file.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Lacquer ratios of the boards, one board each (CSV default 1,2,3,4,5; MERL: the material's
    /// r, or one value).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub ratios: Option<Vec<f64>>,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Print one JSON object (machine, driver, every median, ratio and target verdict) on stdout;
    /// the table then goes to stderr.
    #[arg(long)]
    pub json: bool,
    /// Small sizes and two runs per figure: checks that every stage works (CI smoke run); the
    /// figures are not meaningful.
    #[arg(long)]
    pub quick: bool,
    /// Timed runs per figure, after one warm-up run (default 5, 2 with --quick).
    #[arg(long)]
    pub runs: Option<usize>,
    /// Render benchmark image side in pixels (default 1024).
    #[arg(long = "render-size")]
    pub render_size: Option<u32>,
    /// Prefilter face size (default 512).
    #[arg(long = "face-size")]
    pub face_size: Option<u32>,
    /// Prefilter layer count K (default 8).
    #[arg(long)]
    pub layers: Option<u32>,
    /// Batch benchmark: number of jobs (default 64).
    #[arg(long = "batch-jobs")]
    pub batch_jobs: Option<usize>,
    /// Batch benchmark image side (default 512).
    #[arg(long = "batch-size")]
    pub batch_size: Option<u32>,
    /// Start-up and memory benchmark image side (default 1024).
    #[arg(long = "startup-size")]
    pub startup_size: Option<u32>,
    /// Run only these stages (comma-separated; default all).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub only: Vec<Stage>,
}

#[derive(Debug, Args)]
pub struct MeshArgs {
    // The help lists `BuiltinMesh::ALL`, as `render --mesh` does.
    #[arg(value_name = "BUILTIN", help = builtin_help())]
    pub builtin: String,
    /// Output file: .obj (Wavefront OBJ text) or .glb (glTF 2.0 binary); replaced atomically.
    #[arg(short = 'o', long = "output")]
    pub output: PathBuf,
    #[arg(long, help = segments_help())]
    pub segments: Option<u32>,
}

impl Default for RenderArgs {
    fn default() -> Self {
        // The same defaults clap applies, for `shikki` with no arguments.
        match Cli::try_parse_from(["shikki", "render"]) {
            Ok(Cli {
                command: Some(Command::Render(args)),
            }) => args,
            // Unreachable with the static argument list above; keep a usable value anyway.
            _ => RenderArgs {
                scene: None,
                output: PathBuf::from("shikki.png"),
                size: (1024, 1024),
                material: MaterialArgs {
                    preset: "smooth-red".into(),
                    material: None,
                    set: Vec::new(),
                },
                mesh: "builtin:sphere".into(),
                eye: None,
                target: None,
                fov: None,
                lights: Vec::new(),
                samples: 4,
                exposure: 0.0,
                tonemap: ToneCurve::Aces,
                environment: EnvironmentArgs {
                    env: "builtin:studio".into(),
                    intensity: 1.0,
                    rotation_deg: 0.0,
                },
                background: Background::Environment,
                env_model: None,
                no_shadows: false,
                no_ray_tracing: false,
                bounces: None,
                rays: None,
                no_denoise: false,
            },
        }
    }
}

/// The help of `render --mesh`: every built-in by name.
fn mesh_help() -> String {
    format!("The mesh, one of: {}.", BuiltinMesh::list())
}

fn builtin_help() -> String {
    format!(
        "The built-in mesh to write, one of: {}.",
        BuiltinMesh::list()
    )
}

fn segments_help() -> String {
    format!(
        "Segments around the +Y axis ({}..={}; the other direction keeps the default's \
         proportion), for the built-ins that are tessellated; default: the tessellation \
         `shikki render` draws.",
        BUILTIN_SEGMENTS.start(),
        BUILTIN_SEGMENTS.end()
    )
}

/// `env`, `transparent` or `r,g,b` (linear, finite, ≥ 0).
pub fn parse_background(s: &str) -> std::result::Result<Background, String> {
    match s.trim().to_lowercase().as_str() {
        "env" => Ok(Background::Environment),
        "transparent" => Ok(Background::Transparent),
        _ => {
            let c = parse_vec3("background", s).map_err(|_| {
                format!("background {s:?}: expected env, transparent or a linear colour r,g,b")
            })?;
            if c.min_element() < 0.0 {
                return Err(format!("background {s:?}: colour components must be ≥ 0"));
            }
            Ok(Background::Color([c.x as f32, c.y as f32, c.z as f32]))
        }
    }
}

fn parse_env_model(s: &str) -> std::result::Result<EnvironmentModel, String> {
    EnvironmentModel::from_name(s).ok_or_else(|| {
        format!(
            "environment model {s:?}: must be {}",
            EnvironmentModel::choices()
        )
    })
}

fn parse_tone_curve(s: &str) -> std::result::Result<ToneCurve, String> {
    s.parse::<ToneCurve>().map_err(|e| e.to_string())
}

fn parse_vec3_arg(s: &str) -> std::result::Result<DVec3, String> {
    parse_vec3("vector", s).map_err(|e| e.to_string())
}

/// `WxH` with both in 1..=65535.
pub fn parse_size(s: &str) -> std::result::Result<(u32, u32), String> {
    let err = || {
        format!("size {s:?}: expected WxH with W and H in 1..=65535 (and within the device's image limit), e.g. 1024x768")
    };
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(err)?;
    let w: u32 = w.trim().parse().map_err(|_| err())?;
    let h: u32 = h.trim().parse().map_err(|_| err())?;
    if w == 0 || h == 0 || w > 65535 || h > 65535 {
        return Err(err());
    }
    Ok((w, h))
}

/// `x,y,z` of finite numbers.
pub fn parse_vec3(field: &str, s: &str) -> Result<DVec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(Error::invalid(field, s, "expected three numbers x,y,z"));
    }
    let mut v = [0.0; 3];
    for (slot, part) in v.iter_mut().zip(&parts) {
        let x: f64 = part
            .parse()
            .map_err(|_| Error::invalid(field, s, format!("{part:?} is not a number")))?;
        if !x.is_finite() {
            return Err(Error::invalid(field, s, "components must be finite"));
        }
        *slot = x;
    }
    Ok(DVec3::from_array(v))
}

#[derive(Debug, Args)]
pub struct BatchArgs {
    /// The jobs file: a base scene plus sweeps (docs/scene.md, "Batch").
    pub jobs: PathBuf,
    /// Output directory (created if missing) for the images, manifest.csv and contact_sheet.png.
    #[arg(long, default_value = "batch")]
    pub out: PathBuf,
    /// Render only shard I of N: the jobs whose id % N == I (for Slurm arrays, Kubernetes
    /// indexed Jobs; docs/cluster.md).
    #[arg(long, value_parser = crate::scene::batch::parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Render every job again, even when its output and manifest hash match.
    #[arg(long)]
    pub force: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn render_args(flags: &[&str]) -> RenderArgs {
        let argv = ["shikki", "render"].iter().chain(flags).copied();
        match Cli::try_parse_from(argv) {
            Ok(Cli {
                command: Some(Command::Render(args)),
            }) => args,
            other => panic!("{flags:?} did not parse as render: {other:?}"),
        }
    }

    #[test]
    fn light_between_flags_reach_the_scene_and_its_overrides() {
        let args = render_args(&["--no-denoise", "--no-shadows", "--rays", "16"]);
        let mut spec = RenderSpec::default();
        args.apply_render_overrides(&mut spec);
        assert!(!spec.denoise && !spec.shadows && spec.ray_tracing);
        assert_eq!(spec.rays, 16);
        let sets = args.render_overrides();
        for set in [
            "render.denoise=false",
            "render.shadows=false",
            "render.rays=16",
        ] {
            assert!(sets.iter().any(|s| s == set), "{sets:?} lacks {set}");
        }
        let mut spec = RenderSpec::default();
        render_args(&[]).apply_render_overrides(&mut spec);
        assert_eq!(spec, RenderSpec::default());
    }
}
