//! The display pass (shaders/display.wgsl): the accumulators of both sides of a comparison → the RGBA8
//! image a viewer shows (the native window's and the web page's), plus per-workgroup statistics sums; the
//! false-colour scale's CPU twin for the legend.

use crate::gpu::types::GpuAccum;
use crate::gpu::{GpuContext, GpuError};
use crate::render::film::Tonemap;
use crate::render::RenderError;
use bytemuck::{Pod, Zeroable};

/// WGSL files of the display entry point, in order.
pub const DISPLAY_FILES: &[&str] = &["display.wgsl"];

/// The composed display module.
pub fn display_source() -> String {
    crate::render::shaders::compose(DISPLAY_FILES, "")
}

/// What the image area shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[repr(u32)]
pub enum View {
    /// The tonemapped image.
    #[default]
    Image = 0,
    /// The standard error of each pixel's mean, log scale, false colour.
    StdErr = 1,
    /// Per-pixel relMSE against the loaded reference, log scale, false colour.
    RelMse = 2,
    /// Pixels that received a NaN/Inf sample, in magenta over a dimmed image.
    NonFinite = 3,
}

impl View {
    /// Every view, in tag order.
    pub const ALL: &'static [View] = &[View::Image, View::StdErr, View::RelMse, View::NonFinite];
    /// The name in the panel and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            View::Image => "image",
            // Not "stderr": that reads as the error stream.
            View::StdErr => "std-error",
            View::RelMse => "relmse",
            View::NonFinite => "nan-inf",
        }
    }
    /// The WGSL tag (`VIEW_*`).
    pub fn tag(self) -> u32 {
        self as u32
    }
    /// Whether the view is drawn in false colour (and needs the legend).
    pub fn false_colour(self) -> bool {
        matches!(self, View::StdErr | View::RelMse)
    }
}

/// Every tonemapper, in tag order (`TONEMAP_*` in display.wgsl).
pub const TONEMAPS: &[Tonemap] = &[Tonemap::Clamp, Tonemap::Aces];

/// The panel / CLI name of a tonemapper.
pub fn tonemap_name(t: Tonemap) -> &'static str {
    match t {
        Tonemap::Clamp => "clamp",
        Tonemap::Aces => "aces",
    }
}

/// The WGSL tag of a tonemapper.
pub fn tonemap_tag(t: Tonemap) -> u32 {
    match t {
        Tonemap::Clamp => 0,
        Tonemap::Aces => 1,
    }
}

/// The display uniform (WGSL `DisplayParams`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DisplayParams {
    pub width: u32,
    pub height: u32,
    pub view: u32,
    pub tonemap: u32,
    pub exposure_scale: f32,
    pub split_x: u32,
    pub compare: u32,
    pub has_reference: u32,
    pub preview_scale: u32,
    pub preview_width: u32,
    pub preview_height: u32,
    pub log_min: f32,
    pub log_max: f32,
    pub row_offset: u32,
    pub row_count: u32,
    pub _pad0: u32,
}

/// One column's statistics sums for one side (WGSL `SideSums`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SideSums {
    pub rel_se: f32,
    pub rel_se_n: f32,
    pub sq_err: f32,
    pub rel_mse: f32,
    pub err_n: f32,
    pub nonfinite_px: f32,
    pub sampled_px: f32,
    pub _pad0: f32,
}

/// Both sides' sums of one column (WGSL `Partial`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Partial {
    pub a: SideSums,
    pub b: SideSums,
}

/// One side's image statistics, summed over all pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImageStats {
    /// Mean over pixels (with ≥ 2 samples and a positive mean) of standard error / mean.
    pub mean_rel_se: Option<f64>,
    /// √(mean squared error) against the reference, over pixels and channels.
    pub rmse: Option<f64>,
    /// Mean relMSE against the reference, over pixels and channels.
    pub rel_mse: Option<f64>,
    /// Pixels with at least one NaN/Inf sample.
    pub nonfinite_px: u64,
    /// Pixels with at least one sample.
    pub sampled_px: u64,
}

impl ImageStats {
    /// Sums the per-column partials (in f64).
    pub fn from_partials(p: &[SideSums]) -> ImageStats {
        let mut s = [0f64; 7];
        for x in p {
            for (acc, v) in
                s.iter_mut().zip([x.rel_se, x.rel_se_n, x.sq_err, x.rel_mse, x.err_n, x.nonfinite_px, x.sampled_px])
            {
                *acc += v as f64;
            }
        }
        ImageStats {
            mean_rel_se: (s[1] > 0.0).then(|| s[0] / s[1]),
            rmse: (s[4] > 0.0).then(|| (s[2] / (3.0 * s[4])).sqrt()),
            rel_mse: (s[4] > 0.0).then(|| s[3] / (3.0 * s[4])),
            nonfinite_px: s[5] as u64,
            sampled_px: s[6] as u64,
        }
    }
}

/// The false-colour scale (Turbo, Mikhailov 2019 polynomial fit): t ∈ [0, 1] → sRGB display colour in
/// [0, 1]. Twin of `false_colour` in display.wgsl; the legend draws it.
pub fn false_colour(t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    let v4 = [1.0, t, t * t, t * t * t];
    let v2 = [v4[2] * v4[2], v4[3] * v4[2]];
    let dot4 = |c: [f32; 4]| v4[0] * c[0] + v4[1] * c[1] + v4[2] * c[2] + v4[3] * c[3];
    let dot2 = |c: [f32; 2]| v2[0] * c[0] + v2[1] * c[1];
    let r = dot4([0.13572138, 4.61539260, -42.66032258, 132.13108234]) + dot2([-152.94239396, 59.28637943]);
    let g = dot4([0.09140261, 2.19418839, 4.84296658, -14.18503333]) + dot2([4.27729857, 2.82956604]);
    let b = dot4([0.10667330, 12.64194608, -60.58204836, 110.36276771]) + dot2([-89.90310912, 27.34824973]);
    [r, g, b].map(|c| c.clamp(0.0, 1.0))
}

/// What one display dispatch reads.
pub struct DisplayInputs<'a> {
    /// Full-resolution accumulators of side A and B (B = A without a comparison).
    pub accum: [&'a wgpu::Buffer; 2],
    /// Preview accumulators of side A and B.
    pub preview: [&'a wgpu::Buffer; 2],
    /// Reference image (vec4 per pixel), if loaded.
    pub reference: Option<&'a wgpu::Buffer>,
}

/// The display pipeline and its output buffers on the render device.
pub struct DisplayPass {
    device: wgpu::Device,
    queue: wgpu::Queue,
    /// One per view (`View::tag` order).
    pipelines: Vec<wgpu::ComputePipeline>,
    stats_pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    out: wgpu::Buffer,
    partials: wgpu::Buffer,
    staging: wgpu::Buffer,
    dummy_reference: wgpu::Buffer,
    width: u32,
    height: u32,
    workgroups: (u32, u32),
}

/// The result of a display dispatch, read back.
pub struct DisplayOutput {
    /// RGBA8 pixels, row-major from the top (sRGB-encoded; alpha 255): this frame's rows and the
    /// earlier frames' others.
    pub rgba: Vec<u8>,
    /// Side A's and side B's statistics (when they were summed).
    pub stats: Option<[ImageStats; 2]>,
}

impl DisplayPass {
    /// Builds the display pipeline for a `width`×`height` film.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<DisplayPass, RenderError> {
        let device = ctx.device.clone();
        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let ro = wgpu::BufferBindingType::Storage { read_only: true };
        let rw = wgpu::BufferBindingType::Storage { read_only: false };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("display"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Uniform),
                entry(1, ro),
                entry(2, ro),
                entry(3, ro),
                entry(4, ro),
                entry(5, ro),
                entry(6, rw),
                entry(7, rw),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("display"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = View::ALL
            .iter()
            .map(|v| {
                crate::render::shaders::compute_pipeline(
                    &device,
                    None,
                    "display",
                    &display_source(),
                    "display_main",
                    &[("VIEW", v.tag() as f64)],
                    Some(&pipeline_layout),
                )
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(RenderError::Pipeline)?;
        let stats_pipeline = crate::render::shaders::compute_pipeline(
            &device,
            None,
            "display stats",
            &display_source(),
            "stats_main",
            &[],
            Some(&pipeline_layout),
        )
        .map_err(RenderError::Pipeline)?;
        let workgroups = (width.div_ceil(8), height.div_ceil(8));
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let pixels = width as u64 * height as u64;
        let out = buffer("display out", pixels * 4, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let partial_bytes = width as u64 * std::mem::size_of::<Partial>() as u64;
        let partials =
            buffer("display partials", partial_bytes, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let staging = buffer(
            "display staging",
            pixels * 4 + partial_bytes,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let params = buffer(
            "display params",
            std::mem::size_of::<DisplayParams>() as u64,
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let dummy_reference = buffer("no reference", 16, wgpu::BufferUsages::STORAGE);
        Ok(DisplayPass {
            device,
            queue: ctx.queue.clone(),
            pipelines,
            stats_pipeline,
            layout,
            params,
            out,
            partials,
            staging,
            dummy_reference,
            width,
            height,
            workgroups,
        })
    }

    /// Records the display dispatch for rows `params.row_offset ..+ params.row_count`, the statistics
    /// sums when `stats`, and the copies of what changed to the staging buffer (which keeps the other
    /// rows from earlier frames). Submit, wait, then `read`.
    pub fn encode(
        &self,
        enc: &mut wgpu::CommandEncoder,
        params: &DisplayParams,
        inputs: &DisplayInputs<'_>,
        stats: bool,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        let row_offset = params.row_offset.min(self.height);
        let row_count = params.row_count.min(self.height - row_offset);
        self.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(params));
        let reference = inputs.reference.unwrap_or(&self.dummy_reference);
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("display"),
            layout: &self.layout,
            entries: &[
                bind(0, &self.params),
                bind(1, inputs.accum[0]),
                bind(2, inputs.accum[1]),
                bind(3, inputs.preview[0]),
                bind(4, inputs.preview[1]),
                bind(5, reference),
                bind(6, &self.out),
                bind(7, &self.partials),
            ],
        });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("display"),
                timestamp_writes: timestamps,
            });
            pass.set_pipeline(&self.pipelines[(params.view as usize).min(self.pipelines.len() - 1)]);
            pass.set_bind_group(0, &group, &[]);
            if row_count > 0 {
                pass.dispatch_workgroups(self.workgroups.0, row_count.div_ceil(8), 1);
            }
            if stats {
                pass.set_pipeline(&self.stats_pipeline);
                pass.dispatch_workgroups(self.width.div_ceil(64), 1, 1);
            }
        }
        let image_bytes = self.width as u64 * self.height as u64 * 4;
        let row_bytes = self.width as u64 * 4;
        if row_count > 0 {
            enc.copy_buffer_to_buffer(
                &self.out,
                row_offset as u64 * row_bytes,
                &self.staging,
                row_offset as u64 * row_bytes,
                row_count as u64 * row_bytes,
            );
        }
        if stats {
            enc.copy_buffer_to_buffer(
                &self.partials,
                0,
                &self.staging,
                image_bytes,
                self.partials.size().min(self.staging.size() - image_bytes),
            );
        }
    }

    /// Maps the staging buffer (after the submission that `encode` recorded into), waits for it and reads it.
    pub fn read(&self, ctx: &GpuContext, stats: bool) -> Result<DisplayOutput, GpuError> {
        let (tx, rx) = std::sync::mpsc::channel();
        self.staging.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        ctx.wait()?;
        match rx.recv_timeout(std::time::Duration::from_secs(5)) {
            Ok(Ok(())) => {}
            Ok(Err(e)) => return Err(GpuError::Map(e.to_string())),
            Err(_) => return Err(GpuError::Map("the map callback never ran".into())),
        }
        self.read_mapped(stats)
    }

    /// The staging buffer, for a caller that cannot block (a web page) to map itself; then `read_mapped`.
    pub fn staging(&self) -> &wgpu::Buffer {
        &self.staging
    }

    /// Reads the staging buffer once it is mapped, and unmaps it.
    pub fn read_mapped(&self, stats: bool) -> Result<DisplayOutput, GpuError> {
        let image_bytes = (self.width as usize) * (self.height as usize) * 4;
        let out = {
            let data = self.staging.get_mapped_range(..).map_err(|e| GpuError::Map(format!("{e:?}")))?;
            let rgba = data[..image_bytes].to_vec();
            let n = self.width as usize;
            let partials: Vec<Partial> =
                bytemuck::pod_collect_to_vec(&data[image_bytes..image_bytes + n * std::mem::size_of::<Partial>()]);
            let a: Vec<SideSums> = partials.iter().map(|p| p.a).collect();
            let b: Vec<SideSums> = partials.iter().map(|p| p.b).collect();
            DisplayOutput { rgba, stats: stats.then(|| [ImageStats::from_partials(&a), ImageStats::from_partials(&b)]) }
        };
        self.staging.unmap();
        Ok(out)
    }
}

fn bind(binding: u32, b: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
    wgpu::BindGroupEntry { binding, resource: b.as_entire_binding() }
}

/// Uploads a reference image (linear RGB, the film's size) as one vec4 per pixel.
pub fn upload_reference(ctx: &GpuContext, rgb: &[[f32; 3]]) -> wgpu::Buffer {
    let data: Vec<[f32; 4]> = rgb.iter().map(|c| [c[0], c[1], c[2], 0.0]).collect();
    ctx.storage_buffer("reference", &data, wgpu::BufferUsages::empty())
}

/// Decodes a reference image (an EXR, or any float image `image` reads) of the film's size: linear RGB per pixel.
/// The error says what is wrong; the caller names the file.
pub fn decode_reference(bytes: &[u8], width: u32, height: u32) -> Result<Vec<[f32; 3]>, String> {
    let img = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| e.to_string())?
        .decode()
        .map_err(|e| format!("could not read the reference: {e}"))?
        .to_rgb32f();
    if img.width() != width || img.height() != height {
        return Err(format!(
            "the reference is {}x{} but the film is {width}x{height} (render it with the same --width/--height)",
            img.width(),
            img.height(),
        ));
    }
    Ok(img.pixels().map(|p| p.0).collect())
}

/// Size of one accumulator, for buffer checks.
pub const ACCUM_BYTES: u64 = std::mem::size_of::<GpuAccum>() as u64;
