//! glTF 2.0 loader: `.gltf` (external files or base64 `data:` URIs) and `.glb`.
//!
//! The JSON is parsed into `gltf::json` types, but buffers, accessors and images are read here rather than
//! through `gltf::import` / `gltf::Document`: gltf 1.4.1 panics on some dangling indices and silently reads
//! garbage for bad strides or ranges. So every index, byte range, count and format is checked first, and
//! errors name the accessor, mesh and primitive they belong to.
//!
//! Conventions of the result:
//! - One `Mesh` per primitive per node instance, in world space; mirrored transforms (negative determinant)
//!   swap two indices per triangle so the counter-clockwise geometric normal stays outward.
//! - Missing normals, and zero or non-finite ones, are generated per vertex as the area-weighted sum of the
//!   adjacent face normals (smooth shading; shared vertices across hard edges are averaged).
//! - UVs keep glTF's convention: (0, 0) is the top-left texel, i.e. the first row of `Texture::texels`.
//! - Materials and textures appear in first-use order; only what the chosen scene uses is loaded.
//!
//! Layout: `container` (GLB/JSON parsing, extensions, buffers and URIs), `notes` (warnings), `nodes` (the node
//! graph, scenes and transforms), `accessor` (validated accessor and buffer-view reads), `mesh` (primitives to
//! world-space meshes), `material` (materials, textures and images) and `camera_light` (cameras and
//! KHR_lights_punctual). This file holds the entry point, the limits and the loader's state.

mod accessor;
mod camera_light;
mod container;
mod material;
mod mesh;
mod nodes;
mod notes;

use super::{Camera, LoadOptions, Scene, SceneError};
use camera_light::frame_meshes;
use container::{check_extensions, load_buffers, parse_json, split_container, Uris};
use glam::Mat4;
use gltf::json;
use material::{Decoded, TexKey};
use nodes::check_node_graph;
use notes::Notes;
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;

/// Largest texture side we accept (the GPU texture limit we design for).
const MAX_TEXTURE_SIZE: u32 = 16384;
/// Texel bytes all textures together may take when the device's limit is not known: one texture of the
/// largest size (textures live in one storage buffer, 4 bytes per texel).
const DEFAULT_TEXEL_BYTES: u64 = 4 * (MAX_TEXTURE_SIZE as u64) * (MAX_TEXTURE_SIZE as u64);
/// Largest accessor element count; rejects absurd counts before anything is allocated.
const MAX_ELEMENTS: u64 = 1 << 26;
/// Deepest node hierarchy we follow (bounds the recursion).
const MAX_DEPTH: usize = 512;
/// Most node instances one scene may expand to (a node shared by many parents can multiply).
const MAX_NODE_VISITS: usize = 1 << 20;

type Res<T> = Result<T, String>;

/// Loads a glTF 2.0 file (`.gltf` or `.glb`) into a world-space [`Scene`].
///
/// Uses the file's default scene, or `options.gltf_scene`, or scene 0 when the file names no default. Errors
/// name the file and the offending object; repairs and skipped content are listed in `Scene::warnings`.
pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    load_inner(path, options).map_err(|message| SceneError::new(path, message))
}

fn load_inner(path: &Path, options: &LoadOptions) -> Res<Scene> {
    let bytes =
        crate::io::input_file::read_bounded(path, crate::io::input_file::MAX_GLTF_BYTES).map_err(|e| e.to_string())?;
    let (json_bytes, bin) = split_container(path, &bytes)?;
    let is_glb = bytes.starts_with(b"glTF");
    let root = parse_json(json_bytes)?;
    let mut notes = Notes::default();
    check_extensions(&root, &mut notes)?;
    check_node_graph(&root)?;
    // A bare file name's parent is "": URIs are then relative to the working directory.
    let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let uris = Uris { base, allow_outside: options.allow_outside_paths };
    let buffers = load_buffers(&root, bin, is_glb, uris)?;
    let mut loader = Loader::new(&root, uris, buffers, notes);
    loader.texel_limit = options.max_texel_bytes.unwrap_or(DEFAULT_TEXEL_BYTES);
    loader.scene.name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let roots = loader.scene_roots(options)?;
    let mut on_path = vec![false; root.nodes.len()];
    for node in roots {
        loader.visit(node, &Mat4::IDENTITY, &mut on_path, 0)?;
    }
    Ok(loader.finish())
}

/// `" 'name'"` or nothing, for messages.
fn quoted(name: &Option<String>) -> String {
    name.as_ref().map(|n| format!(" '{n}'")).unwrap_or_default()
}

struct Loader<'a> {
    root: &'a json::Root,
    uris: Uris<'a>,
    /// Bytes of RGBA8 texels the textures may take, and have taken (checked before each image is decoded).
    texel_limit: u64,
    texel_used: u64,
    buffers: Vec<Vec<u8>>,
    notes: Notes,
    scene: Scene,
    camera: Option<Camera>,
    materials: HashMap<Option<usize>, u32>,
    textures: HashMap<TexKey, u32>,
    images: HashMap<usize, Rc<Decoded>>,
    visits: usize,
}

impl<'a> Loader<'a> {
    fn new(root: &'a json::Root, uris: Uris<'a>, buffers: Vec<Vec<u8>>, notes: Notes) -> Self {
        Loader {
            root,
            uris,
            texel_limit: DEFAULT_TEXEL_BYTES,
            texel_used: 0,
            buffers,
            notes,
            scene: Scene::default(),
            camera: None,
            materials: HashMap::new(),
            textures: HashMap::new(),
            images: HashMap::new(),
            visits: 0,
        }
    }

    fn uris(&self) -> Uris<'a> {
        self.uris
    }

    /// The finished scene: camera (from the file or framing the bounds) and warnings.
    fn finish(mut self) -> Scene {
        if self.scene.meshes.is_empty() && self.scene.punctual_lights.is_empty() {
            self.notes.push("the scene contains nothing to render (no triangles and no lights)".into());
        }
        self.scene.camera = self.camera.take().unwrap_or_else(|| frame_meshes(&self.scene.meshes));
        self.scene.warnings = self.notes.finish();
        self.scene
    }
}
