//! A render job: flags checked and turned into settings, a budget and the state file handling, before any scene or
//! device work (so a bad flag or a bad state file fails at once).

use super::budget::Budget;
use super::error::ApiError;
use super::flags::RenderFlags;
use super::scene::SceneHandle;
use crate::render::settings::Settings;
use crate::state::session::Session;
use crate::state::StateHeader;
use std::path::Path;

/// A render to do: the settings, the budget, and the state file it resumes from and writes, if any.
pub struct Job {
    /// The settings asked for (the film size may still come from the scene: `settings_for`).
    pub settings: Settings,
    /// When to stop.
    pub budget: Budget,
    /// Notes for the user about how the flags were read (a sample count rounded for a fixed-count sampler).
    pub notes: Vec<String>,
    /// Check after the render that every pixel got every sample, and redo it with smaller dispatches where a
    /// driver dropped some (lavapipe's per-invocation loop budget; references do this).
    pub verify_complete: bool,
    /// Seconds a submission should take (the observer is asked between submissions).
    pub submit_seconds: f64,
    /// Samples per pixel in one dispatch instead of the renderer's safe default for the mode.
    pub dispatch_spp: Option<u32>,
    pub(crate) session: Option<Session>,
}

impl Job {
    /// Checks `flags` and opens the state to resume, if any. `output` is the image the CLI writes: its name with
    /// `.state` is the default state file; without it, state flags need `state` (or `resume`) to name one.
    pub fn new(flags: &RenderFlags, output: Option<&Path>) -> Result<Job, ApiError> {
        flags.settings.validate().map_err(ApiError::Settings)?;
        let session = Session::open(&flags.state, flags.spp, output).map_err(ApiError::State)?;
        let resumed = session.as_ref().and_then(|s| s.resumed_header().map(|h| (s.path(), h)));
        let flags = match resumed {
            Some((path, saved)) => resume_defaults(flags, path, saved)?,
            None => flags.clone(),
        };
        let (budget, note) = flags.budget()?;
        Ok(Job {
            settings: flags.settings.clone(),
            budget,
            notes: note.into_iter().collect(),
            verify_complete: false,
            submit_seconds: super::drive::TARGET_SUBMIT_SECONDS,
            dispatch_spp: None,
            session,
        })
    }

    /// A job of `settings` to `budget`, with no state file (the lab's tools, which choose settings themselves).
    pub fn of(settings: Settings, budget: Budget) -> Result<Job, ApiError> {
        settings.validate().map_err(ApiError::Settings)?;
        Ok(Job {
            settings,
            budget,
            notes: vec![],
            verify_complete: false,
            submit_seconds: super::drive::TARGET_SUBMIT_SECONDS,
            dispatch_spp: None,
            session: None,
        })
    }

    /// A job from `(name, value)` pairs, named as the CLI's flags (see `RenderFlags::from_pairs`).
    pub fn from_pairs<K: AsRef<str>, V: AsRef<str>>(pairs: &[(K, V)]) -> Result<Job, ApiError> {
        Job::new(&RenderFlags::from_pairs(pairs)?, None)
    }

    /// The settings for `scene`: the scene file's image size (pbrt `Film`, Mitsuba `hdrfilm`) where the width and
    /// height were both left at their defaults, with a note saying so.
    pub fn settings_for(&self, scene: &SceneHandle) -> (Settings, Option<String>) {
        let mut settings = self.settings.clone();
        let default = Settings::default();
        match scene.film_size() {
            Some([w, h]) if settings.width == default.width && settings.height == default.height => {
                (settings.width, settings.height) = (w, h);
                (settings, Some(format!("image size {w}x{h} from the scene file (--width/--height override it)")))
            }
            _ => (settings, None),
        }
    }

    /// The state file this job writes, if it writes one.
    pub fn state_path(&self) -> Option<&Path> {
        self.session.as_ref().map(|s| s.path())
    }
}

/// The flags of a resumed render: the state's sample count and settings where the flags did not give them. A flag
/// given with another value than the state's is kept, and `Session::start` refuses the resume naming every
/// difference (the scene's too).
fn resume_defaults(flags: &RenderFlags, path: &Path, saved: &StateHeader) -> Result<RenderFlags, ApiError> {
    if flags.time.is_some() {
        return Err(ApiError::State(format!(
            "{}: a resumed render continues to the state's sample count ({} spp): --time cannot be given",
            path.display(),
            saved.spp_total
        )));
    }
    let map = |s: &Settings| match serde_json::to_value(s) {
        Ok(serde_json::Value::Object(m)) => m,
        _ => Default::default(),
    };
    let (asked, default) = (map(&flags.settings), map(&Settings::default()));
    let mut merged = map(&saved.settings);
    for (name, value) in asked {
        if flags.was_given(&name, default.get(&name) != Some(&value)) {
            merged.insert(name, value);
        }
    }
    let settings: Settings = serde_json::from_value(serde_json::Value::Object(merged))
        .map_err(|e| ApiError::State(format!("{}: the state's settings cannot be read: {e}", path.display())))?;
    settings.validate().map_err(|e| ApiError::State(format!("{}: {e}", path.display())))?;
    Ok(RenderFlags { spp: Some(flags.spp.unwrap_or(saved.spp_total)), settings, ..flags.clone() })
}
