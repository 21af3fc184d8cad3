//! The SPIR-V of every shader in `shaders/`, compiled by build.rs and embedded in the binary.
include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
