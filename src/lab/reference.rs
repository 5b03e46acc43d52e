//! `mislab reference`: a converged reference image — MIS with the power heuristic and Owen-scrambled Sobol —
//! written as linear EXR whose header records the sample count, the render time, the scene and every setting
//! (custom attributes); and reading such references back for `mislab bench`.

pub use crate::api::header_attributes;
use crate::api::{Budget, RenderStats};
use crate::gpu::timer::GpuTimer;
use crate::gpu::GpuContext;
pub use crate::io::exr_image::ReferenceImage;
use crate::render::film::Film;
use crate::render::settings::*;
use crate::render::Renderer;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::scene::{Scene, SceneSpec};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Seed of references (distinct from the seeds 0, 1, … that `mislab bench` measures, so the reference's
/// error is independent of theirs).
pub const REFERENCE_SEED: u32 = 0x5eed_f00d;

/// `mislab reference` flags.
#[derive(clap::Args, Clone, Debug)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub scene: SceneSpec,
    /// Output EXR.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Replace the output file even if it is read-only.
    #[arg(long)]
    pub force: bool,
    /// Samples per pixel (this or --time is required).
    #[arg(long, conflicts_with = "time", required_unless_present = "time", value_parser = crate::io::cli_values::spp)]
    pub spp: Option<u32>,
    /// Render for this many seconds instead (after compilation; this or --spp is required).
    #[arg(long, value_parser = crate::io::cli_values::seconds)]
    pub time: Option<f64>,
    /// Image width [default: the scene file's Film / hdrfilm size, else 512].
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height [default: the scene file's Film / hdrfilm size, else 512].
    #[arg(long)]
    pub height: Option<u32>,
    /// direct or path.
    #[arg(long, value_enum, default_value_t = Mode::Direct)]
    pub mode: Mode,
    /// Maximum path length (path mode).
    #[arg(long, default_value_t = 8)]
    pub max_depth: u32,
    /// Area-light sampling inside MIS.
    #[arg(long, value_enum, default_value_t = LightSampling::SolidAngle)]
    pub light_sampling: LightSampling,
    /// Environment sampling inside MIS.
    #[arg(long, value_enum, default_value_t = EnvSampling::Importance)]
    pub env_sampling: EnvSampling,
    /// Light selection.
    #[arg(long, value_enum, default_value_t = LightSelect::Uniform)]
    pub light_select: LightSelect,
    /// Seed (0 to 4294967295). The default, 0x5eedf00d, differs from the seeds 0, 1, … that `mislab bench`
    /// measures, so the reference's own error is independent of theirs.
    #[arg(long, default_value_t = REFERENCE_SEED)]
    pub seed: u32,
    /// Render only the K-th (from 0) of N sample ranges of --spp into a state file (--state, default: the
    /// output's name with .state); `mislab merge` makes the reference of the parts (docs/cluster.md).
    #[arg(long, value_name = "K/N", value_parser = crate::state::session::parse_part, requires = "spp")]
    pub part: Option<(u32, u32)>,
    /// Also write the render state (for `mislab merge`) to this file.
    #[arg(long, value_name = "FILE", requires = "spp")]
    pub state: Option<PathBuf>,
}

/// The reference estimator for a film and mode: MIS (multi-sample, power heuristic, one light and one BSDF
/// sample), Owen-scrambled Sobol, `REFERENCE_SEED`.
pub fn reference_settings(base: &Settings) -> Settings {
    Settings {
        strategy: Strategy::Mis,
        heuristic: Heuristic::Power,
        power_beta: 2.0,
        mis: MisKind::Multi,
        light_samples: 1,
        bsdf_samples: 1,
        sampler: SamplerKind::Sobol,
        seed: REFERENCE_SEED,
        ..base.clone()
    }
}

/// Renders a reference to a budget in small, checked dispatches (see `bench`: lavapipe's loop budget).
pub fn render_reference(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &Settings,
    budget: Budget,
    dispatch_spp: u32,
) -> Result<(Film, RenderStats), String> {
    render_reference_from(
        ctx,
        SceneData::build(scene),
        scene,
        settings,
        budget,
        dispatch_spp,
        0,
        &AtomicBool::new(false),
    )
}

/// `render_reference` of the sample indices from `first` on (`--part`: `state::session::part_range`), with the
/// scene's data already built; it stops early with what has accumulated (`RenderStats::interrupted`) once `stop`
/// is set (Ctrl-C, SIGTERM, SIGHUP).
#[allow(clippy::too_many_arguments)]
pub fn render_reference_from(
    ctx: &GpuContext,
    data: SceneData,
    scene: &Scene,
    settings: &Settings,
    budget: Budget,
    dispatch_spp: u32,
    first: u32,
    stop: &AtomicBool,
) -> Result<(Film, RenderStats), String> {
    let gpu_scene = GpuScene::upload(ctx, data).map_err(|e| e.to_string())?;
    let mut r = Renderer::new(ctx, &gpu_scene, scene.camera.clone(), settings.clone())?;
    let mut dispatch = if dispatch_spp > 0 { dispatch_spp } else { r.max_dispatch_spp() };
    let pixels = settings.width as usize * settings.height as usize;
    for _attempt in 0..8 {
        r.restore(&vec![crate::gpu::types::GpuAccum::default(); pixels], first, 0, 0)?;
        r.set_dispatch_spp(Some(dispatch));
        let mut timer = GpuTimer::new(ctx, 64);
        let start = Instant::now();
        let (mut seconds, mut rays) = (0.0, 0u64);
        // Submissions of about a second, so a time budget is met closely.
        let mut chunk = dispatch;
        let mut interrupted = false;
        loop {
            if stop.load(Ordering::SeqCst) && r.samples() > first {
                interrupted = true;
                break;
            }
            let n = match budget {
                Budget::Samples(total) => chunk.min(total - (r.samples() - first)),
                Budget::Time(t) => {
                    if r.samples() > first && start.elapsed() >= t {
                        0
                    } else {
                        chunk
                    }
                }
            };
            if n == 0 {
                break;
            }
            let t = r.render_timed(ctx, n, timer.as_mut())?;
            seconds += t.wall;
            rays += t.rays;
            if t.wall < 0.5 {
                chunk = (chunk * 2).min(1 << 16);
            }
            if let Budget::Time(limit) = budget {
                let per = seconds / (r.samples() - first) as f64;
                let left = limit.saturating_sub(start.elapsed()).as_secs_f64();
                chunk = chunk.min(((left / per.max(1e-9)).ceil() as u32).max(1));
            }
        }
        let film = r.film(ctx).map_err(|e| e.to_string())?;
        if film.is_complete(r.samples() - first) {
            let spp = r.samples() - first;
            let stats = RenderStats { spp, extra_rows: 0, seconds, rays, nonfinite: r.nonfinite_total(), interrupted };
            return Ok((film, stats));
        }
        if dispatch == 1 {
            break;
        }
        dispatch /= 2;
        eprintln!("reference: lavapipe's loop budget dropped samples; retrying with {dispatch} spp per dispatch");
    }
    Err("pixels miss samples even with 1 spp per dispatch".into())
}

/// Writes `film` as linear float EXR with `attributes` (see `header_attributes`) as text attributes.
pub fn write_exr(path: &Path, film: &Film, attributes: &[(String, String)]) -> Result<(), String> {
    crate::io::exr_image::write(path, film.pixels(), attributes)
}

/// Reads a reference: a linear image (EXR from mislab or elsewhere), or a render state (`mislab merge`'s merged
/// state, or a whole render's), with the attributes `write_exr` records where present.
pub fn read_exr(path: &Path) -> Result<ReferenceImage, String> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("state")) {
        return crate::state::RenderState::read(path).map(|s| s.reference_image());
    }
    crate::io::exr_image::read(path)
}

/// The image size from --width/--height and the scene's Film size: a flag given wins; with neither given the
/// scene's size is used (with a note); one flag alone keeps the other at 512 (it is not derived from the aspect).
pub fn film_size(width: Option<u32>, height: Option<u32>, scene: Option<[u32; 2]>) -> [u32; 2] {
    match (width, height, scene) {
        (None, None, Some([w, h])) => {
            eprintln!("note: image size {w}x{h} from the scene file (--width/--height override it)");
            [w, h]
        }
        (w, h, _) => [w.unwrap_or(512), h.unwrap_or(512)],
    }
}

/// Runs `mislab reference`; returns the exit code (0, or 130 when interrupted after writing what it had).
pub fn run(args: &ReferenceArgs) -> Result<u8, String> {
    let ext = args.output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if ext.as_deref() != Some("exr") {
        return Err(format!("{}: a reference is written as .exr", args.output.display()));
    }
    // Before any work: an unwritable output would otherwise be found after the render.
    let target = crate::io::output_file::check(&args.output, args.force)?;
    let budget = match (args.spp, args.time) {
        (Some(0), _) => return Err("--spp must be at least 1".into()),
        (Some(n), _) => Budget::Samples(n),
        (None, Some(t)) if t.is_finite() && t > 0.0 => Budget::Time(Duration::from_secs_f64(t)),
        (None, Some(t)) => return Err(format!("--time {t} must be a positive number of seconds")),
        (None, None) => return Err("give --spp N or --time SECONDS".into()),
    };
    // The scene first: a bad file is reported without waiting for a device, and its Film size is the default.
    let scene = args.scene.load()?;
    let [width, height] = film_size(args.width, args.height, scene.film_size);
    let base = Settings {
        width,
        height,
        mode: args.mode,
        max_depth: args.max_depth,
        light_sampling: args.light_sampling,
        env_sampling: args.env_sampling,
        light_select: args.light_select,
        ..Settings::default()
    };
    let settings = Settings { seed: args.seed, ..reference_settings(&base) };
    settings.validate()?;
    // Ctrl-C, SIGTERM and SIGHUP stop the render; what has accumulated is written and marked interrupted.
    let stop = Arc::new(AtomicBool::new(false));
    {
        let flag = stop.clone();
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    let ctx = GpuContext::new().map_err(|e| e.to_string())?;
    eprintln!("adapter: {} ({:?})", ctx.info.name, ctx.info.device_type);
    let t = Instant::now();
    let data = SceneData::build(&scene);
    let scene_hash = crate::state::scene_hash(&data, &scene.camera);
    let total = args.spp.unwrap_or(0);
    let range = args.part.map_or((0, total), |(k, n)| crate::state::session::part_range(k, n, total));
    let budget = if args.part.is_some() { Budget::Samples(range.1 - range.0) } else { budget };
    // (Without --part a --time budget has no sample count: the range is unused.)
    if args.part.is_some() && range.0 == range.1 {
        return Err(format!("--part of --spp {total} holds no samples (use at most {total} parts)"));
    }
    let (film, stats) = render_reference_from(&ctx, data, &scene, &settings, budget, 0, range.0, &stop)?;
    let attributes = header_attributes(&args.scene, &settings, &stats);
    film.save_to(&target, 0.0, crate::render::film::Tonemap::Clamp, &attributes)?;
    if (args.part.is_some() || args.state.is_some()) && !stats.interrupted {
        let header = crate::state::StateHeader {
            scene: args.scene.scene.clone(),
            scene_hash,
            settings: settings.clone(),
            seed: settings.seed,
            spp_total: total,
            sampler_spp: crate::render::samplers::DEFAULT_SAMPLER_SPP,
            part: args.part,
            range,
            next: range.1,
            nonfinite_total: stats.nonfinite,
            rays_total: stats.rays,
            seconds: stats.seconds,
            mislab_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        let path = args.state.clone().unwrap_or_else(|| args.output.with_extension("state"));
        crate::state::RenderState::from_film(header, &film).write(&path)?;
        eprintln!("wrote state {} (samples {}..{})", path.display(), range.0, range.1);
    }
    let pixels = (settings.width * settings.height) as f64;
    eprintln!(
        "{} spp in {:.2} s ({:.2} s with compilation): {:.2} M samples/s, {} NaN/Inf samples; wrote {}",
        stats.spp,
        stats.seconds,
        t.elapsed().as_secs_f64(),
        stats.spp as f64 * pixels / stats.seconds.max(1e-9) / 1e6,
        stats.nonfinite,
        args.output.display()
    );
    if stats.interrupted {
        eprintln!(
            "interrupted: wrote the {} samples per pixel accumulated so far (the header says interrupted = true)",
            stats.spp
        );
        return Ok(130);
    }
    Ok(0)
}
