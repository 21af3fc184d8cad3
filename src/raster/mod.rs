//! Rasterisation inputs shared by the GPU draw and the CPU oracle: the camera (SPEC §1), the
//! punctual lights (SPEC §4) and the built-in meshes (SPEC §5), plus the GPU draw itself.
//!
//! camera, lights and mesh are plain Rust with no Vulkan; `draw` is the only part that records
//! GPU work. Nothing here knows the lacquer model (that is `model/`).

pub mod camera;
pub mod draw;
pub mod lathe;
pub mod lights;
pub mod mesh;
pub mod mesh_io;
pub mod self_hits;

pub use camera::Camera;
pub use draw::gpu_mesh;
pub use draw::GpuMesh;
pub use lights::{default_lights, Light, MAX_LIGHTS};
pub use mesh::{BuiltinMesh, Mesh};
pub use self_hits::SelfHits;
