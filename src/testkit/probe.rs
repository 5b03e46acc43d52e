//! Probe kernels: run WGSL functions on the GPU over many inputs and read the outputs back (GPU unit tests,
//! chi-square tests of sampling routines).
//!
//! Binding convention (the pipeline layout is explicit, so a shader may use any subset of it):
//! - `@group(0)`: the scene geometry exactly as `geometry_bindings.wgsl` declares it (bindings 0–4: `bvh_nodes`,
//!   `prim_refs`, `tri_verts`, `spheres`, `quads`, 14: `wide_nodes` and 17–19: `tri_verts_hi`…`hi3`, all `var<storage, read>`). Present only when the job has a
//!   [`GeometryBuffers`]; without one the shader must not declare group 0.
//! - `@group(1)` ([`PROBE_GROUP`]): `@binding(0)` the output, `var<storage, read_write>`, pre-filled with
//!   [`PROBE_SENTINEL`] words so unwritten results are recognisable (a NaN as f32); `@binding(1 + k)` the k-th input,
//!   `var<storage, read>`. Inputs are padded to at least 16 bytes (a 0-byte binding is rejected).
//!
//! [`Probe::run`] takes any kernel; [`Probe::map`] wraps a WGSL function `fn f(x: In) -> Out` into a kernel
//! ([`map_kernel`]) and applies it to a slice, one invocation per element.

use bytemuck::Pod;
use glam::Vec3;
use wgpu::util::DeviceExt;

use crate::accel::bvh::Bvh;
use crate::accel::wide_bvh::GpuWideNode;
use crate::gpu::types::{GpuQuad, GpuSphere};
use crate::gpu::{GpuContext, GpuError};
use crate::render::bindings;

/// The bind group of the probe's own buffers.
pub const PROBE_GROUP: u32 = 1;
/// The word the output buffer is filled with before the dispatch (0xffffdead: a NaN as f32).
pub const PROBE_SENTINEL: u32 = 0xffff_dead;
/// Workgroup size of [`map_kernel`] kernels.
pub const MAP_WORKGROUP_SIZE: u32 = 64;

/// A ray as tracing probe kernels take it (WGSL [`PROBE_RAY_WGSL`]): origin, the hit distance limit, direction.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeRay {
    pub o: [f32; 3],
    pub t_max: f32,
    pub d: [f32; 3],
    pub _pad: f32,
}

/// The WGSL declaration of [`ProbeRay`] (32 bytes, the same field order).
pub const PROBE_RAY_WGSL: &str = "struct ProbeRay { o: vec3<f32>, t_max: f32, d: vec3<f32>, _pad: f32 }\n";

/// A tracing probe's module: the files traversal needs and `kernels` after [`PROBE_RAY_WGSL`]. Geometry only: no
/// textures, so no cut-outs (alpha.wgsl needs the shading bindings).
pub fn trace_module(kernels: &str) -> String {
    let no_alpha = "fn alpha_cut_out(prim: u32, b1: f32, b2: f32) -> bool { return false; }\n\
                    fn occluder_range() -> vec2<u32> { return vec2<u32>(0u); }\n";
    crate::render::shaders::compose(
        &[
            "common.wgsl",
            "geometry_bindings.wgsl",
            "bvh.wgsl",
            "bvh_wide.wgsl",
            "geometry_loads.wgsl",
            "baked_geometry.wgsl",
        ],
        &format!("{no_alpha}{PROBE_RAY_WGSL}{kernels}"),
    )
}

/// Why a probe failed.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    /// naga rejected the composed module.
    #[error("{0}")]
    Shader(String),
    /// wgpu reported a validation error (binding mismatch, bad dispatch, ...).
    #[error("wgpu validation error in probe '{entry}': {message}")]
    Validation { entry: String, message: String },
    /// Waiting on or reading from the device failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// The nine geometry storage buffers of `geometry_bindings.wgsl` (group 0).
pub struct GeometryBuffers {
    pub bvh_nodes: wgpu::Buffer,
    pub prim_refs: wgpu::Buffer,
    pub tri_verts: wgpu::Buffer,
    pub spheres: wgpu::Buffer,
    pub quads: wgpu::Buffer,
    pub wide_nodes: wgpu::Buffer,
    pub tri_verts_hi: wgpu::Buffer,
    pub tri_verts_hi2: wgpu::Buffer,
    pub tri_verts_hi3: wgpu::Buffer,
}

impl GeometryBuffers {
    /// Uploads a BVH and the primitives it was built from (triangles as three vertices, stored as three vec4
    /// with w = 0). Empty tables get a small dummy buffer.
    pub fn new(ctx: &GpuContext, bvh: &Bvh, tris: &[[Vec3; 3]], spheres: &[GpuSphere], quads: &[GpuQuad]) -> Self {
        let verts: Vec<[f32; 4]> = tris.iter().flat_map(|t| t.iter().map(|v| [v.x, v.y, v.z, 0.0])).collect();
        let none = wgpu::BufferUsages::empty();
        // As the scene upload does: padded where a device may read 32 bytes at a time.
        let padded = |name: &str, bytes: &[u8], element_size: usize| {
            ctx.storage_buffer_bytes(name, &bindings::pad_for_32_byte_reads(name, bytes), element_size)
        };
        GeometryBuffers {
            bvh_nodes: ctx.storage_buffer("bvh_nodes", &bvh.nodes, none),
            prim_refs: ctx.storage_buffer("prim_refs", &bvh.prim_refs, none),
            tri_verts: padded("tri_verts", bytemuck::cast_slice(&verts), 16),
            spheres: ctx.storage_buffer("spheres", spheres, none),
            quads: ctx.storage_buffer("quads", quads, none),
            wide_nodes: padded("wide_nodes", bytemuck::cast_slice(&bvh.wide), size_of::<GpuWideNode>()),
            tri_verts_hi: ctx.storage_buffer::<[f32; 4]>("tri_verts_hi", &[], none),
            tri_verts_hi2: ctx.storage_buffer::<[f32; 4]>("tri_verts_hi2", &[], none),
            tri_verts_hi3: ctx.storage_buffer::<[f32; 4]>("tri_verts_hi3", &[], none),
        }
    }

    /// In the order of `bindings::geometry()`.
    fn buffers(&self) -> [&wgpu::Buffer; 9] {
        let s = self;
        [
            &s.bvh_nodes,
            &s.prim_refs,
            &s.tri_verts,
            &s.spheres,
            &s.quads,
            &s.wide_nodes,
            &s.tri_verts_hi,
            &s.tri_verts_hi2,
            &s.tri_verts_hi3,
        ]
    }
}

/// One probe dispatch.
pub struct ProbeJob<'a> {
    /// The complete, composed WGSL module (see [`crate::render::shaders::compose`]).
    pub source: &'a str,
    /// Its compute entry point.
    pub entry: &'a str,
    /// Input buffers, bound read-only at group 1, bindings 1, 2, ...
    pub inputs: &'a [&'a [u8]],
    /// Bytes to read back from the output (group 1, binding 0).
    pub output_bytes: u64,
    /// Workgroups in x, y, z.
    pub workgroups: [u32; 3],
    /// Values of `override` constants.
    pub constants: &'a [(&'a str, f64)],
    /// Scene geometry for group 0, if the shader uses it.
    pub geometry: Option<&'a GeometryBuffers>,
}

/// Runs probe kernels on a device.
pub struct Probe<'a> {
    ctx: &'a GpuContext,
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl<'a> Probe<'a> {
    /// A probe runner on `ctx`.
    pub fn new(ctx: &'a GpuContext) -> Self {
        Probe { ctx }
    }

    /// Validates, builds and dispatches one kernel, waits (with the context's timeout) and returns the first
    /// `output_bytes` of the output buffer. wgpu validation errors come back as [`ProbeError::Validation`].
    pub fn run(&self, job: &ProbeJob) -> Result<Vec<u8>, ProbeError> {
        crate::render::shaders::validate(job.source)
            .map_err(|e| ProbeError::Shader(format!("probe '{}' failed to validate:\n{e}", job.entry)))?;
        let device = &self.ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);

        let geometry_layout = job.geometry.map(|_| {
            let entries: Vec<_> = bindings::geometry().map(|b| bindings::layout_entry(&b.binding)).collect();
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("probe geometry"),
                entries: &entries,
            })
        });
        let io_entries: Vec<_> = std::iter::once(storage_entry(0, false))
            .chain((0..job.inputs.len() as u32).map(|k| storage_entry(1 + k, true)))
            .collect();
        let io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("probe io"),
            entries: &io_entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("probe"),
            bind_group_layouts: &[geometry_layout.as_ref(), Some(&io_layout)],
            immediate_size: 0,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(job.entry),
            source: wgpu::ShaderSource::Wgsl(crate::render::shaders::for_device(job.source, device.features())),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(job.entry),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(job.entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants: job.constants,
                zero_initialize_workgroup_memory: false,
            },
            cache: None,
        });

        // Output: at least 16 bytes, a whole number of words, filled with the sentinel.
        let out_size = job.output_bytes.max(16).next_multiple_of(4);
        let fill: Vec<u32> = vec![PROBE_SENTINEL; (out_size / 4) as usize];
        let output = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("probe output"),
            contents: bytemuck::cast_slice(&fill),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        });
        let inputs: Vec<wgpu::Buffer> = job
            .inputs
            .iter()
            .map(|bytes| self.ctx.storage_buffer("probe input", bytes, wgpu::BufferUsages::empty()))
            .collect();

        let geometry_group = job.geometry.zip(geometry_layout.as_ref()).map(|(g, layout)| {
            let entries: Vec<_> = g
                .buffers()
                .iter()
                .zip(bindings::geometry())
                .map(|(buf, b)| wgpu::BindGroupEntry { binding: b.binding.binding, resource: buf.as_entire_binding() })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("probe geometry"),
                layout,
                entries: &entries,
            })
        });
        let io_bind: Vec<_> =
            std::iter::once(wgpu::BindGroupEntry { binding: 0, resource: output.as_entire_binding() })
                .chain(
                    inputs
                        .iter()
                        .enumerate()
                        .map(|(k, b)| wgpu::BindGroupEntry { binding: 1 + k as u32, resource: b.as_entire_binding() }),
                )
                .collect();
        let io_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("probe io"),
            layout: &io_layout,
            entries: &io_bind,
        });

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("probe") });
        {
            let mut pass = encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("probe"), timestamp_writes: None });
            pass.set_pipeline(&pipeline);
            if let Some(g) = &geometry_group {
                pass.set_bind_group(0, g, &[]);
            }
            pass.set_bind_group(PROBE_GROUP, &io_group, &[]);
            let [x, y, z] = job.workgroups;
            pass.dispatch_workgroups(x, y, z);
        }
        self.ctx.queue.submit([encoder.finish()]);
        if let Some(err) = pollster::block_on(scope.pop()) {
            return Err(ProbeError::Validation { entry: job.entry.to_string(), message: err.to_string() });
        }
        self.ctx.wait()?;
        let mut bytes = self.ctx.read_buffer(&output, out_size)?;
        bytes.truncate(job.output_bytes as usize);
        Ok(bytes)
    }

    /// Applies the WGSL function `function: fn(In) -> Out` to every element of `inputs`, one invocation each, and
    /// returns the outputs in order. `library` is the composed module the function lives in (without group 1
    /// declarations: [`map_kernel`] adds them); `in_type` / `out_type` are WGSL type names whose array strides must
    /// equal `size_of::<I>()` / `size_of::<O>()`.
    pub fn map<I: Pod, O: Pod>(
        &self,
        library: &str,
        in_type: &str,
        out_type: &str,
        function: &str,
        inputs: &[I],
        geometry: Option<&GeometryBuffers>,
    ) -> Result<Vec<O>, ProbeError> {
        if inputs.is_empty() {
            return Ok(Vec::new());
        }
        let n = inputs.len() as u64;
        assert!(n <= u32::MAX as u64, "too many probe inputs");
        let source =
            format!("{library}\n{}", map_kernel(in_type, out_type, function, library.contains("fn bvh_set_lane")));
        let groups = n.div_ceil(MAP_WORKGROUP_SIZE as u64) as u32;
        let max = self.ctx.limits().max_compute_workgroups_per_dimension.max(1);
        let workgroups = [groups.min(max), groups.div_ceil(max), 1];
        let bytes = self.run(&ProbeJob {
            source: &source,
            entry: "probe_map",
            inputs: &[bytemuck::cast_slice(inputs)],
            output_bytes: n * std::mem::size_of::<O>() as u64,
            workgroups,
            constants: &[("PROBE_COUNT", n as f64)],
            geometry,
        })?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }
}

/// The WGSL of a kernel `probe_map` that writes `probe_out[i] = function(probe_in[i])` for i < `PROBE_COUNT`
/// (an `override`), with the group-1 declarations of the binding convention. Dispatch is 2D when the element count
/// needs more than the per-dimension workgroup limit.
pub fn map_kernel(in_type: &str, out_type: &str, function: &str, traces: bool) -> String {
    // Kernels that trace rays tell the traversal which workgroup-stack slice is theirs.
    let set_lane = if traces { "bvh_set_lane(lid);" } else { "" };
    format!(
        "override PROBE_COUNT: u32;
@group(1) @binding(0) var<storage, read_write> probe_out: array<{out_type}>;
@group(1) @binding(1) var<storage, read> probe_in: array<{in_type}>;
@compute @workgroup_size({MAP_WORKGROUP_SIZE})
fn probe_map(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>, @builtin(local_invocation_index) lid: u32) {{
    {set_lane}
    let i = gid.x + gid.y * nwg.x * {MAP_WORKGROUP_SIZE}u;
    if i >= PROBE_COUNT {{ return; }}
    probe_out[i] = {function}(probe_in[i]);
}}
"
    )
}
