//! Renderer: the render pipeline, per-render buffers (frame parameters, accumulation, counters),
//! progressive dispatch, reset and readback.

use crate::gpu::timer::GpuTimer;
use crate::gpu::types::*;
use crate::gpu::{GpuContext, GpuError};
use crate::render::env_guide;
pub use crate::render::error::{InvalidSettings, RenderError};
use crate::render::features::{Features, PipelineKey};
use crate::render::film::Film;
use crate::render::gpu_scene::GpuScene;
use crate::render::packed_scene::{for_layout, SceneLayout};
use crate::render::pipeline_cache::PipelineCache;
use crate::render::render_module::{render_source, render_source_for};
use crate::render::render_pipeline::{bind_group_layouts, pipeline_layout, pipeline_request, RENDER_ENTRY};
pub use crate::render::settings::RR_DEPTH;
use crate::render::settings::{Mode, Settings};
use crate::render::shaders;
use crate::render::sky_probe::SkyProbe;
use crate::render::tile_order::tile_row_stride;
use crate::scene::Camera;

mod frame_params;
mod guide;
mod timed;
pub use timed::Timing;

/// Most pixel samples `Renderer::render` submits before it waits on the device: bounds each wait well below
/// `gpu::DEVICE_WAIT_TIMEOUT` however long the render, and the device's 32-bit ray counter between readbacks.
pub const PIXEL_SAMPLES_PER_WAIT: u64 = 1 << 22;

/// A sample pass recorded band by band (the viewer bounds its frame time this way): its samples per pixel and the
/// first row not yet recorded.
#[derive(Clone, Copy, Debug)]
struct PassInFlight {
    spp: u32,
    next_row: u32,
}

/// A progressive renderer of one scene with one set of settings (change either → reset).
///
/// Samples advance one way only: `record_band` (or `record`, a whole-film band) records a pass of `spp` samples
/// per pixel, and `samples()` grows by `spp` when the pass has covered every row. `render` and `render_timed`
/// are loops over `record` for headless callers.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    pipeline_layout: wgpu::PipelineLayout,
    /// This renderer's pipelines, shared through the device's memo (a pipeline another renderer built is not rebuilt).
    pipelines: PipelineCache,
    /// The scene's features (what a specialised pipeline compiles in).
    features: Features,
    /// Whether pipelines are specialised to the settings (headless) or read them at run time (viewer).
    specialize: bool,
    /// The pipeline `warm_up` last ran (compiled on the driver), if any.
    warmed: Option<PipelineKey>,
    scene_group: wgpu::BindGroup,
    frame_group: wgpu::BindGroup,
    params_buffer: wgpu::Buffer,
    accum: wgpu::Buffer,
    counters: wgpu::Buffer,
    settings: Settings,
    camera: Camera,
    /// Samples per pixel of the complete passes since the last reset.
    samples: u32,
    /// The pass being recorded band by band, if one is.
    pass: Option<PassInFlight>,
    /// The film rows every pass covers (all by default; `set_row_window`).
    window: std::ops::Range<u32>,
    /// Target count of the fixed-count samplers (`FrameParams::sampler_spp`; see `samplers::check_spp`).
    sampler_spp: u32,
    /// Samples per pixel per dispatch instead of `max_dispatch_spp`'s safe default.
    dispatch_spp: Option<u32>,
    /// Non-finite samples since the last reset (device counter, summed on the host).
    nonfinite_total: u64,
    /// Rays traced since the last reset.
    rays_total: u64,
    env_light: u32,
    env_size: (u32, u32),
    env_constant: [f32; 3],
    env_scale: f32,
    env_rotation: f32,
    num_lights: u32,
    /// The convex lamps' entries in the light table (first, count) and whether they are its only lights.
    lamps: (u32, u32, bool),
    /// `SceneData::occluders`, for the frame parameters.
    occluders: (u32, u32),
    /// The scene's render origin (`SceneData::origin`): the camera is placed relative to it.
    origin: glam::Vec3,
    offset_scale: f32,
    /// This scene's render module (`render_source_for`) and the shared one (`render_source`).
    source: String,
    shared_source: String,
    /// The environment guide (`--env-sampling guided`): its grid, per-slot CDFs, training counts, and whether it
    /// is learned for the current camera and settings (reset forgets it).
    guide_grid: env_guide::GuideGrid,
    guide_cdf: wgpu::Buffer,
    guide_counts: wgpu::Buffer,
    guide_on: bool,
    /// Slots of the learned guide that draw from it (alpha > 0).
    guided_slots: usize,
    /// What the next dispatch does for the guide (0: uses it; `env_guide::LEARN`, `LEARN_ONLY`: learns it;
    /// `COMPLETE`: renders the rest of sample 0 with it).
    guide_train: u32,
    /// One 8×8 tile in this many learns the guide, instead of the film size's choice (`set_guide_learner_period`).
    guide_learner_period: Option<u32>,
    /// Whether the scene's environment is one constant (the only kind the guide serves).
    env_is_constant: bool,
    /// What the sky probe saw from the camera the renderer was made with (`--env-sampling auto`); None where the
    /// environment is not one constant or the probe cannot see the scene.
    sky_probe: Option<SkyProbe>,
}

impl Renderer {
    /// Builds the pipeline and the per-render buffers for `scene` at the settings' film size.
    pub fn new(
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: Camera,
        settings: Settings,
    ) -> Result<Renderer, RenderError> {
        Ok(Renderer::new_timed(ctx, scene, camera, settings)?.0)
    }

    /// As `new`, with the seconds of its three steps for a start-up report: the per-render buffers (and the sky
    /// probe), the pipeline (built, or found in a cache), and the first dispatch (where a driver that compiles at
    /// first use, like lavapipe, compiles the kernel).
    pub fn new_timed(
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: Camera,
        settings: Settings,
    ) -> Result<(Renderer, [f64; 3]), RenderError> {
        let t0 = web_time::Instant::now();
        let mut r = Renderer::new_unprepared(ctx, scene, camera, settings)?;
        let t1 = web_time::Instant::now();
        r.prepare()?;
        let t2 = web_time::Instant::now();
        r.warm_up(ctx)?;
        Ok((r, [(t1 - t0).as_secs_f64(), (t2 - t1).as_secs_f64(), t2.elapsed().as_secs_f64()]))
    }

    /// The per-render buffers only, with no pipeline yet: the viewer compiles pipelines on another
    /// thread and hands them in with `insert_pipeline` (compiling takes seconds on lavapipe).
    pub fn new_unprepared(
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: Camera,
        settings: Settings,
    ) -> Result<Renderer, RenderError> {
        settings.validate().map_err(RenderError::Settings)?;
        let device = ctx.device.clone();
        let [layout0, layout1] = bind_group_layouts(&device, scene.layout);
        let pipeline_layout = pipeline_layout(&device, [&layout0, &layout1]);
        let scene_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &layout0,
            entries: &scene.bind_group_entries(),
        });
        let pixels = settings.width as u64 * settings.height as u64;
        let accum_bytes = pixels * std::mem::size_of::<GpuAccum>() as u64;
        if accum_bytes > ctx.max_storage_binding() {
            return Err(RenderError::FilmTooLarge {
                width: settings.width,
                height: settings.height,
                need_mib: accum_bytes >> 20,
                limit_mib: ctx.max_storage_binding() >> 20,
            });
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
            ctx.storage_buffer("sampler_data", crate::render::samplers::sampler_data(), wgpu::BufferUsages::empty());
        let d = &scene.data;
        let env_is_constant = d.env_light.is_some() && d.env_size.0 == 0;
        let guide_grid = env_guide::GuideGrid::of_scene(d, settings.width as u64 * settings.height as u64);
        // The guide's buffers at full size only where a guide can serve (one word otherwise).
        let guide_words = if env_is_constant { env_guide::counts_words(guide_grid.slots()) } else { 1 };
        let guide_buffer = |label: &str| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 4 * guide_words as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let (guide_cdf, guide_counts) = (guide_buffer("guide_cdf"), guide_buffer("guide_counts"));
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout: &layout1,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: params_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: accum.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: counters.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: sampler_data.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: guide_cdf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: guide_counts.as_entire_binding() },
            ],
        });
        let film_height = settings.height;
        let mut r = Renderer {
            device,
            queue: ctx.queue.clone(),
            pipeline_layout,
            pipelines: PipelineCache::on_device(&ctx.pipelines),
            features: Features {
                packed_scene: scene.layout == SceneLayout::Packed,
                ..Features::for_backend(d, ctx.info.backend)
            },
            specialize: true,
            warmed: None,
            scene_group,
            frame_group,
            params_buffer,
            accum,
            counters,
            settings,
            camera,
            samples: 0,
            pass: None,
            window: 0..film_height,
            sampler_spp: crate::render::samplers::DEFAULT_SAMPLER_SPP,
            dispatch_spp: None,
            nonfinite_total: 0,
            rays_total: 0,
            env_light: d.env_light.unwrap_or(INVALID),
            env_size: d.env_size,
            env_constant: d.env_constant,
            env_scale: d.env_scale,
            env_rotation: d.env_rotation,
            num_lights: d.selectable_lights() as u32,
            lamps: d.lamp_range(),
            occluders: d.occluders,
            origin: d.origin,
            offset_scale: d.offset_scale,
            // Read only by baked pipelines (`source_for`), which a device that does not bake never keys.
            source: for_layout(render_source_for(d), scene.layout).map_err(RenderError::Pipeline)?,
            shared_source: for_layout(render_source(), scene.layout).map_err(RenderError::Pipeline)?,
            guide_grid,
            guide_cdf,
            guide_counts,
            guide_on: false,
            guide_train: 0,
            guide_learner_period: None,
            guided_slots: 0,
            env_is_constant,
            sky_probe: None,
        };
        if env_is_constant {
            r.sky_probe = r.probe_sky(d);
        }
        r.settings.env_sampling = r.resolved_env_sampling(r.settings.env_sampling);
        r.reset();
        Ok(r)
    }

    /// The layout every render pipeline of this renderer uses (to build one on another thread).
    pub fn pipeline_layout(&self) -> &wgpu::PipelineLayout {
        &self.pipeline_layout
    }

    /// Whether the pipeline for `key` is built.
    pub fn has_pipeline(&self, key: &PipelineKey) -> bool {
        self.pipelines.contains(key)
    }

    /// Adds a pipeline built elsewhere with a layout equal to `pipeline_layout()` (wgpu deduplicates
    /// equal bind group layouts, so renderers of scenes with the same bindings can share pipelines).
    pub fn insert_pipeline(&mut self, key: PipelineKey, pipeline: wgpu::ComputePipeline) {
        self.pipelines.insert(key, pipeline);
    }

    /// The pipeline built for `key`, to share with another renderer (`insert_pipeline`).
    pub fn pipeline(&self, key: &PipelineKey) -> Option<&wgpu::ComputePipeline> {
        self.pipelines.get(key)
    }

    /// The pipeline key the current settings need.
    pub fn key(&self) -> PipelineKey {
        if self.specialize {
            PipelineKey::specialized(self.features, &self.settings)
        } else {
            let mut key = PipelineKey::generic();
            key.features.packed_scene = self.features.packed_scene;
            key
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
            self.pipelines.retain(|k| k.features.baked == 0);
        }
    }

    /// Builds (or finds in this renderer's cache, then in the device's) the pipeline for the current settings. A
    /// pipeline built ahead from an equal request (`render::pipeline_forecast`) is taken instead of building one.
    pub fn prepare(&mut self) -> Result<(), RenderError> {
        let key = self.key();
        let (device, layout) = (&self.device, &self.pipeline_layout);
        let source = if key.features.baked != 0 { &self.source } else { &self.shared_source };
        let memo = self.pipelines.memo().clone();
        self.pipelines
            .get_or_share(key, source, |store| {
                let request = pipeline_request(source, &key);
                let pipeline = match memo.take_offer(&request) {
                    Some(p) => p,
                    None => shaders::compute_pipeline(
                        device,
                        store,
                        "render",
                        source,
                        RENDER_ENTRY,
                        &key.constants(),
                        Some(layout),
                    )?,
                };
                memo.note_request(request);
                Ok(pipeline)
            })
            .map_err(RenderError::Pipeline)
    }

    /// Switches between specialised and generic pipelines (the viewer runs the generic one while a
    /// specialised one compiles). Does not reset: both compute the same estimate.
    pub fn set_specialize(&mut self, on: bool) -> Result<(), RenderError> {
        self.specialize = on;
        self.prepare()
    }

    /// Points a warm-up renderer (one that runs other scenes' pipelines once, so that the driver compiles them
    /// ahead of use) at pipeline `key` with `settings` (its film size kept). False when this renderer cannot run
    /// `key` with those settings.
    pub fn aim_at(&mut self, key: PipelineKey, settings: Settings) -> bool {
        self.features = key.features;
        self.settings = Settings { width: self.settings.width, height: self.settings.height, ..settings };
        self.specialize = key.fixed.is_some();
        self.key() == key
    }

    /// Runs a zero-sample dispatch: drivers such as lavapipe compile the pipeline at its first use
    /// (seconds for the render kernel), and that belongs to start-up, not to the render time.
    pub fn warm_up(&mut self, ctx: &GpuContext) -> Result<(), GpuError> {
        let mut enc = self.device.create_command_encoder(&Default::default());
        self.record_warm_up(&mut enc);
        self.queue.submit([enc.finish()]);
        ctx.wait_at_most(crate::gpu::PIPELINE_COMPILE_TIMEOUT)?;
        self.warmed = Some(self.key());
        Ok(())
    }

    /// Records a zero-sample dispatch of the current pipeline (see `warm_up`); the caller submits and waits. One band
    /// of rows is enough for the driver to compile, and costs little where the pipeline is compiled already (the
    /// whole film's workgroups took lavapipe 0.08–0.1 s at 640×360 for nothing).
    pub fn record_warm_up(&mut self, enc: &mut wgpu::CommandEncoder) {
        self.dispatch(enc, 0, 0, self.settings.height.min(8), None);
    }

    /// Forgets every accumulated sample (the next pass starts from sample 0).
    pub fn reset(&mut self) {
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.clear_buffer(&self.accum, 0, None);
        enc.clear_buffer(&self.counters, 0, None);
        self.queue.submit([enc.finish()]);
        self.samples = 0;
        self.pass = None;
        self.nonfinite_total = 0;
        self.rays_total = 0;
        self.guide_on = false;
    }

    /// Continues from saved accumulators (a render state file, `state::RenderState`): the film holds `accum`
    /// exactly and the next pass starts at sample index `samples`.
    pub fn restore(
        &mut self,
        accum: &[GpuAccum],
        samples: u32,
        nonfinite_total: u64,
        rays_total: u64,
    ) -> Result<(), RenderError> {
        let pixels = self.settings.width as usize * self.settings.height as usize;
        if accum.len() != pixels {
            return Err(RenderError::StateSize { got: accum.len(), want: pixels });
        }
        self.reset();
        self.queue.write_buffer(&self.accum, 0, bytemuck::cast_slice(accum));
        self.samples = samples;
        self.nonfinite_total = nonfinite_total;
        self.rays_total = rays_total;
        Ok(())
    }

    /// Changes settings (film size excluded), resets and builds the pipeline they need.
    pub fn set_settings(&mut self, settings: Settings) -> Result<(), RenderError> {
        self.configure(settings)?;
        self.prepare()
    }

    /// Changes settings (film size excluded) and resets, without building a pipeline (the viewer's compile worker
    /// builds them on another thread).
    pub fn configure(&mut self, settings: Settings) -> Result<(), RenderError> {
        settings.validate().map_err(RenderError::Settings)?;
        if settings.width != self.settings.width || settings.height != self.settings.height {
            return Err(RenderError::FilmSizeChange);
        }
        self.settings = Settings { env_sampling: self.resolved_env_sampling(settings.env_sampling), ..settings };
        self.reset();
        Ok(())
    }

    /// Moves the camera and resets.
    pub fn set_camera(&mut self, camera: Camera) {
        self.camera = camera;
        self.reset();
    }

    /// Settings in force.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Camera in force.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// The scene's features (what a specialised pipeline compiles in).
    pub fn features(&self) -> Features {
        self.features
    }

    /// Whether pipelines are specialised to the settings.
    pub fn is_specialized(&self) -> bool {
        self.specialize
    }

    /// Samples per pixel accumulated in every pixel since the last reset (complete passes).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// The first row of the pass being recorded band by band not yet recorded (0 when no pass is in flight).
    pub fn pass_row(&self) -> u32 {
        self.pass.map_or(0, |p| p.next_row)
    }

    /// Samples per pixel of the pass in flight, if one is.
    pub fn pass_spp(&self) -> Option<u32> {
        self.pass.map(|p| p.spp)
    }

    /// Non-finite samples since the last reset (counted on the device, kept out of the image).
    pub fn nonfinite_total(&self) -> u64 {
        self.nonfinite_total
    }

    /// Rays traced since the last reset.
    pub fn rays_total(&self) -> u64 {
        self.rays_total
    }

    /// Sets the fixed-count samplers' target count (`samplers::check_spp`); a change resets (the points differ).
    pub fn set_sampler_spp(&mut self, n: u32) {
        if n != self.sampler_spp {
            self.sampler_spp = n;
            self.reset();
        }
    }

    /// Samples per pixel per dispatch instead of `max_dispatch_spp`'s safe default: only for scenes so simple
    /// that a sample's loops are short (check the film's sample counts: the driver drops what its budget cuts).
    pub fn set_dispatch_spp(&mut self, n: Option<u32>) {
        self.dispatch_spp = n.map(|n| n.max(1));
    }

    /// Restricts every pass to film rows `rows` (the others stay empty: a test that needs a few rows of a big
    /// film renders only those) and resets.
    pub fn set_row_window(&mut self, rows: std::ops::Range<u32>) {
        let h = self.settings.height;
        self.window = rows.start.min(h)..rows.end.clamp(rows.start.min(h), h);
        self.reset();
    }

    /// Records a whole pass (every row of the window) of `spp` samples per pixel into `enc` (see `record_band`).
    pub fn record(&mut self, enc: &mut wgpu::CommandEncoder, spp: u32, timer: Option<&mut GpuTimer>) {
        let rows = self.settings.height;
        let done = self.record_band(enc, spp, rows, timer);
        debug_assert!(done, "a whole-film band completes its pass");
    }

    /// Records the next `rows` rows of a pass of `spp` samples per pixel into `enc`, after the rows recorded
    /// before (a pass started with one `spp` keeps it until it is complete). Returns whether this band completed
    /// the pass: then `samples()` has grown by `spp`. `timer` times the dispatch. The frame parameters go to the
    /// queue at once, so submit `enc` before recording the next band.
    pub fn record_band(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        spp: u32,
        rows: u32,
        timer: Option<&mut GpuTimer>,
    ) -> bool {
        let end = self.window.end;
        let pass = self.pass.unwrap_or(PassInFlight { spp, next_row: self.window.start });
        let rows = rows.min(end - pass.next_row);
        let writes = timer.and_then(|t| t.pass());
        self.dispatch(enc, pass.spp, pass.next_row, rows, writes);
        let next_row = pass.next_row + rows;
        if next_row >= end {
            self.pass = None;
            self.samples += pass.spp;
            true
        } else {
            self.pass = Some(PassInFlight { next_row, ..pass });
            false
        }
    }

    /// One dispatch of `spp` samples per pixel, starting at sample index `samples`, over film rows
    /// `row_offset .. row_offset + row_count`.
    fn dispatch(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        spp: u32,
        row_offset: u32,
        row_count: u32,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let tile_row_stride = tile_row_stride(row_count.div_ceil(8));
        let p = GpuFrameParams { row_offset, row_count, tile_row_stride, ..self.frame_params(spp) };
        self.queue.write_buffer(&self.params_buffer, 0, bytemuck::bytes_of(&p));
        let mut pass = enc
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("render"), timestamp_writes: timestamps });
        let pipeline = self.pipelines.get(&self.key()).expect("prepare() builds the pipeline before recording");
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &self.scene_group, &[]);
        pass.set_bind_group(1, &self.frame_group, &[]);
        pass.dispatch_workgroups(self.settings.width.div_ceil(8), row_count.div_ceil(8), 1);
    }

    /// Renders `spp` more samples per pixel and waits for them (with the device timeout): dispatches of at most
    /// `max_dispatch_spp()` samples, one submission each, one wait at the end.
    pub fn render(&mut self, ctx: &GpuContext, spp: u32) -> Result<(), RenderError> {
        self.prepare()?;
        // The compile of a pipeline's first use gets its own, longer wait (see PIPELINE_COMPILE_TIMEOUT), so the
        // device timeout below bounds sample work only.
        if self.warmed != Some(self.key()) {
            self.warm_up(ctx)?;
        }
        // The guide's learning pass may be this call's first sample.
        let before = self.samples;
        if spp > 0 {
            self.ensure_guide(ctx)?;
        }
        // lavapipe (Mesa 22.3) gives each invocation one budget of 65535 loop iterations shared by all
        // its loops and silently stops looping when it is spent: a 1024-spp dispatch accumulated only
        // ~300-450 samples. Split into small dispatches (one submit each, so each sees its own
        // parameters) and wait once at the end.
        let chunk = self.max_dispatch_spp();
        let pixels = self.settings.width as u64 * self.window.len() as u64;
        let mut in_flight = 0u64;
        let mut left = spp - (self.samples - before);
        while left > 0 {
            let n = left.min(chunk);
            let mut enc = self.device.create_command_encoder(&Default::default());
            self.record(&mut enc, n, None);
            self.queue.submit([enc.finish()]);
            left -= n;
            in_flight += n as u64 * pixels;
            if in_flight >= PIXEL_SAMPLES_PER_WAIT || left == 0 {
                ctx.wait()?;
                self.collect_counters(ctx)?;
                in_flight = 0;
            }
        }
        Ok(())
    }

    /// Renders one sample more in the next `rows` film rows of a pass (a band, as the viewer records them) and waits:
    /// a time budget's last, partial pass (`api::drive`). Returns whether the band completed the pass.
    pub fn render_rows(&mut self, ctx: &GpuContext, rows: u32) -> Result<bool, RenderError> {
        self.prepare()?;
        if self.warmed != Some(self.key()) {
            self.warm_up(ctx)?;
        }
        self.ensure_guide(ctx)?;
        let mut enc = self.device.create_command_encoder(&Default::default());
        let done = self.record_band(&mut enc, 1, rows, None);
        self.queue.submit([enc.finish()]);
        ctx.wait()?;
        self.collect_counters(ctx)?;
        Ok(done)
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
