//! What a render pipeline is built from: the bind-group layouts of the scene (in its upload layout) and of the
//! frame, the pipeline layout over them, and the whole request (`gpu::PipelineRequest`) — shared by the renderer
//! and by `pipeline_forecast`, which builds a pipeline before its renderer exists.

use crate::gpu::PipelineRequest;
use crate::render::bindings;
use crate::render::features::PipelineKey;
use crate::render::gpu_scene::GpuScene;
use crate::render::packed_scene::SceneLayout;

/// The render kernel's entry point.
pub const RENDER_ENTRY: &str = "render_main";

/// The scene's and the frame's bind-group layouts (groups 0 and 1) for a scene uploaded in `scene`'s layout.
pub fn bind_group_layouts(device: &wgpu::Device, scene: SceneLayout) -> [wgpu::BindGroupLayout; 2] {
    let layout0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("scene"),
        entries: &GpuScene::layout_entries_of(scene),
    });
    let frame_entries: Vec<_> = bindings::FRAME.iter().map(bindings::layout_entry).collect();
    let layout1 = device
        .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some("frame"), entries: &frame_entries });
    [layout0, layout1]
}

/// The layout of every render pipeline over these bind-group layouts.
pub fn pipeline_layout(device: &wgpu::Device, groups: [&wgpu::BindGroupLayout; 2]) -> wgpu::PipelineLayout {
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("render"),
        bind_group_layouts: &[Some(groups[0]), Some(groups[1])],
        immediate_size: 0,
    })
}

/// What the render pipeline for `key` is built from: `source`, the entry point, the key's constants, and the
/// scene's layout (the key says which).
pub fn pipeline_request(source: &str, key: &PipelineKey) -> PipelineRequest {
    let packed = key.features.packed_scene;
    PipelineRequest {
        source: source.to_string(),
        entry: RENDER_ENTRY.to_string(),
        constants: key.constants().into_iter().map(|(n, v)| (n.to_string(), v)).collect(),
        layout: layout_tag(if packed { SceneLayout::Packed } else { SceneLayout::Separate }),
    }
}

/// A scene layout's name in a `PipelineRequest`.
pub fn layout_tag(layout: SceneLayout) -> String {
    format!("{layout:?}")
}
