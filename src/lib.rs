//! # shikki — lacquer ware (urushi) rendered headless on Vulkan
//!
//! An implementation of Inoue & Ikedo, "Expression for a Lacquer Ware Using Measured Data", as
//! specified in `SPEC.md`. The data flow, one module per stage:
//!
//! ```text
//!  model/  (SPEC §2–3: BRDF, material presets, Fresnel table, CIE spectral path; plain Rust)
//!    │  material → BRDF parameters + Fresnel table
//!    ▼
//!  raster/ (mesh, camera, lights) ──► gpu/ (ash + gpu-allocator; the only Vulkan `unsafe`)
//!    │                                   │  gbuffer.frag → coverage.frag → shade.frag (the lacquer
//!    │                                   │  draw, deferred) / brdf_eval.comp (shaders/, SPIR-V
//!    │                                   │  built by build.rs)
//!    ▼                                   ▼
//!  output/ (readback image → EXR linear | PNG exposure → tone curve → sRGB; atomic writes)
//!
//!  oracle/ (CPU reference: ray-casts the analytic sphere/board with model/; tests compare)
//! ```

pub mod bench;
pub mod cli;
pub mod compute;
pub mod environment;
pub mod error;
pub mod fit;
pub mod gpu;
pub mod model;
pub mod oracle;
pub mod output;
pub mod raster;
pub mod scene;
pub mod text;

pub use error::{Error, Result, Warning};
