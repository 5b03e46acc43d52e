//! Renderer: the render pipeline, per-render buffers (frame parameters, accumulation, counters),
//! progressive dispatch, reset and readback.

use crate::features::{Features, PipelineKey};
use crate::film::Film;
use crate::gpu::{GpuContext, GpuError};
use crate::gpu_scene::GpuScene;
use crate::gpu_types::*;
use crate::scene::Camera;
use crate::settings::{Mode, Settings};
use crate::shaders;

/// WGSL files of the render entry point, in order.
pub const RENDER_FILES: &[&str] = &[
    "common.wgsl",
    "geometry_bindings.wgsl",
    "shading_bindings.wgsl",
    "specialize.wgsl",
    "rng.wgsl",
    "samplers.wgsl",
    "warps.wgsl",
    "bvh.wgsl",
    "baked_geometry.wgsl",
    "scene_data.wgsl",
    "bsdf.wgsl",
    "surface.wgsl",
    "lights.wgsl",
    "mis.wgsl",
    "estimators.wgsl",
    "integrator.wgsl",
];

/// Default bounce count from which Russian roulette decides whether a path continues (issue 3: "after depth 3").
pub const RR_DEPTH: u32 = 3;

/// The render module that reads the scene from its buffers (the generic pipeline, shared between scenes).
pub fn render_source() -> String {
    shaders::compose(RENDER_FILES, "")
}

/// The render module for one scene: with its data baked in when it is small enough (`Features::flat`), else
/// `render_source()`.
pub fn render_source_for(data: &crate::gpu_scene::SceneData) -> String {
    match crate::baked::scene_data_source(data) {
        Some((data, geometry)) => {
            shaders::compose_replacing(RENDER_FILES, &[("scene_data.wgsl", &data), ("baked_geometry.wgsl", &geometry)])
        }
        None => render_source(),
    }
}

/// A progressive renderer of one scene with one set of settings (change either → `reset`).
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: std::collections::HashMap<PipelineKey, wgpu::ComputePipeline>,
    /// The scene's features (what a specialised pipeline compiles in).
    pub features: Features,
    /// Whether pipelines are specialised to the settings (headless) or read them at run time (viewer).
    pub specialize: bool,
    scene_group: wgpu::BindGroup,
    frame_group: wgpu::BindGroup,
    params_buffer: wgpu::Buffer,
    accum: wgpu::Buffer,
    counters: wgpu::Buffer,
    /// Settings in force.
    pub settings: Settings,
    /// Camera in force.
    pub camera: Camera,
    /// Samples per pixel accumulated since the last reset.
    pub samples: u32,
    /// Target count of the fixed-count samplers (`FrameParams::sampler_spp`; see `samplers::check_spp`).
    pub sampler_spp: u32,
    /// Samples per pixel per dispatch instead of `max_dispatch_spp`'s safe default: only for scenes so simple
    /// that a sample's loops are short (check the film's sample counts: the driver drops what its budget cuts).
    pub dispatch_spp: Option<u32>,
    /// Non-finite samples since the last reset (device counter, summed on the host).
    pub nonfinite_total: u64,
    /// Rays traced since the last reset.
    pub rays_total: u64,
    env_light: u32,
    env_size: (u32, u32),
    env_constant: [f32; 3],
    env_scale: f32,
    env_rotation: f32,
    num_lights: u32,
    /// The scene's render origin (`SceneData::origin`): the camera is placed relative to it.
    origin: glam::Vec3,
    offset_scale: f32,
    /// This scene's render module (`render_source_for`) and the shared one (`render_source`).
    source: String,
    shared_source: String,
}

impl Renderer {
    /// Builds the pipeline and the per-render buffers for `scene` at the settings' film size.
    pub fn new(ctx: &GpuContext, scene: &GpuScene, camera: Camera, settings: Settings) -> Result<Renderer, String> {
        let mut r = Renderer::new_unprepared(ctx, scene, camera, settings)?;
        r.prepare()?;
        r.warm_up(ctx).map_err(|e| e.to_string())?;
        Ok(r)
    }

    /// The per-render buffers only, with no pipeline yet: the viewer compiles pipelines on another
    /// thread and hands them in with `insert_pipeline` (compiling takes seconds on lavapipe).
    pub fn new_unprepared(
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: Camera,
        settings: Settings,
    ) -> Result<Renderer, String> {
        settings.validate()?;
        let device = ctx.device.clone();
        let storage = |binding: u32, read_only: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let scene_entries: Vec<_> = (0..scene.buffers.len() as u32).map(|i| storage(i, true)).collect();
        let layout0 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &scene_entries,
        });
        let layout1 = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<GpuFrameParams>() as u64),
                    },
                    count: None,
                },
                storage(1, false),
                storage(2, false),
                storage(3, true),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("render"),
            bind_group_layouts: &[Some(&layout0), Some(&layout1)],
            immediate_size: 0,
        });
        let entries: Vec<wgpu::BindGroupEntry> = scene
            .buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() })
            .collect();
        let scene_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &layout0,
            entries: &entries,
        });
        let pixels = settings.width as u64 * settings.height as u64;
        let accum_bytes = pixels * std::mem::size_of::<GpuAccum>() as u64;
        if accum_bytes > ctx.max_storage_binding() {
            return Err(format!(
                "a {}x{} film needs {} MiB of accumulation buffer, more than the device's storage-binding limit of {} MiB",
                settings.width,
                settings.height,
                accum_bytes >> 20,
                ctx.max_storage_binding() >> 20
            ));
        }
        let accum = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("accum"),
            size: accum_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let counters = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("counters"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let params_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("params"),
            size: std::mem::size_of::<GpuFrameParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler_data =
            ctx.storage_buffer("sampler_data", crate::samplers::sampler_data(), wgpu::BufferUsages::empty());
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &layout1,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: accum.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: counters.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: sampler_data.as_entire_binding() },
            ],
        });
        let d = &scene.data;
        let mut r = Renderer {
            device,
            queue: ctx.queue.clone(),
            pipeline_layout,
            pipelines: Default::default(),
            features: Features::of(d),
            specialize: true,
            scene_group,
            frame_group,
            params_buffer,
            accum,
            counters,
            settings,
            camera,
            samples: 0,
            sampler_spp: crate::samplers::DEFAULT_SAMPLER_SPP,
            dispatch_spp: None,
            nonfinite_total: 0,
            rays_total: 0,
            env_light: d.env_light.unwrap_or(INVALID),
            env_size: d.env_size,
            env_constant: d.env_constant,
            env_scale: d.env_scale,
            env_rotation: d.env_rotation,
            num_lights: d.lights.len() as u32,
            origin: d.origin,
            offset_scale: d.offset_scale,
            source: render_source_for(d),
            shared_source: render_source(),
        };
        r.reset();
        Ok(r)
    }

    /// The layout every render pipeline of this renderer uses (to build one on another thread).
    pub fn pipeline_layout(&self) -> &wgpu::PipelineLayout {
        &self.pipeline_layout
    }

    /// Whether the pipeline for `key` is built.
    pub fn has_pipeline(&self, key: &PipelineKey) -> bool {
        self.pipelines.contains_key(key)
    }

    /// Adds a pipeline built elsewhere with a layout equal to `pipeline_layout()` (wgpu deduplicates
    /// equal bind group layouts, so renderers of scenes with the same bindings can share pipelines).
    pub fn insert_pipeline(&mut self, key: PipelineKey, pipeline: wgpu::ComputePipeline) {
        self.pipelines.insert(key, pipeline);
    }

    /// The pipeline key the current settings need.
    pub fn key(&self) -> PipelineKey {
        if self.specialize {
            PipelineKey::specialized(self.features, &self.settings)
        } else {
            PipelineKey::generic()
        }
    }

    /// The module a pipeline with `key` is built from: this scene's baked source for its baked pipelines, else the
    /// shared one (generic pipelines are shared between scenes; see `insert_pipeline`).
    pub fn source_for(&self, key: &PipelineKey) -> &str {
        if key.features.baked != 0 {
            &self.source
        } else {
            &self.shared_source
        }
    }

    /// Replaces the source of baked pipelines (a renderer that compiles other scenes' pipelines ahead of use,
    /// like the viewer's warm-up renderer); forgets the baked pipelines built from the old one.
    pub fn set_baked_source(&mut self, source: &str) {
        if self.source != source {
            self.source = source.to_string();
            self.pipelines.retain(|k, _| k.features.baked == 0);
        }
    }

    /// Builds (or finds in the cache) the pipeline for the current settings.
    pub fn prepare(&mut self) -> Result<(), String> {
        let key = self.key();
        if !self.pipelines.contains_key(&key) {
            let p = shaders::compute_pipeline(
                &self.device,
                "render",
                self.source_for(&key),
                "render_main",
                &key.constants(),
                Some(&self.pipeline_layout),
            )?;
            self.pipelines.insert(key, p);
        }
        Ok(())
    }

    /// Switches between specialised and generic pipelines (the viewer runs the generic one while a
    /// specialised one compiles). Does not reset: both compute the same estimate.
    pub fn set_specialize(&mut self, on: bool) -> Result<(), String> {
        self.specialize = on;
        self.prepare()
    }

    /// Runs a zero-sample dispatch: drivers such as lavapipe compile the pipeline at its first use
    /// (seconds for the render kernel), and that belongs to start-up, not to the render time.
    pub fn warm_up(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        let samples = self.samples;
        let mut enc = self.device.create_command_encoder(&Default::default());
        self.encode(&mut enc, 0);
        self.queue.submit([enc.finish()]);
        self.samples = samples;
        ctx.wait()
    }

    /// Forgets every accumulated sample (the next dispatch starts from sample 0).
    pub fn reset(&mut self) {
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.accum, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        self.queue.submit([enc.finish()]);
        self.samples = 0;
        self.nonfinite_total = 0;
        self.rays_total = 0;
    }

    /// Changes settings (film size excluded) and resets.
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), String> {
        settings.validate()?;
        if settings.width != self.settings.width || settings.height != self.settings.height {
            return Err("the film size cannot change on an existing renderer".into());
        }
        self.settings = settings;
        self.reset();
        self.prepare()
    }

    /// The frame parameters of a dispatch of `spp` samples starting at the current sample count.
    pub fn frame_params(&self, spp: u32) -> GpuFrameParams {
        let s = &self.settings;
        let (right, up, forward) = self.camera.frame();
        GpuFrameParams {
            width: s.width,
            height: s.height,
            sample_base: self.samples,
            samples_per_dispatch: spp,
            seed: s.seed,
            mode: s.mode.tag(),
            max_depth: if s.mode == Mode::Direct { 1 } else { s.max_depth },
            strategy: s.strategy.tag(),
            light_sampling: s.light_sampling.tag(),
            env_sampling: s.env_sampling.tag(),
            light_select: s.light_select.tag(),
            heuristic: s.heuristic.tag(),
            power_beta: s.power_beta,
            light_samples: s.light_samples,
            bsdf_samples: s.bsdf_samples,
            mis_kind: s.mis.tag(),
            sampler: s.sampler.tag(),
            num_lights: self.num_lights,
            rr_depth: s.rr_depth,
            env_light: self.env_light,
            cam_origin: (self.camera.position - self.origin).into(),
            tan_half_fov: (0.5 * self.camera.vfov).tan(),
            cam_right: right.into(),
            aspect: s.width as f32 / s.height as f32,
            cam_up: up.into(),
            env_scale: self.env_scale,
            cam_forward: forward.into(),
            env_rotation: self.env_rotation,
            env_constant: self.env_constant,
            env_width: self.env_size.0,
            env_height: self.env_size.1,
            sampler_spp: self.sampler_spp,
            row_offset: 0,
            row_count: s.height,
            offset_scale: self.offset_scale,
            _pad0: 0,
            _pad1: 0,
            _pad2: 0,
        }
    }

    /// Records one dispatch of `spp` samples per pixel into `enc` and advances the sample count.
    /// The parameters are written to the queue first, so call `submit` before recording another.
    pub fn encode(&mut self, enc: &mut wgpu::CommandEncoder, spp: u32) {
        self.encode_rows(enc, spp, 0, self.settings.height, None);
        self.samples += spp;
    }

    /// Records a dispatch of `spp` samples per pixel for film rows `row_offset .. row_offset + row_count`
    /// only, starting at sample index `samples`, WITHOUT advancing `samples`: the caller adds `spp` once
    /// every row has had them (the viewer renders a pass in bands of rows to bound its frame time).
    /// `timestamps`, when given, brackets the pass with GPU timestamps. Call `submit` before recording another.
    pub fn encode_rows(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        spp: u32,
        row_offset: u32,
        row_count: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let row_offset = row_offset.min(self.settings.height);
        let row_count = row_count.min(self.settings.height - row_offset);
        let p = GpuFrameParams { row_offset, row_count, ..self.frame_params(spp) };
        self.queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&p));
        let mut pass = enc
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("render"), timestamp_writes: timestamps });
        let pipeline = self.pipelines.get(&self.key()).expect("prepare() builds the pipeline before encoding");
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.scene_group, &[]);
        pass.set_bind_group(1, &self.frame_group, &[]);
        pass.dispatch_workgroups(self.settings.width.div_ceil(8), row_count.div_ceil(8), 1);
    }

    /// Renders `spp` more samples per pixel in one submission and waits for them (with the device timeout).
    pub fn render(&mut self, ctx: &GpuContext, spp: u32) -> Result<(), GpuError> {
        // lavapipe (Mesa 22.3) gives each invocation one budget of 65535 loop iterations shared by all
        // its loops and silently stops looping when it is spent: a 1024-spp dispatch accumulated only
        // ~300-450 samples. Split into small dispatches (one submit each, so each sees its own
        // parameters) and wait once at the end.
        let chunk = self.max_dispatch_spp();
        let mut left = spp;
        while left > 0 {
            let n = left.min(chunk);
            let mut enc = self.device.create_command_encoder(&Default::default());
            self.encode(&mut enc, n);
            self.queue.submit([enc.finish()]);
            left -= n;
        }
        ctx.wait()?;
        self.collect_counters(ctx)
    }

    /// Most samples per pixel one dispatch may take without exhausting a driver's per-invocation loop
    /// budget (path tracing through a BVH runs far more traversal steps per sample than direct lighting).
    pub fn max_dispatch_spp(&self) -> u32 {
        if let Some(n) = self.dispatch_spp {
            return n;
        }
        // A baked scene's traversal has no loops, so a path sample spends a few loop iterations per vertex
        // (render_main's vertex loop, shade's sample loops); a BVH walk spends one per node visited.
        if self.settings.mode == Mode::Path && self.features.flat.is_none() {
            4
        } else {
            16
        }
    }

    /// The pipeline built for `key`, to share with another renderer (`insert_pipeline`).
    pub fn pipeline(&self, key: &PipelineKey) -> Option<&wgpu::ComputePipeline> {
        self.pipelines.get(key)
    }

    /// Adds the device counters to the host totals and clears them (u32 on the device would overflow).
    pub fn collect_counters(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        let c: Vec<u32> = ctx.read_pod(&self.counters, 4)?;
        self.nonfinite_total += c[0] as u64;
        self.rays_total += c[1] as u64;
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.counters, 0, None);
        self.queue.submit([enc.finish()]);
        Ok(())
    }

    /// Reads the accumulation back.
    pub fn film(&self, ctx: &GpuContext) -> Result<Film, GpuError> {
        let n = (self.settings.width * self.settings.height) as usize;
        let accum: Vec<GpuAccum> = ctx.read_pod(&self.accum, n)?;
        Ok(Film::from_accum(self.settings.width, self.settings.height, &accum, self.nonfinite_total))
    }

    /// The accumulation buffer (for the viewer's display pass).
    pub fn accum_buffer(&self) -> &wgpu::Buffer {
        &self.accum
    }
}
