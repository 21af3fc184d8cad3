//! GPU compute passes that are not part of drawing: the BRDF evaluator (`brdf_eval`), used by
//! `shikki brdf --backend gpu` and by the tests that hold the GLSL BRDF against the CPU model,
//! and the `brdf` environment model's evaluator (`brdf_environment_eval`), for its tests.

pub mod brdf_environment_eval;
pub mod brdf_eval;

pub use brdf_eval::BrdfEvaluator;
