//! The scene as the command line names it — a file or built-in name, a glTF scene index, an environment map that
//! replaces the scene's own — and the one way every command (render, view, bench, reference, info) loads it.

use super::{envmap, load, Environment, LoadOptions, Scene, SceneError};
use std::path::PathBuf;
use std::sync::Arc;

/// Why the scene the command line names could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file, a file it references, or the environment map (the message names it, and the line).
    #[error(transparent)]
    File(#[from] SceneError),
    /// An override flag out of range (`--env-scale`, `--env-rotation`).
    #[error("{0}")]
    Flag(String),
    /// Nothing to render: no geometry, no lights, no environment.
    #[error("{scene}: the scene is empty: no geometry, no lights and no environment")]
    Empty { scene: String },
}

/// The scene and its environment override, as on the command line.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct SceneSpec {
    /// A .gltf/.glb/.toml file or a built-in scene: veach-mis, cornell-box, furnace, area-vs-cosine.
    #[arg(default_value = "veach-mis")]
    pub scene: String,
    /// glTF scene index (default: the file's default scene).
    #[arg(long)]
    pub gltf_scene: Option<usize>,
    /// Light the scene with this equirectangular .hdr/.exr (replaces its environment).
    #[arg(long)]
    pub env: Option<PathBuf>,
    /// Scale of the --env map (finite, 0 to 1e30).
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true, value_parser = crate::io::cli_values::env_scale)]
    pub env_scale: f32,
    /// Rotation of the --env map about +Y, degrees.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true, value_parser = crate::io::cli_values::degrees)]
    pub env_rotation: f32,
    /// Let the files a scene names (glTF buffers and images; pbrt and Mitsuba includes, meshes, textures and maps)
    /// be absolute paths or lead outside the scene file's directory (by `..` or a symbolic link); without it such a
    /// file name is an error.
    #[arg(long)]
    pub allow_outside_paths: bool,
}

impl Default for SceneSpec {
    fn default() -> Self {
        SceneSpec::named("veach-mis")
    }
}

impl SceneSpec {
    /// A scene file or built-in name with no overrides.
    pub fn named(scene: &str) -> SceneSpec {
        SceneSpec {
            scene: scene.into(),
            gltf_scene: None,
            env: None,
            env_scale: 1.0,
            env_rotation: 0.0,
            allow_outside_paths: false,
        }
    }

    /// Loads the scene and applies the environment override; prints the loader's warnings once. A scene with
    /// nothing in it (no geometry, no lights, no environment) is an error, not a black image. With the device's
    /// storage-binding limit, textures it cannot hold are refused before they are decoded.
    pub fn load(&self, storage_binding_limit: Option<u64>) -> Result<Scene, LoadError> {
        if !(self.env_scale.is_finite() && self.env_scale >= 0.0 && self.env_scale <= 1e30) {
            return Err(LoadError::Flag(format!(
                "--env-scale {} must be a finite number in [0, 1e30]",
                self.env_scale
            )));
        }
        if !self.env_rotation.is_finite() {
            return Err(LoadError::Flag(format!(
                "--env-rotation {} must be a finite number of degrees",
                self.env_rotation
            )));
        }
        let options = LoadOptions {
            gltf_scene: self.gltf_scene,
            allow_outside_paths: self.allow_outside_paths,
            // Two bindings' worth (render/gpu_scene.rs split_texels).
            max_texel_bytes: storage_binding_limit.map(|l| 2 * l),
        };
        let mut s = load(&self.scene, &options)?;
        if let Some(env) = &self.env {
            let (map, warnings) = envmap::load_envmap(env)?;
            s.warnings.extend(warnings);
            s.environment = Environment::Map {
                map: Arc::new(map),
                scale: self.env_scale,
                rotation: self.env_rotation.to_radians(),
            };
        }
        let geometry = s.triangle_count() + s.spheres.len() + s.quads.len();
        if !s.has_lights() && geometry > 0 {
            s.warnings.push("the scene has no lights and no environment: the image will be black".into());
        }
        for w in &s.warnings {
            eprintln!("warning: {}: {w}", self.scene);
        }
        if geometry == 0 && !s.has_lights() {
            return Err(LoadError::Empty { scene: self.scene.clone() });
        }
        Ok(s)
    }
}
