//! The integration tests, one crate whose modules mirror `src/`: the tests of `environment/` are
//! under `environment`, those of `raster/mesh_io/` under `raster::mesh_io`. Techniques (corpus,
//! property tests) are sub-modules of the subject they test; `common` is the shared harness
//! (validated GPU context, image statistics, the corpus and property-test helpers).
//! `scene/soak.rs` is its own test target: it measures this process's resident memory, which other
//! tests running beside it would disturb.

mod bench;
mod cli;
mod common;
mod compute;
mod environment;
mod fit;
mod gpu;
mod output;
mod raster;
mod scene;
