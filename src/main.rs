//! The `mislab` command line: render, info (and the subcommands later issues add).

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use mislab::api::SceneSpec;
use mislab::api::{self, Tonemap};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Exit code for bad input, a missing GPU, or a scene the device cannot hold.
const EXIT_BAD_INPUT: u8 = 2;
/// Exit code after Ctrl-C (the partial image is still written).
const EXIT_INTERRUPTED: u8 = 130;
/// What a signal during start-up (before any sample) leaves: nothing, said plainly.
const STARTUP_INTERRUPTED: &str =
    "interrupted during start-up, before any sample was rendered: no image was written (exit code 130)";

#[derive(Parser)]
#[command(
    name = "mislab",
    version,
    about = "A GPU Monte Carlo renderer for seeing, measuring and trusting sampling strategies"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene progressively to PNG (tonemapped) or EXR (linear radiance).
    Render(RenderArgs),
    /// Render a high-quality reference (MIS, Sobol) to EXR; the header records spp and settings.
    // clap's own usage line would show --spp as required and hide --time, its equal alternative.
    #[command(override_usage = "mislab reference [SCENE] -o <OUTPUT> (--spp <N> | --time <SECONDS>) [OPTIONS]")]
    Reference(mislab::lab::reference::ReferenceArgs),
    /// Combine the state files of `render --part K/N` runs into one image and state; --status DIR reports progress.
    Merge(mislab::state::merge::MergeArgs),
    /// Compare an image with a reference: mean ratio and relMSE of N×N-block means, per channel.
    Compare(mislab::lab::compare::CompareArgs),
    /// Run time against error: configurations × spp ladder × seeds, CSV/JSON and plots.
    Bench(mislab::lab::bench::BenchArgs),
    /// Open the interactive viewer: the image converges while a panel switches estimators live.
    View(mislab::viewer::ViewArgs),
    /// Reproduce a lecture figure: veach (light / BSDF / balance / power), area-vs-cosine, samplers.
    Figure(mislab::lab::figure::FigureArgs),
    /// Run the numerical stress suite (extreme scales, angles, lights, degenerate geometry, broken
    /// environment maps, extreme sample statistics) and print a table; exit 1 if any case fails.
    Stress {
        /// Only the cases whose name or group contains this text.
        #[arg(long)]
        filter: Option<String>,
    },
    /// Print the Vulkan adapters, the chosen one and its limits; with a scene, its statistics.
    Info {
        /// A scene file or built-in name.
        scene: Option<String>,
    },
}

#[derive(Args, Clone)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneSpec,
    /// Output file; .png (sRGB, tonemapped) or .exr (linear float32 RGB). Both record spp, seed, scene and
    /// settings in their header; the image is written through a temporary file, and a symlink through.
    #[arg(short, long, default_value = "render.png")]
    output: PathBuf,
    /// Replace the output file even if it is read-only.
    #[arg(long)]
    force: bool,
    /// Tonemapper for PNG output.
    #[arg(long, value_enum, default_value_t = Tonemap::Clamp)]
    tonemap: Tonemap,
    /// Budget, estimator settings and state files: the same names as the viewer panel, benchmark files and
    /// Python's keyword arguments.
    #[command(flatten)]
    flags: api::RenderFlags,
}

impl Default for RenderArgs {
    fn default() -> Self {
        RenderArgs::parse_from_default()
    }
}

impl RenderArgs {
    fn parse_from_default() -> Self {
        #[derive(Parser)]
        struct Wrapper {
            #[command(flatten)]
            args: RenderArgs,
        }
        Wrapper::parse_from(["mislab"]).args
    }
}

/// An error with the exit code it should produce. The library's layers return their own error types; here, at
/// the command line, they all become one `anyhow::Error` to print.
struct Failure {
    code: u8,
    error: anyhow::Error,
}

/// Bad input (a file, a flag, a device that cannot do it): exit code 2.
fn bad(error: impl Into<anyhow::Error>) -> Failure {
    Failure { code: EXIT_BAD_INPUT, error: error.into() }
}

/// `bad` for the command line's own messages.
fn bad_input(message: String) -> Failure {
    bad(anyhow::anyhow!(message))
}

fn main() -> ExitCode {
    let matches = Cli::command().get_matches();
    let cli = Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit());
    let result = match cli.command.unwrap_or(Command::Render(RenderArgs::default())) {
        Command::Render(mut args) => {
            // Which flags were typed: a resumed render takes the others from its state file.
            let given = matches.subcommand_matches("render").map_or_else(Vec::new, |m| {
                m.ids()
                    .filter(|id| m.value_source(id.as_str()) == Some(clap::parser::ValueSource::CommandLine))
                    .map(|id| id.as_str().to_string())
                    .collect()
            });
            args.flags.given = Some(given);
            render(args)
        }
        Command::Info { scene } => info(scene),
        Command::View(args) => mislab::viewer::run(args).map(|_| 0).map_err(bad),
        Command::Reference(args) => mislab::lab::reference::run(&args).map_err(bad),
        Command::Merge(args) => mislab::state::merge::run(&args).map_err(bad),
        Command::Compare(args) => mislab::lab::compare::run(&args).map_err(bad),
        Command::Bench(args) => mislab::lab::bench::run(&args).map(|_| 0).map_err(bad),
        Command::Stress { filter } => stress(filter.as_deref()),
        Command::Figure(args) => mislab::lab::figure::run(&args).map(|_| 0).map_err(bad),
    };
    match result {
        Ok(code) => ExitCode::from(code),
        Err(f) => {
            eprintln!("error: {}", f.error);
            ExitCode::from(f.code)
        }
    }
}

fn stress(filter: Option<&str>) -> Result<u8, Failure> {
    let lab = api::Lab::open().map_err(bad)?;
    eprintln!("adapter: {}", lab.adapter());
    let outcomes =
        mislab::lab::stress::run(lab.gpu(), filter, |o| eprintln!("{}", mislab::lab::stress::progress_line(o)))
            .map_err(bad)?;
    if outcomes.is_empty() {
        return Err(bad_input(format!("--filter '{}' matches no stress case", filter.unwrap_or_default())));
    }
    println!("{}", mislab::lab::stress::table(&outcomes));
    let failed = outcomes.iter().filter(|o| !o.pass).count();
    println!(
        "{} cases, {} passed, {} failed, {} NaN/Inf samples in all",
        outcomes.len(),
        outcomes.len() - failed,
        failed,
        outcomes.iter().map(|o| o.nonfinite).sum::<u64>()
    );
    Ok(if failed == 0 { 0 } else { 1 })
}

fn render(args: RenderArgs) -> Result<u8, Failure> {
    let ext = args.output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase());
    args.flags.settings.validate().map_err(bad)?;
    if !matches!(ext.as_deref(), Some("png") | Some("exr")) {
        return Err(bad_input(format!("{}: unknown output format (use .png or .exr)", args.output.display())));
    }
    // Before any work: a missing directory or a read-only file would otherwise be found after the render.
    let target = mislab::io::output_file::check(&args.output, args.force).map_err(bad)?;
    if ext.as_deref() == Some("exr") && args.flags.settings.exposure != 0.0 {
        eprintln!("note: --exposure is ignored for EXR output (linear radiance); it applies to PNG and the viewer");
    }
    // The flags and the state to resume first: a bad state file fails before any scene or device work.
    let mut job = api::Job::new(&args.flags, Some(&args.output)).map_err(bad)?;
    for note in &job.notes {
        eprintln!("note: {note}");
    }
    let t_start = Instant::now();
    // Catch Ctrl-C (and SIGTERM, SIGHUP: the ctrlc crate's `termination` feature) from the start: during
    // start-up it stops before rendering, afterwards it writes what has accumulated.
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupt.clone();
        let _ = ctrlc::set_handler(move || {
            // A second signal while start-up (a long load or shader compile) has not yet looked at the first:
            // stop now, and say why nothing was written.
            if flag.swap(true, Ordering::SeqCst) {
                eprintln!("{STARTUP_INTERRUPTED} (second signal)");
                std::process::exit(EXIT_INTERRUPTED as i32);
            }
        });
    }
    let startup_interrupted = || -> Option<u8> {
        interrupt.load(Ordering::SeqCst).then(|| {
            eprintln!("{STARTUP_INTERRUPTED}");
            EXIT_INTERRUPTED
        })
    };
    // The device opens on a second thread while the scene loads, and there builds the render pipeline the last
    // run of this command used (`Lab::build_forecast`): a repeated render then finds it ready.
    let command = forecast_command(&args.scene, &job.settings);
    let opening = Opening::start(command.clone());
    // A bad scene is reported without waiting for (or needing) a device.
    let scene = api::SceneHandle::load(&args.scene).map_err(bad)?;
    if let Some(code) = startup_interrupted() {
        return Ok(code);
    }
    let t_loaded = Instant::now();
    let lab = opening.lab().map_err(bad)?;
    if let Some(code) = startup_interrupted() {
        return Ok(code);
    }
    eprintln!("adapter: {}", lab.adapter());
    eprintln!("scene: {}", scene.summary());
    let t_device = Instant::now();
    for note in job.resolve(&scene) {
        eprintln!("note: {note}");
    }
    let settings = job.settings.clone();
    // Hidden until start-up is over (`CliObserver::started`).
    let length = match job.budget {
        api::Budget::Samples(n) => n as u64,
        api::Budget::Time(t) => (t.as_secs_f64() * 1000.0) as u64,
    };
    let bar = indicatif::ProgressBar::with_draw_target(Some(length), indicatif::ProgressDrawTarget::hidden());
    let pixels = (settings.width * settings.height) as f64;
    let mut observer = CliObserver {
        bar,
        budget: job.budget,
        state: job.state_path().is_some(),
        pixels,
        interrupt: &interrupt,
        started: |s: &api::Startup| {
            let bvh = scene.data().bvh_seconds;
            let load = (t_loaded - t_start).as_secs_f64();
            eprintln!(
                "start-up: {:.2} s (scene load {:.2} s, BVH {:.2} s, device {:.2} s, upload {:.2} s, pipeline {:.2} s, first dispatch {:.2} s) — not counted in the render time",
                (t_device - t_start).as_secs_f64() + s.seconds,
                (load - bvh).max(0.0),
                bvh,
                (t_device - t_loaded).as_secs_f64(),
                s.upload,
                s.pipeline,
                s.first_dispatch
            );
            if lab.forecasts_taken() > 0 {
                eprintln!(
                    "note: the render pipeline was built while the scene loaded (as this command's last run used)"
                );
            }
        },
    };
    let image = api::render(&lab, &scene, &mut job, &mut observer).map_err(bad)?;
    lab.save_forecast(&command);
    observer.bar.finish_and_clear();
    let stats = &image.stats;
    if stats.interrupted && stats.spp == 0 {
        // A signal during start-up or before the first whole sample: an empty image would be a lie.
        eprintln!("{STARTUP_INTERRUPTED} (before the first sample per pixel)");
        return Ok(EXIT_INTERRUPTED);
    }
    if let Some(path) = job.state_path() {
        eprintln!("wrote state {} (samples {}..{})", path.display(), image.sample_range.0, image.sample_range.1);
    }
    image.save_to(&target, args.tonemap).map_err(bad)?;
    let extra = if stats.extra_rows > 0 {
        format!(" (and one more in {} of {} rows)", stats.extra_rows, settings.height)
    } else {
        String::new()
    };
    let samples = stats.spp as f64 * pixels + (stats.extra_rows * settings.width) as f64;
    eprintln!(
        "{} spp in {:.2} s{extra}: {:.2} M samples/s, {:.2} Mrays/s, {} NaN/Inf samples",
        stats.spp,
        stats.seconds,
        samples / stats.seconds.max(1e-9) / 1e6,
        stats.rays as f64 / stats.seconds.max(1e-9) / 1e6,
        stats.nonfinite
    );
    if let (mislab::render::settings::EnvSampling::Auto, Some(p)) = (settings.env_sampling, image.sky_probe) {
        eprintln!(
            "env-sampling auto: {} (sky probe: the guide would draw {:.1} % of the first vertices' light samples; \
             it is used from {:.0} %)",
            if p.wants_guide() { "guided" } else { "importance" },
            100.0 * p.guided_share,
            100.0 * mislab::render::sky_probe::MIN_GUIDED_SHARE
        );
    }
    if let Some((guided, slots)) = image.guide_coverage {
        eprintln!("environment guide: {guided} of {slots} slots (region × normal) draw sky samples from it");
    }
    if stats.interrupted {
        eprintln!(
            "interrupted: wrote the {} samples per pixel accumulated so far to {}",
            stats.spp,
            args.output.display()
        );
        return Ok(EXIT_INTERRUPTED);
    }
    eprintln!("wrote {}", args.output.display());
    Ok(0)
}

/// The render command's observer: a progress bar (shown once sampling starts), the start-up line, and Ctrl-C.
struct CliObserver<'a, S: FnMut(&api::Startup)> {
    bar: indicatif::ProgressBar,
    budget: api::Budget,
    /// A state render counts its bar in sample indices (a resumed render starts where it stopped).
    state: bool,
    pixels: f64,
    interrupt: &'a AtomicBool,
    started: S,
}

impl<S: FnMut(&api::Startup)> api::Observer for CliObserver<'_, S> {
    fn started(&mut self, startup: &api::Startup) {
        (self.started)(startup);
        self.bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        self.bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
    }
    fn progress(&mut self, p: &api::Progress) {
        match self.budget {
            api::Budget::Samples(_) => self.bar.set_position(if self.state { p.sample_index } else { p.spp } as u64),
            api::Budget::Time(_) => self.bar.set_position((p.seconds * 1000.0) as u64),
        }
        let rate = p.spp as f64 * self.pixels / p.seconds.max(1e-9) / 1e6;
        self.bar.set_message(format!("{} spp, {rate:.2} M samples/s", p.spp));
    }
    fn stop_requested(&mut self) -> bool {
        self.interrupt.load(Ordering::SeqCst)
    }
}

fn info(scene_name: Option<String>) -> Result<u8, Failure> {
    println!("Vulkan adapters:");
    for a in api::adapters() {
        println!("  {a}");
    }
    let lab = api::Lab::open().map_err(bad)?;
    print!("chosen {}", lab.describe());
    if let Some(name) = scene_name {
        let scene = api::SceneHandle::named(&name).map_err(bad)?;
        for line in scene.report(&lab) {
            println!("{line}");
        }
    }
    Ok(0)
}

/// What tells one `mislab render`'s render pipeline from another's before its scene is loaded: the working
/// directory, the scene as named and the settings as given (`Lab::build_forecast`; the pipeline is only a
/// forecast, taken where the renderer's own request turns out equal).
fn forecast_command(scene: &mislab::scene::SceneSpec, settings: &mislab::render::settings::Settings) -> String {
    let cwd = std::env::current_dir().unwrap_or_default();
    format!("render\n{cwd:?}\n{scene:?}\n{settings:?}")
}

/// The device opening on a second thread, then building the forecast pipeline (`Lab::build_forecast`), while the
/// scene loads. However `render` ends, the thread is joined first (told to skip the forecast where the lab is not
/// taken): a process that exits while another thread is still loading the driver can abort in the driver's
/// static constructors (LLVM's "registered more than once"), and a bad scene must still end with exit code 2.
struct Opening {
    thread: Option<std::thread::JoinHandle<Result<api::Lab, api::ApiError>>>,
    cancel: Arc<AtomicBool>,
}

impl Opening {
    fn start(command: String) -> Opening {
        // The driver's environment variables are set here, before a second thread exists (`set_var` must not race
        // with another thread's `getenv`).
        mislab::gpu::prepare_driver_environment();
        let cancel = Arc::new(AtomicBool::new(false));
        let skip = cancel.clone();
        let thread = std::thread::spawn(move || {
            let lab = api::Lab::open()?;
            if !skip.load(Ordering::SeqCst) {
                lab.build_forecast(&command);
            }
            Ok(lab)
        });
        Opening { thread: Some(thread), cancel }
    }

    /// The opened lab (waiting for the thread).
    fn lab(mut self) -> Result<api::Lab, api::ApiError> {
        let thread = self.thread.take().expect("joined once");
        thread.join().unwrap_or_else(|_| Err(api::ApiError::Device("the device thread panicked".into())))
    }
}

impl Drop for Opening {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::SeqCst);
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}
