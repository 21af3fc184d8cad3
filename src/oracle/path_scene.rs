//! A scene as the brute-force path tracer takes it: the objects' meshes placed in the world, their
//! materials and the map, loaded from a [`Scene`] the way the renderer reads it, and owned, so
//! that a scene file (examples/path_trace.rs) or a parsed scene (tests) renders with one call.

use glam::DMat4;

use super::path_tracer::{self, PathEnvironment, PathImage, PathScene};
use super::shadows::TracedObject;
use crate::environment::{load_environment, EnvironmentLight, EnvironmentSource, Equirect};
use crate::model::{BrdfParams, FresnelTable};
use crate::raster::mesh_io::transform_mesh;
use crate::raster::{Camera, Light, Mesh};
use crate::scene::{EnvironmentSpec, Scene};
use crate::Result;

/// What [`path_tracer::render`] needs of a scene, owned.
pub struct OwnedPathScene {
    meshes: Vec<Mesh>,
    materials: Vec<(BrdfParams, FresnelTable)>,
    camera: Camera,
    lights: Vec<Light>,
    /// The map and how it lights the world; `None` for `environment = "none"` (black).
    map: Option<(Equirect, EnvironmentLight)>,
}

impl OwnedPathScene {
    /// Loads every mesh and the map of `scene` (errors as the renderer's: file, place, fix).
    pub fn of(scene: &Scene) -> Result<Self> {
        let mut meshes = Vec::with_capacity(scene.objects.len());
        let mut materials = Vec::with_capacity(scene.objects.len());
        for object in &scene.objects {
            let base = object.mesh.load()?;
            meshes.push(match object.transform == DMat4::IDENTITY {
                true => (*base).clone(),
                false => transform_mesh(&base, object.transform),
            });
            materials.push((
                object.material.brdf_params()?,
                object.material.fresnel_table()?,
            ));
        }
        let map = match &scene.environment {
            EnvironmentSpec::None => None,
            EnvironmentSpec::Map { source, light } => {
                let image = match source {
                    EnvironmentSource::Named(name) => load_environment(name)?.image,
                    EnvironmentSource::Loaded(loaded) => loaded.image.clone(),
                };
                Some((image, *light))
            }
        };
        Ok(Self {
            meshes,
            materials,
            camera: scene.camera.clone(),
            lights: scene.lights.clone(),
            map,
        })
    }

    /// [`path_tracer::render`] of the scene at `size` with `bounces` sampled reflections and
    /// `paths` paths per pixel.
    pub fn render(&self, size: (u32, u32), bounces: u32, paths: u32, seed: u64) -> PathImage {
        let objects: Vec<TracedObject> = self
            .meshes
            .iter()
            .zip(&self.materials)
            .map(|(mesh, (brdf, fresnel))| TracedObject {
                mesh,
                brdf,
                fresnel,
            })
            .collect();
        let environment = match &self.map {
            None => PathEnvironment::Constant([0.0; 3]),
            Some((image, light)) => PathEnvironment::Map {
                image,
                light: *light,
            },
        };
        let scene = PathScene {
            objects: &objects,
            camera: &self.camera,
            lights: &self.lights,
            environment,
        };
        path_tracer::render(&scene, size, bounces, paths, seed)
    }
}
