//! The CPU reference renderer (the "oracle") that GPU images are tested against.
//!
//! It ray-casts the exact analytic shapes with the lacquer model of `model/` and the camera and
//! lights of `raster/`. It owns no model maths of its own and must never call the GPU.

pub mod bvh;
pub mod light_between;
pub mod map_sampler;
pub mod path_scene;
pub mod path_tracer;
pub mod raycast;
pub mod shadows;
pub mod visible_normals;

pub use bvh::{BvhHit, SceneBvh};
pub use raycast::{intersect, render, shade, AnalyticShape, OracleScene, SurfaceHit};
