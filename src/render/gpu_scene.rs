//! GpuScene: a scene's flattened tables (`SceneData`) uploaded as the storage buffers of the binding table,
//! with size checks against the device's limits.

use crate::gpu::{GpuContext, GpuError};
use crate::render::bindings;
use crate::render::scene_data::SceneData;

/// The scene's buffers on a device, bound as group 0 of the render pipeline.
pub struct GpuScene {
    /// The CPU copy (statistics, light counts, environment parameters).
    pub data: SceneData,
    /// Group-0 buffers in binding order (`bindings::SCENE`).
    pub buffers: Vec<wgpu::Buffer>,
}

/// Bytes of each group-0 buffer of `data`, in binding order (`bindings::SCENE`).
pub fn binding_sizes(data: &SceneData) -> [u64; bindings::SCENE.len()] {
    bindings::SCENE.map(|b| (b.bytes)(data).len() as u64)
}

/// Checks every group-0 buffer against a device's storage-buffer binding limit (bytes). The error names the
/// buffer, its size and the limit, so that the user knows what to shrink.
pub fn check_binding_sizes(data: &SceneData, limit: u64) -> Result<(), GpuError> {
    for (b, bytes) in bindings::SCENE.iter().zip(binding_sizes(data)) {
        if bytes > limit {
            return Err(GpuError::SceneTooLarge { buffer: b.binding.label, bytes, limit });
        }
    }
    Ok(())
}

impl GpuScene {
    /// Uploads a flattened scene, refusing (with the buffer, its size and the limit named) anything
    /// larger than the device's storage-buffer binding limit.
    pub fn upload(ctx: &GpuContext, data: SceneData) -> Result<GpuScene, GpuError> {
        check_binding_sizes(&data, ctx.max_storage_binding())?;
        let buffers = bindings::SCENE
            .iter()
            .map(|b| ctx.storage_buffer_bytes(b.binding.name, (b.bytes)(&data), b.binding.element_size))
            .collect();
        Ok(GpuScene { data, buffers })
    }
}
