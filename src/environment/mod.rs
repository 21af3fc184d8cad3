//! # environment — light from an HDR environment map (SPEC §4)
//!
//! ```text
//!  load (Radiance .hdr | OpenEXR | builtin:studio) ──► equirect (linear RGB f32)
//!     │  GPU compute (gpu.rs)            │  CPU oracle (oracle.rs), same algorithm, same params
//!     ▼                                  ▼
//!  1. equirect → cube (face N, 4×4 sub-samples per texel, × intensity, rotated about +Y)
//!  2. cube → mip chain (2×2, solid-angle weighted)
//!  3. layer k: brute-force lobe convolution w = exp((c−1)/β_k²) of the mip of the layer's size
//!  4. irradiance: cosine convolution of the 32² mip
//! ```
//! `prepare.rs` is the one way a renderer gets its environment: load → device-clamped parameters
//! → disk cache (`disk_cache.rs`) → GPU prefilter. `definition.rs` is SPEC §4's integral
//! evaluated at full source resolution, for tests only; `brdf_definition.rs` the same for the
//! `brdf` environment model's specular integral.

pub mod brdf_definition;
pub mod brdf_lattice;
pub mod brdf_quadrature;
pub mod bright;
pub mod cube;
pub mod definition;
pub mod disk_cache;
pub mod gpu;
pub mod image;
pub mod layer_pair;
pub mod light_bins;
pub mod load;
pub mod oracle;
pub mod params;
pub mod prepare;
pub mod preview;
pub mod sharp_source;

pub use image::{CubeImage, Equirect, PrefilteredEnvironment};
pub use load::{load_environment, LoadedEnvironment};
pub use oracle::prefilter_cpu;
pub use params::{EnvironmentLight, EnvironmentModel, LayerPlan, PrefilterParams};
pub use prepare::{EnvironmentPreparer, EnvironmentSource};
