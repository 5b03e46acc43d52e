//! What a ray costs in a kernel that only traces (no shading, no path state), against what it costs inside the
//! render's one big kernel — the question a wavefront design turns on (docs/profile-bvh.md). Traces rays against
//! DamagedHelmet's 8-wide BVH in a probe kernel that does nothing else, `REPEAT` times per ray, and prints ns per ray
//! per lane (the difference of two repeat counts, so pipeline compilation and upload cancel out).
//! Where the adapter offers ray queries (wgpu's `EXPERIMENTAL_RAY_QUERY`: VK_KHR_ray_query, which lavapipe has from
//! Mesa 24.1), the same rays are also traced through the driver's own acceleration structure, for comparison, and
//! the two are checked to find the same closest primitives.
//! `cargo run --release --example trace_cost [RAYS]`

use glam::Vec3;
use mislab::accel::bvh;
use mislab::gpu::GpuContext;
use mislab::testkit::probe::{GeometryBuffers, Probe, ProbeRay};
use std::time::Instant;

#[path = "common/rays.rs"]
mod rays;
use rays::{bounce_rays, bounds};

const KERNEL: &str = "
override REPEAT: u32 = 1u;
fn probe_closest(r: ProbeRay) -> u32 {
    var acc = 0u;
    var t_max = r.t_max;
    for (var k = 0u; k < REPEAT; k++) {
        let h = trace_closest(r.o, r.d, t_max);
        acc += h.prim;
        // Never true for a hit (t < t_max), but the compiler cannot know: each trace depends on the last.
        t_max = select(t_max, t_max * 0.5, h.t > t_max);
    }
    return acc;
}
fn probe_any(r: ProbeRay) -> u32 {
    var acc = 0u;
    var t_max = r.t_max;
    for (var k = 0u; k < REPEAT; k++) {
        let a = trace_any(r.o, r.d, t_max);
        acc += select(0u, 1u, a);
        t_max = select(t_max, t_max * 0.5, acc > 1000000u);
    }
    return acc;
}
";

/// Camera rays of a `side`² image in 8×8 tiles (a workgroup's lanes), looking at the model from +z.
fn camera_rays(tris: &[[Vec3; 3]], side: u32) -> Vec<ProbeRay> {
    let (lo, hi) = bounds(tris);
    let c = (lo + hi) * 0.5;
    let r = (hi - lo).length() * 0.5;
    let eye = c + Vec3::new(0.0, 0.0, 2.2 * r);
    let mut rays = Vec::new();
    for ty in 0..side / 8 {
        for tx in 0..side / 8 {
            for l in 0..64 {
                let (x, y) = (tx * 8 + l % 8, ty * 8 + l / 8);
                let u = (x as f32 + 0.5) / side as f32 * 2.0 - 1.0;
                let v = 1.0 - (y as f32 + 0.5) / side as f32 * 2.0;
                let d = Vec3::new(u * 0.5, v * 0.5, -1.0).normalize();
                rays.push(ProbeRay { o: eye.into(), t_max: f32::MAX, d: d.into(), _pad: 0.0 });
            }
        }
    }
    rays
}

fn seconds(probe: &Probe, source: &str, function: &str, rays: &[ProbeRay], geo: &GeometryBuffers) -> f64 {
    let t = Instant::now();
    let out: Vec<u32> =
        probe.map(source, "ProbeRay", "u32", function, rays, Some(geo)).unwrap_or_else(|e| panic!("{e}"));
    std::hint::black_box(out);
    t.elapsed().as_secs_f64()
}

/// The driver's ray queries on the same rays: a second device with `EXPERIMENTAL_RAY_QUERY`, one BLAS of the
/// triangles (non-indexed, opaque, fast-trace), one identity instance.
mod driver_rays {
    use super::ProbeRay;
    use glam::Vec3;
    use mislab::testkit::probe::PROBE_RAY_WGSL;
    use std::time::Instant;
    use wgpu::util::DeviceExt;

    // The ray query is declared outside the loop: declared inside it, the first dispatch lost the device on
    // lavapipe 25.0.7 (wgpu 30.0.1) without any error reported.
    // After `enable wgpu_ray_query;` and the probe's ray struct (mislab::testkit::probe::PROBE_RAY_WGSL).
    const KERNEL: &str = "
@group(0) @binding(0) var<storage, read> rays: array<ProbeRay>;
@group(0) @binding(1) var<storage, read_write> out: array<u32>;
@group(0) @binding(2) var scene: acceleration_structure;
override REPEAT: u32 = 1u;
override ANY_HIT: bool = false;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= arrayLength(&rays) { return; }
    let r = rays[gid.x];
    var rq: ray_query;
    var acc = 0u;
    var t_max = min(r.t_max, 1e30);
    // RAY_FLAG_OPAQUE, and RAY_FLAG_TERMINATE_ON_FIRST_HIT for the any-hit probe.
    let flags = select(0x01u, 0x05u, ANY_HIT);
    for (var k = 0u; k < REPEAT; k++) {
        rayQueryInitialize(&rq, scene, RayDesc(flags, 0xffu, 0.0, t_max, r.o, r.d));
        rayQueryProceed(&rq);
        let h = rayQueryGetCommittedIntersection(&rq);
        acc += select(0xffffffffu, h.primitive_index, h.kind != 0u);
        // Never true for a hit, as in the probe kernel: each trace depends on the last.
        t_max = select(t_max, t_max * 0.5, h.kind != 0u && h.t > t_max);
    }
    out[gid.x] = acc;
}
";

    pub struct DriverRays {
        device: wgpu::Device,
        queue: wgpu::Queue,
        tlas: wgpu::Tlas,
        _blas: wgpu::Blas,
        layout: wgpu::BindGroupLayout,
        pipeline_layout: wgpu::PipelineLayout,
        module: wgpu::ShaderModule,
    }

    impl DriverRays {
        /// On the adapter named `adapter` (the one the rest of the example traces on); None where it offers no
        /// ray queries.
        pub fn new(tris: &[[Vec3; 3]], adapter: &str) -> Option<DriverRays> {
            let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
            desc.backends = wgpu::Backends::VULKAN;
            let instance = wgpu::Instance::new(desc);
            let adapter = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN))
                .into_iter()
                .find(|a| a.get_info().name == adapter)
                .filter(|a| a.features().contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY))?;
            let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
                label: Some("ray queries"),
                required_features: wgpu::Features::EXPERIMENTAL_RAY_QUERY,
                required_limits: adapter.limits(),
                // SAFETY: an example that measures; wgpu marks the ray-query API experimental.
                experimental_features: unsafe { wgpu::ExperimentalFeatures::enabled() },
                ..Default::default()
            }))
            .ok()?;
            let verts: Vec<[f32; 3]> = tris.iter().flatten().map(|v| v.to_array()).collect();
            let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("blas vertices"),
                contents: bytemuck::cast_slice(&verts),
                usage: wgpu::BufferUsages::BLAS_INPUT,
            });
            let size = wgpu::BlasTriangleGeometrySizeDescriptor {
                vertex_format: wgpu::VertexFormat::Float32x3,
                vertex_count: verts.len() as u32,
                index_format: None,
                index_count: None,
                flags: wgpu::AccelerationStructureGeometryFlags::OPAQUE,
            };
            let blas = device.create_blas(
                &wgpu::CreateBlasDescriptor {
                    label: None,
                    flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                    update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                },
                wgpu::BlasGeometrySizeDescriptors::Triangles { descriptors: vec![size.clone()] },
            );
            let mut tlas = device.create_tlas(&wgpu::CreateTlasDescriptor {
                label: None,
                flags: wgpu::AccelerationStructureFlags::PREFER_FAST_TRACE,
                update_mode: wgpu::AccelerationStructureUpdateMode::Build,
                max_instances: 1,
            });
            let identity = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
            tlas[0] = Some(wgpu::TlasInstance::new(&blas, identity, 0, 0xff));
            let mut encoder = device.create_command_encoder(&Default::default());
            let geometry = wgpu::BlasTriangleGeometry {
                size: &size,
                vertex_buffer: &vertex_buffer,
                first_vertex: 0,
                vertex_stride: 12,
                index_buffer: None,
                first_index: None,
                transform_buffer: None,
                transform_buffer_offset: None,
            };
            let entry = wgpu::BlasBuildEntry {
                blas: &blas,
                geometry: wgpu::BlasGeometries::TriangleGeometries(vec![geometry]),
            };
            encoder.build_acceleration_structures(std::iter::once(&entry), std::iter::once(&tlas));
            queue.submit(Some(encoder.finish()));
            let binding = |binding: u32, ty: wgpu::BindingType| wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty,
                count: None,
            };
            let storage = |read_only: bool| wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: None,
                entries: &[
                    binding(0, storage(true)),
                    binding(1, storage(false)),
                    binding(2, wgpu::BindingType::AccelerationStructure { vertex_return: false }),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: None,
                bind_group_layouts: &[Some(&layout)],
                immediate_size: 0,
            });
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("ray query probe"),
                source: wgpu::ShaderSource::Wgsl(format!("enable wgpu_ray_query;\n{PROBE_RAY_WGSL}{KERNEL}").into()),
            });
            Some(DriverRays { device, queue, tlas, _blas: blas, layout, pipeline_layout, module })
        }

        pub fn adapter_name(&self) -> String {
            format!("{:?}", self.device.adapter_info().name)
        }

        /// Seconds of the second of two dispatches (the first compiles), and the primitives found (REPEAT = 1).
        pub fn run(&self, rays: &[ProbeRay], any_hit: bool, repeat: u32) -> (f64, Vec<u32>) {
            let d = &self.device;
            let ray_buffer = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: None,
                contents: bytemuck::cast_slice(rays),
                usage: wgpu::BufferUsages::STORAGE,
            });
            let size = rays.len() as u64 * 4;
            let out = d.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            let readback = d.create_buffer(&wgpu::BufferDescriptor {
                label: None,
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let constants = [("REPEAT", repeat as f64), ("ANY_HIT", if any_hit { 1.0 } else { 0.0 })];
            let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: None,
                layout: Some(&self.pipeline_layout),
                module: &self.module,
                entry_point: Some("main"),
                compilation_options: wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() },
                cache: None,
            });
            let bind_group = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: None,
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: ray_buffer.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: out.as_entire_binding() },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::AccelerationStructure(&self.tlas),
                    },
                ],
            });
            let dispatch = || {
                let mut encoder = d.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_pipeline(&pipeline);
                    pass.set_bind_group(0, Some(&bind_group), &[]);
                    pass.dispatch_workgroups((rays.len() as u32).div_ceil(64), 1, 1);
                }
                self.queue.submit(Some(encoder.finish()));
                d.poll(wgpu::PollType::wait_indefinitely()).unwrap_or_else(|e| panic!("{e}"));
            };
            dispatch();
            let t = Instant::now();
            dispatch();
            let seconds = t.elapsed().as_secs_f64();
            let mut encoder = d.create_command_encoder(&Default::default());
            encoder.copy_buffer_to_buffer(&out, 0, &readback, 0, size);
            self.queue.submit(Some(encoder.finish()));
            readback.slice(..).map_async(wgpu::MapMode::Read, |r| r.unwrap_or_else(|e| panic!("{e}")));
            d.poll(wgpu::PollType::wait_indefinitely()).unwrap_or_else(|e| panic!("{e}"));
            let prims =
                bytemuck::cast_slice(&readback.slice(..).get_mapped_range().unwrap_or_else(|e| panic!("{e}"))).to_vec();
            (seconds, prims)
        }
    }
}

fn main() {
    let n: usize = std::env::args().nth(1).map(|s| s.parse().expect("RAYS")).unwrap_or(1 << 19);
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("{e}"));
    let tris = rays::triangles(rays::HELMET);
    let wide = mislab::accel::wide_bvh::build(&tris, &[], &[], bvh::Presplit::Large { keep_whole: &[] });
    let geo = GeometryBuffers::new(&ctx, &wide, &tris, &[], &[]);
    let library = mislab::testkit::probe::trace_module(KERNEL)
        .replace("override WIDE_BVH: bool = false;", "override WIDE_BVH: bool = true;");
    let probe = Probe::new(&ctx);
    let side = ((n as f64).sqrt() as u32 / 8 * 8).max(8);
    let sets = [
        ("camera rays, 8x8 tiles", camera_rays(&tris, side)),
        ("bounce rays, random order", bounce_rays(&tris, n, false)),
        ("bounce rays, sorted by origin cell + octant", bounce_rays(&tris, n, true)),
    ];
    let driver = driver_rays::DriverRays::new(&tris, &ctx.info.name);
    for (name, rays) in &sets {
        for function in ["probe_closest", "probe_any"] {
            let mut best = f64::MAX;
            for _ in 0..2 {
                let src1 = library.replace("override REPEAT: u32 = 1u;", "override REPEAT: u32 = 1u;");
                let src9 = library.replace("override REPEAT: u32 = 1u;", "override REPEAT: u32 = 9u;");
                let a = seconds(&probe, &src1, function, rays, &geo);
                let b = seconds(&probe, &src9, function, rays, &geo);
                best = best.min((b - a) / 8.0);
            }
            println!(
                "{name:45} {function:14} {:>8} rays: {:6.1} ns per ray ({:.2} Mrays/s)",
                rays.len(),
                best / rays.len() as f64 * 1e9,
                rays.len() as f64 / best / 1e6
            );
        }
        let Some(driver) = &driver else { continue };
        let ours: Vec<u32> =
            probe.map(&library, "ProbeRay", "u32", "probe_closest", rays, Some(&geo)).unwrap_or_else(|e| panic!("{e}"));
        for any_hit in [false, true] {
            let mut best = f64::MAX;
            let mut found = Vec::new();
            for _ in 0..2 {
                let (a, prims) = driver.run(rays, any_hit, 1);
                let (b, _) = driver.run(rays, any_hit, 9);
                best = best.min((b - a) / 8.0);
                found = prims;
            }
            // Closest hits agree where both name the same triangle (ties between coplanar triangles aside).
            let agree = if any_hit {
                ours.iter().zip(&found).filter(|(o, f)| (**o == u32::MAX) == (**f == u32::MAX)).count()
            } else {
                ours.iter().zip(&found).filter(|(o, f)| o == f).count()
            };
            println!(
                "{name:45} {:14} {:>8} rays: {:6.1} ns per ray ({:.2} Mrays/s); {:.2} % agree with ours ({})",
                if any_hit { "driver any" } else { "driver closest" },
                rays.len(),
                best / rays.len() as f64 * 1e9,
                rays.len() as f64 / best / 1e6,
                100.0 * agree as f64 / rays.len() as f64,
                driver.adapter_name()
            );
        }
    }
}
