//! How each [`Command`] from the UI changes the engine: settings, comparison, camera, display options,
//! scene, environment and reference loading, EXR saving, and the test hook that loses the device.

use super::side::SideState;
use super::{scene_centre, Command, Engine};
use crate::render::display;
use crate::render::settings::Settings;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::scene::{self, Environment, LoadOptions, Scene};
use crate::viewer::ViewerError;
use std::sync::Arc;

impl Engine {
    pub(super) fn handle(&mut self, c: Command) -> Result<bool, ViewerError> {
        match c {
            Command::Quit => return Ok(false),
            Command::Settings(side, s) => {
                s.validate()?;
                let i = side as usize;
                let old = &self.settings[i];
                let same_estimator = Settings { exposure: 0.0, width: 0, height: 0, ..old.clone() }
                    == Settings { exposure: 0.0, width: 0, height: 0, ..s.clone() };
                self.settings[i] = s.clone();
                if !same_estimator {
                    self.sides[i].set_settings(s)?;
                    if i < self.active() {
                        self.request_pipelines();
                    }
                }
            }
            Command::Compare(on) => {
                if on != self.compare {
                    self.compare = on;
                    self.shared().compare = on;
                    if on {
                        self.sides[1].restart();
                        self.request_pipelines();
                    }
                }
            }
            Command::Camera(c) => {
                self.camera = c.clone();
                for s in &mut self.sides {
                    s.set_camera(c.clone());
                }
                self.shared().camera = c;
            }
            Command::Display(d) => self.options = d,
            Command::OpenScene(name) => {
                // No panic hook of our own swapped here (issue 12): `scene::load` already catches its file
                // loaders' panics, and `catch_quietly` covers the rest (building a built-in scene). It
                // silences only this thread's panic, so a panic on the UI or compile thread meanwhile is
                // still printed, and a panicking load becomes a message instead of stopping the engine (the
                // swap it replaces left the silent hook installed for good when the load panicked).
                let loaded = scene::catch_quietly(|| scene::load(&name, &LoadOptions::default()))
                    .map_err(|panic| ViewerError::Input(format!("loading {name} failed: {panic}")))
                    .and_then(|r| r.map_err(|e| ViewerError::Scene(e.into())));
                match loaded {
                    Ok(sc) => {
                        let warnings = sc.warnings.len();
                        self.set_scene(sc, name.clone())?;
                        self.message(format!(
                            "opened {name}{}",
                            if warnings > 0 { format!(" ({warnings} warnings)") } else { String::new() }
                        ));
                    }
                    Err(e) => self.message(format!("could not open the scene: {e}")),
                }
            }
            Command::OpenEnv(path) => match scene::envmap::load_envmap(&path) {
                Ok((map, _)) => {
                    let mut sc = self.scene.clone();
                    sc.environment = Environment::Map { map: Arc::new(map), scale: 1.0, rotation: 0.0 };
                    let name = self.scene_name.clone();
                    let camera = self.camera.clone();
                    self.set_scene(sc, name)?;
                    // Lighting changed, the view did not: keep the user's camera.
                    for s in &mut self.sides {
                        s.set_camera(camera.clone());
                    }
                    self.camera = camera.clone();
                    self.shared().camera = camera;
                    self.message(format!("environment {}", path.display()));
                }
                Err(e) => self.message(format!("could not load the environment: {e}")),
            },
            Command::LoadReference(path) => {
                let (w, h) = (self.settings[0].width, self.settings[0].height);
                let read = crate::io::input_file::read_bounded(&path, crate::io::input_file::MAX_ENVMAP_BYTES)
                    .map_err(|e| e.to_string())
                    .and_then(|bytes| display::decode_reference(&bytes, w, h))
                    .map_err(|e| format!("{}: {e}", path.display()));
                match read {
                    Ok(rgb) => {
                        self.reference = Some(display::upload_reference(&self.ctx, &rgb));
                        self.shared().has_reference = true;
                        self.message(format!("reference {}", path.display()));
                    }
                    Err(e) => self.message(format!("could not load the reference: {e}")),
                }
            }
            Command::ClearReference => {
                self.reference = None;
                self.shared().has_reference = false;
            }
            Command::SaveExr(path) => {
                let mut written = vec![];
                for i in 0..self.active() {
                    let p = if i == 0 {
                        path.clone()
                    } else {
                        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("render");
                        path.with_file_name(format!("{stem}-b.exr"))
                    };
                    let film = self.sides[i].renderer.film(&self.ctx).map_err(ViewerError::from)?;
                    match film.save(&p, self.options.exposure, self.options.tonemap) {
                        Ok(()) => written.push(p.display().to_string()),
                        Err(e) => {
                            self.message(e.to_string());
                            return Ok(true);
                        }
                    }
                }
                self.message(format!("wrote {}", written.join(", ")));
            }
            Command::LoseDevice => self.ctx.device.destroy(),
        }
        Ok(true)
    }

    fn set_scene(&mut self, sc: Scene, name: String) -> Result<(), ViewerError> {
        let gs = match GpuScene::upload(&self.ctx, SceneData::build(&sc)) {
            Ok(g) => g,
            Err(e) => {
                self.message(format!("{name}: {e}"));
                return Ok(());
            }
        };
        let camera = sc.camera.clone();
        let mut sides = Vec::new();
        for s in &self.settings {
            sides.push(SideState::new(&self.ctx, &gs, camera.clone(), s.clone())?);
        }
        self.gs = gs;
        self.sides = sides;
        self.camera = camera.clone();
        {
            let mut s = self.shared.lock().unwrap_or_else(|p| p.into_inner());
            s.scene = name.clone();
            s.home_camera = camera.clone();
            s.camera = camera;
            s.pivot = scene_centre(&sc);
        }
        self.scene = sc;
        self.scene_name = name;
        self.request_pipelines();
        Ok(())
    }
}
