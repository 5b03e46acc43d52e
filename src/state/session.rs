//! The render command's state flags (`--state`, `--checkpoint-every`, `--resume`, `--part`): which sample
//! indices this run renders, restoring a saved state into the renderer, and writing checkpoints while it renders.

use super::{RenderState, StateError, StateHeader};
use crate::gpu::types::GpuAccum;
use crate::gpu::GpuContext;
use crate::render::settings::Settings;
use crate::render::{RenderError, Renderer};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// `mislab render` flags for state files, checkpoints and parts.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct StateArgs {
    /// Write the render state (raw per-pixel accumulators + header) to this file at the end (and at every
    /// checkpoint); default with --part or --checkpoint-every: the output's name with extension .state.
    #[arg(long, value_name = "FILE")]
    pub state: Option<PathBuf>,
    /// Write the state atomically every SECONDS (fractions allowed) while rendering.
    #[arg(long, value_name = "SECONDS")]
    pub checkpoint_every: Option<f64>,
    /// Continue the render saved in STATE (same scene, settings and --spp), checkpointing on into it unless
    /// --state names another file. The result equals the uninterrupted render bit for bit.
    #[arg(long, value_name = "STATE")]
    pub resume: Option<PathBuf>,
    /// Render only the K-th (from 0) of N disjoint ranges of the --spp sample indices; `mislab merge` combines
    /// the N state files.
    #[arg(long, value_name = "K/N", value_parser = parse_part)]
    pub part: Option<(u32, u32)>,
}

/// Parses `K/N` with 0 ≤ K < N.
pub fn parse_part(s: &str) -> Result<(u32, u32), String> {
    let (k, n) = s.split_once('/').ok_or_else(|| format!("--part {s}: expected K/N, e.g. 0/4"))?;
    let k: u32 = k.trim().parse().map_err(|_| format!("--part {s}: K must be a whole number"))?;
    let n: u32 = n.trim().parse().map_err(|_| format!("--part {s}: N must be a whole number"))?;
    if n == 0 || k >= n {
        return Err(format!("--part {s}: needs 0 <= K < N (parts are numbered from 0, like Slurm array tasks)"));
    }
    Ok((k, n))
}

/// The sample indices `[start, end)` of part `k` of `n` of a `total`-sample render (sizes differ by at most one).
pub fn part_range(k: u32, n: u32, total: u32) -> (u32, u32) {
    let at = |i: u32| (i as u64 * total as u64 / n as u64) as u32;
    (at(k), at(k + 1))
}

impl StateArgs {
    /// Whether any state flag was given.
    pub fn active(&self) -> bool {
        self.state.is_some() || self.checkpoint_every.is_some() || self.resume.is_some() || self.part.is_some()
    }
}

/// One render run's state handling.
pub struct Session {
    path: PathBuf,
    every: Option<Duration>,
    part: Option<(u32, u32)>,
    resumed: Option<RenderState>,
    header: Option<StateHeader>,
    seconds_before: f64,
}

impl Session {
    /// Checks the flags and reads the state to resume (before any scene or device work, so a bad state file
    /// fails fast). `spp` is the render's --spp, `output` its image (whose name with `.state` is the default
    /// state file; without one, --state or --resume must name the file).
    pub fn open(args: &StateArgs, spp: Option<u32>, output: Option<&Path>) -> Result<Option<Session>, StateError> {
        if !args.active() {
            return Ok(None);
        }
        // The state to resume first: it says the render's sample count and part, and a bad file is reported as such.
        let resumed = args.resume.as_deref().map(RenderState::read).transpose()?;
        if spp.is_none() && resumed.is_none() {
            return Err(StateError::Flags("--state, --checkpoint-every and --part need --spp N (the sample range a state holds is fixed by it; --time is not reproducible)".into()));
        }
        let every = match args.checkpoint_every {
            None => None,
            Some(t) if t.is_finite() && t > 0.0 => Some(Duration::from_secs_f64(t)),
            Some(t) => {
                return Err(StateError::Flags(format!("--checkpoint-every {t} must be a positive number of seconds")))
            }
        };
        let path = match (args.state.clone().or_else(|| args.resume.clone()), output) {
            (Some(path), _) => path,
            (None, Some(output)) => output.with_extension("state"),
            (None, None) => {
                return Err(StateError::Flags(
                    "--part and --checkpoint-every need --state FILE (the state file to write)".into(),
                ))
            }
        };
        check_state_path(&path, output)?;
        // A resumed part stays that part unless --part says otherwise (then `start` refuses a mismatch by name).
        let part = args.part.or(resumed.as_ref().and_then(|r| r.header.part));
        Ok(Some(Session { path, every, part, resumed, header: None, seconds_before: 0.0 }))
    }

    /// The header of the state this run resumes, if it resumes one (its settings and sample count are the run's
    /// defaults: `api::Job`).
    pub fn resumed_header(&self) -> Option<&StateHeader> {
        self.resumed.as_ref().map(|r| &r.header)
    }

    /// The state file this run writes.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Puts `renderer` at this run's first sample: the resumed state's accumulators and next index, or an empty
    /// film at the start of the part. Refuses a resumed state of another scene or other settings, naming each
    /// difference. Call after `set_sampler_spp` (which resets).
    pub fn start(
        &mut self,
        renderer: &mut Renderer,
        scene: &str,
        scene_hash: String,
        settings: &Settings,
        spp_total: u32,
        sampler_spp: u32,
    ) -> Result<(), StateError> {
        let range = match self.part {
            Some((k, n)) => part_range(k, n, spp_total),
            None => (0, spp_total),
        };
        if range.0 == range.1 {
            let (k, n) = self.part.unwrap_or((0, 1));
            return Err(StateError::Flags(format!(
                "--part {k}/{n} of --spp {spp_total} holds no samples (use at most {spp_total} parts)"
            )));
        }
        let header = StateHeader {
            scene: scene.to_string(),
            scene_hash,
            settings: settings.clone(),
            seed: settings.seed,
            spp_total,
            sampler_spp,
            part: self.part,
            range,
            next: range.0,
            nonfinite_total: 0,
            rays_total: 0,
            seconds: 0.0,
            mislab_version: env!("CARGO_PKG_VERSION").to_string(),
        };
        match self.resumed.take() {
            Some(state) => {
                let name = self.resume_name();
                if let Some(d) = state.header.differences(&header) {
                    return Err(StateError::Mismatch(format!(
                        "{name}: cannot resume: the state is of a different render (saved vs this command): {d}"
                    )));
                }
                if state.header.part != header.part || state.header.range != header.range {
                    return Err(StateError::Mismatch(format!(
                        "{name}: cannot resume: the state holds part {:?} (samples {:?}), this command renders part {:?} (samples {:?})",
                        state.header.part, state.header.range, header.part, header.range
                    )));
                }
                renderer.restore(
                    &state.accum,
                    state.header.next,
                    state.header.nonfinite_total,
                    state.header.rays_total,
                )?;
                eprintln!(
                    "resuming {name}: samples {}..{} of {}..{} done",
                    state.header.range.0, state.header.next, range.0, range.1
                );
                self.seconds_before = state.header.seconds;
                self.header = Some(StateHeader { next: state.header.next, ..header });
            }
            None => {
                let pixels = (settings.width * settings.height) as usize;
                renderer.restore(&vec![GpuAccum::default(); pixels], range.0, 0, 0)?;
                self.header = Some(header);
            }
        }
        Ok(())
    }

    fn resume_name(&self) -> String {
        self.path.display().to_string()
    }

    /// How often to checkpoint, if at all.
    pub fn every(&self) -> Option<Duration> {
        self.every
    }

    /// Sample indices `[start, end)` of this run's file.
    pub fn range(&self) -> (u32, u32) {
        self.header.as_ref().map_or((0, 0), |h| h.range)
    }

    /// Writes the renderer's current state to the state file (atomically).
    pub fn save(&self, ctx: &GpuContext, renderer: &Renderer, seconds: f64) -> Result<(), StateError> {
        let header = self.header.as_ref().expect("Session::save is called after Session::start");
        let film = renderer.film(ctx).map_err(RenderError::from)?;
        let header = StateHeader {
            next: renderer.samples(),
            nonfinite_total: renderer.nonfinite_total(),
            rays_total: renderer.rays_total(),
            seconds: self.seconds_before + seconds,
            ..header.clone()
        };
        RenderState::from_film(header, &film).write(&self.path)
    }
}

/// Refuses a state path that is the output image too (the image written after the state would replace it) or that
/// is something other than a regular file (a directory, FIFO or device cannot hold a state, and a FIFO would block).
fn check_state_path(path: &Path, output: Option<&Path>) -> Result<(), StateError> {
    if let Some(output) = output {
        if same_file(path, output) {
            return Err(StateError::Path(format!(
                "{}: the state file and the output image are the same file (the image would overwrite the state); \
                 name the state with --state",
                path.display()
            )));
        }
    }
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => {
            let kind = if m.is_dir() { "a directory" } else { "not a regular file (a FIFO, socket or device)" };
            Err(StateError::Path(format!("{}: is {kind}; a render state is written to a regular file", path.display())))
        }
        _ => Ok(()),
    }
}

/// Whether two paths name the same file, whether or not it exists yet (their folders resolved, links followed).
fn same_file(a: &Path, b: &Path) -> bool {
    let resolve = |p: &Path| -> PathBuf {
        if let Ok(c) = p.canonicalize() {
            return c;
        }
        let parent = p.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        match (parent.canonicalize(), p.file_name()) {
            (Ok(d), Some(n)) => d.join(n),
            _ => p.to_path_buf(),
        }
    };
    resolve(a) == resolve(b)
}
