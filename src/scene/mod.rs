//! Scenes: what one image shows (camera, lacquered objects, lights, environment, output settings),
//! read from TOML files (docs/scene.md), overridden by `--set`/sweeps, rendered by
//! [`SceneRenderer`] and multiplied into many images by [`batch`].
//!
//! A [`Scene`] is the one description every entry point builds — the CLI from its flags or a
//! scene file, a batch from each job, the C API from its calls — and [`SceneRenderer`] is the one
//! renderer they all draw it with.
//!
//! Owns the scene schema and its errors; the model (`model/`), meshes (`raster/mesh*`), the
//! environment prefilter and the draw are used, never changed, here.

pub mod batch;
pub mod doc;
pub mod parse;
pub mod render;
mod sections;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{DMat4, DVec3};

pub use crate::environment::{EnvironmentLight, EnvironmentModel, EnvironmentSource};
use crate::model::LacquerMaterial;
pub use crate::output::ToneCurve;
pub use crate::raster::draw::Background;
use crate::raster::draw::RayTracing;
pub use crate::raster::{BuiltinMesh, Camera, Light, Mesh};
use crate::Result;
pub use doc::{Node, Origin};
pub use parse::{scene_from_document, SceneDocument};
pub use render::SceneRenderer;

/// Everything one image shows and how it is written.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The camera after `orbit_deg` was applied.
    pub camera: Camera,
    pub objects: Vec<SceneObject>,
    pub lights: Vec<Light>,
    pub environment: EnvironmentSpec,
    pub render: RenderSpec,
    pub output: OutputSpec,
}

/// One lacquered object: its mesh placed in the world by `transform`, and its material.
#[derive(Clone, Debug)]
pub struct SceneObject {
    pub mesh: MeshSource,
    pub transform: DMat4,
    pub material: LacquerMaterial,
}

/// Where an object's mesh comes from.
#[derive(Clone, Debug)]
pub enum MeshSource {
    Builtin(BuiltinMesh),
    /// An OBJ, glTF or GLB file (already resolved against the scene file's directory).
    File(PathBuf),
    /// A mesh file loaded ahead of the render (the C API's `shikki_mesh_load`, and the files of
    /// the scenes it loads), with what its loader changed: a render reports them as it does a
    /// file's (`Warning::MeshLoadNotes`).
    Loaded {
        path: PathBuf,
        file: parse::FileMesh,
    },
    /// A mesh handed over in memory (the C API).
    Inline(Arc<Mesh>),
}

impl MeshSource {
    /// The mesh in its own frame: a builtin made anew, a file from the process's file cache
    /// (`parse::cached_file_mesh`), an inline mesh shared.
    pub fn load(&self) -> Result<Arc<Mesh>> {
        Ok(match self {
            MeshSource::Builtin(builtin) => Arc::new(builtin.mesh()),
            MeshSource::File(path) => parse::cached_file_mesh(path)?,
            MeshSource::Loaded { file, .. } => file.mesh.clone(),
            MeshSource::Inline(mesh) => mesh.clone(),
        })
    }
}

/// The environment light (SPEC §4).
#[derive(Clone, PartialEq)]
pub enum EnvironmentSpec {
    None,
    /// A map (`builtin:studio`, a `.hdr`/`.exr` path, or one in memory) and how it lights the
    /// world.
    Map {
        source: EnvironmentSource,
        light: EnvironmentLight,
    },
}

impl EnvironmentSpec {
    /// A map named by `builtin:studio` or a path, as stored and unrotated.
    pub fn named(source: impl Into<String>) -> Self {
        EnvironmentSpec::Map {
            source: EnvironmentSource::Named(source.into()),
            light: EnvironmentLight::default(),
        }
    }
}

impl std::fmt::Debug for EnvironmentSpec {
    /// Flat: `Map { source, intensity, rotation_deg }`. A batch job's scene hash reads this text
    /// (`batch::scene_hash`), so it names values, not how the type groups them.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EnvironmentSpec::None => f.write_str("None"),
            EnvironmentSpec::Map { source, light } => f
                .debug_struct("Map")
                .field("source", source)
                .field("intensity", &light.intensity)
                .field("rotation_deg", &light.rotation_deg)
                .finish(),
        }
    }
}

impl Default for Scene {
    /// Nothing in it: no objects, no lights, no environment, the default camera and output.
    fn default() -> Self {
        Scene {
            camera: Camera::default(),
            objects: Vec::new(),
            lights: Vec::new(),
            environment: EnvironmentSpec::None,
            render: RenderSpec::default(),
            output: OutputSpec::default(),
        }
    }
}

/// How light is computed (`[render]`): SPEC §4's environment model and SPEC §6's light between
/// objects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSpec {
    pub environment_model: EnvironmentModel,
    /// Lights with visibility (shadow rays), where ray tracing is on.
    pub shadows: bool,
    /// Ray queries for light between objects, where the device has them (`false`: every object
    /// shaded as if alone, the image of a device without ray queries).
    pub ray_tracing: bool,
    /// Depth of SPEC §6's integral, 0..=MAX_BOUNCES (0: shadows only).
    pub bounces: u32,
    /// Rays per shaded point for the integral, 1..=MAX_RAYS.
    pub rays: u32,
    /// Seeds the integral's sample sequence.
    pub seed: u32,
    /// Filter the integral's estimate (`raster::draw::denoise`) where `rays` is low enough.
    pub denoise: bool,
}

/// Rays per shaded point unless a scene says otherwise (BENCHMARKS.md, "Light between objects").
pub const DEFAULT_RAYS: u32 = 8;

impl Default for RenderSpec {
    fn default() -> Self {
        Self {
            environment_model: EnvironmentModel::default(),
            shadows: true,
            ray_tracing: true,
            bounces: 1,
            rays: DEFAULT_RAYS,
            seed: 0,
            denoise: true,
        }
    }
}

impl RenderSpec {
    /// What a draw on `gpu` traces: `None` with ray tracing off, on a device without ray queries
    /// (then the image is that of every object alone, and the renderer warns once), or when
    /// nothing would be traced.
    pub fn ray_tracing_on(&self, gpu: &crate::gpu::GpuContext) -> Option<RayTracing> {
        self.ray_tracing_asked()
            .filter(|_| gpu.info().ray_query.is_enabled())
    }

    /// What the scene asks to trace, whatever the device: `None` with ray tracing off or
    /// nothing to trace.
    pub fn ray_tracing_asked(&self) -> Option<RayTracing> {
        let rt = RayTracing {
            shadows: self.shadows,
            bounces: self.bounces,
            rays: self.rays,
            seed: self.seed,
            denoise: self.denoise,
        };
        (self.ray_tracing && rt.traces()).then_some(rt)
    }
}

/// Image size, anti-aliasing and the PNG conversion (SPEC §1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputSpec {
    pub width: u32,
    pub height: u32,
    /// MSAA samples per pixel: 1 or 4.
    pub samples: u32,
    pub exposure_ev: f32,
    pub tone_curve: ToneCurve,
    pub background: Background,
}

impl Default for OutputSpec {
    fn default() -> Self {
        OutputSpec {
            width: 1024,
            height: 1024,
            samples: 4,
            exposure_ev: 0.0,
            tone_curve: ToneCurve::Aces,
            background: Background::Environment,
        }
    }
}

/// Parses scene TOML; `source_name` names it in errors, relative paths resolve against
/// `base_dir`.
pub fn parse_scene_str(text: &str, source_name: &str, base_dir: &Path) -> Result<Scene> {
    SceneDocument::parse(text, source_name, base_dir)?.build()
}

/// Reads and parses a scene file.
pub fn load_scene_file(path: &Path) -> Result<Scene> {
    SceneDocument::load(path)?.build()
}

/// The TOML of [`default_scene`]: the same text is shipped as `examples/default.toml`.
pub const DEFAULT_SCENE_TOML: &str = include_str!("../../examples/default.toml");

/// A red (shu) and a black (kuro) smooth lacquer bowl side by side on a black lacquer tray, lit
/// by the built-in studio environment, which also fills the background: the picture on top of
/// README.md.
pub fn default_scene() -> Scene {
    match parse_scene_str(DEFAULT_SCENE_TOML, "examples/default.toml", Path::new(".")) {
        Ok(scene) => scene,
        // The embedded text is checked by a test; keep a usable scene regardless.
        Err(_) => fallback_default_scene(),
    }
}

fn fallback_default_scene() -> Scene {
    let bowl = |x: f64, preset: &str| SceneObject {
        mesh: MeshSource::Builtin(BuiltinMesh::Bowl),
        transform: DMat4::from_translation(DVec3::new(x, 0.0, 0.0)),
        material: LacquerMaterial::preset(preset).unwrap_or_default(),
    };
    Scene {
        camera: Camera::default(),
        objects: vec![bowl(-1.1, "smooth-red"), bowl(1.1, "smooth-black")],
        lights: crate::raster::default_lights(),
        environment: EnvironmentSpec::named(crate::environment::load::BUILTIN_STUDIO),
        render: RenderSpec::default(),
        output: OutputSpec::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_scene_is_a_red_and_a_black_bowl_on_the_studio() {
        let scene = parse_scene_str(DEFAULT_SCENE_TOML, "default.toml", Path::new(".")).unwrap();
        assert_eq!(scene.objects.len(), 3, "two bowls and the tray");
        let red = LacquerMaterial::preset("smooth-red").unwrap().albedo;
        let black = LacquerMaterial::preset("smooth-black").unwrap().albedo;
        let albedos: Vec<[f64; 3]> = scene.objects.iter().map(|o| o.material.albedo).collect();
        assert!(albedos.contains(&red) && albedos.contains(&black));
        for object in &scene.objects[..2] {
            assert!(matches!(
                object.mesh,
                MeshSource::Builtin(BuiltinMesh::Bowl)
            ));
        }
        assert!(matches!(
            &scene.environment,
            EnvironmentSpec::Map { source, .. } if source.name() == "builtin:studio"
        ));
        assert_eq!(scene.output.background, Background::Environment);
    }

    /// Names in any case; a built-in or a preset by its name alone (a probe found `material =
    /// "smooth-red"` read as a missing file, `Paper` refused while `ACES` was taken).
    #[test]
    fn names_are_read_in_any_case_and_alone() {
        let text = "environment = \"Builtin:Studio\"\n\
                    light = [{ kind = \"Point\", position = [0, 2, 2], intensity = 3 }]\n\
                    [[object]]\nmesh = \"Sphere\"\nmaterial = \"Rough-Red\"\n\
                    [[object]]\nmesh = \"BUILTIN:board\"\n\
                    material = { preset = \"SMOOTH\", r = 2 }\n\
                    [render]\nenvironment_model = \"BRDF\"\n\
                    [output]\ntonemap = \"Reinhard\"\nformat = \"EXR\"\n\
                    background = \"Transparent\"\n";
        let mut document = SceneDocument::parse(text, "s.toml", Path::new(".")).unwrap();
        // An override of a preset named alone starts from that preset.
        document
            .set("object.0.material.r=2", Path::new("."))
            .unwrap();
        let scene = document.build().unwrap();
        let mut rough_red = LacquerMaterial::preset("rough-red").unwrap();
        rough_red.lacquer_ratio = 2.0;
        assert_eq!(scene.objects[0].material, rough_red);
        assert!(matches!(
            scene.objects[0].mesh,
            MeshSource::Builtin(BuiltinMesh::Sphere)
        ));
        assert!(matches!(
            scene.objects[1].mesh,
            MeshSource::Builtin(BuiltinMesh::Board)
        ));
        assert_eq!(
            scene.objects[1].material.beckmann_m,
            LacquerMaterial::preset("smooth").unwrap().beckmann_m
        );
        assert!(matches!(scene.lights[0], Light::Point { .. }));
        assert!(matches!(
            &scene.environment,
            EnvironmentSpec::Map { source, .. } if source.name() == "builtin:studio"
        ));
        assert_eq!(scene.render.environment_model, EnvironmentModel::Brdf);
        assert_eq!(scene.output.background, Background::Transparent);
        assert_eq!(scene.output.tone_curve, ToneCurve::Reinhard);

        // A sweep of the preset replaces a preset named alone (it was "not both", a probe).
        let mut document = SceneDocument::parse(text, "s.toml", Path::new(".")).unwrap();
        document
            .set("object.0.material.preset=smooth-black", Path::new("."))
            .unwrap();
        let scene = document.build().unwrap();
        let smooth_black = LacquerMaterial::preset("smooth-black").unwrap();
        assert_eq!(scene.objects[0].material, smooth_black);
        // Over a material file it is a conflict, named at the override that made it.
        let text = "[[object]]\nmesh = \"sphere\"\nmaterial = \"red.toml\"\n";
        let mut document = SceneDocument::parse(text, "s.toml", Path::new(".")).unwrap();
        document
            .set("object.0.material.preset=smooth-black", Path::new("."))
            .unwrap();
        let message = document.build().unwrap_err().to_string();
        assert!(
            message.contains("--set object.0.material.preset") && message.contains("not both"),
            "{message}"
        );
    }
}
