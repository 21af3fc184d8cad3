//! Environment preparation: the one way an environment map becomes light on the device, whoever
//! asks (CLI flags, a scene file, a batch job, the C API all reach it through
//! `scene::SceneRenderer`):
//!
//! ```text
//!  EnvironmentSource ─► load ─► PrefilterParams for this source, model and device (face
//!    clamped; `PrefilterParams::for_model`) ─► disk cache holds it? ── yes ─► upload
//!                                             └─ no ──► GPU prefilter (× intensity, rotated) ─► store
//! ```
//! For the `brdf` model the map's bright split (`bright.rs`) comes with it: the same steps for the
//! residual map of the same decoded map, beside the lights taken out of it.
//!
//! Owns the order of those steps and the warnings they raise, returned to the caller, never
//! printed. Decoding (`load`), the cache file format (`disk_cache`) and the prefilter itself
//! (`gpu`) stay with their modules.

use std::borrow::Cow;
use std::sync::Arc;

use super::bright::{split_bright, split_bright_rough, BrightLight, BrightSplit};
use super::disk_cache::{CacheKey, EnvironmentDiskCache};
use super::gpu::{model_params, BrightEnvironment, GpuEnvironment, GpuPrefilter};
use super::image::Equirect;
use super::load::{load_environment, LoadedEnvironment};
use super::params::{EnvironmentLight, EnvironmentModel, PrefilterParams};
use super::sharp_source::SharpSource;
use crate::gpu::GpuContext;
use crate::{Result, Warning};

/// Where an environment map comes from.
#[derive(Clone)]
pub enum EnvironmentSource {
    /// `builtin:studio` or the path of a `.hdr`/`.exr` equirectangular map, loaded when prepared.
    Named(String),
    /// A map already in memory (the C API loads when a scene or environment handle is made).
    Loaded(Arc<LoadedEnvironment>),
}

impl EnvironmentSource {
    /// What warnings and errors call the map.
    pub fn name(&self) -> &str {
        match self {
            EnvironmentSource::Named(name) => name,
            EnvironmentSource::Loaded(loaded) => &loaded.source,
        }
    }

    /// Whether both are the same map: the same name, or the same map in memory (by identity; a
    /// file loaded twice is two maps, since it may have changed in between).
    pub fn is(&self, other: &Self) -> bool {
        match (self, other) {
            (EnvironmentSource::Named(a), EnvironmentSource::Named(b)) => a == b,
            (EnvironmentSource::Loaded(a), EnvironmentSource::Loaded(b)) => Arc::ptr_eq(a, b),
            _ => false,
        }
    }

    fn load(&self) -> Result<Cow<'_, LoadedEnvironment>> {
        Ok(match self {
            EnvironmentSource::Named(name) => Cow::Owned(load_environment(name)?),
            EnvironmentSource::Loaded(loaded) => Cow::Borrowed(loaded.as_ref()),
        })
    }
}

impl std::fmt::Debug for EnvironmentSource {
    /// A name as the string itself; a map in memory by its name and size, never its pixels.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EnvironmentSource::Named(name) => std::fmt::Debug::fmt(name, f),
            EnvironmentSource::Loaded(loaded) => f
                .debug_tuple("Loaded")
                .field(&loaded.source)
                .field(&format_args!(
                    "{}x{}",
                    loaded.image.width, loaded.image.height
                ))
                .finish(),
        }
    }
}

impl PartialEq for EnvironmentSource {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (EnvironmentSource::Loaded(a), EnvironmentSource::Loaded(b)) => {
                Arc::ptr_eq(a, b) || a == b
            }
            _ => self.is(other),
        }
    }
}

/// What preparation keeps between maps: the prefilter pipelines (built for the first map the
/// disk cache does not hold, then reused: repeated runs are hazard-free under synchronisation
/// validation), the disk cache, and which maps' replaced pixels were reported already.
pub struct EnvironmentPreparer {
    pipelines: Option<GpuPrefilter>,
    disk_cache: Option<EnvironmentDiskCache>,
    warned: Vec<String>,
}

impl EnvironmentPreparer {
    /// A preparer with the given on-disk cache (`None`: always prefilter).
    pub fn new(disk_cache: Option<EnvironmentDiskCache>) -> Self {
        Self {
            pipelines: None,
            disk_cache,
            warned: Vec::new(),
        }
    }

    pub fn disk_cache(&self) -> Option<&EnvironmentDiskCache> {
        self.disk_cache.as_ref()
    }

    pub fn set_disk_cache(&mut self, disk_cache: Option<EnvironmentDiskCache>) {
        self.disk_cache = disk_cache;
    }

    /// `source` lit by `light`, prefiltered for `gpu` and the environment model that draws with
    /// it (see the module doc); for `brdf`, or with `bright` (a `paper` draw that estimates the
    /// light between objects: [`attach_bright`](Self::attach_bright)), with its bright split
    /// attached, from the same decoded map. Warnings (replaced pixels, once per map; a cache file
    /// ignored or not written) go to `warnings`: none of them stops the render.
    pub fn prepare(
        &mut self,
        gpu: &GpuContext,
        source: &EnvironmentSource,
        (light, model, bright): (EnvironmentLight, EnvironmentModel, bool),
        warnings: &mut Vec<Warning>,
    ) -> Result<GpuEnvironment> {
        let loaded = source.load()?;
        self.note_replaced_pixels(&loaded, warnings);
        light.check_levels(&loaded.image, source.name())?;
        let params = model_params(gpu, loaded.image.width, model);
        let env = self.prepare_image(gpu, &loaded.image, (light, &params), warnings)?;
        if bright || model == EnvironmentModel::Brdf {
            env.attach_bright(self.bright_of(gpu, &loaded.image, (light, model), warnings)?)?;
        }
        Ok(env)
    }

    /// Attaches to `env` (`source` prepared for `model`) its bright split, prefiltered with the
    /// same layers, unless it has one: a ray-traced `paper` draw reads it through the `brdf`
    /// model's quadrature for the light between objects' control variate (lacquer_shade.glsl's
    /// `integral_environment`). A `brdf` environment has one already, and so has one prepared
    /// with `bright`; this is for one prepared earlier without (the map is decoded again).
    pub fn attach_bright(
        &mut self,
        gpu: &GpuContext,
        (source, env): (&EnvironmentSource, &GpuEnvironment),
        (light, model): (EnvironmentLight, EnvironmentModel),
        warnings: &mut Vec<Warning>,
    ) -> Result<()> {
        if env.has_bright() {
            return Ok(());
        }
        let loaded = source.load()?;
        env.attach_bright(self.bright_of(gpu, &loaded.image, (light, model), warnings)?)
    }

    /// The `brdf` model's sources for `source` (bright.rs): the map's bright parts as lights in
    /// the world, and its residual prefiltered as [`prepare`](Self::prepare) does a map for that
    /// model (the disk cache keeps it under the residual's own key).
    pub fn prepare_bright(
        &mut self,
        gpu: &GpuContext,
        source: &EnvironmentSource,
        light: EnvironmentLight,
        warnings: &mut Vec<Warning>,
    ) -> Result<BrightEnvironment> {
        let loaded = source.load()?;
        self.bright_of(
            gpu,
            &loaded.image,
            (light, EnvironmentModel::Brdf),
            warnings,
        )
    }

    /// The bright splits of `image` with their residuals prefiltered as `model` prefilters a map.
    fn bright_of(
        &mut self,
        gpu: &GpuContext,
        image: &Equirect,
        (light, model): (EnvironmentLight, EnvironmentModel),
        warnings: &mut Vec<Warning>,
    ) -> Result<BrightEnvironment> {
        let params = model_params(gpu, image.width, model);
        let (first, rough) = (split_bright(image), split_bright_rough(image));
        // The lattice's sharp reads of both residuals' pixels, where the map is narrow enough.
        let sharp = SharpSource::new(&first.residual, light)
            .zip(SharpSource::new(&rough.residual, light))
            .map(|(a, b)| [a, b]);
        let mut part = |split: BrightSplit| -> Result<(GpuEnvironment, Vec<BrightLight>, f64)> {
            let lights = split.lights_in_world(light);
            let residual = self.prepare_image(gpu, &split.residual, (light, &params), warnings)?;
            Ok((residual, lights, split.block_angle))
        };
        let (residual, lights, _) = part(first)?;
        BrightEnvironment::new((residual, lights), part(rough)?, sharp)
    }

    fn prepare_image(
        &mut self,
        gpu: &GpuContext,
        image: &Equirect,
        (light, params): (EnvironmentLight, &PrefilterParams),
        warnings: &mut Vec<Warning>,
    ) -> Result<GpuEnvironment> {
        let key = self
            .disk_cache
            .as_ref()
            .map(|_| CacheKey::new(image, params, light));
        if let Some(key) = &key {
            if let Some(env) = self.cached(gpu, key, params, warnings) {
                return Ok(env);
            }
        }
        let env = self.prefilter(gpu, image, params, light)?;
        if let (Some(cache), Some(key)) = (&self.disk_cache, &key) {
            let stored = env.read_back(gpu).and_then(|host| cache.store(key, &host));
            if let Err(e) = stored {
                warnings.push(Warning::CacheNotWritten {
                    reason: e.to_string(),
                });
            }
        }
        Ok(env)
    }

    /// What a map's loading found (replaced pixels; a shape that is not 2:1), once per map.
    fn note_replaced_pixels(&mut self, loaded: &LoadedEnvironment, warnings: &mut Vec<Warning>) {
        if self.warned.contains(&loaded.source) {
            return;
        }
        if loaded.replaced_pixels > 0 {
            warnings.push(Warning::ReplacedPixels {
                environment: loaded.source.clone(),
                count: loaded.replaced_pixels,
            });
        }
        let (width, height) = (loaded.image.width, loaded.image.height);
        if u64::from(width) != 2 * u64::from(height) {
            warnings.push(Warning::NotEquirectangular {
                environment: loaded.source.clone(),
                width,
                height,
            });
        }
        self.warned.push(loaded.source.clone());
    }

    /// The disk cache's copy, on the device; a file that cannot be read or uploaded costs a
    /// warning, never the render.
    fn cached(
        &self,
        gpu: &GpuContext,
        key: &CacheKey,
        params: &PrefilterParams,
        warnings: &mut Vec<Warning>,
    ) -> Option<GpuEnvironment> {
        let cache = self.disk_cache.as_ref()?;
        let host = cache.load(key, params, warnings)?;
        match GpuEnvironment::upload(gpu, &host) {
            Ok(env) => Some(env),
            Err(e) => {
                warnings.push(Warning::CacheFileNotUploaded {
                    path: cache.path(key),
                    reason: e.to_string(),
                });
                None
            }
        }
    }

    fn prefilter(
        &mut self,
        gpu: &GpuContext,
        image: &Equirect,
        params: &PrefilterParams,
        light: EnvironmentLight,
    ) -> Result<GpuEnvironment> {
        let pipelines = match &mut self.pipelines {
            Some(pipelines) => pipelines,
            empty => empty.insert(GpuPrefilter::new(gpu)?),
        };
        pipelines.run(gpu, image, params, light)
    }
}
