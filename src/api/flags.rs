//! A render's flags, named once for every front end: the CLI's `--flag value` is Python's `flag=value` (the same
//! strings), parsed and checked by the same declaration, with the same messages.

use super::budget::Budget;
use super::error::ApiError;
use crate::render::settings::Settings;
use crate::state::session::StateArgs;
use clap::{CommandFactory, Parser};
use std::time::Duration;

/// Samples per pixel when neither `--spp` nor `--time` is given.
pub const DEFAULT_SPP: u32 = 64;

/// What a render is asked to do: its budget, its estimator settings, and its state file handling.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct RenderFlags {
    /// Samples per pixel [default: 64 unless --time is given].
    #[arg(long, conflicts_with = "time", value_parser = crate::io::cli_values::spp)]
    pub spp: Option<u32>,
    /// Render for this many seconds (after start-up and shader compilation).
    #[arg(long, value_parser = crate::io::cli_values::seconds)]
    pub time: Option<f64>,
    /// Estimator settings: the same names as the viewer panel and benchmark files.
    #[command(flatten)]
    pub settings: Settings,
    /// State files, checkpoints, resume and parts (src/state).
    #[command(flatten)]
    pub state: StateArgs,
    /// The flags given explicitly (keyword names, `_` for `-`), where the front end knows them: a resumed render
    /// takes every other setting from its state file. None: a flag left at its default counts as not given.
    #[arg(skip)]
    pub given: Option<Vec<String>>,
}

/// `RenderFlags` as a command of its own, to parse name–value pairs and to list every flag.
#[derive(Parser)]
#[command(name = "render", no_binary_name = true, disable_help_flag = true)]
struct FlagsOnly {
    #[command(flatten)]
    flags: RenderFlags,
}

/// One flag: its name (as a keyword, `-` → `_`), help, default and allowed values.
#[derive(Clone, Debug, PartialEq)]
pub struct FlagInfo {
    /// The keyword name (`light_sampling`); the flag is `--light-sampling`.
    pub name: String,
    /// The flag's help.
    pub help: String,
    /// The default, as text, where there is one.
    pub default: Option<String>,
    /// The allowed values, where they are a fixed list.
    pub choices: Vec<String>,
}

impl RenderFlags {
    /// Parses `(name, value)` pairs as the command line would parse `--name=value` (`_` in names read as `-`).
    /// An unknown name or a bad value is an `ApiError::Settings` with clap's message.
    pub fn from_pairs<K: AsRef<str>, V: AsRef<str>>(pairs: &[(K, V)]) -> Result<RenderFlags, ApiError> {
        let argv = pairs.iter().map(|(k, v)| format!("--{}={}", k.as_ref().replace('_', "-"), v.as_ref()));
        let mut flags =
            FlagsOnly::try_parse_from(argv).map(|p| p.flags).map_err(|e| ApiError::Settings(clap_message(&e)))?;
        flags.given = Some(pairs.iter().map(|(k, _)| k.as_ref().replace('-', "_")).collect());
        Ok(flags)
    }

    /// Whether flag `name` (keyword form) was given: by the front end's list, else by differing from its default.
    pub fn was_given(&self, name: &str, differs_from_default: bool) -> bool {
        match &self.given {
            Some(given) => given.iter().any(|g| g == name),
            None => differs_from_default,
        }
    }

    /// Every flag with its help, default and allowed values.
    pub fn describe() -> Vec<FlagInfo> {
        FlagsOnly::command()
            .get_arguments()
            .filter_map(|a| {
                let long = a.get_long()?;
                Some(FlagInfo {
                    name: long.replace('-', "_"),
                    help: a.get_help().map(|h| h.to_string()).unwrap_or_default(),
                    default: a.get_default_values().first().map(|v| v.to_string_lossy().into_owned()),
                    choices: a.get_possible_values().iter().map(|v| v.get_name().to_string()).collect(),
                })
            })
            .collect()
    }

    /// The budget the flags ask for, and a note when a fixed-count sampler rounds the sample count.
    pub fn budget(&self) -> Result<(Budget, Option<String>), ApiError> {
        match (self.spp, self.time) {
            (Some(0), _) => Err(ApiError::Settings("--spp must be at least 1".into())),
            (Some(n), _) => {
                // Hammersley and stratified build their points for a fixed count: refuse or round with a message.
                let used = crate::render::samplers::check_spp(self.settings.sampler, n)?;
                let note = crate::render::samplers::spp_message(self.settings.sampler, n, used);
                Ok((Budget::Samples(used), (!note.is_empty()).then_some(note)))
            }
            (None, Some(t)) if t.is_finite() && t > 0.0 => Ok((Budget::Time(Duration::from_secs_f64(t)), None)),
            (None, Some(t)) => Err(ApiError::Settings(format!("--time {t} must be a positive number of seconds"))),
            (None, None) => Ok((Budget::Samples(DEFAULT_SPP), None)),
        }
    }
}

/// clap's message without its usage lines: what went wrong and, for a bad value, the values allowed.
fn clap_message(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let text = text.split("\n\nUsage:").next().unwrap_or(&text);
    text.trim().trim_start_matches("error: ").replace("\n\n", "\n")
}

/// `SceneSpec` as a command of its own, to parse a scene's name–value pairs.
#[derive(Parser)]
#[command(name = "load", no_binary_name = true, disable_help_flag = true)]
struct SceneOnly {
    #[command(flatten)]
    spec: crate::scene::SceneSpec,
}

/// A scene as the command line names it, from its name and `(name, value)` pairs for the other scene flags
/// (`env`, `env_scale`, `env_rotation`, `gltf_scene`, `allow_outside_paths` = "true"/"false").
pub fn scene_spec<K: AsRef<str>, V: AsRef<str>>(
    name: &str,
    pairs: &[(K, V)],
) -> Result<crate::scene::SceneSpec, ApiError> {
    let mut argv = vec![name.to_string()];
    for (k, v) in pairs {
        let flag = format!("--{}", k.as_ref().replace('_', "-"));
        match (flag.as_str(), v.as_ref()) {
            ("--allow-outside-paths", "true") => argv.push(flag),
            ("--allow-outside-paths", "false") => {}
            (_, v) => argv.push(format!("{flag}={v}")),
        }
    }
    SceneOnly::try_parse_from(argv).map(|p| p.spec).map_err(|e| ApiError::Settings(clap_message(&e)))
}
