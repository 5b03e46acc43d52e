//! The device layer: the Vulkan context, the GPU timer and the structs the shaders share with Rust, byte for byte.
//! Nothing here knows about scenes, estimators or pipelines.

pub mod context;
pub mod octahedral;
pub mod pipeline_request;
pub mod pipeline_store;
pub mod timer;
pub mod types;

pub use context::*;
pub use pipeline_request::PipelineRequest;
pub use pipeline_store::PipelineStore;
