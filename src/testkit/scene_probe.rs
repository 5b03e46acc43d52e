//! Scene probes: kernels that call the render shaders' functions (sampling routines, pdfs, light selection) with a
//! whole scene bound exactly as the renderer binds it. [`super::probe`] covers kernels that need the geometry at most;
//! these need materials, lights, the environment and the frame uniform too.
//!
//! Binding convention:
//! - `@group(0)`: every scene binding of [`bindings::SCENE`] (the renderer's group 0, from the one binding table);
//! - `@group(1)`: `@binding(0)` the frame uniform ([`bindings::FRAME`]`[0]`, `params`), `@binding(4)` and `(5)` the
//!   environment guide's (zero unless `ScenePipelines::write_guide` wrote one);
//! - `@group(2)` ([`SCENE_PROBE_GROUP`]): `@binding(0)` the job (`var<uniform>`, any struct), `@binding(1)` the
//!   output (`var<storage, read_write>`), `@binding(2)` the input (`var<storage, read>`).
//!
//! Pipelines are built once per [`ScenePipelines`] (lavapipe compiles a render-sized module for seconds) and
//! dispatched many times; one dispatch runs at a time because the frame uniform is shared.

use std::sync::Mutex;

use wgpu::util::DeviceExt;

use crate::gpu::types::GpuFrameParams;
use crate::gpu::GpuContext;
use crate::render::bindings;
use crate::render::gpu_scene::GpuScene;

use super::probe::ProbeError;

/// The bind group of a scene probe's own buffers (job, output, input).
pub const SCENE_PROBE_GROUP: u32 = 2;
/// Words of the probes' environment guide buffers: a one-cell grid's six slots of 128 bins, with room to spare.
pub const PROBE_GUIDE_WORDS: u64 = 2048;
/// Workgroup size the kernels must declare (`@workgroup_size(64)`): dispatches cover `invocations` with it.
pub const SCENE_PROBE_WORKGROUP: u32 = 64;

/// A scene uploaded and bound as a probe's group 0.
pub struct BoundScene {
    /// The scene's buffers and CPU tables.
    pub scene: GpuScene,
    group: wgpu::BindGroup,
}

/// Compiled scene-probe kernels of one module, with their layouts and the frame uniform.
pub struct ScenePipelines {
    entries: Vec<(String, wgpu::ComputePipeline)>,
    scene_layout: wgpu::BindGroupLayout,
    io_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    guide_cdf: wgpu::Buffer,
    lock: Mutex<()>,
}

fn io_entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    }
}

impl ScenePipelines {
    /// Validates `source` (a composed module) and builds one pipeline per entry point.
    pub fn new(ctx: &GpuContext, source: &str, entry_points: &[&str]) -> Result<ScenePipelines, ProbeError> {
        let device = &ctx.device;
        let scene_entries: Vec<_> = bindings::SCENE.iter().map(|b| bindings::layout_entry(&b.binding)).collect();
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("probe scene"),
            entries: &scene_entries,
        });
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("probe frame"),
            entries: &[
                bindings::layout_entry(&bindings::FRAME[0]),
                bindings::layout_entry(&bindings::FRAME[4]),
                bindings::layout_entry(&bindings::FRAME[5]),
            ],
        });
        let io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("probe io"),
            entries: &[
                io_entry(0, wgpu::BufferBindingType::Uniform),
                io_entry(1, wgpu::BufferBindingType::Storage { read_only: false }),
                io_entry(2, wgpu::BufferBindingType::Storage { read_only: true }),
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene probe"),
            bind_group_layouts: &[Some(&scene_layout), Some(&frame_layout), Some(&io_layout)],
            immediate_size: 0,
        });
        let mut entries = Vec::new();
        for entry in entry_points {
            let pipeline =
                crate::render::shaders::compute_pipeline(device, None, entry, source, entry, &[], Some(&layout))
                    .map_err(ProbeError::Shader)?;
            entries.push((entry.to_string(), pipeline));
        }
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe params"),
            size: std::mem::size_of::<GpuFrameParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // The environment guide's bindings (never learned in a probe: `guide_on` stays 0).
        let guide_buffer = || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("probe guide"),
                size: 4 * PROBE_GUIDE_WORDS,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (guide_cdf, guide_counts) = (guide_buffer(), guide_buffer());
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe frame"),
            layout: &frame_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: guide_cdf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: guide_counts.as_entire_binding() },
            ],
        });
        Ok(ScenePipelines { entries, scene_layout, io_layout, params, frame_group, guide_cdf, lock: Mutex::new(()) })
    }

    /// Writes an environment guide (`guide_cdf`, at most [`PROBE_GUIDE_WORDS`] words) for kernels whose frame
    /// uniform sets `guide_on`.
    pub fn write_guide(&self, ctx: &GpuContext, cdf: &[f32]) {
        assert!(cdf.len() as u64 <= PROBE_GUIDE_WORDS, "a probe guide holds at most {PROBE_GUIDE_WORDS} words");
        ctx.queue.write_buffer(&self.guide_cdf, 0, bytemuck::cast_slice(cdf));
    }

    /// Binds an uploaded scene as group 0 (probes use the separate layout: `GpuScene::upload` on a device with
    /// bindings enough).
    pub fn bind(&self, ctx: &GpuContext, scene: GpuScene) -> BoundScene {
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe scene"),
            layout: &self.scene_layout,
            entries: &scene.bind_group_entries(),
        });
        BoundScene { scene, group }
    }

    /// Runs `entry` over `invocations` invocations (in 64-wide workgroups, 2D past the per-dimension limit) with
    /// the scene, the frame uniform, the job uniform and the input bound; returns the first `output_bytes` of the
    /// output. wgpu validation errors come back as [`ProbeError::Validation`].
    #[allow(clippy::too_many_arguments)]
    pub fn dispatch(
        &self,
        ctx: &GpuContext,
        entry: &str,
        scene: &BoundScene,
        frame: &GpuFrameParams,
        job: &[u8],
        input: &[u8],
        output_bytes: u64,
        invocations: u32,
    ) -> Result<Vec<u8>, ProbeError> {
        let pipeline = &self
            .entries
            .iter()
            .find(|(e, _)| e == entry)
            .unwrap_or_else(|| panic!("scene probe has no entry point '{entry}'"))
            .1;
        let _guard = self.lock.lock().unwrap_or_else(|e| e.into_inner());
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(frame));
        let job_buf = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("probe job"),
            contents: job,
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let out = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("probe out"),
            size: output_bytes.max(16).next_multiple_of(4),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let input_buf = ctx.storage_buffer_bytes("probe in", input, 16);
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe io"),
            layout: &self.io_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: job_buf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: out.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: input_buf.as_entire_binding() },
            ],
        });
        let groups = invocations.div_ceil(SCENE_PROBE_WORKGROUP).max(1);
        let gx = groups.min(ctx.limits().max_compute_workgroups_per_dimension.max(1));
        let mut enc = device.create_command_encoder(&Default::default());
        {
            let mut pass =
                enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(entry), timestamp_writes: None });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &scene.group, &[]);
            pass.set_bind_group(1, &self.frame_group, &[]);
            pass.set_bind_group(SCENE_PROBE_GROUP, &group, &[]);
            pass.dispatch_workgroups(gx, groups.div_ceil(gx), 1);
        }
        ctx.queue.submit([enc.finish()]);
        if let Some(err) = pollster::block_on(scope.pop()) {
            return Err(ProbeError::Validation { entry: entry.to_string(), message: err.to_string() });
        }
        ctx.wait()?;
        let mut bytes = ctx.read_buffer(&out, output_bytes.max(16).next_multiple_of(4))?;
        bytes.truncate(output_bytes as usize);
        Ok(bytes)
    }
}
