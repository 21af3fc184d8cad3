//! The lacquer model of SPEC §2–3 in plain Rust (f64): the BRDF, the material parameters and
//! presets, the Fresnel table and the spectral path with its CIE tables.
//!
//! This module is the single source of truth that the CPU oracle and the GPU shaders are checked
//! against. It has no Vulkan and no rendering, and no I/O of its own: a material file, and the
//! Fresnel CSV a material names, are read through [`crate::text::read_text_file`]. It must not
//! depend on `gpu/`, `raster/` or `oracle/`.

pub mod brdf;
pub mod cie;
pub mod fresnel;
pub mod limits;
pub mod material;
pub mod material_file;
pub mod spectral;

pub use brdf::{lacquer_brdf, lacquer_specular, BrdfParams};
pub use fresnel::FresnelTable;
pub use material::{LacquerMaterial, MATERIAL_KEYS, PRESET_NAMES};
