//! The laboratory: what measures and shows estimators — benchmarks, references, comparisons, the lecture's figures
//! and the stress cases.

pub mod bench;
pub use error::LabError;
pub mod compare;
pub mod error;
pub mod figure;
pub mod reference;
pub mod sampler_figure;
pub mod stress;
pub mod suite_inputs;
