//! [`SceneRenderer`]: draws a [`Scene`] on the GPU, keeping what jobs of a batch share.
//!
//! Kept across renders: the draw pipelines ([`LacquerRenderer`]), the prefilter pipelines, each
//! distinct environment's prefiltered cube (keyed by source, intensity, rotation and prefilter
//! parameters), built-in meshes, placed (transformed) meshes and each mesh's device copy
//! ([`GpuMesh`], keyed by the identity of its `Arc<Mesh>`, which the cache holds so the identity
//! cannot be reused). Owns no rendering maths: the draw is `raster::draw`, the prefilter
//! `environment::gpu`.

use std::collections::HashMap;
use std::sync::Arc;

use super::parse::cached_file_mesh;
use super::{EnvironmentSpec, MeshSource, Scene};
use crate::environment::disk_cache::{prefilter_cached, EnvironmentDiskCache};
use crate::environment::gpu::{default_params, GpuEnvironment, GpuPrefilter};
use crate::environment::load::load_environment;
use crate::environment::params::ViewBlur;
use crate::gpu::GpuContext;
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::draw::{
    DrawObject, DrawOptions, DrawScene, DrawTimings, LacquerRenderer, RenderSettings,
};
use crate::raster::gpu_mesh::GpuMesh;
use crate::raster::mesh::{BuiltinMesh, Mesh};
use crate::raster::mesh_io::transform_mesh;
use crate::Result;

/// More distinct environments than this in one run (a sweep over rotation, say) evicts the oldest:
/// a 1k-face cube with its layers is tens of MB of device memory.
const MAX_CACHED_ENVIRONMENTS: usize = 8;
/// Placed meshes kept (a bowl is ~100k triangles, ~5 MB).
const MAX_CACHED_PLACED_MESHES: usize = 32;
/// Device copies kept: one per placed mesh plus the built-ins and files they were made from.
const MAX_CACHED_GPU_MESHES: usize = 48;

/// Renders scenes, reusing pipelines, prefiltered environments and meshes across calls.
pub struct SceneRenderer {
    draw: LacquerRenderer,
    /// Built on the first environment the disk cache does not hold.
    prefilter: Option<GpuPrefilter>,
    disk_cache: Option<EnvironmentDiskCache>,
    environments: Vec<(String, GpuEnvironment)>,
    builtin: HashMap<&'static str, Arc<Mesh>>,
    placed: Vec<(String, Arc<Mesh>)>,
    /// Uploaded meshes, oldest first; the `Arc` pins the identity the entry is found by.
    gpu_meshes: Vec<(Arc<Mesh>, GpuMesh)>,
    /// Environment warnings (replaced pixels) already printed, so a batch says each once.
    warned: Vec<String>,
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
            prefilter: None,
            disk_cache,
            environments: Vec::new(),
            builtin: HashMap::new(),
            placed: Vec::new(),
            gpu_meshes: Vec::new(),
            warned: Vec::new(),
        }
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
        for object in &scene.objects {
            meshes.push(self.placed_mesh(&object.mesh, object.transform)?);
            shading.push((
                object.material.brdf_params()?,
                object.material.fresnel_table()?,
                ViewBlur::of(&object.material),
            ));
        }
        let env_index = self.environment(gpu, &scene.environment)?;
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
        self.upload_meshes(gpu, &meshes)?;
        let gpu_meshes: Vec<&GpuMesh> = meshes
            .iter()
            .filter_map(|mesh| {
                self.gpu_meshes
                    .iter()
                    .find(|(m, _)| Arc::ptr_eq(m, mesh))
                    .map(|(_, g)| g)
            })
            .collect();
        let environment = env_index.map(|k| &self.environments[k].1);
        let (image, timings) = self.draw.render_meshes(
            gpu,
            &DrawScene {
                objects: &objects,
                camera: &scene.camera,
                lights: &scene.lights,
                environment,
                background: scene.output.background,
            },
            &gpu_meshes,
            &RenderSettings {
                width: scene.output.width,
                height: scene.output.height,
                samples: scene.output.samples,
            },
            options,
        )?;
        gpu.check_validation()?;
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

    fn base_mesh(&mut self, source: &MeshSource) -> Result<(String, Arc<Mesh>)> {
        Ok(match source {
            MeshSource::Builtin(builtin) => {
                let name = builtin_name(*builtin);
                let mesh = self
                    .builtin
                    .entry(name)
                    .or_insert_with(|| Arc::new(builtin.mesh()))
                    .clone();
                (name.to_string(), mesh)
            }
            MeshSource::File(path) => (format!("file:{}", path.display()), cached_file_mesh(path)?),
            MeshSource::Inline(mesh) => (format!("inline:{:p}", Arc::as_ptr(mesh)), mesh.clone()),
        })
    }

    /// The mesh in world space; identical placements of a mesh are transformed once.
    fn placed_mesh(&mut self, source: &MeshSource, transform: glam::DMat4) -> Result<Arc<Mesh>> {
        let (name, base) = self.base_mesh(source)?;
        if transform == glam::DMat4::IDENTITY {
            return Ok(base);
        }
        let bits: Vec<u64> = transform
            .to_cols_array()
            .iter()
            .map(|x| x.to_bits())
            .collect();
        let key = format!("{name}|{bits:x?}");
        if let Some((_, mesh)) = self.placed.iter().find(|(k, _)| *k == key) {
            return Ok(mesh.clone());
        }
        let mesh = Arc::new(transform_mesh(&base, transform));
        mesh.validate()?;
        if self.placed.len() >= MAX_CACHED_PLACED_MESHES {
            self.placed.remove(0);
        }
        self.placed.push((key, mesh.clone()));
        Ok(mesh)
    }

    /// Index of the prefiltered environment in the cache, prefiltering it on first use.
    fn environment(&mut self, gpu: &GpuContext, spec: &EnvironmentSpec) -> Result<Option<usize>> {
        let EnvironmentSpec::Map {
            source,
            intensity,
            rotation_deg,
        } = spec
        else {
            return Ok(None);
        };
        // The prefilter parameters are a function of the source's width, so the source names
        // them too.
        let key = format!("{source}|{intensity:?}|{rotation_deg:?}");
        if let Some(k) = self.environments.iter().position(|(k, _)| *k == key) {
            return Ok(Some(k));
        }
        let loaded = load_environment(source)?;
        let params = default_params(gpu, loaded.image.width);
        if loaded.replaced_pixels > 0 && !self.warned.contains(source) {
            eprintln!(
                "warning: {source}: {} pixel value(s) were NaN, infinite or negative and were \
                 replaced by 0",
                loaded.replaced_pixels
            );
            self.warned.push(source.clone());
        }
        // One prefilter (its pipelines) for the whole run; repeated runs are hazard-free under
        // synchronisation validation (tests/gpu_environment.rs, one_prefilter_runs_many_times…).
        let env = prefilter_cached(
            gpu,
            &mut self.prefilter,
            self.disk_cache.as_ref(),
            &loaded.image,
            &params,
            *intensity,
            *rotation_deg,
        )?;
        if self.environments.len() >= MAX_CACHED_ENVIRONMENTS {
            self.environments.remove(0);
        }
        self.environments.push((key, env));
        Ok(Some(self.environments.len() - 1))
    }
}

fn builtin_name(mesh: BuiltinMesh) -> &'static str {
    match mesh {
        BuiltinMesh::Sphere => "builtin:sphere",
        BuiltinMesh::Board => "builtin:board",
        BuiltinMesh::Bowl => "builtin:bowl",
        BuiltinMesh::Plate => "builtin:plate",
    }
}
