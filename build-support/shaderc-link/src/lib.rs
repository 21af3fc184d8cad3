//! Build-time only: `shaderc`, linked against Debian's static archives (see build.rs).
pub use shaderc;
