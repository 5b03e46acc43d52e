//! Running a group: its reference (given or rendered and cached), then every configuration over the spp ladder and
//! the seeds, timed per dispatch.

use super::*;
use crate::lab::LabError;

// ---------------------------------------------------------------------------------------------------------------
// Running.

pub(super) struct GroupResult {
    pub(super) group: BenchGroup,
    pub(super) rows: Vec<BenchRow>,
    /// Per configuration label: mean per-pixel relMSE over seeds at the last point.
    pub(super) heatmaps: Vec<(String, Vec<f64>)>,
    pub(super) reference: String,
    /// The reference's real sample count, from its header (None for an EXR from elsewhere, which records none).
    pub(super) reference_spp: Option<u32>,
}

pub(super) fn slug(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') && !out.is_empty() {
            out.push('-');
        }
    }
    out.trim_end_matches('-').chars().take(60).collect()
}

/// The group's reference: the given file, or one rendered (MIS, Sobol) and cached under `refs`.
fn group_reference(
    ctx: &GpuContext,
    g: &BenchGroup,
    scene: &crate::scene::Scene,
    refs: &Path,
) -> Result<(Vec<[f32; 3]>, String, Option<u32>), LabError> {
    // What the header says, not what was asked: a given file's spp is its own.
    let header_spp = |r: &reference::ReferenceImage| r.attributes.get("spp").and_then(|s| s.parse().ok());
    if let Some(path) = &g.reference {
        let r = reference::read_exr(path)?;
        if (r.width, r.height) != (g.width, g.height) {
            return Err(LabError::Input(format!(
                "{}: the reference is {}x{}, the benchmark renders {}x{}",
                path.display(),
                r.width,
                r.height,
                g.width,
                g.height
            )));
        }
        let spp = header_spp(&r);
        return Ok((r.pixels, path.display().to_string(), spp));
    }
    let settings = reference::reference_settings(&Settings {
        width: g.width,
        height: g.height,
        mode: g.mode,
        max_depth: g.max_depth,
        light_select: g.reference_light_select,
        ..Settings::default()
    });
    let key = format!(
        "{}-{}{}-{}x{}-d{}-{}spp{}",
        slug(Path::new(&g.scene).file_stem().and_then(|s| s.to_str()).unwrap_or(&g.scene)),
        g.mode.name(),
        g.env
            .as_ref()
            .map(|e| format!("-{}", slug(&e.file_stem().unwrap_or_default().to_string_lossy())))
            .unwrap_or_default(),
        g.width,
        g.height,
        g.max_depth,
        g.reference_spp,
        match g.reference_light_select {
            LightSelect::Uniform => String::new(),
            other => format!("-{other}"),
        }
    );
    let path = refs.join(format!("{key}.exr"));
    if path.exists() {
        if let Ok(r) = reference::read_exr(&path) {
            if (r.width, r.height) == (g.width, g.height)
                && r.attributes.get("spp").map(|s| s.as_str()) == Some(g.reference_spp.to_string().as_str())
            {
                eprintln!("reference: reusing {}", path.display());
                let spp = header_spp(&r);
                return Ok((r.pixels, path.display().to_string(), spp));
            }
        }
    }
    std::fs::create_dir_all(refs).map_err(|e| LabError::Input(format!("{}: {e}", refs.display())))?;
    eprintln!("reference: rendering {} spp of {} ({}) ...", g.reference_spp, g.scene, g.mode.name());
    let t = Instant::now();
    let (film, stats) = reference::render_reference(
        ctx,
        scene,
        &settings,
        crate::api::Budget::Samples(g.reference_spp),
        g.dispatch_spp,
    )?;
    eprintln!("reference: {} spp in {:.1} s", stats.spp, t.elapsed().as_secs_f64());
    reference::write_exr(&path, &film, &reference::header_attributes(&g.scene_spec(), &settings, &stats))?;
    Ok((film.mean, path.display().to_string(), Some(stats.spp)))
}

pub(super) fn run_group(ctx: &GpuContext, g: &BenchGroup, refs: &Path) -> Result<GroupResult, LabError> {
    let scene = g.scene_spec().load(crate::gpu::chosen_adapter_storage_limit())?;
    let sized;
    let g = match (g.scene_film_size, scene.film_size) {
        (true, Some([width, height])) => {
            eprintln!("note: image size {width}x{height} from the scene file (--width/--height override it)");
            sized = BenchGroup { width, height, ..g.clone() };
            &sized
        }
        _ => g,
    };
    let (reference, ref_name, reference_spp) = group_reference(ctx, g, &scene, refs)?;
    let (rows, heatmaps) = run_configurations(ctx, g, &scene, &reference)?;
    Ok(GroupResult { group: g.clone(), rows, heatmaps, reference: ref_name, reference_spp })
}

/// Every configuration of group `g` (its film size already resolved) over the ladder and the seeds, measured
/// against `reference`: the rows, and per configuration the mean per-pixel relMSE at the last point.
#[allow(clippy::type_complexity)]
pub fn run_configurations(
    ctx: &GpuContext,
    g: &BenchGroup,
    scene: &crate::scene::Scene,
    reference: &[[f32; 3]],
) -> Result<(Vec<BenchRow>, Vec<(String, Vec<f64>)>), LabError> {
    if reference.len() != (g.width * g.height) as usize {
        return Err(LabError::Input(format!(
            "the reference has {} pixels, the benchmark renders {}x{}",
            reference.len(),
            g.width,
            g.height
        )));
    }
    let configs = g.configurations();
    let data = SceneData::build(scene);
    let gpu_scene = GpuScene::upload(ctx, data).map_err(|e| LabError::Input(format!("{}: {e}", g.scene)))?;
    let mut renderer: Option<Renderer> = None;
    let mut rows = vec![];
    let mut heatmaps = vec![];
    let pixels = (g.width * g.height) as f64;
    for settings in &configs {
        let label = g.label(settings);
        // Compile (or find) the pipeline, then one warm-up sample; both timed apart from the measurements.
        let t0 = Instant::now();
        let r = match &mut renderer {
            Some(r) => {
                r.set_settings(settings.clone())?;
                r
            }
            None => renderer.insert(Renderer::new_unprepared(ctx, &gpu_scene, scene.camera.clone(), settings.clone())?),
        };
        r.prepare()?;
        r.warm_up(ctx).map_err(LabError::from)?;
        // The renderer's own dispatch size (as `mislab render` uses), unless the group fixes one.
        let mut dispatch_spp = if g.dispatch_spp > 0 { g.dispatch_spp } else { r.max_dispatch_spp() };
        let compile_seconds = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        r.render(ctx, 1).map_err(LabError::from)?;
        let warmup_seconds = t1.elapsed().as_secs_f64();
        eprintln!("{} / {label}: pipeline ready in {compile_seconds:.2} s, warm-up {warmup_seconds:.2} s", g.name);
        let mut sum_heat: Option<Vec<f64>> = None;
        let mut timer = GpuTimer::new(ctx, 64);
        for seed in 0..g.seeds {
            let mut attempt = 0;
            let seed_rows = loop {
                r.set_dispatch_spp(Some(dispatch_spp));
                match run_seed(ctx, r, &mut timer, g, settings, seed, reference) {
                    Ok(v) => break v,
                    Err(SeedError::Incomplete(spp)) if dispatch_spp > 1 && attempt < 8 => {
                        dispatch_spp /= 2;
                        attempt += 1;
                        eprintln!("  lavapipe's loop budget dropped samples at {spp} spp; retrying with {dispatch_spp} spp per dispatch");
                    }
                    Err(SeedError::Incomplete(spp)) => {
                        return Err(LabError::Input(format!(
                            "{label}: pixels miss samples at {spp} spp even with 1 spp per dispatch"
                        )))
                    }
                    Err(SeedError::Other(e)) => return Err(e),
                }
            };
            for (point, heat) in seed_rows {
                let seconds = point.timing.seconds();
                let m = point.metrics;
                rows.push(BenchRow {
                    group: g.name.clone(),
                    config: label.clone(),
                    scene: g.scene.clone(),
                    mode: settings.mode.name().into(),
                    strategy: settings.strategy.name().into(),
                    sampler: settings.sampler.name().into(),
                    heuristic: settings.heuristic.name().into(),
                    light_sampling: settings.light_sampling.name().into(),
                    env_sampling: settings.env_sampling.name().into(),
                    light_select: settings.light_select.name().into(),
                    mis: settings.mis.name().into(),
                    rr_depth: settings.rr_depth,
                    width: g.width,
                    height: g.height,
                    spp: point.spp,
                    seed,
                    seconds_gpu: seconds,
                    seconds_wall: point.timing.wall,
                    rmse: m.rmse,
                    relmse: m.relmse,
                    mae: m.mae,
                    efficiency: metrics::efficiency(m.relmse, seconds),
                    efficiency_wall: metrics::efficiency(m.relmse, point.timing.wall),
                    samples_per_second: pixels * point.spp as f64 / seconds.max(1e-12),
                    mrays_per_second: point.timing.rays as f64 / seconds.max(1e-12) / 1e6,
                    rays: point.timing.rays,
                    compile_seconds: if seed == 0 { compile_seconds } else { 0.0 },
                    warmup_seconds: if seed == 0 { warmup_seconds } else { 0.0 },
                    dispatch_spp,
                    nonfinite: point.nonfinite,
                });
                if let Some(h) = heat {
                    match &mut sum_heat {
                        Some(s) => s.iter_mut().zip(&h).for_each(|(a, b)| *a += b),
                        None => sum_heat = Some(h),
                    }
                }
            }
        }
        // The mean over seeds at the last point, as summary.md reports it (not the last seed's).
        let s = summarize(&rows.iter().filter(|r| r.config == label).collect::<Vec<_>>());
        let i = s.spp.len() - 1;
        eprintln!(
            "  {label}: {} spp: relMSE {:.3e} (mean of {} seeds), {:.3} s GPU, {:.2} M samples/s, {} NaN/Inf samples",
            s.spp[i],
            s.relmse[i][0],
            g.seeds,
            s.seconds[i],
            s.samples_per_second / 1e6,
            s.nonfinite
        );
        if let Some(mut h) = sum_heat {
            h.iter_mut().for_each(|v| *v /= g.seeds as f64);
            heatmaps.push((label, h));
        }
    }
    Ok((rows, heatmaps))
}

struct Point {
    spp: u32,
    timing: Timing,
    metrics: ErrorMetrics,
    /// NaN/Inf samples in the image at this point (counted on the device).
    nonfinite: u64,
}

enum SeedError {
    /// Some pixel holds fewer samples than dispatched (at this spp).
    Incomplete(u32),
    Other(LabError),
}

impl<E: Into<LabError>> From<E> for SeedError {
    fn from(e: E) -> Self {
        SeedError::Other(e.into())
    }
}

/// One configuration and seed over the ladder (or the time budget). Progressive samplers render the ladder as
/// prefixes of one run; fixed-count ones (stratified, Hammersley) render each point afresh with their target
/// set to it. Returns the points, the last one with its per-pixel relMSE.
#[allow(clippy::type_complexity)]
fn run_seed(
    ctx: &GpuContext,
    r: &mut Renderer,
    timer: &mut Option<GpuTimer>,
    g: &BenchGroup,
    settings: &Settings,
    seed: u32,
    reference: &[[f32; 3]],
) -> Result<Vec<(Point, Option<Vec<f64>>)>, SeedError> {
    r.set_settings(Settings { seed, ..settings.clone() })?;
    let fixed = samplers::is_fixed_count(settings.sampler);
    let ladder: Vec<u32> = match g.time {
        Some(_) => (0..24).map(|k| 1u32 << k).collect(),
        None => g.spp.clone(),
    };
    let mut points: Vec<(Point, Option<Vec<f64>>)> = vec![];
    let mut cumulative = Timing { gpu: Some(0.0), ..Timing::default() };
    for (k, &requested) in ladder.iter().enumerate() {
        let spp = samplers::check_spp(settings.sampler, requested)?;
        if !fixed && spp < r.samples() {
            continue;
        }
        let timing = if fixed {
            r.reset();
            r.set_sampler_spp(spp);
            r.render_timed(ctx, spp, timer.as_mut())?
        } else {
            r.set_sampler_spp(samplers::DEFAULT_SAMPLER_SPP);
            let t = r.render_timed(ctx, spp - r.samples(), timer.as_mut())?;
            cumulative = Timing {
                gpu: cumulative.gpu.zip(t.gpu).map(|(a, b)| a + b),
                wall: cumulative.wall + t.wall,
                rays: cumulative.rays + t.rays,
            };
            cumulative
        };
        let film = r.film(ctx).map_err(LabError::from)?;
        if !film.is_complete(spp) {
            return Err(SeedError::Incomplete(spp));
        }
        let m = metrics::compare(&film.mean, reference)?;
        let last = match g.time {
            Some(t) => timing.seconds() >= t || k + 1 == ladder.len(),
            None => k + 1 == ladder.len(),
        };
        let heat = if last { Some(metrics::per_pixel_relmse(&film.mean, reference)?) } else { None };
        points.push((Point { spp, timing, metrics: m, nonfinite: film.nonfinite_total }, heat));
        if last {
            break;
        }
    }
    Ok(points)
}
