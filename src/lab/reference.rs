//! `mislab reference`: a converged reference image — MIS with the power heuristic and Owen-scrambled Sobol —
//! written as linear EXR whose header records the sample count, the render time, the scene and every setting
//! (custom attributes); and reading such references back for `mislab bench`.

pub use crate::api::header_attributes;
use crate::api::{self, Budget, RenderStats};
use crate::gpu::GpuContext;
pub use crate::io::exr_image::ReferenceImage;
use crate::lab::LabError;
use crate::render::film::Film;
use crate::render::settings::*;
use crate::scene::{Scene, SceneSpec};
use crate::state::session::StateArgs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

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

/// Renders a reference of `scene` with `settings` to a budget, every pixel checked to hold every sample (dispatches
/// halved where a driver dropped some; `dispatch_spp` 0 = the renderer's default for the mode).
pub fn render_reference(
    ctx: &GpuContext,
    scene: &Scene,
    settings: &Settings,
    budget: Budget,
    dispatch_spp: u32,
) -> Result<(Film, RenderStats), LabError> {
    let lab = api::Lab::on(ctx);
    let handle = api::SceneHandle::from_scene(SceneSpec::named(&scene.name), scene.clone());
    let mut job = api::Job::of(settings.clone(), budget)?;
    job.verify_complete = true;
    job.dispatch_spp = (dispatch_spp > 0).then_some(dispatch_spp);
    let image = api::render(&lab, &handle, &mut job, &mut api::Unobserved)?;
    Ok((image.film, image.stats))
}

/// Writes `film` as linear float EXR with `attributes` (see `header_attributes`) as text attributes.
pub fn write_exr(path: &Path, film: &Film, attributes: &[(String, String)]) -> Result<(), LabError> {
    Ok(crate::io::exr_image::write(path, film.pixels(), attributes)?)
}

/// Reads a reference: a linear image (EXR from mislab or elsewhere), or a render state (`mislab merge`'s merged
/// state, or a whole render's), with the attributes `write_exr` records where present.
pub fn read_exr(path: &Path) -> Result<ReferenceImage, LabError> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("state")) {
        return Ok(crate::state::RenderState::read(path).map(|s| s.reference_image())?);
    }
    Ok(crate::io::exr_image::read(path)?)
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
pub fn run(args: &ReferenceArgs) -> Result<u8, LabError> {
    let ext = args.output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    if ext.as_deref() != Some("exr") {
        return Err(LabError::Input(format!("{}: a reference is written as .exr", args.output.display())));
    }
    // Before any work: an unwritable output would otherwise be found after the render.
    let target = crate::io::output_file::check(&args.output, args.force)?;
    if args.spp.is_none() && args.time.is_none() {
        return Err(LabError::Input("give --spp N or --time SECONDS".into()));
    }
    // The scene first: a bad file is reported without waiting for a device, and its Film size is the default.
    let scene = args.scene.load(crate::gpu::chosen_adapter_storage_limit())?;
    let [width, height] = film_size(args.width, args.height, scene.film_size);
    let scene = Scene { film_size: None, ..scene };
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
    // A part or --state writes the render state as `mislab render --part` does (`mislab merge` reads both).
    let flags = api::RenderFlags {
        spp: args.spp,
        time: args.time,
        settings: settings.clone(),
        state: StateArgs { state: args.state.clone(), part: args.part, ..StateArgs::default() },
        given: None,
    };
    let mut job = api::Job::new(&flags, Some(&args.output))?;
    job.verify_complete = true;
    let lab = api::Lab::open()?;
    eprintln!("adapter: {}", lab.adapter());
    let t = Instant::now();
    let handle = api::SceneHandle::from_scene(args.scene.clone(), scene);
    let image =
        api::render(&lab, &handle, &mut job, &mut api::Callbacks { progress: |_: &api::Progress| {}, stop: &stop })?;
    let stats = &image.stats;
    if stats.interrupted && stats.spp == 0 {
        eprintln!("interrupted before the first sample per pixel: no reference was written");
        return Ok(130);
    }
    image.save_to(&target, crate::render::film::Tonemap::Clamp)?;
    if let Some(path) = job.state_path() {
        eprintln!("wrote state {} (samples {}..{})", path.display(), image.sample_range.0, image.sample_range.1);
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
