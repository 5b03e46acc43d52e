//! What the tests use to prove the GPU right: chi-square tests of sampling routines, probe kernels that run WGSL
//! functions on the device (alone, on the geometry, or on a whole bound scene), and image error metrics.

pub mod chi2;
pub mod metrics;
pub mod probe;
pub mod scene_probe;
