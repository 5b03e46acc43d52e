//! A render job: flags checked and turned into settings, a budget and the state file handling, before any scene or
//! device work (so a bad flag or a bad state file fails at once).

use super::budget::Budget;
use super::error::ApiError;
use super::flags::RenderFlags;
use super::scene::SceneHandle;
use crate::render::samplers::check_spp;
use crate::render::settings::{Mode, PixelFilter, SamplerKind, Settings};
use crate::state::session::Session;
use crate::state::StateError;
use crate::state::StateHeader;
use std::path::Path;

/// A render to do: the settings, the budget, and the state file it resumes from and writes, if any.
pub struct Job {
    /// The settings asked for (the scene file's own may still fill those not given: `resolve`).
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
    /// The flags given explicitly, where known (`RenderFlags::given`); None: a value equal to its default was not.
    given: Option<Vec<String>>,
    /// Whether the scene file's settings may fill the flags not given (not for the lab's own jobs).
    file_defaults: bool,
    /// Whether `resolve` has run.
    resolved: bool,
}

impl Job {
    /// Checks `flags` and opens the state to resume, if any. `output` is the image the CLI writes: its name with
    /// `.state` is the default state file; without it, state flags need `state` (or `resume`) to name one.
    pub fn new(flags: &RenderFlags, output: Option<&Path>) -> Result<Job, ApiError> {
        flags.settings.validate()?;
        let session = Session::open(&flags.state, flags.spp, output)?;
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
            given: flags.given.clone().or_else(|| {
                // Without the front end's list: spp and time count as given when set.
                Some(
                    [("spp", flags.spp.is_some()), ("time", flags.time.is_some())]
                        .iter()
                        .filter(|(_, set)| *set)
                        .map(|(n, _)| n.to_string())
                        .chain(non_default_settings(&flags.settings))
                        .collect(),
                )
            }),
            file_defaults: true,
            resolved: false,
            session,
        })
    }

    /// A job of `settings` to `budget`, with no state file (the lab's tools, which choose settings themselves).
    pub fn of(settings: Settings, budget: Budget) -> Result<Job, ApiError> {
        settings.validate()?;
        Ok(Job {
            settings,
            budget,
            notes: vec![],
            verify_complete: false,
            submit_seconds: super::drive::TARGET_SUBMIT_SECONDS,
            dispatch_spp: None,
            session: None,
            given: None,
            file_defaults: false,
            resolved: false,
        })
    }

    /// A job from `(name, value)` pairs, named as the CLI's flags (see `RenderFlags::from_pairs`).
    pub fn from_pairs<K: AsRef<str>, V: AsRef<str>>(pairs: &[(K, V)]) -> Result<Job, ApiError> {
        Job::new(&RenderFlags::from_pairs(pairs)?, None)
    }

    /// Takes the scene file's own settings where the flags did not give them: its image size (pbrt `Film`,
    /// Mitsuba `hdrfilm`), path tracing and its depth (pbrt `Integrator`, Mitsuba `<integrator>`), its sample count
    /// (pbrt `Sampler`, Mitsuba `<sampler>`). Returns a note per setting taken, saying where it came from. Runs once
    /// (`Render::begin` calls it; a front end may call it first to see the settings).
    pub fn resolve(&mut self, scene: &SceneHandle) -> Vec<String> {
        // A resumed render's settings are its state's (`resume_defaults`), whatever the file says.
        let resumed = self.session.as_ref().is_some_and(|s| s.resumed_header().is_some());
        if std::mem::replace(&mut self.resolved, true) || !self.file_defaults || resumed {
            return vec![];
        }
        let given = |name: &str| self.given.as_ref().is_some_and(|g| g.iter().any(|n| n == name));
        let mut notes = Vec::new();
        if let Some([w, h]) = scene.film_size() {
            if !given("width") && !given("height") {
                (self.settings.width, self.settings.height) = (w, h);
                notes.push(format!("image size {w}x{h} from the scene file (--width/--height override it)"));
            }
        }
        let file = &scene.scene().file_settings;
        // The sample count the sampler must fit: the one asked for, or else the file's.
        let spp = match self.budget {
            Budget::Samples(n) if given("spp") => Some(n),
            _ => file.spp.as_ref().map(|(n, _)| *n),
        };
        notes.extend(take_file_settings(&mut self.settings, file, &given, spp));
        if let Some((spp, source)) = &file.spp {
            if !given("spp") && !given("time") && self.session.is_none() {
                let used = check_spp(self.settings.sampler, *spp).unwrap_or(*spp);
                self.budget = Budget::Samples(used);
                notes.push(format!("--spp {used} from the scene file ({source}; --spp/--time override it)"));
            }
        }
        notes
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
        return Err(StateError::Flags(format!(
            "{}: a resumed render continues to the state's sample count ({} spp): --time cannot be given",
            path.display(),
            saved.spp_total
        ))
        .into());
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
        .map_err(|e| invalid_state(path, format!("its settings cannot be read: {e}")))?;
    settings.validate().map_err(|e| invalid_state(path, e.0))?;
    Ok(RenderFlags { spp: Some(flags.spp.unwrap_or(saved.spp_total)), settings, ..flags.clone() })
}

/// The settings whose value differs from the default (taken as given where the front end does not say).
fn non_default_settings(settings: &Settings) -> Vec<String> {
    let map = |s: &Settings| match serde_json::to_value(s) {
        Ok(serde_json::Value::Object(m)) => m,
        _ => Default::default(),
    };
    let default = map(&Settings::default());
    map(settings).into_iter().filter(|(k, v)| default.get(k) != Some(v)).map(|(k, _)| k).collect()
}

/// A state file whose header this mislab cannot use.
fn invalid_state(path: &Path, problem: String) -> ApiError {
    StateError::Invalid { file: path.display().to_string(), problem }.into()
}

/// Takes the render settings a scene file states (path tracing and its depth, the pixel filter, the sampler where
/// it fits `spp` samples) into `settings` where `given` says the user did not set them; a note per setting taken.
/// `Job::resolve` for a render, and any front end that opens scene files (the web page) for its own settings.
pub fn take_file_settings(
    settings: &mut Settings,
    file: &crate::scene::FileSettings,
    given: &dyn Fn(&str) -> bool,
    spp: Option<u32>,
) -> Vec<String> {
    let mut notes = Vec::new();
    if let Some((depth, source)) = &file.max_depth {
        // The file's integrator fills the mode and the depth each where not given (--max-depth 17 alone
        // still path traces, as the file asks; --mode direct alone ignores the file's depth).
        let mut taken = Vec::new();
        if !given("mode") {
            settings.mode = Mode::Path;
            taken.push("--mode path".to_string());
        }
        if settings.mode == Mode::Path && !given("max_depth") {
            settings.max_depth = *depth;
            taken.push(format!("--max-depth {depth}"));
        }
        if !taken.is_empty() {
            notes.push(format!("{} from the scene file ({source}; --mode/--max-depth override it)", taken.join(" ")));
        }
    }
    if let Some((f, source)) = &file.filter {
        if !given("filter") && !given("filter_radius") && !given("filter_sigma") {
            if let Ok(shape) = f.shape.parse::<PixelFilter>() {
                settings.filter = shape;
                settings.filter_radius = Some(f.radius);
                settings.filter_sigma = f.sigma;
                notes.push(format!(
                    "{} from the scene file ({source}; --filter/--filter-radius/--filter-sigma override it)",
                    super::report::filter_flags(f)
                ));
            }
        }
    }
    if let Some((name, source)) = &file.sampler {
        // Taken only where it can render the sample count asked, or else the file's (stratified has a maximum).
        let fits = |s: SamplerKind| spp.is_none_or(|n| check_spp(s, n).is_ok());
        match name.parse::<SamplerKind>() {
            Ok(s) if !given("sampler") && fits(s) => {
                settings.sampler = s;
                notes.push(format!("--sampler {s} from the scene file ({source}; --sampler overrides it)"));
            }
            _ => {}
        }
    }
    notes
}
