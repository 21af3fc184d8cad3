//! [`SceneRenderer`]: the one renderer. The CLI (flags, scene files), batch jobs and the C API
//! all draw their [`Scene`] through it, so they share every step from the environment to the
//! image.
//!
//! Kept across renders: the draw pipelines ([`LacquerRenderer`]), environment preparation
//! ([`EnvironmentPreparer`]: prefilter pipelines, disk cache), each distinct environment's
//! prefiltered cube (keyed by source and light; the prefilter parameters follow from the source
//! and the device), built-in meshes, placed (transformed) meshes and each mesh's device copy
//! ([`GpuMesh`]). Entries keyed by the identity of an `Arc` hold that `Arc`, so the identity
//! cannot be reused while the entry lives. Owns no rendering maths: the draw is `raster::draw`,
//! the environment `environment::prepare`. Prints nothing: warnings wait in
//! [`SceneRenderer::take_warnings`].

use std::path::PathBuf;
use std::sync::Arc;

use super::{parse, EnvironmentSpec, MeshSource, Scene};
use crate::environment::disk_cache::EnvironmentDiskCache;
use crate::environment::gpu::GpuEnvironment;
use crate::environment::params::ViewBlur;
use crate::environment::{
    EnvironmentLight, EnvironmentModel, EnvironmentPreparer, EnvironmentSource,
};
use crate::gpu::GpuContext;
use crate::model::limits;
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::draw::{
    DrawObject, DrawOptions, DrawScene, DrawTimings, LacquerRenderer, RenderSettings,
};
use crate::raster::gpu_mesh::GpuMesh;
use crate::raster::mesh::{BuiltinMesh, Mesh};
use crate::raster::mesh_io::transform_mesh;
use crate::{Error, Result, Warning};

/// More distinct environments than this in one run (a sweep over rotation, say) evicts the oldest:
/// a 1k-face cube with its layers is tens of MB of device memory.
const DEFAULT_CACHED_ENVIRONMENTS: usize = 8;
/// Placed meshes kept (a bowl is ~100k triangles, ~5 MB).
const MAX_CACHED_PLACED_MESHES: usize = 32;
/// Device copies kept: one per placed mesh plus the built-ins and files they were made from.
const MAX_CACHED_GPU_MESHES: usize = 48;

struct CachedEnvironment {
    source: EnvironmentSource,
    light: EnvironmentLight,
    /// The model it was prepared for (its layers: `PrefilterParams::for_model`).
    model: EnvironmentModel,
    prefiltered: GpuEnvironment,
}

/// A mesh moved into the world; `base` pins the identity it is found by.
struct PlacedMesh {
    base: Arc<Mesh>,
    transform_bits: [u64; 16],
    mesh: Arc<Mesh>,
}

/// Renders scenes, reusing pipelines, prefiltered environments and meshes across calls.
pub struct SceneRenderer {
    draw: LacquerRenderer,
    preparer: EnvironmentPreparer,
    environments: Vec<CachedEnvironment>,
    max_environments: usize,
    builtin: Vec<(BuiltinMesh, Arc<Mesh>)>,
    placed: Vec<PlacedMesh>,
    /// Uploaded meshes, oldest first.
    gpu_meshes: Vec<(Arc<Mesh>, GpuMesh)>,
    warnings: Vec<Warning>,
    /// The mesh files whose load notes were given ([`Warning::MeshLoadNotes`], once a file).
    noted_meshes: Vec<PathBuf>,
    /// [`Warning::NoRayQueries`] was given.
    said_no_ray_queries: bool,
    /// [`set_pipelines_on_a_thread`](Self::set_pipelines_on_a_thread).
    pipelines_on_a_thread: bool,
    /// Whether a render built its pipelines on a second thread already: only the first does.
    built_ahead: bool,
    validation_fails_render: bool,
}

impl SceneRenderer {
    /// A renderer whose prefiltered environments are cached on disk beside the context's
    /// pipeline cache (none without one; `environment::disk_cache`). Pipelines are built on
    /// first use.
    pub fn new(gpu: &GpuContext) -> Result<Self> {
        Ok(Self::with_disk_cache(
            EnvironmentDiskCache::beside_pipeline_cache(gpu.pipeline_cache_path()),
        ))
    }

    /// A renderer with the given on-disk environment cache (`None`: always prefilter).
    pub fn with_disk_cache(disk_cache: Option<EnvironmentDiskCache>) -> Self {
        SceneRenderer {
            draw: LacquerRenderer::new(),
            preparer: EnvironmentPreparer::new(disk_cache),
            environments: Vec::new(),
            max_environments: DEFAULT_CACHED_ENVIRONMENTS,
            builtin: Vec::new(),
            placed: Vec::new(),
            gpu_meshes: Vec::new(),
            warnings: Vec::new(),
            noted_meshes: Vec::new(),
            said_no_ray_queries: false,
            pipelines_on_a_thread: false,
            built_ahead: false,
            validation_fails_render: true,
        }
    }

    /// Replaces the on-disk environment cache (`None`: always prefilter).
    pub fn set_disk_cache(&mut self, disk_cache: Option<EnvironmentDiskCache>) {
        self.preparer.set_disk_cache(disk_cache);
    }

    /// How many prefiltered environments stay on the device between renders (at least 1). One
    /// suits a caller that changes maps rarely and wants the memory back at once.
    pub fn set_environment_capacity(&mut self, count: usize) {
        self.max_environments = count.max(1);
        self.evict_environments(self.max_environments);
    }

    /// Whether the first render builds the draw's pipelines on a second thread (a scoped one,
    /// joined before it returns) while the calling thread prepares the environment and meshes:
    /// ~0.2 s off a one-render process on lavapipe (BENCHMARKS.md, "Rays that cannot meet their
    /// own mesh"). Off by default: a process that renders on keeps its resident memory flatter
    /// with every allocation of the driver's compiler on its own threads (the soak test), and a
    /// C caller sees no thread it did not start. `shikki render` turns it on.
    pub fn set_pipelines_on_a_thread(&mut self, on: bool) {
        self.pipelines_on_a_thread = on;
    }

    /// Whether a render that drew validation-layer messages fails with them (the default) or
    /// leaves them in the context for the caller to take (`GpuContext::take_validation_messages`).
    pub fn set_validation_fails_render(&mut self, fails: bool) {
        self.validation_fails_render = fails;
    }

    /// The warnings of the renders so far (oldest first), removed from the renderer: the
    /// caller prints or forwards them.
    pub fn take_warnings(&mut self) -> Vec<Warning> {
        once_each(std::mem::take(&mut self.warnings))
    }

    /// Draws `scene` and returns linear radiance (RGBA, alpha = coverage).
    pub fn render(&mut self, gpu: &GpuContext, scene: &Scene) -> Result<HdrImage> {
        self.render_with(gpu, scene, DrawOptions::default())
            .map(|(image, _)| image)
    }

    /// [`render`](Self::render) with a choice of mesh shader and, with `options.timed`, the GPU
    /// time of each pass (benchmarks).
    pub fn render_with(
        &mut self,
        gpu: &GpuContext,
        scene: &Scene,
        options: DrawOptions,
    ) -> Result<(HdrImage, Option<DrawTimings>)> {
        let mut meshes = Vec::with_capacity(scene.objects.len());
        let mut shading: Vec<(BrdfParams, FresnelTable, ViewBlur)> = Vec::new();
        for (index, object) in scene.objects.iter().enumerate() {
            self.note_mesh_file(&object.mesh)?;
            placement_checked(index, object.transform)?;
            meshes.push(self.placed_mesh(&object.mesh, object.transform)?);
            shading.push((
                object.material.brdf_params()?,
                object.material.fresnel_table()?,
                ViewBlur::of(&object.material),
            ));
        }
        let model = scene.render.environment_model;
        let ray_tracing = scene.render.ray_tracing_on(gpu);
        // The light between objects' control variate reads the bright split in either model.
        let integral = ray_tracing.is_some_and(|rt| rt.bounces > 0);
        let objects: Vec<DrawObject> = meshes
            .iter()
            .zip(&shading)
            .map(|(mesh, (brdf, fresnel, view_blur))| DrawObject {
                mesh,
                brdf,
                fresnel,
                view_blur: *view_blur,
            })
            .collect();
        let draw_scene = |environment| DrawScene {
            objects: &objects,
            camera: &scene.camera,
            lights: &scene.lights,
            environment,
            environment_model: model,
            ray_tracing,
            background: scene.output.background,
        };
        let settings = RenderSettings {
            width: scene.output.width,
            height: scene.output.height,
            samples: scene.output.samples,
        };
        // With `pipelines_on_a_thread`, the first render builds the draw's pipelines on a second
        // thread while this one prepares the environment, the meshes and the materials' albedo
        // (the layers of a map prepared for `model`).
        let layers = match scene.environment {
            EnvironmentSpec::Map { .. } => {
                Some(crate::environment::PrefilterParams::for_model(1, model).layers)
            }
            EnvironmentSpec::None => None,
        };
        // Only the first: what it saves is the start of a one-render process (the CLI's). A
        // thread for every render that builds a pipeline (LLVM's compile, on lavapipe) made the
        // soak test's resident memory climb by tens of MB over 120 renders (glibc's arenas), and
        // later renders find most of their pipelines built. Without the thread the draw builds
        // what it lacks, after the preparation has succeeded.
        let ahead = (self.pipelines_on_a_thread && !self.built_ahead)
            .then(|| {
                self.draw
                    .pipelines_ahead(gpu, &draw_scene(None), (settings.samples, layers))
            })
            .filter(|ahead| !ahead.is_empty());
        self.built_ahead |= ahead.is_some();
        let mut prepare = || {
            self.environment(gpu, &scene.environment, (model, integral))
                .and_then(|env_index| {
                    self.upload_meshes(gpu, &meshes)?;
                    self.draw.albedo_ahead(&draw_scene(None));
                    Ok(env_index)
                })
        };
        let (env_index, built) = match ahead {
            None => (prepare(), None),
            Some(ahead) => std::thread::scope(|scope| {
                let building = scope.spawn(|| ahead.build(gpu));
                let prepared = prepare();
                let built = building.join().unwrap_or_else(|_| {
                    Err(crate::Error::invalid(
                        "pipeline build",
                        "panicked",
                        "report this as a bug",
                    ))
                });
                (prepared, Some(built))
            }),
        };
        let env_index = env_index?;
        if let Some(built) = built {
            self.draw.add_pipelines(built?);
        }
        let gpu_meshes: Vec<&GpuMesh> = meshes
            .iter()
            .filter_map(|mesh| {
                self.gpu_meshes
                    .iter()
                    .find(|(m, _)| Arc::ptr_eq(m, mesh))
                    .map(|(_, g)| g)
            })
            .collect();
        if let (true, false, Some(message)) = (
            scene.render.ray_tracing_asked().is_some(),
            self.said_no_ray_queries,
            gpu.info().ray_query.warning(&gpu.info().name),
        ) {
            self.warnings.push(Warning::NoRayQueries { message });
            self.said_no_ray_queries = true;
        }
        let environment = env_index.map(|k| &self.environments[k].prefiltered);
        let (image, timings) = self.draw.render_meshes(
            gpu,
            &draw_scene(environment),
            &gpu_meshes,
            &settings,
            options,
        )?;
        if self.validation_fails_render {
            gpu.check_validation()?;
        }
        Ok((image, timings))
    }

    /// Uploads each mesh not on the device yet; evicts the oldest entries the scene does not use.
    fn upload_meshes(&mut self, gpu: &GpuContext, meshes: &[Arc<Mesh>]) -> Result<()> {
        for mesh in meshes {
            if !self.gpu_meshes.iter().any(|(m, _)| Arc::ptr_eq(m, mesh)) {
                mesh.validate()?;
                self.gpu_meshes
                    .push((mesh.clone(), GpuMesh::upload(gpu, mesh)?));
            }
        }
        while self.gpu_meshes.len() > MAX_CACHED_GPU_MESHES {
            let Some(unused) = self
                .gpu_meshes
                .iter()
                .position(|(m, _)| !meshes.iter().any(|used| Arc::ptr_eq(m, used)))
            else {
                break;
            };
            self.gpu_meshes.remove(unused);
        }
        Ok(())
    }

    /// Says what the loader changed in a mesh file (once per file and renderer: a batch names the
    /// same file in every job).
    fn note_mesh_file(&mut self, source: &MeshSource) -> Result<()> {
        let path = match source {
            MeshSource::File(path) | MeshSource::Loaded { path, .. } => path,
            MeshSource::Builtin(_) | MeshSource::Inline(_) => return Ok(()),
        };
        if self.noted_meshes.contains(path) {
            return Ok(());
        }
        let notes = match source {
            MeshSource::Loaded { file, .. } => file.notes.clone(),
            _ => parse::cached_file_mesh_noted(path)?.notes,
        };
        if !notes.is_empty() {
            self.warnings.push(Warning::MeshLoadNotes {
                mesh: path.clone(),
                notes: notes.to_vec(),
            });
        }
        self.noted_meshes.push(path.clone());
        Ok(())
    }

    fn base_mesh(&mut self, source: &MeshSource) -> Result<Arc<Mesh>> {
        let MeshSource::Builtin(builtin) = source else {
            return source.load();
        };
        if let Some((_, mesh)) = self.builtin.iter().find(|(b, _)| b == builtin) {
            return Ok(mesh.clone());
        }
        let mesh = source.load()?;
        self.builtin.push((*builtin, mesh.clone()));
        Ok(mesh)
    }

    /// The mesh in world space; identical placements of a mesh are transformed once.
    fn placed_mesh(&mut self, source: &MeshSource, transform: glam::DMat4) -> Result<Arc<Mesh>> {
        let base = self.base_mesh(source)?;
        if transform == glam::DMat4::IDENTITY {
            return Ok(base);
        }
        let transform_bits = transform.to_cols_array().map(f64::to_bits);
        if let Some(hit) = self
            .placed
            .iter()
            .find(|p| Arc::ptr_eq(&p.base, &base) && p.transform_bits == transform_bits)
        {
            return Ok(hit.mesh.clone());
        }
        let mesh = Arc::new(transform_mesh(&base, transform));
        mesh.validate()?;
        if self.placed.len() >= MAX_CACHED_PLACED_MESHES {
            self.placed.remove(0);
        }
        self.placed.push(PlacedMesh {
            base,
            transform_bits,
            mesh: mesh.clone(),
        });
        Ok(mesh)
    }

    /// Index of the prefiltered environment in the cache, prepared on first use; for a draw
    /// that estimates SPEC §6's integral (`integral`), with its bright split
    /// (`EnvironmentPreparer::attach_bright`).
    fn environment(
        &mut self,
        gpu: &GpuContext,
        spec: &EnvironmentSpec,
        (model, integral): (EnvironmentModel, bool),
    ) -> Result<Option<usize>> {
        let EnvironmentSpec::Map { source, light } = spec else {
            return Ok(None);
        };
        let cached = self
            .environments
            .iter()
            .position(|c| c.source.is(source) && c.light.same_bits(light) && c.model == model);
        let k = match cached {
            Some(k) => k,
            None => {
                // Room first: the old cube's memory is free before the new one is made.
                self.evict_environments(self.max_environments - 1);
                let context = (*light, model, integral);
                let prefiltered =
                    (self.preparer).prepare(gpu, source, context, &mut self.warnings)?;
                self.environments.push(CachedEnvironment {
                    source: source.clone(),
                    light: *light,
                    model,
                    prefiltered,
                });
                self.environments.len() - 1
            }
        };
        if integral {
            // Prepared with it above, or earlier by a draw without the integral.
            let env = (source, &self.environments[k].prefiltered);
            (self.preparer).attach_bright(gpu, env, (*light, model), &mut self.warnings)?;
        }
        Ok(Some(k))
    }

    /// Drops the oldest prefiltered environments until at most `keep` remain.
    fn evict_environments(&mut self, keep: usize) {
        let excess = self.environments.len().saturating_sub(keep);
        self.environments.drain(..excess);
    }
}

/// Object `index`'s placement, refused as [`limits::placement_problem`] says, naming the object.
fn placement_checked(index: usize, transform: glam::DMat4) -> Result<()> {
    match limits::placement_problem(&transform) {
        None => Ok(()),
        Some(reason) => Err(Error::invalid(
            format!("object.{index} placement"),
            "its transform",
            reason,
        )),
    }
}

/// `warnings` with each repeat left out, in first-seen order: a map and its bright splits are
/// cached alike, and a cache that could not be written said so three times a render (a probe of
/// the C API, 2026-12-06).
fn once_each(warnings: Vec<Warning>) -> Vec<Warning> {
    let mut kept: Vec<Warning> = Vec::with_capacity(warnings.len());
    for warning in warnings {
        if !kept.contains(&warning) {
            kept.push(warning);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_warning_is_returned_once() {
        let cache = |reason: &str| Warning::CacheNotWritten {
            reason: reason.into(),
        };
        let warnings = vec![cache("a"), cache("b"), cache("a"), cache("a")];
        assert_eq!(once_each(warnings), [cache("a"), cache("b")]);
    }
}
