//! A scene handle: a scene loaded once (file or built-in), flattened for the device with its BVH built, and
//! uploaded once to each lab that renders it.

use super::error::ApiError;
use super::lab::Lab;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::scene::{self, Camera, LoadError, Scene, SceneSpec};
use std::sync::{Arc, Mutex, OnceLock};

/// A loaded scene, ready to render any number of times with any settings.
pub struct SceneHandle {
    spec: SceneSpec,
    scene: Scene,
    data: SceneData,
    /// `state::scene_hash`, computed when first asked for (only a render with a state file needs it, and it reads
    /// every buffer: 25 ms of a 270k-triangle scene's start-up).
    hash: OnceLock<String>,
    /// The scene on the device of the lab that last rendered it (lab id, buffers).
    uploaded: Mutex<Option<(u64, Arc<GpuScene>)>>,
}

impl SceneHandle {
    /// Loads a scene as the command line names it (a .gltf/.glb/.toml/.pbrt/.xml file or a built-in name, with
    /// an environment override) and builds its device data (BVH, light tables). Loader warnings go to stderr.
    pub fn load(spec: &SceneSpec) -> Result<SceneHandle, ApiError> {
        let scene = spec.load(crate::gpu::chosen_adapter_storage_limit()).map_err(|e| {
            let missing = scene::builtin::by_name(&spec.scene).is_none()
                && std::path::Path::new(&spec.scene).symlink_metadata().is_err();
            let env_missing = spec.env.as_ref().is_some_and(|p| p.symlink_metadata().is_err());
            if missing || env_missing {
                ApiError::NotFound(e.to_string())
            } else if let LoadError::Flag(m) = e {
                ApiError::Settings(m)
            } else {
                ApiError::Scene(e)
            }
        })?;
        let data = SceneData::build(&scene);
        Ok(SceneHandle { spec: spec.clone(), scene, data, hash: OnceLock::new(), uploaded: Mutex::new(None) })
    }

    /// A scene loaded elsewhere (the lab's tools that build scenes of their own), named by `spec`.
    pub fn from_scene(spec: SceneSpec, scene: Scene) -> SceneHandle {
        let data = SceneData::build(&scene);
        SceneHandle { spec, scene, data, hash: OnceLock::new(), uploaded: Mutex::new(None) }
    }

    /// A built-in scene or file by name, with no overrides.
    pub fn named(name: &str) -> Result<SceneHandle, ApiError> {
        SceneHandle::load(&SceneSpec::named(name))
    }

    /// How the scene was named.
    pub fn spec(&self) -> &SceneSpec {
        &self.spec
    }

    /// The scene as loaded.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene flattened for the device.
    pub fn data(&self) -> &SceneData {
        &self.data
    }

    /// The scene's camera.
    pub fn camera(&self) -> &Camera {
        &self.scene.camera
    }

    /// The fingerprint a state file records (`state::scene_hash`): a resume of another scene is refused.
    pub fn hash(&self) -> &str {
        self.hash.get_or_init(|| crate::state::scene_hash(&self.data, &self.scene.camera))
    }

    /// The image size the scene file asks for (pbrt `Film`, Mitsuba `hdrfilm`), if it does.
    pub fn film_size(&self) -> Option<[u32; 2]> {
        self.scene.film_size
    }

    /// One line of statistics: primitives, materials, lights, and the BVH.
    pub fn summary(&self) -> String {
        let (s, d) = (&self.scene, &self.data);
        format!(
            "{} — {} triangles, {} spheres, {} quads, {} materials, {} textures, {} lights; BVH {} nodes built in {:.1} ms, {:.1} MiB{}",
            s.name,
            s.triangle_count(),
            s.spheres.len(),
            s.quads.len(),
            s.materials.len(),
            s.textures.len(),
            d.selectable_lights(),
            d.bvh_node_count(),
            d.bvh_seconds * 1e3,
            d.bvh_bytes() as f64 / (1 << 20) as f64,
            // Per triangle only where there are triangles (the BVH also holds spheres and quads).
            match s.triangle_count() {
                0 => String::new(),
                n => format!(" ({:.0} B/triangle)", d.bvh_bytes() as f64 / n as f64),
            },
        )
    }

    /// The scene's buffers on `lab`'s device, uploaded at the first call for that lab.
    pub fn upload(&self, lab: &Lab) -> Result<Arc<GpuScene>, ApiError> {
        let mut slot = self.uploaded.lock().unwrap_or_else(|p| p.into_inner());
        if let Some((id, scene)) = slot.as_ref() {
            if *id == lab.id {
                return Ok(scene.clone());
            }
        }
        let gpu = GpuScene::upload(lab.gpu(), self.data.clone())
            .map_err(|e| ApiError::Upload(format!("{}: {e}", self.spec.scene)))?;
        let gpu = Arc::new(gpu);
        *slot = Some((lab.id, gpu.clone()));
        Ok(gpu)
    }
}
